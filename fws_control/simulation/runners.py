r"""The public runners: :func:`simulate` (one run) and :func:`simulate_batch`.

Both validate the arguments, project the initial poses onto the path, let
the engine (:mod:`~fws_control.simulation.engine`) integrate the closed loop
and return a :class:`~fws_control.simulation.result.SimulationResult`;
:func:`simulate` is a batch of one run, squeezed.

:func:`simulate_batch` stacks the path-frame states of the runs of a chunk
into one state vector and integrates them with one solver. Gains, ratios,
speeds and initial poses may differ per run (numpy broadcasting). A run that
meets a singular state leaves the stacked state at that time (the
integration restarts from there for the others) and is marked in its status;
its samples after the stop are NaN. Large sweeps are split into chunks of
``chunk_size`` runs. With a ``dask.distributed`` client (optional extra
``distributed``) the chunks are submitted to the cluster; otherwise they run
one after the other here. A tqdm progress bar over the chunks is shown on
interactive terminals.

That is the numpy engine. By default (``engine="auto"``) the runners use
the compiled per-run engine of :mod:`~fws_control.simulation.compiled`
instead wherever numba is installed and it covers the case (the paper's
law on the kinematic model with DOP853 or Radau, with a delay DOP853; on
the dynamic model DOP853 without delay): each run then has its own
steps, error norm and stop, and its exact peaks come from its own dense
output.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import sys
import time
import warnings
from typing import Any

import numpy as np
from scipy.integrate import DOP853, RK23, RK45

from ..baselines import LateralController
from ..controllers import check_feedforward
from ..deprecation import legacy_keyword, reject_unknown, warn_deprecated
from ..dynamics import require_dynamics
from ..exceptions import ClusterLostError
from ..gains import SteeringGains
from ..metrics import HORIZON_METRICS, tracking_metrics
from ..paths import Path
from ..plant import LateralPlant
from ..speed_profile import SpeedProfile
from ..validation import (
    MAX_SPEED,
    check_bool,
    check_delay,
    check_nonzero,
    check_scalar,
    check_type,
)
from ..vehicle import Vehicle
from .engine import (
    LSODA_MAX_RUNS,
    PEAK_SIGNALS,
    SAFE_STEP,
    SIGNALS,
    STATUS_FAILED,
    check_method,
    check_model,
    check_output_budget,
    check_sampling,
    check_tolerances,
    choose_method,
    compute_outputs,
    exact_peaks,
    initial_path_state,
    integrate,
    is_sampled,
    output_samples,
    resolve_time_constant,
    run_gains,
    scheduled_gains,
    split_initial_state,
    time_grid,
)
from .result import SimulationResult

__all__ = ["simulate", "simulate_batch", "DEFAULT_CHUNK_SIZE"]

#: Runs per chunk (one solver, one Dask task) unless told otherwise.
DEFAULT_CHUNK_SIZE = 256


def _stderr_is_tty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


#: Samples (runs x output times) whose signals are computed at once: the
#: temporaries of :func:`~fws_control.simulation.engine.compute_outputs`
#: (about forty-five arrays of this size, 12 MB) stay bounded, whatever the
#: size of the output.
_OUTPUT_BLOCK = 1 << 15
_PSI = SIGNALS.index("psi")


def _outputs_in_blocks(vehicle, path, g, *, states, initial_heading, **kw):
    """:func:`compute_outputs` over blocks of output times, into one array.

    ``psi`` is unwrapped in time within a block; each block starts on the
    branch of the previous block's last value (consecutive samples differ
    by less than pi), so the result equals one call over all times.
    """
    n, T = states.shape[1], states.shape[2]
    step = max(1, _OUTPUT_BLOCK // max(n, 1))
    if step >= T:
        return compute_outputs(
            vehicle, path, g, states=states, initial_heading=initial_heading, **kw
        )
    out = np.empty((n, len(SIGNALS), T))
    heading = np.asarray(initial_heading, dtype=float)
    times = kw.pop("times", None)
    for k0 in range(0, T, step):
        part = out[:, :, k0 : k0 + step]
        part[...] = compute_outputs(
            vehicle, path, g, states=states[:, :, k0 : k0 + step],
            initial_heading=heading,
            times=None if times is None else times[k0 : k0 + step], **kw,
        )  # fmt: skip
        heading = part[:, _PSI, -1]
    return out


def _run_chunk(vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl):
    """Simulate one chunk; module-level so that Dask can pickle it.

    Returns ``(signals (n, len(SIGNALS), T), status, message, t_stop,
    peaks (n, len(PEAK_SIGNALS)), peak_times)``: the peaks are those of the
    continuous solution (:func:`~fws_control.simulation.engine.exact_peaks`).
    """
    g = SteeringGains(k1, k2, a) if ctrl is None else ctrl
    # x0: pose and (v_y, r) of the dynamic model (NaN: the default)
    z0 = initial_path_state(path, x0[:, :3])
    body = x0[:, 3:] if opts["model"] == "dynamic" else None
    states, status, message, t_stop = integrate(
        vehicle,
        path,
        g,
        speed=speed,
        feedforward=feedforward,
        path_state=z0,
        t_eval=t,
        time_constant=tau,
        solution=(solution := []),
        body_state=body,
        **opts,
    )
    signals = _outputs_in_blocks(
        vehicle,
        path,
        g,
        speed=speed,
        feedforward=feedforward,
        time_constant=tau,
        states=states,
        initial_heading=x0[:, 2],
        delay=opts["delay"],
        model=opts["model"],
        tyre=opts["tyre"],
        profile=opts.get("profile"),
        schedule=opts.get("schedule"),
        times=t,
    )
    del states  # (the outputs hold everything the peaks need)
    peaks, peak_times = exact_peaks(
        vehicle,
        path,
        g,
        speed=speed,
        feedforward=feedforward,
        time_constant=tau,
        solution=solution[0],
        t_eval=t,
        signals=signals,
        t_stop=t_stop,
        model=opts["model"],
        tyre=opts["tyre"],
        profile=opts.get("profile"),
        schedule=opts.get("schedule"),
    )
    return signals, status, message, t_stop, peaks, peak_times


def _run_isolated(vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl):
    """:func:`_run_chunk`, where a solver failure takes only its own run out.

    The runs of a chunk share one solver, so one run whose solver fails
    (e.g. a speed of 1e300 m/s) fails every run still active in the chunk.
    Those runs are split in halves and integrated again, recursively, until
    a run that fails alone is found: only it keeps the status ``"failed"``
    (and its message); every other run keeps its own result. The cost is at
    most about twice the chunk's (one half of each split finishes normally).
    Module-level so that Dask can pickle it: on a cluster the retries run on
    the worker.
    """
    out = _run_chunk(
        vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl
    )  # fmt: skip
    failed = np.flatnonzero(out[1] == STATUS_FAILED)
    if speed.size == 1 or failed.size == 0:
        return out
    for idx in np.array_split(failed, 2):
        sub_ctrl = ctrl.subset(idx) if ctrl is not None and ctrl.runs() else ctrl
        sub = _run_isolated(
            vehicle, path, k1[idx], k2[idx], a[idx], speed[idx], feedforward,
            x0[idx], t, tau, opts, sub_ctrl,
        )  # fmt: skip
        for whole, part in zip(out, sub, strict=True):
            whole[idx] = part
    return out


# Engines of simulate_batch (documented in its docstring).
_ENGINES = ("auto", "numpy", "compiled")

#: With an actuator of time constant T under ``method="auto"``, the compiled
#: engine's DOP853 steps at most this times T: half its stability bound of
#: about 6.4 T, where its error estimate bounds the error again. Measured on
#: the curve scenario at T = 0.05 s over 15 s against a fixed-step RK4
#: reference: 330 tolerances off at the bound, 5.7 with the cap (0.3 of the
#: bound: 4.3; 0.8: 386), at 0.24 ms of CPU per run (numpy LSODA in chunks
#: of 16: 17.3 ms).
_CAPPED_STEP = SAFE_STEP
#: Beyond this many capped steps "auto" on the compiled engine takes its
#: Radau (implicit, stepping by accuracy: 9-13 ms of CPU per run of the
#: curve scenario with all signals and exact peaks, whatever T and the
#: duration) instead of the capped DOP853 (about 4.3 us per step, 1.0-1.4
#: ms for the 15 s scenario at T = 0.27 and 0.05 s; 16.5 ms at 4,688 steps,
#: 43 ms at 9,375 and 396 ms at 93,750). Measured with `simulate`, best of
#: 3, output step 0.1 s: they cost the same near 2,300 steps.
_RADAU_FROM_STEPS = 2500


def _compiled_reason(
    path, gains, *, delay, method, model, feedforward, profile=None, schedule=None
):
    """Why ``engine="compiled"`` cannot run this case, or None if it can."""
    # imported here: numba's import is paid only by those who use it
    from .compiled import compiled_support
    from .compiled_speed import compiled_speed_reason

    reason = compiled_support(path, gains, delay=delay, method=method, model=model)
    if reason is None and feedforward == "dynamic":
        reason = "feedforward='dynamic' is not compiled"
    if reason is None:
        reason = compiled_speed_reason(profile, schedule, method=method)
    return reason


def _check_compiled(
    path, gains, *, delay, method, model, feedforward, profile=None, schedule=None
) -> None:
    """Raise ValueError if ``engine="compiled"`` cannot run this case."""
    reason = _compiled_reason(
        path, gains, delay=delay, method=method, model=model, feedforward=feedforward,
        profile=profile, schedule=schedule,
    )  # fmt: skip
    if reason is not None:
        raise ValueError(
            f"engine='compiled' cannot run this simulation: {reason}; use "
            "engine='numpy'"
        )


def _choose_engine(
    path, gains, *, delay, method, model, feedforward, profile=None, schedule=None
):
    """The engine ``engine="auto"`` runs, and the compiled engine's table.

    Returns ``("compiled", table)`` where the compiled engine can run the
    case, else ``("numpy", None)``. `method` is already resolved (DOP853
    for a stiff run under ``method="auto"``, which the compiled engine then
    runs as capped DOP853 or Radau, see ``_RADAU_FROM_STEPS``; LSODA and
    BDF: numpy). A path whose curvature table misses its tolerance goes to
    numpy too. A varying speed (`profile`, `schedule`) goes to numpy where
    it is evaluated in Python (a function profile or schedule).
    """
    try:
        import numba  # noqa: F401  (the optional extra "fast")
    except ImportError:
        return "numpy", None
    if _compiled_reason(
        path, gains, delay=delay, method=method, model=model, feedforward=feedforward,
        profile=profile, schedule=schedule,
    ):  # fmt: skip
        return "numpy", None
    from .compiled import curvature_table

    try:
        return "compiled", curvature_table(path)
    except ValueError:
        return "numpy", None


def _run_compiled(
    vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl, out=None
):
    """:func:`_run_chunk` on the compiled engine (each run alone).

    Same arguments and results, the peaks those of each run's own dense
    output (:func:`~fws_control.simulation.compiled.compiled_peaks`);
    module-level so that Dask can pickle it. A run's solver, steps and stop
    are its own, so a failure needs no isolation. `out`: the chunk's rows of
    the batch's signals, written in place (then returned as the signals).
    """
    from .compiled import compiled_method, compiling

    # the first compilation in a process is announced once, with the time
    # of the three stages this call compiles (nothing when they are cached)
    with compiling(compiled_method(opts["method"]), "signals", "peaks"):
        return _run_compiled_stages(
            vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, out
        )


def _run_compiled_stages(
    vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, out
):
    # _run_compiled's integration, signals and exact peaks
    from .compiled import (
        compiled_method,
        compiled_outputs,
        compiled_peaks,
        curvature_table,
        integrate_compiled,
    )

    g = SteeringGains(k1, k2, a)
    profile = opts.get("profile")
    # once per call (simulate_batch builds it), for the integration, the
    # outputs and the peaks
    table = opts.get("curvature_table")
    if table is None:
        table = curvature_table(path)
    # each distinct initial pose projected once (a sweep often shares one);
    # distinct by bit pattern, so the numbers are those of every run's own
    rows = np.ascontiguousarray(x0[:, :3]).view(np.dtype((np.void, 24))).ravel()
    _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
    states, status, message, t_stop, _ = integrate_compiled(
        vehicle,
        table,
        g,
        speed=speed,
        feedforward=feedforward,
        path_state=initial_path_state(path, x0[first, :3])[inverse.ravel()],
        t_eval=t,
        time_constant=tau,
        rtol=opts["rtol"],
        atol=opts["atol"],
        max_step=opts.get("max_step", math.inf),
        method=compiled_method(opts["method"]),
        solution=(solution := []),
        delay=opts["delay"],
        model=opts["model"],
        tyre=opts["tyre"],
        body_state=x0[:, 3:] if opts["model"] == "dynamic" else None,
        profile=profile,
        schedule=opts.get("schedule"),
    )
    if profile is not None:
        return _varying_speed_outputs(
            vehicle, path, g, speed, feedforward, x0, t, tau, opts, out, states,
            status, message, t_stop, solution[0],
        )  # fmt: skip
    signals = compiled_outputs(
        vehicle,
        path,
        g,
        speed=speed,
        feedforward=feedforward,
        time_constant=tau,
        states=states,
        initial_heading=x0[:, 2],
        table=table,
        out=out,
        solution=solution[0],
        t_eval=t,
        model=opts["model"],
        tyre=opts["tyre"],
    )
    peaks, peak_times = compiled_peaks(
        vehicle,
        table,
        g,
        speed=speed,
        feedforward=feedforward,
        time_constant=tau,
        solution=solution[0],
        t_eval=t,
        signals=signals,
        t_stop=t_stop,
        model=opts["model"],
        tyre=opts["tyre"],
    )
    return signals, status, message, t_stop, peaks, peak_times


def _varying_speed_outputs(
    vehicle, path, g, speed, feedforward, x0, t, tau, opts, out, states, status,
    message, t_stop, solution,
):  # fmt: skip
    """Signals and exact peaks of compiled varying-speed runs.

    The numpy engine's :func:`compute_outputs` and :func:`exact_peaks` on
    each run's compiled dense output (``CompiledDense``): the longitudinal
    signals and the scheduled command's rate are the numpy engine's.
    """
    from .compiled_speed import CompiledDense

    kw = dict(
        speed=speed, feedforward=feedforward, time_constant=tau,
        model=opts["model"], tyre=opts["tyre"], profile=opts["profile"],
        schedule=opts.get("schedule"),
    )  # fmt: skip
    signals = _outputs_in_blocks(
        vehicle, path, g, states=states, initial_heading=x0[:, 2],
        delay=0.0, times=t, **kw,
    )  # fmt: skip
    if out is not None:
        out[...] = signals
        signals = out
    n = speed.size
    k1, k2, a = (np.broadcast_to(np.ravel(v), (n,)) for v in (g.k1, g.k2, g.ratio))
    peaks = np.empty((n, len(PEAK_SIGNALS)))
    peak_times = np.empty((n, len(PEAK_SIGNALS)))
    for i in range(n):
        rows = slice(solution.offsets[i], solution.offsets[i + 1])
        dense = CompiledDense(
            solution.records[rows], solution.initial_state[i], float(t[0])
        )
        one = {**kw, "speed": speed[i : i + 1]}
        peaks[i], peak_times[i] = (
            v[0]
            for v in exact_peaks(
                vehicle, path,
                SteeringGains(k1[i : i + 1], k2[i : i + 1], a[i : i + 1]),
                solution=dense, t_eval=t, signals=signals[i : i + 1],
                t_stop=t_stop[i : i + 1], **one,
            )
        )  # fmt: skip
    return signals, status, message, t_stop, peaks, peak_times


#: The choice of ``signals="metrics"``: no time series, only per-run values.
_METRICS_ONLY = "metrics"


def _check_signals(signals: Any) -> tuple[str, ...]:
    """The names of the kept signals, in the order of :data:`SIGNALS`."""
    if signals is None:
        return SIGNALS
    if isinstance(signals, str):
        if signals == _METRICS_ONLY:
            return ()
        raise ValueError(
            f"signals must be None (all), 'metrics' (no time series) or a "
            f"sequence of names of {SIGNALS}, got the str {signals!r}"
            + (
                f" (for one signal: signals=({signals!r},))"
                if signals in SIGNALS
                else ""
            )
        )
    try:
        names = list(signals)
    except TypeError:
        raise TypeError(
            "signals must be None, 'metrics' or a sequence of signal names, got "
            f"{type(signals).__name__} {signals!r}"
        ) from None
    if not names:
        raise ValueError(
            "signals must name at least one signal, got an empty sequence; use "
            "signals='metrics' to keep no time series (only per-run metrics)"
        )
    for name in names:
        if not isinstance(name, str):
            raise TypeError(
                f"signals must hold signal names (str), got {name!r} of type "
                f"{type(name).__name__} in {signals!r}; valid names: {SIGNALS}"
            )
        if name not in SIGNALS:
            raise ValueError(
                f"signals: unknown signal {name!r}; valid names: {SIGNALS} "
                "(or signals=None for all, 'metrics' for none)"
            )
    if len(set(names)) != len(names):
        raise ValueError(f"signals must not repeat a name, got {signals!r}")
    return tuple(k for k in SIGNALS if k in names)


def _check_out(out: Any, shape: tuple[int, int, int]) -> None:
    """Refuse an `out` that cannot receive the kept signals in place."""
    if shape[1] == 0:
        raise ValueError(
            "out must be None with signals='metrics' (no time series to write), "
            f"got {type(out).__name__}"
        )
    # other subclasses of ndarray carry state of their own that the chunks'
    # writes would not update (a masked array's mask)
    if type(out) is not np.ndarray and not isinstance(out, np.memmap):
        raise TypeError(
            f"out must be a numpy.ndarray (e.g. numpy.empty({shape})) or a "
            f"numpy.memmap, got {type(out).__name__}"
        )
    if out.dtype != np.float64 or out.shape != shape:
        raise ValueError(
            f"out must be a float64 array (native byte order) of shape {shape} "
            f"(runs, kept signals, output times), got {out.dtype} of shape "
            f"{out.shape}"
        )
    if not out.flags.c_contiguous:
        raise ValueError(
            f"out must be C-contiguous (the chunks write whole rows), got an "
            f"array with strides {out.strides}"
        )
    if not out.flags.writeable:
        raise ValueError("out must be writeable, got a read-only array")


def _reduce_chunk(out, rows, horizon, exact, args):
    """A chunk's outputs with only the kept signals and the per-run values.

    `out` is what :func:`_run_chunk` returns; `rows` the indices of the
    kept signals in :data:`SIGNALS`. Everything that needs the dropped
    signals is computed here, from the chunk's full signals, before they
    are freed: the number of samples up to each run's stop, the horizon
    metrics of :func:`~fws_control.tracking_metrics` if `horizon` (``e``
    or ``theta`` dropped), and the sample peaks if the engine gave no exact
    ones (not `exact`). Returns ``(kept signals, status, message, t_stop,
    peaks, peak_times, samples, metrics or None)``.
    """
    signals, status, message, t_stop, peak, peak_time = out
    t = args[8]
    samples = np.count_nonzero(np.isfinite(signals[:, SIGNALS.index("s"), :]), axis=1)
    metrics = None
    if horizon or not exact:
        chunk = SimulationResult(
            t=t,
            signals=signals,
            run_status=np.asarray(status).astype(str),
            run_message=tuple(str(m) for m in message),
            run_t_stop=t_stop,
            run_speed=args[5],
            run_k1=args[2],
            run_k2=args[3],
            run_ratio=args[4],
            run_initial_state=args[7][:, :3],
            run_peak=peak if exact else None,
            run_peak_time=peak_time if exact else None,
        )
        if not exact:  # the maxima of the samples, while they exist (once)
            p = chunk.peaks
            peak = np.stack([p[name].value for name in PEAK_SIGNALS], axis=1)
            peak_time = np.stack([p[name].time for name in PEAK_SIGNALS], axis=1)
            chunk = dataclasses.replace(
                chunk, run_peak=peak, run_peak_time=peak_time, peaks_exact=False
            )
        if horizon:
            m = tracking_metrics(chunk)
            metrics = np.stack([getattr(m, k) for k in HORIZON_METRICS], axis=1)
        del chunk
    kept = signals[:, rows, :]  # a copy of the kept rows only
    return kept, status, message, t_stop, peak, peak_time, samples, metrics


def _run_kept(run, rows, horizon, exact, *args):
    """``run(*args)`` reduced by :func:`_reduce_chunk` where it ran.

    Module-level so that Dask can pickle it: on a cluster the full signals
    of a chunk stay on its worker, only the kept ones travel.
    """
    return _reduce_chunk(run(*args), rows, horizon, exact, args)


def _lost_chunk(n: int, t_size: int, note: str):
    """The outputs of :func:`_run_chunk` for runs whose Dask task was lost."""
    nan = np.full((n, len(PEAK_SIGNALS)), np.nan)
    return (
        np.full((n, len(SIGNALS), t_size), np.nan),
        np.full(n, STATUS_FAILED, dtype=object),
        np.full(n, note, dtype=object),
        np.full(n, np.nan),
        nan,
        nan.copy(),
    )


def _chunk_controller(ctrl, lo: int, hi: int):
    """The controller of runs ``lo:hi`` (per-run parameters indexed)."""
    if ctrl is None or not ctrl.runs():
        return ctrl
    return ctrl.subset(np.arange(lo, hi))


class _NoBar:
    """The progress bar's interface when no bar is shown."""

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


