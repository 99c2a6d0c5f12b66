"""The model and law equations of :mod:`fws_control.equations`.

(a) Each equation has exactly one definition in the package: a search of
the syntax trees of ``fws_control/`` (without the sympy oracle
``symbolic.py``) for a recognisable form of each equation finds it in one
function only, the one of ``equations.py``, so copies cannot creep back.
(b) Each function equals its sympy derivation in :mod:`fws_control.symbolic`
(or the formula written here where ``symbolic`` has none) at random points,
and the numba-compiled function equals the numpy one bit for bit (numpy
at its baseline loops, which round as the C library does).
"""

from __future__ import annotations

import ast
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control
from fws_control import equations, symbolic

PACKAGE = Path(fws_control.__file__).parent

# --------------------------------------------------------------------------
# (a) one definition each

# A recognisable form of each equation in the unparsed source of an
# expression (``np.`` and ``math.`` removed), as the copies were written:
# with calls (``sin(df - dr)``) or with names for the factors computed
# before (``sin_fr``, ``cos_f``).
_ANGLE = r"[\w.\[\]]+"
SIGNATURES = {
    # eq. (10): V sin(delta_f - delta_r) / (f cos(delta_f))
    "yaw_rate": r"sin\((\w+) - \w+\) / \(" + _ANGLE + r" \* cos\(\1\)\)"
    r"|\w+ \* sin_fr / \(\w+ \* cos_f\)",
    # eqs. (8)-(9): V cos(psi + delta_r), V sin(psi + delta_r)
    "global_frame_derivatives": r"\w+ \* (cos|sin)\(psi \+ (delta_r|dr)\)",
    # eq. (17): V cos(theta + delta_r) / (1 - kappa e)
    "path_frame_derivatives": r"cos\(\w+ \+ \w+\) / \(1\.0 - \w+ \* e\)"
    # eq. (19): -kappa s_dot + yaw rate
    r"|^-\w+ \* s_dot \+ ",
    # eq. (11): v_y of G = V sin(delta_r) + d r
    "cg_lateral_velocity": r"\w+ \* (sin\((dr|delta_r)\)|sin_r) \+ "
    r"[\w.]*(rear_to_cg|d_cg) \* \w+$",
    # d/dt of eq. (10)
    "yaw_acceleration": r"(cos\(\w+\)|cos_r) / \w+ \*\* 2 \* \w+ - "
    r"(cos\(\w+ - \w+\)|cos_fr) / \w+ \* \w+",
    # eq. (13): V (psi_dot + rate_r) cos(delta_r) + d psi_ddot
    "lateral_acceleration": r"\(\w+ \+ \w+\) \* (cos\(\w+\)|cos_r) \+ "
    r"[\w.]+ \* (psi_ddot|yaw_acceleration)",
    # eq. (26): atan(f kappa) (see _is_feedforward)
    "feedforward_angle": None,
    # its rate: f kappa_dot / (1 + (f kappa)^2)
    "feedforward_angle_rate": r"(wheelbase|\bf) \* \w+ / \(1\.0 \+ "
    r"(\w+ \*\* 2|\(\w+ \* \w+\) \*\* 2|(\w+) \* \3)\)",
    # eqs. (28)-(29): -k1 e - k2 theta
    "feedback_angle": r"^-[\w.\[\], ]+ \* \w+ - [\w.\[\], ]+ \* \w+$",
    # a schedule's gains: the interpolated k1 V^2 divided by V^2
    "unscaled_gains": r"(interp\(.*\)|k1_scaled) / \w+ \*\* 2$",
    # the no-slip motion: r = V (tan delta_f - tan delta_r) / f
    "no_slip_body_state": r"\((tan\([^()]*\)|tan_f) - (tan\([^()]*\)|tan_r)\) / ",
    # slip angles: delta - atan2(lateral speed of the axle, u)
    "slip_angles": r"\w+ - arctan2\(",
    # the magic formula D sin(c atan(B alpha))
    "magic_tyre_force": r"sin\(MAGIC_SHAPE \* arctan\(",
    # I_z r_dot = l_f F_f cos(delta_f) - l_r F_r cos(delta_r)
    "body_derivatives": r"\(\w+ \* lat_f - \w+ \* lat_r\) / ",
    # the dynamic model's path-frame kinematics
    "dynamic_path_kinematics": r"\(\w+ \* cos_t - v_r \* sin_t\) / \(1\.0 - \w+ \* e\)",
    # and its global-frame velocity of R
    "dynamic_global_kinematics": r"\w+ \* (sin|cos)_p [+-] v_r \* (cos|sin)_p",
    # pure pursuit's angle of the look-ahead point: atan2(dy, dx) - psi
    "pure_pursuit_angle": r"arctan2\(\w+ - \w+, \w+ - \w+\) - \w+",
    # Stanley: atan(k e_f / (k_s + |V|))
    "stanley_angle": r"arctan\([\w.\[\]()]+ \* [\w.]+ / \([\w.]+ \+ abs\(",
    # rear-wheel feedback: V kappa cos(theta) / (1 - kappa e)
    "rear_wheel_feedback_angle": r"\w+ \* \w+ \* cos\(\w+\) / \(1\.0 - \w+ \* e\)",
}

