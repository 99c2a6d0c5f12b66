r"""The arguments of :func:`~fws_control.simulate` and
:func:`~fws_control.simulate_batch`, resolved into runs.

The plant (a :class:`~fws_control.LateralPlant`, or the deprecated
:class:`~fws_control.Vehicle` form) gives the vehicle, speed, model, tyre
and steering lag (:func:`resolve_plant`); a
:class:`~fws_control.SpeedProfile` and a gain schedule are resolved by
:func:`speed_option` and :func:`with_profile`; the runs are validated and
broadcast once (:func:`prepare_runs`); the kept signals and an ``out``
array are checked by :func:`check_signals` and :func:`check_out`.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np

from ..deprecation import legacy_keyword, reject_unknown, warn_deprecated
from ..gains import SteeringGains
from ..lateral_controller import LateralController
from ..paths import Path
from ..plant import LateralPlant
from ..speed_profile import SpeedProfile
from ..validation import (
    check_nonzero,
    check_scalar,
    check_type,
)
from ..vehicle import Vehicle
from .loop import is_sampled, scheduled_gains
from .options import (
    SOLVER_NAMES,
    check_method,
    check_model,
    check_output_budget,
    check_sampling,
    check_tolerances,
    choose_method,
    output_samples,
    resolve_time_constant,
    run_gains,
    split_initial_state,
    time_grid,
)
from .outcomes import SIGNALS

__all__ = [
    "check_chunk_size",
    "check_signals",
    "check_out",
    "prepare_runs",
    "check_profile_run",
    "speed_option",
    "resolve_plant",
    "with_profile",
]

#: The choice of ``signals="metrics"``: no time series, only per-run values.
_METRICS_ONLY = "metrics"


def check_signals(signals: Any) -> tuple[str, ...]:
    """The names of the kept signals, in the order of :data:`SIGNALS`."""
    if signals is None:
        return SIGNALS
    if isinstance(signals, str):
        if signals == _METRICS_ONLY:
            return ()
        raise ValueError(
            f"signals must be None (all), 'metrics' (no time series) or a "
            f"sequence of names of {SIGNALS}, got the str {signals!r}"
            + (
                f" (for one signal: signals=({signals!r},))"
                if signals in SIGNALS
                else ""
            )
        )
    try:
        names = list(signals)
    except TypeError:
        raise TypeError(
            "signals must be None, 'metrics' or a sequence of signal names, got "
            f"{type(signals).__name__} {signals!r}"
        ) from None
    if not names:
        raise ValueError(
            "signals must name at least one signal, got an empty sequence; use "
            "signals='metrics' to keep no time series (only per-run metrics)"
        )
    for name in names:
        if not isinstance(name, str):
            raise TypeError(
                f"signals must hold signal names (str), got {name!r} of type "
                f"{type(name).__name__} in {signals!r}; valid names: {SIGNALS}"
            )
        if name not in SIGNALS:
            raise ValueError(
                f"signals: unknown signal {name!r}; valid names: {SIGNALS} "
                "(or signals=None for all, 'metrics' for none)"
            )
    if len(set(names)) != len(names):
        raise ValueError(f"signals must not repeat a name, got {signals!r}")
    return tuple(k for k in SIGNALS if k in names)


def check_out(out: Any, shape: tuple[int, int, int]) -> None:
    """Refuse an `out` that cannot receive the kept signals in place."""
    if shape[1] == 0:
        raise ValueError(
            "out must be None with signals='metrics' (no time series to write), "
            f"got {type(out).__name__}"
        )
    # other subclasses of ndarray carry state of their own that the chunks'
    # writes would not update (a masked array's mask)
    if type(out) is not np.ndarray and not isinstance(out, np.memmap):
        raise TypeError(
            f"out must be a numpy.ndarray (e.g. numpy.empty({shape})) or a "
            f"numpy.memmap, got {type(out).__name__}"
        )
    if out.dtype != np.float64 or out.shape != shape:
        raise ValueError(
            f"out must be a float64 array (native byte order) of shape {shape} "
            f"(runs, kept signals, output times), got {out.dtype} of shape "
            f"{out.shape}"
        )
    if not out.flags.c_contiguous:
        raise ValueError(
            f"out must be C-contiguous (the chunks write whole rows), got an "
            f"array with strides {out.strides}"
        )
    if not out.flags.writeable:
        raise ValueError("out must be writeable, got a read-only array")


#: Most solver steps a delay may force over the run (duration / delay).
_MAX_DELAY_STEPS = 1.0e4


def prepare_runs(
    vehicle,
    path,
    gains,
    speed,
    initial_state,
    duration,
    dt,
    t_eval,
    tau,
    opts,
    kept=None,
):
    """Validate the arguments shared by both runners; broadcast the runs."""
    check_type("vehicle", vehicle, Vehicle)
    # every run records lateral_accel and v_y (and the peak of lateral_accel)
    vehicle.cg_distance(
        needed_by="a simulation (its signals lateral_accel and v_y are at G)"
    )
    check_type("path", path, Path, "a fws_control Path (e.g. fws.Straight())")
    ctrl = gains if isinstance(gains, LateralController) else None
    if ctrl is None:
        fields = _gain_fields(gains)
    else:
        # a controller carries its own parameters: no gains to record (NaN)
        fields = (np.full(ctrl.runs() or 1, np.nan),) * 3
    n_gains = fields[0].size
    # scalars named here: the engine's float() of an array would not name them
    for name, value in (("duration", duration), ("dt", dt)):
        if value is not None and np.ndim(value) != 0:
            raise ValueError(
                f"{name} must be a scalar [s], got an array of shape {np.shape(value)}"
            )
    if tau is not None:
        tau = check_scalar("steering_lag", tau)
    if isinstance(speed, float) and math.isfinite(speed) and speed != 0.0:
        # (a plant's speed: a float, checked without the array round trip)
        speed_arr = np.array([speed], dtype=float)
    else:
        speed_arr = np.atleast_1d(
            np.asarray(check_nonzero("speed", speed), dtype=float)
        )
    if speed_arr.ndim != 1:
        raise ValueError(f"speed must be a scalar or 1-D, got shape {speed_arr.shape}")
    opts["model"], opts["tyre"] = check_model(vehicle, opts["model"], opts["tyre"])
    if opts["model"] == "dynamic" and np.any(speed_arr <= 0.0):
        # the slip angles atan2(., u) and the 1/u of the tyre model assume
        # forward motion
        raise ValueError(
            "speed must be > 0 for model='dynamic' (forward longitudinal speed "
            f"u of the single-track model), got {speed!r}"
        )
    x0 = split_initial_state(initial_state, model=opts["model"])
    sizes = {n_gains, speed_arr.size, x0.shape[0]} - {1}
    if len(sizes) > 1:
        raise ValueError(
            "gains, speed and initial_state must have one entry or the same "
            f"number of runs, got {n_gains}, {speed_arr.size} and {x0.shape[0]}"
        )
    n = sizes.pop() if sizes else 1
    k1, k2, a, V = (
        v.copy() if v.shape == (n,) else np.broadcast_to(v, (n,)).copy()
        for v in (*fields, speed_arr)
    )
    x0 = x0.copy() if x0.shape == (n, 5) else np.broadcast_to(x0, (n, 5)).copy()
    # (before building the grid: dt = 1e-9 must not allocate 112 GiB first)
    samples = output_samples(duration, dt=dt, t_eval=t_eval)
    check_output_budget(
        n,
        samples,
        duration=duration,
        dt=dt,
        t_eval=t_eval,
        signals=len(SIGNALS) if kept is None else kept,
    )
    t = time_grid(duration, dt=dt, t_eval=t_eval)
    span = float(t[-1] - t[0])
    if ctrl is not None and is_sampled(ctrl):
        check_sampling(ctrl, span)
    if 0.0 < opts["delay"] < span / _MAX_DELAY_STEPS:
        # the method of steps takes steps no longer than the delay: a delay of
        # 1e-300 s would never finish
        raise ValueError(
            f"delay must be 0 or >= duration/{_MAX_DELAY_STEPS:g} = "
            f"{span / _MAX_DELAY_STEPS:.3g} s (the solver's steps are bounded by "
            f"the delay), got {opts['delay']!r}"
        )
    tau = resolve_time_constant(vehicle, tau)
    opts["rtol"], opts["atol"] = check_tolerances(opts["rtol"], opts["atol"])
    if isinstance(opts["method"], str) and opts["method"] == "auto":
        # (the duration: see the long-run rule there; the same for every
        # run of a batch, so that a run's accuracy does not depend on it)
        opts["method"] = choose_method(
            tau, opts["rtol"], duration=span, delay=opts["delay"]
        )
    else:
        method = opts["method"]
        if not (isinstance(method, str) and method in SOLVER_NAMES):
            method = check_method(method)  # a class, or raises for a bad one
        _warn_if_stiff(method, tau, float(t[-1]))
    return k1, k2, a, V, x0, t, tau, ctrl


def _gain_fields(gains: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(k1, k2, ratio)`` of the runs as 1-D float arrays (run_gains')."""
    if isinstance(gains, SteeringGains) and not any(
        np.ma.isMaskedArray(v) for v in (gains.k1, gains.k2, gains.ratio)
    ):
        # SteeringGains holds finite floats (or float arrays) already: only
        # broadcast, as run_gains does, without building and checking a copy
        k1, k2, a = np.broadcast_arrays(gains.k1, gains.k2, gains.ratio)
        return k1.ravel().copy(), k2.ravel().copy(), a.ravel().copy()
    g = run_gains(gains, name="gains")  # 1-D float arrays
    return np.asarray(g.k1), np.asarray(g.k2), np.asarray(g.ratio)


