"""CPU of ``fws-control compare`` with its default arguments, and per row.

1. The command itself, ``python -m fws_control compare --out <tmp>.png``
   (ISO 3888-1 at 20 m/s, the default controllers, kinematic model, no
   delay, no steering lag), in a child process: its user + system CPU
   seconds, all threads, from ``getrusage(RUSAGE_CHILDREN)``. A first run
   fills the compiled engine's cache (not timed); then the best of
   ``--repeat`` runs. The environment is passed on as it is (a BLAS thread
   setting such as ``OPENBLAS_NUM_THREADS`` is printed with the result).
2. In this process, each row alone: :func:`fws_control.compare` with that
   one controller, and the call with all of them, best of ``--repeat``
   rounds (each round times every row in turn, so that a drift of the
   machine's speed is shared). The command's CPU minus the whole call's is
   the interpreter's start, the imports, the figure and the table.
3. The same rows in condition B of ``docs/comparison.md``: the BMW 320i on
   the dynamic model (magic tyre) with the 0.24 s delay and the 0.27 s
   steering lag.

The machine load is printed before and after.

Run: ``python benchmarks/bench_compare.py [--repeat 3]`` (a minute of CPU;
minutes of wall time on a busy machine).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from timing import best_of_interleaved, machine_line

import fws_control as fws
from fws_control.controller_comparison import compare, default_controllers

ROOT = Path(__file__).resolve().parents[1]


def command_cpu(out: Path) -> float:
    """User + system CPU seconds of one ``fws-control compare`` run."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]
    )}  # fmt: skip
    subprocess.run(
        [sys.executable, "-m", "fws_control", "compare", "--out", str(out)],
        check=True,
        capture_output=True,
        env=env,
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(machine_line())
    blas = {
        k: os.environ[k]
        for k in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
        if k in os.environ
    }
    print(f"BLAS thread settings in the environment: {blas or 'none'}")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "compare.png"
        command_cpu(out)  # fills the compiled engine's cache
        cmd = min(command_cpu(out) for _ in range(args.repeat))
    print(f"fws-control compare (defaults): {cmd:.2f} s CPU (best of {args.repeat})")

    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    course = fws.double_lane_change(vehicle_width=1.8)
    times = row_times(
        fws.LateralPlant(veh, speed=20.0), course,
        default_controllers(veh, speed=20.0), 0.0, args.repeat,
    )  # fmt: skip
    print(
        f"  {'(start, imports, figure, table)':32s} "
        f"{cmd - times['(all rows)']:6.2f} s CPU (the command minus all rows)"
    )
    # condition B of docs/comparison.md: the dynamic model with the realistic
    # delay and steering lag (every row compiled, the delay by the method of
    # steps)
    bmw = fws.vehicles.BMW_320I
    print("condition B: BMW 320i, dynamic model, magic tyre, delay 0.24 s, lag 0.27 s")
    row_times(
        fws.LateralPlant(bmw, speed=20.0, model="dynamic", tyre="magic",
                         steering_lag=0.27),
        fws.double_lane_change(), default_controllers(bmw, speed=20.0, delay=0.24),
        0.24, args.repeat,
    )  # fmt: skip
    print(machine_line())


def row_times(plant, course, ctrls, delay: float, repeat: int) -> dict[str, float]:
    """Print and return the CPU of each row of `compare` and of all rows."""
    # loads the compiled engine's kernels from the cache
    compare(plant, course, ctrls, delay=delay)
    fns = {
        label: (lambda c={label: ctrl}: compare(plant, course, c, delay=delay))
        for label, ctrl in ctrls.items()
    }
    fns["(all rows)"] = lambda: compare(plant, course, ctrls, delay=delay)
    times = best_of_interleaved(fns, repeat=repeat)
    for label, t in times.items():
        print(f"  {label:32s} {t:6.2f} s CPU")
    return times


if __name__ == "__main__":
    main()
