"""Turning radius against simulation (circle fit) and a geometric construction."""

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws


def _fit_circle(x, y):
    """Algebraic (Kasa) least-squares circle: returns centre and radius."""
    M = np.column_stack([x, y, np.ones_like(x)])
    sol, *_ = np.linalg.lstsq(M, x**2 + y**2, rcond=None)
    cx, cy = sol[0] / 2, sol[1] / 2
    return np.array([cx, cy]), np.sqrt(sol[2] + cx**2 + cy**2)


STEER = [
    (np.radians(30), 0.0),
    (np.radians(30), np.radians(-30)),
    (np.radians(35), np.radians(-17.5)),
    (np.radians(20), np.radians(10)),
    (np.radians(-25), np.radians(37.5)),  # a = -1.5, right turn
    (np.radians(10), np.radians(15)),  # a = 1.5: turns the other way
]


@pytest.mark.parametrize("df, dr", STEER)
def test_radius_matches_simulated_circle(veh, df, dr):
    sys = fws.global_frame_model(veh, speed=3.0)
    t = np.linspace(0.0, 6.0, 400)
    u = np.tile([[df], [dr]], (1, t.size))
    res = ct.input_output_response(
        sys, t, u, X0=[0.0, 0.0, 0.0], solve_ivp_kwargs={"rtol": 1e-11, "atol": 1e-11}
    )
    x, y, psi = res.states
    d = veh.rear_to_cg
    cR, rR = _fit_circle(x, y)
    cG, rG = _fit_circle(x + d * np.cos(psi), y + d * np.sin(psi))
    geo = fws.steady_turn(veh, df, dr)
    np.testing.assert_allclose(geo.rear_axle, rR, rtol=1e-6)
    np.testing.assert_allclose(geo.cg, rG, rtol=1e-6)
    # psi(0) = 0 and R at the origin: the vehicle frame is the global frame.
    np.testing.assert_allclose(geo.centre, cR, atol=1e-5)
    np.testing.assert_allclose(cG, cR, atol=1e-5)
    assert np.sign(geo.curvature) == np.sign(psi[-1])


@pytest.mark.parametrize("df, dr", STEER)
def test_centre_is_intersection_of_wheel_normals(veh, df, dr):
    f, d = veh.wheelbase, veh.rear_to_cg
    nR = np.array([-np.sin(dr), np.cos(dr)])
    nF = np.array([-np.sin(df), np.cos(df)])
    # t nR = (f, 0) + u nF
    t, u = np.linalg.solve(np.column_stack([nR, -nF]), [f, 0.0])
    centre = t * nR
    geo = fws.steady_turn(veh, df, dr)
    np.testing.assert_allclose(geo.centre, centre, atol=1e-12)
    np.testing.assert_allclose(geo.rear_axle, np.hypot(*centre), rtol=1e-12)
    np.testing.assert_allclose(geo.cg, np.hypot(centre[0] - d, centre[1]), rtol=1e-12)


def test_hand_derived_values(veh):
    f, d = veh.wheelbase, veh.rear_to_cg
    delta = np.radians([10.0, 25.0, 40.0])
    fws_only = fws.turning_radius(veh, ratio=0.0, max_steer_front=delta)
    np.testing.assert_allclose(fws_only.rear_axle, f / np.tan(delta), rtol=1e-12)
    np.testing.assert_allclose(fws_only.cg, np.hypot(f / np.tan(delta), d))
    counter = fws.turning_radius(veh, ratio=-1.0, max_steer_front=delta)
    np.testing.assert_allclose(counter.rear_axle, f / (2 * np.sin(delta)))
    # d = f/2: G is the foot of the perpendicular from the centre.
    np.testing.assert_allclose(counter.cg, f / (2 * np.tan(delta)))


def test_straight_and_crab(veh):
    geo = fws.steady_turn(veh, 0.2, 0.2)
    assert geo.curvature == 0.0 and np.isinf(geo.rear_axle) and np.isinf(geo.cg)
    assert np.all(np.isinf(geo.centre))


def test_negative_ratio_shrinks_radius_and_minimum(veh):
    a = np.linspace(-2.5, 0.8, 3301)
    for deg in (20.0, 30.0, 40.0):
        lim = np.radians(deg)
        r = fws.turning_radius(veh, ratio=a, max_steer_front=lim).rear_axle
        # The paper's claim: a < 0 gives a smaller radius than a = 0 ...
        r0 = fws.turning_radius(veh, ratio=0.0, max_steer_front=lim).rear_axle
        assert np.all(r[(a < 0) & (a >= -1.0)] < r0)
        # ... down to the minimum at (1 - a) delta = pi/2, then it grows.
        a_star = 1 - np.pi / (2 * lim)
        np.testing.assert_allclose(a[np.argmin(r)], max(a_star, a[0]), atol=2e-3)


