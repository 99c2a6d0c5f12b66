r"""Dynamic single-track (bicycle) model with front and rear steering.

The kinematic model of the paper assumes that the wheels roll without
slipping sideways. This module adds the lateral tyre dynamics: lateral
velocity and yaw rate become states, driven by the tyre forces at both axles.

Conventions (the equations are written once, in :mod:`fws_control.equations`,
which the functions here call; :mod:`fws_control.symbolic` re-derives them):

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

from typing import TYPE_CHECKING, cast

import numpy as np

from . import equations
from .equations import Real
from .exceptions import SingularStateError
from .hints import RealArrayLike, TyreName
from .kinematic_models import STEERING_INPUTS
from .validation import check_finite, check_nonzero, check_scalar, check_type
from .vehicle import Vehicle

if TYPE_CHECKING:  # imported where a model is built: ~1 s of start-up
    import control as ct

    class DynamicVehicle(Vehicle):
        """For type checkers: a Vehicle whose dynamic data are set.

        :func:`require_dynamics` returns its argument as this type once it
        has checked the fields; at run time it is the same Vehicle.
        """

        rear_to_cg: float
        mass: float
        yaw_inertia: float
        cornering_front: float
        cornering_rear: float


__all__ = [
    "GRAVITY",
    "MAGIC_SHAPE",
    "TYRES",
    "slip_angles",
    "tyre_force",
    "axle_loads",
    "body_derivatives",
    "dynamic_path_derivatives",
    "dynamic_global_derivatives",
    "dynamic_global_model",
    "dynamic_path_model",
    "require_dynamics",
    "slip_for_force",
    "dynamic_feedforward",
    "dynamic_feedforward_derivative",
    "path_jacobians",
    "DYNAMIC_GLOBAL_STATES",
    "DYNAMIC_PATH_STATES",
]

#: States of :func:`dynamic_global_model`: position of the rear-axle point R,
#: yaw angle, lateral velocity of G and yaw rate.
DYNAMIC_GLOBAL_STATES = ("x", "y", "psi", "v_y", "r")

#: States of :func:`dynamic_path_model`: arc length, lateral and heading
#: error at R, lateral velocity of G and yaw rate.
DYNAMIC_PATH_STATES = ("s", "e", "theta", "v_y", "r")

#: Gravitational acceleration [m/s^2] for the static axle loads.
GRAVITY = 9.81

#: Shape factor C of the simplified magic formula for lateral force
#: (Pacejka, *Tyre and Vehicle Dynamics*, 3rd ed., 2012: C ~ 1.3 for the
#: lateral force of car tyres); defined in :mod:`fws_control.equations`.
MAGIC_SHAPE = equations.MAGIC_SHAPE

#: Tyre models: ``"linear"`` (F = C alpha) and ``"magic"`` (saturating).
TYRES = ("linear", "magic")


def require_dynamics(vehicle: Vehicle, *, tyre: str = "linear") -> DynamicVehicle:
    """Return `vehicle` if it carries the data the dynamic model needs.

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`.
    ValueError
        If rear_to_cg, mass, yaw inertia or a cornering stiffness is
        missing (the tyre forces act about G), if `tyre`
        is unknown, or if ``tyre="magic"`` and ``friction`` is missing.
    """
    check_type("vehicle", vehicle, Vehicle)
    if not isinstance(tyre, str) or tyre not in TYRES:
        raise ValueError(f"tyre must be one of {TYRES}, got {tyre!r}")
    # each field with its unit, so the message lists only what is missing
    units = {
        "rear_to_cg": "m",
        "mass": "kg",
        "yaw_inertia": "kg m^2",
        "cornering_front": "N/rad per axle",
        "cornering_rear": "N/rad per axle",
    }
    if tyre == "magic":
        units["friction"] = "for tyre='magic'"
    missing = [name for name in units if getattr(vehicle, name) is None]
    if missing:
        raise ValueError(
            "the dynamic model needs Vehicle fields "
            + ", ".join(f"{name} [{units[name]}]" for name in missing)
            + "; they are None in the vehicle given"
        )
    return cast("DynamicVehicle", vehicle)


def slip_angles(
    vehicle: Vehicle,
    v_y: Real,
    yaw_rate: Real,
    delta_f: Real,
    delta_r: Real,
    *,
    speed: Real,
) -> tuple[Real, Real]:
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
    # a ValueError naming the missing field (not a TypeError from None - 1)
    l_r = vehicle.cg_distance(needed_by="the slip angles")
    l_f = vehicle.wheelbase - l_r
    return equations.slip_angles(speed, l_f, l_r, v_y, yaw_rate, delta_f, delta_r)


def axle_loads(vehicle: Vehicle) -> tuple[float, float]:
    """Static normal loads ``(F_zf, F_zr)`` [N] of the front and rear axle."""
    vehicle = require_dynamics(vehicle)
    weight = vehicle.mass * GRAVITY
    f = vehicle.wheelbase
    return weight * vehicle.rear_to_cg / f, weight * (f - vehicle.rear_to_cg) / f


def tyre_force(
    slip: RealArrayLike, *, stiffness: float, peak: float | None = None
) -> Real:
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
        return equations.linear_tyre_force(np.asarray(slip), stiffness)
    return equations.magic_tyre_force(np.asarray(slip), stiffness, peak)


def _forces(
    vehicle: DynamicVehicle, alpha_f: Real, alpha_r: Real, tyre: str
) -> tuple[Real, Real]:
    if tyre == "linear":
        return (
            tyre_force(alpha_f, stiffness=vehicle.cornering_front),
            tyre_force(alpha_r, stiffness=vehicle.cornering_rear),
        )
    fz_f, fz_r = axle_loads(vehicle)
    # require_dynamics(tyre="magic") has checked it
    mu = cast(float, vehicle.friction)
    return (
        tyre_force(alpha_f, stiffness=vehicle.cornering_front, peak=mu * fz_f),
        tyre_force(alpha_r, stiffness=vehicle.cornering_rear, peak=mu * fz_r),
    )


def body_derivatives(
    vehicle: Vehicle,
    v_y: Real,
    yaw_rate: Real,
    delta_f: Real,
    delta_r: Real,
    *,
    speed: Real,
    tyre: TyreName = "linear",
) -> tuple[Real, Real]:
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
    vehicle = require_dynamics(vehicle, tyre=tyre)
    alpha_f, alpha_r = slip_angles(
        vehicle, v_y, yaw_rate, delta_f, delta_r, speed=speed
    )
    f_f, f_r = _forces(vehicle, alpha_f, alpha_r, tyre)
    l_f = vehicle.wheelbase - vehicle.rear_to_cg
    return equations.body_derivatives(
        speed, vehicle.mass, vehicle.yaw_inertia, l_f, vehicle.rear_to_cg,
        yaw_rate, f_f, f_r, delta_f, delta_r,
    )  # fmt: skip


def dynamic_path_derivatives(
    vehicle: Vehicle,
    curvature: Real,
    e: Real,
    theta: Real,
    v_y: Real,
    yaw_rate: Real,
    delta_f: Real,
    delta_r: Real,
    *,
    speed: Real,
    tyre: TyreName = "linear",
) -> tuple[Real, Real, Real, Real, Real]:
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
    vehicle = cast("DynamicVehicle", vehicle)  # body_derivatives has checked it
    s_dot, e_dot, theta_dot = equations.dynamic_path_kinematics(
        speed, vehicle.rear_to_cg, curvature, e, theta, v_y, yaw_rate
    )
    return s_dot, e_dot, theta_dot, vy_dot, r_dot


def dynamic_global_derivatives(
    vehicle: Vehicle,
    psi: Real,
    v_y: Real,
    yaw_rate: Real,
    delta_f: Real,
    delta_r: Real,
    *,
    speed: Real,
    tyre: TyreName = "linear",
) -> tuple[Real, Real, Real, Real, Real]:
    r"""Global-frame right-hand side ``(x_dot, y_dot, psi_dot, v_y_dot, r_dot)``.

    ``x, y`` is the rear-axle point R, which moves with the body-frame
    velocity :math:`(u, v_y - l_r r)`:

    .. math::
        \dot x = u\cos\psi - (v_y - l_r r)\sin\psi,\quad
        \dot y = u\sin\psi + (v_y - l_r r)\cos\psi,\quad
        \dot\psi = r .

    Broadcasts.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> out = fws.dynamics.dynamic_global_derivatives(
    ...     veh, 0.0, 0.0, 0.0, 0.0, 0.0, speed=10.0)
    >>> [float(x) for x in out]
    [10.0, 0.0, 0.0, 0.0, 0.0]
    """
    vy_dot, r_dot = body_derivatives(
        vehicle, v_y, yaw_rate, delta_f, delta_r, speed=speed, tyre=tyre
    )
    vehicle = cast("DynamicVehicle", vehicle)  # body_derivatives has checked it
    x_dot, y_dot = equations.dynamic_global_kinematics(
        speed, vehicle.rear_to_cg, psi, v_y, yaw_rate
    )
    # psi_dot = r, broadcast to the shape of the other rates
    return x_dot, y_dot, yaw_rate + 0.0 * x_dot, vy_dot, r_dot


def _check_model_args(vehicle: Vehicle, speed: float, tyre: str) -> float:
    require_dynamics(vehicle, tyre=tyre)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    if speed <= 0.0:
        # the slip angles atan2(., u) assume forward driving: reversing would
        # flip every slip angle by pi
        raise ValueError(
            f"speed must be > 0 m/s for the dynamic model (forward driving), "
            f"got {speed!r}"
        )
    return speed


def dynamic_global_model(
    vehicle: Vehicle,
    *,
    speed: float,
    tyre: str = "linear",
    name: str = "vehicle_dynamic",
) -> ct.NonlinearIOSystem:
    r"""Dynamic single-track 4WS model in the global frame.

    States ``x, y`` (position of the rear-axle point R, as in
    :func:`fws_control.global_frame_model`), ``psi`` (yaw angle), ``v_y``
    (lateral velocity of the centre of gravity, body frame) and ``r`` (yaw
    rate); equations in :func:`dynamic_global_derivatives` and the module
    docstring.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and the dynamic data (mass, yaw inertia, cornering
        stiffnesses; friction for ``tyre="magic"``).
    speed : float
        Constant longitudinal speed :math:`u` [m/s], finite and > 0. Stored
        as the system parameter ``speed``.
    tyre : {"linear", "magic"}, optional
        Tyre model (see :func:`tyre_force`), default ``"linear"``.
    name : str, optional
        System name used by :func:`control.interconnect`.

    Returns
    -------
    control.NonlinearIOSystem
        States ``x, y, psi, v_y, r``; inputs ``delta_f, delta_r``; outputs
        equal to the states. Parameter ``speed`` (the vehicle data are fixed
        at construction: build a new system for another vehicle).

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`.
    ValueError
        If the vehicle lacks the dynamic data, `tyre` is unknown or `speed`
        is not finite and > 0.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> sys = fws.dynamics.dynamic_global_model(veh, speed=10.0)
    >>> sys.state_labels, sys.input_labels
    (['x', 'y', 'psi', 'v_y', 'r'], ['delta_f', 'delta_r'])
    >>> sys.dynamics(0.0, [0, 0, 0, 0, 0], [0.01, 0.0]).round(4)
    array([10.    ,  0.    ,  0.    ,  0.5333,  0.432 ])
    """
    speed = _check_model_args(vehicle, speed, tyre)

    def update(t, x, u, params):
        return np.array(
            dynamic_global_derivatives(
                vehicle, x[2], x[3], x[4], u[0], u[1], speed=params["speed"], tyre=tyre
            ),
            dtype=float,
        )

    import control as ct

    return ct.nlsys(
        update,
        None,
        states=list(DYNAMIC_GLOBAL_STATES),
        inputs=list(STEERING_INPUTS),
        outputs=list(DYNAMIC_GLOBAL_STATES),
        params={"speed": speed},
        name=name,
    )


def dynamic_path_model(
    vehicle: Vehicle,
    *,
    speed: float,
    curvature: float = 0.0,
    tyre: str = "linear",
    name: str = "vehicle_dynamic_path",
) -> ct.NonlinearIOSystem:
    r"""Dynamic single-track 4WS model relative to a path of constant curvature.

    States ``s, e, theta`` (arc length, lateral and heading error of the
    rear-axle point R, as in :func:`fws_control.path_frame_model`), ``v_y``
    and ``r``; equations in :func:`dynamic_path_derivatives` and the module
    docstring.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and the dynamic data.
    speed : float
        Constant longitudinal speed :math:`u` [m/s], finite and > 0.
    curvature : float, optional
        Path curvature :math:`\kappa_C` [1/m], finite; positive turns left.
    tyre : {"linear", "magic"}, optional
        Tyre model, default ``"linear"``.
    name : str, optional
        System name.

    Returns
    -------
    control.NonlinearIOSystem
        States ``s, e, theta, v_y, r``; inputs ``delta_f, delta_r``; outputs
        equal to the states. Parameters ``speed`` and ``curvature``.

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`.
    ValueError
        If the vehicle lacks the dynamic data, `tyre` is unknown, `speed` is
        not finite and > 0 or `curvature` is not finite.
    SingularStateError
        At evaluation, if ``1 - curvature*e <= 0``.

    Examples
    --------
    Straight ahead on a straight path every error stays zero:

    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> sys = fws.dynamics.dynamic_path_model(veh, speed=10.0)
    >>> sys.state_labels
    ['s', 'e', 'theta', 'v_y', 'r']
    >>> sys.dynamics(0.0, [0, 0, 0, 0, 0], [0.0, 0.0]).tolist()
    [10.0, 0.0, 0.0, 0.0, 0.0]
    """
    speed = _check_model_args(vehicle, speed, tyre)
    curvature = check_scalar("curvature", curvature)

    def update(t, x, u, params):
        kappa = params["curvature"]
        e = x[1]
        gap = 1.0 - kappa * e
        if gap <= 0.0:
            raise SingularStateError(
                f"1 - curvature*e = {gap!r} <= 0 (curvature={kappa!r}, e={e!r}): "
                "the vehicle is at or beyond the path's centre of curvature"
            )
        return np.array(
            dynamic_path_derivatives(
                vehicle,
                kappa,
                e,
                x[2],
                x[3],
                x[4],
                u[0],
                u[1],
                speed=params["speed"],
                tyre=tyre,
            ),
            dtype=float,
        )

    import control as ct

    return ct.nlsys(
        update,
        None,
        states=list(DYNAMIC_PATH_STATES),
        inputs=list(STEERING_INPUTS),
        outputs=list(DYNAMIC_PATH_STATES),
        params={"speed": speed, "curvature": curvature},
        name=name,
    )


def slip_for_force(
    force: RealArrayLike, *, stiffness: float, peak: float | None = None
) -> np.ndarray:
    r"""Slip angle [rad] at which :func:`tyre_force` gives `force` [N].

    The inverse of :func:`tyre_force` on its rising branch: ``force /
    stiffness`` for the linear tyre, :math:`\tan(\arcsin(F/D)/c)/B` for the
    magic formula. Broadcasts.

    Raises
    ------
    ValueError
        If ``|force| >= peak``: the tyre cannot give that force.

    Examples
    --------
    >>> from fws_control.dynamics import slip_for_force, tyre_force
    >>> a = slip_for_force(3000.0, stiffness=8e4, peak=5e3)
    >>> round(float(tyre_force(a, stiffness=8e4, peak=5e3)), 9)
    3000.0
    """
    force = np.asarray(force, dtype=float)
    if peak is None:
        return force / stiffness
    ratio = force / peak
    if np.any(np.abs(ratio) >= 1.0):
        raise ValueError(
            f"force must satisfy |force| < peak={peak!r} N, got up to "
            f"{float(np.max(np.abs(force)))!r} N: the tyre saturates"
        )
    b = stiffness / (MAGIC_SHAPE * peak)
    return np.tan(np.arcsin(ratio) / MAGIC_SHAPE) / b


def _axle_peaks(
    vehicle: DynamicVehicle, tyre: str
) -> tuple[float | None, float | None]:
    if tyre == "linear":
        return None, None
    fz_f, fz_r = axle_loads(vehicle)
    mu = cast(float, vehicle.friction)  # require_dynamics(tyre="magic") checked it
    return mu * fz_f, mu * fz_r


def _check_point(speed, curvature):
    speed = check_finite("speed", speed)
    if np.any(np.asarray(speed) <= 0.0):
        raise ValueError(
            f"speed must be finite and > 0 m/s for the dynamic model, got {speed!r}"
        )
    curvature = check_finite("curvature", curvature)
    try:
        np.broadcast_shapes(np.shape(speed), np.shape(curvature))
    except ValueError:
        raise ValueError(
            "speed and curvature must broadcast, got shapes "
            f"{np.shape(speed)} and {np.shape(curvature)}"
        ) from None
    return np.asarray(speed, dtype=float), np.asarray(curvature, dtype=float)


def _solve_axle(base, lateral, stiffness, peak, name):
    # delta = base + F^-1(lateral / cos(delta)): a contraction (its slope is
    # about alpha*tan(delta), far below 1 for road angles), so plain fixed-point
    # iteration converges to machine precision in a few steps. The slope
    # reaches 1 at the largest curvature the axle holds (the fold that
    # _axle_reach finds); the step budget reaches to 1e-4 of it.
    delta = base + slip_for_force(lateral, stiffness=stiffness, peak=peak)
    for _ in range(3000):
        cos_d = np.cos(delta)
        if np.any(cos_d <= 0.0):
            break
        new = base + slip_for_force(lateral / cos_d, stiffness=stiffness, peak=peak)
        done = np.max(np.abs(new - delta), initial=0.0) <= 1e-15
        delta = new
        if done:
            return delta
    raise ValueError(
        f"no steady {name} steering angle below pi/2 holds this speed and curvature "
        f"(lateral force {float(np.max(np.abs(lateral)))!r} N needed): the vehicle "
        "cannot follow the curve"
    )


def _axle_reach(vehicle: DynamicVehicle, speed: float, tyre: str, front: bool) -> float:
    """Largest curvature [1/m] one axle holds in the steady turn at `speed`.

    The steady equation of the axle, ``F(alpha) cos(beta + alpha) = q kappa``
    (``beta = arctan(f kappa)`` at the front, 0 at the rear; ``q = m u^2
    l/f``), has a solution on the rising branch of the tyre (and with the
    steering angle below pi/2) while the largest left side reaches the right
    side; the curvature where they meet is the reach.
    """
    from scipy.optimize import brentq, minimize_scalar

    f = vehicle.wheelbase
    lever = vehicle.rear_to_cg if front else vehicle.front_to_cg
    stiff = vehicle.cornering_front if front else vehicle.cornering_rear
    peak = _axle_peaks(vehicle, tyre)[0 if front else 1]
    q = vehicle.mass * speed**2 * lever / f
    if peak is None:
        top, rising = stiff * np.pi / 2, np.pi / 2
    else:
        b = stiff / (MAGIC_SHAPE * peak)
        top, rising = peak, float(np.tan(np.pi / (2 * MAGIC_SHAPE)) / b)

    def margin(kappa):
        beta = float(equations.feedforward_angle(f, kappa)) if front else 0.0
        hi = min(rising, np.pi / 2 - beta)
        best = minimize_scalar(
            lambda a: (
                -float(tyre_force(a, stiffness=stiff, peak=peak)) * np.cos(beta + a)
            ),
            bounds=(0.0, hi),
            method="bounded",
            options={"xatol": 1e-12},
        )
        return -float(best.fun) - q * kappa

    return float(brentq(margin, 0.0, top / q, xtol=1e-15, rtol=1e-12))


def _reach_error(
    vehicle: DynamicVehicle, u: np.ndarray, kappa: np.ndarray, tyre: str
) -> ValueError:
    """The error for a curve the tyres cannot hold, naming its largest curvature."""
    u, kappa = np.broadcast_arrays(u, kappa)
    peaks = _axle_peaks(vehicle, tyre)
    f = vehicle.wheelbase
    # the first point that fails: beyond a peak force already, else the
    # first that has no steady angles of its own
    i = None
    for j in np.ndindex(u.shape):
        try:
            _steady_angles(vehicle, u[j], kappa[j], tyre)
        except ValueError:
            i = j
            break
    i = next(iter(np.ndindex(u.shape))) if i is None else i
    ui, ki = float(u[i]), float(kappa[i])
    reach = {
        axle: _axle_reach(vehicle, ui, tyre, axle == "front")
        for axle in ("front", "rear")
    }
    axle = min(reach, key=reach.__getitem__)
    lever = vehicle.rear_to_cg if axle == "front" else vehicle.front_to_cg
    need = vehicle.mass * ui**2 * abs(ki) * lever / f
    peak = peaks[0 if axle == "front" else 1]
    gives = (
        f"its tyres give at most friction x axle load = {peak:.6g} N"
        if peak is not None
        else "more than its linear tyres give below a steering angle of pi/2"
    )
    largest = (
        f"the largest curvature at this speed is {reach[axle]:.6g} 1/m (radius "
        f"{1.0 / reach[axle]:.6g} m)"
    )
    if abs(ki) < reach[axle]:
        # within round-off of the limit the fixed point does not settle
        return ValueError(
            f"curvature={ki!r} 1/m at speed={ui!r} m/s is too close to the limit "
            f"of the {tyre} tyres for a steady solution: {largest}"
        )
    return ValueError(
        f"curvature={ki!r} 1/m at speed={ui!r} m/s needs a lateral force the "
        f"tyres cannot give ({tyre} tyre): the {axle} axle must carry at least "
        f"{need:.6g} N, {gives}; {largest}"
    )


def dynamic_feedforward(
    vehicle: Vehicle,
    *,
    speed: RealArrayLike,
    curvature: RealArrayLike,
    tyre: TyreName = "linear",
) -> tuple[Real, Real]:
    r"""Front and rear angles that make ``e = theta = 0`` a steady state.

    On a path of constant curvature :math:`\kappa` at speed :math:`u`, the
    rear-axle point R stays on the path with the body aligned to the tangent
    (``e = theta = 0``) only with :math:`r = \kappa u` and
    :math:`v_y = l_r\kappa u` (R moves along the body axis). The tyres must
    then give the lateral forces
    :math:`F_f\cos\delta_f = m u^2\kappa\,l_r/f` and
    :math:`F_r\cos\delta_r = m u^2\kappa\,l_f/f`, so

    .. math::
        \delta_f = \arctan(f\kappa) + F_f^{-1}\!\Big(\frac{m u^2\kappa l_r}
        {f\cos\delta_f}\Big),\qquad
        \delta_r = F_r^{-1}\!\Big(\frac{m u^2\kappa l_f}{f\cos\delta_r}\Big),

    solved here to machine precision (fixed point). Both angles are fixed by
    ``e = theta = 0``: the rear slip angle equals :math:`\delta_r`, because R
    does not slide sideways relative to the path tangent. There is no freedom
    left for a ratio :math:`\delta_r = a\delta_f`; the ratio of the paper's
    controller acts on the feedback only. To first order
    :math:`\delta_f \approx f\kappa + m u^2\kappa l_r/(f C_f)`,
    :math:`\delta_r \approx m u^2\kappa l_f/(f C_r)`, the kinematic angles
    plus the understeer terms.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data.
    speed : float or array_like
        Longitudinal speed :math:`u` [m/s], finite and > 0.
    curvature : float or array_like
        Path curvature :math:`\kappa` [1/m], finite; broadcasts with `speed`.
    tyre : {"linear", "magic"}, optional
        Tyre model, default ``"linear"``.

    Returns
    -------
    delta_f, delta_r : float or ndarray
        Steering angles [rad], broadcast over `speed` and `curvature`.

    Raises
    ------
    ValueError
        For missing vehicle data, a non-positive `speed`, a non-finite
        `curvature`, or a curve the tyres cannot hold (magic tyre beyond its
        peak force, or no angle below pi/2); the message names the force
        the limiting axle needs and the largest curvature at that speed.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> df, dr = fws.dynamics.dynamic_feedforward(veh, speed=20.0, curvature=0.01)
    >>> round(df, 5), round(dr, 5)
    (0.06457, 0.03753)

    To first order: atan(0.027) + 1500*20**2*0.01*1.35/(2.7*8e4) = 0.02699 +
    0.0375 and 0.0375.
    """
    vehicle = require_dynamics(vehicle, tyre=tyre)
    u, kappa = _check_point(speed, curvature)
    try:
        delta_f, delta_r = _steady_angles(vehicle, u, kappa, tyre)
    except ValueError:
        raise _reach_error(vehicle, u, kappa, tyre) from None
    if np.ndim(delta_f) == 0:
        return float(delta_f), float(delta_r)
    return delta_f, delta_r


def _steady_angles(
    vehicle: DynamicVehicle, u: np.ndarray, kappa: np.ndarray, tyre: str
) -> tuple[np.ndarray, np.ndarray]:
    """The fixed points of :func:`dynamic_feedforward` (checked arguments)."""
    f = vehicle.wheelbase
    l_f, l_r = vehicle.front_to_cg, vehicle.rear_to_cg
    need = vehicle.mass * u**2 * kappa / f
    peak_f, peak_r = _axle_peaks(vehicle, tyre)
    delta_f = _solve_axle(
        equations.feedforward_angle(f, kappa),
        need * l_r,
        vehicle.cornering_front,
        peak_f,
        "front",
    )
    delta_r = _solve_axle(
        np.zeros_like(need), need * l_f, vehicle.cornering_rear, peak_r, "rear"
    )
    return delta_f, delta_r


def dynamic_feedforward_derivative(
    vehicle: Vehicle,
    *,
    speed: RealArrayLike,
    curvature: RealArrayLike,
    tyre: TyreName = "linear",
) -> tuple[Real, Real]:
    r"""Derivatives ``(d delta_f/d kappa, d delta_r/d kappa)`` [rad m].

    Of :func:`dynamic_feedforward`, by implicit differentiation of each
    axle's equation :math:`F(\delta - \beta(\kappa))\cos\delta = q\kappa`
    (:math:`\beta = \arctan(f\kappa)` at the front, 0 at the rear;
    :math:`q = m u^2 l_{r|f}/f`):

    .. math::
        \frac{d\delta}{d\kappa} = \frac{q + F'(\alpha)\cos\delta\,
        \beta'(\kappa)}{F'(\alpha)\cos\delta - F(\alpha)\sin\delta}.

    The rate of the feedforward is this times :math:`\dot\kappa`.
    Arguments as in :func:`dynamic_feedforward`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> d = fws.dynamics.dynamic_feedforward_derivative(veh, speed=20.0,
    ...                                                 curvature=0.0)
    >>> [round(float(x), 4) for x in d]      # f + m u^2 l_r/(f C_f), m u^2 l_f/(f C_r)
    [6.45, 3.75]
    """
    delta_f, delta_r = dynamic_feedforward(
        vehicle, speed=speed, curvature=curvature, tyre=tyre
    )
    vehicle = cast("DynamicVehicle", vehicle)  # dynamic_feedforward checked it
    u, kappa = _check_point(speed, curvature)
    f = vehicle.wheelbase
    peak_f, peak_r = _axle_peaks(vehicle, tyre)
    out = []
    for delta, base, base_rate, q, stiff, peak in (
        (
            delta_f,
            equations.feedforward_angle(f, kappa),
            # d/d kappa of the feedforward angle
            equations.feedforward_angle_rate(f, kappa, 1.0),
            vehicle.mass * u**2 * vehicle.rear_to_cg / f,
            vehicle.cornering_front,
            peak_f,
        ),
        (
            delta_r,
            0.0,
            0.0,
            vehicle.mass * u**2 * vehicle.front_to_cg / f,
            vehicle.cornering_rear,
            peak_r,
        ),
    ):
        alpha = delta - base
        slope = _slope(alpha, stiff, peak)
        force = tyre_force(alpha, stiffness=stiff, peak=peak)
        cos_d = np.cos(delta)
        out.append(
            (q + slope * cos_d * base_rate) / (slope * cos_d - force * np.sin(delta))
        )
    return out[0], out[1]


def _slope(alpha, stiffness, peak):
    if peak is None:
        return stiffness + 0.0 * alpha
    b = stiffness / (MAGIC_SHAPE * peak)
    return (
        peak
        * MAGIC_SHAPE
        * np.cos(MAGIC_SHAPE * np.arctan(b * alpha))
        * b
        / (1.0 + (b * alpha) ** 2)
    )


def path_jacobians(
    vehicle: Vehicle,
    *,
    speed: RealArrayLike,
    curvature: RealArrayLike,
    tyre: TyreName = "linear",
) -> tuple[np.ndarray, np.ndarray]:
    r"""``(A, B)`` of the path-frame model at the dynamic-feedforward point.

    States ``e, theta, v_y, r`` (``s`` is dropped: nothing depends on it);
    inputs ``delta_f, delta_r``, deviations from :func:`dynamic_feedforward`.
    At that point (``e = theta = 0``, :math:`v_y = l_r\kappa u`,
    :math:`r = \kappa u`) the analytic Jacobian is

    .. math::
        \mathbf A = \begin{bmatrix}
          0 & u & 1 & -l_r\\
          -\kappa^2 u & 0 & 0 & 1\\
          0 & 0 & (Y_{f,v} + Y_{r,v})/m & (Y_{f,r} + Y_{r,r})/m - u\\
          0 & 0 & (l_f Y_{f,v} - l_r Y_{r,v})/I_z & (l_f Y_{f,r} - l_r Y_{r,r})/I_z
        \end{bmatrix},\quad
        \mathbf B = \begin{bmatrix} 0 & 0\\ 0 & 0\\ Y_{f,\delta}/m &
          Y_{r,\delta}/m\\ l_f Y_{f,\delta}/I_z & -l_r Y_{r,\delta}/I_z
        \end{bmatrix}

    with :math:`Y = F(\alpha)\cos\delta` the body-lateral axle force and
    its partial derivatives :math:`Y_{\cdot,v}, Y_{\cdot,r}, Y_{\cdot,\delta}`
    through the slip angles of the module docstring. On a straight path it
    is the textbook linear single-track model plus the path errors.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data.
    speed, curvature : float or array_like
        Operating point, as in :func:`dynamic_feedforward`.
    tyre : {"linear", "magic"}, optional
        Tyre model, default ``"linear"``.

    Returns
    -------
    A, B : ndarray
        Shapes ``(..., 4, 4)`` and ``(..., 4, 2)``.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, mass=1500.0,
    ...                   yaw_inertia=2500.0, cornering_front=8e4,
    ...                   cornering_rear=8e4)
    >>> A, B = fws.dynamics.path_jacobians(veh, speed=10.0, curvature=0.0)
    >>> A[2:, 2:].round(4)     # -(C_f+C_r)/(m u), -u - (l_f C_f - l_r C_r)/(m u)
    array([[-10.6667, -10.    ],
           [  0.    , -11.664 ]])
    """
    delta_f, delta_r = dynamic_feedforward(
        vehicle, speed=speed, curvature=curvature, tyre=tyre
    )
    vehicle = cast("DynamicVehicle", vehicle)  # dynamic_feedforward checked it
    u, kappa = _check_point(speed, curvature)
    u, kappa, delta_f, delta_r = np.broadcast_arrays(u, kappa, delta_f, delta_r)
    l_f, l_r = vehicle.front_to_cg, vehicle.rear_to_cg
    m, iz = vehicle.mass, vehicle.yaw_inertia
    peak_f, peak_r = _axle_peaks(vehicle, tyre)
    v_y, r = l_r * kappa * u, kappa * u
    # d(atan2(w, u))/dw = u / (u^2 + w^2) for the axle's lateral speed w
    w_f, w_r = v_y + l_f * r, v_y - l_r * r
    g_f, g_r = u / (u**2 + w_f**2), u / (u**2 + w_r**2)
    alpha_f, alpha_r = equations.slip_angles(u, l_f, l_r, v_y, r, delta_f, delta_r)
    c_f = _slope(alpha_f, vehicle.cornering_front, peak_f)
    c_r = _slope(alpha_r, vehicle.cornering_rear, peak_r)
    force_f = tyre_force(alpha_f, stiffness=vehicle.cornering_front, peak=peak_f)
    force_r = tyre_force(alpha_r, stiffness=vehicle.cornering_rear, peak=peak_r)
    cos_f, cos_r = np.cos(delta_f), np.cos(delta_r)
    yf_v, yr_v = -c_f * g_f * cos_f, -c_r * g_r * cos_r
    yf_r, yr_r = -c_f * g_f * l_f * cos_f, c_r * g_r * l_r * cos_r
    yf_d = c_f * cos_f - force_f * np.sin(delta_f)
    yr_d = c_r * cos_r - force_r * np.sin(delta_r)
    zero, one = np.zeros_like(u), np.ones_like(u)
    A = np.stack(
        [
            np.stack([zero, u, one, -l_r * one], -1),
            np.stack([-(kappa**2) * u, zero, zero, one], -1),
            np.stack([zero, zero, (yf_v + yr_v) / m, (yf_r + yr_r) / m - u], -1),
            np.stack(
                [
                    zero,
                    zero,
                    (l_f * yf_v - l_r * yr_v) / iz,
                    (l_f * yf_r - l_r * yr_r) / iz,
                ],
                -1,
            ),
        ],
        -2,
    )
    B = np.stack(
        [
            np.stack([zero, zero], -1),
            np.stack([zero, zero], -1),
            np.stack([yf_d / m, yr_d / m], -1),
            np.stack([l_f * yf_d / iz, -l_r * yr_d / iz], -1),
        ],
        -2,
    )
    return A, B
