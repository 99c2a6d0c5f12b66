"""Stability (closed form and Routh-Hurwitz) against closed-loop eigenvalues."""

import numpy as np
import pytest
from conftest import PAPER_VEHICLE, gain_factor
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import fws_control as fws
from fws_control.stability import routh_hurwitz

VEH = PAPER_VEHICLE
_P13 = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)


def _closed_loop_eigenvalues(veh, speed, curvature, k1, k2, ratio, model):
    """Eigenvalues of A + B K for stacked parameters, without the polynomial."""
    c = gain_factor(veh.wheelbase, curvature, model)
    f = veh.wheelbase
    n = np.broadcast(speed, curvature, k1, k2, ratio).shape
    V, kap, k1, k2, a, c = (
        np.broadcast_to(v, n) for v in (speed, curvature, k1, k2, ratio, c)
    )
    A = np.zeros(n + (2, 2))
    A[..., 0, 1] = V
    A[..., 1, 0] = -V * kap**2
    B = np.zeros(n + (2, 2))
    B[..., 0, 1] = V
    B[..., 1, 0] = c * V / f
    B[..., 1, 1] = -V / f
    K = -np.stack([np.stack([k1, k2], -1), np.stack([a * k1, a * k2], -1)], -2)
    return np.linalg.eigvals(A + B @ K)


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_is_stable_agrees_with_eigenvalues_on_random_points(model):
    rng = np.random.default_rng(7)
    n = 120_000
    V = rng.uniform(1, 40, n) * rng.choice([-1, 1], n)
    kap = rng.uniform(-0.3, 0.3, n)
    a = rng.uniform(-2, 2, n)
    k1, k2 = rng.uniform(-2, 2, (2, n))
    eig = _closed_loop_eigenvalues(VEH, V, kap, k1, k2, a, model)
    max_re = eig.real.max(axis=-1)
    # Away from the boundary: the rightmost pole is not within 1e-6 of the
    # imaginary axis relative to the pole magnitude.
    away = np.abs(max_re) > 1e-6 * np.maximum(np.abs(eig).max(axis=-1), 1e-3)
    assert away.sum() >= 100_000
    # One LateralPlant holds all operating points; the gains broadcast with it.
    plant = fws.LateralPlant(VEH, speed=V, curvature=kap, model=model)
    got = fws.is_stable(plant, fws.SteeringGains(k1, k2, a))
    assert got.shape == (n,)
    np.testing.assert_array_equal(got[away], (max_re < 0)[away])
    assert 0.1 < got.mean() < 0.9  # both outcomes are represented


@given(
    model=st.sampled_from(["kinematic", "paper"]),
    speed=st.one_of(st.floats(1, 40), st.floats(-40, -1)),
    curvature=st.floats(-0.3, 0.3),
    ratio=st.floats(-2, 2),
    k1=st.floats(-3, 3),
    k2=st.floats(-3, 3),
)
def test_boundaries_reproduce_eigenvalues(model, speed, curvature, ratio, k1, k2):
    """Both boundary half-planes hold iff the closed-loop poles are stable."""
    eig = _closed_loop_eigenvalues(VEH, speed, curvature, k1, k2, ratio, model)
    max_re = eig.real.max()
    assume(abs(max_re) > 1e-9 * max(np.abs(eig).max(), 1.0))  # off the boundary
    plant = fws.LateralPlant(VEH, speed=speed, curvature=curvature, model=model)
    # omega given: this test is about the lines; the default frequency grid
    # follows the roots of n1, n2, which run off to infinity as ratio -> 0
    bounds = fws.stability_boundaries(plant, ratio=ratio, omega=[1.0, 2.0])
    b1, b0 = bounds  # unpacking gives the two Routh-Hurwitz lines
    assert (b1.condition, b0.condition) == ("p1 > 0", "p0 > 0")
    assert bounds.order == 2 and bounds.real_root == b0
    assert (b1.satisfied(k1, k2) and b0.satisfied(k1, k2)) == (max_re < 0)


