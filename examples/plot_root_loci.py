"""
Gain and parameter root loci
============================

With the rear angle tied to the front one (``delta_r = a * delta_f``) the
linear plant has a single input, so scaling the feedback gains
:math:`(k_1, k_2) \\to g\\,(k_1, k_2)` is a classical SISO root locus of the
loop transfer function :func:`fws_control.gain_loop`, drawn with
python-control. :func:`fws_control.parameter_locus` follows the two
closed-loop poles while a parameter of the loop -- the ratio ``a``, the
speed, the curvature or one gain -- varies.
"""

import sys

import control as ct
import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
V, kappa = 5.0, 0.1
plant = fws.LateralPlant(veh, speed=V, curvature=kappa)
g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)

# %%
# Gain root locus
# ---------------
# The open loop has the poles :math:`\pm jV\kappa` of the uncontrolled
# motion around the circle (the vehicle oscillates about the path at the
# frequency :math:`V\kappa`) and one zero. At :math:`g = 1` both branches
# meet at the design's double root :math:`\lambda_0 = -1`.

loop = fws.gain_loop(plant, g)
print(loop)
rl = fws.gain_locus(plant, g, scale=np.linspace(0.0, 6.0, 601))
print("poles at g = 1:", np.round(ct.root_locus_map(loop, gains=[1.0]).loci[0], 6))

cplt = rl.plot(grid=False, xlim=(-4.0, 0.5), ylim=(-1.5, 1.5), title=False)
ax = cplt.axes[0, 0]
(star,) = ax.plot([-1.0], [0.0], "k*", ms=12, label="double root at g = 1")
(branch,) = ax.plot([], [], "C0", label="branches, g from 0 to 6")
ax.axvline(0.0, color="0.5", lw=0.8)
ax.grid(True, alpha=0.3)
ax.set_xlabel("Re $\\lambda$ [1/s]")
ax.set_ylabel("Im $\\lambda$ [1/s]")
ax.set_title("Root locus of the gain scale g (a = -1, V = 5 m/s, $\\kappa$ = 0.1 1/m)")
ax.legend(handles=[branch, star], loc="lower left")

# %%
# Parameter loci
# --------------
# Top left: the design's gains held fixed while ``a`` moves away from -1 (so
# the rear gains :math:`k_3 = a k_1`, :math:`k_4 = a k_2` change with it).
# Top right: the same gains at other speeds. Both coefficients of the
# characteristic polynomial scale with the speed (:math:`p_1 \propto V`,
# :math:`p_0 \propto V^2`), so the double root stays double and moves in
# proportion to :math:`V`: :math:`\lambda = \lambda_0 V / V_0`. Bottom
# left: the same gains on paths of other curvature from 0 to 0.3 1/m (only
# :math:`\kappa^2` enters, so the sign of the curvature does not matter).
# Bottom right: gains recomputed for every ``a`` with the paper's
# linearisation and evaluated in the exact one; the poles miss
# :math:`\lambda_0 = -1`, more so as ``a`` approaches 1 (erratum 3).

ratios = np.linspace(-1.5, 0.9, 241)
cases = [
    (
        "ratio a [-]",
        "gains fixed",
        fws.parameter_locus(plant, g, parameter="ratio", values=ratios),
    ),
    (
        "speed V [m/s]",
        "gains fixed",
        fws.parameter_locus(
            plant, g, parameter="speed", values=np.linspace(1.0, 20.0, 191)
        ),
    ),
    (
        "curvature [1/m]",
        "gains fixed",
        fws.parameter_locus(
            plant, g, parameter="curvature", values=np.linspace(0.0, 0.3, 241)
        ),
    ),
    (
        "ratio a [-]",
        "paper's design in the exact model",
        fws.parameter_locus(
            plant,
            g,
            parameter="ratio",
            values=ratios,
            redesign_pole=-1.0,
            design_model="paper",
        ),
    ),
]
fig, axes = plt.subplots(2, 2, figsize=(12, 9), layout="constrained")
for ax, (name, how, pz) in zip(axes.flat, cases, strict=True):
    for branch in range(2):
        sc = ax.scatter(
            pz.loci[:, branch].real,
            pz.loci[:, branch].imag,
            c=pz.gains,
            s=6,
            cmap="viridis",
        )
    ax.plot([-1.0], [0.0], "k*", ms=10, label="$\\lambda_0 = -1$")
    ax.axvline(0.0, color="0.5", lw=0.8)
    ax.set_ylim(-0.8, 0.8)
    ax.set_xlabel("Re $\\lambda$ [1/s]")
    ax.set_ylabel("Im $\\lambda$ [1/s]")
    ax.set_title(f"{name.split(' [')[0]} varies, {how}", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.colorbar(sc, ax=ax, label=name)

i = int(np.argmin(np.abs(ratios - 0.5)))
print(
    "paper's gains at a = 0.5 put the true poles at",
    np.real_if_close(np.round(cases[3][2].loci[i], 3)),
)

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
        names.append(f"root_loci_{k}.png")
        plt.figure(num).savefig(names[-1], dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
