r"""Dynamic single-track (bicycle) model with front and rear steering.

The kinematic model of the paper assumes that the wheels roll without
slipping sideways. This module adds the lateral tyre dynamics: lateral
velocity and yaw rate become states, driven by the tyre forces at both axles.

Conventions (one implementation here; :mod:`fws_control.symbolic` re-derives
them):

* Body frame at the centre of gravity G; ``l_f = wheelbase - rear_to_cg``,
  ``l_r = rear_to_cg``.
* The longitudinal velocity :math:`u` (``speed``) is held constant (the drive
  supplies whatever longitudinal force that takes); :math:`v_y` is the lateral
  velocity of G and :math:`r = \dot\psi` the yaw rate.
* Slip angles (positive slip gives a positive, leftward force):

  .. math::
     \alpha_f = \delta_f - \operatorname{atan2}(v_y + l_f r, u), \qquad
     \alpha_r = \delta_r - \operatorname{atan2}(v_y - l_r r, u)

* Axle forces :math:`F_f = F(\alpha_f)`, :math:`F_r = F(\alpha_r)`, normal to
  the wheel plane; linear :math:`F = C\alpha` by default.
* Equations of motion:

  .. math::
     m(\dot v_y + u r) = F_f\cos\delta_f + F_r\cos\delta_r, \qquad
     I_z \dot r = l_f F_f\cos\delta_f - l_r F_r\cos\delta_r

* Path errors are measured at the rear-axle point R, as in the kinematic
  model. R moves with body-frame velocity :math:`(u, v_y - l_r r)`, so

  .. math::
     \dot e = u\sin\theta + (v_y - l_r r)\cos\theta, \quad
     \dot s = \frac{u\cos\theta - (v_y - l_r r)\sin\theta}{1 - \kappa e},
     \quad \dot\theta = r - \kappa\dot s .

Kinematic limit: as the cornering stiffnesses grow, the slip angles go to
zero, ``v_y - l_r r -> u tan(delta_r)`` and ``r -> u (tan delta_f - tan
delta_r) / f``. This is the kinematic model with the speed of R equal to
``u / cos(delta_r)``: with front steering only (``delta_r = 0``) the two
speeds coincide; with rear steering they differ by a factor
``1/cos(delta_r)`` (0.125 % at 0.05 rad).
"""

from __future__ import annotations

import numpy as np

from .validation import check_type
from .vehicle import Vehicle

__all__ = [
    "GRAVITY",
    "MAGIC_SHAPE",
    "TYRES",
    "slip_angles",
    "tyre_force",
    "axle_loads",
    "body_derivatives",
    "dynamic_path_derivatives",
    "require_dynamics",
]

#: Gravitational acceleration [m/s^2] for the static axle loads.
GRAVITY = 9.81

#: Shape factor C of the simplified magic formula for lateral force
#: (Pacejka, *Tyre and Vehicle Dynamics*, 3rd ed., 2012: C ~ 1.3 for the
#: lateral force of car tyres).
MAGIC_SHAPE = 1.3

#: Tyre models: ``"linear"`` (F = C alpha) and ``"magic"`` (saturating).
TYRES = ("linear", "magic")


def require_dynamics(vehicle: Vehicle, *, tyre: str = "linear") -> Vehicle:
    """Return `vehicle` if it carries the data the dynamic model needs.

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`.
    ValueError
        If mass, yaw inertia or a cornering stiffness is missing, if `tyre`
        is unknown, or if ``tyre="magic"`` and ``friction`` is missing.
    """
    check_type("vehicle", vehicle, Vehicle)
    if tyre not in TYRES:
        raise ValueError(f"tyre must be one of {TYRES}, got {tyre!r}")
    missing = [
        name
        for name in ("mass", "yaw_inertia", "cornering_front", "cornering_rear")
        if getattr(vehicle, name) is None
    ]
    if tyre == "magic" and vehicle.friction is None:
        missing.append("friction")
    if missing:
        raise ValueError(
            "the dynamic model needs Vehicle fields "
            + ", ".join(missing)
            + " (kg, kg m^2, N/rad per axle; friction for tyre='magic'); "
            "they are None in the vehicle given"
        )
    return vehicle


def slip_angles(vehicle: Vehicle, v_y, yaw_rate, delta_f, delta_r, *, speed):
    r"""Slip angles ``(alpha_f, alpha_r)`` [rad] of the front and rear axle.

    Broadcasts over array arguments; see the module docstring for the
    definition.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> af, ar = fws.dynamics.slip_angles(veh, 0.0, 0.0, 0.1, -0.1, speed=10.0)
    >>> float(af), float(ar)
    (0.1, -0.1)
    """
    l_f = vehicle.wheelbase - vehicle.rear_to_cg
    l_r = vehicle.rear_to_cg
    alpha_f = delta_f - np.arctan2(v_y + l_f * yaw_rate, speed)
    alpha_r = delta_r - np.arctan2(v_y - l_r * yaw_rate, speed)
    return alpha_f, alpha_r