# Seconds simulate_batch waits on a Dask cluster that has no worker
# before it gives up the pending chunks (marked "failed", then
# ClusterLostError, see _run_on_dask):
# long enough for a cluster that scales up from zero to start one.
_LOST_CLUSTER_WAIT = 60.0

# Seconds between two checks of the cluster's workers while chunks are pending.
_POLL_INTERVAL = 1.0


def _has_workers(client) -> bool:
    """Whether the Dask cluster behind `client` has a worker (True if unknown)."""
    info = getattr(client, "scheduler_info", None)
    if info is None:
        return True
    try:
        return bool(info().get("workers", True))
    except Exception:  # the scheduler went away: the wait will say so
        return True


def _run_on_dask(client, bounds, args, keep, t_size, bar, run) -> str | None:
    """Run the chunks on a Dask cluster; keep every chunk that finishes.

    A client that cannot take the tasks (closed) raises at once, before any
    work. A task the cluster loses afterwards (cancelled, worker or
    scheduler gone) does not discard the chunks that finished: its runs are
    marked ``"failed"`` with NaN data and a message naming Dask's error, and
    a :class:`RuntimeWarning` says how many runs were lost. A cluster left
    without workers (all killed, no nanny to restart them) would keep the
    tasks pending forever: once it has had no worker for
    ``_LOST_CLUSTER_WAIT`` (60) seconds, the pending tasks are cancelled,
    their runs marked failed in the same way, and the message returned:
    the caller builds the result of the finished chunks and raises
    :class:`~fws_control.ClusterLostError` with it. An exception raised by
    the simulation itself (e.g. an ambiguous initial projection)
    propagates, as it would locally.
    """
    try:
        from dask.distributed import wait
    except ImportError as exc:  # pragma: no cover - optional extra
        raise ImportError(
            "client= needs dask.distributed; install the extra "
            "`pip install fws-control[distributed]`"
        ) from exc
    if getattr(client, "status", "running") in ("closed", "closing"):
        raise RuntimeError(
            f"client={client!r} is closed: no chunk was submitted; start a "
            "new dask.distributed.Client or pass client=None to run here"
        )
    futures = {}
    try:
        for j, (lo, hi) in enumerate(bounds):
            fut = client.submit(run, *args(lo, hi), pure=False)
            futures[fut] = j
    except Exception as exc:
        for fut in futures:
            fut.cancel()
        raise RuntimeError(
            f"the Dask client could not take the chunks ({type(exc).__name__}: "
            f"{exc}); no chunk was kept"
        ) from exc
    pending = dict(futures)
    lost = []
    task_error = None
    cluster_lost = None  # the message once the cluster has no worker left
    idle_since = None  # since when the cluster has had no worker
    try:
        while pending and task_error is None:
            # (a cancelled future counts as done: dask's wait raises on it)
            done = [f for f in pending if f.done() or f.cancelled()]
            if not done:
                try:
                    done, _ = wait(
                        list(pending),
                        timeout=_POLL_INTERVAL,
                        return_when="FIRST_COMPLETED",
                    )
                except TimeoutError:
                    done = ()
                except Exception:
                    done = [f for f in pending if f.cancelled()]
                    if not done:
                        raise  # the cluster went away (below)
            for fut in done:
                j = pending.pop(fut)
                try:
                    chunk = fut.result()
                except Exception as exc:
                    if fut.status == "error":  # the simulation itself raised
                        task_error = exc
                        break
                    lost.append((j, exc))
                    continue
                keep(j, chunk)
                bar.update(1)
            if done or task_error is not None:
                idle_since = None
                continue
            if _has_workers(client):
                idle_since = None
            elif idle_since is None:
                idle_since = time.monotonic()
            elif time.monotonic() - idle_since > _LOST_CLUSTER_WAIT:
                exc = TimeoutError(
                    f"the Dask cluster has had no worker for {_LOST_CLUSTER_WAIT:g} "
                    "s: its workers are gone"
                )
                cluster_lost = str(exc)
                for fut, j in pending.items():
                    fut.cancel()
                    lost.append((j, exc))
                pending.clear()
    except Exception as exc:  # the cluster went away while we waited
        lost.extend((j, exc) for j in pending.values())
        pending.clear()
    if task_error is not None:
        for fut in pending:
            fut.cancel()
        raise task_error  # as it would be raised here
    for j, exc in lost:
        lo, hi = bounds[j]
        note = (
            f"not simulated: the Dask task of runs {lo}..{hi - 1} was lost "
            f"({type(exc).__name__}: {exc}); the other chunks were kept"
        )
        keep(j, _lost_chunk(hi - lo, t_size, note))
    if cluster_lost is not None:
        runs = sum(bounds[j][1] - bounds[j][0] for j, _ in lost)
        return (
            f"simulate_batch: {cluster_lost}; {runs} pending runs were not "
            "simulated (marked 'failed', NaN data); the finished chunks are "
            "kept in this error's `result`"
        )
    if lost:
        runs = sum(bounds[j][1] - bounds[j][0] for j, _ in lost)
        warnings.warn(
            f"simulate_batch: {runs} runs of {len(lost)} lost Dask tasks are "
            "marked 'failed' (NaN data); the finished chunks were kept",
            RuntimeWarning,
            stacklevel=3,
        )
    return None


