"""The dynamic single-track model on the compiled engine.

References: the numpy engine (stacked runs, scipy's DOP853, the same
equations through :mod:`fws_control.dynamics`, its own signals and exact
peaks); and the closed loop written here from the formulas (slip angles,
linear and magic tyre forces, the body equations and the path kinematics
of the rear axle) integrated by :func:`scipy.integrate.solve_ivp`, 100x
tighter.
"""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control.simulation.engine import PEAK_SIGNALS, SIGNALS

pytest.importorskip(
    "numba", reason="numba is not installed: the compiled engine (extra 'fast') "
    "is not tested"
)  # fmt: skip

from fws_control.simulation.compiled import (  # noqa: E402
    compiled_support,
    integrate_compiled,
)

DYN = fws.Vehicle(
    wheelbase=2.7, rear_to_cg=1.2, mass=1500.0, yaw_inertia=2600.0,
    cornering_front=8.0e4, cornering_rear=9.5e4, friction=1.0,
)  # fmt: skip
ARC = fws.Arc(curvature=0.1)
TOL = {"rtol": 1e-10, "atol": 1e-12}


@pytest.mark.parametrize(
    ("tyre", "lag", "delay", "max_front"),
    [
        ("linear", None, 0.0, None),
        ("linear", 0.27, 0.0, None),
        ("magic", None, 0.0, None),
        ("magic", 0.27, 0.0, None),
        # an input delay (the method of steps); with the front angle clipped
        # at the start (the command of the 5 m error exceeds 0.3 rad)
        ("linear", None, 0.1, None),
        ("magic", 0.27, 0.24, None),
        ("magic", None, 0.1, 0.3),
    ],
)
def test_simulate_agrees_with_numpy_engine(tyre, lag, delay, max_front):
    """The curve scenario on the dynamic model: signals within 3e-7 of
    each signal's largest value (the two integrations at rtol 1e-10 round
    differently and their steps part, as along any run: measured 9e-8 on
    the front slip angle, 1.2e-8 on the lateral acceleration, both engines
    within 5 tolerances of the formulas, test_against_the_formulas) and
    the exact peaks to 1e-9 (the kinematic agreement,
    tests/test_compiled_peaks.py). With a delay the signals agree to 6e-11
    (measured); with the clip, whose release puts the front rate's peak on a
    kink that each engine locates with its own steps (with a delay the
    clips are min/max in the right-hand side, not switch events), that
    peak to 6.6e-9 relative: 1e-7 there."""
    veh = DYN
    if max_front is not None:
        veh = dataclasses.replace(DYN, max_steer_front=max_front)
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    plant = fws.LateralPlant(veh, speed=5.0, model="dynamic", tyre=tyre,
                             steering_lag=lag)  # fmt: skip
    kw = dict(initial_state=(0.0, -5.0, 0.0), duration=15.0, dt=0.3,
              method="DOP853", delay=delay, **TOL)  # fmt: skip
    ref = fws.simulate(plant, ARC, g, **kw, engine="numpy")
    got = fws.simulate(plant, ARC, g, **kw)  # auto: compiled
    assert got.engine == "compiled" and ref.engine == "numpy"
    assert got.status == ref.status == "ok"
    scale = np.nanmax(np.abs(ref.signals[0]), axis=1, keepdims=True)
    err = np.abs(got.signals[0] - ref.signals[0]) / np.maximum(scale, 1e-300)
    for r, sig in enumerate(SIGNALS):
        assert np.nanmax(err[r]) <= 3e-7, sig
    # the dynamic model slips: its slip angles are not the kinematic zeros
    assert np.nanmax(np.abs(got.signals[0, SIGNALS.index("slip_front")])) > 1e-3
    if max_front is not None:  # the clip acts: the angle rests at its limit
        assert np.max(np.abs(got.delta_f)) == pytest.approx(max_front, abs=1e-12)
    rel = 1e-9 if max_front is None else 1e-7
    for sig in PEAK_SIGNALS:
        p, r = getattr(got.peaks, sig), getattr(ref.peaks, sig)
        assert p.value == pytest.approx(r.value, rel=rel, abs=1e-12), sig


