"""Feedback gains of the structured 4WS controller, paper eqs. (28)-(29), (33)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .hints import RealArrayLike
from .reprs import value_repr
from .validation import check_finite

__all__ = ["SteeringGains"]


@value_repr
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

    Notes
    -----
    Arrays broadcast, so one object can hold a whole sweep of designs. In a
    sweep where some designs do not exist
    (:func:`~fws_control.double_root_gains` with
    ``uncontrollable="mask"``), `k1` and `k2` are
    :class:`numpy.ma.MaskedArray`\ s: masked (and NaN underneath) where
    there is no design, finite elsewhere; matplotlib leaves the masked
    points out of a plot.

    Examples
    --------
    >>> import fws_control as fws
    >>> g = fws.SteeringGains(k1=0.2, k2=0.5, ratio=-1.0)
    >>> g.k3, g.k4
    (-0.2, -0.5)
    >>> g.K
    array([[ 0.2,  0.5],
           [-0.2, -0.5]])
    >>> g.K_paper[0]
    array([-0.2, -0.5])
    """

    k1: float | np.ndarray
    k2: float | np.ndarray
    ratio: float | np.ndarray

    def __post_init__(self) -> None:
        for name in ("k1", "k2", "ratio"):
            value = getattr(self, name)
            if name != "ratio" and np.ma.isMaskedArray(value):
                # a sweep with designs that do not exist: the masked entries
                # hold NaN (so that reading the data without the mask cannot
                # pass for a design), the others must be finite
                mask = np.ma.getmaskarray(value)
                data = np.asarray(
                    check_finite(name, np.ma.filled(value.astype(float), 0.0))
                )
                value = np.ma.masked_array(np.where(mask, np.nan, data), mask=mask)
            else:
                value = check_finite(name, value)
            object.__setattr__(self, name, value)

    @property
    def k3(self) -> float | np.ndarray:
        """Rear lateral-error gain :math:`k_3 = a k_1`."""
        return self.ratio * self.k1

    @property
    def k4(self) -> float | np.ndarray:
        """Rear heading-error gain :math:`k_4 = a k_2`."""
        return self.ratio * self.k2

    @property
    def K(self) -> np.ndarray:
        r"""Feedback matrix in python-control's sign, ``u = -K y``.

        .. math:: \mathbf K = \begin{bmatrix}k_1 & k_2\\ a k_1 & a k_2\end{bmatrix}

        Shape ``(..., 2, 2)``: rows ``delta_f, delta_r``; columns ``e,
        theta``. This is what :func:`control.place` and :func:`control.lqr`
        return for a plant with these inputs and states, so the two compare
        without a sign change.
        """
        k1, k2, k3, k4 = np.broadcast_arrays(self.k1, self.k2, self.k3, self.k4)
        return np.stack(
            [np.stack([k1, k2], axis=-1), np.stack([k3, k4], axis=-1)], axis=-2
        )

    @property
    def K_paper(self) -> np.ndarray:
        r"""Feedback matrix in the paper's sign, ``u = K_paper x`` (eq. 33).

        :math:`\mathbf K_{paper} = -\mathbf K`, i.e. ``-[[k1, k2], [k3, k4]]``.
        """
        return -self.K

    @classmethod
    def from_K(
        cls, K: RealArrayLike, *, ratio: RealArrayLike | None = None, rtol: float = 1e-9
    ) -> SteeringGains:
        r"""Gains from a python-control feedback matrix (``u = -K y``).

        Parameters
        ----------
        K : array_like
            Either the ``1 x 2`` (or length-2) row ``[k1, k2]`` of a
            single-input design on :math:`(\mathbf A, \mathbf B[1, a]^T)`,
            e.g. from :func:`control.acker`; then `ratio` is required. Or the
            ``2 x 2`` matrix of both steering inputs, which must have the
            structure ``[[k1, k2], [a k1, a k2]]``.
        ratio : float, optional
            The ratio :math:`a` for a single row.
        rtol : float, optional
            Relative tolerance of the rank-one structure check.

        Returns
        -------
        SteeringGains

        Raises
        ------
        ValueError
            If `K` has another shape, lacks `ratio`, or is not of the rank-one
            form (then the feedback cannot be written with one ratio ``a``).

        Examples
        --------
        >>> import fws_control as fws
        >>> fws.SteeringGains.from_K([[0.2, 0.5], [-0.2, -0.5]])
        SteeringGains(k1=0.2, k2=0.5, ratio=-1.0)
        >>> fws.SteeringGains.from_K([[0.2, 0.5]], ratio=0.5).k4
        0.25
        """
        arr = np.asarray(check_finite("K", K), dtype=float)
        if arr.size == 2 and arr.ndim <= 2:
            if ratio is None:
                raise ValueError(
                    "a single row K = [k1, k2] needs ratio= (the rear-to-front "
                    "steering ratio it was designed for)"
                )
            row = arr.ravel()
            return cls(float(row[0]), float(row[1]), check_finite("ratio", ratio))
        if arr.shape != (2, 2):
            raise ValueError(
                f"K must be a 1 x 2 row or a 2 x 2 matrix, got shape {arr.shape}"
            )
        if ratio is not None:
            raise ValueError("ratio= is only for a single row K; a 2 x 2 K fixes it")
        front, rear = arr
        scale = float(np.max(np.abs(front)))
        if scale == 0.0:
            raise ValueError(
                f"K's front row must be nonzero to define a ratio, got K={arr.tolist()}"
            )
        j = int(np.argmax(np.abs(front)))
        a = float(rear[j] / front[j])
        if np.max(np.abs(rear - a * front)) > rtol * max(scale, abs(a) * scale):
            raise ValueError(
                "K must have the rank-one form [[k1, k2], [a*k1, a*k2]] "
                f"(delta_r = a*delta_f), got K={arr.tolist()}: use the "
                "two-input feedback directly"
            )
        return cls(float(front[0]), float(front[1]), a)

    def steering(
        self, e: RealArrayLike, theta: RealArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Feedback steering angles ``(delta_f_fb, delta_r_fb)`` for errors.

        Parameters
        ----------
        e : float or array_like
            Lateral error [m], finite (positive: left of the path).
        theta : float or array_like
            Heading error [rad], finite; broadcasts with `e` and the gains.

        Returns
        -------
        delta_f_fb, delta_r_fb : ndarray
            :math:`-k_1 e - k_2\\theta` and `ratio` times it [rad], without
            the curvature feedforward or any steering limit.

        Examples
        --------
        >>> import fws_control as fws
        >>> g = fws.SteeringGains(k1=0.2, k2=0.5, ratio=-1.0)
        >>> [float(d) for d in g.steering(1.0, 0.1)]
        [-0.25, 0.25]
        """
        delta_f = -self.k1 * np.asarray(e) - self.k2 * np.asarray(theta)
        return delta_f, self.ratio * delta_f
