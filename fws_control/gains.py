"""Feedback gains of the structured 4WS controller, paper eqs. (28)-(29), (33)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validation import check_finite

__all__ = ["SteeringGains"]


@dataclass(frozen=True)
class SteeringGains:
    r"""Feedback gains with the rear gains tied to the front ones.

    The control law is (paper eqs. 28-29)

    .. math::
        \delta_f^{FB} = -k_1 e - k_2\theta,\qquad
        \delta_r^{FB} = -k_3 e - k_4\theta,\qquad k_3 = a k_1,\ k_4 = a k_2,

    so that :math:`\delta_r^{FB} = a\,\delta_f^{FB}`.

    Parameters
    ----------
    k1 : float or array_like
        Lateral-error gain [rad/m].
    k2 : float or array_like
        Heading-error gain [rad/rad].
    ratio : float or array_like
        Rear-to-front steering ratio :math:`a` (``delta_r = ratio*delta_f``);
        0 is front-wheel steering.

    Arrays broadcast, so one object can hold a whole sweep of designs.

    Examples
    --------
    >>> import fws_control as fws
    >>> g = fws.SteeringGains(k1=0.2, k2=0.5, ratio=-1.0)
    >>> g.k3, g.k4
    (-0.2, -0.5)
    >>> g.matrix
    array([[-0.2, -0.5],
           [ 0.2,  0.5]])
    """

    k1: float | np.ndarray
    k2: float | np.ndarray
    ratio: float | np.ndarray

    def __post_init__(self) -> None:
        for name in ("k1", "k2", "ratio"):
            object.__setattr__(self, name, check_finite(name, getattr(self, name)))

    @property
    def k3(self) -> float | np.ndarray:
        """Rear lateral-error gain :math:`k_3 = a k_1`."""
        return self.ratio * self.k1

    @property
    def k4(self) -> float | np.ndarray:
        """Rear heading-error gain :math:`k_4 = a k_2`."""
        return self.ratio * self.k2

    @property
    def matrix(self) -> np.ndarray:
        r"""The feedback matrix :math:`\mathbf{K}` of eq. (33), ``u = K x``.

        Shape ``(..., 2, 2)``: rows ``delta_f, delta_r``; columns ``e, theta``.
        """
        k1, k2, k3, k4 = np.broadcast_arrays(self.k1, self.k2, self.k3, self.k4)
        return -np.stack(
            [np.stack([k1, k2], axis=-1), np.stack([k3, k4], axis=-1)], axis=-2
        )

    def steering(self, e, theta) -> tuple[np.ndarray, np.ndarray]:
        """Feedback steering angles ``(delta_f_fb, delta_r_fb)`` for errors."""
        delta_f = -self.k1 * np.asarray(e) - self.k2 * np.asarray(theta)
        return delta_f, self.ratio * delta_f
