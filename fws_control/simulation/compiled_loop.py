"""The compiled closed loop: the law, the clips and the right-hand side.

The kernels of one run's closed loop for the compiled engine
(:mod:`~fws_control.simulation.compiled`): the path's curvature from its
table, the paper's law or a controller's compiled law with the steering
limits (clipped or held by their switching modes), an input delay's
measured state from the run's own past, the kinematic and the dynamic
model's derivatives, :func:`closed_loop_rhs` and its Jacobian
:func:`closed_loop_jac` (for Radau).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..lateral_controller import RATE_STEP
from .compilation import jit
from .compiled_laws import (
    LAWS,
    P_LAW,
    Q_CURVATURE_ROWS,
    Q_LAW,
    make_law_command,
)
from .compiled_layout import (
    EQUATIONS,
    NP,
    NPOW,
    P_HIST,
    P_K1,
    P_K2,
    P_MODE,
    P_N_HIST,
    P_NOW,
    P_RATIO,
    P_SPEED,
    Q_C_F,
    Q_C_R,
    Q_DELAY,
    Q_DYNAMIC,
    Q_FF,
    Q_FF_ANGLE0,
    Q_INERTIA,
    Q_KAPPA0,
    Q_L_F,
    Q_L_R,
    Q_MASS,
    Q_MAX_F,
    Q_MAX_R,
    Q_PEAK_F,
    Q_PEAK_R,
    Q_PERIOD,
    Q_RATE_F,
    Q_RATE_R,
    Q_S_HI,
    Q_S_LO,
    Q_SWITCH,
    Q_TAU,
    Q_WHEELBASE,
    WITH_DELAY,
    WITH_DYNAMIC,
    WITH_LAW,
    WITH_PROFILE,
    body_derivatives,
    dynamic_path_kinematics,
    feedback_command,
    feedforward_equation,
    feedforward_rate,
    jit_inline,
    linear_tyre_force,
    magic_tyre_force,
    path_frame_derivatives,
    slip_angles,
    table_piece,
)
from .compiled_speed import (
    P_SPEED_TIME,
    Q_PROFILE,
    speed_and_gains,
)

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []

_STATE_FEEDBACK = LAWS.index("state_feedback")

# --------------------------------------------------------------------------
# The closed loop


@jit
def wrap_lap(s, period):
    """``s % period`` with Python's semantics (as np.mod), bit for bit.

    Numba's float ``%`` (fmod, then CPython's sign fix-up) costs 17 ns per
    call, paid at every output time of a closed path and at every
    evaluation of the right-hand side (about 700 per run on the paper's
    curve). Within a lap and the neighbouring ones the
    result is computed as Python does without fmod: on [0, period)
    fmod(s, period) is s itself; on [period, 2 period) it is s - period,
    which is exact (Sterbenz); on [-period, 0) Python adds period to
    fmod(s, period) = s. A zero result is +0.0, as in Python.
    """
    if s >= 0.0:
        if s < period:
            return s if s != 0.0 else 0.0
        if s < 2.0 * period:
            return s - period
    elif s >= -period:
        return s + period
    return s % period


def _table_position(s, q):
    # s as the path's tables take it, as Path._domain does: wrapped into
    # [0, period) on a closed path (Python semantics, as np.mod), clipped to
    # an open one (as the numpy engine does for trial stages)
    period = q[Q_PERIOD]
    if period > 0.0:
        s = wrap_lap(s, period)
        if s >= period:
            s = 0.0
        return s
    return min(max(s, q[Q_S_LO]), q[Q_S_HI])


# (declared: numba's dispatcher has no type of its own)
table_position: Callable[[float, np.ndarray], float] = jit_inline(_table_position)


@jit
def feedforward_angle(kappa, q):
    """``atan(f kappa)``, the feedforward angle; for the first table
    piece's constant curvature (an arc, a straight) the value computed once
    in :func:`shared_parameters` with the same ``atan`` (16 ns a call,
    paid at every output time and right-hand-side evaluation). A
    curvature of -0.0 gets the angle of +0.0."""
    if kappa == q[Q_KAPPA0]:
        return q[Q_FF_ANGLE0]
    return feedforward_equation(q[Q_WHEELBASE], kappa)


@jit
def curvature_at(s, q, breaks, coefs):
    s = table_position(s, q)
    # (other tables follow the curvature's rows in breaks and coefs)
    k = table_piece(s, breaks, 0, int(q[Q_CURVATURE_ROWS]))
    d = s - breaks[k]
    return coefs[k, 0] + d * (coefs[k, 1] + d * (coefs[k, 2] + d * coefs[k, 3]))


@jit_inline
def measured_state(t, y, p, q):
    """``(s, e, theta)`` the law acts on at time `t`: those of `y` without a
    delay; with an input delay D those at ``t - D``, from the run's past
    held in `p` (see ``P_HIST``) as ``engine._History.state`` finds them:
    the initial state up to the start, then the dense output of the last
    accepted step that starts at or before ``t - D``."""
    delay = q[Q_DELAY]
    if not delay > 0.0:
        return y[0], y[1], y[2]
    m = y.size
    n = int(p[P_N_HIST])
    base = P_HIST + m
    stride = 2 + (NPOW + 1) * m
    td = t - delay
    if n == 0 or td <= p[base]:
        return p[P_HIST], p[P_HIST + 1], p[P_HIST + 2]
    lo, hi = 0, n
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if p[base + mid * stride] <= td:
            lo = mid
        else:
            hi = mid
    r = base + lo * stride
    x = (td - p[r]) / p[r + 1]
    s, e, th = 0.0, 0.0, 0.0
    for i in range(3):
        v = 0.0
        for k in range(NPOW):
            v += p[r + 2 + m + (NPOW - 1 - k) * m + i]
            if k % 2 == 0:
                v *= x
            else:
                v *= 1 - x
        v += p[r + 2 + i]
        if i == 0:
            s = v
        elif i == 1:
            e = v
        else:
            th = v
    return s, e, th


@jit
def with_history(p, y0, rows):
    """`p` extended by an empty past (see ``P_HIST``) with room for `rows`
    steps, the initial state `y0` held before the start."""
    m = y0.size
    out = np.empty(P_HIST + m + rows * (2 + (NPOW + 1) * m))
    for i in range(NP):
        # (solve_run may be given the 4 run parameters alone: modes 0)
        out[i] = p[i] if i < p.size else 0.0
    out[P_NOW] = 0.0
    out[P_N_HIST] = 0.0
    for i in range(m):
        out[P_HIST + i] = y0[i]
    return out


@jit
def add_to_history(p, t_old, h, y_old, F):
    """Append an accepted step to the past held in `p`; returns `p`, or a
    copy with twice the room when it was full."""
    m = y_old.size
    stride = 2 + (NPOW + 1) * m
    n = int(p[P_N_HIST])
    r = P_HIST + m + n * stride
    if r + stride > p.size:
        grown = np.empty(P_HIST + m + 2 * max(n, 16) * stride)
        for i in range(r):
            grown[i] = p[i]
        p = grown
    p[r] = t_old
    p[r + 1] = h
    for i in range(m):
        p[r + 2 + i] = y_old[i]
        for k in range(NPOW):
            p[r + 2 + m + k * m + i] = F[k, i]
    p[P_N_HIST] = n + 1
    return p


@jit_inline
def dynamic_derivatives(V, kappa, e, th, vy, r, df, dr, q):
    """``(s_dot, e_dot, theta_dot, v_y_dot, r_dot)`` of the dynamic model, as
    dynamics.dynamic_path_derivatives (the same equations)."""
    l_f, l_r = q[Q_L_F], q[Q_L_R]
    alpha_f, alpha_r = slip_angles(V, l_f, l_r, vy, r, df, dr)
    if q[Q_PEAK_F] > 0.0:
        force_f = magic_tyre_force(alpha_f, q[Q_C_F], q[Q_PEAK_F])
        force_r = magic_tyre_force(alpha_r, q[Q_C_R], q[Q_PEAK_R])
    else:
        force_f = linear_tyre_force(alpha_f, q[Q_C_F])
        force_r = linear_tyre_force(alpha_r, q[Q_C_R])
    vy_dot, r_dot = body_derivatives(
        V, q[Q_MASS], q[Q_INERTIA], l_f, l_r, r, force_f, force_r, df, dr
    )
    s_dot, e_dot, th_dot = dynamic_path_kinematics(V, l_r, kappa, e, th, vy, r)
    return s_dot, e_dot, th_dot, vy_dot, r_dot


law_command = make_law_command(EQUATIONS, table_position, table_piece, jit)
feedback_angle = EQUATIONS["feedback_angle"]


@jit_inline
def follow_speed(t, s, p, q, breaks, coefs):
    # a varying speed (compiled_speed): the run's speed, and a schedule's
    # gains, at time t and arc length s, into p
    V, k1, k2, a, scheduled = speed_and_gains(t, s, q, breaks, coefs)
    p[P_SPEED] = V
    if scheduled:
        p[P_K1], p[P_K2], p[P_RATIO] = k1, k2, a


@jit_inline
def raw_command(s, e, theta, kappa, p, q, breaks, coefs):
    if WITH_LAW and q[Q_LAW] != 0.0:  # a controller's compiled law (compiled_laws)
        return law_command(s, e, theta, kappa, p, q, breaks, coefs)
    cf, cr = feedback_command(e, theta, p[P_K1], p[P_K2], p[P_RATIO])
    if q[Q_FF] != 0.0:
        cf = cf + feedforward_angle(kappa, q)
    return cf, cr


@jit_inline
def rate_needs_curvature_slope(p, q):
    """Whether :func:`command_rate` reads ``d kappa / ds``: the feedforward
    of the paper's law or of a state-feedback law (the other laws' rates
    re-read the curvature at the moved arc length)."""
    if WITH_LAW and q[Q_LAW] != 0.0:
        return q[Q_LAW] == _STATE_FEEDBACK and p[P_LAW + 4] != 0.0
    return q[Q_FF] != 0.0


@jit_inline
def command_rate(s, e, th, s_dot, e_dot, th_dot, kappa, dkappa, raw_f, raw_r,
                 p, q, breaks, coefs):  # fmt: skip
    """Time derivative of the command along the motion, 0 where clipped.

    As the numpy engine's ``ClosedLoop.command_rate``: the chain rule for
    the paper's law and a state-feedback law (``dkappa``: the curvature's
    slope at `s`, where :func:`rate_needs_curvature_slope`); for the other
    laws the central difference of
    :meth:`~fws_control.LateralController.steering_rate` (step
    :data:`~fws_control.lateral_controller.RATE_STEP` along the motion, the
    curvature re-read at the moved arc length, one-sided where the other
    point lies off an open path's ends). ``raw_f, raw_r``: the unclipped
    command at the state.
    """
    code = q[Q_LAW] if WITH_LAW else 0.0
    if code == 0.0:
        rf, rr = feedback_command(e_dot, th_dot, p[P_K1], p[P_K2], p[P_RATIO])
        if q[Q_FF] != 0.0:
            rf = rf + feedforward_rate(q[Q_WHEELBASE], kappa, dkappa * s_dot)
    elif code == _STATE_FEEDBACK:
        a = P_LAW
        rf = feedback_angle(e_dot, th_dot, p[a], p[a + 1])
        rr = feedback_angle(e_dot, th_dot, p[a + 2], p[a + 3])
        if p[a + 4] != 0.0:
            rf = rf + feedforward_rate(q[Q_WHEELBASE], kappa, dkappa * s_dot)
    else:
        h = RATE_STEP
        lo, hi = q[Q_S_LO], q[Q_S_HI]
        open_path = not q[Q_PERIOD] > 0.0 and math.isfinite(hi)
        if open_path:
            s = min(max(s, lo), hi)  # the arc length the numpy law is given
        s_p, s_m = s + h * s_dot, s - h * s_dot
        fp_f, fp_r = law_command(
            s_p, e + h * e_dot, th + h * th_dot, curvature_at(s_p, q, breaks, coefs),
            p, q, breaks, coefs,
        )  # fmt: skip
        fm_f, fm_r = law_command(
            s_m, e + (-h) * e_dot, th + (-h) * th_dot,
            curvature_at(s_m, q, breaks, coefs), p, q, breaks, coefs,
        )  # fmt: skip
        rf = (fp_f - fm_f) / (2 * h)
        rr = (fp_r - fm_r) / (2 * h)
        if open_path:
            fwd = s + h * abs(s_dot) <= hi
            bwd = s - h * abs(s_dot) >= lo
            ahead = s_dot >= 0.0
            lost_p = not fwd if ahead else not bwd
            lost_m = not bwd if ahead else not fwd
            if lost_p:
                rf, rr = (raw_f - fm_f) / h, (raw_r - fm_r) / h
            elif lost_m:
                rf, rr = (fp_f - raw_f) / h, (fp_r - raw_r) / h
    if abs(raw_f) > q[Q_MAX_F]:
        rf = 0.0
    if abs(raw_r) > q[Q_MAX_R]:
        rr = 0.0
    return rf, rr


@jit_inline
def clipped_command(s, e, theta, kappa, p, q, breaks, coefs):
    """The paper's law, as controllers.steering_command (same operations).

    With switching (``q[13] = 1``) a clipped channel is held at its limit
    by its mode (``p[4:6]``) rather than by min/max, so that the right-hand
    side is smooth between the located switches.
    """
    cf, cr = raw_command(s, e, theta, kappa, p, q, breaks, coefs)
    mf, mr = q[Q_MAX_F], q[Q_MAX_R]
    if q[Q_SWITCH] != 0.0:
        if p[P_MODE] != 0.0:
            cf = p[P_MODE] * mf
        if p[P_MODE + 1] != 0.0:
            cr = p[P_MODE + 1] * mr
        return cf, cr
    cf = min(max(cf, -mf), mf)
    cr = min(max(cr, -mr), mr)
    return cf, cr


@jit
def clip_values(y, p, q, breaks, coefs, out):
    """Unclipped front/rear commands and actuator rates, and their limits."""
    if WITH_PROFILE and q[Q_PROFILE] != 0.0:
        follow_speed(p[P_SPEED_TIME], y[0], p, q, breaks, coefs)
    kappa = curvature_at(y[0], q, breaks, coefs)
    raw_f, raw_r = raw_command(y[0], y[1], y[2], kappa, p, q, breaks, coefs)
    out[0], out[1] = raw_f, raw_r
    out[4], out[5] = q[Q_MAX_F], q[Q_MAX_R]
    out[6], out[7] = q[Q_RATE_F], q[Q_RATE_R]
    tau = q[Q_TAU]
    if tau > 0.0:
        cf, cr = clipped_command(y[0], y[1], y[2], kappa, p, q, breaks, coefs)
        out[2] = (cf - y[3]) / tau
        out[3] = (cr - y[4]) / tau
    else:
        out[2], out[3] = 0.0, 0.0
        out[6], out[7] = np.inf, np.inf


@jit_inline
def closed_loop_rhs(t, y, p, q, breaks, coefs, out):
    """Right-hand side of one run; writes ``dy/dt`` into `out`.

    Rows of `y`: ``s, e, theta`` and, with an actuator (``q[4] > 0``),
    ``delta_f, delta_r``. `p` holds the run's ``(V, k1, k2, ratio)``, `q`
    the shared parameters (see :func:`integrate_compiled`), ``breaks,
    coefs`` the curvature table. Compiled with numba when it is installed.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import closed_loop_rhs, curvature_table
    >>> from fws_control.simulation.compiled import shared_parameters
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    >>> p = np.array([5.0, 0.1, 0.5, 0.0])          # V, k1, k2, ratio
    >>> # the copy for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs it (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> closed_loop_rhs = variant(closed_loop_rhs, [])
    >>> out = np.empty(3)
    >>> closed_loop_rhs(0.0, np.array([0.0, 1.0, 0.0]), p, q, tab.breaks,
    ...                 tab.coefs, out)
    >>> out.round(6).tolist()            # theta_dot = V tan(-0.1) / f
    [5.0, 0.0, -0.185805]
    """
    s, e, th = y[0], y[1], y[2]
    if WITH_PROFILE and q[Q_PROFILE] != 0.0:
        follow_speed(t, s, p, q, breaks, coefs)
    kappa = curvature_at(s, q, breaks, coefs)
    if WITH_DELAY and q[Q_DELAY] > 0.0:
        # the law acts on the measurements of t - delay
        s_m, e_m, th_m = measured_state(t, y, p, q)
        kappa_m = curvature_at(s_m, q, breaks, coefs)
        cf, cr = clipped_command(s_m, e_m, th_m, kappa_m, p, q, breaks, coefs)
    else:
        cf, cr = clipped_command(s, e, th, kappa, p, q, breaks, coefs)
    tau = q[Q_TAU]
    if tau > 0.0:
        df, dr = y[3], y[4]
    else:
        df, dr = cf, cr
    if WITH_DYNAMIC and q[Q_DYNAMIC] != 0.0:
        m = y.size  # the body's rows v_y, r last
        out[0], out[1], out[2], out[m - 2], out[m - 1] = dynamic_derivatives(
            p[P_SPEED], kappa, e, th, y[m - 2], y[m - 1], df, dr, q
        )
    else:
        out[0], out[1], out[2] = path_frame_derivatives(
            p[P_SPEED], q[Q_WHEELBASE], kappa, e, th, df, dr
        )
    if tau > 0.0:
        rf = (cf - df) / tau
        rr = (cr - dr) / tau
        mf, mr = q[Q_RATE_F], q[Q_RATE_R]
        if q[Q_SWITCH] != 0.0:
            if p[P_MODE + 2] != 0.0:
                rf = p[P_MODE + 2] * mf
            if p[P_MODE + 3] != 0.0:
                rr = p[P_MODE + 3] * mr
            out[3] = rf
            out[4] = rr
        else:
            out[3] = min(max(rf, -mf), mf)
            out[4] = min(max(rr, -mr), mr)


@jit
def closed_loop_jac(t, y, p, q, breaks, coefs, out):
    """Jacobian ``d(dy/dt)/dy`` of :func:`closed_loop_rhs`; writes into `out`.

    Analytic, for the implicit Radau method (whose Newton iteration needs
    it). Where a clip holds a channel (a mode set with ``q[13] = 1``, or
    the min/max active without switching) that channel's derivative is 0,
    as in the right-hand side between its switches. `out` is ``(n, n)``
    with ``n = len(y)`` (5 with an actuator, 3 without).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import closed_loop_jac, curvature_table
    >>> from fws_control.simulation.compiled import shared_parameters
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=0.05)
    >>> p = np.zeros(8); p[:4] = 5.0, 0.1, 0.5, 0.0   # V, k1, k2, ratio
    >>> # the copy for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs it (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> closed_loop_jac = variant(closed_loop_jac, [])
    >>> J = np.empty((5, 5))
    >>> closed_loop_jac(0.0, np.zeros(5), p, q, tab.breaks, tab.coefs, J)
    >>> J[3].round(6).tolist()           # (cf - delta_f) / T, cf = -k1 e - k2 theta
    [0.0, -2.0, -10.0, -20.0, 0.0]
    """
    s, e, th = y[0], y[1], y[2]
    kappa, slope = curvature_and_rate(s, q, breaks, coefs)
    if q[Q_PERIOD] <= 0.0 and (s < q[Q_S_LO] or s > q[Q_S_HI]):
        slope = 0.0  # the open path's curvature is held outside its domain
    cf, cr = raw_command(s, e, th, kappa, p, q, breaks, coefs)
    wheelbase = q[Q_WHEELBASE]
    # d(cf, cr)/d(s, e, theta)
    cf_s = 0.0
    if q[Q_FF] != 0.0:
        cf_s = feedforward_rate(wheelbase, kappa, slope)
    cf_e, cf_th = -p[P_K1], -p[P_K2]
    a = p[P_RATIO]
    cr_s, cr_e, cr_th = 0.0, a * cf_e, a * cf_th
    mf, mr = q[Q_MAX_F], q[Q_MAX_R]
    switching = q[Q_SWITCH] != 0.0
    if (switching and p[P_MODE] != 0.0) or (not switching and abs(cf) > mf):
        cf_s, cf_e, cf_th = 0.0, 0.0, 0.0
    if (switching and p[P_MODE + 1] != 0.0) or (not switching and abs(cr) > mr):
        cr_s, cr_e, cr_th = 0.0, 0.0, 0.0
    tau = q[Q_TAU]
    n = y.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = 0.0
    # d(delta_f, delta_r)/d(s, e, theta) (0 with an actuator: own states)
    df_x = np.zeros(3)
    dr_x = np.zeros(3)
    if tau > 0.0:
        cf_c, cr_c = clipped_command(s, e, th, kappa, p, q, breaks, coefs)
        df, dr = y[3], y[4]
    else:
        cf_c, cr_c = clipped_command(s, e, th, kappa, p, q, breaks, coefs)
        df, dr = cf_c, cr_c
        df_x[0], df_x[1], df_x[2] = cf_s, cf_e, cf_th
        dr_x[0], dr_x[1], dr_x[2] = cr_s, cr_e, cr_th
    V = p[P_SPEED]
    c, sn = math.cos(th + dr), math.sin(th + dr)
    den = 1.0 - kappa * e
    s_dot = V * c / den
    cos_f = math.cos(df)
    # partials in (s, e, theta, delta_f, delta_r) with delta_* held
    sd = np.empty(5)
    sd[0] = V * c * slope * e / (den * den)
    sd[1] = V * c * kappa / (den * den)
    sd[2] = -V * sn / den
    sd[3] = 0.0
    sd[4] = -V * sn / den
    ed = np.empty(5)
    ed[0], ed[1], ed[2], ed[3], ed[4] = 0.0, 0.0, V * c, 0.0, V * c
    td = np.empty(5)
    for j in range(5):
        td[j] = -kappa * sd[j]
    td[0] -= slope * s_dot
    td[3] += V * math.cos(dr) / (wheelbase * cos_f * cos_f)
    td[4] -= V * math.cos(df - dr) / (wheelbase * cos_f)
    if tau > 0.0:
        for j in range(5):
            out[0, j], out[1, j], out[2, j] = sd[j], ed[j], td[j]
        switching_rate_f = switching and p[P_MODE + 2] != 0.0
        switching_rate_r = switching and p[P_MODE + 3] != 0.0
        rf = (cf_c - df) / tau
        rr = (cr_c - dr) / tau
        if not (switching_rate_f or (not switching and abs(rf) > q[Q_RATE_F])):
            out[3, 0], out[3, 1], out[3, 2] = cf_s / tau, cf_e / tau, cf_th / tau
            out[3, 3] = -1.0 / tau
        if not (switching_rate_r or (not switching and abs(rr) > q[Q_RATE_R])):
            out[4, 0], out[4, 1], out[4, 2] = cr_s / tau, cr_e / tau, cr_th / tau
            out[4, 4] = -1.0 / tau
    else:
        # chain rule through delta_f(s, e, theta), delta_r(s, e, theta)
        rows = (sd, ed, td)
        for i in range(3):
            r = rows[i]
            for j in range(3):
                out[i, j] = r[j] + r[3] * df_x[j] + r[4] * dr_x[j]


@jit_inline
def curvature_and_rate(s, q, breaks, coefs):
    # kappa and d kappa / ds of the table from one lookup, at s clipped or
    # wrapped as in curvature_at (the same operations for kappa)
    s = table_position(s, q)
    k = table_piece(s, breaks, 0, int(q[Q_CURVATURE_ROWS]))
    d = s - breaks[k]
    kappa = coefs[k, 0] + d * (coefs[k, 1] + d * (coefs[k, 2] + d * coefs[k, 3]))
    return kappa, coefs[k, 1] + d * (2.0 * coefs[k, 2] + d * 3.0 * coefs[k, 3])
