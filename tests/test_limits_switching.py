"""The numpy engine locates the switches of the steering clips as events.

On a vehicle with steering-angle and steering-rate limits the numpy engine
holds a clipped channel by a mode and restarts its solver where a clip
switches (:meth:`~fws_control.simulation.loop.ClosedLoop.switch_margins`,
the event function :func:`~fws_control.equations.clip_switch_margin` that
the compiled engine uses too), so that no step integrates across a clip's
kink. The reference here is independent of the library's integration:
:func:`scipy.integrate.solve_ivp` with Radau at ``rtol = 1e-12``, ``atol =
1e-14`` on the closed loop written from the paper's formulas (the corrected
path-frame model of eqs. 17-19, the law of eqs. 24-29 with ``k3 = a k1``,
``k4 = a k2``, the actuator ``d' = clip((d_cmd - d)/T, -r, r)``), the clips
as modes switched by directional terminal events written here: a free clip
at ``value = +-limit`` (crossing outwards), a held one where ``mode *
value`` falls back to the limit.

Tolerance: 1e-6 m (and rad) on every state between the engine at its
defaults (``rtol = 1e-10``, ``atol = 1e-12``) and the reference: the
engine's local tolerance is ~1e-10 relative on states of ~1-50, so 1e-6
leaves a factor of ~100 for the error growth over the run and the roots
of the switches. Integrated across the kinks (``switching=False``, min/max
in the right-hand side) the engine was 3.5e-6 m off a tight reference on
scenario 690 of ``benchmarks/bench_limit_agreement.py``, 30 times the error
with the switches located (docs/reliability.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control import equations
from fws_control.controllers import DEFAULT_ACTUATOR_TIME_CONSTANT
from fws_control.simulation.engine import initial_path_state, integrate
from fws_control.simulation.loop import ClosedLoop

TAU = DEFAULT_ACTUATOR_TIME_CONSTANT
TOL = 1e-6
VEH = fws.Vehicle(
    2.7,
    1.35,
    max_steer_front=0.12,
    max_steer_rear=0.05,
    max_steer_rate_front=0.35,
    max_steer_rate_rear=0.25,
)
SPEED = 12.0
PATH = fws.slalom(pitch=16.0, amplitude=1.2, cones=3, approach=10.0).path
GAINS = fws.double_root_gains(VEH, ratio=-0.4, pole=-2.0, speed=SPEED)
# 2 s: both runs hold and release each of the four clips (18-26 switches
# each), and the largest errors with and without switching (at 0.9 and
# 1.5 s) are those of a 3 s run
DURATION = 2.0
T_EVAL = np.linspace(0.0, DURATION, 41)


def _curvature_knots():
    """The slalom's curvature as knots: piecewise linear in s (clothoids)."""
    lengths = [seg.length for seg in PATH.segments]
    knots = np.concatenate([[0.0], np.cumsum(lengths)])
    kappa = np.asarray(PATH.curvature(np.minimum(knots, PATH.length)), dtype=float)
    # exact between the knots (a check of the chain's pieces, at a fraction of
    # the cost of the path's own evaluation in the reference's thousands of
    # right-hand sides)
    s = np.linspace(0.0, PATH.length, 997)
    kinds = {type(seg).__name__ for seg in PATH.segments}
    assert kinds == {"Straight", "Clothoid"}, kinds
    np.testing.assert_allclose(
        np.interp(s, knots, kappa), PATH.curvature(s), rtol=0, atol=1e-12
    )
    return knots, kappa


