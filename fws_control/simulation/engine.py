r"""The numpy engine's driver: many runs of the closed loop in one solver.

The closed loop (:class:`~fws_control.simulation.loop.ClosedLoop`) of ``n``
runs is stacked in one state vector and stepped by one
:mod:`scipy.integrate` solver, which the engine drives itself (as
:func:`scipy.integrate.solve_ivp` would) so that a run meeting a singular
state can leave the stack at that time while the others go on. No
projection is needed during the integration: the global pose is
reconstructed afterwards as ``position(s) + e * normal(s)``,
``psi = theta + heading(s)``.

A run stops, and is marked rather than raising, when the model becomes
singular: a front steering angle :math:`|\delta_f| = \pi/2` (the yaw rate of
eq. 10 diverges), :math:`1-\kappa e = 0` (the vehicle reaches the centre of
curvature and the projection is lost) or the end of an open path.

The stages around the integration have modules of their own: the names of
the outcomes (:mod:`~fws_control.simulation.outcomes`), the checks of the
options (:mod:`~fws_control.simulation.options`), the dense output
(:mod:`~fws_control.simulation.dense`), the output signals
(:mod:`~fws_control.simulation.signals`) and the exact peaks
(:mod:`~fws_control.simulation.peaks`). Their public names stay importable
from this module too (:data:`__all__` lists them), so that
``fws_control.simulation.engine`` remains the one place to import the
numpy engine from. They are the interface between the modules of the
subpackage, not part of the top-level API.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import BDF, Radau
from scipy.optimize import brentq

from .. import equations
from ..gains import SteeringGains
from ..lateral_controller import saturate
from ..paths import Path
from ..vehicle import Vehicle
from .dense import DenseSolution, History, delayed_rows
from .loop import ClosedLoop, hold_row, is_sampled, scheduled_gains
from .options import (
    AT_SWITCH,
    ATOL_RANGE,
    LONG_RUN_STEPS,
    LSODA_MAX_RUNS,
    MAX_OUTPUT_BYTES,
    MODELS,
    RTOL_RANGE,
    SAFE_STEP,
    SOLVERS,
    STIFF_TIME_CONSTANT,
    check_initial_state,
    check_method,
    check_model,
    check_output_budget,
    check_tolerances,
    choose_method,
    initial_path_state,
    output_samples,
    resolve_time_constant,
    run_gains,
    sample_events,
    split_initial_state,
    time_grid,
)
from .outcomes import (
    PEAK_SIGNALS,
    SIGNALS,
    STATUS_END_OF_PATH,
    STATUS_FAILED,
    STATUS_OK,
    STATUS_SINGULAR_CURVATURE,
    STATUS_SINGULAR_STEERING,
    STATUS_UNCONTROLLABLE,
    STATUSES,
    STOP_MARGIN,
)
from .peaks import exact_peaks
from .signals import compute_outputs

__all__ = [
    "SIGNALS",
    "STATUS_OK",
    "STATUS_SINGULAR_STEERING",
    "STATUS_SINGULAR_CURVATURE",
    "STATUS_END_OF_PATH",
    "STATUS_FAILED",
    "STATUS_UNCONTROLLABLE",
    "STATUSES",
    "STOP_MARGIN",
    "SOLVERS",
    "check_method",
    "check_tolerances",
    "choose_method",
    "LONG_RUN_STEPS",
    "SAFE_STEP",
    "LSODA_MAX_RUNS",
    "STIFF_TIME_CONSTANT",
    "MAX_STEPS",
    "RTOL_RANGE",
    "ATOL_RANGE",
    "check_initial_state",
    "MODELS",
    "check_model",
    "split_initial_state",
    "run_gains",
    "resolve_time_constant",
    "time_grid",
    "MAX_OUTPUT_BYTES",
    "output_samples",
    "check_output_budget",
    "initial_path_state",
    "integrate",
    "compute_outputs",
    "PEAK_SIGNALS",
    "DenseSolution",
    "exact_peaks",
    "scheduled_gains",
]

# Order of the rows of ClosedLoop.margins: the stop condition of each row.
_STOP_KINDS = (STATUS_SINGULAR_STEERING, STATUS_SINGULAR_CURVATURE, STATUS_END_OF_PATH)

_STOP_MESSAGES = {
    STATUS_SINGULAR_STEERING: "front steering angle reached |delta_f| = pi/2 - "
    f"{STOP_MARGIN:g}, next to the singular yaw rate "
    "V*sin(delta_f - delta_r)/(f*cos(delta_f))",
    STATUS_SINGULAR_CURVATURE: f"1 - curvature*e reached {STOP_MARGIN:g}: the "
    "vehicle is at the path's centre of curvature and the projection is lost",
    STATUS_END_OF_PATH: "the projection point left the open path",
}


#: A solver failure is attributed to a singular state when a run is this
#: close to it (``pi/2 - |delta_f|``, ``1 - kappa*e`` or the relative distance
#: to the end of the path).
_COLLAPSE_MARGIN = 1e-3


@dataclass
class _Segment:
    outcome: str  # "done", "event", "failed" or "switch"
    t_last: float
    y_last: np.ndarray
    message: str = ""
    # with "switch": the clip (row of ClosedLoop.modes) and the column
    switch: tuple[int, int] = (-1, -1)


#: Points of each accepted step (fractions of it) where the stop margins are
#: checked: a loose tolerance lets a step cross a singular state and come
#: back, or end where the state is NaN, and the end of the step alone would
#: miss it.
_MARGIN_NODES = (0.25, 0.5, 0.75, 1.0)

#: Most solver steps of one integration segment (beyond those a delay's
#: maximum step forces): beyond it the runs still active are marked failed
#: instead of running on (a speed of 1e20 m/s asks for ~1e20 steps).
MAX_STEPS = 20_000

#: Most located switches of the steering clips in one integration segment
#: (all its runs; a guard against chattering, as the compiled engine's).
MAX_SWITCHES = 100_000

#: brentq's tolerances on an event, as :func:`scipy.integrate.solve_ivp`'s.
_EVENT_TOL = 4 * np.finfo(float).eps


def _locate_stop(event, dense, lo: float, hi: float) -> float:
    """First time in ``(lo, hi]`` where the margin is no longer > 0.

    The margin is > 0 at `lo` and not at `hi`. A NaN margin (a state beyond
    a singularity) counts as a stop, so the root is that of a function that
    is -1 wherever the margin is NaN: brentq keeps a sign-changing bracket.
    """

    def f(tt):
        g = event(tt, dense(tt))
        return -1.0 if math.isnan(g) else max(g, -1.0)

    if f(hi) == 0.0:
        return hi
    if not f(lo) > 0.0:  # (the segment starts regular; kept safe here)
        return lo
    return brentq(f, lo, hi, xtol=4 * np.finfo(float).eps * max(1.0, abs(hi)))


def _jacobian_sparsity(m: int, n: int):
    """Sparsity of the stacked Jacobian: each run's states couple only in it.

    The state is ``(m, n)`` flattened row-major, so entry ``(a*n + i, b*n +
    j)`` can be nonzero only for ``i == j``. Given to the implicit solvers,
    it lets scipy estimate the Jacobian of all runs with ``m`` evaluations of
    the right-hand side (one per state row) instead of ``m * n``, and solve
    with a sparse LU.
    """
    from scipy.sparse import eye, kron

    return kron(np.ones((m, m)), eye(n), format="csc")


def _solve_segment(
    eng, solver_cls, t0, y0, t_end, t_eval, rtol, atol, store, record=None, runs=None
) -> _Segment:
    """Step `solver_cls` from `t0`; stop where a margin first reaches 0.

    Same stepping, dense output and event location as
    :func:`scipy.integrate.solve_ivp` with a terminal event, but the last
    accepted state is kept when the solver fails, so that a collapse of the
    step size at a singular state can be attributed to the run that caused it,
    and the margins are checked at the nodes :data:`_MARGIN_NODES` of every
    accepted step (a NaN margin counts as a stop), so that no tolerance lets
    a run cross a singular state unnoticed. The states at the output times
    `t_eval` are passed to ``store(k, y)`` (``y`` of shape ``(y0.size,
    K)`` for the output times ``k:k+K``) as they are reached, so that no
    copy of them builds up here. With a `record` (:class:`History`), the
    dense output of every accepted step is added to it with the global
    indices `runs` of the stacked runs (the delay's history, and the
    continuous solution for exact peaks). With the clips as modes
    (``eng.modes``), where one switches (:meth:`ClosedLoop.switch_margins`,
    located as :func:`~scipy.integrate.solve_ivp` locates an event) the step
    is cut and the solver restarts there in the new mode, as the compiled
    engine does, so that no step integrates across a kink of a clip.
    """
    extra = {}
    if eng.delay > 0.0:
        # Method of steps: a stage at t + h needs the state at t + h - delay,
        # which is known (accepted) only if h <= delay.
        extra["max_step"] = eng.delay
    if issubclass(solver_cls, (Radau, BDF)):
        extra["jac_sparsity"] = _jacobian_sparsity(eng.m, y0.size // eng.m)
    switches = 0
    k0 = 0  # first output time of the current restart

    def shifted(k, y):
        store(k0 + k, y)

    while True:
        rhs = _DetachableRhs(eng.rhs)
        solver = solver_cls(rhs, t0, y0, t_end, rtol=rtol, atol=atol, **extra)
        try:
            seg = _step_segment(
                eng, solver, t0, t_end, t_eval[k0:], shifted, record, runs
            )
        finally:
            # scipy's solver and its wrappers of the right-hand side are a
            # reference cycle: cut the engine out of it, so that the engine
            # and the history it holds (every step's dense output of the
            # chunk) are freed when the caller drops them, not at the next
            # collection of the cyclic garbage collector (which a batch's
            # memory bound must not depend on: with the collector paused, a
            # 2000-run batch peaked at 45 instead of 34 MB,
            # tests/test_signals_kept.py)
            rhs.fun = None
        if seg.outcome != "switch":
            return seg
        # a clip switches: restart the solver there in the new mode (the
        # rest of the step, integrated in the old one, is discarded)
        switches += 1
        if switches > MAX_SWITCHES:
            return _Segment(
                "failed",
                seg.t_last,
                seg.y_last,
                f"more than {MAX_SWITCHES} switches of the steering clips "
                f"(MAX_SWITCHES) from t={t0:.6g} s: a clip chatters",
            )
        eng.switch(seg.y_last.reshape(eng.m, -1), seg.t_last, *seg.switch)
        t0, y0 = seg.t_last, seg.y_last
        k0 = int(np.searchsorted(t_eval, t0, side="right"))
        if t0 >= t_end:
            return _Segment("done", t0, y0)


class _DetachableRhs:
    """A right-hand side whose target can be dropped (see _solve_segment)."""

    __slots__ = ("fun",)

    def __init__(self, fun):
        self.fun = fun

    def __call__(self, t, y):
        return self.fun(t, y)


def _step_segment(eng, solver, t0, t_end, t_eval, store, record, runs) -> _Segment:
    """The stepping loop of :func:`_solve_segment`."""
    k = 0  # next output time
    steps = 0
    # (the steps a delay's max_step forces come on top of the budget)
    budget = MAX_STEPS + (int((t_end - t0) / eng.delay) if eng.delay > 0.0 else 0)
    switching = eng.modes is not None
    if switching:
        g_old = eng.switch_margins(solver.y.reshape(eng.m, -1), t0)
    while True:
        msg = solver.step()
        steps += 1
        if solver.status != "failed" and steps > budget:
            # a tight rtol with an atol far below it costs the steps at the
            # clips' kinks of the steering limits (inside the steps where the
            # clips are min/max): measured on a rate-limited arc (23 m/s, 6 s)
            # with DOP853, rtol 1e-13: 257-329 steps for atol 1e-15 to
            # 1e-19, 6712 for 1e-20; atol 1e-20: 262, 203 and 159 steps for
            # rtol 1e-12, 1e-11, 1e-10
            rtol = float(np.max(solver.rtol))
            atol = float(np.max(solver.atol))
            msg = (
                f"more than {MAX_STEPS} solver steps (MAX_STEPS) from t={t0:.6g} s "
                f"at rtol={rtol:g}, atol={atol:g}: dynamics too fast for the "
                "output interval, stiff (try method='Radau'), or tolerances "
                "tighter than the kinks of the steering limits allow (try "
                "rtol >= 1e-12 or atol >= 1e-19)"
            )
            return _Segment("failed", float(solver.t), solver.y.copy(), msg)
        if solver.status == "failed":
            return _Segment("failed", float(solver.t), solver.y.copy(), msg)
        t_old, t_new = solver.t_old, solver.t
        dense = solver.dense_output()
        if record is not None:
            record.add(t_old, t_new, dense, runs)
        t_hit = None
        prev = t_old
        for frac in _MARGIN_NODES:
            tt = t_new if frac == 1.0 else t_old + frac * (t_new - t_old)
            y_tt = solver.y if frac == 1.0 else dense(tt)
            if not eng.event(tt, y_tt) > 0.0:  # also NaN
                t_hit = _locate_stop(eng.event, dense, prev, tt)
                break
            prev = tt
        switch = None
        if switching:
            g_new = eng.switch_margins(solver.y.reshape(eng.m, -1), t_new)
            switch = _locate_switch(eng, dense, t_old, t_new, g_old, g_new)
            if switch is not None and (t_hit is None or switch[0] < t_hit):
                t_hit = switch[0]
                if record is not None:
                    # the step's interpolant holds up to the switch only
                    record.pieces[-1] = (t_hit, dense, runs)
            else:
                switch = None
        upto = t_new if t_hit is None else t_hit
        k_end = int(np.searchsorted(t_eval, upto, side="right"))
        if k_end > k:
            store(k, dense(t_eval[k:k_end]))
            k = k_end
        if switch is not None:  # (then t_hit is the switch's time)
            t_sw = float(switch[0])
            y_hit = solver.y.copy() if t_sw == t_new else dense(t_sw)
            return _Segment("switch", t_sw, y_hit, switch=switch[1:])
        if t_hit is not None:
            return _Segment("event", float(t_hit), dense(t_hit))
        if solver.status == "finished":
            return _Segment("done", float(t_new), solver.y.copy())
        if switching:
            if np.any(eng.released):
                # a step after a release: the clips watch both limits again
                eng.released[:] = 0.0
                g_old = eng.switch_margins(solver.y.reshape(eng.m, -1), t_new)
            else:
                g_old = g_new


def _locate_switch(eng, dense, t_old, t_new, g_old, g_new):
    """First switch of a clip in the step: ``(time, clip, column)`` or None.

    A clip's mode is wrong at the step's end where its margin is < 0 (or 0
    from > 0): it switched in the step, at the root of its margin on the
    dense output (brentq, as :func:`~scipy.integrate.solve_ivp` locates an
    event), or it was on the wrong side at the restart already (a margin
    not > 0 at `t_old`: the switch is there).
    """
    hit = (g_new < 0.0) | ((g_new == 0.0) & (g_old > 0.0))
    if not np.any(hit):
        return None
    best = None
    for clip, col in zip(*np.nonzero(hit), strict=True):
        if not g_old[clip, col] > 0.0:
            root = t_old
        else:

            def g(tt, clip=clip, col=col):
                y = dense(tt).reshape(eng.m, -1)
                return float(eng.switch_margins(y, tt)[clip, col])

            # (the interpolant's end equals the step's end to rounding only)
            root = (
                t_new
                if g(t_new) > 0.0
                else brentq(g, t_old, t_new, xtol=_EVENT_TOL, rtol=_EVENT_TOL)
            )
        if best is None or root < best[0]:
            best = (float(root), int(clip), int(col))
    return best


def integrate(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: np.ndarray,
    feedforward: bool,
    path_state: np.ndarray,
    t_eval: np.ndarray,
    time_constant: float | None,
    method: Any = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    delay: float = 0.0,
    solution: list | None = None,
    model: str = "kinematic",
    tyre: str = "linear",
    body_state: np.ndarray | None = None,
    profile: Any = None,
    schedule: Any = None,
    switching: bool | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``n`` runs together; a stopped run leaves the stacked state.

    Parameters
    ----------
    vehicle, path
        Shared by all runs.
    gains : SteeringGains or LateralController
        Per run (fields of shape ``(n,)`` or scalars that broadcast). A
        sampled controller (:func:`~fws_control.simulation.loop.is_sampled`) is
        integrated piece by piece between its samples, its held command two more state
        rows (:func:`~fws_control.simulation.loop.hold_row`): the solver restarts at
        every measurement and switch of the command, and no delayed rows are returned.
    speed : ndarray
        Per run speed, shape ``(n,)``; its size is the number of runs.
    feedforward : bool
        Curvature feedforward on or off (all runs).
    path_state : ndarray
        Initial ``(s, e, theta)`` per run, shape ``(n, 3)``
        (:func:`~fws_control.simulation.options.initial_path_state`).
    t_eval : ndarray
        Output times, from the start time
        (:func:`~fws_control.simulation.options.time_grid`).
    time_constant : float or None
        Actuator lag [s] (:func:`resolve_time_constant`); None: no actuator.
    method, rtol, atol
        Solver (see :func:`~fws_control.simulation.options.check_method`) and its
        tolerances.
    delay : float, optional
        Input delay [s] on the steering command: the controller acts on the
        measurements of ``t - delay``; before ``delay`` the command is the
        one of the initial state (the state is held at its initial value for
        ``t < 0``). Integrated by the method of steps: the solver's step is
        at most the delay, the delayed state comes from the dense output of
        the accepted steps, and the solver restarts at ``delay``,
        ``2 delay`` and ``3 delay``, where the solution's first derivatives
        are not smooth.
    solution : list, optional
        If given, a :class:`~fws_control.simulation.dense.DenseSolution` (the solver's
        dense output of every accepted step: the continuous solution between the output
        times) is appended to it, for :func:`~fws_control.simulation.peaks.exact_peaks`.
    model : {"kinematic", "dynamic"}, optional
        Vehicle model (:data:`MODELS`, checked by :func:`check_model`). The
        dynamic model (:func:`~fws_control.dynamics.dynamic_path_derivatives`,
        ``speed`` is its constant longitudinal speed ``u > 0``) adds the
        rows ``v_y, r`` last.
    tyre : {"linear", "magic"}, optional
        Tyre model of the dynamic model.
    body_state : ndarray, optional
        Initial ``(v_y, r)`` per run, shape ``(n, 2)``; a NaN row (or None
        for all runs): the vehicle starts rolling without tyre slip at the
        initial steering angles, ``r = u (tan delta_f - tan delta_r) / f``
        and ``v_y - l_r r = u tan delta_r`` (the kinematic model's motion).
    profile : SpeedProfile, optional
        A speed that varies along the run
        (:class:`~fws_control.SpeedProfile`, of the time or of the state
        ``s``) instead of the constant `speed`, which then only counts
        the runs. Not with a delay (the runners refuse it).
    schedule : optional
        Gains of the paper's law read at the current speed
        (:func:`scheduled_gains`) instead of the fixed `gains`.
    switching : bool, optional
        True: the steering-angle and steering-rate clips are modes switched
        at located events, where the solver restarts (as in the compiled
        engine), so that no step integrates across a clip's kink; False:
        min/max in the right-hand side. Default: True on a vehicle with a
        limit, without a delay (whose clips are min/max, as in the compiled
        engine). A sampled controller's clips are min/max.

    Returns
    -------
    states : ndarray
        Shape ``(m, n, T)`` with rows ``s, e, theta`` (and ``delta_f,
        delta_r`` with an actuator, then ``v_y, r`` with the dynamic model);
        NaN after a run's stop. With a delay,
        six more rows: the path state ``s, e, theta`` at ``t - delay`` and
        its time derivative (zero before the start), which
        :func:`~fws_control.simulation.signals.compute_outputs` needs for the applied
        steering.
    status, message : ndarray of object
        Per run status (one of :data:`STATUSES`) and explanation.
    t_stop : ndarray
        Per run end time [s].

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.engine import integrate
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(np.array([0.1, 0.1]), 0.5, 0.0)
    >>> states, status, _, t_stop = integrate(
    ...     veh, fws.Straight(), g, speed=np.array([5.0, 5.0]), feedforward=False,
    ...     path_state=np.array([[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]]),
    ...     t_eval=np.linspace(0.0, 1.0, 11), time_constant=None)
    >>> states.shape, status.tolist(), t_stop.tolist()
    ((3, 2, 11), ['ok', 'ok'], [1.0, 1.0])
    """
    if is_sampled(gains):
        return _integrate_sampled(
            vehicle, path, gains, speed=speed, feedforward=feedforward,
            path_state=path_state, t_eval=t_eval, time_constant=time_constant,
            method=method, rtol=rtol, atol=atol, delay=delay, solution=solution,
            model=model, tyre=tyre, body_state=body_state,
        )  # fmt: skip
    tau = time_constant
    z0 = np.asarray(path_state, dtype=float)
    n = speed.size
    T = t_eval.size
    dyn = model == "dynamic"
    m = (3 if tau is None else 5) + (2 if dyn else 0)
    controller = not isinstance(gains, SteeringGains)
    if not controller:
        k1, k2, a = (
            np.broadcast_to(np.asarray(v, dtype=float), (n,))
            for v in (gains.k1, gains.k2, gains.ratio)
        )
    out = np.full((m, n, T), np.nan)
    status = np.full(n, STATUS_OK, dtype=object)
    message = np.full(n, "", dtype=object)
    t_stop = np.full(n, t_eval[-1])

    history = None
    if switching is None:
        switching = delay == 0.0 and _has_limits(vehicle, tau)
    elif switching and delay > 0.0:
        raise ValueError(
            f"switching=True is not available with a delay (delay={delay!r}): the "
            "clips of a delayed command are min/max in the right-hand side"
        )
    # the clips' modes of every run (ClosedLoop.modes), kept across segments
    modes = np.zeros((4, n)) if switching else None

    def engine_for(idx, switched=False):
        return ClosedLoop(
            vehicle,
            path,
            gains.subset(idx)
            if controller
            else SteeringGains(k1[idx], k2[idx], a[idx]),
            speed[idx],
            feedforward,
            tau,
            delay,
            history,
            idx,
            model,
            tyre,
            profile=profile,
            schedule=schedule,
            modes=modes[:, idx] if switched and modes is not None else None,
        )

    active = np.arange(n)
    eng = engine_for(active, switched=True)
    Y = np.zeros((m, n))
    Y[:3] = z0.T
    if switching:
        # an angle beyond its limit starts held (first: the actuator's rate
        # depends on the held command)
        eng.start_modes(Y, float(t_eval[0]), (0, 1))
    if tau is not None or dyn:
        cmd = np.stack(eng.command(Y, eng.curvature(Y[0]), float(t_eval[0])))
    if tau is not None:
        # The actuator starts at the command: no initial transient of its own.
        Y[3:5] = cmd
        if switching:
            eng.start_modes(Y, float(t_eval[0]), (2, 3))
    if modes is not None:
        modes[:] = eng.modes
    if dyn:
        V0 = speed if profile is None else eng.speed_at(float(t_eval[0]), Y[0])
        _initial_body_state(vehicle, Y, cmd, V0, body_state)
    out[:, :, 0] = Y
    if delay > 0.0 or solution is not None:
        history = History(float(t_eval[0]), Y.copy())
    marg = eng.margins(Y, float(t_eval[0]))
    bad = np.min(marg, axis=0) <= 0.0
    for i in np.flatnonzero(bad):
        kind = _STOP_KINDS[int(np.argmin(marg[:, i]))]
        status[i], t_stop[i] = kind, t_eval[0]
        message[i] = f"initial state: {_STOP_MESSAGES[kind]}"
    active = active[~bad]
    Y = Y[:, ~bad]
    t0 = float(t_eval[0])
    t_end = float(t_eval[-1])
    solver_cls = check_method(method)
    # Restart points: where a delay makes the solution's derivatives jump.
    breaks = [t0 + k * delay for k in (1, 2, 3)] if delay > 0.0 else []
    breaks = [b for b in breaks if b < t_end] + [t_end]
    while active.size and t0 < t_end:
        eng = engine_for(active, switched=True)
        first = int(np.searchsorted(t_eval, t0, side="right"))
        seg_end = next(b for b in breaks if b > t0)

        def store(k, y, first=first, active=active):
            # straight into the output: no per-segment copy of the samples
            out[:, active, first + k : first + k + y.shape[1]] = y.reshape(
                m, active.size, -1
            )

        seg = _solve_segment(
            eng,
            solver_cls,
            t0,
            Y.ravel(),
            seg_end,
            t_eval[first:],
            rtol,
            atol,
            store,
            record=history,
            runs=active,
        )
        if modes is not None:
            modes[:, active] = eng.modes
        if seg.outcome == "done":
            if seg_end >= t_end:
                break
            Y, t0 = seg.y_last.reshape(m, active.size), seg_end
            continue
        keep = _stop_runs(eng, seg, active, status, message, t_stop)
        if keep is None:
            break
        Y_last = seg.y_last.reshape(m, active.size)
        active, Y, t0 = active[keep], Y_last[:, keep], seg.t_last
    if delay > 0.0:
        out = np.concatenate(
            [out, delayed_rows(engine_for, history, out, t_eval, delay)]
        )
    if solution is not None:
        assert history is not None  # recorded whenever a solution is asked for
        solution.append(DenseSolution(history, engine_for, delay))
    return out, status, message, t_stop


