r"""The continuous solution of an integration: every step's dense output.

:class:`History` holds the solver's dense output of every accepted step,
with the runs integrated in it, and evaluates run ``runs[j]`` at time
``times[j]``. It is the past that an input delay reads (the method of
steps) and the continuous solution on which the exact peaks are located
(:class:`DenseSolution`); :func:`delayed_rows` gives the delayed path state
and its derivative at the output times. :class:`CompiledDense` is the same
interface on the compiled engine's solution, where every run took steps of
its own.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "History",
    "DenseSolution",
    "CompiledDense",
    "delayed_rows",
]


class History:
    """Past states of the runs for an input delay (method of steps).

    Holds the solver's dense output of every accepted step, with the global
    indices of the runs integrated in it. Before the start the state is held
    at its initial value (the documented initial history: the steering
    command is the one computed from the initial state until ``t = delay``).
    """

    def __init__(self, t0: float, y0: np.ndarray):
        self.t0 = t0
        self.y0 = y0  # (m, n) initial states of all runs
        self.starts: list[float] = []
        self.pieces: list[tuple[float, Any, np.ndarray]] = []
        # built at the first lookup after the last step (None: not DOP853)
        self._table: _Dop853Table | None = None
        self._table_built = False

    def add(self, t_old: float, t_new: float, dense, runs: np.ndarray) -> None:
        self.starts.append(t_old)
        self.pieces.append((t_new, dense, runs))
        self._table, self._table_built = None, False

    def table(self) -> _Dop853Table | None:
        """Every step's DOP853 interpolant in one table (None: other solvers)."""
        if not self._table_built:
            self._table = _Dop853Table.build(self.pieces, self.y0.shape)
            self._table_built = True
        return self._table

    def state(self, t: float, runs: np.ndarray) -> np.ndarray:
        """States ``(m, len(runs))`` of the given runs at time `t`."""
        if t <= self.t0 or not self.pieces:
            return self.y0[:, runs]
        k = max(bisect.bisect_right(self.starts, t) - 1, 0)
        _, dense, piece_runs = self.pieces[k]
        # Solver stages never ask beyond the last accepted step (max_step is
        # the delay); evaluation at its very end may extrapolate by rounding.
        y = np.asarray(dense(t)).reshape(self.y0.shape[0], piece_runs.size)
        return y[:, np.searchsorted(piece_runs, runs)]

    def states_at(self, runs: np.ndarray, times: np.ndarray) -> np.ndarray:
        """States ``(m, len(runs))`` of run ``runs[j]`` at time ``times[j]``.

        Each pair is evaluated on the dense output of the step that holds
        that run at that time (a run that stopped at ``t`` is found in the
        step that ended at ``t``, not in the next segment's first step).
        """
        runs = np.asarray(runs, dtype=int)
        times = np.asarray(times, dtype=float)
        m = self.y0.shape[0]
        out = np.empty((m, runs.size))
        before = times <= self.t0
        out[:, before] = self.y0[:, runs[before]]
        idx = np.flatnonzero(~before)
        if idx.size == 0:
            return out
        if not self.pieces:
            raise ValueError("no integrated step holds the requested times")
        starts = np.asarray(self.starts)
        k = np.maximum(np.searchsorted(starts, times[idx], side="right") - 1, 0)
        table = self.table()
        if table is not None:
            out[:, idx] = table.evaluate(runs[idx], times[idx], k)
            return out
        while idx.size:
            done = np.zeros(idx.size, dtype=bool)
            for kk in np.unique(k):
                sel = np.flatnonzero(k == kk)
                _, dense, piece_runs = self.pieces[kk]
                r = runs[idx[sel]]
                pos = np.minimum(np.searchsorted(piece_runs, r), piece_runs.size - 1)
                present = piece_runs[pos] == r
                sel, pos = sel[present], pos[present]
                if sel.size:
                    out[:, idx[sel]] = _dense_at(
                        dense, times[idx[sel]], pos, m, piece_runs.size
                    )
                    done[sel] = True
            idx, k = idx[~done], k[~done] - 1
            if np.any(k < 0):
                raise ValueError("a run was asked for at a time it was not integrated")
        return out


