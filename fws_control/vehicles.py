r"""Named parameter sets of real cars, from CommonRoad's vehicle models.

The values are transcribed from the BSD-3-licensed package
``commonroad-vehicle-models`` 3.0.2 (M. Althoff and G. Würsching,
*CommonRoad: Vehicle Models*, TU Munich, 2020, table 6;
https://gitlab.lrz.de/tum-cps/commonroad-vehicle-models), files
``vehiclemodels/parameters/parameters_vehicle{1,2,3}.yaml`` and
``parameters_tire.yaml``:

=================  ==  =======  =======  ========  ======  =============
constant           id  a [m]    b [m]    m [kg]    I_z     CommonRoad set
=================  ==  =======  =======  ========  ======  =============
``FORD_ESCORT``    1   0.88392  1.50876  1225.888  1538.9  vehicle1
``BMW_320I``       2   1.15620  1.42272  1093.295  1791.6  vehicle2
``VW_VANAGON``     3   1.15079  1.32114  1478.898  2473.1  vehicle3
=================  ==  =======  =======  ========  ======  =============

(``a`` = centre of gravity to front axle, ``b`` = to rear axle; the
constants carry the package's full digits.)

Cornering stiffness. CommonRoad's single-track model
(``vehicle_dynamics_st``) writes the axle forces as
:math:`\mu C_S F_z \alpha` with the static axle loads
:math:`F_{zf} = m g l_r/l`, :math:`F_{zr} = m g l_f/l` (``g = 9.81``, no
load transfer at constant speed), friction :math:`\mu` = ``p_dy1`` =
1.0489 and, in version 3.0.2, the same normalised stiffness
:math:`C_S = -p_{ky1}/p_{dy1}` = 21.92/1.0489 1/rad on both axles (older
releases list it as ``C_Sf``, ``C_Sr`` = 20.89). The cornering stiffness per
axle of this library is therefore

.. math::
    C_f = \mu C_S\,\frac{m g l_r}{l},\qquad C_r = \mu C_S\,\frac{m g l_f}{l},

with :math:`\mu C_S = -p_{ky1}` = 21.92 1/rad. Because the normalised
stiffness is the same on both axles, these cars are *neutral steer* in the
linear range (:func:`~fws_control.understeer_gradient` = 0 up to rounding).

Mapping to :class:`Vehicle`: ``wheelbase = a + b``, ``rear_to_cg = b``,
``friction`` = :math:`\mu`. The steering limits of CommonRoad (front angle
``steering.max``, rate ``steering.v_max`` = 0.4 rad/s) are *not* set: the
real cars have no rear steering, and the limits would clip the paper's
controller; add them with :func:`dataclasses.replace` (values in
:data:`COMMONROAD_STEERING`). ``tests/test_vehicles.py`` holds every value
against the installed package.
"""

from __future__ import annotations

import math

from .vehicle import Vehicle

__all__ = [
    "FORD_ESCORT",
    "BMW_320I",
    "VW_VANAGON",
    "COMMONROAD_VEHICLES",
    "COMMONROAD_STEERING",
    "COMMONROAD_GRAVITY",
    "commonroad_vehicle",
    "from_commonroad",
]

#: Gravitational acceleration of CommonRoad's single-track model [m/s^2].
COMMONROAD_GRAVITY = 9.81

# Tyre parameters of parameters_tire.yaml (shared by all vehicles).
_P_DY1 = 1.0489  # friction coefficient mu
_P_KY1 = -21.92  # mu * C_S [1/rad], sign of the Pacejka convention

#: Front steering limits of CommonRoad's parameter sets, ``{id: (max angle
#: [rad], max rate [rad/s])}`` (``steering.max``, ``steering.v_max``).
COMMONROAD_STEERING = {1: (0.91, 0.4), 2: (1.066, 0.4), 3: (1.023, 0.4)}