#: Steps an explicit method may be forced to take by the actuator's
#: stability bound (about 6.4 T for DOP853) before a warning.
_STIFF_STEPS = 5000


_EXPLICIT = ("DOP853", "RK23", "RK45")


def _warn_if_stiff(method, tau, duration) -> None:
    """Warn when an explicitly chosen explicit method meets a stiff actuator.

    `method` is one of :data:`SOLVER_NAMES` or a solver class (a name needs
    no import of scipy.integrate).
    """
    if tau is None:
        return
    if isinstance(method, str):
        name, explicit = method, method in _EXPLICIT
    else:
        import scipy.integrate

        name = method.__name__
        explicit = issubclass(
            method, tuple(getattr(scipy.integrate, m) for m in _EXPLICIT)
        )
    if not explicit:
        return
    steps = duration / (6.4 * tau)
    if steps > _STIFF_STEPS:
        warnings.warn(
            f"method={name!r} with steering_lag={tau!r} over "
            f"duration={duration!r}: the actuator makes the loop stiff, so this "
            f"explicit method needs about {steps:.2g} steps (its step is bounded "
            "near 6.4 times the time constant); method='auto' or 'Radau' steps "
            "by accuracy instead",
            RuntimeWarning,
            stacklevel=4,
        )


#: The keywords of the deprecated Vehicle form of simulate/simulate_batch
#: that the plant now holds.
_PLANT_KEYWORDS = ("speed", "model", "tyre", "steering_lag", "actuator_time_constant")


