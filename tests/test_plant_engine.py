"""Plant-first analysis engine (API 0.2) against independent references.

Every plant here is built in the test: the kinematic 2-state model written
out by hand as a ``control.StateSpace``, and a 4-state plant (the kinematic
model behind a first-order lag on each steering input) assembled with
``control.interconnect``. The references are python-control (``ct.acker``,
``ct.place``, ``ct.ss2tf``), numpy eigenvalues and ``np.poly`` of closed-loop
matrices built here, and the closed forms

    p1 = V a k1 + V (c - a)/f k2,
    p0 = V^2/f ((c - a) k1 + (1 - a k2) f kappa^2),  c = 1 + f^2 kappa^2,

of the 2-state characteristic polynomial ``s^2 + p1 s + p0``.

The feedback is ``u = [1, a]^T (-k1 e - k2 theta)``, so the closed-loop matrix
is ``A - b (k1 c_e + k2 c_theta)`` with ``b = B[:, delta_f] + a B[:, delta_r]``
and ``c_e, c_theta`` the rows of C of the outputs ``e`` and ``theta``.
"""

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control as fws
from fws_control import exceptions

F = 2.7
VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
TAU_F, TAU_R = 0.1, 0.2
NAMES = ["e", "theta"]
INPUTS = ["delta_f", "delta_r"]

#: (speed, curvature, model): straight, curves, reversing, the paper's model.
OPERATING_POINTS = [
    (5.0, 0.0, "kinematic"),
    (5.0, 0.1, "kinematic"),
    (20.0, 0.01, "kinematic"),
    (-3.0, 0.05, "kinematic"),
    (-5.0, 0.0, "kinematic"),
    (5.0, 0.1, "paper"),
]
RATIOS = [-1.0, 0.0, 0.5, 2.0]
POLES = [-1.0, -2.5]


# --------------------------------------------------------------------------
# Plants and references built in the test
# --------------------------------------------------------------------------


def gain_factor(curvature, model="kinematic"):
    """c = 1 + f^2 kappa^2 (exact Jacobian) or 1 (paper, eq. 33)."""
    return 1.0 + (F * np.asarray(curvature)) ** 2 if model == "kinematic" else 1.0


def kinematic_matrices(speed, curvature, model="kinematic"):
    c = gain_factor(curvature, model)
    A = np.array([[0.0, speed], [-speed * curvature**2, 0.0]])
    B = np.array([[0.0, speed], [c * speed / F, -speed / F]])
    return A, B


def hand_plant(speed, curvature, model="kinematic"):
    """The kinematic 2-state plant as a named ct.StateSpace, by hand."""
    A, B = kinematic_matrices(speed, curvature, model)
    return ct.ss(
        A, B, np.eye(2), np.zeros((2, 2)), states=NAMES, inputs=INPUTS, outputs=NAMES
    )


def lagged_plant(speed, curvature, tau_f=TAU_F, tau_r=TAU_R):
    """4 states: the kinematic plant behind a first-order lag on each input.

    Inputs ``delta_f, delta_r`` are the steering commands; outputs ``e,
    theta``; the states are named by ``ct.interconnect`` (``kin_e``, ...), so
    the engine has to pick e and theta among the outputs.
    """
    A, B = kinematic_matrices(speed, curvature)
    kin = ct.ss(
        A,
        B,
        np.eye(2),
        np.zeros((2, 2)),
        states=NAMES,
        inputs=["df_act", "dr_act"],
        outputs=NAMES,
        name="kin",
    )
    lag_f = ct.ss(
        ct.tf([1.0], [tau_f, 1.0]), inputs=["delta_f"], outputs=["df_act"], name="lag_f"
    )
    lag_r = ct.ss(
        ct.tf([1.0], [tau_r, 1.0]), inputs=["delta_r"], outputs=["dr_act"], name="lag_r"
    )
    plant = ct.interconnect(
        [kin, lag_f, lag_r], inputs=INPUTS, outputs=NAMES, name="lagged"
    )
    assert plant.nstates == 4 and plant.isctime()
    return plant


def loop_vectors(plant, ratio):
    """(A, b, c_e, c_theta) picked by name, in the test."""
    A, B, C = plant.A, plant.B, plant.C
    b = (
        B[:, plant.input_index["delta_f"]]
        + np.asarray(ratio)[..., None] * (B[:, plant.input_index["delta_r"]])
    )
    return A, b, C[plant.output_index["e"]], C[plant.output_index["theta"]]


def closed_loop_matrix(plant, k1, k2, ratio):
    """A - b (k1 c_e + k2 c_theta), broadcast over k1, k2, ratio: (..., n, n)."""
    A, b, ce, cth = loop_vectors(plant, ratio)
    row = np.asarray(k1, dtype=float)[..., None] * ce + (
        np.asarray(k2, dtype=float)[..., None] * cth
    )
    return A - b[..., :, None] * row[..., None, :]


def poly_from_roots(roots):
    """Monic polynomials (highest power first) of the rows of `roots`."""
    roots = np.asarray(roots, dtype=complex)
    c = np.ones(roots.shape[:-1] + (1,), dtype=complex)
    for i in range(roots.shape[-1]):
        r = roots[..., i : i + 1]
        zero = np.zeros_like(r)
        c = np.concatenate([c, zero], -1) - r * np.concatenate([zero, c], -1)
    scale = np.maximum(np.abs(c).max(-1, keepdims=True), 1.0)
    assert np.all(np.abs(c.imag) <= 1e-9 * scale)  # conjugate pairs
    return c.real


def closed_form_p(speed, curvature, k1, k2, ratio, model="kinematic"):
    """(p1, p0) of the 2-state plant and the scale of their terms."""
    V, kap, a = speed, curvature, ratio
    c = gain_factor(kap, model)
    t1 = (V * a * k1, V * (c - a) / F * k2)
    t0 = (V**2 / F * (c - a) * k1, V**2 * kap**2 + 0 * k1, -(V**2) * a * k2 * kap**2)
    p1, p0 = t1[0] + t1[1], t0[0] + t0[1] + t0[2]
    s1 = np.abs(t1[0]) + np.abs(t1[1])
    s0 = np.abs(t0[0]) + np.abs(t0[1]) + np.abs(t0[2])
    return p1, p0, s1, s0


def assert_close(got, ref, rtol, axis=None):
    """|got - ref| <= rtol * max|ref| (over `axis`, or the whole array)."""
    got = np.asarray(got, dtype=float)
    ref = np.asarray(ref, dtype=float)
    assert got.shape == ref.shape, (got.shape, ref.shape)
    scale = np.maximum(np.abs(ref).max(axis=axis, keepdims=axis is not None), 1e-300)
    err = np.abs(got - ref)
    bad = err > rtol * scale
    assert not np.any(bad), (
        f"{bad.sum()} of {bad.size} entries off by more than rtol={rtol:g}: "
        f"worst relative error {np.max(err / scale):.3g}"
    )


def gains_of(g):
    return np.array([float(g.k1), float(g.k2)])


