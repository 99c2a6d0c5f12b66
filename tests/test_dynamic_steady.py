"""Steady state of the paper's loop on the dynamic model; dynamic feedforward."""

import functools

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import fsolve

import fws_control as fws
from fws_control import dynamics
from fws_control import symbolic as S

VEH = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.2,
    mass=1500.0,
    yaw_inertia=2600.0,
    cornering_front=8.0e4,
    cornering_rear=9.5e4,
    friction=1.0,
)
SYM = {**S.SYMBOLS, **S.DYNAMIC_SYMBOLS}


def _subs_vehicle(expr):
    return expr.subs(
        {
            SYM["wheelbase"]: VEH.wheelbase,
            SYM["rear_to_cg"]: VEH.rear_to_cg,
            SYM["mass"]: VEH.mass,
            SYM["yaw_inertia"]: VEH.yaw_inertia,
            SYM["cornering_front"]: VEH.cornering_front,
            SYM["cornering_rear"]: VEH.cornering_rear,
        }
    )


_ARGS = [SYM[n] for n in ("speed", "curvature", "e", "theta", "v_y", "yaw_rate")]
_ARGS += [SYM["delta_f"], SYM["delta_r"]]


@functools.cache
def _rhs():
    # made by the test that needs it, not at import: sympy's simplification
    # of the dynamic equations costs seconds of CPU, which every xdist
    # worker paid while collecting
    return sp.lambdify(_ARGS, _subs_vehicle(S.dynamic_path_rhs()), "numpy")


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    u=st.floats(1.0, 40.0),
    kappa=st.floats(-0.1, 0.1),
    e=st.floats(-1.0, 1.0),
    theta=st.floats(-0.5, 0.5),
    v_y=st.floats(-2.0, 2.0),
    r=st.floats(-0.5, 0.5),
    df=st.floats(-0.4, 0.4),
    dr=st.floats(-0.4, 0.4),
)
def test_numeric_rhs_is_the_newton_euler_derivation(u, kappa, e, theta, v_y, r, df, dr):
    ref = np.ravel(_rhs()(u, kappa, e, theta, v_y, r, df, dr)).astype(float)
    got = dynamics.dynamic_path_derivatives(
        VEH, kappa, e, theta, v_y, r, df, dr, speed=u
    )
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-11)


def _nonlinear_steady(gains, u, kappa, feedforward=True):
    """fsolve of the closed loop on the nonlinear model, written here."""

    def rates(z):
        e, th, vy, r = z
        df, dr = fws.steering_command(
            VEH, gains, e, th, curvature=kappa, feedforward=feedforward, speed=u
        )
        out = dynamics.dynamic_path_derivatives(
            VEH, kappa, e, th, vy, r, df, dr, speed=u
        )
        return np.array(out[1:], dtype=float)

    z0 = [0.0, 0.0, VEH.rear_to_cg * kappa * u, kappa * u]
    z, info, ok, msg = fsolve(rates, z0, full_output=True, xtol=1e-13)
    assert ok == 1, msg
    assert np.abs(rates(z)).max() < 1e-10
    return z


@pytest.mark.parametrize("ratio", [-0.5, 0.0, 0.5])
@pytest.mark.parametrize("u", [10.0, 20.0, 30.0])
def test_closed_form_is_the_sympy_steady_state(ratio, u):
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=ratio)
    kappa = 0.01
    sol = S.dynamic_steady_state()
    vals = {SYM["speed"]: u, SYM["curvature"]: kappa, SYM["k1"]: 0.02}
    vals |= {SYM["k2"]: 0.3, SYM["ratio"]: ratio}
    e_ref = float(_subs_vehicle(sol[SYM["e"]]).subs(vals))
    th_ref = float(_subs_vehicle(sol[SYM["theta"]]).subs(vals))
    e, th = fws.steady_state_offset(VEH, g, speed=u, curvature=kappa)
    assert e == pytest.approx(e_ref, rel=1e-12)
    assert th == pytest.approx(th_ref, rel=1e-12)


