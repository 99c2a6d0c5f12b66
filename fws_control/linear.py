r"""Linearisation of the path-frame model and the linear closed loop.

Two linearisations about the feedforward operating point
``e = theta = 0, delta_f = atan(curvature*wheelbase), delta_r = 0`` are
offered:

``model="exact"`` (default)
    The true Jacobian of eqs. (18)-(19). The front-steering entry of
    :math:`\mathbf B` is :math:`V(1+f^2\kappa^2)/f = V/(f\cos^2\delta_f^{FF})`.
``model="paper"``
    Eq. (33) verbatim, which takes that entry as :math:`V/f`, exact only on a
    straight path.

Both have the form

.. math::
    \mathbf A = \begin{bmatrix}0 & V\\ -V\kappa^2 & 0\end{bmatrix},\quad
    \mathbf B = \begin{bmatrix}0 & V\\ cV/f & -V/f\end{bmatrix},

with :math:`c = 1 + f^2\kappa^2` (exact) or :math:`c = 1` (paper). The
characteristic polynomial of :math:`\mathbf A + \mathbf B\mathbf K` (eq. 34,
with ``(1-a)`` replaced by ``(c-a)``) is affine in ``(k1, k2)``; this module
holds its single numeric implementation, which the stability and design
modules use.
"""

from __future__ import annotations

from dataclasses import dataclass

import control as ct
import numpy as np

from ._validation import (
    check_finite,
    check_model,
    check_nonzero,
    check_scalar,
    check_vehicle,
)
from .gains import SteeringGains
from .models import STEERING_INPUTS, feedforward_steering
from .vehicle import Vehicle

__all__ = [
    "input_gain_factor",
    "operating_point",
    "linearize",
    "closed_loop",
    "characteristic_polynomial",
    "AffineCoefficients",
    "characteristic_coefficients",
    "LINEAR_STATES",
]

LINEAR_STATES = ("e", "theta")


def input_gain_factor(vehicle: Vehicle, curvature, model: str = "exact"):
    r"""Factor :math:`c` of the front-steering entry :math:`cV/f` of B.

    :math:`c = 1 + f^2\kappa^2` for ``model="exact"`` and :math:`c = 1` for
    ``model="paper"`` (eq. 33). Broadcasts over `curvature`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> round(fws.input_gain_factor(veh, 0.1), 4)
    1.0729
    >>> fws.input_gain_factor(veh, 0.1, model="paper")
    1.0
    """
    check_model(model)
    kappa = np.asarray(check_finite("curvature", curvature))
    if model == "paper":
        out = np.ones_like(kappa)
    else:
        out = 1.0 + (vehicle.wheelbase * kappa) ** 2
    return float(out) if out.ndim == 0 else out


def operating_point(vehicle: Vehicle, curvature) -> tuple[np.ndarray, np.ndarray]:
    """Equilibrium of the path-frame model with feedforward steering.

    Returns ``(x0, u0)`` with ``x0 = [s, e, theta] = [0, 0, 0]`` and
    ``u0 = [atan(curvature*wheelbase), 0]`` (paper eqs. 26-27).
    """
    return np.zeros(3), np.array([feedforward_steering(vehicle, curvature), 0.0])


def _matrices(vehicle: Vehicle, speed, curvature, model):
    check_vehicle(vehicle)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    kappa = check_scalar("curvature", curvature)
    c = input_gain_factor(vehicle, kappa, model)
    f = vehicle.wheelbase
    A = np.array([[0.0, speed], [-speed * kappa**2, 0.0]])
    B = np.array([[0.0, speed], [c * speed / f, -speed / f]])
    return A, B


def linearize(
    vehicle: Vehicle, speed: float, curvature: float = 0.0, model: str = "exact"
) -> ct.StateSpace:
    r"""Linearised lateral dynamics about the feedforward operating point.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed : float
        Speed :math:`V` [m/s], finite and nonzero (negative: reversing).
    curvature : float, optional
        Path curvature :math:`\kappa_C` [1/m].
    model : {"exact", "paper"}, optional
        ``"exact"``: Jacobian of eqs. (18)-(19); ``"paper"``: eq. (33).

    Returns
    -------
    control.StateSpace
        States and outputs ``e, theta`` (deviations from the operating
        point); inputs ``delta_f, delta_r`` (deviations from the feedforward
        angles).

    Raises
    ------
    ValueError
        For a zero or non-finite `speed`, non-finite `curvature` or an
        unknown `model`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sys = fws.linearize(veh, speed=5.0, curvature=0.1)
    >>> sys.B.round(4)
    array([[ 0.    ,  5.    ],
           [ 1.9869, -1.8519]])
    >>> fws.linearize(veh, speed=5.0, curvature=0.1, model="paper").B.round(4)
    array([[ 0.    ,  5.    ],
           [ 1.8519, -1.8519]])
    """
    A, B = _matrices(vehicle, speed, curvature, model)
    return ct.ss(
        A,
        B,
        np.eye(2),
        np.zeros((2, 2)),
        states=list(LINEAR_STATES),
        inputs=list(STEERING_INPUTS),
        outputs=list(LINEAR_STATES),
        name=f"linear_{model}",
    )