def _integrate_sampled(
    vehicle, path, ctrl, *, speed, feedforward, path_state, t_eval, time_constant,
    method, rtol, atol, delay, solution, model, tyre, body_state,
):  # fmt: skip
    """:func:`integrate` with a sampled controller (zero-order hold).

    The controller's command is a pair of state rows
    (:func:`~fws_control.simulation.loop.hold_row`), constant between its
    switches: the solver restarts at every measurement and switch time
    (:func:`~fws_control.simulation.options.sample_events`), where the rows
    are set to the command of that sample, computed by the run's own
    ``ctrl.start(...)`` from the state at the measurement time. The delay is
    in the switch times, so no delayed rows are returned.
    """
    tau = time_constant
    n, T = speed.size, t_eval.size
    dyn = model == "dynamic"
    hold = hold_row(ctrl, tau)
    m = hold + 2 + (2 if dyn else 0)
    out = np.full((m, n, T), np.nan)
    status = np.full(n, STATUS_OK, dtype=object)
    message = np.full(n, "", dtype=object)
    t_stop = np.full(n, t_eval[-1])
    runs = [ctrl.start(vehicle, path, speed=float(v)) for v in speed]

    def engine_for(idx):
        return ClosedLoop(
            vehicle, path, ctrl, speed[idx], feedforward, tau, runs=idx,
            model=model, tyre=tyre, hold=hold,
        )  # fmt: skip

    t0, t_end = float(t_eval[0]), float(t_eval[-1])
    Y = np.zeros((m, n))
    Y[:3] = np.asarray(path_state, dtype=float).T
    events = sample_events(t0, t_end, float(ctrl.sample_time), delay)
    nxt = next(events, None)
    pending: dict[int, np.ndarray] = {}
    active = np.arange(n)
    history = None
    t_cur = t0
    solver_cls = check_method(method)
    while True:
        while nxt is not None and nxt[0] <= t_cur:
            _, kind, k = nxt
            nxt = next(events, None)
            if kind == 0:
                cmd = np.array(
                    [
                        runs[i].step(s=Y[0, j], e=Y[1, j], theta=Y[2, j])
                        for j, i in enumerate(active)
                    ]
                ).reshape(active.size, 2)
                pending[k] = np.stack(saturate(vehicle, cmd[:, 0], cmd[:, 1]))
                continue
            Y[hold : hold + 2] = pending.pop(k)
            if history is not None:
                # a switch at an output time: that sample shows the new
                # command (the hold is right-continuous)
                at = np.flatnonzero(
                    np.abs(t_eval - t_cur) <= AT_SWITCH * ctrl.sample_time
                )
                if at.size:
                    rows = Y[hold : hold + 2, :, None]
                    out[hold : hold + 2, active[:, None], at[None, :]] = rows
        if history is None:
            # the start: the actuator at the first command, the body rolling
            # without slip, the margins checked
            if tau is not None:
                Y[3:5] = Y[hold : hold + 2]
            if dyn:
                _initial_body_state(vehicle, Y, Y[hold : hold + 2], speed, body_state)
            out[:, :, 0] = Y
            history = History(t0, Y.copy())
            marg = engine_for(active).margins(Y, t0)
            bad = np.min(marg, axis=0) <= 0.0
            for i in np.flatnonzero(bad):
                kind = _STOP_KINDS[int(np.argmin(marg[:, i]))]
                status[i], t_stop[i] = kind, t0
                message[i] = f"initial state: {_STOP_MESSAGES[kind]}"
            active, Y = active[~bad], Y[:, ~bad]
            pending = {k: v[:, ~bad] for k, v in pending.items()}
        if active.size == 0 or t_cur >= t_end:
            break
        seg_end = t_end if nxt is None else nxt[0]
        eng = engine_for(active)
        first = int(np.searchsorted(t_eval, t_cur, side="right"))

        def store(k, y, first=first, active=active):
            out[:, active, first + k : first + k + y.shape[1]] = y.reshape(
                m, active.size, -1
            )

        seg = _solve_segment(
            eng, solver_cls, t_cur, Y.ravel(), seg_end, t_eval[first:], rtol, atol,
            store, record=history, runs=active,
        )  # fmt: skip
        if seg.outcome == "done":
            Y, t_cur = seg.y_last.reshape(m, active.size).copy(), seg_end
            continue
        keep = _stop_runs(eng, seg, active, status, message, t_stop)
        if keep is None:
            break
        # the stopped runs take no more samples; the others go on from the stop
        Y = seg.y_last.reshape(m, active.size)[:, keep].copy()
        active, t_cur = active[keep], seg.t_last
        pending = {k: v[:, keep] for k, v in pending.items()}
    if solution is not None:
        if history is None:
            history = History(t0, Y.copy())
        solution.append(DenseSolution(history, engine_for, 0.0))
    return out, status, message, t_stop


