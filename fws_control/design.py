r"""Closed-form double-root pole placement, paper section 4.2.

For a second-order plant the closed-loop polynomial
:math:`s^2 + p_1 s + p_0` is affine in ``(k1, k2)``
(:func:`~fws_control.characteristic_coefficients`), so matching
:math:`(s-\lambda_0)^2` — eqs. (39)-(40) — is a 2 x 2 *linear* system,
solved here by Cramer's rule. For the kinematic plant its determinant is

.. math:: \Delta = -\frac{V^3}{f^2}\left(a^2 f^2\kappa^2 + (c-a)^2\right),

which equals the determinant of the controllability matrix of
:math:`(\mathbf A, \mathbf B[1, a]^T)`. It vanishes only for ``a = c`` and
``a*kappa = 0``, i.e. ``a = 1`` on a straight path in both models; nothing is
special about ``a = 0`` (the paper's eqs. (43)-(46) are singular there only
because of how they are written).

A plant of higher order has ``n`` poles but the structured controller only
two gains, ``k1`` on ``e`` and ``k2`` on ``theta``: a double root does not
determine them and the other poles go where they must. Choose the gains from
:func:`stability_chart` (and :func:`parameter_locus`) instead; a full state
feedback from :func:`control.place` on ``(A, B[:, delta_f] + a B[:,
delta_r])`` is a different controller (it feeds back every state).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .exceptions import UncontrollableError
from .gains import SteeringGains
from .linear import characteristic_coefficients
from .plant import LateralPlant, as_plant, resolve_ratio
from .validation import check_finite

__all__ = ["double_root_gains"]


#: Below this distance from the uncontrollable design (dimensionless
#: a^2 f^2 kappa^2 + (c - a)^2 for the kinematic plant, the determinant
#: relative to |n1| |n2| otherwise) the gains, which grow like its inverse,
#: exceed ~1e12 and are refused.
_SINGULAR_DISTANCE = 1e-12


def double_root_gains(
    plant: Any,
    *,
    ratio,
    pole,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> SteeringGains:
    r"""Gains that put both closed-loop poles of a 2-state plant at :math:`\lambda_0`.

    Solves eqs. (39)-(40) (with ``(c-a)`` in place of ``(1-a)`` for the exact
    model) as a linear system in ``(k1, k2)``:

    .. math::
        -2\lambda_0 = \frac{V}{f}(f a k_1 + (c-a) k_2),\qquad
        \lambda_0^2 = \frac{V^2}{f}\left((c-a)k_1 + (1-a k_2)f\kappa^2\right).

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        A second-order plant (see :mod:`fws_control.plant`).
    ratio : float, array_like or callable
        Rear-to-front steering ratio :math:`a`, or a schedule
        ``ratio(vehicle, speed=...)`` evaluated at the plant's speed (e.g.
        :func:`~fws_control.zero_sideslip_ratio`).
    pole : float or array_like
        Double root :math:`\lambda_0` [1/s], finite and < 0.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    SteeringGains
        Broadcast over the array arguments (and the operating points of a
        :class:`LateralPlant`).

    Raises
    ------
    UncontrollableError
        If :math:`(\mathbf A, \mathbf B[1, a]^T)` is (nearly) uncontrollable,
        e.g. ``ratio = 1`` on a straight path: then ``delta_r = delta_f``,
        the yaw rate is identically zero and the characteristic polynomial is
        :math:`\lambda(\lambda + V k_1)`, so no double root
        :math:`\lambda_0 \ne 0` exists.
    ValueError
        For a plant that does not have two states, a `pole` that is not
        finite and negative, or a non-finite `ratio`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    >>> round(g.k1, 6), round(g.k2, 6)
    (0.054, 0.6129)
    >>> fws.double_root_gains(plant, ratio=1.0, pole=-1.0)
    Traceback (most recent call last):
        ...
    fws_control.exceptions.UncontrollableError: ratio=1.0 with curvature=0.0 makes ...
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    ratio = resolve_ratio(p, ratio)
    a = check_finite("ratio", ratio)
    lam = check_finite("pole", pole)
    if np.any(np.asarray(lam) >= 0):
        raise ValueError(f"pole must be finite and < 0, got {pole!r}")
    cp = characteristic_coefficients(p, ratio=a)
    if cp.order != 2:
        raise ValueError(
            f"double_root_gains needs a 2-state plant, got one of order {cp.order}: "
            "two gains on e and theta cannot place a double root and fix the "
            "other poles. Choose (k1, k2) from stability_chart or parameter_locus; "
            "control.place on (A, B[:, delta_f] + a*B[:, delta_r]) gives a full "
            "state feedback, a different controller"
            + (
                "; for model='dynamic', design on the kinematic plant "
                "(replace(plant, model='exact')) and check the design here"
                if isinstance(p, LateralPlant) and p.model == "dynamic"
                else ""
            )
        )
    a1, b1, g1 = cp.n1[..., 1], cp.n2[..., 1], cp.open_loop[..., 1]
    a0, b0, g0 = cp.n1[..., 2], cp.n2[..., 2], cp.open_loop[..., 2]
    det = a1 * b0 - b1 * a0
    if isinstance(p, LateralPlant):
        # det = -(V^3/f^2) * distance, distance = a^2 f^2 kappa^2 + (c - a)^2:
        # dimensionless, zero exactly at the uncontrollable design.
        V = np.asarray(p.speed, dtype=float)
        distance = -det * p.vehicle.wheelbase**2 / V**3
        kappa = p.curvature
    else:
        scale = np.hypot(a1, a0) * np.hypot(b1, b0)
        with np.errstate(divide="ignore", invalid="ignore"):
            distance = np.where(scale > 0, np.abs(det) / scale, 0.0)
        kappa = None
    singular = np.asarray(distance) <= _SINGULAR_DISTANCE
    if np.any(singular):
        worst = float(np.min(distance))
        if worst == 0.0:
            why = (
                "makes (A, B[1, a]^T) uncontrollable"
                if kappa is None
                else "makes delta_r = delta_f: the yaw rate is identically zero, "
                "the heading is uncontrollable and D(lambda) = lambda*(lambda + "
                f"V*k1), so no double root pole={pole!r} != 0 exists"
            )
        else:
            why = (
                f"is nearly uncontrollable: relative distance {worst:.3g} <= "
                f"{_SINGULAR_DISTANCE:g}; the gains grow like its inverse and would "
                "be meaningless"
            )
            if kappa is not None:
                why += " (delta_r = delta_f on a straight path is uncontrollable)"
        where = f"ratio={ratio!r}" + (
            "" if kappa is None else f" with curvature={kappa!r}"
        )
        raise UncontrollableError(f"{where} {why}")
    r1 = -2.0 * np.asarray(lam) - g1
    r0 = np.asarray(lam) ** 2 - g0
    k1 = (r1 * b0 - b1 * r0) / det
    k2 = (a1 * r0 - r1 * a0) / det
    k1, k2, a_b = np.broadcast_arrays(k1, k2, a)
    return SteeringGains(k1=k1, k2=k2, ratio=a_b)
