"""Linearisation against control.linearize and sympy; closed loop and polynomial."""

import math

import control as ct
import numpy as np
import pytest
from conftest import PAPER_VEHICLE, lambdify
from hypothesis import given
from hypothesis import strategies as st

import fws_control as fws
from fws_control import symbolic as S

speeds = st.one_of(st.floats(1.0, 40.0), st.floats(-40.0, -1.0))
curvatures = st.floats(-0.3, 0.3)


@given(speed=speeds, curvature=curvatures)
def test_exact_equals_control_linearize_of_path_frame_model(speed, curvature):
    veh = PAPER_VEHICLE
    nl = fws.path_frame_model(veh, speed=speed, curvature=curvature)
    # Operating point of eqs. (26)-(27), written out: (s, e, theta) = 0,
    # delta_f = atan(kappa f), delta_r = 0.
    x0, u0 = np.zeros(3), np.array([math.atan(curvature * 2.7), 0.0])
    # python-control differentiates by forward differences; step 1e-8
    # balances truncation (~1e-8 |f''|) against round-off (~1e-16/1e-8).
    ref = ct.linearize(nl, x0, u0, copy_names=True, eps=1e-8)
    tol = 1e-6 * abs(speed)
    idx = [ref.state_labels.index(n) for n in ("e", "theta")]
    lin = fws.linearize(veh, speed=speed, curvature=curvature, model="kinematic")
    np.testing.assert_allclose(lin.A, ref.A[np.ix_(idx, idx)], rtol=0, atol=tol)
    np.testing.assert_allclose(lin.B, ref.B[idx, :], rtol=0, atol=tol)
    assert ref.input_labels == lin.input_labels == ["delta_f", "delta_r"]
    # s does not feed back into (e, theta): the reduction to 2 states is exact
    np.testing.assert_allclose(ref.A[np.ix_(idx, [0])], 0.0, atol=tol)


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_matrices_equal_sympy(veh, rng, model):
    A_s, B_s = S.jacobians(model)
    fA, fB = lambdify(A_s), lambdify(B_s)
    for _ in range(30):
        V, k = rng.uniform(-30, 30), rng.uniform(-0.3, 0.3)
        plant = fws.LateralPlant(veh, speed=V, curvature=k, model=model)
        args = (V, veh.wheelbase, k, 0, 0, 0, 0)
        ref_A, ref_B = np.asarray(fA(*args), float), np.asarray(fB(*args), float)
        # the plant object and the Vehicle convenience keywords agree
        for lin in (
            fws.linearize(veh, speed=V, curvature=k, model=model),
            fws.linearize(plant),
            plant.linearize(),
        ):
            np.testing.assert_allclose(lin.A, ref_A, rtol=1e-13, atol=1e-14)
            np.testing.assert_allclose(lin.B, ref_B, rtol=1e-13, atol=1e-14)
        # input_gain_factor is c of B[1, 0] = c V / f (sympy)
        assert plant.input_gain_factor == pytest.approx(
            ref_B[1, 0] * veh.wheelbase / V, rel=1e-13
        )


def test_exact_front_entry_hand_value(veh):
    """B[1,0] = V(1 + f^2 k^2)/f = 5*1.0729/2.7 at V = 5, k = 0.1."""
    lin = fws.linearize(veh, speed=5.0, curvature=0.1)
    assert lin.B[1, 0] == pytest.approx(5 * 1.0729 / 2.7, rel=1e-14)
    paper = fws.linearize(veh, speed=5.0, curvature=0.1, model="paper")
    assert paper.B[1, 0] == pytest.approx(5 / 2.7)
    assert fws.LateralPlant(veh, 5.0, curvature=0.1).input_gain_factor == pytest.approx(
        1.0729, rel=1e-14
    )
    assert (
        fws.LateralPlant(veh, 5.0, curvature=0.1, model="paper").input_gain_factor
        == 1.0
    )


