"""Timing helpers shared by the benchmarks: best of several runs, machine load.

Benchmarks print ratios measured in one run of one script, so that the
machine's speed cancels; each time is the best of ``repeat`` runs (the least
disturbed by other processes), and the load average is printed next to it so
that a reader can judge how busy the machine was.

Times are CPU seconds of the process (all its threads) by default: on a
machine shared with other jobs the wall time of a computation stretches
with the load (measured: a 11 ms chart took 45-95 ms of wall time at load
average 5 on 2 cores), its CPU time hardly does.
"""

from __future__ import annotations

import os
import platform
import time
from collections.abc import Callable, Hashable, Mapping

__all__ = ["best_of", "best_of_interleaved", "machine_line"]


def best_of(
    fn: Callable[[], object],
    repeat: int = 3,
    number: int = 1,
    clock: Callable[[], float] = time.process_time,
) -> float:
    """Best time per call of ``fn`` [s] over `repeat` runs of `number` calls.

    `clock` is :func:`time.process_time` (CPU time) by default; pass
    :func:`time.perf_counter` for wall time.
    """
    if repeat < 3 or number < 1:
        raise ValueError(
            f"repeat must be >= 3 and number >= 1, got repeat={repeat}, number={number}"
        )
    best = float("inf")
    for _ in range(repeat):
        t0 = clock()
        for _ in range(number):
            fn()
        best = min(best, (clock() - t0) / number)
    return best


def best_of_interleaved(
    fns: Mapping[Hashable, Callable[[], object]],
    repeat: int = 3,
    clock: Callable[[], float] = time.process_time,
) -> dict[Hashable, float]:
    """Best time per call [s] of each of `fns`, timed in turn `repeat` times.

    For a ratio of two timings: on a virtual machine whose speed drifts over
    minutes (measured here: the same loop of ``solve_ivp`` 7.0 and 6.1 ms per
    run in two runs of a script a few minutes apart), timing one function `repeat`
    times and then the other puts the drift into their ratio; round after
    round, each round times every function once, so that both see the same
    spells of a fast and a slow machine.
    """
    if repeat < 3:
        raise ValueError(f"repeat must be >= 3, got repeat={repeat}")
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeat):
        for name, fn in fns.items():
            t0 = clock()
            fn()
            best[name] = min(best[name], clock() - t0)
    return best


def machine_line() -> str:
    """One line: CPU count, load averages (1, 5, 15 min) and Python version."""
    try:
        load = "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
    except OSError:  # pragma: no cover - platforms without getloadavg
        load = "n/a"
    return (
        f"machine: {os.cpu_count()} CPUs, load average {load}, "
        f"Python {platform.python_version()}"
    )
