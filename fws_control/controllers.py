r"""Path-tracking controllers and the steering actuator.

The controller of the paper (eqs. 24-29) computes the steering angles from
the path-frame errors and the path curvature at the projection point:

.. math::
    \delta_f = \underbrace{\arctan(\kappa_C f)}_{\delta_f^{FF}\ (26)}
               \underbrace{-\,k_1 e_C - k_2\theta_C}_{\delta_f^{FB}\ (28)},\qquad
    \delta_r = \underbrace{0}_{\delta_r^{FF}\ (27)}
               \underbrace{-\,a k_1 e_C - a k_2\theta_C}_{\delta_r^{FB}\ (29)}.

The feedback-only controller drops the feedforward term. Each channel is
clipped to the vehicle's steering-angle limit when one is set
(:attr:`Vehicle.max_steer_front`, :attr:`Vehicle.max_steer_rear`);
otherwise no saturation is applied.

A steering-*rate* limit cannot be expressed by a static map: it needs the
actual steering angle as a state. :func:`steering_actuator` provides that
state as a first-order lag whose rate is clipped,

.. math:: \dot\delta = \operatorname{clip}\!\left(
          \frac{\delta^{cmd} - \delta}{\tau}, -\dot\delta_{max},
          \dot\delta_{max}\right),

which the simulators insert between controller and vehicle whenever a rate
limit is set.

The law's equations are written once, in :mod:`fws_control.equations`
(:func:`~fws_control.equations.steering_law`,
:func:`~fws_control.equations.feedback_command` and their rates);
:func:`steering_command` and :func:`steering_command_rate` add the checks,
the dynamic feedforward and the angle limits. The
:class:`control.NonlinearIOSystem` blocks and the numpy engine call these,
the compiled engine the same equations compiled by numba.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np

from . import equations
from .deprecation import legacy_keyword, reject_unknown
from .dynamics import dynamic_feedforward, dynamic_feedforward_derivative
from .gains import SteeringGains
from .hints import FeedforwardLike, RealArrayLike, TyreName
from .kinematic_models import STEERING_INPUTS, check_inputs, check_result
from .validation import check_positive, check_scalar, check_type
from .vehicle import Vehicle

if TYPE_CHECKING:
    # python-control costs 0.7 s to import and the simulation engine, which
    # calls this module's laws, does not need it: imported where it is used
    import control as ct

__all__ = [
    "steering_command",
    "steering_command_rate",
    "path_tracking_controller",
    "feedback_controller",
    "feedforward_feedback_controller",
    "steering_actuator",
    "actuator_rate",
    "CONTROLLER_INPUTS",
    "DEFAULT_ACTUATOR_TIME_CONSTANT",
    "FEEDFORWARDS",
    "check_feedforward",
]

#: Inputs of the controller blocks: the path-frame errors and the path
#: curvature at the projection point.
CONTROLLER_INPUTS = ("e", "theta", "curvature")

#: Time constant [s] of :func:`steering_actuator` used by the simulators when
#: a rate limit is set and no other value is given.
DEFAULT_ACTUATOR_TIME_CONSTANT = 0.05


#: Feedforward options of :func:`steering_command` besides ``True``/``False``.
FEEDFORWARDS = ("kinematic", "dynamic")


def check_feedforward(
    feedforward: bool | str, *, speed: RealArrayLike | None = None
) -> Literal[False, "kinematic", "dynamic"]:
    """Normalise a feedforward option: ``False``, ``"kinematic"`` or ``"dynamic"``.

    ``True`` means ``"kinematic"`` (paper eq. 26). ``"dynamic"`` needs the
    `speed`.

    Examples
    --------
    >>> from fws_control.controllers import check_feedforward
    >>> check_feedforward(True), check_feedforward(False)
    ('kinematic', False)
    """
    if isinstance(feedforward, (bool, np.bool_)):
        return "kinematic" if feedforward else False
    if not isinstance(feedforward, str):
        raise TypeError(
            f"feedforward must be True, False or one of {FEEDFORWARDS}, got "
            f"{feedforward!r}"
        )
    if feedforward not in FEEDFORWARDS:
        raise ValueError(
            f"feedforward must be True, False or one of {FEEDFORWARDS}, got "
            f"{feedforward!r}"
        )
    if feedforward == "dynamic" and speed is None:
        raise ValueError(
            "feedforward='dynamic' needs the keyword speed= (m/s, > 0): the "
            "tyre slip angles it supplies grow with the speed"
        )
    return cast('Literal["kinematic", "dynamic"]', feedforward)  # checked above


def _limit(value: float | None) -> float:
    return math.inf if value is None else float(value)


def _check_gains(gains) -> SteeringGains:
    if not isinstance(gains, SteeringGains):
        raise TypeError(f"gains must be a SteeringGains, got {type(gains).__name__}")
    return gains


def steering_command(
    vehicle: Vehicle,
    gains: SteeringGains,
    e: RealArrayLike,
    theta: RealArrayLike,
    *,
    curvature: RealArrayLike = 0.0,
    feedforward: FeedforwardLike = True,
    speed: RealArrayLike | None = None,
    tyre: TyreName = "linear",
) -> tuple[np.ndarray, np.ndarray]:
    r"""Steering angles of the path-tracking controller, paper eqs. (24)-(29).

    .. math::
        \delta_f = \operatorname{sat}_f\!\big(\arctan(\kappa f)\,[\text{if
        feedforward}] - k_1 e - k_2\theta\big),\quad
        \delta_r = \operatorname{sat}_r\!\big(a(-k_1 e - k_2\theta)\big)

    where :math:`\operatorname{sat}` clips to the vehicle's angle limit if one
    is set and is the identity otherwise.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and optional steering-angle limits.
    gains : SteeringGains
        ``k1, k2, ratio``; may hold arrays that broadcast with the errors.
    e, theta : float or array_like
        Lateral error [m] (positive left of the path) and heading error
        [rad].
    curvature : float or array_like, optional
        Path curvature at the projection point [1/m]; only used by the
        feedforward term.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        ``True`` or ``"kinematic"`` (default): the feedforward angle of
        eq. (26). ``False``: the feedback-only controller of eqs. (28)-(29).
        ``"dynamic"``: the front *and* rear angles of
        :func:`~fws_control.dynamics.dynamic_feedforward`, which hold the
        dynamic (tyre-slip) model on the curve with ``e = theta = 0``
        (removing the offset of :func:`~fws_control.steady_state_offset`);
        needs `speed` and the vehicle's dynamic data.
    speed : float or array_like, optional
        Longitudinal speed [m/s], > 0; only for ``feedforward="dynamic"``.
    tyre : {"linear", "magic"}, optional
        Tyre model of the dynamic feedforward (default ``"linear"``).

    Returns
    -------
    delta_f, delta_r : ndarray
        Front and rear steering angles [rad], broadcast over the arguments.

    Raises
    ------
    TypeError
        If `vehicle` or `gains` has the wrong type, or `feedforward` is not
        a bool (``"False"`` would read as true).
    ValueError
        If an argument is not real numbers or a scalar is not finite (naming
        it; non-finite elements of arrays give non-finite elements in their
        place, see :func:`~fws_control.kinematic_models.check_inputs`), or magnitudes
        so extreme that the command overflows.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=-1.0)
    >>> df, dr = fws.steering_command(veh, g, e=1.0, theta=0.0, curvature=0.1)
    >>> round(float(df), 6), round(float(dr), 6)
    (0.163712, 0.1)
    >>> lim = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_front=0.1)
    >>> float(fws.steering_command(lim, g, 1.0, 0.0, curvature=0.1)[0])
    0.1
    """
    check_type("vehicle", vehicle, Vehicle)
    gains = _check_gains(gains)
    feedforward = check_feedforward(feedforward, speed=speed)
    e_, th_, k_ = check_inputs(e=e, theta=theta, curvature=curvature)
    with np.errstate(over="ignore", invalid="ignore"):
        if feedforward == "kinematic":
            delta_f, delta_r = equations.steering_law(
                e_, th_, k_, vehicle.wheelbase, gains.k1, gains.k2, gains.ratio
            )
        else:
            fb, delta_r = equations.feedback_command(
                e_, th_, gains.k1, gains.k2, gains.ratio
            )
            delta_f = fb
    if feedforward == "dynamic":
        # check_feedforward has refused "dynamic" without a speed
        ff_f, ff_r = dynamic_feedforward(
            vehicle, speed=cast(RealArrayLike, speed), curvature=curvature, tyre=tyre
        )
        delta_f = fb + ff_f
        delta_r = delta_r + ff_r
    check_result("steering command", delta_f, e=e_, theta=th_, curvature=k_)
    check_result("steering command", delta_r, e=e_, theta=th_)
    max_f = _limit(vehicle.max_steer_front)
    max_r = _limit(vehicle.max_steer_rear)
    if math.isfinite(max_f):
        delta_f = np.clip(delta_f, -max_f, max_f)
    if math.isfinite(max_r):
        delta_r = np.clip(delta_r, -max_r, max_r)
    delta_f, delta_r = np.broadcast_arrays(delta_f, delta_r)
    return np.array(delta_f), np.array(delta_r)


def steering_command_rate(
    vehicle: Vehicle,
    gains: SteeringGains,
    e: RealArrayLike,
    theta: RealArrayLike,
    e_rate: RealArrayLike,
    theta_rate: RealArrayLike,
    *,
    curvature: RealArrayLike,
    curvature_rate: RealArrayLike = 0.0,
    feedforward: FeedforwardLike = True,
    speed: RealArrayLike | None = None,
    tyre: TyreName = "linear",
) -> tuple[np.ndarray, np.ndarray]:
    r"""Time derivatives of :func:`steering_command` by the chain rule.

    .. math::
        \dot\delta_f = \frac{f\dot\kappa}{1+f^2\kappa^2}\,[\text{if
        feedforward}] - k_1\dot e - k_2\dot\theta,\qquad
        \dot\delta_r = a(-k_1\dot e - k_2\dot\theta),

    set to zero where the corresponding angle is clipped at its limit (the
    derivative of the clipped signal; at the limit itself the one-sided
    derivative of the unclipped command is returned).

    Parameters
    ----------
    vehicle, gains, e, theta, curvature, feedforward, speed, tyre
        As in :func:`steering_command`; with ``feedforward="dynamic"`` the
        feedforward rates are
        :func:`~fws_control.dynamics.dynamic_feedforward_derivative` times
        `curvature_rate` (at constant speed).
    e_rate, theta_rate : float or array_like
        :math:`\dot e` [m/s] and :math:`\dot\theta` [rad/s].
    curvature_rate : float or array_like, optional
        Time derivative of the curvature at the projection point,
        :math:`\dot\kappa = \kappa'(s)\dot s` [1/(m s)].

    Returns
    -------
    delta_f_rate, delta_r_rate : ndarray
        [rad/s], broadcast over the arguments.

    Raises
    ------
    TypeError, ValueError
        As in :func:`steering_command`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=-1.0)
    >>> r = fws.steering_command_rate(veh, g, 1.0, 0.0, e_rate=-1.0,
    ...                               theta_rate=0.0, curvature=0.0)
    >>> [round(float(v), 6) for v in r]
    [0.1, -0.1]
    """
    check_type("vehicle", vehicle, Vehicle)
    gains = _check_gains(gains)
    feedforward = check_feedforward(feedforward, speed=speed)
    e_, th_, er, thr, k_, kr = check_inputs(
        e=e,
        theta=theta,
        e_rate=e_rate,
        theta_rate=theta_rate,
        curvature=curvature,
        curvature_rate=curvature_rate,
    )
    with np.errstate(over="ignore", invalid="ignore"):
        if feedforward == "kinematic":
            # 1 + (f kappa)^2 overflows to inf for a huge curvature: the
            # feedforward's rate -> 0
            rate_f, rate_r = equations.steering_law_rate(
                er, thr, k_, kr, vehicle.wheelbase, gains.k1, gains.k2, gains.ratio
            )
        else:
            fb_rate, rate_r = equations.feedback_command(
                er, thr, gains.k1, gains.k2, gains.ratio
            )
            rate_f = fb_rate
    if feedforward == "dynamic":
        # check_feedforward has refused "dynamic" without a speed
        d_f, d_r = dynamic_feedforward_derivative(
            vehicle, speed=cast(RealArrayLike, speed), curvature=curvature, tyre=tyre
        )
        rate_f = fb_rate + d_f * kr
        rate_r = rate_r + d_r * kr
    for out in (rate_f, rate_r):
        check_result(
            "steering rate",
            out,
            e_rate=er,
            theta_rate=thr,
            curvature=k_,
            curvature_rate=kr,
        )
    max_f = _limit(vehicle.max_steer_front)
    max_r = _limit(vehicle.max_steer_rear)
    if math.isfinite(max_f) or math.isfinite(max_r):
        # the unclipped command: the vehicle without its angle limits
        cmd_f, cmd_r = steering_command(
            replace(vehicle, max_steer_front=None, max_steer_rear=None),
            gains,
            e,
            theta,
            curvature=curvature,
            feedforward=feedforward,
            speed=speed,
            tyre=tyre,
        )
        rate_f = np.where(np.abs(cmd_f) > max_f, 0.0, rate_f)
        rate_r = np.where(np.abs(cmd_r) > max_r, 0.0, rate_r)
    rate_f, rate_r = np.broadcast_arrays(rate_f, rate_r)
    return np.array(rate_f), np.array(rate_r)


def path_tracking_controller(
    vehicle: Vehicle,
    gains: SteeringGains,
    *,
    feedforward: FeedforwardLike = True,
    speed: float | None = None,
    tyre: TyreName = "linear",
    name: str = "controller",
) -> ct.NonlinearIOSystem:
    r"""Static path-tracking controller block, paper eqs. (24)-(29).

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; its steering-angle limits, if set, clip the outputs.
    gains : SteeringGains
        Scalar ``k1, k2, ratio``.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        Add the curvature feedforward :math:`\arctan(\kappa f)` of eq. (26)
        to the front angle (default, also ``"kinematic"``). ``False`` gives
        the feedback-only law; ``"dynamic"`` the front and rear feedforward
        of :func:`~fws_control.dynamics.dynamic_feedforward` (needs `speed`).
    speed : float, optional
        Longitudinal speed [m/s] for ``feedforward="dynamic"``; stored as the
        block parameter ``speed``.
    tyre : {"linear", "magic"}, optional
        Tyre model of the dynamic feedforward.
    name : str, optional
        System name for :func:`control.interconnect`.

    Returns
    -------
    control.NonlinearIOSystem
        No states; inputs ``e, theta, curvature``; outputs ``delta_f,
        delta_r``. Parameters ``k1, k2, ratio`` (may be overridden per
        simulation with ``params``).

    Raises
    ------
    TypeError
        If `gains` is not a :class:`SteeringGains`.
    ValueError
        If the gains are not scalars.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=-1.0)
    >>> ctrl = fws.path_tracking_controller(veh, g)
    >>> ctrl.input_labels, ctrl.output_labels
    (['e', 'theta', 'curvature'], ['delta_f', 'delta_r'])
    >>> ctrl.output(0.0, [], [1.0, 0.0, 0.1]).round(6)
    array([0.163712, 0.1     ])
    """
    check_type("vehicle", vehicle, Vehicle)
    gains = _check_gains(gains)
    if any(np.ndim(v) != 0 for v in (gains.k1, gains.k2, gains.ratio)):
        raise ValueError(
            "gains must hold scalar k1, k2, ratio for a controller block, got "
            f"shapes {np.shape(gains.k1)}, {np.shape(gains.k2)}, "
            f"{np.shape(gains.ratio)}"
        )
    feedforward = check_feedforward(feedforward, speed=speed)
    extra = {} if speed is None else {"speed": float(speed)}

    def output(t, x, u, params):
        g = SteeringGains(params["k1"], params["k2"], params["ratio"])
        df, dr = steering_command(
            vehicle,
            g,
            u[0],
            u[1],
            curvature=u[2],
            feedforward=feedforward,
            speed=params.get("speed"),
            tyre=tyre,
        )
        return np.array([float(df), float(dr)])

    import control as ct

    return ct.nlsys(
        None,
        output,
        inputs=list(CONTROLLER_INPUTS),
        outputs=list(STEERING_INPUTS),
        params={
            "k1": float(gains.k1),
            "k2": float(gains.k2),
            "ratio": float(gains.ratio),
            **extra,
        },
        name=name,
    )


def feedback_controller(
    vehicle: Vehicle, gains: SteeringGains, *, name: str = "controller"
) -> ct.NonlinearIOSystem:
    """Feedback-only controller, paper eqs. (28)-(29).

    Same as ``path_tracking_controller(vehicle, gains, feedforward=False)``;
    the ``curvature`` input is ignored.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; its steering-angle limits [rad], if set, clip the outputs.
    gains : SteeringGains
        Scalar ``k1`` [rad/m], ``k2`` [rad/rad] and ``ratio`` [-].
    name : str, optional
        System name for :func:`control.interconnect`.

    Returns
    -------
    control.NonlinearIOSystem
        No states; inputs ``e, theta, curvature``; outputs ``delta_f,
        delta_r`` (see :func:`path_tracking_controller`).

    Raises
    ------
    TypeError
        If `gains` is not a :class:`SteeringGains`.
    ValueError
        If the gains are not scalars.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=-1.0)
    >>> fws.feedback_controller(veh, g).output(0.0, [], [1.0, 0.0, 0.1]).round(6)
    array([-0.1,  0.1])
    """
    return path_tracking_controller(vehicle, gains, feedforward=False, name=name)


def feedforward_feedback_controller(
    vehicle: Vehicle, gains: SteeringGains, *, name: str = "controller"
) -> ct.NonlinearIOSystem:
    r"""Feedforward + feedback controller, paper eqs. (24)-(29).

    Same as ``path_tracking_controller(vehicle, gains, feedforward=True)``.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry: the wheelbase :math:`f` [m] enters the feedforward
        :math:`\arctan(\kappa f)`; the steering-angle limits [rad], if set,
        clip the outputs.
    gains : SteeringGains
        Scalar ``k1`` [rad/m], ``k2`` [rad/rad] and ``ratio`` [-].
    name : str, optional
        System name for :func:`control.interconnect`.

    Returns
    -------
    control.NonlinearIOSystem
        No states; inputs ``e, theta, curvature``; outputs ``delta_f,
        delta_r`` (see :func:`path_tracking_controller`).

    Raises
    ------
    TypeError
        If `gains` is not a :class:`SteeringGains`.
    ValueError
        If the gains are not scalars.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=-1.0)
    >>> ctrl = fws.feedforward_feedback_controller(veh, g)
    >>> ctrl.output(0.0, [], [0.0, 0.0, 0.1]).round(6)
    array([0.263712, 0.      ])
    """
    return path_tracking_controller(vehicle, gains, feedforward=True, name=name)


def actuator_rate(
    vehicle: Vehicle,
    command: RealArrayLike,
    angle: RealArrayLike,
    *,
    time_constant: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Rates of the rate-limited first-order actuator (see module docstring).

    `command` and `angle` have the two channels ``(front, rear)`` on their
    first axis. Returns ``(delta_f_rate, delta_r_rate)``.
    """
    rate = (np.asarray(command, dtype=float) - np.asarray(angle, dtype=float)) / (
        time_constant
    )
    max_f = _limit(vehicle.max_steer_rate_front)
    max_r = _limit(vehicle.max_steer_rate_rear)
    return np.clip(rate[0], -max_f, max_f), np.clip(rate[1], -max_r, max_r)


