"""Nonlinear models against sympy, an independent single-track model and geometry."""

import math

import control as ct
import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control import symbolic as S

_sx, _sy, _spsi, _se, _sth = sp.symbols("x y psi e theta", real=True)
_sdf, _sdr = sp.symbols("delta_f delta_r", real=True)
V, f, kappa = S.SYMBOLS["speed"], S.SYMBOLS["wheelbase"], S.SYMBOLS["curvature"]


def test_names_and_params(veh):
    g = fws.global_frame_model(veh, speed=5.0)
    p = fws.path_frame_model(veh, speed=5.0, curvature=0.1)
    assert g.state_labels == ["x", "y", "psi"]
    assert p.state_labels == ["s", "e", "theta"]
    assert g.input_labels == p.input_labels == ["delta_f", "delta_r"]
    assert p.params == {"speed": 5.0, "curvature": 0.1, "wheelbase": 2.7}
    assert g.params == {"speed": 5.0, "wheelbase": 2.7}
    assert (g.name, p.name) == ("vehicle", "vehicle_path")
    named = fws.path_frame_model(veh, speed=5.0, curvature=0.1, name="car")
    assert fws.global_frame_model(veh, speed=5.0, name="car").name == named.name
    # defaults: speed 1 m/s, straight path
    assert fws.path_frame_model(veh).params == {
        "speed": 1.0,
        "curvature": 0.0,
        "wheelbase": 2.7,
    }


def test_global_frame_matches_sympy_solution_of_constraints(veh, rng):
    """Eqs. (8)-(10) as solved by sympy from the constraints (5)-(7)."""
    rhs = sp.lambdify((V, f, _spsi, _sdf, _sdr), S.global_frame_rhs(), "numpy")
    for _ in range(50):
        speed = rng.choice([-1, 1]) * rng.uniform(0.5, 30)
        psi, df, dr = rng.uniform(-3, 3), rng.uniform(-1.4, 1.4), rng.uniform(-1, 1)
        sys = fws.global_frame_model(veh, speed=speed)
        got = sys.dynamics(0.0, [1.0, -2.0, psi], [df, dr])
        ref = np.asarray(rhs(speed, veh.wheelbase, psi, df, dr), float).ravel()
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


def test_path_frame_matches_sympy_transformation(veh, rng):
    """Eqs. (17)-(19) (corrected) from the frame transformation (14)-(16)."""
    rhs = sp.lambdify((V, f, kappa, _se, _sth, _sdf, _sdr), S.path_frame_rhs(), "numpy")
    for _ in range(50):
        speed = rng.choice([-1, 1]) * rng.uniform(0.5, 30)
        k = rng.uniform(-0.3, 0.3)
        e = rng.uniform(-2, 2)
        th, df, dr = rng.uniform(-1, 1), rng.uniform(-1.4, 1.4), rng.uniform(-1, 1)
        sys = fws.path_frame_model(veh, speed=speed, curvature=k)
        got = sys.dynamics(0.0, [0.0, e, th], [df, dr])
        ref = np.asarray(rhs(speed, veh.wheelbase, k, e, th, df, dr), float).ravel()
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


def test_front_steering_only_matches_textbook_single_track(veh, rng):
    """With delta_r = 0 the model is the rear-axle bicycle: psi_dot = V tan(delta)/f."""
    for _ in range(20):
        speed, psi, delta = (
            rng.uniform(-20, 20),
            rng.uniform(-3, 3),
            rng.uniform(-1.5, 1.5),
        )
        sys = fws.global_frame_model(veh, speed=speed)
        got = sys.dynamics(0, [0, 0, psi], [delta, 0])
        ref = [
            speed * math.cos(psi),
            speed * math.sin(psi),
            speed * math.tan(delta) / veh.wheelbase,
        ]
        np.testing.assert_allclose(got, ref, rtol=1e-13, atol=1e-13)


def _arc_coordinates(x, y, psi, k):
    """Hand-written (s, e, theta) of a point w.r.t. the arc of curvature k > 0."""
    radius = 1.0 / k
    x, y, psi = np.atleast_1d(x, y, psi)
    phi = np.unwrap(np.arctan2(y - radius, x))
    r = np.hypot(x, y - radius)
    s = radius * (phi + np.pi / 2)
    heading = phi + np.pi / 2
    return s, radius - r, np.angle(np.exp(1j * (psi - heading)))