def three_paths(speed, curvature, model):
    """The same operating point as a hand-built StateSpace, a LateralPlant and
    Vehicle keywords (the last as a (plant, keywords) pair)."""
    return (
        (hand_plant(speed, curvature, model), {}),
        (fws.LateralPlant(VEH, speed, curvature=curvature, model=model), {}),
        (VEH, {"speed": speed, "curvature": curvature, "model": model}),
    )


# --------------------------------------------------------------------------
# 1. A hand-built StateSpace reaches the same answers as LateralPlant
# --------------------------------------------------------------------------


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_linearize_paths_equal_the_hand_matrices(op):
    V, kap, model = op
    A, B = kinematic_matrices(V, kap, model)
    plant = fws.LateralPlant(VEH, V, curvature=kap, model=model)
    assert float(plant.input_gain_factor) == pytest.approx(
        gain_factor(kap, model), rel=1e-15
    )
    for sys in (
        plant.linearize(),
        fws.linearize(plant),
        fws.linearize(VEH, speed=V, curvature=kap, model=model),
        fws.linearize(hand_plant(V, kap, model)),
    ):
        assert isinstance(sys, ct.StateSpace)
        assert sys.state_labels == NAMES
        assert sys.input_labels == INPUTS
        assert sys.output_labels == NAMES
        assert_close(sys.A, A, 1e-15)
        assert_close(sys.B, B, 1e-15)
        assert_close(sys.C, np.eye(2), 0.0)
        assert not np.any(sys.D)


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_double_root_gains_same_for_statespace_and_lateral_plant(op):
    V, kap, model = op
    A, B = kinematic_matrices(V, kap, model)
    for a in RATIOS:
        for pole in POLES:
            got = [
                fws.double_root_gains(p, ratio=a, pole=pole, **kw)
                for p, kw in three_paths(V, kap, model)
            ]
            ref = gains_of(got[1])  # LateralPlant path
            for g in got:
                assert float(g.ratio) == a
                assert_close(gains_of(g), ref, 1e-12)
            # Independent reference: Ackermann on the single input b = B [1, a]
            # gives K of u = -K x, i.e. [k1, k2].
            K = np.ravel(ct.acker(A, B @ np.array([1.0, a]), [pole, pole]))
            assert_close(gains_of(got[0]), K, 1e-9)


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_is_stable_same_for_statespace_and_lateral_plant(op):
    V, kap, model = op
    rng = np.random.default_rng(101)
    n = 20_000
    A, B = kinematic_matrices(V, kap, model)
    for a in RATIOS:
        k1, k2 = rng.uniform(-2.0, 2.0, (2, n))
        gains = fws.SteeringGains(k1, k2, a)
        got = [fws.is_stable(p, gains, **kw) for p, kw in three_paths(V, kap, model)]
        # Reference: eigenvalues of A - B [1, a]^T [k1, k2].
        Acl = A - (B @ np.array([1.0, a]))[:, None] * np.stack([k1, k2], -1)[:, None, :]
        eig = np.linalg.eigvals(Acl)
        max_re = eig.real.max(-1)
        away = np.abs(max_re) > 1e-9 * np.maximum(np.abs(eig).max(-1), 1.0)
        assert away.mean() > 0.99
        assert 0.02 < (max_re < 0).mean() < 0.98
        for verdict in got:
            assert verdict.shape == (n,) and verdict.dtype == bool
            np.testing.assert_array_equal(verdict[away], (max_re < 0)[away])
        np.testing.assert_array_equal(got[0][away], got[1][away])
        # A scalar gain gives a Python bool.
        assert isinstance(
            fws.is_stable(hand_plant(V, kap, model), fws.SteeringGains(0.1, 0.5, a)),
            bool,
        )


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_stability_chart_same_for_statespace_and_lateral_plant(op):
    V, kap, model = op
    k1 = np.linspace(-1.3, 0.9, 157)  # different lengths: catches a transpose
    k2 = np.linspace(-0.8, 1.1, 143)
    K1, K2 = np.meshgrid(k1, k2)
    for a in RATIOS:
        charts = [
            fws.stability_chart(p, ratio=a, k1=k1, k2=k2, pole=-1.0, **kw)
            for p, kw in three_paths(V, kap, model)
        ]
        p1, p0, s1, s0 = closed_form_p(V, kap, K1, K2, a, model)
        ref = (p1 > 0) & (p0 > 0)
        away = (np.abs(p1) > 1e-9 * s1) & (np.abs(p0) > 1e-9 * s0)
        ref_lines = charts[1].boundaries.lines
        for ch in charts:
            assert ch.stable.shape == (len(k2), len(k1))
            np.testing.assert_array_equal(ch.stable[away], ref[away])
            assert ch.stable_fraction == pytest.approx(np.mean(ch.stable), abs=0)
            assert ch.stable_fraction == pytest.approx(np.mean(ref), abs=0.01)
            assert gains_of(ch.design) == pytest.approx(
                gains_of(charts[1].design), rel=1e-12, abs=1e-12
            )
            lines = ch.boundaries.lines
            assert len(lines) == 2
            for got, want in zip(lines, ref_lines, strict=True):
                assert_close(
                    [got.alpha, got.beta, got.gamma],
                    [want.alpha, want.beta, want.gamma],
                    1e-12,
                )
            rr, rr_ref = ch.boundaries.real_root, charts[1].boundaries.real_root
            assert_close(
                [rr.alpha, rr.beta, rr.gamma],
                [rr_ref.alpha, rr_ref.beta, rr_ref.gamma],
                1e-12,
            )
            cr, cr_ref = ch.boundaries.complex_root, charts[1].boundaries.complex_root
            assert_close(cr.omega, cr_ref.omega, 1e-12)
            assert_close(cr.k1, cr_ref.k1, 1e-12)
            assert_close(cr.k2, cr_ref.k2, 1e-12)
        # The design is the Ackermann gain pair.
        A, B = kinematic_matrices(V, kap, model)
        K = np.ravel(ct.acker(A, B @ np.array([1.0, a]), [-1.0, -1.0]))
        assert_close(gains_of(charts[0].design), K, 1e-9)


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_gain_locus_same_for_statespace_and_lateral_plant(op):
    V, kap, model = op
    scale = np.array([0.1, 0.5, 1.0, 2.0, 5.0])
    for a in RATIOS:
        g = fws.SteeringGains(0.3, 0.7, a)
        loci = [
            fws.gain_locus(p, g, scale=scale, **kw).loci
            for p, kw in three_paths(V, kap, model)
        ]
        # Compare the polynomials the loci define: well conditioned even where
        # two poles (nearly) coincide, unlike the roots themselves.
        polys = [poly_from_roots(lo) for lo in loci]
        Acl = closed_loop_matrix(hand_plant(V, kap, model), scale * 0.3, scale * 0.7, a)
        ref = poly_from_roots(np.linalg.eigvals(Acl))
        for lo, pol in zip(loci, polys, strict=True):
            assert lo.shape == (len(scale), 2)
            assert_close(pol, polys[1], 1e-12, axis=-1)
            assert_close(pol, ref, 1e-9, axis=-1)