#: Largest table of interpolation coefficients :class:`_Dop853Table` builds
#: (it takes over the steps' own arrays): beyond it, the steps are evaluated
#: one by one.
_MAX_TABLE_BYTES = 256 * 2**20


class _Dop853Table:
    """The DOP853 interpolants of all steps of a history, for vectorised lookup.

    Pair ``(run, time)`` -> its step and column in one gather, instead of a
    Python loop over the steps: a delayed 13-run sweep of 30 s takes 0.32
    instead of 0.45 s (the delayed state is looked up twice per output time
    and peak node). Evaluation is :func:`_dop853_interpolant`, as for one
    step, so the values are the same to the last bit.
    """

    def __init__(self, m, keys, base, width, t_old, h, F, y_old, n_runs):
        self.m = m  # state rows
        self.keys = keys  # step * n_runs + run, ascending
        self.base = base  # first column of each entry (component 0)
        self.width = width  # runs in the entry's step (component stride)
        self.t_old, self.h = t_old, h  # per entry
        self.F, self.y_old = F, y_old  # (7, columns), (columns,)
        self.n_runs = n_runs

    @classmethod
    def build(cls, pieces, shape):
        """The table, or None if a step is not DOP853 or it would be too big."""
        from scipy.integrate._ivp.rk import Dop853DenseOutput

        m, n_runs = shape
        dop853 = (isinstance(d, Dop853DenseOutput) for _, d, _ in pieces)
        if not pieces or not all(dop853):
            return None
        widths = np.array([r.size for _, _, r in pieces])
        cols = m * widths
        if 8 * 8 * int(cols.sum()) > _MAX_TABLE_BYTES:
            return None
        step = np.repeat(np.arange(len(pieces)), widths)
        runs = np.concatenate([r for _, _, r in pieces])
        first = np.repeat(np.cumsum(cols) - cols, widths)
        pos = np.arange(runs.size) - np.repeat(np.cumsum(widths) - widths, widths)
        t_old = np.array([d.t_old for _, d, _ in pieces])
        h = np.array([d.h for _, d, _ in pieces])
        # The steps' coefficients move into the table and each step's
        # interpolant keeps a view of its part: the same values, held once
        # (the step's own arrays are freed one by one as they are copied).
        F = np.empty((len(pieces[0][1].F), int(cols.sum())))
        y_old = np.empty(F.shape[1])
        lo = 0
        for (_, d, _), c in zip(pieces, cols.tolist(), strict=True):
            F[:, lo : lo + c] = d.F
            y_old[lo : lo + c] = d.y_old
            d.F, d.y_old = F[:, lo : lo + c], y_old[lo : lo + c]
            lo += c
        return cls(
            m=m,
            keys=step * n_runs + runs,
            base=first + pos,
            width=np.repeat(widths, widths),
            t_old=t_old[step],
            h=h[step],
            F=F,
            y_old=y_old,
            n_runs=n_runs,
        )

    def evaluate(self, runs, times, step) -> np.ndarray:
        """States ``(m, len(runs))`` of run ``runs[j]`` at ``times[j]``.

        Each pair in step ``step[j]``, or the latest earlier step that holds
        its run (a run that stopped at ``t`` is in the step ending at ``t``).
        """
        entry = np.empty(runs.size, dtype=np.int64)
        todo = np.arange(runs.size)
        step = np.asarray(step, dtype=np.int64)
        while todo.size:
            if np.any(step < 0):
                raise ValueError("a run was asked for at a time it was not integrated")
            key = step * self.n_runs + runs[todo]
            e = np.minimum(np.searchsorted(self.keys, key), self.keys.size - 1)
            found = self.keys[e] == key
            entry[todo[found]] = e[found]
            todo, step = todo[~found], step[~found] - 1
        rows = np.arange(self.m)[:, None] * self.width[entry]
        cols = self.base[entry][None, :] + rows  # (m, pairs)
        x = (times - self.t_old[entry]) / self.h[entry]
        return _dop853_interpolant(self.F, self.y_old, cols, x)


