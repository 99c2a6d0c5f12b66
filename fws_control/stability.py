r"""Stability of the structured steering loop for plants of any order.

The closed-loop characteristic polynomial is affine in the gains,
:math:`p(s) = d(s) + k_1 n_1(s) + k_2 n_2(s)`
(:func:`~fws_control.affine_characteristic_polynomial`), so

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

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, SupportsFloat

import numpy as np

from .delay import unstable_root_count
from .gains import SteeringGains
from .hints import RealArrayLike
from .linear import AffinePolynomial, affine_characteristic_polynomial, check_gains
from .plant import LateralPlant, LoopMatrices, as_plant, loop_matrices, resolve_ratio
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
    "stability_verdict",
    "StabilityVerdict",
    "STABLE",
    "NOT_STABLE",
    "UNDECIDED",
    "routh_hurwitz",
    "hurwitz_columns",
    "StabilityBoundary",
    "BoundaryCurve",
    "StabilityBoundaries",
    "stability_boundaries",
    "default_frequencies",
    "complex_root_curve",
]


def routh_hurwitz(coefficients: RealArrayLike) -> bool | np.ndarray:
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


def hurwitz_columns(columns: Sequence[RealArrayLike]) -> np.ndarray:
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


#: Codes of :attr:`StabilityVerdict.code`.
STABLE, NOT_STABLE, UNDECIDED = 1, 0, -1

_EPS = float(np.finfo(float).eps)


def _interval_routh(pm: list, pr: list) -> np.ndarray:
    """Routh test in midpoint-radius interval arithmetic, 1-D arrays.

    ``pm[j] +- pr[j]`` encloses the coefficient of ``s^(n-j)``; leading
    coefficient positive. Every Routh entry is enclosed likewise (outward
    rounding included), so a sign read off an interval that excludes 0 holds
    for every polynomial in the box. Returns the code per polynomial: stable
    when every pivot is certainly positive, not stable at the first pivot
    certainly <= 0 after positive ones, undecided at a pivot whose interval
    holds 0.
    """
    upper = list(zip(pm[0::2], pr[0::2], strict=True))
    lower = list(zip(pm[1::2], pr[1::2], strict=True))
    alive = upper[0][0] - upper[0][1] > 0
    code = np.full(alive.shape, UNDECIDED, dtype=np.int8)
    zero = (np.zeros_like(alive, dtype=float),) * 2
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for _ in range(len(pm) - 1):
            lm_, lr_ = lower[0]
            code[alive & (lm_ + lr_ <= 0)] = NOT_STABLE
            alive &= lm_ - lr_ > 0
            um_, ur_ = upper[0]
            qm = um_ / lm_
            # x/y for x in um +- ur, y in lm +- lr (lm > lr >= 0)
            qr = (ur_ + np.abs(qm) * lr_) / (lm_ - lr_) + _EPS * np.abs(qm)
            new = []
            for j in range(len(upper) - 1):
                bm, br = lower[j + 1] if j + 1 < len(lower) else zero
                am, ar = upper[j + 1]
                prod = qm * bm
                m = am - prod
                r = (
                    ar
                    + np.abs(qm) * br
                    + np.abs(bm) * qr
                    + qr * br
                    + _EPS * (np.abs(am) + 2 * np.abs(prod))
                )
                new.append((m, r))
            upper, lower = lower, new if new else [zero]
    code[alive] = STABLE
    return code


def _polynomial_verdict(cp: AffinePolynomial, k1, k2) -> np.ndarray:
    """Certified verdict from the coefficients and their error bounds."""
    p, r = cp.coefficient_bounds(k1, k2)
    full = np.broadcast_shapes(*(np.shape(x) for x in p + r))
    shape = full if full else (1,)  # one point: an array of one
    sign = np.sign(p[0])  # the leading coefficient: 1 for a monic d
    if np.all(sign == 1.0):
        pm = [np.broadcast_to(x, shape) for x in p]
    else:
        pm = [np.broadcast_to(x * sign, shape) for x in p]
    pr = [np.broadcast_to(x, shape) for x in r]
    # Every coefficient of a Hurwitz polynomial has the leading one's sign:
    # one that certainly has not (exactly 0 included) means not stable.
    bad = np.broadcast_to(pm[0] - pr[0] <= 0, shape)  # leading not certain
    off = np.zeros(shape, dtype=bool)
    sure = ~bad
    for m, rad in zip(pm[1:], pr[1:], strict=True):
        off |= m <= -rad
        sure &= m > rad
    off &= ~bad
    if cp.order <= 2:
        # degree <= 2: Hurwitz iff every coefficient is positive (eqs. 35-36)
        code = np.where(sure, STABLE, np.where(off, NOT_STABLE, UNDECIDED))
        return code.astype(np.int8).reshape(full)
    code = np.full(shape, UNDECIDED, dtype=np.int8)
    code[off] = NOT_STABLE
    todo = np.nonzero(~off & ~bad)
    if todo[0].size:
        code[todo] = _interval_routh([x[todo] for x in pm], [x[todo] for x in pr])
    return code.reshape(full)


def _eigen_verdict(
    lm: LoopMatrices, ratio, k1, k2, shape: tuple, todo: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Verdict from closed-loop eigenvalues and their perturbation bounds.

    For the flat indices `todo` of the grid `shape`. Returns ``(code,
    bound)``; see :class:`StabilityVerdict` for the bound.
    """
    n = lm.order
    shape = shape if shape else (1,)  # one point: a batch of one
    at = np.unravel_index(todo, shape)
    A = np.broadcast_to(np.asarray(lm.A, dtype=float), shape + (n, n))[at]
    bf = np.broadcast_to(lm.B_front, shape + (n,))[at]
    br = np.broadcast_to(lm.B_rear, shape + (n,))[at]
    ce = np.broadcast_to(lm.c_e, shape + (n,))[at]
    ct_ = np.broadcast_to(lm.c_theta, shape + (n,))[at]
    a = np.broadcast_to(np.asarray(ratio, dtype=float), shape)[at][:, None]
    g1 = np.broadcast_to(np.asarray(k1, dtype=float), shape)[at][:, None]
    g2 = np.broadcast_to(np.asarray(k2, dtype=float), shape)[at][:, None]
    b = bf + a * br
    kc = g1 * ce + g2 * ct_
    Acl = A - b[:, :, None] * kc[:, None, :]
    # Entrywise scale of the terms of A - b k^T: forming A_cl rounds each
    # entry by a few units of it, and eig is backward stable in its norm.
    S = (
        np.abs(A)
        + (np.abs(bf) + np.abs(a * br))[:, :, None]
        * (np.abs(g1) * np.abs(ce) + np.abs(g2) * np.abs(ct_))[:, None, :]
    )
    eta = 4.0 * (n + 2) * _EPS * np.sqrt(np.sum(S * S, axis=(-2, -1)))
    code = np.full(todo.size, UNDECIDED, dtype=np.int8)
    bound = np.full(todo.size, np.inf)
    finite = np.all(np.isfinite(Acl), axis=(-2, -1))
    finite &= np.isfinite(eta)
    Acl = np.where(finite[:, None, None], Acl, 0.0)  # overflowed: undecided
    chunk = 50_000
    for lo in range(0, todo.size, chunk):
        sl = slice(lo, lo + chunk)
        c, bnd = _eigen_chunk(Acl[sl], eta[sl])
        c[~finite[sl]] = UNDECIDED
        code[sl] = c
        bound[sl] = bnd
    return code, bound


