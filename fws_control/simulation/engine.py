r"""Numerical engine of the closed-loop simulation (path frame, many runs).

The closed loop is the path-frame model (eqs. 17-19, corrected, with the
path's curvature :math:`\kappa(s)` at the arclength state) closed with the
controller of eqs. (24)-(29) in one vectorised right-hand side. The states
of ``n`` runs are stacked and stepped by one :mod:`scipy.integrate` solver,
which the engine drives itself (as :func:`scipy.integrate.solve_ivp` would)
so that a run meeting a singular state can leave the stack at that time
while the others go on. No projection is needed during the integration: the
global pose is reconstructed afterwards as ``position(s) + e * normal(s)``,
``psi = theta + heading(s)``.

A run stops, and is marked rather than raising, when the model becomes
singular: a front steering angle :math:`|\delta_f| = \pi/2` (the yaw rate of
eq. 10 diverges), :math:`1-\kappa e = 0` (the vehicle reaches the centre of
curvature and the projection is lost) or the end of an open path.

This module is the engine only; :mod:`~fws_control.simulation.runners`
validates the user's arguments and builds the
:class:`~fws_control.simulation.result.SimulationResult`. Its public names
(:func:`time_grid`, :func:`initial_path_state`, :func:`integrate`,
:func:`compute_outputs`, ...) are the interface between the modules of the
subpackage, not part of the top-level API.
"""

from __future__ import annotations

import bisect
import heapq
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, OdeSolver, Radau
from scipy.optimize import brentq

from .. import equations
from ..acceleration import lateral_acceleration
from ..baselines import saturate
from ..controllers import (
    DEFAULT_ACTUATOR_TIME_CONSTANT,
    actuator_rate,
    steering_command,
    steering_command_rate,
)
from ..dynamics import (
    TYRES,
    dynamic_path_derivatives,
    require_dynamics,
    slip_angles,
)
from ..gains import SteeringGains
from ..models import yaw_rate
from ..paths import Arc, Path, Straight
from ..validation import MAX_ANGLE, check_finite, check_positive
from ..vehicle import Vehicle

__all__ = [
    "SIGNALS",
    "STATUS_OK",
    "STATUS_SINGULAR_STEERING",
    "STATUS_SINGULAR_CURVATURE",
    "STATUS_END_OF_PATH",
    "STATUS_FAILED",
    "STATUS_UNCONTROLLABLE",
    "STATUSES",
    "STOP_MARGIN",
    "SOLVERS",
    "check_method",
    "check_tolerances",
    "choose_method",
    "LONG_RUN_STEPS",
    "SAFE_STEP",
    "LSODA_MAX_RUNS",
    "STIFF_TIME_CONSTANT",
    "MAX_STEPS",
    "RTOL_RANGE",
    "ATOL_RANGE",
    "check_initial_state",
    "MODELS",
    "check_model",
    "split_initial_state",
    "run_gains",
    "resolve_time_constant",
    "time_grid",
    "MAX_OUTPUT_BYTES",
    "output_samples",
    "check_output_budget",
    "initial_path_state",
    "integrate",
    "compute_outputs",
    "PEAK_SIGNALS",
    "DenseSolution",
    "exact_peaks",
    "scheduled_gains",
]

#: The run reached the final time.
STATUS_OK = "ok"
#: The front steering angle reached :math:`|\delta_f| = \pi/2 - 10^{-3}`
#: (:data:`STOP_MARGIN` before the singular yaw rate).
STATUS_SINGULAR_STEERING = "singular_steering"
#: :math:`1 - \kappa e` reached :math:`10^{-3}` (:data:`STOP_MARGIN`): the
#: vehicle is at the centre of curvature.
STATUS_SINGULAR_CURVATURE = "singular_curvature"
#: The projection left an open path of finite length.
STATUS_END_OF_PATH = "end_of_path"
#: The ODE solver failed (its message is kept).
STATUS_FAILED = "failed"
#: No gains exist for the requested design (used by the paper's scenarios
#: for ``ratio = 1`` on a straight road); the run was not simulated.
STATUS_UNCONTROLLABLE = "uncontrollable"

#: Every status a run can have, :data:`STATUS_OK` first.
STATUSES = (
    STATUS_OK,
    STATUS_SINGULAR_STEERING,
    STATUS_SINGULAR_CURVATURE,
    STATUS_END_OF_PATH,
    STATUS_FAILED,
    STATUS_UNCONTROLLABLE,
)

#: The scipy solvers accepted by name as ``method``.
SOLVERS: dict[str, type[OdeSolver]] = {
    "DOP853": DOP853,
    "RK45": RK45,
    "RK23": RK23,
    "Radau": Radau,
    "BDF": BDF,
    "LSODA": LSODA,
}

# Order of the rows of _Engine.margins: the stop condition of each row.
_STOP_KINDS = (STATUS_SINGULAR_STEERING, STATUS_SINGULAR_CURVATURE, STATUS_END_OF_PATH)

#: Names of the time series of a result, in order.
SIGNALS = (
    "x",
    "y",
    "psi",
    "s",
    "e",
    "theta",
    "delta_f",
    "delta_r",
    "delta_f_rate",
    "delta_r_rate",
    "lateral_accel",
    "v_y",
    "yaw_rate",
    "slip_front",
    "slip_rear",
)

#: Vehicle models of the engine: the paper's kinematic model and the dynamic
#: single-track model of :mod:`fws_control.dynamics` (tyre slip, states
#: ``v_y`` and ``r`` added after the others).
MODELS = ("kinematic", "dynamic")


# --------------------------------------------------------------------------
# Argument preparation shared by the runners and the reference


def check_method(method: Any) -> type[OdeSolver]:
    """The solver class for `method` (a name of :data:`SOLVERS` or a class).

    Raises
    ------
    ValueError
        For an unknown name, listing the valid ones.

    Examples
    --------
    >>> from fws_control.simulation.engine import check_method
    >>> check_method("RK45").__name__
    'RK45'
    """
    if isinstance(method, type) and issubclass(method, OdeSolver):
        return method
    try:
        return SOLVERS[method]
    except (KeyError, TypeError):
        raise ValueError(
            f"method must be one of {sorted(SOLVERS)} or an OdeSolver class, "
            f"got {method!r}"
        ) from None


#: Accepted ``rtol``: from scipy's own floor ``100 * eps`` (below it scipy
#: raises rtol silently, with a warning) to 0.1 (a 10 % error per step: any
#: looser setting no longer controls the error, and with ``rtol = 10`` the
#: solver strides across singular states).
RTOL_RANGE = (100 * float(np.finfo(float).eps), 0.1)
#: Accepted ``atol`` (the states are metres and radians): from 1e-20, far
#: below the rounding error of any state of the loop (an absolute tolerance
#: of 1e-300 overflows scipy's error norm of a state at 0: the solver then
#: fails at t = 0), to 0.1 m or rad for the reason of the upper bound of
#: ``rtol``. With steering limits the numpy engine integrates across the
#: clips' kinks inside its steps, and the tightest corner of the ranges
#: costs many steps there: on a rate-limited arc (23 m/s, 6 s) DOP853 took
#: 6712 steps at rtol 1e-13, atol 1e-20, but at most 329 with atol >= 1e-19
#: or rtol >= 1e-12; a run beyond MAX_STEPS ends "failed" with a message
#: naming the tolerances.
ATOL_RANGE = (1e-20, 0.1)


#: Actuator time constant [s] below which ``method="auto"`` integrates with
#: Radau, at ``rtol = 1e-10``; it scales as ``(rtol / 1e-10) ** (1/6)`` (see
#: :func:`choose_method`).
STIFF_TIME_CONSTANT = 0.004

#: Steps DOP853's stability bound forces on a run (``duration / (6.4 T)``)
#: above which ``method="auto"`` integrates a run with LSODA (see
#: :func:`choose_method`).
LONG_RUN_STEPS = 10

#: DOP853's largest step, in units of the actuator time constant T, at which
#: its error estimate still bounds its error on the stiff loop: half its
#: stability bound of about 6.4 T. Used by ``method="auto"`` for a delay
#: (:func:`choose_method`) and for the compiled engine's capped steps
#: (:func:`~fws_control.simulate_batch`).
SAFE_STEP = 3.2

#: Most runs :func:`~fws_control.simulate_batch` stacks in one chunk (by
#: default) when the method is LSODA, whose Jacobian of the stacked runs is
#: dense. Measured, CPU per run at T = 0.05 s on the curve scenario, for
#: 1, 4, 8, 16 and 32 runs per chunk: over 15 s 156, 47, 27, 17.6 and 12.7
#: ms; over 150 s 187, 60, 38, 28 and 39 ms.
LSODA_MAX_RUNS = 16


