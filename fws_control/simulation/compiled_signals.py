"""The compiled engine's output signals at the output times.

The signals of :data:`~fws_control.simulation.engine.SIGNALS` of every run
and output time, with the operations of
:func:`~fws_control.simulation.engine.compute_outputs` (the paper's law or
a controller's compiled law; the kinematic and the dynamic model; with an
input delay the law on the delayed path state), for
:func:`~fws_control.simulation.compiled.compiled_outputs`.
"""

from __future__ import annotations

import math

import numpy as np

from .compilation import jit
from .compiled_layout import (
    NPOW,
    NSIG,
    P_SPEED,
    Q_DELAY,
    Q_DYNAMIC,
    Q_L_F,
    Q_L_R,
    Q_MAX_F,
    Q_MAX_R,
    Q_RATE_F,
    Q_RATE_R,
    Q_TAU,
    Q_WHEELBASE,
    WITH_DYNAMIC,
    cg_lateral_velocity,
    dynamic_path_kinematics,
    jit_inline,
    lateral_acceleration,
    path_frame_derivatives,
    slip_angles,
    yaw_acceleration,
    yaw_rate,
)
from .compiled_loop import (
    command_rate,
    curvature_and_rate,
    curvature_at,
    dynamic_derivatives,
    rate_needs_curvature_slope,
    raw_command,
    table_position,
)

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []


@jit_inline
def point_signals(s, e, th, df_s, dr_s, p, q, breaks, coefs, d_cg):
    """The signals of one state with the operations of compute_outputs.

    Returns ``(delta_f, delta_r, their rates, lateral_accel, v_y, yaw_rate,
    ok)``; ``ok`` is False where ``|delta_f| >= pi/2`` (the rates, the
    acceleration, ``v_y`` and the yaw rate are then NaN in a result).
    ``df_s, dr_s``: the actuator states (unused without an actuator); `p`:
    the run's parameters (its speed and its law's gains).
    """
    V = p[P_SPEED]
    f = q[Q_WHEELBASE]
    mf, mr = q[Q_MAX_F], q[Q_MAX_R]
    tau = q[Q_TAU]
    if not tau > 0.0 and rate_needs_curvature_slope(p, q):
        kappa, dkappa = curvature_and_rate(s, q, breaks, coefs)
    else:
        kappa, dkappa = curvature_at(s, q, breaks, coefs), 0.0
    raw_f, raw_r = raw_command(s, e, th, kappa, p, q, breaks, coefs)
    cf = min(max(raw_f, -mf), mf)
    cr = min(max(raw_r, -mr), mr)
    if tau > 0.0:
        df, dr = df_s, dr_s
    else:
        df, dr = cf, cr
    s_dot, e_dot, th_dot = path_frame_derivatives(V, f, kappa, e, th, df, dr)
    psi_dot = yaw_rate(V, f, df, dr)
    if tau > 0.0:
        rf = min(max((cf - df) / tau, -q[Q_RATE_F]), q[Q_RATE_F])
        rr = min(max((cr - dr) / tau, -q[Q_RATE_R]), q[Q_RATE_R])
    else:
        # steering_command_rate: chain rule, 0 where an angle is clipped
        rf, rr = command_rate(s, e, th, s_dot, e_dot, th_dot, kappa, dkappa,
                              raw_f, raw_r, p, q, breaks, coefs)  # fmt: skip
    if not abs(df) < 0.5 * math.pi:
        return df, dr, rf, rr, np.nan, np.nan, psi_dot, False
    psi_ddot = yaw_acceleration(V, f, df, dr, rf, rr)
    lat = lateral_acceleration(V, d_cg, dr, rr, psi_dot, psi_ddot)
    vy = cg_lateral_velocity(V, d_cg, dr, psi_dot)
    return df, dr, rf, rr, lat, vy, psi_dot, True


