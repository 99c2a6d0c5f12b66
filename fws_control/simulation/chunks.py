r"""One chunk of runs on the numpy engine, where it is sent.

A chunk's runs are integrated together (:func:`run_chunk`), a run whose
solver fails alone is isolated by splitting the chunk (:func:`run_isolated`),
and the chunk's signals are reduced to those the caller keeps, with the
per-run values computed before the others are freed (:func:`reduce_chunk`,
:func:`run_kept`). The functions are module-level so that Dask can pickle
them: on a cluster they run on the worker.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..gains import SteeringGains
from ..metrics import HORIZON_METRICS, tracking_metrics
from .options import (
    initial_path_state,
)
from .outcomes import PEAK_SIGNALS, SIGNALS, STATUS_FAILED
from .peaks import exact_peaks
from .result import SimulationResult
from .signals import compute_outputs

__all__ = [
    "OUTPUT_BLOCK",
    "outputs_in_blocks",
    "run_chunk",
    "run_isolated",
    "reduce_chunk",
    "run_kept",
    "chunk_controller",
]

#: Samples (runs x output times) whose signals are computed at once: the
#: temporaries of :func:`~fws_control.simulation.signals.compute_outputs`
#: (about forty-five arrays of this size, 12 MB) stay bounded, whatever the
#: size of the output.
OUTPUT_BLOCK = 1 << 15
_PSI = SIGNALS.index("psi")


def outputs_in_blocks(vehicle, path, g, *, states, initial_heading, **kw):
    """:func:`compute_outputs` over blocks of output times, into one array.

    ``psi`` is unwrapped in time within a block; each block starts on the
    branch of the previous block's last value (consecutive samples differ
    by less than pi), so the result equals one call over all times.
    """
    n, T = states.shape[1], states.shape[2]
    step = max(1, OUTPUT_BLOCK // max(n, 1))
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


def run_chunk(vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl):
    """Simulate one chunk; module-level so that Dask can pickle it.

    Returns ``(signals (n, len(SIGNALS), T), status, message, t_stop,
    peaks (n, len(PEAK_SIGNALS)), peak_times)``: the peaks are those of the
    continuous solution (:func:`~fws_control.simulation.peaks.exact_peaks`).
    """
    # (imported here: the numpy engine brings scipy.integrate and
    # scipy.optimize, which a process that runs compiled never needs)
    from .engine import integrate

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
    signals = outputs_in_blocks(
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


def run_isolated(vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl):
    """:func:`run_chunk`, where a solver failure takes only its own run out.

    The runs of a chunk share one solver, so one run whose solver fails
    (e.g. a speed of 1e300 m/s) fails every run still active in the chunk.
    Those runs are split in halves and integrated again, recursively, until
    a run that fails alone is found: only it keeps the status ``"failed"``
    (and its message); every other run keeps its own result. The cost is at
    most about twice the chunk's (one half of each split finishes normally).
    Module-level so that Dask can pickle it: on a cluster the retries run on
    the worker.
    """
    out = run_chunk(
        vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl
    )  # fmt: skip
    failed = np.flatnonzero(out[1] == STATUS_FAILED)
    if speed.size == 1 or failed.size == 0:
        return out
    for idx in np.array_split(failed, 2):
        sub_ctrl = ctrl.subset(idx) if ctrl is not None and ctrl.runs() else ctrl
        sub = run_isolated(
            vehicle, path, k1[idx], k2[idx], a[idx], speed[idx], feedforward,
            x0[idx], t, tau, opts, sub_ctrl,
        )  # fmt: skip
        for whole, part in zip(out, sub, strict=True):
            whole[idx] = part
    return out


def reduce_chunk(out, rows, horizon, exact, args):
    """A chunk's outputs with only the kept signals and the per-run values.

    `out` is what :func:`run_chunk` returns; `rows` the indices of the
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


def run_kept(run, rows, horizon, exact, *args):
    """``run(*args)`` reduced by :func:`reduce_chunk` where it ran.

    Module-level so that Dask can pickle it: on a cluster the full signals
    of a chunk stay on its worker, only the kept ones travel.
    """
    return reduce_chunk(run(*args), rows, horizon, exact, args)


def chunk_controller(ctrl, lo: int, hi: int):
    """The controller of runs ``lo:hi`` (per-run parameters indexed)."""
    if ctrl is None or not ctrl.runs():
        return ctrl
    return ctrl.subset(np.arange(lo, hi))
