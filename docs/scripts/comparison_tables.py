"""Generate the tables of ``docs/comparison.md``.

Every controller of :func:`fws_control.default_controllers` on the ISO
3888-1 double lane change, with :func:`fws_control.compare`, for the BMW
320i of CommonRoad (:data:`fws_control.vehicles.BMW_320I`, friction
coefficient 1.0489):

* the dynamic single-track model with the saturating tyre
  (``model="dynamic", tyre="magic"``) at 10, 20 and 30 m/s, in two
  conditions: (A) ideal steering, starting 0.2 m left of the centre line
  (inside the entry lane); (B) on the centre line with an input delay of
  0.24 s and a steering lag of 0.27 s;
* the agreement of the kinematic model with it: the paper's law (a = 0),
  pure pursuit and Stanley in condition (A) on both models over a range of
  speeds, the relative difference of max |e|, and the largest speed (and
  peak |a_y| / (mu g)) up to which every one agrees within 10 %;
* the kinematic tables at the speeds of that range.

Run from the repository root (17 s of CPU on two cores at load 2, the
compiled engine's kernels in their cache: every row runs compiled)::

    python docs/scripts/comparison_tables.py

It rewrites the blocks between the markers of the page (atomically) and
prints them. ``tests/test_comparison_doc.py`` recomputes rows independently
and checks the page.
"""

from __future__ import annotations

import math
import pathlib
import sys

import numpy as np

import fws_control as fws

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from pages import write_blocks  # noqa: E402 - the folder is put on the path first

PAGE = pathlib.Path(__file__).resolve().parents[1] / "comparison.md"

#: Speeds [m/s] of the dynamic tables.
SPEEDS = (10.0, 20.0, 30.0)
#: Start of condition (A): R this far left of the centre line [m]; the
#: 1.8 m wide wheel track's left edge is then 1.1 m left, inside the entry
#: gate's cone line at 1.115 m.
OFFSET = 0.2
#: Condition (B): input delay [s] and first-order steering lag [s].
DELAY, LAG = 0.24, 0.27
#: Speeds [m/s] and controllers of the agreement sweep.
SWEEP_SPEEDS = (6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 20.0)
SWEEP_CONTROLLERS = ("paper, a = 0", "pure pursuit", "Stanley")
#: Agreement of max |e| between the two models: relative difference.
AGREEMENT = 0.10

CONDITIONS = {
    "A": "(A) ideal steering, 0.2 m initial offset",
    "B": "(B) 0.24 s delay and 0.27 s steering lag",
}


def vehicle() -> fws.Vehicle:
    """The BMW 320i of CommonRoad's ``parameters_vehicle2``."""
    return fws.vehicles.BMW_320I


def mu_g(veh: fws.Vehicle) -> float:
    """The friction limit of the lateral acceleration [m/s^2]."""
    return float(veh.friction) * fws.dynamics.GRAVITY


def run(speed: float, condition: str, model: str, labels=None):
    """:func:`fws_control.compare` of one table (all controllers, or `labels`)."""
    veh = vehicle()
    # the MPC predicts over the delay of condition (B), as deployed MPCs do
    delay = DELAY if condition == "B" else 0.0
    ctrls = fws.default_controllers(veh, speed=speed, delay=delay)
    if labels is not None:
        ctrls = {k: ctrls[k] for k in labels}
    dyn = {"model": "dynamic", "tyre": "magic"} if model == "dynamic" else {}
    if condition == "A":
        plant = fws.LateralPlant(veh, speed=speed, **dyn)
        kw = {"offset": OFFSET}
    else:
        plant = fws.LateralPlant(veh, speed=speed, steering_lag=LAG, **dyn)
        kw = {"delay": DELAY}
    return fws.compare(plant, fws.double_lane_change(), ctrls, progress=False, **kw)


def sweep() -> list[dict]:
    """Max |e| and friction use of both models, condition (A), per speed of
    :data:`SWEEP_SPEEDS` up to the first one where they disagree."""
    out = []
    for speed in SWEEP_SPEEDS:
        if not all(r["completed"] and r["rel"] <= AGREEMENT for r in out):
            break
        kin = run(speed, "A", "kinematic", SWEEP_CONTROLLERS)
        dyn = run(speed, "A", "dynamic", SWEEP_CONTROLLERS)
        for i, label in enumerate(kin.labels):
            ek = float(kin.table["max e [m]"][i])
            ed = float(dyn.table["max e [m]"][i])
            out.append(
                {
                    "speed": speed,
                    "label": label,
                    "e_kinematic": ek,
                    "e_dynamic": ed,
                    "rel": abs(ed - ek) / ek,
                    "use_kinematic": float(kin.table["peak a_lat / (mu g) [-]"][i]),
                    "use_dynamic": float(dyn.table["peak a_lat / (mu g) [-]"][i]),
                    "completed": bool(dyn.table["completed"][i])
                    and bool(kin.table["completed"][i]),
                }
            )
    return out


