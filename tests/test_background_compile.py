"""Kernels not in the cache compile in a background process (the default).

References: the files on disk (the lock a background compilation holds, the
process id it writes there), the operating system's process table
(``/proc/<pid>/cmdline`` on Linux, else ``os.kill(pid, 0)``), the result's
own ``engine`` field, and the kernel sets' rule written out here from the
module notes of ``fws_control.simulation.precompile`` (a delay, the dynamic
model, a controller's compiled law or a varying speed: the kernels of every
feature).
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

import fws_control as fws
from fws_control.simulation import compilation, compiled, precompile

fcntl = pytest.importorskip("fcntl", reason="POSIX: the background compilation's flock")

ROOT = Path(__file__).resolve().parents[1]

numba = pytest.importorskip("numba", reason="the extra 'fast' (numba)")

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
GAINS = fws.SteeringGains(0.04, 0.4, -1.0)


def _env(cache: Path, **updates: str) -> dict:
    """This checkout first on the path, numba's cache in `cache`, the default
    compile mode."""
    drop = ("XDG_CACHE_HOME", compilation.QUIET_VARIABLE, compilation.COMPILE_VARIABLE)
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update(PYTHONPATH=str(ROOT), NUMBA_CACHE_DIR=str(cache))
    env.update(updates)
    return env


def _python(code: str, env: dict, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=env, cwd=cwd, capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip


def _folder(cache: Path) -> Path:
    # the simulation kernels' cache folder under NUMBA_CACHE_DIR (numba's rule)
    (folder,) = cache.glob("simulation_*")
    return folder


def _child_pid(lock: Path, old: int | None = None) -> int:
    # the pid the background process writes into its lock (waiting for it;
    # its start, imports included, can take seconds on a busy machine)
    for _ in range(2400):
        text = lock.read_text().strip() if lock.exists() else ""
        if text and int(text) != old:
            return int(text)
        time.sleep(0.05)
    raise AssertionError(f"no process id in {lock}")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except OSError:
        return False
    if sys.platform == "linux":  # (a zombie is dead)
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except FileNotFoundError:
            return False
        return stat.rsplit(")", 1)[1].split()[0] != "Z"
    return True


def _is_background(pid: int, name: str) -> bool:
    # a live process compiling kernel set `name` (its command line on Linux)
    if not _alive(pid):
        return False
    if sys.platform != "linux":
        return True
    cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    return (
        len(cmd) > 3
        and b"precompile._background(sys.argv[1], int(sys.argv[2]))" in cmd[2]
        and cmd[3] == name.encode()
    )


def _stop(pid: int) -> None:
    # kill a background compilation (only one: a pid can be reused)
    if not _is_background(pid, _set_of(pid)):
        return
    os.kill(pid, signal.SIGKILL)
    for _ in range(200):  # (a detached process: not our child to wait for)
        if not _alive(pid):
            return
        time.sleep(0.05)
    raise AssertionError(f"process {pid} still runs")


def _set_of(pid: int) -> str:
    # the kernel set a process's command line names (Linux), else ""
    try:
        cmd = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return ""
    return cmd[3].decode() if len(cmd) > 3 else ""


def _stop_all(cache: Path) -> None:
    # every background compilation named in a lock under `cache`
    for lock in cache.rglob("compiling-*.lock"):
        text = lock.read_text().strip()
        if text.isdigit():
            _stop(int(text))


# Two calls of the paper's loop, then Stanley's law; the engine of each and
# whether a notice came.
_CALLS = """
import sys
import fws_control as fws
veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
plant = fws.LateralPlant(veh, speed=5.0)
g = fws.SteeringGains(0.04, 0.4, -1.0)
for law in (g, g, fws.Stanley(gain=2.0)):
    r = fws.simulate(plant, fws.Arc(curvature=0.1), law,
                     initial_state=(0.0, -1.0, 0.0), duration=1.0)
    print(r.engine, flush=True)
    sys.stderr.write("--\\n")