def _stop_runs(eng, seg, active, status, message, t_stop):
    """Mark the runs a segment's stop ended; return the mask of those left.

    A solver failure away from any singular state fails every active run
    (returns None).
    """
    Y_last = seg.y_last.reshape(eng.m, active.size)
    marg = eng.margins(Y_last, seg.t_last)
    j = int(np.argmin(np.min(marg, axis=0)))
    kind = _STOP_KINDS[int(np.argmin(marg[:, j]))]
    if seg.outcome == "event":
        note = _STOP_MESSAGES[kind]
    elif np.min(marg[:, j]) < _COLLAPSE_MARGIN:
        # Near |delta_f| = pi/2 the solution has a square-root singularity
        # (d delta_f/dt ~ 1/cos delta_f): the step size collapses before
        # any accepted step crosses it, so the event cannot fire.
        note = (
            f"{_STOP_MESSAGES[kind]} (the solver's step size collapsed "
            f"{float(np.min(marg[:, j])):.2g} away from it)"
        )
    else:
        for i in active:
            status[i], t_stop[i] = STATUS_FAILED, seg.t_last
            message[i] = f"at t={seg.t_last:.6g} s the ODE solver failed: {seg.message}"
        return None
    # The run that set the stop, and any other at its margin there too
    # (e.g. identical runs): one left in would start the next segment
    # past its stop, where no sign change can be seen.
    stops = np.union1d([j], np.flatnonzero(~(np.min(marg, axis=0) > 0.0)))
    for jj in stops:
        kind_jj = _STOP_KINDS[int(np.argmin(marg[:, jj]))]
        i = active[jj]
        status[i], t_stop[i] = kind_jj, seg.t_last
        message[i] = f"at t={seg.t_last:.6g} s: " + (
            note if jj == j else _STOP_MESSAGES[kind_jj]
        )
    return ~np.isin(np.arange(active.size), stops)


def _has_limits(vehicle, tau) -> bool:
    """True if `vehicle` clips a steering angle, or a rate with an actuator."""
    rates = (vehicle.max_steer_rate_front, vehicle.max_steer_rate_rear)
    angles = (vehicle.max_steer_front, vehicle.max_steer_rear)
    return any(v is not None for v in angles + (rates if tau is not None else ()))


def _initial_body_state(vehicle, Y, cmd, speed, body_state) -> None:
    """Fill the rows ``v_y, r`` of `Y` (the last two) in place.

    Given values where `body_state` is finite; elsewhere the no-slip motion
    at the initial steering `cmd` (both slip angles zero).
    """
    with np.errstate(invalid="ignore"):
        vy0, r0 = equations.no_slip_body_state(
            speed, vehicle.wheelbase, vehicle.rear_to_cg, cmd[0], cmd[1]
        )
    if body_state is not None:
        given = np.isfinite(np.asarray(body_state, dtype=float))
        vy0 = np.where(given[:, 0], body_state[:, 0], vy0)
        r0 = np.where(given[:, 1], body_state[:, 1], r0)
    Y[-2], Y[-1] = vy0, r0