def _eigen_chunk(Acl: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    try:
        lam, X = np.linalg.eig(Acl)
    except np.linalg.LinAlgError:  # QR iteration did not converge: no verdict
        return (
            np.full(Acl.shape[0], UNDECIDED, dtype=np.int8),
            np.full(Acl.shape[0], np.inf),
        )
    with np.errstate(over="ignore", invalid="ignore"):
        kappa = np.full(lam.shape, np.inf)
        try:
            Y = np.linalg.inv(X)
            kappa = np.linalg.norm(X, axis=-2) * np.linalg.norm(Y, axis=-1)
        except np.linalg.LinAlgError:  # an exactly singular eigenvector basis
            for i in range(lam.shape[0]):
                try:
                    Yi = np.linalg.inv(X[i])
                except np.linalg.LinAlgError:
                    continue
                kappa[i] = np.linalg.norm(X[i], axis=0) * np.linalg.norm(Yi, axis=1)
        # first-order eigenvalue perturbation, doubled for the second-order
        # terms of near-defective (double-root) eigenvalues
        rad = 2.0 * eta[:, None] * kappa
        rad = np.where(np.isfinite(rad), rad, np.inf)
        hi = np.max(lam.real + rad, axis=-1)
        low = np.max(lam.real - rad, axis=-1)
    c = np.full(lam.shape[0], UNDECIDED, dtype=np.int8)
    c[hi < 0] = STABLE
    c[low > 0] = NOT_STABLE
    return c, np.where(c == UNDECIDED, 2.0 * np.max(rad, axis=-1), 0.0)


@summary_repr
@dataclass(frozen=True, eq=False)
class StabilityVerdict:
    r"""Tri-state stability verdict of the linear closed loop, per gain point.

    Returned by :func:`stability_verdict`.

    Attributes
    ----------
    code : ndarray of int8
        1 (:data:`STABLE`): every closed-loop pole has a negative real part;
        0 (:data:`NOT_STABLE`): some pole has a real part >= 0; -1
        (:data:`UNDECIDED`): the rounding bounds do not separate the
        rightmost pole from the imaginary axis.
    bound : ndarray of float
        Where undecided without delay: a bound :math:`B` with
        :math:`|\operatorname{Re}\lambda_{max}| \le B` for the rightmost
        closed-loop eigenvalue (see :func:`stability_verdict`); ``inf`` where
        no bound is known (with a delay, or a non-diagonalisable computed
        eigenbasis); 0 where decided.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> v = fws.stability_verdict(fws.LateralPlant(veh, speed=5.0),
    ...                           fws.SteeringGains([0.1, -0.1], 0.5, ratio=0.0))
    >>> v.code.tolist(), v.stable.tolist(), v.undecided.tolist()
    ([1, 0], [True, False], [False, False])
    """

    code: np.ndarray
    bound: np.ndarray

    def _mask(self, value: int) -> bool | np.ndarray:
        out = self.code == value
        return bool(out) if np.ndim(out) == 0 else out

    @property
    def stable(self) -> bool | np.ndarray:
        """True where the loop is certainly stable."""
        return self._mask(STABLE)

    @property
    def not_stable(self) -> bool | np.ndarray:
        """True where the loop certainly has a pole with real part >= 0."""
        return self._mask(NOT_STABLE)

    @property
    def undecided(self) -> bool | np.ndarray:
        """True where the verdict is within the rounding bound."""
        return self._mask(UNDECIDED)


def stability_verdict(
    plant: Any,
    gains: SteeringGains,
    *,
    delay: float = 0.0,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> StabilityVerdict:
    r"""Stable, not stable or undecided, for every gain point, with error bounds.

    Without delay, two stages:

    1. **Coefficients.** :math:`p_j = d_j + k_1 n_{1,j} + k_2 n_{2,j}` with
       the error bound :math:`r_j` of
       :meth:`~fws_control.AffinePolynomial.coefficient_bounds` (the
       polynomials are exact, rounded once; :math:`r_j` adds
       :math:`4\epsilon(|d_j| + |k_1 n_{1,j}| + |k_2 n_{2,j}|)`). A
       coefficient with :math:`p_j + r_j \le 0` proves the loop not stable;
       otherwise the Routh array runs in interval arithmetic on
       :math:`[p_j - r_j, p_j + r_j]` (closed form
       :math:`p_1, p_0 > 0` for two states): where every pivot is certainly
       positive the loop is stable, where one is certainly negative it is
       not. These verdicts are proved, not estimated.
    2. **Eigenvalues**, only for the points stage 1 leaves open (a pivot
       interval holds 0: a pole near the axis, or a polynomial too
       ill-conditioned for its coefficients): stacked
       :func:`numpy.linalg.eig` of :math:`A_{cl} = A - b(k_1 c_e +
       k_2 c_\theta)` with the perturbation radius
       :math:`r_i = 2\eta\,\kappa(\lambda_i)` of each eigenvalue, where
       :math:`\kappa(\lambda_i) = \|x_i\|\|y_i\|/|y_i^H x_i|` is its
       condition number and :math:`\eta = 4(n+2)\epsilon\|S\|_F` bounds the
       backward error of forming :math:`A_{cl}` and of the eigensolver, with
       :math:`S = |A| + (|b_f| + |a||b_r|)(|k_1||c_e| + |k_2||c_\theta|)`
       entrywise. Stable where :math:`\max_i(\operatorname{Re}\lambda_i +
       r_i) < 0`, not stable where :math:`\max_i(\operatorname{Re}\lambda_i -
       r_i) > 0`, otherwise undecided with the bound
       :math:`B = 2\max_i r_i`: then the rightmost eigenvalue satisfies
       :math:`|\operatorname{Re}\lambda_{max}| \le B`. So every point whose
       rightmost eigenvalue is farther than :math:`B` from the axis is
       decided.

    With a delay the verdict is the root count of
    :func:`~fws_control.delay.unstable_root_count` (one operating point,
    scalar ratio): 0 stable, > 0 not stable, undecided where the count is
    (a root on, or within the frequency resolution of, the axis; bound
    ``inf``) unless :math:`p(0) \le 0` certainly (with the coefficient's
    error bound): :math:`D(0) = p(0)` does not depend on the delay, so that
    is a root at ``s = 0`` or a positive real root, not stable.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), of any order.
    gains : SteeringGains
        Gains and ratio; arrays broadcast with each other and with the
        operating points of a :class:`LateralPlant`.
    delay : float, optional
        Input delay on the steering command [s], >= 0.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    StabilityVerdict
        ``code`` and ``bound`` have the broadcast shape of the gains and
        operating points.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> v = fws.stability_verdict(plant, fws.SteeringGains(0.1, 0.5, ratio=0.0))
    >>> int(v.code), bool(v.stable)
    (1, True)
    """
    g = check_gains(gains)
    if check_delay(delay) > 0.0:
        count = np.asarray(
            unstable_root_count(
                plant, g, delay=delay, speed=speed, curvature=curvature, model=model
            )
        )
        code = np.where(
            count == 0, STABLE, np.where(count > 0, NOT_STABLE, UNDECIDED)
        ).astype(np.int8)
        if np.any(code == UNDECIDED):
            # D(0) = p(0) does not depend on the delay: p(0) = 0 is a root at
            # s = 0, and p(0) < 0 a positive real root (D(sigma) -> +inf as
            # sigma -> +inf, since deg q < deg d). Both are decided.
            p_ = as_plant(plant, speed=speed, curvature=curvature, model=model)
            cp = affine_characteristic_polynomial(p_, ratio=resolve_ratio(p_, g.ratio))
            pc, rc = cp.coefficient_bounds(g.k1, g.k2)
            sign = np.sign(pc[0])
            at_zero = np.broadcast_to(sign * pc[-1] + rc[-1] <= 0, code.shape)
            code = np.where((code == UNDECIDED) & at_zero, NOT_STABLE, code)
            code = code.astype(np.int8)
        bound = np.where(code == UNDECIDED, np.inf, 0.0)
        return StabilityVerdict(code=code, bound=bound)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    ratio = resolve_ratio(p, g.ratio)
    cp = affine_characteristic_polynomial(p, ratio=ratio)
    k1, k2 = np.asarray(g.k1, dtype=float), np.asarray(g.k2, dtype=float)
    code = _polynomial_verdict(cp, k1, k2)
    bound = np.zeros(code.shape)
    todo = np.flatnonzero(code.ravel() == UNDECIDED)
    if todo.size:
        sub, b = _eigen_verdict(loop_matrices(p), ratio, k1, k2, code.shape, todo)
        code.reshape(-1)[todo] = sub
        bound.reshape(-1)[todo] = b
    return StabilityVerdict(code=code, bound=bound)


def is_stable(
    plant: Any,
    gains: SteeringGains,
    *,
    delay: float = 0.0,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> bool | np.ndarray:
    """Asymptotic stability of the linear closed loop (proved, never guessed).

    True only where :func:`stability_verdict` proves stability; False where
    it proves a pole with real part >= 0 *and* where it cannot decide (the
    rightmost pole within the stated rounding bound of the imaginary axis,
    or an undecided root count with a delay). Use :func:`stability_verdict`
    to tell "not stable" from "undecided".

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
        scalar ratio).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    bool or ndarray of bool
        True where every closed-loop pole certainly has a negative real part
        (see :func:`stability_verdict` for the method and its error bound).
        Points on a boundary (a pole on the imaginary axis) are not stable.

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
    return stability_verdict(
        plant, gains, delay=delay, speed=speed, curvature=curvature, model=model
    ).stable


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
    def from_coefficients(
        cls,
        alpha: SupportsFloat,
        beta: SupportsFloat,
        gamma: SupportsFloat,
        condition: str,
    ) -> StabilityBoundary:
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

    def satisfied(self, k1: RealArrayLike, k2: RealArrayLike) -> bool | np.ndarray:
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

    def k2_at(self, k1: RealArrayLike) -> np.ndarray:
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

    def k1_at(self, k2: RealArrayLike) -> np.ndarray:
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

    def segment(
        self, k1_range: tuple[float, float], k2_range: tuple[float, float]
    ) -> np.ndarray | None:
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

    def __iter__(self) -> Iterator[StabilityBoundary]:
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
    >>> cp = fws.affine_characteristic_polynomial(veh, speed=5.0, ratio=0.0)
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
    cp: AffinePolynomial, omega: RealArrayLike, delay: float = 0.0
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
    >>> cp = fws.affine_characteristic_polynomial(veh, speed=5.0, ratio=0.0)
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
    ratio: float | Callable[..., Any],
    omega: RealArrayLike | None = None,
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
    a: Any = check_magnitude("ratio", resolve_ratio(p, ratio), MAX_RATIO)
    if np.ndim(a) or (isinstance(p, LateralPlant) and p.shape != ()):
        raise ValueError(
            "stability_boundaries needs one operating point and a scalar ratio"
        )
    cp = affine_characteristic_polynomial(p, ratio=a)
    last = cp.order
    real = StabilityBoundary.from_coefficients(
        cp.n1[..., last], cp.n2[..., last], cp.open_loop[..., last], "p0 > 0"
    )
    tau = check_delay(delay)
    if cp.order == 2 and tau == 0.0:
        p1 = StabilityBoundary.from_coefficients(
            cp.n1[..., 1], cp.n2[..., 1], cp.open_loop[..., 1], "p1 > 0"
        )
        lines: tuple[StabilityBoundary, ...] = (p1, real)
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