def choose_method(
    time_constant: float | None,
    rtol: float,
    *,
    duration: float | None = None,
    delay: float = 0.0,
) -> str:
    r"""The solver ``method="auto"`` uses: implicit when the loop is stiff.

    The steering actuator adds the eigenvalue :math:`-1/T` to the loop. An
    explicit method's step is then bounded by stability, not accuracy: DOP853
    steps about :math:`6.4\,T` (measured), so its cost grows as
    ``duration / T`` (with :math:`T = 10^{-5}` s it needed 20,000 steps, 15
    s of CPU, for the first 1.3 s of the paper's scenario; Radau does the
    whole 5 s run in 0.4 s). The
    implicit Radau IIA method (order 5, L-stable) steps by accuracy alone,
    about 0.19 s on the paper's scenario at ``rtol = 1e-10``, but each step
    costs about 3.5 DOP853 steps. Measured on the paper's 15 s scenarios (V
    = 5 and 20 m/s), the two cost the same near :math:`T = 0.004` s (Radau
    1.7x faster at 0.002 s, DOP853 2-3.5x faster at 0.01-0.02 s). Radau's
    accuracy step grows as :math:`rtol^{1/6}` while the stability bound does
    not, so the first rule is

    .. math:: T < 0.004\,\mathrm{s}\cdot(\mathrm{rtol}/10^{-10})^{1/6}
              \Rightarrow \text{Radau.}

    Once the transient has decayed, the stability bound caps DOP853's
    step at about ``6.4 T`` whatever the accuracy asks: a run then costs
    ``duration / (6.4 T)`` steps of 12 right-hand-side evaluations, and,
    worse, DOP853's error estimate no longer bounds its error. Measured on
    the paper's curve scenario at :math:`T` = 0.05 s against a fixed-step
    reference (``tests/test_rate_limit_reference.py``,
    ``benchmarks/bench_rate_limit.py``): DOP853's largest error is 1-4
    tolerances over the first 1-3 s, 21-1900 tolerances from 5 s on (in the
    actuator states, where the steps reach the bound), at every rtol; LSODA
    (Adams steps, switching to BDF where the loop is stiff, stepping by
    accuracy) stays within about 1 tolerance. One run costs about the same
    either way from 6 to 47 such steps (0.09-0.22 s of CPU, within 21 %)
    and LSODA wins beyond (at 1500 s: DOP853 4739 steps, 4.9 s; LSODA 744,
    0.23 s; BDF 3015, 5.5 s; Radau 3506, 11 s). So, with the `duration`
    given, a run of more than :data:`LONG_RUN_STEPS` (10) such steps
    integrates with ``"LSODA"``.

    The rule is the same for every run of a batch, whatever their number:
    a run's accuracy must not depend on the batch it sits in. (DOP853 for
    large batches would be faster and wrong: on the curve scenario at
    T = 0.05 s over 15 s against a fixed-step reference, a run in a DOP853
    batch of 20 is 330 tolerances off, while alone, with LSODA, it is 0.72
    and in a 16-run LSODA chunk 0.74.) :func:`~fws_control.simulate_batch`
    integrates LSODA runs in chunks of :data:`LSODA_MAX_RUNS` (16) runs, its
    Jacobian of the stacked runs being dense (17.3 ms of CPU per run over
    15 s). The compiled engine has no LSODA: with numba, ``engine="auto"``
    runs such runs there with DOP853 held to ``3.2 T``, half its stability
    bound, where its error estimate holds again (5.7 tolerances off the
    reference, 0.24 ms per run), up to 2,500 such steps, and with its port
    of Radau beyond (see :func:`~fws_control.simulate`).

    With an input `delay` the steps are at most the delay (the method of
    steps), so if ``delay <= 3.2 T`` (:data:`SAFE_STEP`, half the stability
    bound) DOP853's error estimate holds: no long-run rule then. Measured
    on a 30 s delayed run (curve 1/100 at 20 m/s, delay 0.24 s, rtol 1e-8)
    against Radau at rtol 1e-12, in tolerances, for delay / T = 0.89, 2,
    3.2, 4, 5, 6, 6.3: DOP853 0.33, 0.38, 0.49, 1.19, 4.8, 7.7, 16; LSODA
    (up to 6) 1.7, 3.9, 1.1, 1.1, 2.5, 2.2, at 1.14, 0.80, 0.82, 0.82, 0.56
    and 0.60 times DOP853's CPU.
    (``tests/test_rate_limit_reference.py``; the threshold was 6.4 T before.)

    Otherwise DOP853; without an actuator (`time_constant` None) the loop is
    not stiff: DOP853.

    Parameters
    ----------
    time_constant : float or None
        Actuator lag :math:`T` [s]; None: no actuator.
    rtol : float
        Relative tolerance of the run.
    duration : float, optional
        Simulated time [s]; None (default): the rule without the long-run
        case (DOP853 or Radau).
    delay : float, optional
        Input delay [s] of the run (default 0), which bounds its steps.

    Returns
    -------
    str
        ``"DOP853"``, ``"Radau"`` or ``"LSODA"``.

    Examples
    --------
    >>> from fws_control.simulation.engine import choose_method
    >>> choose_method(None, 1e-10), choose_method(0.05, 1e-10)
    ('DOP853', 'DOP853')
    >>> choose_method(1e-4, 1e-10), choose_method(0.01, 1e-4)
    ('Radau', 'Radau')
    >>> choose_method(0.05, 1e-10, duration=2.0)  # 6 stability-bound steps
    'DOP853'
    >>> choose_method(0.05, 1e-10, duration=15.0)  # 47
    'LSODA'
    >>> choose_method(0.05, 1e-10, duration=1500.0)  # 4688
    'LSODA'
    >>> choose_method(0.27, 1e-10, duration=30.0, delay=0.24)  # steps <= 0.24 s
    'DOP853'
    >>> choose_method(0.04, 1e-10, duration=30.0, delay=0.24)  # 0.24 s > 3.2 T
    'LSODA'
    """
    if time_constant is None:
        return "DOP853"
    limit = STIFF_TIME_CONSTANT * (rtol / 1e-10) ** (1.0 / 6.0)
    if time_constant < limit:
        return "Radau"
    bounded = 0.0 < delay <= SAFE_STEP * time_constant  # steps held to half the bound
    if (
        duration is not None
        and not bounded
        and duration / (6.4 * time_constant) > LONG_RUN_STEPS
    ):
        return "LSODA"
    return "DOP853"


def check_tolerances(rtol: Any, atol: Any) -> tuple[float, float]:
    """``(rtol, atol)`` as floats if they lie in :data:`RTOL_RANGE`, :data:`ATOL_RANGE`.

    The solver never returns for ``atol = 0`` with a state that starts at
    exactly 0, nor for a NaN or infinite tolerance (its error norm is NaN,
    so every step is rejected and retried): these are refused here, before
    any integration.

    Raises
    ------
    ValueError
        Naming the argument, its value and the valid range.

    Examples
    --------
    >>> from fws_control.simulation.engine import check_tolerances
    >>> check_tolerances(1e-10, 1e-12)
    (1e-10, 1e-12)
    >>> check_tolerances(1e-10, 0.0)
    Traceback (most recent call last):
    ...
    ValueError: atol must be a finite number in [1e-20, 0.1], got 0.0
    """
    lo, hi = RTOL_RANGE
    out = []
    for name, value, ok, span in (
        ("rtol", rtol, lambda v: lo <= v <= hi, f"[{lo:.3g}, {hi:g}]"),
        ("atol", atol, lambda v: ATOL_RANGE[0] <= v <= ATOL_RANGE[1], "[1e-20, 0.1]"),
    ):
        try:
            v = float(value) if not isinstance(value, (bool, str, bytes)) else math.nan
        except (TypeError, ValueError):
            v = math.nan
        if not (math.isfinite(v) and ok(v)):
            raise ValueError(f"{name} must be a finite number in {span}, got {value!r}")
        out.append(v)
    return out[0], out[1]


def check_initial_state(initial_state: Any) -> np.ndarray:
    """Initial poses ``(x_R, y_R, psi)`` as an array of shape ``(runs, 3)``.

    Raises
    ------
    ValueError
        If the values are not finite, the last axis is not of length 3 or
        a heading's magnitude exceeds
        :data:`~fws_control.validation.MAX_ANGLE`.

    Examples
    --------
    >>> from fws_control.simulation.engine import check_initial_state
    >>> check_initial_state((0.0, 2.0, 0.0)).shape
    (1, 3)
    """
    arr = np.asarray(check_finite("initial_state", initial_state), dtype=float)
    if arr.shape[-1:] != (3,) or arr.ndim > 2:
        raise ValueError(
            "initial_state must be (x_R, y_R, psi) or an array of shape (runs, 3), "
            f"got shape {arr.shape}"
        )
    _check_heading(arr)
    return np.atleast_2d(arr)


def _check_heading(arr: np.ndarray) -> None:
    """Refuse initial headings too large to name a direction (MAX_ANGLE)."""
    psi = np.abs(arr[..., 2])
    if np.any(psi > MAX_ANGLE):
        raise ValueError(
            f"initial_state heading psi must have magnitude <= {MAX_ANGLE:g} rad "
            "(it is used modulo 2 pi, and a larger double names no direction), "
            f"got {float(np.max(psi))!r}"
        )


def check_model(vehicle: Vehicle, model: Any, tyre: Any) -> tuple[str, str]:
    """``(model, tyre)`` if valid for `vehicle`.

    Raises
    ------
    ValueError
        For a model not in :data:`MODELS`, a tyre not in
        :data:`~fws_control.dynamics.TYRES`, ``tyre="magic"`` with the
        kinematic model (which has no tyres), or a vehicle without the data
        of the dynamic model (:func:`~fws_control.dynamics.require_dynamics`).

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.engine import check_model
    >>> check_model(fws.Vehicle(2.7, 1.35), "kinematic", "linear")
    ('kinematic', 'linear')
    >>> check_model(fws.Vehicle(2.7, 1.35), "dynamic", "linear")
    Traceback (most recent call last):
    ...
    ValueError: the dynamic model needs Vehicle fields mass [kg], \
yaw_inertia [kg m^2], cornering_front [N/rad per axle], cornering_rear \
[N/rad per axle]; they are None in the vehicle given
    """
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    if tyre not in TYRES:
        raise ValueError(f"tyre must be one of {TYRES}, got {tyre!r}")
    if model == "kinematic" and tyre != "linear":
        raise ValueError(
            f"tyre={tyre!r} needs model='dynamic' (the kinematic model has no "
            "tyre forces), got model='kinematic'"
        )
    if model == "dynamic":
        require_dynamics(vehicle, tyre=tyre)
    return model, tyre


def split_initial_state(initial_state: Any, *, model: str) -> np.ndarray:
    """Initial states as an array ``(runs, 5)``: pose and ``(v_y, r)``.

    The kinematic model takes poses ``(x_R, y_R, psi)``; the dynamic model
    also ``(x_R, y_R, psi, v_y, r)`` (lateral velocity of G [m/s] and yaw
    rate [rad/s]). Columns 3 and 4 are NaN where not given: the engine then
    starts the dynamic model rolling without tyre slip at the initial
    steering angles (:func:`integrate`).

    Raises
    ------
    ValueError
        If the values are not finite, the last axis has the wrong length or
        a heading's magnitude exceeds
        :data:`~fws_control.validation.MAX_ANGLE`.

    Examples
    --------
    >>> from fws_control.simulation.engine import split_initial_state
    >>> split_initial_state((0.0, 2.0, 0.0), model="dynamic").tolist()
    [[0.0, 2.0, 0.0, nan, nan]]
    >>> split_initial_state((0.0, 2.0, 0.0, 0.1, 0.0), model="dynamic").shape
    (1, 5)
    """
    arr = np.asarray(check_finite("initial_state", initial_state), dtype=float)
    sizes = (3, 5) if model == "dynamic" else (3,)
    if arr.ndim == 0 or arr.shape[-1] not in sizes or arr.ndim > 2:
        shapes = (
            "(x_R, y_R, psi), (x_R, y_R, psi, v_y, r) or an array of shape "
            "(runs, 3) or (runs, 5)"
            if model == "dynamic"
            else "(x_R, y_R, psi) or an array of shape (runs, 3)"
        )
        raise ValueError(
            f"initial_state must be {shapes} for model={model!r}, got shape {arr.shape}"
        )
    _check_heading(arr)
    arr = np.atleast_2d(arr)
    if arr.shape[1] == 5:
        return arr
    return np.concatenate([arr, np.full((arr.shape[0], 2), np.nan)], axis=1)


def run_gains(gains: Any, *, name: str = "gains") -> SteeringGains:
    """One :class:`SteeringGains` with 1-D arrays, one entry per run.

    Parameters
    ----------
    gains : SteeringGains or sequence of SteeringGains
        Fields that broadcast (flattened), or one design per element.
    name : str, optional
        The caller's argument name, used in error messages.

    Raises
    ------
    TypeError
        If `gains` is neither a SteeringGains nor a non-empty sequence of them.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.engine import run_gains
    >>> g = run_gains([fws.SteeringGains(0.1, 0.5, 0.0),
    ...                fws.SteeringGains([0.2, 0.3], 0.6, -1.0)])
    >>> g.k1.tolist(), g.ratio.tolist()
    ([0.1, 0.2, 0.3], [0.0, -1.0, -1.0])
    """
    if isinstance(gains, SteeringGains):
        k1, k2, a = np.broadcast_arrays(
            np.asarray(gains.k1, dtype=float),
            np.asarray(gains.k2, dtype=float),
            np.asarray(gains.ratio, dtype=float),
        )
        return SteeringGains(k1.ravel().copy(), k2.ravel().copy(), a.ravel().copy())
    try:
        items = list(gains)
    except TypeError:
        raise TypeError(
            f"{name} must be a SteeringGains, a sequence of SteeringGains or a "
            f"lateral controller (e.g. fws.PurePursuit()), got {type(gains).__name__}"
        ) from None
    if not items or not all(isinstance(g, SteeringGains) for g in items):
        raise TypeError(
            f"{name} must be a SteeringGains or a non-empty sequence of "
            f"SteeringGains, got {gains!r}"
        )
    parts = [run_gains(g, name=name) for g in items]
    return SteeringGains(
        np.concatenate([p.k1 for p in parts]),
        np.concatenate([p.k2 for p in parts]),
        np.concatenate([p.ratio for p in parts]),
    )