def _dop853_interpolant(F, y_old, cols, x) -> np.ndarray:
    """DOP853's dense output at the stacked-state columns `cols`.

    scipy's ``Dop853DenseOutput`` evaluation, operation for operation, on
    the requested components only; `x` is ``(t - t_old) / h`` per column.
    """
    y = np.zeros(cols.shape)
    for i, f in enumerate(reversed(F)):
        y += f[cols]
        y *= x if i % 2 == 0 else 1 - x
    return y + y_old[cols]


def _dense_at(dense, times, pos, m, width) -> np.ndarray:
    """Rows ``(m, len(times))`` of the runs at positions `pos` of one step.

    `dense` interpolates the stacked state ``(m, width)`` (flattened
    row-major); pair ``j`` is run ``pos[j]`` at ``times[j]``. The
    interpolants of DOP853, the explicit Runge-Kutta methods and Radau are
    evaluated for the requested components only; other solvers' dense
    output is called on the distinct times.
    """
    from scipy.integrate._ivp.radau import RadauDenseOutput
    from scipy.integrate._ivp.rk import Dop853DenseOutput, RkDenseOutput

    cols = np.arange(m)[:, None] * width + pos[None, :]  # (m, P)
    if isinstance(dense, Dop853DenseOutput):
        x = (times - dense.t_old) / dense.h
        return _dop853_interpolant(dense.F, dense.y_old, cols, x)
    if isinstance(dense, (RkDenseOutput, RadauDenseOutput)):
        x = (times - dense.t_old) / dense.h
        p = np.cumprod(np.tile(x, (dense.order + 1, 1)), axis=0)  # (order+1, P)
        y = np.einsum("mpj,jp->mp", dense.Q[cols], p)
        # (scipy's Radau interpolant is not scaled by h, the RK ones are)
        y = y if isinstance(dense, RadauDenseOutput) else dense.h * y
        return y + dense.y_old[cols]
    ut, inv = np.unique(times, return_inverse=True)
    y = np.asarray(dense(ut)).reshape(m, width, ut.size)
    return y[:, pos, inv]


#: Most (run, time) pairs whose delayed rows are evaluated at once: bounds
#: the temporaries of :func:`delayed_rows` to a few MB.
_DELAYED_BLOCK = 1 << 15


def _delayed_state_rows(history, engine_for, delay, runs, times) -> np.ndarray:
    """Path state at ``times[j] - delay`` of run ``runs[j]`` and its derivative.

    Rows ``s, e, theta`` and their time derivatives, shape ``(6, len(runs))``;
    before the start the delayed state is the held initial one, whose
    derivative is 0.
    """
    td = times - delay
    Yd = history.states_at(runs, td)
    rows = np.zeros((6, runs.size))
    rows[:3] = Yd[:3]
    live = td > history.t0
    if np.any(live):
        eng = engine_for(runs[live])
        # The command at td uses the measurements of td - delay.
        eng.delayed = history.states_at(runs[live], td[live] - delay)
        rows[3:, live] = eng.derivatives(Yd[:, live])[0][:3]
    return rows


def delayed_rows(engine_for, history, out, t_eval, delay) -> np.ndarray:
    """Path state at ``t - delay`` and its derivative at the output times.

    Every (run, output time) pair of the integrated samples at once, in
    blocks of :data:`_DELAYED_BLOCK` pairs, rather than time by time: 0.17
    against 0.01 s for the two 30 s runs of ``reproduce``'s actuator figure.
    """
    n, T = out.shape[1], out.shape[2]
    rows = np.full((6, n, T), np.nan)
    have = np.isfinite(out[0])  # (n, T): the run had not stopped
    runs, ks = np.nonzero(have)
    for lo in range(0, runs.size, _DELAYED_BLOCK):
        r, k = runs[lo : lo + _DELAYED_BLOCK], ks[lo : lo + _DELAYED_BLOCK]
        rows[:, r, k] = _delayed_state_rows(history, engine_for, delay, r, t_eval[k])
    return rows


