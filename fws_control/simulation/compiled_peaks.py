"""The exact peaks on each run's compiled dense output.

:func:`~fws_control.simulation.engine.exact_peaks`'s search (nodes per
step, the largest local maxima refined by Brent's bounded search) on the
dense output that the compiled drivers keep, for
:func:`~fws_control.simulation.compiled.compiled_peaks`.
"""

from __future__ import annotations

import math

import numpy as np

from .compilation import jit
from .compiled_layout import (
    NPOW,
    Q_DELAY,
    Q_DYNAMIC,
    Q_MAX_F,
    Q_MAX_R,
    Q_TAU,
    WITH_DELAY,
    WITH_DYNAMIC,
    jit_inline,
)
from .compiled_loop import curvature_at, raw_command
from .compiled_signals import (
    delayed_dynamic_point_signals,
    delayed_point_signals,
    dynamic_point_signals,
    point_signals,
)
from .outcomes import PEAK_SIGNALS, SIGNALS

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []

# --------------------------------------------------------------------------
# Exact peaks on each run's own dense output (engine.exact_peaks, compiled)

# The numpy engine's search (engine.exact_peaks): 8 nodes per solver step,
# the 3 largest local maxima of the nodes and the largest output sample
# refined (here a step densely sampled by the output grid has its start and
# its samples as nodes: see _node_samples). The refinement here is Brent's
# bounded search (scipy's fminbound: golden section with parabolic steps)
# to a time tolerance of
# sqrt(eps) max(|t|, 1 s), converging in a fraction of the golden-section
# iterations; at a smooth maximum a time error dt moves the value by
# f'' dt^2 / 2: about (dt / tau)^2 of it for a signal of time scale tau,
# below 1e-12 for tau >= 0.02 s and t <= 100 s.
_PEAK_NODES = 8
_PEAK_CAND = 3
_PEAK_MAXFUN = 200
_N_PROBES = 4
N_PEAK = 6
# _peak_values computes these, in this order
assert PEAK_SIGNALS == (
    "e", "delta_f", "delta_r", "delta_f_rate", "delta_r_rate", "lateral_accel"
)  # fmt: skip
_PEAK_COLS = tuple(SIGNALS.index(name) for name in PEAK_SIGNALS)


@jit_inline
def _state_at(tt, rec, n_pc, y0, m, ytmp):
    """The run's state at `tt` from its dense output (`rec`: its pieces)."""
    if n_pc == 0:
        for i in range(m):
            ytmp[i] = y0[i]
    else:
        # the piece that starts at or before tt (as engine._History.states_at)
        lo, hi = 0, n_pc
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if rec[mid, 0] <= tt:
                lo = mid
            else:
                hi = mid
        row = rec[lo]
        x = (tt - row[0]) / row[1]
        for i in range(m):
            v = 0.0
            for k in range(NPOW):
                v += row[2 + m + (NPOW - 1 - k) * m + i]
                if k % 2 == 0:
                    v *= x
                else:
                    v *= 1 - x
            ytmp[i] = v + row[2 + i]


@jit_inline
def _peak_values(tt, rec, n_pc, y0, m, p, q, br, co, d_cg, ytmp, out):
    """|signal| of the six peak signals at `tt` on the run's dense output."""
    _state_at(tt, rec, n_pc, y0, m, ytmp)
    df_s, dr_s = 0.0, 0.0
    if q[Q_TAU] > 0.0:
        df_s, dr_s = ytmp[3], ytmp[4]
    if WITH_DELAY and q[Q_DELAY] > 0.0 and WITH_DYNAMIC and q[Q_DYNAMIC] != 0.0:
        df, dr, rf, rr, lat, _, _, ok = delayed_dynamic_point_signals(
            tt, ytmp[0], ytmp[1], ytmp[2], df_s, dr_s, ytmp[m - 2], ytmp[m - 1],
            rec, n_pc, y0, m, p, q, br, co,
        )  # fmt: skip
    elif WITH_DELAY and q[Q_DELAY] > 0.0:
        df, dr, rf, rr, lat, _, _, ok = delayed_point_signals(
            tt, df_s, dr_s, rec, n_pc, y0, m, p, q, br, co, d_cg
        )
    elif WITH_DYNAMIC and q[Q_DYNAMIC] != 0.0:
        df, dr, rf, rr, lat, _, _, ok = dynamic_point_signals(
            ytmp[0], ytmp[1], ytmp[2], df_s, dr_s, ytmp[m - 2], ytmp[m - 1], p, q,
            br, co,
        )  # fmt: skip
    else:
        df, dr, rf, rr, lat, _, _, ok = point_signals(
            ytmp[0], ytmp[1], ytmp[2], df_s, dr_s, p, q, br, co, d_cg
        )
    out[0] = abs(ytmp[1])
    out[1] = abs(df)
    out[2] = abs(dr)
    if ok:
        out[3] = abs(rf)
        out[4] = abs(rr)
        out[5] = abs(lat)
    else:
        out[3] = np.nan
        out[4] = np.nan
        out[5] = np.nan
    # a signal not finite where the state is (it diverges there): inf
    for j in range(N_PEAK):
        if not np.isfinite(out[j]):
            out[j] = np.inf