def resolve_time_constant(vehicle: Vehicle, value: float | None) -> float | None:
    r"""Time constant of the steering actuator, or None when there is none.

    The actuator is the first-order lag of
    :func:`~fws_control.controllers.steering_actuator`,
    :math:`T\dot\delta = \delta_{cmd} - \delta`, with the vehicle's rate
    limits (if any) clipping :math:`\dot\delta`. It is in the loop when a
    time constant is given, or when the vehicle has a rate limit (then with
    :data:`~fws_control.controllers.DEFAULT_ACTUATOR_TIME_CONSTANT` unless
    one is given). Otherwise the steering angles equal the commands.

    Parameters
    ----------
    vehicle : Vehicle
        Its rate limits decide whether an actuator is needed by default.
    value : float or None
        Time constant [s], > 0, or None.

    Returns
    -------
    float or None

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.engine import resolve_time_constant
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> resolve_time_constant(veh, None) is None, resolve_time_constant(veh, 0.27)
    (True, 0.27)
    >>> lim = fws.Vehicle(2.7, 1.35, max_steer_rate_front=0.5)
    >>> resolve_time_constant(lim, None), resolve_time_constant(lim, 0.1)
    (0.05, 0.1)
    """
    if value is not None:
        return float(check_positive("steering_lag", value))
    has_rate = (
        vehicle.max_steer_rate_front is not None
        or vehicle.max_steer_rate_rear is not None
    )
    return DEFAULT_ACTUATOR_TIME_CONSTANT if has_rate else None


#: Budget of the output of one call [bytes]: the returned signals, ``runs x
#: len(SIGNALS) x samples x 8`` bytes (float64), may not exceed it; with
#: ``simulate_batch(..., signals=...)`` the kept signals only, and the full
#: signals of one chunk (its working set) apart. 2 GiB is
#: 17.9 million run-samples of the 15 signals: 11,900 runs of the paper's
#: 15 s scenario at the default output step, or one run with dt = 8.4e-7 s.
#: The peak memory of a call is its output, the states (3/15 of it, 5/15 with
#: an actuator) and a bounded block of about 12 MB of temporaries: measured
#: 2.2 times the output at 13 MB, 1.45 times at 132 MB (with 11 signals; it
#: was 4.4 times before the signals were computed in blocks). Larger requests
#: are refused with the way to ask for less (see :func:`check_output_budget`).
MAX_OUTPUT_BYTES = 2 * 2**30


def output_samples(duration: float, *, dt: float = 0.01, t_eval: Any = None) -> float:
    """Number of output times :func:`time_grid` would give, without building them.

    A float, so that an absurd request (``dt = 1e-320``) is a large number
    (or ``inf``) instead of an overflow.

    Examples
    --------
    >>> from fws_control.simulation.engine import output_samples
    >>> output_samples(15.0, dt=0.01), output_samples(15.0, dt=1e-320)
    (1501.0, inf)
    """
    if t_eval is not None:
        return float(np.size(t_eval))
    duration = float(check_positive("duration", duration))
    dt = float(check_positive("dt", dt))
    with np.errstate(over="ignore"):
        ratio = duration / dt
    return max(float(round(ratio)) if math.isfinite(ratio) else math.inf, 1.0) + 1.0


def check_output_budget(
    runs: int,
    samples: float,
    *,
    duration: float,
    dt: float,
    t_eval: Any = None,
    signals: int = len(SIGNALS),
) -> None:
    """Refuse a call whose signals would exceed :data:`MAX_OUTPUT_BYTES`.

    The solver chooses its own steps: the output grid (`dt` or `t_eval`)
    only sets where the solution is sampled, not its accuracy, so a request
    for more samples than fit in memory is almost always meant as a finer
    solution, which the tolerances give.

    Parameters
    ----------
    runs : int
        Number of runs whose signals are held at once (a whole batch, or one
        chunk for its working set).
    samples : float
        Output times per run (:func:`output_samples`).
    duration, dt, t_eval
        As given to the runner (named in the message).
    signals : int, optional
        Number of signals kept per run (``simulate_batch(...,
        signals=...)``); default all of :data:`SIGNALS`.

    Raises
    ------
    ValueError
        Naming the arguments, the size asked for and the budget, and saying
        how to get what was meant: a larger `dt`, a `t_eval` with the times
        needed, a shorter `duration` or fewer runs per call.

    Examples
    --------
    >>> from fws_control.simulation.engine import check_output_budget
    >>> check_output_budget(1, 1501.0, duration=15.0, dt=0.01)   # 0.13 MB: fine
    >>> check_output_budget(1, 1.5e10 + 1, duration=15.0, dt=1e-9)
    Traceback (most recent call last):
    ...
    ValueError: dt=1e-09 over duration=15.0 asks for 1.5e+10 output samples ...
    """
    nbytes = float(runs) * float(samples) * signals * 8.0
    if nbytes <= MAX_OUTPUT_BYTES:
        return
    limit = MAX_OUTPUT_BYTES / (signals * 8.0)
    what = (
        f"t_eval of {int(samples)} times"
        if t_eval is not None
        else f"dt={dt!r} over duration={duration!r}"
    )
    raise ValueError(
        f"{what} asks for {samples:.4g} output samples for each of {runs} runs: "
        f"{nbytes / 2**30:.4g} GiB of signals (runs x {signals} signals x "
        f"samples x 8 bytes), more than the budget of "
        f"{MAX_OUTPUT_BYTES / 2**30:g} GiB (runs x samples <= {limit:.4g}). The "
        "solver chooses its own steps: dt only sets the output grid, not the "
        "accuracy (use rtol, atol). Ask for less output: a larger dt, t_eval "
        "with only the times you need, a shorter duration, fewer runs per call, "
        "or (simulate_batch) fewer signals kept, signals=('e', ...) or "
        "signals='metrics'"
    )


def time_grid(duration: float, *, dt: float = 0.01, t_eval: Any = None) -> np.ndarray:
    """Output times: ``linspace(0, duration, round(duration/dt) + 1)`` or `t_eval`.

    Raises
    ------
    ValueError
        For a non-positive `duration` or `dt`, a `t_eval` that is not
        strictly increasing from 0 to at most `duration`, or a grid whose
        signals for one run would exceed :data:`MAX_OUTPUT_BYTES`.

    Examples
    --------
    >>> from fws_control.simulation.engine import time_grid
    >>> time_grid(1.0, dt=0.25).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    duration = float(check_positive("duration", duration))
    if t_eval is None:
        dt = float(check_positive("dt", dt))
        samples = output_samples(duration, dt=dt)
        check_output_budget(1, samples, duration=duration, dt=dt)
        return np.linspace(0.0, duration, int(samples))
    # a copy: the result's t must not change with the caller's array (nor
    # with a simulate_batch(out=...) that shares its memory)
    t = np.array(check_finite("t_eval", t_eval), dtype=float).ravel()
    if t.size < 1 or t[0] != 0.0 or np.any(np.diff(t) <= 0) or t[-1] > duration:
        got = f"{t.size} values" + (f" from {t[0]:g} to {t[-1]:g}" if t.size else "")
        raise ValueError(
            "t_eval must be strictly increasing, start at 0 and end at or before "
            f"duration={duration}, got {got}"
        )
    return t


def initial_path_state(path: Path, initial_state: np.ndarray) -> np.ndarray:
    r"""Project global poses ``(runs, 3)`` onto `path` -> ``(s, e, theta)`` rows.

    The heading error is wrapped to :math:`[-\pi, \pi]`.

    Raises
    ------
    AmbiguousProjectionError
        If a position has no unique closest point on the path.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.paths import Arc
    >>> from fws_control.simulation.engine import initial_path_state
    >>> initial_path_state(Arc(curvature=0.1), np.array([[0.0, -5.0, 0.0]]))
    array([[ 0., -5.,  0.]])
    """
    out = np.empty_like(initial_state, dtype=float)
    for i, (x0, y0, psi0) in enumerate(initial_state):
        p = path.project(float(x0), float(y0), strict=True)
        theta0 = math.remainder(float(psi0) - float(p.heading), 2 * math.pi)
        out[i] = (float(p.s), float(p.e), theta0)
    return out


# --------------------------------------------------------------------------
# The vectorised closed loop


def _curvature_function(path):
    """``s -> kappa(s)`` for `path`, with the constant cases short-cut."""
    if isinstance(path, (Arc, Straight)):
        k = float(Path.curvature(path, 0.0))
        return lambda s: np.full(np.shape(s), k)
    return path.curvature


class _History:
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

    def add(self, t_old: float, t_new: float, dense: Any, runs: np.ndarray) -> None:
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

    def __init__(
        self,
        m: int,
        keys: np.ndarray,
        base: np.ndarray,
        width: np.ndarray,
        t_old: np.ndarray,
        h: np.ndarray,
        F: np.ndarray,
        y_old: np.ndarray,
        n_runs: int,
    ) -> None:
        self.m = m  # state rows
        self.keys = keys  # step * n_runs + run, ascending
        self.base = base  # first column of each entry (component 0)
        self.width = width  # runs in the entry's step (component stride)
        self.t_old, self.h = t_old, h  # per entry
        self.F, self.y_old = F, y_old  # (7, columns), (columns,)
        self.n_runs = n_runs

    @classmethod
    def build(
        cls, pieces: list[tuple[float, Any, np.ndarray]], shape: tuple[int, ...]
    ) -> _Dop853Table | None:
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

    def evaluate(
        self, runs: np.ndarray, times: np.ndarray, step: np.ndarray
    ) -> np.ndarray:
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


#: Relative step in the speed of the central difference that gives the
#: rate of a scheduled command, ``(d command/dV) dV/dt`` (error ~ h^2 of the
#: schedule's third derivative; at a knot of a piecewise linear
#: :class:`~fws_control.GainSchedule` the mean of the two slopes).
_SCHEDULE_STEP = 1e-6


def scheduled_gains(schedule: Any, speed: Any) -> SteeringGains:
    """The gains of a schedule at `speed` (``schedule.at`` or the function).

    A schedule is an object with a method ``at(speed)`` (e.g.
    :class:`~fws_control.GainSchedule`) or a function ``speed ->
    SteeringGains``, vectorised over an array of speeds.

    Raises
    ------
    TypeError
        If it returns something else than a SteeringGains.
    """
    at = getattr(schedule, "at", None)
    gains = at(speed) if callable(at) else schedule(speed)
    if not isinstance(gains, SteeringGains):
        raise TypeError(
            "a gain schedule must return a SteeringGains at a speed, got "
            f"{type(gains).__name__} from {schedule!r}"
        )
    return gains


def _check_profile_values(profile, V, x, dynamic: bool) -> None:
    """Refuse what a user's speed function returns mid-run: NaN or reversing."""
    V = np.asarray(V)
    bad = ~np.isfinite(V)
    what = "time [s]" if profile.of == "time" else "arc length [m]"
    xs = np.broadcast_to(np.asarray(x, dtype=float), V.shape)
    if np.any(bad):
        i = int(np.flatnonzero(bad.ravel())[0])
        raise ValueError(
            f"speed: the SpeedProfile function returned {float(V.ravel()[i])!r} at "
            f"{what} {float(xs.ravel()[i])!r}; it must return finite speeds [m/s]"
        )
    # (a function drives forward: its sign cannot be checked ahead of the run)
    low = V <= 0.0 if dynamic else V < 0.0
    if np.any(low):
        i = int(np.flatnonzero(low.ravel())[0])
        rng = "(0, inf) for model='dynamic'" if dynamic else "[0, inf)"
        raise ValueError(
            f"speed: the SpeedProfile function returned {float(V.ravel()[i])!r} m/s at "
            f"{what} {float(xs.ravel()[i])!r}: reversing through zero speed is not "
            f"simulated; speeds must lie in {rng}"
        )


