"""Compile the compiled engine's kernels ahead of their first use.

numba compiles a kernel the first time a call needs it and caches it
(:mod:`~fws_control.simulation.compilation`); the first simulation after
an install then waits for the compilation. :func:`precompile` does that
work at a moment of the user's choosing -- after ``pip install`` in a
container image, before a sweep on a cluster node, before a test suite --
by running one short simulation (or one-run call) of each kernel set, in
worker processes that run side by side, and reports the CPU time each
took. Later processes load the kernels from the cache. The command line runs it as
``fws-control compile``.

The kernel sets (:data:`KERNEL_SETS`):

- ``"paper-dop853"``: the paper's loop with DOP853 (the kernels specialised
  to a call without an input delay, the dynamic model, a controller's law
  or a varying speed: the default ``simulate``);
- ``"paper-radau"``: the same loop with the compiled Radau (a stiff
  steering actuator);
- ``"features-dop853"``: the kernels of every such feature (a call with an
  input delay and a steering lag compiles them: the integration, the
  signals, the delayed signals and the exact peaks);
- ``"single-run"``: the public one-run drivers
  :func:`~fws_control.simulation.compiled.solve_run` (DOP853) and
  :func:`~fws_control.simulation.compiled.radau_run` on the paper's loop,
  which the batch engine does not call (it steps the same methods itself).
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import time
from dataclasses import dataclass

__all__ = ["KERNEL_SETS", "CompiledSet", "precompile"]

#: The kernel sets :func:`precompile` compiles.
KERNEL_SETS = ("paper-dop853", "paper-radau", "features-dop853", "single-run")

# The order precompile starts them in: by their CPU time to compile, longest
# first (one run of `fws-control compile` on two cores: 201, 85, 34 and
# 18 s). With two workers the paper's sets and the one-run drivers together
# take less than the kernels of every feature.
_LONGEST_FIRST = ("features-dop853", "paper-radau", "single-run", "paper-dop853")


@dataclass(frozen=True)
class CompiledSet:
    """One kernel set compiled (or loaded from the cache) by :func:`precompile`.

    Attributes
    ----------
    name : str
        A name of :data:`KERNEL_SETS`.
    cpu_seconds : float
        CPU time of its worker process for the simulation that compiled or
        loaded it (user and system time of that process) [s].
    """

    name: str
    cpu_seconds: float


def _quiet() -> None:
    # in a worker process: the caller reports; no notice of each compilation
    import os

    from .compilation import QUIET_VARIABLE

    os.environ[QUIET_VARIABLE] = "1"


def _run_single() -> None:
    # in a worker process: one short run of each one-run driver, with the
    # argument types of their documented use (numba compiles per type)
    import numpy as np

    import fws_control as fws

    from .compiled import curvature_table, radau_run, shared_parameters, solve_run
    from .compiled_variants import variant

    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    tab = curvature_table(fws.Straight())
    q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    t = np.linspace(0.0, 1.0, 3)
    variant(solve_run, [])(
        np.array([0.0, 1.0, 0.0]), np.array([5.0, 0.1, 0.5, 0.0]), q, tab.breaks,
        tab.coefs, t, 1e-10, 1e-12, np.empty((3, t.size)), np.empty(0),
    )  # fmt: skip
    q = shared_parameters(veh, tab, feedforward=False, time_constant=0.05)
    p = np.zeros(8)
    p[:4] = 5.0, 0.1, 0.5, 0.0
    m = 100
    variant(radau_run, [])(
        np.array([0.0, 1.0, 0.0, 0.0, 0.0]), p, q, tab.breaks, tab.coefs, 0.0,
        0.1, 1e-3, 1e-8, 1e-10, np.empty(m), np.empty((m, 5)), np.empty((m, 5, 3)),
    )  # fmt: skip


def _run_set(name: str) -> CompiledSet:
    # in a worker process: a short simulation that needs exactly this set
    start = time.process_time()
    if name == "single-run":
        _run_single()
        return CompiledSet(name, time.process_time() - start)
    import fws_control as fws

    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    gains = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    # the paper's loop (DOP853 or Radau), or an input delay with a steering
    # lag: the kernels of every feature
    features = name == "features-dop853"
    plant = fws.LateralPlant(veh, speed=5.0, steering_lag=0.1 if features else None)
    res = fws.simulate(
        plant, fws.Arc(0.1), gains, initial_state=(0.0, -1.0, 0.0), duration=2.0,
        engine="compiled", method="Radau" if name == "paper-radau" else "DOP853",
        delay=0.1 if features else 0.0,
    )  # fmt: skip
    if res.engine != "compiled" or res.run_peak is None:  # pragma: no cover
        raise RuntimeError(f"kernel set {name!r} did not run compiled")
    return CompiledSet(name, time.process_time() - start)


def precompile(
    sets: tuple[str, ...] = KERNEL_SETS, *, jobs: int = 2
) -> list[CompiledSet]:
    """Compile the compiled engine's kernels into the cache, side by side.

    Parameters
    ----------
    sets : tuple of str, optional
        Names of :data:`KERNEL_SETS` (default: all).
    jobs : int, optional
        Worker processes that compile at once (default 2), >= 1.

    Returns
    -------
    list of CompiledSet
        In the order of `sets`. A set already in the cache takes about a
        second (the imports and the loading).

    Raises
    ------
    ImportError
        If numba is not installed (``pip install fws-control[fast]``).
    ValueError
        For a name not in :data:`KERNEL_SETS` or `jobs` < 1.

    Examples
    --------
    >>> from fws_control.simulation.precompile import precompile
    >>> [s.name for s in precompile(("paper-dop853",), jobs=1)]
    ['paper-dop853']
    """
    import importlib.util

    for name in sets:
        if name not in KERNEL_SETS:
            raise ValueError(f"sets must hold names of {KERNEL_SETS}, got {name!r}")
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"jobs must be an integer >= 1, got {jobs!r}")
    if importlib.util.find_spec("numba") is None:
        raise ImportError(
            "the compiled engine needs numba: pip install 'fws-control[fast]'"
        )
    # fresh interpreters ("spawn"): a forked child would inherit this
    # process's numba state and locks
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(
        max_workers=min(jobs, len(sets)) or 1, mp_context=context, initializer=_quiet
    ) as pool:
        # the longest first: the kernels of every feature take longer than
        # the other sets together, so with two workers they finish when the
        # features do instead of one other set later
        started = {
            name: pool.submit(_run_set, name)
            for name in sorted(set(sets), key=_LONGEST_FIRST.index)
        }
        return [started[name].result() for name in sets]
