"""Lateral acceleration (eq. 13) against sympy and finite differences."""

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control import symbolic as S


def test_eq13_derived_from_eq12_with_sympy():
    V, d = S.SYMBOLS["speed"], S.SYMBOLS["rear_to_cg"]
    pdot, pddot, dr, drdot = sp.symbols("psi_dot psi_ddot delta_r delta_r_dot")
    printed = V * (pdot + drdot) * sp.cos(dr) + d * pddot
    assert sp.simplify(S.lateral_acceleration() - printed) == 0


def _steering(t):
    df = 0.3 * np.sin(0.9 * t) + 0.1
    dr = -0.2 * np.sin(1.3 * t + 0.4)
    return df, dr, 0.27 * np.cos(0.9 * t), -0.26 * np.cos(1.3 * t + 0.4)


def test_lateral_acceleration_matches_finite_differences_of_trajectory(veh):
    """Differentiate the simulated position of G twice and project it."""
    speed = 7.0

    def rhs(t, x):
        df, dr, _, _ = _steering(t)
        return fws.global_frame_model(veh, speed=speed).dynamics(t, x, [df, dr])

    h = 1e-3
    t = np.arange(0.0, 8.0 + h / 2, h)
    sol = solve_ivp(
        rhs, (0, 8), [0, 0, 0.3], t_eval=t, rtol=1e-12, atol=1e-12, method="DOP853"
    )
    x, y, psi = sol.y
    xg = x + veh.rear_to_cg * np.cos(psi)
    yg = y + veh.rear_to_cg * np.sin(psi)
    ax = (xg[2:] - 2 * xg[1:-1] + xg[:-2]) / h**2
    ay = (yg[2:] - 2 * yg[1:-1] + yg[:-2]) / h**2
    lat_fd = -ax * np.sin(psi[1:-1]) + ay * np.cos(psi[1:-1])
    df, dr, dfd, drd = _steering(t[1:-1])
    lat = fws.lateral_acceleration(veh, df, dr, dfd, drd, speed=speed)
    assert np.max(np.abs(lat - lat_fd)) < 1e-4
    assert np.max(np.abs(lat)) > 1.0  # the check is not vacuous


def test_yaw_acceleration_is_derivative_of_yaw_rate(veh, rng):
    h = 1e-6
    for _ in range(20):
        speed = rng.uniform(-20, 20)
        df, dr = rng.uniform(-1.2, 1.2), rng.uniform(-1, 1)
        dfd, drd = rng.uniform(-1, 1), rng.uniform(-1, 1)
        fd = (
            fws.yaw_rate(veh, df + h * dfd, dr + h * drd, speed=speed)
            - fws.yaw_rate(veh, df - h * dfd, dr - h * drd, speed=speed)
        ) / (2 * h)
        got = fws.yaw_acceleration(veh, df, dr, dfd, drd, speed=speed)
        assert abs(got - fd) < 1e-6 * max(1.0, abs(fd))


def test_steady_turn_gives_centripetal_acceleration():
    """Front steering only, d = 0: a = V^2 / R with R = f / tan(delta)."""
    veh = fws.Vehicle(2.5, 0.0)
    delta, speed = 0.2, 12.0
    radius = 2.5 / np.tan(delta)
    got = fws.lateral_acceleration(veh, delta, 0.0, 0.0, 0.0, speed=speed)
    assert abs(got - speed**2 / radius) < 1e-12


def test_broadcasting(veh):
    df = np.linspace(-0.3, 0.3, 7)
    out = fws.lateral_acceleration(
        veh, df[:, None], 0.1, 0.0, np.zeros((1, 3)), speed=5.0
    )
    assert out.shape == (7, 3)
    ref = [fws.lateral_acceleration(veh, v, 0.1, 0.0, 0.0, speed=5.0) for v in df]
    np.testing.assert_allclose(out[:, 0], ref, rtol=1e-14)
    # speed broadcasts too
    speeds = np.array([-3.0, 2.0, 9.0])
    out = fws.lateral_acceleration(veh, 0.2, 0.1, 0.3, -0.2, speed=speeds)
    ref = [fws.lateral_acceleration(veh, 0.2, 0.1, 0.3, -0.2, speed=v) for v in speeds]
    np.testing.assert_allclose(out, ref, rtol=1e-14)
