"""Most-stable gains under delay, and the rightmost roots they rest on.

Prints, each time the best of three runs in CPU seconds with the machine
load before and after:

1. :func:`fws_control.rightmost_roots` (default options) on a lagged plant
   (V = 5 m/s, kappa = 0.1 1/m, steering lag 0.27 s, a = 0, k1 = 0.005,
   k2 = 0.1, delay 0.24 s);
2. :func:`fws_control.most_stable_gains` on a 3-state plant: the kinematic
   plant at 20 m/s with a 0.27 s lag on the front steering only, a
   user's ``control.StateSpace``, delay 0.24 s, a = 0;
3. the numbers of ``docs/design_delay.md``: the 20 m/s straight-road case
   with Autoware's delay and lag (4 states), the double-root design
   lambda0 = -1, the best of the double-root family and the most-stable
   gains (fixed a = 0 and a free in [-0.5, 0.5]);
4. :func:`fws_control.pareto_front` of the 20 m/s case (5 points per front,
   from the most-stable design), its CPU time and the front;
5. :func:`fws_control.schedule_gains` of the lagged plant over 10-30 m/s.

Run: ``python benchmarks/bench_design_delay.py``
"""

from __future__ import annotations

import control as ct
import numpy as np
from timing import best_of, machine_line

import fws_control as fws
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


def front_lag_plant(speed: float, lag: float) -> ct.StateSpace:
    """States e, theta and the front wheel angle; the rear steers directly."""
    f = VEH.wheelbase
    A = np.array([[0.0, speed, 0.0], [0.0, 0.0, speed / f], [0.0, 0.0, -1.0 / lag]])
    B = np.array([[0.0, speed], [0.0, -speed / f], [1.0 / lag, 0.0]])
    C = np.eye(3)[:2]
    return ct.ss(
        A, B, C, np.zeros((2, 2)), states=["e", "theta", "delta_f_act"],
        inputs=["delta_f", "delta_r"], outputs=["e", "theta"],
    )  # fmt: skip


def main() -> None:
    print(machine_line())
    tau, lag = REALISTIC_DELAY, REALISTIC_STEERING_LAG

    lagged = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, steering_lag=lag)
    g = fws.SteeringGains(0.005, 0.1, 0.0)
    t = best_of(lambda: fws.rightmost_roots(lagged, g, delay=tau))
    r = fws.rightmost_roots(lagged, g, delay=tau)
    print(f"rightmost_roots, lagged plant, n=6: {t:.3f} s CPU; rightmost {r[0]:.6f}")

    three = front_lag_plant(20.0, lag)
    t = best_of(lambda: fws.most_stable_gains(three, delay=tau, ratio=0.0))
    best3 = fws.most_stable_gains(three, delay=tau, ratio=0.0)
    print(
        f"most_stable_gains, 3 states: {t:.2f} s CPU ({best3.evaluations} "
        f"root evaluations); abscissa {best3.abscissa:.4f} 1/s at "
        f"k1 = {best3.gains.k1:.6f}, k2 = {best3.gains.k2:.4f}"
    )

    plant = fws.LateralPlant(VEH, speed=20.0, steering_lag=lag)
    design_plant = fws.LateralPlant(VEH, speed=20.0)
    g1 = fws.double_root_gains(design_plant, ratio=0.0, pole=-1.0)
    r1 = fws.rightmost_roots(plant, g1, delay=tau, n=1)[0]
    c1 = fws.critical_delay(plant, g1).delay
    print(f"20 m/s, delay {tau} s, lag {lag} s, a = 0:")
    print(
        f"  double root lambda0 = -1 (k1 = {g1.k1:.5f}, k2 = {g1.k2:.3f}): "
        f"rightmost {r1.real:.3f} +- {abs(r1.imag):.3f}j, critical delay {c1:.3f} s"
    )
    poles = np.linspace(-1.5, -0.5, 201)
    fam = [
        fws.rightmost_roots(
            plant, fws.double_root_gains(design_plant, ratio=0.0, pole=p),
            delay=tau, n=1,
        )[0].real
        for p in poles
    ]  # fmt: skip
    i = int(np.argmin(fam))
    print(f"  best of the double-root family: {fam[i]:.3f} at lambda0 = {poles[i]:.3f}")
    for label, kw in (
        ("a = 0", {}),
        ("a in [-0.5, 0.5]", {"ratio_bounds": (-0.5, 0.5)}),
    ):
        best = fws.most_stable_gains(plant, delay=tau, ratio=0.0, **kw)
        print(
            f"  most stable, {label}: abscissa {best.abscissa:.4f} 1/s at "
            f"k1 = {best.gains.k1:.6f}, k2 = {best.gains.k2:.4f}, "
            f"a = {best.gains.ratio:.4f}; critical delay {best.critical_delay:.3f} s; "
            f"{best.roots.size} roots within 0.5 1/s; certified {best.certified}"
        )
    best = fws.most_stable_gains(plant, delay=tau, ratio=0.0)
    t = best_of(lambda: fws.pareto_front(plant, delay=tau, points=5, design=best))
    front = fws.pareto_front(plant, delay=tau, points=5, design=best)
    print(
        f"pareto_front, 4 states, 5 points per front: {t:.2f} s CPU "
        f"({front.evaluations} root evaluations, {front.dropped} dominated dropped)"
    )
    for m, dec, k1, k2 in zip(
        front.margin, front.margin_decay, front.margin_gains.k1,
        front.margin_gains.k2, strict=True,
    ):  # fmt: skip
        print(
            f"  margin {m:.3f} s: decay {dec:.4f} 1/s at k1 = {k1:.6f}, k2 = {k2:.4f}"
        )
    for eff, dec, k2 in zip(
        front.effort, front.effort_decay, front.effort_gains.k2, strict=True
    ):
        print(f"  effort |k1| = {eff:.6f} rad/m: decay {dec:.4f} 1/s at k2 = {k2:.4f}")
    sch = fws.schedule_gains(
        VEH, speeds=[10.0, 15.0, 20.0, 25.0, 30.0], delay=tau, steering_lag=lag
    )
    print("schedule_gains, lag 0.27 s, delay 0.24 s, a = 0:")
    for v, k1, k2, al, cd in zip(
        sch.speeds, sch.k1, sch.k2, sch.abscissa, sch.critical_delay, strict=True
    ):
        print(
            f"  V = {v:4.1f} m/s: k1 = {k1:.6f} (k1 V^2 = {k1 * v * v:.4f}), "
            f"k2 = {k2:.4f} (k2 V = {k2 * v:.4f}), abscissa {al:.4f} 1/s, "
            f"critical delay {cd:.3f} s"
        )
    print(machine_line())


if __name__ == "__main__":
    main()
