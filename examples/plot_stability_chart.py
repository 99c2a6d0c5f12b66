"""
Exploring the stability chart as the ratio a and the curvature change
=====================================================================

The closed loop is second order, :math:`\\lambda^2 + p_1\\lambda + p_0`, with
both coefficients affine in the gains :math:`(k_1, k_2)`. Routh-Hurwitz
(paper eqs. 35-36) makes the stable set the intersection of two half planes,
bounded by two straight lines. :func:`fws_control.stability_chart` evaluates
both conditions on a whole gain grid at once and also carries the lines and
the double-root design point.
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Patch

import fws_control as fws

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
k1 = np.linspace(-1.0, 1.0, 301)
k2 = np.linspace(-1.0, 1.0, 301)

# %%
# One chart
# ---------
# Counter-steering rear wheels (``a = -1``) on a 10 m circle at 5 m/s. The
# solid line is :math:`p_1 = 0` (eq. 35), the dashed one :math:`p_0 = 0`
# (eq. 36); the marker is the design with the double root
# :math:`\lambda_0 = -1`.

plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
chart = fws.stability_chart(plant, ratio=-1.0, k1=k1, k2=k2, pole=-1.0)
print(f"stable fraction of the grid: {chart.stable_fraction:.3f}")
print(f"design: k1 = {chart.design.k1:.4f}, k2 = {chart.design.k2:.4f}")
chart.plot()

# %%
# How the ratio a and the curvature move the boundaries
# -----------------------------------------------------
# One panel per ratio ``a``; in each, the stable regions for four curvatures
# are overlaid. The :math:`p_1` line (solid, eq. 35),
# :math:`f a k_1 + (c-a) k_2 = 0`, passes through the origin; its slope is
# set by ``a``: rising for ``a < 0`` (stable above it), flat
# (:math:`k_2 = 0`) for front steering, falling for :math:`0 < a < c`
# (:math:`c = 1 + f^2\kappa^2`), and rising again for :math:`a > c`, with
# the stable side now below it. The :math:`p_0` line (dashed, eq. 36) is
# :math:`k_1 = 0` on a straight path; the curvature term
# :math:`V^2\kappa^2` of :math:`p_0` moves it to negative :math:`k_1` and
# tilts it, so on a curve a small negative lateral-error gain can still be
# stable.

ratios = (-1.5, -1.0, -0.5, 0.0, 0.5, 1.5)
curvatures = (0.0, 0.05, 0.1, 0.2)
fig, axes = plt.subplots(
    2, 3, figsize=(13, 8.5), layout="constrained", sharex=True, sharey=True
)
for ax, a in zip(axes.flat, ratios, strict=True):
    for i, kappa in enumerate(curvatures):
        plant = fws.LateralPlant(veh, speed=5.0, curvature=kappa)
        ch = fws.stability_chart(plant, ratio=a, k1=k1, k2=k2, pole=-1.0)
        ch.plot(
            ax=ax,
            color=f"C{i}",
            label=f"$\\kappa$ = {kappa:g} 1/m",
            outline=True,  # light fill, coloured outline: overlaps stay readable
            alpha=0.12,
            legend=False,
            title=f"a = {a:g}, V = 5 m/s",
        )
# Filled regions make no legend entries of their own: proxies stand in.
axes[0, 0].legend(
    handles=[
        Patch(
            facecolor=f"C{i}",
            alpha=0.4,
            edgecolor=f"C{i}",
            label=f"$\\kappa$ = {kappa:g} 1/m",
        )
        for i, kappa in enumerate(curvatures)
    ],
    fontsize=8,
    loc="lower left",
)
fig.suptitle("Stable gains (shaded) and the $\\lambda_0 = -1$ designs (markers)")

# %%
# The same information as numbers: the fraction of the
# :math:`[-1, 1]^2` gain square that is stable, for each ``a`` and
# :math:`\kappa`. The chart is closed form, so a fine sweep over ``a`` is
# cheap.

a_sweep = np.linspace(-2.0, 2.0, 161)
fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for i, kappa in enumerate(curvatures):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=kappa)
    frac = [
        fws.stability_chart(plant, ratio=a, k1=k1[::3], k2=k2[::3]).stable_fraction
        for a in a_sweep
    ]
    ax.plot(a_sweep, frac, color=f"C{i}", label=f"$\\kappa$ = {kappa:g} 1/m")
ax.set_xlabel("ratio a = $\\delta_r / \\delta_f$ [-]")
ax.set_ylabel("stable fraction of $[-1, 1]^2$ [-]")
ax.set_title("Size of the stable gain set, V = 5 m/s")
ax.grid(True, alpha=0.3)
ax.legend()

# %%
# Paper model versus exact linearisation
# --------------------------------------
# The paper's eq. (33) writes :math:`(1-a)` where the true Jacobian has
# :math:`(c-a)` with :math:`c = 1 + f^2\kappa^2` (see :doc:`/errata`). The
# lines differ on a sharp curve; on a straight path they coincide. The
# markers are the two models' :math:`\lambda_0 = -1` designs.

fig, ax = plt.subplots(figsize=(6, 5), layout="constrained")
k2_wide = np.linspace(-1.0, 2.0, 451)
for color, model in (("C0", "kinematic"), ("C3", "paper")):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.2, model=model)
    ch = fws.stability_chart(plant, ratio=0.5, k1=k1, k2=k2_wide, pole=-1.0)
    ch.plot(
        ax=ax,
        color=color,
        label=f"{model} model",
        legend=False,
        notes=False,
        title="a = 0.5, $\\kappa$ = 0.2 1/m, V = 5 m/s",
    )
    print(f"{model:>5}: design k1 = {ch.design.k1:.3f}, k2 = {ch.design.k2:.3f}")
ax.legend(
    handles=[
        Patch(facecolor=c, alpha=0.4, label=f"{m} model")
        for c, m in (("C0", "kinematic"), ("C3", "paper"))
    ],
    fontsize=8,
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
        names.append(f"stability_chart_{k}.png")
        plt.figure(num).savefig(names[-1], dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
