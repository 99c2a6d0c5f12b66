"""Linearisation against control.linearize and sympy; closed loop and polynomial."""

import control as ct
import numpy as np
import pytest
from conftest import lambdify
from hypothesis import given
from hypothesis import strategies as st

import fws_control as fws
from fws_control import symbolic as S

speeds = st.one_of(st.floats(1.0, 40.0), st.floats(-40.0, -1.0))
curvatures = st.floats(-0.3, 0.3)


@given(speed=speeds, curvature=curvatures)
def test_exact_equals_control_linearize_of_path_frame_model(speed, curvature):
    veh = fws.Vehicle(2.7, 1.35)
    nl = fws.path_frame_model(veh, speed, curvature)
    x0, u0 = fws.operating_point(veh, curvature)
    # python-control differentiates by forward differences; step 1e-8
    # balances truncation (~1e-8 |f''|) against round-off (~1e-16/1e-8).
    ref = ct.linearize(nl, x0, u0, copy_names=True, eps=1e-8)
    tol = 1e-6 * abs(speed)
    idx = [ref.state_labels.index(n) for n in ("e", "theta")]
    lin = fws.linearize(veh, speed, curvature, model="exact")
    np.testing.assert_allclose(lin.A, ref.A[np.ix_(idx, idx)], rtol=0, atol=tol)
    np.testing.assert_allclose(lin.B, ref.B[idx, :], rtol=0, atol=tol)
    assert ref.input_labels == lin.input_labels == ["delta_f", "delta_r"]
    # s does not feed back into (e, theta): the reduction to 2 states is exact
    np.testing.assert_allclose(ref.A[np.ix_(idx, [0])], 0.0, atol=tol)


@pytest.mark.parametrize("model", ["exact", "paper"])
def test_matrices_equal_sympy(veh, rng, model):
    A_s, B_s = S.jacobians(model)
    fA, fB = lambdify(A_s), lambdify(B_s)
    for _ in range(30):
        V, k = rng.uniform(-30, 30), rng.uniform(-0.3, 0.3)
        lin = fws.linearize(veh, V, k, model=model)
        args = (V, veh.wheelbase, k, 0, 0, 0, 0)
        np.testing.assert_allclose(
            lin.A, np.asarray(fA(*args), float), rtol=1e-13, atol=1e-14
        )
        np.testing.assert_allclose(
            lin.B, np.asarray(fB(*args), float), rtol=1e-13, atol=1e-14
        )


def test_exact_front_entry_hand_value(veh):
    """B[1,0] = V(1 + f^2 k^2)/f = 5*1.0729/2.7 at V = 5, k = 0.1."""
    lin = fws.linearize(veh, 5.0, 0.1)
    assert lin.B[1, 0] == pytest.approx(5 * 1.0729 / 2.7, rel=1e-14)
    assert fws.linearize(veh, 5.0, 0.1, "paper").B[1, 0] == pytest.approx(5 / 2.7)


def test_names(veh):
    lin = fws.linearize(veh, 5.0, 0.1)
    assert lin.state_labels == ["e", "theta"] and lin.output_labels == ["e", "theta"]
    cl = fws.closed_loop(veh, 5.0, 0.1, fws.SteeringGains(0.1, 0.5, -1.0))
    assert cl.output_labels == ["e", "theta", "delta_f", "delta_r"]
    assert cl.input_labels == ["delta_f_dist", "delta_r_dist"]


@pytest.mark.parametrize("model", ["exact", "paper"])
def test_characteristic_polynomial_equals_sympy_and_eigenvalues(veh, rng, model):
    poly = S.characteristic_polynomial(model).all_coeffs()
    f1, f0 = lambdify(poly[1]), lambdify(poly[2])
    for _ in range(50):
        V, k, a = rng.uniform(-30, 30), rng.uniform(-0.3, 0.3), rng.uniform(-2, 2)
        k1, k2 = rng.uniform(-2, 2, size=2)
        g = fws.SteeringGains(k1, k2, a)
        num = fws.characteristic_polynomial(veh, V, k, g, model=model)
        ref = [
            1.0,
            f1(V, veh.wheelbase, k, a, k1, k2, 0),
            f0(V, veh.wheelbase, k, a, k1, k2, 0),
        ]
        np.testing.assert_allclose(num, ref, rtol=1e-12, atol=1e-12)
        cl = fws.closed_loop(veh, V, k, g, model=model)
        np.testing.assert_allclose(
            np.sort_complex(cl.poles()),
            np.sort_complex(np.roots(num)),
            rtol=1e-9,
            atol=1e-9,
        )


def test_closed_loop_outputs_are_steering_deviation(veh):
    g = fws.SteeringGains(0.3, 0.7, 0.5)
    cl = fws.closed_loop(veh, 5.0, 0.05, g)
    x = np.array([0.4, -0.1])
    w = np.array([0.01, -0.02])
    y = cl.C @ x + cl.D @ w
    df = -0.3 * 0.4 - 0.7 * -0.1 + 0.01
    dr = 0.5 * (-0.3 * 0.4 - 0.7 * -0.1) - 0.02
    np.testing.assert_allclose(y, [0.4, -0.1, df, dr], rtol=1e-14)


def test_characteristic_polynomial_broadcasts(veh):
    ratios = np.linspace(-1.5, 1.5, 7)
    g = fws.SteeringGains(0.2, 0.4, ratios)
    out = fws.characteristic_polynomial(veh, 5.0, 0.1, g)
    assert out.shape == (7, 3)
    for i, a in enumerate(ratios):
        ref = fws.characteristic_polynomial(
            veh, 5.0, 0.1, fws.SteeringGains(0.2, 0.4, a)
        )
        np.testing.assert_allclose(out[i], ref, rtol=1e-15)


def test_errors(veh):
    with pytest.raises(ValueError, match="model"):
        fws.linearize(veh, 5.0, 0.1, model="linear")
    with pytest.raises(ValueError, match="speed"):
        fws.linearize(veh, 0.0, 0.1)
    with pytest.raises(ValueError, match="curvature"):
        fws.linearize(veh, 5.0, np.inf)
    with pytest.raises(TypeError, match="gains"):
        fws.closed_loop(veh, 5.0, 0.1, (0.1, 0.2))
    with pytest.raises(ValueError, match="k1"):
        fws.SteeringGains(np.nan, 0.2, 0.0)
    with pytest.raises(ValueError, match="scalar"):
        fws.closed_loop(veh, 5.0, 0.1, fws.SteeringGains([0.1, 0.2], 0.2, 0.0))


def test_gains_matrix_is_eq33(veh):
    g = fws.SteeringGains(0.1, 0.2, -0.5)
    # hand-evaluated eq. (33): K = -[[k1, k2], [a k1, a k2]]
    np.testing.assert_array_equal(g.matrix, [[-0.1, -0.2], [0.05, 0.1]])