def _reference(z0):
    """States ``(5, T)`` at T_EVAL: Radau with the clips' switches as events."""
    V, f = SPEED, VEH.wheelbase
    knots, kappas = _curvature_knots()
    k1, k2, a = float(GAINS.k1), float(GAINS.k2), float(GAINS.ratio)
    lim = (
        VEH.max_steer_front,
        VEH.max_steer_rear,
        VEH.max_steer_rate_front,
        VEH.max_steer_rate_rear,
    )

    def raw(y, modes):
        # the law's commands, then the actuator's rates from the held ones
        kappa = float(np.interp(y[0], knots, kappas))
        fb = -k1 * y[1] - k2 * y[2]
        cmd = [math.atan(kappa * f) + fb, a * fb]
        held = [modes[j] * lim[j] if modes[j] else cmd[j] for j in (0, 1)]
        return cmd + [(held[0] - y[3]) / TAU, (held[1] - y[4]) / TAU], kappa

    def rhs(t, y, modes):
        v, kappa = raw(y, modes)
        rate = [modes[j] * lim[j] if modes[j] else v[j] for j in (2, 3)]
        s_dot = V * math.cos(y[2] + y[4]) / (1.0 - kappa * y[1])
        return [
            s_dot,
            V * math.sin(y[2] + y[4]),
            -kappa * s_dot + V * math.sin(y[3] - y[4]) / (f * math.cos(y[3])),
            rate[0],
            rate[1],
        ]

    def events(modes):
        # (solve_ivp passes its args, the modes, to the events too)
        out = []
        for j in range(4):
            if modes[j]:
                # held: leaves its limit where mode * value falls to it
                ev = [(lambda t, y, m, j=j: m[j] * raw(y, m)[0][j] - lim[j], -1)]
            else:
                # free: reaches +limit from below or -limit from above
                ev = [
                    (lambda t, y, m, j=j: raw(y, m)[0][j] - lim[j], 1),
                    (lambda t, y, m, j=j: raw(y, m)[0][j] + lim[j], -1),
                ]
            for fun, direction in ev:
                fun.terminal, fun.direction = True, direction
                out.append((j, fun))
        return out

    modes = [0, 0, 0, 0]
    y = [float(v) for v in z0] + [0.0, 0.0]
    v, _ = raw(y, modes)
    for j in (0, 1):  # an angle beyond its limit starts held
        if abs(v[j]) > lim[j]:
            modes[j] = 1 if v[j] > 0 else -1
    v, _ = raw(y, modes)
    y[3] = modes[0] * lim[0] if modes[0] else v[0]  # the actuator at the command
    y[4] = modes[1] * lim[1] if modes[1] else v[1]
    out = np.full((5, T_EVAL.size), np.nan)
    t, switches = 0.0, 0
    while t < DURATION:
        evs = events(modes)
        sol = solve_ivp(
            rhs, (t, DURATION), y, method="Radau", rtol=1e-12, atol=1e-14,
            events=[e for _, e in evs], dense_output=True, args=(modes,),
        )  # fmt: skip
        assert sol.success, sol.message
        t_end = float(sol.t[-1])
        sel = (T_EVAL >= t) & (T_EVAL <= t_end)
        if sel.any():
            out[:, sel] = sol.sol(T_EVAL[sel])
        if sol.status != 1:
            break
        k = next(i for i, te in enumerate(sol.t_events) if te.size)
        j = evs[k][0]
        modes[j] = 0 if modes[j] else (1 if evs[k][1].direction > 0 else -1)
        t, y = t_end, sol.y_events[k][0].tolist()
        switches += 1
    return out, switches


def _pose(e0, th0):
    (px,), (py,) = PATH.position([2.0])
    (h,) = PATH.heading([2.0])
    return (px - e0 * math.sin(h), py + e0 * math.cos(h), h + th0)


POSES = [_pose(1.5, 0.1), _pose(-0.8, -0.2)]


def _run(poses, **kw):
    z0 = initial_path_state(PATH, np.array(poses))
    return integrate(
        VEH, PATH, GAINS, speed=np.full(len(poses), SPEED), feedforward=True,
        path_state=z0, t_eval=T_EVAL, time_constant=TAU, method="DOP853", **kw,
    ), z0  # fmt: skip


@pytest.fixture(scope="module")
def references():
    z0 = initial_path_state(PATH, np.array(POSES))
    return [_reference(z) for z in z0]


@pytest.fixture(scope="module")
def stacked():
    """The engine's run of both poses in one stacked state (two tests)."""
    return _run(POSES)