class _Engine:
    """Vectorised closed-loop right-hand side for ``n`` runs.

    The state is laid out as ``(m, n)`` flattened row-major: rows ``s, e,
    theta``, with a steering actuator ``delta_f, delta_r``, and with the
    dynamic model ``v_y, r`` last.
    """

    def __init__(
        self, vehicle, path, gains, speed, feedforward, tau, delay=0.0, history=None,
        runs=None, model="kinematic", tyre="linear", hold=None, profile=None,
        schedule=None,
    ):  # fmt: skip
        # hold: first of the two rows of a sampled controller's held command
        # (None: a static law, evaluated at every stage)
        self.hold = hold
        self.delay = delay
        # a SpeedProfile (None: the constant per-run `speed`) and a gain
        # schedule read at the current speed (None: the fixed `gains`)
        self.profile = profile
        self.schedule = schedule
        self.history = history
        self.runs = runs
        self.delayed = None
        self.vehicle = vehicle
        self.path = path
        self.gains = gains
        self.speed = speed
        self.ff = feedforward
        self.tau = tau
        self.dynamic = model == "dynamic"
        self.tyre = tyre
        self.m = (
            (3 if tau is None else 5)
            + (0 if hold is None else 2)
            + (2 if self.dynamic else 0)
        )
        self._kappa = _curvature_function(path)
        length = float(getattr(path, "length", math.inf))
        self.open_length = (
            length if (math.isfinite(length) and not path.closed) else None
        )

    def clip(self, s):
        # Trial stages of the solver may step slightly past the end of an open
        # path, where the path refuses to evaluate; the end-of-path event stops
        # the run there, so clipping only affects rejected or final stages.
        if self.open_length is None:
            return s
        return np.clip(s, 0.0, self.open_length)

    def curvature(self, s):
        return np.broadcast_to(
            np.asarray(self._kappa(self.clip(s)), dtype=float), s.shape
        )

    def speed_at(self, t, s):
        """Speed of each column: the constant ``speed`` or the profile's."""
        if self.profile is None:
            return self.speed
        x = t if self.profile.of == "time" else s
        V = self.profile(np.broadcast_to(np.asarray(x, dtype=float), np.shape(s)))
        if self.profile.function is not None:
            _check_profile_values(self.profile, V, x, self.dynamic)
        return V

    def speed_rate(self, t, s, s_dot):
        """``dV/dt`` of each column (0 at a constant speed)."""
        if self.profile is None:
            return np.zeros(np.shape(s))
        if self.profile.of == "time":
            return self.profile.derivative(np.broadcast_to(t, np.shape(s)))
        return self.profile.derivative(s) * s_dot

    def gains_at(self, V):
        """The gains of the paper's law at the speeds `V` (scheduled or fixed)."""
        if self.schedule is None:
            return self.gains
        return scheduled_gains(self.schedule, V)

    def command(self, Y, kappa, t, V=None):
        """Controller output at time `t`, from the measurements at ``t - delay``."""
        if self.hold is not None:
            # a sampled controller: the command held since its last sample
            # (already delayed and saturated when it was set)
            return Y[self.hold], Y[self.hold + 1]
        if V is None:
            V = self.speed_at(t, Y[0])
        if self.delayed is not None:  # delayed states given (output stage)
            Y, kappa = self.delayed, self.curvature(self.delayed[0])
        elif self.delay > 0.0 and self.history is not None:
            # (no history yet only at the start, where the delayed state is the
            # initial one: the current Y)
            Yd = self.history.state(t - self.delay, self.runs)
            Y, kappa = Yd, self.curvature(Yd[0])
        if not isinstance(self.gains, SteeringGains):  # a LateralController
            df, dr = self.gains.steering(
                self.vehicle,
                self.path,
                s=self.clip(Y[0]),
                e=Y[1],
                theta=Y[2],
                curvature=kappa,
                speed=V,
            )
            return saturate(self.vehicle, df, dr)
        return steering_command(
            self.vehicle,
            self.gains_at(V),
            Y[1],
            Y[2],
            curvature=kappa,
            feedforward=self.ff,
            # (used by feedforward="dynamic" only)
            speed=V,
            tyre=self.tyre,
        )

    def command_rate(self, Y, Ydot, kappa, t=0.0):
        """Time derivative of the command for (delayed) states and their rates."""
        if self.hold is not None:
            # piecewise constant: no rate between the samples (its jumps are
            # not rates)
            zero = np.zeros(np.shape(Y[0]))
            return zero, zero.copy()
        kappa_rate = (
            np.asarray(self.path.curvature_rate(self.clip(Y[0])), dtype=float) * Ydot[0]
        )
        if isinstance(self.gains, SteeringGains):
            V = self.speed_at(t, Y[0])
            rf, rr = steering_command_rate(
                self.vehicle,
                self.gains_at(V),
                Y[1],
                Y[2],
                Ydot[1],
                Ydot[2],
                curvature=kappa,
                curvature_rate=kappa_rate,
                feedforward=self.ff,
                speed=V,
                tyre=self.tyre,
            )
            if self.schedule is None:
                return rf, rr
            # gains that follow the speed add (d command/dV) dV/dt: a central
            # difference in V of the command (clipped where it is), at the
            # state of the sample
            V_dot = self.speed_rate(t, Y[0], Ydot[0])
            h = _SCHEDULE_STEP * np.maximum(1.0, np.abs(V))
            v_up, v_down = V + h, V - h
            # a table does not extrapolate: one-sided at the ends of its range
            speeds = getattr(self.schedule, "speeds", None)
            if speeds is not None:
                v_up = np.minimum(v_up, np.max(speeds))
                v_down = np.maximum(v_down, np.min(speeds))
            up = self.command(Y, kappa, t, v_up)
            down = self.command(Y, kappa, t, v_down)
            return (
                rf + (up[0] - down[0]) / (v_up - v_down) * V_dot,
                rr + (up[1] - down[1]) / (v_up - v_down) * V_dot,
            )
        ctrl = self.gains
        kw = dict(
            s=self.clip(Y[0]), e=Y[1], theta=Y[2], curvature=kappa, speed=self.speed
        )
        raw_f, raw_r = ctrl.steering(self.vehicle, self.path, **kw)
        rf, rr = ctrl.steering_rate(
            self.vehicle, self.path, s_dot=Ydot[0], e_dot=Ydot[1], theta_dot=Ydot[2],
            **kw,
        )  # fmt: skip
        # a saturated channel does not move
        lim_f = self.vehicle.max_steer_front
        lim_r = self.vehicle.max_steer_rear
        if lim_f is not None:
            rf = np.where(np.abs(raw_f) > lim_f, 0.0, rf)
        if lim_r is not None:
            rr = np.where(np.abs(raw_r) > lim_r, 0.0, rr)
        return rf, rr

    def steering(self, Y, kappa, t=0.0):
        if self.tau is None:
            return self.command(Y, kappa, t)
        return Y[3], Y[4]

    def derivatives(self, Y, t=0.0):
        """Return ``(Ydot, kappa, delta_f, delta_r)`` for states ``Y (m, n)``."""
        s, e, th = Y[0], Y[1], Y[2]
        kappa = self.curvature(s)
        V = self.speed_at(t, s)
        df, dr = self.command(Y, kappa, t, V) if self.tau is None else (Y[3], Y[4])
        body = ()
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.dynamic:
                # v_y, r are the last two rows (after the actuator's)
                s_dot, e_dot, th_dot, *body = dynamic_path_derivatives(
                    self.vehicle, kappa, e, th, Y[-2], Y[-1], df, dr,
                    speed=V, tyre=self.tyre,
                )  # fmt: skip
            else:
                s_dot, e_dot, th_dot = equations.path_frame_derivatives(
                    V, self.vehicle.wheelbase, kappa, e, th, df, dr
                )
        held = () if self.hold is None else (np.zeros_like(s_dot),) * 2
        if self.tau is None:
            Ydot = np.stack([s_dot, e_dot, th_dot, *held, *body])
        else:
            cmd = self.command(Y, kappa, t, V)
            rf, rr = actuator_rate(self.vehicle, cmd, (df, dr), time_constant=self.tau)
            Ydot = np.stack([s_dot, e_dot, th_dot, rf, rr, *held, *body])
        return Ydot, kappa, df, dr

    def rhs(self, t, y):
        Y = y.reshape(self.m, -1)
        return self.derivatives(Y, t)[0].ravel()

    def margins(self, Y, t=0.0):
        """Distance to each stop condition, shape ``(3, n)``; stop where <= 0."""
        kappa = self.curvature(Y[0])
        df, _ = self.steering(Y, kappa, t)
        out = np.full((3, Y.shape[1]), np.inf)
        out[0] = (0.5 * math.pi - STOP_MARGIN) - np.abs(df)
        out[1] = (1.0 - kappa * Y[1]) - STOP_MARGIN
        if self.open_length is not None:
            # The offset lets a run start exactly at s = 0 (or at the end).
            out[2] = np.minimum(Y[0], self.open_length - Y[0]) / self.open_length + 1e-9
        return out

    def event(self, t, y):
        return float(np.min(self.margins(y.reshape(self.m, -1), t)))


#: Distance before a singular state at which a run stops:
#: ``|delta_f| = pi/2 - STOP_MARGIN`` [rad] and ``1 - kappa*e = STOP_MARGIN``.
#: At the singular state itself the solution has a square-root singularity
#: (``d delta_f/dt ~ 1/cos delta_f``) and the step size collapses before any
#: step reaches it: 4455 steps and 5.8 s for a delayed run at 20 m/s that
#: the margin stops after 0.17 s (tests/test_delay_simulation.py). Both
#: engines use it (the compiled one as its default ``steer_margin``,
#: ``curvature_margin``).
STOP_MARGIN = 1e-3

_STOP_MESSAGES = {
    STATUS_SINGULAR_STEERING: "front steering angle reached |delta_f| = pi/2 - "
    f"{STOP_MARGIN:g}, next to the singular yaw rate "
    "V*sin(delta_f - delta_r)/(f*cos(delta_f))",
    STATUS_SINGULAR_CURVATURE: f"1 - curvature*e reached {STOP_MARGIN:g}: the "
    "vehicle is at the path's centre of curvature and the projection is lost",
    STATUS_END_OF_PATH: "the projection point left the open path",
}


