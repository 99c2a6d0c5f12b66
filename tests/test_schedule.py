r"""Speed schedules of most-stable gains (schedule_gains, GainSchedule).

References: the interpolation rule evaluated by hand; the speed invariance
of the delayed two-state loop :math:`s^2 + e^{-s\tau}(V k_2 s + V^2 k_1)/f`
(constant :math:`k_1 V^2`, :math:`k_2 V` give the same roots at every
speed); the rightmost root from a 12th-order :func:`control.pade` of the
delay and the eigenvalues of the closed loop, with matrices written here.
"""

from __future__ import annotations

import control as ct
import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws

F = 2.7
VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
TAU = 0.24


def pade_abscissa(speed, k1, k2, tau=TAU):
    """Rightmost real part of the straight kinematic loop (a = 0), Pade(12)."""
    A = np.array([[0.0, speed], [0.0, 0.0]])
    b = np.array([0.0, speed / F])
    num, den = ct.pade(tau, 12)
    P = ct.ss(ct.tf(num, den))
    PA, PB, PC, PD = (np.asarray(m) for m in (P.A, P.B, P.C, P.D))
    K = np.array([k1, k2])
    top = np.hstack([A - PD[0, 0] * np.outer(b, K), np.outer(b, PC[0])])
    bottom = np.hstack([-np.outer(PB[:, 0], K), PA])
    return float(np.max(np.linalg.eigvals(np.vstack([top, bottom])).real))


@pytest.fixture(scope="module")
def schedule():
    # grid 4 (the smallest start grid; 6 is the default) reaches the same
    # optimum: abscissas 1.5e-6 relative apart (1.8e-6 with 6), Pade
    # differences <= 2e-8 at the grid and 1.1e-6 between, as with 6; each
    # search costs 0.6 of one from grid 6
    return fws.schedule_gains(VEH, speeds=[10.0, 20.0, 30.0], delay=TAU, grid=4)


def test_scaled_gains_are_constant_for_the_two_state_loop(schedule):
    V = schedule.speeds
    np.testing.assert_allclose(
        schedule.k1 * V**2, schedule.k1[0] * V[0] ** 2, rtol=1e-4
    )
    np.testing.assert_allclose(schedule.k2 * V, schedule.k2[0] * V[0], rtol=1e-4)
    # at the optimum roots coalesce, where the abscissa moves as a fractional
    # power of the gains' error: each speed's search stops on its own path
    # (measured 1.4e-6 relative apart); the Pade check below is to 1e-6
    np.testing.assert_allclose(schedule.abscissa, schedule.abscissa[0], rtol=1e-5)
    for v, k1, k2, alpha in zip(
        V, schedule.k1, schedule.k2, schedule.abscissa, strict=True
    ):
        assert pade_abscissa(v, k1, k2) == pytest.approx(alpha, abs=1e-6)
    assert np.all(schedule.ratio == 0.0)
    assert schedule.delay == TAU
    assert len(schedule.designs) == 3 and all(d.certified for d in schedule.designs)


def test_interpolated_gains_are_the_optimum_between_grid_speeds(schedule):
    # k1 V^2 and k2 V are what the interpolation holds: at 15 and 25 m/s the
    # interpolated gains have the grid's abscissa
    for v in (15.0, 25.0):
        g = schedule.at(v)
        assert pade_abscissa(v, g.k1, g.k2) == pytest.approx(
            schedule.abscissa[0], abs=1e-5
        )


def test_at_grid_speeds_returns_the_designs(schedule):
    for v, d in zip(schedule.speeds, schedule.designs, strict=True):
        g = schedule.at(v)
        assert g.k1 == pytest.approx(float(d.gains.k1), rel=1e-14)
        assert g.k2 == pytest.approx(float(d.gains.k2), rel=1e-14)


def test_interpolation_rule_by_hand():
    sch = fws.GainSchedule(
        speeds=[10.0, 20.0, 40.0], k1=[0.01, 0.004, 0.0005], k2=[0.3, 0.2, 0.05],
        ratio=[0.0, 0.2, -0.2],
    )  # fmt: skip
    # 30 m/s, halfway between 20 and 40: k1 V^2 = (1.6 + 0.8)/2 = 1.2,
    # k2 V = (4 + 2)/2 = 3, a = 0
    g = sch.at(30.0)
    assert g.k1 == pytest.approx(1.2 / 900.0, rel=1e-14)
    assert g.k2 == pytest.approx(3.0 / 30.0, rel=1e-14)
    assert g.ratio == pytest.approx(0.0, abs=1e-15)
    # 12.5 m/s: a quarter from 10 to 20: k1 V^2 = 1 + 0.6/4 = 1.15
    g = sch.at(np.array([12.5, 40.0]))
    np.testing.assert_allclose(g.k1, [1.15 / 156.25, 0.0005], rtol=1e-14)
    np.testing.assert_allclose(g.ratio, [0.05, -0.2], rtol=1e-14)


