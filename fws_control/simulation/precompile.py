"""Compile the compiled engine's kernels ahead of their first use.

numba compiles a kernel the first time a call needs it and caches it
(:mod:`~fws_control.simulation.compilation`); after an install the first
simulations run on the numpy engine while a background process compiles
(below), or wait for the compilation. :func:`precompile` does that
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
    :func:`ready_or_background` starts a background process that compiles
    the set into the cache (``python -c``, detached, at a lower priority),
    says so once per process on standard error, and the call runs on the
    numpy engine; the calls after the set is cached run compiled. One
    process per set for all processes of an install: it holds an exclusive
    ``flock`` on ``compiling-<set>.lock`` in the cache folder (writing its
    pid there), which ends with the process however it ends. It writes its
    output to ``compiling-<set>.log``; if it fails, it leaves
    ``compiling-<set>.failed``, and the calls then compile the set
    themselves (where the error shows) until it is cached; if it is killed,
    the process that started it compiles in the foreground and a later
    process starts another. Where the file system has no ``flock``, and on
    Windows, the calls compile in the foreground. :func:`precompile`'s
    workers take the same lock: one waits for a background compilation of
    its set to end and then loads what it compiled.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
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


def _run_set_locked(name: str) -> CompiledSet:
    # in a worker process: the set under its lock (see the module notes), so
    # that a background compilation of the set finishes first and this run
    # loads what it compiled, and no background one starts meanwhile
    lock = None if sys.platform == "win32" else _set_file(name, ".lock")
    if lock is None:
        return _run_set(name)
    import fcntl

    os.makedirs(os.path.dirname(lock), exist_ok=True)
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        with contextlib.suppress(OSError):  # (no flock there: unlocked)
            fcntl.flock(fd, fcntl.LOCK_EX)
        return _run_set(name)
    finally:
        os.close(fd)


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
            name: pool.submit(_run_set_locked, name)
            for name in sorted(set(sets), key=_LONGEST_FIRST.index)
        }
        return [started[name].result() for name in sets]


# Sets found in the cache by this process.
_READY: set[str] = set()

# The background process this process started for each set (kept: a Popen
# object collected while its process runs warns).
_CHILDREN: dict[str, subprocess.Popen] = {}


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
        The call's control law: a controller (its compiled law, or the held
        command of a sampled one such as the MPC) runs the kernels of every
        feature.
    profile : SpeedProfile or None
        The speed (None or a constant profile: a constant speed).

    Returns
    -------
    str
        A name of :data:`KERNEL_SETS`: ``"features-dop853"`` with a delay,
        the dynamic model, a controller or a varying speed, else
        ``"paper-radau"`` or ``"paper-dop853"``.

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
    from ..gains import SteeringGains

    varying = profile is not None and not profile.is_constant
    controller = not isinstance(law, SteeringGains)
    if delay > 0.0 or model == "dynamic" or varying or controller:
        return "features-dop853"
    return "paper-radau" if method == "Radau" else "paper-dop853"


def _check_set(name: str) -> None:
    if name not in KERNEL_SETS:
        raise ValueError(f"name must be one of {KERNEL_SETS}, got {name!r}")


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

    _check_set(name)
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

    _check_set(name)
    if name == "single-run":
        return STAGE_SECONDS["DOP853"] + STAGE_SECONDS["Radau"]
    seconds = FULL_STAGE_SECONDS if name == "features-dop853" else STAGE_SECONDS
    method = "Radau" if name == "paper-radau" else "DOP853"
    return seconds[method] + seconds["signals"] + seconds["peaks"]


def _set_file(name: str, suffix: str) -> str | None:
    # compiling-<set>.<suffix> in the cache folder (None: no cache folder)
    from .compilation import cache_dir

    folder = cache_dir()
    return None if folder is None else os.path.join(folder, f"compiling-{name}{suffix}")


def _try_lock(path: str) -> int | None:
    # an open descriptor of `path` holding its exclusive lock, or None if
    # another process holds it. flock: the lock belongs to the open file,
    # which the background process inherits, and ends when the last process
    # holding it exits, however it exits (no stale lock to clean up).
    import fcntl

    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        return None
    except OSError:  # (no flock on this file system: the caller compiles)
        os.close(fd)
        raise
    return fd


def _start(name: str) -> bool:
    # start the background process unless one holds the set's lock; False
    # if one runs
    lock = _set_file(name, ".lock")
    assert lock is not None
    os.makedirs(os.path.dirname(lock), exist_ok=True)
    fd = _try_lock(lock)
    if fd is None:
        return False
    try:
        os.ftruncate(fd, 0)  # (the background process writes its pid)
        # at a lower priority (the user's own work first); any failure,
        # the imports' too, leaves the .failed mark
        code = (
            "import os, sys\n"
            "os.nice(10)\n"
            "try:\n"
            "    from fws_control.simulation import precompile\n"
            "    precompile._background(sys.argv[1], int(sys.argv[2]))\n"
            "except Exception as exc:\n"
            "    with open(sys.argv[3], 'w') as f:\n"
            "        f.write(f'{type(exc).__name__}: {exc}\\n')\n"
            "    raise\n"
        )
        env = dict(os.environ)
        from .compilation import QUIET_VARIABLE

        env[QUIET_VARIABLE] = "1"
        # this process's fws_control, wherever it was imported from
        root = os.path.dirname(os.path.dirname(os.path.dirname(__file__)))
        env["PYTHONPATH"] = os.pathsep.join(
            [root, *filter(None, [env.get("PYTHONPATH")])]
        )
        log, failed = _set_file(name, ".log"), _set_file(name, ".failed")
        assert log is not None and failed is not None
        with open(log, "w") as out:
            child = subprocess.Popen(
                [sys.executable, "-c", code, name, str(fd), failed],
                stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                env=env, pass_fds=(fd,), start_new_session=True,
            )  # fmt: skip
    finally:
        os.close(fd)  # (the child holds the lock from here)
    _CHILDREN[name] = child
    return True


def _running(name: str) -> bool:
    # a background process holds the set's lock
    lock = _set_file(name, ".lock")
    if lock is None or not os.path.exists(lock):
        return False
    fd = _try_lock(lock)
    if fd is None:
        return True
    os.close(fd)
    return False


def _background(name: str, fd: int) -> None:
    # the background process: compile the set while holding the lock on fd
    # (a failure: the caller's code leaves compiling-<set>.failed)
    os.set_inheritable(fd, False)  # (not into processes this one starts)
    os.write(fd, f"{os.getpid()}\n".encode())
    _check_set(name)
    item = _run_set(name)
    print(f"{item.name}: {item.cpu_seconds:.1f} s CPU", flush=True)


def ready_or_background(name: str) -> bool:
    """Whether a call of ``engine="auto"`` runs kernel set `name` compiled now.

    True if the set is cached (:func:`is_cached`), or where the call is to
    compile it itself: with ``FWS_CONTROL_COMPILE=foreground``, where no
    cache folder is writable or no process can be started, after a
    background compilation of the set failed, and on Windows. Otherwise
    False: a background process compiles the set (this call starts it
    unless one runs already), announced once per process on standard error
    (see the module notes), and the call runs on the numpy engine.

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

    if compile_mode() == "foreground" or name in _READY:
        return True
    failed = _set_file(name, ".failed")
    child = _CHILDREN.get(name)
    ended = child is not None and child.poll() is not None  # (and reaped)
    if is_cached(name):
        _READY.add(name)  # (cached once, cached for the process)
        if failed is not None:
            with contextlib.suppress(OSError):
                os.remove(failed)  # (compiled since, in the foreground)
        return True
    if failed is None or os.path.exists(failed) or ended or sys.platform == "win32":
        # no cache folder, a background compilation that failed (or that
        # this process started and that ended without the set: killed), or
        # Windows (no flock there): compiled here, where an error shows
        return True
    try:
        if not _running(name):
            _start(name)
    except OSError:
        return True  # (no flock, no process started: compiled here)
    announce_background(compile_estimate(name))
    return False