@jit
def _peak_value(tt, j, rec, n_pc, y0, m, p, q, br, co, d_cg, ytmp, vals):
    """|signal j| at `tt`: :func:`_peak_values` computing only what j needs."""
    if j > 2 or (j > 0 and not q[Q_TAU] > 0.0 and q[Q_DELAY] > 0.0):
        # (_peak_values finds the state itself)
        _peak_values(tt, rec, n_pc, y0, m, p, q, br, co, d_cg, ytmp, vals)
        return vals[j]
    _state_at(tt, rec, n_pc, y0, m, ytmp)
    if j == 0:
        v = abs(ytmp[1])
    elif q[Q_TAU] > 0.0:
        v = abs(ytmp[2 + j])  # the actuator's angles are states
    else:
        # the clipped commands, with the operations of point_signals
        kappa = curvature_at(ytmp[0], q, br, co)
        raw_f, raw_r = raw_command(ytmp[0], ytmp[1], ytmp[2], kappa, p, q, br, co)
        if j == 1:
            v = abs(min(max(raw_f, -q[Q_MAX_F]), q[Q_MAX_F]))
        else:
            v = abs(min(max(raw_r, -q[Q_MAX_R]), q[Q_MAX_R]))
    return v if math.isfinite(v) else np.inf


@jit
def _refine_peak(lo, hi, j, best, rec, n_pc, y0, m, p, q, br, co,
                 d_cg, ytmp, vals):  # fmt: skip
    """Brent's bounded search for the largest |signal j| in [lo, hi].

    scipy.optimize.fminbound's algorithm on -|signal|; every evaluation
    updates ``best = (value, time)`` (a 2-vector), as engine.exact_peaks
    keeps the best of all its evaluations.
    """
    sqrt_eps = math.sqrt(2.2e-16)
    golden = 0.5 * (3.0 - math.sqrt(5.0))
    a_, b_ = lo, hi
    fulc = a_ + golden * (b_ - a_)
    nfc, xf = fulc, fulc
    rat = 0.0
    e = 0.0
    x = xf
    fx = -_peak_value(x, j, rec, n_pc, y0, m, p, q, br, co, d_cg, ytmp, vals)
    if -fx > best[0]:
        best[0], best[1] = -fx, x
    num = 1
    ffulc = fx
    fnfc = fx
    xm = 0.5 * (a_ + b_)
    tol1 = sqrt_eps * max(abs(xf), 1.0)
    tol2 = 2.0 * tol1
    while abs(xf - xm) > (tol2 - 0.5 * (b_ - a_)):
        golden_step = True
        if abs(e) > tol1:
            golden_step = False
            r = (xf - nfc) * (fx - ffulc)
            qq = (xf - fulc) * (fx - fnfc)
            pp = (xf - fulc) * qq - (xf - nfc) * r
            qq = 2.0 * (qq - r)
            if qq > 0.0:
                pp = -pp
            qq = abs(qq)
            r = e
            e = rat
            if (
                (abs(pp) < abs(0.5 * qq * r))
                and (pp > qq * (a_ - xf))
                and (pp < qq * (b_ - xf))
            ):
                rat = pp / qq
                x = xf + rat
                if ((x - a_) < tol2) or ((b_ - x) < tol2):
                    si = 1.0 if xm - xf >= 0.0 else -1.0
                    rat = tol1 * si
            else:
                golden_step = True
        if golden_step:
            if xf >= xm:
                e = a_ - xf
            else:
                e = b_ - xf
            rat = golden * e
        si = 1.0 if rat >= 0.0 else -1.0
        x = xf + si * max(abs(rat), tol1)
        fu = -_peak_value(x, j, rec, n_pc, y0, m, p, q, br, co, d_cg, ytmp, vals)
        if -fu > best[0]:
            best[0], best[1] = -fu, x
        num += 1
        if fu <= fx:
            if x >= xf:
                a_ = xf
            else:
                b_ = xf
            fulc, ffulc = nfc, fnfc
            nfc, fnfc = xf, fx
            xf, fx = x, fu
        else:
            if x < xf:
                a_ = x
            else:
                b_ = x
            if (fu <= fnfc) or (nfc == xf):
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = x, fu
            elif (fu <= ffulc) or (fulc == xf) or (fulc == nfc):
                fulc, ffulc = x, fu
        xm = 0.5 * (a_ + b_)
        tol1 = sqrt_eps * max(abs(xf), 1.0)
        tol2 = 2.0 * tol1
        if num >= _PEAK_MAXFUN or not math.isfinite(fx):
            break