@pytest.mark.parametrize("op", OPERATING_POINTS)
@pytest.mark.parametrize("parameter", ["ratio", "k1", "k2"])
def test_parameter_locus_same_for_statespace_and_lateral_plant(op, parameter):
    V, kap, model = op
    g = fws.SteeringGains(0.3, 0.7, -0.5)
    values = {
        "ratio": np.linspace(-2.0, 2.0, 33),
        "k1": np.linspace(-1.0, 1.0, 33),
        "k2": np.linspace(-1.5, 1.5, 33),
    }[parameter]
    loci = [
        fws.parameter_locus(p, g, parameter=parameter, values=values, **kw).loci
        for p, kw in three_paths(V, kap, model)
    ]
    par = {"k1": 0.3, "k2": 0.7, "ratio": -0.5, parameter: values}
    Acl = closed_loop_matrix(
        hand_plant(V, kap, model),
        np.broadcast_to(par["k1"], values.shape),
        np.broadcast_to(par["k2"], values.shape),
        np.broadcast_to(par["ratio"], values.shape),
    )
    ref = poly_from_roots(np.linalg.eigvals(Acl))
    polys = [poly_from_roots(lo) for lo in loci]
    for lo, pol in zip(loci, polys, strict=True):
        assert lo.shape == (len(values), 2)
        assert_close(pol, polys[1], 1e-12, axis=-1)
        assert_close(pol, ref, 1e-9, axis=-1)


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_parameter_locus_redesign_same_for_statespace_and_lateral_plant(op):
    V, kap, model = op
    # a = c makes the straight-path design uncontrollable: stay clear of 1.
    values = np.concatenate([np.linspace(-2.0, 0.8, 15), np.linspace(1.3, 2.5, 5)])
    g = fws.SteeringGains(0.3, 0.7, -0.5)
    loci = [
        fws.parameter_locus(
            p, g, parameter="ratio", values=values, redesign_pole=-1.5, **kw
        ).loci
        for p, kw in three_paths(V, kap, model)
    ]
    want = np.broadcast_to([1.0, 3.0, 2.25], (len(values), 3))  # (s + 1.5)^2
    for lo in loci:
        assert_close(poly_from_roots(lo), poly_from_roots(loci[1]), 1e-12, axis=-1)
        assert_close(poly_from_roots(lo), want, 1e-9, axis=-1)


def test_speed_and_curvature_loci_need_a_vehicle():
    g = fws.SteeringGains(0.3, 0.7, -0.5)
    for parameter in ("speed", "curvature"):
        with pytest.raises((TypeError, ValueError), match=parameter):
            fws.parameter_locus(
                hand_plant(5.0, 0.1), g, parameter=parameter, values=[1.0, 2.0]
            )


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    speed=st.one_of(st.floats(0.5, 40.0), st.floats(-40.0, -0.5)),
    curvature=st.floats(-0.3, 0.3),
    ratio=st.floats(-2.0, 2.0),
    pole=st.floats(-5.0, -0.2),
)
def test_double_root_gains_statespace_equals_plant_anywhere(
    speed, curvature, ratio, pole
):
    c = gain_factor(curvature)
    # Stay away from the uncontrollable design (a = c, a kappa = 0).
    distance = ratio**2 * F**2 * curvature**2 + (c - ratio) ** 2
    if distance < 0.05:
        return
    g_ss = fws.double_root_gains(hand_plant(speed, curvature), ratio=ratio, pole=pole)
    g_lp = fws.double_root_gains(
        fws.LateralPlant(VEH, speed, curvature=curvature), ratio=ratio, pole=pole
    )
    assert_close(gains_of(g_ss), gains_of(g_lp), 1e-12)
    A, B = kinematic_matrices(speed, curvature)
    assert_close(
        np.poly(A - (B @ [1.0, ratio])[:, None] * gains_of(g_ss)[None, :]),
        [1.0, -2.0 * pole, pole**2],
        1e-9,
    )


def test_uncontrollable_statespace_design_is_refused():
    """a = 1 on a straight path: delta_r = delta_f, the heading is lost."""
    with pytest.raises(fws.UncontrollableError):
        fws.double_root_gains(hand_plant(5.0, 0.0), ratio=1.0, pole=-1.0)
    assert issubclass(fws.UncontrollableError, ValueError)
    assert fws.UncontrollableError is exceptions.UncontrollableError


# --------------------------------------------------------------------------
# 2. Unnamed 2-state systems: states are (e, theta), inputs (delta_f, delta_r)
# --------------------------------------------------------------------------


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_unnamed_two_state_system_is_taken_as_e_theta(op):
    V, kap, model = op
    A, B = kinematic_matrices(V, kap, model)
    named = hand_plant(V, kap, model)
    unnamed = ct.ss(A, B, np.eye(2), 0)
    assert unnamed.input_labels == ["u[0]", "u[1]"]
    # Default names, a C that is not the identity: feedback is on the states.
    skewed = ct.ss(A, B, np.array([[2.0, 1.0], [0.0, 3.0]]), 0)
    rng = np.random.default_rng(202)
    k1, k2 = rng.uniform(-2.0, 2.0, (2, 2000))
    for a in RATIOS:
        ref = fws.double_root_gains(named, ratio=a, pole=-1.0)
        K = np.ravel(ct.acker(A, B @ np.array([1.0, a]), [-1.0, -1.0]))
        assert_close(gains_of(ref), K, 1e-9)
        gains = fws.SteeringGains(k1, k2, a)
        want = fws.characteristic_polynomial_coefficients(named, gains)
        for sys in (unnamed, skewed):
            g = fws.double_root_gains(sys, ratio=a, pole=-1.0)
            assert_close(gains_of(g), gains_of(ref), 1e-12)
            assert_close(
                fws.characteristic_polynomial_coefficients(sys, gains), want, 1e-12, -1
            )
            np.testing.assert_array_equal(
                fws.is_stable(sys, gains), fws.is_stable(named, gains)
            )


# --------------------------------------------------------------------------
# 3. A 4-state plant (first-order steering lags) built with ct.interconnect
# --------------------------------------------------------------------------

#: (speed, curvature, ratio, gain box): the boxes hold both outcomes.
LAGGED_CASES = [
    (5.0, 0.0, -1.0, (-1.0, 1.0)),
    (5.0, 0.1, 0.5, (-1.0, 1.0)),
    (5.0, 0.1, 0.0, (-1.0, 1.0)),
    (-4.0, 0.05, -0.5, (-1.0, 1.0)),
]


def _max_real(Acl):
    eig = np.linalg.eigvals(Acl)
    return eig.real.max(-1), np.abs(eig).max(-1)


