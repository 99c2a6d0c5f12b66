r"""Independent symbolic derivations with sympy.

Everything here is derived from the paper's starting points — the kinematic
constraints (5)-(7), the frame transformation (14)-(16) (with the sign of the
curvature term as it must be, see the errata) and the transport formula (11)
— and not from the numeric code. The tests hold the numeric implementation
equal to these expressions, so each equation has one numeric implementation
and one independent derivation.

Symbols: ``V`` speed, ``f`` wheelbase, ``d`` rear_to_cg, ``kappa``
curvature, ``a`` ratio, ``k1, k2`` gains, ``lam0`` double root, ``lam`` the
Laplace variable; for the dynamic model also ``m`` mass, ``I_z`` yaw
inertia, ``C_f, C_r`` cornering stiffnesses, ``v_y`` lateral velocity of G
and ``r`` yaw rate (:data:`DYNAMIC_SYMBOLS`). In the dynamic model ``V`` is
the constant longitudinal speed :math:`u` of the body.
"""

from __future__ import annotations

from functools import cache

import sympy as sp

from .deprecation import warn_deprecated

__all__ = [
    "SYMBOLS",
    "global_frame_rhs",
    "path_frame_rhs",
    "jacobians",
    "characteristic_polynomial",
    "double_root_gains",
    "paper_gain_formulas",
    "lateral_acceleration",
    "DYNAMIC_SYMBOLS",
    "dynamic_path_rhs",
    "dynamic_small_angle_rhs",
    "dynamic_steady_state",
    "zero_sideslip_ratio",
]

V: sp.Symbol
f: sp.Symbol
d: sp.Symbol
kappa: sp.Symbol
a: sp.Symbol
k1: sp.Symbol
k2: sp.Symbol
lam0: sp.Symbol
lam: sp.Symbol
V, f, d, kappa, a, k1, k2, lam0, lam = sp.symbols(
    "V f d kappa a k1 k2 lam0 lam", real=True
)
t: sp.Symbol = sp.Symbol("t", real=True)
SYMBOLS = {
    "speed": V,
    "wheelbase": f,
    "rear_to_cg": d,
    "curvature": kappa,
    "ratio": a,
    "k1": k1,
    "k2": k2,
    "pole": lam0,
    "lam": lam,
}

_x, _y, _psi, _e, _theta, _s = sp.symbols("x y psi e theta s", real=True)
_df, _dr = sp.symbols("delta_f delta_r", real=True)


@cache
def global_frame_rhs() -> sp.Matrix:
    """``[x_dot, y_dot, psi_dot]`` solved from the constraints (5)-(7)."""
    xd, yd, pd = sp.symbols("xd yd pd")
    eqs = [
        (xd - f * pd * sp.sin(_psi)) * sp.sin(_psi + _df)
        - (yd + f * pd * sp.cos(_psi)) * sp.cos(_psi + _df),
        xd * sp.sin(_psi + _dr) - yd * sp.cos(_psi + _dr),
        xd * sp.cos(_psi + _dr) + yd * sp.sin(_psi + _dr) - V,
    ]
    sol = sp.solve(eqs, [xd, yd, pd], dict=True)[0]
    return sp.Matrix(
        [
            sp.simplify(sol[xd]),
            sp.simplify(sol[yd]),
            sp.simplify(sp.expand_trig(sol[pd])),
        ]
    )


@cache
def path_frame_rhs() -> sp.Matrix:
    """``[s_dot, e_dot, theta_dot]`` from (14)-(16) with ``psi = theta + psi_C``.

    Eq. (16) is used as ``theta_dot = psi_dot - kappa*s_dot``, the
    consequence of ``theta = psi - psi_C`` and ``psi_C_dot = kappa*s_dot``.
    """
    psi_c = sp.Symbol("psi_C", real=True)
    xd, yd, pd = global_frame_rhs().subs(_psi, _theta + psi_c)
    s_dot = (xd * sp.cos(psi_c) + yd * sp.sin(psi_c)) / (1 - kappa * _e)
    e_dot = -xd * sp.sin(psi_c) + yd * sp.cos(psi_c)
    theta_dot = pd - kappa * s_dot
    return sp.Matrix([sp.simplify(s_dot), sp.simplify(e_dot), sp.simplify(theta_dot)])


