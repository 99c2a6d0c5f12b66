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

Compiling in the background
    A call of ``engine="auto"`` whose kernel set is not in the cache does not
    wait for it (unless ``FWS_CONTROL_COMPILE=foreground``):
    :func:`ready_or_background` starts one background process that compiles
    the set into the cache (``python -c``, detached, at a lower priority,
    one per set at a time over all processes of the install: a lock file in
    the cache folder), says so once on standard error, and the call runs on
    the numpy engine. Later calls run compiled once the set is in the
    cache. The process writes its output to ``compiling-<set>.log`` in the
    cache folder; if it ends without the set in the cache, the next call
    compiles in the foreground, where an error shows.
"""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import subprocess
import sys
import time
from dataclasses import dataclass
from typing import Any

__all__ = [
    "KERNEL_SETS",
    "CompiledSet",
    "precompile",
    "kernel_set",
    "is_cached",
    "ready_or_background",
    "compile_estimate",
]

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


# A background compilation's lock older than this is stale (its process was
# killed before it removed the lock): the kernels of every feature compile
# in 200-300 s of CPU.
_STALE_SECONDS = 3600.0

# Sets whose background compilation this process started: if one ends
# without its kernels in the cache, the next call compiles in the
# foreground (where the error shows) instead of starting another.
_STARTED: set[str] = set()

# Sets found in the cache by this process.
_READY: set[str] = set()

# The background processes this process started.
_CHILDREN: list[subprocess.Popen] = []


def kernel_set(*, method: str, delay: float, model: str, law: Any, profile: Any) -> str:
    """The kernel set a call of the compiled engine runs.

    Parameters
    ----------
    method : {"DOP853", "Radau"}
        The compiled method of the call.
    delay : float
        Input delay [s].
    model : {"kinematic", "dynamic"}
        The plant's model.
    law : SteeringGains or LateralController
        The call's control law.
    profile : SpeedProfile or None
        A varying speed.

    Returns
    -------
    str
        A name of :data:`KERNEL_SETS`: ``"features-dop853"`` with a delay,
        the dynamic model, a controller's compiled law or a varying speed,
        else ``"paper-radau"`` or ``"paper-dop853"``.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.precompile import kernel_set
    >>> kernel_set(method="DOP853", delay=0.0, model="kinematic",
    ...            law=fws.SteeringGains(0.1, 0.5, 0.0), profile=None)
    'paper-dop853'
    >>> kernel_set(method="DOP853", delay=0.0, model="kinematic",
    ...            law=fws.Stanley(), profile=None)
    'features-dop853'
    """
    from .compiled_laws import law_code

    if delay > 0.0 or model == "dynamic" or profile is not None or law_code(law) > 0:
        return "features-dop853"
    return "paper-radau" if method == "Radau" else "paper-dop853"


def _set_kernels(name: str) -> list:
    # the top kernels that a set's run compiles
    from .compiled import radau_run, solve_run
    from .compiled_variants import FEATURES, kernels, variant

    if name == "single-run":
        return [variant(solve_run, []), variant(radau_run, [])]
    k = kernels(FEATURES if name == "features-dop853" else ())
    solve = k.solve_batch_radau if name == "paper-radau" else k.solve_batch
    top = [solve, k.signals_batch, k.peaks_batch]
    return top + [k.delayed_signals_batch] if name == "features-dop853" else top


def is_cached(name: str) -> bool:
    """Whether kernel set `name` runs without compiling.

    Parameters
    ----------
    name : str
        A name of :data:`KERNEL_SETS`.

    Returns
    -------
    bool
        True if each of the set's top kernels is compiled in this process or
        in the cache with the current source
        (:func:`~fws_control.simulation.compilation.is_compiled`); False
        also without numba.

    Raises
    ------
    ValueError
        For a name not in :data:`KERNEL_SETS`.

    Examples
    --------
    >>> from fws_control.simulation.precompile import is_cached
    >>> isinstance(is_cached("paper-dop853"), bool)
    True
    """
    import importlib.util

    if name not in KERNEL_SETS:
        raise ValueError(f"name must be one of {KERNEL_SETS}, got {name!r}")
    if importlib.util.find_spec("numba") is None:
        return False
    from .compilation import is_compiled

    return all(is_compiled(kernel) for kernel in _set_kernels(name))


def compile_estimate(name: str) -> float:
    """CPU seconds kernel set `name` takes to compile with an empty cache.

    The sum of its stages' estimates
    (:data:`~fws_control.simulation.compiled.STAGE_SECONDS`, or
    :data:`~fws_control.simulation.compiled.FULL_STAGE_SECONDS` for the
    kernels of every feature), measured with
    ``benchmarks/bench_first_use.py`` on a busy machine (an idle one takes
    less, by up to 2x). The one-run drivers: the two methods' drivers.

    Parameters
    ----------
    name : str
        A name of :data:`KERNEL_SETS`.

    Returns
    -------
    float

    Raises
    ------
    ValueError
        For a name not in :data:`KERNEL_SETS`.

    Examples
    --------
    >>> from fws_control.simulation.precompile import compile_estimate
    >>> compile_estimate("paper-dop853")       # DOP853, signals, peaks
    54.0
    """
    from .compiled import FULL_STAGE_SECONDS, STAGE_SECONDS

    if name not in KERNEL_SETS:
        raise ValueError(f"name must be one of {KERNEL_SETS}, got {name!r}")
    if name == "single-run":
        return STAGE_SECONDS["DOP853"] + STAGE_SECONDS["Radau"]
    seconds = FULL_STAGE_SECONDS if name == "features-dop853" else STAGE_SECONDS
    method = "Radau" if name == "paper-radau" else "DOP853"
    return seconds[method] + seconds["signals"] + seconds["peaks"]


def _lock_path(name: str) -> str | None:
    from .compilation import cache_dir

    folder = cache_dir()
    return None if folder is None else os.path.join(folder, f"compiling-{name}.lock")


def _running(lock: str) -> bool:
    # a background compilation holds the lock (removing a stale one)
    try:
        age = time.time() - os.path.getmtime(lock)
    except FileNotFoundError:
        return False
    if age <= _STALE_SECONDS:
        return True
    try:
        os.remove(lock)
    except FileNotFoundError:
        pass
    return False


def _start(name: str, lock: str) -> bool:
    # take the lock and start the detached process; False if another
    # process took the lock first
    os.makedirs(os.path.dirname(lock), exist_ok=True)
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return False
    os.close(fd)  # (the background process writes its pid into it)
    log = lock[: -len(".lock")] + ".log"
    # at a lower priority: the user's own work first
    code = (
        "import os, sys\n"
        "if hasattr(os, 'nice'): os.nice(10)\n"
        "from fws_control.simulation import precompile\n"
        "precompile._background(sys.argv[1], sys.argv[2])\n"
    )
    env = dict(os.environ)
    from .compilation import QUIET_VARIABLE

    env[QUIET_VARIABLE] = "1"
    detach: dict[str, Any] = {"start_new_session": True}
    if sys.platform == "win32":  # pragma: no cover - POSIX CI
        detach = {
            "creationflags": subprocess.DETACHED_PROCESS
            | subprocess.CREATE_NEW_PROCESS_GROUP
        }
    try:
        with open(log, "w") as out:
            child = subprocess.Popen(
                [sys.executable, "-c", code, name, lock],
                stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                env=env, close_fds=True, **detach,
            )  # fmt: skip
    except OSError:
        os.remove(lock)
        raise
    # (kept: a Popen object collected while its process runs warns)
    _CHILDREN.append(child)
    return True


def _background(name: str, lock: str) -> None:
    # the background process: compile the set, then release the lock (which
    # names this process meanwhile, for whoever needs to stop it)
    try:
        with open(lock, "w") as f:
            f.write(f"{os.getpid()}\n")
        item = _run_set(name)
        print(f"{item.name}: {item.cpu_seconds:.1f} s CPU", flush=True)
    finally:
        try:
            os.remove(lock)
        except FileNotFoundError:
            pass


def ready_or_background(name: str) -> bool:
    """Whether a call of ``engine="auto"`` runs kernel set `name` compiled now.

    True if the set is cached (:func:`is_cached`), or where the call is to
    compile it itself: with ``FWS_CONTROL_COMPILE=foreground``, where no
    cache folder is writable, or when a background compilation that this
    process started has ended without the set in the cache. Otherwise
    False: a background process compiles the set (this call starts it
    unless one runs already), announced once on standard error (see the
    module notes), and the call runs on the numpy engine.

    Parameters
    ----------
    name : str
        A name of :data:`KERNEL_SETS`.

    Returns
    -------
    bool

    Raises
    ------
    ValueError
        For a name not in :data:`KERNEL_SETS`, or a bad
        ``FWS_CONTROL_COMPILE``.

    Examples
    --------
    >>> import os
    >>> from fws_control.simulation.precompile import ready_or_background
    >>> os.environ["FWS_CONTROL_COMPILE"] = "foreground"
    >>> ready_or_background("paper-dop853")
    True
    >>> del os.environ["FWS_CONTROL_COMPILE"]
    """
    from .compilation import announce_background, compile_mode

    if name in _READY or compile_mode() == "foreground":
        return True
    if is_cached(name):
        _READY.add(name)  # (cached once, cached for the process)
        return True
    lock = _lock_path(name)
    if lock is None:
        return True
    if not _running(lock):
        if name in _STARTED:
            return True  # it ended without the kernels: compile here
        if _start(name, lock):
            _STARTED.add(name)
    announce_background(compile_estimate(name))
    return False
