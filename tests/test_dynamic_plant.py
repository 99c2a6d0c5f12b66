"""LateralPlant(model="dynamic") against python-control's linearisation."""

from dataclasses import replace

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


def _reference(u, kappa, tyre="linear"):
    """ct.linearize of the path-frame nlsys at its e = theta = 0 equilibrium."""
    sys = dynamics.dynamic_path_model(VEH, speed=u, curvature=kappa, tyre=tyre)
    df, dr = dynamics.dynamic_feedforward(VEH, speed=u, curvature=kappa, tyre=tyre)
    x0 = [0.0, 0.0, 0.0, VEH.rear_to_cg * kappa * u, kappa * u]
    # the point is an equilibrium of everything but s
    rates = sys.dynamics(0.0, x0, [df, dr])
    np.testing.assert_allclose(rates[1:], 0.0, atol=1e-9)
    lin = ct.linearize(sys, x0, [df, dr], eps=1e-7)
    return np.asarray(lin.A)[1:, 1:], np.asarray(lin.B)[1:, :]


@settings(derandomize=True, max_examples=25, deadline=None)
@given(u=st.floats(3.0, 40.0), kappa=st.floats(-0.02, 0.02))
def test_matrices_are_the_linearisation_of_the_nlsys(u, kappa):
    plant = fws.LateralPlant(VEH, speed=u, curvature=kappa, model="dynamic")
    sys = plant.linearize()
    A_ref, B_ref = _reference(u, kappa)
    scale = np.abs(A_ref).max()
    np.testing.assert_allclose(sys.A, A_ref, rtol=1e-5, atol=1e-6 * scale)
    np.testing.assert_allclose(sys.B, B_ref, rtol=1e-5, atol=1e-6 * np.abs(B_ref).max())
    assert sys.state_labels == ["e", "theta", "v_y", "r"]
    assert sys.input_labels == ["delta_f", "delta_r"]
    assert sys.output_labels == ["e", "theta"]


@pytest.mark.parametrize("u, kappa", [(15.0, 0.01), (25.0, -0.008)])
def test_magic_tyre_matrices(u, kappa):
    plant = fws.LateralPlant(
        VEH, speed=u, curvature=kappa, model="dynamic", tyre="magic"
    )
    A_ref, B_ref = _reference(u, kappa, tyre="magic")
    np.testing.assert_allclose(plant.linearize().A, A_ref, rtol=1e-5, atol=1e-4)
    np.testing.assert_allclose(plant.linearize().B, B_ref, rtol=1e-5, atol=1e-4)
    # saturating tyres are softer at the operating point than linear ones
    lin = fws.LateralPlant(VEH, speed=u, curvature=kappa, model="dynamic")
    assert abs(plant.linearize().B[2, 0]) < abs(lin.linearize().B[2, 0])


