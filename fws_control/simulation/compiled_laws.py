r"""The baseline controllers' laws on the compiled engine.

A :class:`~fws_control.LateralController` declares its law with
:meth:`~fws_control.LateralController.compiled_law`: a name of
:data:`LAWS` and up to six per-run parameters. The compiled engine
(:mod:`~fws_control.simulation.compiled`) then evaluates that law in its
right-hand side instead of the paper's, from the same functions of
:mod:`fws_control.equations` that the controllers' numpy ``steering``
methods call:

=========================  =================================================
law                        parameters (``p[12:]``)
=========================  =================================================
``"state_feedback"``       ``K[0, 0], K[0, 1], K[1, 0], K[1, 1]``, feedforward
``"pure_pursuit"``         look-ahead [m], look-ahead time [s] (0: none), ratio
``"stanley"``              gain [1/s], softening [m/s], ratio
``"rear_wheel_feedback"``  ``K_e`` [1/m^2], ``K_theta`` [1/m], ratio
``"held"``                 ``delta_f``, ``delta_r`` [rad]
=========================  =================================================

``"held"`` is a constant command: a sampled controller's zero-order hold
between two switches (:mod:`~fws_control.simulation.compiled_sampled`).

Pure pursuit and Stanley need the path's position and heading, which the
kernels read from a :class:`GeometryTable`: cubic Hermite interpolants of
``x(s)``, ``y(s)`` (slopes ``cos psi, sin psi``) and the heading
``psi(s)`` (slope the curvature), refined until they are within a stated
tolerance of the path (exact for a :class:`~fws_control.Straight`). The
rows of that table follow the curvature table's rows in the kernels'
``breaks`` / ``coefs`` arrays; their start and size are in the shared
parameters. Stanley's projection of the front axle onto the path is the
numpy :meth:`~fws_control.paths.Path.project`'s local Newton iteration
(same start, same steps, same stop) on the table.

The steering angles are then clipped, held at the angle limits and passed
through the actuator with its rate limits exactly as the paper's law is.
The signals and exact peaks of a controller's runs are compiled too
(:func:`~fws_control.simulation.compiled.compiled_outputs`,
:func:`~fws_control.simulation.compiled.compiled_peaks`), with the numpy
engine's formulas: the analytic rate of a state-feedback law and, for the
others, the central difference of
:meth:`~fws_control.LateralController.steering_rate`. At a varying speed
they are the numpy engine's
:func:`~fws_control.simulation.engine.compute_outputs` and
:func:`~fws_control.simulation.engine.exact_peaks` on each run's compiled
dense output (:func:`controller_outputs`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..baselines import saturate
from ..hints import RealArrayLike
from ..paths import Path, Straight
from ..validation import check_positive
from .dense import CompiledDense
from .peaks import exact_peaks_per_run
from .signals import compute_outputs

__all__ = [
    "LAWS",
    "GeometryTable",
    "geometry_table",
    "law_code",
    "law_parameters",
    "needs_geometry",
    "kernel_arrays",
    "make_law_command",
    "initial_command",
    "controller_outputs",
    "Q_LAW",
    "Q_CURVATURE_ROWS",
    "Q_GEOMETRY_BREAK",
    "Q_GEOMETRY_ROW",
    "Q_GEOMETRY_PIECES",
    "P_LAW",
    "N_LAW_PARAMETERS",
]

#: Names of the compiled laws; the code of a law is its index (0: the
#: paper's law of :class:`~fws_control.SteeringGains`).
LAWS = (
    "paper", "state_feedback", "pure_pursuit", "stanley", "rear_wheel_feedback",
    "held",
)  # fmt: skip
_STATE_FEEDBACK, _PURE_PURSUIT, _STANLEY, _REAR_WHEEL, _HELD = 1, 2, 3, 4, 5

# Slots of the shared parameter vector q (the compiled engine's layout,
# slots 28-35): the law's code, the number of rows of the curvature table
# (the geometry follows them), the geometry's first break and first row,
# and its number of pieces.
Q_LAW, Q_CURVATURE_ROWS, Q_GEOMETRY_BREAK, Q_GEOMETRY_ROW, Q_GEOMETRY_PIECES = (
    28, 29, 30, 31, 32,
)  # fmt: skip
#: First slot of a run's law parameters in its vector p (slots 12-17).
P_LAW = 12
N_LAW_PARAMETERS = 6
# slots of the compiled engine's layout read here (see compiled.py)
_Q_WHEELBASE, _Q_PERIOD, _Q_S_LO, _Q_S_HI, _P_SPEED = 0, 9, 10, 11, 0
# Newton iterations of the projection, as Path.project's local search
_NEWTON_MAXITER = 40
_WINDOW = 10.0


def law_code(controller: Any) -> int:
    """Code (index in :data:`LAWS`) of `controller`'s compiled law.

    0 for :class:`~fws_control.SteeringGains`, -1 where the controller
    declares no compiled law.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled_laws import law_code
    >>> law_code(fws.Stanley()), law_code(fws.SteeringGains(0.1, 0.5, 0.0))
    (3, 0)
    """
    from ..gains import SteeringGains

    if isinstance(controller, SteeringGains):
        return 0
    declare = getattr(controller, "compiled_law", None)
    law = declare() if callable(declare) else None
    if law is None:
        return -1
    name, params = law
    if name not in LAWS[1:] or len(params) > N_LAW_PARAMETERS:
        raise ValueError(
            f"compiled_law() must return a name of {LAWS[1:]} and at most "
            f"{N_LAW_PARAMETERS} parameters, got {name!r} with {len(params)}"
        )
    return LAWS.index(name)


def law_parameters(controller: Any, n: int) -> np.ndarray:
    """The law parameters of `n` runs, shape ``(n, 6)`` (unused slots 0).

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled_laws import law_parameters
    >>> law_parameters(fws.PurePursuit(lookahead=4.0), 2)[:, :3].tolist()
    [[4.0, 0.0, 0.0], [4.0, 0.0, 0.0]]
    """
    out = np.zeros((n, N_LAW_PARAMETERS))
    _, params = controller.compiled_law()
    for j, v in enumerate(params):
        out[:, j] = np.broadcast_to(np.asarray(v, dtype=float).ravel(), (n,))
    return out


def needs_geometry(code: int) -> bool:
    """Whether law `code` reads the path's position and heading."""
    return code in (_PURE_PURSUIT, _STANLEY)


