r"""Stability of the structured steering loop for plants of any order.

The closed-loop characteristic polynomial is affine in the gains,
:math:`p(s) = d(s) + k_1 n_1(s) + k_2 n_2(s)`
(:func:`~fws_control.characteristic_coefficients`), so

* **stability** on whole arrays of gains is a vectorised Routh-Hurwitz test
  on the coefficient arrays (:func:`routh_hurwitz`); for the second-order
  kinematic plant it reduces to the closed form :math:`p_1 > 0,\ p_0 > 0`
  (eqs. 35-36), kept as the fast path;
* the **boundaries** in the ``(k1, k2)`` plane follow from D-subdivision: a
  root crosses the imaginary axis either at ``s = 0`` — the straight line
  :math:`p(0) = 0` — or at :math:`s = \pm j\omega` — the curve that solves
  the 2 x 2 linear system :math:`\operatorname{Re} p(j\omega) =
  \operatorname{Im} p(j\omega) = 0` for ``(k1, k2)`` at each
  :math:`\omega > 0` (:func:`stability_boundaries`).

For the kinematic plant the curve is the ray of the line :math:`p_1 = 0` on
which :math:`p_0 = \omega^2 > 0`. The lines :math:`p_1 = 0` and
:math:`p_0 = 0` do not depend on the speed (``V`` only scales them), but the
stable *side* of :math:`p_1 = 0` does: for ``V < 0`` (reversing) condition
(35) flips while (36), which carries :math:`V^2`, does not.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .delay import unstable_root_count
from .gains import SteeringGains
from .linear import AffinePolynomial, characteristic_coefficients, check_gains
from .plant import LateralPlant, as_plant, resolve_ratio
from .reprs import summary_repr
from .validation import (
    MAX_RATIO,
    check_delay,
    check_finite,
    check_magnitude,
    check_scalar,
)

__all__ = [
    "is_stable",
    "routh_hurwitz",
    "hurwitz_columns",
    "StabilityBoundary",
    "BoundaryCurve",
    "StabilityBoundaries",
    "stability_boundaries",
    "default_frequencies",
    "complex_root_curve",
]


def routh_hurwitz(coefficients) -> bool | np.ndarray:
    r"""Hurwitz test of polynomials on the last axis, vectorised.

    True where every root has a negative real part. The first column of the
    Routh array is computed for all polynomials at once (a Python loop over
    the order only); a polynomial is Hurwitz iff that column has no zero and
    no sign change. A zero in it (a root on the imaginary axis, or a
    singular array) counts as not stable, so boundary points are never
    stable.

    Parameters
    ----------
    coefficients : array_like
        Shape ``(..., n + 1)``, highest power first, nonzero leading
        coefficient.

    Returns
    -------
    bool or ndarray of bool
        Shape ``(...)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.stability import routh_hurwitz
    >>> routh_hurwitz(np.poly([-1.0, -2.0, -3.0]))
    True
    >>> routh_hurwitz([[1.0, 1.0, 1.0, 1.0], [1.0, 2.0, 2.0, 1.0]]).tolist()
    [False, True]
    """
    c = np.asarray(coefficients, dtype=float)
    if c.ndim == 0 or c.shape[-1] < 2:
        raise ValueError(
            f"coefficients must have at least 2 entries on the last axis, got "
            f"shape {c.shape}"
        )
    out = hurwitz_columns([c[..., j] for j in range(c.shape[-1])])
    return bool(out) if np.ndim(out) == 0 else out


def hurwitz_columns(columns) -> np.ndarray:
    """:func:`routh_hurwitz` on coefficients given as a list of arrays.

    ``columns[j]`` holds the coefficient of :math:`s^{n-j}` for every
    polynomial (arrays that broadcast). Working on whole contiguous arrays,
    one per Routh-array entry, keeps the cost at about :math:`n^2/4`
    array operations.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.stability import hurwitz_columns
    >>> hurwitz_columns([1.0, np.array([1.0, 2.0]), 1.0, 1.0]).tolist()
    [False, True]
    """
    cols = np.broadcast_arrays(*(np.asarray(c, dtype=float) for c in columns))
    sign = np.sign(cols[0])
    upper = [c * sign for c in cols[0::2]]
    lower = [c * sign for c in cols[1::2]]
    ok = upper[0] > 0
    finite = np.ones(ok.shape, dtype=bool)
    for c in cols:
        finite &= np.isfinite(c)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(len(cols) - 1):
            pivot = lower[0]
            ok &= pivot > 0
            ratio = upper[0] / pivot
            new = [
                upper[j + 1] - ratio * (lower[j + 1] if j + 1 < len(lower) else 0.0)
                for j in range(len(upper) - 1)
            ]
            upper, lower = lower, new if new else [np.zeros_like(pivot)]
    return ok & finite


#: Relative rounding bound of a coefficient ``d_j + k1 n1_j + k2 n2_j``
#: (three terms, two products): a few units of the machine epsilon.
_ROUNDING = 8 * np.finfo(float).eps


def _stable_from_polynomial(cp: AffinePolynomial, k1, k2) -> bool | np.ndarray:
    cols = [
        cp.open_loop[..., j] + k1 * cp.n1[..., j] + k2 * cp.n2[..., j]
        for j in range(cp.order + 1)
    ]
    # A coefficient within rounding of zero is zero: a point on a boundary line
    # (p1 = 0 or p0 = 0) must not come out stable by a floating-point tie. The
    # bound uses the largest gains asked, so it costs no extra pass over a grid.
    big1 = float(np.max(np.abs(k1), initial=0.0))
    big2 = float(np.max(np.abs(k2), initial=0.0))
    tol = [
        _ROUNDING
        * float(
            np.max(
                np.abs(cp.open_loop[..., j])
                + big1 * np.abs(cp.n1[..., j])
                + big2 * np.abs(cp.n2[..., j]),
                initial=0.0,
            )
        )
        for j in range(cp.order + 1)
    ]
    if cp.order == 2:
        # Closed form of eqs. (35)-(36); monic, so p1 > 0 and p0 > 0.
        out = (cols[1] > tol[1]) & (cols[2] > tol[2])
    else:
        out = hurwitz_columns(cols)
        for c, t in zip(cols[1:], tol[1:], strict=True):
            out &= c > t  # every coefficient of a Hurwitz polynomial is > 0
    return bool(out) if np.ndim(out) == 0 else out


def is_stable(
    plant: Any,
    gains: SteeringGains,
    *,
    delay: float = 0.0,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> bool | np.ndarray:
    """Asymptotic stability of the linear closed loop.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), of any order.
    gains : SteeringGains
        Gains and ratio; arrays broadcast with each other and with the
        operating points of a :class:`LateralPlant`, so a whole grid is one
        call.
    delay : float, optional
        Input delay on the steering command [s], >= 0. With a delay the
        verdict is the root count of
        :func:`~fws_control.delay.unstable_root_count` (one operating point,
        scalar ratio); undecided points (a root on the axis) are not stable.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    bool or ndarray of bool
        True where every closed-loop pole has a negative real part (closed
        form for two states, :func:`routh_hurwitz` otherwise). Points on a
        boundary (a pole on the imaginary axis) are not stable.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> fws.is_stable(plant, fws.SteeringGains(0.1, 0.5, ratio=0.0))
    True
    >>> k1, k2 = np.meshgrid(np.linspace(-1, 1, 3), np.linspace(-1, 1, 3))
    >>> fws.is_stable(plant, fws.SteeringGains(k1, k2, ratio=0.0)).astype(int)
    array([[0, 0, 0],
           [0, 0, 0],
           [0, 0, 1]])
    """
    g = check_gains(gains)
    if check_delay(delay) > 0.0:
        count = unstable_root_count(
            plant, g, delay=delay, speed=speed, curvature=curvature, model=model
        )
        out = count == 0
        return bool(out) if out.ndim == 0 else out
    cp = characteristic_coefficients(
        plant, ratio=g.ratio, speed=speed, curvature=curvature, model=model
    )
    return _stable_from_polynomial(cp, np.asarray(g.k1), np.asarray(g.k2))


@dataclass(frozen=True)
class StabilityBoundary:
    r"""A straight boundary in the ``(k1, k2)`` plane.

    The set ``alpha*k1 + beta*k2 + gamma = 0``; its condition holds where
    ``alpha*k1 + beta*k2 + gamma > 0``. Coefficients are normalised so that
    ``hypot(alpha, beta) == 1`` unless the line is degenerate (then ``alpha
    = beta = 0`` and ``gamma`` is the sign of the gain-independent
    coefficient).

    Attributes
    ----------
    alpha, beta, gamma : float
        Line coefficients.
    condition : str
        The coefficient condition, e.g. ``"p0 > 0"``.

    Examples
    --------
    >>> import fws_control as fws
    >>> b = fws.StabilityBoundary(1.0, 0.0, -0.5, "p0 > 0")
    >>> b.vertical, float(b.k1_at(3.0)), b.satisfied(1.0, 0.0)
    (True, 0.5, True)
    """

    alpha: float
    beta: float
    gamma: float
    condition: str

    def __post_init__(self) -> None:
        # finite real scalars and a text condition (issue 13: NaN and bools
        # were stored)
        for f in ("alpha", "beta", "gamma"):
            object.__setattr__(self, f, check_scalar(f, getattr(self, f)))
        if not isinstance(self.condition, str):
            raise TypeError(
                f"condition must be a str such as 'p0 > 0', got {self.condition!r}"
            )

    @classmethod
    def from_coefficients(cls, alpha, beta, gamma, condition: str) -> StabilityBoundary:
        """Normalised boundary from raw coefficients (scalars).

        Parameters
        ----------
        alpha : float
            Coefficient of ``k1`` (per rad/m), finite.
        beta : float
            Coefficient of ``k2`` (per rad/rad), finite.
        gamma : float
            Gain-independent term, finite. Only the ratios of `alpha`,
            `beta` and `gamma` matter: the three are divided by
            ``hypot(alpha, beta)``; with ``alpha = beta = 0`` the boundary
            is degenerate and keeps only the sign of `gamma`.
        condition : str
            The coefficient condition the line bounds, e.g. ``"p0 > 0"``.

        Returns
        -------
        StabilityBoundary

        Examples
        --------
        >>> import fws_control as fws
        >>> fws.StabilityBoundary.from_coefficients(3.0, 4.0, -5.0, "p1 > 0")
        StabilityBoundary(alpha=0.6, beta=0.8, gamma=-1.0, condition='p1 > 0')
        """
        alpha, beta, gamma = float(alpha), float(beta), float(gamma)
        norm = float(np.hypot(alpha, beta))
        # No tolerance: a = c on a straight path cancels to an exact 0.0, and
        # any fuzz would make the lines disagree with is_stable near them.
        if norm == 0.0:
            return cls(0.0, 0.0, float(np.sign(gamma)), condition)
        return cls(alpha / norm, beta / norm, gamma / norm, condition)

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
        """True where this condition holds strictly (broadcasts).

        Parameters
        ----------
        k1 : float or array_like
            Lateral-error gains [rad/m], finite.
        k2 : float or array_like
            Heading-error gains [rad/rad], finite; broadcasts with `k1`.

        Returns
        -------
        bool or ndarray of bool
            ``alpha*k1 + beta*k2 + gamma > 0``; a bool for scalar gains.
        """
        out = self.alpha * np.asarray(k1) + self.beta * np.asarray(k2) + self.gamma > 0
        return bool(out) if np.ndim(out) == 0 else out

    @property
    def vertical(self) -> bool:
        """True for a line ``k1 = const`` (``beta == 0``)."""
        return self.beta == 0.0 and self.alpha != 0.0

    def k2_at(self, k1) -> np.ndarray:
        """``k2`` on the line for given ``k1`` (not for vertical lines).

        Parameters
        ----------
        k1 : float or array_like
            Lateral-error gains [rad/m], finite.

        Returns
        -------
        ndarray
            Heading-error gains ``k2`` [rad/rad] on the line, same shape.

        Raises
        ------
        ValueError
            If the line is vertical (``beta == 0``) or degenerate.
        """
        if self.beta == 0.0:
            raise ValueError(
                f"boundary {self.condition} is vertical or degenerate: use k1_at"
            )
        return -(self.alpha * np.asarray(k1, dtype=float) + self.gamma) / self.beta

    def k1_at(self, k2) -> np.ndarray:
        """``k1`` on the line for given ``k2`` (not for horizontal lines).

        Parameters
        ----------
        k2 : float or array_like
            Heading-error gains [rad/rad], finite.

        Returns
        -------
        ndarray
            Lateral-error gains ``k1`` [rad/m] on the line, same shape.

        Raises
        ------
        ValueError
            If the line is horizontal (``alpha == 0``) or degenerate.
        """
        if self.alpha == 0.0:
            raise ValueError(
                f"boundary {self.condition} is horizontal or degenerate: use k2_at"
            )
        return -(self.beta * np.asarray(k2, dtype=float) + self.gamma) / self.alpha

    def segment(self, k1_range, k2_range) -> np.ndarray | None:
        """End points of the part of the line inside a rectangle.

        Parameters
        ----------
        k1_range : (float, float)
            The rectangle's ``k1`` interval [rad/m], finite, in either order.
        k2_range : (float, float)
            The rectangle's ``k2`` interval [rad/rad], finite, in either
            order.

        Returns
        -------
        ndarray or None
            ``[[k1a, k2a], [k1b, k2b]]``, sorted by ``k1``, or None if the
            line misses the rectangle (or is degenerate).

        Examples
        --------
        >>> import fws_control as fws
        >>> b = fws.StabilityBoundary(0.6, 0.8, -1.0, "p1 > 0")
        >>> b.segment((-1.0, 1.0), (-1.0, 1.0)).round(4)
        array([[0.3333, 1.    ],
               [1.    , 0.5   ]])
        >>> print(b.segment((-1.0, 0.0), (-1.0, 0.0)))
        None
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