def closed_loop(
    vehicle: Vehicle,
    speed: float,
    curvature: float,
    gains: SteeringGains,
    model: str = "exact",
) -> ct.StateSpace:
    r"""Linear closed loop with the structured feedback ``u = K x + w``.

    .. math:: \dot x = (\mathbf A + \mathbf B\mathbf K) x + \mathbf B w

    Parameters
    ----------
    vehicle, speed, curvature, model
        As in :func:`linearize`.
    gains : SteeringGains
        Scalar gains; ``K`` is :attr:`SteeringGains.matrix`.

    Returns
    -------
    control.StateSpace
        States ``e, theta``; inputs ``delta_f_dist, delta_r_dist`` (steering
        disturbances added to the controller's output); outputs ``e, theta,
        delta_f, delta_r``, the last two being the steering deviations from the
        feedforward angles, ``K x + w``.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    >>> cl = fws.closed_loop(veh, 5.0, 0.1, g)
    >>> np.allclose(cl.poles(), [-1.0, -1.0], atol=1e-6)
    True
    """
    if not isinstance(gains, SteeringGains):
        raise TypeError(f"gains must be a SteeringGains, got {type(gains).__name__}")
    K = gains.matrix
    if K.shape != (2, 2):
        raise ValueError(
            f"gains must hold scalar k1, k2, ratio for closed_loop, got shape {K.shape}"
        )
    A, B = _matrices(vehicle, speed, curvature, model)
    return ct.ss(
        A + B @ K,
        B,
        np.vstack([np.eye(2), K]),
        np.vstack([np.zeros((2, 2)), np.eye(2)]),
        states=list(LINEAR_STATES),
        inputs=["delta_f_dist", "delta_r_dist"],
        outputs=[*LINEAR_STATES, *STEERING_INPUTS],
        name=f"closed_loop_{model}",
    )


@dataclass(frozen=True)
class AffineCoefficients:
    r"""Coefficients of :math:`\lambda^2 + p_1\lambda + p_0` as affine maps.

    ``p1 = alpha1*k1 + beta1*k2 + gamma1`` and
    ``p0 = alpha0*k1 + beta0*k2 + gamma0`` (eq. 34 with ``(c-a)`` for
    ``(1-a)``). The bilinear ``k1*k2`` terms cancel, which is why the
    stability boundaries are straight lines and the double-root design is a
    2x2 linear system. Fields broadcast.
    """

    alpha1: np.ndarray
    beta1: np.ndarray
    gamma1: np.ndarray
    alpha0: np.ndarray
    beta0: np.ndarray
    gamma0: np.ndarray

    def p1(self, k1, k2):
        """Coefficient of :math:`\\lambda` (Routh-Hurwitz condition 35)."""
        return self.alpha1 * k1 + self.beta1 * k2 + self.gamma1

    def p0(self, k1, k2):
        """Constant coefficient (Routh-Hurwitz condition 36)."""
        return self.alpha0 * k1 + self.beta0 * k2 + self.gamma0


def characteristic_coefficients(
    vehicle: Vehicle, speed, curvature, ratio, model: str = "exact"
) -> AffineCoefficients:
    r"""Characteristic polynomial of the closed loop as affine maps of (k1, k2).

    .. math::
        p_1 = \frac{V}{f}\left(f a k_1 + (c-a)k_2\right),\qquad
        p_0 = \frac{V^2}{f}\left((c-a)k_1 + (1-a k_2) f\kappa^2\right)

    with :math:`c` from :func:`input_gain_factor`. Broadcasts over `speed`,
    `curvature` and `ratio`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> cc = fws.characteristic_coefficients(veh, 5.0, 0.0, 0.0)
    >>> round(float(cc.p1(0.2, 0.5)), 9), round(float(cc.p0(0.2, 0.5)), 9)
    (0.925925926, 1.851851852)
    """
    check_vehicle(vehicle)
    check_model(model)
    V = np.asarray(check_nonzero("speed", speed))
    kappa = np.asarray(check_finite("curvature", curvature))
    a = np.asarray(check_finite("ratio", ratio))
    f = vehicle.wheelbase
    c = np.asarray(input_gain_factor(vehicle, kappa, model))
    V, kappa, a, c = np.broadcast_arrays(V, kappa, a, c)
    return AffineCoefficients(
        alpha1=V * a,
        beta1=V * (c - a) / f,
        gamma1=np.zeros_like(V),
        alpha0=V**2 * (c - a) / f,
        beta0=-(V**2) * a * kappa**2,
        gamma0=V**2 * kappa**2,
    )


def characteristic_polynomial(
    vehicle: Vehicle,
    speed,
    curvature,
    gains: SteeringGains,
    model: str = "exact",
) -> np.ndarray:
    r"""Coefficients ``[1, p1, p0]`` of :math:`D(\lambda)`, eq. (34).

    Broadcasts: the result has shape ``(..., 3)``, highest power first, so a
    scalar design gives an array usable with :func:`numpy.roots`.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, 20.0, 0.01, ratio=0.5, pole=-2.0)
    >>> fws.characteristic_polynomial(veh, 20.0, 0.01, g).round(9)
    array([1., 4., 4.])
    """
    cc = characteristic_coefficients(vehicle, speed, curvature, gains.ratio, model)
    p1 = cc.p1(gains.k1, gains.k2)
    p0 = cc.p0(gains.k1, gains.k2)
    p1, p0 = np.broadcast_arrays(p1, p0)
    return np.stack([np.ones_like(p1), p1, p0], axis=-1)