@cache
def jacobians(model: str = "kinematic") -> tuple[sp.Matrix, sp.Matrix]:
    """``(A, B)`` of the ``(e, theta)`` dynamics at the feedforward point.

    ``model="kinematic"`` differentiates :func:`path_frame_rhs` at
    ``e = theta = delta_r = 0, delta_f = atan(kappa*f)``; ``model="paper"``
    returns eq. (33) as printed.
    """
    if model == "paper":
        return (
            sp.Matrix([[0, V], [-V * kappa**2, 0]]),
            sp.Matrix([[0, V], [V / f, -V / f]]),
        )
    if model == "exact":
        warn_deprecated("model='exact'", "model='kinematic'")
        model = "kinematic"
    if model != "kinematic":
        raise ValueError(f"model must be 'kinematic' or 'paper', got {model!r}")
    rhs = path_frame_rhs()[1:, :]
    point = {_e: 0, _theta: 0, _dr: 0, _df: sp.atan(kappa * f)}
    A = rhs.jacobian([_e, _theta]).subs(point)
    B = rhs.jacobian([_df, _dr]).subs(point)
    return sp.simplify(A), sp.simplify(B)


@cache
def characteristic_polynomial(model: str = "kinematic") -> sp.Poly:
    """``det(lam*I - A - B*K)`` with ``K = -[[k1, k2], [a*k1, a*k2]]``."""
    A, B = jacobians(model)
    K = -sp.Matrix([[k1, k2], [a * k1, a * k2]])
    return sp.Poly(sp.expand((lam * sp.eye(2) - A - B * K).det()), lam)


@cache
def double_root_gains(model: str = "kinematic") -> dict[sp.Symbol, sp.Expr]:
    """``{k1: ..., k2: ...}`` matching ``(lam - lam0)**2`` (eqs. 39-40)."""
    p = characteristic_polynomial(model).all_coeffs()
    target = sp.Poly((lam - lam0) ** 2, lam).all_coeffs()
    sol = sp.solve([p[1] - target[1], p[2] - target[2]], [k1, k2], dict=True)
    (only,) = sol
    return {k: sp.simplify(v) for k, v in only.items()}


def paper_gain_formulas() -> dict[str, dict[sp.Symbol, sp.Expr]]:
    """The paper's printed gain formulas, eqs. (41), (42), (44), (45)-(46).

    Returned verbatim (including the wrong k1 of eq. 42) so that the errata
    tests can show where they differ from :func:`double_root_gains`.
    """
    den = V**2 * (a**2 * f**2 * kappa**2 + (1 - a) ** 2)
    num = V**2 * a * f * kappa**2 - 2 * V * lam0 * (1 - a) - a * f * lam0**2
    K2 = f * num / den
    K1 = -2 * lam0 / (V * a) + num / den * (1 - 1 / a)
    return {
        "41": {
            k1: f * lam0**2 / (V**2 * (1 - a)),
            k2: -lam0 * f / (V * (1 - a)) * (2 + lam0 * a * f / (V * (1 - a))),
        },
        "42": {k1: -2 * lam0 / f},
        "44": {k1: f * (lam0**2 / V**2 - kappa**2), k2: -2 * lam0 * f / V},
        "45-46": {k1: K1, k2: K2},
    }