def commonroad_vehicle(
    *,
    a: float,
    b: float,
    mass: float,
    yaw_inertia: float,
    friction: float,
    stiffness_front: float,
    stiffness_rear: float,
) -> Vehicle:
    r"""A :class:`Vehicle` from CommonRoad single-track parameters.

    Parameters
    ----------
    a, b : float
        Distances from the centre of gravity to the front and rear axle [m].
    mass : float
        Mass [kg].
    yaw_inertia : float
        Yaw moment of inertia [kg m^2].
    friction : float
        Friction coefficient :math:`\mu` [-].
    stiffness_front, stiffness_rear : float
        Normalised cornering stiffnesses :math:`C_{Sf}, C_{Sr}` [1/rad]
        (force per unit normal load and friction).

    Returns
    -------
    Vehicle
        ``wheelbase = a + b``, ``rear_to_cg = b``,
        :math:`C_f = \mu C_{Sf} m g b/(a+b)`, :math:`C_r = \mu C_{Sr} m g
        a/(a+b)`.

    Examples
    --------
    >>> from fws_control.vehicles import commonroad_vehicle
    >>> veh = commonroad_vehicle(a=1.0, b=1.5, mass=1000.0, yaw_inertia=1500.0,
    ...                          friction=1.0, stiffness_front=20.0,
    ...                          stiffness_rear=20.0)
    >>> veh.wheelbase, round(veh.cornering_front, 3)     # 20*1000*9.81*1.5/2.5
    (2.5, 117720.0)
    """
    wheelbase = a + b
    weight = mass * COMMONROAD_GRAVITY
    return Vehicle(
        wheelbase,
        b,
        mass=mass,
        yaw_inertia=yaw_inertia,
        cornering_front=friction * stiffness_front * weight * b / wheelbase,
        cornering_rear=friction * stiffness_rear * weight * a / wheelbase,
        friction=friction,
    )


_C_S = -_P_KY1 / _P_DY1

#: Ford Escort, CommonRoad parameter set 1.
FORD_ESCORT = commonroad_vehicle(
    a=0.88392,
    b=1.50876,
    mass=1225.8878467253344,
    yaw_inertia=1538.8533713561394,
    friction=_P_DY1,
    stiffness_front=_C_S,
    stiffness_rear=_C_S,
)

#: BMW 320i, CommonRoad parameter set 2.
BMW_320I = commonroad_vehicle(
    a=1.1561957064,
    b=1.4227170936,
    mass=1093.2952334674046,
    yaw_inertia=1791.5995300122856,
    friction=_P_DY1,
    stiffness_front=_C_S,
    stiffness_rear=_C_S,
)

#: VW Vanagon, CommonRoad parameter set 3.
VW_VANAGON = commonroad_vehicle(
    a=1.1507916024,
    b=1.3211363976000001,
    mass=1478.8979637767998,
    yaw_inertia=2473.1176915564442,
    friction=_P_DY1,
    stiffness_front=_C_S,
    stiffness_rear=_C_S,
)

#: The transcribed parameter sets by CommonRoad id.
COMMONROAD_VEHICLES = {1: FORD_ESCORT, 2: BMW_320I, 3: VW_VANAGON}


def from_commonroad(vehicle_id: int) -> Vehicle:
    """Read CommonRoad's parameter set `vehicle_id` from the installed package.

    Needs the optional dependency ``commonroad-vehicle-models``
    (``pip install commonroad-vehicle-models``); uses its tyre parameters
    ``p_dy1`` (friction) and ``p_ky1`` (normalised stiffness, both axles) as
    its ``vehicle_dynamics_st`` does.

    Parameters
    ----------
    vehicle_id : int
        1 (Ford Escort), 2 (BMW 320i) or 3 (VW Vanagon). Set 4, a
        semi-trailer truck, has no single-track parameters.

    Returns
    -------
    Vehicle

    Raises
    ------
    ValueError
        For an unknown `vehicle_id`.
    ModuleNotFoundError
        If the package is not installed.

    Examples
    --------
    >>> from fws_control.vehicles import from_commonroad, FORD_ESCORT
    >>> from_commonroad(1) == FORD_ESCORT          # doctest: +SKIP
    True
    """
    if isinstance(vehicle_id, bool) or vehicle_id not in (1, 2, 3):
        raise ValueError(
            f"vehicle_id must be 1, 2 or 3 (the cars of CommonRoad), got {vehicle_id!r}"
        )
    try:
        from vehiclemodels.vehicle_parameters import setup_vehicle_parameters
    except ModuleNotFoundError as exc:
        raise ModuleNotFoundError(
            "from_commonroad needs the package commonroad-vehicle-models "
            "(pip install commonroad-vehicle-models); the constants FORD_ESCORT, "
            "BMW_320I and VW_VANAGON hold sets 1-3 without it"
        ) from exc
    p = setup_vehicle_parameters(vehicle_id=vehicle_id)
    mu = float(p.tire.p_dy1)
    c_s = -float(p.tire.p_ky1) / mu
    if not (math.isfinite(c_s) and c_s > 0):
        raise ValueError(f"CommonRoad set {vehicle_id} has no positive C_S: {c_s!r}")
    return commonroad_vehicle(
        a=float(p.a),
        b=float(p.b),
        mass=float(p.m),
        yaw_inertia=float(p.I_z),
        friction=mu,
        stiffness_front=c_s,
        stiffness_rear=c_s,
    )
