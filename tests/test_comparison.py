"""Linear versus nonlinear responses."""

import math

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import fsolve

import fws_control as fws


@pytest.fixture
def plant(veh):
    return fws.LateralPlant(veh, speed=5.0, curvature=0.1)


@pytest.fixture
def design(plant):
    return fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)


def test_linear_part_is_matrix_exponential(plant, design):
    cmp = fws.compare_linear_nonlinear(
        plant, design, initial_errors=(0.3, 0.05), duration=6.0
    )
    assert (cmp.speed, cmp.curvature, cmp.model) == (5.0, 0.1, "kinematic")
    cl = fws.closed_loop(plant, design)
    x0 = np.array([0.3, 0.05])
    for i in (0, 50, 200, 599):
        t = cmp.linear.time[i]
        np.testing.assert_allclose(
            cmp.linear.outputs[:2, i], expm(cl.A * t) @ x0, atol=1e-9
        )
    # Same initial errors in both responses.
    np.testing.assert_allclose(cmp.initial_errors, (0.3, 0.05), atol=1e-12)
    np.testing.assert_allclose(cmp.nonlinear.t, cmp.linear.time)


def test_gap_is_second_order_in_the_initial_error(plant, design):
    gaps = []
    for e0 in (0.02, 0.04, 0.08):
        cmp = fws.compare_linear_nonlinear(
            plant, design, initial_errors=(e0, 0.0), duration=8.0
        )
        gaps.append(cmp.max_difference()["e"])
    ratios = np.array(gaps[1:]) / np.array(gaps[:-1])
    # Doubling e0 multiplies the linearisation error by ~4 (quadratic terms).
    np.testing.assert_allclose(ratios, 4.0, rtol=0.1)
    assert gaps[0] < 1e-3 * 0.02 * 10


def test_paper_model_prediction_is_worse_on_curves(veh):
    # Each model's own lambda0 = -1 design, predicted by its own linearisation:
    # the exact model tracks the nonlinear run closer than eq. (33) does.
    gaps = {}
    for model in ("kinematic", "paper"):
        plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1, model=model)
        g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
        cmp = fws.compare_linear_nonlinear(
            plant, g, initial_errors=(0.05, 0.0), duration=8.0
        )
        assert cmp.model == model
        gaps[model] = cmp.max_difference()["e"]
    assert gaps["kinematic"] < 0.2 * gaps["paper"]


def test_initial_state_and_initial_errors_agree(veh, plant, design):
    a = fws.compare_linear_nonlinear(
        plant, design, initial_state=(0.0, -5.0, 0.0), duration=3.0
    )
    # the Vehicle convenience keywords build the same plant
    b = fws.compare_linear_nonlinear(
        veh,
        design,
        initial_errors=(-5.0, 0.0),
        duration=3.0,
        speed=5.0,
        curvature=0.1,
    )
    np.testing.assert_allclose(a.nonlinear.e, b.nonlinear.e, atol=1e-9)
    np.testing.assert_allclose(a.linear.outputs, b.linear.outputs, atol=1e-12)


def test_feedback_only_offset(veh):
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.0, ratio=-1.0, pole=-1.0)
    kap, f = 0.1, veh.wheelbase
    curved = fws.LateralPlant(veh, speed=5.0, curvature=kap)
    cmp = fws.compare_linear_nonlinear(
        curved, g, initial_errors=(0.0, 0.0), duration=20.0, feedforward=False
    )
    assert cmp.feedforward is False

    # Nonlinear equilibrium from eqs. (18)-(19) without feedforward (fsolve):
    # sin(theta + d_r) = 0 and yaw rate = V kappa cos(theta + d_r)/(1 - kappa e).
    def residual(z):
        e, th = z
        df = -g.k1 * e - g.k2 * th
        dr = -1.0 * df
        return [
            math.sin(th + dr),
            math.sin(df - dr) / (f * math.cos(df))
            - kap * math.cos(th + dr) / (1 - kap * e),
        ]

    e_star, th_star = fsolve(residual, [-1.0, 0.0], xtol=1e-12)
    np.testing.assert_allclose(cmp.nonlinear.e[-1], e_star, atol=1e-4)
    np.testing.assert_allclose(cmp.nonlinear.theta[-1], th_star, atol=1e-5)
    # Linear prediction: steady state of the disturbance w = (-delta_ff, 0).
    cl = fws.closed_loop(curved, g)
    x_ss = -np.linalg.solve(cl.A, cl.B @ [-math.atan(kap * f), 0.0])
    np.testing.assert_allclose(cmp.linear.outputs[:2, -1], x_ss, atol=1e-6)
    assert np.sign(x_ss[0]) == np.sign(e_star)