@cache
def lateral_acceleration() -> sp.Expr:
    """Lateral acceleration of G from eqs. (11)-(12), projected as in (13).

    Differentiates the velocity of G (transport formula 11) in time with
    ``x_R, y_R, psi, delta_f, delta_r`` functions of time and eq. (8)-(9)
    for the velocity of R, then projects on ``[-sin psi, cos psi]``. The
    result is expressed with symbols ``psi_dot, psi_ddot, delta_r,
    delta_r_dot``.
    """
    psi = sp.Function("psi", real=True)(t)
    dr = sp.Function("delta_r", real=True)(t)
    v_r = sp.Matrix([V * sp.cos(psi + dr), V * sp.sin(psi + dr), 0])
    omega = sp.Matrix([0, 0, psi.diff(t)])
    r_rg = sp.Matrix([d * sp.cos(psi), d * sp.sin(psi), 0])
    v_g = v_r + omega.cross(r_rg)
    a_g = v_g.diff(t)
    lat = -a_g[0] * sp.sin(psi) + a_g[1] * sp.cos(psi)
    pdot, pddot, drs, drdot = sp.symbols("psi_dot psi_ddot delta_r delta_r_dot")
    lat = (
        lat.subs({psi.diff(t, 2): pddot, dr.diff(t): drdot})
        .subs({psi.diff(t): pdot})
        .subs({dr: drs})
    )
    return sp.simplify(lat)


m: sp.Symbol
I_z: sp.Symbol
C_f: sp.Symbol
C_r: sp.Symbol
m, I_z, C_f, C_r = sp.symbols("m I_z C_f C_r", positive=True)
_vy, _r = sp.symbols("v_y r", real=True)
DYNAMIC_SYMBOLS = {
    "mass": m,
    "yaw_inertia": I_z,
    "cornering_front": C_f,
    "cornering_rear": C_r,
    "v_y": _vy,
    "yaw_rate": _r,
    "e": _e,
    "theta": _theta,
    "delta_f": _df,
    "delta_r": _dr,
}


@cache
def dynamic_path_rhs() -> sp.Matrix:
    r"""``[s_dot, e_dot, theta_dot, v_y_dot, r_dot]`` of the dynamic model.

    Derived from Newton-Euler for a rigid body in the plane with linear
    tyres, not from the numeric code:

    * the velocity of G in the world is :math:`R(\psi)[V, v_y]^T`; its time
      derivative (``psi``, ``v_y`` functions of time, ``V`` constant),
      projected on the body's lateral axis, is the lateral acceleration;
    * each axle point P (``+l_f`` and ``-l_r`` on the body axis) moves with
      :math:`v_G + \omega\times r_{GP}` (transport formula); its slip angle
      is the steering angle minus the direction of that velocity in the body
      frame, :math:`\alpha = \delta - \arctan(v_{P,y}/V)` (``V > 0``);
    * the axle force :math:`C\alpha`, normal to the wheel, is the vector
      :math:`C\alpha[-\sin\delta, \cos\delta]` in the body frame; the
      lateral equation takes the body-``y`` components, the yaw equation the
      moments :math:`(r_{GP}\times F)_z` about G;
    * R is the point ``-l_r``; its world velocity, rotated into the path
      frame at ``psi = theta + psi_C``, gives ``s_dot``, ``e_dot`` as in
      :func:`path_frame_rhs`, and ``theta_dot = r - kappa*s_dot``.

    The longitudinal equation is not used: the drive holds ``V`` constant.
    """
    tt = t
    psi = sp.Function("psi", real=True)(tt)
    vy = sp.Function("v_y", real=True)(tt)
    rot = sp.Matrix([[sp.cos(psi), -sp.sin(psi)], [sp.sin(psi), sp.cos(psi)]])
    acc = rot.T * (rot * sp.Matrix([V, vy])).diff(tt)  # body-frame acceleration
    r_t = psi.diff(tt)
    lat_acc = sp.simplify(acc[1]).subs({vy.diff(tt): sp.Symbol("vyd"), r_t: _r})
    lat_acc = lat_acc.subs(vy, _vy)
    l_f, l_r = f - d, d
    omega = sp.Matrix([0, 0, _r])
    v_g = sp.Matrix([V, _vy, 0])
    forces, moment = sp.Integer(0), sp.Integer(0)
    for pos, delta, stiff in ((l_f, _df, C_f), (-l_r, _dr, C_r)):
        r_gp = sp.Matrix([pos, 0, 0])
        v_p = v_g + omega.cross(r_gp)
        # atan2(v_y, v_x) = atan(v_y/v_x) for v_x = V > 0 (forward driving)
        alpha = delta - sp.atan(v_p[1] / v_p[0])
        force = stiff * alpha * sp.Matrix([-sp.sin(delta), sp.cos(delta), 0])
        forces += force[1]
        moment += r_gp.cross(force)[2]
    vyd = sp.solve(sp.Eq(m * lat_acc, forces), sp.Symbol("vyd"))[0]
    rd = moment / I_z
    # R in the world frame, then in the path frame
    psi_c = sp.Symbol("psi_C", real=True)
    v_r_body = v_g + omega.cross(sp.Matrix([-l_r, 0, 0]))
    ps = _theta + psi_c
    xd = v_r_body[0] * sp.cos(ps) - v_r_body[1] * sp.sin(ps)
    yd = v_r_body[0] * sp.sin(ps) + v_r_body[1] * sp.cos(ps)
    s_dot = (xd * sp.cos(psi_c) + yd * sp.sin(psi_c)) / (1 - kappa * _e)
    e_dot = -xd * sp.sin(psi_c) + yd * sp.cos(psi_c)
    theta_dot = _r - kappa * s_dot
    return sp.Matrix(
        [
            sp.simplify(s_dot),
            sp.simplify(e_dot),
            sp.simplify(theta_dot),
            sp.expand(vyd),
            sp.expand(rd),
        ]
    )


