"""The compiled per-run engine against scipy, run by run.

References, all written here from the formulas: the closed-loop right-hand
side (corrected eqs. 17-19 with the paper's law, eqs. 24-29, and the
rate-limited first-order actuator) and its stop events, integrated by
:func:`scipy.integrate.solve_ivp` / :class:`scipy.integrate.DOP853`. The
compiled engine is a port of scipy's DOP853, so it must take the same steps
(times to 1e-12 relative), give the same dense output at ``t_eval`` and the
same event times; and since each run is integrated alone, a run's result in
a batch must be bitwise the result of the same run alone.
"""

import math

import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import DOP853, solve_ivp

import fws_control as fws

numba = pytest.importorskip(
    "numba", reason="numba is not installed: the compiled engine (extra 'fast') "
    "is not tested"
)  # fmt: skip

from fws_control.simulation import compiled  # noqa: E402
from fws_control.simulation.compiled import (  # noqa: E402
    DEFAULT_MARGIN,
    CurvatureTable,
    compiled_support,
    curvature_table,
    integrate_compiled,
    shared_parameters,
)
from fws_control.simulation.compiled_variants import variant  # noqa: E402

# The kernels these tests call one step at a time, as the engine compiles
# them for a call without a delay, the dynamic model, a controller's law or
# a varying speed (none of these tests uses one): the code that runs for
# such a call (test_kernel_cache checks it bit for bit against the full
# kernels), and a third of the full kernels' compilation, which no
# production call makes from Python.
closed_loop_rhs, dense_output, dop853_step, locate_event = (
    variant(getattr(compiled, name), ())
    for name in ("closed_loop_rhs", "dense_output", "dop853_step", "locate_event")
)

VEH = PAPER_VEHICLE
TOL = {"rtol": 1e-10, "atol": 1e-12}


# --------------------------------------------------------------------------
# The reference, from the formulas


def reference_rhs(vehicle, kappa_of_s, k1, k2, a, V, *, ff=True, tau=None):
    """Closed loop of one run as a scalar right-hand side (math only)."""
    f = vehicle.wheelbase
    mf = math.inf if vehicle.max_steer_front is None else vehicle.max_steer_front
    mr = math.inf if vehicle.max_steer_rear is None else vehicle.max_steer_rear
    rf_max = (
        math.inf
        if vehicle.max_steer_rate_front is None
        else vehicle.max_steer_rate_front
    )
    rr_max = (
        math.inf if vehicle.max_steer_rate_rear is None else vehicle.max_steer_rate_rear
    )

    def command(e, th, kap):
        fb = -k1 * e - k2 * th  # feedback, eqs. (28)-(29)
        cf = fb + math.atan(kap * f) if ff else fb  # + feedforward, eq. (26)
        return min(max(cf, -mf), mf), min(max(a * fb, -mr), mr)

    def rhs(t, y):
        s, e, th = y[0], y[1], y[2]
        kap = kappa_of_s(s)
        cf, cr = command(e, th, kap)
        df, dr = (y[3], y[4]) if tau else (cf, cr)
        s_dot = V * math.cos(th + dr) / (1 - kap * e)
        out = [
            s_dot,
            V * math.sin(th + dr),
            -kap * s_dot + V * math.sin(df - dr) / (f * math.cos(df)),
        ]
        if tau:
            out += [
                min(max((cf - df) / tau, -rf_max), rf_max),
                min(max((cr - dr) / tau, -rr_max), rr_max),
            ]
        return np.array(out)

    def events(length=math.inf, margin=DEFAULT_MARGIN):
        def steer(t, y):
            df = y[3] if tau else command(y[1], y[2], kappa_of_s(y[0]))[0]
            return (math.pi / 2 - margin) - abs(df)

        def curv(t, y):
            return (1 - kappa_of_s(y[0]) * y[1]) - margin

        evs = [steer, curv]
        if math.isfinite(length):
            evs += [lambda t, y: (length - y[0]) / length + 1e-9]
        for ev in evs:
            ev.terminal, ev.direction = True, -1
        return evs

    return rhs, command, events


def _const(k):
    return lambda s: k


def _run_alone(path, k1, k2, a, V, z0, t, **kw):
    g = fws.SteeringGains(np.array([k1]), k2, a)
    return integrate_compiled(
        kw.pop("vehicle", VEH), path, g, speed=np.array([V]),
        feedforward=kw.pop("feedforward", True), path_state=np.array([z0]),
        t_eval=t, time_constant=kw.pop("time_constant", None), **TOL, **kw,
    )  # fmt: skip


def _scale(y):
    return TOL["atol"] + TOL["rtol"] * np.abs(y)


# --------------------------------------------------------------------------
# Right-hand side


