"""
Open-loop tests of the vehicle model (ISO 7401, ISO 4138)
=========================================================

Before a closed-loop comparison is trusted, the vehicle model is driven
open loop: a step steer (ISO 7401), the steering frequency response, and
steady-state driving on a circle of constant radius (ISO 4138). The model
is the dynamic single-track model of :mod:`fws_control.dynamics` with the
BMW 320i of CommonRoad (:data:`fws_control.vehicles.BMW_320I`) at 20 m/s,
front-steered and with four-wheel steering at the zero-sideslip ratio
:func:`fws_control.zero_sideslip_ratio`. See :doc:`/openloop` for the
numbers.
"""

import math
import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws

veh = fws.vehicles.BMW_320I
speed = 20.0
schedules = {"front": 0.0, "4WS a(V)": fws.zero_sideslip_ratio}

# %%
# Step steer
# ----------
# A ramp of 0.02 rad, 10 % to 90 % in 0.15 s, then held; linear model and
# the nonlinear model with the saturating tyre.

fig1, axes1 = plt.subplots(2, 2, figsize=(11, 6), sharex=True, layout="constrained")
for j, (label, ratio) in enumerate(schedules.items()):
    for model, tyre in (("linear", "linear"), ("nonlinear", "magic")):
        res = fws.step_steer(
            veh, speed=speed, amplitude=0.02, ratio=ratio, model=model, tyre=tyre
        )
        res.plot(ax=axes1[:, j])
        m = res.yaw_rate_metrics
        print(
            f"{label}, {model}: yaw rate {m.steady_state:.4f} rad/s, "
            f"response time {m.response_time:.3f} s, rise time {m.rise_time:.3f} s"
        )
    axes1[0, j].set_title(f"{label}, a = {res.ratio:.3f}", fontsize=10)

# %%
# Frequency response
# ------------------
# The linear model, stepped sines of the nonlinear model at 1e-4 rad (on
# top of the linear curve) and at 0.06 rad with the saturating tyre.

omega = 2 * math.pi * np.geomspace(0.1, 5.0, 25)
fig2, axes2 = plt.subplots(2, 1, figsize=(7, 6), sharex=True, layout="constrained")
lin = fws.steering_frequency_response(veh, speed=speed, omega=omega)
small = fws.steering_frequency_response(
    veh, speed=speed, omega=omega, model="nonlinear", amplitude=1e-4
)
big = fws.steering_frequency_response(
    veh, speed=speed, omega=omega, model="nonlinear", tyre="magic", amplitude=0.06
)
for fr in (lin, small, big):
    fr.plot(ax=axes2)
gap = np.max(np.abs(small.yaw_rate_gain / lin.yaw_rate_gain - 1.0))
print(f"small-amplitude sweep vs linear model: largest gain difference {gap:.2e}")
kept = big.lateral_acceleration_gain / lin.lateral_acceleration_gain
print(f"lateral-acceleration gain kept at 0.06 rad: {kept.min():.3f} at the least")

# %%
# Steady-state circle
# -------------------
# Radius 100 m, speed raised until the tyres saturate.

fig3, axes3 = plt.subplots(2, 1, figsize=(7, 6), sharex=True, layout="constrained")
ay = np.linspace(0.5, 10.0, 39)
for label, ratio in schedules.items():
    circle = fws.steady_state_circle(
        veh, radius=100.0, lateral_acceleration=ay, ratio=ratio
    )
    circle.plot(ax=axes3, label=label)
    print(
        f"{label}: delta_f {math.degrees(circle.delta_f[0]):.3f} deg at "
        f"{ay[0]:g} m/s^2, {math.degrees(circle.delta_f[-1]):.3f} deg at "
        f"{ay[-1]:g} m/s^2"
    )

# %%
# Run as a script without a display, the figures go to files.

if "sphinx_gallery" not in sys.modules and matplotlib.get_backend().lower() in (
    "agg",
    "pdf",
    "ps",
    "svg",
    "pgf",
    "cairo",
    "template",
):
    names = ("openloop_step.png", "openloop_frequency.png", "openloop_circle.png")
    for fig, name in zip((fig1, fig2, fig3), names, strict=True):
        fig.savefig(name, dpi=110)
    print("saved " + ", ".join(names))
else:
    plt.show()
