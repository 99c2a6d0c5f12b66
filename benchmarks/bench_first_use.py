"""CPU cost of the first compiled ``simulate`` in a fresh environment, and later.

Runs the paper's 15 s curve scenario (``PAPER_SCENARIOS["curve_5"]``: arc
1/10 m, 5 m/s, start (0, -5 m, 0), feedforward; the double-root design at
ratio -1, pole -1) in fresh interpreters, ``python -c`` as a user would:

- **first call** (the default, ``FWS_CONTROL_COMPILE=background``): numba's
  cache in a new empty folder; the call runs on the numpy engine while a
  background process compiles the kernels. Printed: the process's CPU to
  its result and its notice, then (waiting for the background process to
  release the flock on its lock file) that process's own CPU for the
  compilation (from its log) and the wall time until the kernels were
  cached, and a next process's CPU to its first (compiled) result;
- **cold** (``FWS_CONTROL_COMPILE=foreground``): numba's cache in a new
  empty folder (``NUMBA_CACHE_DIR``, a fresh temporary folder for each
  run), so the call compiles the engine's kernels and waits;
  printed with the compilation time of each stage (from numba's compile
  events: the stages' top kernels and everything they compile) and the
  first-use notice the process wrote on standard error;
- **warm**: ``--repeat`` (5) more processes on the cache the cold run
  filled, the best of them; then as many with ``OPENBLAS_NUM_THREADS=1``
  (numpy's and scipy's OpenBLAS start a pool of spinning threads when
  loaded: CPU that the process pays at its start whatever it computes);
- **the floor**: alternating with the warm processes (which of the two
  goes first changes every round), a process that imports numpy and numba
  and calls one trivial cached kernel (a loop summing an array, compiled
  once beforehand): the start-up of Python, numpy and numba (numba's
  import, its typing and target registries, and the scipy.linalg import
  of its BLAS check), which any process that runs a cached numba kernel
  pays. The warm process's excess over it is fws_control's share. Every
  value is printed, so that the spread shows.

Each time is the process's own CPU time (user + system, all threads, from
``resource.getrusage``) up to its first result, the imports included, and
the CPU time of the ``simulate`` call alone. The machine load (load
averages from ``os.getloadavg()``) is printed before and after: CPU times
stretch on a busy machine too (shared caches and cores).

Targets: the first compiled ``simulate`` <= 10 s of CPU with a message (here:
the first call, which does not wait for the compilation), warm <= 1 s of CPU
to the first result.

``--case stanley`` runs Stanley (gain 2) instead of the paper's law, from
0.5 m beside an arc of 1/100 m at 20 m/s for 5 s: a call that uses the
kernels of every feature (a controller's law), whose stages give the
estimates of ``compiled.FULL_STAGE_SECONDS``.

Run: ``python benchmarks/bench_first_use.py [--cold 1] [--case stanley]``
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from timing import machine_line

ROOT = Path(__file__).resolve().parents[1]

# One user's first call. The stage of each of fws_control's compilations is
# its top kernel (a kernel compiled while no other one of ours compiles).
_CHILD = r"""
import resource, time
def cpu():
    ru = resource.getrusage(resource.RUSAGE_SELF)
    return ru.ru_utime + ru.ru_stime
stages = {}
try:
    from numba.core import event
except ImportError:
    event = None
if event is not None:
    class Stages(event.Listener):
        depth = 0
        def on_start(self, ev):
            fn = ev.data["dispatcher"].py_func
            if not fn.__module__.startswith("fws_control."):
                return
            if Stages.depth == 0:
                Stages.name, Stages.t0 = fn.__name__, time.process_time()
            Stages.depth += 1
        def on_end(self, ev):
            fn = ev.data["dispatcher"].py_func
            if not fn.__module__.startswith("fws_control."):
                return
            Stages.depth -= 1
            if Stages.depth == 0:
                name = Stages.name
                stages[name] = stages.get(name, 0.0) + time.process_time() - Stages.t0
    event.register("numba:compile", Stages())