class GeometryTable:
    r"""Position and heading of a path as piecewise cubics in ``s``.

    On ``[breaks[k], breaks[k+1])`` with ``d = s - breaks[k]``, row ``k``
    of `coefs` gives ``x``, row ``K + k`` ``y`` and row ``2 K + k`` the
    heading ``psi`` as ``c0 + c1 d + c2 d^2 + c3 d^3`` (``K`` pieces).

    Attributes
    ----------
    breaks : ndarray
        Shape ``(K + 1,)``, increasing [m].
    coefs : ndarray
        Shape ``(3 K, 4)``.
    max_error : float
        Largest distance to the path's position [m] or heading [rad] found
        at the quarter points of the pieces when the table was built (0:
        exact).

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled_laws import geometry_table
    >>> tab = geometry_table(fws.Straight())
    >>> tab.breaks.tolist(), tab.max_error
    ([0.0, inf], 0.0)
    """

    __slots__ = ("breaks", "coefs", "max_error")

    def __init__(
        self, breaks: RealArrayLike, coefs: RealArrayLike, *, max_error: float = 0.0
    ) -> None:
        self.breaks: np.ndarray = np.ascontiguousarray(breaks, dtype=float)
        self.coefs: np.ndarray = np.ascontiguousarray(coefs, dtype=float).reshape(-1, 4)
        if self.coefs.shape[0] != 3 * (self.breaks.size - 1):
            raise ValueError(
                f"coefs must have 3 rows per piece, got {self.coefs.shape[0]} "
                f"for {self.breaks.size - 1} pieces"
            )
        self.max_error: float = float(max_error)

    def __call__(self, s: RealArrayLike) -> tuple[np.ndarray, ...]:
        """``(x, y, psi)`` at `s` (numpy, for checks; `s` in the breaks)."""
        s = np.asarray(s, dtype=float)
        K = self.breaks.size - 1
        k = np.clip(np.searchsorted(self.breaks, s, side="right") - 1, 0, K - 1)
        d = s - self.breaks[k]
        out = []
        for block in range(3):
            c = self.coefs[block * K + k]
            out.append(c[..., 0] + d * (c[..., 1] + d * (c[..., 2] + d * c[..., 3])))
        return tuple(out)

    def __repr__(self) -> str:
        return (
            f"GeometryTable(pieces={self.breaks.size - 1}, "
            f"max_error={self.max_error:.3g})"
        )