@summary_repr
@dataclass(frozen=True, eq=False)
class BoundaryCurve:
    r"""The complex-root boundary: gains that put a root pair at ``±jω``.

    Attributes
    ----------
    omega : ndarray
        Crossing frequencies :math:`\omega > 0` [rad/s], increasing.
    k1, k2 : ndarray
        Gains on the curve; NaN where the 2 x 2 system is singular (there the
        curve leaves to infinity or is not unique), which splits it into
        branches.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> b = fws.stability_boundaries(fws.LateralPlant(veh, speed=5.0), ratio=0.0,
    ...                              omega=[1.0, 2.0])
    >>> b.complex_root.k1.round(6), b.complex_root.k2
    (array([0.108, 0.432]), array([0., 0.]))
    """

    omega: np.ndarray
    k1: np.ndarray
    k2: np.ndarray

    def branches(self) -> list[np.ndarray]:
        """The finite runs of the curve, each an array of shape ``(m, 3)``.

        Columns ``omega, k1, k2``.
        """
        pts = np.column_stack([self.omega, self.k1, self.k2])
        good = np.all(np.isfinite(pts), axis=1)
        edges = np.flatnonzero(np.diff(np.concatenate([[0], good, [0]])))
        return [pts[a:b] for a, b in zip(edges[::2], edges[1::2], strict=True)]