@pytest.mark.parametrize("speed", [5.0, -3.0])
def test_path_frame_agrees_with_global_frame_on_arc(veh, speed):
    """Integrate both frames with the same smooth steering signals; compare.

    The systems' own ``dynamics`` are integrated with smooth input functions
    (``input_output_response`` interpolates inputs linearly, whose kinks
    would limit the attainable accuracy to ~1e-6).
    """
    k = 0.1

    def u(t):
        return [0.25 + 0.1 * np.sin(t), 0.05 * np.cos(2 * t)]

    glob = fws.global_frame_model(veh, speed=speed)
    path = fws.path_frame_model(veh, speed=speed, curvature=k)
    t = np.linspace(0.0, 6.0, 601)
    x0 = np.array([0.0, -1.0, 0.2])  # (x, y, psi): e0 = -1, theta0 = 0.2
    z0 = [v[0] for v in _arc_coordinates(*x0, k)]
    opts = {"t_eval": t, "rtol": 1e-12, "atol": 1e-12, "method": "DOP853"}
    a = solve_ivp(lambda t, x: glob.dynamics(t, x, u(t)), (0, 6), x0, **opts)
    b = solve_ivp(lambda t, x: path.dynamics(t, x, u(t)), (0, 6), z0, **opts)
    s, e, th = _arc_coordinates(*a.y, k)
    np.testing.assert_allclose(b.y[0], s, atol=1e-8)
    np.testing.assert_allclose(b.y[1], e, atol=1e-8)
    np.testing.assert_allclose(b.y[2], th, atol=1e-8)
    assert np.ptp(e) > 0.5  # the vehicle really left the path


def test_params_override_speed(veh):
    sys = fws.global_frame_model(veh, speed=5.0)
    t = np.linspace(0, 2, 21)
    res = ct.input_output_response(
        sys, t, [[0.0] * 21, [0.0] * 21], [0, 0, 0], params={"speed": -2.0}
    )
    np.testing.assert_allclose(res.states[0, -1], -4.0, rtol=1e-9)


def test_singular_steering_raises(veh):
    with pytest.raises(fws.SingularStateError, match="delta_f"):
        fws.global_frame_model(veh, speed=5.0).dynamics(0, [0, 0, 0], [math.pi / 2, 0])
    with pytest.raises(fws.SingularStateError, match="delta_f"):
        fws.yaw_rate(veh, -2.0, 0.0, speed=5.0)
    # the exception lives in fws_control.exceptions and is a ValueError
    from fws_control.exceptions import SingularStateError

    assert SingularStateError is fws.SingularStateError
    assert issubclass(SingularStateError, ValueError)


def test_beyond_centre_of_curvature_raises(veh):
    sys = fws.path_frame_model(veh, speed=5.0, curvature=0.1)
    with pytest.raises(fws.SingularStateError, match="curvature"):
        sys.dynamics(0, [0, 10.0, 0], [0, 0])
    with pytest.raises(fws.SingularStateError):
        sys.dynamics(0, [0, 12.0, 0], [0, 0])
    assert np.all(np.isfinite(sys.dynamics(0, [0, 9.9, 0], [0, 0])))


@pytest.mark.parametrize("bad", [0.0, math.nan, math.inf])
def test_bad_speed(veh, bad):
    with pytest.raises(ValueError, match="speed"):
        fws.global_frame_model(veh, speed=bad)
    with pytest.raises(ValueError, match="speed"):
        fws.path_frame_model(veh, speed=bad)


def test_bad_curvature(veh):
    with pytest.raises(ValueError, match="curvature"):
        fws.path_frame_model(veh, speed=5.0, curvature=math.nan)
    with pytest.raises(ValueError, match="curvature"):
        fws.feedforward_steering(veh, curvature=math.inf)


def test_feedforward_is_equilibrium_for_any_speed(veh):
    for speed in (-7.0, 3.0, 30.0):
        for k in (-0.2, 0.0, 0.05):
            sys = fws.path_frame_model(veh, speed=speed, curvature=k)
            u_ff = [fws.feedforward_steering(veh, curvature=k), 0.0]
            dx = sys.dynamics(0, [0, 0, 0], u_ff)
            np.testing.assert_allclose(dx, [speed, 0.0, 0.0], atol=1e-14)
    # geometry: with R on a circle of radius 1/k and the rear wheel tangent,
    # the front axle centre F = R + f (cos psi, sin psi) must have its wheel
    # normal through the circle's centre: tan(delta_f) = f / radius.
    k = 0.1
    radius, f = 1.0 / k, veh.wheelbase
    centre, rear, front = np.array([0.0, radius]), np.zeros(2), np.array([f, 0.0])
    delta = fws.feedforward_steering(veh, curvature=k)
    normal = np.array([-np.sin(delta), np.cos(delta)])  # front wheel's left normal
    to_centre = centre - front
    assert abs(normal[0] * to_centre[1] - normal[1] * to_centre[0]) < 1e-12
    assert np.linalg.norm(rear - centre) == pytest.approx(radius)