def test_limits_from_vehicle_and_rear_clipping():
    veh = fws.Vehicle(
        2.7, 1.35, max_steer_front=np.radians(30), max_steer_rear=np.radians(10)
    )
    geo = fws.turning_radius(veh, ratio=-1.0)
    np.testing.assert_allclose(geo.delta_f, np.radians(30))
    np.testing.assert_allclose(geo.delta_r, -np.radians(10))
    ref = fws.steady_turn(veh, np.radians(30), -np.radians(10))
    np.testing.assert_allclose(geo.rear_axle, ref.rear_axle)
    # explicit limits override the vehicle's
    geo = fws.turning_radius(
        veh, ratio=-1.0, max_steer_front=np.radians(20), max_steer_rear=np.radians(25)
    )
    np.testing.assert_allclose(geo.delta_r, -np.radians(20))
    np.testing.assert_allclose(geo.rear_axle, 2.7 / (2 * np.sin(np.radians(20))))
    with pytest.raises(ValueError, match="max_steer_front"):
        fws.turning_radius(PAPER_VEHICLE, ratio=-1.0)
    with pytest.raises(ValueError, match="max_steer_front"):
        fws.turning_radius(veh, ratio=-1.0, max_steer_front=2.0)
    with pytest.raises(ValueError, match="max_steer_rear"):
        fws.turning_radius(veh, ratio=-1.0, max_steer_rear=0.0)
    with pytest.raises(fws.SingularStateError):
        fws.steady_turn(veh, np.pi / 2, 0.0)


def test_plot(veh):
    cplt = fws.plot_turning_radius(veh, limits=[np.radians(30)])
    assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == (1, 1)
    ax = cplt.axes[0, 0]
    assert ax.get_ylabel() == "steady turning radius [m]"
    solid, dashed = ax.lines[0], ax.lines[1]
    a = solid.get_xdata()
    # hand-derived: delta_f = 30 deg, delta_r = a delta_f
    df = np.radians(30)
    dr = a * df
    f, d = veh.wheelbase, veh.rear_to_cg
    t = f * np.cos(df) / np.sin(df - dr)
    np.testing.assert_allclose(solid.get_ydata(), np.abs(t), rtol=1e-12)
    np.testing.assert_allclose(
        dashed.get_ydata(), np.sqrt(t**2 + 2 * d * t * np.sin(dr) + d**2), rtol=1e-12
    )
    assert cplt.lines[0, 0] == list(ax.lines)
    plt.close(cplt.figure)
    # into given axes
    fig, given = plt.subplots()
    assert fws.plot_turning_radius(veh, ax=given).axes[0, 0] is given
    assert len(given.lines) > 0
    plt.close(fig)


_V13 = PAPER_VEHICLE


@pytest.mark.parametrize(
    "make, arg, exc",
    [
        (lambda: fws.steady_turn(None, 0.3, 0.0), "vehicle", TypeError),
        (
            lambda: fws.turning_radius("car", ratio=0.0, max_steer_front=0.5),
            "vehicle",
            TypeError,
        ),  # fmt: skip
        (
            lambda: fws.turning_radius(
                _V13, ratio=0.0, max_steer_front=0.5, max_steer_rear=[0.1, 0.2]
            ),
            "max_steer_rear",
            ValueError,
        ),  # fmt: skip
        (
            lambda: fws.turning_radius(_V13, ratio=[0.0, 1.0], max_steer_front=[]),
            "max_steer_front",
            ValueError,
        ),  # fmt: skip
        (lambda: fws.plot_turning_radius(1.0), "vehicle", TypeError),
        (lambda: fws.plot_turning_radius(_V13, ratios=np.nan), "ratios", ValueError),
        (lambda: fws.plot_turning_radius(_V13, limits=0.0), "limits", ValueError),
        (lambda: fws.plot_turning_radius(_V13, limits=[2.0]), "limits", ValueError),
        (lambda: fws.plot_turning_radius(_V13, ylim=np.inf), "ylim", ValueError),
        (lambda: fws.plot_turning_radius(_V13, ylim=True), "ylim", TypeError),
    ],
)
def test_issue13_turning_arguments_named(make, arg, exc):
    # before: AttributeError for a non-Vehicle, the limits named as
    # max_steer_front, matplotlib's "Axis limits cannot be NaN or Inf"
    n_figs = len(plt.get_fignums())
    with pytest.raises(exc, match=rf"\b{arg}\b"):
        make()
    assert len(plt.get_fignums()) == n_figs  # refused before drawing
