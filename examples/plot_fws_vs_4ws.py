"""
Front-wheel versus four-wheel steering on a curve, at low and high speed
========================================================================

The paper's two scenarios (section 5), each with the double root
:math:`\\lambda_0 = -1` and curvature feedforward:

* **low speed** -- :math:`V = 5` m/s on a circle of curvature 0.1 1/m
  (radius 10 m), starting 5 m outside it;
* **high speed** -- :math:`V = 20` m/s on a circle of curvature 0.01 1/m
  (radius 100 m), starting 10 m outside it.

Front-wheel steering is ``a = 0``; ``a < 0`` steers the rear wheels against
the front ones, ``a > 0`` with them. The runs of each scenario are integrated
together by :func:`fws_control.simulate_batch`.
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws
from fws_control.paths import Arc
from fws_control.turning import turning_radius

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


def run(speed, curvature, e0, ratios):
    plant = fws.LateralPlant(veh, speed=speed, curvature=curvature)
    gains = fws.double_root_gains(plant, ratio=ratios, pole=-1.0)
    return fws.simulate_batch(
        fws.LateralPlant(veh, speed=speed),
        Arc(curvature=curvature),
        gains,
        initial_state=(0.0, e0, 0.0),
        duration=15.0,
        dt=0.02,
        progress=False,
    )


def report(batch):
    for r in batch:  # each run as a result of its own
        peak = np.max(np.abs(r.lateral_accel))
        g = r.gains
        print(
            f"a = {g.ratio:5.2f}: k1 = {g.k1:7.4f}, k2 = {g.k2:8.4f}, "
            f"peak |a_lat| = {peak:7.2f} m/s^2, status = {r.status}"
        )


# %%
# Low speed: 5 m/s on a 10 m circle
# ---------------------------------
# Counter-steering (``a < 0``) turns the vehicle onto the circle with a
# smaller front angle, but the lateral acceleration of the centre of
# gravity is higher than with front steering alone: the rear axle is pushed
# sideways as well.

low = run(5.0, 0.1, -5.0, np.array([0.0, -0.5, -1.0]))
report(low)
cplt = low.plot()
cplt.figure.suptitle("V = 5 m/s, $\\kappa$ = 0.1 1/m, $\\lambda_0$ = -1")

# %%
# High speed: 20 m/s on a 100 m circle
# ------------------------------------
# Steering the rear wheels with the front ones (``a = 0.5``) lowers the peak
# lateral acceleration. The design for ``a = 1`` is printed too: on this
# gentle curve ``a = 1`` is close to the uncontrollable case of a straight
# path (erratum 5), its gains are large and the front steering angle runs
# into the singularity :math:`|\\delta_f| = \\pi/2` -- the run stops there.

high = run(20.0, 0.01, -10.0, np.array([0.0, 0.5]))
report(high)
report(run(20.0, 0.01, -10.0, np.array([1.0])))
cplt = high.plot()
cplt.figure.suptitle("V = 20 m/s, $\\kappa$ = 0.01 1/m, $\\lambda_0$ = -1")

# %%
# Manoeuvrability at low speed
# ----------------------------
# What counter-steering buys at low speed is a tighter turn: with the front
# wheels at their limit, the steady turning radius of the rear-axle centre
# R shrinks as ``a`` goes negative.

ratios = np.linspace(-1.5, 0.5, 201)
fig, ax = plt.subplots(figsize=(7, 4.2), layout="constrained")
for i, limit_deg in enumerate((25.0, 35.0)):
    geo = turning_radius(veh, ratio=ratios, max_steer_front=np.radians(limit_deg))
    ax.plot(
        ratios, geo.rear_axle, color=f"C{i}", label=f"R, front limit {limit_deg:g}°"
    )
    ax.plot(ratios, geo.cg, "--", color=f"C{i}", label=f"G, front limit {limit_deg:g}°")
ax.set_xlabel("ratio a [-]")
ax.set_ylabel("steady turning radius [m]")
ax.set_ylim(0, 12)
ax.grid(True, alpha=0.3)
ax.legend()
r = turning_radius(veh, ratio=[0.0, -1.0], max_steer_front=np.radians(35.0)).rear_axle
print(f"turning radius of R at a 35° limit: a = 0: {r[0]:.2f} m, a = -1: {r[1]:.2f} m")

# %%
# Run as a script without a display (a non-interactive backend such as Agg),
# the figures go to files in the current directory instead of windows; the
# documentation build (sphinx-gallery) collects them by itself.

if "sphinx_gallery" not in sys.modules and matplotlib.get_backend().lower() in (
    "agg",
    "pdf",
    "ps",
    "svg",
    "pgf",
    "cairo",
    "template",
):
    names = []
    for k, num in enumerate(plt.get_fignums(), start=1):
        names.append(f"fws_vs_4ws_{k}.png")
        plt.figure(num).savefig(names[-1], dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