"""


@contextlib.contextmanager
def _holding(*locks: Path):
    # the locks' flocks held here, as a running background process holds
    # its own (acquiring one also proves that no process holds it)
    fds = [os.open(lock, os.O_RDWR) for lock in locks]
    try:
        for fd in fds:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        yield
    finally:
        for fd in fds:
            os.close(fd)


def test_a_cold_call_runs_on_numpy_and_starts_one_background_compilation(tmp_path):
    cache = tmp_path / "cache"
    pids: list[int] = []
    try:
        run = _python(_CALLS, _env(cache), tmp_path)
        assert run.returncode == 0, run.stderr[-2000:]
        folder = _folder(cache)
        paper = folder / "compiling-paper-dop853.lock"
        features = folder / "compiling-features-dop853.lock"
        pids.extend(_child_pid(lock) for lock in (paper, features))
        assert run.stdout.split() == ["numpy", "numpy", "numpy"]
        # one notice in the process, at its first call
        blocks = run.stderr.split("--\n")
        assert blocks[0].count("\n") == 1, run.stderr
        assert blocks[0].startswith(
            "fws_control: compiling the simulation engine in a background process"
        )
        # the estimate: DOP853, signals and peaks of the paper's loop
        estimate = sum(
            compiled.STAGE_SECONDS[k] for k in ("DOP853", "signals", "peaks")
        )
        assert f"about {estimate:.0f} s of CPU" in blocks[0]
        assert f"cached in {folder}" in blocks[0]
        assert "FWS_CONTROL_COMPILE=foreground" in blocks[0]
        assert blocks[1:] == ["", "", ""]
        # one process per set, each compiling its own set
        assert pids[0] != pids[1]
        assert _is_background(pids[0], "paper-dop853")
        assert _is_background(pids[1], "features-dop853")

        # killed: their locks end with them
        for pid in pids:
            _stop(pid)
        with _holding(paper, features):
            # another process while the locks are held: the numpy engine,
            # no new process (no pid written)
            again = _python(_CALLS, _env(cache), tmp_path)
            assert again.returncode == 0, again.stderr[-2000:]
            assert again.stdout.split() == ["numpy", "numpy", "numpy"]
            assert again.stderr.startswith("fws_control: compiling the simulation")
            # quiet: the same, nothing printed
            quiet = _python(_CALLS, _env(cache, FWS_CONTROL_QUIET="1"), tmp_path)
            assert quiet.stdout.split() == ["numpy", "numpy", "numpy"]
            assert quiet.stderr == "--\n--\n--\n"
            assert [_child_pid(paper), _child_pid(features)] == pids

        # released (the killed compilation): the next call starts another
        one = _python(_CALLS.replace("(g, g, fws.Stanley(gain=2.0))", "(g,)"),
                      _env(cache), tmp_path)  # fmt: skip
        assert one.stdout.split() == ["numpy"]
        pids.append(_child_pid(paper, old=pids[0]))
        assert _is_background(pids[-1], "paper-dop853")
    finally:
        for pid in pids:
            _stop(pid)
        _stop_all(cache)


def test_a_failed_background_compilation_leaves_a_mark(tmp_path, monkeypatch):
    # a background process that fails (here: a set it does not know) writes
    # its pid, then compiling-<set>.failed with the error, and its log
    files = {s: tmp_path / f"compiling-x{s}" for s in (".lock", ".failed", ".log")}
    monkeypatch.setattr(precompile, "_set_file", lambda name, s: str(files[s]))
    monkeypatch.setattr(precompile, "_CHILDREN", {})
    assert precompile._start("no-such-set")
    child = precompile._CHILDREN["no-such-set"]
    assert child.wait(timeout=300) != 0
    assert int(files[".lock"].read_text()) == child.pid
    assert files[".failed"].read_text() == (
        f"ValueError: name must be one of {precompile.KERNEL_SETS}, got 'no-such-set'\n"
    )
    assert "Traceback" in files[".log"].read_text()
    # the calls: compiled here (True), no process started
    monkeypatch.delenv(compilation.COMPILE_VARIABLE, raising=False)
    monkeypatch.setattr(precompile, "is_cached", lambda name: False)
    monkeypatch.setattr(precompile, "_READY", set())
    monkeypatch.setattr(precompile, "_start", lambda name: pytest.fail("started"))
    assert precompile.ready_or_background("paper-radau")
    # without the mark, a process of this one's that ended (killed): the same
    files[".failed"].unlink()
    monkeypatch.setattr(precompile, "_CHILDREN", {"paper-radau": child})
    assert precompile.ready_or_background("paper-radau")
    # once the set is cached the mark goes
    files[".failed"].write_text("x")
    monkeypatch.setattr(precompile, "is_cached", lambda name: True)
    assert precompile.ready_or_background("paper-radau")
    assert not files[".failed"].exists()


def test_cached_kernels_run_compiled_without_a_notice(monkeypatch, capsys):
    plant = fws.LateralPlant(VEH, speed=5.0)
    kw = dict(initial_state=(0.0, -1.0, 0.0), duration=1.0)
    # compiled here (or loaded from the cache): the set is then cached
    ref = fws.simulate(plant, fws.Arc(curvature=0.1), GAINS, engine="compiled", **kw)
    assert precompile.is_cached("paper-dop853")
    monkeypatch.delenv(compilation.COMPILE_VARIABLE, raising=False)
    capsys.readouterr()
    res = fws.simulate(plant, fws.Arc(curvature=0.1), GAINS, **kw)
    assert res.engine == "compiled"
    assert (res.signals == ref.signals).all()
    assert capsys.readouterr().err == ""


def test_foreground_mode_and_the_mode_names(monkeypatch):
    with pytest.raises(ValueError, match="name must be one of .*got 'paper-lsoda'"):
        precompile.is_cached("paper-lsoda")
    monkeypatch.setattr(precompile, "is_cached", lambda name: False)
    monkeypatch.setattr(precompile, "_READY", set())
    monkeypatch.setenv(compilation.COMPILE_VARIABLE, "Foreground")
    assert compilation.compile_mode() == "foreground"
    assert precompile.ready_or_background("paper-dop853")
    monkeypatch.setenv(compilation.COMPILE_VARIABLE, "later")
    with pytest.raises(
        ValueError, match="FWS_CONTROL_COMPILE must be 'background' or "
        "'foreground', got 'later'"
    ):  # fmt: skip
        fws.simulate(
            fws.LateralPlant(VEH, speed=5.0), fws.Straight(), GAINS,
            initial_state=(0.0, -1.0, 0.0), duration=1.0,
        )  # fmt: skip


@pytest.mark.parametrize(
    ("case", "expected"),
    [
        (dict(), "paper-dop853"),
        (dict(method="Radau"), "paper-radau"),
        (dict(delay=0.1), "features-dop853"),
        (dict(model="dynamic"), "features-dop853"),
        (dict(law=fws.Stanley()), "features-dop853"),
        (dict(law=fws.PurePursuit()), "features-dop853"),
        (dict(law=fws.StateFeedback(GAINS.K)), "features-dop853"),
        # sampled: the MPC's held command is a compiled law of its own
        (dict(law=fws.MPCController()), "features-dop853"),
        (dict(profile=fws.SpeedProfile.from_time([0, 5], [5, 3])), "features-dop853"),
        (dict(profile=fws.SpeedProfile.constant(5.0)), "paper-dop853"),
    ],
)
def test_kernel_set_of_a_call(case, expected):
    args = dict(method="DOP853", delay=0.0, model="kinematic", law=GAINS, profile=None)
    args.update(case)
    assert precompile.kernel_set(**args) == expected


def test_precompile_waits_for_a_background_compilation_of_its_set(
    tmp_path, monkeypatch
):
    lock = tmp_path / "compiling-paper-radau.lock"
    lock.touch()
    monkeypatch.setattr(precompile, "_set_file", lambda name, suffix: str(lock))
    ran = []
    monkeypatch.setattr(precompile, "_run_set", lambda name: ran.append(name))
    worker = threading.Thread(target=precompile._run_set_locked, args=("paper-radau",))
    with _holding(lock):  # a background process compiling the set
        worker.start()
        worker.join(0.5)
        assert worker.is_alive() and ran == []  # waiting for the lock
    worker.join(10.0)
    assert not worker.is_alive() and ran == ["paper-radau"]