@summary_repr
@dataclass(frozen=True, eq=False)
class StabilityBoundaries:
    r"""D-subdivision boundaries of the stable set in the ``(k1, k2)`` plane.

    Attributes
    ----------
    real_root : StabilityBoundary
        The line :math:`p(0) = 0` (a real root at ``s = 0``), condition
        ``"p0 > 0"`` (constant coefficient positive).
    complex_root : BoundaryCurve
        The curve :math:`p(\pm j\omega) = 0`, :math:`\omega > 0`.
    lines : tuple of StabilityBoundary
        Straight boundaries: for two states the Routh-Hurwitz lines
        ``p1 = 0`` (eq. 35) and ``p0 = 0`` (eq. 36), on which the complex
        curve is a ray; otherwise ``(real_root,)``.
    order : int
        Order ``n`` of the closed loop.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> b = fws.stability_boundaries(veh, speed=5.0, curvature=0.1, ratio=1.0,
    ...                              model="paper")
    >>> p1, p0 = b.lines
    >>> round(float(p0.k2_at(0.3)), 12)       # the line k2 = 1 of erratum 4
    1.0
    """

    real_root: StabilityBoundary
    complex_root: BoundaryCurve
    lines: tuple[StabilityBoundary, ...]
    order: int

    def __iter__(self):
        # unpacking gives the straight lines, as stability_boundaries did in 0.1
        return iter(self.lines)


