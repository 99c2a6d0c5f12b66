"""scipy's DOP853 ported to numba: the step, the dense output, the events.

A line-by-line port of :class:`scipy.integrate.DOP853` (the same Butcher
tableau taken from scipy itself, the same initial step selection, step-size
control, error norm and dense output) and of
:func:`~scipy.integrate.solve_ivp`'s event location (scipy's ``brentq`` on
the dense output), for the compiled engine
(:mod:`~fws_control.simulation.compiled`).
"""

from __future__ import annotations

import math

import numpy as np

from .compilation import jit
from .compiled_events import event_values, set_now
from .compiled_layout import (
    DOP853_TABLEAU,
    EPS,
    N_EVENTS,
    NPOW,
    NS,
    NSE,
    Q_MAX_STEP,
    jit_inline,
)
from .compiled_loop import closed_loop_rhs

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []

# --------------------------------------------------------------------------
# DOP853 tableau (scipy's), as module constants frozen into the kernels

_dop = DOP853_TABLEAU
_A = np.ascontiguousarray(_dop.A[:NS, :NS])
_B = np.ascontiguousarray(_dop.B)
_C = np.ascontiguousarray(_dop.C[:NS])
_E3 = np.ascontiguousarray(_dop.E3)
_E5 = np.ascontiguousarray(_dop.E5)
_D = np.ascontiguousarray(_dop.D)
_A_EXTRA = np.ascontiguousarray(_dop.A[NS + 1 :])
_C_EXTRA = np.ascontiguousarray(_dop.C[NS + 1 :])
# Hairer's stiffness test compares the last stage (at t + h) with f(y_new).
assert _C[NS - 1] == 1.0
_ERROR_EXPONENT = -1.0 / (7 + 1)  # DOP853's error estimator is of order 7
_SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0


# --------------------------------------------------------------------------
# DOP853, as scipy.integrate.DOP853 (line by line; comments name scipy's code)


@jit
def _rms(x):
    # scipy.integrate._ivp.common.norm: np.linalg.norm(x) / x.size ** 0.5
    acc = 0.0
    for v in x:
        acc += v * v
    return math.sqrt(acc) / x.size**0.5


@jit
def select_initial_step(t0, y0, t_bound, f0, rtol, atol, p, q, br, co, work, order):
    # scipy.integrate._ivp.common.select_initial_step, direction +1, the
    # method's error estimator order (DOP853 7, Radau 3)
    interval_length = abs(t_bound - t0)
    if interval_length == 0.0:
        return 0.0
    m = y0.size
    scale = atol + np.abs(y0) * rtol
    d0 = _rms(y0 / scale)
    d1 = _rms(f0 / scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval_length)
    y1 = y0 + h0 * 1.0 * f0
    f1 = work[:m]
    closed_loop_rhs(t0 + h0 * 1.0, y1, p, q, br, co, f1)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval_length, q[Q_MAX_STEP])


@jit
def dense_coefficients(t_old, h, y_old, y, f, K, p, q, br, co, F, ytmp):
    # DOP853._dense_output_impl: three extra stages, then the 7 coefficients
    m = y.size
    for s in range(NS + 1, NSE):
        a = _A_EXTRA[s - NS - 1]
        c = _C_EXTRA[s - NS - 1]
        for i in range(m):
            acc = 0.0
            for j in range(s):
                acc += K[j, i] * a[j]
            ytmp[i] = y_old[i] + acc * h
        closed_loop_rhs(t_old + c * h, ytmp, p, q, br, co, K[s])
    for i in range(m):
        f_old = K[0, i]
        delta_y = y[i] - y_old[i]
        F[0, i] = delta_y
        F[1, i] = h * f_old - delta_y
        F[2, i] = 2 * delta_y - h * (f[i] + f_old)
        for r in range(NPOW - 3):
            acc = 0.0
            for j in range(NSE):
                acc += _D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@jit_inline
def dense_eval(tt, t_old, t_new, y_old, F, out):
    # Dop853DenseOutput._call_impl at one time
    x = (tt - t_old) / (t_new - t_old)
    m = y_old.size
    for i in range(m):
        v = 0.0
        for k in range(NPOW):
            v += F[NPOW - 1 - k, i]
            if k % 2 == 0:
                v *= x
            else:
                v *= 1 - x
        out[i] = v + y_old[i]


@jit
def _event_at(tt, j, t_old, t_new, y_old, F, p, q, br, co, ytmp, g):
    dense_eval(tt, t_old, t_new, y_old, F, ytmp)
    set_now(tt, p, q)
    event_values(ytmp, p, q, br, co, g)
    return g[j]