@settings(max_examples=40)
@given(
    e=st.floats(-3, 3),
    th=st.floats(-1, 1),
    s=st.floats(0, 50),
    k1=st.floats(0.0, 2.0),
    k2=st.floats(0.0, 3.0),
    a=st.floats(-2, 2),
    act=st.booleans(),
)
def test_rhs_matches_formulas(e, th, s, k1, k2, a, act):
    veh = fws.Vehicle(
        2.7, 1.35, max_steer_front=0.6, max_steer_rear=0.3,
        max_steer_rate_front=0.4, max_steer_rate_rear=0.2,
    )  # fmt: skip
    path = fws.Clothoid(0.02, -0.08, length=50.0)
    tau = 0.05 if act else None
    # the clothoid's curvature, linear in s: 0.02 -> -0.08 over 50 m
    rhs, _, _ = reference_rhs(
        veh, lambda s: 0.02 - 0.1 * s / 50, k1, k2, a, 7.0, tau=tau
    )
    y = np.array([s, e, th, 0.1, -0.05][: 5 if act else 3])
    tab = curvature_table(path)
    q = shared_parameters(veh, tab, feedforward=True, time_constant=tau)
    out = np.empty(y.size)
    closed_loop_rhs(0.0, y, np.array([7.0, k1, k2, a]), q, tab.breaks, tab.coefs, out)
    np.testing.assert_allclose(out, rhs(0.0, y), rtol=1e-13, atol=1e-13)


def test_curvature_tables():
    clo = fws.Clothoid(0.01, 0.1, length=30.0)
    chain = fws.PathChain(
        [
            fws.Straight(length=20.0),
            fws.Clothoid(0.0, 0.1, 10.0),
            fws.Arc(0.1, length=20.0),
        ]
    )
    s = np.linspace(0.0, 50.0, 1001)
    for path in (clo, chain):
        tab = curvature_table(path)
        assert tab.max_error == 0.0 and tab.open_length == path.length
        np.testing.assert_allclose(tab(np.clip(s, 0, path.length)),
                                   path.curvature(np.clip(s, 0, path.length)),
                                   rtol=0, atol=1e-15)  # fmt: skip
    # at a joint the following segment gives the value, as PathChain does
    assert tab(20.0) == chain.curvature(20.0) and tab(30.0) == 0.1
    ring = fws.Arc(curvature=-0.2)
    tab = curvature_table(ring)
    assert tab.period == pytest.approx(2 * math.pi / 0.2) and tab(1e3) == -0.2
    # a spline: the Hermite fit meets its tolerance against path.curvature
    pts = np.array([[0, 0], [10, 2], [20, -1], [30, 3], [40, 0.0]])
    spl = fws.Spline(pts)
    tab = curvature_table(spl, tol=1e-8)
    probe = np.linspace(0.0, spl.length, 7777)
    assert np.max(np.abs(tab(probe) - spl.curvature(probe))) <= 1e-8
    with pytest.raises(ValueError, match="max_pieces"):
        curvature_table(spl, tol=1e-14, max_pieces=128)
    with pytest.raises(ValueError, match="tol"):
        curvature_table(spl, tol=0.0)


def _bits(x: float) -> int:
    return int(np.float64(x).view(np.int64))


_PERIODS = st.floats(1e-6, 1e6)


@settings(max_examples=300)
@given(
    period=_PERIODS,
    s=st.one_of(
        # the laps around 0, where the kernel avoids fmod, and their ends
        st.floats(-3.0, 3.0).map(lambda u: ("laps", u)),
        st.floats(allow_nan=True, allow_infinity=True).map(lambda x: ("any", x)),
        st.sampled_from([-2.0, -1.0, 0.0, 1.0, 2.0]).map(lambda u: ("ends", u)),
    ),
    nudge=st.sampled_from([-1, 0, 1]),
)
def test_lap_wrap_is_python_modulo_bit_for_bit(period, s, nudge):
    """The kernels' lap wrap is ``s % period`` of Python, sign of zero too."""
    from fws_control.simulation import compiled_loop

    kind, u = s
    x = u * period if kind in ("laps", "ends") else u
    if nudge and math.isfinite(x):
        x = math.nextafter(x, nudge * math.inf)
    for value in (x, -x):
        want = value % period  # the reference: CPython's float remainder
        got = compiled_loop.wrap_lap(value, period)
        if math.isnan(want):
            assert math.isnan(got)
        else:
            assert _bits(got) == _bits(want), (value, period, got, want)


