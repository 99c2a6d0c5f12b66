r"""How the compiled engine's kernels are compiled, cached and announced.

The kernels of :mod:`~fws_control.simulation.compiled` are compiled by
numba the first time a call needs them (numba compiles lazily, one kernel
and the kernels it calls at a time) and kept in numba's on-disk cache, so
that the compilation (seconds of CPU) is paid once per installation and
numba version, not once per process.

Where the cache goes
    In a folder of fws_control's own, outside the installed package, so that
    ``pip uninstall fws-control`` removes the whole package (numba's
    default, a ``__pycache__`` folder next to each source file, is not in
    pip's record of the installed files: the package's folders stayed behind
    after an uninstall, holding only those files, and ``import fws_control``
    still succeeded as an empty namespace package). The folder is
    :func:`cache_dir`:

    - ``$NUMBA_CACHE_DIR/<folder>_<hash>`` where ``NUMBA_CACHE_DIR`` is set
      (numba's own setting, honoured as numba honours it);
    - otherwise the user's cache folder: ``$XDG_CACHE_HOME/fws_control``
      or ``~/.cache/fws_control`` on Linux, ``~/Library/Caches/fws_control``
      on macOS, ``%LOCALAPPDATA%\fws_control\Cache`` on Windows (as numba
      places its own user-wide cache), followed by ``<folder>_<hash>``, the
      name and a hash of the installed package folder that holds the
      kernels' source (two installs do not share their kernels).

    Other users of numba in the same process keep numba's defaults: only
    fws_control's kernels get this locator. Where no such folder is writable
    (a read-only home without ``NUMBA_CACHE_DIR``) the kernels are compiled
    in every process, with one :class:`RuntimeWarning`. Deleting the folder
    clears the cache; an upgrade of fws_control or numba invalidates the
    stale entries by itself (numba checks the source's stamp and its own
    version).

The first compilation in a process
    says so on standard error, once per process, with an estimate of its
    CPU time and the cache folder, and when it is done, one line with the
    CPU time it took. Nothing is printed when the kernels load from the
    cache (numba compiles nothing then), nor with the environment variable
    ``FWS_CONTROL_QUIET=1``. Standard error, as progress bars: a library
    does not write to standard output, and the notice is no warning about
    the user's code.

In the background
    A call of ``engine="auto"`` whose kernels are not in the cache does not
    compile them itself by default: a background process does, and the
    call runs on the numpy engine (:func:`compile_mode`,
    :func:`~fws_control.simulation.precompile.ready_or_background`), with
    one notice per process (:func:`announce_background`).
    ``FWS_CONTROL_COMPILE=foreground`` makes the call compile and wait.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import inspect
import os
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator
from typing import Any

try:  # optional dependency (extra "fast")
    import numba
    from numba.core import caching as _caching
    from numba.core import event as _event
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None

__all__ = [
    "QUIET_VARIABLE",
    "COMPILE_VARIABLE",
    "compile_mode",
    "announce_background",
    "jit",
    "cache_dir",
    "first_use",
    "compile_seconds",
    "is_compiled",
]

#: Environment variable that silences the first-use notice (``1``).
QUIET_VARIABLE = "FWS_CONTROL_QUIET"

#: Environment variable: where a call of ``engine="auto"`` compiles kernels
#: that are not in the cache: ``background`` (default) or ``foreground``.
COMPILE_VARIABLE = "FWS_CONTROL_COMPILE"

#: The application name of the user cache folder.
_APP = "fws_control"

# Whether the kernels are compiled with the on-disk cache. It turns False,
# with one RuntimeWarning, where no cache folder is writable; the kernels
# are then compiled in every process.
_CACHING = True


@functools.cache
def _kernel_sources_stamp() -> tuple:
    """(mtime, size) of every source a kernel may inline, in a fixed order.

    Taken once per process: the kernels are the code imported then (a
    source edited later is not what this process compiles), and every jitted
    function asks for it: 157 times before the paper's case runs, which took
    50 ms of a process's first result.
    """
    here = os.path.dirname(os.path.abspath(__file__))
    files = sorted(
        os.path.join(here, name) for name in os.listdir(here) if name.endswith(".py")
    )
    files.append(os.path.join(os.path.dirname(here), "equations.py"))
    stamp = []
    for name in files:
        try:
            st = os.stat(name)
        except OSError:  # (equations.py absent: nothing inlined from it)
            continue
        stamp.append((os.path.basename(name), st.st_mtime, st.st_size))
    return tuple(stamp)


def _cache_root() -> str:
    """The folder under which every install keeps its cache folder."""
    if numba.config.CACHE_DIR:
        return os.path.abspath(numba.config.CACHE_DIR)
    # numba's vendored appdirs: the same rules numba applies to its own
    # user-wide cache folder, under fws_control's name
    from numba.misc.appdirs import AppDirs

    return AppDirs(appname=_APP, appauthor=False).user_cache_dir


if numba is not None:

    class _KernelLocator(
        _caching._SourceFileBackedLocatorMixin, _caching._CacheLocator
    ):
        # numba's locator for NUMBA_CACHE_DIR (a folder per source folder
        # under a root), with the root of _cache_root: never the package's
        # own folder
        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            subpath = self.get_suitable_cache_subpath(py_file)
            self._cache_path = os.path.join(_cache_root(), subpath)

        def get_cache_path(self):
            return self._cache_path

        def get_source_stamp(self):
            # numba stamps a cache entry with its own source file only, but
            # a kernel inlines functions of other modules (the equations,
            # the solver helpers): with that stamp alone an edit of
            # equations.py would load kernels compiled with the old
            # equations. The stamp of every kernel source invalidates them.
            return _kernel_sources_stamp()

    class _KernelCacheImpl(_caching.CompileResultCacheImpl):
        _locator_classes = [_KernelLocator]

    class _KernelCacheFile(_caching.IndexDataCacheFile):
        # numba's index and data files, with the data file of an entry named
        # after its key. numba names a new entry's file after the first
        # number free in the index it has just read, and writes the index
        # before the data: two processes that save different overloads of
        # one function at once (the DOP853 and the Radau driver, compiled
        # side by side before the test workers start) both take the same
        # number, and the index can then point the Radau key at the DOP853
        # code (a Radau call that returned DOP853's steps). A name from the
        # key cannot serve two keys, and the data is written before the
        # index refers to it; a race then only loses an index entry, which
        # costs a compilation.
        def __init__(self, cache_path, filename_base, source_stamp):
            super().__init__(cache_path, filename_base, source_stamp)
            self._filename_base = filename_base

        def data_name(self, key: Any) -> str:
            # the key: the signature, the target machine, the hashes of
            # the bytecode and of the closure's values (numba types print
            # their identity)
            digest = hashlib.sha256(repr(key).encode()).hexdigest()[:20]
            return f"{self._filename_base}.{digest}.nbc"

        def save(self, key, data):
            name = self.data_name(key)
            self._save_data(name, data)
            overloads = self._load_index()
            if overloads.get(key) != name:
                overloads[key] = name
                self._save_index(overloads)

    class _KernelCache(_caching.FunctionCache):
        # numba's FunctionCache (what njit(cache=True) installs), located
        # by _KernelLocator alone, its files kept by _KernelCacheFile
        _impl_class = _KernelCacheImpl

        def __init__(self, py_func):
            super().__init__(py_func)
            self._cache_file = _KernelCacheFile(
                cache_path=self._cache_path,
                filename_base=self._impl.filename_base,
                source_stamp=self._cache_file._source_stamp,
            )


def jit(fn: Callable, *, inline: str = "never") -> Callable:
    """Compile `fn` with numba, the engine's options and the on-disk cache.

    ``numba.njit(nogil=True, error_model="numpy", inline=inline)`` with
    numba's cache located in :func:`cache_dir` (see the module notes).
    ``error_model="numpy"``: a division by zero gives inf or NaN as in
    numpy (and the solver then rejects the step or fails the run) instead
    of raising ZeroDivisionError out of a whole batch. Without numba, `fn`
    is returned unchanged (importable, never called by the engine).

    Parameters
    ----------
    fn : callable
        A function numba can compile in nopython mode.
    inline : {"never", "always"}, optional
        numba's ``inline``: ``"always"`` inlines `fn` into every compiled
        caller at numba-IR level.

    Returns
    -------
    callable
        numba's dispatcher (or `fn` without numba).

    Examples
    --------
    >>> from fws_control.simulation.compilation import jit
    >>> def hypot3(x, y, z):
    ...     return (x * x + y * y + z * z) ** 0.5
    >>> jit(hypot3)(2.0, 3.0, 6.0)
    7.0
    """
    global _CACHING
    if numba is None:  # pragma: no cover
        return fn
    if inline not in ("never", "always"):
        raise ValueError(f"inline must be 'never' or 'always', got {inline!r}")
    # no_cfunc_wrapper: the kernels are called from Python or from other
    # kernels, never as C callbacks; the wrapper's lowering cost 4 % of the
    # first compilation
    dispatcher = numba.njit(
        nogil=True, error_model="numpy", inline=inline, no_cfunc_wrapper=True
    )(fn)
    if _CACHING and os.path.exists(inspect.getfile(fn)):
        # (a function without a source file, typed at a prompt or in a
        # doctest, has nothing to check a cache entry against: uncached)
        try:
            # what numba's enable_caching does for cache=True, with our cache
            dispatcher._cache = _KernelCache(fn)
        except RuntimeError as exc:
            # numba's "cannot cache function ...: no locator available",
            # where the cache folder cannot be created or written
            if "cannot cache" not in str(exc):
                raise
            _CACHING = False
            warnings.warn(
                f"numba finds no writable cache folder ({exc}; tried "
                f"{_cache_root()}); the compiled engine is compiled in every "
                "process (up to a minute of CPU). Set NUMBA_CACHE_DIR to a "
                "writable folder to keep the compilation.",
                RuntimeWarning,
                stacklevel=3,
            )
    return dispatcher


def cache_dir() -> str | None:
    """The folder that holds the compiled kernels (numba's cache files).

    Returns
    -------
    str or None
        The folder (see the module notes), or None if numba is not
        installed or no cache folder is writable (the kernels are then
        compiled in every process).

    Examples
    --------
    >>> from fws_control.simulation.compilation import cache_dir
    >>> folder = cache_dir()
    >>> folder is None or "site-packages" not in folder
    True
    """
    if numba is None or not _CACHING:
        return None
    # the folder depends on the source's folder only: this module's, which
    # holds the kernels' modules
    return _KernelLocator(cache_dir, __file__).get_cache_path()


# --------------------------------------------------------------------------
# The first-use notice


def compile_mode() -> str:
    """Where a call of ``engine="auto"`` compiles the kernels it needs.

    Returns
    -------
    str
        ``"background"`` (default): a background process compiles them
        into the cache while the calls run on the numpy engine;
        ``"foreground"``: the call compiles them and waits. From the
        environment variable ``FWS_CONTROL_COMPILE``.

    Raises
    ------
    ValueError
        If ``FWS_CONTROL_COMPILE`` is set to another value.

    Examples
    --------
    >>> from fws_control.simulation.compilation import compile_mode
    >>> compile_mode() in ("background", "foreground")
    True
    """
    value = os.environ.get(COMPILE_VARIABLE, "").strip().lower()
    if value in ("", "background"):
        return "background"
    if value == "foreground":
        return "foreground"
    raise ValueError(
        f"{COMPILE_VARIABLE} must be 'background' or 'foreground', got "
        f"{os.environ[COMPILE_VARIABLE]!r}"
    )


def _quiet() -> bool:
    return os.environ.get(QUIET_VARIABLE, "").strip() not in ("", "0")


class _Notice:
    """Whether this process has announced a compilation, and a compilation in
    the background (each once per process)."""

    announced = False
    background = False


class _ThreadNotice(threading.local):
    """Each thread's first_use blocks and compilations (Dask runs chunks in
    threads; numba compiles one kernel at a time, under its lock)."""

    def __init__(self):
        self.depth = 0  # nesting of our kernels' compilations in progress
        self.start = 0.0
        self.seconds = 0.0  # CPU time of our compilations in the block
        self.plans = []  # estimate callbacks of the active first_use blocks
        self.pending_line = False  # the announcement wants its closing line


_local = _ThreadNotice()


def _ours(dispatcher: Any) -> bool:
    module = getattr(getattr(dispatcher, "py_func", None), "__module__", "")
    return isinstance(module, str) and module.startswith("fws_control.")


def _announce() -> None:
    _Notice.announced = True
    if _quiet():
        return
    estimate = _local.plans[0]() if _local.plans else None
    about = f"about {estimate:.0f} s of CPU; " if estimate else ""
    where = cache_dir()
    cached = f"cached in {where}" if where else "not cached: no writable folder"
    sys.stderr.write(
        f"fws_control: compiling the simulation engine (once: {about}{cached}; "
        f"{QUIET_VARIABLE}=1 silences this)\n"
    )
    sys.stderr.flush()
    _local.pending_line = True


def announce_background(seconds: float) -> None:
    """Say on standard error, once per process, that the kernels compile in
    a background process while the calls run on the numpy engine.

    Silent with ``FWS_CONTROL_QUIET=1``. A compilation in the foreground
    later in the process is still announced (:func:`first_use`).

    Parameters
    ----------
    seconds : float
        The expected compilation time [s of CPU] (0: not stated).

    Examples
    --------
    >>> import os
    >>> from fws_control.simulation.compilation import announce_background
    >>> os.environ["FWS_CONTROL_QUIET"] = "1"
    >>> announce_background(30.0)      # silenced: nothing printed
    >>> del os.environ["FWS_CONTROL_QUIET"]
    """
    if _Notice.background:
        return
    _Notice.background = True
    if _quiet():
        return
    about = f"about {seconds:.0f} s of CPU; " if seconds > 0 else ""
    sys.stderr.write(
        "fws_control: compiling the simulation engine in a background process "
        f"(once: {about}cached in {cache_dir()}); until it is done, simulations "
        f"run on the numpy engine ({COMPILE_VARIABLE}=foreground waits for it "
        f"instead; {QUIET_VARIABLE}=1 silences this)\n"
    )
    sys.stderr.flush()


def _close() -> None:
    if _local.pending_line:
        _local.pending_line = False
        if not _quiet():
            sys.stderr.write(
                f"fws_control: compiled in {_local.seconds:.1f} s of CPU\n"
            )
            sys.stderr.flush()
    _local.seconds = 0.0


if numba is not None:

    class _Listener(_event.Listener):
        # numba fires "numba:compile" for a compilation only, never for a
        # kernel loaded from the cache: the notice is exactly the cold case
        # Only inside a first_use block (the engine's entry points): a
        # kernel called directly, e.g. to test it, compiles silently.
        def on_start(self, ev):
            if not _local.plans or not _ours(ev.data.get("dispatcher")):
                return
            if _local.depth == 0:
                _local.start = time.process_time()
                if not _Notice.announced:
                    _announce()
            _local.depth += 1

        def on_end(self, ev):
            if not _local.plans or not _ours(ev.data.get("dispatcher")):
                return
            _local.depth -= 1
            if _local.depth == 0:
                _local.seconds += time.process_time() - _local.start

    _event.register("numba:compile", _Listener())


@contextlib.contextmanager
def first_use(estimate: Callable[[], float] | None = None) -> Iterator[None]:
    """Announce a compilation inside this block, with an estimate of its cost.

    The first compilation of a kernel of fws_control in the process is
    announced on standard error (see the module notes); `estimate` is then
    called for the CPU seconds the block is expected to compile in all. The
    outermost block closes the announcement with one line giving the CPU
    time the compilations took. Blocks nest (only the outermost counts).

    Parameters
    ----------
    estimate : callable, optional
        Returns the expected compilation time [s of CPU] of what is still
        to compile, called once, when the first compilation starts.

    Examples
    --------
    >>> from fws_control.simulation.compilation import first_use
    >>> with first_use(lambda: 1.0):
    ...     pass                       # nothing compiled: nothing printed
    """
    _local.plans.append(estimate or (lambda: 0.0))
    try:
        yield
    finally:
        _local.plans.pop()
        if not _local.plans:
            _close()


def compile_seconds(dispatcher: Any, seconds: float) -> float:
    """`seconds` if `dispatcher` still needs compiling, else 0.

    A kernel needs compiling unless :func:`is_compiled`.

    Parameters
    ----------
    dispatcher : numba dispatcher
        A kernel made by :func:`jit`.
    seconds : float
        Its compilation time [s of CPU] when it compiles.

    Returns
    -------
    float

    Examples
    --------
    >>> from fws_control.simulation.compilation import compile_seconds, jit
    >>> twice = jit(lambda x: 2.0 * x)
    >>> _ = twice(1.0)                 # compiled (or loaded) now
    >>> compile_seconds(twice, 5.0)
    0.0
    """
    return 0.0 if is_compiled(dispatcher) else float(seconds)


def is_compiled(dispatcher: Any) -> bool:
    """Whether `dispatcher` runs without compiling: compiled in this process
    or in the cache with the current source.

    Parameters
    ----------
    dispatcher : numba dispatcher
        A kernel made by :func:`jit`.

    Returns
    -------
    bool
        True if it has a compiled version in this process, or an index file
        in its cache folder stamped with the kernels' current source (numba
        writes the index with the first compilation, and ignores one of an
        older source).

    Examples
    --------
    >>> from fws_control.simulation.compilation import is_compiled, jit
    >>> twice = jit(lambda x: 2.0 * x)
    >>> _ = twice(1.0)                 # compiled (or loaded) now
    >>> is_compiled(twice)
    True
    """
    if numba is None:  # pragma: no cover
        return False
    if getattr(dispatcher, "overloads", None):
        return True
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if not isinstance(cache_file, _KernelCacheFile):
        return False
    # (an empty dict: no index, another numba version or an older source)
    return bool(cache_file._load_index())