@pytest.mark.parametrize("ratio", [-0.5, 0.0, 0.5])
def test_closed_form_is_the_nonlinear_steady_state(ratio):
    # the closed form is first order: its relative error against the
    # nonlinear steady state is O(kappa^2), so it quarters when kappa halves
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=ratio)
    errors = []
    for kappa in (0.01, 0.005):
        e_nl, th_nl = _nonlinear_steady(g, 20.0, kappa)[:2]
        e, th = fws.steady_state_offset(VEH, g, speed=20.0, curvature=kappa)
        errors.append(abs(e - e_nl) / abs(e_nl))
        assert th == pytest.approx(th_nl, rel=5e-3)
    assert errors[0] < 5e-3
    assert 3.5 < errors[0] / errors[1] < 4.5
    if ratio == 0.0:
        # the docstring's figure
        assert errors[0] == pytest.approx(0.0029, abs=5e-5)


def test_offset_broadcasts_and_linear_plant_agrees():
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=np.array([[-0.5], [0.5]]))
    speeds = np.array([10.0, 20.0, 30.0])
    e, th = fws.steady_state_offset(VEH, g, speed=speeds, curvature=0.002)
    assert e.shape == (2, 3)
    # independent route: the linearised dynamic plant, driven by the constant
    # input offset (kinematic minus dynamic feedforward), x = -A_cl^-1 B w
    for i, a in enumerate([-0.5, 0.5]):
        for j, v in enumerate(speeds):
            plant = fws.LateralPlant(VEH, speed=v, curvature=0.002, model="dynamic")
            gi = fws.SteeringGains(0.02, 0.3, ratio=a)
            A, B = plant.matrices()
            A_cl = A - B @ np.outer([1.0, a], [0.02, 0.3]) @ np.eye(4)[:2]
            ff = np.array(plant.operating_point)
            w = np.array([np.arctan(0.002 * VEH.wheelbase), 0.0]) - ff
            x = -np.linalg.solve(A_cl, B @ w)
            assert e[i, j] == pytest.approx(x[0], rel=2e-3)
            assert th[i, j] == pytest.approx(x[1], rel=2e-3)
            assert fws.steady_state_offset(VEH, gi, speed=v, curvature=0.002)[0] == (
                pytest.approx(e[i, j], rel=1e-14)
            )


@pytest.mark.parametrize("tyre", ["linear", "magic"])
@pytest.mark.parametrize("u, kappa", [(10.0, 0.05), (25.0, -0.01), (35.0, 0.004)])
def test_dynamic_feedforward_is_an_equilibrium(tyre, u, kappa):
    df, dr = dynamics.dynamic_feedforward(VEH, speed=u, curvature=kappa, tyre=tyre)
    out = dynamics.dynamic_path_derivatives(
        VEH,
        kappa,
        0.0,
        0.0,
        VEH.rear_to_cg * kappa * u,
        kappa * u,
        df,
        dr,
        speed=u,
        tyre=tyre,
    )
    np.testing.assert_allclose(out[1:], 0.0, atol=1e-12)


def test_dynamic_feedforward_first_order_is_sympy():
    # first order in kappa: solve the small-angle model with e = theta = 0
    small = S.dynamic_small_angle_rhs()
    z = {SYM["e"]: 0, SYM["theta"]: 0}
    unknowns = [SYM[n] for n in ("delta_f", "delta_r", "v_y", "yaw_rate")]
    (sol,) = sp.solve([x.subs(z) for x in small[1:]], unknowns, dict=True)
    for u in (10.0, 30.0):
        for kappa in (1e-4, 1e-5):
            vals = {SYM["speed"]: u, SYM["curvature"]: kappa}
            ref = [float(_subs_vehicle(sol[k]).subs(vals)) for k in unknowns[:2]]
            got = dynamics.dynamic_feedforward(VEH, speed=u, curvature=kappa)
            np.testing.assert_allclose(got, ref, rtol=30 * kappa)


def test_controller_with_dynamic_feedforward_has_no_offset():
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=0.5)
    z = _nonlinear_steady(g, 20.0, 0.01, feedforward="dynamic")
    np.testing.assert_allclose(z[:2], 0.0, atol=1e-10)
    z_kin = _nonlinear_steady(g, 20.0, 0.01, feedforward=True)
    assert abs(z_kin[0]) > 0.3