import fws_control as fws
veh = fws.Vehicle(wheelbase=WHEELBASE, rear_to_cg=REAR_TO_CG)
g = LAW
before = cpu()
res = fws.simulate(fws.LateralPlant(veh, speed=SPEED), fws.Arc(curvature=CURVATURE),
                   g, initial_state=INITIAL, duration=DURATION, feedforward=True)
after = cpu()
import json
print(json.dumps({"total": after, "simulate": after - before, "stages": stages,
                  "engine": res.engine, "status": str(res.status)}))
"""

# the top kernels' names (their stage in compiled.STAGES)
_STAGE_OF = {
    "solve_batch": "DOP853 or Radau driver",
    "signals_batch": "signals",
    "peaks_batch": "peaks",
}


def child_code(case: str = "paper") -> str:
    from fws_control.paper.data import PAPER_VEHICLE
    from fws_control.paper.scenarios import PAPER_SCENARIOS

    sc = PAPER_SCENARIOS["curve_5"]
    values = {
        "WHEELBASE": PAPER_VEHICLE.wheelbase,
        "REAR_TO_CG": PAPER_VEHICLE.rear_to_cg,
        "SPEED": sc.speed,
        "CURVATURE": sc.curvature,
        "INITIAL": sc.initial_state,
        "DURATION": sc.duration,
    }
    law = (
        "fws.double_root_gains(veh, speed=SPEED, curvature=CURVATURE, "
        "ratio=-1.0, pole=-1.0)"
    )
    if case == "stanley":
        values.update(SPEED=20.0, CURVATURE=0.01, INITIAL=(0.0, 0.5, 0.0),
                      DURATION=5.0)  # fmt: skip
        law = "fws.Stanley(gain=2.0)"
    code = _CHILD.replace("LAW", law)
    for name, value in values.items():
        code = code.replace(name, repr(value))
    return code


# numba's floor: a process that runs one trivial cached kernel
_FLOOR_KERNEL = """
import numba

@numba.njit(cache=True)
def total(x):
    s = 0.0
    for i in range(x.size):
        s += x[i]
    return s
"""

_FLOOR = r"""
import resource, sys
sys.path.insert(0, FOLDER)
import numpy as np
import floor_kernel
floor_kernel.total(np.ones(3))
ru = resource.getrusage(resource.RUSAGE_SELF)
import json
print(json.dumps({"total": ru.ru_utime + ru.ru_stime}))
"""


def floor_code(folder: str) -> str:
    """A process's code that runs :data:`_FLOOR_KERNEL` from `folder`."""
    Path(folder, "floor_kernel.py").write_text(_FLOOR_KERNEL)
    return _FLOOR.replace("FOLDER", repr(folder))


def run(code: str, cache: str, **extra_env: str) -> tuple[dict, str]:
    env = dict(os.environ, **extra_env)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(ROOT), *filter(None, [env.get("PYTHONPATH")])]
    )
    env["NUMBA_CACHE_DIR"] = cache
    env.pop("FWS_CONTROL_QUIET", None)
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=tempfile.gettempdir(),
        capture_output=True, text=True, check=True, timeout=1800,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1]), out.stderr


def first_call(code: str, cache: str) -> float:
    """The default: the first call runs on numpy, the kernels compile aside."""
    start = time.perf_counter()
    first, notice = run(code, cache, FWS_CONTROL_COMPILE="background")
    print(
        f"first call (background): {first['total']:6.2f} s of CPU to the first "
        f"result, simulate {first['simulate']:6.2f} s (engine {first['engine']}, "
        f"status {first['status']})"
    )
    for line in notice.splitlines():
        print(f"    stderr: {line}")
    import fcntl  # (the background mode is POSIX's)

    (folder,) = Path(cache).glob("simulation_*")
    for lock in folder.glob("compiling-*.lock"):
        # the background process holds the lock's flock until it ends
        fd = os.open(lock, os.O_RDWR)
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.close(fd)
    cached = time.perf_counter() - start
    for log in sorted(folder.glob("compiling-*.log")):
        print(f"    background {log.name}: {log.read_text().strip()}")
    print(f"    cached {cached:.1f} s (wall) after the first call started")
    later, _ = run(code, cache, FWS_CONTROL_COMPILE="background")
    print(
        f"next process: {later['total']:6.3f} s of CPU to the first result "
        f"(engine {later['engine']})"
    )
    return float(first["total"])


