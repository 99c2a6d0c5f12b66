"""Closed-form Routh-Hurwitz stability against closed-loop eigenvalues."""

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import fws_control as fws

VEH = fws.Vehicle(2.7, 1.35)


def _closed_loop_eigenvalues(veh, speed, curvature, k1, k2, ratio, model):
    """Eigenvalues of A + B K for stacked parameters, without the polynomial."""
    c = fws.input_gain_factor(veh, curvature, model)
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


@pytest.mark.parametrize("model", ["exact", "paper"])
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
    got = fws.is_stable(VEH, V, kap, k1, k2, a, model=model)
    np.testing.assert_array_equal(got[away], (max_re < 0)[away])
    assert 0.1 < got.mean() < 0.9  # both outcomes are represented


@given(
    model=st.sampled_from(["exact", "paper"]),
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
    b1, b0 = fws.stability_boundaries(VEH, speed, curvature, ratio, model=model)
    assert (b1.satisfied(k1, k2) and b0.satisfied(k1, k2)) == (max_re < 0)


@given(
    model=st.sampled_from(["exact", "paper"]),
    curvature=st.floats(-0.3, 0.3),
    ratio=st.floats(-2, 2),
    t=st.floats(-2, 2),
)
def test_points_on_boundary_have_a_zero_coefficient(model, curvature, ratio, t):
    for b, coef in zip(
        fws.stability_boundaries(VEH, 5.0, curvature, ratio, model),
        ("p1", "p0"),
        strict=True,
    ):
        if b.degenerate:
            continue
        # a point on the line: foot of the normal plus t along the direction
        k1 = -b.gamma * b.alpha + t * b.beta
        k2 = -b.gamma * b.beta - t * b.alpha
        cc = fws.characteristic_coefficients(VEH, 5.0, curvature, ratio, model)
        val = getattr(cc, coef)(k1, k2)
        scale = (
            max(
                abs(cc.alpha1) + abs(cc.beta1),
                abs(cc.alpha0) + abs(cc.beta0) + abs(cc.gamma0),
                1.0,
            )
            * 10
        )
        assert abs(val) < 1e-10 * scale


def test_lines_do_not_depend_on_speed_but_reversing_flips_eq35_side():
    for model in ("exact", "paper"):
        fwd = fws.stability_boundaries(VEH, 5.0, 0.1, -0.5, model)
        fast = fws.stability_boundaries(VEH, 20.0, 0.1, -0.5, model)
        rev = fws.stability_boundaries(VEH, -5.0, 0.1, -0.5, model)
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
    for model in ("exact", "paper"):
        b1, b0 = fws.stability_boundaries(VEH, 5.0, 0.0, 1.0, model)
        assert b1.vertical and b1.k1_at(0.7) == pytest.approx(0.0, abs=1e-15)
        assert b0.degenerate and b0.always is False
        k1, k2 = np.meshgrid(np.linspace(-1, 1, 11), np.linspace(-1, 1, 11))
        assert not fws.is_stable(VEH, 5.0, 0.0, k1, k2, 1.0, model).any()
        eig = _closed_loop_eigenvalues(VEH, 5.0, 0.0, k1, k2, 1.0, model)
        # a zero pole everywhere (heading uncontrollable), the other at -V k1
        np.testing.assert_allclose(np.abs(eig).min(axis=-1), 0.0, atol=1e-12)


def test_segment_lies_on_line_and_in_box():
    b1, b0 = fws.stability_boundaries(VEH, 5.0, 0.1, -1.0)
    for b in (b1, b0):
        seg = b.segment((-1, 1), (-1, 1))
        assert seg is not None and seg.shape == (2, 2)
        np.testing.assert_allclose(
            b.alpha * seg[:, 0] + b.beta * seg[:, 1] + b.gamma, 0.0, atol=1e-14
        )
        assert np.all(np.abs(seg) <= 1 + 1e-12)
    far = fws.stability_boundaries(VEH, 5.0, 0.0, 1.0)[0]
    assert far.segment((0.5, 1.0), (-1, 1)) is None  # k1 = 0 misses the box


def test_broadcast_grid_shape():
    k1 = np.linspace(-1, 1, 50)
    k2 = np.linspace(-1, 1, 40)[:, None]
    assert fws.is_stable(VEH, 5.0, 0.1, k1, k2, -1.0).shape == (40, 50)