def _hermite(s, v, m):
    h = np.diff(s)
    slope = np.diff(v) / h
    c2 = (3 * slope - 2 * m[:-1] - m[1:]) / h
    c3 = (m[:-1] + m[1:] - 2 * slope) / h**2
    return np.stack([v[:-1], m[:-1], c2, c3], axis=1)


def _frame(path: Path, s):
    x, y = path.position(s)
    psi = np.unwrap(np.asarray(path.heading(s), dtype=float))
    return np.asarray(x, float), np.asarray(y, float), psi


def geometry_table(
    path: Path, *, tol: float = 1e-10, max_pieces: int = 1 << 18
) -> GeometryTable:
    r"""The :class:`GeometryTable` of `path`, within `tol`.

    Exact for :class:`~fws_control.Straight`. Other paths (of finite length)
    get cubic Hermite interpolants of ``x, y`` (slopes ``cos psi, sin psi``)
    and ``psi`` (slope the curvature) on nodes that include the curvature's
    breaks of a chain, halved where the position [m] or the heading [rad]
    misses the path by more than `tol` at a piece's quarter points. A
    position error ``tol`` moves pure pursuit's and Stanley's angles by
    about ``tol`` times their gain on the lateral error.

    Parameters
    ----------
    path : Path
        The reference path.
    tol : float, optional
        Tolerance [m] and [rad], > 0 (default 1e-10).
    max_pieces : int, optional
        Largest number of pieces.

    Returns
    -------
    GeometryTable

    Raises
    ------
    ValueError
        If the path is unbounded (other than a Straight) or `tol` is not
        reached with `max_pieces` pieces.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled_laws import geometry_table
    >>> path = fws.Arc(curvature=0.05)
    >>> tab = geometry_table(path)
    >>> x, y, psi = tab(np.array([3.3]))
    >>> bool(abs(x[0] - path.position(3.3)[0]) <= 1e-10), tab.max_error <= 1e-10
    (True, True)
    """
    tol = float(check_positive("tol", tol))
    L = float(path.length)
    if isinstance(path, Straight):
        (x0, y0), psi0 = path.start, float(path.start_heading)
        c, sn = math.cos(psi0), math.sin(psi0)
        line = [[x0, c, 0.0, 0.0], [y0, sn, 0.0, 0.0], [psi0, 0.0, 0.0, 0.0]]
        return GeometryTable([0.0, L], line)
    if not math.isfinite(L):
        raise ValueError(f"path must have a finite length for a table, got {path!r}")
    s = np.linspace(0.0, L, 65)
    offsets = getattr(path, "offsets", None)
    if offsets is not None:  # a chain: its joints are nodes (kinks of kappa')
        s = np.unique(np.concatenate([s, np.asarray(offsets, dtype=float)]))
        s = s[(s >= 0.0) & (s <= L)]
    err = math.inf
    while s.size - 1 <= max_pieces:
        x, y, psi = _frame(path, s)
        kappa = np.asarray(path.curvature(s), dtype=float)
        coefs = np.concatenate(
            [
                _hermite(s, x, np.cos(psi)),
                _hermite(s, y, np.sin(psi)),
                _hermite(s, psi, kappa),
            ]
        )
        table = GeometryTable(s, coefs)
        h = np.diff(s)
        probe = s[:-1, None] + h[:, None] * np.array([0.25, 0.5, 0.75])
        tx, ty, tpsi = table(probe)
        px, py, ppsi = _frame(path, probe.ravel())
        miss = np.maximum(
            np.hypot(tx - px.reshape(probe.shape), ty - py.reshape(probe.shape)),
            np.abs(np.remainder(tpsi - ppsi.reshape(probe.shape) + math.pi,
                                2 * math.pi) - math.pi),
        )  # fmt: skip
        err = float(np.max(miss))
        if err <= tol:
            table.max_error = err
            return table
        bad = np.flatnonzero(np.max(miss, axis=1) > tol)
        s = np.sort(np.concatenate([s, s[bad] + 0.5 * h[bad]]))
    raise ValueError(
        f"position of {type(path).__name__} not within tol={tol} with "
        f"max_pieces={max_pieces} cubic pieces (last error {err:.3g}); use the "
        "numpy engine for this path"
    )


# tables of the paths last used (a path is immutable; id-keyed, with the
# path kept alive so that the id is not reused)
_GEOMETRY_CACHE: dict[int, tuple[Path, GeometryTable]] = {}


