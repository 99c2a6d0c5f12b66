"""One test per erratum of docs/errata.md: the difference shown numerically.

Each test computes what the paper prints and what the physics gives, and
asserts that they differ (and that the library follows the physics).
"""

import control as ct
import numpy as np
import pytest
import sympy as sp
from conftest import PAPER_VEHICLE, lambdify
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control import symbolic as S

VEH = PAPER_VEHICLE


def _arc_errors(x, y, psi, k):
    radius = 1.0 / k
    phi = np.unwrap(np.arctan2(y - radius, x))
    return (
        radius * (phi + np.pi / 2),
        radius - np.hypot(x, y - radius),
        psi - phi - np.pi / 2,
    )


def _drive_on_arc(speed, k, delta_f, duration=3.0):
    """Global-frame motion from (0, -1, 0.1) with constant steering."""
    glob = fws.global_frame_model(VEH, speed=speed)
    t = np.linspace(0.0, duration, 301)
    sol = solve_ivp(
        lambda t, x: glob.dynamics(t, x, [delta_f, 0.0]),
        (0, duration),
        [0.0, -1.0, 0.1],
        t_eval=t,
        rtol=1e-12,
        atol=1e-12,
    )
    return t, _arc_errors(*sol.y, k)


def test_erratum_1_sign_of_curvature_term_eq16():
    """theta_dot = psi_dot - kappa*s_dot; eq. (16) prints + kappa*s_dot."""
    speed, k, delta = 5.0, 0.1, 0.3
    t, (s, e, theta) = _drive_on_arc(speed, k, delta)
    theta_dot_geo = np.gradient(theta, t, edge_order=2)
    s_dot = speed * np.cos(theta) / (1 - k * e)
    psi_dot = fws.yaw_rate(VEH, delta, 0.0, speed=speed)
    corrected = psi_dot - k * s_dot
    printed = psi_dot + k * s_dot
    assert np.max(np.abs(theta_dot_geo - corrected)[5:-5]) < 1e-5
    assert np.min(np.abs(theta_dot_geo - printed)) > 0.5  # = 2 kappa s_dot ~ 1 rad/s


def test_erratum_2_missing_speed_in_eq17():
    """s_dot = V cos(theta + delta_r)/(1 - kappa e); eq. (17) lacks V."""
    speed, k = 5.0, 0.1
    t, (s, e, theta) = _drive_on_arc(speed, k, 0.3)
    s_dot_geo = np.gradient(s, t, edge_order=2)
    corrected = speed * np.cos(theta) / (1 - k * e)
    printed = np.cos(theta) / (1 - k * e)
    assert np.max(np.abs(s_dot_geo - corrected)[5:-5]) < 1e-5
    assert np.min(np.abs(s_dot_geo - printed)) > 3.0


def _nonlinear_closed_loop_poles(speed, k, gains):
    """Poles of the *nonlinear* path-frame closed loop, linearised numerically."""
    plant = fws.path_frame_model(VEH, speed=speed, curvature=k)
    ff = fws.feedforward_steering(VEH, curvature=k)

    def rhs(t, x, u, params):
        d_fb, r_fb = gains.steering(x[1], x[2])
        return plant.dynamics(t, x, [ff + d_fb, r_fb])

    sys = ct.nlsys(rhs, None, states=3, inputs=0, outputs=3)
    lin = ct.linearize(sys, np.zeros(3), [], eps=1e-8)
    return np.sort_complex(np.linalg.eigvals(lin.A[1:, 1:]))


@pytest.mark.parametrize("ratio", [-1.0, -0.5, 0.0, 0.5, 1.0])
def test_erratum_3_paper_gains_miss_the_double_root_on_a_curve(ratio):
    """V = 5 m/s, kappa = 0.1: paper gains for lam0 = -1 do not give -1, -1."""
    speed, k, lam0 = 5.0, 0.1, -1.0
    exact_plant = fws.LateralPlant(VEH, speed=speed, curvature=k, model="kinematic")
    paper_plant = fws.LateralPlant(VEH, speed=speed, curvature=k, model="paper")
    paper = fws.double_root_gains(paper_plant, ratio=ratio, pole=lam0)
    exact = fws.double_root_gains(exact_plant, ratio=ratio, pole=lam0)
    true_paper = _nonlinear_closed_loop_poles(speed, k, paper)
    true_exact = _nonlinear_closed_loop_poles(speed, k, exact)
    # the exact design lands on the double root of the nonlinear model ...
    np.testing.assert_allclose(true_exact, [lam0, lam0], atol=2e-3)
    # ... the paper's misses it by >= 0.2 1/s (a real or imaginary split)
    assert np.max(np.abs(true_paper - lam0)) > 0.2
    # and the exact linearisation predicts where the paper's poles really are
    predicted = np.sort_complex(fws.closed_loop(exact_plant, paper).poles())
    np.testing.assert_allclose(true_paper, predicted, atol=1e-5)


