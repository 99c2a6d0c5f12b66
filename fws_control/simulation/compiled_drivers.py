"""The compiled engine's per-run drivers and batch loops.

One run at a time: the steps of its method (DOP853 or Radau), the events
located on each step's dense output (the stops, the clips' switches), the
outputs at the requested times, an input delay's method of steps and the
dense output kept for the exact peaks; then the loop over the runs of a
batch. Each method's driver is compiled apart (see :func:`drivers`).
"""

from __future__ import annotations

import math

import numpy as np

from .compilation import jit
from .compiled_dop853 import (
    brentq,
    dense_coefficients,
    dense_eval,
    dop853_step,
    select_initial_step,
)
from .compiled_events import event_values, set_now, stop_event_values
from .compiled_layout import (
    INNER_NODES,
    MAX_SWITCHES,
    N_EVENTS,
    N_INNER,
    N_STOPS,
    NP,
    NPOW,
    NS,
    NSE,
    P_MODE,
    P_RELEASED,
    Q_DELAY,
    Q_SWITCH,
    RADAU,
    WITH_DELAY,
    jit_inline,
)
from .compiled_loop import add_to_history, clip_values, closed_loop_rhs, with_history
from .compiled_radau import NRS, radau_dense, radau_start, radau_step

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []


@jit
def solve_run(y0, p, q, breaks, coefs, t_eval, rtol, atol, out, trace):
    r"""Integrate one run from ``t_eval[0]`` to ``t_eval[-1]`` (compiled).

    `out` ``(m, T)`` receives the states at `t_eval` (columns after a stop
    are left untouched); `trace` ``(N,)`` receives the times of the first
    ``N`` accepted steps (pass an empty array for none).

    Returns ``(status_code, t_stop, steps, rejected, rhs_evaluations,
    stiff, switches)``: the code indexes :data:`STATUS_CODES`; ``stiff`` is
    1 if Hairer's stiffness test fired (15 steps with
    :math:`|h\lambda| > 6.1` without 6 non-stiff steps in between);
    ``switches`` counts the located switches of the clips (with
    ``q[13] = 1``; `p` then has 8 entries, the last four the clips' modes,
    which are overwritten).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import (
    ...     curvature_table, shared_parameters, solve_run)
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    >>> # the copy for a call without a delay, the dynamic model, a law or a
    >>> # varying speed, as the engine runs it (a third of the compilation)
    >>> from fws_control.simulation.compiled_variants import variant
    >>> solve_run = variant(solve_run, [])
    >>> t = np.linspace(0.0, 10.0, 3)
    >>> out = np.empty((3, t.size))
    >>> code, t_stop, *_ = solve_run(np.array([0.0, 1.0, 0.0]),
    ...     np.array([5.0, 0.1, 0.5, 0.0]), q, tab.breaks, tab.coefs, t,
    ...     1e-10, 1e-12, out, np.empty(0))
    >>> code, t_stop, bool(abs(out[1, -1]) < 0.1)
    (0, 10.0, True)
    """
    r = _run_impl(
        y0, p, q, breaks, coefs, t_eval, rtol, atol, out, trace, np.empty((0, 0)),
        0, False,
    )  # fmt: skip
    return r[0], r[1], r[2], r[3], r[4], r[5], r[6]


@jit
def _segment_end(t, t0, t_bound, delay):
    """End of the integration segment from `t`: the first of the restart
    points ``t0 + k delay`` (k = 1, 2, 3) after `t` and before `t_bound`
    (the numpy engine's ``breaks``), else `t_bound`."""
    if delay > 0.0:
        for k in (1, 2, 3):
            b = t0 + k * delay
            if t < b < t_bound:
                return b
    return t_bound


@jit_inline
def _initial_modes(y, p, q, breaks, coefs):
    """The clips' modes at the start: a channel beyond its limit starts held
    (angles first: the actuator's rate depends on the held command)."""
    v = np.empty(8)
    for j in range(4):
        p[P_MODE + j] = 0.0
        if p.size >= NP:
            p[P_RELEASED + j] = 0.0
    for j in range(4):
        clip_values(y, p, q, breaks, coefs, v)
        if abs(v[j]) > v[4 + j]:
            p[P_MODE + j] = 1.0 if v[j] > 0 else -1.0