@pytest.mark.parametrize("case", LAGGED_CASES)
def test_lagged_plant_is_stable_agrees_with_eigenvalues(case):
    V, kap, a, (lo, hi) = case
    plant = lagged_plant(V, kap)
    rng = np.random.default_rng(303)
    n = 110_000
    k1, k2 = rng.uniform(lo, hi, (2, n))
    got = fws.is_stable(plant, fws.SteeringGains(k1, k2, a))
    max_re, size = _max_real(closed_loop_matrix(plant, k1, k2, a))
    away = np.abs(max_re) > 1e-6 * np.maximum(size, 1.0)
    assert away.sum() >= 100_000
    assert 0.02 < (max_re < 0).mean() < 0.98
    assert got.shape == (n,) and got.dtype == bool
    bad = got[away] != (max_re < 0)[away]
    assert bad.sum() == 0, (
        f"{bad.sum()} disagreements, e.g. k1, k2 = "
        f"{k1[away][bad][:3]}, {k2[away][bad][:3]}"
    )


@pytest.mark.parametrize("case", LAGGED_CASES)
def test_lagged_plant_chart_agrees_with_eigenvalues(case):
    V, kap, a, (lo, hi) = case
    plant = lagged_plant(V, kap)
    k1 = np.linspace(lo, hi, 320)
    k2 = np.linspace(hi, lo, 315)  # decreasing: allowed, strictly monotonic
    chart = fws.stability_chart(plant, ratio=a, k1=k1, k2=k2)
    assert chart.stable.shape == (315, 320)
    assert chart.design is None  # n > 2: no double-root design
    K1, K2 = np.meshgrid(k1, k2)
    max_re, size = _max_real(closed_loop_matrix(plant, K1, K2, a))
    away = np.abs(max_re) > 1e-6 * np.maximum(size, 1.0)
    assert away.sum() >= 100_000
    assert 0.02 < (max_re < 0).mean() < 0.98
    assert int((chart.stable[away] != (max_re < 0)[away]).sum()) == 0
    assert chart.stable_fraction == pytest.approx(chart.stable.mean(), abs=0)


@pytest.mark.parametrize("case", LAGGED_CASES)
def test_lagged_plant_boundaries_are_on_the_imaginary_axis(case):
    V, kap, a, _ = case
    plant = lagged_plant(V, kap)
    sb = fws.stability_boundaries(plant, ratio=a)
    # n > 2: the only Routh-Hurwitz line is p(0) = 0.
    assert len(sb.lines) == 1
    rr = sb.real_root
    line = sb.lines[0]
    assert_close([line.alpha, line.beta, line.gamma], [rr.alpha, rr.beta, rr.gamma], 0)
    assert np.hypot(rr.alpha, rr.beta) == pytest.approx(1.0, abs=1e-12)
    # The lags have unit DC gain, so p(0) is the 2-state p0 times
    # 1/(tau_f tau_r) > 0: the same normalised line (up to orientation).
    c = gain_factor(kap)
    p0_line = np.array([V**2 / F * (c - a), -(V**2) * a * kap**2, V**2 * kap**2])
    p0_line /= np.hypot(*p0_line[:2])
    got = np.array([rr.alpha, rr.beta, rr.gamma])
    assert min(np.abs(got - p0_line).max(), np.abs(got + p0_line).max()) <= 1e-12
    # Points on the line have a closed-loop eigenvalue at 0.
    t = np.linspace(-2.0, 2.0, 21)
    k1 = -rr.gamma * rr.alpha - t * rr.beta
    k2 = -rr.gamma * rr.beta + t * rr.alpha
    eig = np.linalg.eigvals(closed_loop_matrix(plant, k1, k2, a))
    assert np.abs(eig).min(-1).max() <= 1e-8
    # The complex-root curve: eigenvalues +-j omega at (k1, k2).
    cr = sb.complex_root
    omega, ck1, ck2 = (np.asarray(x, dtype=float) for x in (cr.omega, cr.k1, cr.k2))
    assert omega.ndim == 1
    assert omega.shape == ck1.shape == ck2.shape
    assert np.all(omega > 0)
    _assert_on_imaginary_axis(plant, a, omega, ck1, ck2)
    # An explicit frequency grid is honoured.
    w = np.linspace(0.3, 12.0, 40)
    cr = fws.stability_boundaries(plant, ratio=a, omega=w).complex_root
    assert np.all(np.isin(cr.omega, w))
    _assert_on_imaginary_axis(plant, a, cr.omega, cr.k1, cr.k2)


def _assert_on_imaginary_axis(plant, ratio, omega, k1, k2, min_points=10):
    """The closed loop at (k1[i], k2[i]) has eigenvalues +-j omega[i].

    Non-finite entries (a frequency where the 2x2 system of the
    D-subdivision is singular) are left out; most points must be finite.
    """
    omega, k1, k2 = (np.asarray(x, dtype=float) for x in (omega, k1, k2))
    ok = np.isfinite(k1) & np.isfinite(k2)
    assert ok.sum() >= min(min_points, omega.size) and ok.mean() > 0.9
    omega, k1, k2 = omega[ok], k1[ok], k2[ok]
    eig = np.linalg.eigvals(closed_loop_matrix(plant, k1, k2, ratio))
    assert np.abs(eig.real).min(-1).max() <= 1e-8
    dist = np.abs(eig - 1j * omega[:, None]).min(-1)
    assert np.all(dist <= 1e-7 * np.maximum(omega, 1.0))


def test_lagged_plant_double_root_design_is_refused():
    plant = lagged_plant(5.0, 0.1)
    with pytest.raises(ValueError, match=r"(?i)(order|2-state|two-state)") as err:
        fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    # The spec: the message says what to use instead.
    assert "place" in str(err.value) or "acker" in str(err.value)


@pytest.mark.parametrize("case", LAGGED_CASES)
def test_lagged_plant_characteristic_polynomial_is_np_poly(case):
    V, kap, a, (lo, hi) = case
    plant = lagged_plant(V, kap)
    rng = np.random.default_rng(404)
    k1, k2 = rng.uniform(lo, hi, (2, 40))
    for x1, x2 in zip(k1, k2, strict=True):
        got = fws.characteristic_polynomial_coefficients(
            plant, fws.SteeringGains(x1, x2, a)
        )
        want = np.poly(closed_loop_matrix(plant, x1, x2, a))
        assert got.shape == (5,)
        assert_close(got, want, 1e-9)
    # Array gains: one call, shape (..., n + 1).
    got = fws.characteristic_polynomial_coefficients(
        plant, fws.SteeringGains(k1, k2, a)
    )
    want = np.array([np.poly(M) for M in closed_loop_matrix(plant, k1, k2, a)])
    assert got.shape == (40, 5)
    assert_close(got, want, 1e-9, axis=-1)


