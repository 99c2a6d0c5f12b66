"""Numbers quoted in the docs' prose, parsed from the pages and recomputed.

Each test reads a number from a page (delay.md, comparison.md, dynamic.md,
dynamic_simulation.md) and recomputes it with the library, against a
reference written here where one exists:

* delay.md: how many of the coarse Fig. 5 sweep's runs converge (a run
  converges if it completes and ``max |e| < 1e-3`` m over its last 5 s of
  30), how close the converging runs stay to the path, and the critical
  delays of the loops to which the closed form (``lambda0`` and ``V kappa``
  only) does not extend;
* comparison.md: the course's peak curvature (a dense sample of the path)
  and the footprint's overlap of the entry gate's cone line (geometry);
* dynamic.md: the small-angle error of ``steady_state_offset`` against the
  nonlinear steady state (``scipy.optimize.fsolve`` on the nonlinear path
  equations);
* dynamic_simulation.md: the gap between CommonRoad's single-track model and
  fws's dynamic model on a tight circle (the loop around CommonRoad written
  here, as in ``tests/test_dynamic_commonroad.py``).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

import fws_control as fws
from fws_control import dynamics
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG
from fws_control.paper.scenarios import scenario_responses
from fws_control.vehicles import BMW_320I

DOCS = Path(__file__).resolve().parents[1] / "docs"
VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
DESIGN_RATIOS = (-1.0, -0.5, 0.0, 0.5)


def _prose(page: str) -> str:
    """The page with every run of white space made one blank."""
    return " ".join((DOCS / page).read_text(encoding="utf-8").split())


def _sci(text: str) -> float:
    """``9.0\\cdot10^{-6}`` -> 9.0e-6."""
    m = re.fullmatch(r"([\d.]+)\\cdot10\^\{(-?\d+)\}", text)
    assert m, text
    return float(m[1]) * 10.0 ** int(m[2])


def _rounds_to(value: float, printed: str) -> bool:
    decimals = len(printed.split(".")[1]) if "." in printed else 0
    return math.isclose(round(value, decimals), float(printed), abs_tol=1e-12)


def _range(text: str) -> tuple[str, str]:
    lo, hi = text.split("–")
    return lo, hi


# --------------------------------------------------------------------------
# delay.md: the paper's scenarios with the realistic actuator


COARSE = np.round(np.linspace(-1.5, 1.5, 13), 12)
POLES = {"straight_5": (-1.0, -2.0), "curve_5": (-1.0, -2.0)}
POLES |= {"straight_20": (-1.0, -2.0, -3.0), "curve_20": (-1.0, -2.0, -3.0)}


def _last_5_s(result) -> tuple[np.ndarray, np.ndarray]:
    """(converged, max |e| over the last 5 s) per run."""
    last = result.t >= result.t[-1] - 5.0 - 1e-9
    tail = np.max(np.abs(np.asarray(result.e)[:, last]), axis=1)
    return (result.status == "ok") & (tail < 1e-3), tail


def test_delay_page_convergence_counts():
    prose = _prose("delay.md")
    m = re.search(
        r"\(0 of (\d+); (\d+) of them converge with the ideal steering\)", prose
    )
    total, ideal_ok = int(m[1]), int(m[2])
    m = re.search(
        r"converging runs stay within \$(\S+)\$ m of the path "
        r"\(\$(\S+)\$ m with the ideal steering\)",
        prose,
    )
    within_real, within_ideal = _sci(m[1]), _sci(m[2])

    runs, converged, tails = 0, 0, {"ideal": [], "real": []}
    actuator = {
        "delay": REALISTIC_DELAY,
        "steering_lag": REALISTIC_STEERING_LAG,
    }
    for name, poles in POLES.items():
        for pole in poles:
            kinds = {"ideal": {}}
            if pole == -1.0:
                kinds["real"] = actuator
            for kind, kw in kinds.items():
                r = scenario_responses(
                    name, ratios=COARSE, pole=pole, duration=30.0, progress=False, **kw
                )
                ok, tail = _last_5_s(r.result)
                if pole == -1.0:
                    tails[kind].extend(tail[ok].tolist())
                else:
                    runs += ok.size
                    converged += int(ok.sum())
    assert runs == total
    assert converged == ideal_ok
    # the page's bound is the largest tail, rounded up to its two digits
    for kind, bound in (("real", within_real), ("ideal", within_ideal)):
        worst = max(tails[kind])
        assert worst <= bound < worst * 1.06, (kind, worst, bound)


def test_critical_delay_beyond_the_closed_form():
    prose = _prose("delay.md")
    pa = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, model="paper")
    ex = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, model="kinematic")

    # a paper-model design on the exact plant
    m = re.search(r"on the 5 m/s curve the margin is (\S+) s depending on \$a\$", prose)
    lo, hi = _range(m[1])
    own = []
    tau = []
    for a in DESIGN_RATIOS:
        g = fws.double_root_gains(pa, ratio=a, pole=-1.0)
        tau.append(float(fws.critical_delay(ex, g).delay))
        own.append(float(fws.critical_delay(pa, g).delay))
    assert _rounds_to(min(tau), lo) and _rounds_to(max(tau), hi), tau
    # on its own model the margin is the closed form's, whatever a
    assert np.ptp(own) < 1e-12
    assert "against 0.6512 s on the model the design was made on" in prose
    assert _rounds_to(own[0], "0.6512")

    # unequal front and rear lags: the ratio no longer cancels
    m = re.search(r"steering_lag=\(0\.27, 0\.1\)\)`, same curve\): (\S+) s", prose)
    lo, hi = _range(m[1])
    unequal, equal = [], []
    for a in DESIGN_RATIOS:
        g = fws.double_root_gains(ex, ratio=a, pole=-1.0)
        lagged = fws.LateralPlant(
            VEH, speed=5.0, curvature=0.1, steering_lag=(0.27, 0.1)
        )
        unequal.append(float(fws.critical_delay(lagged, g).delay))
        same = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, steering_lag=0.27)
        equal.append(float(fws.critical_delay(same, g).delay))
    assert _rounds_to(min(unequal), lo) and _rounds_to(max(unequal), hi), unequal
    m = re.search(r"the ratio cancels again, (\S+) s for every \$a\$", prose)
    assert np.ptp(equal) < 1e-9 and _rounds_to(equal[0], m[1]), equal

    # the dynamic plant with the kinematic design
    m = re.search(r"kinematic design\): (\S+) s at 5 m/s and (\S+) s at 20 m/s", prose)
    quoted = {5.0: m[1], 20.0: m[2]}
    for speed, text in quoted.items():
        dyn = fws.LateralPlant(BMW_320I, speed=speed, curvature=0.0, model="dynamic")
        kin = fws.LateralPlant(BMW_320I, speed=speed, curvature=0.0, model="kinematic")
        taus = [
            float(
                fws.critical_delay(
                    dyn, fws.double_root_gains(kin, ratio=a, pole=-1.0)
                ).delay
            )
            for a in DESIGN_RATIOS
        ]
        lo, hi = _range(text) if "–" in text else (text, text)
        assert _rounds_to(min(taus), lo) and _rounds_to(max(taus), hi), (speed, taus)
        assert np.ptp(taus) < 1e-4  # "a moves only the fifth digit"
    # against the kinematic plant's closed form on a straight road
    w = math.sqrt(2.0 + math.sqrt(5.0))
    assert "against 0.6474 s on the kinematic plant" in prose
    assert _rounds_to(math.atan(2.0 * w) / w, "0.6474")


# --------------------------------------------------------------------------
# comparison.md: the double lane change


def test_comparison_page_course_geometry():
    prose = _prose("comparison.md")
    course = fws.double_lane_change()
    s = np.linspace(0.0, course.path.length, 400_001)
    peak = float(np.max(np.abs(course.path.curvature(s))))
    m = re.search(r"curvature, peak ([\d.]+) 1/m\)", prose)
    assert _rounds_to(peak, m[1]), peak
    # condition (A): the footprint, 1.8 m wide, 0.2 m left of the centre
    # line; the entry gate's left cone line 1.1 b / 2 + 0.125 m from it
    # (ISO 3888-1)
    gate = course.gates[0]
    assert gate.y_left == pytest.approx(0.5 * (1.1 * 1.8 + 0.25))
    edge = 0.2 + 0.5 * course.vehicle_width
    m = re.search(
        r"left edge at ([\d.]+) m, inside the entry\s+gate's cone line at "
        r"([\d.]+) m\)",
        prose,
    )
    assert m is not None
    assert _rounds_to(edge, m[1]), edge
    assert _rounds_to(gate.y_left, m[2]), gate.y_left
    assert edge < gate.y_left


# --------------------------------------------------------------------------
# dynamic.md: steady_state_offset is a small-angle result


def _nonlinear_offset(vehicle, gains, speed, curvature):
    """Lateral error of the nonlinear loop's steady state (fsolve)."""

    def rates(z):
        e, th, vy, r = z
        df, dr = fws.steering_command(vehicle, gains, e, th, curvature=curvature)
        out = dynamics.dynamic_path_derivatives(
            vehicle, curvature, e, th, vy, r, df, dr, speed=speed
        )
        return np.array(out[1:], dtype=float)

    z0 = [0.0, 0.0, vehicle.rear_to_cg * curvature * speed, curvature * speed]
    z, _, ok, msg = fsolve(rates, z0, full_output=True, xtol=1e-13)
    assert ok == 1, msg
    assert np.abs(rates(z)).max() < 1e-10
    return float(z[0])


