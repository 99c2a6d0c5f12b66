r"""Design questions of the dynamic single-track model.

* :func:`steady_state_offset`: the lateral and heading error that the
  paper's controller with the *kinematic* feedforward leaves on a curve when
  the tyres slip (closed form, linear tyres);
* :func:`zero_sideslip_ratio`: the classic speed-dependent rear-to-front
  ratio :math:`a(V)` with zero steady sideslip at the centre of gravity;
* :func:`understeer_gradient`.

Small-angle model of the closed forms: first order in the steering angles,
the lateral velocity, the yaw rate, the errors and the curvature (the
:math:`-\kappa^2 V e` of :math:`\dot\theta` kept, as in the exact kinematic
linearisation); :func:`fws_control.symbolic.dynamic_steady_state` derives it
from Newton-Euler, and the tests hold the numeric formulas here equal to it
and to the nonlinear steady state (``scipy.optimize.fsolve``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .dynamics import require_dynamics
from .gains import SteeringGains
from .validation import check_finite, check_type
from .vehicle import Vehicle

__all__ = [
    "understeer_gradient",
    "zero_sideslip_ratio",
    "steady_state_offset",
]


def _check_speed(speed) -> np.ndarray | float:
    v = check_finite("speed", speed)
    if np.any(np.asarray(v) <= 0.0):
        raise ValueError(f"speed must be finite and > 0 m/s, got {speed!r}")
    return v


def understeer_gradient(vehicle: Vehicle) -> float:
    r"""Understeer gradient :math:`K_{us}` [rad s^2/m] of the linear tyres.

    .. math:: K_{us} = \frac{m}{f}\left(\frac{l_r}{C_f} - \frac{l_f}{C_r}\right)

    In a steady front-steered turn :math:`\delta_f = f\kappa + K_{us}
    a_y` with :math:`a_y = V^2\kappa`; > 0 understeer, < 0 oversteer (then
    the vehicle is unstable above the critical speed
    :math:`\sqrt{-f/K_{us}}`).

    Parameters
    ----------
    vehicle : Vehicle
        With mass and cornering stiffnesses.

    Returns
    -------
    float

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, mass=1500.0,
    ...                   yaw_inertia=2600.0, cornering_front=8e4,
    ...                   cornering_rear=9.5e4)
    >>> round(fws.understeer_gradient(veh), 6)     # 1500/2.7*(1.2/8e4 - 1.5/9.5e4)
    -0.000439
    """
    require_dynamics(vehicle)
    m, f = vehicle.mass, vehicle.wheelbase
    return (
        m
        / f
        * (
            vehicle.rear_to_cg / vehicle.cornering_front
            - vehicle.front_to_cg / vehicle.cornering_rear
        )
    )


def zero_sideslip_ratio(vehicle: Vehicle, *, speed) -> float | np.ndarray:
    r"""Ratio :math:`a(V) = \delta_r/\delta_f` with zero steady sideslip at G.

    .. math::
        a(V) = \frac{-l_r + \dfrac{m l_f V^2}{f C_r}}
                    {l_f + \dfrac{m l_r V^2}{f C_f}}

    (linear tyres, small angles). Counter-phase (:math:`a < 0`, tighter
    turns) below :math:`V_0 = \sqrt{f C_r l_r/(m l_f)}`, in phase above it;
    :math:`a \to -l_r/l_f` as :math:`V \to 0` and :math:`a \to C_f l_f/(C_r
    l_r)` as :math:`V \to \infty`. This is the classic proportional
    four-wheel-steering ratio of Sano, Furukawa and Shiraishi (SAE 860625,
    1986), derived e.g. in M. Abe, *Vehicle Handling Dynamics*, 2nd ed.,
    Butterworth-Heinemann 2015, section 8.2 (with :math:`C = 2K` per axle).
    :func:`fws_control.symbolic.zero_sideslip_ratio` derives it.

    Its call ``(vehicle, speed=...)`` is that of a ratio schedule: pass it
    as ``ratio=`` where a design or chart takes a ratio to evaluate it at
    the plant's speed.

    Parameters
    ----------
    vehicle : Vehicle
        With mass and cornering stiffnesses.
    speed : float or array_like
        Longitudinal speed :math:`V` [m/s], finite and > 0.

    Returns
    -------
    float or ndarray
        :math:`a(V)` [-], broadcast over `speed`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, mass=1500.0,
    ...                   yaw_inertia=2600.0, cornering_front=8e4,
    ...                   cornering_rear=9.5e4)
    >>> [round(float(a), 4) for a in fws.zero_sideslip_ratio(veh, speed=[5.0, 30.0])]
    [-0.5741, 0.7439]
    """
    require_dynamics(vehicle)
    v = np.asarray(_check_speed(speed), dtype=float)
    m, f = vehicle.mass, vehicle.wheelbase
    l_f, l_r = vehicle.front_to_cg, vehicle.rear_to_cg
    num = -l_r + m * l_f * v**2 / (f * vehicle.cornering_rear)
    den = l_f + m * l_r * v**2 / (f * vehicle.cornering_front)
    out = num / den
    return float(out) if out.ndim == 0 else out


def steady_state_offset(
    vehicle: Vehicle,
    gains: SteeringGains,
    *,
    speed: Any,
    curvature: Any,
) -> tuple[float | np.ndarray, float | np.ndarray]:
    r"""Steady lateral and heading error of the paper's loop on the dynamic model.

    The controller of the paper, :math:`\delta_f = \arctan(\kappa f) - k_1 e
    - k_2\theta`, :math:`\delta_r = a(-k_1 e - k_2\theta)`, designed for the
    kinematic model, steers the dynamic model (linear tyres) on a circle of
    curvature :math:`\kappa` at speed :math:`V`. The tyres need slip angles
    the kinematic feedforward does not supply, so the loop settles at

    .. math::
        e_{ss} = \frac{\kappa\left(P_f(1 - a k_2) - P_r(1 - k_2)\right)}{\Delta},
        \qquad
        \theta_{ss} = \frac{\kappa\left((a k_1 + P_r\kappa^2) P_f
            - (k_1 + (f + P_f)\kappa^2) P_r\right)}{\Delta},

    .. math::
        \Delta = (1 - k_2)(a k_1 + P_r\kappa^2)
                 - (1 - a k_2)(k_1 + (f + P_f)\kappa^2),\qquad
        P_f = \frac{m V^2 l_r}{f C_f},\ P_r = \frac{m V^2 l_f}{f C_r}

    (:math:`P\kappa` is the slip angle each axle needs). Without the
    :math:`\kappa^2` terms, :math:`\Delta = -k_1(1 - a)` and
    :math:`e_{ss} = \kappa(P_r(1-k_2) - P_f(1-a k_2))/(k_1(1-a))`: for front
    steering (:math:`a = 0`), :math:`-\kappa(K_{us}V^2 + k_2 P_r)/k_1`.

    This is the steady state of the small-angle model (module docstring),
    exact to first order in the angles; the nonlinear model with linear
    tyres differs by terms of relative order :math:`\kappa^2` (0.29 % of
    the offset for the example below, 20 m/s on a 100 m radius, solved with
    ``scipy.optimize.fsolve`` in ``tests/test_dynamic_steady.py``). It is reached
    only if the closed loop is stable (:func:`fws_control.is_stable` on
    ``LateralPlant(..., model="dynamic")``). Saturating tyres need a
    numeric solution.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry, mass and cornering stiffnesses.
    gains : SteeringGains
        ``k1, k2, ratio``; arrays broadcast.
    speed : float or array_like
        Longitudinal speed :math:`V` [m/s], finite and > 0.
    curvature : float or array_like
        Path curvature :math:`\kappa` [1/m], finite.

    Returns
    -------
    e, theta : float or ndarray
        Steady lateral error [m] (positive left of the path) and heading
        error [rad] of the rear-axle point R.

    Raises
    ------
    ValueError
        For missing vehicle data, a non-positive speed, a non-finite
        curvature or a loop with no steady state (:math:`\Delta = 0`, a
        closed-loop pole at 0: e.g. ``k1 = 0``, or ``ratio = 1`` with
        :math:`K_{us} \ne 0`).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, mass=1500.0,
    ...                   yaw_inertia=2600.0, cornering_front=8e4,
    ...                   cornering_rear=9.5e4)
    >>> g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=0.0)
    >>> e, th = fws.steady_state_offset(veh, g, speed=20.0, curvature=0.01)
    >>> round(e, 4), round(th, 5)
    (-0.4309, 0.03494)
    """
    require_dynamics(vehicle)
    check_type("gains", gains, SteeringGains)
    v = np.asarray(_check_speed(speed), dtype=float)
    kappa = np.asarray(check_finite("curvature", curvature), dtype=float)
    m, f = vehicle.mass, vehicle.wheelbase
    l_f, l_r = vehicle.front_to_cg, vehicle.rear_to_cg
    k1, k2, a = (np.asarray(x, dtype=float) for x in (gains.k1, gains.k2, gains.ratio))
    p_f = m * v**2 * l_r / (f * vehicle.cornering_front)
    p_r = m * v**2 * l_f / (f * vehicle.cornering_rear)
    k_sq = kappa**2
    # the two steady equations, linear in (e, theta):
    #   -(k1 + (f + P_f) kappa^2) e + (1 - k2) theta = P_f kappa
    #   -(a k1 + P_r kappa^2) e + (1 - a k2) theta = P_r kappa
    m11, m12 = -(k1 + (f + p_f) * k_sq), 1.0 - k2
    m21, m22 = -(a * k1 + p_r * k_sq), 1.0 - a * k2
    det = m11 * m22 - m12 * m21
    scale = np.abs(m11 * m22) + np.abs(m12 * m21)
    if np.any(np.abs(det) <= 1e-12 * scale):
        raise ValueError(
            "the loop has no steady state for these gains (a closed-loop pole at "
            f"s = 0): k1={gains.k1!r}, k2={gains.k2!r}, ratio={gains.ratio!r}; "
            "k1 must be nonzero and ratio = 1 is uncontrollable"
        )
    e = kappa * (p_f * m22 - m12 * p_r) / det
    theta = kappa * (m11 * p_r - m21 * p_f) / det
    if np.ndim(e) == 0:
        return float(e), float(theta)
    return e, theta