_WHEELBASE = {"wheelbase", "f", "_Q_WHEELBASE"}
_CURVATURE = {"k", "k_", "k0", "kappa", "curvature"}
_NOT_DATA = {"np", "math", "asarray", "float", "vehicle", "q", "dtype"}


def _is_feedforward(node: ast.AST) -> bool:
    """``atan(f * kappa)`` in any spelling of f and kappa."""
    if not isinstance(node, ast.Call) or len(node.args) != 1:
        return False
    func = node.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
    arg = node.args[0]
    if name not in {"atan", "arctan", "_atan"} or not isinstance(arg, ast.BinOp):
        return False
    if not isinstance(arg.op, ast.Mult):
        return False
    idents = {n.id for n in ast.walk(arg) if isinstance(n, ast.Name)}
    idents |= {n.attr for n in ast.walk(arg) if isinstance(n, ast.Attribute)}
    idents -= _NOT_DATA
    return len(idents) == 2 and bool(idents & _WHEELBASE) and bool(idents & _CURVATURE)


def _normalised(node: ast.AST) -> str:
    return re.sub(r"\b(np|math)\.", "", ast.unparse(node))


def definitions(root: Path) -> dict[str, set[tuple[str, str]]]:
    """For each equation, the functions ``(file, name)`` that write it out."""
    found: dict[str, set[tuple[str, str]]] = {name: set() for name in SIGNATURES}
    patterns = {k: re.compile(v) for k, v in SIGNATURES.items() if v is not None}
    for path in sorted(root.rglob("*.py")):
        if path.name == "symbolic.py":
            continue  # the independent sympy oracle
        tree = ast.parse(path.read_text(encoding="utf-8"))
        rel = path.relative_to(root).as_posix()
        # the innermost function around each node
        owner: dict[int, str] = {}
        stack = [(tree, "<module>")]
        while stack:
            node, name = stack.pop()
            for child in ast.iter_child_nodes(node):
                inner = name
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    inner = child.name
                owner[id(child)] = inner
                stack.append((child, inner))
        for node in ast.walk(tree):
            if not isinstance(node, ast.expr):
                continue
            where = (rel, owner.get(id(node), "<module>"))
            if _is_feedforward(node):
                found["feedforward_angle"].add(where)
            if isinstance(node, (ast.BinOp, ast.UnaryOp)):
                text = _normalised(node)
                for key, pattern in patterns.items():
                    if pattern.search(text):
                        found[key].add(where)
    return found


def test_each_equation_is_defined_once():
    found = definitions(PACKAGE)
    wrong = {
        key: sorted(where)
        for key, where in found.items()
        if where != {("equations.py", key)}
    }
    assert not wrong, f"equations written outside fws_control.equations: {wrong}"


