"""Generate the table of ``docs/dynamic_simulation.md``.

The kinematic double-root design (pole -1, designed on the exact kinematic
plant) simulated on the dynamic single-track model (linear tyres) of a BMW
320i, for each speed and rear-steering schedule: peak lateral acceleration,
steady-state lateral offset and the stability verdict of the linearised
closed loop. Run from the repository root::

    python docs/scripts/dynamic_table.py

It rewrites the table between the markers of the page (atomically) and
prints it. ``tests/test_dynamic_simulation_doc.py`` recomputes entries independently
and checks the page.
"""

from __future__ import annotations

import math
import pathlib
import sys

import numpy as np

import fws_control as fws

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from pages import markers, write_blocks  # noqa: E402 - the folder is put on the path first

PAGE = pathlib.Path(__file__).resolve().parents[1] / "dynamic_simulation.md"
BLOCK = "dynamic-table"
START, END = markers(BLOCK)

#: Speeds [m/s] of the table.
SPEEDS = (5.0, 10.0, 20.0, 30.0, 40.0)
#: Rear-steering schedules: constant ratios and the zero-sideslip ratio.
SCHEDULES = ("-0.5", "0", "0.5", "zero sideslip")
#: The curve: an arc of radius 400 m (lateral acceleration u^2 kappa = 4 m/s^2
#: at 40 m/s), entered 1 m to the right of it, heading along it.
CURVATURE = 0.0025
INITIAL_STATE = (0.0, -1.0, 0.0)
#: Long enough for the offset to settle (the slowest pole is near -1/s).
DURATION = 60.0


def vehicle() -> fws.Vehicle:
    """BMW 320i of CommonRoad's ``parameters_vehicle2``: :data:`fws.vehicles.BMW_320I`.

    ``a = 1.156`` m (G to front axle), ``b = 1.423`` m, ``m = 1093.3`` kg,
    ``I_z = 1791.6`` kg m^2; CommonRoad's single-track model uses the
    cornering stiffness ``-p_ky1 = 21.92`` per unit normal load, so per axle
    ``C = 21.92 * static axle load``. Linear tyres (its friction is unused).
    """
    return fws.vehicles.BMW_320I


def ratio(veh: fws.Vehicle, schedule: str, speed: float) -> float:
    """The rear-to-front ratio ``a`` of `schedule` at `speed`."""
    if schedule == "zero sideslip":
        return float(fws.zero_sideslip_ratio(veh, speed=speed))
    return float(schedule)


def closed_loop_eigenvalues(veh, gains, speed) -> np.ndarray:
    """Poles of the linearised closed loop (dynamic plant, the gains)."""
    plant = fws.LateralPlant(veh, speed=speed, curvature=CURVATURE, model="dynamic")
    loop = fws.loop_matrices(plant)
    b = loop.input_vector(gains.ratio)
    a_cl = loop.A - np.outer(b, gains.k1 * loop.c_e + gains.k2 * loop.c_theta)
    return np.linalg.eigvals(a_cl)


def rows(speeds=SPEEDS, schedules=SCHEDULES) -> list[dict]:
    """One dict per (speed, schedule), in table order."""
    veh = vehicle()
    path = fws.Arc(curvature=CURVATURE)
    out = []
    for speed in speeds:
        ratios = np.array([ratio(veh, s, speed) for s in schedules])
        # the kinematic design, on the exact kinematic plant
        g = fws.double_root_gains(
            veh, speed=speed, curvature=CURVATURE, ratio=ratios, pole=-1.0
        )
        kw = dict(initial_state=INITIAL_STATE, duration=DURATION, dt=0.5)
        dynamic = fws.LateralPlant(veh, speed=speed, model="dynamic")
        dyn = fws.simulate_batch(dynamic, path, g, **kw)
        kin = fws.simulate_batch(fws.LateralPlant(veh, speed=speed), path, g, **kw)
        for j, schedule in enumerate(schedules):
            gj = fws.SteeringGains(float(g.k1[j]), float(g.k2[j]), float(ratios[j]))
            poles = closed_loop_eigenvalues(veh, gj, speed)
            plant = fws.LateralPlant(
                veh, speed=speed, curvature=CURVATURE, model="dynamic"
            )
            stable = bool(fws.is_stable(plant, gj))
            e_cf, _ = fws.steady_state_offset(veh, gj, speed=speed, curvature=CURVATURE)
            e = dyn.e[j]
            settled = dyn.status[j] == "ok" and abs(e[-1] - e[-21]) < 1e-6
            out.append(
                {
                    "speed": speed,
                    "schedule": schedule,
                    "ratio": float(ratios[j]),
                    "peak_dynamic": float(dyn.peaks.lateral_accel.value[j]),
                    "peak_kinematic": float(kin.peaks.lateral_accel.value[j]),
                    "offset": float(e[-1]) if settled else math.nan,
                    "offset_closed_form": float(e_cf),
                    "max_real": float(np.max(poles.real)),
                    "poles": poles,
                    "stable": stable,
                }
            )
    return out


def _poles(poles: np.ndarray) -> str:
    """Poles as ``re ± im j`` pairs (one per conjugate pair), slowest first."""
    upper = sorted((p for p in poles if p.imag >= 0.0), key=lambda p: -p.real)
    parts = []
    for p in upper:
        if p.imag > 0.0:
            parts.append(f"{p.real:.3f} ± {p.imag:.3f}j")
        else:
            parts.append(f"{p.real:.3f}")
    return ", ".join(parts)


def markdown(table: list[dict]) -> str:
    """The rows as a Markdown table."""
    lines = [
        "| V [m/s] | schedule | a | peak a_y dynamic [m/s²] "
        "| peak a_y kinematic [m/s²] | e_ss simulated [m] | e_ss closed form [m] "
        "| poles of the linearised loop [1/s] | verdict |",
        "|---:|:---|---:|---:|---:|---:|---:|:---|:---|",
    ]
    for r in table:
        offset = "—" if math.isnan(r["offset"]) else f"{r['offset']:.4f}"
        lines.append(
            f"| {r['speed']:g} | {r['schedule']} | {r['ratio']:.3f} "
            f"| {r['peak_dynamic']:.3f} | {r['peak_kinematic']:.3f} | {offset} "
            f"| {r['offset_closed_form']:.4f} "
            f"| {_poles(r['poles'])} | {'stable' if r['stable'] else 'unstable'} |"
        )
    return "\n".join(lines)


def write_page(text: str, page: pathlib.Path = PAGE) -> None:
    """Put `text` between the markers of `page` (atomically)."""
    write_blocks(page, {BLOCK: text})


def main() -> int:
    text = markdown(rows())
    write_page(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