#: A solver failure is attributed to a singular state when a run is this
#: close to it (``pi/2 - |delta_f|``, ``1 - kappa*e`` or the relative distance
#: to the end of the path).
_COLLAPSE_MARGIN = 1e-3


@dataclass
class _Segment:
    outcome: str  # "done", "event" or "failed"
    t_last: float
    y_last: np.ndarray
    message: str = ""


#: Points of each accepted step (fractions of it) where the stop margins are
#: checked: a loose tolerance lets a step cross a singular state and come
#: back, or end where the state is NaN, and the end of the step alone would
#: miss it.
_MARGIN_NODES = (0.25, 0.5, 0.75, 1.0)

#: Most solver steps of one integration segment (beyond those a delay's
#: maximum step forces): beyond it the runs still active are marked failed
#: instead of running on (a speed of 1e20 m/s asks for ~1e20 steps).
MAX_STEPS = 20_000


def _locate_stop(event, dense, lo: float, hi: float) -> float:
    """First time in ``(lo, hi]`` where the margin is no longer > 0.

    The margin is > 0 at `lo` and not at `hi`. A NaN margin (a state beyond
    a singularity) counts as a stop, so the root is that of a function that
    is -1 wherever the margin is NaN: brentq keeps a sign-changing bracket.
    """

    def f(tt):
        g = event(tt, dense(tt))
        return -1.0 if math.isnan(g) else max(g, -1.0)

    if f(hi) == 0.0:
        return hi
    if not f(lo) > 0.0:  # (the segment starts regular; kept safe here)
        return lo
    return brentq(f, lo, hi, xtol=4 * np.finfo(float).eps * max(1.0, abs(hi)))


def _jacobian_sparsity(m: int, n: int):
    """Sparsity of the stacked Jacobian: each run's states couple only in it.

    The state is ``(m, n)`` flattened row-major, so entry ``(a*n + i, b*n +
    j)`` can be nonzero only for ``i == j``. Given to the implicit solvers,
    it lets scipy estimate the Jacobian of all runs with ``m`` evaluations of
    the right-hand side (one per state row) instead of ``m * n``, and solve
    with a sparse LU.
    """
    from scipy.sparse import eye, kron

    return kron(np.ones((m, m)), eye(n), format="csc")