def test_the_signatures_recognise_the_copies_they_were_written_for():
    # each form that the signatures above were made from, as the package
    # wrote it before the equations were gathered in one module
    samples = {
        "yaw_rate": [
            "def a():\n    speed * np.sin(delta_f - delta_r)"
            " / (wheelbase * np.cos(delta_f))",
            "def a():\n    V * math.sin(df - dr) / (q[_Q_WHEELBASE] * math.cos(df))",
            "def a():\n    V * sin_fr / (f * cos_f)",
        ],
        "path_frame_derivatives": [
            "def a():\n    V * math.cos(th + dr) / (1.0 - kappa * e)",
            "def a():\n    th_dot = -kappa * s_dot + psi_dot",
        ],
        "feedforward_angle": [
            "def a():\n    np.arctan(np.asarray(k) * vehicle.wheelbase)",
            "def a():\n    math.atan(q[_Q_WHEELBASE] * kappa)",
            "def a():\n    np.arctan(f * kappa)",
        ],
        "feedback_angle": [
            "def a():\n    -gains.k1 * e_ - gains.k2 * th_",
            "def a():\n    -K[0, 0] * e - K[0, 1] * theta",
        ],
        "lateral_acceleration": [
            "def a():\n    V * (psi_dot + rr) * cos_r + d_cg * psi_ddot",
        ],
        "yaw_acceleration": [
            "def a():\n    (V / f) * (cos_r / cos_f**2 * rf - cos_fr / cos_f * rr)",
        ],
        "feedforward_angle_rate": [
            "def a():\n    f * k_rate / (1.0 + (f * kappa) ** 2)",
            "def a():\n    wheelbase * slope / (1.0 + lk * lk)",
        ],
        "no_slip_body_state": [
            "def a():\n    speed * (np.tan(u0[0]) - np.tan(u0[1])) / vehicle.wheelbase",
        ],
        "unscaled_gains": [
            "def a():\n    np.interp(v, V, self.k1 * V**2) / v**2",
        ],
    }
    import tempfile

    for key, codes in samples.items():
        for code in codes:
            with tempfile.TemporaryDirectory() as tmp:
                Path(tmp, "copy.py").write_text(code + "\n")
                assert definitions(Path(tmp))[key] == {("copy.py", "a")}, (key, code)


# --------------------------------------------------------------------------
# (b) against sympy


def _sym(name: str) -> sp.Symbol:
    return symbolic.SYMBOLS.get(name) or symbolic.DYNAMIC_SYMBOLS[name]


V, f, d, kappa = (_sym(n) for n in ("speed", "wheelbase", "rear_to_cg", "curvature"))
k1, k2, ratio = (_sym(n) for n in ("k1", "k2", "ratio"))
E, TH, DF, DR = (_sym(n) for n in ("e", "theta", "delta_f", "delta_r"))
VY, R = _sym("v_y"), _sym("yaw_rate")
M, IZ = _sym("mass"), _sym("yaw_inertia")
CF, CR = _sym("cornering_front"), _sym("cornering_rear")
T = sp.Symbol("t", real=True)
GLOBAL = symbolic.global_frame_rhs()
PSI = next(s for s in GLOBAL.free_symbols if s.name == "psi")
PATH = symbolic.path_frame_rhs()
# the yaw rate of eq. (10) as sympy solves it from the constraints
YAW = GLOBAL[2]


def _value(expr, values) -> float:
    return float(sp.N(expr.subs(values), 30))


def _close(got, want, scale):
    got = float(got)
    assert math.isfinite(got)
    assert abs(got - want) <= 1e-12 * scale + 1e-12 * abs(want), (got, want)


angles = st.floats(-1.4, 1.4)
units = st.floats(-1.0, 1.0)
speeds = st.floats(-40.0, 40.0)
lengths = st.floats(0.5, 5.0)


@settings(max_examples=40, deadline=None)
@given(speeds, lengths, angles, units, units, st.floats(-0.4, 0.4), units, units)
def test_kinematic_model_against_sympy(Vv, fv, dfv, drv, thv, kv, ev, psiv):
    values = {V: Vv, f: fv, kappa: kv, E: ev, TH: thv, DF: dfv, DR: drv, PSI: psiv}
    scale = (1.0 + abs(Vv)) / math.cos(dfv) ** 2 / (1.0 - kv * ev) ** 2
    _close(equations.yaw_rate(Vv, fv, dfv, drv), _value(YAW, values), scale)
    got = equations.global_frame_derivatives(Vv, fv, psiv, dfv, drv)
    for g, want in zip(got, GLOBAL, strict=True):
        _close(g, _value(want, values), scale)
    got = equations.path_frame_derivatives(Vv, fv, kv, ev, thv, dfv, drv)
    for g, want in zip(got, PATH, strict=True):
        _close(g, _value(want, values), scale)


