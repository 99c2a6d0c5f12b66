"""CPU per run of stiff batches: LSODA per chunk size against DOP853 (issue 14).

With the steering actuator of ``T = 0.05 s`` the paper's curve scenario
(``curve_5``: V = 5 m/s, curvature 1/10, R(0) = (0, -5 m), double root -1;
``--runs`` ratios over [-1, 0.5]) is stiff over long runs: ``method="auto"``
takes LSODA (``fws_control.simulation.options.choose_method``) and
``simulate_batch`` stacks 16 runs per chunk on the numpy engine
(``LSODA_MAX_RUNS``). Printed for 15 s and 150 s (output step 0.1 s), CPU
per run, best of ``--repeat`` >= 3: numpy LSODA at 1, 4, 8, 16 and 32 runs
per chunk, numpy DOP853 (default chunks) and compiled DOP853 (each run
alone; at its stability bound, 10^2-10^3 tolerances off a fixed-step
reference: ``tests/test_rate_limit_reference.py``). The chosen method and
its chunk are also printed for the default call.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from timing import machine_line

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE


def best_cpu(fn, repeat: int) -> float:
    """Best CPU time of `repeat` calls of ``fn`` [s]."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=32)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if args.repeat < 3:
        parser.error("--repeat must be >= 3 (best of at least three)")
    print(machine_line())
    n = args.runs
    g = fws.double_root_gains(PAPER_VEHICLE, speed=5.0, curvature=0.1,
                              ratio=np.linspace(-1.0, 0.5, n), pole=-1.0)  # fmt: skip
    base = dict(initial_state=(0.0, -5.0, 0.0), dt=0.1, progress=False)
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, steering_lag=0.05)

    def run(**kw):
        return fws.simulate_batch(plant, fws.Arc(0.1), g, **base, **kw)

    run(duration=2.0, method="DOP853", engine="compiled")  # numba warm-up
    print(f"{n} runs, CPU per run [ms], best of {args.repeat}:")
    for duration in (15.0, 150.0):
        default = run(duration=duration)
        print(f"  {duration:g} s: default call -> {default.engine} {default.method}")
        for chunk in (1, 4, 8, 16, 32):
            t = best_cpu(lambda c=chunk, d=duration: run(
                duration=d, method="LSODA", engine="numpy", chunk_size=c),
                args.repeat)  # fmt: skip
            print(f"    numpy LSODA, {chunk:2d} runs per chunk   {t / n * 1e3:8.1f}")
        for engine in ("numpy", "compiled"):
            t = best_cpu(lambda e=engine, d=duration: run(
                duration=d, method="DOP853", engine=e), args.repeat)  # fmt: skip
            print(f"    {engine:8s} DOP853                {t / n * 1e3:8.1f}")
    print(machine_line())


if __name__ == "__main__":
    main()