@given(
    model=st.sampled_from(["kinematic", "paper"]),
    curvature=st.floats(-0.3, 0.3),
    ratio=st.floats(-2, 2),
    t=st.floats(-2, 2),
)
def test_points_on_boundary_have_a_zero_coefficient(model, curvature, ratio, t):
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=curvature, model=model)
    cp = fws.affine_characteristic_polynomial(plant, ratio=ratio)
    lines = fws.stability_boundaries(plant, ratio=ratio, omega=[1.0]).lines
    for b, which in zip(lines, (1, 2), strict=True):
        if b.degenerate:
            continue
        # a point on the line: foot of the normal plus t along the direction
        k1 = -b.gamma * b.alpha + t * b.beta
        k2 = -b.gamma * b.beta - t * b.alpha
        val = cp.coefficients(k1, k2)[which]
        # p1 = gamma1 + alpha1 k1 + beta1 k2, p0 = gamma0 + alpha0 k1 + beta0 k2
        scale = (
            max(
                abs(cp.n1[1]) + abs(cp.n2[1]),
                abs(cp.n1[2]) + abs(cp.n2[2]) + abs(cp.open_loop[2]),
                1.0,
            )
            * 10
        )
        assert abs(val) < 1e-10 * scale


def test_lines_do_not_depend_on_speed_but_reversing_flips_eq35_side():
    for model in ("kinematic", "paper"):
        fwd, fast, rev = (
            fws.stability_boundaries(
                VEH, speed=V, curvature=0.1, ratio=-0.5, model=model
            ).lines
            for V in (5.0, 20.0, -5.0)
        )
        for p, q in zip(fwd, fast, strict=True):
            assert (p.alpha, p.beta, p.gamma) == pytest.approx(
                (q.alpha, q.beta, q.gamma)
            )
        # (35): same line, opposite side; (36): identical
        assert (rev[0].alpha, rev[0].beta) == pytest.approx(
            (-fwd[0].alpha, -fwd[0].beta)
        )
        assert (rev[1].alpha, rev[1].beta, rev[1].gamma) == pytest.approx(
            (fwd[1].alpha, fwd[1].beta, fwd[1].gamma)
        )


def test_ratio_one_straight_path():
    """Eq. (38): k1 = 0 is the boundary of (35); (36) is degenerate, p0 = 0."""
    for model in ("kinematic", "paper"):
        plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.0, model=model)
        b1, b0 = fws.stability_boundaries(plant, ratio=1.0)
        assert b1.vertical and b1.k1_at(0.7) == pytest.approx(0.0, abs=1e-15)
        assert b0.degenerate and b0.always is False
        k1, k2 = np.meshgrid(np.linspace(-1, 1, 11), np.linspace(-1, 1, 11))
        assert not fws.is_stable(plant, fws.SteeringGains(k1, k2, 1.0)).any()
        eig = _closed_loop_eigenvalues(VEH, 5.0, 0.0, k1, k2, 1.0, model)
        # a zero pole everywhere (heading uncontrollable), the other at -V k1
        np.testing.assert_allclose(np.abs(eig).min(axis=-1), 0.0, atol=1e-12)


def test_segment_lies_on_line_and_in_box():
    b1, b0 = fws.stability_boundaries(VEH, speed=5.0, curvature=0.1, ratio=-1.0)
    for b in (b1, b0):
        seg = b.segment((-1, 1), (-1, 1))
        assert seg is not None and seg.shape == (2, 2)
        np.testing.assert_allclose(
            b.alpha * seg[:, 0] + b.beta * seg[:, 1] + b.gamma, 0.0, atol=1e-14
        )
        assert np.all(np.abs(seg) <= 1 + 1e-12)
    far = fws.stability_boundaries(VEH, speed=5.0, curvature=0.0, ratio=1.0).lines[0]
    assert far.segment((0.5, 1.0), (-1, 1)) is None  # k1 = 0 misses the box


def test_broadcast_grid_shape():
    k1 = np.linspace(-1, 1, 50)
    k2 = np.linspace(-1, 1, 40)[:, None]
    g = fws.SteeringGains(k1, k2, -1.0)
    assert fws.is_stable(VEH, g, speed=5.0, curvature=0.1).shape == (40, 50)


# --------------------------------------------------------------------------
# Operating points as arrays: one call equals a loop of scalar calls
# --------------------------------------------------------------------------


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_array_plant_equals_loop_of_scalar_calls(model):
    rng = np.random.default_rng(11)
    speeds = np.array([-20.0, -1.5, 2.0, 5.0, 30.0])[:, None, None]  # (5, 1, 1)
    kappas = np.array([0.0, -0.05, 0.1, 0.3])[:, None]  # (4, 1)
    k1, k2, a = rng.uniform(-2, 2, (3, 7))  # (7,)
    plant = fws.LateralPlant(VEH, speed=speeds, curvature=kappas, model=model)
    got = fws.is_stable(plant, fws.SteeringGains(k1, k2, a))
    assert got.shape == (5, 4, 7)
    for i in range(5):
        for j in range(4):
            one = fws.LateralPlant(
                VEH, speed=speeds[i, 0, 0], curvature=kappas[j, 0], model=model
            )
            for m in range(7):
                ref = fws.is_stable(one, fws.SteeringGains(k1[m], k2[m], a[m]))
                assert isinstance(ref, bool)
                assert got[i, j, m] == ref
    assert 0 < got.sum() < got.size  # both outcomes are represented


