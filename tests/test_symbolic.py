"""The sympy derivations against the paper's printed equations."""

import sympy as sp

from fws_control import symbolic as S

V, f, kap, a = (S.SYMBOLS[n] for n in ("speed", "wheelbase", "curvature", "ratio"))
k1, k2, lam0, lam = (S.SYMBOLS[n] for n in ("k1", "k2", "pole", "lam"))
e, th, psi, df, dr = sp.symbols("e theta psi delta_f delta_r", real=True)


def _zero(expr):
    return sp.simplify(sp.expand_trig(sp.simplify(expr))) == 0


def test_constraints_give_eqs_8_to_10():
    rhs = S.global_frame_rhs()
    printed = [
        V * sp.cos(psi + dr),
        V * sp.sin(psi + dr),
        V * sp.sin(df - dr) / (f * sp.cos(df)),
    ]
    for got, ref in zip(rhs, printed, strict=True):
        assert _zero(got - ref)


def test_transformation_gives_corrected_eqs_17_to_19():
    rhs = S.path_frame_rhs()
    s_dot = V * sp.cos(th + dr) / (1 - kap * e)
    printed = [
        s_dot,
        V * sp.sin(th + dr),
        -kap * s_dot + V * sp.sin(df - dr) / (f * sp.cos(df)),
    ]
    for got, ref in zip(rhs, printed, strict=True):
        assert _zero(got - ref)


def test_exact_jacobian_front_entry():
    _, B = S.jacobians("kinematic")
    assert sp.simplify(B[1, 0] - V * (1 + f**2 * kap**2) / f) == 0
    A_p, B_p = S.jacobians("paper")
    A_e, B_e = S.jacobians("kinematic")
    assert sp.simplify(A_p - A_e) == sp.zeros(2, 2)  # only B differs
    assert sp.simplify(B_e - B_p) == sp.Matrix([[0, 0], [V * f * kap**2, 0]])


def test_paper_characteristic_polynomial_is_eq34():
    p = S.characteristic_polynomial("paper").as_expr()
    printed = (
        lam**2
        + V / f * (f * a * k1 + (1 - a) * k2) * lam
        + V**2 / f * ((1 - a) * k1 + (1 - a * k2) * f * kap**2)
    )
    assert sp.expand(p - printed) == 0


def test_exact_polynomial_replaces_one_minus_a_by_c_minus_a():
    c = 1 + f**2 * kap**2
    p = S.characteristic_polynomial("kinematic").as_expr()
    ref = (
        lam**2
        + V / f * (f * a * k1 + (c - a) * k2) * lam
        + V**2 / f * ((c - a) * k1 + (1 - a * k2) * f * kap**2)
    )
    assert sp.expand(p - ref) == 0


def test_paper_gains_45_46_and_41_44_solve_eqs_39_40():
    sol = S.double_root_gains("paper")
    printed = S.paper_gain_formulas()
    for k in (k1, k2):
        assert sp.simplify(sol[k] - printed["45-46"][k]) == 0
        assert sp.simplify(sol[k].subs(kap, 0) - printed["41"][k]) == 0
        assert sp.simplify(sol[k].subs(a, 0) - printed["44"][k]) == 0
