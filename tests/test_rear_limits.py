r"""Rear steering limits: the band of ratios and saturation on a run.

References: hand-derived numbers (|a| <= L/|delta_f|; the command at t = 0
is -k1 e0, the rear one a times it) and the linear double-root loop written
here in closed form, x(t) = e^{lambda t}(x0 + t (A_cl - lambda I) x0).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import fws_control as fws

F = 2.7
VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)


def test_band_hand_numbers():
    band = fws.rear_limit_band(
        VEH, front_angle=np.radians([10.0, 20.0, 0.0, -5.0]), rear_limit=np.radians(5.0)
    )
    np.testing.assert_allclose(band.high[[0, 1, 3]], [0.5, 0.25, 1.0], rtol=1e-14)
    np.testing.assert_allclose(band.low, -band.high)
    assert band.high[2] == math.inf
    assert band.allows(0.5).tolist() == [True, False, True, True]
    assert band.allows(-0.26).tolist() == [True, False, True, True]


def test_band_takes_the_vehicle_limit():
    # Porsche-like 2.8 deg rear limit at 20 deg front: |a| <= 0.14
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35, max_steer_rear=np.radians(2.8))
    band = fws.rear_limit_band(veh, front_angle=np.radians(20.0))
    assert float(band.high) == pytest.approx(0.14, rel=1e-14)
    assert band.rear_limit == pytest.approx(np.radians(2.8), rel=1e-15)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"front_angle": 0.1}, "rear_limit"),
        ({"front_angle": 0.1, "rear_limit": 0.0}, "rear_limit"),
        ({"front_angle": 0.1, "rear_limit": 2.0}, "rear_limit"),
        ({"front_angle": 1.6, "rear_limit": 0.05}, "front_angle"),
        ({"front_angle": np.nan, "rear_limit": 0.05}, "front_angle"),
    ],
)
def test_band_refuses_bad_input(kwargs, words):
    with pytest.raises(ValueError, match=words):
        fws.rear_limit_band(VEH, **kwargs)


def _double_root_run(vehicle, e0=0.5):
    plant = fws.LateralPlant(VEH, speed=5.0)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    res = fws.simulate(
        fws.LateralPlant(vehicle, speed=5.0), fws.Straight(), g,
        initial_state=(0.0, e0, 0.0), duration=8.0, dt=0.005,
    )  # fmt: skip
    return g, res


def test_saturation_against_the_linear_double_root_loop():
    e0, limit = 0.5, 0.02
    g, res = _double_root_run(VEH, e0)
    sat = fws.rear_saturation(res, rear_limit=limit)
    # t = 0: delta_f = -k1 e0, delta_r = a delta_f: |a| k1 e0 = 0.054 * 0.5
    assert float(g.k1) == pytest.approx(0.054, rel=1e-12)
    assert sat.peak == pytest.approx(0.027, rel=1e-9)
    assert sat.peak_time == pytest.approx(0.0, abs=1e-12)
    assert sat.saturates
    # linear loop (a = -1, straight): e' = V theta + V a u, theta' = V/f (1 - a) u,
    # u = -k1 e - k2 theta, double root -1: u(t) = e^{-t}(u0 + t K (A_cl + I) x0)
    V, a = 5.0, -1.0
    b = np.array([V * a, V * (1 - a) / F])
    K = np.array([float(g.k1), float(g.k2)])
    Acl = np.array([[0.0, V], [0.0, 0.0]]) - np.outer(b, K)
    np.testing.assert_allclose(np.linalg.eigvals(Acl), [-1.0, -1.0], atol=1e-6)
    x0 = np.array([e0, 0.0])
    c = -K @ (Acl + np.eye(2)) @ x0

    def rear(t):
        return abs(a * math.exp(-t) * (-K @ x0 + t * c)) - limit

    t_cross = brentq(rear, 0.0, 3.0, xtol=1e-14)
    # nonlinear run, 0.5 m start: the linear crossing to 1 %
    assert sat.time_above == pytest.approx(t_cross, rel=1e-2)


def test_a_clipped_run_reports_the_time_at_the_limit():
    limit = 0.02
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35, max_steer_rear=limit)
    _, free = _double_root_run(VEH)
    _, clipped = _double_root_run(veh)
    sat = fws.rear_saturation(clipped)  # the limit from the vehicle
    assert sat.rear_limit == limit
    assert sat.saturates and sat.peak == pytest.approx(limit, rel=1e-9)
    free_sat = fws.rear_saturation(free, rear_limit=limit)
    # clipping slows the correction, so the command stays at the limit
    # at least as long as the free command stays above it
    assert sat.time_above >= free_sat.time_above - 0.01


def test_unsaturated_run():
    _, res = _double_root_run(VEH)
    sat = fws.rear_saturation(res, rear_limit=0.03)
    assert not sat.saturates and sat.time_above == 0.0


def test_saturation_refuses_bad_input():
    _, res = _double_root_run(VEH)
    with pytest.raises(TypeError, match="result"):
        fws.rear_saturation("run", rear_limit=0.02)
    with pytest.raises(ValueError, match="rear_limit"):
        fws.rear_saturation(res)  # the vehicle has no rear limit
    with pytest.raises(ValueError, match="rear_limit"):
        fws.rear_saturation(res, rear_limit=-0.1)


def test_band_plot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    band = fws.rear_limit_band(
        VEH, front_angle=np.radians(np.linspace(1.0, 30.0, 30)), rear_limit=0.05
    )
    cplt = band.plot()
    try:
        ax = cplt.axes[0, 0]
        assert ax.get_ylabel() == "ratio $a$ [-]"
        assert ax.get_ylim() == (-2.0, 2.0)
    finally:
        plt.close(cplt.figure)
