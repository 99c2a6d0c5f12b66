"""Worst-case agreement of the closed-form design with python-control.

Samples the issue's domain (ratio in [-2, 2], |curvature| <= 0.3, speed in
[1, 40] m/s, pole in [-5, -0.1], both models), skipping designs within 1e-4
of the uncontrollable one (a = 1 on a straight path), and prints the worst
relative differences against control.acker, control.place (poles split by
1e-6) and the target polynomial (lambda - pole)^2.
Run: python benchmarks/accuracy_core.py
"""

import control as ct
import numpy as np

import fws_control as fws


def main(n: int = 5000, seed: int = 1) -> None:
    veh = fws.Vehicle(2.7, 1.35)
    rng = np.random.default_rng(seed)
    worst = {"acker": 0.0, "place": 0.0, "poly": 0.0}
    used = 0
    for _ in range(n):
        model = str(rng.choice(["kinematic", "paper"]))
        V, k = rng.uniform(1, 40), rng.uniform(-0.3, 0.3)
        a, lam = rng.uniform(-2, 2), rng.uniform(-5, -0.1)
        plant = fws.LateralPlant(veh, speed=V, curvature=k, model=model)
        c = plant.input_gain_factor
        if (a * veh.wheelbase * k) ** 2 + (c - a) ** 2 <= 1e-4:
            continue
        used += 1
        g = fws.double_root_gains(plant, ratio=a, pole=lam)
        lin = fws.linearize(plant)
        b = lin.B @ np.array([[1.0], [a]])
        got = np.array([g.k1, g.k2])
        for name, ref in (
            ("acker", ct.acker(lin.A, b, [lam, lam])),
            ("place", ct.place(lin.A, b, [lam * (1 + 1e-6), lam * (1 - 1e-6)])),
        ):
            ref = np.asarray(ref).ravel()
            worst[name] = max(
                worst[name], np.linalg.norm(got - ref) / np.linalg.norm(ref)
            )
        poly = fws.characteristic_polynomial_coefficients(plant, g)
        target = np.array([1.0, -2 * lam, lam**2])
        worst["poly"] = max(
            worst["poly"], np.abs(poly - target).max() / np.abs(target).max()
        )
    print(f"designs sampled: {used}")
    for name, val in worst.items():
        print(f"worst relative difference vs {name:5s}: {val:.2e}")


if __name__ == "__main__":
    main()
