"""The dynamic single-track model as python-control systems."""

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control as fws
from fws_control import dynamics

VEH = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.2,
    mass=1500.0,
    yaw_inertia=2600.0,
    cornering_front=8.0e4,
    cornering_rear=9.5e4,
    friction=1.0,
)

angle = st.floats(-0.3, 0.3)


@settings(derandomize=True, max_examples=30, deadline=None)
@given(
    e=st.floats(-1.0, 1.0),
    theta=angle,
    v_y=st.floats(-2.0, 2.0),
    r=st.floats(-0.5, 0.5),
    df=angle,
    dr=angle,
    u=st.floats(1.0, 40.0),
    kappa=st.floats(-0.1, 0.1),
)
def test_path_model_is_the_path_derivatives(e, theta, v_y, r, df, dr, u, kappa):
    for tyre in dynamics.TYRES:
        sys = dynamics.dynamic_path_model(VEH, speed=u, curvature=kappa, tyre=tyre)
        got = sys.dynamics(0.0, [3.0, e, theta, v_y, r], [df, dr])
        ref = dynamics.dynamic_path_derivatives(
            VEH, kappa, e, theta, v_y, r, df, dr, speed=u, tyre=tyre
        )
        np.testing.assert_allclose(got, ref, rtol=0, atol=0)
        np.testing.assert_array_equal(sys.output(0.0, got, [df, dr]), got)


@settings(derandomize=True, max_examples=30, deadline=None)
@given(
    psi=st.floats(-3.0, 3.0),
    v_y=st.floats(-2.0, 2.0),
    r=st.floats(-0.5, 0.5),
    df=angle,
    dr=angle,
    u=st.floats(1.0, 40.0),
)
def test_global_model_matches_the_path_frame_on_a_straight_path(psi, v_y, r, df, dr, u):
    # On the straight path along the x axis, y = e, psi = theta and x = s:
    # the two frames must give the same rates (independent of how each is
    # written).
    glob = dynamics.dynamic_global_model(VEH, speed=u)
    path = dynamics.dynamic_path_model(VEH, speed=u, curvature=0.0)
    g = glob.dynamics(0.0, [5.0, 0.4, psi, v_y, r], [df, dr])
    p = path.dynamics(0.0, [5.0, 0.4, psi, v_y, r], [df, dr])
    np.testing.assert_allclose(g, p, rtol=1e-12, atol=1e-12)


def test_global_rates_by_hand():
    # R at distance l_r behind G: its world velocity is v_G + r x (-l_r e_x)
    u, psi, v_y, r = 12.0, 0.7, 0.3, 0.2
    glob = dynamics.dynamic_global_model(VEH, speed=u)
    out = glob.dynamics(0.0, [0.0, 0.0, psi, v_y, r], [0.0, 0.0])
    c, s = np.cos(psi), np.sin(psi)
    v_g = np.array([u * c - v_y * s, u * s + v_y * c])
    rel = -VEH.rear_to_cg * np.array([c, s])  # G -> R in the world frame
    v_r = v_g + r * np.array([-rel[1], rel[0]])
    np.testing.assert_allclose(out[:2], v_r, rtol=1e-13)
    assert out[2] == r


@pytest.mark.parametrize("delta_f, delta_r", [(0.05, 0.0), (0.08, -0.04)])
def test_no_slip_limit_equals_the_kinematic_systems(delta_f, delta_r):
    # With v_y, r on the no-slip manifold the kinematic-state rates of the
    # dynamic systems equal those of the kinematic nlsys at V = u/cos(delta_r)
    u, kappa = 10.0, 0.05
    f, lr = VEH.wheelbase, VEH.rear_to_cg
    r = u * (np.tan(delta_f) - np.tan(delta_r)) / f
    v_y = u * np.tan(delta_r) + lr * r
    kin_v = u / np.cos(delta_r)
    dyn = dynamics.dynamic_path_model(VEH, speed=u, curvature=kappa)
    kin = fws.path_frame_model(VEH, speed=kin_v, curvature=kappa)
    x = [1.0, 0.3, 0.1]
    np.testing.assert_allclose(
        dyn.dynamics(0.0, [*x, v_y, r], [delta_f, delta_r])[:3],
        kin.dynamics(0.0, x, [delta_f, delta_r]),
        rtol=1e-12,
    )
    dglob = dynamics.dynamic_global_model(VEH, speed=u)
    kglob = fws.global_frame_model(VEH, speed=kin_v)
    x = [1.0, -2.0, 0.4]
    np.testing.assert_allclose(
        dglob.dynamics(0.0, [*x, v_y, r], [delta_f, delta_r])[:3],
        kglob.dynamics(0.0, x, [delta_f, delta_r]),
        rtol=1e-12,
    )


