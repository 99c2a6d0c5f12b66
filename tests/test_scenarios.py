"""The paper's scenarios as data: set-up, gains, sweeps, feedback-only steady state."""

import math

import numpy as np
import pytest

import fws_control as fws
from fws_control.paper import FIG5_RATIOS, PAPER_VEHICLE
from fws_control.paper.scenarios import (
    PAPER_SCENARIOS,
    feedback_only_curve,
    feedback_only_steady_state,
    fig5_peak_lateral_accel,
    fig6_to_9_responses,
    paper_scenario,
    scenario_gains,
    scenario_responses,
)
from fws_control.paths import Arc, Straight


def test_scenarios_are_the_papers():
    # section 4.3: f = 2.7 m, d = 1.35 m; initial positions and controllers
    assert (PAPER_VEHICLE.wheelbase, PAPER_VEHICLE.rear_to_cg) == (2.7, 1.35)
    expect = {
        "straight_5": (5.0, 0.0, (0.0, 2.0, 0.0), False, 6),
        "curve_5": (5.0, 0.1, (0.0, -5.0, 0.0), True, 7),
        "straight_20": (20.0, 0.0, (0.0, 2.0, 0.0), False, 8),
        "curve_20": (20.0, 0.01, (0.0, -10.0, 0.0), True, 9),
    }
    for name, (V, k, x0, ff, fig) in expect.items():
        sc = paper_scenario(name)
        assert (sc.speed, sc.curvature, sc.initial_state, sc.feedforward) == (
            V,
            k,
            x0,
            ff,
        )
        assert sc.figure == fig
    assert isinstance(PAPER_SCENARIOS["straight_5"].path, Straight)
    arc = PAPER_SCENARIOS["curve_20"].path
    assert isinstance(arc, Arc) and arc.center == pytest.approx((0.0, 100.0))
    # e0 from the projection: 2, -5, 2, -10 as in the design notes
    for name, e0 in zip(PAPER_SCENARIOS, (2.0, -5.0, 2.0, -10.0), strict=True):
        sc = PAPER_SCENARIOS[name]
        assert float(sc.path.project(*sc.initial_state[:2]).e) == pytest.approx(e0)
    with pytest.raises(ValueError, match="curve_5"):
        paper_scenario("curve_7")
    np.testing.assert_allclose(FIG5_RATIOS[[0, 30, 50, -1]], [-1.5, 0.0, 1.0, 1.5])


def test_scenario_gains_mark_only_a_equal_one_on_straight_roads():
    ratios = np.array([-1.5, 0.0, 0.5, 1.0, 1.5])
    for name, sc in PAPER_SCENARIOS.items():
        for model in ("kinematic", "paper"):
            k1, k2, ok = scenario_gains(name, ratios, -1.0, model)
            expect_ok = ~((ratios == 1.0) & (sc.curvature == 0.0))
            np.testing.assert_array_equal(ok, expect_ok)
            for i in np.flatnonzero(ok):
                plant = fws.LateralPlant(
                    PAPER_VEHICLE, speed=sc.speed, curvature=sc.curvature, model=model
                )
                g = fws.double_root_gains(plant, ratio=ratios[i], pole=-1.0)
                assert (k1[i], k2[i]) == (g.k1, g.k2)
            assert np.all(np.isnan(k1[~ok]))


def test_scenario_gains_sweep_through_ratio_one_equals_one_design_per_ratio():
    # the vectorised sweep (halved around refused designs) against one
    # scalar double_root_gains per element, on a 2-D grid of ratios and
    # poles that crosses ratio = 1 (and its refused neighbours) several times
    ratios = np.linspace(0.9, 1.1, 41).reshape(-1, 1) + np.zeros((1, 3))
    poles = np.array([-0.5, -1.0, -3.0])
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, curvature=0.0, model="kinematic")
    k1, k2, ok = scenario_gains("straight_5", ratios, poles, "kinematic")
    assert k1.shape == ratios.shape and 0 < (~ok).sum() < ok.size
    for idx in np.ndindex(ratios.shape):
        try:
            g = fws.double_root_gains(plant, ratio=ratios[idx], pole=poles[idx[1]])
        except fws.UncontrollableError:
            assert not ok[idx] and np.isnan(k1[idx]) and np.isnan(k2[idx])
            continue
        assert ok[idx] and (k1[idx], k2[idx]) == (float(g.k1), float(g.k2))


def test_scenario_responses_keep_uncontrollable_rows_and_match_simulate():
    r = scenario_responses(
        "straight_20", ratios=[-1.0, 1.0, 0.5], duration=4.0, dt=0.05
    )
    res = r.result
    assert res.status.tolist() == ["ok", "uncontrollable", "ok"]
    assert np.all(np.isnan(res.e[1])) and math.isnan(res.k1[1])
    assert math.isnan(res.t_stop[1])  # never simulated
    assert "uncontrollable" in res.message[1]
    assert r.feedforward is False and r.ratios.tolist() == [-1.0, 1.0, 0.5]
    for i in (0, 2):
        g = fws.double_root_gains(
            PAPER_VEHICLE, speed=20.0, curvature=0.0, ratio=r.ratios[i], pole=-1.0
        )
        single = fws.simulate(
            fws.LateralPlant(PAPER_VEHICLE, speed=20.0),
            Straight(),
            g,
            initial_state=(0, 2, 0),
            duration=4.0,
            feedforward=False,
            dt=0.05,
        )
        np.testing.assert_allclose(res.e[i], single.e, rtol=0, atol=1e-6)
        assert (res.k1[i], res.k2[i]) == (g.k1, g.k2)
    assert res[1].gains is None and res[1].t.size == 0
    # the result is a batch (not squeezed) and keeps every run's design
    assert not res.squeeze and res.ratio.tolist() == [-1.0, 1.0, 0.5]
    assert res.speed.tolist() == [20.0] * 3
    df = res.to_pandas()
    assert df.groupby("run")["ratio"].first().tolist() == [-1.0, 1.0, 0.5]
    assert df.loc[df["run"] == 1, "status"].tolist() == ["uncontrollable"]


