"""Print the numbers of ``docs/speed_certificate.md`` and draw its figure.

The largest acceleration bound |dV/dt| that :func:`fws_control.speed_certificate`
certifies (bisection, relative width 2 %, cap 1000 m/s^2) for

* the paper's double-root schedule on 5-30 m/s, for the poles
  lambda0 = -0.5, -1, -2 1/s, with a = 0 (paper's vehicle, f = 2.7 m) and
  with the zero-sideslip ratio a(V) of the BMW 320i (the paper's vehicle
  has no tyre data), the gains tabulated at the certificate's nodes;
* the counterexample of the page (stiffness pumped by the speed, 10-20 m/s).

Run from the repository root (about a minute per row on one core)::

    python docs/scripts/speed_certificate_table.py [--figure PATH]

``--figure`` also draws the certified bound against lambda0 (PNG).
``tests/test_speed_certificate.py`` certifies the schedules at the printed
bounds of the page and simulates them there.
"""

from __future__ import annotations

import argparse

import numpy as np

import fws_control as fws

CELLS = 24
#: Cap of the bisection [m/s^2] (the default of speed_certificate).
MAX_RATE = 1e3
POLES = (-0.5, -1.0, -2.0)
PAPER = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
BMW = fws.vehicles.BMW_320I


def schedule_a0(pole: float) -> fws.GainSchedule:
    """k1 = lambda0^2 f / V^2, k2 = -2 lambda0 f / V: exact in the interpolation."""
    g = fws.double_root_gains(
        fws.LateralPlant(PAPER, speed=np.array([5.0, 30.0])), ratio=0.0, pole=pole
    )
    return fws.GainSchedule(speeds=[5.0, 30.0], k1=g.k1, k2=g.k2, ratio=[0.0, 0.0])


def gains_zero_sideslip(pole: float):
    """speed -> double-root gains with a = a(V) of the BMW 320i."""

    def gains(v):
        plant = fws.LateralPlant(BMW, speed=v)
        return fws.double_root_gains(plant, ratio=fws.zero_sideslip_ratio, pole=pole)

    return gains


def counterexample() -> fws.GainSchedule:
    """a = 0; omega^2 = k1 V^2/f alternates 1, 9 1/s^2 per m/s; damping 0.4 1/s."""
    v = np.arange(10.0, 20.5, 1.0)
    w2 = np.where(np.arange(v.size) % 2 == 0, 1.0, 9.0)
    return fws.GainSchedule(
        speeds=v, k1=w2 * 2.7 / v**2, k2=0.4 * 2.7 / v, ratio=np.zeros(v.size)
    )


def rows():
    out = []
    for pole in POLES:
        c0 = fws.speed_certificate(
            PAPER, schedule_a0(pole), cells=CELLS, max_rate=MAX_RATE
        )
        cz = fws.speed_certificate(
            BMW,
            gains_zero_sideslip(pole),
            speed_range=(5.0, 30.0),
            cells=CELLS,
            max_rate=MAX_RATE,
        )
        out.append((pole, c0, cz))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", help="PNG path of the figure")
    args = parser.parse_args()
    table = rows()
    print(f"cells = {CELLS}")
    print("| lambda0 [1/s] | a = 0: certified rho [m/s^2] | a = a(V): certified "
          "rho [m/s^2] |")  # fmt: skip
    for pole, c0, cz in table:

        def fmt(c):
            hi = c.rate_bracket[1]
            if hi == np.inf:
                return f"{c.max_rate:.4g} (cap)"
            return f"{c.max_rate:.4g} ({hi:.4g} refused)"

        print(f"| {pole:g} | {fmt(c0)} | {fmt(cz)} |")
    cx = fws.speed_certificate(PAPER, counterexample(), cells=20)
    print(f"counterexample: {cx.message}; frozen abscissa "
          f"{cx.frozen_abscissa:.4g} 1/s")  # fmt: skip
    if args.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(5.5, 3.5), layout="constrained")
        lam = np.array([-p for p, _, _ in table])
        for k, label, marker in ((1, "a = 0", "o"), (2, "a = a(V), BMW 320i", "s")):
            rho = np.array([row[k].max_rate for row in table])
            capped = np.array([row[k].rate_bracket[1] == np.inf for row in table])
            (line,) = ax.plot(lam, rho, marker=marker, label=label)
            # at the cap the bound is "at least": hollow markers
            ax.plot(lam[capped], rho[capped], marker, mfc="white",
                    color=line.get_color())  # fmt: skip
        ax.axhline(MAX_RATE, color="k", ls=":", lw=1.0,
                   label=f"search cap ({MAX_RATE:g} m/s$^2$)")  # fmt: skip
        ax.set_xlabel(r"$-\lambda_0$ [1/s]")
        ax.set_ylabel(r"certified $|dV/dt|$ [m/s$^2$]")
        ax.set_title("double-root schedule, 5-30 m/s (hollow: at the cap)")
        ax.set_ylim(0.0, 1.1 * MAX_RATE)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="lower right")
        fig.savefig(args.figure, dpi=110)
        print(f"figure: {args.figure}")


if __name__ == "__main__":
    main()
