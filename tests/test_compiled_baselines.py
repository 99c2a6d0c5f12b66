"""The baseline controllers on the compiled engine (compiled_laws).

(a) Agreement with the numpy engine, per controller, on the ISO 3888-1
lane change (a chain of straights, arcs and clothoids) and on an arc.
Both engines integrate the same equations with DOP853 at rtol 1e-10, atol
1e-12; the compiled law reads the path's position and heading from a table
within 1e-10 m / rad (:func:`geometry_table`), so the laws differ by about
1e-10 times their gains, and the solutions by the integration error the
two step sequences leave: a few 1e-8 over these runs. The tolerance
(1e-6 on e [m], theta and delta_f [rad]) bounds both with a margin.
(b) An independent reference: the path-frame equations of the paper
(corrected eqs. 17-19) integrated by scipy's solve_ivp with Stanley's and
pure pursuit's laws written here from their formulas, with the circle's
projection in closed form.
(c) The routing: ``engine="auto"`` picks the compiled engine for them, the
cases it refuses go to numpy with the reason.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control.simulation import compiled
from fws_control.simulation.compiled_laws import geometry_table, law_code
from fws_control.simulation.engine import PEAK_SIGNALS, SIGNALS

pytestmark = pytest.mark.skipif(
    not compiled.available(), reason="numba is not installed: no compiled engine"
)

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_front=0.6)
# the dynamic model's car (the runs with model='dynamic')
DYN_VEH = fws.Vehicle(
    wheelbase=2.7, rear_to_cg=1.2, mass=1500.0, yaw_inertia=2600.0,
    cornering_front=8.0e4, cornering_rear=9.5e4, friction=0.9, max_steer_front=0.6,
)  # fmt: skip
SPEED = 15.0
PLANT = fws.LateralPlant(VEH, speed=SPEED)
ARC = fws.Arc(curvature=0.04)


def _controllers():
    return {
        "lqr": fws.LQRController(PLANT, Q=np.diag([1.0, 0.5]), R=np.eye(2)),
        "pure_pursuit": fws.PurePursuit(lookahead=4.0, lookahead_time=0.4),
        "stanley": fws.Stanley(gain=2.0),
        "rear_wheel": fws.RearWheelFeedback(k_e=0.1, k_theta=0.5),
    }


@functools.cache
def _lane_change():
    # built once (half a second; paths are immutable, so the tests share it)
    return fws.double_lane_change(vehicle_width=1.8).path


def _both(plant, path, ctrl, *, duration, x0=(0.0, 0.4, 0.05)):
    kw = dict(initial_state=x0, duration=duration, dt=0.01)
    rc = fws.simulate(plant, path, ctrl, engine="compiled", **kw)
    rn = fws.simulate(plant, path, ctrl, engine="numpy", **kw)
    return rc, rn


@pytest.mark.parametrize("name", ["lqr", "pure_pursuit", "stanley", "rear_wheel"])
@pytest.mark.parametrize("where", ["lane_change", "arc"])
def test_compiled_baseline_agrees_with_numpy(name, where):
    ctrl = _controllers()[name]
    path = _lane_change() if where == "lane_change" else ARC
    rc, rn = _both(PLANT, path, ctrl, duration=2.5)
    assert rc.engine == "compiled" and rn.engine == "numpy"
    assert rc.status == rn.status == "ok"
    for sig in ("e", "theta", "delta_f", "delta_r", "x", "y"):
        a, b = getattr(rc, sig), getattr(rn, sig)
        assert np.max(np.abs(a - b)) <= 1e-6, (sig, np.max(np.abs(a - b)))
    # the rates and the lateral acceleration: the same formulas (numpy's
    # compute_outputs) on states that agree to 1e-6
    for sig in ("delta_f_rate", "lateral_accel"):
        a, b = getattr(rc, sig), getattr(rn, sig)
        scale = 1.0 + np.max(np.abs(b))
        assert np.max(np.abs(a - b)) <= 1e-4 * scale, sig


def test_compiled_baseline_with_actuator_and_limits_agrees_with_numpy():
    # the steering lag with angle and rate limits, held as the paper's law's
    veh = fws.Vehicle(
        wheelbase=2.7, rear_to_cg=1.35, max_steer_front=0.3, max_steer_rate_front=0.6
    )
    plant = fws.LateralPlant(veh, speed=SPEED, steering_lag=0.1)
    ctrl = fws.Stanley(gain=3.0)
    rc, rn = _both(plant, _lane_change(), ctrl, duration=2.0, x0=(0.0, 1.0, 0.0))
    assert rc.status == rn.status == "ok"
    # the rate limit is active: the angle's rate reaches it
    assert np.max(np.abs(rn.delta_f_rate)) == pytest.approx(0.6, abs=1e-9)
    for sig in ("e", "theta", "delta_f"):
        a, b = getattr(rc, sig), getattr(rn, sig)
        assert np.max(np.abs(a - b)) <= 1e-6, (sig, np.max(np.abs(a - b)))


# An input delay: the law acts on the path state at t - delay (the method of
# steps on both engines: steps of at most the delay, each engine reading the
# delayed state from its own dense output). At rtol 1e-10 the seven runs
# below agree to 6.2e-9 of each signal's largest value and their exact
# peaks to 1.7e-8 relative (measured; the largest: rear-wheel feedback's
# angle, Stanley's and rear-wheel feedback's peaks, both with the lag). The
# tolerance, 1e-7 of each signal's largest value and of each peak, bounds
# these with a margin; a delay acting on the wrong state moves them by 1e-2
# or more.
@pytest.mark.parametrize(
    ("name", "model", "lag", "delay"),
    [
        ("stanley", "kinematic", 0.27, 0.24),
        ("pure_pursuit", "kinematic", None, 0.1),
        ("rear_wheel", "kinematic", 0.27, 0.24),
        ("lqr", "kinematic", None, 0.1),
        ("stanley", "dynamic", 0.27, 0.24),
        ("pure_pursuit", "dynamic", None, 0.1),
        # (the state-feedback law's rate reads the clothoids' curvature slope)
        ("lqr", "dynamic", None, 0.1),
    ],
)
def test_compiled_baseline_with_delay_agrees_with_numpy(name, model, lag, delay):
    veh = DYN_VEH if model == "dynamic" else VEH
    tyre = {"tyre": "magic"} if model == "dynamic" else {}
    plant = fws.LateralPlant(veh, speed=SPEED, steering_lag=lag, model=model, **tyre)
    kw = dict(initial_state=(0.0, 0.4, 0.05), duration=2.0, dt=0.01, delay=delay,
              rtol=1e-10, atol=1e-12)  # fmt: skip
    ctrl = _controllers()[name]
    rc = fws.simulate(plant, _lane_change(), ctrl, **kw)  # auto: compiled
    rn = fws.simulate(plant, _lane_change(), ctrl, engine="numpy", **kw)
    assert rc.engine == "compiled" and rn.engine == "numpy"
    assert rc.status == rn.status == "ok"
    got, ref = rc.signals[0], rn.signals[0]
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    scale = np.maximum(np.nanmax(np.abs(ref), axis=1), 1e-300)
    for j, sig in enumerate(SIGNALS):
        err = np.nanmax(np.abs(got[j] - ref[j])) / scale[j]
        assert err <= 1e-7, (sig, err)
    for sig in PEAK_SIGNALS:
        p, r = getattr(rc.peaks, sig), getattr(rn.peaks, sig)
        assert p.value == pytest.approx(r.value, rel=1e-7, abs=1e-12), sig
    # the delay acts: without the lag the angle before t = delay is the
    # command of the initial state, held; and the run parts from the
    # undelayed one
    first = rc.t < delay - 1e-9
    if lag is None:
        assert np.all(rc.delta_f[first] == rc.delta_f[0])
    undelayed = fws.simulate(plant, _lane_change(), ctrl, **{**kw, "delay": 0.0})
    assert np.max(np.abs(rc.delta_f - undelayed.delta_f)) > 1e-3


def test_geometry_table_within_its_tolerance():
    path = _lane_change()
    tab = geometry_table(path)
    s = np.linspace(0.0, float(path.length), 20_001)
    x, y, psi = tab(s)
    px, py = path.position(s)
    ph = np.asarray(path.heading(s))
    assert np.max(np.hypot(x - px, y - py)) <= 1e-10
    assert np.max(np.abs(np.angle(np.exp(1j * (psi - ph))))) <= 1e-10
    assert tab.max_error <= 1e-10


# --------------------------------------------------------------------------
# (b) solve_ivp of the path-frame equations with the laws written here


def _arc_point(kappa, s):
    # the arc from the origin with heading 0, centre (0, 1/kappa)
    return math.sin(kappa * s) / kappa, (1 - math.cos(kappa * s)) / kappa, kappa * s


def _stanley_here(s, e, th, kappa, f, gain, soft, V):
    cx, cy, h = _arc_point(kappa, s)
    rx, ry = cx - e * math.sin(h), cy + e * math.cos(h)
    psi = th + h
    fx, fy = rx + f * math.cos(psi), ry + f * math.sin(psi)
    # nearest point of the circle: along the radius through F
    r = 1.0 / kappa
    dx, dy = fx, fy - r
    dist = math.hypot(dx, dy)
    e_f = r - dist  # positive left (towards the centre of a left turn)
    h_f = math.atan2(dy, dx) + math.pi / 2
    theta_f = math.remainder(psi - h_f, 2 * math.pi)
    return -theta_f - math.atan(gain * e_f / (soft + abs(V)))


def _pure_pursuit_here(s, e, th, kappa, f, ld, V):
    cx, cy, h = _arc_point(kappa, s)
    rx, ry = cx - e * math.sin(h), cy + e * math.cos(h)
    px, py, _ = _arc_point(kappa, s + math.sqrt(max(ld**2 - e**2, 0.0)))
    psi = th + h
    # the look-ahead point in the vehicle frame
    lx = math.cos(psi) * (px - rx) + math.sin(psi) * (py - ry)
    ly = -math.sin(psi) * (px - rx) + math.cos(psi) * (py - ry)
    return math.atan(2.0 * f * (ly / math.hypot(lx, ly)) / ld)


def _reference(law, kappa, f, V, x0, t):
    def rhs(_, z):
        s, e, th = z
        df = min(max(law(s, e, th), -VEH.max_steer_front), VEH.max_steer_front)
        s_dot = V * math.cos(th) / (1 - kappa * e)
        return [s_dot, V * math.sin(th), -kappa * s_dot + V * math.tan(df) / f]

    sol = solve_ivp(rhs, (t[0], t[-1]), x0, method="DOP853", t_eval=t,
                    rtol=1e-12, atol=1e-13)  # fmt: skip
    assert sol.success
    return sol.y


@pytest.mark.parametrize("name", ["stanley", "pure_pursuit"])
def test_compiled_baseline_against_solve_ivp_reference(name):
    kappa, f = 0.04, VEH.wheelbase
    if name == "stanley":
        ctrl = fws.Stanley(gain=2.0, softening=0.1)

        def law(s, e, th):
            return _stanley_here(s, e, th, kappa, f, 2.0, 0.1, SPEED)
    else:
        ctrl = fws.PurePursuit(lookahead=6.0)

        def law(s, e, th):
            return _pure_pursuit_here(s, e, th, kappa, f, 6.0, SPEED)

    # the start: R at e = 0.5 beside the arc's start, heading 0.05 off
    res = fws.simulate(PLANT, ARC, ctrl, initial_state=(0.0, 0.5, 0.05),
                       duration=4.0, dt=0.05, engine="compiled")  # fmt: skip
    assert res.engine == "compiled" and res.status == "ok"
    z0 = [float(res.s[0]), float(res.e[0]), float(res.theta[0])]
    ref = _reference(law, kappa, f, SPEED, z0, np.asarray(res.t))
    assert np.max(np.abs(res.e - ref[1])) <= 1e-6
    assert np.max(np.abs(res.theta - ref[2])) <= 1e-6
    assert np.max(np.abs(res.s - ref[0])) <= 1e-6


# The controllers' signals and peaks in compiled code against the numpy
# engine's formulas (compute_outputs, exact_peaks) on the same compiled
# states. The compiled law reads the path from its geometry table (within
# 1e-10 m / rad of the path) where numpy reads the path itself: the angles
# differ by about 1e-10 times the gains. The central-difference rate
# (step 1e-6 s) divides that by nothing new: both difference their own
# smooth law, so the table's error cancels to its slope's (about 1e-10 /s),
# and rounding leaves eps |delta| / 1e-6 s ~ 1e-10 rad/s.


@pytest.mark.parametrize(
    ("name", "model", "lag", "duration"),
    [
        ("stanley", "kinematic", None, 2.5),
        ("pure_pursuit", "kinematic", None, 2.5),
        ("rear_wheel", "kinematic", None, 2.5),
        ("lqr", "kinematic", None, 2.5),
        # to the end of the open course: the rate one-sided at its end
        ("stanley", "kinematic", None, 15.0),
        ("pure_pursuit", "dynamic", None, 2.5),
        ("stanley", "kinematic", 0.1, 2.5),
    ],
)
def test_compiled_signals_and_peaks_are_the_numpy_formulas(name, model, lag,
                                                           duration):  # fmt: skip
    from fws_control.simulation.compiled_laws import controller_outputs
    from fws_control.simulation.signals import compute_outputs

    veh = DYN_VEH if model == "dynamic" else VEH
    ctrl = _controllers()[name]
    path = _lane_change()
    x0 = np.array([[0.0, 0.4, 0.05], [3.0, -0.8, 0.0]])
    n = len(x0)
    speed = np.full(n, SPEED)
    t = np.arange(0.0, duration + 1e-9, 0.01)
    sol = []
    kw = dict(speed=speed, feedforward=True, time_constant=lag, model=model,
              tyre="linear")  # fmt: skip
    states, status, _, t_stop, _ = compiled.integrate_compiled(
        veh, path, ctrl, path_state=x0, t_eval=t, solution=sol,
        body_state=np.full((n, 2), np.nan) if model == "dynamic" else None, **kw,
    )  # fmt: skip
    if duration > 10.0:
        assert set(status) == {"end_of_path"} and np.all(t_stop < duration)
    got = compiled.compiled_outputs(
        veh, path, ctrl, states=states, initial_heading=np.zeros(n), **kw
    )
    ref = compute_outputs(
        veh, path, ctrl, states=states, initial_heading=np.zeros(n), **kw
    )
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    for j, sig in enumerate(SIGNALS):
        a, b = got[:, j], ref[:, j]
        ok = np.isfinite(b)
        scale = 1.0 + np.max(np.abs(b[ok]), initial=0.0)
        assert np.max(np.abs(a[ok] - b[ok]), initial=0.0) <= 1e-8 * scale, sig
    peaks, times = compiled.compiled_peaks(
        veh, path, ctrl, solution=sol[0], t_eval=t, signals=got, t_stop=t_stop, **kw
    )
    _, ref_peaks, _ = controller_outputs(
        veh, path, ctrl, states=states, initial_heading=np.zeros(n),
        solution=sol[0], t_eval=t, t_stop=t_stop, **kw,
    )  # fmt: skip
    np.testing.assert_allclose(peaks, ref_peaks, rtol=1e-8, atol=1e-10)
    assert np.all((times >= 0.0) & (times <= t_stop[:, None]))


# --------------------------------------------------------------------------
# (c) routing


def test_auto_runs_baselines_compiled_and_refuses_what_it_cannot():
    path = _lane_change()
    for ctrl in _controllers().values():
        assert law_code(ctrl) > 0
        res = fws.simulate(PLANT, path, ctrl, initial_state=(0.0, 0.3, 0.0),
                           duration=0.5)  # fmt: skip
        assert res.engine == "compiled", ctrl.label
    # an input delay: compiled too (test_compiled_baseline_with_delay_agrees_with_numpy)
    st = fws.Stanley()
    res = fws.simulate(PLANT, path, st, initial_state=(0.0, 0.3, 0.0),
                       duration=0.3, delay=0.05)  # fmt: skip
    assert res.engine == "compiled"
    # Radau: the numpy engine, and "compiled" says why
    res = fws.simulate(PLANT, path, st, initial_state=(0.0, 0.3, 0.0),
                       duration=0.3, method="Radau")  # fmt: skip
    assert res.engine == "numpy"
    with pytest.raises(ValueError, match="compiled law runs with method='DOP853'"):
        fws.simulate(PLANT, path, st, initial_state=(0.0, 0.3, 0.0), duration=0.3,
                     method="Radau", engine="compiled")  # fmt: skip


def test_a_subclass_that_changes_the_law_is_not_compiled():
    class Halved(fws.Stanley):
        def steering(self, vehicle, path, **kw):
            df, dr = super().steering(vehicle, path, **kw)
            return 0.5 * df, 0.5 * dr

    ctrl = Halved(gain=1.0)
    assert ctrl.compiled_law() is None and law_code(ctrl) == -1
    res = fws.simulate(PLANT, fws.Straight(), ctrl, initial_state=(0.0, 0.3, 0.0),
                       duration=0.2)  # fmt: skip
    assert res.engine == "numpy"