def warm_and_floor(
    code: str, cache: str, floor: str, floor_cache: str, repeat: int, **env: str
) -> tuple[dict, float]:
    """Best of `repeat` warm and floor processes, run alternately.

    The two alternate, the first of each round changing from round to
    round, so that a drift of the machine's speed is shared; every value
    is printed.
    """
    warm, floors = [], []
    for i in range(repeat):
        for kind in ("warm", "floor") if i % 2 == 0 else ("floor", "warm"):
            if kind == "warm":
                res = run(code, cache, FWS_CONTROL_COMPILE="foreground", **env)[0]
                warm.append(res)
            else:
                floors.append(run(floor, floor_cache, **env)[0]["total"])
    print("    warm:  " + ", ".join(f"{r['total']:.3f}" for r in warm))
    print("    floor: " + ", ".join(f"{v:.3f}" for v in floors))
    return min(warm, key=lambda r: r["total"]), min(floors)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cold", type=int, default=1, help="cold runs (each >= 10 s)")
    parser.add_argument("--case", choices=("paper", "stanley"), default="paper")
    parser.add_argument(
        "--repeat", type=int, default=5, help="warm and floor processes (5)"
    )
    args = parser.parse_args()
    if args.cold < 1:
        # the warm runs use the cache the best cold run filled
        parser.error(f"--cold must be >= 1, got {args.cold}")
    code = child_code(args.case)
    print(machine_line())
    with tempfile.TemporaryDirectory(prefix="fws-first-use-") as tmp:
        first = first_call(code, os.path.join(tmp, "background"))
        best_cold = None
        for i in range(args.cold):
            cache = os.path.join(tmp, f"cache{i}")  # a new empty folder
            cold, notice = run(code, cache, FWS_CONTROL_COMPILE="foreground")
            print(
                f"cold (empty cache) : {cold['total']:6.2f} s of CPU to the first "
                f"result, simulate {cold['simulate']:6.2f} s (engine "
                f"{cold['engine']}, status {cold['status']})"
            )
            for name, sec in cold["stages"].items():
                print(f"    compiled {_STAGE_OF.get(name, name):24s} {sec:6.2f} s")
            for line in notice.splitlines():
                print(f"    stderr: {line}")
            if best_cold is None or cold["total"] < best_cold["total"]:
                best_cold, warm_cache = cold, cache
        floor = floor_code(tmp)
        floor_cache = os.path.join(tmp, "floor")
        run(floor, floor_cache)  # compiles the trivial kernel once
        best, floor_best = warm_and_floor(
            code, warm_cache, floor, floor_cache, args.repeat
        )
        print(
            f"warm (cached), best of {args.repeat}: {best['total']:6.3f} s of CPU "
            f"to the first result, simulate {best['simulate']:6.3f} s; numba's floor "
            f"{floor_best:6.3f} s, fws_control's share "
            f"{best['total'] - floor_best:6.3f} s"
        )
        # numpy's and scipy's OpenBLAS each start a pool of threads when
        # loaded, which spin for a while: CPU that the process pays but
        # fws_control does not spend
        one, floor_one = warm_and_floor(
            code, warm_cache, floor, floor_cache, args.repeat, OPENBLAS_NUM_THREADS="1"
        )
        print(
            f"warm, OPENBLAS_NUM_THREADS=1, best of {args.repeat}: "
            f"{one['total']:6.3f} s of CPU to the first result, simulate "
            f"{one['simulate']:6.3f} s; numba's floor {floor_one:6.3f} s"
        )
        print(
            f"targets: first call {first:.2f} / 10 s of CPU; "
            f"cold (foreground) {best_cold['total']:.2f} s of CPU; "
            f"warm {best['total']:.3f} / 1 s target"
        )
    print(machine_line())


if __name__ == "__main__":
    main()
