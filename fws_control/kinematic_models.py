"""Nonlinear kinematic 4WS bicycle models as :class:`control.NonlinearIOSystem`.

Two frames are provided:

* the global (Earth-fixed) frame, paper eqs. (8)-(10), states ``x, y, psi``
  of the rear-axle centre R;
* the path frame relative to a path of constant curvature, paper eqs.
  (17)-(19) with the corrections listed in the errata (``s_dot`` carries the
  factor ``V``; the curvature term of ``theta_dot`` is negative), states
  ``s, e, theta``.

Both take the steering angles ``delta_f, delta_r`` as inputs. The speed (and
the path curvature) are system parameters, so they can be changed per call
with the ``params`` argument of :func:`control.input_output_response` or
:func:`control.linearize`. A negative speed means reversing.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from . import equations
from .equations import path_frame_derivatives
from .exceptions import SingularStateError
from .hints import RealArrayLike
from .validation import (
    check_finite,
    check_nonzero,
    check_real,
    check_scalar,
    check_type,
)
from .vehicle import Vehicle

if TYPE_CHECKING:  # imported where a model is built: ~1 s of start-up
    import control as ct

__all__ = [
    "global_frame_model",
    "path_frame_model",
    "yaw_rate",
    "feedforward_steering",
    "check_steering",
    "check_inputs",
    "check_result",
    "GLOBAL_STATES",
    "PATH_STATES",
    "STEERING_INPUTS",
]

GLOBAL_STATES = ("x", "y", "psi")
PATH_STATES = ("s", "e", "theta")
STEERING_INPUTS = ("delta_f", "delta_r")


def check_steering(delta_f: RealArrayLike) -> None:
    """Raise :class:`SingularStateError` where ``|delta_f| >= pi/2``.

    The kinematic yaw rate of eq. (10) has ``cos(delta_f)`` in the
    denominator.

    Parameters
    ----------
    delta_f : float or array_like
        Front steering angle(s) [rad].

    Examples
    --------
    >>> from fws_control.kinematic_models import check_steering
    >>> check_steering([0.1, -1.5])   # fine: nothing raised
    """
    if np.any(np.abs(delta_f) >= math.pi / 2):
        raise SingularStateError(
            f"front steering angle delta_f={delta_f!r} rad has |delta_f| >= pi/2: "
            "the yaw rate V*sin(delta_f - delta_r)/(f*cos(delta_f)) is singular"
        )


def check_inputs(**values: RealArrayLike) -> list[np.ndarray]:
    """Each keyword as a float array of real numbers, checked by name.

    ``None``, bools, complex numbers, strings and foreign objects raise
    :class:`TypeError` or :class:`ValueError` naming the keyword, and so does
    a non-finite **scalar**. In an **array** a non-finite element is data
    (a vectorised evaluation over many samples, e.g. the batch simulation's
    stopped runs): it gives a non-finite element in its place of the result,
    and the finite elements are unaffected. The shapes must broadcast.

    Examples
    --------
    >>> from fws_control.kinematic_models import check_inputs
    >>> [a.tolist() for a in check_inputs(e=1.0, theta=[0.0, 0.1])]
    [1.0, [0.0, 0.1]]
    >>> check_inputs(e=float("nan"))
    Traceback (most recent call last):
        ...
    ValueError: e must be finite, got nan
    """
    out = []
    for k, v in values.items():
        arr = check_real(k, v)
        if arr.ndim == 0 and not np.isfinite(arr):
            raise ValueError(f"{k} must be finite, got {v!r}")
        out.append(arr)
    try:
        np.broadcast_shapes(*(a.shape for a in out))
    except ValueError:
        shapes = ", ".join(f"{k} {a.shape}" for k, a in zip(values, out, strict=True))
        raise ValueError(f"the arguments must broadcast, got shapes {shapes}") from None
    return out


def check_result(what: str, value: RealArrayLike, **inputs: RealArrayLike) -> None:
    """Raise ValueError naming the inputs if finite scalars overflowed.

    A scalar result that is not finite although every input is finite comes
    from a magnitude beyond the floating-point range (e.g. a speed of
    1e300); the message names the inputs. An array result is an elementwise
    evaluation over samples (the batch simulation's runs, one of which may
    have failed): its non-finite elements stay in their places, as those of
    array inputs do (see :func:`check_inputs`).

    Examples
    --------
    >>> from fws_control.kinematic_models import check_result
    >>> check_result("yaw rate", 0.5, speed=5.0)  # fine: nothing raised
    """
    value = np.asarray(value, dtype=float)
    if value.ndim or np.all(np.isfinite(value)):
        return
    finite = np.ones(value.shape, dtype=bool)
    for v in inputs.values():
        finite = finite & np.isfinite(np.asarray(v, dtype=float))
    if np.any(~np.isfinite(value) & finite):
        names = ", ".join(
            f"{k}={v!r}" if np.ndim(v) == 0 else f"{k} (array)"
            for k, v in inputs.items()
        )
        raise ValueError(
            f"the {what} overflows for these magnitudes ({names}): "
            "use physical values (speed in m/s, angles in rad)"
        )


def yaw_rate(
    vehicle: Vehicle,
    delta_f: RealArrayLike,
    delta_r: RealArrayLike,
    *,
    speed: RealArrayLike,
) -> float | np.ndarray:
    r"""Yaw rate of the kinematic 4WS model, paper eq. (10).

    .. math:: \dot\psi = \frac{V \sin(\delta_f - \delta_r)}{f \cos\delta_f}

    Broadcasts over array arguments.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; ``wheelbase`` is :math:`f` [m].
    delta_f : float or array_like
        Front steering angle [rad], ``|delta_f| < pi/2``.
    delta_r : float or array_like
        Rear steering angle [rad], finite.
    speed : float or array_like
        Speed :math:`V` [m/s], finite (negative: reversing).

    Returns
    -------
    float or ndarray
        Yaw rate :math:`\dot\psi` [rad/s], positive counter-clockwise; a
        float for scalar arguments.

    Raises
    ------
    SingularStateError
        If any ``|delta_f| >= pi/2``.
    ValueError, TypeError
        If an argument is not real numbers or a scalar is not finite (naming
        it), or the magnitudes are so extreme that the yaw rate overflows.
        Non-finite elements of arrays give non-finite elements in their place
        (see :func:`check_inputs`).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> round(fws.yaw_rate(veh, 0.1, -0.1, speed=5.0), 6)
    0.369753
    """
    check_type("vehicle", vehicle, Vehicle)
    df, dr, V = check_inputs(delta_f=delta_f, delta_r=delta_r, speed=speed)
    check_steering(df)
    with np.errstate(over="ignore", invalid="ignore"):
        out = equations.yaw_rate(V, vehicle.wheelbase, df, dr)
    check_result("yaw rate", out, delta_f=df, delta_r=dr, speed=V)
    return float(out) if np.ndim(out) == 0 else out


def feedforward_steering(
    vehicle: Vehicle, *, curvature: RealArrayLike
) -> float | np.ndarray:
    r"""Front steering angle that holds R on a path of constant curvature.

    Paper eq. (26), :math:`\delta_f^{FF} = \arctan(\kappa_C f)`, with
    :math:`\delta_r^{FF} = 0` (eq. 27). Valid for any speed, including
    reversing.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; ``wheelbase`` is :math:`f` [m].
    curvature : float or array_like
        Path curvature :math:`\kappa_C` [1/m], finite (positive: turning
        left; 0: straight path).

    Returns
    -------
    float or ndarray
        Front steering angle :math:`\delta_f^{FF}` [rad], in
        :math:`(-\pi/2, \pi/2)`; a float for a scalar `curvature`.

    Raises
    ------
    ValueError
        If `curvature` is not finite.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> round(fws.feedforward_steering(veh, curvature=0.1), 6)
    0.263712
    """
    check_type("vehicle", vehicle, Vehicle)
    k = check_finite("curvature", curvature)
    with np.errstate(over="ignore"):  # arctan(inf) = pi/2 is the right limit
        out = equations.feedforward_angle(vehicle.wheelbase, np.asarray(k))
    return float(out) if np.ndim(out) == 0 else out


def _global_update(t, x, u, params):
    speed = params["speed"]
    f = params["wheelbase"]
    psi = x[2]
    delta_f, delta_r = u[0], u[1]
    check_steering(delta_f)
    return np.array(
        equations.global_frame_derivatives(speed, f, psi, delta_f, delta_r), dtype=float
    )


def _path_update(t, x, u, params):
    speed = params["speed"]
    f = params["wheelbase"]
    kappa = params["curvature"]
    e, theta = x[1], x[2]
    delta_f, delta_r = u[0], u[1]
    check_steering(delta_f)
    gap = 1.0 - kappa * e
    if gap <= 0.0:
        raise SingularStateError(
            f"1 - curvature*e = {gap!r} <= 0 (curvature={kappa!r}, e={e!r}): the "
            "vehicle is at or beyond the path's centre of curvature"
        )
    return np.array(
        path_frame_derivatives(speed, f, kappa, e, theta, delta_f, delta_r), dtype=float
    )


def global_frame_model(
    vehicle: Vehicle, *, speed: float = 1.0, name: str = "vehicle"
) -> ct.NonlinearIOSystem:
    r"""Kinematic 4WS bicycle model in the global frame, paper eqs. (8)-(10).

    .. math::
        \dot x_R = V\cos(\psi+\delta_r),\quad
        \dot y_R = V\sin(\psi+\delta_r),\quad
        \dot\psi = \frac{V\sin(\delta_f-\delta_r)}{f\cos\delta_f}

    Parameters
    ----------
    vehicle : Vehicle
        Geometry (``wheelbase`` is :math:`f`).
    speed : float, optional
        Longitudinal speed :math:`V` [m/s] of the rear-axle centre R;
        negative means reversing. Stored as the system parameter ``speed``.
    name : str, optional
        System name used by :func:`control.interconnect`.

    Returns
    -------
    control.NonlinearIOSystem
        States ``x, y, psi``; inputs ``delta_f, delta_r``; outputs equal to the
        states. Parameters ``speed`` and ``wheelbase``.

    Raises
    ------
    ValueError
        If `speed` is not finite and nonzero.
    SingularStateError
        At evaluation, if ``|delta_f| >= pi/2``.

    Examples
    --------
    >>> import numpy as np, control as ct, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sys = fws.global_frame_model(veh, speed=5.0)
    >>> sys.state_labels, sys.input_labels
    (['x', 'y', 'psi'], ['delta_f', 'delta_r'])
    >>> sys.dynamics(0.0, [0.0, 0.0, 0.0], [0.1, 0.0]).round(4)
    array([5.    , 0.    , 0.1858])
    """
    check_type("vehicle", vehicle, Vehicle)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    import control as ct

    return ct.nlsys(
        _global_update,
        None,
        states=list(GLOBAL_STATES),
        inputs=list(STEERING_INPUTS),
        outputs=list(GLOBAL_STATES),
        params={"speed": float(speed), "wheelbase": vehicle.wheelbase},
        name=name,
    )


def path_frame_model(
    vehicle: Vehicle,
    *,
    speed: float = 1.0,
    curvature: float = 0.0,
    name: str = "vehicle_path",
) -> ct.NonlinearIOSystem:
    r"""Kinematic 4WS model relative to a path of constant curvature.

    Paper eqs. (17)-(19), corrected (see the errata):

    .. math::
        \dot s = \frac{V\cos(\theta+\delta_r)}{1-\kappa e},\quad
        \dot e = V\sin(\theta+\delta_r),\quad
        \dot\theta = -\kappa\dot s + \frac{V\sin(\delta_f-\delta_r)}{f\cos\delta_f}

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed : float, optional
        Speed :math:`V` [m/s]; negative means reversing.
    curvature : float, optional
        Path curvature :math:`\kappa_C` [1/m]; positive turns left.
    name : str, optional
        System name.

    Returns
    -------
    control.NonlinearIOSystem
        States ``s, e, theta``; inputs ``delta_f, delta_r``; outputs equal to
        the states. Parameters ``speed``, ``curvature`` and ``wheelbase``.

    Raises
    ------
    ValueError
        If `speed` is not finite and nonzero or `curvature` is not finite.
    SingularStateError
        At evaluation, if ``|delta_f| >= pi/2`` or ``1 - curvature*e <= 0``.

    Examples
    --------
    On the path with the feedforward steering angle the errors stay zero:

    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sys = fws.path_frame_model(veh, speed=5.0, curvature=0.1)
    >>> u_ff = [fws.feedforward_steering(veh, curvature=0.1), 0.0]
    >>> np.allclose(sys.dynamics(0.0, [0.0, 0.0, 0.0], u_ff), [5.0, 0.0, 0.0])
    True
    """
    check_type("vehicle", vehicle, Vehicle)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    curvature = check_scalar("curvature", curvature)
    import control as ct

    return ct.nlsys(
        _path_update,
        None,
        states=list(PATH_STATES),
        inputs=list(STEERING_INPUTS),
        outputs=list(PATH_STATES),
        params={
            "speed": float(speed),
            "curvature": float(curvature),
            "wheelbase": vehicle.wheelbase,
        },
        name=name,
    )