@pytest.mark.parametrize("speed", [9.99, 40.01, np.nan, [15.0, 50.0]])
def test_no_extrapolation(speed):
    sch = fws.GainSchedule(speeds=[10.0, 40.0], k1=[0.01, 0.001], k2=[0.3, 0.1],
                           ratio=[0.0, 0.0])  # fmt: skip
    with pytest.raises(ValueError, match="speed"):
        sch.at(speed)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"speeds": [10.0]}, "speeds"),
        ({"speeds": [20.0, 10.0]}, "increasing"),
        ({"speeds": [-10.0, 10.0]}, "sign"),
        ({"k1": [0.01]}, "k1"),
        ({"k2": [0.3, np.inf]}, "k2"),
    ],
)
def test_bad_schedules_are_refused(kwargs, words):
    base = dict(speeds=[10.0, 20.0], k1=[0.01, 0.004], k2=[0.3, 0.2], ratio=[0, 0])
    with pytest.raises(ValueError, match=words):
        fws.GainSchedule(**{**base, **kwargs})


def test_schedule_gains_refuses_bad_input():
    with pytest.raises(TypeError, match="plant"):
        fws.schedule_gains("car", speeds=[10.0, 20.0], delay=TAU)
    with pytest.raises(ValueError, match="speeds"):
        fws.schedule_gains(VEH, speeds=[20.0, 10.0], delay=TAU)
    with pytest.raises(ValueError, match="delay"):
        fws.schedule_gains(VEH, speeds=[10.0, 20.0], delay=0.0)


def test_plant_kinds_agree():
    # a LateralPlant whose speed is replaced, and a function speed -> plant
    plant = fws.LateralPlant(VEH, speed=5.0)
    a = fws.schedule_gains(plant, speeds=[10.0, 20.0], delay=TAU, grid=4)
    b = fws.schedule_gains(
        lambda v: fws.LateralPlant(VEH, speed=v), speeds=[10.0, 20.0], delay=TAU,
        grid=4,
    )  # fmt: skip
    np.testing.assert_allclose(a.k1, b.k1, rtol=1e-12)
    np.testing.assert_allclose(a.k2, b.k2, rtol=1e-12)


def test_plot_has_units(schedule):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cplt = schedule.plot()
    try:
        ax = cplt.axes
        assert ax.shape == (2, 2)
        assert ax[0, 0].get_ylabel() == "$k_1$ [rad/m]"
        assert ax[1, 1].get_xlabel() == "speed V [m/s]"
        np.testing.assert_allclose(ax[1, 1].lines[0].get_ydata(), schedule.abscissa)
    finally:
        plt.close(cplt.figure)


def test_simulators_read_a_schedule_at_the_plant_speed():
    # a schedule is run as its gains at the run's speed: bit for bit the
    # run of sch.at(V), for one run and per run of a batch
    sch = fws.GainSchedule(
        speeds=[5.0, 25.0], k1=[0.05, 0.002], k2=[0.5, 0.1], ratio=[-0.5, 0.2]
    )
    veh = PAPER_VEHICLE
    kw = dict(initial_state=(0.0, 0.5, 0.0), duration=3.0, dt=0.05)
    path = fws.Straight()
    one = fws.simulate(fws.LateralPlant(veh, speed=12.0), path, sch, **kw)
    ref = fws.simulate(fws.LateralPlant(veh, speed=12.0), path, sch.at(12.0), **kw)
    np.testing.assert_array_equal(one.e, ref.e)
    # the interpolation itself: k1 V^2 and k2 V linear in V, by hand
    w = (12.0 - 5.0) / 20.0
    assert ref.k1 * 144.0 == pytest.approx((1 - w) * 0.05 * 25 + w * 0.002 * 625)
    speeds = np.array([6.0, 20.0])
    batch = fws.simulate_batch(fws.LateralPlant(veh, speed=speeds), path, sch, **kw)
    for i, V in enumerate(speeds):
        alone = fws.simulate(fws.LateralPlant(veh, speed=V), path, sch.at(V), **kw)
        np.testing.assert_allclose(batch.e[i], alone.e, rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="speed must lie in the schedule's range"):
        fws.simulate(fws.LateralPlant(veh, speed=30.0), path, sch, **kw)
