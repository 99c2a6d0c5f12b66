"""Numbers of docs/robust.md: the robust region over 10-30 m/s and its checks.

The paper's vehicle on a straight road, speed 10-30 m/s, input delay
0-0.24 s, steering lag 0.27 s, ratios a = 0 and a = 0.5, 200 x 200 grid.
For each ratio: the stable fraction, the boundary pieces with their
parameter points, and 10^4 random (gain in the region, parameter point of
the box) pairs judged by the rightmost root (fws.rightmost_roots); then the
robust design (fws.robust_gains) for a = 0.

Run: ``python docs/scripts/robust_region.py``
"""

from __future__ import annotations

import numpy as np

import fws_control as fws

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
BOX = {"speed": (10.0, 30.0), "delay": (0.0, 0.24), "steering_lag": 0.27,
       "curvature": 0.0}  # fmt: skip
WINDOWS = {0.0: ((-0.001, 0.009), (-0.05, 0.45)), 0.5: ((-0.002, 0.02), (-0.05, 0.95))}
RANDOM = 10_000


def main() -> None:
    rng = np.random.default_rng(2026)
    for a, ((x0, x1), (y0, y1)) in WINDOWS.items():
        reg = fws.robust_region(VEH, ratio=a, box=BOX, k1=np.linspace(x0, x1, 200),
                                k2=np.linspace(y0, y1, 200))  # fmt: skip
        iy, ix = np.nonzero(reg.stable)
        print(f"a = {a}: stable fraction {reg.stable_fraction:.4f}, "
              f"k1 <= {reg.k1[ix].max():.5f} rad/m, k2 in "
              f"[{reg.k2[iy].min():.4f}, {reg.k2[iy].max():.4f}], "
              f"{reg.evaluations} parameter points")  # fmt: skip
        for p in reg.boundary:
            par = {k: sorted({round(float(v), 4) for v in vals})
                   for k, vals in p.parameters.items()}  # fmt: skip
            print(f"  boundary {p.kind}: {p.k1.size} points, parameters {par}")
        pick = rng.integers(0, ix.size, RANDOM)
        V = rng.uniform(10.0, 30.0, RANDOM)
        tau = rng.uniform(0.0, 0.24, RANDOM)
        worst, unstable = -np.inf, 0
        for i, v, t in zip(pick, V, tau, strict=True):
            plant = fws.LateralPlant(VEH, speed=v, steering_lag=0.27)
            g = fws.SteeringGains(reg.k1[ix[i]], reg.k2[iy[i]], a)
            re = fws.rightmost_roots(plant, g, delay=t, n=1, nodes=10)[0].real
            worst = max(worst, re)
            unstable += re >= 0.0
        print(f"  {RANDOM} random points: {unstable} unstable, largest real part "
              f"of a rightmost root {worst:.3e} 1/s")  # fmt: skip
    des = fws.robust_gains(VEH, ratio=0.0, box=BOX, k1=np.linspace(-0.001, 0.009, 40),
                           k2=np.linspace(-0.05, 0.45, 40))  # fmt: skip
    print(f"design a = 0: k1 = {des.gains.k1:.5f} rad/m, k2 = {des.gains.k2:.4f}, "
          f"worst-case abscissa {des.abscissa:.4f} 1/s at {des.worst}")  # fmt: skip


if __name__ == "__main__":
    main()
