"""Writing output files safely: atomic replacement and a lock per folder.

Every file that ``fws_control`` writes (the PNG, CSV and Markdown files of
the command line and of :func:`fws_control.paper.reproduce`) goes through
:func:`atomic_write`: the data go to a temporary file in the same folder,
which is flushed to disk and then renamed onto the final name with
:func:`os.replace`. A reader therefore sees the old file, the new file or no
file, never a truncated one -- whatever interrupts the writer (Ctrl-C,
``kill``, a full disk, an exception while drawing).

:func:`lock_folder` lets one process at a time own an output folder. The
lock is an advisory ``flock`` on the file ``.fws-control.lock`` in that
folder: the operating system releases it when the process ends, however it
ends, so a run killed with ``SIGKILL`` never blocks the next one. The empty
lock file itself stays in the folder (removing it would let two processes
hold locks on two different files of the same name).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = [
    "FolderInUseError",
    "LOCK_NAME",
    "TEMP_SUFFIX",
    "atomic_write",
    "lock_folder",
    "remove_stale_temporaries",
]

#: Name of the lock file that :func:`lock_folder` creates in the folder.
LOCK_NAME = ".fws-control.lock"

#: Suffix of the temporary files of :func:`atomic_write` (hidden files:
#: ``.<name>.<random>`` + this suffix).
TEMP_SUFFIX = ".fws-tmp"

# Signals that must not land between creating a temporary file and knowing
# its name, nor between the rename and the clean-up: they are held back for
# those few statements and delivered right after (POSIX only).
_DEFERRED = tuple(
    s for s in (getattr(signal, "SIGINT", None), getattr(signal, "SIGTERM", None)) if s
)


class FolderInUseError(BlockingIOError):
    """Another process holds the lock of an output folder (:func:`lock_folder`).

    Examples
    --------
    >>> from fws_control.files import FolderInUseError
    >>> issubclass(FolderInUseError, OSError)
    True
    """


@contextlib.contextmanager
def _signals_deferred() -> Iterator[None]:
    # Python runs signal handlers in the main thread only; masking from
    # another thread would not defer them.
    can_mask = (
        hasattr(signal, "pthread_sigmask")
        and bool(_DEFERRED)
        and threading.current_thread() is threading.main_thread()
    )
    if not can_mask:
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _DEFERRED)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


@contextlib.contextmanager
def atomic_write(
    path: str | os.PathLike, *, mode: str = "wb", encoding: str | None = None
) -> Iterator[IO]:
    r"""Open a temporary file next to ``path``; rename it onto ``path`` on success.

    The temporary file lives in the folder of ``path`` (so that the rename
    is atomic: same file system) under a hidden name ending in
    :data:`TEMP_SUFFIX`. When the ``with`` block ends normally the data are
    flushed and synced and the file replaces ``path`` in one step; when it
    ends with an exception (including ``KeyboardInterrupt``) the temporary
    file is removed and ``path`` is left as it was. The folder is created if
    needed.

    Parameters
    ----------
    path : path-like
        Final name of the file.
    mode : {"wb", "w"}, optional
        Binary or text.
    encoding : str, optional
        Text encoding for ``mode="w"`` (default UTF-8).

    Yields
    ------
    file object
        Open for writing.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from fws_control.files import atomic_write
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     target = pathlib.Path(tmp) / "table.csv"
    ...     with atomic_write(target, mode="w") as fh:
    ...         _ = fh.write("a,b\n1,2\n")
    ...     sorted(p.name for p in pathlib.Path(tmp).iterdir()), target.read_text()
    (['table.csv'], 'a,b\n1,2\n')
    """
    if mode not in ("wb", "w"):
        raise ValueError(f"mode must be 'wb' or 'w', got {mode!r}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with _signals_deferred():
        try:
            tmp: str | None
            fd, tmp = tempfile.mkstemp(
                dir=path.parent, prefix=f".{path.name}.", suffix=TEMP_SUFFIX
            )
        except OSError as exc:
            # Name the file the caller asked for, not the temporary one.
            raise type(exc)(exc.errno, exc.strerror, str(path)) from None
    try:
        fh: IO[Any]
        if mode == "w":
            fh = open(fd, "w", encoding=encoding or "utf-8", newline="")
        else:
            fh = open(fd, "wb")
        with fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        # mkstemp creates the file private (0600); give it the mode that a
        # plain open() would have given.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        with _signals_deferred():
            os.replace(tmp, path)
            tmp = None
    finally:
        if tmp is not None:
            with _signals_deferred():
                with contextlib.suppress(OSError):
                    os.unlink(tmp)


def remove_stale_temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    r"""Remove temporary files that an earlier, killed writer left in ``folder``.

    Only files named like the temporaries of :func:`atomic_write` are
    touched. Call it only while holding :func:`lock_folder` of the folder,
    so that no live writer's temporary file is removed.

    Parameters
    ----------
    folder : path-like

    Returns
    -------
    list of pathlib.Path
        The files removed.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from fws_control.files import remove_stale_temporaries
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     _ = (pathlib.Path(tmp) / ".fig2.png.x1y2.fws-tmp").write_bytes(b"\x89P")
    ...     [p.name for p in remove_stale_temporaries(tmp)]
    ['.fig2.png.x1y2.fws-tmp']
    """
    removed = []
    for p in Path(folder).glob(f".*{TEMP_SUFFIX}"):
        with contextlib.suppress(OSError):
            p.unlink()
            removed.append(p)
    return removed


@contextlib.contextmanager
def lock_folder(folder: str | os.PathLike) -> Iterator[Path]:
    """Hold the lock of an output folder for the duration of a ``with`` block.

    Creates the folder if needed and takes an exclusive, non-blocking
    ``flock`` on ``folder/.fws-control.lock`` (:data:`LOCK_NAME`). If another
    process holds it, :class:`FolderInUseError` is raised at once (no
    waiting): two runs writing into one folder would mix their files. The
    lock dies with the process, so a killed run leaves no stale lock. On
    systems without ``fcntl`` (Windows) ``msvcrt.locking`` is used.

    Parameters
    ----------
    folder : path-like

    Yields
    ------
    pathlib.Path
        The lock file.

    Raises
    ------
    FolderInUseError
        The folder is locked by another process (or another open lock in
        this process).

    Examples
    --------
    >>> import tempfile
    >>> from fws_control.files import FolderInUseError, lock_folder
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     with lock_folder(tmp):
    ...         try:
    ...             with lock_folder(tmp):
    ...                 pass
    ...         except FolderInUseError:
    ...             print("in use")
    in use
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lock = folder / LOCK_NAME
    fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            _lock_fd(fd)
        except OSError:
            raise FolderInUseError(
                f"output folder {str(folder)!r} is in use by another fws-control "
                "run (lock held on "
                f"{LOCK_NAME}); wait for it to finish or choose another folder"
            ) from None
        try:
            yield lock
        finally:
            _unlock_fd(fd)
    finally:
        os.close(fd)


if sys.platform == "win32":  # pragma: no cover - not tested on Linux CI
    import msvcrt

    def _lock_fd(fd: int) -> None:
        msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)

    def _unlock_fd(fd: int) -> None:
        os.lseek(fd, 0, os.SEEK_SET)
        msvcrt.locking(fd, msvcrt.LK_UNLCK, 1)

else:
    import fcntl

    def _lock_fd(fd: int) -> None:
        # flock locks belong to the open file description: a second
        # os.open of the same file, even in this process, cannot take it.
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)

    def _unlock_fd(fd: int) -> None:
        fcntl.flock(fd, fcntl.LOCK_UN)