def test_names(veh):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    lin = fws.linearize(plant)
    assert lin.state_labels == ["e", "theta"] and lin.output_labels == ["e", "theta"]
    assert lin.input_labels == ["delta_f", "delta_r"]
    cl = fws.closed_loop(plant, fws.SteeringGains(0.1, 0.5, -1.0))
    assert cl.output_labels == ["e", "theta", "delta_f", "delta_r"]
    assert cl.input_labels == ["delta_f_dist", "delta_r_dist"]
    assert cl.state_labels == ["e", "theta"]


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_characteristic_polynomial_equals_sympy_and_eigenvalues(veh, rng, model):
    poly = S.characteristic_polynomial(model).all_coeffs()
    f1, f0 = lambdify(poly[1]), lambdify(poly[2])
    for _ in range(50):
        V, k, a = rng.uniform(-30, 30), rng.uniform(-0.3, 0.3), rng.uniform(-2, 2)
        k1, k2 = rng.uniform(-2, 2, size=2)
        g = fws.SteeringGains(k1, k2, a)
        plant = fws.LateralPlant(veh, speed=V, curvature=k, model=model)
        num = fws.characteristic_polynomial_coefficients(plant, g)
        ref = [
            1.0,
            f1(V, veh.wheelbase, k, a, k1, k2, 0),
            f0(V, veh.wheelbase, k, a, k1, k2, 0),
        ]
        np.testing.assert_allclose(num, ref, rtol=1e-12, atol=1e-12)
        cl = fws.closed_loop(plant, g)
        np.testing.assert_allclose(
            np.sort_complex(cl.poles()),
            np.sort_complex(np.roots(num)),
            rtol=1e-9,
            atol=1e-9,
        )


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_affine_parts_equal_sympy_derivatives(veh, rng, model):
    """open_loop, n1, n2 are p at k = 0 and the partial derivatives in k1, k2."""
    k1s, k2s = S.SYMBOLS["k1"], S.SYMBOLS["k2"]
    coeffs = S.characteristic_polynomial(model).all_coeffs()
    parts = [
        [lambdify(c.subs({k1s: 0, k2s: 0})) for c in coeffs],
        [lambdify(c.diff(k1s)) for c in coeffs],
        [lambdify(c.diff(k2s)) for c in coeffs],
    ]
    for _ in range(30):
        V, k, a = rng.uniform(-30, 30), rng.uniform(-0.3, 0.3), rng.uniform(-2, 2)
        plant = fws.LateralPlant(veh, speed=V, curvature=k, model=model)
        cp = fws.affine_characteristic_polynomial(plant, ratio=a)
        assert cp.order == 2
        args = (V, veh.wheelbase, k, a, 0, 0, 0)
        for got, funcs in zip((cp.open_loop, cp.n1, cp.n2), parts, strict=True):
            ref = [float(fn(*args)) for fn in funcs]
            np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12)


def test_affine_polynomial_evaluate_equals_polyval(veh, rng):
    """evaluate(s, k1, k2) and polynomials_at(s) against numpy.polyval."""
    for V, k, a, model in ((5.0, 0.1, -1.0, "kinematic"), (-20.0, 0.02, 0.7, "paper")):
        cp = fws.affine_characteristic_polynomial(
            fws.LateralPlant(veh, speed=V, curvature=k, model=model), ratio=a
        )
        s = rng.uniform(-3, 3, 40) + 1j * rng.uniform(-3, 3, 40)
        for k1, k2 in rng.uniform(-2, 2, (10, 2)):
            g = fws.SteeringGains(k1, k2, a)
            coeffs = fws.characteristic_polynomial_coefficients(
                fws.LateralPlant(veh, speed=V, curvature=k, model=model), g
            )
            ref = np.polyval(coeffs, s)
            np.testing.assert_allclose(cp.evaluate(s, k1, k2), ref, rtol=1e-13)
            # and det(sI - A_cl) of the closed loop, by numpy
            A_cl = fws.closed_loop(
                fws.LateralPlant(veh, speed=V, curvature=k, model=model), g
            ).A
            det = np.linalg.det(s[:, None, None] * np.eye(2) - A_cl)
            np.testing.assert_allclose(cp.evaluate(s, k1, k2), det, rtol=1e-10)
        d, n1, n2 = cp.polynomials_at(s)
        for got, c in zip((d, n1, n2), (cp.open_loop, cp.n1, cp.n2), strict=True):
            np.testing.assert_allclose(got, np.polyval(c, s), rtol=1e-13)
        # gains that broadcast against s: shape (10, 40)
        k1 = rng.uniform(-2, 2, (10, 1))
        out = cp.evaluate(s, k1, 0.3)
        assert out.shape == (10, 40)
        for i in range(10):
            ref = np.polyval(cp.open_loop + k1[i, 0] * cp.n1 + 0.3 * cp.n2, s)
            np.testing.assert_allclose(out[i], ref, rtol=1e-13)


def test_closed_loop_outputs_are_steering_deviation(veh):
    g = fws.SteeringGains(0.3, 0.7, 0.5)
    cl = fws.closed_loop(veh, g, speed=5.0, curvature=0.05)
    x = np.array([0.4, -0.1])
    w = np.array([0.01, -0.02])
    y = cl.C @ x + cl.D @ w
    df = -0.3 * 0.4 - 0.7 * -0.1 + 0.01
    dr = 0.5 * (-0.3 * 0.4 - 0.7 * -0.1) - 0.02
    np.testing.assert_allclose(y, [0.4, -0.1, df, dr], rtol=1e-14)


def test_characteristic_polynomial_broadcasts(veh):
    ratios = np.linspace(-1.5, 1.5, 7)
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    g = fws.SteeringGains(0.2, 0.4, ratios)
    out = fws.characteristic_polynomial_coefficients(plant, g)
    assert out.shape == (7, 3)
    for i, a in enumerate(ratios):
        ref = fws.characteristic_polynomial_coefficients(
            plant, fws.SteeringGains(0.2, 0.4, a)
        )
        np.testing.assert_allclose(out[i], ref, rtol=1e-15)