#: Most solver steps a delay may force over the run (duration / delay).
_MAX_DELAY_STEPS = 1.0e4


def _prepare(
    vehicle,
    path,
    gains,
    speed,
    initial_state,
    duration,
    dt,
    t_eval,
    tau,
    opts,
    kept=None,
):
    """Validate the arguments shared by both runners; broadcast the runs."""
    check_type("vehicle", vehicle, Vehicle)
    # every run records lateral_accel and v_y (and the peak of lateral_accel)
    vehicle.cg_distance(
        needed_by="a simulation (its signals lateral_accel and v_y are at G)"
    )
    check_type("path", path, Path, "a fws_control Path (e.g. fws.Straight())")
    ctrl = gains if isinstance(gains, LateralController) else None
    if ctrl is None:
        g = run_gains(gains, name="gains")
        fields = (g.k1, g.k2, g.ratio)
    else:
        # a controller carries its own parameters: no gains to record (NaN)
        fields = (np.full(ctrl.runs() or 1, np.nan),) * 3
    n_gains = fields[0].size
    # scalars named here: the engine's float() of an array would not name them
    for name, value in (("duration", duration), ("dt", dt)):
        if value is not None and np.ndim(value) != 0:
            raise ValueError(
                f"{name} must be a scalar [s], got an array of shape {np.shape(value)}"
            )
    if tau is not None:
        tau = check_scalar("steering_lag", tau)
    speed_arr = np.atleast_1d(np.asarray(check_nonzero("speed", speed), dtype=float))
    if speed_arr.ndim != 1:
        raise ValueError(f"speed must be a scalar or 1-D, got shape {speed_arr.shape}")
    opts["model"], opts["tyre"] = check_model(vehicle, opts["model"], opts["tyre"])
    if opts["model"] == "dynamic" and np.any(speed_arr <= 0.0):
        # the slip angles atan2(., u) and the 1/u of the tyre model assume
        # forward motion
        raise ValueError(
            "speed must be > 0 for model='dynamic' (forward longitudinal speed "
            f"u of the single-track model), got {speed!r}"
        )
    x0 = split_initial_state(initial_state, model=opts["model"])
    sizes = {n_gains, speed_arr.size, x0.shape[0]} - {1}
    if len(sizes) > 1:
        raise ValueError(
            "gains, speed and initial_state must have one entry or the same "
            f"number of runs, got {n_gains}, {speed_arr.size} and {x0.shape[0]}"
        )
    n = sizes.pop() if sizes else 1
    k1, k2, a, V = (np.broadcast_to(v, (n,)).copy() for v in (*fields, speed_arr))
    x0 = np.broadcast_to(x0, (n, 5)).copy()
    # (before building the grid: dt = 1e-9 must not allocate 112 GiB first)
    samples = output_samples(duration, dt=dt, t_eval=t_eval)
    check_output_budget(
        n,
        samples,
        duration=duration,
        dt=dt,
        t_eval=t_eval,
        signals=len(SIGNALS) if kept is None else kept,
    )
    t = time_grid(duration, dt=dt, t_eval=t_eval)
    span = float(t[-1] - t[0])
    if ctrl is not None and is_sampled(ctrl):
        check_sampling(ctrl, span)
    if 0.0 < opts["delay"] < span / _MAX_DELAY_STEPS:
        # the method of steps takes steps no longer than the delay: a delay of
        # 1e-300 s would never finish
        raise ValueError(
            f"delay must be 0 or >= duration/{_MAX_DELAY_STEPS:g} = "
            f"{span / _MAX_DELAY_STEPS:.3g} s (the solver's steps are bounded by "
            f"the delay), got {opts['delay']!r}"
        )
    tau = resolve_time_constant(vehicle, tau)
    opts["rtol"], opts["atol"] = check_tolerances(opts["rtol"], opts["atol"])
    if isinstance(opts["method"], str) and opts["method"] == "auto":
        # (the duration: see the long-run rule there; the same for every
        # run of a batch, so that a run's accuracy does not depend on it)
        opts["method"] = choose_method(
            tau, opts["rtol"], duration=span, delay=opts["delay"]
        )
    else:
        _warn_if_stiff(check_method(opts["method"]), tau, float(t[-1]))
    return k1, k2, a, V, x0, t, tau, ctrl


