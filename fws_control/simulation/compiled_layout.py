"""The compiled engine's shared layout: its parameter vectors, its sizes,
the decorators of its kernels and the equations compiled for them.

Every kernel of the compiled engine (:mod:`~fws_control.simulation.compiled`)
takes a shared parameter vector ``q`` (one per call) and a per-run vector
``p``; the slots of both are named here (``Q_*``, ``P_*``), with the sizes of
DOP853's dense output and of the event vector that the kernels share, and
:data:`EQUATIONS`, every function of :mod:`fws_control.equations` compiled
by numba, which the kernels inline.
"""

from __future__ import annotations

import importlib.util
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import scipy

from .. import equations
from .compilation import jit
from .outcomes import SIGNALS

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []


def jit_inline(fn):
    # As jit, and numba inlines the kernel into every compiled caller (at
    # numba-IR level; a direct call from Python still works, with jit's
    # settings). Inlined, the kernel takes its caller's error_model and
    # nogil: every caller here is compiled with jit. For the small
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
    # Not for curvature_at, wrap_lap and feedforward_angle: inlined into
    # the right-hand side as well, they made the integration 1.07x slower.
    return jit(fn, inline="always")


def _table_piece(x, breaks, row, pieces):
    """The piece ``row + j`` of a table holding `x`: ``searchsorted(...,
    side="right") - 1`` on ``breaks[row : row + pieces + 1]``, clipped to
    ``[row, row + pieces - 1]``.

    The tables of a run share one ``breaks`` array (the curvature's rows
    first, then a law's geometry or a speed profile), so each search keeps
    to its own rows. A binary search over them, not ``np.searchsorted`` on
    a slice: the slice's array view cost 35 ns at each evaluation of the
    right-hand side (170 instead of 135 ns on the paper's curve), a fifth
    of it.
    """
    lo, hi = row, row + pieces
    # invariant: breaks[lo] <= x < breaks[hi] (or x beyond an end)
    if x < breaks[lo]:
        return row
    if x >= breaks[hi]:
        return row + pieces - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if breaks[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


# (declared: numba's dispatcher has no type of its own)
table_piece: Callable[[float, np.ndarray, int, int], int] = jit_inline(_table_piece)


def _load_dop853_tableau() -> types.ModuleType:
    """scipy's own DOP853 tableau (``scipy.integrate._ivp.dop853_coefficients``).

    The port takes exactly scipy's steps because it uses scipy's tableau (a
    private scipy module: the test suite checks the port step by step against
    :class:`scipy.integrate.DOP853`, so a change there cannot go unseen). The
    module needs only numpy, but importing it by name runs
    ``scipy/integrate/__init__``, which brings scipy.optimize, scipy.linalg,
    scipy.sparse and scipy.special: half a second before the first result of
    a process that runs compiled kernels from the cache. So it is loaded from
    its file; if scipy has moved it, by name.
    """
    name = "scipy.integrate._ivp.dop853_coefficients"
    file = Path(scipy.__file__).parent / "integrate" / "_ivp" / "dop853_coefficients.py"
    spec = importlib.util.spec_from_file_location(
        "fws_control._scipy_dop853_coefficients", file
    )
    if spec is None or spec.loader is None or not file.is_file():
        return importlib.import_module(name)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


#: scipy's DOP853 tableau, the module (see :func:`_load_dop853_tableau`).
DOP853_TABLEAU = _load_dop853_tableau()
_dop = DOP853_TABLEAU

# The sizes of scipy's DOP853 tableau that the layouts below use (the
# tableau itself: compiled_dop853)
NS = _dop.N_STAGES  # 12
NSE = _dop.N_STAGES_EXTENDED  # 16
NPOW = _dop.INTERPOLATOR_POWER  # 7
EPS = float(np.finfo(float).eps)


#: The features of a call that a kernel may be compiled without (see
#: :mod:`~fws_control.simulation.compiled_variants`): each kernel tests its
#: flag before the parameter that switches the feature on, as in ``if
#: WITH_DELAY and q[Q_DELAY] > 0.0``. Here all are True (the kernels of
#: every call); a variant compiled without a feature sees its flag False,
#: a constant, and numba leaves that branch out before compiling it.
WITH_DELAY = True
WITH_DYNAMIC = True
WITH_LAW = True
WITH_PROFILE = True

# Layout of the shared parameter vector (one per call).
Q_WHEELBASE, Q_FF, Q_MAX_F, Q_MAX_R, Q_TAU = 0, 1, 2, 3, 4
Q_RATE_F, Q_RATE_R, Q_STEER_MARGIN, Q_CURV_MARGIN = 5, 6, 7, 8
Q_PERIOD, Q_S_LO, Q_S_HI, Q_OPEN_LENGTH = 9, 10, 11, 12
Q_SWITCH = 13  # 1: clips as modes switched at located events; 0: min/max
Q_MAX_STEP = 14  # scipy's max_step (inf: none)
# the first table piece's constant curvature and its feedforward angle
# atan(f kappa0), computed once (see feedforward_angle)
Q_KAPPA0, Q_FF_ANGLE0 = 15, 16
Q_METHOD = 17  # 0: DOP853, 1: Radau (see METHODS)
RADAU = 1  # q[Q_METHOD] of Radau, and the constant of its drivers
Q_DELAY = 18  # input delay [s] (0: none)
# the dynamic single-track model (q[Q_DYNAMIC] = 1; its rows v_y, r last):
# mass, yaw inertia, l_f, l_r, the axles' cornering stiffnesses and peak
# forces (0: the linear tyre)
Q_DYNAMIC, Q_MASS, Q_INERTIA, Q_L_F, Q_L_R = 19, 20, 21, 22, 23
Q_C_F, Q_C_R, Q_PEAK_F, Q_PEAK_R = 24, 25, 26, 27
# slots 28-35: a controller's compiled law and the curvature table's rows
# (compiled_laws); 36-43: speed profiles and gain schedules
NQ = 44
# Layout of the per run parameter vector.
P_SPEED, P_K1, P_K2, P_RATIO = 0, 1, 2, 3
# modes of the four clips (front/rear angle, front/rear rate): -1, 0 or +1
P_MODE = 4
# the held mode (-1 or +1) each clip was released from at the restart of
# the current step, 0 otherwise (see event_values)
P_RELEASED = 8
# slots 12-17: a controller's law parameters (compiled_laws); 18-21: speed
# profiles and gain schedules
NP = 22
# With an input delay the driver extends a run's p by its past (the method
# of steps), so that every function given p -- the right-hand side, the
# events, the steps -- can look up the delayed state without another
# argument: p[P_NOW] is the time of the state the events are evaluated on
# (they take no time), p[P_N_HIST] the number of accepted steps held, then
# the initial state (m values) and one row per accepted step laid out as the
# rows of CompiledSolution.records: t_old, h, y_old, DOP853's F.
P_NOW, P_N_HIST, P_HIST = NP, NP + 1, NP + 2
# rows of compiled_outputs, in the order of engine.SIGNALS
NSIG = len(SIGNALS)
N_STOPS = 4
N_EVENTS = 8
# Points of a step (fractions) where, with the dense output kept, the stop
# conditions are checked too (engine._MARGIN_NODES without the step's end).
INNER_NODES = (0.25, 0.5, 0.75)
N_INNER = len(INNER_NODES)
#: Most clip switches per run (a guard against chattering).
MAX_SWITCHES = 100_000


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
    # (see jit_inline): the kernels' own copies of these lines were part of
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
        out[name] = jit_inline(clone)
    shared.update(out)
    return out


#: name -> compiled function of :mod:`fws_control.equations`
EQUATIONS = _compile_equations()
yaw_rate = EQUATIONS["yaw_rate"]
path_frame_derivatives = EQUATIONS["path_frame_derivatives"]
cg_lateral_velocity = EQUATIONS["cg_lateral_velocity"]
yaw_acceleration = EQUATIONS["yaw_acceleration"]
lateral_acceleration = EQUATIONS["lateral_acceleration"]
feedforward_equation = EQUATIONS["feedforward_angle"]
feedforward_rate = EQUATIONS["feedforward_angle_rate"]
feedback_command = EQUATIONS["feedback_command"]
slip_angles = EQUATIONS["slip_angles"]
linear_tyre_force = EQUATIONS["linear_tyre_force"]
magic_tyre_force = EQUATIONS["magic_tyre_force"]
body_derivatives = EQUATIONS["body_derivatives"]
dynamic_path_kinematics = EQUATIONS["dynamic_path_kinematics"]
clip_switch_margin = EQUATIONS["clip_switch_margin"]