def default_frequencies(cp: AffinePolynomial, num: int = 2001) -> np.ndarray:
    """Logarithmic frequency grid covering the plant's time scales [rad/s].

    From ``1e-3`` times the smallest to ``1e3`` times the largest nonzero
    root magnitude of the open loop and of :math:`n_1, n_2` (1 rad/s
    included). Leading coefficients that are negligible against the others
    (below 1e-9 of the largest) are dropped first: they stand for roots near
    infinity (e.g. ``n1``'s ``V a`` for a tiny ratio), not for a time scale.
    At least 200 points per decade.

    Parameters
    ----------
    cp : AffinePolynomial
        Characteristic polynomial of one operating point.
    num : int, optional
        Minimum number of frequencies.

    Returns
    -------
    ndarray
        Increasing frequencies [rad/s].

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> cp = fws.characteristic_coefficients(veh, speed=5.0, ratio=0.0)
    >>> w = fws.stability.default_frequencies(cp, num=5)
    >>> float(w[0]), float(w[-1])
    (0.001, 1000.0)
    """
    lo = hi = 1.0
    for c in (cp.open_loop, cp.n1, cp.n2):
        c = np.asarray(c, dtype=float).reshape(-1, c.shape[-1])[0]
        big = float(np.max(np.abs(c), initial=0.0))
        if big == 0.0:
            continue
        keep = np.flatnonzero(np.abs(c) > 1e-9 * big)
        c = c[keep[0] :]
        if c.size > 1:
            r = np.abs(np.roots(c))
            r = r[r > 1e-9 * max(1.0, float(np.max(r, initial=0.0)))]
            if r.size:
                lo = min(lo, float(np.min(r)))
                hi = max(hi, float(np.max(r)))
    decades = np.log10(hi / lo) + 6.0
    return np.geomspace(1e-3 * lo, 1e3 * hi, max(int(num), int(200 * decades)))