@settings(max_examples=40, deadline=None)
@given(speeds, lengths, angles, units, units, units)
def test_accelerations_against_sympy(Vv, fv, dfv, drv, rfv, rrv):
    dv = 0.4 * fv
    # the yaw rate of eq. (10) along delta_f(t), delta_r(t): its time
    # derivative by sympy's chain rule, then eq. (13) of symbolic
    df_t, dr_t = sp.Function("df")(T), sp.Function("dr")(T)
    yaw_t = YAW.subs({DF: df_t, DR: dr_t})
    rates = {sp.Derivative(df_t, T): rfv, sp.Derivative(dr_t, T): rrv}
    point = {df_t: dfv, dr_t: drv, V: Vv, f: fv, PSI: 0.0}
    yaw_dd = _value(sp.diff(yaw_t, T).subs(rates), point)
    yaw_d = _value(YAW, {DF: dfv, DR: drv, V: Vv, f: fv, PSI: 0.0})
    scale = (1.0 + abs(Vv)) * (1.0 + abs(rfv) + abs(rrv)) / math.cos(dfv) ** 3
    _close(equations.yaw_acceleration(Vv, fv, dfv, drv, rfv, rrv), yaw_dd, scale)
    lat = symbolic.lateral_acceleration()
    names = {s.name: s for s in lat.free_symbols}
    want = _value(
        lat,
        {
            names["psi_dot"]: yaw_d,
            names["psi_ddot"]: yaw_dd,
            names["delta_r"]: drv,
            names["delta_r_dot"]: rrv,
            V: Vv,
            d: dv,
        },
    )
    got = equations.lateral_acceleration(Vv, dv, drv, rrv, yaw_d, yaw_dd)
    _close(got, want, scale * (1.0 + abs(Vv)))
    # v_y of G: the velocity of G of eq. (11) on the vehicle's lateral axis
    psi_t = sp.Function("psi")(T)
    v_g = sp.Matrix(
        [
            V * sp.cos(psi_t + dr_t) - d * sp.sin(psi_t) * sp.diff(psi_t, T),
            V * sp.sin(psi_t + dr_t) + d * sp.cos(psi_t) * sp.diff(psi_t, T),
        ]
    )
    lateral = -sp.sin(psi_t) * v_g[0] + sp.cos(psi_t) * v_g[1]
    want = _value(
        lateral.subs({sp.Derivative(psi_t, T): yaw_d}),
        {psi_t: 0.3, dr_t: drv, V: Vv, d: dv},
    )
    _close(equations.cg_lateral_velocity(Vv, dv, drv, yaw_d), want, scale)


@settings(max_examples=40, deadline=None)
@given(
    lengths, st.floats(-0.4, 0.4), units, units, units, units,
    st.floats(0.0, 2.0), st.floats(0.0, 2.0), st.floats(-2.0, 2.0),
)  # fmt: skip
def test_law_against_sympy(fv, kv, ev, thv, erv, thrv, k1v, k2v, av):
    # the law of symbolic.characteristic_polynomial, u = K x with
    # K = -[[k1, k2], [a k1, a k2]], plus the feedforward that holds the
    # path-frame model of symbolic on the curve: theta_dot = 0 at
    # e = theta = delta_r = 0
    ff = equations.feedforward_angle(fv, kv)
    at_ff = {V: 7.0, f: fv, kappa: kv, E: 0.0, TH: 0.0, DF: ff, DR: 0.0}
    assert abs(_value(PATH[2], at_ff)) < 1e-13
    K = -sp.Matrix([[k1, k2], [ratio * k1, ratio * k2]])
    e_t, th_t, k_t = (sp.Function(n)(T) for n in ("e", "th", "k"))
    law = K * sp.Matrix([e_t, th_t]) + sp.Matrix([sp.atan(k_t * f), 0])
    krv = 0.3 * erv
    point = {e_t: ev, th_t: thv, k_t: kv, f: fv, k1: k1v, k2: k2v, ratio: av}
    rates = {
        sp.Derivative(e_t, T): erv,
        sp.Derivative(th_t, T): thrv,
        sp.Derivative(k_t, T): krv,
    }
    scale = 10.0 * (1.0 + fv) * (1.0 + abs(av))
    got = equations.steering_law(ev, thv, kv, fv, k1v, k2v, av)
    for g, want in zip(got, law, strict=True):
        _close(g, _value(want, point), scale)
    fb = equations.feedback_command(ev, thv, k1v, k2v, av)
    feedback = K * sp.Matrix([e_t, th_t])
    for g, want in zip(fb, feedback, strict=True):
        _close(g, _value(want, point), scale)
    _close(
        equations.feedback_angle(ev, thv, k1v, k2v), _value(feedback[0], point), scale
    )
    got = equations.steering_law_rate(erv, thrv, kv, krv, fv, k1v, k2v, av)
    for g, want in zip(got, sp.diff(law, T), strict=True):
        _close(g, _value(want.subs(rates), point), scale)
    _close(
        equations.feedforward_angle_rate(fv, kv, krv),
        _value(sp.diff(sp.atan(k_t * f), T).subs(rates), point),
        scale,
    )