# --------------------------------------------------------------------------
# Routh-Hurwitz: the general path and its n = 2 fast path
# --------------------------------------------------------------------------


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_two_state_fast_path_equals_routh_hurwitz(model):
    """is_stable's closed form p1 > 0, p0 > 0 = routh_hurwitz of the polynomial."""
    rng = np.random.default_rng(2024)
    n = 50_000
    V = rng.uniform(0.5, 40, n) * rng.choice([-1, 1], n)
    kap = rng.uniform(-0.3, 0.3, n)
    k1, k2, a = rng.uniform(-2, 2, (3, n))
    # exact boundary points too: k = 0 on a straight path (p1 = p0 = 0); a = c
    # with k1 = 0 (p1 = 0, p0 = V^2 kappa^2 > 0 on a curve); k1 = 0 on a
    # straight path (p0 = 0, p1 = V (1 - a) k2 / f of either sign)
    kap[:500] = 0.0
    k1[:500] = k2[:500] = 0.0
    k1[500:1000] = 0.0
    a[500:1000] = gain_factor(VEH.wheelbase, kap[500:1000], model)
    kap[1000:1500] = k1[1000:1500] = 0.0
    p = fws.characteristic_polynomial_coefficients(
        fws.LateralPlant(VEH, speed=V[:1500], curvature=kap[:1500], model=model),
        fws.SteeringGains(k1[:1500], k2[:1500], a[:1500]),
    )
    assert np.all(p[:500, 1:] == 0.0) and np.all(p[500:1000, 1] == 0.0)
    assert np.all(p[1000:1500, 2] == 0.0) and np.mean(p[1000:1500, 1] > 0) > 0.3
    plant = fws.LateralPlant(VEH, speed=V, curvature=kap, model=model)
    g = fws.SteeringGains(k1, k2, a)
    fast = fws.is_stable(plant, g)
    general = routh_hurwitz(fws.characteristic_polynomial_coefficients(plant, g))
    np.testing.assert_array_equal(fast, general)
    assert not fast[:1500].any()
    assert 0.1 < fast.mean() < 0.9
    # scalar calls give Python bools through both paths
    for i in range(0, n, 5000):
        gi = fws.SteeringGains(k1[i], k2[i], a[i])
        pi = fws.LateralPlant(VEH, speed=V[i], curvature=kap[i], model=model)
        assert fws.is_stable(pi, gi) is routh_hurwitz(
            fws.characteristic_polynomial_coefficients(pi, gi)
        )


def _rightmost(coefficients):
    """Largest real part of the roots (numpy), and the roots' scale."""
    r = np.roots(coefficients)
    return float(r.real.max()), float(max(1.0, np.abs(r).max()))


@st.composite
def polynomials(draw):
    """Real polynomials of degree 1-6, highest power first.

    Half from random coefficients (mostly unstable for higher degrees), half
    from random roots biased to the left half plane (often stable), each
    with a random nonzero leading coefficient of either sign.
    """
    n = draw(st.integers(1, 6))
    lead = draw(st.floats(0.1, 10.0)) * draw(st.sampled_from([-1.0, 1.0]))
    if draw(st.booleans()):
        rest = draw(st.lists(st.floats(-10, 10), min_size=n, max_size=n))
        return np.array([lead, *rest])
    roots = []
    while len(roots) < n:
        re = draw(st.floats(-4.0, 1.0))
        if len(roots) <= n - 2 and draw(st.booleans()):
            im = draw(st.floats(0.05, 4.0))
            roots += [complex(re, im), complex(re, -im)]
        else:
            roots.append(complex(re, 0.0))
    return lead * np.real(np.poly(roots))


@settings(derandomize=True, max_examples=600, deadline=None)
@given(c=polynomials())
def test_routh_hurwitz_against_numpy_roots(c):
    re, scale = _rightmost(c)
    assume(abs(re) > 1e-6 * scale)  # off the imaginary axis
    assert routh_hurwitz(c) == (re < 0)