def kernel_arrays(path: Any, table: Any, code: int, q: np.ndarray):
    """The kernels' ``breaks, coefs``: the curvature table, then the geometry.

    Sets the geometry's slots of `q` (none without it).
    """
    q[Q_GEOMETRY_BREAK : Q_GEOMETRY_PIECES + 1] = 0.0
    if not needs_geometry(code):
        return table.breaks, table.coefs
    if not isinstance(path, Path):
        raise ValueError(
            f"law {LAWS[code]!r} needs the path itself (its position), not a "
            f"{type(path).__name__}"
        )
    hit = _GEOMETRY_CACHE.get(id(path))
    if hit is None or hit[0] is not path:
        if len(_GEOMETRY_CACHE) >= 8:
            _GEOMETRY_CACHE.pop(next(iter(_GEOMETRY_CACHE)))
        hit = (path, geometry_table(path))
        _GEOMETRY_CACHE[id(path)] = hit
    geo = hit[1]
    q[Q_GEOMETRY_BREAK] = table.breaks.size
    q[Q_GEOMETRY_ROW] = table.coefs.shape[0]
    q[Q_GEOMETRY_PIECES] = geo.breaks.size - 1
    breaks = np.concatenate([table.breaks, geo.breaks])
    coefs = np.ascontiguousarray(np.concatenate([table.coefs, geo.coefs]))
    return breaks, coefs


def initial_command(vehicle, path, controller, z0, kappa, speed):
    """The saturated command of the initial states, as the numpy engine's.

    Returns ``(delta_f, delta_r)`` of shape ``(n,)``.
    """
    s = z0[:, 0]
    L = float(getattr(path, "length", math.inf))
    if math.isfinite(L) and not getattr(path, "closed", False):
        s = np.clip(s, 0.0, L)
    df, dr = controller.steering(
        vehicle, path, s=s, e=z0[:, 1], theta=z0[:, 2], curvature=kappa, speed=speed
    )
    df, dr = saturate(vehicle, df, dr)
    n = z0.shape[0]
    return np.broadcast_to(df, (n,)), np.broadcast_to(dr, (n,))