@pytest.mark.parametrize("case", LAGGED_CASES)
def test_lagged_plant_affine_polynomial(case):
    """open_loop = det(sI - A), n_i(s) = c_i adj(sI - A) b, evaluated at s."""
    V, kap, a, _ = case
    plant = lagged_plant(V, kap)
    ap = fws.affine_characteristic_polynomial(plant, ratio=a)
    assert isinstance(ap, fws.AffinePolynomial)
    assert ap.order == 4
    A, b, ce, cth = loop_vectors(plant, a)
    assert_close(ap.open_loop, np.poly(A), 1e-12)
    for s in (0.7, -1.3 + 2.0j, 0.2 + 5.0j, 3.0j):
        M = s * np.eye(4) - A
        det = np.linalg.det(M)
        x = np.linalg.solve(M, b)
        for n_i, c_i in ((ap.n1, ce), (ap.n2, cth)):
            want = det * (c_i @ x)
            assert abs(np.polyval(n_i, s) - want) <= 1e-10 * max(abs(want), 1.0)
        k1, k2 = 0.4, -0.3
        want = np.linalg.det(s * np.eye(4) - closed_loop_matrix(plant, k1, k2, a))
        assert abs(ap.evaluate(s, k1, k2) - want) <= 1e-10 * max(abs(want), 1.0)
    assert_close(
        ap.coefficients(0.4, -0.3),
        np.poly(closed_loop_matrix(plant, 0.4, -0.3, a)),
        1e-9,
    )
    # A ratio array broadcasts: fields of shape (3, n + 1), row i = ratio[i].
    ratios = np.array([a, a + 0.5, -2.0])
    apa = fws.affine_characteristic_polynomial(plant, ratio=ratios)
    for i, r in enumerate(ratios):
        one = fws.affine_characteristic_polynomial(plant, ratio=r)
        for field in ("open_loop", "n1", "n2"):
            arr = np.broadcast_to(getattr(apa, field), (3, 5))
            assert_close(arr[i], getattr(one, field), 1e-14)
        assert_close(
            apa.coefficients(0.4, -0.3)[i],
            np.poly(closed_loop_matrix(plant, 0.4, -0.3, r)),
            1e-9,
        )


@pytest.mark.parametrize("case", LAGGED_CASES)
def test_lateral_plant_steering_lag_is_the_interconnected_plant(case):
    """LateralPlant(steering_lag=(T_f, T_r)) against the ct.interconnect plant.

    (``steering_lag`` goes beyond the 0.2 spec; its docstring defines it as
    ``T d(delta)/dt = delta_cmd - delta`` with the commands as inputs.)
    """
    V, kap, a, (lo, hi) = case
    ref_plant = lagged_plant(V, kap)
    plant = fws.LateralPlant(VEH, V, curvature=kap, steering_lag=(TAU_F, TAU_R))
    rng = np.random.default_rng(909)
    k1, k2 = rng.uniform(lo, hi, (2, 5000))
    gains = fws.SteeringGains(k1, k2, a)
    Acl = closed_loop_matrix(ref_plant, k1, k2, a)
    got = fws.characteristic_polynomial_coefficients(plant, gains)
    assert got.shape == (5000, 5)
    assert_close(got[:100], np.array([np.poly(M) for M in Acl[:100]]), 1e-9, -1)
    eig = np.linalg.eigvals(Acl)
    max_re = eig.real.max(-1)
    away = np.abs(max_re) > 1e-6 * np.maximum(np.abs(eig).max(-1), 1.0)
    np.testing.assert_array_equal(fws.is_stable(plant, gains)[away], (max_re < 0)[away])
    with pytest.raises(ValueError, match=r"(?i)(order|2-state|two-state)"):
        fws.double_root_gains(plant, ratio=a, pole=-1.0)
    # Arrays of operating points broadcast with the gains.
    speeds = np.array([V, 2.0 * V, -V])
    curv = np.array([kap, 0.0, 0.2])
    sweep = fws.LateralPlant(VEH, speeds, curvature=curv, steering_lag=(TAU_F, TAU_R))
    got = fws.characteristic_polynomial_coefficients(
        sweep, fws.SteeringGains(k1[:3], k2[:3], a)
    )
    for i in range(3):
        M = closed_loop_matrix(lagged_plant(speeds[i], curv[i]), k1[i], k2[i], a)
        assert_close(got[i], np.poly(M), 1e-9)


def test_lagged_plant_closed_loop_gain_loop_and_loci():
    V, kap, a = 5.0, 0.1, 0.5
    plant = lagged_plant(V, kap)
    g = fws.SteeringGains(0.2, 0.4, a)
    A, b, ce, cth = loop_vectors(plant, a)
    Acl = closed_loop_matrix(plant, 0.2, 0.4, a)
    # closed_loop: states of the plant, disturbances added to the controller.
    cl = fws.closed_loop(plant, g)
    assert cl.input_labels == ["delta_f_dist", "delta_r_dist"]
    assert cl.output_labels == ["e", "theta", "delta_f", "delta_r"]
    assert cl.state_labels == plant.state_labels
    assert_close(cl.A, Acl, 1e-14)
    assert_close(cl.B, plant.B, 1e-15)
    u_f = -(0.2 * ce + 0.4 * cth)
    assert_close(cl.C, np.vstack([plant.C, u_f, a * u_f]), 1e-14)
    assert_close(cl.D, np.vstack([np.zeros((2, 2)), np.eye(2)]), 0)
    # gain_loop: L(s) = (k1 c_e + k2 c_theta)(sI - A)^-1 b, against ct.ss2tf.
    loop = fws.gain_loop(plant, g)
    ref = ct.ss2tf(ct.ss(A, b[:, None], (0.2 * ce + 0.4 * cth)[None, :], 0))
    for s in (0.5, -0.7 + 1.1j, 4.0j, 20.0j):
        want = complex(ref(s))
        assert abs(complex(loop(s)) - want) <= 1e-10 * max(abs(want), 1.0)
    # gain_locus at the scales g: eigenvalues of A - g b (k1 c_e + k2 c_theta).
    scale = np.array([0.1, 0.5, 1.0, 2.0])
    loci = fws.gain_locus(plant, g, scale=scale).loci
    assert loci.shape == (4, 4)
    ref = np.linalg.eigvals(closed_loop_matrix(plant, 0.2 * scale, 0.4 * scale, a))
    assert_close(poly_from_roots(loci), poly_from_roots(ref), 1e-8, axis=-1)
    # parameter_locus over the ratio, k1 and k2.
    for parameter, values in (
        ("ratio", np.linspace(-1.5, 1.5, 13)),
        ("k1", np.linspace(-1.0, 1.0, 13)),
        ("k2", np.linspace(-1.0, 1.0, 13)),
    ):
        par = {"k1": 0.2, "k2": 0.4, "ratio": a, parameter: values}
        loci = fws.parameter_locus(plant, g, parameter=parameter, values=values).loci
        assert loci.shape == (13, 4)
        ref = np.linalg.eigvals(
            closed_loop_matrix(
                plant,
                np.broadcast_to(par["k1"], values.shape),
                np.broadcast_to(par["k2"], values.shape),
                np.broadcast_to(par["ratio"], values.shape),
            )
        )
        assert_close(poly_from_roots(loci), poly_from_roots(ref), 1e-8, axis=-1)