@jit
def _falls_from_end(end, other, f_end, f_other, j, best, rec, n_pc, y0, m, p,
                    q, br, co, d_cg, ytmp, vals):  # fmt: skip
    """True if |signal j| falls monotonically from `end` towards `other`.

    Checked at _N_PROBES interior points (5x finer than the nodes; updating
    `best`). A bracket whose largest value is at its end and that falls at
    every probe has its maximum at that end: a rise again between two
    probes would be a feature of the solution 40x shorter than its solver
    step, which the step's error control does not allow. Saves the search
    (about 30 evaluations) converging to the end.
    """
    prev = f_end
    for r in range(1, _N_PROBES + 1):
        x = end + (r / (_N_PROBES + 1)) * (other - end)
        v = _peak_value(x, j, rec, n_pc, y0, m, p, q, br, co, d_cg,
                        ytmp, vals)  # fmt: skip
        if v > best[0]:
            best[0], best[1] = v, x
        if not v <= prev:
            return False
        prev = v
    return f_other <= prev


@jit
def _sample_value(signals, i, j, k):
    """|peak signal j| of run i at output sample k, with _peak_values' inf
    where it is not finite (the state there is)."""
    v = abs(signals[i, _PEAK_COLS[j], k])
    return v if np.isfinite(v) else np.inf


@jit
def _node_samples(signals, i, t_eval, k_s, b0, b1, ts):
    """End of the output samples that can serve as the nodes of a piece.

    The samples from `k_s` (the first at or after the piece's start `b0`)
    before its end `b1` and the stop `ts`: returns their end index if they
    leave no gap wider than the piece's node spacing ``(b1 - b0) /
    _PEAK_NODES`` (from `b0`, between them, to `b1`) and all have a state,
    else `k_s` (none: the piece gets its own nodes). On the paper's
    scenario (steps of about 0.3 s, samples every 0.01 s) every piece has
    about 30 samples: the coarse search is then finer than its 8 nodes and
    costs no evaluation.
    """
    T = t_eval.size
    gap = (b1 - b0) / _PEAK_NODES
    prev = b0
    k = k_s
    while k < T and t_eval[k] < b1 and t_eval[k] < ts:
        if t_eval[k] - prev > gap or not np.isfinite(signals[i, 3, k]):
            return k_s
        prev = t_eval[k]
        k += 1
    if k == k_s or b1 - prev > gap:
        return k_s
    return k