@jit_inline
def dynamic_point_signals(s, e, th, df_s, dr_s, vy, r, p, q, breaks, coefs):
    """The signals of one state of the dynamic model, as compute_outputs.

    Returns ``(delta_f, delta_r, their rates, lateral_accel, slip_front,
    slip_rear, ok)``: the acceleration of G along the body's lateral axis
    ``dv_y/dt + u r`` (NaN where ``|delta_f| >= pi/2``, as the rates).
    """
    V = p[P_SPEED]
    mf, mr = q[Q_MAX_F], q[Q_MAX_R]
    tau = q[Q_TAU]
    if not tau > 0.0 and rate_needs_curvature_slope(p, q):
        kappa, dkappa = curvature_and_rate(s, q, breaks, coefs)
    else:
        kappa, dkappa = curvature_at(s, q, breaks, coefs), 0.0
    raw_f, raw_r = raw_command(s, e, th, kappa, p, q, breaks, coefs)
    cf = min(max(raw_f, -mf), mf)
    cr = min(max(raw_r, -mr), mr)
    df, dr = (df_s, dr_s) if tau > 0.0 else (cf, cr)
    s_dot, e_dot, th_dot, vy_dot, _ = dynamic_derivatives(
        V, kappa, e, th, vy, r, df, dr, q
    )
    if tau > 0.0:
        rf = min(max((cf - df) / tau, -q[Q_RATE_F]), q[Q_RATE_F])
        rr = min(max((cr - dr) / tau, -q[Q_RATE_R]), q[Q_RATE_R])
    else:
        rf, rr = command_rate(s, e, th, s_dot, e_dot, th_dot, kappa, dkappa,
                              raw_f, raw_r, p, q, breaks, coefs)  # fmt: skip
    alpha_f, alpha_r = slip_angles(V, q[Q_L_F], q[Q_L_R], vy, r, df, dr)
    if not abs(df) < 0.5 * math.pi:
        return df, dr, np.nan, np.nan, np.nan, alpha_f, alpha_r, False
    return df, dr, rf, rr, vy_dot + V * r, alpha_f, alpha_r, True


@jit_inline
def _path_state_at(tt, rec, n_pc, y0, m, first):
    """Rows ``first`` to ``first + 2`` of a run's state at `tt` (``first =
    0``: ``s, e, theta``) from its dense output (`rec`: its pieces), the
    initial state up to the start (engine._History.states_at)."""
    if n_pc == 0 or tt <= rec[0, 0]:
        return y0[first], y0[first + 1], y0[first + 2]
    lo, hi = 0, n_pc
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if rec[mid, 0] <= tt:
            lo = mid
        else:
            hi = mid
    row = rec[lo]
    x = (tt - row[0]) / row[1]
    v0, v1, v2 = 0.0, 0.0, 0.0
    for k in range(NPOW):
        c = 2 + m + (NPOW - 1 - k) * m + first
        v0 += row[c]
        v1 += row[c + 1]
        v2 += row[c + 2]
        w = x if k % 2 == 0 else 1 - x
        v0 *= w
        v1 *= w
        v2 *= w
    return v0 + row[2 + first], v1 + row[3 + first], v2 + row[4 + first]