def test_erratum_3_exact_gains_at_ratio_zero_carry_one_over_c():
    """Eq. (44) has no (1 - a) to replace, yet the exact a = 0 gains are /c.

    Reference: the double root solved by sympy from the exact characteristic
    polynomial, and eq. (44) evaluated by hand.
    """
    V, f, kap, lam0 = 5.0, 2.7, 0.1, -1.0
    c = 1 + f**2 * kap**2
    k1s, k2s, lam = (S.SYMBOLS[n] for n in ("k1", "k2", "lam"))
    subs = {
        S.SYMBOLS["speed"]: V,
        S.SYMBOLS["wheelbase"]: f,
        S.SYMBOLS["curvature"]: kap,
        S.SYMBOLS["ratio"]: 0,
    }
    D = S.characteristic_polynomial("kinematic").as_expr().subs(subs)
    target = sp.expand((lam - lam0) ** 2)
    sol = sp.solve(sp.Poly(sp.expand(D - target), lam).all_coeffs(), [k1s, k2s])
    eq44 = (f * (lam0**2 / V**2 - kap**2), -2 * lam0 * f / V)
    assert float(sol[k1s]) == pytest.approx(eq44[0] / c, rel=1e-12)
    assert float(sol[k2s]) == pytest.approx(eq44[1] / c, rel=1e-12)
    g = fws.double_root_gains(VEH, speed=V, curvature=kap, ratio=0.0, pole=lam0)
    assert g.k1 == pytest.approx(float(sol[k1s]), rel=1e-12)
    assert g.k2 == pytest.approx(float(sol[k2s]), rel=1e-12)
    assert (round(g.k1, 4), round(g.k2, 4)) == (0.0755, 1.0066)
    # the straight-road formulas (41)-(42) are the same in both models (c = 1)
    for a in (-1.0, 0.0, 0.5):
        exact = fws.double_root_gains(VEH, speed=V, curvature=0.0, ratio=a, pole=lam0)
        paper = fws.double_root_gains(
            fws.LateralPlant(VEH, speed=V, curvature=0.0, model="paper"),
            ratio=a,
            pole=lam0,
        )
        assert exact.k1 == paper.k1 and exact.k2 == paper.k2


def test_erratum_4_ratio_one_on_curve_still_needs_k2_below_one():
    """a = 1, kappa != 0: k2 < 1 (paper's model), k2 < 1 + f k1 (exact)."""
    V, f, a, kap = (S.SYMBOLS[n] for n in ("speed", "wheelbase", "ratio", "curvature"))
    k1, k2, lam = (S.SYMBOLS[n] for n in ("k1", "k2", "lam"))
    D = sp.Poly(S.characteristic_polynomial("kinematic").as_expr().subs(a, 1), lam)
    _, p1, p0 = D.all_coeffs()
    assert sp.simplify(p1 - V * (k1 + f * kap**2 * k2)) == 0
    assert sp.simplify(p0 - V**2 * kap**2 * (f * k1 + 1 - k2)) == 0
    paper = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, model="paper")
    exact = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, model="kinematic")
    # bound of the exact model at k1 = 0.5: 1 + 2.7 * 0.5 = 2.35
    for plant, k2_val, expected in (
        (paper, 0.9, True),
        (paper, 1.1, False),
        (exact, 1.1, True),  # the paper's example point is stable here
        (exact, 2.3, True),
        (exact, 2.4, False),
    ):
        g = fws.SteeringGains(0.5, k2_val, 1.0)
        poles = fws.closed_loop(plant, g).poles()
        assert (np.max(poles.real) < 0) == expected, (plant.model, k2_val)
        assert fws.is_stable(plant, g) == expected


