"""Rate-limited runs against an independent fixed-step RK4 reference.

The reference is written here from the paper's model (eqs. 17-19, with the
speed factor of eq. 17; law of eqs. 24-29 with ``k3 = a k1, k4 = a k2``)
and the rate-clipped actuator ``d' = clip((d_cmd - d)/T, -r, r)``, nothing
from the library: classical RK4 with a fixed step, the clip as min/max in
the right-hand side. A step whose stages see the clip in different modes
(a kink inside the step, where RK4's local error is only O(h^2)) is redone
as 32 substeps, and such a substep as 32 more. Its own error is estimated
by Richardson extrapolation (``|y_h/2 - y_h| / 15``, order 4) and must be
below a tenth of the tolerance checked. An input delay (the last test)
has the same RK4 with the delayed state read on its own past steps
(:func:`_delayed_reference`).

The tolerance: an engine run at ``rtol, atol`` agrees with the reference
if every state's largest error is within ``AGREE`` = 100 units of ``atol +
rtol * max|y_i|`` (a local error tolerance bounds the global error of a
run only up to such a factor: measured here 7-35 units for DOP853 and
LSODA at rtol 1e-8, and all of them converge to the reference as rtol
falls; DOP853 at its stability bound is 10^2-10^3 units off).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws
from fws_control.simulation.engine import LSODA_MAX_RUNS, SOLVERS, choose_method

VEH = PAPER_VEHICLE
SPEED, KAPPA, E0 = 5.0, 0.1, -5.0  # the paper's curve scenario curve_5
RATIO = -0.5
AGREE = 100.0
DT_OUT = 0.5


def _rhs(y, p, measured=None):
    """Closed loop from the paper's formulas; returns (dy/dt, clip mode).

    `measured`: the ``(e, theta)`` the law acts on (an input delay's
    delayed state); None: the current ones.
    """
    V, f, kappa, k1, k2, a, T, r = p
    s_dot = V * math.cos(y[2] + y[4]) / (1.0 - kappa * y[1])
    e, theta = (y[1], y[2]) if measured is None else measured
    fb = -k1 * e - k2 * theta
    cmds = (math.atan(kappa * f) + fb, a * fb)  # eqs. (24)-(29)
    dy = [
        s_dot,
        V * math.sin(y[2] + y[4]),
        -kappa * s_dot + V * math.sin(y[3] - y[4]) / (f * math.cos(y[3])),
    ]
    mode = 0
    for j, cmd in enumerate(cmds):
        u = (cmd - y[3 + j]) / T
        dy.append(min(max(u, -r), r))
        mode = 3 * mode + (1 if u > r else 2 if u < -r else 0)
    return dy, mode


def _rk4(y, h, p, depth=2):
    k1, m1 = _rhs(y, p)
    k2, m2 = _rhs([a + 0.5 * h * b for a, b in zip(y, k1, strict=True)], p)
    k3, m3 = _rhs([a + 0.5 * h * b for a, b in zip(y, k2, strict=True)], p)
    k4, m4 = _rhs([a + h * b for a, b in zip(y, k3, strict=True)], p)
    y1 = [
        a + h / 6 * (b + 2 * c + 2 * d + e)
        for a, b, c, d, e in zip(y, k1, k2, k3, k4, strict=True)
    ]
    if depth and len({m1, m2, m3, m4, _rhs(y1, p)[1]}) > 1:
        for _ in range(32):  # a kink in the step: substeps
            y = _rk4(y, h / 32, p, depth - 1)
        return y
    return y1


def _reference(g, tau, rate, duration, h):
    p = (SPEED, VEH.wheelbase, KAPPA, float(g.k1), float(g.k2), float(g.ratio),
         tau, rate)  # fmt: skip
    fb = -float(g.k1) * E0
    y = [0.0, E0, 0.0, math.atan(KAPPA * VEH.wheelbase) + fb, float(g.ratio) * fb]
    every = int(round(DT_OUT / h))
    out = [y]
    for _ in range(int(round(duration / DT_OUT))):
        for _ in range(every):
            y = _rk4(y, h, p)
        out.append(y)
    return np.array(out)


@functools.cache
def _cached_reference(k1, k2, ratio, tau, rate, duration, h):
    """:func:`_reference`, once per process: several tests and cases
    compare with the same run (the reference is pure Python, seconds)."""
    ref = _reference(fws.SteeringGains(k1, k2, ratio), tau, rate, duration, h)
    ref.flags.writeable = False
    return ref


def _check_reference(g, tau, rate, duration, h, rtol, atol):
    case = (float(g.k1), float(g.k2), float(g.ratio), tau, rate, duration)
    coarse = _cached_reference(*case, h)
    ref = _cached_reference(*case, h / 2)
    tol = atol + rtol * np.max(np.abs(ref), axis=0)
    own = np.max(np.abs(ref - coarse), axis=0) / 15.0
    assert np.all(own < 0.1 * tol), (own, tol)
    return ref, tol


def _delayed_reference(p, y0, delay, duration, h, dt_out):
    """Fixed-step RK4 of the loop with an input delay (the law acts on the
    ``(e, theta)`` of ``t - delay``, the initial ones before the start; no
    clips). The step divides the delay, so the derivative jumps at
    multiples of it fall on the grid; a stage's delayed state is the
    cubic Hermite interpolant of a past step (error O(h^4), which keeps
    RK4's order 4)."""
    n_delay, every = round(delay / h), round(dt_out / h)
    assert n_delay >= 2 and math.isclose(n_delay * h, delay, rel_tol=1e-12)
    ys, fs = [], []  # the grid's states and derivatives: the history

    def measured(m, half):  # (e, theta) at t_m, or at t_m + h/2 (half)
        if m < 0:
            return y0[1], y0[2]
        if not half:
            return ys[m][1], ys[m][2]
        a, b, fa, fb = ys[m], ys[m + 1], fs[m], fs[m + 1]
        return tuple(0.5 * (a[i] + b[i]) + h / 8 * (fa[i] - fb[i]) for i in (1, 2))

    y, out = list(y0), [list(y0)]
    for n in range(round(duration / h)):
        m = n - n_delay  # the grid index of t_n - delay
        k1 = _rhs(y, p, measured(m, False))[0]
        ys.append(y)
        fs.append(k1)
        y_half = [a + 0.5 * h * b for a, b in zip(y, k1, strict=True)]
        k2 = _rhs(y_half, p, measured(m, True))[0]
        y_half = [a + 0.5 * h * b for a, b in zip(y, k2, strict=True)]
        k3 = _rhs(y_half, p, measured(m, True))[0]
        y_end = [a + h * b for a, b in zip(y, k3, strict=True)]
        k4 = _rhs(y_end, p, measured(m + 1, False))[0]
        y = [
            a + h / 6 * (b + 2 * c + 2 * d + e)
            for a, b, c, d, e in zip(y, k1, k2, k3, k4, strict=True)
        ]
        if (n + 1) % every == 0:
            out.append(y)
    return np.array(out)


def _run(tau, rate, duration, engine, rtol, atol, method="auto"):
    veh = dataclasses.replace(VEH, max_steer_rate_front=rate, max_steer_rate_rear=rate)
    g = fws.double_root_gains(VEH, speed=SPEED, curvature=KAPPA, ratio=RATIO,
                              pole=-1.0)  # fmt: skip
    res = fws.simulate(
        fws.LateralPlant(veh, speed=SPEED, steering_lag=tau),
        fws.Arc(KAPPA), g, initial_state=(0.0, E0, 0.0),
        duration=duration, dt=DT_OUT, engine=engine,
        method=method, rtol=rtol, atol=atol,
    )  # fmt: skip
    assert res.status == "ok", res.message
    y = np.stack([res.s, res.e, res.theta, res.delta_f, res.delta_r], axis=1)
    return res, y, g


def _cases():
    yield "numpy", "auto", "LSODA"  # 47 stability-bound steps > 10
    yield "numpy", "DOP853", "DOP853"  # min/max kinks inside its steps
    try:
        import numba  # noqa: F401

        marks = ()
    except ImportError:
        reason = "numba is not installed: the compiled engine (extra 'fast')"
        marks = pytest.mark.skip(reason=reason)
    # switched at located events
    yield pytest.param("compiled", "auto", "DOP853", marks=marks)
    # the compiled Radau: restarted at each located switch
    yield pytest.param("compiled", "Radau", "Radau", marks=marks)


@pytest.mark.parametrize(("engine", "method", "expect"), list(_cases()))
def test_binding_rate_limits_agree_with_fixed_step_reference(engine, method, expect):
    # T = 0.2 s over 60 s; rate limits 0.2 rad/s bind on both channels
    # (unlimited peaks ~0.45 and ~0.22 rad/s)
    tau, rate, duration, rtol, atol = 0.2, 0.2, 60.0, 1e-8, 1e-10
    res, y, g = _run(tau, rate, duration, engine, rtol, atol, method=method)
    assert res.method == expect
    ref, tol = _check_reference(g, tau, rate, duration, 5e-3, rtol, atol)
    # the limits bind: the engine's rates reach the limit on both channels
    assert np.max(np.abs(res.delta_f_rate)) == pytest.approx(rate, rel=1e-9)
    assert np.max(np.abs(res.delta_r_rate)) == pytest.approx(rate, rel=1e-9)
    units = np.max(np.abs(y - ref), axis=0) / tol
    assert np.all(units <= AGREE), units


def test_long_stiff_rate_limited_run_auto_lsoda_agrees_and_dop853_does_not():
    # T = 0.05 s over 30 s: 94 stability-bound DOP853 steps (> 10), so auto
    # takes LSODA; 0.2 rad/s binds. LSODA agrees to the tolerance; DOP853
    # at its stability bound (also the compiled engine's method) is
    # 10^2-10^3 tolerances off in the actuator states (documented in
    # docs/performance.md), which is why auto does not use it here. The
    # largest errors over 30 s (LSODA 0.9, DOP853 23 tolerances here) are
    # those over 100 s: both are reached before 30 s.
    tau, rate, duration, rtol, atol = 0.05, 0.2, 30.0, 1e-8, 1e-10
    res, y, g = _run(tau, rate, duration, "numpy", rtol, atol)
    assert res.method == "LSODA"
    ref, tol = _check_reference(g, tau, rate, duration, 2.5e-3, rtol, atol)
    units = np.max(np.abs(y - ref), axis=0) / tol
    assert np.all(units <= AGREE), units
    _, y_dop, _ = _run(tau, rate, duration, "numpy", rtol, atol, method="DOP853")
    units_dop = np.max(np.abs(y_dop - ref), axis=0) / tol
    assert np.max(units_dop) > 10 * np.max(units), (units_dop, units)


def _counts(method, tau, duration):
    """(steps, right-hand-side evaluations) of `method`, numpy engine."""
    seen = {"steps": 0, "nfev": 0}

    class Counting(SOLVERS[method]):
        def _step_impl(self):
            seen["steps"] += 1
            out = super()._step_impl()
            seen["nfev"] = self.nfev
            return out

    _run(tau, None, duration, "numpy", 1e-10, 1e-12, method=Counting)
    return seen["steps"], seen["nfev"]


@pytest.mark.parametrize(
    ("tau", "duration"),
    [(0.05, 2.0), (0.5, 20.0), (0.05, 15.0), (0.5, 150.0), (0.005, 5.0)],
)
def test_auto_long_run_rule_against_measured_step_counts(tau, duration):
    bound = duration / (6.4 * tau)  # the rule's count of stability-bound steps
    chosen = choose_method(tau, 1e-10, duration=duration)
    dop_steps, dop_nfev = _counts("DOP853", tau, duration)
    lsoda_steps, lsoda_nfev = _counts("LSODA", tau, duration)
    # DOP853 cannot step much beyond its stability bound of ~6.4 T
    assert dop_steps >= 0.8 * bound, (dop_steps, bound)
    if bound > 10:
        assert chosen == "LSODA"
        # where LSODA is chosen it needs fewer evaluations than DOP853
        assert lsoda_nfev < dop_nfev, (lsoda_nfev, dop_nfev)
    else:
        assert chosen == "DOP853"
        # short runs: the bound hardly binds (DOP853 takes several times the
        # bound's steps for accuracy) and LSODA takes 3x DOP853's steps
        # (each costs the engine its margin checks and outputs)
        assert dop_steps > 3 * bound, (dop_steps, bound)
        assert lsoda_steps > 3 * dop_steps, (lsoda_steps, dop_steps)


def test_auto_rule_follows_dop853s_error_at_its_stability_bound():
    # T = 0.05 s, no rate limit, default tolerances: over 2 s (6 bound steps)
    # DOP853 agrees with the reference; over 15 s (47) its steps reach the
    # bound and the actuator states are far off, LSODA's are not
    rtol, atol = 1e-10, 1e-12
    errors = {}
    for duration in (2.0, 15.0):
        _, y, g = _run(0.05, None, duration, "numpy", rtol, atol, method="DOP853")
        ref, tol = _check_reference(g, 0.05, math.inf, duration, 1e-3, rtol, atol)
        errors[duration, "DOP853"] = np.max(np.abs(y - ref) / tol)
        res, y, _ = _run(0.05, None, duration, "numpy", rtol, atol)
        errors[duration, res.method] = np.max(np.abs(y - ref) / tol)
    assert set(errors) == {(2.0, "DOP853"), (15.0, "DOP853"), (15.0, "LSODA")}
    assert errors[2.0, "DOP853"] <= AGREE, errors
    assert errors[15.0, "DOP853"] > AGREE, errors
    assert errors[15.0, "LSODA"] <= AGREE, errors


def _numba() -> bool:
    try:
        import numba  # noqa: F401
    except ImportError:
        return False
    return True


def _mixed_batch():
    # the run of the curve scenario (ratio RATIO, pole -1) first, then 19
    # runs with other ratios and poles -0.2 and -5 alternating (the -5 runs
    # stop at |delta_f| = pi/2 from the 5 m initial error)
    n = 20
    ratios = np.concatenate([[RATIO], np.linspace(-1.0, 0.5, n - 1)])
    poles = np.concatenate([[-1.0], np.where(np.arange(n - 1) % 2, -0.2, -5.0)])
    return fws.double_root_gains(VEH, speed=SPEED, curvature=KAPPA, ratio=ratios,
                                 pole=poles)  # fmt: skip


def _batch_units(g, engine, tau=0.05, duration=15.0, rtol=1e-10, atol=1e-12, **kw):
    """Error of run 0 against the reference [tolerances], alone and in `g`."""
    ref, tol = _check_reference(fws.SteeringGains(g.k1[0], g.k2[0], g.ratio[0]),
                                tau, math.inf, duration, 1e-3, rtol, atol)  # fmt: skip
    common = dict(initial_state=(0.0, E0, 0.0), duration=duration,
                  dt=DT_OUT, rtol=rtol, atol=atol,
                  progress=False, engine=engine, **kw)  # fmt: skip
    plant = fws.LateralPlant(VEH, speed=SPEED, steering_lag=tau)

    def units(res):
        y = np.stack([res.s[0], res.e[0], res.theta[0], res.delta_f[0],
                      res.delta_r[0]], axis=1)  # fmt: skip
        return float(np.max(np.abs(y - ref) / tol))

    one = fws.SteeringGains(g.k1[:1], g.k2[:1], g.ratio[:1])
    alone = fws.simulate_batch(plant, fws.Arc(KAPPA), one, **common)
    batch = fws.simulate_batch(plant, fws.Arc(KAPPA), g, **common)
    assert batch.status[0] == "ok"
    assert set(batch.status[1::2]) == {"singular_steering"}  # stops in the mix
    return alone, batch, units(alone), units(batch)


def test_numpy_auto_stacks_lsoda_16_runs_per_chunk_within_the_tolerance():
    # T = 0.05 s over 15 s (47 stability-bound steps): the numpy engine's
    # auto takes LSODA for the run alone and in the batch of 20, in chunks
    # of LSODA_MAX_RUNS runs. The stacked runs of a chunk share LSODA's
    # steps and error norm, so the error is not the run's alone (measured
    # 2.0 against 0.72 units), but within the tolerance (AGREE); with
    # chunk_size=1 it is bitwise the run alone. DOP853 for the batch (the
    # choice for more than 16 runs before) is far outside the tolerance.
    g = _mixed_batch()
    alone, batch, u_alone, u_batch = _batch_units(g, "numpy")
    assert alone.method == batch.method == "LSODA"
    assert u_alone <= AGREE and u_batch <= AGREE, (u_alone, u_batch)
    kw = dict(initial_state=(0.0, E0, 0.0), duration=15.0,
              dt=DT_OUT, rtol=1e-10, atol=1e-12,
              progress=False, engine="numpy")  # fmt: skip
    plant = fws.LateralPlant(VEH, speed=SPEED, steering_lag=0.05)
    # chunk_size=1 integrates each run alone: the first two runs (one that
    # finishes, one that stops) show it as well as all 20 (the method rule
    # does not depend on the number of runs)
    two = fws.SteeringGains(g.k1[:2], g.k2[:2], g.ratio[:2])
    one_by_one = fws.simulate_batch(plant, fws.Arc(KAPPA), two, chunk_size=1, **kw)
    assert one_by_one.method == "LSODA"
    assert one_by_one.status.tolist() == ["ok", "singular_steering"]
    np.testing.assert_array_equal(one_by_one.e[0], alone.e[0])
    # the default chunking: the first 16 runs share one solver, the other 4
    # another -- the first run is bitwise the same in a batch of 16
    m = LSODA_MAX_RUNS
    first16 = fws.simulate_batch(
        plant, fws.Arc(KAPPA), fws.SteeringGains(g.k1[:m], g.k2[:m], g.ratio[:m]), **kw
    )
    np.testing.assert_array_equal(first16.e[0], batch.e[0])
    *_, u_dop = _batch_units(g, "numpy", method="DOP853")
    assert u_dop > AGREE


@pytest.mark.skipif(not _numba(), reason="numba is not installed: the compiled engine")
def test_auto_capped_dop853_gives_each_run_its_own_accuracy():
    # The default engine (compiled where numba is installed): DOP853 with
    # its steps held to 3.2 T, half its stability bound, each run alone --
    # the run's result in the batch of 20 is bitwise the run alone and
    # within the tolerance; uncapped (the bound) it is not. The same with
    # binding rate limits (0.2 rad/s, located switches).
    g = _mixed_batch()
    alone, batch, u_alone, u_batch = _batch_units(g, "auto")
    assert batch.engine == "compiled" and batch.method == "DOP853"
    np.testing.assert_array_equal(batch.signals[0], alone.signals[0])
    assert u_alone == u_batch <= 10.0, u_alone
    *_, u_bound = _batch_units(g, "compiled", method="DOP853")
    assert u_bound > AGREE
    veh = dataclasses.replace(VEH, max_steer_rate_front=0.2, max_steer_rate_rear=0.2)
    g0 = fws.SteeringGains(g.k1[0], g.k2[0], g.ratio[0])
    res = fws.simulate(fws.LateralPlant(veh, speed=SPEED, steering_lag=0.05),
                       fws.Arc(KAPPA), g0, duration=15.0,
                       initial_state=(0.0, E0, 0.0), dt=DT_OUT)  # fmt: skip
    assert res.engine == "compiled"
    ref, tol = _check_reference(g0, 0.05, 0.2, 15.0, 1e-3, 1e-10, 1e-12)
    assert np.max(np.abs(res.delta_f_rate)) == pytest.approx(0.2, rel=1e-9)
    y = np.stack([res.s, res.e, res.theta, res.delta_f, res.delta_r], axis=1)
    assert np.max(np.abs(y - ref) / tol) <= AGREE


@pytest.mark.skipif(not _numba(), reason="numba is not installed: the compiled engine")
def test_compiled_radau_gives_each_run_its_own_accuracy():
    # The compiled Radau (what "auto" takes beyond 2,500 capped DOP853
    # steps): the run in the batch of 20, where every other run stops at
    # |delta_f| = pi/2 - margin, is bitwise the run alone and within the
    # tolerance of the fixed-step reference; and its peaks, from Radau's own
    # dense output, are those of the capped DOP853 run to 1e-9.
    g = _mixed_batch()
    alone, batch, u_alone, u_batch = _batch_units(g, "compiled", method="Radau")
    assert batch.engine == "compiled" and batch.method == "Radau"
    np.testing.assert_array_equal(batch.signals[0], alone.signals[0])
    np.testing.assert_array_equal(batch.run_peak[0], alone.run_peak[0])
    assert u_alone == u_batch <= 10.0, u_alone
    capped = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=SPEED, steering_lag=0.05),
        fws.Arc(KAPPA), fws.SteeringGains(g.k1[:1], g.k2[:1], g.ratio[:1]),
        initial_state=(0.0, E0, 0.0), duration=15.0, dt=DT_OUT,
        progress=False,
    )  # fmt: skip
    assert capped.method == "DOP853"
    np.testing.assert_allclose(alone.run_peak[0], capped.run_peak[0], rtol=1e-9)
    # the runs that stop, stop where the capped DOP853 runs stop
    stop = batch.status == "singular_steering"
    dop = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=SPEED, steering_lag=0.05),
        fws.Arc(KAPPA), g, initial_state=(0.0, E0, 0.0),
        duration=15.0, dt=DT_OUT, progress=False,
    )  # fmt: skip
    assert np.array_equal(dop.status == "singular_steering", stop)
    np.testing.assert_allclose(batch.t_stop[stop], dop.t_stop[stop], rtol=1e-7)