def test_steady_state_offset_small_angle_error():
    prose = _prose("dynamic.md")
    m = re.search(
        r"it is ([\d.]+) % off the nonlinear steady state at 20 m/s on a 100 m "
        r"radius and ([\d.]+) % off at 5 m/s on a 10 m radius",
        prose,
    )
    for (speed, curvature), printed in zip(
        ((20.0, 0.01), (5.0, 0.1)), m.groups(), strict=True
    ):
        g = fws.double_root_gains(
            BMW_320I, speed=speed, curvature=curvature, ratio=0.0, pole=-1.0
        )
        e, _ = fws.steady_state_offset(BMW_320I, g, speed=speed, curvature=curvature)
        e_nl = _nonlinear_offset(BMW_320I, g, speed, curvature)
        assert _rounds_to(100.0 * abs(e - e_nl) / abs(e_nl), printed), (e, e_nl)
    # the docstring quotes the same two figures
    doc = " ".join(fws.steady_state_offset.__doc__.split())
    assert f"{m[1]} % at 20 m/s on a 100 m radius and {m[2]} % at 5 m/s" in doc


# --------------------------------------------------------------------------
# dynamic_simulation.md: CommonRoad agrees at small angles only

SERVO_T = 0.05
GRAVITY = 9.81  # CommonRoad's value, in vehicle_dynamics_st
DURATION = 20.0  # [s]: long enough to settle (checked below)


