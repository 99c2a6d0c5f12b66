r"""The chunks of a batch on a Dask cluster, :func:`run_on_dask`.

The chunks are submitted to a ``dask.distributed`` client (optional extra
``distributed``); every chunk that finishes is kept, a lost task marks its
runs ``"failed"``, and a cluster left without workers for
:data:`LOST_CLUSTER_WAIT` seconds gives up the pending chunks.
"""

from __future__ import annotations

import time
import warnings

import numpy as np

from .outcomes import PEAK_SIGNALS, SIGNALS, STATUS_FAILED


def _wait_timeouts() -> tuple[type[BaseException], ...]:
    """What Dask's ``wait`` raises when the poll interval passes.

    Python 3.10's asyncio and concurrent.futures timeouts are not yet the
    builtin TimeoutError (they are from 3.11 on). Imported here, when a batch
    goes to a cluster: the two packages take 60 ms of CPU to import, which
    every process that simulates would pay otherwise.
    """
    import asyncio
    import concurrent.futures

    return (TimeoutError, asyncio.TimeoutError, concurrent.futures.TimeoutError)


__all__ = [
    "LOST_CLUSTER_WAIT",
    "POLL_INTERVAL",
    "lost_chunk",
    "run_on_dask",
]


def lost_chunk(n: int, t_size: int, note: str):
    """The outputs of :func:`run_chunk` for runs whose Dask task was lost."""
    nan = np.full((n, len(PEAK_SIGNALS)), np.nan)
    return (
        np.full((n, len(SIGNALS), t_size), np.nan),
        np.full(n, STATUS_FAILED, dtype=object),
        np.full(n, note, dtype=object),
        np.full(n, np.nan),
        nan,
        nan.copy(),
    )


#: Seconds simulate_batch waits on a Dask cluster that has no worker
#: before it gives up the pending chunks (marked "failed", then
#: ClusterLostError, see run_on_dask):
#: long enough for a cluster that scales up from zero to start one.
LOST_CLUSTER_WAIT = 60.0

#: Seconds between two checks of the cluster's workers while chunks are
#: pending.
POLL_INTERVAL = 1.0


def _has_workers(client) -> bool:
    """Whether the Dask cluster behind `client` has a worker (True if unknown)."""
    info = getattr(client, "scheduler_info", None)
    if info is None:
        return True
    try:
        return bool(info().get("workers", True))
    except Exception:  # the scheduler went away: the wait will say so
        return True


def run_on_dask(client, bounds, args, keep, t_size, bar, run) -> str | None:
    """Run the chunks on a Dask cluster; keep every chunk that finishes.

    A client that cannot take the tasks (closed) raises at once, before any
    work. A task the cluster loses afterwards (cancelled, worker or
    scheduler gone) does not discard the chunks that finished: its runs are
    marked ``"failed"`` with NaN data and a message naming Dask's error, and
    a :class:`RuntimeWarning` says how many runs were lost. A cluster left
    without workers (all killed, no nanny to restart them) would keep the
    tasks pending forever: once it has had no worker for
    ``LOST_CLUSTER_WAIT`` (60) seconds, the pending tasks are cancelled,
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
    wait_timeouts = _wait_timeouts()
    try:
        while pending and task_error is None:
            # (a cancelled future counts as done: dask's wait raises on it)
            done = [f for f in pending if f.done() or f.cancelled()]
            if not done:
                try:
                    done, _ = wait(
                        list(pending),
                        timeout=POLL_INTERVAL,
                        return_when="FIRST_COMPLETED",
                    )
                except wait_timeouts:
                    done = []
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
            elif time.monotonic() - idle_since > LOST_CLUSTER_WAIT:
                gone = TimeoutError(
                    f"the Dask cluster has had no worker for {LOST_CLUSTER_WAIT:g} "
                    "s: its workers are gone"
                )
                cluster_lost = str(gone)
                for fut, j in pending.items():
                    fut.cancel()
                    lost.append((j, gone))
                pending.clear()
    except Exception as exc:  # the cluster went away while we waited
        lost.extend((j, exc) for j in pending.values())
        pending.clear()
    if task_error is not None:
        for fut in pending:
            fut.cancel()
        raise task_error  # as it would be raised here
    for j, reason in lost:
        lo, hi = bounds[j]
        note = (
            f"not simulated: the Dask task of runs {lo}..{hi - 1} was lost "
            f"({type(reason).__name__}: {reason}); the other chunks were kept"
        )
        keep(j, lost_chunk(hi - lo, t_size, note))
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