def axle_loads(vehicle: Vehicle) -> tuple[float, float]:
    """Static normal loads ``(F_zf, F_zr)`` [N] of the front and rear axle."""
    require_dynamics(vehicle)
    weight = vehicle.mass * GRAVITY
    f = vehicle.wheelbase
    return weight * vehicle.rear_to_cg / f, weight * (f - vehicle.rear_to_cg) / f


def tyre_force(slip, *, stiffness: float, peak: float | None = None):
    r"""Lateral axle force [N] for slip angle(s) `slip` [rad].

    ``peak=None``: linear, :math:`F = C\alpha`. Otherwise the simplified magic
    formula :math:`F = D\sin(c\arctan(B\alpha))` with :math:`D` = `peak`,
    :math:`c` = :data:`MAGIC_SHAPE` and :math:`B = C/(cD)`, which has the same
    slope `stiffness` at zero slip and saturates at `peak`.

    Examples
    --------
    >>> from fws_control.dynamics import tyre_force
    >>> float(tyre_force(0.01, stiffness=8e4))
    800.0
    >>> round(float(tyre_force(1e-6, stiffness=8e4, peak=5e3)), 6)  # same slope
    0.08
    """
    if peak is None:
        return stiffness * np.asarray(slip)
    b = stiffness / (MAGIC_SHAPE * peak)
    return peak * np.sin(MAGIC_SHAPE * np.arctan(b * np.asarray(slip)))


def _forces(vehicle: Vehicle, alpha_f, alpha_r, tyre: str):
    if tyre == "linear":
        return (
            tyre_force(alpha_f, stiffness=vehicle.cornering_front),
            tyre_force(alpha_r, stiffness=vehicle.cornering_rear),
        )
    fz_f, fz_r = axle_loads(vehicle)
    mu = vehicle.friction
    return (
        tyre_force(alpha_f, stiffness=vehicle.cornering_front, peak=mu * fz_f),
        tyre_force(alpha_r, stiffness=vehicle.cornering_rear, peak=mu * fz_r),
    )


def body_derivatives(
    vehicle: Vehicle, v_y, yaw_rate, delta_f, delta_r, *, speed, tyre: str = "linear"
):
    r"""Return ``(v_y_dot, r_dot)``: the lateral and yaw equations of motion.

    Broadcasts; no argument checks beyond the vehicle data (callers that
    integrate many runs check their inputs once).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> vy_dot, r_dot = fws.dynamics.body_derivatives(veh, 0.0, 0.0, 0.01, 0.0,
    ...                                               speed=10.0)
    >>> # C_f*0.01*cos(0.01)/m and l_f*C_f*0.01*cos(0.01)/I_z:
    >>> round(float(vy_dot), 6), round(float(r_dot), 6)
    (0.533307, 0.431978)
    """
    require_dynamics(vehicle, tyre=tyre)
    alpha_f, alpha_r = slip_angles(
        vehicle, v_y, yaw_rate, delta_f, delta_r, speed=speed
    )
    f_f, f_r = _forces(vehicle, alpha_f, alpha_r, tyre)
    lat_f = f_f * np.cos(delta_f)
    lat_r = f_r * np.cos(delta_r)
    l_f = vehicle.wheelbase - vehicle.rear_to_cg
    l_r = vehicle.rear_to_cg
    vy_dot = (lat_f + lat_r) / vehicle.mass - speed * yaw_rate
    r_dot = (l_f * lat_f - l_r * lat_r) / vehicle.yaw_inertia
    return vy_dot, r_dot


def dynamic_path_derivatives(
    vehicle: Vehicle,
    curvature,
    e,
    theta,
    v_y,
    yaw_rate,
    delta_f,
    delta_r,
    *,
    speed,
    tyre: str = "linear",
):
    r"""Path-frame right-hand side ``(s_dot, e_dot, theta_dot, v_y_dot, r_dot)``.

    Errors at the rear-axle point R (module docstring). Broadcasts.

    Examples
    --------
    Driving straight along the path with no slip keeps every error constant:

    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> out = fws.dynamics.dynamic_path_derivatives(
    ...     veh, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, speed=10.0)
    >>> [float(x) for x in out]
    [10.0, 0.0, 0.0, 0.0, 0.0]
    """
    vy_dot, r_dot = body_derivatives(
        vehicle, v_y, yaw_rate, delta_f, delta_r, speed=speed, tyre=tyre
    )
    v_r = v_y - vehicle.rear_to_cg * yaw_rate  # lateral velocity of R
    sin_t, cos_t = np.sin(theta), np.cos(theta)
    s_dot = (speed * cos_t - v_r * sin_t) / (1.0 - curvature * e)
    e_dot = speed * sin_t + v_r * cos_t
    theta_dot = yaw_rate - curvature * s_dot
    return s_dot, e_dot, theta_dot, vy_dot, r_dot
