"""Speed of the closed-form stability chart against a per-point eigenvalue loop.

Times :func:`fws_control.stability_chart` on a 1000 x 1000 gain grid (10^6
points) and a plain Python loop that builds ``A + B K`` and calls
:func:`numpy.linalg.eigvals` at each point. The loop is timed on a random
subsample and extrapolated to 10^6 points; the two verdicts are compared on
that subsample. Prints the ratio (target >= 100).

Run: ``python benchmarks/bench_stability.py``
"""

from __future__ import annotations

import time

import numpy as np

import fws_control as fws

N = 1000
SUBSAMPLE = 20_000


def main() -> None:
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    speed, curvature, ratio = 5.0, 0.1, -1.0
    k1 = np.linspace(-1.0, 1.0, N)
    k2 = np.linspace(-1.0, 1.0, N)

    fws.stability_chart(veh, curvature, ratio, speed, k1, k2)  # warm-up
    reps = 20
    t0 = time.perf_counter()
    for _ in range(reps):
        chart = fws.stability_chart(veh, curvature, ratio, speed, k1, k2)
    t_chart = (time.perf_counter() - t0) / reps

    lin = fws.linearize(veh, speed, curvature)
    A, B = lin.A, lin.B
    rng = np.random.default_rng(0)
    idx = rng.integers(0, N, size=(SUBSAMPLE, 2))
    t0 = time.perf_counter()
    verdict = np.empty(SUBSAMPLE, dtype=bool)
    b = B @ np.array([1.0, ratio])
    # The plainest fair loop: one 2x2 closed-loop matrix and one eigvals call
    # per point (no SteeringGains validation overhead).
    for n, (i, j) in enumerate(idx):
        K = np.array([k1[j], k2[i]])
        verdict[n] = np.linalg.eigvals(A - np.outer(b, K)).real.max() < 0
    t_loop = (time.perf_counter() - t0) / SUBSAMPLE * N * N

    agree = np.mean(verdict == chart.stable[idx[:, 0], idx[:, 1]])
    print(f"stability_chart, {N}x{N} grid: {t_chart * 1e3:.2f} ms")
    print(
        f"per-point eigenvalue loop: {t_loop:.1f} s for 10^6 points "
        f"(extrapolated from {SUBSAMPLE} points)"
    )
    print(f"agreement on the subsample: {agree:.6f}")
    print(f"speed-up ratio: {t_loop / t_chart:.0f}x (target >= 100x)")


if __name__ == "__main__":
    main()
