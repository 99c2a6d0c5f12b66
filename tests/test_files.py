"""fws_control.files: atomic writes and the per-folder lock."""

import os
import signal
import subprocess
import sys
import time

import pytest

from fws_control.files import (
    LOCK_NAME,
    TEMP_SUFFIX,
    FolderInUseError,
    atomic_write,
    lock_folder,
    remove_stale_temporaries,
)


def test_atomic_write_replaces_whole_file(tmp_path):
    target = tmp_path / "sub" / "data.bin"
    payload = os.urandom(300_000)
    with atomic_write(target) as fh:
        fh.write(payload[:1000])
        # Until the block ends the final name does not exist.
        assert not target.exists()
        fh.write(payload[1000:])
    assert target.read_bytes() == payload
    assert [p.name for p in target.parent.iterdir()] == ["data.bin"]
    # Permissions as a plain open() gives them, not mkstemp's 0600.
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask


@pytest.mark.parametrize("exc", [RuntimeError, KeyboardInterrupt])
def test_atomic_write_failure_keeps_old_file(tmp_path, exc):
    target = tmp_path / "fig.png"
    target.write_bytes(b"old complete content")
    with pytest.raises(exc):
        with atomic_write(target) as fh:
            fh.write(b"\x89PNG half a file")
            raise exc
    assert target.read_bytes() == b"old complete content"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig.png"]


def test_atomic_write_text_and_bad_mode(tmp_path):
    target = tmp_path / "t.md"
    with atomic_write(target, mode="w") as fh:
        fh.write("a\nb\n")
    assert target.read_bytes() == b"a\nb\n"  # no newline translation
    with pytest.raises(ValueError, match="mode must be 'wb' or 'w', got 'a'"):
        with atomic_write(target, mode="a"):
            pass


def test_atomic_write_error_names_the_final_file(tmp_path):
    blocker = tmp_path / "plain_file"
    blocker.write_bytes(b"")
    target = blocker / "out.png"  # its folder is a file: cannot be created
    with pytest.raises(OSError) as exc:
        with atomic_write(target):
            pass
    assert "out.png" in str(exc.value) or "plain_file" in str(exc.value)
    assert TEMP_SUFFIX not in str(exc.value)
    if sys.platform.startswith("linux"):
        # /proc exists, but no file can be created in it (not even by root):
        # the temporary file fails, and the error names the final file.
        with pytest.raises(OSError) as exc:
            with atomic_write("/proc/fws_control_test.png"):
                pass
        assert str(exc.value).endswith("'/proc/fws_control_test.png'"), exc.value


def test_remove_stale_temporaries_only_touches_temporaries(tmp_path):
    stale = tmp_path / f".fig3.png.k2j3{TEMP_SUFFIX}"
    stale.write_bytes(b"\x89PNG trunc")
    keep = [tmp_path / "fig3.png", tmp_path / ".hidden", tmp_path / "x.fws-tmp.png"]
    for p in keep:
        p.write_bytes(b"x")
    assert remove_stale_temporaries(tmp_path) == [stale]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in keep)


_HOLDER = """
import fcntl, os, sys, time
fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT, 0o644)
fcntl.flock(fd, fcntl.LOCK_EX)
print("locked", flush=True)
time.sleep(60)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="flock holder script is POSIX")
def test_lock_refuses_while_held_and_dies_with_its_process(tmp_path):
    """A second locker is refused; a SIGKILLed holder leaves no stale lock."""
    holder = subprocess.Popen(
        [sys.executable, "-c", _HOLDER, str(tmp_path / LOCK_NAME)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        t0 = time.perf_counter()
        with pytest.raises(FolderInUseError, match="in use by another fws-control"):
            with lock_folder(tmp_path):
                pass
        assert time.perf_counter() - t0 < 1.0  # refused at once, no waiting
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=10)
    assert holder.returncode == -signal.SIGKILL
    with lock_folder(tmp_path) as lock:
        assert lock == tmp_path / LOCK_NAME
    # Released at the end of the block: it can be taken again.
    with lock_folder(tmp_path):
        pass