@jit_inline
def _delayed_steering(tt, df_s, dr_s, rec, n_pc, y0, m, p, q, breaks, coefs,
                      dynamic):  # fmt: skip
    """The applied steering and its rates at `tt` with an input delay, as
    compute_outputs with the delayed rows: the law acts on the path state
    at ``tt - delay`` (`rec`, `y0`: the run's dense output and initial
    state). With an actuator (``df_s, dr_s``: its angles at `tt`) the rates
    are the actuator's; without one the angles are the delayed command and
    their rates its derivative along the delayed motion, 0 before the
    start: the path state's derivative at ``tt - delay``, for the kinematic
    model its closed loop's (the law then on the state at ``tt - 2
    delay``), for the `dynamic` one the path kinematics of its body state
    there. Returns ``(delta_f, delta_r, their rates)``.
    """
    V = p[P_SPEED]
    mf, mr = q[Q_MAX_F], q[Q_MAX_R]
    tau = q[Q_TAU]
    delay = q[Q_DELAY]
    td = tt - delay
    s_m, e_m, th_m = _path_state_at(td, rec, n_pc, y0, m, 0)
    if not tau > 0.0 and rate_needs_curvature_slope(p, q):
        kappa, dkappa = curvature_and_rate(s_m, q, breaks, coefs)
    else:
        kappa, dkappa = curvature_at(s_m, q, breaks, coefs), 0.0
    raw_f, raw_r = raw_command(s_m, e_m, th_m, kappa, p, q, breaks, coefs)
    cf = min(max(raw_f, -mf), mf)
    cr = min(max(raw_r, -mr), mr)
    if tau > 0.0:
        rf = min(max((cf - df_s) / tau, -q[Q_RATE_F]), q[Q_RATE_F])
        rr = min(max((cr - dr_s) / tau, -q[Q_RATE_R]), q[Q_RATE_R])
        return df_s, dr_s, rf, rr
    # the measured state is held before the start: no rate there
    s_dot, e_dot, th_dot = 0.0, 0.0, 0.0
    if n_pc > 0 and td > rec[0, 0]:
        if dynamic:
            # the body's rows v_y, r are the last two (the row before unused)
            _, vy_m, r_m = _path_state_at(td, rec, n_pc, y0, m, m - 3)
            s_dot, e_dot, th_dot = dynamic_path_kinematics(
                V, q[Q_L_R], kappa, e_m, th_m, vy_m, r_m
            )
        else:
            s2, e2, th2 = _path_state_at(td - delay, rec, n_pc, y0, m, 0)
            kappa2 = curvature_at(s2, q, breaks, coefs)
            c2f, c2r = raw_command(s2, e2, th2, kappa2, p, q, breaks, coefs)
            c2f = min(max(c2f, -mf), mf)
            c2r = min(max(c2r, -mr), mr)
            s_dot, e_dot, th_dot = path_frame_derivatives(
                V, q[Q_WHEELBASE], kappa, e_m, th_m, c2f, c2r
            )
    rf, rr = command_rate(s_m, e_m, th_m, s_dot, e_dot, th_dot, kappa, dkappa,
                          raw_f, raw_r, p, q, breaks, coefs)  # fmt: skip
    return cf, cr, rf, rr


@jit_inline
def delayed_point_signals(tt, df_s, dr_s, rec, n_pc, y0, m, p, q, breaks, coefs,
                          d_cg):  # fmt: skip
    """:func:`point_signals` with an input delay (:func:`_delayed_steering`);
    ``df_s, dr_s``: the run's actuator states at `tt`; `p`: the run's
    parameters.
    """
    V = p[P_SPEED]
    f = q[Q_WHEELBASE]
    df, dr, rf, rr = _delayed_steering(
        tt, df_s, dr_s, rec, n_pc, y0, m, p, q, breaks, coefs, False
    )
    psi_dot = yaw_rate(V, f, df, dr)
    if not abs(df) < 0.5 * math.pi:
        return df, dr, rf, rr, np.nan, np.nan, psi_dot, False
    psi_ddot = yaw_acceleration(V, f, df, dr, rf, rr)
    lat = lateral_acceleration(V, d_cg, dr, rr, psi_dot, psi_ddot)
    vy = cg_lateral_velocity(V, d_cg, dr, psi_dot)
    return df, dr, rf, rr, lat, vy, psi_dot, True


