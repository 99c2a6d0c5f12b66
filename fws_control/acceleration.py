"""Yaw acceleration and lateral acceleration of the centre of gravity.

Paper eq. (13): the acceleration of G projected on the vehicle's lateral
axis ``[-sin(psi), cos(psi)]``,

.. math:: a_G^{lat} = V(\\dot\\psi + \\dot\\delta_r)\\cos\\delta_r + d\\,\\ddot\\psi,

with :math:`\\ddot\\psi` obtained from eq. (10) by the chain rule, so that no
finite difference enters. With constant speed the expression depends on the
steering angles and their rates only, not on the position or heading.
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np

from . import equations
from .hints import RealArrayLike
from .kinematic_models import check_inputs, check_result, check_steering, yaw_rate
from .validation import check_type
from .vehicle import Vehicle

__all__ = ["yaw_acceleration", "lateral_acceleration"]


def yaw_acceleration(
    vehicle: Vehicle,
    delta_f: RealArrayLike,
    delta_r: RealArrayLike,
    delta_f_rate: RealArrayLike,
    delta_r_rate: RealArrayLike,
    *,
    speed: RealArrayLike,
) -> float | np.ndarray:
    r"""Yaw acceleration :math:`\ddot\psi` from eq. (10) by the chain rule.

    .. math::
        \ddot\psi = \frac{V}{f}\left(
        \frac{\cos\delta_r}{\cos^2\delta_f}\dot\delta_f
        - \frac{\cos(\delta_f-\delta_r)}{\cos\delta_f}\dot\delta_r\right)

    Broadcasts over array arguments. Speed is taken constant, as in the paper.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; ``wheelbase`` is :math:`f` [m].
    delta_f : float or array_like
        Front steering angle [rad], ``|delta_f| < pi/2``.
    delta_r : float or array_like
        Rear steering angle [rad], finite.
    delta_f_rate : float or array_like
        Front steering rate :math:`\dot\delta_f` [rad/s], finite.
    delta_r_rate : float or array_like
        Rear steering rate :math:`\dot\delta_r` [rad/s], finite.
    speed : float or array_like
        Speed :math:`V` [m/s] (constant in time), finite (negative:
        reversing).

    Returns
    -------
    float or ndarray
        Yaw acceleration :math:`\ddot\psi` [rad/s^2]; a float for scalar
        arguments.

    Raises
    ------
    SingularStateError
        If any ``|delta_f| >= pi/2``.
    ValueError, TypeError
        If an argument is not real numbers or a scalar is not finite (naming
        it), the shapes do not broadcast, or magnitudes so extreme that the
        result overflows. Non-finite elements of arrays give non-finite
        elements in their place (see
        :func:`~fws_control.kinematic_models.check_inputs`).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> round(fws.yaw_acceleration(veh, 0.0, 0.0, 0.27, 0.0, speed=5.0), 6)
    0.5
    """
    check_type("vehicle", vehicle, Vehicle)
    df, dr, rf, rr, V = check_inputs(
        delta_f=delta_f,
        delta_r=delta_r,
        delta_f_rate=delta_f_rate,
        delta_r_rate=delta_r_rate,
        speed=speed,
    )
    check_steering(df)
    with np.errstate(over="ignore", invalid="ignore"):
        out = equations.yaw_acceleration(V, vehicle.wheelbase, df, dr, rf, rr)
    check_result(
        "yaw acceleration",
        out,
        delta_f=df,
        delta_r=dr,
        delta_f_rate=rf,
        delta_r_rate=rr,
        speed=V,
    )
    return float(out) if np.ndim(out) == 0 else out


def lateral_acceleration(
    vehicle: Vehicle,
    delta_f: RealArrayLike,
    delta_r: RealArrayLike,
    delta_f_rate: RealArrayLike,
    delta_r_rate: RealArrayLike,
    *,
    speed: RealArrayLike,
) -> float | np.ndarray:
    r"""Lateral acceleration of the centre of gravity G, paper eq. (13).

    .. math:: a_G^{lat} = V(\dot\psi + \dot\delta_r)\cos\delta_r + d\ddot\psi

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; ``rear_to_cg`` is :math:`d`.
    speed : float or array_like
        Speed :math:`V` [m/s] (constant in time).
    delta_f, delta_r : float or array_like
        Front and rear steering angles [rad].
    delta_f_rate, delta_r_rate : float or array_like
        Their time derivatives [rad/s].

    Returns
    -------
    float or ndarray
        Lateral acceleration [m/s^2], positive to the left of the vehicle.
        Broadcasts over the arguments.

    Raises
    ------
    SingularStateError
        If any ``|delta_f| >= pi/2``.
    ValueError, TypeError
        If an argument is not real numbers or a scalar is not finite (naming
        it), the shapes do not broadcast, or magnitudes so extreme that the
        result overflows. Non-finite elements of arrays give non-finite
        elements in their place (see
        :func:`~fws_control.kinematic_models.check_inputs`). Also a ValueError if
        ``vehicle.rear_to_cg`` is None (the acceleration is that of G).

    Examples
    --------
    Steady cornering with front steering only gives :math:`V^2/R`:

    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=0.0)
    >>> delta = fws.feedforward_steering(veh, curvature=0.1)   # radius 10 m
    >>> round(fws.lateral_acceleration(veh, delta, 0.0, 0.0, 0.0, speed=5.0), 9)
    2.5
    """
    # yaw_rate checks and names the arguments (numbers or arrays)
    psi_dot = yaw_rate(vehicle, delta_f, delta_r, speed=cast(Any, speed))
    d = vehicle.cg_distance(needed_by="lateral_acceleration (the acceleration of G)")
    psi_ddot = yaw_acceleration(
        vehicle, delta_f, delta_r, delta_f_rate, delta_r_rate, speed=speed
    )
    # the inputs passed the checks of yaw_rate and yaw_acceleration
    dr, rr, V = (np.asarray(v, dtype=float) for v in (delta_r, delta_r_rate, speed))
    with np.errstate(over="ignore", invalid="ignore"):
        out = equations.lateral_acceleration(V, d, dr, rr, psi_dot, psi_ddot)
    check_result(
        "lateral acceleration",
        out,
        delta_f=delta_f,
        delta_r=dr,
        delta_f_rate=delta_f_rate,
        delta_r_rate=rr,
        speed=V,
    )
    return float(out) if np.ndim(out) == 0 else out