def _profile_start(profile: SpeedProfile) -> float:
    """Where a profile is read for the direction and the nominal gains."""
    if profile.of == "time" or profile.points is None:
        return 0.0
    return float(profile.points[0])


def check_profile_run(profile, *, model, delay, feedforward, gains, engine) -> None:
    """Refuse the cases a varying speed is not simulated in (ValueError)."""
    if np.ndim(delay) == 0 and float(delay) > 0.0:
        raise ValueError(
            f"delay must be 0 with a varying speed (speed={profile!r}), got "
            f"{delay!r}: the delayed measurements would need the speed of their "
            "own time"
        )
    if isinstance(feedforward, str) and feedforward == "dynamic":
        raise ValueError(
            "feedforward='dynamic' is not simulated with a varying speed "
            f"(speed={profile!r}); use feedforward=True (eq. 26, independent "
            "of the speed) or False"
        )
    if isinstance(gains, LateralController):
        raise ValueError(
            f"controller: {type(gains).__name__} is not simulated with a varying "
            f"speed (speed={profile!r}); use SteeringGains or a gain schedule"
        )
    if model == "dynamic" and profile.speeds is not None:
        low = np.flatnonzero(profile.speeds <= 0.0)
        if low.size:
            i = int(low[0])
            raise ValueError(
                f"speed: the SpeedProfile's speeds must lie in (0, inf) m/s for "
                f"model='dynamic' (forward longitudinal speed u), got "
                f"{float(profile.speeds[i])!r} at index {i}"
            )


