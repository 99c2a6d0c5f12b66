"""
Batch sweep of the ratio a: peak lateral acceleration
=====================================================

For passenger comfort the paper rates each ratio ``a`` by the largest
lateral acceleration of the centre of gravity during the manoeuvre (its
Fig. 5). :func:`fws_control.simulate_batch` integrates all designs of a
sweep together on stacked numpy state, so a sweep over ``a`` is one call per
scenario.

Scenarios (the paper's): straight road with feedback only, starting 2 m to
the left; curved road with feedforward + feedback, starting 5 m (at 5 m/s,
curvature 0.1 1/m) or 10 m (at 20 m/s, curvature 0.01 1/m) outside the
circle. Every run uses the exact double-root gains for its ``a``.
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws
from fws_control.paths import Arc, Straight

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)

# a = 1 on a straight path is uncontrollable (erratum 5): the grid skips it.
ratios = np.linspace(-1.5, 1.5, 46)
assert not np.any(np.isclose(ratios, 1.0))

# (title, speed [m/s], curvature [1/m], initial lateral offset y_R(0) [m])
scenarios = [
    ("V = 5 m/s, straight, feedback", 5.0, 0.0, 2.0),
    ("V = 5 m/s, $\\kappa$ = 0.1 1/m, feedforward + feedback", 5.0, 0.1, -5.0),
    ("V = 20 m/s, straight, feedback", 20.0, 0.0, 2.0),
    ("V = 20 m/s, $\\kappa$ = 0.01 1/m, feedforward + feedback", 20.0, 0.01, -10.0),
]
poles = (-1.0, -2.0)

peaks = {}
for title, speed, kappa, e0 in scenarios:
    path = Straight() if kappa == 0.0 else Arc(curvature=kappa)
    for pole in poles:
        plant = fws.LateralPlant(veh, speed=speed, curvature=kappa)
        gains = fws.double_root_gains(plant, ratio=ratios, pole=pole)
        batch = fws.simulate_batch(
            fws.LateralPlant(veh, speed=speed),
            path,
            gains,
            initial_state=(0.0, e0, 0.0),
            duration=15.0,
            feedforward=kappa != 0.0,
            dt=0.02,
            progress=False,
        )
        # A run counts if it reached the final time with a physical front
        # steering angle, |delta_f| < pi/2, all along.
        steer = np.where(np.isnan(batch.delta_f), 0.0, np.abs(batch.delta_f))
        valid = batch.ok & np.all(steer < np.pi / 2, axis=1)
        acc = np.where(valid[:, None], np.abs(batch.lateral_accel), 0.0)
        peak = np.where(valid, acc.max(axis=1), np.nan)
        peaks[title, pole] = (peak, valid)
        print(
            f"{title.replace('$', ''):<52} lambda0 = {pole:g}: "
            f"{np.count_nonzero(valid)}/{len(batch)} runs valid"
        )

# %%
# Peak lateral acceleration against ``a`` (logarithmic axis). Runs whose
# front steering angle reaches :math:`\pm\pi/2`, where the kinematic model
# is singular, are left out and marked by crosses at the bottom: the vehicle
# has no steering limit here, as in the paper, and a large initial error
# times a large gain asks for an impossible angle. Close to that, the peaks
# grow without bound, because the yaw rate of eq. (10) has
# :math:`\cos\delta_f` in its denominator. The gains themselves blow up as
# ``a`` approaches 1 on the straight path and on the gentle curve, where the
# design degenerates (erratum 5).

fig, axes = plt.subplots(2, 2, figsize=(12, 8), layout="constrained", sharex=True)
for ax, (title, *_rest) in zip(axes.flat, scenarios, strict=True):
    for i, pole in enumerate(poles):
        peak, ok = peaks[title, pole]
        ax.semilogy(
            ratios, peak, "o-", ms=3, color=f"C{i}", label=f"$\\lambda_0$ = {pole:g}"
        )
        # Left-out runs: crosses just above the bottom axis.
        ax.plot(
            ratios[~ok],
            np.full(np.count_nonzero(~ok), 0.03 * (i + 1)),
            "x",
            color=f"C{i}",
            transform=ax.get_xaxis_transform(),
        )
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("ratio a [-]")
    ax.set_ylabel("peak |lateral acceleration of G| [m/s²]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)

# %%
# The best ratio (lowest peak) for each scenario and double root:

for title, *_rest in scenarios:
    for pole in poles:
        peak, ok = peaks[title, pole]
        j = int(np.nanargmin(peak))
        print(
            f"{title.replace('$', ''):<52} lambda0 = {pole:g}: lowest peak "
            f"{peak[j]:.2f} m/s^2 at a = {ratios[j]:.2f}"
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
        names.append(f"ratio_sweep_{k}.png")
        plt.figure(num).savefig(names[-1], dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
