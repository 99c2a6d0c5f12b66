"""CPU time of a 200 x 200 robust region over a parameter box.

The paper's vehicle on a straight road, speed 10-30 m/s, input delay
0-0.24 s, steering lag 0.27 s, a = 0: :func:`fws_control.robust_region` on a
200 x 200 gain grid (the region, its adaptive parameter grid and its computed
boundary). Best of three runs in CPU seconds, with the machine load.

Run: ``python benchmarks/bench_robust.py``
"""

from __future__ import annotations

import numpy as np
from timing import best_of_interleaved, machine_line

import fws_control as fws

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
BOX = {"speed": (10.0, 30.0), "delay": (0.0, 0.24), "steering_lag": 0.27}


def main() -> None:
    print(machine_line())
    k1 = np.linspace(-0.001, 0.009, 200)
    k2 = np.linspace(-0.05, 0.45, 200)

    def region():
        return fws.robust_region(VEH, ratio=0.0, box=BOX, k1=k1, k2=k2)

    region()  # imports and first calls
    best = best_of_interleaved({"region": region})
    print(f"robust region 200x200 (10-30 m/s, 0-0.24 s, lag 0.27 s, a = 0): "
          f"{best['region']:.2f} s CPU (best of 3)")  # fmt: skip
    print(machine_line())


if __name__ == "__main__":
    main()
