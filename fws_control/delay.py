r"""Feedback delay: critical delay, rightmost roots and root counts.

With a constant delay :math:`\tau` on the steering command, the rank-one
feedback of the structured controller gives the characteristic
quasi-polynomial

.. math::
    D(s) = d(s) + e^{-s\tau} q(s),\qquad q(s) = k_1 n_1(s) + k_2 n_2(s),

with :math:`d, n_1, n_2` of :func:`~fws_control.affine_characteristic_polynomial`
(a steering lag is part of the plant, so it simply adds states). Since
:math:`\deg q < \deg d` the equation is of *retarded* type: finitely many
roots lie in any right half plane and they move continuously with the
gains and the delay. Three computations build on that:

:func:`critical_delay`
    A root is on the imaginary axis, :math:`D(j\omega) = 0` with
    :math:`\omega > 0`, only where :math:`|d(j\omega)| = |q(j\omega)|` — a
    polynomial equation in :math:`\omega^2` of degree ``n`` — and then
    :math:`e^{-j\omega\tau} = -d(j\omega)/q(j\omega)` fixes the delays
    :math:`\tau_m = (\tau_0 + 2\pi m)/\omega`. The smallest of them over the
    crossing frequencies is the delay margin of a loop that is stable
    without delay (a root at ``s = 0`` does not depend on the delay).
:func:`unstable_root_count`
    The number of roots in the open right half plane by the argument
    principle on the imaginary axis: for a retarded quasi-polynomial with
    monic ``d`` of degree ``n``, :math:`N = n/2 - \Delta_{[0,\infty)}\arg
    D(j\omega)/\pi`. The phase increment is summed on a frequency grid fine
    enough for the delay term, up to a frequency beyond which
    :math:`|q| < |d|/2` for the gains asked, and the tail to infinity is
    added in closed form from the roots of ``d``. Points where the phase
    cannot be followed (a root on or very near the axis) are reported as
    undecided, never guessed.
:func:`rightmost_roots`
    The rightmost characteristic roots by spectral (Chebyshev collocation)
    discretisation of the infinitesimal generator of the delay equation
    (Breda, Maset and Vermiglio, *SIAM J. Sci. Comput.* 27, 2005), whose
    eigenvalues converge to the roots spectrally fast in the number of
    nodes, each then refined by Newton's method on :math:`D(s)`.
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .gains import SteeringGains
from .linear import (
    AffinePolynomial,
    affine_characteristic_polynomial,
    check_gains,
    horner,
)
from .plant import LateralPlant, as_plant, loop_matrices
from .validation import check_delay

__all__ = [
    "CriticalDelay",
    "critical_delay",
    "rightmost_roots",
    "unstable_root_count",
]


def _even_odd(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Split ``p(j w) = R(w^2) + j w I(w^2)``; coefficients in ``x = w^2``.

    `c` has shape ``(..., m)`` highest power first; outputs are highest power
    first in ``x`` with the same leading shape.
    """
    c = np.asarray(c)
    asc = c[..., ::-1]  # ascending powers of s
    m = asc.shape[-1]
    even = asc[..., 0::2] * (-1.0) ** np.arange((m + 1) // 2)
    odd = asc[..., 1::2] * (-1.0) ** np.arange(m // 2)
    return even[..., ::-1], odd[..., ::-1]


def _polymul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Batch product of polynomials (highest power first) on the last axis."""
    a = np.asarray(a)
    b = np.asarray(b)
    shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
    out = np.zeros(shape + (a.shape[-1] + b.shape[-1] - 1,))
    for i in range(a.shape[-1]):
        out[..., i : i + b.shape[-1]] += a[..., i : i + 1] * b
    return out


def _polyadd(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    n = max(a.shape[-1], b.shape[-1])
    pad = [
        np.concatenate([np.zeros(p.shape[:-1] + (n - p.shape[-1],)), p], -1)
        for p in (a, b)
    ]
    return pad[0] + pad[1]


def _abs2_in_x(c: np.ndarray) -> np.ndarray:
    r""":math:`|p(j\omega)|^2` as a polynomial in :math:`x = \omega^2`."""
    re, im = _even_odd(c)
    x = np.array([1.0, 0.0])
    return _polyadd(_polymul(re, re), _polymul(_polymul(im, im), x))


def _batch_roots(c: np.ndarray) -> np.ndarray:
    """Roots of monic polynomials ``(..., m)`` via stacked companion matrices."""
    c = np.asarray(c, dtype=float)
    n = c.shape[-1] - 1
    comp = np.zeros(c.shape[:-1] + (n, n))
    comp[..., 0, :] = -c[..., 1:] / c[..., :1]
    if n > 1:
        comp[..., np.arange(1, n), np.arange(n - 1)] = 1.0
    return np.linalg.eigvals(comp)


@dataclass(frozen=True)
class CriticalDelay:
    r"""The delay margin of a loop: the smallest delay with a root at ``±jω``.

    Attributes
    ----------
    delay : float or ndarray
        Critical delay :math:`\tau_c` [s]: the loop is stable for every
        delay in :math:`[0, \tau_c)`. ``inf`` when no delay destabilises it;
        0 when it is not stable without delay.
    frequency : float or ndarray
        Crossing frequency :math:`\omega_c` [rad/s] at :math:`\tau_c` (NaN
        when ``delay`` is ``inf`` or 0).
    stable_without_delay : bool or ndarray
        Whether the loop is stable at zero delay.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    >>> cd = fws.critical_delay(plant, g)
    >>> round(cd.delay, 4), round(cd.frequency, 4)
    (0.6474, 2.0582)
    """

    delay: float | np.ndarray
    frequency: float | np.ndarray
    stable_without_delay: bool | np.ndarray


def _scalar(v):
    return v.item() if isinstance(v, np.ndarray) and v.ndim == 0 else v


def critical_delay(
    plant: Any,
    gains: SteeringGains,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> CriticalDelay:
    r"""Smallest input delay at which a closed-loop root reaches the imaginary axis.

    Solves :math:`|d(j\omega)|^2 = |q(j\omega)|^2` (a polynomial of degree
    ``n`` in :math:`\omega^2`, roots from its companion matrix) for the
    crossing frequencies and takes the smallest delay
    :math:`\tau = \arg(-q(j\omega)/d(j\omega)) / \omega \bmod 2\pi/\omega`
    over them. Vectorised over array gains.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), any order; a steering lag
        belongs in the plant.
    gains : SteeringGains
        Gains (arrays broadcast).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    CriticalDelay
        ``.delay`` [s] (``inf``: no delay destabilises; 0: unstable without
        delay) and ``.frequency`` [rad/s].

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0)
    >>> g = fws.double_root_gains(plant, ratio=0.5, pole=-1.0)
    >>> round(fws.critical_delay(plant, g).delay, 4)
    0.6474
    """
    g = check_gains(gains)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    cp = affine_characteristic_polynomial(p, ratio=g.ratio)
    k1 = np.asarray(g.k1, dtype=float)[..., np.newaxis]
    k2 = np.asarray(g.k2, dtype=float)[..., np.newaxis]
    q = k1 * cp.n1 + k2 * cp.n2
    d = np.broadcast_to(cp.open_loop, q.shape)
    F = _polyadd(_abs2_in_x(d), -_abs2_in_x(q))  # monic, degree n in x
    x = _batch_roots(F)
    real = np.abs(x.imag) <= 1e-7 * np.maximum(1.0, np.abs(x))
    pos = real & (x.real > 0)
    # Newton on F for the real roots: the eigenvalues of a companion matrix
    # are accurate to about eps*cond; two steps recover full precision.
    deg = F.shape[-1] - 1
    dF = F[..., :-1] * np.arange(deg, 0, -1)
    xr = np.where(pos, x.real, 1.0)
    for _ in range(2):
        f = horner(F[..., np.newaxis, :], xr)
        fp = horner(dF[..., np.newaxis, :], xr)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(pos & (fp != 0), f / fp, 0.0)
        xr = np.where(np.abs(step) < 1e-3 * xr, xr - step, xr)
    w = np.sqrt(xr)
    s = 1j * w
    dv = horner(d[..., np.newaxis, :], s)
    qv = horner(q[..., np.newaxis, :], s)
    with np.errstate(divide="ignore", invalid="ignore"):
        phase = np.angle(-qv / dv)  # e^{-jw tau} = -d/q  <=>  w tau = arg(-q/d)
    tau = np.mod(phase, 2 * math.pi) / w
    tau = np.where(pos & np.isfinite(tau), tau, np.inf)
    j = np.argmin(tau, axis=-1)
    tau_c = np.take_along_axis(tau, j[..., np.newaxis], -1)[..., 0]
    w_c = np.take_along_axis(w, j[..., np.newaxis], -1)[..., 0]
    # Stability without delay from the roots of d + q (this module sits below
    # the stability module, which uses it for delayed charts).
    stable0 = np.max(_batch_roots(d + q).real, axis=-1) < 0.0
    w_c = np.where(np.isfinite(tau_c) & stable0, w_c, np.nan)
    tau_c = np.where(stable0, tau_c, 0.0)
    return CriticalDelay(
        delay=_scalar(tau_c) if tau_c.ndim else float(tau_c),
        frequency=_scalar(w_c) if w_c.ndim else float(w_c),
        stable_without_delay=bool(stable0) if stable0.ndim == 0 else stable0.copy(),
    )


def _cheb(N: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev extremal nodes on [-1, 1] (descending), differentiation matrix."""
    x = np.cos(np.pi * np.arange(N + 1) / N)
    c = np.ones(N + 1)
    c[0] = c[-1] = 2.0
    c *= (-1.0) ** np.arange(N + 1)
    X = x[:, None] - x[None, :]
    Dm = np.outer(c, 1.0 / c) / (X + np.eye(N + 1))
    Dm -= np.diag(Dm.sum(axis=1))
    return x, Dm