def complex_root_curve(
    cp: AffinePolynomial, omega, delay: float = 0.0
) -> BoundaryCurve:
    r"""Solve :math:`p(j\omega) = 0` for ``(k1, k2)`` at each frequency.

    .. math::
        \begin{bmatrix}\operatorname{Re} n_1 & \operatorname{Re} n_2\\
        \operatorname{Im} n_1 & \operatorname{Im} n_2\end{bmatrix}
        \begin{bmatrix}k_1\\ k_2\end{bmatrix}
        = -\begin{bmatrix}\operatorname{Re} r\\ \operatorname{Im} r\end{bmatrix}
        \quad\text{at } s = j\omega,\quad r = d(j\omega)\,e^{j\omega\tau},

    i.e. :math:`d(j\omega) + e^{-j\omega\tau}(k_1 n_1 + k_2 n_2) = 0` with
    the input delay :math:`\tau` (0: no delay).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> cp = fws.characteristic_coefficients(veh, speed=5.0, ratio=0.0)
    >>> fws.stability.complex_root_curve(cp, [1.0]).k1.round(6)
    array([0.108])
    """
    w = np.asarray(omega, dtype=float)
    d, n1, n2 = cp.polynomials_at(1j * w)
    if delay:
        d = d * np.exp(1j * w * delay)
    det = n1.real * n2.imag - n2.real * n1.imag
    scale = np.abs(n1) * np.abs(n2)
    with np.errstate(divide="ignore", invalid="ignore"):
        k1 = (-d.real * n2.imag + d.imag * n2.real) / det
        k2 = (-n1.real * d.imag + n1.imag * d.real) / det
    # A relative test: det is a 2x2 determinant of vectors of size |n1|, |n2|.
    singular = ~(np.abs(det) > 1e-12 * scale)
    # + 0.0 turns -0.0 into 0.0
    k1 = np.where(singular, np.nan, k1) + 0.0
    k2 = np.where(singular, np.nan, k2) + 0.0
    return BoundaryCurve(omega=w, k1=k1, k2=k2)


