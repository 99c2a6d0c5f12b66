r"""Exact peaks of the continuous solution, :func:`exact_peaks`.

The peak ``max |signal|`` of each signal of
:data:`~fws_control.simulation.outcomes.PEAK_SIGNALS`, per run, over the
whole integrated interval (the solver's dense output), not over the output
samples: it does not depend on the output grid.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..gains import SteeringGains
from ..paths import Path
from ..vehicle import Vehicle
from .dense import CompiledDense, DenseSolution
from .outcomes import PEAK_SIGNALS, SIGNALS
from .signals import compute_outputs

__all__ = [
    "exact_peaks",
    "exact_peaks_per_run",
    "BLOCK_STEPS",
]

_PEAK_ROWS = [SIGNALS.index(name) for name in PEAK_SIGNALS]
# Nodes per solver step on which the signals are first evaluated, candidate
# local maxima refined per run and signal, and the most golden-section
# iterations (0.618**80 shrinks a bracket of a step below 1e-16 of it).
_NODES_PER_STEP = 8
_PEAK_CANDIDATES = 3
_GOLDEN_ITERATIONS = 80
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0

#: Steps of compiled runs whose exact peaks are located at once
#: (:func:`exact_peaks_per_run`): with 8 nodes a step, one block's
#: evaluations hold about 32 768 points of every signal where its runs
#: take similar numbers of steps (each run is padded to the longest).
BLOCK_STEPS = 4096


def _sample_peaks(signals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index and value of the largest output sample of each peak signal.

    ``|signal|`` per run and signal of
    :data:`~fws_control.simulation.outcomes.PEAK_SIGNALS`, ``inf`` where a signal is not
    finite at a sample where the state is, ``-inf`` after the stop. One signal at a
    time, so that the temporaries are a fraction of the signals (``1 / len(SIGNALS)``
    each), not a copy of them.
    """
    n, T = signals.shape[0], signals.shape[2]
    have = np.isfinite(signals[:, SIGNALS.index("s"), :])
    k = np.zeros((n, len(_PEAK_ROWS)), dtype=int)
    v = np.full((n, len(_PEAK_ROWS)), -np.inf)
    if T == 0:
        return k, v
    for j, row in enumerate(_PEAK_ROWS):
        a = np.abs(signals[:, row, :])
        a[~np.isfinite(a)] = np.inf
        a[~have] = -np.inf
        k[:, j] = np.argmax(a, axis=1)
        v[:, j] = a[np.arange(n), k[:, j]]
    return k, v


