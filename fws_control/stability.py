r"""Routh-Hurwitz stability of the linear closed loop, paper section 4.1.

For the second-order characteristic polynomial
:math:`\lambda^2 + p_1\lambda + p_0` both roots lie in the open left half
plane iff :math:`p_1 > 0` and :math:`p_0 > 0` (eqs. 35-36). Both are affine
in ``(k1, k2)`` (see :func:`~fws_control.characteristic_coefficients`), so
each boundary is a straight line in the gain plane and the tests are closed
form on arrays.

The lines :math:`p_1 = 0` and :math:`p_0 = 0` do not depend on the speed
(``V`` only scales them), but the stable *side* of :math:`p_1 = 0` does:
for ``V < 0`` (reversing) :math:`p_1` changes sign, so condition (35) flips
while (36), which carries :math:`V^2`, does not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validation import check_finite
from .linear import characteristic_coefficients
from .vehicle import Vehicle

__all__ = ["is_stable", "StabilityBoundary", "stability_boundaries"]


def is_stable(
    vehicle: Vehicle, speed, curvature, k1, k2, ratio, model: str = "exact"
) -> bool | np.ndarray:
    """Asymptotic stability of the linear closed loop (Routh-Hurwitz).

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed, curvature : float or array_like
        Speed [m/s] (nonzero) and path curvature [1/m].
    k1, k2, ratio : float or array_like
        Gains and rear-to-front ratio; all arguments broadcast, so a grid of
        gains is one call.
    model : {"exact", "paper"}, optional
        Linearisation, see :func:`linearize`.

    Returns
    -------
    bool or ndarray of bool
        True where both closed-loop poles have negative real part. Points on
        a boundary (a zero coefficient) are not stable.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> fws.is_stable(veh, 5.0, 0.0, k1=0.1, k2=0.5, ratio=0.0)
    True
    >>> k1, k2 = np.meshgrid(np.linspace(-1, 1, 3), np.linspace(-1, 1, 3))
    >>> fws.is_stable(veh, 5.0, 0.0, k1, k2, ratio=0.0).astype(int)
    array([[0, 0, 0],
           [0, 0, 0],
           [0, 0, 1]])
    """
    cc = characteristic_coefficients(vehicle, speed, curvature, ratio, model)
    k1 = check_finite("k1", k1)
    k2 = check_finite("k2", k2)
    out = (cc.p1(k1, k2) > 0) & (cc.p0(k1, k2) > 0)
    return bool(out) if np.ndim(out) == 0 else out


@dataclass(frozen=True)
class StabilityBoundary:
    r"""One Routh-Hurwitz boundary in the ``(k1, k2)`` plane.

    The set ``alpha*k1 + beta*k2 + gamma = 0``; the condition holds (stable
    side) where ``alpha*k1 + beta*k2 + gamma > 0``. Coefficients are
    normalised so that ``hypot(alpha, beta) == 1`` unless the line is
    degenerate (then ``alpha = beta = 0`` and ``gamma`` is the sign of the
    gain-independent coefficient).

    Attributes
    ----------
    alpha, beta, gamma : float
        Line coefficients.
    condition : str
        ``"p1 > 0 (eq. 35)"`` or ``"p0 > 0 (eq. 36)"``.
    """

    alpha: float
    beta: float
    gamma: float
    condition: str

    @property
    def degenerate(self) -> bool:
        r"""True when the condition does not depend on the gains.

        Then there is no line: the condition holds everywhere (``always``)
        or nowhere, as for ``p0`` with ``a = 1`` on a straight path, where
        :math:`p_0 \equiv 0`.
        """
        return self.alpha == 0.0 and self.beta == 0.0

    @property
    def always(self) -> bool | None:
        """For a degenerate boundary, whether its condition always holds."""
        if not self.degenerate:
            return None
        return bool(self.gamma > 0)

    def satisfied(self, k1, k2) -> bool | np.ndarray:
        """True where this condition holds strictly (broadcasts)."""
        out = self.alpha * np.asarray(k1) + self.beta * np.asarray(k2) + self.gamma > 0
        return bool(out) if np.ndim(out) == 0 else out

    @property
    def vertical(self) -> bool:
        """True for a line ``k1 = const`` (``beta == 0``)."""
        return self.beta == 0.0 and self.alpha != 0.0

    def k2_at(self, k1) -> np.ndarray:
        """``k2`` on the line for given ``k1`` (not for vertical lines)."""
        if self.beta == 0.0:
            raise ValueError(
                f"boundary {self.condition} is vertical or degenerate: use k1_at"
            )
        return -(self.alpha * np.asarray(k1, dtype=float) + self.gamma) / self.beta

    def k1_at(self, k2) -> np.ndarray:
        """``k1`` on the line for given ``k2`` (not for horizontal lines)."""
        if self.alpha == 0.0:
            raise ValueError(
                f"boundary {self.condition} is horizontal or degenerate: use k2_at"
            )
        return -(self.beta * np.asarray(k2, dtype=float) + self.gamma) / self.alpha

    def segment(self, k1_range, k2_range) -> np.ndarray | None:
        """End points of the part of the line inside a rectangle.

        Returns an array ``[[k1a, k2a], [k1b, k2b]]`` or None if the line
        misses the rectangle (or is degenerate).
        """
        if self.degenerate:
            return None
        (x0, x1), (y0, y1) = sorted(k1_range), sorted(k2_range)
        pts = []
        if self.beta != 0.0:
            for x in (x0, x1):
                y = float(self.k2_at(x))
                if y0 <= y <= y1:
                    pts.append((x, y))
        if self.alpha != 0.0:
            for y in (y0, y1):
                x = float(self.k1_at(y))
                if x0 <= x <= x1:
                    pts.append((x, y))
        pts = sorted(set(pts))
        if len(pts) < 2:
            return None
        return np.array([pts[0], pts[-1]])


def stability_boundaries(
    vehicle: Vehicle,
    speed: float,
    curvature: float,
    ratio: float,
    model: str = "exact",
) -> tuple[StabilityBoundary, StabilityBoundary]:
    r"""Both Routh-Hurwitz boundary lines in the ``(k1, k2)`` plane.

    In the paper's notation (eq. 37, with ``(c-a)`` for ``(1-a)`` in the exact
    model) the lines are

    .. math::
        f a k_1 + (c-a) k_2 = 0 \quad (p_1 = 0),\qquad
        (c-a) k_1 - a f\kappa^2 k_2 + f\kappa^2 = 0 \quad (p_0 = 0).

    For ``a = c`` (``a = 1`` on a straight path) the first is ``k1 = 0``
    (eq. 38); on a curved path the second then reads ``k2 = 1/a`` — with
    ``a = 1`` in the paper's model ``k2 < 1`` is still required, so eq. (38)'s
    "any k2" holds only on a straight path. On a straight path with ``a = 1``
    the second is degenerate (:math:`p_0 \equiv 0`, never stable).

    Parameters
    ----------
    vehicle : Vehicle
    speed : float
        Nonzero speed [m/s]; its sign decides the stable side of ``p1 = 0``
        (the line itself does not depend on it).
    curvature, ratio : float
    model : {"exact", "paper"}, optional

    Returns
    -------
    (StabilityBoundary, StabilityBoundary)
        The ``p1 = 0`` and ``p0 = 0`` boundaries.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> b1, b0 = fws.stability_boundaries(veh, 5.0, 0.1, ratio=1.0, model="paper")
    >>> round(float(b0.k2_at(0.3)), 12)       # the line k2 = 1 of erratum 4
    1.0
    """
    cc = characteristic_coefficients(vehicle, speed, curvature, ratio, model)
    out = []
    for alpha, beta, gamma, cond in (
        (cc.alpha1, cc.beta1, cc.gamma1, "p1 > 0 (eq. 35)"),
        (cc.alpha0, cc.beta0, cc.gamma0, "p0 > 0 (eq. 36)"),
    ):
        alpha, beta, gamma = float(alpha), float(beta), float(gamma)
        norm = float(np.hypot(alpha, beta))
        # No tolerance: a = c on a straight path cancels to an exact 0.0, and
        # any fuzz would make the lines disagree with is_stable near them.
        if norm == 0.0:
            out.append(StabilityBoundary(0.0, 0.0, float(np.sign(gamma)), cond))
            continue
        out.append(StabilityBoundary(alpha / norm, beta / norm, gamma / norm, cond))
    return out[0], out[1]
