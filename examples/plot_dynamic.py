"""
The kinematic design on the dynamic single-track model
======================================================

The paper designs on the kinematic model; at road speeds the tyres slip.
``LateralPlant(..., model="dynamic")`` linearises the dynamic single-track
model (states ``e, theta, v_y, r``) with the BMW 320i of CommonRoad's
vehicle models (:data:`fws_control.vehicles.BMW_320I`). Here: the stable
gains of the paper's controller on the kinematic plant and on the dynamic
plant at 10, 20 and 30 m/s, and where a kinematic double-root design stops
describing the dynamic closed loop (:func:`fws_control.kinematic_design_limit`).
See :doc:`/dynamic` for the numbers.
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Patch

import fws_control as fws

veh = fws.vehicles.BMW_320I
ratio = 0.0
k1 = np.linspace(-0.2, 0.6, 201)
k2 = np.linspace(-0.5, 1.5, 201)

# %%
# Stable gains
# ------------
# On a straight path the kinematic stable set does not depend on the speed;
# the dynamic one shrinks as the speed grows.

kin = fws.stability_chart(fws.LateralPlant(veh, speed=20.0), ratio=ratio, k1=k1, k2=k2)
print(f"kinematic: stable fraction {kin.stable_fraction:.4f}")
fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
kin.plot(ax=axes[0], color="0.6", label="kinematic", title="")
legend = [Patch(color="0.6", alpha=0.5, label="kinematic, any speed")]
for i, speed in enumerate((10.0, 20.0, 30.0)):
    plant = fws.LateralPlant(veh, speed=speed, model="dynamic")
    dyn = fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2)
    print(f"dynamic, V = {speed:g} m/s: stable fraction {dyn.stable_fraction:.4f}")
    dyn.plot(ax=axes[0], color=f"C{i}", label=f"dynamic, {speed:g} m/s", title="")
    legend.append(Patch(color=f"C{i}", alpha=0.5, label=f"dynamic, {speed:g} m/s"))
# each chart draws its own legend; one legend for all of them instead
axes[0].legend(handles=legend, fontsize=8, loc="upper right")
axes[0].set_title(f"stable gains, a = {ratio:g}, straight path", fontsize=10)

# %%
# Where the kinematic design holds
# --------------------------------
# The double root designed on the kinematic plant, applied to the dynamic
# plant: the drift of the two dominant poles against the speed.

lim = fws.kinematic_design_limit(veh, ratio=ratio, pole=-1.0)
print(f"drift > 25 % above {lim.drift_speed:.1f} m/s; unstable above "
      f"{lim.unstable_speed:.1f} m/s")  # fmt: skip
lim.plot(ax=axes[1])

# %%
# Run as a script without a display, the figure goes to a file.

if "sphinx_gallery" not in sys.modules and matplotlib.get_backend().lower() in (
    "agg",
    "pdf",
    "ps",
    "svg",
    "pgf",
    "cairo",
    "template",
):
    fig.savefig("dynamic_charts.png", dpi=110)
    print("saved dynamic_charts.png")
else:
    plt.show()