@pytest.mark.parametrize("w_to_e", [0.0, 1.0])
@pytest.mark.parametrize("order", [2, 4])
def test_closed_loop_with_other_inputs_is_the_interconnection(order, w_to_e):
    """closed_loop against ct.interconnect of the plant and a static controller.

    The plant has a third input ``w`` (a disturbance) and a third output
    ``y`` with a feedthrough from delta_f; ``w_to_e`` is a feedthrough from
    ``w`` to ``e``, which the spec allows (only delta_f/delta_r -> e/theta is
    refused). The controller measures e = C_e x + D_ew w, so w reaches the
    steering through the gains.
    """
    base = hand_plant(5.0, 0.1) if order == 2 else lagged_plant(5.0, 0.1)
    A, B, C = base.A, base.B, base.C
    n = A.shape[0]
    Bw = np.arange(1.0, n + 1.0)[:, None] / n
    Cy = np.full((1, n), 0.5)
    D = np.zeros((3, 3))
    D[0, 2] = w_to_e  # w -> e
    D[2, 0] = 1.0  # delta_f -> y (not an e/theta output: allowed)
    plant = ct.ss(
        A,
        np.hstack([B, Bw]),
        np.vstack([C, Cy]),
        D,
        states=list(base.state_labels),
        inputs=[*INPUTS, "w"],
        outputs=[*NAMES, "y"],
    )
    g = fws.SteeringGains(0.2, 0.4, 0.5)
    ctrl = ct.ss(
        [],
        [],
        [],
        np.hstack([-np.asarray(g.K), np.eye(2)]),
        inputs=[*NAMES, "delta_f_dist", "delta_r_dist"],
        outputs=INPUTS,
        name="ctrl",
    )
    ref = ct.interconnect(
        [plant, ctrl],
        inputs=["delta_f_dist", "delta_r_dist", "w"],
        outputs=[*NAMES, "y", *INPUTS],
    )
    cl = fws.closed_loop(plant, g)
    assert cl.input_labels == ["delta_f_dist", "delta_r_dist", "w"]
    assert cl.output_labels == [*NAMES, "y", *INPUTS]
    assert cl.state_labels == plant.state_labels
    for name in ("A", "B", "C", "D"):
        np.testing.assert_allclose(
            getattr(cl, name),
            getattr(ref, name),
            rtol=1e-13,
            atol=1e-13,
            err_msg=f"closed-loop matrix {name}",
        )


def test_points_on_a_boundary_are_not_stable():
    """p(s) = s^2 (zero gains on a straight path): marginal, not stable."""
    zero = fws.SteeringGains(0.0, 0.0, -1.0)
    for plant in (
        hand_plant(5.0, 0.0),
        fws.LateralPlant(VEH, 5.0, curvature=0.0),
        lagged_plant(5.0, 0.0),
    ):
        assert fws.is_stable(plant, zero) is False
    # k1 = 0 on a straight path: p0 = 0 exactly, an eigenvalue at 0.
    g = fws.SteeringGains(0.0, np.array([0.3, 0.6, 0.9]), -1.0)
    for plant in (hand_plant(5.0, 0.0), fws.LateralPlant(VEH, 5.0, curvature=0.0)):
        assert not np.any(fws.is_stable(plant, g))
    # The same for the lagged plant, where the zero is the last entry of the
    # Routh column: the other three poles are stable, one sits at 0.
    for V in (5.0, 20.0):
        plant = lagged_plant(V, 0.0)
        for a in (-1.0, 0.0, 0.5):
            k2 = np.array([0.1, 0.3, 0.5])
            eig = np.linalg.eigvals(closed_loop_matrix(plant, 0.0 * k2, k2, a))
            eig = eig[np.arange(3)[:, None], np.argsort(eig.real, -1)]
            assert np.all(eig[:, :-1].real < -0.05)
            assert np.all(np.abs(eig[:, -1]) < 1e-12)
            assert not np.any(fws.is_stable(plant, fws.SteeringGains(0.0, k2, a)))


def random_plant(rng, n, shift=1.0):
    """A random named n-state plant with a stable open loop."""
    A = rng.normal(size=(n, n)) / np.sqrt(n) - shift * np.eye(n)
    return ct.ss(
        A,
        rng.normal(size=(n, 2)),
        rng.normal(size=(2, n)),
        0,
        states=[f"s{i}" for i in range(n)],
        inputs=INPUTS,
        outputs=NAMES,
    )


def test_random_higher_order_plants_against_eigenvalues():
    """Routh-Hurwitz for n = 3..6 on random plants, where instability also
    comes with all coefficients positive (the full Routh column matters)."""
    rng = np.random.default_rng(808)
    n_pts = 20_000
    stable = positive_unstable = total = 0
    for n in (3, 4, 5, 6):
        for _ in range(3):
            plant = random_plant(rng, n)
            a = rng.uniform(-2.0, 2.0)
            k1, k2 = rng.uniform(-3.0, 3.0, (2, n_pts))
            gains = fws.SteeringGains(k1, k2, a)
            eig = np.linalg.eigvals(closed_loop_matrix(plant, k1, k2, a))
            max_re = eig.real.max(-1)
            away = np.abs(max_re) > 1e-6 * np.maximum(np.abs(eig).max(-1), 1.0)
            assert away.mean() > 0.99
            got = fws.is_stable(plant, gains)
            np.testing.assert_array_equal(got[away], (max_re < 0)[away])
            ref_poly = poly_from_roots(eig)
            stable += int((max_re < 0).sum())
            positive_unstable += int((np.all(ref_poly > 0, -1) & (max_re > 0)).sum())
            total += n_pts
            # The polynomial itself, against np.poly of the closed loop.
            assert_close(
                fws.characteristic_polynomial_coefficients(plant, gains)[:50],
                np.array(
                    [np.poly(M) for M in closed_loop_matrix(plant, k1[:50], k2[:50], a)]
                ),
                1e-9,
                axis=-1,
            )
            # Boundary curve on an explicit grid.
            w = np.geomspace(0.05, 20.0, 60)
            cr = fws.stability_boundaries(plant, ratio=a, omega=w).complex_root
            _assert_on_imaginary_axis(plant, a, cr.omega, cr.k1, cr.k2)
    assert 0.2 < stable / total < 0.8
    assert positive_unstable >= 1000


# --------------------------------------------------------------------------
# 4. For n = 2 the general engine is the closed form
# --------------------------------------------------------------------------