def test_commonroad_gap_on_a_tight_circle():
    params = pytest.importorskip(
        "vehiclemodels.parameters_vehicle2",
        reason="commonroad-vehicle-models (extra 'test') is not installed",
    )
    st = pytest.importorskip("vehiclemodels.vehicle_dynamics_st")
    prose = _prose("dynamic_simulation.md")
    m = re.search(
        r"\$\\delta_f\$ settles at ([\d.]+) rad and \$\\beta\$ at ([\d.]+) rad, "
        r"\$\\varepsilon\$ = ([\d.]+) over the run\) settles at a lateral offset "
        r"of −([\d.]+) m in fws and −([\d.]+) m in CommonRoad: "
        r"(\d+) % of CommonRoad's offset apart",
        prose,
    )
    p = params.parameters_vehicle2()
    mu, c_s, f = p.tire.p_dy1, -p.tire.p_ky1 / p.tire.p_dy1, p.a + p.b
    veh = fws.Vehicle(
        wheelbase=f, rear_to_cg=p.b, mass=p.m, yaw_inertia=p.I_z,
        cornering_front=mu * c_s * p.m * GRAVITY * p.b / f,
        cornering_rear=mu * c_s * p.m * GRAVITY * p.a / f,
        max_steer_rate_front=p.steering.v_max,
    )  # fmt: skip
    speed, curvature = 5.0, 0.1
    path = fws.Arc(curvature=curvature)
    g = fws.double_root_gains(
        veh, speed=speed, curvature=curvature, ratio=0.0, pole=-1.0
    )
    t = np.linspace(0.0, DURATION, 401)
    x0 = (0.0, -1.0, 0.0)
    plant = fws.LateralPlant(veh, speed=speed, model="dynamic", steering_lag=SERVO_T)
    res = fws.simulate(
        plant, path, g, initial_state=x0, duration=DURATION, t_eval=t,
    )  # fmt: skip
    assert res.status == "ok"

    def rhs(_, z):
        xg, yg, delta, v, psi, r, beta = z
        xr, yr = xg - p.b * math.cos(psi), yg - p.b * math.sin(psi)
        _, e, th, k = path.errors(xr, yr, psi)
        cmd, _ = fws.steering_command(veh, g, float(e), float(th), curvature=float(k))
        return st.vehicle_dynamics_st(z, [(float(cmd) - delta) / SERVO_T, 0.0], p)

    v_y0, r0 = res.v_y[0], res.yaw_rate[0]
    z0 = [p.b, -1.0, res.delta_f[0], math.hypot(speed, v_y0), 0.0, r0,
          math.atan2(v_y0, speed)]  # fmt: skip
    # the quoted offsets have three digits: rtol 1e-8 is ample
    sol = solve_ivp(
        rhs, (0.0, DURATION), z0, t_eval=t, method="DOP853", rtol=1e-8, atol=1e-9
    )
    assert sol.success
    xg, yg, delta, _, psi, _, beta = sol.y
    e_cr = np.array([
        path.errors(x - p.b * math.cos(q), y - p.b * math.sin(q), q)[1]
        for x, y, q in zip(xg[-20:], yg[-20:], psi[-20:], strict=True)
    ])  # fmt: skip
    # settled: the last second moves e by far less than the quoted digits
    assert np.ptp(res.e[-20:]) < 1e-4 and np.ptp(e_cr) < 1e-4
    e_cr, e_fws = float(e_cr[-1]), float(res.e[-1])
    assert _rounds_to(res.delta_f[-1], m[1]) and _rounds_to(beta[-1], m[2])
    eps = np.max(np.abs(beta)) ** 2 + np.max(np.abs(delta)) ** 2
    assert _rounds_to(eps, m[3]), eps
    assert _rounds_to(-e_fws, m[4]) and _rounds_to(-e_cr, m[5]), (e_fws, e_cr)
    assert _rounds_to(100.0 * abs(e_fws - e_cr) / abs(e_cr), m[6])