@pytest.mark.parametrize(
    "path",
    [
        fws.Arc(curvature=0.1),
        fws.Arc(curvature=-0.25, length=20.0),
        fws.Straight(),
        fws.Clothoid(0.02, -0.08, length=50.0),
        fws.PathChain([fws.Arc(0.05, length=10.0), fws.Clothoid(0.05, 0.0, 20.0)]),
    ],
)
def test_feedforward_angle_is_atan_bit_for_bit(path):
    """The feedforward angle kept for the first piece is atan(f kappa)."""
    from fws_control.simulation import compiled_loop

    tab = curvature_table(path)
    q = shared_parameters(VEH, tab, feedforward=True, time_constant=None)
    s = np.linspace(-5.0, 80.0, 1701)
    kappa = np.concatenate([tab(s), [tab.coefs[0, 0], 0.0, 1e-3, -1e-3]])
    for k in kappa:
        want = math.atan(VEH.wheelbase * k)  # CPython's, the C library's atan
        assert _bits(compiled_loop.feedforward_angle(k, q)) == _bits(want), k
    # through the public right-hand side: the paper's law with the angle
    # recomputed by the reference formulas (test_rhs_matches_formulas)
    y = np.array([3.0, 0.4, -0.1])
    out = np.empty(3)
    p = np.array([5.0, 0.2, 0.7, -0.4])
    closed_loop_rhs(0.0, y, p, q, tab.breaks, tab.coefs, out)
    rhs, _, _ = reference_rhs(VEH, lambda s: float(tab(s)), 0.2, 0.7, -0.4, 5.0)
    np.testing.assert_allclose(out, rhs(0.0, y), rtol=1e-14, atol=1e-15)


# --------------------------------------------------------------------------
# The port against scipy's DOP853, step by step
#
# Why steps are compared from identical inputs: DOP853's error estimate is
# a sum of O(|f|) stage terms that cancels to O(h^8); at rtol = 1e-10 it
# carries a rounding noise of up to ~1e-6 relative (100 % in the first step,
# where |K|/|err| ~ 1e16), so any other summation order -- numpy's BLAS dot
# in scipy against the stage-ordered loops here, or scipy on two BLAS builds
# -- moves the next step size by ~1e-7 relative. Given the same (t, y, f,
# h), the port must give the same accepted step t_new (bitwise), y_new and
# f(y_new) to rounding, the same dense output, and a next step size within
# that noise; whole trajectories then take the same number of steps, at
# times within 1e-5 relative, and agree far below the tolerance.


def _step_case(name):
    if name == "arc":
        return fws.Arc(curvature=0.1), _const(0.1), None, VEH
    if name == "clothoid":
        path = fws.Clothoid(0.0, 0.05, length=200.0)
        return path, lambda s: 0.05 * s / 200.0, None, VEH
    veh = fws.Vehicle(2.7, 1.35, max_steer_rate_front=0.3, max_steer_rate_rear=0.3)
    return fws.Arc(curvature=0.1), _const(0.1), 0.1, veh


def _engine_run(veh, tab, g, y0, t_eval, tau, max_step=math.inf):
    """One run of integrate_compiled (the engine's batch driver, as the
    shared parameters of these tests: no switch events): its accepted steps,
    their end times and its states at `t_eval`."""
    sol = []
    states, status, _, t_stop, stats = integrate_compiled(
        veh, tab, fws.SteeringGains(np.atleast_1d(g.k1), g.k2, g.ratio),
        speed=np.array([5.0]), feedforward=True, path_state=y0[None, :3],
        t_eval=t_eval, time_constant=tau, switching=False, max_step=max_step,
        solution=sol, **TOL,
    )  # fmt: skip
    assert (status[0], t_stop[0]) == ("ok", 15.0)
    records = sol[0].records
    assert stats[0, 0] == len(records)  # (no cut step: no event, no switch)
    return int(stats[0, 0]), records[:, 0] + records[:, 1], states[:, 0, :]


