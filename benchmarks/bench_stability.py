"""Speed of the stability chart against per-point eigenvalue computations.

For a 2-state plant (the kinematic :class:`fws_control.LateralPlant`) and a
4-state plant (the same with a first-order lag on each steering input, built
with :func:`control.interconnect`), times :func:`fws_control.stability_chart`
on a gain grid against two references that decide stability from the
closed-loop eigenvalues:

1. a plain Python loop that builds ``A - b k^T C`` and calls
   :func:`numpy.linalg.eigvals` at each point (timed on a random subsample,
   extrapolated to the grid);
2. one vectorised :func:`numpy.linalg.eigvals` call on the stacked matrices of
   the same subsample (the fastest eigenvalue route numpy offers),
   extrapolated likewise.

Each time is the best of three runs, in CPU seconds, the three computations
timed in turn round after round (``timing.best_of_interleaved``); the
machine load is printed before and after. Prints the ratios (targets:
>= 1000x against the loop for n = 2, >= 100x for n = 4) and the agreement
of the verdicts on the subsample, away from the boundary.

Run: ``python benchmarks/bench_stability.py``
"""

from __future__ import annotations

import control as ct
import numpy as np
from timing import best_of_interleaved, machine_line

import fws_control as fws

SUBSAMPLE = 20_000


def four_state_plant(speed: float, curvature: float) -> ct.StateSpace:
    """Kinematic plant behind first-order steering lags (0.1 s front, 0.2 s rear)."""
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    lin = fws.LateralPlant(veh, speed=speed, curvature=curvature).linearize()
    body = ct.ss(
        lin.A, lin.B, lin.C, lin.D,
        inputs=["df", "dr"], outputs=["e", "theta"], states=["e", "theta"],
        name="body",
    )  # fmt: skip
    lags = [
        ct.ss(-1 / tau, 1 / tau, 1, 0, inputs=u, outputs=y, states=y, name=y)
        for tau, u, y in ((0.1, "delta_f", "df"), (0.2, "delta_r", "dr"))
    ]
    return ct.interconnect(
        [*lags, body],
        inplist=["delta_f", "delta_r"],
        inputs=["delta_f", "delta_r"],
        outlist=["body.e", "body.theta"],
        outputs=["e", "theta"],
    )


def run(label: str, plant, ratio: float, n_grid: int, target: float) -> None:
    k1 = np.linspace(-1.0, 1.0, n_grid)
    k2 = np.linspace(-1.0, 2.0, n_grid)
    chart = fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2)

    lm = fws.loop_matrices(plant)
    A = np.asarray(lm.A, dtype=float)
    b = lm.input_vector(ratio)
    rng = np.random.default_rng(0)
    idx = rng.integers(0, n_grid, size=(SUBSAMPLE, 2))
    g1, g2 = k1[idx[:, 1]], k2[idx[:, 0]]

    def loop():
        out = np.empty(SUBSAMPLE)
        for n in range(SUBSAMPLE):
            kc = g1[n] * lm.c_e + g2[n] * lm.c_theta
            out[n] = np.linalg.eigvals(A - np.outer(b, kc)).real.max()
        return out

    def stacked():
        kc = g1[:, None] * lm.c_e + g2[:, None] * lm.c_theta
        M = A[None] - b[None, :, None] * kc[:, None, :]
        return np.linalg.eigvals(M).real.max(axis=1)

    scale = n_grid * n_grid / SUBSAMPLE
    # in turn, round after round: the ratios do not take up the machine's drift
    best = best_of_interleaved(
        {
            "chart": lambda: fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2),
            "loop": loop,
            "stacked": stacked,
        }
    )
    t_chart = best["chart"]
    t_loop = best["loop"] * scale
    t_stacked = best["stacked"] * scale
    re = stacked()
    far = np.abs(re) > 1e-6
    agree = np.mean((re < 0)[far] == chart.stable[idx[:, 0], idx[:, 1]][far])
    print(f"{label}, {n_grid}x{n_grid} grid:")
    print(f"  stability_chart            {t_chart * 1e3:9.2f} ms CPU")
    print(f"  per-point eigvals loop     {t_loop * 1e3:9.0f} ms CPU (extrapolated)")
    print(f"  stacked numpy eigvals      {t_stacked * 1e3:9.0f} ms CPU (extrapolated)")
    print(
        f"  ratio vs loop: {t_loop / t_chart:.0f}x (target >= {target:g}x); "
        f"vs stacked eigvals: {t_stacked / t_chart:.0f}x"
    )
    print(f"  verdicts agree on {far.sum()} subsample points: {agree:.6f}")


def main() -> None:
    print(machine_line())
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    run(
        "n = 2 (LateralPlant, V = 5 m/s, kappa = 0.1 1/m, a = -1)",
        fws.LateralPlant(veh, speed=5.0, curvature=0.1),
        -1.0,
        1000,
        1000,
    )
    run(
        "n = 4 (with steering lags, V = 5 m/s, kappa = 0.1 1/m, a = -0.5)",
        four_state_plant(5.0, 0.1),
        -0.5,
        1000,
        100,
    )
    print(machine_line())


if __name__ == "__main__":
    main()