def _model(vehicle, kappa, u, *, magic):
    """The dynamic model's derivatives at a given steering (math only):
    ``model(y, df, dr)`` of ``y = (s, e, theta, v_y, r)``, and the slip
    angles ``slips(y, df, dr)``."""
    f, l_r = vehicle.wheelbase, vehicle.rear_to_cg
    l_f = f - l_r
    m, iz = vehicle.mass, vehicle.yaw_inertia
    c_f, c_r = vehicle.cornering_front, vehicle.cornering_rear
    g0 = 9.81  # [m/s^2], the value of fws_control.dynamics.GRAVITY
    d_f = vehicle.friction * m * g0 * l_r / f  # static axle loads times mu
    d_r = vehicle.friction * m * g0 * l_f / f

    def force(alpha, c, d):
        if not magic:
            return c * alpha
        return d * math.sin(1.3 * math.atan(c / (1.3 * d) * alpha))

    def slips(y, df, dr):
        vy, r = y[3], y[4]
        return df - math.atan2(vy + l_f * r, u), dr - math.atan2(vy - l_r * r, u)

    def model(y, df, dr):
        s, e, th, vy, r = y
        alpha_f, alpha_r = slips(y, df, dr)
        ff = force(alpha_f, c_f, d_f) * math.cos(df)
        fr = force(alpha_r, c_r, d_r) * math.cos(dr)
        v_r = vy - l_r * r  # lateral velocity of R
        s_dot = (u * math.cos(th) - v_r * math.sin(th)) / (1 - kappa * e)
        return [
            s_dot,
            u * math.sin(th) + v_r * math.cos(th),
            r - kappa * s_dot,
            (ff + fr) / m - u * r,
            (l_f * ff - l_r * fr) / iz,
        ]

    return model, slips


def _reference(vehicle, kappa, k1, k2, a, u, y0, t, *, magic):
    """The closed loop on the dynamic model from the formulas (math only)."""
    f = vehicle.wheelbase
    model, _ = _model(vehicle, kappa, u, magic=magic)

    def rhs(_, y):
        fb = -k1 * y[1] - k2 * y[2]
        return model(y, fb + math.atan(kappa * f), a * fb)

    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method="DOP853", t_eval=t,
                    rtol=1e-12, atol=1e-14)  # fmt: skip
    return sol.y


@pytest.mark.parametrize("magic", [False, True], ids=["linear", "magic"])
def test_against_the_formulas(magic):
    """At rtol 1e-10 within 100x the tolerance (on each state's largest
    value) of the loop written here at 1e-12; the initial body state given."""
    kappa, u = 0.1, 8.0
    k1, k2, a = 0.3, 0.9, -0.5
    z0 = np.array([0.0, -1.0, 0.05])
    body = np.array([0.1, 0.2])
    t = np.linspace(0.0, 10.0, 101)
    states, status, _, _, _ = integrate_compiled(
        DYN, fws.Arc(kappa), fws.SteeringGains(k1, k2, a), speed=np.array([u]),
        feedforward=True, path_state=z0[None], t_eval=t, time_constant=None,
        model="dynamic", tyre="magic" if magic else "linear",
        body_state=body[None], **TOL,
    )  # fmt: skip
    assert status[0] == "ok"
    ref = _reference(DYN, kappa, k1, k2, a, u, np.concatenate([z0, body]), t,
                     magic=magic)  # fmt: skip
    scale = np.max(np.abs(ref), axis=1, keepdims=True)
    err = np.abs(states[:, 0, :] - ref)
    assert np.all(err <= 100 * (TOL["rtol"] * scale + TOL["atol"]))