def speed_option(plant: Any, speed: Any, kwargs: dict) -> SpeedProfile | None:
    """The varying speed of a plant-first call, or None.

    For the deprecated Vehicle form, `speed` is its constant speed and goes
    back to `kwargs`. A constant profile gives None (the plant's speed is
    replaced by the caller).
    """
    if speed is None:
        return None
    if not isinstance(plant, LateralPlant):
        kwargs["speed"] = speed
        return None
    if isinstance(speed, SpeedProfile):
        return speed
    raise TypeError(
        f"speed={speed!r} ({type(speed).__name__}) with a LateralPlant: a number "
        "as speed= applies only to the deprecated Vehicle form (the plant holds "
        "its constant speed: dataclasses.replace(plant, speed=...)); speed= "
        "must be None or a fws.SpeedProfile (e.g. fws.SpeedProfile.from_time(t, "
        "v)) for a speed that varies"
    )


def _is_schedule(controller: Any) -> bool:
    """A gain schedule: ``at(speed)`` or a plain function of the speed."""
    if isinstance(controller, (SteeringGains, LateralController)):
        return False
    return callable(getattr(controller, "at", None)) or callable(controller)


def _scheduled(controller: Any, speed: Any) -> Any:
    """The gains of a gain schedule at the run's speed; others unchanged.

    A gain schedule is an object with a method ``at(speed)`` that returns
    :class:`~fws_control.SteeringGains` (e.g.
    :class:`~fws_control.GainSchedule`); the runs hold their speed, so the
    schedule is read once per run. Its range errors name the speed.
    """
    if isinstance(controller, (SteeringGains, LateralController)):
        return controller
    at = getattr(controller, "at", None)
    if not callable(at):
        return controller
    gains = at(np.asarray(speed, dtype=float))
    if not isinstance(gains, SteeringGains):
        raise TypeError(
            f"controller.at(speed) must return a SteeringGains (a gain "
            f"schedule), got {type(gains).__name__} from {controller!r}"
        )
    return gains


def resolve_plant(function: str, plant: Any, controller: Any, kwargs: dict):
    """``(vehicle, controller, speed, model, tyre, lag)`` of a call.

    `plant` is a :class:`LateralPlant`, or (deprecated, with a
    FutureWarning) a :class:`Vehicle` with the keywords of
    :data:`_PLANT_KEYWORDS` in `kwargs`. The deprecated ``gains=`` names
    the controller. `kwargs` is emptied; an unknown keyword raises.
    """
    controller = legacy_keyword(kwargs, "gains", _CONTROLLER[function], controller)
    if controller is None:
        raise TypeError(
            f"{function}() missing the argument {_CONTROLLER[function]!r} (a "
            "SteeringGains or a lateral controller)"
        )
    if isinstance(plant, LateralPlant):
        given = [k for k in _PLANT_KEYWORDS if k in kwargs]
        if given:
            raise TypeError(
                f"{function}(): {', '.join(k + '=' for k in given)} applies only "
                "to the deprecated Vehicle form; the LateralPlant already holds "
                "its speed, model, tyre and steering lag (e.g. "
                "dataclasses.replace(plant, steering_lag=0.1))"
            )
        reject_unknown(function, kwargs)
        lag = plant.steering_lag
        if lag is not None:
            # LateralPlant stores the pair; a float is read as both axles
            front, rear = (lag, lag) if isinstance(lag, float) else lag
            if front != rear:
                raise ValueError(
                    f"plant.steering_lag must hold one time constant for both "
                    f"axles in the simulation (front == rear > 0 s), got "
                    f"{lag!r}: the simulated actuator has one time constant"
                )
            lag = front
        # "kinematic" and "paper" are two linearisations of one nonlinear
        # kinematic model, which is what is simulated
        model = "dynamic" if plant.model == "dynamic" else "kinematic"
        return plant.vehicle, controller, plant.speed, model, plant.tyre, lag
    if isinstance(plant, Vehicle):
        if "speed" not in kwargs:
            raise TypeError(
                f"{function}(): plant must be a fws.LateralPlant (vehicle, speed, "
                f"model, tyre, steering lag), got a Vehicle without speed=; pass "
                f"fws.LateralPlant(vehicle, speed=...)"
            )
        warn_deprecated(
            f"{function}(vehicle, path, gains, speed=...)",
            f"{function}(plant, path, {_CONTROLLER[function]}) and pass a "
            "fws.LateralPlant(vehicle, speed=..., model=..., tyre=..., "
            "steering_lag=...) as the plant",
        )
        speed = kwargs.pop("speed")
        model = kwargs.pop("model", "kinematic")
        tyre = kwargs.pop("tyre", "linear")
        lag = legacy_keyword(
            kwargs, "actuator_time_constant", "steering_lag",
            kwargs.pop("steering_lag", None),
        )  # fmt: skip
        reject_unknown(function, kwargs)
        return plant, controller, speed, model, tyre, lag
    raise TypeError(
        f"{function}(): plant must be a fws.LateralPlant (the simulated system: "
        f"vehicle, speed, model, tyre, steering lag), got {type(plant).__name__}"
    )


