"""scipy's Radau IIA (order 5) ported to numba, for stiff closed loops.

The same steps as :class:`scipy.integrate.Radau` given the analytic
Jacobian :func:`~fws_control.simulation.compiled_loop.closed_loop_jac`:
its simplified Newton iteration, step-size control and decisions of when
to recompute the Jacobian, for the compiled engine
(:mod:`~fws_control.simulation.compiled`).
"""

from __future__ import annotations

import math

import numpy as np

from .compilation import jit
from .compiled_dop853 import MAX_FACTOR, MIN_FACTOR
from .compiled_layout import EPS
from .compiled_loop import closed_loop_jac, closed_loop_rhs

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []

# --------------------------------------------------------------------------
# Radau IIA (order 5), a port of scipy.integrate.Radau (no events yet)

_S6 = 6**0.5
_RC = np.array([(4 - _S6) / 10, (4 + _S6) / 10, 1.0])
_RE = np.array([-13 - 7 * _S6, -13 + 7 * _S6, -1.0]) / 3
_MU_REAL = 3 + 3 ** (2 / 3) - 3 ** (1 / 3)
_MU_COMPLEX = (
    3 + 0.5 * (3 ** (1 / 3) - 3 ** (2 / 3)) - 0.5j * (3 ** (5 / 6) + 3 ** (7 / 6))
)
_RT = np.array([
    [0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
    [0.25021312296533332, 0.20412935229379994, -0.38294211275726192],
    [1, 1, 0]])  # fmt: skip
_RTI = np.array([
    [4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
    [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
    [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])  # fmt: skip
_RP = np.array([
    [13/3 + 7*_S6/3, -23/3 - 22*_S6/3, 10/3 + 5 * _S6],
    [13/3 - 7*_S6/3, -23/3 + 22*_S6/3, 10/3 - 5 * _S6],
    [1/3, -8/3, 10/3]])  # fmt: skip
_NEWTON_MAXITER = 6


@jit
def _rms2(x):
    return math.sqrt(np.sum(x * x) / x.size)


@jit
def _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old):
    if error_norm_old < 0.0 or h_abs_old < 0.0 or error_norm == 0:
        multiplier = 1.0
    else:
        multiplier = h_abs / h_abs_old * (error_norm_old / error_norm) ** 0.25
    if error_norm == 0.0:
        return np.inf
    return min(1.0, multiplier) * error_norm**-0.25


# The state of a Radau run between steps (scipy's Radau attributes), in
# rs: its stored h_abs, h_abs_old and error_norm_old (-1: None), whether
# the Jacobian is current, whether M_real and M_complex are built for the
# current h (scipy's LU_real is not None), whether a previous step's dense
# output exists (scipy's sol), and that step's start t_old.
_RS_H, _RS_H_OLD, _RS_ERR_OLD, _RS_CURRENT_JAC, _RS_HAVE_LU = 0, 1, 2, 3, 4
_RS_HAVE_SOL, _RS_T_OLD = 5, 6
NRS = 7


@jit
def radau_start(t, y, h0, p, q, breaks, coefs, rs, J):
    """Radau's state at a (re)start at ``(t, y)`` with first step `h0`."""
    closed_loop_jac(t, y, p, q, breaks, coefs, J)
    rs[_RS_H] = h0
    rs[_RS_H_OLD] = -1.0
    rs[_RS_ERR_OLD] = -1.0
    rs[_RS_CURRENT_JAC] = 1.0
    rs[_RS_HAVE_LU] = 0.0
    rs[_RS_HAVE_SOL] = 0.0
    rs[_RS_T_OLD] = t


@jit
def radau_step(
    t, y, f, t_bound, rtol, atol, p, q, breaks, coefs, rs, J, M_real, M_complex,
    Q, y_old, y_new, f_new,
):  # fmt: skip
    """One accepted step of scipy's ``Radau._step_impl`` from ``(t, y, f)``.

    Writes the new state into `y_new` and its derivative into `f_new`; on
    acceptance updates the state `rs` (see ``_RS_*``), the Jacobian `J`,
    the dense-output matrix `Q` (scipy's ``RadauDenseOutput.Q`` of this
    step) and `y_old` (the step's start, for the next step's predictor).
    Returns ``(status, t_new, rejected, rhs_evaluations)``: status 0 on
    acceptance, -1 when the step size falls below scipy's minimum.
    """
    n = y.size
    tol_newton = max(10 * EPS / rtol, min(0.03, rtol**0.5))
    nfev = 0
    n_rej = 0
    min_step = 10 * abs(np.nextafter(t, np.inf) - t)
    if rs[_RS_H] < min_step:
        h_abs = min_step
        h_abs_old = -1.0
        error_norm_old = -1.0
    else:
        h_abs = rs[_RS_H]
        h_abs_old = rs[_RS_H_OLD]
        error_norm_old = rs[_RS_ERR_OLD]
    current_jac = rs[_RS_CURRENT_JAC] != 0.0
    have_lu = rs[_RS_HAVE_LU] != 0.0
    have_sol = rs[_RS_HAVE_SOL] != 0.0
    t_old = rs[_RS_T_OLD]
    Z = np.zeros((3, n))
    F = np.empty((3, n))
    dW = np.empty((3, n))
    yst = np.empty(n)
    fst = np.empty(n)
    rejected = False
    accepted = False
    n_iter = 0
    rate = -1.0
    error_norm = 0.0
    safety = 0.0
    t_new = t
    h = 0.0
    while not accepted:
        if h_abs < min_step:
            return -1, t, n_rej, nfev
        h = h_abs
        t_new = t + h
        if t_new - t_bound > 0:
            t_new = t_bound
        h = t_new - t
        h_abs = abs(h)
        Z0 = np.zeros((3, n))
        if have_sol:
            for i in range(3):
                x = (t + h * _RC[i] - t_old) / (t - t_old)
                x2 = x * x
                x3 = x2 * x
                for j in range(n):
                    Z0[i, j] = (
                        Q[j, 0] * x + Q[j, 1] * x2 + Q[j, 2] * x3 + y_old[j]
                    ) - y[j]
        scale = atol + np.abs(y) * rtol
        converged = False
        while not converged:
            if not have_lu:
                for i in range(n):
                    for j in range(n):
                        eye = 1.0 if i == j else 0.0
                        M_real[i, j] = _MU_REAL / h * eye - J[i, j]
                        M_complex[i, j] = _MU_COMPLEX / h * eye - J[i, j]
                have_lu = True
            # solve_collocation_system
            Mr = _MU_REAL / h
            Mc = _MU_COMPLEX / h
            W = _RTI @ Z0
            Z = Z0.copy()
            dW_norm_old = -1.0
            converged = False
            rate = -1.0
            finite = True
            k = 0
            for k in range(_NEWTON_MAXITER):
                for i in range(3):
                    for j in range(n):
                        yst[j] = y[j] + Z[i, j]
                    closed_loop_rhs(t + h * _RC[i], yst, p, q, breaks, coefs,
                                    fst)  # fmt: skip
                    F[i] = fst
                nfev += 3
                if not np.all(np.isfinite(F)):
                    finite = False
                    break
                f_real = np.empty(n)
                f_complex = np.empty(n, dtype=np.complex128)
                for j in range(n):
                    f_real[j] = (
                        F[0, j] * _RTI[0, 0] + F[1, j] * _RTI[0, 1]
                        + F[2, j] * _RTI[0, 2]
                    ) - Mr * W[0, j]  # fmt: skip
                    f_complex[j] = (
                        F[0, j] * (_RTI[1, 0] + 1j * _RTI[2, 0])
                        + F[1, j] * (_RTI[1, 1] + 1j * _RTI[2, 1])
                        + F[2, j] * (_RTI[1, 2] + 1j * _RTI[2, 2])
                    ) - Mc * (W[1, j] + 1j * W[2, j])  # fmt: skip
                dW_real = np.linalg.solve(M_real, f_real)
                dW_complex = np.linalg.solve(M_complex, f_complex)
                dW[0] = dW_real
                dW[1] = dW_complex.real
                dW[2] = dW_complex.imag
                sc = np.empty((3, n))
                for i in range(3):
                    sc[i] = dW[i] / scale
                dW_norm = _rms2(sc)
                if dW_norm_old >= 0.0:
                    rate = dW_norm / dW_norm_old
                if rate >= 0.0 and (
                    rate >= 1
                    or rate ** (_NEWTON_MAXITER - k) / (1 - rate) * dW_norm > tol_newton
                ):
                    break
                W += dW
                Z = _RT @ W
                if dW_norm == 0 or (
                    rate >= 0.0 and rate / (1 - rate) * dW_norm < tol_newton
                ):
                    converged = True
                    break
                dW_norm_old = dW_norm
            if not finite:
                converged = False
            n_iter = k + 1
            if not converged:
                if current_jac:
                    break
                closed_loop_jac(t, y, p, q, breaks, coefs, J)
                current_jac = True
                have_lu = False
        if not converged:
            h_abs *= 0.5
            have_lu = False
            n_rej += 1
            continue
        for j in range(n):
            y_new[j] = y[j] + Z[2, j]
        ZE = np.empty(n)
        for j in range(n):
            ZE[j] = (Z[0, j] * _RE[0] + Z[1, j] * _RE[1] + Z[2, j] * _RE[2]) / h
        error = np.linalg.solve(M_real, f + ZE)
        scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
        error_norm = _rms2(error / scale)
        safety = 0.9 * (2 * _NEWTON_MAXITER + 1) / (2 * _NEWTON_MAXITER + n_iter)
        if rejected and error_norm > 1:
            closed_loop_rhs(t, y + error, p, q, breaks, coefs, fst)
            nfev += 1
            error = np.linalg.solve(M_real, fst + ZE)
            error_norm = _rms2(error / scale)
        if error_norm > 1:
            factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old)
            h_abs *= max(MIN_FACTOR, safety * factor)
            have_lu = False
            rejected = True
            n_rej += 1
        else:
            accepted = True
    recompute_jac = n_iter > 2 and rate > 1e-3
    factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old)
    factor = min(MAX_FACTOR, safety * factor)
    if not recompute_jac and factor < 1.2:
        factor = 1.0
    else:
        have_lu = False
    closed_loop_rhs(t_new, y_new, p, q, breaks, coefs, f_new)
    nfev += 1
    if recompute_jac:
        closed_loop_jac(t_new, y_new, p, q, breaks, coefs, J)
        current_jac = True
    else:
        current_jac = False
    # as scipy: the old step is the one this step was asked to try
    rs[_RS_H_OLD] = rs[_RS_H]
    rs[_RS_ERR_OLD] = error_norm
    rs[_RS_H] = h_abs * factor
    rs[_RS_CURRENT_JAC] = 1.0 if current_jac else 0.0
    rs[_RS_HAVE_LU] = 1.0 if have_lu else 0.0
    rs[_RS_HAVE_SOL] = 1.0
    rs[_RS_T_OLD] = t
    for j in range(n):
        y_old[j] = y[j]
        for m in range(3):
            Q[j, m] = Z[0, j] * _RP[0, m] + Z[1, j] * _RP[1, m] + Z[2, j] * _RP[2, m]
    return 0, t_new, n_rej, nfev


@jit
def radau_dense(Q, F):
    """Radau's dense output ``Q @ (x, x^2, x^3)`` as DOP853's coefficients.

    :func:`dense_eval` computes ``y_old + x (F0 + (1 - x) (F1 + x (F2 +
    ...)))``; the cubic ``Q0 x + Q1 x^2 + Q2 x^3`` is that form with ``F0 =
    Q0 + Q1 + Q2``, ``F1 = -(Q1 + Q2)``, ``F2 = -Q2`` and the higher
    coefficients 0, so the events, the outputs and the exact peaks read a
    Radau step as they read a DOP853 step.
    """
    for i in range(Q.shape[0]):
        F[0, i] = Q[i, 0] + Q[i, 1] + Q[i, 2]
        F[1, i] = -(Q[i, 1] + Q[i, 2])
        F[2, i] = -Q[i, 2]
        for k in range(3, F.shape[0]):
            F[k, i] = 0.0


@jit
def radau_run(y0, p, q, breaks, coefs, t0, t_bound, h0, rtol, atol, ts, ys, qs):
    """Integrate one run with Radau IIA order 5: a port of scipy's ``Radau``.

    The same steps as :class:`scipy.integrate.Radau` given the first step
    `h0` and the Jacobian :func:`closed_loop_jac` (simplified Newton with a
    real and a complex system, scipy's step-size control and its decisions
    of when to recompute the Jacobian and rebuild the Newton matrices; each
    solve factorises anew with ``np.linalg.solve``, LAPACK's ``gesv``: for
    the real system bit for bit scipy's ``lu_factor`` and ``lu_solve``, for
    the complex one within 1e-14). Writes the accepted times into `ts`
    (``ts[0] = t0``), states into `ys` and each step's dense-output matrix
    ``Q`` (scipy's ``RadauDenseOutput.Q``, ``(n, 3)``) into `qs`; returns
    ``(steps, status)``, status 0 when `t_bound` was reached, 1 out of room,
    -1 step too small. The engines step with :func:`radau_step`, which this
    loop drives (no events here: the clips must be min/max, ``q[13] = 0``).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import radau_run, curvature_table
    >>> from fws_control.simulation.compiled import shared_parameters
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=0.05)
    >>> p = np.zeros(8); p[:4] = 5.0, 0.1, 0.5, 0.0
    >>> # the copy for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs it (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> radau_run = variant(radau_run, [])
    >>> m = 5000
    >>> ts, ys, qs = np.empty(m), np.empty((m, 5)), np.empty((m, 5, 3))
    >>> n, status = radau_run(np.array([0, 1.0, 0, 0, 0]), p, q, tab.breaks,
    ...                       tab.coefs, 0.0, 30.0, 1e-3, 1e-8, 1e-10, ts, ys, qs)
    >>> status, bool(abs(ys[n, 1]) < 0.05)
    (0, True)
    """
    n = y0.size
    t = t0
    y = y0.copy()
    f = np.empty(n)
    closed_loop_rhs(t, y, p, q, breaks, coefs, f)
    rs = np.empty(NRS)
    J = np.empty((n, n))
    radau_start(t, y, h0, p, q, breaks, coefs, rs, J)
    M_real = np.empty((n, n))
    M_complex = np.empty((n, n), dtype=np.complex128)
    Q = np.zeros((n, 3))
    y_old = y.copy()
    y_new = np.empty(n)
    f_new = np.empty(n)
    ts[0] = t
    ys[0] = y
    k_step = 0
    while t < t_bound:
        if k_step + 1 >= ts.size:
            return k_step, 1
        status, t_new, _, _ = radau_step(
            t, y, f, t_bound, rtol, atol, p, q, breaks, coefs, rs, J, M_real,
            M_complex, Q, y_old, y_new, f_new,
        )  # fmt: skip
        if status != 0:
            return k_step, -1
        t = t_new
        y, y_new = y_new, y
        f, f_new = f_new, f
        k_step += 1
        ts[k_step] = t
        ys[k_step] = y
        qs[k_step - 1] = Q
    return k_step, 0