@pytest.mark.parametrize("ratio", [-0.5, 0.0, 0.5])
@pytest.mark.parametrize("u", [5.0, 20.0, 35.0])
def test_closed_loop_engine_on_the_dynamic_plant(ratio, u):
    kappa = 0.01
    plant = fws.LateralPlant(VEH, speed=u, curvature=kappa, model="dynamic")
    kin = replace(plant, model="kinematic")
    g = fws.double_root_gains(kin, ratio=ratio, pole=-1.0)
    A_ref, B_ref = _reference(u, kappa)
    # u = [1, a]^T (-k1 e - k2 theta), written here from the control law
    K = np.outer([1.0, ratio], [g.k1, g.k2])
    A_cl = A_ref - B_ref @ K @ np.eye(4)[:2]
    eig = np.sort_complex(np.linalg.eigvals(A_cl))
    poles = np.sort_complex(fws.closed_loop(plant, g).poles())
    np.testing.assert_allclose(poles, eig, rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(
        fws.characteristic_polynomial_coefficients(plant, g),
        np.poly(A_cl),
        rtol=1e-4,
        atol=1e-4,
    )
    assert fws.is_stable(plant, g) == bool(np.all(eig.real < 0))
    # the gain root locus passes through the same poles at g = 1
    pz = fws.gain_locus(plant, g, scale=[1.0])
    np.testing.assert_allclose(np.sort_complex(pz.loci[0]), eig, rtol=1e-4, atol=1e-4)


def test_stability_chart_on_the_dynamic_plant():
    plant = fws.LateralPlant(VEH, speed=20.0, curvature=0.01, model="dynamic")
    k1 = np.linspace(-0.043, 0.31, 8)  # no point on k1 = 0 (marginal)
    k2 = np.linspace(-0.47, 1.53, 9)
    ch = fws.stability_chart(plant, ratio=0.0, k1=k1, k2=k2)
    A_ref, B_ref = _reference(20.0, 0.01)
    for i, kk2 in enumerate(ch.k2):
        for j, kk1 in enumerate(ch.k1):
            A_cl = A_ref - np.outer(B_ref[:, 0], [kk1, kk2]) @ np.eye(4)[:2]
            ref = np.all(np.linalg.eigvals(A_cl).real < 0)
            assert ch.stable[i, j] == ref, (kk1, kk2)
    assert 0 < ch.stable_fraction < 1


def test_parameter_locus_of_the_kinematic_design():
    plant = fws.LateralPlant(VEH, speed=10.0, curvature=0.01, model="dynamic")
    g = fws.double_root_gains(replace(plant, model="kinematic"), ratio=0.0, pole=-1.0)
    speeds = np.array([5.0, 10.0, 30.0])
    pz = fws.parameter_locus(
        plant,
        g,
        parameter="speed",
        values=speeds,
        redesign_pole=-1.0,
        design_model="kinematic",
    )
    for v, loci in zip(speeds, pz.loci, strict=True):
        p = replace(plant, speed=v)
        gv = fws.double_root_gains(replace(p, model="kinematic"), ratio=0.0, pole=-1.0)
        A_ref, B_ref = _reference(v, 0.01)
        A_cl = A_ref - np.outer(B_ref[:, 0], [gv.k1, gv.k2]) @ np.eye(4)[:2]
        np.testing.assert_allclose(
            np.sort_complex(loci), np.sort_complex(np.linalg.eigvals(A_cl)), atol=1e-4
        )


def test_double_root_design_refuses_the_four_state_plant():
    plant = fws.LateralPlant(VEH, speed=10.0, model="dynamic")
    with pytest.raises(ValueError, match="order 4.*model='kinematic'"):
        fws.double_root_gains(plant, ratio=0.0, pole=-1.0)


def test_broadcast_and_lag():
    speeds = np.array([5.0, 20.0])
    plant = fws.LateralPlant(VEH, speed=speeds, curvature=0.01, model="dynamic")
    A, B = plant.matrices()
    assert A.shape == (2, 4, 4) and B.shape == (2, 4, 2)
    for i, v in enumerate(speeds):
        Ai, Bi = fws.LateralPlant(
            VEH, speed=v, curvature=0.01, model="dynamic"
        ).matrices()
        np.testing.assert_array_equal(A[i], Ai)
        np.testing.assert_array_equal(B[i], Bi)
    lag = fws.LateralPlant(
        VEH, speed=20.0, curvature=0.01, model="dynamic", steering_lag=0.1
    )
    sys = lag.linearize()
    assert sys.state_labels[4:] == ["delta_f_act", "delta_r_act"]
    A4, B4 = fws.LateralPlant(
        VEH, speed=20.0, curvature=0.01, model="dynamic"
    ).matrices()
    # the lag in series: the plant driven by first-order lags 1/(0.1 s + 1)
    lags = ct.ss(-10 * np.eye(2), 10 * np.eye(2), np.eye(2), 0)
    series = ct.ss(A4, B4, np.eye(4)[:2], 0) * lags
    np.testing.assert_allclose(
        np.sort_complex(sys.poles()), np.sort_complex(series.poles()), atol=1e-9
    )
    assert plant.order == 4 and lag.order == 6


def test_operating_point_and_errors():
    plant = fws.LateralPlant(VEH, speed=20.0, curvature=0.01, model="dynamic")
    assert plant.operating_point == dynamics.dynamic_feedforward(
        VEH, speed=20.0, curvature=0.01
    )
    with pytest.raises(ValueError, match="input_gain_factor"):
        _ = plant.input_gain_factor
    with pytest.raises(ValueError, match="needs Vehicle fields mass"):
        fws.LateralPlant(fws.Vehicle(2.7, 1.2), speed=5.0, model="dynamic")
    with pytest.raises(ValueError, match="speed must be finite and > 0"):
        fws.LateralPlant(VEH, speed=-5.0, model="dynamic")
    with pytest.raises(ValueError, match="applies only to model='dynamic'"):
        fws.LateralPlant(VEH, speed=5.0, tyre="magic")
    with pytest.raises(ValueError, match="tyre must be one of"):
        fws.LateralPlant(VEH, speed=5.0, model="dynamic", tyre="brush")
    with pytest.raises(ValueError, match="model must be one of"):
        fws.LateralPlant(VEH, speed=5.0, model="Dynamic")
    # 40 m/s on a 50 m radius needs 3.2 g: beyond the magic tyre's peak
    with pytest.raises(ValueError, match="needs a lateral force the tyres cannot give"):
        fws.LateralPlant(VEH, speed=40.0, curvature=0.02, model="dynamic", tyre="magic")


def test_linear_nonlinear_comparison_refuses_the_dynamic_plant():
    plant = fws.LateralPlant(VEH, speed=10.0, model="dynamic")
    g = fws.double_root_gains(replace(plant, model="kinematic"), ratio=0.0, pole=-1.0)
    with pytest.raises(ValueError, match="compares the kinematic models"):
        fws.compare_linear_nonlinear(plant, g, duration=1.0)