@jit
def delayed_dynamic_point_signals(tt, s, e, th, df_s, dr_s, vy, r, rec, n_pc, y0,
                                  m, p, q, breaks, coefs):  # fmt: skip
    """:func:`dynamic_point_signals` with an input delay
    (:func:`_delayed_steering`). ``s, e, th, df_s, dr_s, vy, r``: the run's
    state at `tt` (the actuator's rows unused without an actuator).

    Returns ``(delta_f, delta_r, their rates, lateral_accel, slip_front,
    slip_rear, ok)``: the acceleration ``dv_y/dt + u r`` and the slip angles
    at the current body state with the applied angles. Called, not inlined
    as the other point functions are: only a delayed run of the dynamic
    model needs it, and inlined at each of the peaks' call sites it would
    lengthen the compilation of the kernels of every feature.
    """
    V = p[P_SPEED]
    df, dr, rf, rr = _delayed_steering(
        tt, df_s, dr_s, rec, n_pc, y0, m, p, q, breaks, coefs, True
    )
    kappa = curvature_at(s, q, breaks, coefs)
    _, _, _, vy_dot, _ = dynamic_derivatives(V, kappa, e, th, vy, r, df, dr, q)
    alpha_f, alpha_r = slip_angles(V, q[Q_L_F], q[Q_L_R], vy, r, df, dr)
    if not abs(df) < 0.5 * math.pi:
        return df, dr, np.nan, np.nan, np.nan, alpha_f, alpha_r, False
    return df, dr, rf, rr, vy_dot + V * r, alpha_f, alpha_r, True


@jit
def delayed_signals_batch(states, P, q, breaks, coefs, d_cg, rec, offsets, Y0,
                           t_eval, sig):  # fmt: skip
    # rows 6-14 of sig anew for an input delay: the law on the state at
    # t - delay, from each run's dense output. The kinematic model: the
    # steering angles, their rates, the lateral acceleration, v_y and the
    # yaw rate (its slip angles are 0); the dynamic model: the angles, the
    # rates, the acceleration and the slip angles (v_y and the yaw rate are
    # states). Rows 0-5 do not depend on the law.
    n, m, T = states.shape
    for i in range(n):
        pc = rec[offsets[i] : offsets[i + 1]]
        n_pc = pc.shape[0]
        for k in range(T):
            if not np.isfinite(states[i, 0, k]):
                continue
            df_s, dr_s = 0.0, 0.0
            if q[Q_TAU] > 0.0:
                df_s, dr_s = states[i, 3, k], states[i, 4, k]
            if WITH_DYNAMIC and q[Q_DYNAMIC] != 0.0:
                df, dr, rf, rr, lat, slip_f, slip_r, ok = (
                    delayed_dynamic_point_signals(
                        t_eval[k], states[i, 0, k], states[i, 1, k],
                        states[i, 2, k], df_s, dr_s, states[i, m - 2, k],
                        states[i, m - 1, k], pc, n_pc, Y0[i], m, P[i], q, breaks,
                        coefs,
                    )
                )  # fmt: skip
                sig[i, 6, k] = df
                sig[i, 7, k] = dr
                sig[i, 8, k] = rf
                sig[i, 9, k] = rr
                sig[i, 10, k] = lat
                sig[i, 13, k] = slip_f
                sig[i, 14, k] = slip_r
                continue
            df, dr, rf, rr, lat, vy, psi_dot, ok = delayed_point_signals(
                t_eval[k], df_s, dr_s, pc, n_pc, Y0[i], m, P[i], q, breaks,
                coefs, d_cg,
            )  # fmt: skip
            sig[i, 6, k] = df
            sig[i, 7, k] = dr
            if ok:
                sig[i, 8, k] = rf
                sig[i, 9, k] = rr
                sig[i, 10, k] = lat
                sig[i, 11, k] = vy
                sig[i, 12, k] = psi_dot
                sig[i, 13, k] = 0.0
                sig[i, 14, k] = 0.0
            else:
                for r in range(8, NSIG):
                    sig[i, r, k] = np.nan