@jit
def brentq(j, xa, xb, t_old, t_new, y_old, F, p, q, br, co, ytmp, g):
    # scipy.optimize.brentq (its C code), xtol = rtol = 4 eps, maxiter 100,
    # on event j of the dense output: scipy's solve_event_equation
    xtol = 4 * EPS
    rtol = 4 * EPS
    xpre, xcur = xa, xb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    fpre = _event_at(xpre, j, t_old, t_new, y_old, F, p, q, br, co, ytmp, g)
    fcur = _event_at(xcur, j, t_old, t_new, y_old, F, p, q, br, co, ytmp, g)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    for _ in range(100):
        if fpre != 0 and fcur != 0 and (np.signbit(fpre) != np.signbit(fcur)):
            xblk = xpre
            fblk = fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre = xcur
            xcur = xblk
            xblk = xpre
            fpre = fcur
            fcur = fblk
            fblk = fpre
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)  # interpolate
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk - fpre) / (fblk * dpre - fpre * dblk)
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre = scur
                scur = stry
            else:
                spre = sbis
                scur = sbis
        else:
            spre = sbis
            scur = sbis
        xpre = xcur
        fpre = fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = _event_at(xcur, j, t_old, t_new, y_old, F, p, q, br, co, ytmp, g)
    return xcur


@jit
def dop853_step(
    t, y, f, h_abs, t_bound, rtol, atol, p, q, breaks, coefs, K, y_new, ystage
):
    """One accepted step of scipy's ``RungeKutta._step_impl`` for DOP853.

    From ``(t, y)`` with ``f = f(t, y)`` and the proposed step `h_abs`, try
    steps (shrinking after a rejection) until the error norm is below 1.
    Fills `K` ``(16, m)`` (stage 13 is ``f(t_new, y_new)``), `y_new` and
    `ystage` (the argument of the last stage, for the stiffness test).

    Returns ``(ok, t_new, h, h_abs_next, rejected)``; ``ok`` is False when
    the step fell below 10 ulp of ``t`` (scipy's TOO_SMALL_STEP).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import (
    ...     closed_loop_rhs, curvature_table, dop853_step, shared_parameters)
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    >>> p, y = np.array([5.0, 0.1, 0.5, 0.0]), np.array([0.0, 1.0, 0.0])
    >>> # the copies for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs them (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> closed_loop_rhs = variant(closed_loop_rhs, [])
    >>> dop853_step = variant(dop853_step, [])
    >>> f = np.empty(3)
    >>> closed_loop_rhs(0.0, y, p, q, tab.breaks, tab.coefs, f)
    >>> K, y_new = np.empty((16, 3)), np.empty(3)
    >>> ok, t_new, h, h_next, rej = dop853_step(0.0, y, f, 0.01, 1.0, 1e-10,
    ...     1e-12, p, q, tab.breaks, tab.coefs, K, y_new, np.empty(3))
    >>> ok, t_new, rej, round(float(y_new[0]), 6)
    (True, 0.01, 0, 0.05)
    """
    m = y.size
    min_step = 10 * abs(np.nextafter(t, np.inf) - t)
    if h_abs > q[Q_MAX_STEP]:
        h_abs = q[Q_MAX_STEP]
    elif h_abs < min_step:
        h_abs = min_step
    step_rejected = False
    rejected = 0
    while True:
        if h_abs < min_step:
            return False, t, 0.0, h_abs, rejected
        h = h_abs
        t_new = t + h
        if t_new - t_bound > 0:
            t_new = t_bound
        h = t_new - t
        h_abs = abs(h)
        # rk_step (sums in the order of the stages)
        for i in range(m):
            K[0, i] = f[i]
        for s in range(1, NS):
            a = _A[s]
            for i in range(m):
                acc = 0.0
                for j in range(s):
                    acc += K[j, i] * a[j]
                ystage[i] = y[i] + acc * h
            closed_loop_rhs(t + _C[s] * h, ystage, p, q, breaks, coefs, K[s])
        for i in range(m):
            acc = 0.0
            for j in range(NS):
                acc += K[j, i] * _B[j]
            y_new[i] = y[i] + h * acc
        closed_loop_rhs(t + h, y_new, p, q, breaks, coefs, K[NS])
        # DOP853._estimate_error_norm, scale = atol + max(|y|, |y_new|) rtol
        e5 = 0.0
        e3 = 0.0
        for i in range(m):
            sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
            a5 = 0.0
            a3 = 0.0
            for j in range(NS + 1):
                a5 += K[j, i] * _E5[j]
                a3 += K[j, i] * _E3[j]
            a5 /= sc
            a3 /= sc
            e5 += a5 * a5
            e3 += a3 * a3
        e5 = math.sqrt(e5) ** 2
        e3 = math.sqrt(e3) ** 2
        if e5 == 0 and e3 == 0:
            error_norm = 0.0
        else:
            denom = e5 + 0.01 * e3
            error_norm = abs(h) * e5 / math.sqrt(denom * m)
        if error_norm < 1:
            if error_norm == 0:
                factor = MAX_FACTOR
            else:
                factor = min(MAX_FACTOR, _SAFETY * error_norm**_ERROR_EXPONENT)
            if step_rejected:
                factor = min(1.0, factor)
            return True, t_new, h, h_abs * factor, rejected
        h_abs *= max(MIN_FACTOR, _SAFETY * error_norm**_ERROR_EXPONENT)
        step_rejected = True
        rejected += 1