def test_plot(veh, plant, design):
    cmp = fws.compare_linear_nonlinear(
        plant, design, initial_state=(0.0, -5.0, 0.0), duration=4.0
    )
    cplt = cmp.plot()
    assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == (1, 5)
    fig = cplt.figure
    assert len(fig.axes) == 5
    ax_e = cplt.axes[0, 0]
    assert ax_e.get_ylabel() == "lateral error e [m]"
    labels = [t.get_text() for t in ax_e.get_legend().get_texts()]
    assert any(s.startswith("nonlinear") for s in labels)
    assert any(s.startswith("linear") for s in labels)
    np.testing.assert_allclose(ax_e.lines[1].get_ydata(), cmp.linear.outputs[0])
    # Steering panel shows absolute angles: linear deviation + feedforward.
    ff = math.atan(0.1 * veh.wheelbase)
    np.testing.assert_allclose(
        cplt.axes[0, 2].lines[1].get_ydata(),
        np.degrees(cmp.linear.outputs[2] + ff),
    )
    plt.close(fig)
    # ax= draws into five given axes
    fig, given = plt.subplots(1, 5)
    out = cmp.plot(ax=given)
    assert list(out.axes.flat) == list(given)
    np.testing.assert_allclose(given[0].lines[0].get_ydata(), cmp.nonlinear.e)
    plt.close(fig)
    with pytest.raises(ValueError, match="5 axes"):
        cmp.plot(ax=given[:4])


def test_bad_input(veh, plant, design):
    with pytest.raises(ValueError, match="not both"):
        fws.compare_linear_nonlinear(
            plant, design, initial_state=(0, 0, 0), initial_errors=(0, 0)
        )
    with pytest.raises(TypeError, match="SteeringGains"):
        fws.compare_linear_nonlinear(plant, (0.1, 0.2))
    with pytest.raises(ValueError, match="duration"):
        fws.compare_linear_nonlinear(plant, design, duration=0.0)
    # the nonlinear run needs the vehicle: a state space is refused
    with pytest.raises(TypeError, match="LateralPlant"):
        fws.compare_linear_nonlinear(plant.linearize(), design)
    with pytest.raises(ValueError, match="one operating point"):
        fws.compare_linear_nonlinear(fws.LateralPlant(veh, speed=[5.0, 6.0]), design)
    with pytest.raises(TypeError, match="speed="):
        fws.compare_linear_nonlinear(veh, design)


def test_max_difference_refuses_a_run_that_stopped(veh, plant, design):
    # Issue 13 item 6: from e0 = 12 m beyond the centre of the 10 m arc the
    # nonlinear run stops at t = 0 (1 - kappa*e < 0); both responses share
    # the initial state, so the "gap" used to be all zeros.
    cmp = fws.compare_linear_nonlinear(plant, design, initial_errors=(12.0, 0.0))
    assert cmp.nonlinear.status != "ok" and cmp.nonlinear.t[-1] == 0.0
    with pytest.raises(ValueError, match=r"stopped at t = 0 s with status"):
        cmp.max_difference()
    # a run that reaches the end still compares (gap > 0 from e0 = 2 m)
    ok = fws.compare_linear_nonlinear(plant, design, initial_errors=(2.0, 0.0))
    assert ok.max_difference()["e"] > 0.0


@pytest.mark.parametrize("bad", ["False", 0, 1.0, None])
def test_feedforward_must_be_a_bool(plant, design, bad):
    # "False" is a true string: it used to run *with* feedforward
    with pytest.raises(TypeError, match="feedforward must be True or False"):
        fws.compare_linear_nonlinear(plant, design, feedforward=bad, duration=1.0)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(dt=float("nan")), "dt"),
        (dict(dt=-0.1), "dt"),
        (dict(dt=1e-9), "dt"),
        (dict(duration=float("inf")), "duration"),
        (dict(initial_errors=(1.0, 0.0, 3.0)), "initial_errors"),
        (dict(initial_errors=(True, 0.0)), "initial_errors"),
    ],
)
def test_bad_values_name_the_argument(plant, design, kwargs, name):
    with pytest.raises((ValueError, TypeError), match=name):
        fws.compare_linear_nonlinear(plant, design, **kwargs)