def test_fig5_peaks_match_single_simulations_and_flag_stopped_runs():
    ratios = [-1.0, 0.9, 1.0]
    fig5 = fig5_peak_lateral_accel(ratios=ratios, duration=4.0, dt=0.01)
    assert set(fig5) == {"a", "b", "c", "d"}
    a = fig5["a"]
    assert a.peak_lateral_accel.shape == (2, 3) and a.poles.tolist() == [-1.0, -2.0]
    assert fig5["c"].poles.tolist() == [-1.0, -2.0, -3.0]
    assert a.status[:, 2].tolist() == ["uncontrollable"] * 2
    # a = 0.9 at 5 m/s: k1 = f lam^2/(V^2 (1-a)) makes |delta_f(0)| = 2 k1 > pi/2
    assert 2 * a.k1[0, 1] > math.pi / 2
    assert a.status[0, 1] == "singular_steering" and a.t_stop[0, 1] == 0.0
    assert np.isnan(a.peak_lateral_accel[0, 1])
    # an ok point equals the peak of the single simulation
    sc = PAPER_SCENARIOS["curve_20"]
    for j, lam in enumerate(fig5["d"].poles):
        g = fws.double_root_gains(
            PAPER_VEHICLE, speed=20.0, curvature=0.01, ratio=-1.0, pole=lam
        )
        single = fws.simulate(
            fws.LateralPlant(PAPER_VEHICLE, speed=20.0),
            sc.path,
            g,
            initial_state=sc.initial_state,
            duration=4.0,
            dt=0.01,
        )
        assert fig5["d"].status[j, 0] == "ok"
        assert fig5["d"].peak_lateral_accel[j, 0] == pytest.approx(
            np.max(np.abs(single.lateral_accel)), abs=1e-6
        )


def test_fig6_to_9_uses_the_papers_controllers_and_model_gains():
    exact = fig6_to_9_responses(duration=1.0, dt=0.1)
    paper = fig6_to_9_responses(model="paper", duration=1.0, dt=0.1)
    assert list(exact) == [6, 7, 8, 9]
    assert [exact[k].feedforward for k in exact] == [False, True, False, True]
    assert exact[6].result.status.tolist()[-1] == "uncontrollable"
    # on the straight road both linearisations coincide; on a curve they differ
    np.testing.assert_array_equal(exact[8].result.k1, paper[8].result.k1)
    assert not np.allclose(exact[7].result.k1, paper[7].result.k1)


def _path_frame_rates(vehicle, kappa, e, theta, df, dr, V=5.0):
    sys = fws.path_frame_model(vehicle, speed=V, curvature=kappa)
    return sys.dynamics(0.0, [0.0, e, theta], [df, dr])


def test_feedback_only_steady_state_is_an_equilibrium_of_the_model():
    ratios = np.array([-1.0, -0.5, 0.0, 0.5])
    for V, kappa in ((5.0, 0.1), (20.0, 0.01)):
        g = fws.double_root_gains(
            PAPER_VEHICLE, speed=V, curvature=kappa, ratio=ratios, pole=-1.0
        )
        ss = feedback_only_steady_state(PAPER_VEHICLE, g, curvature=kappa)
        assert np.all(ss.exists)
        for i in range(ratios.size):
            gi = fws.SteeringGains(g.k1[i], g.k2[i], g.ratio[i])
            df, dr = fws.steering_command(
                PAPER_VEHICLE,
                gi,
                ss.e[i],
                ss.theta[i],
                curvature=kappa,
                feedforward=False,
            )
            assert (float(df), float(dr)) == pytest.approx(
                (ss.delta_f[i], ss.delta_r[i])
            )
            rates = _path_frame_rates(
                PAPER_VEHICLE, kappa, ss.e[i], ss.theta[i], df, dr, V
            )
            np.testing.assert_allclose(rates[1:], [0.0, 0.0], atol=1e-12)
            assert abs(ss.e[i]) > 0.5  # a real steady-state error
    # a = 1: delta_f = delta_r, no yaw, no equilibrium on a circle
    g1 = fws.SteeringGains(0.3, 0.5, 1.0)
    assert not feedback_only_steady_state(PAPER_VEHICLE, g1, curvature=0.1).exists


def test_feedback_only_simulation_converges_to_the_analytic_steady_state():
    fb = feedback_only_curve("curve_5", ratios=[-1.0, 0.0, 0.5, 1.0], duration=40.0)
    res = fb.responses.result
    assert fb.responses.feedforward is False
    ok = res.status == "ok"
    assert ok.tolist() == [True, True, True, False]  # a = 1 is singular
    np.testing.assert_allclose(res.e[ok, -1], fb.steady_state.e[ok], atol=1e-6)
    np.testing.assert_allclose(res.theta[ok, -1], fb.steady_state.theta[ok], atol=1e-6)
    with pytest.raises(ValueError, match="curve"):
        feedback_only_curve("straight_5")