@jit_inline
def _stiffness(K, y_new, ystage, h, iasti, nonsti, stiff):
    """Hairer's stiffness detection (dop853.f) after an accepted step:
    ``|h lambda|`` from the last stage and f(y_new), both at t + h; returns
    the updated ``(iasti, nonsti, stiff)``."""
    num = 0.0
    den = 0.0
    for i in range(y_new.size):
        num += (K[NS, i] - K[NS - 1, i]) ** 2
        den += (y_new[i] - ystage[i]) ** 2
    if den > 0.0:
        if h * math.sqrt(num / den) > 6.1:
            nonsti = 0
            iasti += 1
            if iasti == 15:
                stiff = 1
        else:
            nonsti += 1
            if nonsti == 6:
                iasti = 0
    return iasti, nonsti, stiff


@jit_inline
def _record(rec, n_rec, t_old, h, y_old, F):
    """Row `n_rec` of `rec` (grown when full; returned): the accepted step's
    ``(t_old, h, y_old, F)``."""
    m = y_old.size
    if n_rec == rec.shape[0]:
        grown = np.empty((max(2 * n_rec, 16), rec.shape[1]))
        # element by element: numba compiles an array-to-slice
        # assignment with its shape-mismatch error, whose string
        # formatting cost a fifth of this driver's compilation
        for r_ in range(n_rec):
            for c_ in range(rec.shape[1]):
                grown[r_, c_] = rec[r_, c_]
        rec = grown
    row = rec[n_rec]
    row[0] = t_old
    row[1] = h
    for i in range(m):
        row[2 + i] = y_old[i]
        for k in range(NPOW):
            row[2 + m + k * m + i] = F[k, i]
    return rec


@jit_inline
def _switch_clip(site, y, p, q, breaks, coefs):
    """Clip `site` switches at the state `y`: held becomes free (released
    from the held side), free becomes held at the side of its command."""
    track = p.size >= NP
    v = np.empty(8)
    if track:
        # a clip released before and now inside its limits watches both
        # limits again
        clip_values(y, p, q, breaks, coefs, v)
        for jj in range(4):
            if p[P_RELEASED + jj] != 0.0 and abs(v[jj]) < v[4 + jj]:
                p[P_RELEASED + jj] = 0.0
    if p[P_MODE + site] != 0.0:
        if track:
            p[P_RELEASED + site] = p[P_MODE + site]
        p[P_MODE + site] = 0.0
    else:
        clip_values(y, p, q, breaks, coefs, v)
        p[P_MODE + site] = 1.0 if v[site] > 0 else -1.0
        if track:
            p[P_RELEASED + site] = 0.0


@jit_inline
def _first_event(
    keep, g_old, g_new, g_inner, t_old, t, h, y_old, y, f, K, F, p, q, breaks, coefs,
    ytmp, g_tmp, dense_ready,
):  # fmt: skip
    """The first event of the accepted step ``t_old -> t`` (solve_ivp's
    direction -1: g from >= 0 to <= 0), located on its dense output.

    Returns ``(t_hit, j_hit, dense_ready, nfev)``: ``j_hit`` -1 for none;
    the dense output's coefficients `F` computed if they were not
    (`dense_ready`), at 3 right-hand-side evaluations (``nfev``).
    """
    nfev = 0
    t_hit = np.inf
    j_hit = -1
    if keep:
        # with the dense output kept (the runners), the stop conditions
        # are also checked at three points inside the step, as the numpy
        # engine checks its margins: a loose tolerance must not step
        # across a singular state and back
        for r in range(N_INNER):
            t_in = t_old + INNER_NODES[r] * h
            dense_eval(t_in, t_old, t, y_old, F, ytmp)
            set_now(t_in, p, q)
            stop_event_values(ytmp, p, q, breaks, coefs, g_inner[r])
    for j in range(N_EVENTS):
        lo_b, hi_b = t_old, t
        if j < N_STOPS:
            hit = g_old[j] >= 0 and g_new[j] <= 0  # solve_ivp, direction -1
            if keep and not hit and g_old[j] >= 0:
                for r in range(N_INNER):
                    if g_inner[r, j] <= 0:
                        hit = True
                        hi_b = t_old + INNER_NODES[r] * h
                        break
                    lo_b = t_old + INNER_NODES[r] * h
        else:
            # a clip's mode is wrong at the step's end: it switched in the
            # step (g from > 0), or it was ~0 on the wrong side already at
            # a restart (then the switch is at the step's start)
            hit = g_new[j] < 0 or (g_new[j] == 0 and g_old[j] > 0)
        if not hit:
            continue
        if j >= N_STOPS and not g_old[j] > 0:
            root = t_old
        else:
            if not dense_ready:
                dense_coefficients(
                    t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                )
                nfev += 3
                dense_ready = True
            root = brentq(
                j, lo_b, hi_b, t_old, t, y_old, F, p, q, breaks, coefs,
                ytmp, g_tmp,
            )  # fmt: skip
        if root < t_hit:
            t_hit = root
            j_hit = j
    return t_hit, j_hit, dense_ready, nfev