def test_errors(veh):
    with pytest.raises(ValueError, match="model"):
        fws.linearize(veh, speed=5.0, curvature=0.1, model="linear")
    with pytest.raises(ValueError, match="speed"):
        fws.linearize(veh, speed=0.0, curvature=0.1)
    with pytest.raises(ValueError, match="curvature"):
        fws.linearize(veh, speed=5.0, curvature=np.inf)
    with pytest.raises(TypeError, match="gains"):
        fws.closed_loop(veh, (0.1, 0.2), speed=5.0, curvature=0.1)
    with pytest.raises(ValueError, match="k1"):
        fws.SteeringGains(np.nan, 0.2, 0.0)
    with pytest.raises(ValueError, match="scalar"):
        fws.closed_loop(
            veh, fws.SteeringGains([0.1, 0.2], 0.2, 0.0), speed=5.0, curvature=0.1
        )
    # a plant holding several operating points has no single state space
    with pytest.raises(ValueError, match=r"speed and curvature have shape \(2,\)"):
        fws.LateralPlant(veh, speed=[5.0, 6.0]).linearize()
    with pytest.raises(ValueError, match="broadcast"):
        fws.LateralPlant(veh, speed=[5.0, 6.0], curvature=[0.1, 0.2, 0.3])


def test_gains_matrices_are_eq33_and_python_control_sign(veh):
    g = fws.SteeringGains(0.1, 0.2, -0.5)
    # hand-evaluated eq. (33): K_paper = -[[k1, k2], [a k1, a k2]]
    np.testing.assert_array_equal(g.K_paper, [[-0.1, -0.2], [0.05, 0.1]])
    # python-control's u = -K y
    np.testing.assert_array_equal(g.K, [[0.1, 0.2], [-0.05, -0.1]])
    # closed_loop's A is A + B K_paper = A - B K (B from sympy, eq. 33 / exact)
    lin = fws.linearize(veh, speed=5.0, curvature=0.1)
    cl = fws.closed_loop(veh, g, speed=5.0, curvature=0.1)
    np.testing.assert_allclose(cl.A, lin.A + lin.B @ g.K_paper, rtol=1e-14)
    np.testing.assert_allclose(cl.A, lin.A - lin.B @ g.K, rtol=1e-14)


# --------------------------------------------------------------------------
# as_plant: what counts as a plant
# --------------------------------------------------------------------------


def test_as_plant_builds_and_passes_through(veh):
    plant = fws.as_plant(veh, speed=5.0)
    assert isinstance(plant, fws.LateralPlant)
    assert (plant.vehicle, plant.speed, plant.curvature, plant.model) == (
        veh,
        5.0,
        0.0,
        "kinematic",
    )
    plant = fws.as_plant(veh, speed=-3.0, curvature=0.2, model="paper")
    assert (plant.speed, plant.curvature, plant.model) == (-3.0, 0.2, "paper")
    lp = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    assert fws.as_plant(lp) is lp
    sys = lp.linearize()
    assert fws.as_plant(sys) is sys


@pytest.mark.parametrize("keyword", ["speed", "curvature", "model"])
def test_as_plant_keywords_only_with_a_vehicle(veh, keyword):
    value = {"speed": 5.0, "curvature": 0.1, "model": "paper"}[keyword]
    lp = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    for plant in (lp, lp.linearize()):
        with pytest.raises(TypeError, match=rf"{keyword}=.*applies only to a Vehicle"):
            fws.as_plant(plant, **{keyword: value})


def test_as_plant_vehicle_needs_speed(veh):
    for kwargs in ({}, {"curvature": 0.1}, {"model": "paper"}):
        with pytest.raises(TypeError, match="speed="):
            fws.as_plant(veh, **kwargs)
    # and so does every analysis function fed a bare Vehicle
    with pytest.raises(TypeError, match="speed="):
        fws.linearize(veh, curvature=0.1)


def test_as_plant_refuses_other_objects(veh):
    nonlinear = fws.path_frame_model(veh, speed=5.0)
    for bad in ("car", None, np.eye(2), 5.0, ct.tf([1.0], [1.0, 1.0]), nonlinear):
        with pytest.raises(TypeError, match="^plant must be"):
            fws.as_plant(bad)
    # a nonlinear system is told how to get a linear one
    with pytest.raises(TypeError, match="linearize"):
        fws.as_plant(nonlinear)


@pytest.mark.parametrize(
    "kw, arg",
    [
        (dict(speed=1e300, curvature=0.1), "speed"),
        (dict(speed=-2e6, curvature=0.1), "speed"),
        (dict(speed=5.0, curvature=1e300), "curvature"),
        (dict(speed=5.0, curvature=-1e7), "curvature"),
    ],
)
def test_extreme_speed_or_curvature_refused_with_range(veh, kw, arg):
    # issue 13: V^2 kappa^2 overflowed to inf in A; now a range refusal
    with pytest.raises(ValueError, match=rf"{arg} must be finite with magnitude"):
        fws.LateralPlant(veh, **kw)
    # at the bounds themselves A holds the hand values -V kappa^2 and V
    V, k = fws.validation.MAX_SPEED, fws.validation.MAX_CURVATURE
    A, _ = fws.LateralPlant(veh, speed=V, curvature=k).matrices()
    assert A[1, 0] == pytest.approx(-V * k * k) and A[0, 1] == pytest.approx(V)
