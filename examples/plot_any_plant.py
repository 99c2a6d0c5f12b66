"""
Stability chart of any plant: steering actuators with a lag
===========================================================

The analysis functions take any :class:`control.StateSpace` whose inputs are
``delta_f``, ``delta_r`` and whose outputs are ``e``, ``theta`` -- of any
order. Here a first-order lag on each steering channel (time constants
0.1 s in front, 0.2 s at the rear) is put between the controller and the
kinematic plant with :func:`control.interconnect`, giving a 4-state plant.
With the paper's feedback :math:`\\delta_f = -k_1 e - k_2\\theta`,
:math:`\\delta_r = a\\,\\delta_f` the characteristic polynomial is still
affine in the gains, so :func:`fws_control.stability_chart` draws the
stable set by D-subdivision: the line :math:`p(0) = 0` and the curve on
which a pair of closed-loop poles sits at :math:`\\pm j\\omega`.
"""

import sys

import control as ct
import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
speed, curvature, ratio = 5.0, 0.1, -1.0
tau_f, tau_r = 0.1, 0.2  # actuator time constants [s]

# %%
# Two plants
# ----------
# The 2-state kinematic plant is a :class:`fws_control.LateralPlant`. For the
# 4-state plant, the kinematic block takes the *actual* steering angles
# ``df_act``, ``dr_act``; the lags turn the commands ``delta_f``,
# ``delta_r`` into them.

lateral = fws.LateralPlant(veh, speed=speed, curvature=curvature)
kin = fws.linearize(lateral)
kin = ct.ss(
    kin.A,
    kin.B,
    kin.C,
    kin.D,
    states=["e", "theta"],
    inputs=["df_act", "dr_act"],
    outputs=["e", "theta"],
    name="kin",
)
lag_f = ct.ss(
    ct.tf([1.0], [tau_f, 1.0]), inputs=["delta_f"], outputs=["df_act"], name="lag_f"
)
lag_r = ct.ss(
    ct.tf([1.0], [tau_r, 1.0]), inputs=["delta_r"], outputs=["dr_act"], name="lag_r"
)
lagged = ct.interconnect(
    [kin, lag_f, lag_r],
    inputs=["delta_f", "delta_r"],
    outputs=["e", "theta"],
    name="lagged",
)
print(f"4-state plant, states {lagged.state_labels}")

# %%
# The double-root design exists for the 2-state plant only (two gains cannot
# place four poles: :func:`fws_control.double_root_gains` refuses the lagged
# plant). The lags move its poles; the design stays stable here.

g = fws.double_root_gains(lateral, ratio=ratio, pole=-1.0)
print(f"2-state design for lambda0 = -1: k1 = {g.k1:.4f} rad/m, k2 = {g.k2:.4f}")
print("stable with the lags:", fws.is_stable(lagged, g))
poles = np.sort_complex(fws.closed_loop(lagged, g).poles())
print("closed-loop poles with the lags:", np.round(poles, 3))

# %%
# The two charts
# --------------
# Same gain grid, same ratio ``a = -1``. The lags shrink the stable set. The
# line :math:`p(0) = 0` (dashed) barely moves, but the straight
# :math:`p_1 = 0` line of the 2-state plant, on which a complex pair of
# poles crosses the imaginary axis, becomes a curve that asks for a larger
# heading gain :math:`k_2` at the same :math:`k_1`: the slower steering
# needs more damping. The star is the 2-state design.

k1 = np.linspace(-1.0, 1.0, 401)
k2 = np.linspace(-1.0, 1.0, 401)
chart2 = fws.stability_chart(lateral, ratio=ratio, k1=k1, k2=k2, pole=-1.0)
chart4 = fws.stability_chart(lagged, ratio=ratio, k1=k1, k2=k2)
print(f"stable fraction of the grid, 2 states: {chart2.stable_fraction:.4f}")
print(f"stable fraction of the grid, 4 states: {chart4.stable_fraction:.4f}")

fig, axes = plt.subplots(
    1, 2, figsize=(11, 4.8), layout="constrained", sharex=True, sharey=True
)
chart2.plot(ax=axes[0], title="kinematic plant (2 states)")
# draw() leaves the legend to the caller, which adds the 2-state design.
handles = chart4.draw(axes[1], color="C1")
(star,) = axes[1].plot(
    [g.k1], [g.k2], "k*", ms=11, label="2-state $\\lambda_0 = -1$ design"
)
axes[1].legend(handles=[*handles, star], fontsize=8, loc="lower left")
axes[1].set_title(
    f"with steering lags {tau_f:g} s / {tau_r:g} s (4 states)", fontsize=10
)
for ax in axes:  # the charts label the axes: k1 [rad/m], k2 [-]
    ax.grid(True, alpha=0.3)
fig.suptitle(
    f"Stable gains, a = {ratio:g}, V = {speed:g} m/s, $\\kappa$ = {curvature:g} 1/m"
)

# %%
# The boundary curve is where the closed loop has eigenvalues
# :math:`\pm j\omega`; one point of it, checked with python-control:

curve = fws.stability_boundaries(lagged, ratio=ratio).complex_root
i = int(np.argmin(np.abs(curve.omega - 2.0)))
on_curve = fws.SteeringGains(curve.k1[i], curve.k2[i], ratio=ratio)
rightmost = max(fws.closed_loop(lagged, on_curve).poles(), key=lambda p: p.real)
print(
    f"boundary at omega = {curve.omega[i]:.3f} rad/s: "
    f"k1 = {curve.k1[i]:.6f}, k2 = {curve.k2[i]:.6f}, "
    f"rightmost pole {rightmost.real:.1e} {rightmost.imag:+.3f}j"
)

# %%
# Run as a script without a display (a non-interactive backend such as Agg),
# the figure goes to a file instead of a window; the documentation build
# (sphinx-gallery) collects it by itself.

if "sphinx_gallery" not in sys.modules and matplotlib.get_backend().lower() in (
    "agg",
    "pdf",
    "ps",
    "svg",
    "pgf",
    "cairo",
    "template",
):
    fig.savefig("any_plant_charts.png", dpi=110)
    print("saved any_plant_charts.png")
else:
    plt.show()
