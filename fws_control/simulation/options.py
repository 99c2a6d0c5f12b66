r"""The options of a closed-loop simulation, each checked once.

The solver (:data:`SOLVERS`, :func:`check_method`, :func:`choose_method`)
and its tolerances (:func:`check_tolerances`), the vehicle model
(:data:`MODELS`, :func:`check_model`), the initial state
(:func:`check_initial_state`, :func:`split_initial_state`,
:func:`initial_path_state`), the gains of the runs (:func:`run_gains`), the
steering lag (:func:`resolve_time_constant`), the output times and their
memory (:func:`time_grid`, :func:`output_samples`,
:func:`check_output_budget`) and a sampled controller's sample time
(:func:`check_sampling`). The runners and the python-control reference call
these before a run starts; the engines take the checked values.
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..controllers import (
    DEFAULT_ACTUATOR_TIME_CONSTANT,
)
from ..dynamics import (
    TYRES,
    require_dynamics,
)
from ..gains import SteeringGains
from ..paths import Path
from ..validation import MAX_ANGLE, check_finite, check_positive
from ..vehicle import Vehicle
from .outcomes import SIGNALS

if TYPE_CHECKING:
    from scipy.integrate import OdeSolver

__all__ = [
    "SOLVERS",
    "SOLVER_NAMES",
    "MODELS",
    "check_method",
    "RTOL_RANGE",
    "ATOL_RANGE",
    "STIFF_TIME_CONSTANT",
    "LONG_RUN_STEPS",
    "SAFE_STEP",
    "LSODA_MAX_RUNS",
    "choose_method",
    "check_tolerances",
    "check_initial_state",
    "check_model",
    "split_initial_state",
    "run_gains",
    "resolve_time_constant",
    "MAX_OUTPUT_BYTES",
    "output_samples",
    "check_output_budget",
    "time_grid",
    "initial_path_state",
    "path_key",
    "MAX_SAMPLES",
    "check_sampling",
    "WHOLE_SAMPLES",
    "AT_SWITCH",
    "sample_events",
]


#: Entries each cache of this module keeps (the oldest goes first).
_CACHE_SIZE = 32
#: Output grids by ``(duration, samples)``, read-only (time_grid copies them).
_GRIDS: dict = {}
#: Initial path states by ``(path_key(path), shape, bytes of the poses)``
#: (initial_path_state), for calls of at most _CACHED_POSES poses.
_PROJECTIONS: dict = {}
_CACHED_POSES = 8
#: Field values a path's key is made of (with tuples of them).
_PLAIN = (float, int, bool, str, type(None))


def path_key(path: Path) -> tuple | None:
    """A hashable key that equals another path's only if both are the same path.

    The path's type and the reprs of its fields (exact for floats, -0.0
    included), for the runners' caches of what depends on the path alone
    (its initial projections, the compiled engine's curvature table):
    paths are frozen, so equal keys give equal results, bit for bit.

    Returns
    -------
    tuple or None
        None for a path holding anything but numbers, strings and tuples
        of them (arrays, other paths): such a path is not cached.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.options import path_key
    >>> path_key(fws.Arc(0.1)) == path_key(fws.Arc(curvature=0.1))
    True
    >>> path_key(fws.Arc(0.1, start_heading=0.0)) == path_key(
    ...     fws.Arc(0.1, start_heading=-0.0))
    False
    """
    try:
        fields = vars(path)
    except TypeError:
        return None
    values = tuple(fields.values())
    for value in values:
        if type(value) is tuple:
            for item in value:
                if type(item) not in _PLAIN:
                    return None
        elif type(value) not in _PLAIN:
            return None
    return (type(path), repr(values))


def _remember(cache: dict, key: Any, value: Any) -> None:
    """Store `value` under `key`, dropping the oldest entry beyond _CACHE_SIZE."""
    if len(cache) >= _CACHE_SIZE:
        cache.pop(next(iter(cache)))
    cache[key] = value


def _positive_float(name: str, value: Any) -> float:
    """`value` as a float if it is finite and > 0, else check_positive's error.

    A Python float (or numpy float64) is checked without the array round
    trip of check_positive: the durations and steps of every call are.
    """
    if isinstance(value, float) and 0.0 < value < math.inf:
        return float(value)
    return float(check_positive(name, value))


#: The names of the scipy solvers accepted as ``method``.
SOLVER_NAMES = ("DOP853", "RK45", "RK23", "Radau", "BDF", "LSODA")


class _ScipySolvers(Mapping[str, "type[OdeSolver]"]):
    """scipy's solver classes by name, imported at the first lookup.

    A compiled run names its method and never needs scipy's classes; importing
    :mod:`scipy.integrate` (which brings scipy.optimize, scipy.linalg and
    scipy.sparse) would cost a process about half a second before its first
    result.
    """

    def __getitem__(self, name: str) -> type[OdeSolver]:
        if name not in SOLVER_NAMES:
            raise KeyError(name)
        import scipy.integrate

        return getattr(scipy.integrate, name)

    def __iter__(self) -> Iterator[str]:
        return iter(SOLVER_NAMES)

    def __len__(self) -> int:
        return len(SOLVER_NAMES)

    def __repr__(self) -> str:
        return f"<scipy.integrate solvers {', '.join(SOLVER_NAMES)}>"


#: The scipy solvers accepted by name as ``method``: a mapping from each of
#: :data:`SOLVER_NAMES` to its :class:`scipy.integrate.OdeSolver` class
#: (scipy.integrate is imported at the first lookup).
SOLVERS: Mapping[str, type[OdeSolver]] = _ScipySolvers()

#: Vehicle models of the engine: the paper's kinematic model and the dynamic
#: single-track model of :mod:`fws_control.dynamics` (tyre slip, states
#: ``v_y`` and ``r`` added after the others).
MODELS = ("kinematic", "dynamic")


def check_method(method: Any) -> type[OdeSolver]:
    """The solver class for `method` (a name of :data:`SOLVERS` or a class).

    Raises
    ------
    ValueError
        For an unknown name, listing the valid ones.

    Examples
    --------
    >>> from fws_control.simulation.options import check_method
    >>> check_method("RK45").__name__
    'RK45'
    """
    if isinstance(method, type):
        from scipy.integrate import OdeSolver

        if issubclass(method, OdeSolver):
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
#: ``rtol``. With steering limits and a delay both engines clip with
#: min/max inside their steps (without a delay they locate the switches as
#: events), and the tightest corner of the ranges costs many steps at the
#: clips' kinks; a run beyond MAX_STEPS ends "failed" with a message naming
#: the tolerances.
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
    >>> from fws_control.simulation.options import choose_method
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
    >>> from fws_control.simulation.options import check_tolerances
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
    >>> from fws_control.simulation.options import check_initial_state
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
    >>> from fws_control.simulation.options import check_model
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
    steering angles (:func:`~fws_control.simulation.engine.integrate`).

    Raises
    ------
    ValueError
        If the values are not finite, the last axis has the wrong length or
        a heading's magnitude exceeds
        :data:`~fws_control.validation.MAX_ANGLE`.

    Examples
    --------
    >>> from fws_control.simulation.options import split_initial_state
    >>> split_initial_state((0.0, 2.0, 0.0), model="dynamic").tolist()
    [[0.0, 2.0, 0.0, nan, nan]]
    >>> split_initial_state((0.0, 2.0, 0.0, 0.1, 0.0), model="dynamic").shape
    (1, 5)
    """
    if (
        type(initial_state) is np.ndarray
        and initial_state.dtype == np.float64
        and np.isfinite(initial_state).all()
    ):
        arr = initial_state  # (what check_finite returns for it)
    else:
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
    >>> from fws_control.simulation.options import run_gains
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
    >>> from fws_control.simulation.options import resolve_time_constant
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
    >>> from fws_control.simulation.options import output_samples
    >>> output_samples(15.0, dt=0.01), output_samples(15.0, dt=1e-320)
    (1501.0, inf)
    """
    if t_eval is not None:
        return float(np.size(t_eval))
    duration = _positive_float("duration", duration)
    dt = _positive_float("dt", dt)
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
        signals=...)``); default all of
        :data:`~fws_control.simulation.outcomes.SIGNALS`.

    Raises
    ------
    ValueError
        Naming the arguments, the size asked for and the budget, and saying
        how to get what was meant: a larger `dt`, a `t_eval` with the times
        needed, a shorter `duration` or fewer runs per call.

    Examples
    --------
    >>> from fws_control.simulation.options import check_output_budget
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
    >>> from fws_control.simulation.options import time_grid
    >>> time_grid(1.0, dt=0.25).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    duration = _positive_float("duration", duration)
    if t_eval is None:
        dt = _positive_float("dt", dt)
        samples = output_samples(duration, dt=dt)
        check_output_budget(1, samples, duration=duration, dt=dt)
        key = (duration, int(samples))
        grid = _GRIDS.get(key)
        if grid is None:
            grid = np.linspace(0.0, duration, int(samples))
            grid.flags.writeable = False
            _remember(_GRIDS, key, grid)
        # a copy: the caller owns (and may change) the grid it is given
        return grid.copy()
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
    >>> from fws_control.simulation.options import initial_path_state
    >>> initial_path_state(Arc(curvature=0.1), np.array([[0.0, -5.0, 0.0]]))
    array([[ 0., -5.,  0.]])
    """
    # A few poses are remembered, keyed on the path's value (paths are
    # frozen) and the poses' bit patterns: a loop of simulate calls projects
    # the same pose onto the same path run after run, and one projection
    # costs about as much as integrating the paper's 15 s run.
    key = path_key(path) if len(initial_state) <= _CACHED_POSES else None
    if key is not None:
        poses = np.ascontiguousarray(initial_state, dtype=float)
        key = (key, poses.shape, poses.tobytes())
        hit = _PROJECTIONS.get(key)
        if hit is not None:
            return hit.copy()
    out = np.empty_like(initial_state, dtype=float)
    for i, (x0, y0, psi0) in enumerate(initial_state):
        p = path.project(float(x0), float(y0), strict=True)
        theta0 = math.remainder(float(psi0) - float(p.heading), 2 * math.pi)
        out[i] = (float(p.s), float(p.e), theta0)
    if key is not None:
        _remember(_PROJECTIONS, key, out.copy())
    return out


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


#: Relative slack with which a delay counts as a whole number of samples
#: (then the commands switch exactly at the sample times).
WHOLE_SAMPLES = 1e-9

#: An output time this close to a switch, in sample times, shows the new
#: command: a zero-order hold is right-continuous.
AT_SWITCH = 1e-9


def sample_events(
    t0: float, t_end: float, sample_time: float, delay: float
) -> Iterator[tuple[float, int, int]]:
    """``(time, kind, k)`` of a sampled run, in the order they happen (lazily).

    Sample ``k`` measures the state at ``t0 + k Ts`` (the initial state for
    ``k <= 0``: the state is held before ``t0``) and its command is applied
    from ``t0 + k Ts + delay`` until the next one's; kind 0 is the
    measurement, kind 1 the switch. The first sample is the one whose command
    is applied at ``t0``. Both engines run a sampled controller on these
    events.

    Parameters
    ----------
    t0, t_end : float
        Start and end of the run [s]; switches at or after `t_end` are left
        out (but those at `t0` of a run that is the instant `t0`).
    sample_time : float
        :math:`T_s` [s], > 0.
    delay : float
        Input delay [s], >= 0; within :data:`WHOLE_SAMPLES` of a whole
        number of samples it counts as that number.

    Returns
    -------
    iterator of (float, int, int)
        ``(time, kind, k)`` in time order, a measurement before a switch at
        the same time.

    Examples
    --------
    >>> from fws_control.simulation.options import sample_events
    >>> [(round(t, 9), kind, k) for t, kind, k in sample_events(0.0, 0.1, 0.05, 0.05)]
    [(0.0, 0, -1), (0.0, 0, 0), (0.0, 1, -1), (0.05, 0, 1), (0.05, 1, 0)]
    """
    ts = sample_time
    d = delay / ts
    if abs(d - round(d)) <= WHOLE_SAMPLES * max(1.0, d):
        d = round(d)
    k_first = math.floor(-d)
    k_last = math.floor((t_end - t0) / ts - d)  # the last switch before t_end
    samples = range(k_first, k_last + 1)
    measures = ((t0 + max(k, 0) * ts, 0, k) for k in samples)
    # (a switch at t0 also when the run is that instant: its command shows)
    switches = (
        (max(t0 + (k + d) * ts, t0), 1, k)
        for k in samples
        if t0 + (k + d) * ts < t_end or t0 + (k + d) * ts <= t0
    )
    return heapq.merge(measures, switches)