#: Steps an explicit method may be forced to take by the actuator's
#: stability bound (about 6.4 T for DOP853) before a warning.
_STIFF_STEPS = 5000


def _warn_if_stiff(solver, tau, duration) -> None:
    """Warn when an explicitly chosen explicit method meets a stiff actuator."""
    if tau is None or not issubclass(solver, (DOP853, RK23, RK45)):
        return
    steps = duration / (6.4 * tau)
    if steps > _STIFF_STEPS:
        warnings.warn(
            f"method={solver.__name__!r} with steering_lag={tau!r} over "
            f"duration={duration!r}: the actuator makes the loop stiff, so this "
            f"explicit method needs about {steps:.2g} steps (its step is bounded "
            "near 6.4 times the time constant); method='auto' or 'Radau' steps "
            "by accuracy instead",
            RuntimeWarning,
            stacklevel=4,
        )


def _simulate_run(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: float,
    initial_state: Any,
    duration: float,
    feedforward: bool = True,
    dt: float = 0.01,
    t_eval: Any = None,
    actuator_time_constant: float | None = None,
    delay: float = 0.0,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    model: str = "kinematic",
    tyre: str = "linear",
    engine: str = "auto",
    profile: SpeedProfile | None = None,
    schedule: Any = None,
) -> SimulationResult:
    """:func:`simulate` on the resolved plant (its vehicle, speed, model,
    tyre and lag as separate arguments)."""
    n_gains = (
        (gains.runs() or 1)
        if isinstance(gains, LateralController)
        else run_gains(gains, name="gains").k1.size
    )
    if n_gains != 1:
        raise ValueError(
            f"controller must be scalar for simulate (got {n_gains} designs); use "
            "simulate_batch for several runs"
        )
    if np.size(speed) != 1:
        raise ValueError(
            f"speed must be a scalar for simulate, got {speed!r}; use "
            "simulate_batch for several runs"
        )
    if np.ndim(initial_state) != 1:
        raise ValueError(
            "initial_state must be (x_R, y_R, psi) for simulate, got shape "
            f"{np.shape(initial_state)}; use simulate_batch for several runs"
        )
    batch = _simulate_batch(
        vehicle,
        path,
        gains,
        speed=speed,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        dt=dt,
        t_eval=t_eval,
        actuator_time_constant=actuator_time_constant,
        delay=delay,
        method=method,
        rtol=rtol,
        atol=atol,
        model=model,
        tyre=tyre,
        engine=engine,
        chunk_size=1,
        progress=False,
        profile=profile,
        schedule=schedule,
    )
    # batch[0] without copying the signals: the squeezed run's grid ends at
    # its last sample (a view of the batch's arrays).
    count = int(batch.run_samples[0])
    return dataclasses.replace(
        batch, t=batch.t[:count], signals=batch.signals[:, :, :count], squeeze=True
    )


