r"""Closed-form double-root pole placement, paper section 4.2.

The double root :math:`(\lambda-\lambda_0)^2` is matched by solving eqs.
(39)-(40) as a 2x2 *linear* system in ``(k1, k2)`` (Cramer's rule). Its
determinant is

.. math:: \Delta = -\frac{V^3}{f^2}\left(a^2 f^2\kappa^2 + (c-a)^2\right),

which equals the determinant of the controllability matrix of
:math:`(\mathbf A, \mathbf B[1, a]^T)`. It vanishes only for ``a = c`` and
``a*kappa = 0``, i.e. ``a = 1`` on a straight path in both models; nothing is
special about ``a = 0`` (the paper's eqs. (43)-(46) are singular there only
because of how they are written).
"""

from __future__ import annotations

import numpy as np

from ._validation import check_finite, check_model, check_nonzero
from .gains import SteeringGains
from .linear import characteristic_coefficients
from .vehicle import Vehicle

__all__ = ["UncontrollableError", "double_root_gains"]


#: Below this distance from the uncontrollable design (dimensionless
#: a^2 f^2 kappa^2 + (c - a)^2) the gains, which grow like its inverse,
#: exceed ~1e12 and are refused.
_SINGULAR_DISTANCE = 1e-12


class UncontrollableError(ValueError):
    """The requested closed-loop poles cannot be reached by any gains."""


def double_root_gains(
    vehicle: Vehicle,
    speed,
    curvature,
    ratio,
    pole,
    model: str = "exact",
) -> SteeringGains:
    r"""Gains that put both closed-loop poles at :math:`\lambda_0`.

    Solves eqs. (39)-(40) (with ``(c-a)`` in place of ``(1-a)`` for the exact
    model):

    .. math::
        -2\lambda_0 = \frac{V}{f}(f a k_1 + (c-a) k_2),\qquad
        \lambda_0^2 = \frac{V^2}{f}\left((c-a)k_1 + (1-a k_2)f\kappa^2\right).

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed : float or array_like
        Speed :math:`V` [m/s], finite and nonzero.
    curvature : float or array_like
        Path curvature :math:`\kappa_C` [1/m].
    ratio : float or array_like
        Rear-to-front steering ratio :math:`a`.
    pole : float or array_like
        Double root :math:`\lambda_0` [1/s], finite and < 0.
    model : {"exact", "paper"}, optional
        Linearisation, see :func:`linearize`.

    Returns
    -------
    SteeringGains
        Broadcast over the array arguments.

    Raises
    ------
    UncontrollableError
        For ``ratio = 1`` on a straight path: then ``delta_r = delta_f``, the
        yaw rate is identically zero and the characteristic polynomial is
        :math:`\lambda(\lambda + V k_1)`, so no double root
        :math:`\lambda_0 \ne 0` exists.
    ValueError
        For a zero or non-finite `speed`, a `pole` that is not finite and
        negative, non-finite `curvature` or `ratio`, or an unknown `model`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=5.0, curvature=0.0, ratio=-1.0, pole=-1.0)
    >>> round(g.k1, 6), round(g.k2, 6)
    (0.054, 0.6129)
    >>> fws.double_root_gains(veh, 5.0, 0.0, ratio=1.0, pole=-1.0)
    Traceback (most recent call last):
        ...
    fws_control.design.UncontrollableError: ratio=1.0 with curvature=0.0 makes ...
    """
    check_model(model)
    V = check_nonzero("speed", speed)
    kappa = check_finite("curvature", curvature)
    a = check_finite("ratio", ratio)
    lam = check_finite("pole", pole)
    if np.any(np.asarray(lam) >= 0):
        raise ValueError(f"pole must be finite and < 0, got {pole!r}")

    cc = characteristic_coefficients(vehicle, V, kappa, a, model)
    det = cc.alpha1 * cc.beta0 - cc.beta1 * cc.alpha0
    # det is -(V^3/f^2)(a^2 f^2 kappa^2 + (c-a)^2): compare with that scale so
    # that the test does not depend on units.
    # det = -(V^3/f^2) * distance, distance = a^2 f^2 kappa^2 + (c - a)^2:
    # dimensionless, zero exactly at the uncontrollable design.
    distance = -det * vehicle.wheelbase**2 / np.asarray(V) ** 3
    singular = distance <= _SINGULAR_DISTANCE
    if np.any(singular):
        worst = float(np.min(distance))
        if worst == 0.0:
            why = (
                "makes delta_r = delta_f: the yaw rate is identically zero, the "
                "heading is uncontrollable and D(lambda) = lambda*(lambda + V*k1), "
                f"so no double root pole={pole!r} != 0 exists"
            )
        else:
            why = (
                "is nearly uncontrollable (delta_r = delta_f on a straight path is "
                "uncontrollable): a^2 f^2 kappa^2 + (c - a)^2 = "
                f"{worst:.3g} <= {_SINGULAR_DISTANCE:g}; the gains grow like its "
                "inverse and would be meaningless"
            )
        raise UncontrollableError(f"ratio={ratio!r} with curvature={curvature!r} {why}")
    r1 = -2.0 * np.asarray(lam) - cc.gamma1
    r0 = np.asarray(lam) ** 2 - cc.gamma0
    k1 = (r1 * cc.beta0 - cc.beta1 * r0) / det
    k2 = (cc.alpha1 * r0 - r1 * cc.alpha0) / det
    k1, k2, a_b = np.broadcast_arrays(k1, k2, a)
    return SteeringGains(k1=k1, k2=k2, ratio=a_b)