def test_feedforward_derivative_and_rate():
    for tyre in ("linear", "magic"):
        kappa, h = 0.01, 1e-6
        d = dynamics.dynamic_feedforward_derivative(
            VEH, speed=20.0, curvature=kappa, tyre=tyre
        )
        hi = dynamics.dynamic_feedforward(
            VEH, speed=20.0, curvature=kappa + h, tyre=tyre
        )
        lo = dynamics.dynamic_feedforward(
            VEH, speed=20.0, curvature=kappa - h, tyre=tyre
        )
        np.testing.assert_allclose(d, (np.array(hi) - lo) / (2 * h), rtol=1e-6)
    # the command rate along kappa(t) = 0.01 + 0.002 t, e(t), theta(t)
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=-0.5)

    def cmd(t):
        return np.array(
            fws.steering_command(
                VEH,
                g,
                0.1 + 0.3 * t,
                0.02 - 0.1 * t,
                curvature=0.01 + 0.002 * t,
                feedforward="dynamic",
                speed=20.0,
            )
        )

    rate = fws.steering_command_rate(
        VEH,
        g,
        0.1,
        0.02,
        e_rate=0.3,
        theta_rate=-0.1,
        curvature=0.01,
        curvature_rate=0.002,
        feedforward="dynamic",
        speed=20.0,
    )
    np.testing.assert_allclose(rate, (cmd(1e-5) - cmd(-1e-5)) / 2e-5, rtol=1e-6)


def test_feedforward_option_errors():
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=0.0)
    with pytest.raises(ValueError, match="needs the keyword speed="):
        fws.steering_command(VEH, g, 0.0, 0.0, curvature=0.01, feedforward="dynamic")
    with pytest.raises(ValueError, match="feedforward must be True, False or one of"):
        fws.steering_command(VEH, g, 0.0, 0.0, feedforward="static")
    with pytest.raises(ValueError, match="mass"):
        fws.steering_command(
            fws.Vehicle(2.7, 1.2), g, 0.0, 0.0, feedforward="dynamic", speed=5.0
        )
    # True and "kinematic" are the same law
    np.testing.assert_array_equal(
        fws.steering_command(VEH, g, 0.1, 0.0, curvature=0.02),
        fws.steering_command(VEH, g, 0.1, 0.0, curvature=0.02, feedforward="kinematic"),
    )
    with pytest.raises(ValueError, match="no steady state"):
        fws.steady_state_offset(
            VEH, fws.SteeringGains(0.0, 0.3, ratio=0.0), speed=20.0, curvature=0.0
        )
    with pytest.raises(ValueError, match="speed must be finite and > 0"):
        fws.steady_state_offset(VEH, g, speed=0.0, curvature=0.01)
    with pytest.raises(TypeError, match="gains must be"):
        fws.steady_state_offset(VEH, (0.1, 0.2), speed=10.0, curvature=0.01)


def test_controller_block_with_dynamic_feedforward():
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=-0.5)
    block = fws.path_tracking_controller(VEH, g, feedforward="dynamic", speed=20.0)
    out = block.output(0.0, [], [0.1, 0.02, 0.01])
    ref = fws.steering_command(
        VEH, g, 0.1, 0.02, curvature=0.01, feedforward="dynamic", speed=20.0
    )
    np.testing.assert_allclose(out, np.ravel(ref), rtol=1e-15)
    # the speed is a block parameter: overriding it changes the feedforward
    out30 = block.output(0.0, [], [0.1, 0.02, 0.01], params={"speed": 30.0})
    ref30 = fws.steering_command(
        VEH, g, 0.1, 0.02, curvature=0.01, feedforward="dynamic", speed=30.0
    )
    np.testing.assert_allclose(out30, np.ravel(ref30), rtol=1e-15)
    with pytest.raises(ValueError, match="needs the keyword speed="):
        fws.path_tracking_controller(VEH, g, feedforward="dynamic")