@pytest.mark.parametrize("name", ["arc", "clothoid", "rate-limited-actuator"])
def test_same_steps_dense_output_as_scipy(name):
    path, kappa, tau, veh = _step_case(name)
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    k1, k2, a = float(g.k1), float(g.k2), float(g.ratio)
    rhs, command, _ = reference_rhs(veh, kappa, k1, k2, a, 5.0, tau=tau)
    y0 = [0.0, -5.0, 0.0]
    if tau:
        y0 += list(command(-5.0, 0.0, kappa(0.0)))
    y0 = np.array(y0)
    m = y0.size
    tab = curvature_table(path)
    q = shared_parameters(veh, tab, feedforward=True, time_constant=tau)
    p = np.array([5.0, k1, k2, a])
    K, y_new, ystage, val = np.empty((16, m)), np.empty(m), np.empty(m), np.empty(m)

    solver = DOP853(rhs, 0.0, y0, 15.0, **TOL)
    ref_times, worst_h, n_rejected = [], 0.0, 0
    while solver.status == "running":
        t, y, f, h_abs = solver.t, solver.y.copy(), solver.f.copy(), solver.h_abs
        solver.step()
        ref_times.append(solver.t)
        ok, t_new, _, h_next, rejected = dop853_step(
            t, y, f, h_abs, 15.0, TOL["rtol"], TOL["atol"], p, q, tab.breaks,
            tab.coefs, K, y_new, ystage,
        )  # fmt: skip
        assert ok
        if rejected:  # the retried step size carries the noise (see above)
            assert abs(t_new - solver.t) <= 1e-5 * (solver.t - t)
            n_rejected += 1
            continue
        assert t_new == solver.t
        # rounding of the two orders of operations accumulates over the
        # run's steps (measured 1.03e-15 on a rate-limited state with scipy
        # 1.17)
        np.testing.assert_allclose(y_new, solver.y, rtol=1e-14, atol=4e-15)
        np.testing.assert_allclose(K[12], solver.f, rtol=1e-13, atol=1e-14)
        worst_h = max(worst_h, abs(h_next / solver.h_abs - 1))
        ref_dense = solver.dense_output()
        for x in (0.1, 0.5, 0.9):
            tt = t + x * (t_new - t)
            dense_output(tt, t, t_new, y, y_new, K[12].copy(), K, p, q,
                         tab.breaks, tab.coefs, val)  # fmt: skip
            np.testing.assert_allclose(val, ref_dense(tt), rtol=1e-14, atol=4e-15)
    assert solver.status == "finished"
    assert n_rejected <= 0.25 * len(ref_times)  # most steps compared exactly
    # the error estimate's rounding noise (see above); larger on the steps
    # across the rate clip's kinks, where the estimate is small differences
    # of a non-smooth right-hand side
    assert worst_h < (1e-3 if tau else 1e-5)

    # whole run, through the engine's batch driver: the same number of
    # steps, times within the noise
    t_eval = np.linspace(0.0, 15.0, 1501)
    steps, trace, out = _engine_run(veh, tab, g, y0, t_eval, tau)
    ref = solve_ivp(rhs, (0.0, 15.0), y0, method="DOP853", t_eval=t_eval, **TOL)
    if tau:
        # across the unlocated kinks of the rate clip the accept/reject
        # decisions follow the noise: 74 steps here against scipy's 77; the
        # outputs still agree to the tolerance
        assert abs(steps - len(ref_times)) <= 0.1 * len(ref_times)
        # (both solutions err at the unlocated kinks: measured 1.7e-9 on s,
        # which reaches 70 m, i.e. 2.5e-11 relative, with scipy 1.17)
        assert np.max(np.abs(out - ref.y)) <= 5e-9
        return
    assert steps == len(ref_times)
    np.testing.assert_allclose(trace[:steps], ref_times, rtol=1e-5)
    assert np.all(np.abs(out - ref.y) <= 0.1 * _scale(ref.y))


def test_max_step_as_scipy_and_accurate_on_a_stiff_actuator():
    """max_step as scipy's DOP853(max_step=): the same steps from the same
    inputs, the same whole run; at half the actuator's stability bound
    (3.2 T) the run agrees with a tight solve_ivp where the unbounded one,
    stepping at the bound, does not."""
    tau, max_step = 0.05, 3.2 * 0.05
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-0.5, pole=-1.0)
    k1, k2, a = float(g.k1), float(g.k2), float(g.ratio)
    kappa = _const(0.1)
    rhs, command, _ = reference_rhs(VEH, kappa, k1, k2, a, 5.0, tau=tau)
    y0 = np.array([0.0, -5.0, 0.0, *command(-5.0, 0.0, 0.1)])
    tab = curvature_table(fws.Arc(curvature=0.1))
    q = shared_parameters(VEH, tab, feedforward=True, time_constant=tau,
                          max_step=max_step)  # fmt: skip
    p = np.array([5.0, k1, k2, a])
    K, y_new, ystage = np.empty((16, 5)), np.empty(5), np.empty(5)
    solver = DOP853(rhs, 0.0, y0, 15.0, max_step=max_step, **TOL)
    times = []
    while solver.status == "running":
        t, y, f, h_abs = solver.t, solver.y.copy(), solver.f.copy(), solver.h_abs
        solver.step()
        times.append(solver.t)
        ok, t_new, *_, rejected = dop853_step(
            t, y, f, h_abs, 15.0, TOL["rtol"], TOL["atol"], p, q, tab.breaks,
            tab.coefs, K, y_new, ystage,
        )  # fmt: skip
        assert ok
        if not rejected:
            assert t_new == solver.t
            assert t_new - t <= max_step * (1 + 1e-12)  # (t + h - t: rounding)
            np.testing.assert_allclose(y_new, solver.y, rtol=1e-14, atol=1e-15)
    steps = np.diff([0.0, *times])
    assert np.max(steps) == pytest.approx(max_step)  # the cap binds
    t_eval = np.linspace(0.0, 15.0, 31)
    ref = solve_ivp(rhs, (0.0, 15.0), y0, method="Radau", t_eval=t_eval,
                    rtol=1e-12, atol=1e-14).y  # fmt: skip
    tol = TOL["atol"] + TOL["rtol"] * np.max(np.abs(ref), axis=1, keepdims=True)
    units = {}
    for cap in (max_step, math.inf):
        n_steps, _, out = _engine_run(VEH, tab, g, y0, t_eval, tau, max_step=cap)
        if cap == max_step:
            assert n_steps == len(times)
        units[cap] = float(np.max(np.abs(out - ref) / tol))
    assert units[max_step] <= 20.0 < 100.0 < units[math.inf], units