@jit
def signals_batch(states, P, q, breaks, coefs, d_cg, pose, sig):
    # sig (n, 15, T) in the order of engine.SIGNALS. Rows 3-14 -- s, e,
    # theta, delta_f, delta_r, their rates, the lateral acceleration of
    # eq. (13), v_y, the yaw rate of eq. (10) and the slip angles (0: the
    # kinematic model has no slip) -- are computed here with the operations
    # of compute_outputs;
    # rows 0-2 (x, y, psi) too when pose[0] is 1 (Straight) or 2 (Arc):
    # pose = (kind, x0, y0, psi0, kappa). psi = theta + psi0 + kappa * s is
    # continuous in time by construction (no unwrapping needed).
    n, m, T = states.shape
    tau = q[Q_TAU]
    kind = int(pose[0])
    x0, y0, psi0, kp = pose[1], pose[2], pose[3], pose[4]
    c0, s0 = math.cos(psi0), math.sin(psi0)
    for i in range(n):
        p = P[i]
        for k in range(T):
            s = states[i, 0, k]
            if not np.isfinite(s):
                for r in range(NSIG):
                    sig[i, r, k] = np.nan
                continue
            e = states[i, 1, k]
            th = states[i, 2, k]
            if tau > 0.0:
                df_s, dr_s = states[i, 3, k], states[i, 4, k]
            else:
                df_s, dr_s = 0.0, 0.0
            if WITH_DYNAMIC and q[Q_DYNAMIC] != 0.0:
                # v_y and the yaw rate are states, the slip angles signals
                vy, psi_dot = states[i, m - 2, k], states[i, m - 1, k]
                df, dr, rf, rr, lat, slip_f, slip_r, ok = dynamic_point_signals(
                    s, e, th, df_s, dr_s, vy, psi_dot, p, q, breaks, coefs
                )
                sig[i, 8, k] = rf
                sig[i, 9, k] = rr
                sig[i, 10, k] = lat
                sig[i, 11, k] = vy
                sig[i, 12, k] = psi_dot
                sig[i, 13, k] = slip_f
                sig[i, 14, k] = slip_r
            else:
                df, dr, rf, rr, lat, vy, psi_dot, ok = point_signals(
                    s, e, th, df_s, dr_s, p, q, breaks, coefs, d_cg
                )
            sig[i, 3, k] = s
            sig[i, 4, k] = e
            sig[i, 5, k] = th
            sig[i, 6, k] = df
            sig[i, 7, k] = dr
            if WITH_DYNAMIC and q[Q_DYNAMIC] != 0.0:
                pass  # rows 8-14 above (rates, acceleration NaN as returned)
            elif ok:
                sig[i, 8, k] = rf
                sig[i, 9, k] = rr
                sig[i, 10, k] = lat
                sig[i, 11, k] = vy
                sig[i, 12, k] = psi_dot
                sig[i, 13, k] = 0.0
                sig[i, 14, k] = 0.0
            else:
                for r in range(8, NSIG):
                    sig[i, r, k] = np.nan
            if kind == 0:
                continue
            sp = table_position(s, q)
            if kind == 1:
                lx, ly = sp, 0.0
                sh, ch = s0, c0  # the path's heading is psi0
            else:  # Arc._frame, from one sincos of half the turned angle
                half = 0.5 * (kp * sp)
                sn, cs = math.sin(half), math.cos(half)
                sin_ks = 2.0 * sn * cs
                cos_ks = (cs - sn) * (cs + sn)
                lx = sin_ks / kp
                ly = 2.0 * sn * sn / kp
                # sin, cos of the heading psi0 + kappa sp by rotation (sp is
                # s wrapped to the lap: the same angle modulo 2 pi)
                sh = s0 * cos_ks + c0 * sin_ks
                ch = c0 * cos_ks - s0 * sin_ks
            px = x0 + c0 * lx - s0 * ly
            py = y0 + s0 * lx + c0 * ly
            h = psi0 + kp * s  # unwrapped heading of the path at s
            sig[i, 0, k] = px - e * sh
            sig[i, 1, k] = py + e * ch
            sig[i, 2, k] = th + h