@jit
def dense_output(tt, t_old, t_new, y_old, y_new, f_new, K, p, q, breaks, coefs, out):
    """Value at `tt` of the dense output of the step ``t_old -> t_new``.

    `K` holds the stages of :func:`dop853_step` (its three extra rows are
    overwritten), as ``DOP853.dense_output()(tt)`` (scipy).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import (closed_loop_rhs,
    ...     curvature_table, dense_output, dop853_step, shared_parameters)
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    >>> p, y = np.array([5.0, 0.1, 0.5, 0.0]), np.array([0.0, 1.0, 0.0])
    >>> # the copies for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs them (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> closed_loop_rhs, dop853_step, dense_output = (
    ...     variant(k, []) for k in (closed_loop_rhs, dop853_step, dense_output))
    >>> f = np.empty(3)
    >>> closed_loop_rhs(0.0, y, p, q, tab.breaks, tab.coefs, f)
    >>> K, y_new = np.empty((16, 3)), np.empty(3)
    >>> ok, t_new, *_ = dop853_step(0.0, y, f, 0.01, 1.0, 1e-10, 1e-12, p, q,
    ...     tab.breaks, tab.coefs, K, y_new, np.empty(3))
    >>> out = np.empty(3)
    >>> dense_output(0.005, 0.0, t_new, y, y_new, K[12].copy(), K, p, q,
    ...              tab.breaks, tab.coefs, out)
    >>> round(float(out[0]), 6)
    0.025
    """
    m = y_old.size
    F = np.empty((NPOW, m))
    dense_coefficients(
        t_old, t_new - t_old, y_old, y_new, f_new, K, p, q, breaks, coefs, F, out
    )
    dense_eval(tt, t_old, t_new, y_old, F, out)


@jit
def locate_event(j, t_old, t_new, y_old, y_new, f_new, K, p, q, breaks, coefs):
    """Root of stop event `j` on the dense output of one step (brentq).

    As scipy's ``solve_event_equation``: ``brentq`` with ``xtol = rtol =
    4 eps`` on ``event(t, sol(t))`` over ``[t_old, t_new]``. Events: 0
    steering, 1 curvature, 2 end and 3 start of an open path.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import (closed_loop_rhs,
    ...     curvature_table, dop853_step, locate_event, shared_parameters)
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight(length=0.1))   # ends after 0.02 s
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    >>> p, y = np.array([5.0, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 0.0])
    >>> # the copies for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs them (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> closed_loop_rhs, dop853_step, locate_event = (
    ...     variant(k, []) for k in (closed_loop_rhs, dop853_step, locate_event))
    >>> f = np.empty(3)
    >>> closed_loop_rhs(0.0, y, p, q, tab.breaks, tab.coefs, f)
    >>> K, y_new = np.empty((16, 3)), np.empty(3)
    >>> ok, t_new, *_ = dop853_step(0.0, y, f, 0.05, 1.0, 1e-10, 1e-12, p, q,
    ...     tab.breaks, tab.coefs, K, y_new, np.empty(3))
    >>> t = locate_event(2, 0.0, t_new, y, y_new, K[12].copy(), K, p, q,
    ...                  tab.breaks, tab.coefs)
    >>> round(t, 14)          # s = L (1 + 1e-9) at V = 5 m/s
    0.02000000002
    """
    m = y_old.size
    F = np.empty((NPOW, m))
    ytmp = np.empty(m)
    g = np.empty(N_EVENTS)
    dense_coefficients(
        t_old, t_new - t_old, y_old, y_new, f_new, K, p, q, breaks, coefs, F, ytmp
    )
    return brentq(j, t_old, t_new, t_old, t_new, y_old, F, p, q, breaks, coefs, ytmp, g)