def test_event_root_as_scipy_on_the_same_step():
    """brentq on the dense output: scipy's root on scipy's step, to 1e-12."""
    k1, k2 = 0.5, -2.0  # k2 < 0: |delta_f| grows to pi/2 - margin
    rhs, _, events = reference_rhs(VEH, _const(0.0), k1, k2, 0.0, 5.0, ff=False)
    steer = events()[0]
    tab = curvature_table(fws.Straight())
    q = shared_parameters(VEH, tab, feedforward=False, time_constant=None)
    p = np.array([5.0, k1, k2, 0.0])
    K, y_new, ystage = np.empty((16, 3)), np.empty(3), np.empty(3)
    solver = DOP853(rhs, 0.0, np.array([0.0, 2.0, 0.0]), 20.0, **TOL)
    while True:
        t, y, f, h_abs = solver.t, solver.y.copy(), solver.f.copy(), solver.h_abs
        solver.step()
        if steer(solver.t, solver.y) <= 0:
            break
    from scipy.optimize import brentq

    eps = np.finfo(float).eps
    dense = solver.dense_output()
    t_ref = brentq(lambda x: steer(x, dense(x)), t, solver.t, xtol=4 * eps,
                   rtol=4 * eps)  # fmt: skip
    ok, t_new, *_ = dop853_step(
        t, y, f, h_abs, 20.0, TOL["rtol"], TOL["atol"], p, q, tab.breaks,
        tab.coefs, K, y_new, ystage,
    )  # fmt: skip
    assert ok and t_new == solver.t
    root = locate_event(0, t, t_new, y, y_new, K[12].copy(), K, p, q,
                        tab.breaks, tab.coefs)  # fmt: skip
    assert root == pytest.approx(t_ref, rel=1e-12, abs=0)
    assert t < root < t_new


# --------------------------------------------------------------------------
# Each stop condition: the same event time as solve_ivp


@pytest.mark.parametrize(
    ("case", "status"),
    [("steer", "singular_steering"), ("curvature", "singular_curvature"),
     ("end", "end_of_path")],
)  # fmt: skip
def test_event_times_as_solve_ivp(case, status):
    if case == "steer":  # k2 < 0: the heading feedback destabilises
        path, k, V, k1, k2, a, z0 = fws.Straight(), 0.0, 5.0, 0.5, -2.0, 0.0, (0, 2, 0)
    elif case == "curvature":  # no steering, heading at the centre of the arc
        path, k, V, k1, k2, a = fws.Arc(0.1), 0.1, 5.0, 0.0, 0.0, 0.0
        z0 = (0.0, 5.0, math.pi / 2)
    else:
        path, k, V, k1, k2, a, z0 = (
            fws.Straight(length=30.0), 0.0, 5.0, 0.1, 0.5, -0.5, (0.0, 1.0, 0.0),
        )  # fmt: skip
    ff = case != "curvature"
    rhs, _, events = reference_rhs(VEH, _const(k), k1, k2, a, V, ff=ff)
    length = math.inf if path.closed else path.length
    t = np.linspace(0.0, 20.0, 2001)
    ref = solve_ivp(
        rhs, (0.0, 20.0), np.array(z0, float), method="DOP853", t_eval=t,
        events=events(length), **TOL,
    )  # fmt: skip
    assert ref.status == 1
    t_ref = min(float(te[0]) for te in ref.t_events if te.size)
    states, st_, msg, t_stop, _ = _run_alone(path, k1, k2, a, V, z0, t, feedforward=ff)
    assert st_[0] == status and f"at t={t_stop[0]:.6g} s" in msg[0]
    # (whole runs: steps differ at the error estimate's noise, see above)
    assert t_stop[0] == pytest.approx(t_ref, rel=1e-9, abs=1e-9)
    n = ref.t.size
    got = states[:, 0, :]
    assert np.all(np.abs(got[:, :n] - ref.y) <= 0.1 * _scale(ref.y))
    assert np.all(np.isnan(got[:, n:]))  # NaN after the stop
    # the stop is where the reference's event function vanishes
    ev = {"steer": 0, "curvature": 1, "end": 2}[case]
    sol = solve_ivp(rhs, (0.0, t_ref), np.array(z0, float), method="DOP853", **TOL)
    evs = events(length)
    assert abs(evs[ev](t_ref, sol.y[:, -1])) < 1e-6