_CONTROLLER = {"simulate": "controller", "simulate_batch": "controllers"}


def with_profile(
    profile: SpeedProfile | None, speed: Any, controller: Any
) -> tuple[SpeedProfile | None, Any, Any, Any]:
    """``(profile, speed, controller, schedule)`` of a call.

    A constant profile replaces the plant's speed (the run is then the
    constant-speed run, on either engine). With a varying profile a gain
    schedule is kept as the `schedule`, read at the current speed during
    the run, and `speed` becomes the direction of travel; otherwise a
    schedule is read once at the plant's speed (:func:`_scheduled`).
    """
    if profile is not None and np.ndim(speed) != 0:
        raise ValueError(
            "plant.speed must be one number with speed= a SpeedProfile (the "
            "profile gives every run's speed; the plant's is its linearisation "
            f"point), got an array of shape {np.shape(speed)}"
        )
    if profile is not None and profile.is_constant:
        speed, profile = float(np.asarray(profile.speeds)[0]), None
    if profile is None:
        return None, speed, _scheduled(controller, speed), None
    schedule = None
    if _is_schedule(controller):
        # the gains at the profile's start count the runs (the record is
        # the schedule's at each run's own start)
        schedule = controller
        controller = scheduled_gains(schedule, profile(_profile_start(profile)))
    return profile, profile.initial_sign or 1.0, controller, schedule


def check_chunk_size(
    chunk_size: Any,
    *,
    runs: int,
    kept: tuple[str, ...],
    out: Any,
    duration: Any,
    dt: Any,
    t_eval: Any,
    samples: int,
) -> int:
    """The runs per chunk as an int, refused unless an integer >= 1 or when
    a chunk's full signals (all of :data:`~fws_control.simulation.outcomes.SIGNALS`,
    computed before the kept ones are taken or written to `out`) exceed
    :data:`~fws_control.simulation.options.MAX_OUTPUT_BYTES`."""
    if (
        isinstance(chunk_size, bool)
        or not isinstance(chunk_size, (int, np.integer, float))
        or not math.isfinite(chunk_size)
        or int(chunk_size) != chunk_size
        or chunk_size < 1
    ):
        raise ValueError(f"chunk_size must be an integer >= 1, got {chunk_size!r}")
    chunk_size = int(chunk_size)
    if kept != SIGNALS or out is not None:
        # the working set: one chunk's full signals (the kept ones are counted
        # in prepare_runs, unless they go to out)
        try:
            check_output_budget(
                min(chunk_size, runs), samples, duration=duration, dt=dt, t_eval=t_eval
            )
        except ValueError as exc:
            where = f"keeps {len(kept)} of them"
            if out is not None:
                where = "writes them into out"
            raise ValueError(
                f"chunk_size={chunk_size}: a chunk computes all {len(SIGNALS)} "
                f"signals before it {where}, and {exc}; or a smaller chunk_size"
            ) from None
    return chunk_size