@dataclass
class DenseSolution:
    """The continuous solution of an integration.

    The solution of a call of :func:`~fws_control.simulation.engine.integrate`.

    ``history`` holds the solver's dense output of every accepted step with
    the runs integrated in it; ``engine_for(runs)`` builds the right-hand
    side of the given runs (for the derivative of the delayed state).
    """

    history: History
    engine_for: Any
    delay: float

    def step_bounds(self) -> np.ndarray:
        """The start, the ends of the accepted steps and their starts, ascending.

        Shape ``(1, B)``: the stacked runs share their steps.
        """
        hist = self.history
        ends = [hist.t0, *hist.starts, *(end for end, _, _ in hist.pieces)]
        return np.unique(np.asarray(ends, dtype=float))[None, :]

    def states(self, runs: np.ndarray, times: np.ndarray) -> np.ndarray:
        """States of run ``runs[j]`` at ``times[j]``, rows as
        :func:`~fws_control.simulation.engine.integrate`.

        With a delay the six rows of the delayed path state and its
        derivative follow, as :func:`~fws_control.simulation.signals.compute_outputs`
        expects them.
        """
        Y = self.history.states_at(runs, times)
        if self.delay <= 0.0:
            return Y
        rows = _delayed_state_rows(
            self.history, self.engine_for, self.delay, runs, times
        )
        return np.concatenate([Y, rows])


