"""
Quick start: design a 4WS path-tracking controller and simulate it
==================================================================

The ten-line tour of the library: a vehicle and an operating point (the
plant), the linearised lateral dynamics as a :class:`control.StateSpace`,
gains that put both closed-loop poles on a chosen double root, a
Routh-Hurwitz check, and a simulation of the nonlinear closed loop on a
circular path.
"""

# %%
# A vehicle and its linearisation
# -------------------------------
# The paper's vehicle: wheelbase :math:`f = 2.7` m, centre of gravity
# :math:`d = 1.35` m ahead of the rear axle. On a circle of curvature
# :math:`\kappa = 0.1` 1/m (radius 10 m) at :math:`V = 5` m/s. A
# :class:`fws_control.LateralPlant` freezes this operating point; every
# analysis function takes it first (or any :class:`control.StateSpace` with
# the same signal names). Its linearisation about the feedforward steering
# angle has states ``e`` (lateral error) and ``theta`` (heading error) and
# inputs ``delta_f``, ``delta_r``.

from sys import modules

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws
from fws_control.paths import Arc

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)  # model="kinematic"
sys = fws.linearize(plant)
print(sys)

# %%
# Gains for a double root
# -----------------------
# With the rear angle tied to the front one, ``delta_r = ratio * delta_f``
# (here ``ratio = -1``: the rear wheels counter-steer), the closed loop is
# second order. :func:`fws_control.double_root_gains` solves for the gains
# ``k1, k2`` that place both poles at :math:`\lambda_0 = -1` 1/s.

g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
print(f"k1 = {g.k1:.4f} rad/m, k2 = {g.k2:.4f}, k3 = {g.k3:.4f}, k4 = {g.k4:.4f}")
print("K (python-control's sign, u = -K y):\n", g.K.round(4))

cl = fws.closed_loop(plant, g)
print("closed-loop poles:", np.real_if_close(np.round(cl.poles(), 6)))
print("stable:", fws.is_stable(plant, g))

# %%
# The paper's linearisation (eq. 33) treats the front-steering entry of
# :math:`\mathbf B` as :math:`V/f`; the true Jacobian has
# :math:`V(1+f^2\kappa^2)/f`. Gains designed with the paper's model miss the
# double root of the true linearisation:

paper_plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1, model="paper")
g_paper = fws.double_root_gains(paper_plant, ratio=-1.0, pole=-1.0)
poles = fws.closed_loop(plant, g_paper).poles()
print("paper's gains, true poles:", np.round(np.sort(poles.real), 3))

# %%
# Simulate the nonlinear closed loop
# ----------------------------------
# The vehicle starts 5 m outside the circle, at :math:`(x_R, y_R) = (0, -5)`
# m, heading along +x. :func:`fws_control.simulate` integrates the nonlinear
# kinematic model with curvature feedforward and the feedback gains.

res = fws.simulate(
    fws.LateralPlant(veh, speed=5.0),
    Arc(curvature=0.1),
    g,
    initial_state=(0.0, -5.0, 0.0),
    duration=15.0,
)
print(f"status: {res.status}, final lateral error {res.e[-1]:.1e} m")
print(f"peak lateral acceleration of G: {np.max(np.abs(res.lateral_accel)):.2f} m/s^2")

cplt = res.plot(labels=["a = -1, $\\lambda_0$ = -1"])
cplt.figure.suptitle("4WS path tracking on a 10 m circle at 5 m/s")

# %%
# Run as a script without a display (a non-interactive backend such as Agg),
# the figures go to files in the current directory instead of windows; the
# documentation build (sphinx-gallery) collects them by itself.

if "sphinx_gallery" not in modules and matplotlib.get_backend().lower() in (
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
        names.append(f"quick_start_{k}.png")
        plt.figure(num).savefig(names[-1], dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