def _simulate_batch(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains | Any,
    *,
    speed: Any,
    initial_state: Any,
    duration: float,
    feedforward: bool = True,
    dt: float = 0.01,
    t_eval: Any = None,
    actuator_time_constant: float | None = None,
    delay: float = 0.0,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    model: str = "kinematic",
    tyre: str = "linear",
    engine: str = "auto",
    chunk_size: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    signals: Any = None,
    out: np.ndarray | None = None,
    profile: SpeedProfile | None = None,
    schedule: Any = None,
) -> SimulationResult:
    """:func:`simulate_batch` on the resolved plant (its vehicle, speed,
    model, tyre and lag as separate arguments). With a varying speed
    `profile`, `speed` is only its direction (+1 or -1) and the recorded
    speed of each run is the profile's at its start; with a `schedule` the
    recorded gains are the schedule's at that speed."""
    if not isinstance(engine, str) or engine not in _ENGINES:
        raise ValueError(f"engine must be one of {_ENGINES}, got {engine!r}")
    if profile is not None:
        _check_profile_run(
            profile, model=model, delay=delay, feedforward=feedforward,
            gains=gains, engine=engine,
        )  # fmt: skip
    auto_method = isinstance(method, str) and method == "auto"
    opts = {
        "method": method,
        "rtol": rtol,
        "atol": atol,
        "delay": check_delay(delay),
        "model": model,
        "tyre": tyre,
    }
    kept = _check_signals(signals)
    k1, k2, a, V, x0, t, tau, ctrl = _prepare(
        vehicle,
        path,
        gains,
        speed,
        initial_state,
        duration,
        dt,
        t_eval,
        actuator_time_constant,
        opts,
        # a given out holds the kept signals: only the chunk's working set
        # is counted (below)
        kept=0 if out is not None else len(kept),
    )
    n = k1.size
    if profile is not None:
        # the speed of each run at its start: the record of the run
        x_start = np.full(n, float(t[0]))
        if profile.of == "distance":
            x_start = initial_path_state(path, x0[:, :3])[:, 0]
        V = np.asarray(profile(x_start), dtype=float)
        if schedule is not None:
            g0 = scheduled_gains(schedule, V)
            k1, k2, a = (
                np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy()
                for v in (g0.k1, g0.k2, g0.ratio)
            )
        opts["profile"], opts["schedule"] = profile, schedule
        if engine == "auto" and schedule is not None:
            _say_if_schedule_not_compiled(schedule)
    if out is not None:
        _check_out(out, (n, len(kept), t.size))
    # False, True (eq. 26) or "dynamic" (dynamics.dynamic_feedforward)
    feedforward = check_feedforward(feedforward, speed=V)
    if feedforward == "dynamic":
        require_dynamics(vehicle, tyre=opts["tyre"])
        if np.any(V <= 0.0):
            raise ValueError(
                f"speed must be > 0 for feedforward='dynamic', got {speed!r}"
            )
    else:
        feedforward = bool(feedforward)
    table = None
    # With an actuator, "auto" on the compiled engine is DOP853 with its steps
    # held to half its stability bound (see _CAPPED_STEP), or Radau beyond
    # _RADAU_FROM_STEPS such steps, also where the numpy engine would take
    # LSODA or Radau: the compiled engine runs every stiff case.
    stiff_auto = auto_method and tau is not None
    if engine == "auto":
        engine, table = _choose_engine(
            path,
            SteeringGains(k1, k2, a) if ctrl is None else ctrl,
            delay=opts["delay"],
            method="DOP853" if stiff_auto else opts["method"],
            model=opts["model"],
            feedforward=feedforward,
            profile=profile,
            schedule=schedule,
        )
    if engine == "compiled" and auto_method:
        duration_run = float(t[-1] - t[0])
        # (with a delay or the dynamic model the compiled engine has DOP853
        # only; with a delay its steps are at most the delay too)
        if (
            stiff_auto
            and duration_run > _RADAU_FROM_STEPS * _CAPPED_STEP * tau
            and not opts["delay"] > 0.0
            and opts["model"] == "kinematic"
            and profile is None
        ):
            opts["method"] = "Radau"
        else:
            opts["method"] = "DOP853"
            if tau is not None:
                opts["max_step"] = _CAPPED_STEP * tau
    if engine == "compiled":
        _check_compiled(
            path,
            SteeringGains(k1, k2, a) if ctrl is None else ctrl,
            delay=opts["delay"],
            method=opts["method"],
            model=opts["model"],
            feedforward=feedforward,
            profile=profile,
            schedule=schedule,
        )
        if table is None:
            from .compiled import curvature_table

            table = curvature_table(path)
        opts["curvature_table"] = table  # built once, for every chunk
    if chunk_size is None:
        chunk_size = DEFAULT_CHUNK_SIZE
        if engine == "numpy" and opts["method"] == "LSODA":
            # LSODA's Jacobian of the stacked runs is dense. Measured (CPU
            # per run, T = 0.05 s, curve scenario): 16 runs per chunk 17.6 ms
            # over 15 s and 28 ms over 150 s, 32 runs 12.7 and 39 ms, one
            # run 156 and 187 ms. The stacked runs share LSODA's steps and
            # error norm: a run 0.72 tolerances off alone was 0.74 and 2.0 off
            # in two mixed chunks (within its tolerance, not bitwise alone;
            # chunk_size=1 is).
            chunk_size = LSODA_MAX_RUNS
    if (
        isinstance(chunk_size, bool)
        or not isinstance(chunk_size, (int, np.integer, float))
        or not math.isfinite(chunk_size)
        or int(chunk_size) != chunk_size
        or chunk_size < 1
    ):
        raise ValueError(f"chunk_size must be an integer >= 1, got {chunk_size!r}")
    chunk_size = int(chunk_size)
    if kept != SIGNALS or out is not None:
        # the working set: one chunk's full signals (the kept ones are counted
        # in _prepare, unless they go to out)
        try:
            check_output_budget(
                min(chunk_size, n), t.size, duration=duration, dt=dt, t_eval=t_eval
            )
        except ValueError as exc:
            where = f"keeps {len(kept)} of them"
            if out is not None:
                where = "writes them into out"
            raise ValueError(
                f"chunk_size={chunk_size}: a chunk computes all {len(SIGNALS)} "
                f"signals before it {where}, and {exc}; or a smaller chunk_size"
            ) from None
    bounds = [(i, min(i + chunk_size, n)) for i in range(0, n, chunk_size)]
    if progress is None:
        progress = _stderr_is_tty()
    progress = check_bool("progress", progress)

    run = _run_isolated if engine == "numpy" else _run_compiled
    # both engines give the exact peaks of the continuous solution (the
    # compiled one on each run's own dense output)
    exact = True
    reduce = kept != SIGNALS
    if reduce:
        rows = [SIGNALS.index(k) for k in kept]
        horizon = not {"e", "theta"} <= set(kept)
        run = functools.partial(_run_kept, run, rows, horizon, exact)

    def args(lo, hi):
        return (
            vehicle,
            path,
            k1[lo:hi],
            k2[lo:hi],
            a[lo:hi],
            V[lo:hi],
            feedforward,
            x0[lo:hi],
            t,
            tau,
            opts,
            _chunk_controller(ctrl, lo, hi),
        )

    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(bounds), desc="simulate_batch", unit="chunk")
    else:
        # no bar, no tqdm import (tqdm.auto pulls in asyncio: 0.05 s of CPU
        # in a fresh process, a tenth of a short CLI call)
        bar = _NoBar()
    # The chunks are written into the batch's arrays of the kept signals as
    # they arrive (a single chunk is kept as it is) and freed, so no second
    # copy of the signals builds up: the peak memory is the result and one
    # chunk's working set.
    single = len(bounds) == 1 and out is None
    if out is not None:
        data = out
    else:
        data = None if single else np.empty((n, len(kept), t.size))
    status = np.empty(n, dtype=object)
    message = np.empty(n, dtype=object)
    t_stop = np.empty(n)
    peak = np.empty((n, len(PEAK_SIGNALS)))
    peak_time = np.empty((n, len(PEAK_SIGNALS)))
    samples = np.empty(n, dtype=np.int64) if reduce else None
    metrics = np.empty((n, len(HORIZON_METRICS))) if reduce and horizon else None

    def keep(j, chunk, written=False):
        nonlocal data
        lo, hi = bounds[j]
        if reduce and len(chunk) == 6:  # a lost Dask task: reduced here
            chunk = _reduce_chunk(chunk, rows, horizon, exact, args(lo, hi))
        if single:
            data = chunk[0]
        elif not written:
            data[lo:hi] = chunk[0]
        parts = (status, message, t_stop, peak, peak_time, samples, metrics)
        for whole, part in zip(parts, chunk[1:], strict=False):
            if whole is not None:
                whole[lo:hi] = part

    cluster_lost = None
    try:
        if client is None:
            # The compiled engine writes all signals straight into the
            # batch's array: no chunk buffer to fill and copy (46 MB for 256
            # runs of the paper's scenario; about 10 us of CPU per run).
            direct = engine == "compiled" and not reduce and data is not None
            for j, (lo, hi) in enumerate(bounds):
                if direct:
                    # (a memmap's rows as a plain array view: the same memory)
                    part = np.asarray(data[lo:hi])
                    keep(j, _run_compiled(*args(lo, hi), out=part), True)
                else:
                    keep(j, run(*args(lo, hi)))
                bar.update(1)
        else:
            cluster_lost = _run_on_dask(client, bounds, args, keep, t.size, bar, run)
    finally:
        bar.close()

    result = SimulationResult(
        t=t,
        signals=data,
        run_status=status.astype(str),
        run_message=tuple(str(m) for m in message),
        run_t_stop=t_stop,
        # without the samples, the sample peaks were computed per chunk
        run_peak=peak if exact or reduce else None,
        run_peak_time=peak_time if exact or reduce else None,
        run_speed=V,
        run_k1=k1,
        run_k2=k2,
        run_ratio=a,
        run_initial_state=x0[:, :3],
        feedforward=feedforward,
        squeeze=False,
        vehicle=vehicle,
        path=path,
        method=opts["method"]
        if isinstance(opts["method"], str)
        else opts["method"].__name__,
        model=opts["model"],
        tyre=opts["tyre"],
        engine=engine,
        signal_names=kept,
        run_samples=samples,
        run_metrics=metrics,
        peaks_exact=exact,
        speed_profile=profile,
    )
    if cluster_lost is not None:
        raise ClusterLostError(cluster_lost, result=result)
    return result


#: The keywords of the deprecated Vehicle form of simulate/simulate_batch
#: that the plant now holds.
_PLANT_KEYWORDS = ("speed", "model", "tyre", "steering_lag", "actuator_time_constant")


def _profile_start(profile: SpeedProfile) -> float:
    """Where a profile is read for the direction and the nominal gains."""
    if profile.of == "time" or profile.points is None:
        return 0.0
    return float(profile.points[0])


def _say_if_schedule_not_compiled(schedule) -> None:
    """Warn that a gain schedule given as a function runs on the numpy engine."""
    from ..schedule import GainSchedule

    if isinstance(schedule, GainSchedule):
        return
    warnings.warn(
        f"the gain schedule {schedule!r} is a Python function, evaluated at "
        "every step: this varying-speed run is not compiled and runs on the "
        "numpy engine (a GainSchedule table is compiled)",
        RuntimeWarning,
        stacklevel=5,
    )


def _check_profile_run(profile, *, model, delay, feedforward, gains, engine) -> None:
    """Refuse the cases a varying speed is not simulated in (ValueError)."""
    if np.ndim(delay) == 0 and float(delay) > 0.0:
        raise ValueError(
            f"delay must be 0 with a varying speed (speed={profile!r}), got "
            f"{delay!r}: the delayed measurements would need the speed of their "
            "own time"
        )
    if isinstance(feedforward, str) and feedforward == "dynamic":
        raise ValueError(
            "feedforward='dynamic' is not simulated with a varying speed "
            f"(speed={profile!r}); use feedforward=True (eq. 26, independent "
            "of the speed) or False"
        )
    if isinstance(gains, LateralController):
        raise ValueError(
            f"controller: {type(gains).__name__} is not simulated with a varying "
            f"speed (speed={profile!r}); use SteeringGains or a gain schedule"
        )
    if model == "dynamic" and profile.speeds is not None:
        low = np.flatnonzero(profile.speeds <= 0.0)
        if low.size:
            i = int(low[0])
            raise ValueError(
                f"speed: the SpeedProfile's speeds must lie in (0, inf) m/s for "
                f"model='dynamic' (forward longitudinal speed u), got "
                f"{float(profile.speeds[i])!r} at index {i}"
            )


def _speed_option(plant: Any, speed: Any, kwargs: dict) -> SpeedProfile | None:
    """The varying speed of a plant-first call, or None.

    For the deprecated Vehicle form, `speed` is its constant speed and goes
    back to `kwargs`. A constant profile gives None (the plant's speed is
    replaced by the caller).
    """
    if speed is None:
        return None
    if not isinstance(plant, LateralPlant):
        kwargs["speed"] = speed
        return None
    if isinstance(speed, SpeedProfile):
        return speed
    raise TypeError(
        f"speed={speed!r} ({type(speed).__name__}) with a LateralPlant: a number "
        "as speed= applies only to the deprecated Vehicle form (the plant holds "
        "its constant speed: dataclasses.replace(plant, speed=...)); speed= "
        "must be None or a fws.SpeedProfile (e.g. fws.SpeedProfile.from_time(t, "
        "v)) for a speed that varies"
    )