#: Delays [s] the Chebyshev discretisation of :func:`rightmost_roots` takes.
_MIN_CHEB_DELAY, _MAX_CHEB_DELAY = 1.0e-6, 1.0e3
#: Most roots asked for, and most starting nodes: the discretisation doubles
#: the nodes up to five times (100 nodes: 3200, a matrix of 3204 x 3204 for
#: four states, 82 MB, whose eigenvalues LAPACK computes in copies of it).
_MAX_ROOTS, _MAX_NODES = 1000, 100
#: Most frequency points of the phase grid of :func:`unstable_root_count`
#: (it grows with delay times the frequency bound).
_MAX_PHASE_POINTS = 200_000


def _check_count(name: str, value, minimum: int, maximum: int) -> int:
    """An integer in [minimum, maximum], given as an int or an integral float."""
    ok = (
        not isinstance(value, (bool, np.bool_))
        and isinstance(value, (int, np.integer, float, np.floating))
        and math.isfinite(value)
        and int(value) == value
        and minimum <= value <= maximum
    )
    if not ok:
        raise ValueError(
            f"{name} must be an integer in [{minimum}, {maximum}], got {value!r}"
        )
    return int(value)


def rightmost_roots(
    plant: Any,
    gains: SteeringGains,
    *,
    delay: float,
    n: int = 6,
    nodes: int = 8,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> np.ndarray:
    r"""The rightmost characteristic roots of the delayed closed loop.

    The loop :math:`\dot x(t) = \mathbf A x(t) + \mathbf b\,u(t-\tau)`,
    :math:`u = -(k_1\mathbf c_e + k_2\mathbf c_\theta) x`, is discretised by
    Chebyshev collocation of its infinitesimal generator, the history of the
    scalar :math:`u` on ``nodes + 1`` points of :math:`[-\tau, 0]`; the
    eigenvalues of that matrix of size ``n_states + nodes`` approximate the
    characteristic roots, the rightmost first. (They are those of the
    collocation of the whole state's history, of size ``n_states * (nodes +
    1)``, less the eigenvalues of the bare transport that the feedback does
    not reach, which depend on no plant.) The rightmost eigenvalues, and the
    eigenvalues of the undelayed loop (the roots at :math:`\tau = 0`, which a
    small delay only perturbs), start Newton's method on :math:`D(s) = d(s) +
    e^{-s\tau}q(s)`; a start that lands on a root already found is restarted
    with that root deflated (Newton on :math:`D(s)/\prod(s - r_i)`), so that
    the two roots a small delay splits off a double root are both found.
    The nodes are doubled until the finer discretisation adds no root among
    the `n` rightmost: its eigenvalues start Newton only where they are no
    root found already (to 1e-6 relative) and lie right enough to matter.
    The result is the polished roots, each a root of :math:`D` to rounding.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), one operating point.
    gains : SteeringGains
        Scalar gains.
    delay : float
        Input delay :math:`\tau` [s]: 0 (the eigenvalues of the undelayed
        closed loop) or in [1e-6, 1e3] s.
    n : int, optional
        How many roots to return, 1 to 1000.
    nodes : int, optional
        Chebyshev nodes of the first discretisation, 4 to 100. The nodes are
        doubled until the polished `n` rightmost roots agree (to 1e-8
        relative) between two successive discretisations, at least once and
        at most five times.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    ndarray of complex
        The `n` rightmost roots [1/s], by decreasing real part (a complex
        pair: the one with positive imaginary part first).

    Raises
    ------
    RuntimeError
        If the discretisation does not converge for `n` roots (with a
        message saying what to change).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    >>> tc = fws.critical_delay(plant, g)
    >>> r = fws.rightmost_roots(plant, g, delay=tc.delay, n=2)
    >>> np.allclose(r.real, 0.0, atol=1e-9), np.allclose(abs(r.imag), tc.frequency)
    (True, True)
    """
    g = check_gains(gains, scalar=True)
    tau = check_delay(delay)
    if tau != 0.0 and not (_MIN_CHEB_DELAY <= tau <= _MAX_CHEB_DELAY):
        # the discretisation scales the Chebyshev matrix by 2/delay: 1e-300 s
        # overflows it, 1e300 s leaves nothing of the plant in it (NaN roots)
        raise ValueError(
            f"delay must be 0 or in [{_MIN_CHEB_DELAY:g}, {_MAX_CHEB_DELAY:g}] s "
            f"for the Chebyshev discretisation, got {delay!r}"
        )
    k = _check_count("n", n, 1, _MAX_ROOTS)
    N = _check_count("nodes", nodes, 4, _MAX_NODES)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    # a search (most_stable_gains, pareto_front) asks for the roots of one
    # plant and ratio at hundreds of gains: a LateralPlant is frozen, so its
    # matrices and polynomial are computed once (other plants every call)
    cached = isinstance(p, LateralPlant)
    ratio = float(g.ratio)
    loop = _loop_arrays if cached else _loop_arrays.__wrapped__
    A, b, c_e, c_theta = loop(p, ratio)
    c = -(g.k1 * c_e + g.k2 * c_theta)  # u = c x, delayed by tau
    lam0 = np.linalg.eigvals(A + np.outer(b, c))
    if tau == 0.0:
        return lam0[np.argsort(-lam0.real, kind="stable")][:k]
    polynomial = _loop_polynomial if cached else _loop_polynomial.__wrapped__
    cp = polynomial(p, ratio)
    quasi = _Quasi(cp, float(g.k1), float(g.k2), tau)
    m = A.shape[0]
    # start at least so fine that the matrix has a few eigenvalues per root
    # asked for
    N = max(N, min(_MAX_NODES, -(-2 * k // m)))
    # the undelayed roots start Newton too: a small delay only moves them a
    # little, and splits a double root into two close ones
    previous = quasi.polish(_spectrum(A, b, c, tau, N), k, extra=lam0)
    for _ in range(5):
        N *= 2
        # the finer discretisation starts from the roots found so far: Newton
        # runs only from its eigenvalues that are no known root and lie right
        # enough to matter; a new root among the k rightmost means the
        # coarser one had missed it
        roots = quasi.polish(_spectrum(A, b, c, tau, N), k, known=previous)
        if _same_rightmost(previous.roots, roots.roots, k):
            return roots.roots[:k]
        previous = roots
    raise RuntimeError(
        f"rightmost_roots did not converge with {N} Chebyshev nodes for n={k} "
        "roots; ask for fewer roots (n) or a larger nodes"
    )


@functools.lru_cache(maxsize=64)
def _loop_arrays(
    p: Any, ratio: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The loop's A, input column and measurement rows (e, theta)."""
    lm = loop_matrices(p)
    A = np.asarray(lm.A, dtype=float)
    if A.ndim != 2:
        raise ValueError("rightmost_roots needs one operating point")
    # read-only copies: the cache hands the same arrays to every call
    b, c_e, c_theta = (
        np.array(v, dtype=float) for v in (lm.input_vector(ratio), lm.c_e, lm.c_theta)
    )
    A = A.copy()
    for v in (A, b, c_e, c_theta):
        v.flags.writeable = False
    return A, b, c_e, c_theta


@functools.lru_cache(maxsize=64)
def _loop_polynomial(p: Any, ratio: float) -> AffinePolynomial:
    """The loop's characteristic polynomial, affine in the gains."""
    return affine_characteristic_polynomial(p, ratio=ratio)


def _spectrum(A: np.ndarray, b: np.ndarray, c: np.ndarray, tau: float, N: int):
    """Eigenvalues of the Chebyshev discretisation with `N` nodes.

    The state is ``x`` and the history ``U_j = u(t + theta_j)`` of the
    delayed scalar at the nodes ``theta_j = tau (x_j - 1)/2``, ``j = 1..N``
    (``U_0 = c x``): ``x' = A x + b U_N``, ``U' = (2/tau) D U`` at the nodes.

    Upper half plane and real axis only (the rest are their conjugates),
    rightmost first. They start Newton in batches from the right, past the
    `n`-th root found: the discretisation has spurious eigenvalues (``|s|
    tau`` of the order of ``N``) that can lie right of true roots, e.g. of
    the far roots of a loop with a tiny delay.
    """
    m = A.shape[0]
    _, Dm = _cheb(N)
    scale = 2.0 / tau
    big = np.zeros((m + N, m + N))
    big[:m, :m] = A
    big[:m, -1] = b
    big[m:, :m] = np.outer(Dm[1:, 0] * scale, c)
    big[m:, m:] = Dm[1:, 1:] * scale
    lam = np.linalg.eigvals(big)
    lam = lam[lam.imag >= 0.0]
    return lam[np.argsort(-lam.real, kind="stable")]


def _same_rightmost(coarse: np.ndarray, fine: np.ndarray, k: int) -> bool:
    """Whether two sets of polished roots agree on their `k` rightmost.

    Each of the `k` rightmost fine roots is in the coarse set, and every
    coarse root right of the `k`-th fine root is in the fine set (so that a
    root is neither missing nor spurious in either).
    """
    if fine.size < k or coarse.size == 0:
        return False
    tol = 1e-8 * (1.0 + np.abs(fine[:k]))
    if np.any(np.min(np.abs(fine[:k, None] - coarse[None, :]), axis=1) > tol):
        return False
    edge = fine[k - 1].real - 1e-8 * (1.0 + abs(fine[k - 1]))
    right = coarse[coarse.real >= edge]
    return bool(
        np.all(
            np.min(np.abs(right[:, None] - fine[None, :]), axis=1)
            <= 1e-8 * (1.0 + np.abs(right))
        )
    )


@dataclass(frozen=True)
class _Polished:
    """Polished roots: all of them rightmost first, and the upper-half ones found."""

    roots: np.ndarray
    found: list[complex]
    found_err: list[float]


class _Quasi:
    r"""``D(s) = d(s) + e^{-s tau} q(s)`` of one loop, and Newton's method on it."""

    def __init__(self, cp: AffinePolynomial, k1: float, k2: float, tau: float):
        d = np.asarray(cp.open_loop, dtype=float)
        q = k1 * np.asarray(cp.n1, dtype=float) + k2 * np.asarray(cp.n2, dtype=float)
        n = d.size
        # d, d', q, q' as rows of one coefficient array (zero padded in
        # front), so that one Horner pass evaluates all four
        rows = np.zeros((4, n))
        rows[0] = d
        rows[1, 1:] = np.polyder(d)
        rows[2, n - q.size :] = q
        if q.size > 1:
            dq = np.polyder(q)
            rows[3, n - dq.size :] = dq
        # the columns, for Horner's scheme in Python's complex arithmetic
        self.cols = [tuple(c) for c in rows.T.tolist()]
        # sizes of the terms, for a residual relative to them (a common root
        # of d and q, e.g. a mode the steering cannot reach, makes both small)
        self.sizes = np.abs(rows[[0, 2]])[:, np.newaxis, :]
        self.tau = tau

    def value_at(self, z: complex) -> tuple[complex, complex]:
        """D(z) and D'(z) at one point.

        Raises OverflowError beyond the float range and ValueError at an
        infinite imaginary part (``cmath.exp``).

        Python's complex arithmetic: Newton asks for a few points at a time,
        on which numpy's overhead per call outweighs the arithmetic.
        """
        d, dd, q, dq = self.cols[0]
        for cd, cdd, cq, cdq in self.cols[1:]:
            d, dd, q, dq = d * z + cd, dd * z + cdd, q * z + cq, dq * z + cdq
        e = cmath.exp(-z * self.tau)
        return d + e * q, dd + e * (dq - self.tau * q)

    def value(self, s):
        """D(s) and D'(s) for a 1-d array `s` (NaN where :meth:`value_at` raises)."""
        f = np.empty(s.shape, dtype=complex)
        df = np.empty(s.shape, dtype=complex)
        for i, z in enumerate(s.tolist()):
            try:
                f[i], df[i] = self.value_at(z)
            except (OverflowError, ValueError):
                f[i] = df[i] = complex(math.nan, math.nan)
        return f, df

    def relative_residual(self, s):
        """|D(s)| over the size of its terms (sum of |coefficient| |s|^k)."""
        f, _ = self.value(s)
        a = np.abs(s)
        d_size, q_size = horner(self.sizes, a)
        return np.abs(f) / (d_size + np.abs(np.exp(-s * self.tau)) * q_size)

    def newton(self, s, known=None, steps: int = 20):
        """Newton from the starts `s` (array); the `known` roots deflated.

        Returns the end points, whether each is a root (relative residual of
        :math:`D` below 1e-11) and its error estimate (the size of one more,
        undeflated, Newton step: about the distance to the root, also to a
        multiple one, on which Newton converges only linearly). A start
        not converged in `steps` steps is a far, spurious one (an eigenvalue
        start near a root converges in a few); a root it would have reached
        is an eigenvalue of the finer discretisation.
        """
        s = np.array(s, dtype=complex)
        # a start that runs off this far has left for no root near it
        far = 1e3 * (1.0 + float(np.max(np.abs(s), initial=0.0)))
        deflate = known.tolist() if known is not None and known.size else []
        for i, z in enumerate(s.tolist()):
            for _ in range(steps):
                try:
                    f, df = self.value_at(z)
                    if f == 0:  # an exact root
                        break
                    # D'/D: deflation subtracts 1/(s - r) per root r
                    w = df / f
                    for r in deflate:
                        w -= 1.0 / (z - r)
                    step = 1.0 / w
                except (OverflowError, ValueError, ZeroDivisionError):
                    break  # no finite step: the start stays where it is
                if not cmath.isfinite(step):
                    break
                z -= step
                try:
                    if abs(step) <= 1e-14 * max(1.0, abs(z)) or abs(z) > far:
                        break
                except OverflowError:
                    break  # |z| beyond the float range: far
            s[i] = z
        with np.errstate(all="ignore"):
            f, df = self.value(s)
            err = np.where(f == 0, 0.0, np.abs(f / df))
            # f == 0: an exact root (e.g. s = 0 of a loop without feedback,
            # where the size of the terms is 0 too)
            ok = (
                np.isfinite(s)
                & np.isfinite(err)
                & ((f == 0) | (self.relative_residual(s) <= 1e-11))
            )
        return s, ok, np.where(ok, err, np.inf)

    def polish(
        self,
        starts: np.ndarray,
        k: int,
        *,
        extra: np.ndarray | None = None,
        known: _Polished | None = None,
    ) -> _Polished:
        """Distinct roots from the starts, conjugates added, rightmost first.

        Newton starts from the `starts` (sorted by decreasing real part) in
        batches, until `k` roots are found and the next start lies well left
        of the `k`-th (the rest, further left, would only find roots further
        left), then from each of `extra`. A multiple root (to rounding) is
        returned once. The `known` roots (of a coarser discretisation) are
        taken as found: a start within 1e-6 (relative) of one is that root
        and starts no Newton, and so does a first batch that lies well left
        of the `k`-th known root.
        """
        if known is None:
            found: list[complex] = []
            found_err: list[float] = []
        else:
            found, found_err = list(known.found), list(known.found_err)
            starts = starts[starts.imag >= 0.0]
            if found:
                z = np.array(found)
                gap = np.min(np.abs(starts[:, None] - z[None, :]), axis=1)
                starts = starts[gap > 1e-6 * (1.0 + np.abs(starts))]
        retries: dict[int, int] = {}
        batch = 2 * k + 4
        todo, rest = starts[:batch], starts[batch:]
        first = known is None
        extra_done = None
        if extra is not None and first:
            # one Newton run for the first batch and the extra starts (their
            # roots are matched after the batches, as if run then)
            extra = extra[extra.imag >= 0.0]
            todo = todo[todo.imag >= 0.0]
            s, ok, err = self.newton(np.concatenate([todo, extra]))
            n = todo.size
            self._polish_into(todo, found, found_err, retries, (s[:n], ok[:n], err[:n]))
            extra_done = (s[n:], ok[n:], err[n:])
            first = False
            todo, rest = rest[:batch], rest[batch:]
            batch *= 2
        while todo.size:
            if not first:
                z = np.array(found, dtype=complex)
                # a complex root stands for itself and its conjugate
                re = np.sort(np.repeat(z.real, np.where(z.imag > 0, 2, 1)))[::-1]
                if re.size >= k and todo[0].real < re[k - 1] - 0.1 * (
                    1.0 + abs(re[k - 1])
                ):
                    break
            self._polish_into(todo, found, found_err, retries)
            first = False
            todo, rest = rest[:batch], rest[batch:]
            batch *= 2
        if extra is not None:
            self._polish_into(extra, found, found_err, retries, extra_done)
        roots = np.array(found, dtype=complex)
        errs = np.array(found_err)
        # a root within its error (or 1e-7) of the real axis is real (a
        # double real root to rounding); the others come
        # with their conjugates (the coefficients are real)
        small = np.abs(roots.imag) <= 1e-7 * (1.0 + np.abs(roots)) + 10.0 * errs
        roots = np.where(small, roots.real + 0j, roots)
        roots = np.concatenate([roots, np.conj(roots[~small & (roots.imag > 0)])])
        return _Polished(
            roots[np.lexsort((-roots.imag, -roots.real))], found, found_err
        )

    def _polish_into(self, starts, found, found_err, retries, done=None) -> None:
        """Newton from `starts`; new roots (upper half plane) appended to `found`.

        `done`: the Newton results of the upper-half `starts`, if run already.
        """
        starts = starts[starts.imag >= 0.0]
        s, ok, err = self.newton(starts) if done is None else done
        # each root stands for its conjugate pair: keep the upper one
        s = np.where(s.imag < 0.0, np.conj(s), s)

        def match(z, e):
            for i, (r, er) in enumerate(zip(found, found_err, strict=True)):
                # closer than 1e-7 is a multiple root to rounding (Newton
                # finds a double root to about the square root of eps)
                if abs(z - r) <= 1e-7 * (1.0 + abs(z)) + 10.0 * (e + er):
                    return i
            return -1

        for z0, z, good, e in zip(starts, s, ok, err, strict=True):
            if not good:
                continue
            i = match(z, e)
            if i < 0:
                found.append(z)
                found_err.append(e)
                continue
            if abs(z - z0) > 1e-2 * (1.0 + abs(z)) or retries.get(i, 0) >= 2:
                # a start far from the known root it reached: spurious
                continue
            # landed, from close by, on a root already found: a cluster (the
            # roots a small delay splits off a double root). Deflate the roots
            # found so far and start again, a little off the known root; a
            # deflated cluster root converges within a few steps
            retries[i] = retries.get(i, 0) + 1
            known = np.array(found + [np.conj(r) for r in found if r.imag != 0])
            start = z0 * (1.0 + 1e-7) + 1e-7
            (z2,), (good2,), (e2,) = self.newton(np.array([start]), known, steps=20)
            if good2 and match(z2, e2) < 0 and z2.imag >= -10.0 * e2:
                found.append(z2)
                found_err.append(e2)


def _tail_phase(roots_d: np.ndarray, w_max: float) -> float:
    """Phase change of d(jw) from w_max to infinity (roots of d below w_max)."""
    return float(np.sum(math.pi / 2 - np.angle(1j * w_max - roots_d)))


def unstable_root_count(
    plant: Any,
    gains: SteeringGains,
    *,
    delay: float = 0.0,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> np.ndarray:
    r"""Number of characteristic roots in the open right half plane.

    By the argument principle on the imaginary axis (see the module
    docstring); vectorised over array gains, so a whole chart is one call.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), one operating point.
    gains : SteeringGains
        Gains (arrays broadcast).
    delay : float, optional
        Input delay :math:`\tau \ge 0` [s]. Refused (ValueError) when the
        phase grid it needs exceeds 200 000 frequency points (delay times
        the frequency bound of the loop above about 78 500).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    ndarray of int
        The count per gain point; ``-1`` where it cannot be decided (a root
        on, or within the frequency resolution of, the imaginary axis: a
        boundary point).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    >>> fws.unstable_root_count(plant, g, delay=0.4).item()
    0
    >>> fws.unstable_root_count(plant, g, delay=0.7).item()
    2
    """
    g = check_gains(gains)
    tau = check_delay(delay)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    cp = affine_characteristic_polynomial(p, ratio=g.ratio)
    if cp.open_loop.ndim > 1 or cp.n1.ndim > 1:
        # one operating point and a scalar ratio: the polynomials are shared
        if np.ndim(g.ratio) or cp.open_loop.shape[:-1]:
            raise ValueError(
                "unstable_root_count needs one operating point and a scalar ratio"
            )
    k1, k2 = np.broadcast_arrays(
        np.asarray(g.k1, dtype=float), np.asarray(g.k2, dtype=float)
    )
    shape = k1.shape
    k1 = k1.ravel()
    k2 = k2.ravel()
    n = cp.order
    d_c, n1_c, n2_c = (
        np.asarray(c, dtype=float).reshape(-1) for c in (cp.open_loop, cp.n1, cp.n2)
    )
    roots_d = np.roots(d_c) if n > 0 else np.array([])
    # Frequency beyond which |q| < |d|/2 for every gain asked, and beyond the
    # imaginary parts of d's roots (so the tail is closed form).
    K1, K2 = (
        float(np.max(np.abs(k1), initial=0.0)),
        float(np.max(np.abs(k2), initial=0.0)),
    )
    w_hi = max(1.0, float(np.max(np.abs(roots_d), initial=0.0)) * 2.0 + 1.0)
    for _ in range(200):
        ww = w_hi * np.geomspace(1.0, 1e3, 64)
        s = 1j * ww
        bound = K1 * np.abs(horner(n1_c, s)) + K2 * np.abs(horner(n2_c, s))
        if np.all(bound < 0.5 * np.abs(horner(d_c, s))):
            break
        w_hi *= 2.0
    else:  # pragma: no cover - deg q < deg d guarantees termination
        raise RuntimeError("no frequency bound found")
    # Grid: resolve the delay's phase (tau*dw <= pi/8) and the polynomials'
    # time scales (geometric near 0).
    m_lin = 8.0 * tau * w_hi / math.pi + 64.0
    if m_lin > _MAX_PHASE_POINTS:
        # the grid (and its memory) grows with the delay: refuse rather than
        # run out of memory at delay = 1e300 s
        raise ValueError(
            f"delay={delay!r} s needs {m_lin:.3g} frequency points to resolve "
            f"the phase up to {w_hi:.3g} rad/s (at most {_MAX_PHASE_POINTS}); "
            f"delay must be <= {(_MAX_PHASE_POINTS - 64) * math.pi / (8 * w_hi):.4g} "
            "s for these gains"
        )
    m_lin = int(math.ceil(m_lin))
    w = np.unique(
        np.concatenate(
            [[0.0], np.geomspace(1e-4 * w_hi, w_hi, 256), np.linspace(0.0, w_hi, m_lin)]
        )
    )
    count = np.full(k1.size, -1, dtype=int)
    todo = np.arange(k1.size)
    tail = _tail_phase(roots_d, w_hi)
    for _refinement in range(3):
        if todo.size == 0:
            break
        s = 1j * w
        dv, v1, v2 = horner(d_c, s), horner(n1_c, s), horner(n2_c, s)
        e = np.exp(-s * tau)
        chunk = max(1, 2_000_000 // w.size)
        still = []
        for lo in range(0, todo.size, chunk):
            idx = todo[lo : lo + chunk]
            D = dv + e * (k1[idx, None] * v1 + k2[idx, None] * v2)
            with np.errstate(divide="ignore", invalid="ignore"):
                inc = np.angle(D[:, 1:] / D[:, :-1])
                end = np.angle(D[:, -1] / dv[-1])
            total = np.sum(inc, axis=1) + tail - end
            N = n / 2.0 - total / math.pi
            ok = (
                np.all(np.isfinite(inc), axis=1)
                & (np.max(np.abs(inc), axis=1) < math.pi / 2)
                & (np.abs(N - np.round(N)) < 0.1)
                & (np.abs(D[:, 0]) > 0)
            )
            count[idx[ok]] = np.round(N[ok]).astype(int)
            still.append(idx[~ok])
        todo = np.concatenate(still) if still else todo[:0]
        # refine for the undecided points: 8x denser grid
        frac = np.linspace(0.0, 1.0, 9)[:-1]
        w = np.append((w[:-1, None] + np.diff(w)[:, None] * frac).ravel(), w[-1])
    return count.reshape(shape)