@settings(max_examples=30, deadline=None)
@given(
    st.floats(1.0, 40.0), lengths, st.floats(0.2, 0.8), angles, units, units,
    units, st.floats(-0.4, 0.4), units, units,
)  # fmt: skip
def test_dynamic_model_against_sympy(Vv, fv, share, dfv, drv, thv, ev, kv, vyv, rv):
    # slip angles, linear tyres, body equations and path kinematics together
    # against symbolic.dynamic_path_rhs (linear tyres, forward driving)
    dv = share * fv
    mv, izv, cfv, crv = 1500.0, 2600.0, 8.0e4, 9.5e4
    values = {
        V: Vv, f: fv, d: dv, kappa: kv, E: ev, TH: thv, DF: dfv, DR: drv,
        VY: vyv, R: rv, M: mv, IZ: izv, CF: cfv, CR: crv,
    }  # fmt: skip
    want = [_value(x, values) for x in symbolic.dynamic_path_rhs()]
    lf = fv - dv
    alpha_f, alpha_r = equations.slip_angles(Vv, lf, dv, vyv, rv, dfv, drv)
    force_f = equations.linear_tyre_force(alpha_f, cfv)
    force_r = equations.linear_tyre_force(alpha_r, crv)
    body = equations.body_derivatives(
        Vv, mv, izv, lf, dv, rv, force_f, force_r, dfv, drv
    )
    kin = equations.dynamic_path_kinematics(Vv, dv, kv, ev, thv, vyv, rv)
    scale = (1.0 + Vv) * (1.0 + abs(vyv) + abs(rv)) / (1.0 - kv * ev) ** 2
    for g, w in zip([*kin, *body], want, strict=True):
        _close(g, w, scale * (1.0 + abs(w)))
    # the global velocity of R, (u, v_y - l_r r) in the body frame, rotated
    rot = sp.Matrix([[sp.cos(PSI), -sp.sin(PSI)], [sp.sin(PSI), sp.cos(PSI)]])
    v_r = rot * sp.Matrix([V, VY - d * R])
    got = equations.dynamic_global_kinematics(Vv, dv, thv, vyv, rv)
    for g, w in zip(got, v_r, strict=True):
        _close(g, _value(w, {**values, PSI: thv}), scale)
    # no slip: both slip angles vanish at the no-slip body state
    vy0, r0 = equations.no_slip_body_state(Vv, fv, dv, dfv, drv)
    slip = equations.slip_angles(Vv, lf, dv, vy0, r0, dfv, drv)
    assert np.allclose(slip, 0.0, atol=1e-12 / math.cos(dfv) ** 2)


