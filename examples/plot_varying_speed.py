"""
Varying speed: fixed gains, scheduled gains and a(V)
====================================================

A :class:`fws_control.SpeedProfile` makes the speed vary along a run (a
table of the time or of the arc length, interpolated by PCHIP, or a
braking manoeuvre), and a :class:`fws_control.GainSchedule` passed as the
controller is then read at the current speed at every step. Three
scenarios on the dynamic single-track model (BMW 320i data, linear tyres):

* **braking lane change**: the ISO 3888-1 double lane change entered at
  80 km/h, braking at 4 m/s² from the entry gate down to 30 km/h;
* **accelerating curve exit**: 50 m of a 40 m radius, a clothoid back to
  straight, accelerating from 10 m/s (20 m into the arc) to 25 m/s;
* **parking-lot exit**: a quarter turn of radius 8 m at 3 m/s,
  accelerating from halfway through the turn to 22 m/s on the road (80 m
  after the turn); the zero-sideslip ratio
  :math:`a(V)` (:func:`fws_control.zero_sideslip_ratio`) changes sign at
  :math:`V_0 = \\sqrt{f C_r l_r/(m l_f)} = 17.5` m/s, so the four-wheel
  steering switches from counter-phase to in-phase during the run.

Three controllers, all double-root designs of the kinematic plant (both
poles at -1.5 1/s on a straight road): **fixed** gains designed at the
initial speed with :math:`a = 0`; **scheduled** gains
(:meth:`fws_control.GainSchedule.double_root` on a grid of speeds) with
:math:`a = 0`; **scheduled + a(V)**, the same with the zero-sideslip ratio.
The table printed at the end (peak lateral error and peak lateral
acceleration, exact peaks of the continuous solution) is the one of
``docs/varying_speed.md``.
"""

import sys

import matplotlib
import matplotlib.pyplot as plt
import numpy as np

import fws_control as fws

VEH = fws.vehicles.BMW_320I
POLE = -1.5
GRID = np.linspace(1.0, 30.0, 59)  # schedule speeds [m/s], every 0.5 m/s


def scenarios():
    """name -> (path, speed profile, initial state, duration)."""
    lane = fws.double_lane_change(vehicle_width=1.8)
    v_in = 80.0 / 3.6
    braking = fws.SpeedProfile.braking(
        v_in, 4.0, start=lane.start_x / v_in, final=30.0 / 3.6
    )
    exit_curve = fws.PathChain(
        [
            fws.Arc(1 / 40, length=50.0),
            fws.Clothoid(1 / 40, 0.0, 30.0),
            fws.Straight(length=150.0),
        ]
    )
    # the acceleration begins 20 m into the 50 m arc
    accelerating = fws.SpeedProfile.from_distance(
        [0.0, 20.0, 130.0], [10.0, 10.0, 25.0]
    )
    # a quarter turn of radius 8 m (the clothoids turn 0.625 rad of it)
    arc = 0.5 * np.pi * 8.0 - 10.0
    parking = fws.PathChain(
        [
            fws.Clothoid(0.0, 1 / 8, 5.0),
            fws.Arc(1 / 8, length=arc),
            fws.Clothoid(1 / 8, 0.0, 5.0),
            fws.Straight(length=250.0),
        ]
    )
    turned = arc + 10.0
    # the acceleration begins halfway through the turn
    pulling_out = fws.SpeedProfile.from_distance(
        [0.0, 0.5 * turned, turned + 80.0], [3.0, 3.0, 22.0]
    )
    return {
        "braking lane change": (lane.path, braking, (0.0, 0.0, 0.0), 12.0),
        "accelerating curve exit": (exit_curve, accelerating, (0.0, 0.0, 0.0), 9.0),
        "parking-lot exit": (parking, pulling_out, (0.0, 0.0, 0.0), 18.0),
    }


def controllers(v_start):
    """name -> controller: fixed gains, scheduled gains, scheduled with a(V)."""
    fixed = fws.double_root_gains(
        fws.LateralPlant(VEH, speed=v_start), ratio=0.0, pole=POLE
    )
    scheduled = fws.GainSchedule.double_root(VEH, speeds=GRID, pole=POLE, ratio=0.0)
    with_ratio = fws.GainSchedule.double_root(
        VEH, speeds=GRID, pole=POLE, ratio=fws.zero_sideslip_ratio
    )
    return {"fixed": fixed, "scheduled": scheduled, "scheduled + a(V)": with_ratio}


def run_all():
    """(scenario, controller) -> SimulationResult."""
    out = {}
    for name, (path, profile, x0, duration) in scenarios().items():
        v_start = float(profile(0.0))
        plant = fws.LateralPlant(VEH, speed=v_start, model="dynamic")
        for label, ctrl in controllers(v_start).items():
            out[name, label] = fws.simulate(
                plant, path, ctrl, initial_state=x0, duration=duration, speed=profile
            )
    return out


def table(results):
    """Rows (scenario, controller, peak |e| [m], peak |a_y| [m/s^2], friction
    circle exceeded at a sample, status)."""
    rows = []
    for (name, label), res in results.items():
        rows.append(
            (
                name,
                label,
                float(res.peaks.e.value),
                float(res.peaks.lateral_accel.value),
                bool(res.friction_exceeded),
                res.status,
            )
        )
    return rows


def print_table(rows):
    print(
        "| scenario | controller | peak abs(e) [m] | peak abs(a_y) [m/s²] "
        "| friction circle exceeded |"
    )
    print("|---|---|---|---|---|")
    for name, label, e, ay, over, status in rows:
        note = "" if status == "ok" else f" ({status})"
        yes = "yes" if over else "no"
        print(f"| {name} | {label} | {e:.3f} | {ay:.2f}{note} | {yes} |")


# %%
# The runs and the table of ``docs/varying_speed.md``.

results = run_all()
print_table(table(results))

# %%
# Lateral error, lateral acceleration and rear angle; the speed dotted.

fig, axes = plt.subplots(3, 3, figsize=(11.0, 8.0), layout="constrained")
for row, name in enumerate(scenarios()):
    for label in ("fixed", "scheduled", "scheduled + a(V)"):
        res = results[name, label]
        axes[row, 0].plot(res.t, res.e, label=label)
        axes[row, 1].plot(res.t, res.lateral_accel, label=label)
        axes[row, 2].plot(res.t, res.delta_r, label=label)
    axes[row, 0].set_ylabel(f"{name}\nlateral error e [m]", fontsize=9)
    axes[row, 1].set_ylabel("lateral accel. [m/s²]", fontsize=9)
    axes[row, 2].set_ylabel("rear angle [rad]", fontsize=9)
    ax_v = axes[row, 2].twinx()
    ax_v.plot(res.t, res.longitudinal_speed, "k:", lw=1.0)
    ax_v.set_ylabel("speed V [m/s] (dotted)", fontsize=9)
for ax in axes[-1]:
    ax.set_xlabel("time t [s]")
axes[0, 0].legend(fontsize=8)

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
    fig.savefig("varying_speed.png", dpi=110)
    print("saved varying_speed.png")
else:
    plt.show()