def test_routh_hurwitz_batches_equal_numpy_roots():
    """One vectorised call on (m, n + 1) arrays, every degree 1-6."""
    rng = np.random.default_rng(99)
    m = 4000
    for n in range(1, 7):
        roots = rng.uniform(-3.0, 0.6, (m, n)) + 0j
        pairs = rng.random(m) < 0.5
        if n >= 2:  # a complex pair in half of the polynomials
            im = rng.uniform(0.1, 3.0, m)
            roots[pairs, 1] = roots[pairs, 0] - 1j * im[pairs]
            roots[pairs, 0] = roots[pairs, 0] + 1j * im[pairs]
        lead = rng.uniform(0.2, 5.0, m) * rng.choice([-1.0, 1.0], m)
        c = np.stack([lead[i] * np.real(np.poly(roots[i])) for i in range(m)])
        got = routh_hurwitz(c)
        assert got.shape == (m,)
        ref = np.array([_rightmost(ci)[0] for ci in c])
        away = np.abs(ref) > 1e-6 * (1 + np.abs(roots).max(axis=1))
        assert away.mean() > 0.99
        np.testing.assert_array_equal(got[away], (ref < 0)[away])
        assert 0.05 < got.mean() < 0.95  # both outcomes at every degree


def test_routh_hurwitz_boundary_and_bad_input():
    # roots on the imaginary axis are never stable
    assert routh_hurwitz(np.poly([-1.0, 1j, -1j]).real) is False  # (s+1)(s^2+1)
    assert routh_hurwitz([1.0, 1.0, 0.0]) is False  # s (s + 1)
    assert routh_hurwitz([1.0, 0.0]) is False  # s
    assert routh_hurwitz([2.0, 3.0]) is True  # 2 s + 3
    assert routh_hurwitz([-2.0, -3.0]) is True  # same roots, negative lead
    assert routh_hurwitz(np.poly([-1.0, -2.0, -3.0, -4.0])) is True
    assert routh_hurwitz([1.0, np.nan, 1.0]) is False
    with pytest.raises(ValueError, match="coefficients"):
        routh_hurwitz([1.0])


@pytest.mark.parametrize(
    "make, arg, exc",
    [
        (
            lambda: fws.StabilityBoundary(np.nan, 0.0, -0.5, "p0 > 0"),
            "alpha",
            ValueError,
        ),  # fmt: skip
        (lambda: fws.StabilityBoundary(1.0, True, -0.5, "p0 > 0"), "beta", TypeError),
        (
            lambda: fws.StabilityBoundary(1.0, 0.0, -np.inf, "p0 > 0"),
            "gamma",
            ValueError,
        ),  # fmt: skip
        (lambda: fws.StabilityBoundary(1.0, 0.0, -0.5, 0.0), "condition", TypeError),
        (lambda: fws.stability_boundaries(_P13, ratio=1e300), "ratio", ValueError),
        (
            lambda: fws.stability_chart(_P13, ratio=-1e300, pole=-1.0),
            "ratio",
            ValueError,
        ),  # fmt: skip
        (
            lambda: fws.delay_margin_chart(_P13, ratio=1e300, pole=-1.0),
            "ratio",
            ValueError,
        ),  # fmt: skip
        (
            lambda: fws.delay_margin_chart(_P13, ratio=0.0, pole=-1e300),
            "pole",
            ValueError,
        ),  # fmt: skip
    ],
)
def test_issue13_boundary_fields_and_extreme_ratio(make, arg, exc):
    # before: NaN/bool coefficients stored, a number as condition, and a
    # ratio of 1e300 overflowing the coefficients to non-finite lines
    with pytest.raises(exc, match=rf"\b{arg}\b"):
        make()


def test_boundary_at_max_ratio_is_finite_and_matches_is_stable():
    # at |a| = MAX_RATIO the lines are finite; a point on the stable side of
    # both is stable by the Hurwitz test of is_stable (independent path)
    a = -fws.validation.MAX_RATIO
    b = fws.stability_boundaries(_P13, ratio=a)
    for ln in b.lines:
        assert np.isfinite([ln.alpha, ln.beta, ln.gamma]).all()
    g = fws.double_root_gains(_P13, ratio=a, pole=-1.0)
    inside = all(ln.satisfied(g.k1, g.k2) for ln in b.lines)
    assert inside == bool(fws.is_stable(_P13, g))