def test_initial_state_at_a_stop():
    # |delta_f| = 0.9 * 2 > pi/2 - margin at t = 0: stopped at once
    states, status, _, t_stop, stats = _run_alone(
        fws.Straight(), 0.9, 0.0, 0.0, 5.0, (0.0, 2.0, 0.0), np.linspace(0, 1, 11)
    )
    assert status[0] == "singular_steering" and t_stop[0] == 0.0
    assert stats[0, 0] == 0 and np.all(states[:, 0, 0] == [0.0, 2.0, 0.0])
    assert np.all(np.isnan(states[:, 0, 1:]))


# --------------------------------------------------------------------------
# Accuracy against the reference at the tolerance


def test_paper_curve_agrees_with_solve_ivp_scalar_rhs():
    """The paper's curve (V = 5, 1/10, a = -1, pole -1): within 10x rtol."""
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    t = np.linspace(0.0, 15.0, 1501)
    rhs, _, _ = reference_rhs(VEH, _const(0.1), float(g.k1), float(g.k2), -1.0, 5.0)
    # an independent reference: the same RHS 100x tighter (rtol 1e-12)
    ref = solve_ivp(rhs, (0, 15), [0.0, -5.0, 0.0], method="DOP853", t_eval=t,
                    rtol=1e-12, atol=1e-14)  # fmt: skip
    states, *_ = _run_alone(fws.Arc(0.1), float(g.k1), float(g.k2), -1.0, 5.0,
                            (0.0, -5.0, 0.0), t)  # fmt: skip
    err = np.abs(states[:, 0, :] - ref.y)
    assert np.all(err <= 10 * (TOL["rtol"] * np.abs(ref.y) + TOL["atol"]) + 1e-9)


# --------------------------------------------------------------------------
# Per-run independence in batches


def _poles_batch(n):
    poles = np.where(np.arange(n) % 2 == 0, -0.2, -5.0)
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=poles)
    return g


def test_mixed_poles_batch_is_bitwise_each_run_alone():
    n = 8
    g = _poles_batch(n)
    t = np.linspace(0.0, 15.0, 1501)
    z0 = np.zeros((n, 3))
    z0[:, 1] = np.linspace(-0.2, 0.2, n)  # (-5 m would saturate the fast design)
    kw = dict(speed=np.full(n, 5.0), feedforward=True, t_eval=t, time_constant=None)
    states, status, _, t_stop, stats = integrate_compiled(
        VEH, fws.Arc(0.1), g, path_state=z0, **kw, **TOL
    )
    assert status.tolist() == ["ok"] * n
    # the fast runs take many more steps; the slow ones are not charged for it
    assert np.all(stats[1::2, 0] > 2 * stats[0::2, 0])
    for i in range(n):
        alone = _run_alone(fws.Arc(0.1), g.k1[i], g.k2[i], -1.0, 5.0, z0[i], t)
        np.testing.assert_array_equal(states[:, i, :], alone[0][:, 0, :])
        np.testing.assert_array_equal(stats[i], alone[4][0])