@pytest.mark.parametrize("magic", [False, True], ids=["linear", "magic"])
def test_delay_against_the_formulas(magic):
    """An input delay D: the paper's law on the state at t - D (the initial
    one before the start), the method of steps written here (solve_ivp on
    each interval [k D, (k + 1) D] at rtol 1e-12, the delayed state from
    the previous intervals' dense output). At rtol 1e-10 the states, the
    steering, its rate (the law's derivative along the delayed motion),
    the slip angles and the lateral acceleration dv_y/dt + u r, within 100x
    the tolerance of each signal's largest value, as the undelayed test
    (measured: at most 4 tolerances, v_y with the magic tyre)."""
    kappa, u, delay = 0.1, 8.0, 0.2
    # (the undelayed test's gains 0.3, 0.9 lose this loop with the delay:
    # singular steering after 3.4 s)
    k1, k2, a = 0.1, 0.5, -0.5
    f = DYN.wheelbase
    y0 = np.array([0.0, -1.0, 0.05, 0.1, 0.2])
    model, slips = _model(DYN, kappa, u, magic=magic)
    pieces = []  # (t_lo, t_hi, dense) of the intervals done

    def past(tt):
        if tt <= 0.0:
            return y0
        for lo, hi, dense in pieces:
            # (hi + 1e-12: an interval's stages reach lo + delay rounded up)
            if lo <= tt <= hi + 1e-12:
                return dense(tt)
        raise AssertionError(tt)

    def command(tt):
        fb = -k1 * past(tt - delay)[1] - k2 * past(tt - delay)[2]
        return fb + math.atan(kappa * f), a * fb  # feedforward on the arc

    def rhs(tt, y):
        return model(y, *command(tt))

    t_end, lo, y = 6.0, 0.0, y0
    while lo < t_end - 1e-12:
        hi = min(lo + delay, t_end)
        sol = solve_ivp(rhs, (lo, hi), y, method="DOP853", rtol=1e-12,
                        atol=1e-14, dense_output=True)  # fmt: skip
        pieces.append((lo, hi, sol.sol))
        lo, y = hi, sol.y[:, -1]
    plant = fws.LateralPlant(DYN, speed=u, model="dynamic",
                             tyre="magic" if magic else "linear")  # fmt: skip
    path = fws.Arc(kappa)
    # the pose (x, y, psi) of the path state (0, -1, 0.05) on the arc: e to
    # the left of the path's heading
    (px, py), h0 = path.position(0.0), path.heading(0.0)
    e0, th0 = y0[1], y0[2]
    start = (px - e0 * math.sin(h0), py + e0 * math.cos(h0), h0 + th0, *y0[3:])
    res = fws.simulate(plant, path, fws.SteeringGains(k1, k2, a),
                       initial_state=start, duration=t_end, dt=0.05, delay=delay,
                       **TOL)  # fmt: skip
    assert res.engine == "compiled" and res.status == "ok"
    ref = {name: [] for name in ("s", "e", "theta", "v_y", "yaw_rate", "delta_f",
                                 "delta_r", "delta_f_rate", "slip_front",
                                 "slip_rear", "lateral_accel")}  # fmt: skip
    for tt in res.t:
        y = past(tt)
        df, dr = command(tt)
        ydot = model(y, df, dr)
        td = tt - delay
        # d/dt of the law on the delayed state: its derivative at t - D (0
        # while the initial state is held)
        yd_dot = model(past(td), *command(td)) if td > 0.0 else [0.0] * 5
        rate = -k1 * yd_dot[1] - k2 * yd_dot[2]  # (the feedforward is constant)
        values = (*y, df, dr, rate, *slips(y, df, dr), ydot[3] + u * y[4])
        for name, val in zip(ref, values, strict=True):
            ref[name].append(val)
    for name, val in ref.items():
        val = np.asarray(val)
        err = np.max(np.abs(getattr(res, name) - val))
        scale = np.max(np.abs(val))
        assert err <= 100 * (TOL["rtol"] * scale + TOL["atol"]), (name, err, scale)
    # the delay acts: the angle is the initial state's command until t = D
    assert np.all(res.delta_f[res.t < delay - 1e-9] == res.delta_f[0])


def test_default_body_state_rolls_without_slip():
    """NaN body state: both slip angles zero at the start (no-slip motion at
    the initial command), by hand from the slip-angle definitions."""
    g = fws.SteeringGains(0.3, 0.9, -0.5)
    z0 = np.array([[0.0, -1.0, 0.05]])
    states = integrate_compiled(
        DYN, ARC, g, speed=np.array([8.0]), feedforward=True, path_state=z0,
        t_eval=np.array([0.0, 0.1]), time_constant=None, model="dynamic",
        body_state=np.full((1, 2), np.nan),
    )[0]  # fmt: skip
    vy, r = states[3, 0, 0], states[4, 0, 0]
    fb = -0.3 * -1.0 - 0.9 * 0.05
    df, dr = fb + math.atan(0.1 * 2.7), -0.5 * fb
    l_r = 1.2
    assert df - math.atan2(vy + 1.5 * r, 8.0) == pytest.approx(0.0, abs=1e-15)
    assert dr - math.atan2(vy - l_r * r, 8.0) == pytest.approx(0.0, abs=1e-15)


def test_support():
    g = fws.SteeringGains(0.1, 0.5, 0.0)
    assert compiled_support(ARC, g, model="dynamic") is None
    assert "DOP853" in compiled_support(ARC, g, model="dynamic", method="Radau")
    assert compiled_support(ARC, g, model="dynamic", delay=0.24) is None
    assert "DOP853" in compiled_support(
        ARC, g, model="dynamic", delay=0.24, method="Radau"
    )