def agreement_limit(rows: list[dict]) -> tuple[float, float]:
    """``(speed, friction use)``: the largest swept speed up to which every
    controller's max |e| agrees within :data:`AGREEMENT` (both runs complete),
    and the largest kinematic peak |a_y| / (mu g) of those runs."""
    speed, use = math.nan, math.nan
    for v in SWEEP_SPEEDS:
        at = [r for r in rows if r["speed"] == v]
        if not all(r["completed"] and r["rel"] <= AGREEMENT for r in at):
            break
        speed = v
        use = max(r["use_kinematic"] for r in rows if r["speed"] <= v)
    return speed, use


def kinematic_speeds(speed: float) -> list[float]:
    """Speeds of the kinematic tables: those of :data:`SPEEDS` within the
    agreement range, else the range's largest swept speed."""
    kept = [v for v in SPEEDS if v <= speed]
    return kept or ([] if math.isnan(speed) else [speed])


def sweep_markdown(rows: list[dict]) -> str:
    lines = [
        "| V [m/s] | controller | max e kinematic [m] | max e dynamic [m] "
        "| relative difference | peak a_lat / (mu g) kinematic "
        "| peak a_lat / (mu g) dynamic |",
        "|---:|:---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['speed']:g} | {r['label']} | {r['e_kinematic']:.3g} "
            f"| {r['e_dynamic']:.3g} | {r['rel']:.2f} | {r['use_kinematic']:.3g} "
            f"| {r['use_dynamic']:.3g} |"
        )
    speed, use = agreement_limit(rows)
    peak_curvature = course_peak_curvature()
    lines += [
        "",
        f"Agreement within {AGREEMENT:.0%}: up to V = {speed:g} m/s, peak "
        f"|a_y| / (mu g) <= {use:.2f} on the kinematic model (the course's "
        f"V² κ_max = {speed**2 * peak_curvature:.2f} m/s², "
        f"{speed**2 * peak_curvature / mu_g(vehicle()):.2f} mu g).",
    ]
    peaks = []
    for v in SPEEDS[1:]:
        kin = run(v, "A", "kinematic", ["paper, a = 0"])
        acc = float(kin.table["peak a_lat [m/s^2]"][0])
        peaks.append(f"{acc:.3g} m/s² at {v:g} m/s ({acc / mu_g(vehicle()):.2f} mu g)")
    lines.append(
        "On the kinematic model the paper's law (a = 0) in condition (A) peaks "
        f"at {' and '.join(peaks)}."
    )
    return "\n".join(lines)


def course_peak_curvature() -> float:
    """Largest |curvature| of the course's centre line [1/m] (dense grid)."""
    path = fws.double_lane_change().path
    s = np.linspace(0.0, float(path.length), 200_001)
    return float(np.max(np.abs(path.curvature(s))))


def tables_markdown(model: str, speeds, conditions=tuple(CONDITIONS)) -> str:
    """The tables of `model` at `speeds`, one per condition (``"A"``, ``"B"``)."""
    blocks = []
    for speed in speeds:
        blocks.append(f"### {speed:g} m/s")
        for cond in conditions:
            title = CONDITIONS[cond]
            blocks += ["", f"#### {title}", "", run(speed, cond, model).to_markdown()]
        blocks.append("")
    return "\n".join(blocks).rstrip()


def write_block(name: str, text: str, page: pathlib.Path = PAGE) -> None:
    """Put `text` between the markers `name` of `page` (atomically)."""
    write_blocks(page, {name: text})


def main() -> int:
    rows = sweep()
    text = sweep_markdown(rows)
    write_block("comparison-agreement", text)
    print(text, flush=True)
    kept = kinematic_speeds(agreement_limit(rows)[0])
    text = tables_markdown("kinematic", kept)
    write_block("comparison-kinematic", text)
    print(text, flush=True)
    text = tables_markdown("dynamic", SPEEDS)
    write_block("comparison-dynamic", text)
    print(text, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