def test_rate_limited_slalom_against_radau_with_switch_events(references, stacked):
    # both runs in one stacked state: a switch of either restarts the solver
    (states, status, _, _), _ = stacked
    assert status.tolist() == ["ok", "ok"]
    for i, (ref, switches) in enumerate(references):
        # the clips do switch (held and released) in this run
        assert switches >= 4, switches
        err = np.max(np.abs(states[:, i, :] - ref), axis=1)
        assert np.all(err < TOL), (i, err)


def test_without_switching_the_kinks_cost_accuracy(references):
    # the same runs with min/max in the right-hand side: further from the
    # reference than with the switches located (the reason for them). At
    # the default tolerances both errors are about 1e-9, where a change of
    # the path by 1e-14 relative decides which is larger; at rtol 1e-8 the
    # steps over the kinks dominate: 20-24x the error with the switches
    # located (measured on two paths differing by 1e-14)
    ref = references[0][0]
    (on, _, _, _), _ = _run(POSES[:1])
    assert np.max(np.abs(on[:, 0, :] - ref)) < TOL
    coarse = dict(rtol=1e-8, atol=1e-10)
    (on, _, _, _), _ = _run(POSES[:1], **coarse)
    (off, _, _, _), _ = _run(POSES[:1], switching=False, **coarse)
    err_on = np.max(np.abs(on[:, 0, :] - ref))
    err_off = np.max(np.abs(off[:, 0, :] - ref))
    assert err_off > 5.0 * err_on, (err_off, err_on)


def test_engines_agree_on_the_rate_limited_slalom(references, stacked):
    pytest.importorskip("numba", reason="the compiled engine needs numba")
    from fws_control.simulation.compiled import integrate_compiled
    from fws_control.simulation.engine import SAFE_STEP

    (states, _, _, _), z0 = stacked
    kw = dict(
        speed=np.full(len(POSES), SPEED), feedforward=True, path_state=z0,
        t_eval=T_EVAL, time_constant=TAU,
    )  # fmt: skip
    comp = integrate_compiled(VEH, PATH, GAINS, max_step=SAFE_STEP * TAU, **kw)[0]
    assert np.max(np.abs(comp - states)) < TOL
    for i, (ref, _) in enumerate(references):
        assert np.max(np.abs(comp[:, i, :] - ref)) < TOL


def test_switch_margins_are_the_equation_of_each_clip():
    # ClosedLoop.switch_margins: clip_switch_margin of the law's raw
    # commands (written here from eqs. 24-29) and of the actuator's rates
    z0 = initial_path_state(PATH, np.array(POSES))
    Y = np.zeros((5, 2))
    Y[:3] = z0.T
    Y[3:5] = [[0.1, -0.2], [0.02, 0.04]]
    modes = np.array([[1.0, 0.0], [0.0, -1.0], [0.0, 1.0], [-1.0, 0.0]])
    eng = ClosedLoop(VEH, PATH, GAINS, np.full(2, SPEED), True, TAU, modes=modes)
    eng.released[:] = [[0.0, 0.0], [0.0, 0.0], [0.0, -1.0], [0.0, 0.0]]
    kappa = PATH.curvature(Y[0])
    fb = -float(GAINS.k1) * Y[1] - float(GAINS.k2) * Y[2]
    cmd = np.array([np.arctan(kappa * VEH.wheelbase) + fb, float(GAINS.ratio) * fb])
    lim = np.array([0.12, 0.05, 0.35, 0.25])
    held = np.where(modes[:2] != 0.0, modes[:2] * lim[:2, None], cmd)
    raw = np.concatenate([cmd, (held - Y[3:5]) / TAU])
    want = equations.clip_switch_margin(raw, lim[:, None], modes, eng.released)
    np.testing.assert_allclose(eng.switch_margins(Y), want, rtol=0, atol=1e-12)
    # a held clip gives the limit, a free one the value
    Ydot = eng.derivatives(Y)[0]
    np.testing.assert_allclose(Ydot[3], [(0.12 - 0.1) / TAU, 0.35], rtol=1e-12)
    np.testing.assert_allclose(Ydot[4], [-0.25, (-0.05 - 0.04) / TAU], rtol=1e-12)


def test_switching_refused_with_a_delay():
    with pytest.raises(ValueError, match=r"switching=True.*delay=0\.1"):
        _run(POSES[:1], switching=True, delay=0.1)