def _is_schedule(controller: Any) -> bool:
    """A gain schedule: ``at(speed)`` or a plain function of the speed."""
    if isinstance(controller, (SteeringGains, LateralController)):
        return False
    return callable(getattr(controller, "at", None)) or callable(controller)


def _scheduled(controller: Any, speed: Any) -> Any:
    """The gains of a gain schedule at the run's speed; others unchanged.

    A gain schedule is an object with a method ``at(speed)`` that returns
    :class:`~fws_control.SteeringGains` (e.g.
    :class:`~fws_control.GainSchedule`); the runs hold their speed, so the
    schedule is read once per run. Its range errors name the speed.
    """
    if isinstance(controller, (SteeringGains, LateralController)):
        return controller
    at = getattr(controller, "at", None)
    if not callable(at):
        return controller
    gains = at(np.asarray(speed, dtype=float))
    if not isinstance(gains, SteeringGains):
        raise TypeError(
            f"controller.at(speed) must return a SteeringGains (a gain "
            f"schedule), got {type(gains).__name__} from {controller!r}"
        )
    return gains


def _resolve_plant(function: str, plant: Any, controller: Any, kwargs: dict):
    """``(vehicle, controller, speed, model, tyre, lag)`` of a call.

    `plant` is a :class:`LateralPlant`, or (deprecated, with a
    FutureWarning) a :class:`Vehicle` with the keywords of
    :data:`_PLANT_KEYWORDS` in `kwargs`. The deprecated ``gains=`` names
    the controller. `kwargs` is emptied; an unknown keyword raises.
    """
    controller = legacy_keyword(kwargs, "gains", _CONTROLLER[function], controller)
    if controller is None:
        raise TypeError(
            f"{function}() missing the argument {_CONTROLLER[function]!r} (a "
            "SteeringGains or a lateral controller)"
        )
    if isinstance(plant, LateralPlant):
        given = [k for k in _PLANT_KEYWORDS if k in kwargs]
        if given:
            raise TypeError(
                f"{function}(): {', '.join(k + '=' for k in given)} applies only "
                "to the deprecated Vehicle form; the LateralPlant already holds "
                "its speed, model, tyre and steering lag (e.g. "
                "dataclasses.replace(plant, steering_lag=0.1))"
            )
        reject_unknown(function, kwargs)
        lag = plant.steering_lag
        if lag is not None:
            front, rear = lag
            if front != rear:
                raise ValueError(
                    f"plant.steering_lag must hold one time constant for both "
                    f"axles in the simulation (front == rear > 0 s), got "
                    f"{lag!r}: the simulated actuator has one time constant"
                )
            lag = front
        # "kinematic" and "paper" are two linearisations of one nonlinear
        # kinematic model, which is what is simulated
        model = "dynamic" if plant.model == "dynamic" else "kinematic"
        return plant.vehicle, controller, plant.speed, model, plant.tyre, lag
    if isinstance(plant, Vehicle):
        if "speed" not in kwargs:
            raise TypeError(
                f"{function}(): plant must be a fws.LateralPlant (vehicle, speed, "
                f"model, tyre, steering lag), got a Vehicle without speed=; pass "
                f"fws.LateralPlant(vehicle, speed=...)"
            )
        warn_deprecated(
            f"{function}(vehicle, path, gains, speed=...)",
            f"{function}(plant, path, {_CONTROLLER[function]}) and pass a "
            "fws.LateralPlant(vehicle, speed=..., model=..., tyre=..., "
            "steering_lag=...) as the plant",
        )
        speed = kwargs.pop("speed")
        model = kwargs.pop("model", "kinematic")
        tyre = kwargs.pop("tyre", "linear")
        lag = legacy_keyword(
            kwargs, "actuator_time_constant", "steering_lag",
            kwargs.pop("steering_lag", None),
        )  # fmt: skip
        reject_unknown(function, kwargs)
        return plant, controller, speed, model, tyre, lag
    raise TypeError(
        f"{function}(): plant must be a fws.LateralPlant (the simulated system: "
        f"vehicle, speed, model, tyre, steering lag), got {type(plant).__name__}"
    )


_CONTROLLER = {"simulate": "controller", "simulate_batch": "controllers"}