@cache
def dynamic_small_angle_rhs() -> sp.Matrix:
    """:func:`dynamic_path_rhs` to first order in the small quantities.

    First order in the angles, velocities, errors and the curvature; keeps
    the ``-kappa**2 V e`` term of ``theta_dot`` (first order in ``e`` at a
    given curvature), as the exact kinematic linearisation does.
    """
    rhs = dynamic_path_rhs()
    eps = sp.Symbol("epsilon")
    small = {x: eps * x for x in (_e, _theta, _vy, _r, _df, _dr)}
    out = []
    for expr in rhs:
        # scale the small quantities and the curvature by eps and keep the
        # first order; the kappa**2*e term is restored below
        scaled = expr.subs(small).subs(kappa, eps * kappa)
        first = scaled.subs(eps, 0) + sp.diff(scaled, eps).subs(eps, 0)
        out.append(sp.expand(sp.simplify(first)))
    out[2] = out[2] - kappa**2 * V * _e
    return sp.Matrix(out)


@cache
def dynamic_steady_state() -> dict[sp.Symbol, sp.Expr]:
    r"""Steady ``{e: ..., theta: ..., v_y: ..., r: ...}`` of the paper's loop.

    The paper's controller with the kinematic feedforward,
    :math:`\delta_f = \kappa f - k_1 e - k_2\theta` (first order of
    :math:`\arctan(\kappa f)`), :math:`\delta_r = a(-k_1 e - k_2\theta)`,
    closes the small-angle form of :func:`dynamic_path_rhs` (first order in
    every angle, velocity, error and in the curvature, keeping the
    :math:`-\kappa^2 V e` of ``theta_dot``); the steady state solves
    ``e_dot = theta_dot = v_y_dot = r_dot = 0``.
    """
    rhs = dynamic_small_angle_rhs()
    z = k1 * _e + k2 * _theta
    law = {_df: kappa * f - z, _dr: -a * z}
    eqs = [sp.expand(x.subs(law)) for x in rhs[1:]]
    sol = sp.solve(eqs, [_e, _theta, _vy, _r], dict=True)
    (only,) = sol
    return {k: sp.factor(v) for k, v in only.items()}


@cache
def zero_sideslip_ratio() -> sp.Expr:
    r"""Ratio :math:`a = \delta_r/\delta_f` with zero steady sideslip at G.

    Steady turning of the small-angle form of :func:`dynamic_path_rhs`
    (``v_y_dot = r_dot = 0``) with ``delta_r = a*delta_f`` and ``v_y = 0``,
    solved for ``a``.
    """
    rhs = dynamic_small_angle_rhs()
    eqs = [x.subs({_vy: 0, _dr: a * _df}) for x in rhs[3:]]
    sol = sp.solve(eqs, [a, _r], dict=True)
    sol = [s_ for s_ in sol if s_[_r] != 0]
    (only,) = sol
    return sp.factor(only[a])