def exact_peaks(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: np.ndarray,
    feedforward: bool,
    time_constant: float | None,
    solution: DenseSolution | CompiledDense,
    t_eval: np.ndarray,
    signals: np.ndarray,
    t_stop: np.ndarray,
    model: str = "kinematic",
    tyre: str = "linear",
    profile: Any = None,
    schedule: Any = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Peaks ``max |signal|`` of the continuous solution, per run and signal.

    The maximum is taken over the whole integrated interval ``[t0,
    t_stop]`` of each run, not over the output samples, so it does not
    depend on the output grid. Each signal of
    :data:`~fws_control.simulation.outcomes.PEAK_SIGNALS` is evaluated (with
    :func:`~fws_control.simulation.signals.compute_outputs`, on the solver's dense
    output) at :data:`_NODES_PER_STEP` points per solver step and at the run's stop; the
    largest local maxima of these nodes and the largest output sample are then refined
    by a golden-section search between their neighbours. The endpoints (``t = 0``, where
    the static controller's peaks often lie, and the stop) are nodes themselves. A
    signal that is not finite at a time where the state is (a rate or the lateral
    acceleration at a singular stop, where they diverge) has the peak
    ``inf`` at that time.

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, time_constant
        As given to :func:`~fws_control.simulation.engine.integrate`.
    solution : DenseSolution or CompiledDense
        From ``integrate(..., solution=[])``, or the compiled engine's
        solution (each run's peaks then on its own steps).
    t_eval : ndarray
        The output times of :func:`~fws_control.simulation.engine.integrate`.
    signals : ndarray
        :func:`~fws_control.simulation.signals.compute_outputs` at the output times,
        ``(n, len(SIGNALS), T)``.
    t_stop : ndarray
        Per run end time, from :func:`~fws_control.simulation.engine.integrate`.
    model, tyre, profile, schedule : optional
        As given to :func:`~fws_control.simulation.engine.integrate`.

    Returns
    -------
    values, times : ndarray
        Shape ``(n, len(PEAK_SIGNALS))``: the peak of ``|signal|`` and the
        time at which it occurs.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.engine import integrate
    >>> from fws_control.simulation.outcomes import PEAK_SIGNALS
    >>> from fws_control.simulation.peaks import exact_peaks
    >>> from fws_control.simulation.signals import compute_outputs
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(np.array([0.1]), 0.5, 0.0)
    >>> kw = dict(speed=np.array([5.0]), feedforward=False, time_constant=None)
    >>> t = np.linspace(0.0, 10.0, 11)           # a coarse grid: 1 s
    >>> sol = []
    >>> states, status, _, t_stop = integrate(
    ...     veh, fws.Straight(), g, path_state=np.array([[0.0, 1.0, 0.0]]),
    ...     t_eval=t, solution=sol, **kw)
    >>> sig = compute_outputs(veh, fws.Straight(), g, states=states,
    ...                       initial_heading=np.zeros(1), **kw)
    >>> val, when = exact_peaks(veh, fws.Straight(), g, solution=sol[0],
    ...                         t_eval=t, signals=sig, t_stop=t_stop, **kw)
    >>> j = PEAK_SIGNALS.index("delta_f_rate")
    >>> round(float(when[0, j]), 3) > 0.0      # the rate peaks between samples
    True
    """
    n = speed.size
    S = len(PEAK_SIGNALS)
    t_stop = np.asarray(t_stop, dtype=float)
    all_runs = np.arange(n)

    def evaluate(times: np.ndarray) -> np.ndarray:
        """``|signal|`` ``(n, S, K)`` at times ``(n, K)`` (NaN: no point)."""
        valid = np.isfinite(times)
        runs = np.broadcast_to(all_runs[:, None], times.shape)[valid]
        st = solution.states(runs, times[valid])
        states = np.full((st.shape[0], n, times.shape[1]), np.nan)
        states[:, valid] = st
        # (at a singular stop the rates are inf or NaN: they diverge there)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            out = compute_outputs(
                vehicle,
                path,
                gains,
                speed=speed,
                feedforward=feedforward,
                time_constant=time_constant,
                states=states,
                initial_heading=np.zeros(n),
                delay=solution.delay,
                model=model,
                tyre=tyre,
                profile=profile,
                schedule=schedule,
                times=times,
            )
        vals = np.abs(out[:, _PEAK_ROWS, :])
        vals = np.where(np.isfinite(vals), vals, np.inf)
        return np.where(valid[:, None, :], vals, -np.inf)

    # Nodes: the solver's step boundaries (they do not depend on the output
    # grid), subdivided, then the stop. One row shared by all runs, or a
    # row per run (NaN-padded) where each run took its own steps.
    bounds = solution.step_bounds()
    frac = np.arange(_NODES_PER_STEP) / _NODES_PER_STEP
    grid = bounds[:, :-1, None] + frac * np.diff(bounds, axis=1)[..., None]
    last = bounds[np.arange(bounds.shape[0]), np.sum(np.isfinite(bounds), axis=1) - 1]
    # (sorted: a padded row's NaN go to its end)
    grid = np.sort(np.concatenate([grid.reshape(bounds.shape[0], -1),
                                   last[:, None]], axis=1), axis=1)  # fmt: skip
    inside = grid < t_stop[:, None]
    count = np.count_nonzero(inside, axis=1)
    times = np.full((n, grid.shape[1] + 1), np.nan)
    times[:, :-1] = np.where(inside, grid, np.nan)
    times[all_runs, count] = t_stop
    node_v = evaluate(times)  # (n, S, K)
    K = times.shape[1]

    # Best so far: the nodes and the output samples (all on the solution).
    k_samp, samp_v = _sample_peaks(np.asarray(signals, dtype=float))
    j_node = np.argmax(node_v, axis=2)
    best_v = np.take_along_axis(node_v, j_node[..., None], 2)[..., 0]
    best_t = times[all_runs[:, None], j_node]
    better = samp_v > best_v
    best_v = np.where(better, samp_v, best_v)
    best_t = np.where(better, t_eval[k_samp], best_t)

    # Candidate brackets: the largest local maxima of the nodes ...
    left = np.concatenate([np.full((n, S, 1), -np.inf), node_v[..., :-1]], axis=2)
    right = np.concatenate([node_v[..., 1:], np.full((n, S, 1), -np.inf)], axis=2)
    score = np.where((node_v >= left) & (node_v >= right), node_v, -np.inf)
    C = min(_PEAK_CANDIDATES, K)
    idx = np.argsort(-score, axis=2, kind="stable")[..., :C]  # (n, S, C)
    last = count[:, None, None]
    t_at = times[all_runs[:, None, None], np.clip(idx, 0, None)]
    lo = times[all_runs[:, None, None], np.maximum(idx - 1, 0)]
    hi = times[all_runs[:, None, None], np.minimum(idx + 1, last)]
    lo = np.where(np.isfinite(lo), lo, t_at)
    hi = np.where(np.isfinite(hi), hi, t_at)
    # ... and the largest output sample.
    T = t_eval.size
    s_lo = t_eval[np.maximum(k_samp - 1, 0)]
    s_hi = np.minimum(t_eval[np.minimum(k_samp + 1, T - 1)], t_stop[:, None])
    lo = np.concatenate([lo, s_lo[..., None]], axis=2)
    hi = np.concatenate([hi, np.maximum(s_hi, s_lo)[..., None]], axis=2)
    C1 = lo.shape[2]
    diag = np.arange(S)

    def f(x):  # |signal s| at x[:, s, c], shape (n, S, C1)
        v = evaluate(x.reshape(n, S * C1)).reshape(n, S, S, C1)
        return v[:, diag, diag, :]

    def keep_best(x, v):
        nonlocal best_v, best_t
        j = np.argmax(v, axis=2)
        vj = np.take_along_axis(v, j[..., None], 2)[..., 0]
        tj = np.take_along_axis(x, j[..., None], 2)[..., 0]
        up = vj > best_v
        best_v = np.where(up, vj, best_v)
        best_t = np.where(up, tj, best_t)

    # Golden-section search for the maximum in every bracket at once.
    a, b = lo, hi
    c = b - _GOLDEN * (b - a)
    d = a + _GOLDEN * (b - a)
    fc, fd = f(c), f(d)
    keep_best(c, fc)
    keep_best(d, fd)
    for _ in range(_GOLDEN_ITERATIONS):
        # A bracket of 1e-10 s leaves a value error of f''/2 * 1e-20: none.
        if np.all(b - a <= 1e-10 * np.maximum(1.0, np.abs(b))):
            break
        left_side = fc > fd  # the maximum is in [a, d]
        b = np.where(left_side, d, b)
        a = np.where(left_side, a, c)
        new_c = b - _GOLDEN * (b - a)
        new_d = a + _GOLDEN * (b - a)
        x = np.where(left_side, new_c, new_d)
        fx = f(x)
        keep_best(x, fx)
        c, fc, d, fd = (
            np.where(left_side, x, d),
            np.where(left_side, fx, fd),
            np.where(left_side, c, x),
            np.where(left_side, fc, fx),
        )
    return best_v, best_t


def exact_peaks_per_run(
    vehicle: Vehicle,
    path: Path,
    subset: Callable[[int, int], Any],
    *,
    speed: np.ndarray,
    solution: CompiledDense,
    t_eval: np.ndarray,
    signals: np.ndarray,
    t_stop: np.ndarray,
    **options: Any,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`exact_peaks` of runs that each took their own steps.

    The runs go in blocks of consecutive runs of at most
    :data:`BLOCK_STEPS` steps in all (:meth:`CompiledDense.split
    <fws_control.simulation.dense.CompiledDense.split>`), each block's
    peaks located at once, each run on its own steps.

    Parameters
    ----------
    vehicle, path
        As given to :func:`exact_peaks`.
    subset : callable
        ``subset(lo, hi)``: the gains or controller of runs ``lo:hi``.
    speed, t_eval, signals, t_stop
        As given to :func:`exact_peaks`, for all runs.
    solution : CompiledDense
        The runs' dense output.
    **options
        The other keywords of :func:`exact_peaks` (``feedforward``,
        ``time_constant``, ``model``, ``tyre``, ``profile``, ``schedule``).

    Returns
    -------
    values, times : ndarray
        As :func:`exact_peaks`.
    """
    n = speed.size
    values = np.empty((n, len(PEAK_SIGNALS)))
    times = np.empty((n, len(PEAK_SIGNALS)))
    for lo, hi, part in solution.split(BLOCK_STEPS):
        values[lo:hi], times[lo:hi] = exact_peaks(
            vehicle, path, subset(lo, hi), speed=speed[lo:hi], solution=part,
            t_eval=t_eval, signals=signals[lo:hi], t_stop=t_stop[lo:hi], **options,
        )  # fmt: skip
    return values, times