def simulate(
    plant: LateralPlant,
    path: Path,
    controller: SteeringGains | LateralController | None = None,
    *,
    initial_state: Any,
    duration: float,
    delay: float = 0.0,
    feedforward: bool | str = True,
    dt: float = 0.01,
    t_eval: Any = None,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    engine: str = "auto",
    speed: SpeedProfile | None = None,
    **kwargs: Any,
) -> SimulationResult:
    r"""Simulate the closed loop (one run) with the fast path-frame engine.

    Integrates the corrected path-frame model (eqs. 17-19 with the curvature
    :math:`\kappa(s)` of the path at the projection point) closed with the
    controller of eqs. (24)-(29) in one right-hand side. The initial pose is
    projected onto the path once; the global pose is reconstructed from
    ``(s, e, theta)``.

    Parameters
    ----------
    plant : LateralPlant
        The simulated system, the same object the analysis takes: its
        vehicle (geometry and optional steering limits: angle limits clip
        the commands, rate limits insert the actuator of
        :func:`~fws_control.steering_actuator`), its `speed` :math:`V`
        [m/s] (one nonzero number; negative: reversing), its `model` and
        `tyre` and its `steering_lag`. ``model="kinematic"`` and
        ``model="paper"`` are two linearisations of one nonlinear kinematic
        model: both simulate that nonlinear model (eqs. 17-19). With
        ``model="dynamic"`` the single-track model of
        :mod:`fws_control.dynamics` is integrated (tyre slip; lateral velocity
        and yaw rate as states; `speed` is its constant longitudinal speed
        :math:`u > 0`), with the plant's `tyre` (linear, or the saturating
        simplified magic formula). The path errors are those of the
        rear-axle centre R in both models, so every controller applies
        unchanged; delay and lag combine with either model. The plant's
        `steering_lag` :math:`T` [s] is a first-order actuator
        :math:`T\dot\delta = \delta_{cmd} - \delta` on each axle, whose rate
        the vehicle's rate limits clip (its states start at the initial
        command); the simulation runs one time constant for both axles, so
        a (front, rear) pair must hold equal values. ``None``: an actuator
        only if the vehicle has a rate limit, with
        :data:`~fws_control.controllers.DEFAULT_ACTUATOR_TIME_CONSTANT`.
        The plant's `curvature` is its linearisation point and is not used
        here: the path gives the curvature along the run.
    path : Path
        Reference path (e.g. :class:`~fws_control.Straight`,
        :class:`~fws_control.Arc`).
    controller : SteeringGains, LateralController or GainSchedule
        Scalar ``k1, k2, ratio`` of the paper's law, or any controller of
        :mod:`fws_control.baselines` (e.g. :class:`~fws_control.PurePursuit`),
        which carries its own feedforward (`feedforward` applies to gains
        only), or a gain schedule (:class:`~fws_control.GainSchedule`, or
        any object whose ``at(speed)`` returns SteeringGains): its gains at
        the plant's speed. A sampled controller (one with a
        :attr:`~fws_control.LateralController.sample_time`, e.g.
        :class:`~fws_control.MPCController`) measures the state at the
        sample times ``k * sample_time`` and its command is held from
        ``k * sample_time + delay`` until the next one (zero-order hold; the
        output at a switch time shows the new command, whose rate is zero
        between switches), on the numpy engine.
    initial_state : array_like
        ``(x_R, y_R, psi)`` of the rear-axle centre [m, m, rad].
    duration : float
        Final time [s], > 0.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        Include the curvature feedforward (default ``True``, the same as
        ``"kinematic"``: eq. 26); ``False`` is the feedback-only controller;
        ``"dynamic"`` the front and rear angles of
        :func:`~fws_control.dynamics.dynamic_feedforward` (for the plant's
        tyre model), which hold the dynamic model on a curve without offset.
    dt : float, optional
        Nominal spacing of the output times [s] (the solver chooses its own
        steps). The grid is ``linspace(0, duration, round(duration/dt) + 1)``,
        so the actual spacing is ``duration/round(duration/dt)`` (at least
        one interval): pass `t_eval` for exact times. It sets the output
        only, not the accuracy (`rtol`, `atol`); the signals of one call may
        not exceed
        :data:`~fws_control.simulation.engine.MAX_OUTPUT_BYTES` (2 GiB).
    t_eval : array_like, optional
        Output times instead of `dt`; increasing, from 0 to at most
        `duration`.
    delay : float, optional
        Input delay :math:`\tau_d \ge 0` [s] on the steering command: the
        controller acts on the measurements of ``t - delay`` (perception and
        computation latency). Initial history: the state is held at its
        initial value before ``t = 0``, so the command is the one of the
        initial state until ``t = delay``. Integrated by the method of steps
        (see :func:`~fws_control.simulation.engine.integrate`). Default 0.
        The delay belongs to the loop, not to the plant, as in the analysis
        (:func:`~fws_control.critical_delay` of a plant and gains; the
        delayed charts take ``delay=``).
    method : str or scipy.integrate.OdeSolver, optional
        Integration method: ``"auto"`` (default), a name in ``"DOP853",
        "RK45", "RK23", "Radau", "BDF", "LSODA"`` or an OdeSolver class. The
        engine steps that solver itself, as :func:`scipy.integrate.solve_ivp`
        would, so that it can stop a run at a singular state. ``"auto"`` is
        DOP853, or Radau when a fast actuator makes the loop stiff, or LSODA
        for a run long enough that the actuator's stability bound would cost
        DOP853 more than 10 steps (rule and measurements in
        :func:`~fws_control.simulation.engine.choose_method`); the result's
        ``method`` says which. An explicit method chosen for a stiff loop
        gives a :class:`RuntimeWarning`.
    rtol, atol : float, optional
        Relative and absolute tolerances of the solver: rtol in
        ``[100 eps, 0.1]`` (scipy's own floor to a 10 % error per step),
        atol in ``[1e-20, 0.1]`` [m, rad]; see
        :func:`~fws_control.simulation.engine.check_tolerances`.
    engine : {"auto", "numpy", "compiled"}, optional
        ``"compiled"``: the numba ports of DOP853 and Radau of
        :mod:`fws_control.simulation.compiled` (extra ``fast``), each run
        with its own steps and stop, at compiled speed. It runs the paper's
        law (:class:`~fws_control.SteeringGains`) on the kinematic model
        (and on the dynamic model with DOP853 and no delay)
        with ``method="DOP853"``, ``"Radau"`` or ``"auto"``
        (which then means DOP853; with an actuator of time constant T, its
        steps held to 3.2 T, half its stability bound, where its error
        estimate bounds the error again, up to 2,500 such steps, and Radau
        beyond: 9-13 ms per run of the paper's curve scenario whatever T
        and the duration; with a delay DOP853 only, its steps at most the
        delay: the method of steps, its clips min/max as the numpy
        engine's) and `feedforward` True or
        False, on any path whose curvature it can tabulate; any other case
        raises :class:`ValueError` (no fallback). Its results agree with the
        numpy engine's to the solver tolerance (the same method; angle and
        rate limits are switched as events, and a run stops ``1e-3`` before
        a singularity: see that module), and its
        :attr:`~fws_control.SimulationResult.peaks` are the exact peaks of
        each run's own dense output
        (:func:`~fws_control.simulation.compiled.compiled_peaks`).
        ``"numpy"``: the engine described above, for every case.
        ``"auto"`` (default): the compiled engine where numba is installed
        and it runs the case (with ``method="auto"`` and an actuator: DOP853
        held to 3.2 T or Radau, as above; the numpy engine's own choice is
        :func:`~fws_control.simulation.engine.choose_method`); the numpy
        engine otherwise. The result's
        ``engine`` says which ran, and is bitwise the result of asking for
        that engine explicitly.
    speed : SpeedProfile, optional
        A speed that varies along the run (:class:`~fws_control.SpeedProfile`:
        a table of the time or of the arc length, a braking manoeuvre, a
        function), instead of the plant's constant speed, which is then its
        linearisation point only. A table (of the time or the arc length)
        runs on the compiled engine (DOP853), with a gain schedule only a
        :class:`~fws_control.GainSchedule` whose grid holds the profile's
        speeds; a function profile or schedule runs on the numpy engine
        (``engine="auto"`` chooses it, with a RuntimeWarning for a schedule
        function; ``"compiled"`` raises). The
        dynamic model's longitudinal speed :math:`u` follows the profile,
        and a gain schedule passed as `controller` (a
        :class:`~fws_control.GainSchedule` or a function ``speed ->
        SteeringGains``) is read at the current speed at every step. The
        result's :attr:`~fws_control.SimulationResult.longitudinal_speed`,
        ``longitudinal_accel``, ``longitudinal_force`` and
        ``friction_usage`` report the longitudinal motion. Not with a
        delay, ``feedforward="dynamic"`` or a controller of
        :mod:`fws_control.baselines` (ValueError). A constant profile
        (:meth:`~fws_control.SpeedProfile.constant`) is the constant-speed
        run on the plant with that speed. See ``docs/varying_speed.md``.

    **kwargs
        Deprecated calling form, accepted until fws_control 0.4 with a
        :class:`FutureWarning`: a :class:`~fws_control.Vehicle` as `plant`
        with ``speed=``, ``model=`` ({"kinematic", "dynamic"}), ``tyre=``
        and ``steering_lag=`` (formerly ``actuator_time_constant=``), and
        ``gains=`` for `controller`. Any other keyword raises
        :class:`TypeError`.

    Returns
    -------
    SimulationResult
        One run, squeezed: ``res.e`` etc. have shape ``(time,)``,
        ``res.status`` is a str. If the run meets a singular state it stops
        there; ``status`` and ``message`` say why and the data end at the
        last output time before ``t_stop``.

    Raises
    ------
    TypeError
        If `plant` is not a :class:`~fws_control.LateralPlant` (a
        :class:`~fws_control.Vehicle` without ``speed=`` included), or for
        an unknown keyword.
    ValueError
        For non-scalar gains, plant speed or initial state (use
        :func:`simulate_batch`), a plant whose front and rear lags differ, a
        non-positive duration, an unknown method or feedforward, tolerances
        out of range, or an output larger than
        :data:`~fws_control.simulation.engine.MAX_OUTPUT_BYTES`; for
        ``feedforward="dynamic"`` a vehicle without the dynamic data or a
        negative speed; for an unknown `engine`, or ``engine="compiled"``
        for a case it does not run (the message says why).
    AmbiguousProjectionError
        If the initial position has no unique closest point on the path.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(fws.LateralPlant(veh, speed=5.0, curvature=0.1),
    ...                           ratio=-1.0, pole=-1.0)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> res = fws.simulate(plant, fws.Arc(curvature=0.1), g,
    ...                    initial_state=(0.0, -5.0, 0.0), duration=15.0)
    >>> res.status, round(float(res.e[0]), 6), round(float(res.e[-1]), 5)
    ('ok', -5.0, -3e-05)
    >>> len(res), res.e.shape
    (1, (1501,))
    """
    profile = _speed_option(plant, speed, kwargs)
    vehicle, controller, speed, model, tyre, lag = _resolve_plant(
        "simulate", plant, controller, kwargs
    )
    profile, speed, controller, schedule = _with_profile(profile, speed, controller)
    if isinstance(plant, LateralPlant) and np.ndim(speed) != 0:
        raise ValueError(
            "plant.speed must be one speed (a scalar, nonzero, at most "
            f"{MAX_SPEED:g} m/s) for simulate, got an array of shape "
            f"{np.shape(speed)}: {np.array2string(np.asarray(speed), threshold=6)}; "
            "use simulate_batch for several runs"
        )
    return _simulate_run(
        vehicle,
        path,
        controller,
        speed=speed,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        dt=dt,
        t_eval=t_eval,
        actuator_time_constant=lag,
        delay=delay,
        method=method,
        rtol=rtol,
        atol=atol,
        model=model,
        tyre=tyre,
        engine=engine,
        profile=profile,
        schedule=schedule,
    )


def _with_profile(profile, speed, controller):
    """``(profile, speed, controller, schedule)`` of a call.

    A constant profile replaces the plant's speed (the run is then the
    constant-speed run, on either engine). With a varying profile a gain
    schedule is kept as the `schedule`, read at the current speed during
    the run, and `speed` becomes the direction of travel; otherwise a
    schedule is read once at the plant's speed (:func:`_scheduled`).
    """
    if profile is not None and np.ndim(speed) != 0:
        raise ValueError(
            "plant.speed must be one number with speed= a SpeedProfile (the "
            "profile gives every run's speed; the plant's is its linearisation "
            f"point), got an array of shape {np.shape(speed)}"
        )
    if profile is not None and profile.is_constant:
        speed, profile = float(profile.speeds[0]), None
    if profile is None:
        return None, speed, _scheduled(controller, speed), None
    schedule = None
    if _is_schedule(controller):
        # the gains at the profile's start count the runs (the record is
        # the schedule's at each run's own start)
        schedule = controller
        controller = scheduled_gains(schedule, profile(_profile_start(profile)))
    return profile, profile.initial_sign or 1.0, controller, schedule


