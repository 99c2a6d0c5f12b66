"""Valid-looking input that gave silent garbage or an unhelpful message.

Each test holds the library to a reference computed here: the steady turn's
force balance and the tyre formula written out, the geometry of a circle
from the simulated positions, the spacing of doubles.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from scipy.optimize import brentq, minimize_scalar

import fws_control as fws
from fws_control.cli import main

BMW = fws.vehicles.BMW_320I
GRAVITY = 9.81  # the value fws_control.dynamics states for its axle loads
MAGIC_C = 1.3  # shape factor c of the simplified magic formula (dynamics docs)


def _axle_loads(veh):
    """Static normal loads (front, rear) [N] from the lever rule."""
    w = veh.mass * GRAVITY
    lf = veh.wheelbase - veh.rear_to_cg
    return w * veh.rear_to_cg / veh.wheelbase, w * lf / veh.wheelbase


def _magic(alpha, stiffness, peak):
    """F = D sin(c arctan(B alpha)), B = C/(c D): slope C at 0, peak D."""
    b = stiffness / (MAGIC_C * peak)
    return peak * np.sin(MAGIC_C * np.arctan(b * alpha))


# --------------------------------------------------------------------------
# steady_state_offset at a speed no tyre can hold


def test_steady_state_offset_refuses_a_speed_no_tyre_holds():
    # A steady state (e, theta constant) moves R on a circle about the
    # path's centre, radius |1/kappa - e|, at a speed >= V (R's velocity is
    # tangential): the yaw rate is then |r| >= V |kappa| / |1 - kappa e|.
    # The body's lateral balance m V r = F_f cos(delta_f) + F_r cos(delta_r)
    # with linear tyres (|slip| < pi for steering below pi/2) bounds
    # |r| < pi (C_f + C_r) / (m V). So |1 - kappa e| must exceed:
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=0.0)
    V, kappa = 1.0e6, 0.01
    c_sum = BMW.cornering_front + BMW.cornering_rear
    least = abs(kappa) * BMW.mass * V**2 / (math.pi * c_sum)
    assert least > 1e7  # any steady state lies > 1e9 m from this 100 m circle
    with pytest.raises(ValueError, match=r"speed=1000000\.0 m/s") as info:
        fws.steady_state_offset(BMW, g, speed=V, curvature=kappa)
    msg = str(info.value)
    assert "curvature=0.01" in msg and "cannot give" in msg
    # the largest curvature it names must obey the same force balance at
    # e = theta = 0 (r = kappa V): kappa <= pi (C_f + C_r) / (m V^2)
    largest = float(re.search(r"largest curvature at this speed is (\S+) 1/m", msg)[1])
    assert 0.0 < largest <= math.pi * c_sum / (BMW.mass * V**2)
    # and the dynamic plant refuses the same point with the same words
    with pytest.raises(ValueError, match="cannot give"):
        fws.LateralPlant(BMW, speed=V, curvature=kappa, model="dynamic")


def test_steady_state_offset_refuses_a_solution_beyond_the_centre():
    # The closed form of the docstring, written here: for these gains at an
    # operating point the dynamic plant accepts, the first-order solution
    # puts R beyond the circle's centre (1 - kappa e < 0), where e and theta
    # of the path frame do not exist.
    g = fws.SteeringGains(k1=0.02, k2=-2.0, ratio=-1.0)
    V, kappa = 20.0, 0.05
    fws.LateralPlant(BMW, speed=V, curvature=kappa, model="dynamic")  # exists
    m, f = BMW.mass, BMW.wheelbase
    lr, lf = BMW.rear_to_cg, f - BMW.rear_to_cg
    pf = m * V**2 * lr / (f * BMW.cornering_front)
    pr = m * V**2 * lf / (f * BMW.cornering_rear)
    a, k1, k2 = -1.0, 0.02, -2.0
    M = np.array(
        [
            [-(k1 + (f + pf) * kappa**2), 1.0 - k2],
            [-(a * k1 + pr * kappa**2), 1.0 - a * k2],
        ]
    )
    e, theta = np.linalg.solve(M, kappa * np.array([pf, pr]))
    assert 1.0 - kappa * e < 0.0  # beyond the centre
    with pytest.raises(ValueError, match="no steady state near the path") as info:
        fws.steady_state_offset(BMW, g, speed=V, curvature=kappa)
    assert f"e={e:.4g} m" in str(info.value)


# --------------------------------------------------------------------------
# a curve too tight for the magic tyre


def _front_reach(veh, V):
    """Largest curvature the front axle holds at V: the fold of its equation.

    F(alpha) cos(arctan(f kappa) + alpha) = m V^2 kappa l_r / f on the
    rising branch of the tyre, written here with a dense slip grid and
    bisection on kappa.
    """
    peak = veh.friction * _axle_loads(veh)[0]
    f, q = veh.wheelbase, veh.mass * V**2 * veh.rear_to_cg / veh.wheelbase
    b = veh.cornering_front / (MAGIC_C * peak)
    rising = math.tan(math.pi / (2 * MAGIC_C)) / b

    def margin(kappa):
        alpha = np.linspace(0.0, rising, 200_001)
        lhs = _magic(alpha, veh.cornering_front, peak) * np.cos(
            np.arctan(f * kappa) + alpha
        )
        return float(lhs.max()) - q * kappa

    return brentq(margin, 1e-9, peak / q, xtol=1e-13)


def test_dynamic_plant_beyond_the_tyre_names_the_largest_curvature():
    V, kappa = 20.0, 0.2
    fz_f, fz_r = _axle_loads(BMW)
    # the peak of the tyre formula, by maximising it here
    res = minimize_scalar(
        lambda a: -_magic(a, BMW.cornering_front, BMW.friction * fz_f),
        bounds=(0.0, 1.5),
        method="bounded",
        options={"xatol": 1e-12},
    )
    peak_f = -res.fun
    assert peak_f == pytest.approx(BMW.friction * fz_f, rel=1e-9)
    with pytest.raises(ValueError) as info:
        fws.LateralPlant(BMW, speed=V, curvature=kappa, model="dynamic", tyre="magic")
    msg = str(info.value)
    assert "curvature=0.2 1/m at speed=20.0 m/s" in msg
    assert "needs a lateral force the tyres cannot give" in msg
    # the force the front axle needs (m V^2 kappa l_r / f) and its peak
    need = BMW.mass * V**2 * kappa * BMW.rear_to_cg / BMW.wheelbase
    got_need = float(re.search(r"must carry at least (\S+) N", msg)[1])
    got_peak = float(re.search(r"= (\S+) N", msg)[1])
    assert got_need == pytest.approx(need, rel=1e-5)
    assert got_peak == pytest.approx(peak_f, rel=1e-5)
    # the largest curvature: the fold of the front axle's steady equation
    # (the rear holds more for this car: l_f C_r-limited load is larger)
    largest = float(re.search(r"largest curvature at this speed is (\S+) 1/m", msg)[1])
    ref = _front_reach(BMW, V)
    assert largest == pytest.approx(ref, rel=1e-5)
    # below it the operating point exists; above it the same message
    fws.LateralPlant(BMW, speed=V, curvature=0.999 * ref, model="dynamic", tyre="magic")
    with pytest.raises(ValueError, match="largest curvature at this speed"):
        fws.LateralPlant(
            BMW, speed=V, curvature=1.01 * ref, model="dynamic", tyre="magic"
        )


# --------------------------------------------------------------------------
# compare with a sweep of designs


def test_compare_refuses_an_array_of_designs_and_says_what_to_use():
    veh = PAPER_VEHICLE
    m = fws.constant_radius(radius=40.0, turns=0.05)
    sweep = fws.SteeringGains(k1=[0.1, 0.2], k2=0.5, ratio=0.0)
    with pytest.raises(ValueError) as info:
        fws.compare(fws.LateralPlant(veh, speed=5.0), m, {"sweep": sweep}, dt=0.1)
    msg = str(info.value)
    assert "controllers['sweep']" in msg and "k1 of shape (2,)" in msg
    assert "one design" in msg and "simulate_batch" in msg
    # the suggested function runs the sweep: one run per design, each the
    # run of that design alone
    batch = fws.simulate_batch(
        fws.LateralPlant(veh, speed=5.0),
        m.path,
        sweep,
        initial_state=(0.0, 0.5, 0.0),
        duration=2.0,
    )
    assert len(batch) == 2
    for i, k1 in enumerate((0.1, 0.2)):
        one = fws.simulate(
            fws.LateralPlant(veh, speed=5.0),
            m.path,
            fws.SteeringGains(k1, 0.5, ratio=0.0),
            initial_state=(0.0, 0.5, 0.0),
            duration=2.0,
        )
        np.testing.assert_allclose(batch.e[i], one.e, rtol=1e-6, atol=1e-9)


# --------------------------------------------------------------------------
# closed courses: turns and completion


def _swept(result, centre):
    """Angle [rad] R swept about `centre`, from the simulated positions."""
    x, y = np.asarray(result.x, float), np.asarray(result.y, float)
    ok = np.isfinite(x) & np.isfinite(y)
    phi = np.unwrap(np.arctan2(y[ok] - centre[1], x[ok] - centre[0]))
    return float(phi[-1] - phi[0])


def test_constant_radius_drives_its_turns():
    veh = PAPER_VEHICLE
    R, V = 10.0, 5.0
    m = fws.constant_radius(radius=R, turns=3)
    g = fws.double_root_gains(
        fws.LateralPlant(veh, speed=V, curvature=1.0 / R), ratio=0.0, pole=-1.0
    )
    cmp = fws.compare(fws.LateralPlant(veh, speed=V), m, {"paper": g})
    r = cmp.results[0]
    # three laps about the centre (0, R), read from x and y
    assert _swept(r, (0.0, R)) >= 3 * 2 * math.pi
    assert bool(cmp.table["completed"][0]) is True
    # a fraction of a turn is an open arc of that length: driven to its end
    half = fws.compare(
        fws.LateralPlant(veh, speed=V),
        fws.constant_radius(radius=R, turns=0.5),
        {"p": g},
    )
    swept = _swept(half.results[0], (0.0, R))
    assert swept == pytest.approx(math.pi, abs=0.02)
    assert bool(half.table["completed"][0]) is True


def test_completed_on_a_tight_circle_means_the_lap_was_driven():
    # On a 2.5 m circle at 3 m/s Stanley's steering reaches its singular
    # angle and the run stops; the others track the circle. Completion is
    # read here from the positions: a full lap about the centre, ending on
    # the circle, without a stop.
    veh = PAPER_VEHICLE
    R, V = 2.5, 3.0
    every = fws.default_controllers(veh, speed=V)
    names = ["paper, a = 0", "pure pursuit", "Stanley", "LQR (independent rear)"]
    cmp = fws.compare(
        fws.LateralPlant(veh, speed=V),
        fws.constant_radius(radius=R),
        {n: every[n] for n in names},
    )
    tracked = []
    for r in cmp.results:
        x, y = np.asarray(r.x, float), np.asarray(r.y, float)
        ok = np.isfinite(x)
        end_off = abs(math.hypot(x[ok][-1], y[ok][-1] - R) - R)
        lap = _swept(r, (0.0, R)) >= 2 * math.pi
        tracked.append(str(r.status) == "ok" and lap and end_off < 0.2)
    assert tracked == [True, True, False, True]
    assert [bool(c) for c in cmp.table["completed"]] == tracked


# --------------------------------------------------------------------------
# headings too large to name a direction


def test_huge_initial_heading_is_refused():
    # at 1e300 rad neighbouring doubles are ~1e284 rad apart: the number
    # names no direction; at 1e6 rad they are 1e-10 rad apart
    assert np.spacing(1e300) > 2 * math.pi and np.spacing(1e6) < 1e-9
    veh = PAPER_VEHICLE
    g = fws.SteeringGains(0.1, 0.5, ratio=0.0)
    kw = dict(duration=1.0)
    plant = fws.LateralPlant(veh, speed=5.0)
    with pytest.raises(ValueError, match=r"initial_state heading psi .* 1e\+300"):
        fws.simulate(plant, fws.Straight(), g, initial_state=(0.0, 1.0, 1e300), **kw)
    with pytest.raises(ValueError, match="initial_state"):
        fws.simulate_batch(
            plant, fws.Straight(), g, initial_state=[(0, 1, 0), (0, 1, -1e300)], **kw
        )
    with pytest.raises(ValueError, match="initial_errors"):
        fws.compare_linear_nonlinear(
            fws.LateralPlant(veh, speed=5.0), g, initial_errors=(0.5, 1e300)
        )
    # a large heading that still names a direction runs, and is that direction
    turns = 1e5
    far = fws.simulate(
        plant, fws.Straight(), g, initial_state=(0.0, 1.0, 2 * math.pi * turns), **kw
    )
    near = fws.simulate(plant, fws.Straight(), g, initial_state=(0.0, 1.0, 0.0), **kw)
    np.testing.assert_allclose(far.e, near.e, atol=1e-8)


def test_cli_refuses_a_huge_psi0(tmp_path, capsys):
    out = tmp_path / "sim.png"
    with pytest.raises(SystemExit) as info:
        main(["simulate", "--psi0", "1e300", "--out", str(out)])
    code = info.value.code
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and not out.exists()
    assert len(err) == 1 and "--psi0" in err[0] and "1e+300" in err[0]