def stability_boundaries(
    plant: Any,
    *,
    ratio: float,
    omega=None,
    delay: float = 0.0,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> StabilityBoundaries:
    r"""Stability boundaries in the ``(k1, k2)`` plane (D-subdivision).

    For the kinematic plant the straight lines are (eq. 37, with ``(c-a)``
    for ``(1-a)`` in the exact model)

    .. math::
        f a k_1 + (c-a) k_2 = 0 \quad (p_1 = 0),\qquad
        (c-a) k_1 - a f\kappa^2 k_2 + f\kappa^2 = 0 \quad (p_0 = 0).

    For ``a = c`` (``a = 1`` on a straight path) the first is ``k1 = 0``
    (eq. 38); on a curved path the second then reads ``k2 = 1/a``, so eq.
    (38)'s "any k2" holds only on a straight path. On a straight path with
    ``a = 1`` the second is degenerate (:math:`p_0 \equiv 0`, never stable).

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        One operating point (see :mod:`fws_control.plant`), any order.
    ratio : float or callable
        Rear-to-front steering ratio :math:`a`, or a schedule
        ``ratio(vehicle, speed=...)`` evaluated at the plant's speed.
    omega : array_like, optional
        Frequencies [rad/s] of the complex-root curve; default
        :func:`default_frequencies`.
    delay : float, optional
        Input delay [s], >= 0: the complex-root curve becomes the
        D-subdivision curve of the quasi-polynomial (many branches); the
        straight lines other than ``p(0) = 0`` no longer bound the stable set
        and are omitted.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    StabilityBoundaries
        Unpacking it gives the straight lines (for two states
        ``p1_line, p0_line = stability_boundaries(...)``, as in 0.1).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> b = fws.stability_boundaries(fws.LateralPlant(veh, speed=5.0), ratio=-1.0)
    >>> b.real_root.condition, [ln.condition for ln in b.lines]
    ('p0 > 0', ['p1 > 0', 'p0 > 0'])
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    ratio = check_magnitude("ratio", resolve_ratio(p, ratio), MAX_RATIO)
    if np.ndim(ratio) or (isinstance(p, LateralPlant) and p.shape != ()):
        raise ValueError(
            "stability_boundaries needs one operating point and a scalar ratio"
        )
    cp = characteristic_coefficients(p, ratio=ratio)
    last = cp.order
    real = StabilityBoundary.from_coefficients(
        cp.n1[..., last], cp.n2[..., last], cp.open_loop[..., last], "p0 > 0"
    )
    tau = check_delay(delay)
    if cp.order == 2 and tau == 0.0:
        p1 = StabilityBoundary.from_coefficients(
            cp.n1[..., 1], cp.n2[..., 1], cp.open_loop[..., 1], "p1 > 0"
        )
        lines = (p1, real)
    else:
        lines = (real,)
    if omega is None:
        w = default_frequencies(cp)
    else:
        w = np.atleast_1d(check_finite("omega", omega)).astype(float)
        if w.ndim != 1 or np.any(w <= 0):
            raise ValueError(
                f"omega must be a 1-D array of frequencies > 0 rad/s, got {omega!r}"
            )
    return StabilityBoundaries(
        real_root=real,
        complex_root=complex_root_curve(cp, w, tau),
        lines=lines,
        order=cp.order,
    )