def make_law_command(eqs: dict, table_position, table_piece, jit):
    """The compiled law ``(s, e, theta, kappa, p, q, breaks, coefs) -> (cf, cr)``.

    Built from the compiled equations `eqs` (``compiled_layout.EQUATIONS``),
    the arc length on the path's tables (``compiled_loop.table_position``),
    the search of a table's piece (``compiled_layout.table_piece``) and the
    engine's decorator, for the law whose
    code is ``q[Q_LAW]`` (1-5); unclipped angles. Called, not inlined: a
    copy of the projection in every kernel multiplied the compilation time.
    """
    feedback_angle = eqs["feedback_angle"]
    feedforward_angle = eqs["feedforward_angle"]
    rear_axle_point = eqs["rear_axle_point"]
    front_axle_point = eqs["front_axle_point"]
    wrap_angle = eqs["wrap_angle"]
    lookahead_distance = eqs["lookahead_distance"]
    lookahead_offset = eqs["lookahead_offset"]
    pure_pursuit_angle = eqs["pure_pursuit_angle"]
    stanley_angle = eqs["stanley_angle"]
    rear_wheel_feedback_angle = eqs["rear_wheel_feedback_angle"]

    @jit
    def frame(s, q, breaks, coefs):
        # x, y, psi and d psi / ds of the geometry table at s (on the path)
        b0 = int(q[Q_GEOMETRY_BREAK])
        r0 = int(q[Q_GEOMETRY_ROW])
        n = int(q[Q_GEOMETRY_PIECES])
        k = table_piece(s, breaks, b0, n) - b0
        d = s - breaks[b0 + k]
        rx, ry, rp = r0 + k, r0 + n + k, r0 + 2 * n + k
        x = coefs[rx, 0] + d * (coefs[rx, 1] + d * (coefs[rx, 2] + d * coefs[rx, 3]))
        y = coefs[ry, 0] + d * (coefs[ry, 1] + d * (coefs[ry, 2] + d * coefs[ry, 3]))
        psi = coefs[rp, 0] + d * (coefs[rp, 1] + d * (coefs[rp, 2] + d * coefs[rp, 3]))
        kap = coefs[rp, 1] + d * (2.0 * coefs[rp, 2] + d * 3.0 * coefs[rp, 3])
        return x, y, psi, kap

    @jit
    def project(px, py, s0, q, breaks, coefs):
        # Path._local's Newton iteration for the nearest point: (s, e, psi)
        if q[_Q_PERIOD] > 0.0:
            lo, hi = -np.inf, np.inf
        else:
            lo, hi = q[_Q_S_LO], q[_Q_S_HI]
        s = s0
        for _ in range(_NEWTON_MAXITER):
            fx, fy, psi, kap = frame(table_position(s, q), q, breaks, coefs)
            dx, dy = fx - px, fy - py
            c, sn = math.cos(psi), math.sin(psi)
            g = dx * c + dy * sn
            e = dx * sn - dy * c
            H = 1.0 - kap * e
            if (s <= lo and g >= 0.0) or (s >= hi and g <= 0.0) or H <= 1e-12:
                break
            step = min(max(-g / H, -_WINDOW), _WINDOW)
            new = min(max(s + step, lo), hi)
            done = abs(new - s) <= 1e-12 * (1.0 + abs(e))
            s = new
            if done:
                break
        fx, fy, psi, _ = frame(table_position(s, q), q, breaks, coefs)
        dx, dy = fx - px, fy - py
        return s, dx * math.sin(psi) - dy * math.cos(psi), psi

    @jit
    def law_command(s, e, th, kappa, p, q, breaks, coefs):
        code = int(q[Q_LAW])
        f = q[_Q_WHEELBASE]
        V = p[_P_SPEED]
        a = P_LAW
        if code == _HELD:
            return p[a], p[a + 1]
        if code == _STATE_FEEDBACK:
            cf = feedback_angle(e, th, p[a], p[a + 1])
            if p[a + 4] != 0.0:
                cf = cf + feedforward_angle(f, kappa)
            return cf, feedback_angle(e, th, p[a + 2], p[a + 3])
        if code == _REAR_WHEEL:
            cf = rear_wheel_feedback_angle(V, f, kappa, e, th, p[a], p[a + 1])
            return cf, p[a + 2] * cf
        s_c = table_position(s, q)
        cx, cy, h, _ = frame(s_c, q, breaks, coefs)
        if code == _PURE_PURSUIT:
            ld = lookahead_distance(p[a], p[a + 1], V)
            sp = table_position(s_c + np.sign(V) * lookahead_offset(ld, e), q)
            px, py, _, _ = frame(sp, q, breaks, coefs)
            rx, ry = rear_axle_point(cx, cy, h, e)
            cf = pure_pursuit_angle(f, ld, rx, ry, th + h, px, py)
            return cf, p[a + 2] * cf
        # Stanley: the front axle projected from a wheelbase ahead
        fx, fy, psi = front_axle_point(cx, cy, h, e, th, f)
        guess = table_position(s_c + f * math.cos(th), q)
        if q[_Q_PERIOD] > 0.0:
            guess = s_c + f * math.cos(th)
        _, e_f, h_f = project(fx, fy, guess, q, breaks, coefs)
        cf = stanley_angle(wrap_angle(psi - h_f), e_f, p[a], p[a + 1], V)
        return cf, p[a + 2] * cf

    return law_command


def controller_outputs(
    vehicle, path, controller, *, speed, feedforward, time_constant, states,
    initial_heading, solution, t_eval, t_stop, model, tyre,
):  # fmt: skip
    """Signals and exact peaks of a controller's compiled runs.

    :func:`~fws_control.simulation.engine.compute_outputs` at the output
    times and :func:`~fws_control.simulation.engine.exact_peaks` on each
    run's own dense output (:class:`~fws_control.simulation.dense.CompiledDense`:
    every run on its own steps, all runs at once), the numpy
    engine's signals of the same states. Returns ``(signals, peaks,
    peak_times)``.
    """
    kw = dict(feedforward=feedforward, time_constant=time_constant, model=model,
              tyre=tyre)  # fmt: skip
    signals = compute_outputs(
        vehicle, path, controller, speed=speed, states=states,
        initial_heading=initial_heading, times=t_eval, **kw,
    )  # fmt: skip
    # every run on its own steps, a block of runs at once
    dense = CompiledDense(
        solution.records, solution.offsets, solution.initial_state, float(t_eval[0])
    )
    per_run = controller.runs() is not None

    def subset(lo: int, hi: int) -> Any:
        return controller.subset(np.arange(lo, hi)) if per_run else controller

    peaks, times = exact_peaks_per_run(
        vehicle, path, subset, speed=speed, solution=dense, t_eval=t_eval,
        signals=signals, t_stop=t_stop, **kw,
    )  # fmt: skip
    return signals, peaks, times
