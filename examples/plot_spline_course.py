"""
Tracking a spline course
========================

The controller needs the path's curvature at the projection point only, so
it tracks any smooth path. Here a closed course is a C² cubic spline through
a handful of waypoints (:class:`fws_control.paths.Spline`, parameterised by
arc length). The gains are designed once, for a straight path; the
curvature feedforward :math:`\\delta_f^{FF} = \\arctan(\\kappa(s) f)` handles
the bends. Without it, the feedback alone leaves a lateral error wherever the
path curves.
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws
from fws_control.paths import Spline

veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)

waypoints = 2.0 * np.array(
    [
        [0, 0],
        [30, 0],
        [55, 8],
        [70, 30],
        [60, 55],
        [35, 60],
        [20, 45],
        [5, 50],
        [-15, 40],
        [-20, 15],
        [0, 0],
    ],
    dtype=float,
)
course = Spline(waypoints)  # first == last waypoint: a closed course
s = np.linspace(0.0, course.length, 1000, endpoint=False)
kappa = course.curvature(s)
print(f"closed: {course.closed}, length {course.length:.1f} m")
print(f"curvature from {kappa.min():.3f} to {kappa.max():.3f} 1/m")

# %%
# One lap at 6 m/s with four-wheel steering, ``a = -0.5``, the vehicle
# starting 3 m to the right of the course and 0.2 rad off its heading. Gains
# for the double root :math:`\lambda_0 = -1` on a straight path.

speed, ratio = 6.0, -0.5
g = fws.double_root_gains(veh, speed=speed, curvature=0.0, ratio=ratio, pole=-1.0)
runs = {
    "feedforward + feedback": True,
    "feedback only": False,
}
results = {}
for label, ff in runs.items():
    results[label] = fws.simulate(
        fws.LateralPlant(veh, speed=speed),
        course,
        g,
        initial_state=(0.0, -3.0, 0.2),
        duration=course.length / speed,
        feedforward=ff,
        dt=0.05,
    )
    r = results[label]
    late = r.t > 10.0  # after the initial error has decayed
    print(
        f"{label:>22}: status {r.status}, max |e| after 10 s = "
        f"{np.max(np.abs(r.e[late])):.1e} m, peak |a_lat| = "
        f"{np.max(np.abs(r.lateral_accel)):.2f} m/s^2"
    )

# %%
# The course and the two runs (left), the lateral error along the course
# (top right) and the course's curvature (bottom right): the feedback-only
# error follows the curvature.

fig = plt.figure(figsize=(13, 6), layout="constrained")
ax_xy, ax_e, ax_k = fig.subplot_mosaic([["xy", "e"], ["xy", "k"]]).values()
px, py = course.position(s)
ax_xy.plot(px, py, "k--", lw=1, label="course")
ax_xy.plot(*waypoints.T, "ko", ms=4, label="waypoints")
for i, (label, r) in enumerate(results.items()):
    ax_xy.plot(r.x, r.y, color=f"C{i}", label=label)
    ax_e.plot(r.s, r.e, color=f"C{i}", label=label)
ax_xy.set_aspect("equal")
ax_xy.set_xlabel("x [m]")
ax_xy.set_ylabel("y [m]")
ax_xy.set_title(f"one lap, V = {speed:g} m/s, a = {ratio:g}")
ax_xy.legend(fontsize=8)
ax_e.set_ylabel("lateral error e [m]")
ax_e.set_xlabel("arc length s [m]")
ax_e.set_ylim(-3.5, 3.5)
ax_e.legend(fontsize=8)
ax_k.plot(s, kappa, "k")
ax_k.set_ylabel("curvature $\\kappa$ [1/m]")
ax_k.set_xlabel("arc length s [m]")
for ax in (ax_xy, ax_e, ax_k):
    ax.grid(True, alpha=0.3)

# %%
# The full response of the run with feedforward (errors, trajectory,
# steering angles and lateral acceleration over time):

cplt = results["feedforward + feedback"].plot(labels="feedforward + feedback")

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
        names.append(f"spline_course_{k}.png")
        plt.figure(num).savefig(names[-1], dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
