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
in the right-hand side (DOP853 only; ``tests/test_compiled_delay.py``).

The dynamic single-track model (linear or saturating tyre) is compiled from
the same functions of :mod:`fws_control.equations` as
:func:`~fws_control.dynamics.dynamic_path_derivatives` (DOP853, no delay;
``tests/test_compiled_dynamic.py``).

A :class:`~fws_control.LateralController` that declares a compiled law
(the baselines: :mod:`~fws_control.simulation.compiled_laws`) runs in the
same right-hand side with DOP853 and without a delay
(``tests/test_compiled_baselines.py``).

A speed that varies along the run (a :class:`~fws_control.SpeedProfile`
table of the time or the arc length) and a
:class:`~fws_control.GainSchedule` read at the current speed are compiled
with DOP853 (:mod:`~fws_control.simulation.compiled_speed`: the tables
follow the curvature table's rows in ``breaks`` and ``coefs``).

Not supported here (the numpy engine remains the general path;
``simulate(..., engine="compiled")`` raises for these, and the default
``engine="auto"`` runs them on the numpy engine): controllers without a
compiled law, a controller's law with Radau or a delay, a delay with Radau
or with the dynamic model, the dynamic model with Radau, and other solvers
than DOP853 and Radau.
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
import types
from dataclasses import dataclass
from typing import Any

import numpy as np

# The tableau of scipy's DOP853 itself, so that the port takes exactly the
# same steps (a private scipy module: the test suite checks the port step by
# step against scipy.integrate.DOP853, so a change there cannot go unseen).
from scipy.integrate import DOP853, Radau
from scipy.integrate._ivp import dop853_coefficients as _dop

from .. import equations
from ..controllers import steering_command
from ..dynamics import axle_loads, require_dynamics
from ..gains import SteeringGains
from ..hints import RealArrayLike
from ..paths import Arc, Clothoid, Path, PathChain, Straight
from ..validation import check_positive
from ..vehicle import Vehicle
from .compilation import compile_seconds, first_use, jit
from .compiled_laws import (
    P_LAW,
    Q_CURVATURE_ROWS,
    Q_LAW,
    initial_command,
    kernel_arrays,
    law_code,
    law_parameters,
    make_law_command,
)
from .compiled_speed import (
    P_SPEED_TIME,
    Q_PROFILE,
    compiled_speed_reason,
    speed_and_gains,
    speed_tables,
)
from .engine import (
    PEAK_SIGNALS,
    SIGNALS,
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

__all__ = [
    "available",
    "compiling",
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


def _jit(fn, inline="never"):
    # compilation.jit: numba.njit(nogil=True, error_model="numpy") with the
    # on-disk cache in fws_control's own folder (compilation.cache_dir), so
    # that the compilation (seconds) is paid once per machine and numba
    # version, not once per process, and never written into the package.
    return jit(fn, inline=inline)


def _jit_inline(fn):
    # As _jit, and numba inlines the kernel into every compiled caller (at
    # numba-IR level; a direct call from Python still works, with _jit's
    # settings). Inlined, the kernel takes its caller's error_model and
    # nogil: every caller here is compiled with _jit. For the small
    # kernels called once per right-hand side, output time or peak
    # evaluation: LLVM did not inline these calls between numba functions
    # (seen in the machine code), and each call passes every array as a
    # struct and increments and decrements its reference count, two atomic
    # operations per array that numba does not remove across a call. The
    # same operations in the same order, so the results are bit for bit
    # those of the calls (checked on arcs, a straight, a clothoid, angle
    # and rate limits with an actuator under DOP853 and Radau, and stops).
    # Measured on the paper's curve at 4000 runs (best of 5, interleaved
    # with a copy of the package without the inlining): the
    # integration 0.86x, the output stage 0.94x, the exact peaks 0.87x,
    # simulate_batch 0.91x. The cost: the first default simulate with an
    # empty cache took 22.5-23.5 instead of 16.4-17.0 s of CPU.
    # Not for _curvature, _wrap_lap and _feedforward_angle: inlined into
    # the right-hand side as well, they made the integration 1.07x slower.
    return _jit(fn, inline="always")


#: The compiled engine's stages, each compiled on its first use: the
#: per-run drivers of :data:`METHODS` (integration, events, dense output),
#: the output signals and the exact peaks.
STAGES = (*METHODS, "signals", "peaks")

# CPU seconds each stage takes to compile with an empty cache, for the
# notice's estimate: rounded from the stage times that
# benchmarks/bench_first_use.py prints (numba 0.68; they vary with the
# machine and its load, by 2-3x on a busy one).
_STAGE_SECONDS = {"DOP853": 12.0, "Radau": 10.0, "signals": 1.0, "peaks": 6.0}


def _stage_kernel(stage):
    # the top-level kernel of a stage (module globals, defined below)
    return {
        "DOP853": _solve_batch,
        "Radau": _solve_batch_radau,
        "signals": _signals_batch,
        "peaks": _peaks_batch,
    }[stage]


def compiling(*stages: str) -> Any:
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

    def estimate():
        return sum(compile_seconds(_stage_kernel(s), _STAGE_SECONDS[s]) for s in stages)

    return first_use(estimate)


# --------------------------------------------------------------------------
# DOP853 tableau (scipy's), as module constants frozen into the kernels

_NS = _dop.N_STAGES  # 12
_A = np.ascontiguousarray(_dop.A[:_NS, :_NS])
_B = np.ascontiguousarray(_dop.B)
_C = np.ascontiguousarray(_dop.C[:_NS])
_E3 = np.ascontiguousarray(_dop.E3)
_E5 = np.ascontiguousarray(_dop.E5)
_D = np.ascontiguousarray(_dop.D)
_A_EXTRA = np.ascontiguousarray(_dop.A[_NS + 1 :])
_C_EXTRA = np.ascontiguousarray(_dop.C[_NS + 1 :])
_NSE = _dop.N_STAGES_EXTENDED  # 16
_NPOW = _dop.INTERPOLATOR_POWER  # 7
# Hairer's stiffness test compares the last stage (at t + h) with f(y_new).
assert _C[_NS - 1] == 1.0
_EPS = float(np.finfo(float).eps)
_ERROR_EXPONENT = -1.0 / (7 + 1)  # DOP853's error estimator is of order 7
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0

# Layout of the shared parameter vector (one per call).
_Q_WHEELBASE, _Q_FF, _Q_MAX_F, _Q_MAX_R, _Q_TAU = 0, 1, 2, 3, 4
_Q_RATE_F, _Q_RATE_R, _Q_STEER_MARGIN, _Q_CURV_MARGIN = 5, 6, 7, 8
_Q_PERIOD, _Q_S_LO, _Q_S_HI, _Q_OPEN_LENGTH = 9, 10, 11, 12
_Q_SWITCH = 13  # 1: clips as modes switched at located events; 0: min/max
_Q_MAX_STEP = 14  # scipy's max_step (inf: none)
# the first table piece's constant curvature and its feedforward angle
# atan(f kappa0), computed once (see _feedforward_angle)
_Q_KAPPA0, _Q_FF_ANGLE0 = 15, 16
_Q_METHOD = 17  # 0: DOP853, 1: Radau (see METHODS)
_RADAU = 1  # q[_Q_METHOD] of Radau, and the constant of its drivers
_Q_DELAY = 18  # input delay [s] (0: none)
# the dynamic single-track model (q[_Q_DYNAMIC] = 1; its rows v_y, r last):
# mass, yaw inertia, l_f, l_r, the axles' cornering stiffnesses and peak
# forces (0: the linear tyre)
_Q_DYNAMIC, _Q_MASS, _Q_INERTIA, _Q_L_F, _Q_L_R = 19, 20, 21, 22, 23
_Q_C_F, _Q_C_R, _Q_PEAK_F, _Q_PEAK_R = 24, 25, 26, 27
# slots 28-35: a controller's compiled law and the curvature table's rows
# (compiled_laws); 36-43: speed profiles and gain schedules
_NQ = 44
# Layout of the per run parameter vector.
_P_SPEED, _P_K1, _P_K2, _P_RATIO = 0, 1, 2, 3
# modes of the four clips (front/rear angle, front/rear rate): -1, 0 or +1
_P_MODE = 4
# the held mode (-1 or +1) each clip was released from at the restart of
# the current step, 0 otherwise (see _events)
_P_RELEASED = 8
# slots 12-17: a controller's law parameters (compiled_laws); 18-21: speed
# profiles and gain schedules
_NP = 22
# With an input delay the driver extends a run's p by its past (the method
# of steps), so that every function given p -- the right-hand side, the
# events, the steps -- can look up the delayed state without another
# argument: p[_P_NOW] is the time of the state the events are evaluated on
# (they take no time), p[_P_N_HIST] the number of accepted steps held, then
# the initial state (m values) and one row per accepted step laid out as the
# rows of CompiledSolution.records: t_old, h, y_old, DOP853's F.
_P_NOW, _P_N_HIST, _P_HIST = _NP, _NP + 1, _NP + 2
# rows of compiled_outputs, in the order of engine.SIGNALS
_NSIG = len(SIGNALS)
_N_STOPS = 4
_N_EVENTS = 8
# Points of a step (fractions) where, with the dense output kept, the stop
# conditions are checked too (engine._MARGIN_NODES without the step's end).
_INNER_NODES = (0.25, 0.5, 0.75)
_N_INNER = len(_INNER_NODES)
#: Most clip switches per run (a guard against chattering).
_MAX_SWITCHES = 100_000


# --------------------------------------------------------------------------
# The equations of fws_control.equations, compiled


def _compile_equations() -> dict[str, Any]:
    # Every function of fws_control.equations, compiled by numba for float
    # scalars: the same functions as the numpy engine and the analysis
    # call. numba resolves the names a function calls in its globals, so
    # the functions are compiled from copies sharing one globals dict in
    # which the equations that others call (path_frame_derivatives calls
    # yaw_rate) are their compiled versions (numba reads the names when it
    # first compiles, after the dict is complete). Inlined into every kernel
    # (see _jit_inline): the kernels' own copies of these lines were part of
    # them.
    names = [n for n in equations.__all__ if callable(getattr(equations, n))]
    shared = dict(vars(equations))
    out = {}
    for name in names:
        fn = getattr(equations, name)
        clone = types.FunctionType(
            fn.__code__, shared, fn.__name__, fn.__defaults__, fn.__closure__
        )
        clone.__qualname__ = fn.__qualname__
        clone.__doc__ = fn.__doc__
        out[name] = _jit_inline(clone)
    shared.update(out)
    return out


#: name -> compiled function of :mod:`fws_control.equations`
_EQUATIONS = _compile_equations()
_yaw_rate = _EQUATIONS["yaw_rate"]
_path_frame_derivatives = _EQUATIONS["path_frame_derivatives"]
_cg_lateral_velocity = _EQUATIONS["cg_lateral_velocity"]
_yaw_acceleration = _EQUATIONS["yaw_acceleration"]
_lateral_acceleration = _EQUATIONS["lateral_acceleration"]
_feedforward = _EQUATIONS["feedforward_angle"]
_feedforward_rate = _EQUATIONS["feedforward_angle_rate"]
_feedback_command = _EQUATIONS["feedback_command"]
_slip_angles = _EQUATIONS["slip_angles"]
_linear_tyre_force = _EQUATIONS["linear_tyre_force"]
_magic_tyre_force = _EQUATIONS["magic_tyre_force"]
_body_derivatives = _EQUATIONS["body_derivatives"]
_dynamic_path_kinematics = _EQUATIONS["dynamic_path_kinematics"]
_clip_switch_margin = _EQUATIONS["clip_switch_margin"]


# --------------------------------------------------------------------------
# The closed loop


@_jit
def _wrap_lap(s, period):
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


@_jit
def _feedforward_angle(kappa, q):
    """``atan(f kappa)``, the feedforward angle; for the first table
    piece's constant curvature (an arc, a straight) the value computed once
    in :func:`shared_parameters` with the same ``atan`` (16 ns a call,
    paid at every output time and right-hand-side evaluation). A
    curvature of -0.0 gets the angle of +0.0."""
    if kappa == q[_Q_KAPPA0]:
        return q[_Q_FF_ANGLE0]
    return _feedforward(q[_Q_WHEELBASE], kappa)


@_jit
def _curvature(s, q, breaks, coefs):
    period = q[_Q_PERIOD]
    if period > 0.0:
        s = _wrap_lap(s, period)  # Python semantics, as np.mod in Path._domain
        if s >= period:
            s = 0.0
    else:
        # open paths: clipped, as the numpy engine does for trial stages
        s = min(max(s, q[_Q_S_LO]), q[_Q_S_HI])
    # (other tables follow the curvature's rows in breaks and coefs)
    rows = int(q[Q_CURVATURE_ROWS])
    k = np.searchsorted(breaks[: rows + 1], s, side="right") - 1
    k = min(max(k, 0), rows - 1)
    d = s - breaks[k]
    return coefs[k, 0] + d * (coefs[k, 1] + d * (coefs[k, 2] + d * coefs[k, 3]))


@_jit_inline
def _measured_state(t, y, p, q):
    """``(s, e, theta)`` the law acts on at time `t`: those of `y` without a
    delay; with an input delay D those at ``t - D``, from the run's past
    held in `p` (see ``_P_HIST``) as ``engine._History.state`` finds them:
    the initial state up to the start, then the dense output of the last
    accepted step that starts at or before ``t - D``."""
    delay = q[_Q_DELAY]
    if not delay > 0.0:
        return y[0], y[1], y[2]
    m = y.size
    n = int(p[_P_N_HIST])
    base = _P_HIST + m
    stride = 2 + (_NPOW + 1) * m
    td = t - delay
    if n == 0 or td <= p[base]:
        return p[_P_HIST], p[_P_HIST + 1], p[_P_HIST + 2]
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
        for k in range(_NPOW):
            v += p[r + 2 + m + (_NPOW - 1 - k) * m + i]
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


@_jit
def _with_history(p, y0, rows):
    """`p` extended by an empty past (see ``_P_HIST``) with room for `rows`
    steps, the initial state `y0` held before the start."""
    m = y0.size
    out = np.empty(_P_HIST + m + rows * (2 + (_NPOW + 1) * m))
    for i in range(_NP):
        # (solve_run may be given the 4 run parameters alone: modes 0)
        out[i] = p[i] if i < p.size else 0.0
    out[_P_NOW] = 0.0
    out[_P_N_HIST] = 0.0
    for i in range(m):
        out[_P_HIST + i] = y0[i]
    return out


@_jit
def _add_to_history(p, t_old, h, y_old, F):
    """Append an accepted step to the past held in `p`; returns `p`, or a
    copy with twice the room when it was full."""
    m = y_old.size
    stride = 2 + (_NPOW + 1) * m
    n = int(p[_P_N_HIST])
    r = _P_HIST + m + n * stride
    if r + stride > p.size:
        grown = np.empty(_P_HIST + m + 2 * max(n, 16) * stride)
        for i in range(r):
            grown[i] = p[i]
        p = grown
    p[r] = t_old
    p[r + 1] = h
    for i in range(m):
        p[r + 2 + i] = y_old[i]
        for k in range(_NPOW):
            p[r + 2 + m + k * m + i] = F[k, i]
    p[_P_N_HIST] = n + 1
    return p


@_jit_inline
def _dynamic_derivatives(V, kappa, e, th, vy, r, df, dr, q):
    """``(s_dot, e_dot, theta_dot, v_y_dot, r_dot)`` of the dynamic model, as
    dynamics.dynamic_path_derivatives (the same equations)."""
    l_f, l_r = q[_Q_L_F], q[_Q_L_R]
    alpha_f, alpha_r = _slip_angles(V, l_f, l_r, vy, r, df, dr)
    if q[_Q_PEAK_F] > 0.0:
        force_f = _magic_tyre_force(alpha_f, q[_Q_C_F], q[_Q_PEAK_F])
        force_r = _magic_tyre_force(alpha_r, q[_Q_C_R], q[_Q_PEAK_R])
    else:
        force_f = _linear_tyre_force(alpha_f, q[_Q_C_F])
        force_r = _linear_tyre_force(alpha_r, q[_Q_C_R])
    vy_dot, r_dot = _body_derivatives(
        V, q[_Q_MASS], q[_Q_INERTIA], l_f, l_r, r, force_f, force_r, df, dr
    )
    s_dot, e_dot, th_dot = _dynamic_path_kinematics(V, l_r, kappa, e, th, vy, r)
    return s_dot, e_dot, th_dot, vy_dot, r_dot


_law_command = make_law_command(_EQUATIONS, _wrap_lap, _jit)


@_jit_inline
def _follow_speed(t, s, p, q, breaks, coefs):
    # a varying speed (compiled_speed): the run's speed, and a schedule's
    # gains, at time t and arc length s, into p
    V, k1, k2, a, scheduled = speed_and_gains(t, s, q, breaks, coefs)
    p[_P_SPEED] = V
    if scheduled:
        p[_P_K1], p[_P_K2], p[_P_RATIO] = k1, k2, a


@_jit_inline
def _raw_command(s, e, theta, kappa, p, q, breaks, coefs):
    if q[Q_LAW] != 0.0:  # a controller's compiled law (compiled_laws)
        return _law_command(s, e, theta, kappa, p, q, breaks, coefs)
    cf, cr = _feedback_command(e, theta, p[_P_K1], p[_P_K2], p[_P_RATIO])
    if q[_Q_FF] != 0.0:
        cf = cf + _feedforward_angle(kappa, q)
    return cf, cr


@_jit_inline
def _command(s, e, theta, kappa, p, q, breaks, coefs):
    """The paper's law, as controllers.steering_command (same operations).

    With switching (``q[13] = 1``) a clipped channel is held at its limit
    by its mode (``p[4:6]``) rather than by min/max, so that the right-hand
    side is smooth between the located switches.
    """
    cf, cr = _raw_command(s, e, theta, kappa, p, q, breaks, coefs)
    mf, mr = q[_Q_MAX_F], q[_Q_MAX_R]
    if q[_Q_SWITCH] != 0.0:
        if p[_P_MODE] != 0.0:
            cf = p[_P_MODE] * mf
        if p[_P_MODE + 1] != 0.0:
            cr = p[_P_MODE + 1] * mr
        return cf, cr
    cf = min(max(cf, -mf), mf)
    cr = min(max(cr, -mr), mr)
    return cf, cr


@_jit
def _clip_values(y, p, q, breaks, coefs, out):
    """Unclipped front/rear commands and actuator rates, and their limits."""
    if q[Q_PROFILE] != 0.0:
        _follow_speed(p[P_SPEED_TIME], y[0], p, q, breaks, coefs)
    kappa = _curvature(y[0], q, breaks, coefs)
    raw_f, raw_r = _raw_command(y[0], y[1], y[2], kappa, p, q, breaks, coefs)
    out[0], out[1] = raw_f, raw_r
    out[4], out[5] = q[_Q_MAX_F], q[_Q_MAX_R]
    out[6], out[7] = q[_Q_RATE_F], q[_Q_RATE_R]
    tau = q[_Q_TAU]
    if tau > 0.0:
        cf, cr = _command(y[0], y[1], y[2], kappa, p, q, breaks, coefs)
        out[2] = (cf - y[3]) / tau
        out[3] = (cr - y[4]) / tau
    else:
        out[2], out[3] = 0.0, 0.0
        out[6], out[7] = np.inf, np.inf


@_jit_inline
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
    >>> out = np.empty(3)
    >>> closed_loop_rhs(0.0, np.array([0.0, 1.0, 0.0]), p, q, tab.breaks,
    ...                 tab.coefs, out)
    >>> out.round(6).tolist()            # theta_dot = V tan(-0.1) / f
    [5.0, 0.0, -0.185805]
    """
    s, e, th = y[0], y[1], y[2]
    if q[Q_PROFILE] != 0.0:
        _follow_speed(t, s, p, q, breaks, coefs)
    kappa = _curvature(s, q, breaks, coefs)
    if q[_Q_DELAY] > 0.0:
        # the law acts on the measurements of t - delay
        s_m, e_m, th_m = _measured_state(t, y, p, q)
        kappa_m = _curvature(s_m, q, breaks, coefs)
        cf, cr = _command(s_m, e_m, th_m, kappa_m, p, q, breaks, coefs)
    else:
        cf, cr = _command(s, e, th, kappa, p, q, breaks, coefs)
    tau = q[_Q_TAU]
    if tau > 0.0:
        df, dr = y[3], y[4]
    else:
        df, dr = cf, cr
    if q[_Q_DYNAMIC] != 0.0:
        m = y.size  # the body's rows v_y, r last
        out[0], out[1], out[2], out[m - 2], out[m - 1] = _dynamic_derivatives(
            p[_P_SPEED], kappa, e, th, y[m - 2], y[m - 1], df, dr, q
        )
    else:
        out[0], out[1], out[2] = _path_frame_derivatives(
            p[_P_SPEED], q[_Q_WHEELBASE], kappa, e, th, df, dr
        )
    if tau > 0.0:
        rf = (cf - df) / tau
        rr = (cr - dr) / tau
        mf, mr = q[_Q_RATE_F], q[_Q_RATE_R]
        if q[_Q_SWITCH] != 0.0:
            if p[_P_MODE + 2] != 0.0:
                rf = p[_P_MODE + 2] * mf
            if p[_P_MODE + 3] != 0.0:
                rr = p[_P_MODE + 3] * mr
            out[3] = rf
            out[4] = rr
        else:
            out[3] = min(max(rf, -mf), mf)
            out[4] = min(max(rr, -mr), mr)


@_jit
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
    >>> J = np.empty((5, 5))
    >>> closed_loop_jac(0.0, np.zeros(5), p, q, tab.breaks, tab.coefs, J)
    >>> J[3].round(6).tolist()           # (cf - delta_f) / T, cf = -k1 e - k2 theta
    [0.0, -2.0, -10.0, -20.0, 0.0]
    """
    s, e, th = y[0], y[1], y[2]
    kappa, slope = _curvature_and_rate(s, q, breaks, coefs)
    if q[_Q_PERIOD] <= 0.0 and (s < q[_Q_S_LO] or s > q[_Q_S_HI]):
        slope = 0.0  # the open path's curvature is held outside its domain
    cf, cr = _raw_command(s, e, th, kappa, p, q, breaks, coefs)
    wheelbase = q[_Q_WHEELBASE]
    # d(cf, cr)/d(s, e, theta)
    cf_s = 0.0
    if q[_Q_FF] != 0.0:
        cf_s = _feedforward_rate(wheelbase, kappa, slope)
    cf_e, cf_th = -p[_P_K1], -p[_P_K2]
    a = p[_P_RATIO]
    cr_s, cr_e, cr_th = 0.0, a * cf_e, a * cf_th
    mf, mr = q[_Q_MAX_F], q[_Q_MAX_R]
    switching = q[_Q_SWITCH] != 0.0
    if (switching and p[_P_MODE] != 0.0) or (not switching and abs(cf) > mf):
        cf_s, cf_e, cf_th = 0.0, 0.0, 0.0
    if (switching and p[_P_MODE + 1] != 0.0) or (not switching and abs(cr) > mr):
        cr_s, cr_e, cr_th = 0.0, 0.0, 0.0
    tau = q[_Q_TAU]
    n = y.shape[0]
    for i in range(n):
        for j in range(n):
            out[i, j] = 0.0
    # d(delta_f, delta_r)/d(s, e, theta) (0 with an actuator: own states)
    df_x = np.zeros(3)
    dr_x = np.zeros(3)
    if tau > 0.0:
        cf_c, cr_c = _command(s, e, th, kappa, p, q, breaks, coefs)
        df, dr = y[3], y[4]
    else:
        cf_c, cr_c = _command(s, e, th, kappa, p, q, breaks, coefs)
        df, dr = cf_c, cr_c
        df_x[0], df_x[1], df_x[2] = cf_s, cf_e, cf_th
        dr_x[0], dr_x[1], dr_x[2] = cr_s, cr_e, cr_th
    V = p[_P_SPEED]
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
        switching_rate_f = switching and p[_P_MODE + 2] != 0.0
        switching_rate_r = switching and p[_P_MODE + 3] != 0.0
        rf = (cf_c - df) / tau
        rr = (cr_c - dr) / tau
        if not (switching_rate_f or (not switching and abs(rf) > q[_Q_RATE_F])):
            out[3, 0], out[3, 1], out[3, 2] = cf_s / tau, cf_e / tau, cf_th / tau
            out[3, 3] = -1.0 / tau
        if not (switching_rate_r or (not switching and abs(rr) > q[_Q_RATE_R])):
            out[4, 0], out[4, 1], out[4, 2] = cr_s / tau, cr_e / tau, cr_th / tau
            out[4, 4] = -1.0 / tau
    else:
        # chain rule through delta_f(s, e, theta), delta_r(s, e, theta)
        rows = (sd, ed, td)
        for i in range(3):
            r = rows[i]
            for j in range(3):
                out[i, j] = r[j] + r[3] * df_x[j] + r[4] * dr_x[j]


@_jit_inline
def _set_now(t, p, q):
    # the time of the state the events are next evaluated on (a delay's
    # applied angle depends on it; see _P_NOW)
    if q[_Q_DELAY] > 0.0:
        p[_P_NOW] = t
    if q[Q_PROFILE] != 0.0:
        p[P_SPEED_TIME] = t


@_jit
def _stop_events(y, p, q, breaks, coefs, g):
    """The stop events 0-3 of :func:`_events` (into ``g[:4]``)."""
    s, e = y[0], y[1]
    if q[Q_PROFILE] != 0.0:
        _follow_speed(p[P_SPEED_TIME], s, p, q, breaks, coefs)
    kappa = _curvature(s, q, breaks, coefs)
    if q[_Q_TAU] > 0.0:
        df = y[3]
    elif q[_Q_DELAY] > 0.0:
        # the applied angle: the law on the measurements of t - delay, for
        # the time the caller set in p[_P_NOW]
        s_m, e_m, th_m = _measured_state(p[_P_NOW], y, p, q)
        kappa_m = _curvature(s_m, q, breaks, coefs)
        df = _command(s_m, e_m, th_m, kappa_m, p, q, breaks, coefs)[0]
    else:
        df = _command(s, e, y[2], kappa, p, q, breaks, coefs)[0]
    g[0] = (0.5 * math.pi - q[_Q_STEER_MARGIN]) - abs(df)
    g[1] = (1.0 - kappa * e) - q[_Q_CURV_MARGIN]
    L = q[_Q_OPEN_LENGTH]
    if L < np.inf:
        # the offset lets a run start exactly at s = 0 (or at the end)
        g[2] = (L - s) / L + 1e-9
        g[3] = s / L + 1e-9
    else:
        g[2] = np.inf
        g[3] = np.inf


@_jit
def _events(y, p, q, breaks, coefs, g):
    """Event functions: 0-3 stop a run, 4-7 switch a clip's mode (at <= 0).

    A clip released from its limit at the start of the step (``p[8 + j]``,
    with ``p`` of 12 entries) is at that limit there: it can only move away
    from it, so only the opposite limit switches it in that step. With
    ``|raw|`` against the limit, the released clip would start the step on
    the wrong side by the rounding of the located switch and be switched
    back at once, for ever, when the step crosses to the opposite limit.
    """
    _stop_events(y, p, q, breaks, coefs, g)
    if q[_Q_SWITCH] == 0.0:
        for j in range(_N_STOPS, _N_EVENTS):
            g[j] = np.inf
        return
    # clip j: free (mode 0) while |raw| < limit, held while mode * raw > limit
    v = np.empty(8)
    _clip_values(y, p, q, breaks, coefs, v)
    released = p.size >= _NP
    for j in range(4):
        side = p[_P_RELEASED + j] if released else 0.0
        g[_N_STOPS + j] = _clip_switch_margin(v[j], v[4 + j], p[_P_MODE + j], side)


# --------------------------------------------------------------------------
# DOP853, as scipy.integrate.DOP853 (line by line; comments name scipy's code)


@_jit
def _rms(x):
    # scipy.integrate._ivp.common.norm: np.linalg.norm(x) / x.size ** 0.5
    acc = 0.0
    for v in x:
        acc += v * v
    return math.sqrt(acc) / x.size**0.5


@_jit
def _select_initial_step(t0, y0, t_bound, f0, rtol, atol, p, q, br, co, work, order):
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
    return min(100 * h0, h1, interval_length, q[_Q_MAX_STEP])


@_jit
def _dense_coefficients(t_old, h, y_old, y, f, K, p, q, br, co, F, ytmp):
    # DOP853._dense_output_impl: three extra stages, then the 7 coefficients
    m = y.size
    for s in range(_NS + 1, _NSE):
        a = _A_EXTRA[s - _NS - 1]
        c = _C_EXTRA[s - _NS - 1]
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
        for r in range(_NPOW - 3):
            acc = 0.0
            for j in range(_NSE):
                acc += _D[r, j] * K[j, i]
            F[3 + r, i] = h * acc


@_jit_inline
def _dense_eval(tt, t_old, t_new, y_old, F, out):
    # Dop853DenseOutput._call_impl at one time
    x = (tt - t_old) / (t_new - t_old)
    m = y_old.size
    for i in range(m):
        v = 0.0
        for k in range(_NPOW):
            v += F[_NPOW - 1 - k, i]
            if k % 2 == 0:
                v *= x
            else:
                v *= 1 - x
        out[i] = v + y_old[i]


@_jit
def _event_at(tt, j, t_old, t_new, y_old, F, p, q, br, co, ytmp, g):
    _dense_eval(tt, t_old, t_new, y_old, F, ytmp)
    _set_now(tt, p, q)
    _events(ytmp, p, q, br, co, g)
    return g[j]


@_jit
def _brentq(j, xa, xb, t_old, t_new, y_old, F, p, q, br, co, ytmp, g):
    # scipy.optimize.brentq (its C code), xtol = rtol = 4 eps, maxiter 100,
    # on event j of the dense output: scipy's solve_event_equation
    xtol = 4 * _EPS
    rtol = 4 * _EPS
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


@_jit
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
    if h_abs > q[_Q_MAX_STEP]:
        h_abs = q[_Q_MAX_STEP]
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
        for s in range(1, _NS):
            a = _A[s]
            for i in range(m):
                acc = 0.0
                for j in range(s):
                    acc += K[j, i] * a[j]
                ystage[i] = y[i] + acc * h
            closed_loop_rhs(t + _C[s] * h, ystage, p, q, breaks, coefs, K[s])
        for i in range(m):
            acc = 0.0
            for j in range(_NS):
                acc += K[j, i] * _B[j]
            y_new[i] = y[i] + h * acc
        closed_loop_rhs(t + h, y_new, p, q, breaks, coefs, K[_NS])
        # DOP853._estimate_error_norm, scale = atol + max(|y|, |y_new|) rtol
        e5 = 0.0
        e3 = 0.0
        for i in range(m):
            sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
            a5 = 0.0
            a3 = 0.0
            for j in range(_NS + 1):
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
                factor = _MAX_FACTOR
            else:
                factor = min(_MAX_FACTOR, _SAFETY * error_norm**_ERROR_EXPONENT)
            if step_rejected:
                factor = min(1.0, factor)
            return True, t_new, h, h_abs * factor, rejected
        h_abs *= max(_MIN_FACTOR, _SAFETY * error_norm**_ERROR_EXPONENT)
        step_rejected = True
        rejected += 1


@_jit
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
    F = np.empty((_NPOW, m))
    _dense_coefficients(
        t_old, t_new - t_old, y_old, y_new, f_new, K, p, q, breaks, coefs, F, out
    )
    _dense_eval(tt, t_old, t_new, y_old, F, out)


@_jit
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
    F = np.empty((_NPOW, m))
    ytmp = np.empty(m)
    g = np.empty(_N_EVENTS)
    _dense_coefficients(
        t_old, t_new - t_old, y_old, y_new, f_new, K, p, q, breaks, coefs, F, ytmp
    )
    return _brentq(
        j, t_old, t_new, t_old, t_new, y_old, F, p, q, breaks, coefs, ytmp, g
    )


@_jit
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


@_jit
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


def _drivers(method):
    """The per-run driver and the batch loop of one method, compiled apart.

    `method` (0: DOP853, :data:`_RADAU`) is a constant of the closures, so
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
        K = np.empty((_NSE, m))
        F = np.empty((_NPOW, m))
        ytmp = np.empty(m)
        ystage = np.empty(m)
        work = np.empty(m)
        g_old = np.empty(_N_EVENTS)
        g_new = np.empty(_N_EVENTS)
        g_tmp = np.empty(_N_EVENTS)
        g_inner = np.empty((_N_INNER, _N_EVENTS))
        t = t_eval[0]
        t_bound = t_eval[T - 1]
        y = y0.copy()
        # an input delay: the run's past in p, and the segments of the
        # method of steps, which end where the solution's derivatives jump
        # (t0 + k delay, k = 1, 2, 3) and restart the method there, as the
        # numpy engine does
        delay = q[_Q_DELAY]
        delayed = delay > 0.0
        t_seg = _segment_end(t, t_eval[0], t_bound, delay)
        if delayed:
            p = _with_history(p, y0, 64)
        y_new = np.empty(m)
        f = np.empty(m)
        switches = 0
        # Radau (q[_Q_METHOD] = _RADAU): its state between steps (_radau_step)
        radau = method == _RADAU
        order = 3 if radau else 7
        rs = np.empty(_NRS)
        J = np.empty((m, m))
        M_real = np.empty((m, m))
        M_complex = np.empty((m, m), dtype=np.complex128)
        Q = np.zeros((m, 3))
        y_prev = np.empty(m)
        f_new = np.empty(m)
        if q[_Q_SWITCH] != 0.0:
            # initial modes: a channel beyond its limit starts held (angles
            # first: the actuator's rate depends on the held command)
            v = np.empty(8)
            for j in range(4):
                p[_P_MODE + j] = 0.0
                if p.size >= _NP:
                    p[_P_RELEASED + j] = 0.0
            for j in range(4):
                _clip_values(y, p, q, breaks, coefs, v)
                if abs(v[j]) > v[4 + j]:
                    p[_P_MODE + j] = 1.0 if v[j] > 0 else -1.0
        closed_loop_rhs(t, y, p, q, breaks, coefs, f)
        nfev = 1
        steps = 0
        rejected_total = 0
        iasti = 0
        nonsti = 0
        stiff = 0

        # a run that starts at or beyond a stop condition stops at once
        _set_now(t, p, q)
        _events(y, p, q, breaks, coefs, g_old)
        worst = 0
        for j in range(_N_STOPS):
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

        h_abs = _select_initial_step(
            t, y, t_seg, f, rtol, atol, p, q, breaks, coefs, work, order
        )
        nfev += 1
        if radau:
            _radau_start(t, y, h_abs, p, q, breaks, coefs, rs, J)
        k_out = 0
        while True:
            if radau:
                # ---- Radau._step_impl (its Jacobian: closed_loop_jac)
                code_r, t_new, n_rej, nf = _radau_step(
                    t, y, f, t_bound, rtol, atol, p, q, breaks, coefs, rs, J, M_real,
                    M_complex, Q, y_prev, y_new, f_new,
                )  # fmt: skip
                ok = code_r == 0
                nfev += nf
                h = t_new - t
            else:
                # ---- RungeKutta._step_impl (direction +1, max_step q[_Q_MAX_STEP])
                ok, t_new, h, h_abs, n_rej = dop853_step(
                    t, y, f, h_abs, t_seg, rtol, atol, p, q, breaks, coefs, K, y_new,
                    ystage,
                )  # fmt: skip
                nfev += _NS * (n_rej + 1)
            rejected_total += n_rej
            if not ok:
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
            if method != _RADAU:
                # Hairer's stiffness detection (dop853.f): |h lambda| from the
                # last stage and f(y_new), both at t + h
                num = 0.0
                den = 0.0
                for i in range(m):
                    num += (K[_NS, i] - K[_NS - 1, i]) ** 2
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
            # accepted: y_old = y, y = y_new, f = f_new
            # (buffers swapped: y_old is only overwritten by the next step)
            t_old = t
            y_old = y
            y = y_new
            y_new = y_old
            t = t_new
            for i in range(m):
                f[i] = f_new[i] if radau else K[_NS, i]
            if steps < n_trace:
                trace[steps] = t
            steps += 1
            dense_ready = False
            if radau:
                # its collocation polynomial, in the form _dense_eval reads
                _radau_dense(Q, F)
                dense_ready = True
            if keep:
                # the dense output of every accepted step, for the exact peaks
                # (a step cut at a switch or a stop keeps its interpolant)
                if not dense_ready:
                    _dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                    dense_ready = True
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
                    for k in range(_NPOW):
                        row[2 + m + k * m + i] = F[k, i]
                n_rec += 1
            if delayed:
                # the step joins the past before its events are located, as
                # the numpy engine records it before checking its margins
                if not dense_ready:
                    _dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                    dense_ready = True
                p = _add_to_history(p, t_old, h, y_old, F)
            # ---- solve_ivp: events (direction -1: g from >= 0 to <= 0)
            _set_now(t, p, q)
            _events(y, p, q, breaks, coefs, g_new)
            code = 0
            t_hit = np.inf
            j_hit = -1
            if keep:
                # with the dense output kept (the runners), the stop conditions
                # are also checked at three points inside the step, as the numpy
                # engine checks its margins: a loose tolerance must not step
                # across a singular state and back
                for r in range(_N_INNER):
                    t_in = t_old + _INNER_NODES[r] * h
                    _dense_eval(t_in, t_old, t, y_old, F, ytmp)
                    _set_now(t_in, p, q)
                    _stop_events(ytmp, p, q, breaks, coefs, g_inner[r])
            for j in range(_N_EVENTS):
                lo_b, hi_b = t_old, t
                if j < _N_STOPS:
                    hit = g_old[j] >= 0 and g_new[j] <= 0  # solve_ivp, direction -1
                    if keep and not hit and g_old[j] >= 0:
                        for r in range(_N_INNER):
                            if g_inner[r, j] <= 0:
                                hit = True
                                hi_b = t_old + _INNER_NODES[r] * h
                                break
                            lo_b = t_old + _INNER_NODES[r] * h
                else:
                    # a clip's mode is wrong at the step's end: it switched in the
                    # step (g from > 0), or it was ~0 on the wrong side already at
                    # a restart (then the switch is at the step's start)
                    hit = g_new[j] < 0 or (g_new[j] == 0 and g_old[j] > 0)
                if not hit:
                    continue
                if j >= _N_STOPS and not g_old[j] > 0:
                    root = t_old
                else:
                    if not dense_ready:
                        _dense_coefficients(
                            t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                        )
                        nfev += 3
                        dense_ready = True
                    root = _brentq(
                        j,
                        lo_b,
                        hi_b,
                        t_old,
                        t,
                        y_old,
                        F,
                        p,
                        q,
                        breaks,
                        coefs,
                        ytmp,
                        g_tmp,
                    )
                if root < t_hit:
                    t_hit = root
                    j_hit = j
            if 0 <= j_hit < _N_STOPS:
                code = min(j_hit, 2) + 1
            upto = t if j_hit < 0 else t_hit
            # ---- solve_ivp: outputs at t_eval <= upto from this step's dense output
            while k_out < T and t_eval[k_out] <= upto:
                if not dense_ready:
                    _dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                    dense_ready = True
                _dense_eval(t_eval[k_out], t_old, t, y_old, F, ytmp)
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
            if j_hit >= _N_STOPS:
                # a clip switches: restart at the switch with the new mode (the
                # rest of the step, integrated in the old mode, is discarded)
                if not dense_ready:
                    _dense_coefficients(
                        t_old, h, y_old, y, f, K, p, q, breaks, coefs, F, ytmp
                    )
                    nfev += 3
                _dense_eval(t_hit, t_old, t, y_old, F, ytmp)
                for i in range(m):
                    y[i] = ytmp[i]
                t = t_hit
                _set_now(t, p, q)
                site = j_hit - _N_STOPS
                track = p.size >= _NP
                v = np.empty(8)
                if track:
                    # a clip released before and now inside its limits
                    # watches both limits again
                    _clip_values(y, p, q, breaks, coefs, v)
                    for jj in range(4):
                        if p[_P_RELEASED + jj] != 0.0 and abs(v[jj]) < v[4 + jj]:
                            p[_P_RELEASED + jj] = 0.0
                if p[_P_MODE + site] != 0.0:
                    if track:
                        p[_P_RELEASED + site] = p[_P_MODE + site]
                    p[_P_MODE + site] = 0.0
                else:
                    _clip_values(y, p, q, breaks, coefs, v)
                    p[_P_MODE + site] = 1.0 if v[site] > 0 else -1.0
                    if track:
                        p[_P_RELEASED + site] = 0.0
                switches += 1
                if switches > _MAX_SWITCHES:
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
                h_abs = _select_initial_step(
                    t, y, t_seg, f, rtol, atol, p, q, breaks, coefs, work, order
                )
                nfev += 2
                if radau:
                    # a new solver at the switch, as for DOP853
                    _radau_start(t, y, h_abs, p, q, breaks, coefs, rs, J)
                _set_now(t, p, q)
                _events(y, p, q, breaks, coefs, g_old)
                continue
            if t == t_bound:
                return 0, t, steps, rejected_total, nfev, stiff, switches, rec, n_rec
            if t == t_seg:
                # the next segment of a delay's method of steps: a new
                # solver there (f and the first step anew, as scipy's)
                t_seg = _segment_end(t, t_eval[0], t_bound, delay)
                closed_loop_rhs(t, y, p, q, breaks, coefs, f)
                h_abs = _select_initial_step(
                    t, y, t_seg, f, rtol, atol, p, q, breaks, coefs, work, order
                )
                nfev += 2
            released = False
            if q[_Q_SWITCH] != 0.0 and p.size >= _NP:
                for j in range(4):
                    if p[_P_RELEASED + j] != 0.0:
                        p[_P_RELEASED + j] = 0.0
                        released = True
            if released:
                # a step after a release: the clips watch both limits again
                _set_now(t, p, q)
                _events(y, p, q, breaks, coefs, g_old)
            else:
                for j in range(_N_EVENTS):
                    g_old[j] = g_new[j]

    def solve_batch(
        Y0, P, q, breaks, coefs, t_eval, rtol, atol, out, codes, t_stop, stats, rec,
        offsets, keep,
    ):  # fmt: skip
        # with keep: run i's dense pieces are rows offsets[i]:offsets[i + 1] of the
        # returned record (rec, grown as needed)
        empty = np.empty(0)
        offsets[0] = 0
        for i in range(Y0.shape[0]):
            if method == _RADAU:
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

    return _jit(run_impl), _jit(solve_batch)


_run_impl, _solve_batch = _drivers(0)
_run_impl_radau, _solve_batch_radau = _drivers(_RADAU)


@_jit_inline
def _curvature_and_rate(s, q, breaks, coefs):
    # kappa and d kappa / ds of the table from one lookup, at s clipped or
    # wrapped as in _curvature (the same operations for kappa)
    period = q[_Q_PERIOD]
    if period > 0.0:
        s = _wrap_lap(s, period)
        if s >= period:
            s = 0.0
    else:
        s = min(max(s, q[_Q_S_LO]), q[_Q_S_HI])
    rows = int(q[Q_CURVATURE_ROWS])
    k = np.searchsorted(breaks[: rows + 1], s, side="right") - 1
    k = min(max(k, 0), rows - 1)
    d = s - breaks[k]
    kappa = coefs[k, 0] + d * (coefs[k, 1] + d * (coefs[k, 2] + d * coefs[k, 3]))
    return kappa, coefs[k, 1] + d * (2.0 * coefs[k, 2] + d * 3.0 * coefs[k, 3])


@_jit_inline
def _point_signals(s, e, th, df_s, dr_s, V, k1, k2, a, q, breaks, coefs, d_cg):
    """The signals of one state with the operations of compute_outputs.

    Returns ``(delta_f, delta_r, their rates, lateral_accel, v_y, yaw_rate,
    ok)``; ``ok`` is False where ``|delta_f| >= pi/2`` (the rates, the
    acceleration, ``v_y`` and the yaw rate are then NaN in a result).
    ``df_s, dr_s``: the actuator states (unused without an actuator).
    """
    f = q[_Q_WHEELBASE]
    mf, mr = q[_Q_MAX_F], q[_Q_MAX_R]
    tau = q[_Q_TAU]
    ff = q[_Q_FF] != 0.0
    if ff and not tau > 0.0:  # the feedforward's rate needs d kappa / ds
        kappa, dkappa = _curvature_and_rate(s, q, breaks, coefs)
    else:
        kappa, dkappa = _curvature(s, q, breaks, coefs), 0.0
    raw_f, raw_r = _feedback_command(e, th, k1, k2, a)
    if ff:
        raw_f = raw_f + _feedforward_angle(kappa, q)
    cf = min(max(raw_f, -mf), mf)
    cr = min(max(raw_r, -mr), mr)
    if tau > 0.0:
        df, dr = df_s, dr_s
    else:
        df, dr = cf, cr
    s_dot, e_dot, th_dot = _path_frame_derivatives(V, f, kappa, e, th, df, dr)
    psi_dot = _yaw_rate(V, f, df, dr)
    if tau > 0.0:
        rf = min(max((cf - df) / tau, -q[_Q_RATE_F]), q[_Q_RATE_F])
        rr = min(max((cr - dr) / tau, -q[_Q_RATE_R]), q[_Q_RATE_R])
    else:
        # steering_command_rate: chain rule, 0 where an angle is clipped
        rf, rr = _feedback_command(e_dot, th_dot, k1, k2, a)
        if ff:
            rf = rf + _feedforward_rate(f, kappa, dkappa * s_dot)
        if abs(raw_f) > mf:
            rf = 0.0
        if abs(raw_r) > mr:
            rr = 0.0
    if not abs(df) < 0.5 * math.pi:
        return df, dr, rf, rr, np.nan, np.nan, psi_dot, False
    psi_ddot = _yaw_acceleration(V, f, df, dr, rf, rr)
    lat = _lateral_acceleration(V, d_cg, dr, rr, psi_dot, psi_ddot)
    vy = _cg_lateral_velocity(V, d_cg, dr, psi_dot)
    return df, dr, rf, rr, lat, vy, psi_dot, True


@_jit_inline
def _dynamic_point_signals(s, e, th, df_s, dr_s, vy, r, V, k1, k2, a, q, breaks,
                           coefs):  # fmt: skip
    """The signals of one state of the dynamic model, as compute_outputs.

    Returns ``(delta_f, delta_r, their rates, lateral_accel, slip_front,
    slip_rear, ok)``: the acceleration of G along the body's lateral axis
    ``dv_y/dt + u r`` (NaN where ``|delta_f| >= pi/2``, as the rates).
    """
    f = q[_Q_WHEELBASE]
    mf, mr = q[_Q_MAX_F], q[_Q_MAX_R]
    tau = q[_Q_TAU]
    ff = q[_Q_FF] != 0.0
    if ff and not tau > 0.0:
        kappa, dkappa = _curvature_and_rate(s, q, breaks, coefs)
    else:
        kappa, dkappa = _curvature(s, q, breaks, coefs), 0.0
    raw_f, raw_r = _feedback_command(e, th, k1, k2, a)
    if ff:
        raw_f = raw_f + _feedforward_angle(kappa, q)
    cf = min(max(raw_f, -mf), mf)
    cr = min(max(raw_r, -mr), mr)
    df, dr = (df_s, dr_s) if tau > 0.0 else (cf, cr)
    s_dot, e_dot, th_dot, vy_dot, _ = _dynamic_derivatives(
        V, kappa, e, th, vy, r, df, dr, q
    )
    if tau > 0.0:
        rf = min(max((cf - df) / tau, -q[_Q_RATE_F]), q[_Q_RATE_F])
        rr = min(max((cr - dr) / tau, -q[_Q_RATE_R]), q[_Q_RATE_R])
    else:
        rf, rr = _feedback_command(e_dot, th_dot, k1, k2, a)
        if ff:
            rf = rf + _feedforward_rate(f, kappa, dkappa * s_dot)
        if abs(raw_f) > mf:
            rf = 0.0
        if abs(raw_r) > mr:
            rr = 0.0
    alpha_f, alpha_r = _slip_angles(V, q[_Q_L_F], q[_Q_L_R], vy, r, df, dr)
    if not abs(df) < 0.5 * math.pi:
        return df, dr, np.nan, np.nan, np.nan, alpha_f, alpha_r, False
    return df, dr, rf, rr, vy_dot + V * r, alpha_f, alpha_r, True


@_jit_inline
def _path_state_at(tt, rec, n_pc, y0, m):
    """``(s, e, theta)`` of a run at `tt` from its dense output (`rec`: its
    pieces), the initial state up to the start (engine._History.states_at)."""
    if n_pc == 0 or tt <= rec[0, 0]:
        return y0[0], y0[1], y0[2]
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
    for k in range(_NPOW):
        c = _NPOW - 1 - k
        v0 += row[2 + m + c * m]
        v1 += row[2 + m + c * m + 1]
        v2 += row[2 + m + c * m + 2]
        w = x if k % 2 == 0 else 1 - x
        v0 *= w
        v1 *= w
        v2 *= w
    return v0 + row[2], v1 + row[3], v2 + row[4]


@_jit_inline
def _delayed_point_signals(tt, df_s, dr_s, rec, n_pc, y0, m, V, k1, k2, a, q,
                           breaks, coefs, d_cg):  # fmt: skip
    """:func:`_point_signals` with an input delay, as compute_outputs with
    the delayed rows: the law acts on the state at ``tt - delay`` (`rec`,
    `y0`: the run's dense output and initial state), whose rates are its
    closed-loop derivative there (the law then on the state at ``tt - 2
    delay``), 0 before the start; ``df_s, dr_s``: the run's actuator states
    at `tt`.
    """
    f = q[_Q_WHEELBASE]
    mf, mr = q[_Q_MAX_F], q[_Q_MAX_R]
    tau = q[_Q_TAU]
    ff = q[_Q_FF] != 0.0
    delay = q[_Q_DELAY]
    td = tt - delay
    s_m, e_m, th_m = _path_state_at(td, rec, n_pc, y0, m)
    if ff and not tau > 0.0:
        kappa, dkappa = _curvature_and_rate(s_m, q, breaks, coefs)
    else:
        kappa, dkappa = _curvature(s_m, q, breaks, coefs), 0.0
    raw_f, raw_r = _feedback_command(e_m, th_m, k1, k2, a)
    if ff:
        raw_f = raw_f + _feedforward_angle(kappa, q)
    cf = min(max(raw_f, -mf), mf)
    cr = min(max(raw_r, -mr), mr)
    if tau > 0.0:
        df, dr = df_s, dr_s
        rf = min(max((cf - df) / tau, -q[_Q_RATE_F]), q[_Q_RATE_F])
        rr = min(max((cr - dr) / tau, -q[_Q_RATE_R]), q[_Q_RATE_R])
    else:
        df, dr = cf, cr
        # the measured state is held before the start: no rate there
        s_dot, e_dot, th_dot = 0.0, 0.0, 0.0
        if n_pc > 0 and td > rec[0, 0]:
            s2, e2, th2 = _path_state_at(td - delay, rec, n_pc, y0, m)
            kappa2 = _curvature(s2, q, breaks, coefs)
            c2f, c2r = _feedback_command(e2, th2, k1, k2, a)
            if ff:
                c2f = c2f + _feedforward_angle(kappa2, q)
            c2f = min(max(c2f, -mf), mf)
            c2r = min(max(c2r, -mr), mr)
            s_dot, e_dot, th_dot = _path_frame_derivatives(
                V, f, kappa, e_m, th_m, c2f, c2r
            )
        rf, rr = _feedback_command(e_dot, th_dot, k1, k2, a)
        if ff:
            rf = rf + _feedforward_rate(f, kappa, dkappa * s_dot)
        if abs(raw_f) > mf:
            rf = 0.0
        if abs(raw_r) > mr:
            rr = 0.0
    psi_dot = _yaw_rate(V, f, df, dr)
    if not abs(df) < 0.5 * math.pi:
        return df, dr, rf, rr, np.nan, np.nan, psi_dot, False
    psi_ddot = _yaw_acceleration(V, f, df, dr, rf, rr)
    lat = _lateral_acceleration(V, d_cg, dr, rr, psi_dot, psi_ddot)
    vy = _cg_lateral_velocity(V, d_cg, dr, psi_dot)
    return df, dr, rf, rr, lat, vy, psi_dot, True


@_jit
def _delayed_signals_batch(states, P, q, breaks, coefs, d_cg, rec, offsets, Y0,
                           t_eval, sig):  # fmt: skip
    # rows 6-12 of sig (the steering angles, their rates, the lateral
    # acceleration, v_y, the yaw rate) anew for an input delay: the law on
    # the state at t - delay, from each run's dense output (rows 0-5 and the
    # slip angles do not depend on the law)
    n, m, T = states.shape
    for i in range(n):
        V = P[i, _P_SPEED]
        k1, k2, a = P[i, _P_K1], P[i, _P_K2], P[i, _P_RATIO]
        pc = rec[offsets[i] : offsets[i + 1]]
        n_pc = pc.shape[0]
        for k in range(T):
            if not np.isfinite(states[i, 0, k]):
                continue
            df_s, dr_s = 0.0, 0.0
            if q[_Q_TAU] > 0.0:
                df_s, dr_s = states[i, 3, k], states[i, 4, k]
            df, dr, rf, rr, lat, vy, psi_dot, ok = _delayed_point_signals(
                t_eval[k], df_s, dr_s, pc, n_pc, Y0[i], m, V,
                k1, k2, a, q, breaks, coefs, d_cg,
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
                for r in range(8, _NSIG):
                    sig[i, r, k] = np.nan


@_jit
def _signals_batch(states, P, q, breaks, coefs, d_cg, pose, sig):
    # sig (n, 15, T) in the order of engine.SIGNALS. Rows 3-14 -- s, e,
    # theta, delta_f, delta_r, their rates, the lateral acceleration of
    # eq. (13), v_y, the yaw rate of eq. (10) and the slip angles (0: the
    # kinematic model has no slip) -- are computed here with the operations
    # of compute_outputs;
    # rows 0-2 (x, y, psi) too when pose[0] is 1 (Straight) or 2 (Arc):
    # pose = (kind, x0, y0, psi0, kappa). psi = theta + psi0 + kappa * s is
    # continuous in time by construction (no unwrapping needed).
    n, m, T = states.shape
    tau = q[_Q_TAU]
    kind = int(pose[0])
    x0, y0, psi0, kp = pose[1], pose[2], pose[3], pose[4]
    c0, s0 = math.cos(psi0), math.sin(psi0)
    period = q[_Q_PERIOD]
    for i in range(n):
        V = P[i, _P_SPEED]
        k1, k2, a = P[i, _P_K1], P[i, _P_K2], P[i, _P_RATIO]
        for k in range(T):
            s = states[i, 0, k]
            if not np.isfinite(s):
                for r in range(_NSIG):
                    sig[i, r, k] = np.nan
                continue
            e = states[i, 1, k]
            th = states[i, 2, k]
            if tau > 0.0:
                df_s, dr_s = states[i, 3, k], states[i, 4, k]
            else:
                df_s, dr_s = 0.0, 0.0
            if q[_Q_DYNAMIC] != 0.0:
                # v_y and the yaw rate are states, the slip angles signals
                vy, psi_dot = states[i, m - 2, k], states[i, m - 1, k]
                df, dr, rf, rr, lat, slip_f, slip_r, ok = _dynamic_point_signals(
                    s, e, th, df_s, dr_s, vy, psi_dot, V, k1, k2, a, q, breaks, coefs
                )
                sig[i, 8, k] = rf
                sig[i, 9, k] = rr
                sig[i, 10, k] = lat
                sig[i, 11, k] = vy
                sig[i, 12, k] = psi_dot
                sig[i, 13, k] = slip_f
                sig[i, 14, k] = slip_r
            else:
                df, dr, rf, rr, lat, vy, psi_dot, ok = _point_signals(
                    s, e, th, df_s, dr_s, V, k1, k2, a, q, breaks, coefs, d_cg
                )
            sig[i, 3, k] = s
            sig[i, 4, k] = e
            sig[i, 5, k] = th
            sig[i, 6, k] = df
            sig[i, 7, k] = dr
            if q[_Q_DYNAMIC] != 0.0:
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
                for r in range(8, _NSIG):
                    sig[i, r, k] = np.nan
            if kind == 0:
                continue
            sp = s
            if period > 0.0:
                sp = _wrap_lap(s, period)
                if sp >= period:
                    sp = 0.0
            else:
                sp = min(max(sp, q[_Q_S_LO]), q[_Q_S_HI])
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
_N_PEAK = 6
# _peak_values computes these, in this order
assert PEAK_SIGNALS == (
    "e", "delta_f", "delta_r", "delta_f_rate", "delta_r_rate", "lateral_accel"
)  # fmt: skip
_PEAK_COLS = tuple(SIGNALS.index(name) for name in PEAK_SIGNALS)


@_jit_inline
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
            for k in range(_NPOW):
                v += row[2 + m + (_NPOW - 1 - k) * m + i]
                if k % 2 == 0:
                    v *= x
                else:
                    v *= 1 - x
            ytmp[i] = v + row[2 + i]


@_jit_inline
def _peak_values(tt, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg, ytmp, out):
    """|signal| of the six peak signals at `tt` on the run's dense output."""
    _state_at(tt, rec, n_pc, y0, m, ytmp)
    df_s, dr_s = 0.0, 0.0
    if q[_Q_TAU] > 0.0:
        df_s, dr_s = ytmp[3], ytmp[4]
    if q[_Q_DELAY] > 0.0:
        df, dr, rf, rr, lat, _, _, ok = _delayed_point_signals(
            tt, df_s, dr_s, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg
        )
    elif q[_Q_DYNAMIC] != 0.0:
        df, dr, rf, rr, lat, _, _, ok = _dynamic_point_signals(
            ytmp[0], ytmp[1], ytmp[2], df_s, dr_s, ytmp[m - 2], ytmp[m - 1], V, k1,
            k2, a, q, br, co,
        )  # fmt: skip
    else:
        df, dr, rf, rr, lat, _, _, ok = _point_signals(
            ytmp[0], ytmp[1], ytmp[2], df_s, dr_s, V, k1, k2, a, q, br, co, d_cg
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
    for j in range(_N_PEAK):
        if not np.isfinite(out[j]):
            out[j] = np.inf


@_jit
def _peak_value(tt, j, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg, ytmp, vals):
    """|signal j| at `tt`: :func:`_peak_values` computing only what j needs."""
    if j > 2 or (j > 0 and not q[_Q_TAU] > 0.0 and q[_Q_DELAY] > 0.0):
        # (_peak_values finds the state itself)
        _peak_values(tt, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg, ytmp, vals)
        return vals[j]
    _state_at(tt, rec, n_pc, y0, m, ytmp)
    if j == 0:
        v = abs(ytmp[1])
    elif q[_Q_TAU] > 0.0:
        v = abs(ytmp[2 + j])  # the actuator's angles are states
    else:
        # the clipped commands, with the operations of _point_signals
        kappa = _curvature(ytmp[0], q, br, co)
        fb = -k1 * ytmp[1] - k2 * ytmp[2]
        if j == 1:
            raw = fb
            if q[_Q_FF] != 0.0:
                raw = fb + _feedforward_angle(kappa, q)
            v = abs(min(max(raw, -q[_Q_MAX_F]), q[_Q_MAX_F]))
        else:
            v = abs(min(max(a * fb, -q[_Q_MAX_R]), q[_Q_MAX_R]))
    return v if math.isfinite(v) else np.inf


@_jit
def _refine_peak(lo, hi, j, best, rec, n_pc, y0, m, V, k1, k2, a, q, br, co,
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
    fx = -_peak_value(x, j, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg, ytmp, vals)
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
        fu = -_peak_value(
            x, j, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg, ytmp, vals
        )
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


@_jit
def _falls_from_end(end, other, f_end, f_other, j, best, rec, n_pc, y0, m, V,
                    k1, k2, a, q, br, co, d_cg, ytmp, vals):  # fmt: skip
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
        v = _peak_value(x, j, rec, n_pc, y0, m, V, k1, k2, a, q, br, co, d_cg,
                        ytmp, vals)  # fmt: skip
        if v > best[0]:
            best[0], best[1] = v, x
        if not v <= prev:
            return False
        prev = v
    return f_other <= prev


@_jit
def _sample_value(signals, i, j, k):
    """|peak signal j| of run i at output sample k, with _peak_values' inf
    where it is not finite (the state there is)."""
    v = abs(signals[i, _PEAK_COLS[j], k])
    return v if np.isfinite(v) else np.inf


@_jit
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


@_jit
def _peaks_batch(rec, offsets, Y0, P, q, br, co, d_cg, t_eval, signals, t_stop,
                 values, times):  # fmt: skip
    n, m = Y0.shape
    T = t_eval.size
    ytmp = np.empty(m)
    vals = np.empty(_N_PEAK)
    best = np.empty(2)
    ks_all = np.empty(_N_PEAK, dtype=np.int64)
    sv_all = np.empty(_N_PEAK)
    cand = np.empty(_PEAK_CAND, dtype=np.int64)
    cval = np.empty(_PEAK_CAND)
    for i in range(n):
        V, k1, k2, a = P[i, _P_SPEED], P[i, _P_K1], P[i, _P_K2], P[i, _P_RATIO]
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
        for j in range(_N_PEAK):
            ks_all[j] = -1
            sv_all[j] = -np.inf
        for k in range(T):
            if not np.isfinite(signals[i, 3, k]):
                continue
            for j in range(_N_PEAK):
                v = _sample_value(signals, i, j, k)
                if ks_all[j] < 0 or v > sv_all[j]:
                    ks_all[j], sv_all[j] = k, v
        # node values per signal, contiguous (the searches below run along
        # one signal)
        node_v = np.empty((_N_PEAK, K))
        for k in range(K):
            kk = sample_n[k]
            if kk >= 0:
                for j in range(_N_PEAK):
                    node_v[j, k] = _sample_value(signals, i, j, kk)
                continue
            _peak_values(times_n[k], pc, n_pc, Y0[i], m, V, k1, k2, a, q, br, co,
                         d_cg, ytmp, vals)  # fmt: skip
            for j in range(_N_PEAK):
                node_v[j, k] = vals[j]
        for j in range(_N_PEAK):
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
                    Y0[i], m, V, k1, k2, a, q, br, co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    continue
                if k == K - 1 and _falls_from_end(
                    hi, lo, row[k], row[k_lo], j, best, pc, n_pc,
                    Y0[i], m, V, k1, k2, a, q, br, co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    continue
                _refine_peak(lo, hi, j, best, pc, n_pc, Y0[i], m, V, k1, k2,
                             a, q, br, co, d_cg, ytmp, vals)  # fmt: skip
            if ks >= 0 and np.isfinite(sv):
                lo = t_eval[max(ks - 1, 0)]
                hi = max(min(t_eval[min(ks + 1, T - 1)], ts), lo)
                if not hi > lo:
                    pass
                elif t_eval[ks] == lo and _falls_from_end(
                    lo, hi, sv, -np.inf, j, best, pc, n_pc, Y0[i], m, V, k1, k2,
                    a, q, br, co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    pass
                elif t_eval[ks] == hi and _falls_from_end(
                    hi, lo, sv, -np.inf, j, best, pc, n_pc, Y0[i], m, V, k1, k2,
                    a, q, br, co, d_cg, ytmp, vals,
                ):  # fmt: skip
                    pass
                else:
                    _refine_peak(lo, hi, j, best, pc, n_pc, Y0[i], m, V, k1, k2,
                                 a, q, br, co, d_cg, ytmp, vals)  # fmt: skip
            values[i, j] = best[0]
            times[i, j] = best[1]


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


@_jit
def _rms2(x):
    return math.sqrt(np.sum(x * x) / x.size)


@_jit
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
_NRS = 7


@_jit
def _radau_start(t, y, h0, p, q, breaks, coefs, rs, J):
    """Radau's state at a (re)start at ``(t, y)`` with first step `h0`."""
    closed_loop_jac(t, y, p, q, breaks, coefs, J)
    rs[_RS_H] = h0
    rs[_RS_H_OLD] = -1.0
    rs[_RS_ERR_OLD] = -1.0
    rs[_RS_CURRENT_JAC] = 1.0
    rs[_RS_HAVE_LU] = 0.0
    rs[_RS_HAVE_SOL] = 0.0
    rs[_RS_T_OLD] = t


@_jit
def _radau_step(
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
    tol_newton = max(10 * _EPS / rtol, min(0.03, rtol**0.5))
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
            h_abs *= max(_MIN_FACTOR, safety * factor)
            have_lu = False
            rejected = True
            n_rej += 1
        else:
            accepted = True
    recompute_jac = n_iter > 2 and rate > 1e-3
    factor = _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old)
    factor = min(_MAX_FACTOR, safety * factor)
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


@_jit
def _radau_dense(Q, F):
    """Radau's dense output ``Q @ (x, x^2, x^3)`` as DOP853's coefficients.

    :func:`_dense_eval` computes ``y_old + x (F0 + (1 - x) (F1 + x (F2 +
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


@_jit
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
    -1 step too small. The engines step with :func:`_radau_step`, which this
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
    rs = np.empty(_NRS)
    J = np.empty((n, n))
    _radau_start(t, y, h0, p, q, breaks, coefs, rs, J)
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
        status, t_new, _, _ = _radau_step(
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


def _exact_pieces(path) -> tuple[list[float], list[list[float]]] | None:
    """Breaks and coefficients of an exactly representable path, else None."""
    if isinstance(path, Straight):
        return [0.0, path.length], [[0.0, 0.0, 0.0, 0.0]]
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
    if model == "dynamic" and delay > 0.0:
        raise ValueError(
            f"model='dynamic' is compiled without a delay only, got delay={delay!r}"
        )
    if delay > 0.0 and (method != "DOP853" or switching):
        raise ValueError(
            f"delay={delay!r} is compiled with method='DOP853' and switching=False "
            f"only, got method={method!r}, switching={switching!r}"
        )
    q = np.empty(_NQ)
    q[_Q_WHEELBASE] = vehicle.wheelbase
    q[_Q_FF] = 1.0 if feedforward else 0.0
    q[_Q_MAX_F] = _limit(vehicle.max_steer_front)
    q[_Q_MAX_R] = _limit(vehicle.max_steer_rear)
    q[_Q_TAU] = 0.0 if time_constant is None else float(time_constant)
    q[_Q_RATE_F] = _limit(vehicle.max_steer_rate_front)
    q[_Q_RATE_R] = _limit(vehicle.max_steer_rate_rear)
    q[_Q_STEER_MARGIN] = steer_margin
    q[_Q_CURV_MARGIN] = curvature_margin
    q[_Q_PERIOD] = table.period
    if table.period > 0.0:
        q[_Q_S_LO], q[_Q_S_HI] = 0.0, table.period
    elif math.isfinite(table.open_length):
        q[_Q_S_LO], q[_Q_S_HI] = 0.0, table.open_length
    else:
        q[_Q_S_LO], q[_Q_S_HI] = -math.inf, math.inf
    q[_Q_OPEN_LENGTH] = table.open_length
    q[_Q_SWITCH] = 1.0 if switching else 0.0
    # the method of steps: a stage at t + h needs the state at t + h - delay,
    # known (accepted) only if h <= delay
    q[_Q_MAX_STEP] = float(min(max_step, delay)) if delay > 0.0 else float(max_step)
    q[_Q_DELAY] = float(delay)
    q[_Q_DYNAMIC:] = 0.0  # (with the law slots: the paper's law)
    q[Q_CURVATURE_ROWS] = table.coefs.shape[0]
    if model == "dynamic":
        require_dynamics(vehicle, tyre=tyre)
        q[_Q_DYNAMIC] = 1.0
        q[_Q_MASS] = vehicle.mass
        q[_Q_INERTIA] = vehicle.yaw_inertia
        q[_Q_L_F] = vehicle.wheelbase - vehicle.rear_to_cg
        q[_Q_L_R] = vehicle.rear_to_cg
        q[_Q_C_F] = vehicle.cornering_front
        q[_Q_C_R] = vehicle.cornering_rear
        if tyre == "magic":
            load_f, load_r = axle_loads(vehicle)
            q[_Q_PEAK_F] = vehicle.friction * load_f
            q[_Q_PEAK_R] = vehicle.friction * load_r
    q[_Q_METHOD] = float(METHODS.index(method))
    # a curvature equal to the first piece's constant term (every s of an
    # arc or a straight) takes its feedforward angle from here, computed by
    # the kernels' own compiled equation, so the angle is the one they would
    # compute
    k0 = float(table.coefs[0, 0])
    q[_Q_KAPPA0] = k0
    q[_Q_FF_ANGLE0] = _feedforward(vehicle.wheelbase, k0)
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
        controller that declares a compiled law (DOP853, no delay).
    delay : float, optional
        Input delay [s]: compiled with DOP853 (the method of steps).
    method : str or scipy.integrate.OdeSolver, optional
        Only :data:`METHODS` (``"DOP853"``, ``"Radau"`` or their classes)
        are compiled; with a delay only DOP853.
    model : {"kinematic", "dynamic"}, optional
        Vehicle model: the dynamic one is compiled with DOP853 and without
        a delay.

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
    if code > 0 and (compiled_method(method) != "DOP853" or delay != 0.0):
        return (
            "a controller's compiled law runs with method='DOP853' and without "
            f"an input delay only, got method={method!r}, delay={delay!r}"
        )
    if compiled_method(method) is None:
        return f"only method={METHODS} is compiled, got {method!r}"
    if delay != 0.0 and compiled_method(method) != "DOP853":
        return f"an input delay is compiled with method='DOP853' only, got {method!r}"
    if model == "dynamic" and compiled_method(method) != "DOP853":
        return f"model='dynamic' is compiled with method='DOP853' only, got {method!r}"
    if model == "dynamic" and delay != 0.0:
        return "model='dynamic' with an input delay is not compiled"
    if model not in ("kinematic", "dynamic"):
        return f"model={model!r} is not compiled"
    if _exact_pieces(path) is None and not math.isfinite(float(path.length)):
        return "an unbounded path other than Straight has no curvature table"
    return None


def integrate_compiled(
    vehicle: Vehicle,
    path: Path | CurvatureTable,
    gains: SteeringGains,
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
        model adds the rows ``v_y, r`` last. DOP853 without a delay only.
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
    if (time_constant is not None or dyn) and code > 0:
        cmd = initial_command(vehicle, path, gains, z0, table(z0[:, 0]), speed)
    elif time_constant is not None or dyn:
        kappa = table(z0[:, 0])
        cmd = steering_command(
            vehicle,
            SteeringGains(P[:, _P_K1], P[:, _P_K2], P[:, _P_RATIO]),
            z0[:, 1],
            z0[:, 2],
            curvature=kappa,
            feedforward=feedforward,
        )
    if time_constant is not None:
        # The actuator starts at the command: no initial transient of its own.
        Y0[:, 3:5] = np.stack(cmd, axis=1)
    if dyn:
        # the no-slip motion at the initial steering, where not given
        with np.errstate(invalid="ignore"):
            vy0, r0 = equations.no_slip_body_state(
                speed, vehicle.wheelbase, vehicle.rear_to_cg, cmd[0], cmd[1]
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
    rec = np.empty((64 * n if keep else 0, 2 + (_NPOW + 1) * m))
    solve = _solve_batch_radau if q[_Q_METHOD] == _RADAU else _solve_batch
    with compiling(METHODS[int(q[_Q_METHOD])]):
        rec = solve(
            Y0, P, q, breaks, coefs, t_eval, rtol, atol, out, codes, t_stop, stats,
            rec, offsets, keep,
        )  # fmt: skip
    if keep:
        solution.append(
            CompiledSolution(
                records=rec[: offsets[-1]],
                offsets=offsets,
                initial_state=Y0,
                delay=float(q[_Q_DELAY]),
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


def _run_parameters(gains: SteeringGains, speed: np.ndarray) -> np.ndarray:
    n = speed.size
    P = np.zeros((n, _NP))  # clip modes 0
    P[:, _P_SPEED] = speed
    if not isinstance(gains, SteeringGains):  # a controller's compiled law
        P[:, P_LAW : P_LAW + 6] = law_parameters(gains, n)
        return P
    for col, v in ((_P_K1, gains.k1), (_P_K2, gains.k2), (_P_RATIO, gains.ratio)):
        P[:, col] = np.broadcast_to(np.asarray(v, dtype=float).ravel(), (n,))
    return P


def compiled_outputs(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
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
) -> np.ndarray:
    """All signals of :data:`~fws_control.simulation.engine.SIGNALS`, compiled.

    The compiled counterpart of
    :func:`~fws_control.simulation.engine.compute_outputs` for the paper's
    law: ``s, e, theta``, the steering angles, their exact rates (chain rule
    through the law and the curvature table's derivative, zero where an
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
    if law_code(gains) != 0:
        raise ValueError(
            "compiled_outputs computes the paper's law (SteeringGains); a "
            "controller's: compiled_laws.controller_outputs"
        )
    table = curvature_table(path) if table is None else table
    delay = 0.0 if solution is None else solution.delay
    q = shared_parameters(
        vehicle, table, feedforward=feedforward, time_constant=time_constant,
        delay=delay, model=model, tyre=tyre,
    )  # fmt: skip
    speed = np.ascontiguousarray(speed, dtype=float).ravel()
    P = _run_parameters(gains, speed)
    st = np.moveaxis(np.asarray(states, dtype=float), 0, 1)  # (n, m, T)
    n, m, T = st.shape
    if n != speed.size:
        raise ValueError(f"states must hold {speed.size} runs, got {n}")
    if out is None:
        out = np.empty((n, _NSIG, T))
    elif out.shape != (n, _NSIG, T) or out.dtype != np.float64:
        raise ValueError(
            f"out must be a float64 array of shape {(n, _NSIG, T)}, got "
            f"{out.dtype} {out.shape}"
        )
    if isinstance(path, Straight):
        pose = np.array([1.0, *path.start, path.start_heading, 0.0])
    elif isinstance(path, Arc):
        pose = np.array([2.0, *path.start, path.start_heading, path.kappa])
    else:
        pose = np.zeros(5)
    with compiling("signals"):
        _signals_batch(
            st, P, q, table.breaks, table.coefs, float(vehicle.rear_to_cg), pose, out
        )
        if delay > 0.0:
            if t_eval is None or t_eval.shape != (T,):
                raise ValueError(
                    f"t_eval must be the {T} output times of the states with an "
                    f"input delay, got {None if t_eval is None else t_eval.shape}"
                )
            _delayed_signals_batch(
                st, P, q, table.breaks, table.coefs, float(vehicle.rear_to_cg),
                np.ascontiguousarray(solution.records), solution.offsets,
                np.ascontiguousarray(solution.initial_state, dtype=float),
                np.ascontiguousarray(t_eval, dtype=float), out,
            )  # fmt: skip
    S = out[:, 3]
    valid = np.isfinite(S)
    if pose[0] == 0.0:
        # other paths: position and heading from the path (numpy), psi
        # unwrapped in time (a stopped run's NaN tail held at its last value)
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
    # psi on the branch of the given initial heading
    psi0 = np.asarray(initial_heading, dtype=float)
    shift = 2 * math.pi * np.round((psi0 - out[:, 2, 0]) / (2 * math.pi))
    out[:, 2] += np.nan_to_num(shift)[:, None]
    return out


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
    gains: SteeringGains,
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
    such as a kink of a spline's curvature table, up to about 1e-8).

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
    if law_code(gains) != 0:
        raise ValueError(
            "compiled_peaks computes the paper's law (SteeringGains); a "
            "controller's: compiled_laws.controller_outputs"
        )
    table = path if isinstance(path, CurvatureTable) else curvature_table(path)
    q = shared_parameters(
        vehicle, table, feedforward=feedforward, time_constant=time_constant,
        delay=solution.delay, model=model, tyre=tyre,
    )  # fmt: skip
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
    if signals.shape != (n, _NSIG, t_eval.size):
        raise ValueError(
            f"signals must have shape {(n, _NSIG, t_eval.size)}, got {signals.shape}"
        )
    values = np.empty((n, _N_PEAK))
    times = np.empty((n, _N_PEAK))
    with compiling("peaks"):
        _peaks_batch(
            np.ascontiguousarray(solution.records), solution.offsets, Y0, P, q,
            table.breaks, table.coefs, float(vehicle.rear_to_cg), t_eval, signals,
            np.ascontiguousarray(t_stop, dtype=float), values, times,
        )  # fmt: skip
    return values, times