def _drivers(method):
    """The per-run driver of one method, compiled apart.

    `method` (0: DOP853, :data:`RADAU`) is a constant of the closures, so
    numba prunes the other method's branches before compiling: a DOP853 run
    never compiles Radau's linear algebra (with one driver for both the
    first compilation took 34 instead of 18.6 s and loading the cached
    kernels 0.1 s more in every process).
    """

    def run_impl(
        y0, p, q, breaks, coefs, t_eval, rtol, atol, out, trace, rec, start, keep
    ):
        # solve_run; with keep, rows start, start + 1, ... of rec (grown when
        # full, returned) receive each accepted step's (t_old, h, y_old, F):
        # its DOP853 dense output, the piece [t_old, next row's t_old or t_stop]
        m = y0.size
        T = t_eval.size
        n_rec = start
        n_trace = trace.size
        K = np.empty((NSE, m))
        F = np.empty((NPOW, m))
        ytmp = np.empty(m)
        ystage = np.empty(m)
        work = np.empty(m)
        g_old = np.empty(N_EVENTS)
        g_new = np.empty(N_EVENTS)
        g_tmp = np.empty(N_EVENTS)
        g_inner = np.empty((N_INNER, N_EVENTS))
        t = t_eval[0]
        t_bound = t_eval[T - 1]
        y = y0.copy()
        # an input delay: the run's past in p, and the segments of the
        # method of steps, which end where the solution's derivatives jump
        # (t0 + k delay, k = 1, 2, 3) and restart the method there, as the
        # numpy engine does
        delay = q[Q_DELAY]
        delayed = False
        if WITH_DELAY:
            delayed = delay > 0.0
        t_seg = _segment_end(t, t_eval[0], t_bound, delay)
        if delayed:
            p = with_history(p, y0, 64)
        y_new = np.empty(m)
        f = np.empty(m)
        switches = 0
        # Radau (q[Q_METHOD] = RADAU): its state between steps (radau_step)
        radau = method == RADAU
        order = 3 if radau else 7
        rs = np.empty(NRS)
        J = np.empty((m, m))
        M_real = np.empty((m, m))
        M_complex = np.empty((m, m), dtype=np.complex128)
        Q = np.zeros((m, 3))
        y_prev = np.empty(m)
        f_new = np.empty(m)
        if q[Q_SWITCH] != 0.0:
            _initial_modes(y, p, q, breaks, coefs)
        closed_loop_rhs(t, y, p, q, breaks, coefs, f)
        nfev = 1
        steps = 0
        rejected_total = 0
        iasti = 0
        nonsti = 0
        stiff = 0

        # a run that starts at or beyond a stop condition stops at once
        set_now(t, p, q)
        event_values(y, p, q, breaks, coefs, g_old)
        worst = 0
        for j in range(N_STOPS):
            if g_old[j] < g_old[worst]:
                worst = j
        if g_old[worst] <= 0.0:
            for i in range(m):
                out[i, 0] = y[i]
            return min(worst, 2) + 1, t, 0, 0, nfev, 0, 0, rec, n_rec
        if T == 1 or t_bound == t:
            for i in range(m):
                out[i, 0] = y[i]
            return 0, t, 0, 0, nfev, 0, 0, rec, n_rec

        h_abs = select_initial_step(
            t, y, t_seg, f, rtol, atol, p, q, breaks, coefs, work, order
        )
        nfev += 1
        if radau:
            radau_start(t, y, h_abs, p, q, breaks, coefs, rs, J)
        k_out = 0
        while True:
            if radau:
                # ---- Radau._step_impl (its Jacobian: closed_loop_jac)
                code_r, t_new, n_rej, nf = radau_step(
                    t, y, f, t_bound, rtol, atol, p, q, breaks, coefs, rs, J, M_real,
                    M_complex, Q, y_prev, y_new, f_new,
                )  # fmt: skip
                ok = code_r == 0
                nfev += nf
                h = t_new - t
            else:
                # ---- RungeKutta._step_impl (direction +1, max_step q[Q_MAX_STEP])
                ok, t_new, h, h_abs, n_rej = dop853_step(
                    t, y, f, h_abs, t_seg, rtol, atol, p, q, breaks, coefs, K, y_new,
                    ystage,
                )  # fmt: skip
                nfev += NS * (n_rej + 1)
            rejected_total += n_rej
            if not ok:
                return 4, t, steps, rejected_total, nfev, stiff, switches, rec, n_rec
            if method != RADAU:
                iasti, nonsti, stiff = _stiffness(
                    K, y_new, ystage, h, iasti, nonsti, stiff
                )
            # accepted: y_old = y, y = y_new, f = f_new
            # (buffers swapped: y_old is only overwritten by the next step)
            t_old = t
            y_old = y
            y = y_new
            y_new = y_old
            t = t_new
            for i in range(m):
                f[i] = f_new[i] if radau else K[NS, i]
            if steps < n_trace:
                trace[steps] = t
            steps += 1
            dense_ready = False
            if radau:
                # its collocation polynomial, in the form dense_eval reads
                radau_dense(Q, F)
                dense_ready = True
            if keep:
                # the dense output of every accepted step, for the exact peaks
                # (a step cut at a switch or a stop keeps its interpolant)
                if not dense_ready:
                    dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                    dense_ready = True
                rec = _record(rec, n_rec, t_old, h, y_old, F)
                n_rec += 1
            if delayed:
                # the step joins the past before its events are located, as
                # the numpy engine records it before checking its margins
                if not dense_ready:
                    dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                    dense_ready = True
                p = add_to_history(p, t_old, h, y_old, F)
            # ---- solve_ivp: events (direction -1: g from >= 0 to <= 0)
            set_now(t, p, q)
            event_values(y, p, q, breaks, coefs, g_new)
            code = 0
            t_hit, j_hit, dense_ready, n_f = _first_event(
                keep, g_old, g_new, g_inner, t_old, t, h, y_old, y, f, K, F, p, q,
                breaks, coefs, ytmp, g_tmp, dense_ready,
            )  # fmt: skip
            nfev += n_f
            if 0 <= j_hit < N_STOPS:
                code = min(j_hit, 2) + 1
            upto = t if j_hit < 0 else t_hit
            # ---- solve_ivp: outputs at t_eval <= upto from this step's dense output
            while k_out < T and t_eval[k_out] <= upto:
                if not dense_ready:
                    dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                    dense_ready = True
                dense_eval(t_eval[k_out], t_old, t, y_old, F, ytmp)
                for i in range(m):
                    out[i, k_out] = ytmp[i]
                k_out += 1
            if code != 0:
                return (
                    code,
                    t_hit,
                    steps,
                    rejected_total,
                    nfev,
                    stiff,
                    switches,
                    rec,
                    n_rec,
                )
            if j_hit >= N_STOPS:
                # a clip switches: restart at the switch with the new mode (the
                # rest of the step, integrated in the old mode, is discarded)
                if not dense_ready:
                    dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                dense_eval(t_hit, t_old, t, y_old, F, ytmp)
                for i in range(m):
                    y[i] = ytmp[i]
                t = t_hit
                set_now(t, p, q)
                _switch_clip(j_hit - N_STOPS, y, p, q, breaks, coefs)
                switches += 1
                if switches > MAX_SWITCHES:
                    return (
                        4,
                        t,
                        steps,
                        rejected_total,
                        nfev,
                        stiff,
                        switches,
                        rec,
                        n_rec,
                    )
                if t >= t_bound:
                    return (
                        0,
                        t_bound,
                        steps,
                        rejected_total,
                        nfev,
                        stiff,
                        switches,
                        rec,
                        n_rec,
                    )
                closed_loop_rhs(t, y, p, q, breaks, coefs, f)
                h_abs = select_initial_step(
                    t, y, t_seg, f, rtol, atol, p, q, breaks, coefs, work, order
                )
                nfev += 2
                if radau:
                    # a new solver at the switch, as for DOP853
                    radau_start(t, y, h_abs, p, q, breaks, coefs, rs, J)
                set_now(t, p, q)
                event_values(y, p, q, breaks, coefs, g_old)
                continue
            if t == t_bound:
                return 0, t, steps, rejected_total, nfev, stiff, switches, rec, n_rec
            if t == t_seg:
                # the next segment of a delay's method of steps: a new
                # solver there (f and the first step anew, as scipy's)
                t_seg = _segment_end(t, t_eval[0], t_bound, delay)
                closed_loop_rhs(t, y, p, q, breaks, coefs, f)
                h_abs = select_initial_step(
                    t, y, t_seg, f, rtol, atol, p, q, breaks, coefs, work, order
                )
                nfev += 2
            released = False
            if q[Q_SWITCH] != 0.0 and p.size >= NP:
                for j in range(4):
                    if p[P_RELEASED + j] != 0.0:
                        p[P_RELEASED + j] = 0.0
                        released = True
            if released:
                # a step after a release: the clips watch both limits again
                set_now(t, p, q)
                event_values(y, p, q, breaks, coefs, g_old)
            else:
                for j in range(N_EVENTS):
                    g_old[j] = g_new[j]

    return jit(_named_for(run_impl, method))


