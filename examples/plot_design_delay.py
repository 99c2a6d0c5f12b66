"""
Designing for delay and actuator lag
====================================

At 20 m/s on a straight road with Autoware's 0.24 s input delay and 0.27 s
steering lag, :func:`fws_control.most_stable_gains` finds the gains of
fastest decay (smallest spectral abscissa) of the delayed, lagged loop.
Those gains are not the ones that tolerate the most delay:
:func:`fws_control.pareto_front` gives the trade-off, the largest decay
rate for each delay margin and for each steering effort :math:`|k_1|`.
Last, the ratios :math:`a` a rear steering limit of 5 degrees allows at
each front wheel angle (:func:`fws_control.rear_limit_band`).
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
plant = fws.LateralPlant(veh, speed=20.0, steering_lag=REALISTIC_STEERING_LAG)

# %%
# The most-stable gains, certified (Newton-polished roots, none missed by
# the argument principle), on the delayed stability chart with contours of
# the abscissa.
best = fws.most_stable_gains(plant, delay=REALISTIC_DELAY, ratio=0.0, grid=6)
print(
    f"most stable: k1 = {best.gains.k1!r} rad/m, k2 = {best.gains.k2!r}, "
    f"abscissa {best.abscissa:.4f} 1/s, critical delay {best.critical_delay:.3f} s, "
    f"certified {best.certified}"
)
fig1 = best.plot().figure

# %%
# The Pareto fronts start at the most-stable design: more delay margin, or
# a smaller step of the front command per metre of error, costs decay rate.
front = fws.pareto_front(plant, delay=REALISTIC_DELAY, points=3, design=best)
for m, d in zip(front.margin, front.margin_decay, strict=True):
    print(f"delay margin {m:.3f} s: decay rate {d:.4f} 1/s")
fig2 = front.plot().figure

# %%
# A production rear limit of 5 degrees: the band of ratios it allows.
band = fws.rear_limit_band(
    veh, front_angle=np.radians(np.linspace(1.0, 35.0, 200)), rear_limit=np.radians(5.0)
)
fig3 = band.plot().figure

if "sphinx_gallery" not in sys.modules and matplotlib.get_backend().lower() in (
    "agg",
    "pdf",
    "ps",
    "svg",
    "pgf",
    "cairo",
    "template",
):
    fig1.savefig("design_chart.png", dpi=110)
    fig2.savefig("design_pareto.png", dpi=110)
    fig3.savefig("design_rear_band.png", dpi=110)
    print("saved design_chart.png, design_pareto.png, design_rear_band.png")
else:
    plt.show()
