"""Controllers: control law, chain-rule rates, saturation, blocks, actuator."""

import math

import control as ct
import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from hypothesis import given
from hypothesis import strategies as st

import fws_control as fws
from fws_control.controllers import actuator_rate

VEH = PAPER_VEHICLE
finite = st.floats(-3.0, 3.0, allow_nan=False)


@given(e=finite, theta=st.floats(-1, 1), kappa=st.floats(-0.2, 0.2), a=finite)
def test_command_matches_paper_equations(e, theta, kappa, a):
    g = fws.SteeringGains(k1=0.3, k2=0.7, ratio=a)
    df, dr = fws.steering_command(VEH, g, e, theta, curvature=kappa)
    # eqs. (24)-(29) written out by hand
    fb_f = -0.3 * e - 0.7 * theta
    assert float(df) == pytest.approx(math.atan(kappa * 2.7) + fb_f, abs=1e-14)
    assert float(dr) == pytest.approx(-a * 0.3 * e - a * 0.7 * theta, abs=1e-14)
    df0, dr0 = fws.steering_command(
        VEH, g, e, theta, curvature=kappa, feedforward=False
    )
    assert float(df0) == pytest.approx(fb_f, abs=1e-14)
    assert float(dr0) == float(dr)


def test_command_broadcasts_over_gains_and_errors():
    g = fws.SteeringGains(k1=np.array([0.1, 0.2, 0.3]), k2=0.5, ratio=-1.0)
    e = np.array([[1.0], [2.0]])
    df, dr = fws.steering_command(VEH, g, e, 0.0)  # curvature defaults to 0
    assert df.shape == dr.shape == (2, 3)
    np.testing.assert_allclose(df, -np.outer([1.0, 2.0], [0.1, 0.2, 0.3]))
    np.testing.assert_allclose(dr, -df)


def test_no_saturation_without_limits_and_clip_with_limits():
    g = fws.SteeringGains(k1=1.0, k2=0.0, ratio=0.5)
    df, dr = fws.steering_command(VEH, g, -1.4, 0.0, curvature=0.0)
    assert (float(df), float(dr)) == (1.4, 0.7)  # beyond any plausible limit
    lim = fws.Vehicle(2.7, 1.35, max_steer_front=0.5, max_steer_rear=0.2)
    df, dr = fws.steering_command(lim, g, np.array([-1.4, 1.4, 0.1]), 0.0)
    np.testing.assert_array_equal(df, [0.5, -0.5, -0.1])
    np.testing.assert_array_equal(dr, [0.2, -0.2, -0.05])


def _signals(t):
    """Smooth error and curvature histories used to test the chain rule."""
    e = 1.5 * np.sin(0.7 * t) + 0.2
    th = 0.3 * np.cos(1.3 * t)
    kap = 0.1 * np.sin(0.4 * t)
    return e, th, kap


def _command(vehicle, g, t, feedforward=True):
    e, th, kap = _signals(t)
    return fws.steering_command(
        vehicle, g, e, th, curvature=kap, feedforward=feedforward
    )