def _batch(method):
    """The loop over the runs of a batch, of one method's driver."""

    def solve_batch(
        Y0, P, q, breaks, coefs, t_eval, rtol, atol, out, codes, t_stop, stats, rec,
        offsets, keep,
    ):  # fmt: skip
        # with keep: run i's dense pieces are rows offsets[i]:offsets[i + 1] of the
        # returned record (rec, grown as needed)
        empty = np.empty(0)
        offsets[0] = 0
        for i in range(Y0.shape[0]):
            if method == RADAU:
                r = _run_impl_radau(
                    Y0[i], P[i], q, breaks, coefs, t_eval, rtol, atol, out[i], empty,
                    rec, offsets[i], keep,
                )  # fmt: skip
            else:
                r = _run_impl(
                    Y0[i], P[i], q, breaks, coefs, t_eval, rtol, atol, out[i], empty,
                    rec, offsets[i], keep,
                )  # fmt: skip
            rec = r[7]
            offsets[i + 1] = r[8]
            codes[i] = r[0]
            t_stop[i] = r[1]
            stats[i, 0] = r[2]
            stats[i, 1] = r[3]
            stats[i, 2] = r[4]
            stats[i, 3] = r[5]
            stats[i, 4] = r[6]
            # NaN after the stop (the columns up to it are written by solve_run)
            for k in range(t_eval.size):
                if t_eval[k] > r[1]:
                    out[i, :, k] = np.nan
        return rec

    return jit(_named_for(solve_batch, method))


def _named_for(fn, method):
    # a qualified name per method: numba keeps a function's cache entries
    # in files named after it, and the two methods' closures would
    # otherwise share them
    fn.__qualname__ = f"{fn.__qualname__}_{'radau' if method == RADAU else 'dop853'}"
    return fn


_run_impl = _drivers(0)
_run_impl_radau = _drivers(RADAU)
solve_batch = _batch(0)
solve_batch_radau = _batch(RADAU)