# the reference's step: its Richardson estimate below a tenth of the
# tolerance (measured 0.002, 0.05 and 0.02 of it; T = 0.04 s needs the
# finer step, 5e-3 s leaves 0.36 there)
@pytest.mark.parametrize(
    "tau, method, h",
    [(0.27, "DOP853", 5e-3), (0.075, "DOP853", 5e-3), (0.04, "LSODA", 2.5e-3)],
)
def test_auto_rule_keeps_dop853_when_a_delay_bounds_the_steps(tau, method, h):
    # With an input delay the method of steps holds every step to the delay;
    # a delay of at most 3.2 T (half DOP853's stability bound; delay / T =
    # 0.89 and 3.2 here) keeps its error estimate valid over the 30 s, where
    # the long-run rule alone would take LSODA. At delay / T = 6, nearer the
    # bound, DOP853 drifts (7.7 tolerances) and LSODA is taken. Either way
    # the run agrees within a few of its own tolerances with the fixed-step
    # RK4 reference of the delayed loop (steps far inside RK4's stability
    # bound of 2.8 T; Radau at rtol 1e-12 is within 0.002-0.05 tolerances
    # of it, its own Richardson estimate).
    assert choose_method(tau, 1e-8, duration=30.0) == "LSODA"
    assert choose_method(tau, 1e-8, duration=30.0, delay=0.24) == method
    g = fws.double_root_gains(VEH, speed=20.0, curvature=0.01, ratio=0.5, pole=-1.0)
    kw = dict(initial_state=(0.0, -10.0, 0.0), duration=30.0, dt=0.1, delay=0.24)
    plant = fws.LateralPlant(VEH, speed=20.0, steering_lag=tau)
    res = fws.simulate(plant, fws.Arc(0.01), g, rtol=1e-8, atol=1e-10, **kw)
    # the numpy engine's rule above; the compiled engine (numba installed)
    # runs a delayed case as DOP853 with its steps capped at the delay and
    # at 3.2 T, inside DOP853's stability bound at every ratio here
    assert res.engine == ("compiled" if _numba() else "numpy")
    if _numba():
        method = "DOP853"
    assert res.method == method and res.status == "ok"
    p = (20.0, VEH.wheelbase, 0.01, float(g.k1), float(g.k2), float(g.ratio),
         tau, math.inf)  # fmt: skip
    fb = 10.0 * float(g.k1)  # -k1 e0: the actuators start at rest
    y0 = [0.0, -10.0, 0.0, math.atan(0.01 * VEH.wheelbase) + fb, float(g.ratio) * fb]
    coarse = _delayed_reference(p, y0, 0.24, 30.0, h, 0.1)
    y_ref = _delayed_reference(p, y0, 0.24, 30.0, h / 2, 0.1)
    tol = 1e-10 + 1e-8 * np.max(np.abs(y_ref), axis=0)
    own = np.max(np.abs(y_ref - coarse), axis=0) / 15.0
    assert np.all(own < 0.1 * tol), (own, tol)
    names = ("s", "e", "theta", "delta_f", "delta_r")
    y = np.stack([getattr(res, k) for k in names], axis=1)
    assert np.all(np.max(np.abs(y - y_ref), axis=0) <= 5.0 * tol)