@pytest.mark.parametrize("feedforward", [True, False])
def test_command_rate_matches_finite_differences(feedforward):
    g = fws.SteeringGains(k1=0.4, k2=0.9, ratio=-0.6)
    t = np.linspace(0.0, 10.0, 201)
    h = 1e-5
    e, th, kap = _signals(t)
    e_rate = (_signals(t + h)[0] - _signals(t - h)[0]) / (2 * h)
    th_rate = (_signals(t + h)[1] - _signals(t - h)[1]) / (2 * h)
    kap_rate = (_signals(t + h)[2] - _signals(t - h)[2]) / (2 * h)
    rf, rr = fws.steering_command_rate(
        VEH,
        g,
        e,
        th,
        e_rate,
        th_rate,
        curvature=kap,
        curvature_rate=kap_rate,
        feedforward=feedforward,
    )
    plus = _command(VEH, g, t + h, feedforward)
    minus = _command(VEH, g, t - h, feedforward)
    np.testing.assert_allclose(rf, (plus[0] - minus[0]) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(rr, (plus[1] - minus[1]) / (2 * h), atol=1e-8)


def test_command_rate_is_zero_where_saturated():
    lim = fws.Vehicle(2.7, 1.35, max_steer_front=0.3, max_steer_rear=0.1)
    g = fws.SteeringGains(k1=0.4, k2=0.9, ratio=-0.6)
    t = np.linspace(0.0, 10.0, 401)
    h = 1e-6
    e, th, kap = _signals(t)
    e_rate, th_rate, kap_rate = (
        (a - b) / (2 * h) for a, b in zip(_signals(t + h), _signals(t - h), strict=True)
    )
    rf, rr = fws.steering_command_rate(
        lim, g, e, th, e_rate, th_rate, curvature=kap, curvature_rate=kap_rate
    )
    plus = _command(lim, g, t + h)
    minus = _command(lim, g, t - h)
    fd_f = (plus[0] - minus[0]) / (2 * h)
    fd_r = (plus[1] - minus[1]) / (2 * h)
    # Away from the switching instants the derivative of the clipped signal
    # is the finite difference; both channels do saturate somewhere.
    smooth_f = np.abs(np.abs(_command(lim, g, t)[0]) - 0.3) > 1e-4
    smooth_r = np.abs(np.abs(_command(lim, g, t)[1]) - 0.1) > 1e-4
    assert np.any(rf == 0.0) and np.any(rr == 0.0)
    np.testing.assert_allclose(rf[smooth_f], fd_f[smooth_f], atol=1e-6)
    np.testing.assert_allclose(rr[smooth_r], fd_r[smooth_r], atol=1e-6)


def test_blocks_wrap_the_same_law_and_accept_params():
    g = fws.SteeringGains(k1=0.2, k2=0.6, ratio=0.4)
    u = [0.7, -0.1, 0.05]
    ff = fws.feedforward_feedback_controller(VEH, g)
    fb = fws.feedback_controller(VEH, g)
    assert ff.nstates == fb.nstates == 0
    assert ff.input_labels == ["e", "theta", "curvature"]
    # eqs. (24)-(29) by hand: feedback -k1 e - k2 theta, rear = a * feedback
    fb_ref = -0.2 * u[0] - 0.6 * u[1]
    ff_ref = math.atan(2.7 * u[2])
    np.testing.assert_allclose(
        ff.output(0.0, [], u), [ff_ref + fb_ref, 0.4 * fb_ref], atol=1e-15
    )
    np.testing.assert_allclose(
        ff.output(0.0, [], u),
        fws.steering_command(VEH, g, u[0], u[1], curvature=u[2]),
        atol=1e-15,
    )
    np.testing.assert_allclose(
        fb.output(0.0, [], u), [fb_ref, 0.4 * fb_ref], atol=1e-15
    )
    np.testing.assert_allclose(
        fws.path_tracking_controller(VEH, g, feedforward=False).output(0.0, [], u),
        fb.output(0.0, [], u),
        atol=0,
    )
    assert fws.path_tracking_controller(VEH, g, name="ctl").name == "ctl"
    # per-call parameters, as ct.input_output_response(params=...) passes them
    out = ff.output(0.0, [], u, params={"k1": 1.0, "k2": 0.0, "ratio": 0.0})
    np.testing.assert_allclose(out, [ff_ref - 1.0 * u[0], 0.0], atol=1e-15)


def test_block_rejects_wrong_gains():
    with pytest.raises(TypeError, match="SteeringGains"):
        fws.path_tracking_controller(VEH, (0.1, 0.2, 0.0))
    with pytest.raises(ValueError, match="scalar"):
        fws.path_tracking_controller(VEH, fws.SteeringGains([0.1, 0.2], 0.5, 0.0))


def test_actuator_rate_clips_each_channel():
    veh = fws.Vehicle(2.7, 1.35, max_steer_rate_front=0.5)
    rf, rr = actuator_rate(
        veh, np.array([1.0, 1.0]), np.array([0.0, 0.0]), time_constant=0.1
    )
    assert (float(rf), float(rr)) == (0.5, 10.0)  # rear has no limit


def test_actuator_step_response_matches_closed_form():
    """Ramp at the rate limit, then the first-order lag (solved by hand)."""
    rmax, tau, c = 0.5, 0.1, 0.4
    veh = fws.Vehicle(2.7, 1.35, max_steer_rate_front=rmax, max_steer_rate_rear=rmax)
    act = fws.steering_actuator(veh, steering_lag=tau)
    t = np.linspace(0.0, 2.0, 401)
    resp = ct.input_output_response(
        act,
        t,
        inputs=np.vstack([np.full_like(t, c), np.full_like(t, 0.02)]),
        initial_state=[0.0, 0.0],
        solve_ivp_method="LSODA",
        solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12, "max_step": 0.01},
    )
    t1 = (c - tau * rmax) / rmax  # the rate limit stops binding here
    expect = np.where(t < t1, rmax * t, c - tau * rmax * np.exp(-(t - t1) / tau))
    np.testing.assert_allclose(resp.outputs[0], expect, atol=1e-7)
    # a small step never reaches the rate limit: pure lag
    np.testing.assert_allclose(
        resp.outputs[1], 0.02 * (1 - np.exp(-t / tau)), atol=1e-9
    )