def test_two_state_engine_equals_closed_forms_on_random_points():
    rng = np.random.default_rng(505)
    n = 500
    for _ in range(25):
        V = rng.uniform(0.5, 40.0) * rng.choice([-1.0, 1.0])
        kap = rng.uniform(-0.3, 0.3)
        model = rng.choice(["kinematic", "paper"])
        k1, k2, a = rng.uniform(-2.0, 2.0, (3, n))
        gains = fws.SteeringGains(k1, k2, a)
        p1, p0, s1, s0 = closed_form_p(V, kap, k1, k2, a, model)
        for plant in (
            hand_plant(V, kap, model),
            fws.LateralPlant(VEH, V, curvature=kap, model=model),
        ):
            got = fws.characteristic_polynomial_coefficients(plant, gains)
            assert got.shape == (n, 3)
            assert np.all(got[:, 0] == 1.0)
            assert np.all(np.abs(got[:, 1] - p1) <= 1e-12 * s1)
            assert np.all(np.abs(got[:, 2] - p0) <= 1e-12 * s0)
            ap = fws.affine_characteristic_polynomial(plant, ratio=a)
            assert ap.order == 2
            got = ap.coefficients(k1, k2)
            assert np.all(np.abs(got[:, 1] - p1) <= 1e-12 * s1)
            assert np.all(np.abs(got[:, 2] - p0) <= 1e-12 * s0)
            away = (np.abs(p1) > 1e-9 * s1) & (np.abs(p0) > 1e-9 * s0)
            np.testing.assert_array_equal(
                fws.is_stable(plant, gains)[away], ((p1 > 0) & (p0 > 0))[away]
            )


def test_lateral_plant_arrays_broadcast_like_the_closed_forms():
    rng = np.random.default_rng(606)
    n = 3000
    V = rng.uniform(0.5, 40.0, n) * rng.choice([-1.0, 1.0], n)
    kap = rng.uniform(-0.3, 0.3, n)
    k1, k2, a = rng.uniform(-2.0, 2.0, (3, n))
    plant = fws.LateralPlant(VEH, speed=V, curvature=kap)
    gains = fws.SteeringGains(k1, k2, a)
    p1, p0, s1, s0 = closed_form_p(V, kap, k1, k2, a)
    got = fws.characteristic_polynomial_coefficients(plant, gains)
    assert got.shape == (n, 3)
    assert np.all(np.abs(got[:, 1] - p1) <= 1e-12 * s1)
    assert np.all(np.abs(got[:, 2] - p0) <= 1e-12 * s0)
    away = (np.abs(p1) > 1e-9 * s1) & (np.abs(p0) > 1e-9 * s0)
    np.testing.assert_array_equal(
        fws.is_stable(plant, gains)[away], ((p1 > 0) & (p0 > 0))[away]
    )


@settings(derandomize=True, max_examples=150, deadline=None)
@given(
    speed=st.one_of(st.floats(0.5, 40.0), st.floats(-40.0, -0.5)),
    curvature=st.floats(-0.3, 0.3),
    ratio=st.floats(-2.0, 2.0),
    k1=st.floats(-3.0, 3.0),
    k2=st.floats(-3.0, 3.0),
)
def test_two_state_polynomial_equals_closed_form(speed, curvature, ratio, k1, k2):
    got = fws.characteristic_polynomial_coefficients(
        hand_plant(speed, curvature), fws.SteeringGains(k1, k2, ratio)
    )
    p1, p0, s1, s0 = closed_form_p(speed, curvature, k1, k2, ratio)
    assert got.shape == (3,)
    assert got[0] == 1.0
    assert abs(got[1] - p1) <= 1e-12 * s1
    assert abs(got[2] - p0) <= 1e-12 * s0


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_two_state_boundaries_are_the_closed_form_lines(op):
    V, kap, model = op
    c = gain_factor(kap, model)
    w = np.linspace(0.2, 8.0, 30)
    for a in RATIOS:
        sb = fws.stability_boundaries(hand_plant(V, kap, model), ratio=a, omega=w)
        # lines: p1 = 0 and p0 = 0, stable side where the coefficient is > 0.
        want1 = np.array([V * a, V * (c - a) / F, 0.0])
        want0 = np.array([V**2 / F * (c - a), -(V**2) * a * kap**2, V**2 * kap**2])
        for line, want in zip(sb.lines, (want1, want0), strict=True):
            want = want / np.hypot(*want[:2])
            assert_close([line.alpha, line.beta, line.gamma], want, 1e-12)
        # complex_root: s = +-j w is a root iff p1 = 0 and p0 = w^2.
        M = np.array([want1[:2], want0[:2]])
        rhs = np.stack([np.zeros_like(w), w**2 - V**2 * kap**2])
        k = np.linalg.solve(M, rhs)
        cr = sb.complex_root
        assert_close(cr.omega, w, 1e-15)
        assert_close(cr.k1, k[0], 1e-12)
        assert_close(cr.k2, k[1], 1e-12)


# --------------------------------------------------------------------------
# 5. g.K, g.K_paper, SteeringGains.from_K
# --------------------------------------------------------------------------


@pytest.mark.parametrize("op", OPERATING_POINTS)
def test_K_follows_python_control_sign(op):
    V, kap, model = op
    A, B = kinematic_matrices(V, kap, model)
    plant = hand_plant(V, kap, model)
    for a in RATIOS:
        for pole in POLES:
            g = fws.double_root_gains(plant, ratio=a, pole=pole)
            K = np.asarray(g.K)
            assert K.shape == (2, 2)
            assert_close(K, [[g.k1, g.k2], [a * g.k1, a * g.k2]], 1e-15)
            # python-control sign: u = -K x, closed loop A - B K.
            assert_close(np.poly(A - B @ K), [1.0, -2.0 * pole, pole**2], 1e-9)
            assert_close(np.sort(np.linalg.eigvals(A - B @ K).real), [pole, pole], 1e-5)
            np.testing.assert_array_equal(g.K_paper, -K)
            # ct.place with two nearby distinct poles (it refuses a repeated
            # pole on a single input): the gains differ by O(delta^2).
            delta = 1e-4 * abs(pole)
            Kp = np.ravel(
                ct.place(A, (B @ [1.0, a])[:, None], [pole - delta, pole + delta])
            )
            assert_close(gains_of(g), Kp, 1e-6)
            # closed_loop's A is A - B K.
            assert_close(fws.closed_loop(plant, g).A, A - B @ K, 1e-14)
            # from_K round-trips.
            h = fws.SteeringGains.from_K(K)
            assert_close([h.k1, h.k2, h.ratio], [g.k1, g.k2, a], 1e-14)
            # ... and takes a K built from Ackermann's single-input row.
            row = np.ravel(ct.acker(A, B @ np.array([1.0, a]), [pole, pole]))
            h = fws.SteeringGains.from_K(np.outer([1.0, a], row))
            assert_close([h.k1, h.k2, h.ratio], [row[0], row[1], a], 1e-14)
            h = fws.SteeringGains.from_K(row, ratio=a)  # single-input row
            assert_close([h.k1, h.k2, h.ratio], [row[0], row[1], a], 0)
    assert not hasattr(fws.SteeringGains(0.1, 0.2, -1.0), "matrix")