class CompiledDense:
    """The compiled engine's dense output, with :class:`DenseSolution`'s interface.

    Every run of the compiled engine takes steps of its own: run ``i`` owns
    the rows ``offsets[i]:offsets[i + 1]`` of `records` (one per accepted
    step, as :class:`~fws_control.simulation.compiled.CompiledSolution`
    holds them: ``t_old, h``, the state at ``t_old`` and DOP853's ``7 m``
    interpolant coefficients). :meth:`states` evaluates the interpolant of
    the step that holds each time (the initial state up to the start),
    :meth:`step_bounds` gives each run's steps, so that
    :func:`~fws_control.simulation.peaks.exact_peaks` locates the peaks of
    all runs at once on their own steps. No input delay (``delay`` 0).

    Parameters
    ----------
    records : ndarray
        Shape ``(R, 2 + 8 m)``.
    offsets : ndarray
        Shape ``(n + 1,)``, ascending, ``offsets[-1] <= R``.
    initial_state : ndarray
        The runs' initial states, shape ``(n, m)``.
    t0 : float
        The start time [s].

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import integrate_compiled
    >>> from fws_control.simulation.dense import CompiledDense
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sol, t = [], np.linspace(0.0, 1.0, 11)
    >>> states, *_ = integrate_compiled(
    ...     veh, fws.Straight(), fws.SteeringGains(0.1, 0.5, 0.0),
    ...     speed=np.array([5.0, 5.0]), feedforward=False,
    ...     path_state=np.array([[0.0, 1.0, 0.0], [0.0, -2.0, 0.0]]),
    ...     t_eval=t, time_constant=None, solution=sol)
    >>> dense = CompiledDense(sol[0].records, sol[0].offsets,
    ...                       sol[0].initial_state, 0.0)
    >>> runs = np.repeat([0, 1], 11)
    >>> bool(np.allclose(dense.states(runs, np.tile(t, 2)),
    ...                  states.reshape(3, 22), rtol=0, atol=1e-15))
    True
    """

    delay = 0.0

    def __init__(
        self,
        records: np.ndarray,
        offsets: np.ndarray,
        initial_state: np.ndarray,
        t0: float,
    ):
        self.records = np.asarray(records, dtype=float)
        self.offsets = np.asarray(offsets, dtype=np.int64)
        self.y0 = np.asarray(initial_state, dtype=float)
        self.t0 = float(t0)
        n = self.offsets.size - 1
        if self.y0.ndim != 2 or self.y0.shape[0] != n:
            raise ValueError(
                f"initial_state must have shape ({n}, m), got {self.y0.shape}"
            )
        # each row's run, for a search by (run, time) in one call: numpy
        # orders complex numbers by their real, then their imaginary part,
        # and the rows are sorted by run, then by time
        run_of_row = np.repeat(np.arange(n), np.diff(self.offsets))
        self._keys = run_of_row + 1j * self.records[: self.offsets[-1], 0]

    def split(self, max_steps: int) -> list[tuple[int, int, CompiledDense]]:
        """Consecutive runs ``lo:hi`` with at most `max_steps` steps in all.

        Each block holds at least one run; returns ``(lo, hi, dense of the
        block)`` in order. Bounds the memory of a computation over every
        step of every run (the exact peaks evaluate a few points per step).
        """
        n = self.offsets.size - 1
        blocks: list[tuple[int, int, CompiledDense]] = []
        lo = 0
        while lo < n:
            # the last run whose steps, counted from run lo, fit the budget
            hi = int(
                np.searchsorted(self.offsets, self.offsets[lo] + max_steps, "right")
            )
            hi = min(max(hi - 1, lo + 1), n)
            rows = slice(int(self.offsets[lo]), int(self.offsets[hi]))
            blocks.append((lo, hi, CompiledDense(
                self.records[rows], self.offsets[lo : hi + 1] - self.offsets[lo],
                self.y0[lo:hi], self.t0,
            )))  # fmt: skip
            lo = hi
        return blocks

    def step_bounds(self) -> np.ndarray:
        """Each run's start and step ends, ascending, NaN-padded: ``(n, B)``."""
        n = self.offsets.size - 1
        rec = self.records[: self.offsets[-1]]
        run_of_row = np.repeat(np.arange(n), np.diff(self.offsets))
        # every run's start, step starts and step ends, sorted by run, then
        # by time, each value once per run
        runs = np.concatenate([np.arange(n), run_of_row, run_of_row])
        vals = np.concatenate([np.full(n, self.t0), rec[:, 0], rec[:, 0] + rec[:, 1]])
        order = np.lexsort((vals, runs))
        runs, vals = runs[order], vals[order]
        new = np.ones(vals.size, dtype=bool)
        new[1:] = (runs[1:] != runs[:-1]) | (vals[1:] != vals[:-1])
        runs, vals = runs[new], vals[new]
        col = np.arange(vals.size) - np.searchsorted(runs, runs)
        bounds = np.full((n, int(col.max(initial=0)) + 1), np.nan)
        bounds[runs, col] = vals
        return bounds

    def states(self, runs: np.ndarray, times: np.ndarray) -> np.ndarray:
        """States ``(m, len(times))`` of run ``runs[j]`` at ``times[j]``."""
        runs = np.asarray(runs, dtype=np.int64)
        times = np.asarray(times, dtype=float)
        m = self.y0.shape[1]
        out = self.y0[runs].T.copy()
        after = np.flatnonzero((times > self.t0) & (np.diff(self.offsets)[runs] > 0))
        if after.size == 0:
            return out
        r, tt = runs[after], times[after]
        k = np.searchsorted(self._keys, r + 1j * tt, side="right") - 1
        # (a time before the run's first step's start: that step)
        k = np.maximum(k, self.offsets[r])
        row = self.records[k]
        x = (tt - row[:, 0]) / row[:, 1]
        npow = (self.records.shape[1] - 2) // m - 1
        F = row[:, 2 + m :].reshape(-1, npow, m)
        # scipy's Dop853DenseOutput evaluation, as the kernels' _dense_eval
        v = np.zeros((tt.size, m))
        for j in range(npow):
            v += F[:, npow - 1 - j, :]
            v *= (x if j % 2 == 0 else 1.0 - x)[:, None]
        out[:, after] = (v + row[:, 2 : 2 + m]).T
        return out