def _solve_segment(
    eng, solver_cls, t0, y0, t_end, t_eval, rtol, atol, store, record=None, runs=None
) -> _Segment:
    """Step `solver_cls` from `t0`; stop where a margin first reaches 0.

    Same stepping, dense output and event location as
    :func:`scipy.integrate.solve_ivp` with a terminal event, but the last
    accepted state is kept when the solver fails, so that a collapse of the
    step size at a singular state can be attributed to the run that caused it,
    and the margins are checked at the nodes :data:`_MARGIN_NODES` of every
    accepted step (a NaN margin counts as a stop), so that no tolerance lets
    a run cross a singular state unnoticed. The states at the output times
    `t_eval` are passed to ``store(k, y)`` (``y`` of shape ``(y0.size,
    K)`` for the output times ``k:k+K``) as they are reached, so that no
    copy of them builds up here. With a `record` (:class:`_History`), the
    dense output of every accepted step is added to it with the global
    indices `runs` of the stacked runs (the delay's history, and the
    continuous solution for exact peaks).
    """
    extra = {}
    if eng.delay > 0.0:
        # Method of steps: a stage at t + h needs the state at t + h - delay,
        # which is known (accepted) only if h <= delay.
        extra["max_step"] = eng.delay
    if issubclass(solver_cls, (Radau, BDF)):
        extra["jac_sparsity"] = _jacobian_sparsity(eng.m, y0.size // eng.m)
    rhs = _DetachableRhs(eng.rhs)
    solver = solver_cls(rhs, t0, y0, t_end, rtol=rtol, atol=atol, **extra)
    try:
        return _step_segment(eng, solver, t0, t_end, t_eval, store, record, runs)
    finally:
        # scipy's solver and its wrappers of the right-hand side are a
        # reference cycle: cut the engine out of it, so that the engine and
        # the history it holds (every step's dense output of the chunk) are
        # freed when the caller drops them, not at the next collection of
        # the cyclic garbage collector (which a batch's memory bound must not
        # depend on: with the collector paused, a 2000-run batch peaked at
        # 45 instead of 34 MB, tests/test_signals_kept.py)
        rhs.fun = None


class _DetachableRhs:
    """A right-hand side whose target can be dropped (see _solve_segment)."""

    __slots__ = ("fun",)

    def __init__(self, fun):
        self.fun = fun

    def __call__(self, t, y):
        return self.fun(t, y)


def _step_segment(eng, solver, t0, t_end, t_eval, store, record, runs) -> _Segment:
    """The stepping loop of :func:`_solve_segment`."""
    k = 0  # next output time
    steps = 0
    # (the steps a delay's max_step forces come on top of the budget)
    budget = MAX_STEPS + (int((t_end - t0) / eng.delay) if eng.delay > 0.0 else 0)
    while True:
        msg = solver.step()
        steps += 1
        if solver.status != "failed" and steps > budget:
            # a tight rtol with an atol far below it costs the steps at the
            # clips' kinks of the steering limits (inside the steps here):
            # measured on a rate-limited arc (23 m/s, 6 s) with DOP853, rtol
            # 1e-13: 257-329 steps for atol 1e-15 to 1e-19, 6712 for 1e-20;
            # atol 1e-20: 262, 203 and 159 steps for rtol 1e-12, 1e-11, 1e-10
            rtol = float(np.max(solver.rtol))
            atol = float(np.max(solver.atol))
            msg = (
                f"more than {MAX_STEPS} solver steps (MAX_STEPS) from t={t0:.6g} s "
                f"at rtol={rtol:g}, atol={atol:g}: dynamics too fast for the "
                "output interval, stiff (try method='Radau'), or tolerances "
                "tighter than the kinks of the steering limits allow (try "
                "rtol >= 1e-12 or atol >= 1e-19)"
            )
            return _Segment("failed", float(solver.t), solver.y.copy(), msg)
        if solver.status == "failed":
            return _Segment("failed", float(solver.t), solver.y.copy(), msg)
        t_old, t_new = solver.t_old, solver.t
        dense = solver.dense_output()
        if record is not None:
            record.add(t_old, t_new, dense, runs)
        t_hit = None
        prev = t_old
        for frac in _MARGIN_NODES:
            tt = t_new if frac == 1.0 else t_old + frac * (t_new - t_old)
            y_tt = solver.y if frac == 1.0 else dense(tt)
            if not eng.event(tt, y_tt) > 0.0:  # also NaN
                t_hit = _locate_stop(eng.event, dense, prev, tt)
                break
            prev = tt
        upto = t_new if t_hit is None else t_hit
        k_end = int(np.searchsorted(t_eval, upto, side="right"))
        if k_end > k:
            store(k, dense(t_eval[k:k_end]))
            k = k_end
        if t_hit is not None:
            return _Segment("event", float(t_hit), dense(t_hit))
        if solver.status == "finished":
            return _Segment("done", float(t_new), solver.y.copy())


def integrate(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: np.ndarray,
    feedforward: bool,
    path_state: np.ndarray,
    t_eval: np.ndarray,
    time_constant: float | None,
    method: Any = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    delay: float = 0.0,
    solution: list[DenseSolution] | None = None,
    model: str = "kinematic",
    tyre: str = "linear",
    body_state: np.ndarray | None = None,
    profile: Any = None,
    schedule: Any = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Integrate ``n`` runs together; a stopped run leaves the stacked state.

    Parameters
    ----------
    vehicle, path
        Shared by all runs.
    gains : SteeringGains or LateralController
        Per run (fields of shape ``(n,)`` or scalars that broadcast). A
        sampled controller (:func:`is_sampled`) is integrated piece by piece
        between its samples, its held command two more state rows
        (:func:`hold_row`): the solver restarts at every measurement and
        switch of the command, and no delayed rows are returned.
    speed : ndarray
        Per run speed, shape ``(n,)``; its size is the number of runs.
    feedforward : bool
        Curvature feedforward on or off (all runs).
    path_state : ndarray
        Initial ``(s, e, theta)`` per run, shape ``(n, 3)``
        (:func:`initial_path_state`).
    t_eval : ndarray
        Output times, from the start time (:func:`time_grid`).
    time_constant : float or None
        Actuator lag [s] (:func:`resolve_time_constant`); None: no actuator.
    method, rtol, atol
        Solver (see :func:`check_method`) and its tolerances.
    delay : float, optional
        Input delay [s] on the steering command: the controller acts on the
        measurements of ``t - delay``; before ``delay`` the command is the
        one of the initial state (the state is held at its initial value for
        ``t < 0``). Integrated by the method of steps: the solver's step is
        at most the delay, the delayed state comes from the dense output of
        the accepted steps, and the solver restarts at ``delay``,
        ``2 delay`` and ``3 delay``, where the solution's first derivatives
        are not smooth.
    solution : list, optional
        If given, a :class:`DenseSolution` (the solver's dense output of
        every accepted step: the continuous solution between the output
        times) is appended to it, for :func:`exact_peaks`.
    model : {"kinematic", "dynamic"}, optional
        Vehicle model (:data:`MODELS`, checked by :func:`check_model`). The
        dynamic model (:func:`~fws_control.dynamics.dynamic_path_derivatives`,
        ``speed`` is its constant longitudinal speed ``u > 0``) adds the
        rows ``v_y, r`` last.
    tyre : {"linear", "magic"}, optional
        Tyre model of the dynamic model.
    body_state : ndarray, optional
        Initial ``(v_y, r)`` per run, shape ``(n, 2)``; a NaN row (or None
        for all runs): the vehicle starts rolling without tyre slip at the
        initial steering angles, ``r = u (tan delta_f - tan delta_r) / f``
        and ``v_y - l_r r = u tan delta_r`` (the kinematic model's motion).
    profile : SpeedProfile, optional
        A speed that varies along the run
        (:class:`~fws_control.SpeedProfile`, of the time or of the state
        ``s``) instead of the constant `speed`, which then only counts
        the runs. Not with a delay (the runners refuse it).
    schedule : optional
        Gains of the paper's law read at the current speed
        (:func:`scheduled_gains`) instead of the fixed `gains`.

    Returns
    -------
    states : ndarray
        Shape ``(m, n, T)`` with rows ``s, e, theta`` (and ``delta_f,
        delta_r`` with an actuator, then ``v_y, r`` with the dynamic model);
        NaN after a run's stop. With a delay,
        six more rows: the path state ``s, e, theta`` at ``t - delay`` and
        its time derivative (zero before the start), which
        :func:`compute_outputs` needs for the applied steering.
    status, message : ndarray of object
        Per run status (one of :data:`STATUSES`) and explanation.
    t_stop : ndarray
        Per run end time [s].

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.engine import integrate
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(np.array([0.1, 0.1]), 0.5, 0.0)
    >>> states, status, _, t_stop = integrate(
    ...     veh, fws.Straight(), g, speed=np.array([5.0, 5.0]), feedforward=False,
    ...     path_state=np.array([[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]]),
    ...     t_eval=np.linspace(0.0, 1.0, 11), time_constant=None)
    >>> states.shape, status.tolist(), t_stop.tolist()
    ((3, 2, 11), ['ok', 'ok'], [1.0, 1.0])
    """
    if is_sampled(gains):
        return _integrate_sampled(
            vehicle, path, gains, speed=speed, feedforward=feedforward,
            path_state=path_state, t_eval=t_eval, time_constant=time_constant,
            method=method, rtol=rtol, atol=atol, delay=delay, solution=solution,
            model=model, tyre=tyre, body_state=body_state,
        )  # fmt: skip
    tau = time_constant
    z0 = np.asarray(path_state, dtype=float)
    n = speed.size
    T = t_eval.size
    dyn = model == "dynamic"
    m = (3 if tau is None else 5) + (2 if dyn else 0)
    controller = not isinstance(gains, SteeringGains)
    if not controller:
        k1, k2, a = (
            np.broadcast_to(np.asarray(v, dtype=float), (n,))
            for v in (gains.k1, gains.k2, gains.ratio)
        )
    out = np.full((m, n, T), np.nan)
    status = np.full(n, STATUS_OK, dtype=object)
    message = np.full(n, "", dtype=object)
    t_stop = np.full(n, t_eval[-1])

    history = None

    def engine_for(idx):
        return _Engine(
            vehicle,
            path,
            gains.subset(idx)
            if controller
            else SteeringGains(k1[idx], k2[idx], a[idx]),
            speed[idx],
            feedforward,
            tau,
            delay,
            history,
            idx,
            model,
            tyre,
            profile=profile,
            schedule=schedule,
        )

    active = np.arange(n)
    eng = engine_for(active)
    Y = np.empty((m, n))
    Y[:3] = z0.T
    if tau is not None or dyn:
        cmd = np.stack(eng.command(Y, eng.curvature(Y[0]), float(t_eval[0])))
    if tau is not None:
        # The actuator starts at the command: no initial transient of its own.
        Y[3:5] = cmd
    if dyn:
        V0 = speed if profile is None else eng.speed_at(float(t_eval[0]), Y[0])
        _initial_body_state(vehicle, Y, cmd, V0, body_state)
    out[:, :, 0] = Y
    if delay > 0.0 or solution is not None:
        history = _History(float(t_eval[0]), Y.copy())
    marg = eng.margins(Y, float(t_eval[0]))
    bad = np.min(marg, axis=0) <= 0.0
    for i in np.flatnonzero(bad):
        kind = _STOP_KINDS[int(np.argmin(marg[:, i]))]
        status[i], t_stop[i] = kind, t_eval[0]
        message[i] = f"initial state: {_STOP_MESSAGES[kind]}"
    active = active[~bad]
    Y = Y[:, ~bad]
    t0 = float(t_eval[0])
    t_end = float(t_eval[-1])
    solver_cls = check_method(method)
    # Restart points: where a delay makes the solution's derivatives jump.
    breaks = [t0 + k * delay for k in (1, 2, 3)] if delay > 0.0 else []
    breaks = [b for b in breaks if b < t_end] + [t_end]
    while active.size and t0 < t_end:
        eng = engine_for(active)
        first = int(np.searchsorted(t_eval, t0, side="right"))
        seg_end = next(b for b in breaks if b > t0)

        def store(k, y, first=first, active=active):
            # straight into the output: no per-segment copy of the samples
            out[:, active, first + k : first + k + y.shape[1]] = y.reshape(
                m, active.size, -1
            )

        seg = _solve_segment(
            eng,
            solver_cls,
            t0,
            Y.ravel(),
            seg_end,
            t_eval[first:],
            rtol,
            atol,
            store,
            record=history,
            runs=active,
        )
        if seg.outcome == "done":
            if seg_end >= t_end:
                break
            Y, t0 = seg.y_last.reshape(m, active.size), seg_end
            continue
        keep = _stop_runs(eng, seg, active, status, message, t_stop)
        if keep is None:
            break
        Y_last = seg.y_last.reshape(m, active.size)
        active, Y, t0 = active[keep], Y_last[:, keep], seg.t_last
    if delay > 0.0:
        out = np.concatenate(
            [out, _delayed_rows(engine_for, history, out, t_eval, delay)]
        )
    if solution is not None:
        solution.append(DenseSolution(history, engine_for, delay))
    return out, status, message, t_stop


def is_sampled(controller: Any) -> bool:
    """True for a sampled controller (one that declares a ``sample_time``)."""
    return getattr(controller, "sample_time", None) is not None


def hold_row(controller: Any, time_constant: float | None) -> int | None:
    """First state row of a sampled controller's held command (else None).

    The rows follow ``s, e, theta`` and the actuator's ``delta_f, delta_r``
    (with a lag) and precede the dynamic model's ``v_y, r``.
    """
    if not is_sampled(controller):
        return None
    return 3 if time_constant is None else 5


#: Relative slack with which a delay counts as a whole number of samples
#: (then the commands switch exactly at the sample times).
_WHOLE_SAMPLES = 1e-9


#: Most samples of a sampled controller in one run: each restarts the solver
#: and calls the controller (an MPC step costs about a millisecond).
MAX_SAMPLES = 1_000_000


def check_sampling(controller: Any, duration: float) -> None:
    """Refuse a sampled controller's `sample_time` that is not a number > 0,
    or more than :data:`MAX_SAMPLES` samples over `duration` [s]."""
    ts = controller.sample_time
    if isinstance(ts, (bool, np.bool_)) or not isinstance(
        ts, (int, float, np.integer, np.floating)
    ):
        raise TypeError(
            f"controller.sample_time must be a number of seconds, got {ts!r}"
        )
    if not (math.isfinite(ts) and ts > 0.0):
        raise ValueError(f"controller.sample_time must be finite and > 0 s, got {ts!r}")
    if duration / ts > MAX_SAMPLES:
        raise ValueError(
            f"controller.sample_time={ts!r} s over duration={duration!r} s gives "
            f"{duration / ts:.3g} samples, more than MAX_SAMPLES = {MAX_SAMPLES:g} "
            "(each restarts the solver and calls the controller); a longer "
            "sample_time or a shorter duration"
        )


def _sample_events(t0: float, t_end: float, sample_time: float, delay: float):
    """``(time, kind, k)`` of a sampled run, in the order they happen (lazily).

    Sample ``k`` measures the state at ``t0 + k Ts`` (the initial state for
    ``k <= 0``: the state is held before ``t0``) and its command is applied
    from ``t0 + k Ts + delay`` until the next one's; kind 0 is the
    measurement, kind 1 the switch. The first sample is the one whose command
    is applied at ``t0``.
    """
    ts = sample_time
    d = delay / ts
    if abs(d - round(d)) <= _WHOLE_SAMPLES * max(1.0, d):
        d = round(d)
    k_first = math.floor(-d)
    k_last = math.floor((t_end - t0) / ts - d)  # the last switch before t_end
    samples = range(k_first, k_last + 1)
    measures = ((t0 + max(k, 0) * ts, 0, k) for k in samples)
    switches = (
        (max(t0 + (k + d) * ts, t0), 1, k) for k in samples if t0 + (k + d) * ts < t_end
    )
    return heapq.merge(measures, switches)


def _integrate_sampled(
    vehicle, path, ctrl, *, speed, feedforward, path_state, t_eval, time_constant,
    method, rtol, atol, delay, solution, model, tyre, body_state,
):  # fmt: skip
    """:func:`integrate` with a sampled controller (zero-order hold).

    The controller's command is a pair of state rows (:func:`hold_row`),
    constant between its switches: the solver restarts at every measurement
    and switch time (:func:`_sample_events`), where the rows are set to the
    command of that sample, computed by the run's own ``ctrl.start(...)``
    from the state at the measurement time. The delay is in the switch
    times, so no delayed rows are returned.
    """
    tau = time_constant
    n, T = speed.size, t_eval.size
    dyn = model == "dynamic"
    hold = hold_row(ctrl, tau)
    m = hold + 2 + (2 if dyn else 0)
    out = np.full((m, n, T), np.nan)
    status = np.full(n, STATUS_OK, dtype=object)
    message = np.full(n, "", dtype=object)
    t_stop = np.full(n, t_eval[-1])
    runs = [ctrl.start(vehicle, path, speed=float(v)) for v in speed]

    def engine_for(idx):
        return _Engine(
            vehicle, path, ctrl, speed[idx], feedforward, tau, runs=idx,
            model=model, tyre=tyre, hold=hold,
        )  # fmt: skip

    t0, t_end = float(t_eval[0]), float(t_eval[-1])
    Y = np.zeros((m, n))
    Y[:3] = np.asarray(path_state, dtype=float).T
    events = _sample_events(t0, t_end, float(ctrl.sample_time), delay)
    nxt = next(events, None)
    pending: dict[int, np.ndarray] = {}
    active = np.arange(n)
    history = None
    t_cur = t0
    solver_cls = check_method(method)
    while True:
        while nxt is not None and nxt[0] <= t_cur:
            _, kind, k = nxt
            nxt = next(events, None)
            if kind == 0:
                cmd = np.array(
                    [
                        runs[i].step(s=Y[0, j], e=Y[1, j], theta=Y[2, j])
                        for j, i in enumerate(active)
                    ]
                ).reshape(active.size, 2)
                pending[k] = np.stack(saturate(vehicle, cmd[:, 0], cmd[:, 1]))
                continue
            Y[hold : hold + 2] = pending.pop(k)
            if history is not None:
                # a switch at an output time: that sample shows the new
                # command (the hold is right-continuous)
                at = np.flatnonzero(np.abs(t_eval - t_cur) <= 1e-9 * ctrl.sample_time)
                if at.size:
                    rows = Y[hold : hold + 2, :, None]
                    out[hold : hold + 2, active[:, None], at[None, :]] = rows
        if history is None:
            # the start: the actuator at the first command, the body rolling
            # without slip, the margins checked
            if tau is not None:
                Y[3:5] = Y[hold : hold + 2]
            if dyn:
                _initial_body_state(vehicle, Y, Y[hold : hold + 2], speed, body_state)
            out[:, :, 0] = Y
            history = _History(t0, Y.copy())
            marg = engine_for(active).margins(Y, t0)
            bad = np.min(marg, axis=0) <= 0.0
            for i in np.flatnonzero(bad):
                kind = _STOP_KINDS[int(np.argmin(marg[:, i]))]
                status[i], t_stop[i] = kind, t0
                message[i] = f"initial state: {_STOP_MESSAGES[kind]}"
            active, Y = active[~bad], Y[:, ~bad]
            pending = {k: v[:, ~bad] for k, v in pending.items()}
        if active.size == 0 or t_cur >= t_end:
            break
        seg_end = t_end if nxt is None else nxt[0]
        eng = engine_for(active)
        first = int(np.searchsorted(t_eval, t_cur, side="right"))

        def store(k, y, first=first, active=active):
            out[:, active, first + k : first + k + y.shape[1]] = y.reshape(
                m, active.size, -1
            )

        seg = _solve_segment(
            eng, solver_cls, t_cur, Y.ravel(), seg_end, t_eval[first:], rtol, atol,
            store, record=history, runs=active,
        )  # fmt: skip
        if seg.outcome == "done":
            Y, t_cur = seg.y_last.reshape(m, active.size).copy(), seg_end
            continue
        keep = _stop_runs(eng, seg, active, status, message, t_stop)
        if keep is None:
            break
        # the stopped runs take no more samples; the others go on from the stop
        Y = seg.y_last.reshape(m, active.size)[:, keep].copy()
        active, t_cur = active[keep], seg.t_last
        pending = {k: v[:, keep] for k, v in pending.items()}
    if solution is not None:
        if history is None:
            history = _History(t0, Y.copy())
        solution.append(DenseSolution(history, engine_for, 0.0))
    return out, status, message, t_stop


def _stop_runs(eng, seg, active, status, message, t_stop):
    """Mark the runs a segment's stop ended; return the mask of those left.

    A solver failure away from any singular state fails every active run
    (returns None).
    """
    Y_last = seg.y_last.reshape(eng.m, active.size)
    marg = eng.margins(Y_last, seg.t_last)
    j = int(np.argmin(np.min(marg, axis=0)))
    kind = _STOP_KINDS[int(np.argmin(marg[:, j]))]
    if seg.outcome == "event":
        note = _STOP_MESSAGES[kind]
    elif np.min(marg[:, j]) < _COLLAPSE_MARGIN:
        # Near |delta_f| = pi/2 the solution has a square-root singularity
        # (d delta_f/dt ~ 1/cos delta_f): the step size collapses before
        # any accepted step crosses it, so the event cannot fire.
        note = (
            f"{_STOP_MESSAGES[kind]} (the solver's step size collapsed "
            f"{float(np.min(marg[:, j])):.2g} away from it)"
        )
    else:
        for i in active:
            status[i], t_stop[i] = STATUS_FAILED, seg.t_last
            message[i] = f"at t={seg.t_last:.6g} s the ODE solver failed: {seg.message}"
        return None
    # The run that set the stop, and any other at its margin there too
    # (e.g. identical runs): one left in would start the next segment
    # past its stop, where no sign change can be seen.
    stops = np.union1d([j], np.flatnonzero(~(np.min(marg, axis=0) > 0.0)))
    for jj in stops:
        kind_jj = _STOP_KINDS[int(np.argmin(marg[:, jj]))]
        i = active[jj]
        status[i], t_stop[i] = kind_jj, seg.t_last
        message[i] = f"at t={seg.t_last:.6g} s: " + (
            note if jj == j else _STOP_MESSAGES[kind_jj]
        )
    return ~np.isin(np.arange(active.size), stops)


def _initial_body_state(vehicle, Y, cmd, speed, body_state) -> None:
    """Fill the rows ``v_y, r`` of `Y` (the last two) in place.

    Given values where `body_state` is finite; elsewhere the no-slip motion
    at the initial steering `cmd` (both slip angles zero).
    """
    with np.errstate(invalid="ignore"):
        vy0, r0 = equations.no_slip_body_state(
            speed, vehicle.wheelbase, vehicle.rear_to_cg, cmd[0], cmd[1]
        )
    if body_state is not None:
        given = np.isfinite(np.asarray(body_state, dtype=float))
        vy0 = np.where(given[:, 0], body_state[:, 0], vy0)
        r0 = np.where(given[:, 1], body_state[:, 1], r0)
    Y[-2], Y[-1] = vy0, r0


#: Most (run, time) pairs whose delayed rows are evaluated at once: bounds
#: the temporaries of :func:`_delayed_rows` to a few MB.
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


def _delayed_rows(engine_for, history, out, t_eval, delay) -> np.ndarray:
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


def _unwrap_time(psi: np.ndarray) -> np.ndarray:
    """Unwrap along the last axis, ignoring the NaN tail of stopped runs."""
    filled = psi.copy()
    nan = np.isnan(filled)
    if np.any(nan):
        # Forward-fill so that np.unwrap sees no NaN; the tail is reset below.
        idx = np.where(~nan, np.arange(psi.shape[-1]), 0)
        np.maximum.accumulate(idx, axis=-1, out=idx)
        filled = np.take_along_axis(filled, idx, axis=-1)
        filled = np.nan_to_num(filled)
    out = np.unwrap(filled, axis=-1)
    out[nan] = np.nan
    return out


def compute_outputs(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: np.ndarray,
    feedforward: bool,
    time_constant: float | None,
    states: np.ndarray,
    initial_heading: np.ndarray,
    delay: float = 0.0,
    model: str = "kinematic",
    tyre: str = "linear",
    profile: Any = None,
    schedule: Any = None,
    times: np.ndarray | None = None,
) -> np.ndarray:
    """All signals of :data:`SIGNALS` from the path-frame states.

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, time_constant
        As given to :func:`integrate`.
    states : ndarray
        Its states, shape ``(m, n, T)``, NaN after a run's stop.
    initial_heading : ndarray
        Per run initial ``psi`` [rad], shape ``(n,)``: ``psi`` is unwrapped in
        time and put on the branch of this value.
    delay : float, optional
        The input delay given to :func:`integrate` [s]; its six extra rows
        of `states` then give the applied (delayed) steering command (for a
        sampled controller the held rows give it: no extra rows).
    model, tyre, profile, schedule : optional
        As given to :func:`integrate`.
    times : ndarray, optional
        The times of the states, ``(T,)`` or ``(n, T)`` [s]; needed with a
        `profile` (the speed at each sample).

    Returns
    -------
    ndarray
        Shape ``(n, len(SIGNALS), T)``, NaN where `states` is NaN. The rates
        are exact (chain rule through the controller and the path's
        curvature derivative, or the actuator's rates). ``lateral_accel`` is
        the acceleration of the centre of gravity G along the vehicle's
        lateral axis: eq. (13) for the kinematic model, ``dv_y/dt + u r``
        for the dynamic one; NaN where ``|delta_f| >= pi/2``. ``v_y`` is the
        lateral velocity of G in the vehicle's frame and ``yaw_rate`` the
        yaw rate (for the kinematic model ``V sin(delta_r) + l_r r`` and
        eq. (10)); ``slip_front``, ``slip_rear`` are the slip angles of the
        dynamic model (0 for the kinematic one, which has no slip).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.engine import SIGNALS, compute_outputs
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, 0.0)
    >>> states = np.array([0.0, 2.0, 0.0]).reshape(3, 1, 1)   # s, e, theta
    >>> out = compute_outputs(veh, fws.Straight(), g, speed=np.array([5.0]),
    ...                       feedforward=False, time_constant=None,
    ...                       states=states, initial_heading=np.array([0.0]))
    >>> float(out[0, SIGNALS.index("delta_f"), 0])   # -k1 * e
    -0.2
    """
    tau = time_constant
    psi0 = np.asarray(initial_heading, dtype=float)
    delayed = None
    # (a sampled controller's held rows already hold the delayed command)
    if delay > 0.0 and not is_sampled(gains):
        delayed, states = states[-6:], states[:-6]
    m, n, T = states.shape
    valid = np.isfinite(states[0])
    out = {name: np.full((n, T), np.nan) for name in SIGNALS}
    if not np.any(valid):
        return np.stack([out[name] for name in SIGNALS], axis=1)
    run_idx = np.broadcast_to(np.arange(n)[:, None], (n, T))[valid]
    Y = states[:, valid]
    if isinstance(gains, SteeringGains):
        k1, k2, a = (
            np.broadcast_to(np.asarray(v, dtype=float), (n,))[run_idx]
            for v in (gains.k1, gains.k2, gains.ratio)
        )
        g = SteeringGains(k1, k2, a)
    else:
        g = gains.subset(run_idx) if gains.runs() else gains
    V = speed[run_idx]
    eng = _Engine(
        vehicle, path, g, V, feedforward, tau, model=model, tyre=tyre,
        hold=hold_row(gains, tau), profile=profile, schedule=schedule,
    )  # fmt: skip
    t_s = 0.0
    if profile is not None:
        if times is None:
            raise ValueError("times are needed to evaluate a speed profile")
        t_s = np.broadcast_to(np.asarray(times, dtype=float), (n, T))[valid]
        V = eng.speed_at(t_s, Y[0])
    if delayed is not None:
        Yd, Ydd = delayed[:3, valid], delayed[3:, valid]
        eng.delayed = Yd
    Ydot, kappa, df, dr = eng.derivatives(Y, t_s)
    if tau is None and delayed is not None:
        # The applied steering is the command of the delayed measurements.
        rf, rr = eng.command_rate(Yd, Ydd, eng.curvature(Yd[0]))
    elif tau is None:
        rf, rr = eng.command_rate(Y, Ydot, kappa, t_s)
    else:
        rf, rr = Ydot[3], Ydot[4]
    ok = np.abs(df) < math.pi / 2
    acc = np.full(df.shape, np.nan)
    if eng.dynamic:
        v_y, r = Y[-2], Y[-1]
        slip_f, slip_r = slip_angles(vehicle, v_y, r, df, dr, speed=V)
        # body-frame acceleration of G: d(v_y)/dt + u r
        acc[ok] = (Ydot[-2] + V * r)[ok]
    else:
        r = np.full(df.shape, np.nan)
        r[ok] = yaw_rate(vehicle, df[ok], dr[ok], speed=V[ok])
        # G moves with R's velocity V (cos dr, sin dr) plus r x (l_r, 0)
        v_y = equations.cg_lateral_velocity(V, vehicle.rear_to_cg, dr, r)
        slip_f = slip_r = np.where(ok, 0.0, np.nan)
        acc[ok] = lateral_acceleration(
            vehicle,
            df[ok],
            dr[ok],
            np.asarray(rf)[ok],
            np.asarray(rr)[ok],
            speed=V[ok],
        )
        if profile is not None:
            # eq. (13) holds V constant; d(v_y)/dt adds dV/dt v_y / V, and
            # v_y / V = sin(dr) + l_r sin(df - dr) / (f cos df) (no 0/0 at
            # a stop)
            V_dot = eng.speed_rate(t_s, Y[0], Ydot[0])[ok]
            acc[ok] += V_dot * (
                np.sin(dr[ok])
                + vehicle.rear_to_cg
                * np.sin(df[ok] - dr[ok])
                / (vehicle.wheelbase * np.cos(df[ok]))
            )
    rf = np.where(ok, rf, np.nan)
    rr = np.where(ok, rr, np.nan)
    s_path = eng.clip(Y[0])
    heading = np.asarray(path.heading(s_path), dtype=float)
    px, py = path.position(s_path)
    for name, val in (
        ("s", Y[0]),
        ("e", Y[1]),
        ("theta", Y[2]),
        ("delta_f", df),
        ("delta_r", dr),
        ("delta_f_rate", rf),
        ("delta_r_rate", rr),
        ("lateral_accel", acc),
        ("v_y", v_y),
        ("yaw_rate", r),
        ("slip_front", slip_f),
        ("slip_rear", slip_r),
        ("x", np.asarray(px) - Y[1] * np.sin(heading)),
        ("y", np.asarray(py) + Y[1] * np.cos(heading)),
        ("psi", Y[2] + heading),
    ):
        out[name][valid] = val
    psi = _unwrap_time(out["psi"])
    # Put psi on the branch of the given initial heading.
    shift = 2 * math.pi * np.round((psi0 - psi[:, 0]) / (2 * math.pi))
    out["psi"] = psi + shift[:, None]
    return np.stack([out[name] for name in SIGNALS], axis=1)


# --------------------------------------------------------------------------
# Exact peaks of the continuous solution

#: Signals whose peak ``max |signal|`` :func:`exact_peaks` locates.
PEAK_SIGNALS = (
    "e",
    "delta_f",
    "delta_r",
    "delta_f_rate",
    "delta_r_rate",
    "lateral_accel",
)
_PEAK_ROWS = [SIGNALS.index(name) for name in PEAK_SIGNALS]
# Nodes per solver step on which the signals are first evaluated, candidate
# local maxima refined per run and signal, and the most golden-section
# iterations (0.618**80 shrinks a bracket of a step below 1e-16 of it).
_NODES_PER_STEP = 8
_PEAK_CANDIDATES = 3
_GOLDEN_ITERATIONS = 80
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


@dataclass
class DenseSolution:
    """The continuous solution of an :func:`integrate` call.

    ``history`` holds the solver's dense output of every accepted step with
    the runs integrated in it; ``engine_for(runs)`` builds the right-hand
    side of the given runs (for the derivative of the delayed state).
    """

    history: _History
    engine_for: Any
    delay: float

    def states(self, runs: np.ndarray, times: np.ndarray) -> np.ndarray:
        """States of run ``runs[j]`` at ``times[j]``, rows as :func:`integrate`.

        With a delay the six rows of the delayed path state and its
        derivative follow, as :func:`compute_outputs` expects them.
        """
        Y = self.history.states_at(runs, times)
        if self.delay <= 0.0:
            return Y
        rows = _delayed_state_rows(
            self.history, self.engine_for, self.delay, runs, times
        )
        return np.concatenate([Y, rows])


def _sample_peaks(signals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index and value of the largest output sample of each peak signal.

    ``|signal|`` per run and signal of :data:`PEAK_SIGNALS`, ``inf`` where a
    signal is not finite at a sample where the state is, ``-inf`` after the
    stop. One signal at a time, so that the temporaries are a fraction of
    the signals (``1 / len(SIGNALS)`` each), not a copy of them.
    """
    n, T = signals.shape[0], signals.shape[2]
    have = np.isfinite(signals[:, SIGNALS.index("s"), :])
    k = np.zeros((n, len(_PEAK_ROWS)), dtype=int)
    v = np.full((n, len(_PEAK_ROWS)), -np.inf)
    if T == 0:
        return k, v
    for j, row in enumerate(_PEAK_ROWS):
        a = np.abs(signals[:, row, :])
        a[~np.isfinite(a)] = np.inf
        a[~have] = -np.inf
        k[:, j] = np.argmax(a, axis=1)
        v[:, j] = a[np.arange(n), k[:, j]]
    return k, v


def exact_peaks(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: np.ndarray,
    feedforward: bool,
    time_constant: float | None,
    solution: DenseSolution,
    t_eval: np.ndarray,
    signals: np.ndarray,
    t_stop: np.ndarray,
    model: str = "kinematic",
    tyre: str = "linear",
    profile: Any = None,
    schedule: Any = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Peaks ``max |signal|`` of the continuous solution, per run and signal.

    The maximum is taken over the whole integrated interval ``[t0,
    t_stop]`` of each run, not over the output samples, so it does not
    depend on the output grid. Each signal of :data:`PEAK_SIGNALS` is
    evaluated (with :func:`compute_outputs`, on the solver's dense output)
    at :data:`_NODES_PER_STEP` points per solver step and at the run's
    stop; the largest local maxima of these nodes and the largest output
    sample are then refined by a golden-section search between their
    neighbours. The endpoints (``t = 0``, where the static controller's
    peaks often lie, and the stop) are nodes themselves. A signal that is
    not finite at a time where the state is (a rate or the lateral
    acceleration at a singular stop, where they diverge) has the peak
    ``inf`` at that time.

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, time_constant
        As given to :func:`integrate`.
    solution : DenseSolution
        From ``integrate(..., solution=[])``.
    t_eval : ndarray
        The output times of :func:`integrate`.
    signals : ndarray
        :func:`compute_outputs` at the output times, ``(n, len(SIGNALS), T)``.
    t_stop : ndarray
        Per run end time, from :func:`integrate`.
    model, tyre, profile, schedule : optional
        As given to :func:`integrate`.

    Returns
    -------
    values, times : ndarray
        Shape ``(n, len(PEAK_SIGNALS))``: the peak of ``|signal|`` and the
        time at which it occurs.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.engine import (
    ...     PEAK_SIGNALS, compute_outputs, exact_peaks, integrate)
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(np.array([0.1]), 0.5, 0.0)
    >>> kw = dict(speed=np.array([5.0]), feedforward=False, time_constant=None)
    >>> t = np.linspace(0.0, 10.0, 11)           # a coarse grid: 1 s
    >>> sol = []
    >>> states, status, _, t_stop = integrate(
    ...     veh, fws.Straight(), g, path_state=np.array([[0.0, 1.0, 0.0]]),
    ...     t_eval=t, solution=sol, **kw)
    >>> sig = compute_outputs(veh, fws.Straight(), g, states=states,
    ...                       initial_heading=np.zeros(1), **kw)
    >>> val, when = exact_peaks(veh, fws.Straight(), g, solution=sol[0],
    ...                         t_eval=t, signals=sig, t_stop=t_stop, **kw)
    >>> j = PEAK_SIGNALS.index("delta_f_rate")
    >>> round(float(when[0, j]), 3) > 0.0      # the rate peaks between samples
    True
    """
    n = speed.size
    S = len(PEAK_SIGNALS)
    hist = solution.history
    t0 = float(hist.t0)
    t_stop = np.asarray(t_stop, dtype=float)
    all_runs = np.arange(n)

    def evaluate(times: np.ndarray) -> np.ndarray:
        """``|signal|`` ``(n, S, K)`` at times ``(n, K)`` (NaN: no point)."""
        valid = np.isfinite(times)
        runs = np.broadcast_to(all_runs[:, None], times.shape)[valid]
        st = solution.states(runs, times[valid])
        states = np.full((st.shape[0], n, times.shape[1]), np.nan)
        states[:, valid] = st
        # (at a singular stop the rates are inf or NaN: they diverge there)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            out = compute_outputs(
                vehicle,
                path,
                gains,
                speed=speed,
                feedforward=feedforward,
                time_constant=time_constant,
                states=states,
                initial_heading=np.zeros(n),
                delay=solution.delay,
                model=model,
                tyre=tyre,
                profile=profile,
                schedule=schedule,
                times=times,
            )
        vals = np.abs(out[:, _PEAK_ROWS, :])
        vals = np.where(np.isfinite(vals), vals, np.inf)
        return np.where(valid[:, None, :], vals, -np.inf)

    # Nodes: the solver's step boundaries (they do not depend on the output
    # grid), subdivided, then the stop.
    bounds = [t0]
    for start, (end, _, _) in zip(hist.starts, hist.pieces, strict=True):
        bounds += [start, end]
    bounds = np.unique(np.asarray(bounds, dtype=float))
    frac = np.arange(_NODES_PER_STEP) / _NODES_PER_STEP
    grid = (bounds[:-1, None] + frac[None, :] * np.diff(bounds)[:, None]).ravel()
    grid = np.append(grid, bounds[-1])
    inside = grid[None, :] < t_stop[:, None]
    count = np.count_nonzero(inside, axis=1)
    times = np.full((n, grid.size + 1), np.nan)
    times[:, :-1] = np.where(inside, grid[None, :], np.nan)
    times[all_runs, count] = t_stop
    node_v = evaluate(times)  # (n, S, K)
    K = times.shape[1]

    # Best so far: the nodes and the output samples (all on the solution).
    k_samp, samp_v = _sample_peaks(np.asarray(signals, dtype=float))
    j_node = np.argmax(node_v, axis=2)
    best_v = np.take_along_axis(node_v, j_node[..., None], 2)[..., 0]
    best_t = times[all_runs[:, None], j_node]
    better = samp_v > best_v
    best_v = np.where(better, samp_v, best_v)
    best_t = np.where(better, t_eval[k_samp], best_t)

    # Candidate brackets: the largest local maxima of the nodes ...
    left = np.concatenate([np.full((n, S, 1), -np.inf), node_v[..., :-1]], axis=2)
    right = np.concatenate([node_v[..., 1:], np.full((n, S, 1), -np.inf)], axis=2)
    score = np.where((node_v >= left) & (node_v >= right), node_v, -np.inf)
    C = min(_PEAK_CANDIDATES, K)
    idx = np.argsort(-score, axis=2, kind="stable")[..., :C]  # (n, S, C)
    last = count[:, None, None]
    t_at = times[all_runs[:, None, None], np.clip(idx, 0, None)]
    lo = times[all_runs[:, None, None], np.maximum(idx - 1, 0)]
    hi = times[all_runs[:, None, None], np.minimum(idx + 1, last)]
    lo = np.where(np.isfinite(lo), lo, t_at)
    hi = np.where(np.isfinite(hi), hi, t_at)
    # ... and the largest output sample.
    T = t_eval.size
    s_lo = t_eval[np.maximum(k_samp - 1, 0)]
    s_hi = np.minimum(t_eval[np.minimum(k_samp + 1, T - 1)], t_stop[:, None])
    lo = np.concatenate([lo, s_lo[..., None]], axis=2)
    hi = np.concatenate([hi, np.maximum(s_hi, s_lo)[..., None]], axis=2)
    C1 = lo.shape[2]
    diag = np.arange(S)

    def f(x):  # |signal s| at x[:, s, c], shape (n, S, C1)
        v = evaluate(x.reshape(n, S * C1)).reshape(n, S, S, C1)
        return v[:, diag, diag, :]

    def keep_best(x, v):
        nonlocal best_v, best_t
        j = np.argmax(v, axis=2)
        vj = np.take_along_axis(v, j[..., None], 2)[..., 0]
        tj = np.take_along_axis(x, j[..., None], 2)[..., 0]
        up = vj > best_v
        best_v = np.where(up, vj, best_v)
        best_t = np.where(up, tj, best_t)

    # Golden-section search for the maximum in every bracket at once.
    a, b = lo, hi
    c = b - _GOLDEN * (b - a)
    d = a + _GOLDEN * (b - a)
    fc, fd = f(c), f(d)
    keep_best(c, fc)
    keep_best(d, fd)
    for _ in range(_GOLDEN_ITERATIONS):
        # A bracket of 1e-10 s leaves a value error of f''/2 * 1e-20: none.
        if np.all(b - a <= 1e-10 * np.maximum(1.0, np.abs(b))):
            break
        left_side = fc > fd  # the maximum is in [a, d]
        b = np.where(left_side, d, b)
        a = np.where(left_side, a, c)
        new_c = b - _GOLDEN * (b - a)
        new_d = a + _GOLDEN * (b - a)
        x = np.where(left_side, new_c, new_d)
        fx = f(x)
        keep_best(x, fx)
        c, fc, d, fd = (
            np.where(left_side, x, d),
            np.where(left_side, fx, fd),
            np.where(left_side, c, x),
            np.where(left_side, fc, fx),
        )
    return best_v, best_t