def test_erratum_5_ratio_one_straight_is_uncontrollable_and_eq42_is_wrong():
    V, f, a, kap = (S.SYMBOLS[n] for n in ("speed", "wheelbase", "ratio", "curvature"))
    k1, k2, lam0, lam = (S.SYMBOLS[n] for n in ("k1", "k2", "pole", "lam"))
    for model in ("kinematic", "paper"):
        D = S.characteristic_polynomial(model).as_expr().subs({a: 1, kap: 0})
        assert sp.expand(D - lam * (lam + V * k1)) == 0
    # printed k1 = -2 lam0 / f in eq. (39): p1 = V k1 = -2 lam0 V / f != -2 lam0
    p1 = S.characteristic_polynomial("paper").all_coeffs()[1].subs({a: 1, kap: 0})
    printed_k1 = S.paper_gain_formulas()["42"][k1]
    assert sp.simplify(p1.subs(k1, printed_k1) + 2 * lam0) != 0
    assert sp.solve(sp.Eq(p1, -2 * lam0), k1) == [-2 * lam0 / V]
    with pytest.raises(fws.UncontrollableError):
        fws.double_root_gains(VEH, speed=5.0, curvature=0.0, ratio=1.0, pole=-1.0)


def test_erratum_6_no_singularity_at_ratio_zero():
    """Eqs. (45)-(46) divide by a; the 2x2 solve does not."""
    printed = S.paper_gain_formulas()["45-46"]
    k1 = S.SYMBOLS["k1"]
    f_k1 = lambdify(printed[k1])
    with pytest.raises(ZeroDivisionError):
        f_k1(5.0, 2.7, 0.1, 0.0, 0, 0, -1.0)
    # near a = 0 the printed form cancels two terms of size 1/a
    near = f_k1(5.0, 2.7, 0.1, 1e-12, 0, 0, -1.0)
    paper = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, model="paper")
    g_near = fws.double_root_gains(paper, ratio=1e-12, pole=-1.0)
    assert abs(near - g_near.k1) > 1e-6 * abs(g_near.k1)
    g0 = fws.double_root_gains(paper, ratio=0.0, pole=-1.0)
    assert np.isfinite(g0.k1)
    # and it is the limit of the regular solution: eq. (44), hand-evaluated
    assert g0.k1 == pytest.approx(2.7 * (1 / 25 - 0.01), rel=1e-14)
    assert g_near.k1 == pytest.approx(g0.k1, rel=1e-9)
    # the printed formula agrees away from a = 0 (where it is well defined)
    g = fws.double_root_gains(paper, ratio=0.3, pole=-1.0)
    assert g.k1 == pytest.approx(f_k1(5.0, 2.7, 0.1, 0.3, 0, 0, -1.0), rel=1e-12)


def test_erratum_7_reversing_flips_condition_35_only():
    """V < 0: p1 changes sign with V, p0 carries V^2 and does not.

    A clarification, not an error: the printed (35) has the signed factor
    V/f, so it flips by itself (checked here with the paper's model).
    """
    k, a, k1, k2 = 0.05, -0.5, 0.3, 0.6
    forward = fws.LateralPlant(VEH, speed=5.0, curvature=k)
    reverse = fws.LateralPlant(VEH, speed=-5.0, curvature=k)
    fwd = fws.affine_characteristic_polynomial(forward, ratio=a)
    rev = fws.affine_characteristic_polynomial(reverse, ratio=a)
    _, p1_f, p0_f = fwd.coefficients(k1, k2)
    _, p1_r, p0_r = rev.coefficients(k1, k2)
    assert p1_r == pytest.approx(-p1_f)
    assert p0_r == pytest.approx(p0_f)
    # hence the forward-stable design is unstable in reverse (eigenvalues)
    g = fws.SteeringGains(k1, k2, a)
    assert np.max(fws.closed_loop(forward, g).poles().real) < 0
    assert np.max(fws.closed_loop(reverse, g).poles().real) > 0
    # "both conditions flip" would make p0 < 0 the reverse requirement: a
    # design with p1 < 0 and p0 > 0 (forward form of 36) is stable in reverse
    k1r, k2r = 0.3, -0.6
    _, p1_r, p0_r = rev.coefficients(k1r, k2r)
    assert p1_r > 0 and p0_r > 0
    g_rev = fws.SteeringGains(k1r, k2r, a)
    assert np.max(fws.closed_loop(reverse, g_rev).poles().real) < 0
    assert fws.is_stable(reverse, g_rev)
    # the paper's (35), p1 = (V/f)(f a k1 + (1 - a) k2), carries the signed V
    for speed in (5.0, -5.0):
        plant = fws.LateralPlant(VEH, speed=speed, curvature=k, model="paper")
        _, p1, _ = fws.affine_characteristic_polynomial(plant, ratio=a).coefficients(
            k1, k2
        )
        assert p1 == pytest.approx(speed / 2.7 * (2.7 * a * k1 + (1 - a) * k2))