def test_half_the_runs_stop_others_unchanged():
    n = 8
    t = np.linspace(0.0, 15.0, 1501)
    k1 = np.full(n, 0.5)
    k2 = np.where(np.arange(n) % 2 == 0, -2.0, 1.2)  # even runs diverge and stop
    g = fws.SteeringGains(k1, k2, 0.0)
    z0 = np.tile([0.0, 2.0, 0.0], (n, 1))
    states, status, _, t_stop, _ = integrate_compiled(
        VEH, fws.Straight(), g, speed=np.full(n, 5.0), feedforward=False,
        path_state=z0, t_eval=t, time_constant=None, **TOL,
    )  # fmt: skip
    assert status[0::2].tolist() == ["singular_steering"] * (n // 2)
    assert status[1::2].tolist() == ["ok"] * (n // 2)
    assert np.all(t_stop[0::2] < 5.0) and np.all(t_stop[1::2] == 15.0)
    for i in range(n):
        alone = _run_alone(fws.Straight(), 0.5, k2[i], 0.0, 5.0, z0[i], t,
                           feedforward=False)  # fmt: skip
        np.testing.assert_array_equal(states[:, i, :], alone[0][:, 0, :])
        assert t_stop[i] == alone[3][0]


# --------------------------------------------------------------------------
# Arguments


def test_out_array_and_validation():
    g = fws.SteeringGains(np.array([0.1, 0.2]), 0.5, 0.0)
    t = np.linspace(0.0, 1.0, 5)
    kw = dict(speed=np.array([5.0, 5.0]), feedforward=False,
              path_state=np.array([[0.0, 1.0, 0.0]] * 2), t_eval=t)  # fmt: skip
    buf = np.zeros((2, 5, 5))
    states, *_ = integrate_compiled(VEH, fws.Straight(), g, time_constant=0.1,
                                    out=buf, **kw)  # fmt: skip
    assert np.shares_memory(states, buf) and np.all(np.isfinite(buf))
    # the actuator starts at the initial command -k1 * e
    np.testing.assert_allclose(buf[:, 3, 0], [-0.1, -0.2], rtol=1e-15)
    with pytest.raises(ValueError, match=r"out must be a float64 array of shape"):
        integrate_compiled(VEH, fws.Straight(), g, time_constant=None, out=buf, **kw)
    with pytest.raises(ValueError, match="rtol"):
        integrate_compiled(VEH, fws.Straight(), g, time_constant=None, rtol=0.0, **kw)
    with pytest.raises(ValueError, match="steer_margin"):
        integrate_compiled(VEH, fws.Straight(), g, time_constant=None,
                           steer_margin=2.0, **kw)  # fmt: skip
    with pytest.raises(ValueError, match="breaks"):
        CurvatureTable([0.0, 1.0, 2.0], [[0, 0, 0, 0]])
    assert compiled_support(fws.Straight(), g) is None
    # a baseline declares its compiled law (with a delay too); with Radau it
    # is not compiled
    assert compiled_support(fws.Straight(), fws.PurePursuit()) is None
    assert compiled_support(fws.Straight(), fws.PurePursuit(), delay=0.1) is None
    assert "DOP853" in compiled_support(
        fws.Straight(), fws.PurePursuit(), method="Radau"
    )
    assert "DOP853" in compiled_support(fws.Straight(), g, method="RK45")
    assert compiled_support(fws.Straight(), g, method=DOP853) is None


# --------------------------------------------------------------------------
# Output signals


@pytest.mark.parametrize(
    ("path", "tau", "ff"),
    [
        (fws.Arc(0.1, start=(1.0, 2.0), start_heading=3.0), None, True),
        (fws.Clothoid(0.0, 0.05, length=100.0), None, True),
        (fws.Arc(-0.1), 0.1, True),
        (fws.Straight(start=(1.0, 1.0), start_heading=-2.0), None, False),
        (fws.Straight(length=40.0), None, False),  # half the runs reach the end
    ],
    ids=["arc-placed", "clothoid", "actuator", "straight", "open-line"],
)
def test_outputs_as_numpy_engine_and_finite_differences(path, tau, ff):
    """compiled_outputs == compute_outputs (the numpy engine's output stage),
    and the steering rates are the derivatives of the steering angles."""
    from fws_control.simulation.compiled import compiled_outputs
    from fws_control.simulation.engine import SIGNALS, compute_outputs

    veh = fws.Vehicle(2.7, 1.35, max_steer_front=0.5)
    n = 6
    g = fws.double_root_gains(
        VEH, speed=5.0, curvature=0.1, ratio=np.linspace(-1.5, 0.6, n), pole=-1.0
    )
    t = np.linspace(0.0, 15.0, 3001)
    z0 = np.tile([0.0, -5.0, 0.0], (n, 1))
    z0[:, 0] = np.linspace(0.0, 30.0, n)
    V = np.full(n, 5.0)
    states, status, *_ = integrate_compiled(
        veh, path, g, speed=V, feedforward=ff, path_state=z0, t_eval=t,
        time_constant=tau, **TOL,
    )  # fmt: skip
    kw = dict(speed=V, feedforward=ff, time_constant=tau, states=states,
              initial_heading=np.full(n, 9.0))  # fmt: skip
    ref = compute_outputs(veh, path, g, **kw)
    got = compiled_outputs(veh, path, g, **kw)
    assert np.array_equal(np.isnan(got), np.isnan(ref))
    np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-13)
    # psi starts on the branch of the initial heading 9 rad
    assert np.all(np.abs(got[:, 2, 0] - 9.0) <= math.pi)
    # rates against central differences of the angles (smooth stretches)
    for name in ("delta_f", "delta_r"):
        ang = got[:, SIGNALS.index(name)]
        rate = got[:, SIGNALS.index(name + "_rate")]
        fd = (ang[:, 2:] - ang[:, :-2]) / (t[2] - t[0])
        mid = rate[:, 1:-1]
        smooth = np.isfinite(fd) & (np.abs(ang[:, 1:-1]) < 0.49)  # not clipped
        assert np.all(np.abs(fd - mid)[smooth] <= 1e-3 * (1 + np.abs(mid[smooth])))
    if path == fws.Straight(length=40.0):
        assert "end_of_path" in set(status)


def test_stiff_actuator_is_detected_and_step_bounded_by_stability():
    """A lag T adds the eigenvalue -1/T: DOP853's steps are bounded near 6 T
    (its stability interval on the negative real axis) and Hairer's test
    flags the run; without the actuator the same 15 s run is not stiff."""
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    t = np.linspace(0.0, 15.0, 151)
    args = (fws.Arc(0.1), float(g.k1), float(g.k2), -1.0, 5.0, (0.0, -5.0, 0.0), t)
    *_, plain = _run_alone(*args)
    *_, stiff = _run_alone(*args, time_constant=0.005)
    assert plain[0, 3] == 0 and stiff[0, 3] == 1
    # mean accepted step within [3 T, 7 T] (stability, not accuracy)
    mean_step = 15.0 / stiff[0, 0]
    assert 3 * 0.005 <= mean_step <= 7 * 0.005


def test_located_clip_switches_rate_limited_actuator():
    """Angle and rate limits that bind: with the switches located (default)
    the run agrees with a 1000x tighter solve_ivp reference (clips with
    min/max, written here) to 1e-8 and needs fewer right-hand-side
    evaluations than with the clips' kinks inside the steps."""
    veh = fws.Vehicle(
        2.7, 1.35, max_steer_front=0.3, max_steer_rear=0.2,
        max_steer_rate_front=0.3, max_steer_rate_rear=0.2,
    )  # fmt: skip
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-2.0)
    k1, k2, tau = float(g.k1), float(g.k2), 0.05
    rhs, command, _ = reference_rhs(veh, _const(0.1), k1, k2, -1.0, 5.0, tau=tau)
    y0 = np.array([0.0, -1.0, 0.0, *command(-1.0, 0.0, 0.1)])
    t = np.linspace(0.0, 15.0, 1501)
    ref = solve_ivp(rhs, (0.0, 15.0), y0, method="DOP853", t_eval=t,
                    rtol=1e-13, atol=1e-15)  # fmt: skip
    runs = {
        sw: _run_alone(
            fws.Arc(0.1),
            k1,
            k2,
            -1.0,
            5.0,
            (0.0, -1.0, 0.0),
            t,
            vehicle=veh,
            time_constant=tau,
            switching=sw,
        )  # fmt: skip
        for sw in (True, False)
    }
    states, status, _, _, stats = runs[True]
    assert status[0] == "ok"
    assert stats[0, 4] >= 2  # the limits bind, and are released
    assert np.max(np.abs(states[:, 0, :] - ref.y)) <= 1e-8
    assert stats[0, 2] < 0.8 * runs[False][4][0, 2]
    # held at the limits between the switches: the angles never exceed them
    assert np.max(np.abs(states[3, 0, :])) <= 0.3 + 1e-12
    assert np.max(np.abs(states[4, 0, :])) <= 0.2 + 1e-12


