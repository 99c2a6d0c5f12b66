"""
Feedback delay and a steering actuator
======================================

The paper's controller acts at once on an ideal steering. A real loop has
an input delay :math:`\\tau` on the steering command (perception and
computation) and a steering actuator that lags. With the delay the
characteristic function becomes the quasi-polynomial
:math:`D(s) = d(s) + e^{-s\\tau}\\,(k_1 n_1(s) + k_2 n_2(s))`, and
:func:`fws_control.stability_chart` with ``delay=`` decides every gain
point by counting its right-half-plane roots. Here: the stable gains on the
paper's 5 m/s curve for delays of 0, 0.24 and 0.5 s, and the delay margin
(:func:`fws_control.critical_delay`) of the paper's double-root designs,
with and without the first-order steering lag of 0.27 s. The values 0.24 s
and 0.27 s are the defaults of Autoware's MPC lateral controller
(:data:`fws_control.paper.data.ACTUATOR_SOURCE`).
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq

import fws_control as fws
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
speed, curvature, ratio = 5.0, 0.1, -1.0
delays = (0.0, REALISTIC_DELAY, 0.5)  # [s]
lag = REALISTIC_STEERING_LAG  # [s]

# %%
# The design and its delay margin
# -------------------------------
# The double-root design :math:`\lambda_0 = -1` of the paper's curved-road
# scenario at 5 m/s (curvature 1/10 m, ratio a = -1). Its critical delay is
# the smallest delay at which a pair of roots reaches :math:`\pm j\omega`.

plant = fws.LateralPlant(veh, speed=speed, curvature=curvature)
g = fws.double_root_gains(plant, ratio=ratio, pole=-1.0)
cd = fws.critical_delay(plant, g)
print(f"lambda0 = -1 design: k1 = {g.k1:.5f} rad/m, k2 = {g.k2:.5f}")
print(
    f"critical delay of the design: {cd.delay:.4f} s "
    f"(crossing at {cd.frequency:.4f} rad/s)"
)

# %%
# Delayed stability charts
# ------------------------
# The same gain grid for three delays. The delay eats into the stable set
# from the side of large gains: fast loops tolerate less delay. Points whose
# root count cannot be decided (a root within the frequency resolution of
# the imaginary axis, i.e. on a boundary) are counted as not stable.

k1 = np.linspace(-0.1, 0.8, 301)
k2 = np.linspace(-0.1, 1.5, 301)
charts = [
    fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2, delay=tau, pole=-1.0)
    for tau in delays
]
for tau, ch in zip(delays, charts, strict=True):
    print(
        f"delay {tau:.2f} s: stable fraction of the grid: {ch.stable_fraction:.4f} "
        f"({ch.undecided} undecided points)"
    )

fig1, axes = plt.subplots(
    1, 3, figsize=(15, 4.8), layout="constrained", sharex=True, sharey=True
)
for ax, tau, ch in zip(axes, delays, charts, strict=True):
    ch.plot(ax=ax, notes=False, title=f"input delay {tau:g} s")
    ax.grid(True, alpha=0.3)
fig1.suptitle(
    f"Stable gains with an input delay: a = {ratio:g}, V = {speed:g} m/s, "
    f"$\\kappa$ = {curvature:g} 1/m (star: the $\\lambda_0 = -1$ design, "
    f"critical delay {cd.delay:.3f} s)"
)

# %%
# Which double roots survive a real actuator
# ------------------------------------------
# On a straight road the delayed characteristic function of a double-root
# design is :math:`s^2 + e^{-s\tau}(-2\lambda_0 s + \lambda_0^2)`: the delay
# margin depends on :math:`\lambda_0` only (not on the speed, the ratio or
# the model), :math:`\tau_c|\lambda_0| = \arctan(2w)/w` with
# :math:`w^2 = 2 + \sqrt 5`. The lag is a plant with two more states
# (``LateralPlant(..., steering_lag=0.27)``); the gains stay those designed
# without it. Designs whose curve lies above the 0.24 s line survive.

straight = fws.LateralPlant(veh, speed=20.0)
lagged = fws.LateralPlant(veh, speed=20.0, steering_lag=lag)
poles = np.linspace(-4.0, -0.25, 76)
ideal = fws.delay_margin_chart(straight, ratio=0.0, pole=poles)
real = fws.delay_margin_chart(lagged, ratio=0.0, pole=poles, design_plant=straight)


def margin(pole, with_lag):
    """Critical delay [s] of the lambda0 = pole design, straight road."""
    on = lagged if with_lag else straight
    ch = fws.delay_margin_chart(on, ratio=0.0, pole=pole, design_plant=straight)
    return float(ch.delay[0, 0])


for lam in (-1.0, -2.0, -3.0):
    print(
        f"lambda0 = {lam:g}: critical delay {margin(lam, False):.4f} s, "
        f"with the {lag:g} s lag {margin(lam, True):.4f} s"
    )
# the largest |lambda0| whose margin still exceeds the realistic delay
largest = {
    with_lag: brentq(lambda m, w=with_lag: margin(-m, w) - REALISTIC_DELAY, 0.3, 4.0)
    for with_lag in (False, True)
}
print(
    f"largest |lambda0| surviving {REALISTIC_DELAY:g} s: "
    f"{largest[False]:.4f} 1/s without lag, {largest[True]:.4f} 1/s with the lag"
)

fig2, ax = plt.subplots(figsize=(7.5, 4.8), layout="constrained")
ax.plot(poles, ideal.delay[0], "-", color="C0", label="ideal steering")
ax.plot(poles, real.delay[0], "-", color="C3", label=f"{lag:g} s steering lag")
ax.fill_between(poles, 0.0, real.delay[0], color="C3", alpha=0.1)
ax.axhline(
    REALISTIC_DELAY, color="k", ls="--", lw=1.0, label=f"delay {REALISTIC_DELAY:g} s"
)
for lam in (-1.0, -2.0, -3.0):  # the double roots the paper uses
    ax.plot([lam], [margin(lam, True)], "o", color="C3", ms=5)
for with_lag, color in ((False, "C0"), (True, "C3")):
    edge = -largest[with_lag]
    label = rf"$\lambda_0$ = {edge:.2f} 1/s: margin {REALISTIC_DELAY:g} s"
    ax.axvline(edge, color=color, ls=":", lw=1.0, label=label)
ax.set_xlabel(r"double root $\lambda_0$ [1/s]")
ax.set_ylabel("critical delay [s]")
ax.set_ylim(0.0, 1.5)
ax.grid(True, alpha=0.3)
ax.legend(fontsize=9, loc="upper left")
ax.set_title(
    "Delay margin of the double-root designs on a straight road\n"
    "(every speed and ratio; stable below the curve; dots: the paper's "
    r"$\lambda_0$ with the lag)",
    fontsize=10,
)

# %%
# Run as a script without a display (a non-interactive backend such as Agg),
# the figures go to files instead of windows; the documentation build
# (sphinx-gallery) collects them by itself.

if "sphinx_gallery" not in sys.modules and matplotlib.get_backend().lower() in (
    "agg",
    "pdf",
    "ps",
    "svg",
    "pgf",
    "cairo",
    "template",
):
    fig1.savefig("delay_charts.png", dpi=110)
    fig2.savefig("delay_margins.png", dpi=110)
    print("saved delay_charts.png, delay_margins.png")
else:
    plt.show()
