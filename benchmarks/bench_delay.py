"""Speed of a delayed stability chart against per-point rightmost roots.

A 500 x 500 gain grid of the kinematic plant (V = 5 m/s, kappa = 0.1 1/m,
a = -1) with a 0.24 s input delay: :func:`fws_control.stability_chart` with
``delay=`` counts the right-half-plane roots of the quasi-polynomial at every
point at once (argument principle). The reference decides each point from
its rightmost characteristic root (:func:`fws_control.rightmost_roots`,
spectral discretisation + Newton), timed on a random subsample and
extrapolated to the grid. Each time is the best of three runs, in CPU
seconds, the two timed in turn (``timing.best_of_interleaved``); the
machine load is printed before and after. Prints the ratio and the
agreement of the verdicts on the subsample (points whose rightmost root is
within 1e-3 1/s of the axis are left out).

Run: ``python benchmarks/bench_delay.py``
"""

from __future__ import annotations

import numpy as np
from timing import best_of_interleaved, machine_line

import fws_control as fws

N = 500
SUBSAMPLE = 400
DELAY = 0.24


def main() -> None:
    print(machine_line())
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    ratio = -1.0
    k1 = np.linspace(-0.5, 1.5, N)
    k2 = np.linspace(-0.5, 2.5, N)

    def chart():
        return fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2, delay=DELAY)

    rng = np.random.default_rng(0)
    idx = rng.integers(0, N, size=(SUBSAMPLE, 2))

    def per_point():
        out = np.empty(SUBSAMPLE)
        for n, (i, j) in enumerate(idx):
            g = fws.SteeringGains(k1[j], k2[i], ratio)
            out[n] = fws.rightmost_roots(plant, g, delay=DELAY, n=1)[0].real
        return out

    # in turn, round after round: the ratio does not take up the machine's drift
    best = best_of_interleaved({"chart": chart, "points": per_point})
    t_chart = best["chart"]
    t_points = best["points"] * N * N / SUBSAMPLE
    ch = chart()
    re = per_point()
    far = np.abs(re) > 1e-3
    agree = np.mean((re < 0)[far] == ch.stable[idx[:, 0], idx[:, 1]][far])
    print(f"delayed chart {N}x{N}, delay {DELAY} s:")
    print(f"  stability_chart(delay=...)   {t_chart:8.2f} s CPU")
    print(f"  rightmost root per point     {t_points:8.0f} s CPU (extrapolated)")
    print(f"  ratio: {t_points / t_chart:.0f}x")
    print(
        f"  verdicts agree on {far.sum()} subsample points: {agree:.6f}; "
        f"undecided chart points: {ch.undecided}"
    )
    print(machine_line())


if __name__ == "__main__":
    main()
