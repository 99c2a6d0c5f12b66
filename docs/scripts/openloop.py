"""Generate the tables of ``docs/openloop.md``.

The open-loop tests of :mod:`fws_control.openloop` for the BMW 320i of
CommonRoad (:data:`fws_control.vehicles.BMW_320I`) at 20 m/s, with front
steering and with four-wheel steering at the zero-sideslip ratio
:func:`fws_control.zero_sideslip_ratio`. Run from the repository root::

    python docs/scripts/openloop.py

It rewrites the tables between the markers of the page (atomically) and
prints them. ``tests/test_openloop_doc.py`` checks that the page holds what
this script computes now and recomputes entries by other routes.
"""

from __future__ import annotations

import math
import pathlib
import sys

import numpy as np

import fws_control as fws

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from pages import markers as block_markers  # noqa: E402 - the folder is put on the path first
from pages import write_blocks  # noqa: E402

PAGE = pathlib.Path(__file__).resolve().parents[1] / "openloop.md"
TABLES = ("step", "frequency", "circle")

VEHICLE = fws.vehicles.BMW_320I
SPEED = 20.0
#: Steering schedules: front steering and 4WS with a(V).
SCHEDULES = {"front": 0.0, "4WS a(V)": fws.zero_sideslip_ratio}
#: Step steer: final front angle [rad] (a steady 3.1 m/s^2 with front
#: steering) and the ISO 7401 ramp (10 % to 90 % in 0.15 s).
STEP_ANGLE = 0.02
#: Frequencies of the table [Hz] and the large amplitude [rad] of the
#: saturating-tyre sweep (a steady 0.9 g with front steering).
FREQUENCIES_HZ = (0.1, 0.5, 1.0, 2.0, 4.0)
LARGE_AMPLITUDE = 0.06
#: ISO 4138 constant radius [m] and lateral accelerations [m/s^2].
RADIUS = 100.0
LATERAL_ACCELERATIONS = (1.0, 4.0, 7.0, 9.0, 10.0)


def markers(name: str) -> tuple[str, str]:
    """The markers of table `name` on the page."""
    return block_markers(f"openloop-{name}")


def step_rows() -> list[dict]:
    """ISO 7401 values of the step steer, per schedule and model."""
    out = []
    for label, ratio in SCHEDULES.items():
        for model, tyre in (("linear", "linear"), ("nonlinear", "magic")):
            res = fws.step_steer(
                VEHICLE, speed=SPEED, amplitude=STEP_ANGLE, ratio=ratio,
                model=model, tyre=tyre,
            )  # fmt: skip
            for what, m in (
                ("r", res.yaw_rate_metrics),
                ("a_y", res.lateral_acceleration_metrics),
            ):
                out.append(
                    {
                        "schedule": label,
                        "ratio": res.ratio,
                        "model": f"{model} ({tyre} tyre)",
                        "output": what,
                        "steady": m.steady_state,
                        "response_time": m.response_time,
                        "rise_time": m.rise_time,
                        "peak_time": m.peak_response_time,
                        "overshoot": m.overshoot,
                    }
                )
    return out


def frequency_rows() -> list[dict]:
    """Linear gain and phase, and the gain kept at the large amplitude."""
    w = 2.0 * math.pi * np.array(FREQUENCIES_HZ)
    out = []
    for label, ratio in SCHEDULES.items():
        lin = fws.steering_frequency_response(
            VEHICLE, speed=SPEED, omega=w, ratio=ratio
        )
        big = fws.steering_frequency_response(
            VEHICLE, speed=SPEED, omega=w, ratio=ratio, model="nonlinear",
            tyre="magic", amplitude=LARGE_AMPLITUDE,
        )  # fmt: skip
        for k, hz in enumerate(FREQUENCIES_HZ):
            out.append(
                {
                    "schedule": label,
                    "hz": hz,
                    "r_gain": lin.yaw_rate_gain[k],
                    "r_phase": math.degrees(lin.yaw_rate_phase[k]),
                    "ay_gain": lin.lateral_acceleration_gain[k],
                    "ay_phase": math.degrees(lin.lateral_acceleration_phase[k]),
                    "ay_kept": big.lateral_acceleration_gain[k]
                    / lin.lateral_acceleration_gain[k],
                }
            )
    return out


def circle_rows() -> list[dict]:
    """Steady states on the 100 m circle, saturating tyre."""
    out = []
    for label, ratio in SCHEDULES.items():
        c = fws.steady_state_circle(
            VEHICLE, radius=RADIUS, lateral_acceleration=LATERAL_ACCELERATIONS,
            ratio=ratio,
        )  # fmt: skip
        for k, ay in enumerate(LATERAL_ACCELERATIONS):
            out.append(
                {
                    "schedule": label,
                    "a_y": ay,
                    "speed": c.speed[k],
                    "delta_f": math.degrees(c.delta_f[k]),
                    "delta_r": math.degrees(c.delta_r[k]),
                    "sideslip": math.degrees(c.sideslip[k]),
                    "gradient": math.degrees(c.understeer_gradient[k]),
                }
            )
    return out


def _time(t: float) -> str:
    return "none" if math.isinf(t) else f"{t:.3f}"


def markdown_step(rows: list[dict]) -> str:
    lines = [
        "| schedule | a | model | output | steady value | response time [s] "
        "| rise time [s] | peak response time [s] | overshoot [%] |",
        "|:---|---:|:---|:---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        unit = "rad/s" if r["output"] == "r" else "m/s²"
        lines.append(
            f"| {r['schedule']} | {r['ratio']:.4f} | {r['model']} | {r['output']} "
            f"| {r['steady']:.4f} {unit} | {r['response_time']:.3f} "
            f"| {r['rise_time']:.3f} | {_time(r['peak_time'])} "
            f"| {100 * r['overshoot']:.2f} |"
        )
    return "\n".join(lines)


def markdown_frequency(rows: list[dict]) -> str:
    lines = [
        "| schedule | f [Hz] | r/δf [1/s] | phase r [deg] | a_y/δf [m/s²/rad] "
        f"| phase a_y [deg] | a_y gain kept at {LARGE_AMPLITUDE} rad, magic tyre |",
        "|:---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['schedule']} | {r['hz']:g} | {r['r_gain']:.3f} "
            f"| {r['r_phase']:.1f} | {r['ay_gain']:.2f} | {r['ay_phase']:.1f} "
            f"| {r['ay_kept']:.3f} |"
        )
    return "\n".join(lines)


def markdown_circle(rows: list[dict]) -> str:
    lines = [
        "| schedule | a_y [m/s²] | u [m/s] | δf [deg] | δr [deg] | sideslip β [deg] "
        "| dδf/da_y [deg s²/m] |",
        "|:---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['schedule']} | {r['a_y']:g} | {r['speed']:.3f} "
            f"| {r['delta_f']:.4f} | {r['delta_r']:.4f} | {r['sideslip']:.4f} "
            f"| {r['gradient']:.5f} |"
        )
    return "\n".join(lines)


def tables() -> dict[str, str]:
    """The three tables, by marker name."""
    return {
        "step": markdown_step(step_rows()),
        "frequency": markdown_frequency(frequency_rows()),
        "circle": markdown_circle(circle_rows()),
    }


def write_page(texts: dict[str, str], page: pathlib.Path = PAGE) -> None:
    """Put each text between its markers of `page` (atomically)."""
    write_blocks(page, {f"openloop-{name}": text for name, text in texts.items()})


def main() -> int:
    texts = tables()
    write_page(texts)
    for name in TABLES:
        print(texts[name], end="\n\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