def test_K_broadcasts_and_from_K_rejects_other_shapes():
    k1 = np.linspace(-1, 1, 12).reshape(3, 4)
    g = fws.SteeringGains(k1, 0.5, -0.7)
    K = g.K
    assert K.shape == (3, 4, 2, 2)
    assert_close(K[..., 0, 0], k1, 0)
    assert_close(K[..., 0, 1], np.full((3, 4), 0.5), 0)
    assert_close(K[..., 1, 0], -0.7 * k1, 1e-15)
    assert_close(K[..., 1, 1], np.full((3, 4), -0.35), 1e-15)
    np.testing.assert_array_equal(g.K_paper, -K)
    for bad in (
        np.array([[1.0, 2.0], [3.0, 5.0]]),  # rank two
        np.array([[0.0, 0.0], [1.0, 2.0]]),  # rear gain without a front gain
        np.array([[1.0, 2.0], [2.0, 1.0]]),  # rows not proportional
    ):
        with pytest.raises(ValueError):
            fws.SteeringGains.from_K(bad)


# --------------------------------------------------------------------------
# 6. Misuse raises TypeError
# --------------------------------------------------------------------------


def test_positional_operating_point_is_a_type_error():
    veh = VEH
    plant = fws.LateralPlant(veh, 5.0, curvature=0.1)
    g = fws.SteeringGains(0.1, 0.5, -1.0)
    k1, k2 = 0.1, 0.5
    calls = [
        lambda: fws.stability_chart(veh, 5.0, 0.1, -1.0),
        lambda: fws.is_stable(veh, 5.0, 0.1, k1, k2),
        lambda: fws.double_root_gains(veh, 5.0, 0.0, -1.0, -1.0),
        lambda: fws.linearize(veh, 5.0),
        lambda: fws.closed_loop(plant, g, 5.0),
        lambda: fws.stability_boundaries(plant, -1.0),
        lambda: fws.affine_characteristic_polynomial(plant, -1.0),
        lambda: fws.parameter_locus(plant, g, "ratio", [0.0, 1.0]),
        lambda: fws.gain_locus(plant, g, [1.0, 2.0]),
    ]
    for call in calls:
        with pytest.raises(TypeError):
            call()


@pytest.mark.parametrize("keyword", ["speed", "curvature", "model"])
@pytest.mark.parametrize("kind", ["LateralPlant", "StateSpace"])
def test_vehicle_keywords_with_a_plant_are_a_type_error(keyword, kind):
    kw = {keyword: {"speed": 5.0, "curvature": 0.1, "model": "kinematic"}[keyword]}
    g = fws.SteeringGains(0.1, 0.5, -1.0)
    plant = {
        "LateralPlant": fws.LateralPlant(VEH, 5.0, curvature=0.1),
        "StateSpace": hand_plant(5.0, 0.1),
    }[kind]
    calls = [
        lambda: fws.linearize(plant, **kw),
        lambda: fws.is_stable(plant, g, **kw),
        lambda: fws.double_root_gains(plant, ratio=-1.0, pole=-1.0, **kw),
        lambda: fws.stability_chart(plant, ratio=-1.0, **kw),
        lambda: fws.characteristic_polynomial_coefficients(plant, g, **kw),
    ]
    for call in calls:
        with pytest.raises(TypeError, match=keyword):
            call()


def test_something_else_as_plant_is_a_type_error_naming_plant():
    g = fws.SteeringGains(0.1, 0.5, -1.0)
    for bad in ("car", np.eye(2), ct.tf([1.0], [1.0, 1.0]), None):
        with pytest.raises(TypeError, match="plant"):
            fws.linearize(bad)
        with pytest.raises(TypeError, match="plant"):
            fws.is_stable(bad, g)


# --------------------------------------------------------------------------
# 7. StateSpace plants that the engine must refuse
# --------------------------------------------------------------------------


def _refusals(sys):
    g = fws.SteeringGains(0.1, 0.5, -1.0)
    return [
        lambda: fws.is_stable(sys, g),
        lambda: fws.characteristic_polynomial_coefficients(sys, g),
        lambda: fws.affine_characteristic_polynomial(sys, ratio=-1.0),
        lambda: fws.stability_chart(sys, ratio=-1.0, k1=[0.0, 1.0], k2=[0.0, 1.0]),
        lambda: fws.double_root_gains(sys, ratio=-1.0, pole=-1.0),
    ]


FEEDTHROUGH_MESSAGE = r"([Ff]eedthrough|[Aa]lgebraic|[Aa]ffine|\bD\b)"


@pytest.mark.parametrize("entry", [(0, 0), (0, 1), (1, 0)])
def test_feedthrough_to_e_theta_is_refused(entry):
    A, B = kinematic_matrices(5.0, 0.1)
    D = np.zeros((2, 2))
    D[entry] = 0.1
    sys = ct.ss(A, B, np.eye(2), D, states=NAMES, inputs=INPUTS, outputs=NAMES)
    for call in _refusals(sys):
        with pytest.raises(ValueError, match=FEEDTHROUGH_MESSAGE):
            call()


def test_feedthrough_elsewhere_is_accepted():
    """D from another input, or to another output, does not close a loop."""
    A, B = kinematic_matrices(5.0, 0.1)
    sys = ct.ss(
        A,
        np.hstack([B, [[1.0], [0.0]]]),
        np.vstack([np.eye(2), [[0.5, 0.5]]]),
        np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
        states=NAMES,
        inputs=[*INPUTS, "w"],
        outputs=[*NAMES, "y"],
    )
    ref = hand_plant(5.0, 0.1)
    for a in RATIOS:
        assert_close(
            gains_of(fws.double_root_gains(sys, ratio=a, pole=-1.0)),
            gains_of(fws.double_root_gains(ref, ratio=a, pole=-1.0)),
            1e-12,
        )


def test_discrete_time_is_refused():
    A, B = kinematic_matrices(5.0, 0.1)
    sys = ct.ss(
        np.eye(2) + 0.01 * A,
        0.01 * B,
        np.eye(2),
        0,
        dt=0.01,
        states=NAMES,
        inputs=INPUTS,
        outputs=NAMES,
    )
    for call in _refusals(sys):
        with pytest.raises(ValueError, match=r"(?i)(discrete|continuous|\bdt\b)"):
            call()


def test_missing_signals_are_named():
    A, B = kinematic_matrices(5.0, 0.1)
    no_rear = ct.ss(
        A, B, np.eye(2), 0, states=NAMES, inputs=["delta_f", "steer_r"], outputs=NAMES
    )
    no_front = ct.ss(
        A, B, np.eye(2), 0, states=NAMES, inputs=["steer_f", "delta_r"], outputs=NAMES
    )
    no_theta = ct.ss(
        A,
        B,
        np.eye(2),
        0,
        states=["p", "q"],
        inputs=INPUTS,
        outputs=["e", "heading"],
    )
    cases = ((no_rear, "delta_r"), (no_front, "delta_f"), (no_theta, "theta"))
    for sys, missing in cases:
        for call in _refusals(sys):
            with pytest.raises((ValueError, TypeError), match=missing):
                call()
    # Default names are only taken for 2 states and 2 inputs.
    rng = np.random.default_rng(707)
    three = ct.ss(rng.normal(size=(3, 3)), rng.normal(size=(3, 2)), np.eye(3), 0)
    for call in _refusals(three):
        with pytest.raises((ValueError, TypeError)):
            call()