@settings(max_examples=30, deadline=None)
@given(st.floats(1.0, 40.0), st.floats(0.1, 10.0), st.floats(0.5, 10.0))
def test_unscaled_gains_keep_the_kinematic_roots(Vv, k1s, k2s):
    """k1 V^2 and k2 V fix the straight-road loop s^2 + k2V/f s + k1V^2/f."""
    import fws_control as fws

    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    k1v, k2v = equations.unscaled_gains(Vv, k1s, k2s)
    A = fws.closed_loop(
        fws.LateralPlant(veh, speed=Vv), fws.SteeringGains(float(k1v), float(k2v), 0.0)
    ).A
    got = np.sort_complex(np.linalg.eigvals(A))
    want = np.sort_complex(np.roots([1.0, k2s / 2.7, k1s / 2.7]))
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.floats(-1.5, 1.5), st.floats(1e4, 2e5), st.floats(1e3, 2e4))
def test_magic_tyre_against_its_formula(alpha, stiffness, peak):
    a, C, D = sp.symbols("alpha C D", real=True)
    c = sp.Rational(13, 10)
    assert equations.MAGIC_SHAPE == 1.3
    formula = D * sp.sin(c * sp.atan(C / (c * D) * a))
    point = {a: alpha, C: stiffness, D: peak}
    _close(
        equations.magic_tyre_force(alpha, stiffness, peak), _value(formula, point), peak
    )
    # the slope at zero slip is the stiffness, and the force stays below D
    assert sp.simplify(sp.diff(formula, a).subs(a, 0) - C) == 0
    assert abs(equations.magic_tyre_force(alpha, stiffness, peak)) <= peak
    _close(equations.linear_tyre_force(alpha, stiffness), stiffness * alpha, stiffness)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-30.0, 30.0), st.floats(-30.0, 30.0), st.floats(-4.0, 4.0), units,
    units, lengths, st.floats(1.0, 15.0), st.floats(-30.0, 30.0),
    st.floats(-30.0, 30.0),
)  # fmt: skip
def test_baseline_geometry_and_laws_against_their_formulas(
    xc, yc, hc, ev, thv, fv, ld, xp, yp
):
    # R and F from the rotation of the path frame and the body frame
    rot = np.array([[math.cos(hc), -math.sin(hc)], [math.sin(hc), math.cos(hc)]])
    r_pt = np.array([xc, yc]) + rot @ np.array([0.0, ev])
    got = equations.rear_axle_point(xc, yc, hc, ev)
    assert np.allclose(got, r_pt, rtol=0.0, atol=1e-12 * (1 + abs(xc) + abs(yc)))
    psi = thv + hc
    f_pt = r_pt + fv * np.array([math.cos(psi), math.sin(psi)])
    xf, yf, psi_got = equations.front_axle_point(xc, yc, hc, ev, thv, fv)
    assert np.allclose([xf, yf], f_pt, rtol=0.0, atol=1e-11 * (1 + abs(xc) + abs(yc)))
    assert psi_got == psi
    # wrap: the representative in (-pi, pi] differing by a multiple of 2 pi
    for a in (psi, 7.0 * psi, -3.0 * psi):
        w = float(equations.wrap_angle(a))
        assert -math.pi < w <= math.pi
        turns = (a - w) / (2 * math.pi)
        assert abs(turns - round(turns)) < 1e-9
    # pure pursuit (Coulter 1992): the look-ahead point in the vehicle
    # frame (x ahead, y left); the arc through R and P has curvature
    # 2 y / L^2 with L^2 = x^2 + y^2, and delta_f = atan(f * curvature) for
    # the distance L_d used in place of L
    local = rot_inv = np.array([[math.cos(psi), math.sin(psi)],
                                [-math.sin(psi), math.cos(psi)]]) @ (
        np.array([xp, yp]) - r_pt)  # fmt: skip
    del rot_inv
    dist = math.hypot(*local)
    if dist > 1e-6:
        sin_alpha = local[1] / dist
        want = math.atan(2.0 * fv * sin_alpha / ld)
        got = equations.pure_pursuit_angle(fv, ld, r_pt[0], r_pt[1], psi, xp, yp)
        assert abs(float(got) - want) <= 1e-9 * (1 + fv / ld)
    assert float(equations.lookahead_offset(ld, ev)) == pytest.approx(
        math.sqrt(max(ld**2 - ev**2, 0.0)), abs=1e-12 * ld
    )
    assert float(equations.lookahead_distance(ld, 0.3, -xp)) == max(ld, 0.3 * abs(xp))


@settings(max_examples=40, deadline=None)
@given(speeds, lengths, st.floats(-0.2, 0.2), units, units, st.floats(0.01, 2.0),
       st.floats(0.01, 2.0))  # fmt: skip
