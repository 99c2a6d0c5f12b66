"""The dynamic single-track core against textbook forms and the kinematic limit."""

import numpy as np
import pytest
from conftest import PAPER_VEHICLE
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


def _jacobian(fun, x0, h=1e-6):
    x0 = np.asarray(x0, float)
    cols = []
    for i in range(x0.size):
        dx = np.zeros_like(x0)
        dx[i] = h
        cols.append((np.asarray(fun(x0 + dx)) - np.asarray(fun(x0 - dx))) / (2 * h))
    return np.array(cols).T


@settings(derandomize=True, max_examples=40, deadline=None)
@given(u=st.floats(2.0, 40.0))
def test_linearisation_is_the_textbook_single_track(u):
    # Textbook linear single-track model with rear steering (e.g. Rajamani,
    # Vehicle Dynamics and Control, 2nd ed., eq. 2.31, extended by the rear
    # input), written here from the formula, held against a central
    # difference of the nonlinear right-hand side.
    m, iz = VEH.mass, VEH.yaw_inertia
    cf, cr = VEH.cornering_front, VEH.cornering_rear
    lf, lr = VEH.front_to_cg, VEH.rear_to_cg
    a = np.array(
        [
            [-(cf + cr) / (m * u), -u - (lf * cf - lr * cr) / (m * u)],
            [-(lf * cf - lr * cr) / (iz * u), -(lf**2 * cf + lr**2 * cr) / (iz * u)],
        ]
    )
    b = np.array([[cf / m, cr / m], [lf * cf / iz, -lr * cr / iz]])

    def f(z):
        return dynamics.body_derivatives(VEH, z[0], z[1], z[2], z[3], speed=u)

    jac = _jacobian(f, np.zeros(4))
    np.testing.assert_allclose(jac[:, :2], a, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(jac[:, 2:], b, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("delta_f, delta_r", [(0.05, 0.0), (0.08, -0.04), (-0.1, 0.05)])
def test_kinematic_limit_of_the_path_derivatives(delta_f, delta_r):
    # With no slip, v_R = u tan(delta_r) and r = u (tan df - tan dr) / f; the
    # path-frame rates then equal the kinematic ones at V = u / cos(delta_r).
    u, kappa, e, theta = 10.0, 0.05, 0.3, 0.1
    f, lr = VEH.wheelbase, VEH.rear_to_cg
    r = u * (np.tan(delta_f) - np.tan(delta_r)) / f
    v_y = u * np.tan(delta_r) + lr * r
    af, ar = dynamics.slip_angles(VEH, v_y, r, delta_f, delta_r, speed=u)
    np.testing.assert_allclose([af, ar], [0.0, 0.0], atol=1e-15)
    s_dot, e_dot, th_dot, _, _ = dynamics.dynamic_path_derivatives(
        VEH, kappa, e, theta, v_y, r, delta_f, delta_r, speed=u
    )
    kin = fws.kinematic_models.path_frame_derivatives(
        u / np.cos(delta_r), f, kappa, e, theta, delta_f, delta_r
    )
    np.testing.assert_allclose([s_dot, e_dot, th_dot], kin, rtol=1e-13)


def test_magic_tyre_slope_and_peak():
    fz_f, fz_r = dynamics.axle_loads(VEH)
    # static loads by moments about each axle, by hand
    assert fz_f == pytest.approx(1500 * 9.81 * 1.2 / 2.7)
    assert fz_f + fz_r == pytest.approx(1500 * 9.81)
    peak = VEH.friction * fz_f
    h = 1e-7
    slope = (
        dynamics.tyre_force(h, stiffness=VEH.cornering_front, peak=peak)
        - dynamics.tyre_force(-h, stiffness=VEH.cornering_front, peak=peak)
    ) / (2 * h)
    assert slope == pytest.approx(VEH.cornering_front, rel=1e-9)
    alpha = np.linspace(0, 0.5, 20001)
    force = dynamics.tyre_force(alpha, stiffness=VEH.cornering_front, peak=peak)
    assert force.max() == pytest.approx(peak, rel=1e-8)


def test_missing_data_is_named():
    # each missing field is named with its unit; the paper's vehicle has none
    message = (
        r"mass \[kg\], yaw_inertia \[kg m\^2\], "
        r"cornering_front \[N/rad per axle\], cornering_rear \[N/rad per axle\];"
    )
    with pytest.raises(ValueError, match=message):
        dynamics.body_derivatives(PAPER_VEHICLE, 0.0, 0.0, 0.0, 0.0, speed=5)
    with pytest.raises(ValueError, match="friction"):
        dynamics.require_dynamics(
            fws.Vehicle(
                2.7,
                1.35,
                mass=1.0,
                yaw_inertia=1.0,
                cornering_front=1.0,
                cornering_rear=1.0,
            ),
            tyre="magic",
        )
    with pytest.raises(ValueError, match="tyre must be one of"):
        dynamics.require_dynamics(VEH, tyre="pacejka")
    with pytest.raises(TypeError, match="vehicle must be"):
        dynamics.require_dynamics("car")
    # the slip angles need only G's position: without it, the field is named
    with pytest.raises(ValueError, match="rear_to_cg is None, but the slip angles"):
        dynamics.slip_angles(fws.Vehicle(2.7), 0.0, 0.0, 0.1, 0.0, speed=10.0)


@pytest.mark.parametrize(
    "field, value",
    [
        ("mass", -1.0),
        ("yaw_inertia", np.nan),
        ("cornering_rear", True),
        ("cornering_front", 0.0),
        ("friction", 1j),
        ("mass", "heavy"),
    ],
)
def test_vehicle_refuses_bad_dynamic_fields(field, value):
    with pytest.raises(ValueError, match=field):
        fws.Vehicle(2.7, 1.35, **{field: value})
