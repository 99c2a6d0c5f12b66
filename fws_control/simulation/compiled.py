r"""Compiled per-run engine: scipy's DOP853 ported to numba, one run at a time.

The numpy engine (:mod:`~fws_control.simulation.engine`) stacks the runs of
a chunk into one state vector and steps them with one scipy solver, so the
step size, the error norm and the restarts after a stop are shared by the
chunk: a run's answer depends on the batch it sits in. This module gives
every run its **own** integration, at compiled speed:

- the closed-loop right-hand side (kinematic path-frame model, corrected
  eqs. 17-19; the paper's law of eqs. 24-29 with the curvature feedforward
  and the steering-angle limits; optionally the rate-limited first-order
  steering actuator of :func:`~fws_control.steering_actuator`) is compiled
  with numba, from the same functions of :mod:`fws_control.equations` that
  the numpy engine and the analysis call;
- it is integrated by a line-by-line port of scipy's
  :class:`~scipy.integrate.DOP853` (same Butcher tableau taken from scipy
  itself, same initial step selection, step-size control, error norm and
  dense output) with :func:`~scipy.integrate.solve_ivp`'s event handling
  (sign change on the accepted step, root by a port of scipy's ``brentq``
  on the dense output with ``xtol = rtol = 4 eps``) and output at ``t_eval``
  from the dense output of the step that holds each time;
- the error norm is scipy's RMS norm over *that run's* states only, and a
  stop ends only that run.

So each run gives exactly what :func:`scipy.integrate.solve_ivp` gives for
it alone with ``method="DOP853"`` and a terminal event per stop condition
(``tests/test_compiled_engine.py`` checks step by step), whatever else is in
the batch.

Stop conditions (each a terminal event, located on the dense output):

======================  ===================================================
status                  event
======================  ===================================================
``singular_steering``   :math:`|\delta_f| = \pi/2 - m_\delta`
``singular_curvature``  :math:`1 - \kappa e = m_\kappa`
``end_of_path``         ``s`` leaves ``[0, length]`` of an open path
======================  ===================================================

The margins :math:`m_\delta, m_\kappa` (default ``1e-3``) stop a run just
before the singularity, where the solution has a square-root singularity
and the step size would collapse; the numpy engine stops at the same places
(it attributes a collapse within ``1e-3`` of the singularity to it).

The path enters only through its curvature :math:`\kappa(s)`, given as a
piecewise cubic table in ``s`` (:func:`curvature_table`): exact for
:class:`~fws_control.Straight`, :class:`~fws_control.Arc`,
:class:`~fws_control.Clothoid` and :class:`~fws_control.PathChain` of them;
a cubic Hermite fit to a stated tolerance for other paths.

The steering-angle and steering-rate limits are switched, not clipped:
where a channel reaches its limit (or leaves it) is located as an event on
the dense output, the step is cut there and the integration restarts with
that channel held at the limit (or free), so that the right-hand side is
smooth within every step (``switching=False`` clips with min/max inside the
right-hand side instead, as the numpy engine does). A channel released from
a limit starts the next step at that limit (to the rounding of the located
switch), so in that step only its opposite limit switches it: a command
that crosses from one limit to the other within a step is then located
there instead of being switched back at the restart without end
(``tests/test_compiled_limits.py``; agreement with the numpy engine on
random rate-limited scenarios: ``benchmarks/bench_limit_agreement.py``).

With ``integrate_compiled(..., solution=[])`` every run's dense output is
kept (:class:`CompiledSolution`), and :func:`compiled_peaks` finds the
exact peaks of each run's continuous solution on it, as
:func:`~fws_control.simulation.engine.exact_peaks` does for the numpy
engine; with it kept the stop conditions are also checked at three points
inside every step (as the numpy engine checks its margins), so that a loose
tolerance cannot step across a singular state and back.

An input delay is integrated by the method of steps, as the numpy engine
does it: the steps are at most the delay, the law acts on the state at
``t - delay`` found on the run's own dense output (the initial state
before the start), DOP853 restarts at ``delay``, ``2 delay`` and ``3
delay``, where the solution's derivatives jump, and the clips are min/max
in the right-hand side (DOP853 only; ``tests/test_compiled_delay.py``);
with the dynamic model and with a controller's law as well
(``tests/test_compiled_dynamic.py``, ``tests/test_compiled_baselines.py``).

The dynamic single-track model (linear or saturating tyre) is compiled from
the same functions of :mod:`fws_control.equations` as
:func:`~fws_control.dynamics.dynamic_path_derivatives` (DOP853;
``tests/test_compiled_dynamic.py``).

A :class:`~fws_control.LateralController` that declares a compiled law
(the baselines: :mod:`~fws_control.simulation.compiled_laws`) runs in the
same right-hand side with DOP853 (``tests/test_compiled_baselines.py``).

A speed that varies along the run (a :class:`~fws_control.SpeedProfile`
table of the time or the arc length) and a
:class:`~fws_control.GainSchedule` read at the current speed are compiled
with DOP853 (:mod:`~fws_control.simulation.compiled_speed`: the tables
follow the curvature table's rows in ``breaks`` and ``coefs``).

Not supported here (the numpy engine remains the general path;
``simulate(..., engine="compiled")`` raises for these, and the default
``engine="auto"`` runs them on the numpy engine): controllers without a
compiled law, a controller's law, a delay or the dynamic model with Radau,
and other solvers than DOP853 and Radau.
A stiff actuator (small time constant) is detected with Hairer's test
(``stiff`` in the statistics of DOP853, whose step is then limited by
stability to about :math:`6\,T`); ``method="Radau"`` integrates it with
scipy's implicit Radau IIA, ported like DOP853 (:func:`radau_run`, the
same steps as scipy's given the analytic Jacobian :func:`closed_loop_jac`),
whose steps follow the accuracy alone (see ``docs/performance.md``).

numba is an optional dependency (extra ``fast``). Without it the module
still imports; :func:`integrate_compiled` raises :class:`ImportError`.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from .. import equations
from ..controllers import steering_command
from ..dynamics import axle_loads, require_dynamics
from ..gains import SteeringGains
from ..hints import RealArrayLike
from ..lateral_controller import LateralController
from ..paths import Arc, Clothoid, Path, PathChain, Straight
from ..validation import check_finite, check_positive
from ..vehicle import Vehicle
from .compilation import compile_seconds, first_use
from .compiled_laws import (
    P_LAW,
    Q_CURVATURE_ROWS,
    Q_LAW,
    initial_command,
    kernel_arrays,
    law_code,
    law_parameters,
)
from .compiled_speed import (
    P_SPEED_TIME,
    compiled_speed_reason,
    speed_tables,
)
from .outcomes import (
    STATUS_END_OF_PATH,
    STATUS_FAILED,
    STATUS_OK,
    STATUS_SINGULAR_CURVATURE,
    STATUS_SINGULAR_STEERING,
    STOP_MARGIN,
)

try:  # optional dependency (extra "fast")
    import numba
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None
from .compiled_dop853 import dense_output, dop853_step, locate_event
from .compiled_drivers import solve_run
from .compiled_layout import (
    NP,
    NPOW,
    NQ,
    NSIG,
    P_K1,
    P_K2,
    P_RATIO,
    P_SPEED,
    Q_C_F,
    Q_C_R,
    Q_CURV_MARGIN,
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
    Q_MAX_STEP,
    Q_METHOD,
    Q_OPEN_LENGTH,
    Q_PEAK_F,
    Q_PEAK_R,
    Q_PERIOD,
    Q_RATE_F,
    Q_RATE_R,
    Q_S_HI,
    Q_S_LO,
    Q_STEER_MARGIN,
    Q_SWITCH,
    Q_TAU,
    Q_WHEELBASE,
    RADAU,
    feedforward_equation,
)
from .compiled_loop import closed_loop_jac, closed_loop_rhs
from .compiled_peaks import N_PEAK
from .compiled_radau import radau_run
from .compiled_variants import FEATURES, features_of, kernels

__all__ = [
    "available",
    "compiling",
    "STAGE_SECONDS",
    "FULL_STAGE_SECONDS",
    "STAGES",
    "CurvatureTable",
    "curvature_table",
    "compiled_support",
    "compiled_method",
    "integrate_compiled",
    "compiled_outputs",
    "compiled_peaks",
    "CompiledSolution",
    "shared_parameters",
    "closed_loop_rhs",
    "closed_loop_jac",
    "radau_run",
    "dop853_step",
    "dense_output",
    "locate_event",
    "solve_run",
    "STATUS_CODES",
    "STAT_FIELDS",
    "pose_signals",
    "DEFAULT_MARGIN",
    "METHODS",
]

#: Status of each integer code returned by the kernels.
STATUS_CODES = (
    STATUS_OK,
    STATUS_SINGULAR_STEERING,
    STATUS_SINGULAR_CURVATURE,
    STATUS_END_OF_PATH,
    STATUS_FAILED,
)

#: Per run statistics returned by :func:`integrate_compiled` (columns).
STAT_FIELDS = ("steps", "rejected", "rhs_evaluations", "stiff", "switches")

#: Integration methods of the compiled engine: scipy's explicit ``DOP853``
#: (with located clip switches and ``max_step``) and its implicit
#: ``Radau`` (order 5, with the analytic :func:`closed_loop_jac`; no
#: ``max_step``), for a loop made stiff by a fast actuator.
METHODS = ("DOP853", "Radau")

#: Default stop margins ``steer_margin`` [rad] and ``curvature_margin`` [-]:
#: the numpy engine's :data:`~fws_control.simulation.engine.STOP_MARGIN`.
DEFAULT_MARGIN = STOP_MARGIN

_MESSAGES = {
    STATUS_SINGULAR_STEERING: "front steering angle reached |delta_f| = pi/2 - "
    "steer_margin, next to the singular yaw rate V*sin(delta_f - delta_r)/"
    "(f*cos(delta_f))",
    STATUS_SINGULAR_CURVATURE: "1 - curvature*e reached curvature_margin: the "
    "vehicle is at the path's centre of curvature and the projection is lost",
    STATUS_END_OF_PATH: "the projection point left the open path",
    STATUS_FAILED: "the ODE solver failed: the step size fell below 10 ulp of t "
    "(scipy's TOO_SMALL_STEP)",
}


def available() -> bool:
    """True if numba is installed, so that :func:`integrate_compiled` runs.

    Examples
    --------
    >>> from fws_control.simulation.compiled import available
    >>> isinstance(available(), bool)
    True
    """
    return numba is not None


#: The compiled engine's stages, each compiled on its first use: the
#: per-run drivers of :data:`METHODS` (integration, events, dense output),
#: the output signals and the exact peaks.
STAGES = (*METHODS, "signals", "peaks")

# CPU seconds each stage takes to compile with an empty cache, for the
# notice's estimate: the kernels specialised to a call without a delay, the
# dynamic model, a controller's law or a varying speed (compiled_variants),
# and the kernels of a call with any of these. Measured with
# benchmarks/bench_first_use.py (its paper scenario, and --case stanley for
# the kernels of every feature; numba 0.68, two cores shared with other
# compilations: an idle machine takes less, by up to 2x); Radau's full
# driver scaled from DOP853's by their earlier ratio.
#: CPU seconds each stage of :data:`STAGES` takes to compile with an empty
#: cache, the kernels of the paper's loop (the notices' estimates).
STAGE_SECONDS = {"DOP853": 35.0, "Radau": 30.0, "signals": 3.0, "peaks": 16.0}
#: The same for the kernels of every feature.
FULL_STAGE_SECONDS = {"DOP853": 89.0, "Radau": 72.0, "signals": 9.0, "peaks": 84.0}

# the features of the call a thread runs, for the estimate (set by the
# kernels' callers below before they enter their stage)
_call = threading.local()


def _stage_kernels(q: np.ndarray) -> Any:
    # the top kernels of the call whose shared parameters are q: those
    # specialised to a call without any of the variants' features (the
    # paper's kinematic loop, the default), else the kernels of every
    # feature. Each variant is a compilation of the whole engine of its own:
    # the calls with a feature share one, as the test suite does.
    features: frozenset[str] = frozenset(FEATURES if features_of(q) else ())
    _call.features = features
    return kernels(_call.features)


def _stage_seconds(stage: str) -> float:
    # the estimate of a stage for the features of the thread's call
    features: frozenset[str] = getattr(_call, "features", frozenset())
    top = kernels(features)
    kernel = {
        "DOP853": top.solve_batch,
        "Radau": top.solve_batch_radau,
        "signals": top.signals_batch,
        "peaks": top.peaks_batch,
    }[stage]
    seconds = FULL_STAGE_SECONDS if features else STAGE_SECONDS
    return compile_seconds(kernel, seconds[stage])


def compiling(*stages: str, features: bool | None = None) -> Any:
    """Context of a call that runs the compiled `stages`, for the notice.

    numba compiles a stage's kernels the first time a call needs them (a
    DOP853 run compiles neither Radau nor, unless asked, the signals and
    peaks). The first compilation in a process is announced on standard
    error with the CPU time the `stages` still to compile take, and closed
    with the time it took (see
    :mod:`~fws_control.simulation.compilation`); nothing is printed when
    they load from the cache.

    Parameters
    ----------
    *stages : str
        Names in :data:`STAGES`.
    features : bool, optional
        Whether the call uses a feature of
        :data:`~fws_control.simulation.compiled_variants.FEATURES` (an
        input delay, the dynamic model, a controller's law, a varying
        speed), whose kernels take longer to compile; the estimate is of
        those kernels then. Default: as the thread's last call.

    Returns
    -------
    context manager

    Raises
    ------
    ValueError
        For a name not in :data:`STAGES`.

    Examples
    --------
    >>> from fws_control.simulation.compiled import compiling
    >>> with compiling("DOP853", "signals"):
    ...     pass
    """
    for stage in stages:
        if stage not in STAGES:
            raise ValueError(f"stages must be in {STAGES}, got {stage!r}")
    if features is not None:
        # (a compilation may start before the call selects its kernels: the
        # notice's estimate then needs the call's features already)
        _call.features = frozenset(FEATURES if features else ())

    def estimate():
        return sum(_stage_seconds(s) for s in stages)

    return first_use(estimate)


# --------------------------------------------------------------------------
# Python side: curvature tables, parameters, the batch driver


class CurvatureTable:
    r"""Curvature :math:`\kappa(s)` of a path as a piecewise cubic in ``s``.

    On ``[breaks[k], breaks[k+1])``, :math:`\kappa = c_0 + c_1 d + c_2 d^2 +
    c_3 d^3` with ``d = s - breaks[k]`` and ``c = coefs[k]``. A closed path
    (``period > 0``) wraps ``s`` modulo the period; an open one clips it to
    ``[breaks[0], breaks[-1]]`` (``-inf``/``inf`` for an unbounded line).

    Attributes
    ----------
    breaks : ndarray
        Shape ``(K + 1,)``, increasing [m].
    coefs : ndarray
        Shape ``(K, 4)`` [1/m, 1/m^2, 1/m^3, 1/m^4].
    period : float
        Length of a closed path [m], 0 for an open one.
    open_length : float
        Length of an open path of finite length [m] (its end is a stop
        event), ``inf`` otherwise.
    max_error : float
        Largest difference to the path's curvature found when the table was
        built [1/m]: 0 for tables that are exact by construction.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled import curvature_table
    >>> tab = curvature_table(fws.Clothoid(0.0, 0.1, length=10.0))
    >>> tab.breaks.tolist(), tab.coefs.tolist(), tab.max_error
    ([0.0, 10.0], [[0.0, 0.01, 0.0, 0.0]], 0.0)
    """

    __slots__ = ("breaks", "coefs", "period", "open_length", "max_error")

    def __init__(
        self,
        breaks: RealArrayLike,
        coefs: RealArrayLike,
        *,
        period: float = 0.0,
        open_length: float = math.inf,
        max_error: float = 0.0,
    ) -> None:
        self.breaks: np.ndarray = np.ascontiguousarray(breaks, dtype=float)
        self.coefs: np.ndarray = np.ascontiguousarray(coefs, dtype=float).reshape(-1, 4)
        if self.breaks.size != self.coefs.shape[0] + 1:
            raise ValueError(
                f"breaks must have one entry more than coefs has rows, got "
                f"{self.breaks.size} and {self.coefs.shape[0]}"
            )
        self.period: float = float(period)
        self.open_length: float = float(open_length)
        self.max_error: float = float(max_error)

    def __call__(self, s: RealArrayLike) -> np.ndarray:
        """Evaluate :math:`\\kappa(s)` (numpy, for checks)."""
        s = np.asarray(s, dtype=float)
        if self.period > 0.0:
            s = np.mod(s, self.period)
            s = np.where(s >= self.period, 0.0, s)
        else:
            s = np.clip(s, self.breaks[0], self.breaks[-1])
        k = np.clip(np.searchsorted(self.breaks, s, side="right") - 1, 0,
                    self.coefs.shape[0] - 1)  # fmt: skip
        d = s - self.breaks[k]
        c = self.coefs[k]
        return c[..., 0] + d * (c[..., 1] + d * (c[..., 2] + d * c[..., 3]))

    def __repr__(self) -> str:
        return (
            f"CurvatureTable(pieces={self.coefs.shape[0]}, period={self.period}, "
            f"open_length={self.open_length}, max_error={self.max_error:.3g})"
        )


def _exact_pieces(path) -> tuple[list[float], list[list[float]]] | None:
    """Breaks and coefficients of an exactly representable path, else None."""
    if isinstance(path, Straight):
        # inf, not None, after Straight.__post_init__
        return [0.0, cast(float, path.length)], [[0.0, 0.0, 0.0, 0.0]]
    if isinstance(path, Arc):
        return [0.0, path.length], [[path.kappa, 0.0, 0.0, 0.0]]
    if isinstance(path, Clothoid):
        return [0.0, path.length], [[path.curvature_start, path.sharpness, 0.0, 0.0]]
    if isinstance(path, PathChain):
        breaks, coefs = [0.0], []
        for seg, off in zip(path.segments, path.offsets[:-1], strict=True):
            sub = _exact_pieces(seg)
            if sub is None:
                return None
            breaks += [float(off) + b for b in sub[0][1:]]
            coefs += sub[1]
        breaks[-1] = float(path.length)
        return breaks, coefs
    return None


def curvature_table(
    path: Path, *, tol: float = 1e-10, max_pieces: int = 1 << 16
) -> CurvatureTable:
    r"""Curvature of `path` as a :class:`CurvatureTable` for the compiled engine.

    Exact for :class:`~fws_control.Straight`, :class:`~fws_control.Arc`,
    :class:`~fws_control.Clothoid` and :class:`~fws_control.PathChain` of
    them. Other paths get a cubic Hermite interpolant of their curvature and
    curvature rate on a uniform grid, refined (doubling) until the
    difference to :meth:`~fws_control.paths.Path.curvature` at the midpoints
    and quarter points of the pieces is at most `tol`.

    Parameters
    ----------
    path : Path
        The reference path.
    tol : float, optional
        Tolerance of the interpolant [1/m], > 0 (not used for exact tables).
    max_pieces : int, optional
        Largest number of pieces tried.

    Returns
    -------
    CurvatureTable

    Raises
    ------
    ValueError
        If the tolerance is not reached with `max_pieces` pieces (then use
        the numpy engine), or `tol` is not > 0.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled import curvature_table
    >>> curvature_table(fws.Arc(curvature=0.1))
    CurvatureTable(pieces=1, period=62.83185307179586, open_length=inf, max_error=0)
    """
    tol = float(check_positive("tol", tol))
    L = float(path.length)
    closed = bool(path.closed)
    period = L if closed else 0.0
    open_length = L if (not closed and math.isfinite(L)) else math.inf
    exact = _exact_pieces(path)
    if exact is not None:
        breaks, coefs = exact
        return CurvatureTable(breaks, coefs, period=period, open_length=open_length)
    if not math.isfinite(L):
        raise ValueError(f"path must have a finite length for a table, got {path!r}")
    # Adaptive bisection: a piece is halved while the interpolant misses the
    # curvature by more than tol at its quarter points. Kinks of the
    # curvature (a spline's curvature rate jumps at its waypoints) end up in
    # tiny pieces; smooth stretches keep long ones.
    s = np.linspace(0.0, L, 65)
    err = math.inf
    while s.size - 1 <= max_pieces:
        table = _hermite_table(path, s, period, open_length)
        h = np.diff(s)
        probe = s[:-1, None] + h[:, None] * np.array([0.25, 0.5, 0.75])
        miss = np.abs(table(probe) - path.curvature(probe))
        err = float(np.max(miss))
        if err <= tol:
            table.max_error = err
            return table
        bad = np.flatnonzero(np.max(miss, axis=1) > tol)
        s = np.sort(np.concatenate([s, s[bad] + 0.5 * h[bad]]))
    raise ValueError(
        f"curvature of {type(path).__name__} not within tol={tol} with "
        f"max_pieces={max_pieces} cubic pieces (last error {err:.3g}); use the "
        "numpy engine for this path"
    )


def _hermite_table(path, s, period, open_length) -> CurvatureTable:
    """Cubic Hermite interpolant of the curvature on the nodes `s`."""
    k = np.asarray(path.curvature(s), dtype=float)
    dk = np.asarray(path.curvature_rate(s), dtype=float)
    h = np.diff(s)
    # one-sided rates at a kink: the right piece uses the rate just after it
    slope = np.diff(k) / h
    c2 = (3 * slope - 2 * dk[:-1] - dk[1:]) / h
    c3 = (dk[:-1] + dk[1:] - 2 * slope) / h**2
    coefs = np.stack([k[:-1], dk[:-1], c2, c3], axis=1)
    return CurvatureTable(s, coefs, period=period, open_length=open_length)


def _rear_to_cg(vehicle: Vehicle) -> float:
    # the distance the signals' lateral velocity and acceleration need
    if vehicle.rear_to_cg is None:
        raise ValueError(
            "vehicle.rear_to_cg must be a distance [m] for the compiled signals, "
            "got None"
        )
    return float(vehicle.rear_to_cg)


def _limit(value) -> float:
    return math.inf if value is None else float(value)


def shared_parameters(
    vehicle: Vehicle,
    table: CurvatureTable,
    *,
    feedforward: bool,
    time_constant: float | None,
    steer_margin: float = DEFAULT_MARGIN,
    curvature_margin: float = DEFAULT_MARGIN,
    switching: bool = False,
    max_step: float = math.inf,
    method: str = "DOP853",
    delay: float = 0.0,
    model: str = "kinematic",
    tyre: str = "linear",
) -> np.ndarray:
    """The parameter vector shared by all runs of a call (for the kernels).

    Parameters
    ----------
    vehicle : Vehicle
        Wheelbase, steering-angle and steering-rate limits.
    table : CurvatureTable
        The path's curvature (its period and open length).
    feedforward : bool
        Curvature feedforward of the paper's law on or off.
    time_constant : float or None
        Actuator lag [s]; None: no actuator (the angles are the commands).
    steer_margin, curvature_margin : float, optional
        Stop margins (see the module notes), >= 0.
    switching : bool, optional
        Locate the switches of the angle and rate clips as events and hold a
        clipped channel by its mode (then the per run parameter vectors have
        8 entries); default False: min/max in the right-hand side.
    max_step : float, optional
        Longest step [s], > 0, as scipy's ``max_step`` (default: none;
        DOP853 only).
    method : {"DOP853", "Radau"}, optional
        Integration method (:data:`METHODS`).
    delay : float, optional
        Input delay [s], >= 0 (default 0): the law acts on the measurements
        of ``t - delay`` (the method of steps: the steps are at most the
        delay). DOP853 without `switching` only.
    model : {"kinematic", "dynamic"}, optional
        Vehicle model; the dynamic single-track model
        (:func:`~fws_control.dynamics.dynamic_path_derivatives`) takes the
        vehicle's mass, yaw inertia and cornering stiffnesses. DOP853 only.
    tyre : {"linear", "magic"}, optional
        Tyre model of the dynamic model (``"magic"``: saturating at the
        friction times the axle's static load).

    Returns
    -------
    ndarray
        Shape ``(44,)``.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled import curvature_table, shared_parameters
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> shared_parameters(veh, curvature_table(fws.Straight()), feedforward=True,
    ...                   time_constant=None)[:3].tolist()
    [2.7, 1.0, inf]
    """
    for name, val in (
        ("steer_margin", steer_margin),
        ("curvature_margin", curvature_margin),
    ):
        if not (isinstance(val, (int, float)) and 0.0 <= val < 1.0):
            raise ValueError(f"{name} must be a number in [0, 1), got {val!r}")
    if not (isinstance(max_step, (int, float)) and max_step > 0.0):
        raise ValueError(f"max_step must be a number > 0 [s], got {max_step!r}")
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if method == "Radau" and max_step != math.inf:
        raise ValueError(
            f"max_step applies to method='DOP853' only, got max_step={max_step!r} "
            "with method='Radau'"
        )
    if not (isinstance(delay, (int, float)) and math.isfinite(delay) and delay >= 0.0):
        raise ValueError(f"delay must be a finite number >= 0 [s], got {delay!r}")
    if model not in ("kinematic", "dynamic"):
        raise ValueError(f"model must be 'kinematic' or 'dynamic', got {model!r}")
    if tyre not in ("linear", "magic"):
        raise ValueError(f"tyre must be 'linear' or 'magic', got {tyre!r}")
    if model == "dynamic" and method != "DOP853":
        raise ValueError(
            f"model='dynamic' is compiled with method='DOP853' only, got {method!r}"
        )
    if delay > 0.0 and (method != "DOP853" or switching):
        raise ValueError(
            f"delay={delay!r} is compiled with method='DOP853' and switching=False "
            f"only, got method={method!r}, switching={switching!r}"
        )
    q = np.empty(NQ)
    q[Q_WHEELBASE] = vehicle.wheelbase
    q[Q_FF] = 1.0 if feedforward else 0.0
    q[Q_MAX_F] = _limit(vehicle.max_steer_front)
    q[Q_MAX_R] = _limit(vehicle.max_steer_rear)
    q[Q_TAU] = 0.0 if time_constant is None else float(time_constant)
    q[Q_RATE_F] = _limit(vehicle.max_steer_rate_front)
    q[Q_RATE_R] = _limit(vehicle.max_steer_rate_rear)
    q[Q_STEER_MARGIN] = steer_margin
    q[Q_CURV_MARGIN] = curvature_margin
    q[Q_PERIOD] = table.period
    if table.period > 0.0:
        q[Q_S_LO], q[Q_S_HI] = 0.0, table.period
    elif math.isfinite(table.open_length):
        q[Q_S_LO], q[Q_S_HI] = 0.0, table.open_length
    else:
        q[Q_S_LO], q[Q_S_HI] = -math.inf, math.inf
    q[Q_OPEN_LENGTH] = table.open_length
    q[Q_SWITCH] = 1.0 if switching else 0.0
    # the method of steps: a stage at t + h needs the state at t + h - delay,
    # known (accepted) only if h <= delay
    q[Q_MAX_STEP] = float(min(max_step, delay)) if delay > 0.0 else float(max_step)
    q[Q_DELAY] = float(delay)
    q[Q_DYNAMIC:] = 0.0  # (with the law slots: the paper's law)
    q[Q_CURVATURE_ROWS] = table.coefs.shape[0]
    if model == "dynamic":
        body = require_dynamics(vehicle, tyre=tyre)
        q[Q_DYNAMIC] = 1.0
        q[Q_MASS] = body.mass
        q[Q_INERTIA] = body.yaw_inertia
        q[Q_L_F] = body.wheelbase - body.rear_to_cg
        q[Q_L_R] = body.rear_to_cg
        q[Q_C_F] = body.cornering_front
        q[Q_C_R] = body.cornering_rear
        if tyre == "magic":
            load_f, load_r = axle_loads(vehicle)
            # (require_dynamics checked the friction of the magic tyre)
            friction = cast(float, vehicle.friction)
            q[Q_PEAK_F] = friction * load_f
            q[Q_PEAK_R] = friction * load_r
    q[Q_METHOD] = float(METHODS.index(method))
    # a curvature equal to the first piece's constant term (every s of an
    # arc or a straight) takes its feedforward angle from here, computed by
    # the kernels' own compiled equation, so the angle is the one they would
    # compute
    k0 = float(table.coefs[0, 0])
    q[Q_KAPPA0] = k0
    q[Q_FF_ANGLE0] = feedforward_equation(vehicle.wheelbase, k0)
    return q


def compiled_method(method: Any) -> str | None:
    """The name in :data:`METHODS` of `method` (a name or scipy's class).

    Parameters
    ----------
    method : str or scipy.integrate.OdeSolver
        A method as :func:`~fws_control.simulate` takes it.

    Returns
    -------
    str or None
        ``"DOP853"`` or ``"Radau"``; None where the compiled engine has no
        such method.

    Examples
    --------
    >>> from scipy.integrate import Radau
    >>> from fws_control.simulation.compiled import compiled_method
    >>> compiled_method(Radau), compiled_method("DOP853"), compiled_method("BDF")
    ('Radau', 'DOP853', None)
    """
    if isinstance(method, str):
        return method if method in METHODS else None
    # (a class: the caller has imported scipy.integrate already)
    from scipy.integrate import DOP853, Radau

    if method is DOP853:
        return "DOP853"
    if method is Radau:
        return "Radau"
    return None


def compiled_support(
    path: Path,
    gains: Any,
    *,
    delay: float = 0.0,
    method: Any = "DOP853",
    model: str = "kinematic",
) -> str | None:
    """Why :func:`integrate_compiled` cannot run this case, or None if it can.

    Parameters
    ----------
    path : Path
        Reference path (any path with a finite length, or Straight/Arc).
    gains : SteeringGains or LateralController
        :class:`~fws_control.SteeringGains` (the paper's law) or a
        controller that declares a compiled law (DOP853).
    delay : float, optional
        Input delay [s]: compiled with DOP853 (the method of steps).
    method : str or scipy.integrate.OdeSolver, optional
        Only :data:`METHODS` (``"DOP853"``, ``"Radau"`` or their classes)
        are compiled; with a delay only DOP853.
    model : {"kinematic", "dynamic"}, optional
        Vehicle model: the dynamic one is compiled with DOP853.

    Returns
    -------
    str or None
        A reason for the numpy engine, or None.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled import compiled_support
    >>> g = fws.SteeringGains(0.1, 0.5, 0.0)
    >>> compiled_support(fws.Straight(), g, delay=0.1) is None
    True
    >>> compiled_support(fws.Straight(), g, delay=0.1, method="Radau")
    "an input delay is compiled with method='DOP853' only, got 'Radau'"
    """
    if numba is None:
        return "numba is not installed (pip install fws-control[fast])"
    code = law_code(gains)
    if code < 0:
        return (
            f"{type(gains).__name__} declares no compiled law "
            "(LateralController.compiled_law)"
        )
    if code > 0 and compiled_method(method) != "DOP853":
        return (
            "a controller's compiled law runs with method='DOP853' only, got "
            f"method={method!r}"
        )
    if compiled_method(method) is None:
        return f"only method={METHODS} is compiled, got {method!r}"
    if delay != 0.0 and compiled_method(method) != "DOP853":
        return f"an input delay is compiled with method='DOP853' only, got {method!r}"
    if model == "dynamic" and compiled_method(method) != "DOP853":
        return f"model='dynamic' is compiled with method='DOP853' only, got {method!r}"
    if model not in ("kinematic", "dynamic"):
        return f"model={model!r} is not compiled"
    if _exact_pieces(path) is None and not math.isfinite(float(path.length)):
        return "an unbounded path other than Straight has no curvature table"
    return None


def integrate_compiled(
    vehicle: Vehicle,
    path: Path | CurvatureTable,
    gains: SteeringGains | LateralController,
    *,
    speed: np.ndarray,
    feedforward: bool,
    path_state: np.ndarray,
    t_eval: np.ndarray,
    time_constant: float | None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    steer_margin: float = DEFAULT_MARGIN,
    curvature_margin: float = DEFAULT_MARGIN,
    switching: bool | None = None,
    max_step: float = math.inf,
    method: str = "DOP853",
    out: np.ndarray | None = None,
    solution: list | None = None,
    delay: float = 0.0,
    model: str = "kinematic",
    tyre: str = "linear",
    body_state: np.ndarray | None = None,
    profile: Any = None,
    schedule: Any = None,
    actuator_state: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``n`` runs, each with its own steps and events.

    Same arguments and results as
    :func:`~fws_control.simulation.engine.integrate` (with a delay without
    its six rows of the delayed state: :func:`compiled_outputs` finds it on
    the `solution`), plus the per run solver statistics.

    Parameters
    ----------
    vehicle : Vehicle
        Shared by all runs.
    path : Path or CurvatureTable
        The reference path (its :func:`curvature_table` is built), or a
        table built once for many calls.
    gains : SteeringGains or LateralController
        Per run ``k1, k2, ratio`` (arrays of shape ``(n,)`` or scalars), or a
        controller with a compiled law (then `path` must be the path, whose
        position and heading the law may read).
    speed : ndarray
        Per run speed [m/s], shape ``(n,)``; its size is the number of runs.
    feedforward : bool
        Curvature feedforward on or off (all runs).
    path_state : ndarray
        Initial ``(s, e, theta)`` per run, shape ``(n, 3)``.
    t_eval : ndarray
        Output times, increasing; the runs go from ``t_eval[0]`` to
        ``t_eval[-1]``.
    time_constant : float or None
        Actuator lag [s]; None: no actuator. The actuator states start at
        the initial command.
    rtol, atol : float, optional
        Tolerances of the method (scipy's meaning), > 0.
    steer_margin, curvature_margin : float, optional
        Stop margins, in [0, 1) (see the module notes).
    switching : bool, optional
        Locate where the steering-angle and steering-rate limits start and
        stop clipping as events and restart the step there (the default
        without a delay), so that the right-hand side is smooth within every
        step; False (the default with a delay, the only choice there): clip
        with min/max inside the right-hand side, as the numpy engine does
        (its kinks then fall inside steps).
    max_step : float, optional
        Longest step [s], as scipy's ``max_step`` (default: none). Half the
        actuator's stability bound, ``3.2 T``, keeps DOP853's error estimate
        valid on a stiff loop (see
        :func:`~fws_control.simulation.engine.choose_method`). DOP853 only.
    method : {"DOP853", "Radau"}, optional
        :data:`METHODS`: scipy's ``DOP853`` (default) or its implicit
        ``Radau`` with the analytic Jacobian :func:`closed_loop_jac`, the
        same steps as :class:`scipy.integrate.Radau` given that Jacobian
        (its first step from scipy's rule for order 3; a clip switch
        restarts it like a new solver). Its dense output is the cubic
        collocation polynomial, read by events, outputs and
        :func:`compiled_peaks` as DOP853's.
    out : ndarray, optional
        Preallocated ``(n, m, T)`` float array for the states (``m = 3``, or
        5 with an actuator), e.g. a slice of a larger result or a
        memory-mapped file; NaN after each run's stop.
    solution : list, optional
        If given, a :class:`CompiledSolution` (each run's dense output, for
        :func:`compiled_peaks`) is appended to it, as
        ``engine.integrate(..., solution=[])`` does. Keeping it costs the
        dense output of the steps that hold no output time and about
        ``8 (m + 1)`` floats per step.
    delay : float, optional
        Input delay [s] on the steering command (default 0), as
        :func:`~fws_control.simulation.engine.integrate` takes it: the law
        acts on the measurements of ``t - delay``, the initial state's
        before the start; the method of steps (steps of at most the delay,
        each run's past from its own dense output, DOP853 restarted at
        ``delay``, ``2 delay`` and ``3 delay``). DOP853 only.
    model, tyre : str, optional
        Vehicle model and tyre (see :func:`shared_parameters`); the dynamic
        model adds the rows ``v_y, r`` last. DOP853 only.
    body_state : ndarray, optional
        Initial ``(v_y, r)`` per run of the dynamic model, shape ``(n, 2)``;
        where NaN (or None): the no-slip motion at the initial steering, as
        :func:`~fws_control.simulation.engine.integrate`.
    profile : SpeedProfile, optional
        A speed that varies along the run, a table of the time or the arc
        length (:mod:`~fws_control.simulation.compiled_speed`); each run's
        `speed` is then the profile's at its start. DOP853 only.
    schedule : GainSchedule, optional
        With a `profile`: gains read at the current speed instead of
        `gains` (each run's start gains are the schedule's at its start).
    actuator_state : ndarray, optional
        Initial ``(delta_f, delta_r)`` of the actuator per run, finite, shape
        ``(n, 2)``, with a `time_constant` (default: the initial command,
        so that the actuator has no transient of its own); the dynamic
        model's no-slip start is then at these angles.

    Returns
    -------
    states : ndarray
        Shape ``(m, n, T)`` (a transposed view of `out`), NaN after a run's
        stop.
    status, message : ndarray of object
        Per run status (one of :data:`STATUS_CODES`) and explanation.
    t_stop : ndarray
        Per run end time [s].
    stats : ndarray
        Shape ``(n, 5)``, columns :data:`STAT_FIELDS`.

    Raises
    ------
    ImportError
        If numba is not installed.
    ValueError
        For non-positive tolerances, margins out of range, or shapes that do
        not match.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import integrate_compiled
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(np.array([0.1, 0.1]), 0.5, 0.0)
    >>> states, status, _, t_stop, stats = integrate_compiled(
    ...     veh, fws.Straight(), g, speed=np.array([5.0, 5.0]), feedforward=False,
    ...     path_state=np.array([[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]]),
    ...     t_eval=np.linspace(0.0, 1.0, 11), time_constant=None)
    >>> states.shape, status.tolist(), t_stop.tolist()
    ((3, 2, 11), ['ok', 'ok'], [1.0, 1.0])
    """
    if numba is None:
        raise ImportError(
            "integrate_compiled needs numba: pip install fws-control[fast]"
        )
    table = path if isinstance(path, CurvatureTable) else curvature_table(path)
    rtol = float(check_positive("rtol", rtol))
    atol = float(check_positive("atol", atol))
    if switching is None:
        switching = not (isinstance(delay, (int, float)) and delay > 0.0)
    q = shared_parameters(
        vehicle,
        table,
        feedforward=feedforward,
        time_constant=time_constant,
        steer_margin=steer_margin,
        curvature_margin=curvature_margin,
        switching=switching,
        max_step=max_step,
        method=method,
        delay=delay,
        model=model,
        tyre=tyre,
    )
    speed = np.ascontiguousarray(speed, dtype=float).ravel()
    n = speed.size
    code = law_code(gains)
    if code < 0:
        raise ValueError(
            f"gains must be SteeringGains or a controller with a compiled law, "
            f"got {type(gains).__name__}"
        )
    q[Q_LAW] = code
    breaks, coefs = kernel_arrays(path, table, code, q)
    z0 = np.asarray(path_state, dtype=float)
    if z0.shape != (n, 3):
        raise ValueError(f"path_state must have shape ({n}, 3), got {z0.shape}")
    t_eval = np.ascontiguousarray(t_eval, dtype=float)
    if profile is not None and not profile.is_constant:
        reason = compiled_speed_reason(profile, schedule, method=method)
        if reason is not None:
            raise ValueError(f"profile: {reason}")
        breaks, coefs = speed_tables(breaks, coefs, profile, schedule, q)
        # each run's speed (and scheduled gains) at its start
        x0 = t_eval[:1] if profile.of == "time" else z0[:, 0]
        speed = np.ascontiguousarray(np.broadcast_to(profile(x0), (n,)), dtype=float)
        if schedule is not None:
            gains = schedule.at(speed)
    P = _run_parameters(gains, speed)
    P[:, P_SPEED_TIME] = t_eval[0]
    T = t_eval.size
    dyn = model == "dynamic"
    m = (3 if time_constant is None else 5) + (2 if dyn else 0)
    Y0 = np.empty((n, m))
    Y0[:, :3] = z0
    if actuator_state is not None and time_constant is None:
        raise ValueError(
            "actuator_state needs an actuator: a time_constant > 0 s, got "
            "time_constant=None"
        )
    if (time_constant is not None or dyn) and code > 0:
        cmd = initial_command(vehicle, path, gains, z0, table(z0[:, 0]), speed)
    elif time_constant is not None or dyn:
        kappa = table(z0[:, 0])
        cmd = steering_command(
            vehicle,
            SteeringGains(P[:, P_K1], P[:, P_K2], P[:, P_RATIO]),
            z0[:, 1],
            z0[:, 2],
            curvature=kappa,
            feedforward=feedforward,
        )
    if actuator_state is not None:
        act = np.asarray(check_finite("actuator_state", actuator_state), dtype=float)
        if act.shape != (n, 2):
            raise ValueError(
                f"actuator_state must have shape ({n}, 2), got {act.shape}"
            )
        Y0[:, 3:5] = act
        cmd = (act[:, 0], act[:, 1])  # (the wheels' angles: the body's start)
    elif time_constant is not None:
        # The actuator starts at the command: no initial transient of its own.
        Y0[:, 3:5] = np.stack(cmd, axis=1)
    if dyn:
        # the no-slip motion at the initial steering, where not given
        with np.errstate(invalid="ignore"):
            vy0, r0 = equations.no_slip_body_state(
                speed, vehicle.wheelbase, _rear_to_cg(vehicle), cmd[0], cmd[1]
            )
        if body_state is not None:
            body = np.asarray(body_state, dtype=float)
            if body.shape != (n, 2):
                raise ValueError(
                    f"body_state must have shape ({n}, 2), got {body.shape}"
                )
            vy0 = np.where(np.isfinite(body[:, 0]), body[:, 0], vy0)
            r0 = np.where(np.isfinite(body[:, 1]), body[:, 1], r0)
        Y0[:, m - 2], Y0[:, m - 1] = vy0, r0
    if out is None:
        out = np.empty((n, m, T))
    elif out.shape != (n, m, T) or out.dtype != np.float64:
        raise ValueError(
            f"out must be a float64 array of shape {(n, m, T)}, got "
            f"{out.dtype} {out.shape}"
        )
    codes = np.empty(n, dtype=np.int64)
    t_stop = np.empty(n)
    stats = np.empty((n, len(STAT_FIELDS)), dtype=np.int64)
    keep = solution is not None
    offsets = np.empty(n + 1, dtype=np.int64)
    # (room for ~64 steps per run; the kernel doubles it when needed)
    rec = np.empty((64 * n if keep else 0, 2 + (NPOW + 1) * m))
    top = _stage_kernels(q)
    solve = top.solve_batch_radau if q[Q_METHOD] == RADAU else top.solve_batch
    with compiling(METHODS[int(q[Q_METHOD])]):
        rec = solve(
            Y0, P, q, breaks, coefs, t_eval, rtol, atol, out, codes, t_stop, stats,
            rec, offsets, keep,
        )  # fmt: skip
    if solution is not None:  # (keep)
        solution.append(
            CompiledSolution(
                records=rec[: offsets[-1]],
                offsets=offsets,
                initial_state=Y0,
                delay=float(q[Q_DELAY]),
            )  # fmt: skip
        )
    status = np.array([STATUS_CODES[c] for c in codes], dtype=object)
    message = np.array(
        [
            "" if c == 0 else f"at t={ts:.6g} s: {_MESSAGES[STATUS_CODES[c]]}"
            for c, ts in zip(codes, t_stop, strict=True)
        ],
        dtype=object,
    )
    return np.moveaxis(out, 1, 0), status, message, t_stop, stats


def _run_parameters(
    gains: SteeringGains | LateralController, speed: np.ndarray
) -> np.ndarray:
    n = speed.size
    P = np.zeros((n, NP))  # clip modes 0
    P[:, P_SPEED] = speed
    if not isinstance(gains, SteeringGains):  # a controller's compiled law
        P[:, P_LAW : P_LAW + 6] = law_parameters(gains, n)
        return P
    # (a gain of one value or one per run; an assignment broadcasts it)
    P[:, P_K1] = np.ravel(gains.k1)
    P[:, P_K2] = np.ravel(gains.k2)
    P[:, P_RATIO] = np.ravel(gains.ratio)
    return P


def _law_arrays(
    gains: Any, path: Any, table: CurvatureTable, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    # the law's code into q and the kernels' breaks and coefs (a geometry
    # table after the curvature's for a law that reads the path's position)
    code = law_code(gains)
    if code < 0:
        raise ValueError(
            "gains must be SteeringGains or a controller with a compiled law, "
            f"got {type(gains).__name__}"
        )
    q[Q_LAW] = code
    return kernel_arrays(path, table, code, q)


def compiled_outputs(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains | LateralController,
    *,
    speed: np.ndarray,
    feedforward: bool,
    time_constant: float | None,
    states: np.ndarray,
    initial_heading: np.ndarray,
    table: CurvatureTable | None = None,
    out: np.ndarray | None = None,
    solution: CompiledSolution | None = None,
    t_eval: np.ndarray | None = None,
    model: str = "kinematic",
    tyre: str = "linear",
    pose: bool = True,
) -> np.ndarray:
    """All signals of :data:`~fws_control.simulation.engine.SIGNALS`, compiled.

    The compiled counterpart of
    :func:`~fws_control.simulation.engine.compute_outputs` for the paper's
    law and a controller's compiled law: ``s, e, theta``, the steering
    angles, their rates (chain rule through the law and the curvature
    table's derivative; for the controllers without an analytic rate the
    central difference of
    :meth:`~fws_control.LateralController.steering_rate`; zero where an
    angle is clipped; the actuator's rates with an actuator), the lateral
    acceleration of eq. (13), ``v_y``, the yaw rate of eq. (10) and the slip
    angles (0: the kinematic model has no slip) are computed per output time
    in compiled code;
    the global pose ``x, y, psi`` from the path's position and heading at
    ``s`` (numpy), with ``psi`` unwrapped in time on the branch of the
    initial heading.

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, time_constant
        As given to :func:`integrate_compiled`.
    states : ndarray
        Its states, shape ``(m, n, T)``, NaN after a run's stop.
    initial_heading : ndarray
        Per run initial ``psi`` [rad], shape ``(n,)``.
    table : CurvatureTable, optional
        The path's table, if already built.
    out : ndarray, optional
        Preallocated ``(n, len(SIGNALS), T)`` float array for the result.
    solution : CompiledSolution, optional
        The integration's solution; needed with an input delay (its
        ``delay``), where the law acts on the state at ``t - delay`` and
        the rates of the angles are those of that state, found on the runs'
        dense output (as the delayed rows of the numpy engine).
    t_eval : ndarray, optional
        The output times of `states` (needed with an input delay).
    model, tyre : str, optional
        As given to :func:`integrate_compiled`; with the dynamic model
        ``v_y`` and the yaw rate are its states, the slip angles those of
        its axles and the lateral acceleration ``dv_y/dt + u r``.
    pose : bool, optional
        If False, the rows ``x, y, psi`` are left unset (for a caller that
        fills them once for several calls, :func:`pose_signals`).

    Returns
    -------
    ndarray
        Shape ``(n, len(SIGNALS), T)``, NaN where `states` is NaN.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import compiled_outputs
    >>> from fws_control.simulation.engine import SIGNALS
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, 0.0)
    >>> states = np.array([0.0, 2.0, 0.0]).reshape(3, 1, 1)   # s, e, theta
    >>> sig = compiled_outputs(veh, fws.Straight(), g, speed=np.array([5.0]),
    ...                        feedforward=False, time_constant=None,
    ...                        states=states, initial_heading=np.array([0.0]))
    >>> float(sig[0, SIGNALS.index("delta_f"), 0])   # -k1 * e
    -0.2
    """
    if numba is None:
        raise ImportError("compiled_outputs needs numba: pip install fws-control[fast]")
    table = curvature_table(path) if table is None else table
    delay = 0.0 if solution is None else solution.delay
    q = shared_parameters(
        vehicle, table, feedforward=feedforward, time_constant=time_constant,
        delay=delay, model=model, tyre=tyre,
    )  # fmt: skip
    breaks, coefs = _law_arrays(gains, path, table, q)
    speed = np.ascontiguousarray(speed, dtype=float).ravel()
    P = _run_parameters(gains, speed)
    st = np.moveaxis(np.asarray(states, dtype=float), 0, 1)  # (n, m, T)
    n, m, T = st.shape
    if n != speed.size:
        raise ValueError(f"states must hold {speed.size} runs, got {n}")
    if out is None:
        out = np.empty((n, NSIG, T))
    elif out.shape != (n, NSIG, T) or out.dtype != np.float64:
        raise ValueError(
            f"out must be a float64 array of shape {(n, NSIG, T)}, got "
            f"{out.dtype} {out.shape}"
        )
    # the pose in the kernels for Straight and Arc, else pose_signals (numpy)
    if pose and isinstance(path, Straight):
        kind = np.array([1.0, *path.start, path.start_heading, 0.0])
    elif pose and isinstance(path, Arc):
        kind = np.array([2.0, *path.start, path.start_heading, path.kappa])
    else:
        kind = np.zeros(5)
    top = _stage_kernels(q)
    with compiling("signals"):
        top.signals_batch(st, P, q, breaks, coefs, _rear_to_cg(vehicle), kind, out)
        if solution is not None and delay > 0.0:  # (a delay: a solution)
            if t_eval is None or t_eval.shape != (T,):
                raise ValueError(
                    f"t_eval must be the {T} output times of the states with an "
                    f"input delay, got {None if t_eval is None else t_eval.shape}"
                )
            top.delayed_signals_batch(
                st, P, q, breaks, coefs, _rear_to_cg(vehicle),
                np.ascontiguousarray(solution.records), solution.offsets,
                np.ascontiguousarray(solution.initial_state, dtype=float),
                np.ascontiguousarray(t_eval, dtype=float), out,
            )  # fmt: skip
    if pose and kind[0] == 0.0:
        pose_signals(path, table, out, initial_heading)
    elif pose:
        _psi_on_branch(out, initial_heading)
    return out


def pose_signals(
    path: Path, table: CurvatureTable, signals: np.ndarray, initial_heading: Any
) -> None:
    """Fill the rows ``x, y, psi`` of `signals` from its rows ``s, e, theta``.

    In place, on every run and time where ``s`` is finite: the global pose
    of the rear axle from the path's position and heading at ``s`` (numpy,
    ``s`` clipped to an open path's ends), ``psi`` unwrapped in time (a
    stopped run's NaN tail held at its last value) on the branch of each
    run's `initial_heading`.

    Parameters
    ----------
    path : Path
        The reference path.
    table : CurvatureTable
        Its curvature table (its period and open length).
    signals : ndarray
        Shape ``(n, len(SIGNALS), T)`` in the order of
        :data:`~fws_control.simulation.outcomes.SIGNALS`.
    initial_heading : array_like
        Per run initial ``psi`` [rad], shape ``(n,)``.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import curvature_table, pose_signals
    >>> path = fws.Arc(curvature=0.1)
    >>> sig = np.full((1, 15, 1), np.nan)
    >>> sig[0, 3:6, 0] = [5 * np.pi, 0.0, 0.0]   # s, e, theta: a quarter turn
    >>> pose_signals(path, curvature_table(path), sig, [0.0])
    >>> np.round(sig[0, :3, 0], 9).tolist()        # x, y, psi (radius 10 m)
    [10.0, 10.0, 1.570796327]
    """
    out = signals
    n, _, T = out.shape
    S = out[:, 3]
    valid = np.isfinite(S)
    s_path = S[valid]
    if table.period == 0.0 and math.isfinite(table.open_length):
        s_path = np.clip(s_path, 0.0, table.open_length)
    heading = np.asarray(path.heading(s_path), dtype=float)
    px, py = path.position(s_path)
    e = out[:, 4][valid]
    out[:, 0][valid] = px - e * np.sin(heading)
    out[:, 1][valid] = py + e * np.cos(heading)
    psi = np.full((n, T), np.nan)
    psi[valid] = out[:, 5][valid] + heading
    idx = np.where(valid, np.arange(T), 0)
    np.maximum.accumulate(idx, axis=1, out=idx)
    filled = np.nan_to_num(np.take_along_axis(psi, idx, axis=1))
    out[:, 2] = np.where(valid, np.unwrap(filled, axis=1), np.nan)
    _psi_on_branch(out, initial_heading)


def _psi_on_branch(signals: np.ndarray, initial_heading: Any) -> None:
    # the row psi of each run shifted by whole turns onto the branch of the
    # run's initial heading (in place)
    psi0 = np.asarray(initial_heading, dtype=float)
    shift = 2 * math.pi * np.round((psi0 - signals[:, 2, 0]) / (2 * math.pi))
    signals[:, 2] += np.nan_to_num(shift)[:, None]


@dataclass(frozen=True)
class CompiledSolution:
    """Each run's continuous solution from :func:`integrate_compiled`.

    Attributes
    ----------
    records : ndarray
        One row per accepted step (or step cut at a switch or a stop):
        ``t_old, h``, the state at ``t_old`` (``m`` values) and the ``7 m``
        coefficients of DOP853's dense output (scipy's ``F``, row-major);
        the row holds the solution from its ``t_old`` to the next row's
        ``t_old`` (the run's ``t_stop`` for its last row).
    offsets : ndarray
        Run ``i`` owns rows ``offsets[i]:offsets[i + 1]``, shape ``(n + 1,)``.
    initial_state : ndarray
        The runs' initial states, shape ``(n, m)``.
    delay : float
        The input delay of the integration [s] (0: none).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import integrate_compiled
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sol = []
    >>> _ = integrate_compiled(
    ...     veh, fws.Straight(), fws.SteeringGains(0.1, 0.5, 0.0),
    ...     speed=np.array([5.0]), feedforward=False,
    ...     path_state=np.array([[0.0, 1.0, 0.0]]),
    ...     t_eval=np.linspace(0.0, 1.0, 11), time_constant=None, solution=sol)
    >>> sol[0].records.shape[1], sol[0].offsets.tolist() == [0, len(sol[0].records)]
    (26, True)
    """

    records: np.ndarray
    offsets: np.ndarray
    initial_state: np.ndarray
    delay: float = 0.0


def compiled_peaks(
    vehicle: Vehicle,
    path: Path | CurvatureTable,
    gains: SteeringGains | LateralController,
    *,
    speed: np.ndarray,
    feedforward: bool,
    time_constant: float | None,
    solution: CompiledSolution,
    t_eval: np.ndarray,
    signals: np.ndarray,
    t_stop: np.ndarray,
    model: str = "kinematic",
    tyre: str = "linear",
) -> tuple[np.ndarray, np.ndarray]:
    r"""Peaks ``max |signal|`` of each run's continuous solution (compiled).

    The compiled counterpart of
    :func:`~fws_control.simulation.engine.exact_peaks`, with the same
    definition: for each signal of
    :data:`~fws_control.simulation.engine.PEAK_SIGNALS` the largest
    absolute value over ``[t0, t_stop]`` of the run, found on the run's own
    DOP853 dense output (its :class:`CompiledSolution`). The signals are
    first evaluated at 8 nodes per step and at the stop -- in a step whose
    output samples leave no gap wider than those nodes' spacing, at the
    step's start and those samples instead (already computed: on the
    paper's scenarios, 0.01 s apart in steps of 0.1-0.4 s); the 3 largest
    local maxima of the nodes (between their neighbours) and the largest
    output sample (between its neighbours) are then refined by Brent's
    bounded search (scipy's ``fminbound`` algorithm, tolerance
    :math:`\sqrt{\epsilon}\max(|t|, 1\,\mathrm{s})`), keeping the best of
    all evaluations. A signal that is not finite where the state is has the
    peak ``inf`` there. The peaks depend on the output grid only within
    that tolerance (at a smooth maximum about 1e-13 relative; at a corner,
    such as a kink of a spline's curvature table or a joint of two
    clothoids, up to the signal's slope times the time tolerance, as
    ``tests/test_baselines.py`` checks for a steering peak at such a joint).

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, time_constant
        As given to :func:`integrate_compiled` (`path` may be its table).
    solution : CompiledSolution
        From ``integrate_compiled(..., solution=[])``.
    t_eval : ndarray
        Its output times.
    signals : ndarray
        :func:`compiled_outputs` of its states, ``(n, len(SIGNALS), T)``.
    t_stop : ndarray
        Per run end time, from :func:`integrate_compiled`.
    model, tyre : str, optional
        As given to :func:`integrate_compiled`.

    Returns
    -------
    values, times : ndarray
        Shape ``(n, len(PEAK_SIGNALS))``: the peak of ``|signal|`` and the
        time at which it occurs.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import (
    ...     compiled_outputs, compiled_peaks, integrate_compiled)
    >>> from fws_control.simulation.engine import PEAK_SIGNALS
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, 0.0)
    >>> kw = dict(speed=np.array([5.0]), feedforward=False, time_constant=None)
    >>> t, sol = np.linspace(0.0, 10.0, 11), []       # a coarse grid: 1 s
    >>> states, _, _, t_stop, _ = integrate_compiled(
    ...     veh, fws.Straight(), g, path_state=np.array([[0.0, 1.0, 0.0]]),
    ...     t_eval=t, solution=sol, **kw)
    >>> sig = compiled_outputs(veh, fws.Straight(), g, states=states,
    ...                        initial_heading=np.zeros(1), **kw)
    >>> val, when = compiled_peaks(veh, fws.Straight(), g, solution=sol[0],
    ...                            t_eval=t, signals=sig, t_stop=t_stop, **kw)
    >>> j = PEAK_SIGNALS.index("delta_f_rate")
    >>> bool(0.0 < when[0, j] < 1.0)      # the rate peaks between samples
    True
    """
    if numba is None:
        raise ImportError("compiled_peaks needs numba: pip install fws-control[fast]")
    table = path if isinstance(path, CurvatureTable) else curvature_table(path)
    q = shared_parameters(
        vehicle, table, feedforward=feedforward, time_constant=time_constant,
        delay=solution.delay, model=model, tyre=tyre,
    )  # fmt: skip
    breaks, coefs = _law_arrays(gains, path, table, q)
    speed = np.ascontiguousarray(speed, dtype=float).ravel()
    n = speed.size
    P = _run_parameters(gains, speed)
    Y0 = np.ascontiguousarray(solution.initial_state, dtype=float)
    m = (3 if time_constant is None else 5) + (2 if model == "dynamic" else 0)
    if Y0.shape != (n, m) or solution.offsets.shape != (n + 1,):
        raise ValueError(
            f"solution must hold {n} runs of {m} states, got initial states of "
            f"shape {Y0.shape}"
        )
    t_eval = np.ascontiguousarray(t_eval, dtype=float)
    signals = np.asarray(signals, dtype=float)
    if signals.shape != (n, NSIG, t_eval.size):
        raise ValueError(
            f"signals must have shape {(n, NSIG, t_eval.size)}, got {signals.shape}"
        )
    values = np.empty((n, N_PEAK))
    times = np.empty((n, N_PEAK))
    top = _stage_kernels(q)
    with compiling("peaks"):
        top.peaks_batch(
            np.ascontiguousarray(solution.records), solution.offsets, Y0, P, q,
            breaks, coefs, _rear_to_cg(vehicle), t_eval, signals,
            np.ascontiguousarray(t_stop, dtype=float), values, times,
        )  # fmt: skip
    return values, times