def test_stanley_and_rear_wheel_feedback_against_their_formulas(
    Vv, fv, kv, ev, thv, kev, ktv
):
    want = -thv - math.atan(kev * ev / (0.1 + abs(Vv)))
    assert float(equations.stanley_angle(thv, ev, kev, 0.1, Vv)) == pytest.approx(
        want, abs=1e-14
    )
    if abs(Vv) < 1e-3:
        return
    sinc = math.sin(thv) / thv if thv != 0.0 else 1.0
    omega = (
        Vv * kv * math.cos(thv) / (1 - kv * ev)
        - ktv * abs(Vv) * thv
        - kev * Vv * ev * sinc
    )
    got = equations.rear_wheel_feedback_angle(Vv, fv, kv, ev, thv, kev, ktv)
    assert float(got) == pytest.approx(math.atan(fv * omega / Vv), abs=1e-13)


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-3.0, 3.0),
    st.one_of(st.floats(0.01, 2.0), st.just(math.inf)),
    st.sampled_from([-1.0, 0.0, 1.0]),
    st.sampled_from([-1.0, 0.0, 1.0]),
)
def test_clip_switch_margin_against_its_cases(value, limit, mode, released):
    # the event function of a clip's switch, case by case: held at a limit
    # it switches when the value comes back inside; free, at either limit;
    # released from a limit, at the opposite one only
    if mode != 0.0:
        if math.isinf(limit):
            return  # no clip: never held
        want = mode * value - limit
    elif released == 0.0:
        want = limit - abs(value)
    else:
        want = limit + released * value
    got = equations.clip_switch_margin(value, limit, mode, released)
    assert got == want  # the same operations: exactly
    # the sign says whether the mode is right for the value
    if mode != 0.0:
        assert (got > 0.0) == (mode * value > limit)
    elif released == 0.0:
        assert (got > 0.0) == (abs(value) < limit)


# --------------------------------------------------------------------------
# (c) the compiled equations are the numpy ones, bit for bit


def _random_arguments(name: str, n: int, rng) -> list[np.ndarray]:
    """Random arguments for each equation, n of each (fixed seed)."""
    u = rng.uniform
    arg = {
        "speed": u(-40.0, 40.0, n),
        "wheelbase": u(0.5, 5.0, n),
        "rear_to_cg": u(0.2, 3.0, n),
        "front_to_cg": u(0.2, 3.0, n),
        "curvature": u(-0.5, 0.5, n),
        "curvature_rate": u(-1.0, 1.0, n),
        "e": u(-1.5, 1.5, n),
        "theta": u(-1.5, 1.5, n),
        "psi": u(-4.0, 4.0, n),
        "e_rate": u(-20.0, 20.0, n),
        "theta_rate": u(-5.0, 5.0, n),
        "delta_f": u(-1.5, 1.5, n),
        "delta_r": u(-1.5, 1.5, n),
        "delta_f_rate": u(-5.0, 5.0, n),
        "delta_r_rate": u(-5.0, 5.0, n),
        "yaw_rate": u(-2.0, 2.0, n),
        "yaw_acceleration": u(-5.0, 5.0, n),
        "k_e": u(0.0, 2.0, n),
        "k_theta": u(0.0, 2.0, n),
        "k1": u(0.0, 2.0, n),
        "k1_scaled": u(0.0, 20.0, n),
        "k2_scaled": u(0.0, 20.0, n),
        "k2": u(0.0, 2.0, n),
        "ratio": u(-2.0, 2.0, n),
        "v_y": u(-5.0, 5.0, n),
        "slip": u(-1.0, 1.0, n),
        "stiffness": u(1e4, 2e5, n),
        "peak": u(1e3, 2e4, n),
        "mass": u(500.0, 3000.0, n),
        "yaw_inertia": u(500.0, 5000.0, n),
        "force_f": u(-1e4, 1e4, n),
        "force_r": u(-1e4, 1e4, n),
        "x": u(-50.0, 50.0, n),
        "y": u(-50.0, 50.0, n),
        "heading": u(-4.0, 4.0, n),
        "angle": u(-10.0, 10.0, n),
        "lookahead": u(0.5, 20.0, n),
        "lookahead_time": u(0.0, 2.0, n),
        "x_r": u(-50.0, 50.0, n),
        "y_r": u(-50.0, 50.0, n),
        "x_p": u(-50.0, 50.0, n),
        "y_p": u(-50.0, 50.0, n),
        "theta_f": u(-3.0, 3.0, n),
        "e_f": u(-3.0, 3.0, n),
        "gain": u(0.1, 5.0, n),
        "softening": u(0.0, 1.0, n),
        "value": u(-3.0, 3.0, n),
        "limit": u(0.05, 2.0, n),
        "mode": rng.integers(-1, 2, n).astype(float),
        "released": rng.integers(-1, 2, n).astype(float),
    }
    fn = getattr(equations, name)
    names = fn.__code__.co_varnames[: fn.__code__.co_argcount]
    return [arg[a] for a in names]