@jit
def peaks_batch(rec, offsets, Y0, P, q, br, co, d_cg, t_eval, signals, t_stop,
                 values, times):  # fmt: skip
    n, m = Y0.shape
    T = t_eval.size
    ytmp = np.empty(m)
    vals = np.empty(N_PEAK)
    best = np.empty(2)
    ks_all = np.empty(N_PEAK, dtype=np.int64)
    sv_all = np.empty(N_PEAK)
    cand = np.empty(_PEAK_CAND, dtype=np.int64)
    cval = np.empty(_PEAK_CAND)
    for i in range(n):
        p = P[i]
        pc = rec[offsets[i] : offsets[i + 1]]
        n_pc = pc.shape[0]
        ts = t_stop[i]
        # nodes: each piece split in _PEAK_NODES, the ones before the stop,
        # then the stop (engine.exact_peaks); but a piece whose output
        # samples leave no gap wider than that split (from its start,
        # between them, to its end) has its start and those samples as its
        # nodes: they are values of the same dense output, already computed
        # (_node_samples)
        times_n = np.empty(n_pc * (_PEAK_NODES + 1) + T + 1)
        sample_n = np.empty(n_pc * (_PEAK_NODES + 1) + T + 1, dtype=np.int64)
        K = 0
        k_s = 0  # the first output time not before the piece
        for k in range(n_pc):
            b0 = pc[k, 0]
            b1 = pc[k + 1, 0] if k + 1 < n_pc else ts
            while k_s < T and t_eval[k_s] < b0:
                k_s += 1
            k_e = _node_samples(signals, i, t_eval, k_s, b0, b1, ts)
            if k_e > k_s:
                # the piece's start stays a node: a located switch of a clip,
                # where a rate or the acceleration has a corner, is a start
                if t_eval[k_s] > b0:
                    times_n[K] = b0
                    sample_n[K] = -1
                    K += 1
                for kk in range(k_s, k_e):
                    times_n[K] = t_eval[kk]
                    sample_n[K] = kk
                    K += 1
                k_s = k_e
                continue
            for jj in range(_PEAK_NODES):
                tt = b0 + (jj / _PEAK_NODES) * (b1 - b0)
                if tt < ts:
                    times_n[K] = tt
                    sample_n[K] = -1
                    K += 1
        times_n[K] = ts
        sample_n[K] = -1
        K += 1
        # the largest output sample of each signal, all six in one pass
        # over the samples (inf where the signal is not finite but the
        # state is; after the stop no sample)
        for j in range(N_PEAK):
            ks_all[j] = -1
            sv_all[j] = -np.inf
        for k in range(T):
            if not np.isfinite(signals[i, 3, k]):
                continue
            for j in range(N_PEAK):
                v = _sample_value(signals, i, j, k)
                if ks_all[j] < 0 or v > sv_all[j]:
                    ks_all[j], sv_all[j] = k, v
        # node values per signal, contiguous (the searches below run along
        # one signal)
        node_v = np.empty((N_PEAK, K))
        for k in range(K):
            kk = sample_n[k]
            if kk >= 0:
                for j in range(N_PEAK):
                    node_v[j, k] = _sample_value(signals, i, j, kk)
                continue
            _peak_values(times_n[k], pc, n_pc, Y0[i], m, p, q, br, co,
                         d_cg, ytmp, vals)  # fmt: skip
            for j in range(N_PEAK):
                node_v[j, k] = vals[j]
        for j in range(N_PEAK):
            row = node_v[j]
            # the largest local maxima of the nodes, refined between their
            # neighbours (ties: the earlier node, as a stable sort); the
            # first is the best node (first of equals, as np.argmax): the
            # values are never NaN or -inf (absolute values, inf where not
            # finite), so the first largest node has no larger neighbour,
            # beats every earlier value and no later one displaces it
            for c in range(_PEAK_CAND):
                cand[c], cval[c] = -1, -np.inf
            for k in range(K):
                v = row[k]
                # (the three tests in the order that rejects most nodes
                # first: one comparison for a node below the third largest)
                if not v > cval[_PEAK_CAND - 1]:
                    continue
                if k > 0 and row[k - 1] > v:
                    continue
                if k + 1 < K and row[k + 1] > v:
                    continue
                c = _PEAK_CAND - 1
                while c > 0 and v > cval[c - 1]:
                    cand[c], cval[c] = cand[c - 1], cval[c - 1]
                    c -= 1
                cand[c], cval[c] = k, v
            kb = cand[0]
            best[0], best[1] = row[kb], times_n[kb]
            # ... or the largest output sample
            ks, sv = ks_all[j], sv_all[j]
            if sv > best[0]:
                best[0], best[1] = sv, t_eval[ks]
            for c in range(_PEAK_CAND):
                k = cand[c]
                if k < 0 or not np.isfinite(cval[c]):
                    continue
                k_lo, k_hi = max(k - 1, 0), min(k + 1, K - 1)
                lo, hi = times_n[k_lo], times_n[k_hi]
                if not hi > lo:
                    continue
                # a local maximum at an end of the run: the end itself, unless
                # the signal rises again inside the bracket
                if k == 0 and _falls_from_end(
                    lo, hi, row[0], row[k_hi], j, best, pc, n_pc,
                    Y0[i], m, p, q, br, co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    continue
                if k == K - 1 and _falls_from_end(
                    hi, lo, row[k], row[k_lo], j, best, pc, n_pc,
                    Y0[i], m, p, q, br, co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    continue
                _refine_peak(lo, hi, j, best, pc, n_pc, Y0[i], m, p, q, br,
                             co, d_cg, ytmp, vals)  # fmt: skip
            if ks >= 0 and np.isfinite(sv):
                lo = t_eval[max(ks - 1, 0)]
                hi = max(min(t_eval[min(ks + 1, T - 1)], ts), lo)
                if not hi > lo:
                    pass
                elif t_eval[ks] == lo and _falls_from_end(
                    lo, hi, sv, -np.inf, j, best, pc, n_pc, Y0[i], m, p, q, br,
                    co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    pass
                elif t_eval[ks] == hi and _falls_from_end(
                    hi, lo, sv, -np.inf, j, best, pc, n_pc, Y0[i], m, p, q, br,
                    co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    pass
                else:
                    _refine_peak(lo, hi, j, best, pc, n_pc, Y0[i], m, p, q, br,
                                 co, d_cg, ytmp, vals)  # fmt: skip
            values[i, j] = best[0]
            times[i, j] = best[1]