@pytest.mark.parametrize(
    ("path", "speed", "x0"),
    [
        (fws.Straight(), -3.0, (0.0, 1.0, 0.3)),  # reversing
        (fws.Arc(0.2), 5.0, (0.0, -1.0, 0.0)),  # a closed path: s wraps
        (
            fws.PathChain([fws.Straight(length=20.0), fws.Clothoid(0.0, 0.1, 10.0),
                           fws.Arc(0.1, length=20.0)]),
            5.0,
            (0.0, 0.5, 0.0),
        ),  # ends: end_of_path
    ],
    ids=["reversing", "closed-arc", "chain"],
)  # fmt: skip
def test_agrees_with_numpy_engine(path, speed, x0):
    from fws_control.simulation.engine import initial_path_state, integrate

    g = fws.double_root_gains(
        VEH, speed=speed, curvature=0.05, ratio=np.array([-0.5, 0.3]), pole=-1.0
    )
    z0 = initial_path_state(path, np.array([x0, x0], float))
    t = np.linspace(0.0, 20.0, 2001)
    kw = dict(speed=np.full(2, speed), feedforward=True, path_state=z0, t_eval=t,
              time_constant=None, **TOL)  # fmt: skip
    ref = integrate(VEH, path, g, **kw)
    got = integrate_compiled(VEH, path, g, **kw)
    assert got[1].tolist() == ref[1].tolist()
    np.testing.assert_allclose(got[3], ref[3], rtol=1e-9)
    assert np.array_equal(np.isnan(got[0]), np.isnan(ref[0]))
    # the numpy engine's error norm is over both runs: agreement at ~100 rtol
    # (measured 1.5e-8 m on the chain with scipy 1.17)
    assert np.nanmax(np.abs(got[0] - ref[0])) <= 3e-8


def test_the_tableau_read_from_its_file_is_scipys():
    # compiled_layout reads scipy's DOP853 tableau from its file (importing
    # it by name runs scipy.integrate's __init__); it must be the module
    # scipy's own DOP853 uses, every array and size
    from scipy.integrate._ivp import dop853_coefficients as scipys

    from fws_control.simulation.compiled_layout import DOP853_TABLEAU

    names = [n for n in vars(scipys) if n.isupper()]
    assert {"A", "B", "C", "D", "E3", "E5", "N_STAGES"} <= set(names)
    for name in names:
        np.testing.assert_array_equal(
            getattr(DOP853_TABLEAU, name), getattr(scipys, name), err_msg=name
        )