def test_stiff_tyres_track_the_kinematic_trajectory():
    # Open-loop front-steering run: stiffness x100 brings the dynamic
    # trajectory within a small distance of the kinematic one (delta_r = 0,
    # so the speeds coincide).
    u, T = 8.0, np.linspace(0.0, 3.0, 301)
    stiff = fws.Vehicle(
        wheelbase=2.7,
        rear_to_cg=1.2,
        mass=1500.0,
        yaw_inertia=2600.0,
        cornering_front=8.0e6,
        cornering_rear=9.5e6,
    )
    steer = np.vstack([0.05 * np.ones_like(T), np.zeros_like(T)])
    dyn = ct.input_output_response(
        dynamics.dynamic_global_model(stiff, speed=u), T, steer, np.zeros(5)
    )
    kin = ct.input_output_response(
        fws.global_frame_model(stiff, speed=u), T, steer, np.zeros(3)
    )
    gap = np.hypot(dyn.outputs[0] - kin.outputs[0], dyn.outputs[1] - kin.outputs[1])
    assert gap.max() < 0.02
    # and the same run with the nominal tyres is visibly apart (understeer)
    soft = ct.input_output_response(
        dynamics.dynamic_global_model(VEH, speed=u), T, steer, np.zeros(5)
    )
    gap_soft = np.hypot(
        soft.outputs[0] - kin.outputs[0], soft.outputs[1] - kin.outputs[1]
    )
    assert gap_soft.max() > 20 * gap.max()


def test_params_override_the_speed():
    sys = dynamics.dynamic_path_model(VEH, speed=10.0, curvature=0.02)
    assert sys.params == {"speed": 10.0, "curvature": 0.02}
    x, u = [0.0, 0.1, 0.02, 0.1, 0.05], [0.03, 0.0]
    ref = dynamics.dynamic_path_derivatives(VEH, 0.0, *x[1:], *u, speed=20.0)
    out = sys.dynamics(0.0, x, u, params={"speed": 20.0, "curvature": 0.0})
    np.testing.assert_allclose(out, ref, rtol=1e-14)


def test_arguments_are_validated():
    with pytest.raises(ValueError, match="speed must be > 0"):
        dynamics.dynamic_path_model(VEH, speed=-5.0)
    with pytest.raises(ValueError, match="speed must be finite and nonzero"):
        dynamics.dynamic_global_model(VEH, speed=0.0)
    with pytest.raises(ValueError, match="curvature must be finite"):
        dynamics.dynamic_path_model(VEH, speed=5.0, curvature=np.inf)
    with pytest.raises(ValueError, match="curvature must be a scalar"):
        dynamics.dynamic_path_model(VEH, speed=5.0, curvature=[0.1, 0.2])
    with pytest.raises(ValueError, match="tyre must be one of"):
        dynamics.dynamic_global_model(VEH, speed=5.0, tyre="brush")
    with pytest.raises(ValueError, match="mass"):
        dynamics.dynamic_global_model(fws.Vehicle(2.7, 1.2), speed=5.0)
    with pytest.raises(TypeError, match="vehicle must be"):
        dynamics.dynamic_path_model("car", speed=5.0)
    with pytest.raises(TypeError):
        dynamics.dynamic_path_model(VEH, 5.0)  # keyword-only
    sys = dynamics.dynamic_path_model(VEH, speed=5.0, curvature=0.5)
    with pytest.raises(fws.SingularStateError, match="1 - curvature\\*e"):
        sys.dynamics(0.0, [0.0, 2.0, 0.0, 0.0, 0.0], [0.0, 0.0])
