"""Peak memory of a 10^5-run sweep that keeps a few signals or only metrics.

The paper's curve scenario as in ``bench_engine.py`` (``curve_5``: V = 5
m/s, curvature 1/10, R(0) = (0, -5 m), feedforward + feedback, 15 s; double
root -1, ratios spread over [-1.5, 0.6]; DOP853, rtol 1e-10, atol 1e-12),
``simulate_batch(..., engine="compiled")`` with

(a) ``signals=("e", "lateral_accel")`` at the output step 0.02 s (``--dt``):
    two signals at the default 0.01 s over 10^5 runs are 2.4 GB, above the
    2 GiB of ``simulation.options.MAX_OUTPUT_BYTES``, and refused (printed);
(b) ``signals="metrics"`` at the default output step 0.01 s: no time
    series; per run the status, the peaks and the horizon metrics of
    ``tracking_metrics``, computed per chunk before its signals are freed.

Each case runs in a fresh Python process (so that one case's freed memory
does not hide the next one's): it imports, warms the numba cache up on a
4-run batch, resets the kernel's high-water mark of its resident set
(``echo 5 > /proc/self/clear_refs``), reads its resident set size
(``VmRSS`` of ``/proc/self/status``) just before the call and the
high-water mark ``VmHWM`` just after: the difference is the peak that the
call added, every allocation counted (numpy's, numba's, Python's). Where
the mark cannot be reset, ``resource.getrusage(...).ru_maxrss`` is used
instead, an upper bound (it may hold an earlier peak of the imports). The
returned data are the bytes of every array of the result (signals, time
grid, per-run fields). Wall and CPU time (``time.process_time``, all
threads) of the call, and the load average before and after, are printed.
One measurement per case: the peak memory does not depend on the load, the
times do (the wall time stretches with other jobs on the machine).

Run: ``python benchmarks/bench_memory.py [--runs 100000]`` (two to three
minutes at 10^5 runs on 2 cores); ``--engine numpy --runs 10000`` measures
the numpy engine (exact peaks of the dense output; about 1 ms of CPU a
run, so 10^4 runs).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

from timing import machine_line

_CASE = r"""
import dataclasses, json, os, resource, sys, time
import numpy as np
import fws_control as fws
from fws_control.paper import PAPER_VEHICLE
from fws_control.paper.scenarios import paper_scenario

runs, dt, signals = int(sys.argv[1]), float(sys.argv[2]), json.loads(sys.argv[3])
engine = sys.argv[4]
signals = tuple(signals) if isinstance(signals, list) else signals
veh, sc = PAPER_VEHICLE, paper_scenario("curve_5")
ratios = np.linspace(-1.5, 0.6, runs)
g = fws.double_root_gains(veh, speed=sc.speed, curvature=sc.curvature,
                          ratio=ratios, pole=-1.0)
plant = fws.LateralPlant(veh, speed=sc.speed)
kw = dict(initial_state=sc.initial_state, duration=sc.duration,
          dt=dt, engine=engine, progress=False, signals=signals)
g4 = fws.SteeringGains(g.k1[:4], g.k2[:4], g.ratio[:4])
fws.simulate_batch(plant, sc.path, g4, **{**kw, "duration": 1.0})  # numba cache


def status(key):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024


try:  # reset the high-water mark VmHWM to the current resident set size
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    method = "VmHWM after - VmRSS before (high-water mark reset)"
except OSError:
    method = "ru_maxrss after - VmRSS before (an upper bound)"
base = status("VmRSS")
load0 = os.getloadavg()[0]
w0, c0 = time.perf_counter(), time.process_time()
res = fws.simulate_batch(plant, sc.path, g, **kw)
wall, cpu = time.perf_counter() - w0, time.process_time() - c0
if method.startswith("VmHWM"):
    peak = status("VmHWM")
else:
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
data = sum(
    getattr(res, f.name).nbytes
    for f in dataclasses.fields(res)
    if isinstance(getattr(res, f.name), np.ndarray)
)
print(json.dumps({
    "signal_bytes": res.signals.nbytes, "data": data, "peak": peak - base,
    "base": base, "wall": wall, "cpu": cpu, "load0": load0,
    "load1": os.getloadavg()[0], "ok": int(np.sum(res.ok)),
    "names": list(res.signal_names), "samples": int(res.t.size),
    "method": method,
}))
"""


def run_case(runs: int, dt: float, signals, engine: str) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", _CASE, str(runs), str(dt), json.dumps(signals), engine],
        capture_output=True,
        text=True,
        check=True,
        env=dict(os.environ),
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100_000)
    parser.add_argument(
        "--dt", type=float, default=0.02, help="output step of case (a) [s]"
    )
    parser.add_argument(
        "--engine",
        choices=("compiled", "numpy"),
        default="compiled",
        help="numpy: about 1 ms of CPU per run, use --runs 10000",
    )
    args = parser.parse_args()
    print(machine_line())

    import numpy as np

    import fws_control as fws
    from fws_control.paper import PAPER_VEHICLE
    from fws_control.paper.scenarios import paper_scenario

    sc = paper_scenario("curve_5")
    g = fws.double_root_gains(
        PAPER_VEHICLE,
        speed=sc.speed,
        curvature=sc.curvature,
        ratio=np.linspace(-1.5, 0.6, args.runs),
        pole=-1.0,
    )
    from fws_control.simulation.engine import MAX_OUTPUT_BYTES

    if args.runs * 1501 * 2 * 8 > MAX_OUTPUT_BYTES:
        try:  # refused before any work: the budget counts the kept signals
            fws.simulate_batch(
                fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed),
                sc.path,
                g,
                initial_state=sc.initial_state,
                duration=sc.duration,
                engine=args.engine,
                signals=("e", "lateral_accel"),
            )
            print("two signals at dt = 0.01 s: accepted")
        except ValueError as exc:
            print(f"two signals at dt = 0.01 s: refused ({str(exc)[:100]}...)")

    cases = (
        ("(a) e, lateral_accel", ["e", "lateral_accel"], args.dt),
        ("(b) metrics only", "metrics", 0.01),
    )
    print(f"\n{args.runs} runs of {sc.name}, engine={args.engine!r}")
    print(
        f"{'case':22s} {'dt s':>5s} {'signals MB':>10s} {'returned MB':>11s} "
        f"{'peak MB':>8s} {'peak/ret':>8s} {'wall s':>7s} {'CPU s':>7s}"
        "  load before/after  ok"
    )
    for label, signals, dt in cases:
        r = run_case(args.runs, dt, signals, args.engine)
        print(
            f"{label:22s} {dt:5.2f} {r['signal_bytes'] / 1e6:10.1f} "
            f"{r['data'] / 1e6:11.1f} {r['peak'] / 1e6:8.1f} "
            f"{r['peak'] / r['data']:8.3f} "
            f"{r['wall']:7.1f} {r['cpu']:7.1f}  {r['load0']:.2f} / {r['load1']:.2f}"
            f"  {r['ok']}/{args.runs}"
        )
    print(f"peak: {r['method']}, in a fresh process per case")
    print(machine_line())


if __name__ == "__main__":
    main()