def steering_actuator(
    vehicle: Vehicle,
    *,
    steering_lag: float | None = None,
    name: str = "actuator",
    **kwargs: Any,
) -> ct.NonlinearIOSystem:
    r"""Steering actuator with rate limits: a rate-clipped first-order lag.

    .. math:: \dot\delta_i = \operatorname{clip}\!\left(
              \frac{\delta_i^{cmd} - \delta_i}{\tau},
              -\dot\delta_{i,max}, \dot\delta_{i,max}\right),\quad i = f, r

    with the rate limits ``max_steer_rate_front/rear`` of the vehicle
    (unlimited where ``None``). Both channels get the same lag :math:`\tau`;
    the simulators insert this block only when a rate limit is set, so
    without rate limits the steering angles equal the commands exactly.

    Parameters
    ----------
    vehicle : Vehicle
        Rate limits.
    steering_lag : float, optional
        :math:`\tau` [s], > 0, the plant's steering lag (the name
        :class:`~fws_control.LateralPlant` and the simulation use); default
        :data:`DEFAULT_ACTUATOR_TIME_CONSTANT`. With a small :math:`\tau` the
        actuator follows the command closely until the rate limit binds.
    name : str, optional
        System name.
    **kwargs
        ``time_constant=``, the former name of `steering_lag`, accepted with
        a :class:`FutureWarning` until fws_control 0.4; any other keyword
        raises :class:`TypeError`.

    Returns
    -------
    control.NonlinearIOSystem
        States and outputs ``delta_f, delta_r``; inputs ``delta_f_cmd,
        delta_r_cmd``.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_rate_front=0.5)
    >>> act = fws.steering_actuator(veh, steering_lag=0.1)
    >>> act.dynamics(0.0, [0.0, 0.0], [0.2, 0.01]).round(6)
    array([0.5, 0.1])
    """
    check_type("vehicle", vehicle, Vehicle)
    steering_lag = legacy_keyword(kwargs, "time_constant", "steering_lag", steering_lag)
    reject_unknown("steering_actuator", kwargs)
    if steering_lag is None:
        steering_lag = DEFAULT_ACTUATOR_TIME_CONSTANT
    tau = check_scalar("steering_lag", check_positive("steering_lag", steering_lag))

    def update(t, x, u, params):
        rf, rr = actuator_rate(vehicle, u, x, time_constant=tau)
        return np.array([float(rf), float(rr)])

    import control as ct

    return ct.nlsys(
        update,
        None,
        states=list(STEERING_INPUTS),
        inputs=[f"{n}_cmd" for n in STEERING_INPUTS],
        outputs=list(STEERING_INPUTS),
        name=name,
    )