def _functions() -> list[str]:
    return [n for n in equations.__all__ if callable(getattr(equations, n))]


def test_every_equation_has_random_arguments():
    rng = np.random.default_rng(0)
    for name in _functions():
        fn = getattr(equations, name)
        assert len(_random_arguments(name, 3, rng)) == fn.__code__.co_argcount >= 1


# numpy's SIMD loops for AVX-512 (dispatch target X86_V4 in numpy 2.4,
# AVX512_SKX before) compute arctan, tan, exp and arctan2 with their own
# polynomials: measured on a Cascade Lake CPU, 0.2-7 % of random arguments
# differ from the C library's result by 1 ulp. numba calls the C library.
# numpy with its dispatched targets switched off (NPY_DISABLE_CPU_FEATURES,
# read at its import: hence a process of its own) runs its baseline loops,
# which round as the C library does; on a CPU without AVX-512 (numpy's
# AVX2 loops) the two agree in-process too.
_EVALUATE = """
import sys
import numpy as np
from fws_control import equations
data = np.load(sys.argv[1])
out = {}
with np.errstate(all="ignore"):
    for name in sorted({k.split(":")[0] for k in data.files}):
        args = [data[f"{name}:{i}"] for i in range(int(data[f"{name}:n"]))]
        value = np.array(getattr(equations, name)(*args), dtype=float)
        out[name] = np.atleast_2d(value)
np.savez(sys.argv[2], **out)
"""


@pytest.fixture(scope="module")
def baseline_numpy(tmp_path_factory):
    """Each equation's numpy result on the random arguments of
    :func:`_random_arguments` (n = 10 000, seed 26), computed by numpy at
    its baseline loops in a fresh process; and those arguments."""
    import subprocess
    import sys

    try:
        from numpy._core._multiarray_umath import __cpu_dispatch__
    except ImportError:  # numpy < 2
        from numpy.core._multiarray_umath import __cpu_dispatch__
    folder = tmp_path_factory.mktemp("equations")
    args, flat = {}, {}
    for name in _functions():
        args[name] = _random_arguments(name, 10_000, np.random.default_rng(26))
        flat[f"{name}:n"] = np.array(len(args[name]))
        for i, a in enumerate(args[name]):
            flat[f"{name}:{i}"] = a
    np.savez(folder / "args.npz", **flat)
    env = dict(os.environ, NPY_DISABLE_CPU_FEATURES=" ".join(__cpu_dispatch__))
    done = subprocess.run(
        [sys.executable, "-c", _EVALUATE, str(folder / "args.npz"),
         str(folder / "want.npz")],
        env=env, capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    with np.load(folder / "want.npz") as want:
        return args, {name: want[name] for name in want.files}


@pytest.mark.parametrize("name", _functions())
def test_compiled_equation_equals_numpy_bit_for_bit(name, baseline_numpy):
    from fws_control.simulation import compiled

    if not compiled.available():
        pytest.skip("numba is not installed: no compiled equations to compare")
    import numba

    # the compiled engine's own version
    from fws_control.simulation.compiled_layout import EQUATIONS

    fn = EQUATIONS[name]
    assert isinstance(fn, numba.core.dispatcher.Dispatcher)
    args, want = baseline_numpy[0][name], baseline_numpy[1][name]
    n = args[0].size
    got = np.empty_like(want)
    for i in range(n):
        out = fn(*(a[i] for a in args))
        got[:, i] = out if isinstance(out, tuple) else (out,)
    assert np.isfinite(want).all()
    # equal bit for bit (not only to a tolerance), signs of zeros included
    assert np.array_equal(got.view(np.int64), want.view(np.int64))
