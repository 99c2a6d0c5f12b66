"""Time per call of :func:`fws_control.rightmost_roots`, best of several.

Two loops of the test suite's delayed charts: the 2-state kinematic plant
(V = 5 m/s, kappa = 0.1 1/m, a = -1, delay 0.3 s) and the 4-state plant with
the steering lag 0.27 s (a = 0, delay 0.24 s). Each is timed on 200 gain
points drawn (fixed seed) from the charts' gain ranges, with the charts'
call (``n=1, nodes=6``) and the default call (``n=6``); printed is the best of
five runs in CPU milliseconds per call (one BLAS thread, as in the tests),
with the machine load before and after.

Run: ``python benchmarks/bench_rightmost.py``
"""

from __future__ import annotations

import os

# one BLAS thread, as in the test suite (tests/conftest.py): on small
# matrices more threads only busy-wait
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from timing import best_of, machine_line  # noqa: E402

import fws_control as fws  # noqa: E402

POINTS = 200


def cases():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    rng = np.random.default_rng(0)
    two = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    lagged = fws.LateralPlant(veh, speed=5.0, curvature=0.1, steering_lag=0.27)
    g2 = [
        fws.SteeringGains(k1, k2, -1.0)
        for k1, k2 in zip(
            rng.uniform(-0.05, 0.4, POINTS), rng.uniform(0.0, 1.8, POINTS), strict=True
        )
    ]
    g4 = [
        fws.SteeringGains(k1, k2, 0.0)
        for k1, k2 in zip(
            rng.uniform(-0.05, 0.35, POINTS),
            rng.uniform(-0.2, 1.5, POINTS),
            strict=True,
        )
    ]
    return {"2-state": (two, g2, 0.3), "lagged": (lagged, g4, 0.24)}


def main() -> None:
    print(machine_line())
    for name, (plant, gains, tau) in cases().items():
        for label, kw in (("n=1, nodes=6", {"n": 1, "nodes": 6}), ("n=6", {})):

            def run(plant=plant, gains=gains, tau=tau, kw=kw):
                for g in gains:
                    fws.rightmost_roots(plant, g, delay=tau, **kw)

            t = best_of(run, repeat=5) / len(gains)
            print(f"  {name:8s} {label:13s} {1e3 * t:7.2f} ms per call")
    print(machine_line())


if __name__ == "__main__":
    main()