def test_actuator_time_constant_must_be_positive():
    with pytest.raises(ValueError, match="steering_lag"):
        fws.steering_actuator(VEH, steering_lag=0.0)


# -- issue 13 item 7: types, non-finite values, flags, magnitudes -------------

_G = fws.SteeringGains(0.1, 0.5, ratio=-1.0)
_V = PAPER_VEHICLE


@pytest.mark.parametrize(
    "call, name, exc",
    [
        (lambda: fws.yaw_rate(_V, float("nan"), 0.0, speed=5.0), "delta_f", ValueError),
        (lambda: fws.yaw_rate(_V, 0.1, None, speed=5.0), "delta_r", ValueError),
        (lambda: fws.yaw_rate(_V, 0.1, 0.0, speed=float("inf")), "speed", ValueError),
        (lambda: fws.yaw_rate(_V, True, 0.0, speed=5.0), "delta_f", TypeError),
        (lambda: fws.yaw_rate(_V, 0.1 + 1j, 0.0, speed=5.0), "delta_f", TypeError),
        # V sin(1.5)/(f cos(1.5)) = 5.2e308 overflows
        (lambda: fws.yaw_rate(_V, 1.5, 0.0, speed=1e308), "speed", ValueError),
        (lambda: fws.yaw_rate("veh", 0.1, 0.0, speed=5.0), "vehicle", TypeError),
        (lambda: fws.feedforward_steering(None, curvature=0.1), "vehicle", TypeError),
        (
            lambda: fws.lateral_acceleration(
                _V, 0.1, 0.0, float("nan"), 0.0, speed=5.0
            ),
            "delta_f_rate",
            ValueError,
        ),
        (
            lambda: fws.yaw_acceleration(_V, 0.1, 0.0, 0.0, None, speed=5.0),
            "delta_r_rate",
            ValueError,
        ),
        (lambda: fws.steering_command(_V, _G, float("nan"), 0.0), "e", ValueError),
        (lambda: fws.steering_command(_V, _G, 0.0, None), "theta", ValueError),
        (
            lambda: fws.steering_command(_V, fws.SteeringGains(10, 0, 0), 1e308, 0.0),
            "e",
            ValueError,
        ),
        (lambda: fws.steering_command(_V, "g", 0.0, 0.0), "gains", TypeError),
        (lambda: fws.steering_command(3.0, _G, 0.0, 0.0), "vehicle", TypeError),
        (
            # a string is a valid type ("kinematic", "dynamic"); "False" is not
            # one of the values
            lambda: fws.steering_command(_V, _G, 1.0, 0.0, feedforward="False"),
            "feedforward",
            ValueError,
        ),
        (
            lambda: fws.steering_command(_V, _G, 1.0, 0.0, feedforward=1j),
            "feedforward",
            TypeError,
        ),
        (
            lambda: fws.steering_command_rate(
                _V, _G, 1.0, 0.0, float("inf"), 0.0, curvature=0.1
            ),
            "e_rate",
            ValueError,
        ),
        (
            lambda: fws.path_tracking_controller(_V, _G, feedforward="False"),
            "feedforward",
            ValueError,
        ),
        (lambda: fws.steering_actuator(None), "vehicle", TypeError),
    ],
)
def test_bad_input_names_the_argument(call, name, exc):
    with pytest.raises(exc, match=rf"\b{name}\b"):
        call()


def test_feedforward_false_string_was_feedforward_on():
    # the reference: by the formula, with and without the feedforward angle
    ff = math.atan(2.7 * 0.1)
    fb = -0.1 * 1.0
    on = fws.steering_command(_V, _G, 1.0, 0.0, curvature=0.1, feedforward=True)
    off = fws.steering_command(_V, _G, 1.0, 0.0, curvature=0.1, feedforward=False)
    assert float(on[0]) == pytest.approx(ff + fb, abs=1e-15)
    assert float(off[0]) == pytest.approx(fb, abs=1e-15)


def test_array_inputs_are_elementwise_with_nan_samples():
    # a NaN sample (a stopped run of a batch) stays in its place; the finite
    # samples equal the scalar evaluations of eq. (10)
    df = np.array([0.1, np.nan, -0.2])
    got = fws.yaw_rate(_V, df, 0.0, speed=5.0)
    ref = 5.0 * np.sin(df) / (2.7 * np.cos(df))
    assert np.isnan(got[1])
    np.testing.assert_allclose(got[[0, 2]], ref[[0, 2]], rtol=1e-15)