def simulate_batch(
    plant: LateralPlant,
    path: Path,
    controllers: SteeringGains | Any = None,
    *,
    initial_state: Any,
    duration: float,
    delay: float = 0.0,
    feedforward: bool | str = True,
    dt: float = 0.01,
    t_eval: Any = None,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    engine: str = "auto",
    speed: SpeedProfile | None = None,
    chunk_size: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    signals: Any = None,
    out: np.ndarray | None = None,
    **kwargs: Any,
) -> SimulationResult:
    r"""Simulate many closed loops at once on stacked numpy state.

    Parameters
    ----------
    plant : LateralPlant
        The simulated system (shared by all runs), as in :func:`simulate`;
        its `speed` may be an array, one speed per run (1-D), broadcast
        against the gains and the initial states. Its `curvature` is not
        used (the path gives the curvature).
    path : Path
        Reference path (shared by all runs).
    controllers : SteeringGains, sequence of SteeringGains or LateralController
        Per-run gains: one :class:`~fws_control.SteeringGains` whose fields
        are arrays (e.g. from :func:`~fws_control.double_root_gains` over an
        array of ratios; flattened), or a sequence of them; or a controller
        of :mod:`fws_control.baselines` (its array parameters, if any, hold
        one value per run). A controller's runs record NaN gains. A gain
        schedule (:class:`~fws_control.GainSchedule`) gives each run its
        gains at that run's speed. A sampled controller (e.g.
        :class:`~fws_control.MPCController`) is held between its samples as
        in :func:`simulate`, each run with its own controller state.
    initial_state : array_like
        ``(x_R, y_R, psi)`` for all runs, or shape ``(runs, 3)``; with
        a ``model="dynamic"`` plant also ``(x_R, y_R, psi, v_y, r)`` or ``(runs,
        5)``, as in :func:`simulate`.
    duration : float
        Final time [s], > 0.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        Curvature feedforward (default ``True``), as in :func:`simulate`.
    dt : float, optional
        Nominal output spacing [s], as in :func:`simulate`.
    t_eval : array_like, optional
        Output times instead of `dt`, as in :func:`simulate`.
    delay : float, optional
        Input delay [s] on the steering command, as in :func:`simulate` (a
        property of the loop, not of the plant).
    method : str or scipy.integrate.OdeSolver, optional
        Integration method, as in :func:`simulate`.
    rtol, atol : float, optional
        Solver tolerances, as in :func:`simulate`.
    engine : {"auto", "numpy", "compiled"}, optional
        Integration engine, as in :func:`simulate` (default ``"auto"``: the
        compiled engine where numba is installed and it runs the case --
        the paper's law, kinematic model, DOP853, Radau or ``"auto"``
        (with a delay, or on the dynamic model without delay, DOP853 or
        ``"auto"``) -- else the numpy engine). With
        ``"compiled"`` each run has its own steps, error norm and stop, so a
        run's result does not depend on the other runs (nor on
        `chunk_size`).
    speed : SpeedProfile, optional
        A speed that varies along the run, shared by all runs, as in
        :func:`simulate` (the plant's `speed` then must be one number: its
        linearisation point). Each run's recorded ``speed`` is the
        profile's at its start. A table runs on the compiled engine under
        ``"auto"`` (see :func:`simulate`).
    chunk_size : int, optional
        Runs per chunk (one solver; one Dask task); default
        :data:`DEFAULT_CHUNK_SIZE`, or
        :data:`~fws_control.simulation.engine.LSODA_MAX_RUNS` (16) when the
        numpy engine integrates with LSODA (``method="LSODA"``, or what
        ``method="auto"`` picks for a stiff actuator over a long run).
        Smaller chunks decouple the step sizes of runs with very different
        dynamics.
    client : dask.distributed.Client, optional
        Submit the chunks to this Dask cluster (needs the extra
        ``distributed``). The vehicle, path and arguments are pickled to the
        workers. Chunks that the cluster loses (a task cancelled, the
        scheduler gone) are marked ``"failed"`` with NaN data and a
        :class:`RuntimeWarning`; the finished chunks are kept. A cluster
        left with no worker for 60 s raises
        :class:`~fws_control.ClusterLostError`, whose ``result`` holds the
        finished chunks (the pending runs marked ``"failed"``).
    progress : bool, optional
        Show a tqdm progress bar over the chunks. ``None`` (default): only if
        standard error is a terminal.
    signals : None, sequence of str or "metrics", optional
        The time series to keep, for sweeps too large to hold them all.
        ``None`` (default): all of
        :data:`~fws_control.simulation.SIGNALS`. A sequence of their names:
        only those (held in the order of ``SIGNALS``; the result's
        ``signal_names`` says which). ``"metrics"``: none. Each chunk
        computes its signals, writes the kept ones into the preallocated
        result and is freed, so the peak memory is the returned data and one
        chunk's working set, and the budget
        :data:`~fws_control.simulation.engine.MAX_OUTPUT_BYTES` counts the
        kept signals only (and one chunk's full signals). Whatever is kept,
        the result holds per run the status, ``t_stop``, the peaks
        (:attr:`~fws_control.SimulationResult.peaks`, computed before the
        signals are dropped: exact on either engine) and, when ``e`` or
        ``theta`` is dropped, the horizon metrics of
        :func:`~fws_control.tracking_metrics` (settling time, overshoot, RMS
        and steady-state errors, with its default settings), so
        ``tracking_metrics(result)`` works on every result.
        Reading a signal not kept (``result.theta``,
        :meth:`~fws_control.SimulationResult.signal`, ``plot``) raises
        :class:`~fws_control.SignalNotKeptError`.
    out : ndarray, optional
        Where to write the kept signals: a writeable, C-contiguous float64
        array (or :class:`numpy.memmap`) of shape ``(runs, len(kept),
        time)``, with ``time`` the number of output times; the result's
        ``signals`` is a view of it (the same memory). Each chunk is written
        into it as it finishes. One array reused across sweeps of the same
        size spares the kernel's providing fresh memory for every result
        at its first touch (measured on the paper's scenario: from next to
        nothing to about 150 us of CPU per run in best-of-5 timings, and up
        to 450 us of system time in single batches, next to the compiled
        engine's own 300 us: ``docs/performance.md``); a
        memory map of a ``.npy`` file
        (:func:`numpy.lib.format.open_memmap`) streams a sweep larger than
        memory to disk. The output budget
        :data:`~fws_control.simulation.engine.MAX_OUTPUT_BYTES` then counts
        one chunk's working set only. If the call raises, `out` may hold
        some runs' signals. Not with ``signals="metrics"``. A result whose
        `out` is written again (by another sweep) shows the new signals
        next to its own per-run values: copy the signals of a result you
        keep (``result.signals.copy()``).

    **kwargs
        Deprecated calling form, accepted until fws_control 0.4 with a
        :class:`FutureWarning`: a :class:`~fws_control.Vehicle` as `plant`
        with ``speed=``, ``model=`` ({"kinematic", "dynamic"}), ``tyre=``
        and ``steering_lag=`` (formerly ``actuator_time_constant=``), and
        ``gains=`` for `controllers`. Any other keyword raises
        :class:`TypeError`.

    Returns
    -------
    SimulationResult
        Not squeezed, whatever the number of runs: signals of shape ``(runs,
        time)`` on the common output grid, NaN after a run's stop; per-run
        ``status``, ``t_stop``, ``speed``, ``k1``, ``k2``, ``ratio``. The
        number of runs is the broadcast of the numbers of gains, speeds and
        initial states.

    Raises
    ------
    ValueError
        If the per-run arguments do not broadcast, for an invalid
        `chunk_size`, for `signals` naming an unknown or repeated signal,
        empty or another str than ``"metrics"``, for an `out` of another
        shape or dtype, not C-contiguous or read-only (or given with
        ``signals="metrics"``), or as in :func:`simulate`.
    TypeError
        If `plant` is not a :class:`~fws_control.LateralPlant`, for an
        unknown keyword, if `controllers` is not a SteeringGains or a
        sequence of them, `signals` is not None, a str or a sequence of
        str, or `out` is not a numpy array.
    ClusterLostError
        If the Dask cluster of `client` has had no worker for 60 s (its
        ``result`` keeps the finished chunks).

    Examples
    --------
    Peak lateral acceleration over a sweep of the ratio ``a``:

    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> ratios = np.array([-1.0, -0.5, 0.0, 0.5])
    >>> plant = fws.LateralPlant(veh, speed=20.0)
    >>> g = fws.double_root_gains(plant, ratio=ratios, pole=-1.0)
    >>> res = fws.simulate_batch(plant, fws.Straight(), g,
    ...                          initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                          feedforward=False)
    >>> res.e.shape, res.status.tolist()
    ((4, 1001), ['ok', 'ok', 'ok', 'ok'])
    >>> bool(np.all(np.abs(res.e[:, -1]) < 1e-2))
    True
    >>> fws.tracking_metrics(res).peak_lateral_accel.round(2).tolist()
    [2.0, 1.91, 1.73, 1.19]

    A large sweep keeps only what it needs: here the lateral error, or only
    the metrics (the same values, computed before the signals are dropped):

    >>> few = fws.simulate_batch(plant, fws.Straight(), g,
    ...                          initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                          feedforward=False, signals=("e",))
    >>> few.signal_names, few.signals.shape, bool(np.all(few.e == res.e))
    (('e',), (4, 1, 1001), True)
    >>> none = fws.simulate_batch(plant, fws.Straight(), g,
    ...                           initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                           feedforward=False, signals="metrics")
    >>> m = fws.tracking_metrics(none)
    >>> m.peak_lateral_accel.round(2).tolist(), m.settling_time.round(2).tolist()
    ([2.0, 1.91, 1.73, 1.19], [5.9, 5.88, 5.83, 5.69])
    >>> bool(np.all(m.settling_time == fws.tracking_metrics(res).settling_time))
    True

    A sweep streamed to a ``.npy`` file as its chunks finish (a memory map
    as `out`; written under a temporary name and renamed when complete, so
    that an interrupted sweep leaves no file that looks finished):

    >>> import os, tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     part = os.path.join(folder, "sweep.npy.part")
    ...     disk = np.lib.format.open_memmap(part, mode="w+", shape=(4, 1, 1001))
    ...     _ = fws.simulate_batch(plant, fws.Straight(), g,
    ...                            initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                            feedforward=False, signals=("e",), out=disk)
    ...     disk.flush()
    ...     del disk
    ...     os.replace(part, os.path.join(folder, "sweep.npy"))
    ...     saved = np.load(os.path.join(folder, "sweep.npy"))
    >>> saved.shape, bool(np.all(saved[:, 0] == res.e))
    ((4, 1, 1001), True)
    """
    profile = _speed_option(plant, speed, kwargs)
    vehicle, controllers, speed, model, tyre, lag = _resolve_plant(
        "simulate_batch", plant, controllers, kwargs
    )
    profile, speed, controllers, schedule = _with_profile(profile, speed, controllers)
    return _simulate_batch(
        vehicle,
        path,
        controllers,
        speed=speed,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        dt=dt,
        t_eval=t_eval,
        actuator_time_constant=lag,
        delay=delay,
        method=method,
        rtol=rtol,
        atol=atol,
        model=model,
        tyre=tyre,
        engine=engine,
        chunk_size=chunk_size,
        client=client,
        progress=progress,
        signals=signals,
        out=out,
        profile=profile,
        schedule=schedule,
    )
