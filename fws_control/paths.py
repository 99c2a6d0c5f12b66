r"""Reference paths and the projection of points onto them.

A path is a plane curve parameterised by its arc length ``s`` [m]. Every path
gives, broadcasting over arrays of ``s``, its position ``(x, y)``, heading
:math:`\psi_C`, curvature :math:`\kappa_C` and curvature rate
:math:`d\kappa_C/ds`, and projects points onto itself (nearest point, signed
lateral error ``e``).

Conventions
-----------
* SI units and radians. Positive curvature turns left; the lateral error
  ``e`` is positive to the LEFT of the path.
* Headings are returned wrapped to :math:`(-\pi, \pi]`.
* Placement: :class:`Straight`, :class:`Arc` and :class:`Clothoid` take
  ``start=(x0, y0)`` and ``start_heading=psi0`` (default: origin, heading
  +x). A :class:`Spline` is placed by its waypoints. In a :class:`PathChain`
  the first segment keeps its own placement and every later segment is moved
  rigidly (:meth:`Path.placed`) so that it starts at the end pose of the
  previous one; the segments' own placements are ignored.
* Domains: an unbounded :class:`Straight` accepts any ``s``; a closed path
  (a full :class:`Arc`, a closed :class:`Spline` or :class:`PathChain`)
  wraps ``s`` modulo its length, and projections return ``s`` in
  ``[0, length)``; an open path of finite length accepts ``s`` in
  ``[0, length]`` only and raises :class:`ValueError` otherwise (there is no
  silent extrapolation).
* At a joint of a :class:`PathChain` the curvature (which may jump) is the
  one of the following segment.

Projection
----------
:meth:`Path.project` returns the nearest point of the path. Straight lines and
arcs use their closed forms. Other paths use, for each point with a guess
``s_guess``, a Newton iteration on the derivative of the squared distance; its
result is accepted only if it converges to a strict local minimum
(:math:`1 - \kappa_C e > 0`, or an end of the path), lies within ``window`` of
arc length from the guess, and no sample of the path within ``window`` of it
is nearer. Otherwise (and when there is no guess) a global search samples the
whole path, refines every competing local minimum with safeguarded Newton
steps and keeps the best. With a guess the answer is therefore the nearest
point of the stretch of path the guess is on -- what a tracker wants on
hairpins and figure eights -- and without one it is the globally nearest
point.

When two separate parts of the path are equally near (the centre of an arc,
the medial axis of a course) the nearest point is not unique: the result has
``unique=False`` (distances equal to a relative ``1e-9``) and ``strict=True``
raises :class:`AmbiguousProjectionError`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from scipy.interpolate import CubicHermiteSpline, CubicSpline

from .exceptions import AmbiguousProjectionError
from .reprs import value_repr
from .validation import check_real

__all__ = [
    "Arc",
    "Clothoid",
    "Path",
    "PathChain",
    "Projection",
    "Spline",
    "Straight",
]

# Gauss-Legendre rules: 16 nodes for the clothoid's Fresnel-type integrals,
# 8 nodes per sub-panel for the spline's arc length (smooth integrands, so
# both reach round-off on the panel sizes used below).
_GL16_X, _GL16_W = np.polynomial.legendre.leggauss(16)
_GL8_X, _GL8_W = np.polynomial.legendre.leggauss(8)

# Two distances closer than this (relative) count as a tie: the nearest point
# is then not unique.
_TIE_RTOL = 1e-9
_NEWTON_MAXITER = 40
# Points per path sample chunk in the global search: bounds the (n, m) array.
_CHUNK = 2_000_000
# First pass of the global search: "kdtree" (scipy.spatial.cKDTree over the
# path samples, then a ball query), "dense" (all point-sample distances, the
# method before 0.2) or "auto": the tree from _TREE_MIN_SAMPLES samples on
# (below, the dense pass is cheaper: 3.5 ms against 6.3 ms for 2000 points
# on 120 samples; 32 ms against 9 ms on 320, benchmarks/bench_projection.py).
# Both select the same candidates, so the choice never changes a result.
_FIRST_PASS = "auto"
_TREE_MIN_SAMPLES = 200

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Projection:
    """Nearest point of a path to one or more points.

    All fields have the broadcast shape of the query points (numpy scalars
    for scalar queries).

    Attributes
    ----------
    s : ndarray
        Arc length of the nearest point [m]; in ``[0, length)`` on closed
        paths.
    e : ndarray
        Lateral error [m]: the component of (point - nearest point) along the
        path's left normal, positive to the left. Equal to ``±distance``
        except where the nearest point is an end of an open path.
    heading : ndarray
        Path heading :math:`\\psi_C` at ``s`` [rad], in :math:`(-\\pi, \\pi]`.
    curvature : ndarray
        Path curvature :math:`\\kappa_C` at ``s`` [1/m].
    x, y : ndarray
        The nearest point of the path [m].
    distance : ndarray
        Euclidean distance from the query point to ``(x, y)`` [m].
    unique : ndarray of bool
        False where another, separate part of the path is equally near.

    Examples
    --------
    >>> from fws_control.paths import Straight
    >>> p = Straight().project(3.0, -2.0)
    >>> float(p.s), float(p.e), float(p.distance), bool(p.unique)
    (3.0, -2.0, 2.0, True)
    """

    s: Any
    e: Any
    heading: Any
    curvature: Any
    x: Any
    y: Any
    distance: Any
    unique: Any


# --------------------------------------------------------------------------
# helpers


def _wrap_angle(a: ArrayLike) -> Array:
    """Wrap angles to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)


def _finite_array(name: str, value: Any) -> Array:
    arr = np.array(check_real(name, value), dtype=float)
    bad = ~np.isfinite(arr)
    if np.any(bad):
        if arr.ndim == 0:
            raise ValueError(f"{name} must be finite, got {value!r}")
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{name} must be finite, got {float(arr[idx])!r} at index {idx} "
            f"({int(bad.sum())} non-finite value(s))"
        )
    return arr


def _check_real(name: str, value: Any) -> float:
    arr = check_real(name, value)
    if arr.ndim != 0 or not math.isfinite(float(arr)):
        raise ValueError(f"{name} must be a finite real number, got {value!r}")
    return float(arr)


def _check_start(start: Any) -> tuple[float, float]:
    try:
        arr = check_real("start", start)
    except ValueError:
        arr = np.zeros(0)
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"start must be a pair of finite numbers (x0, y0) in m, got {start!r}"
        )
    return float(arr[0]), float(arr[1])


def _check_length(value: Any, upper: float = math.inf, why: str = "") -> float:
    try:
        v = _check_real("length", value)
    except ValueError as exc:
        raise ValueError(
            f"length must be a number in (0, {upper}] m{why}, got {value!r}"
        ) from exc
    if not (v > 0.0 and v <= upper):
        raise ValueError(
            f"length must be finite and in (0, {upper}] m{why}, got {value!r}"
        )
    return v


def _check_closed(closed: Any) -> bool | None:
    if closed is None or isinstance(closed, (bool, np.bool_)):
        return None if closed is None else bool(closed)
    raise TypeError(f"closed must be None, True or False, got {closed!r}")


def _to_global(
    start: tuple[float, float], psi0: float, lx: Array, ly: Array, lpsi: Array
) -> tuple[Array, Array, Array]:
    c, s = math.cos(psi0), math.sin(psi0)
    x = start[0] + c * lx - s * ly
    y = start[1] + s * lx + c * ly
    return x, y, _wrap_angle(psi0 + lpsi)


def _to_local(
    start: tuple[float, float], psi0: float, px: Array, py: Array
) -> tuple[Array, Array]:
    c, s = math.cos(psi0), math.sin(psi0)
    dx, dy = px - start[0], py - start[1]
    return c * dx + s * dy, -s * dx + c * dy


def _fmt(path: Path) -> str:
    text = repr(path)
    return text if len(text) <= 120 else text[:117] + "..."


# --------------------------------------------------------------------------
# base class


class Path(ABC):
    """Abstract base of all reference paths.

    Subclasses are frozen dataclasses with the attributes ``length`` (float,
    ``math.inf`` if unbounded) and ``closed`` (bool), and implement
    ``_frame``, ``_curvature_rate`` and :meth:`placed`.

    Examples
    --------
    >>> from fws_control.paths import Path, Arc
    >>> isinstance(Arc(curvature=0.1), Path)
    True
    """

    length: float
    closed: bool
    # Straight and Arc project in closed form; a guess buys them nothing.
    _closed_form: bool = False

    # -- to implement ------------------------------------------------------

    @abstractmethod
    def _frame(self, s: Array) -> tuple[Array, Array, Array, Array]:
        """(x, y, heading, curvature) at arc lengths already in the domain."""

    @abstractmethod
    def _curvature_rate(self, s: Array) -> Array:
        """dκ/ds at arc lengths already in the domain."""

    def _curvature(self, s: Array) -> Array:
        """κ at arc lengths already in the domain: ``_frame``'s fourth value.

        A path whose curvature is cheaper than its position (a closed form
        in ``s``) overrides it with the same expression as its ``_frame``;
        a controller or the model's right-hand side asks for the curvature
        alone many times per step.
        """
        return self._frame(s)[3]

    @abstractmethod
    def placed(self, start: Sequence[float], start_heading: float) -> Path:
        """The same path moved rigidly so that it starts at the given pose.

        Parameters
        ----------
        start : (float, float)
            New start point (x0, y0) [m].
        start_heading : float
            New start heading [rad].

        Returns
        -------
        Path
            A path of the same type and shape.
        """

    def _search_samples(self) -> Array:
        """Increasing arc lengths for the global search (0 first; L last if open)."""
        raise NotImplementedError

    # -- evaluation --------------------------------------------------------

    def _domain(self, s: Any, name: str = "s") -> Array:
        arr = _finite_array(name, s)
        L = self.length
        if self.closed:
            arr = np.mod(arr, L)
            # np.mod can round a tiny negative number up to exactly L.
            arr = np.where(arr >= L, 0.0, arr)
        elif math.isfinite(L):
            tol = 1e-9 * max(1.0, L)
            out = (arr < -tol) | (arr > L + tol)
            if np.any(out):
                bad = float(arr[out].flat[0])
                raise ValueError(
                    f"{name} must be in [0, length={L!r}] m on this open path, "
                    f"got {bad!r}"
                )
            arr = np.clip(arr, 0.0, L)
        return arr

    def _clip_guess(self, s: Array) -> Array:
        L = self.length
        if self.closed:
            return np.mod(s, L)
        if math.isfinite(L):
            return np.clip(s, 0.0, L)
        return s

    def position(self, s: ArrayLike) -> tuple[Array, Array]:
        """Position of the path at arc length ``s``.

        Parameters
        ----------
        s : array_like
            Arc length [m]; see the module notes for the valid domain.

        Returns
        -------
        x, y : ndarray
            Coordinates [m], with the shape of ``s``.

        Raises
        ------
        ValueError
            If ``s`` is not finite or lies outside ``[0, length]`` on an open
            path.

        Examples
        --------
        >>> import numpy as np
        >>> from fws_control.paths import Arc
        >>> x, y = Arc(curvature=0.2).position(np.pi / 0.4)  # a quarter circle
        >>> round(float(x), 12), round(float(y), 12)
        (5.0, 5.0)
        """
        x, y, _, _ = self._frame(self._domain(s))
        return x[()], y[()]

    def heading(self, s: ArrayLike) -> Array:
        """Heading :math:`\\psi_C` of the path at ``s``, wrapped to (-pi, pi].

        Parameters
        ----------
        s : array_like
            Arc length [m].

        Returns
        -------
        ndarray
            Heading [rad], shape of ``s``.

        Examples
        --------
        >>> from fws_control.paths import Arc
        >>> round(float(Arc(curvature=0.1).heading(5.0)), 12)
        0.5
        """
        return self._frame(self._domain(s))[2][()]

    def curvature(self, s: ArrayLike) -> Array:
        """Curvature :math:`\\kappa_C` at ``s`` [1/m], positive turning left.

        Parameters
        ----------
        s : array_like
            Arc length [m].

        Returns
        -------
        ndarray
            Curvature, shape of ``s``.

        Examples
        --------
        >>> from fws_control.paths import Clothoid
        >>> float(Clothoid(0.0, 0.1, length=10.0).curvature(5.0))
        0.05
        """
        return np.asarray(self._curvature(self._domain(s)))[()]

    def curvature_rate(self, s: ArrayLike) -> Array:
        """Derivative of the curvature with respect to arc length [1/m^2].

        Parameters
        ----------
        s : array_like
            Arc length [m].

        Returns
        -------
        ndarray
            :math:`d\\kappa_C/ds`, shape of ``s``.

        Examples
        --------
        >>> from fws_control.paths import Clothoid
        >>> round(float(Clothoid(0.0, 0.1, length=10.0).curvature_rate(3.0)), 12)
        0.01
        """
        return np.asarray(self._curvature_rate(self._domain(s)))[()]

    def _end_pose(self) -> tuple[tuple[float, float], float]:
        x, y, psi, _ = self._frame(np.array([self.length]))
        return (float(x[0]), float(y[0])), float(psi[0])

    # -- projection --------------------------------------------------------

    def project(
        self,
        x: ArrayLike,
        y: ArrayLike,
        *,
        s_guess: ArrayLike | None = None,
        strict: bool = False,
        window: float = 10.0,
    ) -> Projection:
        """Nearest point of the path to the point(s) ``(x, y)``.

        Parameters
        ----------
        x, y : array_like
            Query points [m]; broadcast against each other.
        s_guess : array_like, optional
            Previous arc length of each point (broadcast to the points'
            shape), e.g. from the last time step of a simulation. The local
            Newton result near the guess is used if it passes the checks in
            the module notes; otherwise, and without a guess, the global
            search is used. Ignored by :class:`Straight` and :class:`Arc`,
            whose closed forms are exact.
        strict : bool, default False
            Raise :class:`AmbiguousProjectionError` if a nearest point is not
            unique.
        window : float, default 10.0
            Arc length [m] by which the local result may differ from the
            guess, and half-width of the neighbourhood in which it must be
            the nearest sample.

        Returns
        -------
        Projection
            Arc length, lateral error, heading, curvature, nearest point,
            distance and uniqueness flag, each shaped like the points.

        Raises
        ------
        ValueError
            If inputs are not finite, shapes do not broadcast or ``window``
            is not > 0.
        AmbiguousProjectionError
            With ``strict=True``, if a nearest point is not unique.

        Examples
        --------
        >>> from fws_control.paths import Arc
        >>> p = Arc(curvature=0.1).project([0.0, 0.0], [-5.0, 10.0])
        >>> p.e.round(12).tolist(), p.unique.tolist()  # (0, 10) is the centre
        ([-5.0, 10.0], [True, False])
        >>> round(float(p.s[0]), 12)
        0.0
        """
        px = _finite_array("x", x)
        py = _finite_array("y", y)
        try:
            px, py = np.broadcast_arrays(px, py)
        except ValueError as exc:
            raise ValueError(
                f"x and y must have broadcastable shapes, got {px.shape} and {py.shape}"
            ) from exc
        shape = px.shape
        px = px.ravel().astype(float)
        py = py.ravel().astype(float)
        w = _check_real("window", window)
        if w <= 0.0:
            raise ValueError(f"window must be finite and > 0 m, got {window!r}")
        n = px.size
        s = np.zeros(n)
        unique = np.ones(n, dtype=bool)
        todo = np.ones(n, dtype=bool)
        if s_guess is not None:
            g = _finite_array("s_guess", s_guess)
            try:
                g = np.broadcast_to(g, shape).ravel()
            except ValueError as exc:
                raise ValueError(
                    f"s_guess must broadcast to the points' shape {shape}, "
                    f"got shape {g.shape}"
                ) from exc
            if not self._closed_form and n:
                s_loc, ok = self._local(px, py, self._clip_guess(g), w)
                s[ok] = s_loc[ok]
                todo = ~ok
        if np.any(todo):
            s_g, _, u_g = self._global(px[todo], py[todo])
            s[todo] = s_g
            unique[todo] = u_g
        if self.closed:
            s = self._clip_guess(s)
            s = np.where(s >= self.length, 0.0, s)
        fx, fy, psi, kap = self._frame(s)
        dx, dy = px - fx, py - fy
        e = np.cos(psi) * dy - np.sin(psi) * dx
        dist = np.hypot(dx, dy)
        if strict and not np.all(unique):
            i = int(np.flatnonzero(~unique)[0])
            raise AmbiguousProjectionError(
                f"point (x, y) = ({float(px[i])!r}, {float(py[i])!r}) has no unique "
                f"nearest point on {_fmt(self)}: separate parts of the path lie at "
                f"the same distance {dist[i]:.6g} m ({int((~unique).sum())} "
                "ambiguous point(s))"
            )

        def out(a: np.ndarray) -> Any:
            return a.reshape(shape)[()]

        return Projection(
            s=out(s),
            e=out(e),
            heading=out(psi),
            curvature=out(kap),
            x=out(fx),
            y=out(fy),
            distance=out(dist),
            unique=out(unique),
        )

    def errors(
        self,
        x: ArrayLike,
        y: ArrayLike,
        psi: ArrayLike,
        *,
        s_guess: ArrayLike | None = None,
        strict: bool = False,
        window: float = 10.0,
    ) -> tuple[Array, Array, Array, Array]:
        """Path-frame errors of vehicle pose(s) ``(x, y, psi)``.

        Parameters
        ----------
        x, y : array_like
            Position of the tracked point [m].
        psi : array_like
            Vehicle heading [rad]; broadcast with ``x`` and ``y``.
        s_guess, strict, window
            As in :meth:`project`.

        Returns
        -------
        s : ndarray
            Arc length of the nearest point [m].
        e : ndarray
            Lateral error [m], positive to the left.
        theta : ndarray
            Heading error :math:`\\theta = \\psi - \\psi_C` wrapped to
            :math:`(-\\pi, \\pi]` [rad].
        curvature : ndarray
            Path curvature at ``s`` [1/m].

        Examples
        --------
        >>> from fws_control.paths import Straight
        >>> s, e, theta, k = Straight().errors(4.0, 1.5, 0.25)
        >>> float(s), float(e), float(theta), float(k)
        (4.0, 1.5, 0.25, 0.0)
        """
        h = _finite_array("psi", psi)
        proj = self.project(x, y, s_guess=s_guess, strict=strict, window=window)
        try:
            theta = _wrap_angle(h - proj.heading)
        except ValueError as exc:
            raise ValueError(
                f"psi must broadcast with x and y, got shape {h.shape} and "
                f"{np.shape(proj.s)}"
            ) from exc
        s, e, k = proj.s, proj.e, proj.curvature
        if theta.shape != np.shape(s):
            s, e, k = (np.broadcast_to(a, theta.shape) for a in (s, e, k))
        return s, e, theta[()], k

    # -- projection internals ---------------------------------------------

    def _newton_quantities(
        self, s: Array, px: Array, py: Array
    ) -> tuple[Array, Array, Array, Array]:
        """Slope g and curvature H of half the squared distance; e; distance."""
        fx, fy, psi, kap = self._frame(self._wrap(s))
        dx, dy = fx - px, fy - py
        c, sn = np.cos(psi), np.sin(psi)
        g = dx * c + dy * sn
        e = dx * sn - dy * c
        return g, 1.0 - kap * e, e, np.hypot(dx, dy)

    def _wrap(self, s: Array) -> Array:
        if self.closed:
            s = np.mod(s, self.length)
            return np.where(s >= self.length, 0.0, s)
        return s

    def _distance(self, s: Array, px: Array, py: Array) -> Array:
        fx, fy, _, _ = self._frame(self._wrap(s))
        return np.hypot(fx - px, fy - py)

    def _bounds(self) -> tuple[float, float]:
        if self.closed or not math.isfinite(self.length):
            return -math.inf, math.inf
        return 0.0, self.length

    def _local(
        self, px: Array, py: Array, s0: Array, window: float
    ) -> tuple[Array, NDArray[np.bool_]]:
        """Newton from the guesses; returns (s, accepted)."""
        lo, hi = self._bounds()
        n = px.size
        s = s0.astype(float).copy()
        active = np.ones(n, dtype=bool)
        ok = np.zeros(n, dtype=bool)
        for _ in range(_NEWTON_MAXITER):
            idx = np.flatnonzero(active)
            if idx.size == 0:
                break
            si = s[idx]
            g, H, e, _ = self._newton_quantities(si, px[idx], py[idx])
            at_end = ((si <= lo) & (g >= 0.0)) | ((si >= hi) & (g <= 0.0))
            # H <= 0: the point is at or beyond the local centre of curvature,
            # so the stationary point Newton heads for is not a minimum.
            bad = (H <= 1e-12) & ~at_end
            step = np.where(bad | at_end, 0.0, -g / np.where(bad, 1.0, H))
            step = np.clip(step, -window, window)
            new = np.clip(si + step, lo, hi)
            done = (np.abs(new - si) <= 1e-12 * (1.0 + np.abs(e))) & ~bad
            s[idx] = new
            active[idx[bad | done]] = False
            ok[idx[done]] = True
        idx = np.flatnonzero(ok)
        if idx.size:
            si = s[idx]
            jump = si - s0[idx]
            if self.closed:
                jump = (jump + 0.5 * self.length) % self.length - 0.5 * self.length
            good = np.abs(jump) <= window
            d_star = self._distance(si, px[idx], py[idx])
            offs = window * np.concatenate([-np.arange(1, 9), np.arange(1, 9)]) / 8.0
            samples = np.clip(si[:, None] + offs, lo, hi)
            d_nb = self._distance(samples, px[idx, None], py[idx, None])
            tol = _TIE_RTOL * (1.0 + d_star)
            good &= np.all(d_nb >= d_star[:, None] - tol[:, None], axis=1)
            ok[idx[~good]] = False
        return s, ok

    def _global(self, px: Array, py: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        """Globally nearest points by sampling and refinement: (s, distance, unique)."""
        # Paths are immutable, so the samples (and their KD-tree) are computed
        # once per path.
        cache = getattr(self, "_search_cache", None)
        if cache and "samples" in cache:
            S, X, Y = cache["samples"]
        else:
            S = self._search_samples()
            X, Y, _, _ = self._frame(S)
            if cache is not None:
                cache["samples"] = (S, X, Y)
        tree = None
        if _FIRST_PASS == "kdtree" or (
            _FIRST_PASS == "auto" and S.size >= _TREE_MIN_SAMPLES
        ):
            tree = cache.get("tree") if cache else None
            if tree is None:
                # (imported here: scipy.spatial brings scipy.sparse,
                # scipy.linalg and scipy.optimize, about 0.5 s of CPU that a
                # process without a dense projection never pays)
                from scipy.spatial import cKDTree

                tree = cKDTree(np.column_stack([X, Y]))
                if cache is not None:
                    cache["tree"] = tree
        n = px.size
        s_out, d_out = np.empty(n), np.empty(n)
        u_out = np.empty(n, dtype=bool)
        # bounds the (points, samples) arrays of the dense pass, and the
        # candidate lists of the tree pass (all samples in the worst case)
        chunk = max(1, _CHUNK // S.size)
        for i0 in range(0, n, chunk):
            sl = slice(i0, i0 + chunk)
            res = self._global_chunk(px[sl], py[sl], S, X, Y, tree)
            s_out[sl], d_out[sl], u_out[sl] = res
        return s_out, d_out, u_out

    def _candidates(
        self, px: Array, py: Array, S: Array, X: Array, Y: Array, tree: Any
    ) -> tuple[NDArray[np.intp], NDArray[np.bool_], Array, Array, float]:
        """Up to K local minima of the sampled distance per point (first pass).

        Returns sample indices ``j`` (n, K), their validity, their distances,
        the extended arc lengths ``S_ext`` and the largest sample gap ``h``.
        The path is 1-Lipschitz in s, so the true minimiser lies within h/2
        of a sample no farther than dmin + h/2: only local minima of the
        sampled distance within dmin + h can hold it. With a KD-tree only the
        samples within that radius are looked at (``scipy.spatial.cKDTree``:
        the nearest sample, then a ball query); the dense pass computes all
        distances. Both select the same candidates.
        """
        L = self.length
        m = S.size
        n = px.size
        if self.closed:
            S_ext = np.concatenate([[S[-1] - L], S, [S[0] + L]])
        else:
            S_ext = np.concatenate([[S[0]], S, [S[-1]]])
        h = float(np.max(np.diff(S_ext)))
        K = min(8, m)
        if tree is None:
            d = np.hypot(px[:, None] - X, py[:, None] - Y)
            if self.closed:
                left, right = np.roll(d, 1, axis=1), np.roll(d, -1, axis=1)
            else:
                inf = np.full((n, 1), np.inf)
                left = np.concatenate([inf, d[:, :-1]], axis=1)
                right = np.concatenate([d[:, 1:], inf], axis=1)
            dmin = d.min(axis=1)
            cand = (d <= left) & (d <= right) & (d <= dmin[:, None] + h)
            key = np.where(cand, d, np.inf)
            j = np.argsort(key, axis=1, kind="stable")[:, :K]
            dj = np.take_along_axis(key, j, axis=1)
            return j, np.isfinite(dj), dj, S_ext, h
        pts = np.column_stack([px, py])
        _, jmin = tree.query(pts)
        dmin = np.hypot(px - X[jmin], py - Y[jmin])
        # a little wider than dmin + h, then the exact test on hypot
        radius = (dmin + h) * (1.0 + 1e-9) + 1e-300
        lists = tree.query_ball_point(pts, radius)
        count = np.fromiter((len(q) for q in lists), dtype=np.intp, count=n)
        jj = np.fromiter(
            (j for q in lists for j in q), dtype=np.intp, count=int(count.sum())
        )
        row = np.repeat(np.arange(n), count)
        qx, qy = px[row], py[row]

        def dist(idx):
            return np.hypot(qx - X[idx], qy - Y[idx])

        d = dist(jj)
        if self.closed:
            left, right = dist((jj - 1) % m), dist((jj + 1) % m)
        else:
            left = np.where(jj > 0, dist(np.maximum(jj - 1, 0)), np.inf)
            right = np.where(jj < m - 1, dist(np.minimum(jj + 1, m - 1)), np.inf)
        # dmin exactly as the dense pass has it: the least hypot in the ball
        dmin = np.full(n, np.inf)
        np.minimum.at(dmin, row, d)
        cand = (d <= left) & (d <= right) & (d <= dmin[row] + h)
        row, jj, d = row[cand], jj[cand], d[cand]
        # the K nearest candidates of each point, in order of distance (ties
        # by sample index, as a stable sort of the dense rows would)
        order = np.lexsort((jj, d, row))
        row, jj, d = row[order], jj[order], d[order]
        first = np.searchsorted(row, np.arange(n))
        rank = np.arange(row.size) - first[row]
        keep = rank < K
        j = np.zeros((n, K), dtype=np.intp)
        dj = np.full((n, K), np.inf)
        j[row[keep], rank[keep]] = jj[keep]
        dj[row[keep], rank[keep]] = d[keep]
        return j, np.isfinite(dj), dj, S_ext, h

    def _global_chunk(
        self, px: Array, py: Array, S: Array, X: Array, Y: Array, tree: Any = None
    ) -> tuple[Array, Array, NDArray[np.bool_]]:
        L = self.length
        j, valid, d_cand, S_ext, h = self._candidates(px, py, S, X, Y, tree)
        K = j.shape[1]
        jj = j.ravel()
        a, b, s = S_ext[jj].copy(), S_ext[jj + 2].copy(), S[jj].copy()
        qx, qy = np.repeat(px, K), np.repeat(py, K)
        active = valid.ravel().copy()
        for _ in range(2 * _NEWTON_MAXITER):
            idx = np.flatnonzero(active)
            if idx.size == 0:
                break
            si = s[idx]
            g, H, e, _ = self._newton_quantities(si, qx[idx], qy[idx])
            a[idx] = np.where(g < 0.0, si, a[idx])
            b[idx] = np.where(g > 0.0, si, b[idx])
            newton = si - g / np.where(H > 0.0, H, 1.0)
            use = (H > 0.0) & (newton > a[idx]) & (newton < b[idx])
            new = np.where(use, newton, 0.5 * (a[idx] + b[idx]))
            tol = 1e-12 * (1.0 + np.abs(e))
            done = (np.abs(new - si) <= tol) | (b[idx] - a[idx] <= tol) | (g == 0.0)
            s[idx] = np.where(g == 0.0, si, new)
            active[idx[done]] = False
        # only the valid slots: the others (up to K - 1 per point) are unused
        vf = valid.ravel()
        d_ref = np.full(s.size, np.inf)
        d_ref[vf] = self._distance(s[vf], qx[vf], qy[vf])
        d_smp = d_cand.ravel()
        # Never worse than the sample the refinement started from.
        worse = d_ref > d_smp
        s = np.where(worse, S[jj], s)
        d_ref = np.where(worse, d_smp, d_ref)
        s = s.reshape(-1, K)
        dc = np.where(valid, d_ref.reshape(-1, K), np.inf)
        best = np.argmin(dc, axis=1)
        rows = np.arange(px.size)
        s_best, d_best = s[rows, best], dc[rows, best]
        unique = np.ones(px.size, dtype=bool)
        tol = _TIE_RTOL * (1.0 + d_best)
        tie = valid & (np.abs(dc - d_best[:, None]) <= tol[:, None])
        tie[rows, best] = False
        if np.any(tie):
            r, c = np.nonzero(tie)
            sa, sb = s_best[r], s[r, c]
            xa, ya, _, _ = self._frame(self._wrap(sa))
            xb, yb, _, _ = self._frame(self._wrap(sb))
            apart = np.hypot(xa - xb, ya - yb) > 1e-8 * (1.0 + d_best[r])
            delta = sb - sa
            if self.closed:
                delta = (delta + 0.5 * L) % L - 0.5 * L
            d_mid = self._distance(sa + 0.5 * delta, px[r], py[r])
            # Two minima separated by a rise in distance are two nearest
            # points; a flat valley (degenerate minimum) is one.
            bump = d_mid > np.maximum(d_best[r], dc[r, c]) + tol[r]
            amb = apart & bump
            unique[r[amb]] = False
        return self._wrap(s_best), d_best, unique

    # -- shared helpers for sampled paths ----------------------------------

    def _uniform_samples(self, h: float) -> Array:
        L = self.length
        m = max(8, math.ceil(L / h))
        if self.closed:
            return np.arange(m, dtype=np.float64) * (L / m)
        return np.linspace(0.0, L, m + 1, dtype=np.float64)


# --------------------------------------------------------------------------
# straight line


@value_repr
@dataclass(frozen=True)
class Straight(Path):
    """Straight line (by default the x-axis).

    Parameters
    ----------
    length : float or None, optional
        ``None`` (default) or ``math.inf``: unbounded in both directions, any
        ``s`` is valid. A finite value > 0 gives a segment ``s`` in
        ``[0, length]``, e.g. for a :class:`PathChain`.
    start : (float, float), default (0, 0)
        Point at ``s = 0`` [m].
    start_heading : float, default 0
        Direction of the line [rad].

    Raises
    ------
    ValueError
        If ``length`` is not > 0 or the placement is not finite.

    Examples
    --------
    >>> from fws_control.paths import Straight
    >>> line = Straight(length=20.0, start=(1.0, 2.0), start_heading=0.0)
    >>> [float(v) for v in line.position(5.0)], float(line.curvature(5.0))
    ([6.0, 2.0], 0.0)
    >>> Straight().length
    inf
    """

    # None (unbounded) becomes inf in __post_init__: a float from then on
    length: float | None = None  # type: ignore[assignment]
    start: tuple[float, float] = (0.0, 0.0)
    start_heading: float = 0.0

    _closed_form = True

    def __post_init__(self) -> None:
        if self.length is None or (
            isinstance(self.length, (int, float)) and self.length == math.inf
        ):
            L = math.inf
        else:
            L = _check_length(self.length)
        object.__setattr__(self, "length", L)
        object.__setattr__(self, "start", _check_start(self.start))
        object.__setattr__(
            self, "start_heading", _check_real("start_heading", self.start_heading)
        )

    @property
    def closed(self) -> bool:  # type: ignore[override]  # a constant here
        """Always False."""
        return False

    def placed(self, start: Sequence[float], start_heading: float) -> Straight:
        """Same line starting at another pose (see :meth:`Path.placed`).

        Parameters
        ----------
        start : (float, float)
            New start point ``(x0, y0)`` [m], finite.
        start_heading : float
            New start heading [rad] from the x-axis, counter-clockwise
            positive, finite.

        Returns
        -------
        Straight
            The same length, at the new pose.

        Examples
        --------
        >>> from fws_control.paths import Straight
        >>> Straight(length=2.0).placed((1.0, 1.0), 0.5).start
        (1.0, 1.0)
        """
        # start is checked (two finite numbers) by Straight itself
        return Straight(self.length, cast("tuple[float, float]", start), start_heading)

    def _frame(self, s: Array) -> tuple[Array, Array, Array, Array]:
        z = np.zeros_like(s)
        x, y, psi = _to_global(self.start, self.start_heading, s, z, z)
        return x, y, psi, z

    def _curvature(self, s: Array) -> Array:
        return np.zeros_like(s)

    def _curvature_rate(self, s: Array) -> Array:
        return np.zeros_like(s)

    def _global(self, px: Array, py: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        lx, ly = _to_local(self.start, self.start_heading, px, py)
        L = cast(float, self.length)  # inf, not None, after __post_init__
        s = np.clip(lx, 0.0, L) if math.isfinite(L) else lx
        return s, np.hypot(lx - s, ly), np.ones(px.size, dtype=bool)


# --------------------------------------------------------------------------
# circular arc


@dataclass(frozen=True, init=False, repr=False)
class Arc(Path):
    """Circular arc of constant curvature.

    Starts at ``start`` heading ``start_heading``; with the default placement
    the centre is at ``(0, 1/curvature)``, so for ``curvature > 0`` the
    circle lies above the x-axis and the point ``(0, -5)`` has ``e = -5``.

    Parameters
    ----------
    curvature : float
        Signed curvature [1/m], finite and nonzero (use :class:`Straight`
        for zero curvature). Positive turns left.
    length : float or None, optional
        ``None`` (default): the full circle, a closed path of length
        ``2*pi/|curvature|`` on which ``s`` wraps. A value in
        ``(0, 2*pi/|curvature|]``: an open arc segment.
    start : (float, float), default (0, 0)
        Point at ``s = 0`` [m].
    start_heading : float, default 0
        Heading at ``s = 0`` [rad].

    Attributes
    ----------
    kappa : float
        The constant curvature given as ``curvature`` (stored under another
        name because ``curvature(s)`` is the method every path has).
    length : float
        Arc length [m]; ``2*pi/|kappa|`` for the full circle.
    closed : bool
        True for the full circle (``length=None``).
    center : (float, float)
        Centre of the circle [m].
    radius : float
        ``1/|curvature|`` [m].

    Raises
    ------
    ValueError
        If ``curvature`` is zero or not finite, or ``length`` is out of range.

    Examples
    --------
    >>> import math
    >>> from fws_control.paths import Arc
    >>> arc = Arc(curvature=0.1)
    >>> arc.closed, round(arc.length, 9) == round(20 * math.pi, 9), arc.center
    (True, True, (0.0, 10.0))
    >>> p = arc.project(0.0, -5.0)
    >>> round(float(p.s), 12), round(float(p.e), 12)
    (0.0, -5.0)
    """

    kappa: float
    length: float
    start: tuple[float, float]
    start_heading: float
    closed: bool

    _closed_form = True

    def __init__(
        self,
        curvature: float,
        length: float | None = None,
        start: Sequence[float] = (0.0, 0.0),
        start_heading: float = 0.0,
    ) -> None:
        k = _check_real("curvature", curvature)
        if k == 0.0:
            raise ValueError(
                "curvature must be finite and nonzero (use Straight for zero "
                f"curvature), got {curvature!r}"
            )
        full = 2.0 * math.pi / abs(k)
        object.__setattr__(self, "kappa", k)
        object.__setattr__(self, "closed", length is None)
        L = (
            full
            if length is None
            else _check_length(
                length, upper=full, why=f" (one full turn at curvature={k!r})"
            )
        )
        object.__setattr__(self, "length", L)
        object.__setattr__(self, "start", _check_start(start))
        object.__setattr__(
            self, "start_heading", _check_real("start_heading", start_heading)
        )

    def __repr__(self) -> str:
        length = None if self.closed else self.length
        return (
            f"Arc(curvature={self.kappa!r}, length={length!r}, start={self.start!r}, "
            f"start_heading={self.start_heading!r})"
        )

    @property
    def radius(self) -> float:
        """Radius ``1/|curvature|`` [m]."""
        return 1.0 / abs(self.kappa)

    @property
    def center(self) -> tuple[float, float]:
        """Centre of the circle [m]."""
        x, y, _ = _to_global(
            self.start,
            self.start_heading,
            np.array(0.0),
            np.array(1.0 / self.kappa),
            np.array(0.0),
        )
        return float(x), float(y)

    def placed(self, start: Sequence[float], start_heading: float) -> Arc:
        """Same arc starting at another pose (see :meth:`Path.placed`).

        Parameters
        ----------
        start : (float, float)
            New start point ``(x0, y0)`` [m], finite.
        start_heading : float
            New start heading [rad] from the x-axis, counter-clockwise
            positive, finite.

        Returns
        -------
        Arc
            The same curvature and length (or full circle), at the new pose.

        Examples
        --------
        >>> from fws_control.paths import Arc
        >>> Arc(0.1, length=5.0).placed((0.0, 0.0), 3.14).length
        5.0
        """
        length = None if self.closed else self.length
        return Arc(self.kappa, length, start, start_heading)

    def _frame(self, s: Array) -> tuple[Array, Array, Array, Array]:
        k = self.kappa
        ks = k * s
        # 2 sin^2(ks/2) rather than 1 - cos(ks): no cancellation near s = 0.
        lx, ly = np.sin(ks) / k, 2.0 * np.sin(0.5 * ks) ** 2 / k
        x, y, psi = _to_global(self.start, self.start_heading, lx, ly, ks)
        return x, y, psi, np.full_like(s, k)

    def _curvature(self, s: Array) -> Array:
        return np.full_like(s, self.kappa)

    def _curvature_rate(self, s: Array) -> Array:
        return np.zeros_like(s)

    def _global(self, px: Array, py: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        k, R = self.kappa, 1.0 / abs(self.kappa)
        lx, ly = _to_local(self.start, self.start_heading, px, py)
        vx, vy = lx, ly - 1.0 / k
        rho = np.hypot(vx, vy)
        sg = math.copysign(1.0, k)
        # Foot point c + R v/|v|; on the circle k (r - c) = (sin ks, -cos ks).
        ks = np.arctan2(sg * vx, -sg * vy)
        full = 2.0 * math.pi * R
        s = np.mod(ks / k, full)
        s = np.where(s >= full, 0.0, s)
        # At the centre every point of the circle is equally near.
        unique = 2.0 * rho > _TIE_RTOL * (1.0 + R)
        if not self.closed:
            L = self.length
            outside = s > L
            d0 = np.hypot(lx, ly)
            xe, ye, _ = _to_global((0.0, 0.0), 0.0, *self._local_end())
            dL = np.hypot(lx - xe, ly - ye)
            s = np.where(outside, np.where(dL < d0, L, 0.0), s)
            tie = np.abs(d0 - dL) <= _TIE_RTOL * (1.0 + np.minimum(d0, dL))
            unique &= ~(outside & tie)
        d = np.abs(rho - R)
        if not self.closed:
            d = np.where(s == 0.0, np.hypot(lx, ly), d)
            xe, ye, _ = _to_global((0.0, 0.0), 0.0, *self._local_end())
            d = np.where(s == self.length, np.hypot(lx - xe, ly - ye), d)
        return s, d, unique

    def _local_end(self) -> tuple[Array, Array, Array]:
        k, L = self.kappa, self.length
        return (
            np.array(math.sin(k * L) / k),
            np.array(2.0 * math.sin(0.5 * k * L) ** 2 / k),
            np.array(0.0),
        )


# --------------------------------------------------------------------------
# clothoid


@value_repr
@dataclass(frozen=True)
class Clothoid(Path):
    """Clothoid (Euler spiral): curvature linear in arc length.

    :math:`\\kappa(s) = \\kappa_0 + (\\kappa_1 - \\kappa_0) s / L`, heading
    :math:`\\psi_0 + \\kappa_0 s + (\\kappa_1 - \\kappa_0) s^2 / (2L)`. The
    position integrals (Fresnel integrals in general position) are evaluated
    by composite 16-point Gauss-Legendre quadrature with at most 1 rad of
    heading change per panel, which is accurate to round-off and has no
    special case or cancellation when the curvature is (nearly) constant.

    Parameters
    ----------
    curvature_start, curvature_end : float
        Curvature at ``s = 0`` and ``s = length`` [1/m].
    length : float
        Length [m], finite and > 0.
    start : (float, float), default (0, 0)
        Point at ``s = 0`` [m].
    start_heading : float, default 0
        Heading at ``s = 0`` [rad].

    Raises
    ------
    ValueError
        If a curvature is not finite or ``length`` is not finite and > 0.

    Examples
    --------
    >>> from fws_control.paths import Clothoid
    >>> c = Clothoid(0.0, 0.1, length=10.0)
    >>> round(float(c.heading(10.0)), 12)  # (0 + 0.1) / 2 * 10
    0.5
    >>> [round(float(v), 6) for v in c.position(10.0)]
    [9.752877, 1.63714]
    """

    curvature_start: float
    curvature_end: float
    length: float
    start: tuple[float, float] = (0.0, 0.0)
    start_heading: float = 0.0
    _equivalent: Path | None = field(init=False, repr=False, compare=False)
    _search_cache: dict = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        k0 = _check_real("curvature_start", self.curvature_start)
        k1 = _check_real("curvature_end", self.curvature_end)
        L = _check_length(self.length)
        start = _check_start(self.start)
        psi0 = _check_real("start_heading", self.start_heading)
        for name, v in (
            ("curvature_start", k0),
            ("curvature_end", k1),
            ("length", L),
            ("start", start),
            ("start_heading", psi0),
        ):
            object.__setattr__(self, name, v)
        # Constant curvature: project with the arc/line closed form, which
        # also flags the centre of the arc as ambiguous.
        equiv: Path | None = None
        if k0 == k1:
            if k0 == 0.0:
                equiv = Straight(L, start, psi0)
            elif L <= 2.0 * math.pi / abs(k0):
                equiv = Arc(k0, L, start, psi0)
        object.__setattr__(self, "_equivalent", equiv)

    @property
    def closed(self) -> bool:  # type: ignore[override]  # a constant here
        """Always False."""
        return False

    @property
    def sharpness(self) -> float:
        """Curvature rate ``(curvature_end - curvature_start) / length`` [1/m^2]."""
        return (self.curvature_end - self.curvature_start) / self.length

    def placed(self, start: Sequence[float], start_heading: float) -> Clothoid:
        """Same clothoid starting at another pose (see :meth:`Path.placed`).

        Parameters
        ----------
        start : (float, float)
            New start point ``(x0, y0)`` [m], finite.
        start_heading : float
            New start heading [rad] from the x-axis, counter-clockwise
            positive, finite.

        Returns
        -------
        Clothoid
            The same curvatures and length, at the new pose.

        Examples
        --------
        >>> from fws_control.paths import Clothoid
        >>> Clothoid(0.0, 0.1, 10.0).placed((1.0, 2.0), 0.0).start
        (1.0, 2.0)
        """
        return Clothoid(
            self.curvature_start,
            self.curvature_end,
            self.length,
            cast("tuple[float, float]", start),  # checked by Clothoid itself
            start_heading,
        )

    def _local_heading(self, s: Array) -> Array:
        return s * (self.curvature_start + 0.5 * self.sharpness * s)

    def _panels(self) -> tuple[float, Array, Array]:
        """Panel width and the local position at every panel start (cached).

        ``P = 1 + int(kmax * L)`` panels of equal length, so the heading turns
        by less than 1 rad in each; the positions at their starts are sums of
        16-point Gauss-Legendre integrals, computed once per clothoid.
        """
        cache = self._search_cache
        if "panels" not in cache:
            kmax = max(abs(self.curvature_start), abs(self.curvature_end))
            P = 1 + int(kmax * self.length)
            width = self.length / P
            a = np.arange(P) * width
            u = a[:, None] + 0.5 * width * (_GL16_X + 1.0)
            lpsi = self._local_heading(u)
            dx = 0.5 * width * (np.cos(lpsi) @ _GL16_W)
            dy = 0.5 * width * (np.sin(lpsi) @ _GL16_W)
            X0 = np.concatenate([[0.0], np.cumsum(dx)])
            Y0 = np.concatenate([[0.0], np.cumsum(dy)])
            cache["panels"] = (width, X0, Y0)
        return cache["panels"]

    def _frame(self, s: Array) -> tuple[Array, Array, Array, Array]:
        # Position = position at the start of s's panel + one 16-point Gauss
        # integral over less than 1 rad of turning: memory and time O(1) per
        # point, whatever the total turning (integrating from 0 for each
        # point cost O(kmax L) per point: 6 GB at 1000 rad for the search).
        width, X0, Y0 = self._panels()
        k = np.minimum(np.maximum(np.floor(s / width), 0), X0.size - 2).astype(np.intp)
        a = k * width
        half = 0.5 * (s - a)
        u = (a + half)[..., None] + half[..., None] * _GL16_X
        lpsi_u = self._local_heading(u)
        lx = X0[k] + half * (np.cos(lpsi_u) @ _GL16_W)
        ly = Y0[k] + half * (np.sin(lpsi_u) @ _GL16_W)
        lpsi = self._local_heading(s)
        x, y, psi = _to_global(self.start, self.start_heading, lx, ly, lpsi)
        return x, y, psi, self.curvature_start + self.sharpness * s

    def _curvature(self, s: Array) -> Array:
        return self.curvature_start + self.sharpness * s

    def _curvature_rate(self, s: Array) -> Array:
        return np.full_like(s, self.sharpness)

    def _search_samples(self) -> Array:
        kmax = max(abs(self.curvature_start), abs(self.curvature_end))
        h = self.length / 32.0 if kmax == 0.0 else min(self.length / 32.0, 0.25 / kmax)
        return self._uniform_samples(h)

    def _global(self, px: Array, py: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        if self._equivalent is not None:
            return self._equivalent._global(px, py)
        return super()._global(px, py)


# --------------------------------------------------------------------------
# spline


@dataclass(frozen=True, repr=False)
class Spline(Path):
    """C² cubic spline through 2-D waypoints, parameterised by arc length.

    A cubic spline is fitted to the waypoints on the chord-length parameter
    (``natural`` end conditions -- zero curvature at the ends -- for an open
    spline, ``periodic`` for a closed one). Its arc length is tabulated with
    8-point Gauss-Legendre quadrature on 16 sub-panels per waypoint interval,
    and ``s`` is inverted to the spline parameter by cubic Hermite
    interpolation of the table followed by two Newton steps, so ``s`` is the
    true arc length to round-off. Heading and curvature come from the
    analytic derivatives, :math:`\\kappa = (x'y'' - y'x'')/(x'^2+y'^2)^{3/2}`,
    so the curvature is continuous (the curvature rate jumps at waypoints).

    Parameters
    ----------
    waypoints : array_like, shape (N, 2)
        Points [m], finite, no two consecutive ones equal; N >= 3 distinct
        points (a closed spline needs 3 distinct points besides the repeated
        first one).
    closed : bool or None, optional
        ``None`` (default): closed if the first and last waypoints coincide
        (to ``1e-9`` of the course size). ``True``: closed (the first
        waypoint is appended if needed). ``False``: open even if the ends
        coincide.

    Attributes
    ----------
    length : float
        Arc length [m].
    waypoint_s : ndarray
        Arc length at each waypoint [m], read-only; for a closed spline the
        last entry is ``length``, where the first waypoint comes round again.

    Raises
    ------
    ValueError
        For a wrong shape, non-finite or repeated consecutive waypoints, too
        few points, or waypoints that give a spline with a cusp.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.paths import Spline
    >>> t = np.linspace(0.0, 2.0 * np.pi, 25)
    >>> ring = Spline(np.column_stack([10 * np.cos(t), 10 * np.sin(t)]))
    >>> ring.closed, round(ring.length, 3), round(float(ring.curvature(5.0)), 3)
    (True, 62.831, 0.1)

    (The circle's length is 62.832 m: 25 waypoints give a spline 0.5 mm
    shorter.)
    """

    waypoints: Any
    # None (decided from the waypoints) becomes a bool in __post_init__
    closed: bool | None = None  # type: ignore[assignment]
    length: float = field(init=False)
    _cs: CubicSpline = field(init=False, compare=False)
    _t_tab: Array = field(init=False, compare=False)
    _s_tab: Array = field(init=False, compare=False)
    _inv: CubicHermiteSpline = field(init=False, compare=False)
    _knots_s: Array = field(init=False, compare=False)
    _search_cache: dict = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        w = np.array(check_real("waypoints", self.waypoints), dtype=float)
        if w.ndim != 2 or w.shape[1] != 2:
            raise ValueError(f"waypoints must have shape (N, 2), got shape {w.shape}")
        bad = ~np.isfinite(w).all(axis=1)
        if np.any(bad):
            i = int(np.flatnonzero(bad)[0])
            raise ValueError(
                f"waypoints must be finite, got {w[i].tolist()} at row {i}"
            )
        if w.shape[0] < 3:
            raise ValueError(f"waypoints must have N >= 3 rows, got N = {w.shape[0]}")
        scale = max(float(np.ptp(w, axis=0).max()), 1e-300)
        steps = np.hypot(*np.diff(w, axis=0).T)
        rep = steps <= 1e-12 * scale
        if np.any(rep):
            i = int(np.flatnonzero(rep)[0])
            raise ValueError(
                "waypoints must not repeat consecutively, got waypoints["
                f"{i}] == waypoints[{i + 1}] == {w[i].tolist()}"
            )
        coincide = math.hypot(*(w[-1] - w[0])) <= 1e-9 * scale
        flag = _check_closed(self.closed)
        closed = coincide if flag is None else flag
        if closed:
            pts = np.vstack([w[:-1] if coincide else w, w[:1]])
            if pts.shape[0] - 1 < 3:
                raise ValueError(
                    "waypoints of a closed spline must hold >= 3 distinct points, "
                    f"got {pts.shape[0] - 1}"
                )
        else:
            pts = w
        # (imported here: scipy.interpolate brings scipy.optimize, scipy.linalg
        # and scipy.special, about 0.4 s of CPU that a process without a
        # spline never pays)
        from scipy.interpolate import CubicHermiteSpline, CubicSpline

        t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))])
        cs = CubicSpline(t, pts, axis=0, bc_type="periodic" if closed else "natural")

        # Arc-length table: 16 sub-panels per interval, 8-point Gauss each.
        sub = 16
        frac = np.arange(sub)[None, :] / sub
        t_tab = np.append((t[:-1, None] + np.diff(t)[:, None] * frac).ravel(), t[-1])
        half = 0.5 * np.diff(t_tab)
        nodes = 0.5 * (t_tab[:-1] + t_tab[1:])[:, None] + half[:, None] * _GL8_X
        speed_nodes = np.hypot(*np.moveaxis(cs(nodes, 1), -1, 0))
        speed_tab = np.hypot(*cs(t_tab, 1).T)
        vmax = max(float(speed_nodes.max()), float(speed_tab.max()))
        vmin = min(float(speed_nodes.min()), float(speed_tab.min()))
        if vmin <= 1e-6 * vmax:
            i = int(np.argmin(speed_tab) // sub)
            raise ValueError(
                "waypoints give a spline with a cusp (zero speed) near waypoint "
                f"{i} at {pts[min(i, len(pts) - 1)].tolist()}; move or add waypoints"
            )
        # A cusp where the spline doubles back (both components of the
        # derivative vanish at the same t, e.g. collinear waypoints that turn
        # back) need not be sampled at zero speed: detect it as a reversal of
        # the tangent between neighbouring samples (16 per waypoint interval
        # plus the Gauss nodes), which no trackable bend makes.
        t_all = np.concatenate([t_tab, nodes.ravel()])
        order = np.argsort(t_all, kind="stable")
        t_all = t_all[order]
        tan = cs(t_all, 1)
        tan = tan / np.hypot(tan[:, 0], tan[:, 1])[:, None]
        dots = np.sum(tan[:-1] * tan[1:], axis=1)
        if closed:
            dots = np.append(dots, float(tan[-1] @ tan[0]))
        back = dots <= 0.0
        if np.any(back):
            j = int(np.flatnonzero(back)[0])
            tj = 0.5 * (t_all[j] + t_all[min(j + 1, t_all.size - 1)])
            i = int(np.argmin(np.abs(t - tj))) % (len(pts) - 1 if closed else len(pts))
            raise ValueError(
                "waypoints give a spline with a cusp (it doubles back on itself) "
                f"near waypoint {i} at {pts[i].tolist()}; move or add waypoints "
                "so that the path turns instead of reversing"
            )
        s_tab = np.concatenate([[0.0], np.cumsum(half * (speed_nodes @ _GL8_W))])
        inv = CubicHermiteSpline(s_tab, t_tab, 1.0 / speed_tab)

        object.__setattr__(self, "waypoints", tuple(map(tuple, w.tolist())))
        object.__setattr__(self, "closed", closed)
        object.__setattr__(self, "length", float(s_tab[-1]))
        object.__setattr__(self, "_cs", cs)
        object.__setattr__(self, "_t_tab", t_tab)
        object.__setattr__(self, "_s_tab", s_tab)
        object.__setattr__(self, "_inv", inv)
        knots_s = s_tab[::sub].copy()
        knots_s.flags.writeable = False
        object.__setattr__(self, "_knots_s", knots_s)

    def __repr__(self) -> str:
        return (
            f"Spline(<{len(self.waypoints)} waypoints from {self.waypoints[0]}>, "
            f"closed={self.closed}, length={self.length:.6g})"
        )

    @property
    def waypoint_s(self) -> Array:
        """Arc length at each distinct waypoint [m] (the last = ``length``)."""
        return self._knots_s

    def placed(self, start: Sequence[float], start_heading: float) -> Spline:
        """Same spline moved rigidly so it starts at the given pose.

        Parameters
        ----------
        start : (float, float)
            New first waypoint ``(x0, y0)`` [m], finite.
        start_heading : float
            New heading of the spline's tangent at its start [rad] from the
            x-axis, counter-clockwise positive, finite; the waypoints are
            rotated about the first one to match it.

        Returns
        -------
        Spline
            Spline through the moved waypoints (same `closed`).

        Examples
        --------
        >>> from fws_control.paths import Spline
        >>> sp = Spline([[0, 0], [5, 1], [10, 0]]).placed((1.0, 1.0), 0.0)
        >>> round(float(sp.heading(0.0)), 12), sp.waypoints[0]
        (0.0, (1.0, 1.0))
        """
        x0, y0 = _check_start(start)
        psi = _check_real("start_heading", start_heading)
        w = np.asarray(self.waypoints)
        d1 = self._cs(0.0, 1)
        rot = psi - math.atan2(d1[1], d1[0])
        c, s = math.cos(rot), math.sin(rot)
        rel = w - w[0]
        new = np.column_stack(
            [x0 + c * rel[:, 0] - s * rel[:, 1], y0 + s * rel[:, 0] + c * rel[:, 1]]
        )
        return Spline(new, closed=self.closed)

    def _t_of_s(self, s: Array) -> Array:
        t = self._inv(s)
        t_tab, s_tab, cs = self._t_tab, self._s_tab, self._cs
        for _ in range(2):
            k = np.clip(np.searchsorted(t_tab, t, side="right") - 1, 0, t_tab.size - 2)
            a = t_tab[k]
            half = 0.5 * (t - a)
            nodes = (0.5 * (a + t))[..., None] + half[..., None] * _GL8_X
            speed = np.hypot(*np.moveaxis(cs(nodes, 1), -1, 0))
            S = s_tab[k] + half * (speed @ _GL8_W)
            v = np.hypot(*np.moveaxis(cs(t, 1), -1, 0))
            t = t - (S - s) / v
        return t

    def _derivs(self, s: Array) -> tuple[Array, ...]:
        t = self._t_of_s(s)
        p0, p1, p2 = (np.moveaxis(self._cs(t, k), -1, 0) for k in range(3))
        return p0[0], p0[1], p1[0], p1[1], p2[0], p2[1], t

    def _frame(self, s: Array) -> tuple[Array, Array, Array, Array]:
        x, y, xp, yp, xpp, ypp, _ = self._derivs(s)
        v2 = xp * xp + yp * yp
        return x, y, np.arctan2(yp, xp), (xp * ypp - yp * xpp) / v2**1.5

    def _curvature_rate(self, s: Array) -> Array:
        _, _, xp, yp, xpp, ypp, t = self._derivs(s)
        p3 = np.moveaxis(self._cs(t, 3), -1, 0)
        v2 = xp * xp + yp * yp
        v = np.sqrt(v2)
        num = xp * ypp - yp * xpp
        dnum = xp * p3[1] - yp * p3[0]
        dk_dt = dnum / v**3 - 3.0 * num * (xp * xpp + yp * ypp) / v**5
        return dk_dt / v

    def _search_samples(self) -> Array:
        base = self._s_tab[::2]
        ds = np.diff(base)
        kap = np.abs(self._frame(base)[3])
        kmax = np.maximum(kap[:-1], kap[1:])
        # At most a quarter radian of turning between samples.
        n = np.maximum(1, np.ceil(kmax * ds / 0.25)).astype(int)
        starts = np.repeat(base[:-1], n)
        offs = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
        S = starts + np.repeat(ds / n, n) * offs
        if not self.closed:
            S = np.append(S, self.length)
        return S


# --------------------------------------------------------------------------
# chain


@value_repr
@dataclass(frozen=True)
class PathChain(Path):
    """Segments joined end to start with continuous position and heading.

    The first segment keeps its placement; each later segment is moved
    rigidly (:meth:`Path.placed`) to start at the previous segment's end pose.
    ``s`` runs over the segments in order; at a joint the following segment
    provides the values (curvature may jump there).

    Parameters
    ----------
    segments : sequence of Path
        Open paths of finite length (e.g. ``Straight(length=...)``,
        ``Arc(k, length=...)``, :class:`Clothoid`, an open :class:`Spline`,
        another open :class:`PathChain`).
    closed : bool or None, optional
        ``None`` (default): closed if the end pose equals the start pose to
        ``1e-9`` (relative to the length for positions; radians for the
        heading). ``True``: require that (to ``1e-6``). ``False``: open.

    Attributes
    ----------
    length : float
        Sum of the segment lengths [m].
    offsets : ndarray
        Arc length at the start of each segment, plus ``length`` at the end.

    Raises
    ------
    ValueError
        If ``segments`` is empty, holds something that is not a finite open
        path, or ``closed=True`` but the chain does not close.

    Examples
    --------
    >>> from fws_control.paths import PathChain, Straight, Clothoid, Arc
    >>> chain = PathChain([Straight(length=20), Clothoid(0, 0.1, 10),
    ...                    Arc(0.1, length=20)])
    >>> chain.length, chain.offsets.tolist()
    (50.0, [0.0, 20.0, 30.0, 50.0])
    >>> round(float(chain.heading(30.0)), 12)  # 0 + (0 + 0.1) / 2 * 10
    0.5
    """

    segments: Sequence[Path]
    # None (decided from the segments) becomes a bool in __post_init__
    closed: bool | None = None  # type: ignore[assignment]
    length: float = field(init=False)
    offsets: Array = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        _check_closed(self.closed)
        try:
            segs = list(self.segments)
        except TypeError as exc:
            raise ValueError(
                f"segments must be a sequence of Path objects, got {self.segments!r}"
            ) from exc
        if not segs:
            raise ValueError(
                "segments must hold at least one path, got an empty sequence"
            )
        for i, seg in enumerate(segs):
            if not isinstance(seg, Path):
                raise ValueError(f"segments[{i}] must be a Path, got {seg!r}")
            if seg.closed or not math.isfinite(seg.length):
                raise ValueError(
                    f"segments[{i}] must be an open path of finite length, got "
                    f"{_fmt(seg)} (closed={seg.closed}, length={seg.length})"
                )
        placed = [segs[0]]
        for seg in segs[1:]:
            end, psi = placed[-1]._end_pose()
            placed.append(seg.placed(end, psi))
        lengths = np.array([seg.length for seg in placed])
        offsets = np.concatenate([[0.0], np.cumsum(lengths)])
        L = float(offsets[-1])
        offsets.flags.writeable = False
        fx0, fy0, fpsi0, _ = placed[0]._frame(np.array([0.0]))
        x0, y0, psi0 = float(fx0[0]), float(fy0[0]), float(fpsi0[0])
        (x1, y1), psi1 = placed[-1]._end_pose()
        gap = math.hypot(x1 - x0, y1 - y0)
        turn = abs(float(_wrap_angle(psi1 - psi0)))
        if self.closed is None:
            closed = gap <= 1e-9 * (1.0 + L) and turn <= 1e-9
        elif self.closed:
            if gap > 1e-6 * (1.0 + L) or turn > 1e-6:
                raise ValueError(
                    "closed=True needs the chain to end at its start pose, but the "
                    f"end is {gap:.6g} m and {turn:.6g} rad away from it"
                )
            closed = True
        else:
            closed = False
        object.__setattr__(self, "segments", tuple(placed))
        object.__setattr__(self, "closed", closed)
        object.__setattr__(self, "length", L)
        object.__setattr__(self, "offsets", offsets)

    def placed(self, start: Sequence[float], start_heading: float) -> PathChain:
        """The chain moved rigidly to start at the given pose.

        Parameters
        ----------
        start : (float, float)
            New start point ``(x0, y0)`` of the first segment [m], finite.
        start_heading : float
            New start heading of the first segment [rad] from the x-axis,
            counter-clockwise positive, finite; the other segments follow.

        Returns
        -------
        PathChain
            The same segments (same `closed`), at the new pose.

        Examples
        --------
        >>> from fws_control.paths import PathChain, Straight
        >>> c = PathChain([Straight(length=1.0), Straight(length=2.0)])
        >>> [float(v) for v in c.placed((0.0, 5.0), 0.0).position(3.0)]
        [3.0, 5.0]
        """
        first = self.segments[0].placed(start, start_heading)
        return PathChain([first, *self.segments[1:]], closed=self.closed)

    def _dispatch(self, s: Array) -> tuple[NDArray[np.intp], Array]:
        n = len(self.segments)
        # np.minimum/np.maximum rather than np.clip: the same numbers, without
        # np.clip's overhead per call (the model's right-hand side asks for one
        # point at a time)
        idx = np.searchsorted(self.offsets, s, side="right") - 1
        idx = np.minimum(np.maximum(idx, 0), n - 1)
        lengths = self.offsets[1:] - self.offsets[:-1]
        local = np.minimum(np.maximum(s - self.offsets[idx], 0.0), lengths[idx])
        return idx, local

    @staticmethod
    def _hit(idx: NDArray[np.intp]) -> Any:
        """The segments that `idx` hits, each once."""
        return (int(idx),) if np.ndim(idx) == 0 else np.unique(idx)

    def _frame(self, s: Array) -> tuple[Array, Array, Array, Array]:
        idx, local = self._dispatch(s)
        out = [np.empty_like(s) for _ in range(4)]
        # only the segments hit: a point or a short step hits one or two of
        # a chain's many, and each segment visited costs a few array calls
        for i in self._hit(idx):
            m = idx == i
            for o, v in zip(out, self.segments[i]._frame(local[m]), strict=True):
                o[m] = v
        return out[0], out[1], out[2], out[3]

    def _curvature(self, s: Array) -> Array:
        idx, local = self._dispatch(s)
        out = np.empty_like(s)
        for i in self._hit(idx):
            m = idx == i
            out[m] = self.segments[i]._curvature(local[m])
        return out

    def _curvature_rate(self, s: Array) -> Array:
        idx, local = self._dispatch(s)
        out = np.empty_like(s)
        for i in self._hit(idx):
            m = idx == i
            out[m] = self.segments[i]._curvature_rate(local[m])
        return out

    def _global(self, px: Array, py: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
        res = [seg._global(px, py) for seg in self.segments]
        S = np.stack([r[0] for r in res])
        D = np.stack([r[1] for r in res])
        U = np.stack([r[2] for r in res])
        best = np.argmin(D, axis=0)
        cols = np.arange(px.size)
        d_best = D[best, cols]
        unique = U[best, cols].copy()
        s_best = S[best, cols] + self.offsets[best]
        tol = _TIE_RTOL * (1.0 + d_best)
        tie = np.abs(D - d_best) <= tol
        tie[best, cols] = False
        if np.any(tie):
            fx, fy, _, _ = self._frame(self._wrap(s_best))
            for i, seg in enumerate(self.segments):
                m = tie[i]
                if np.any(m):
                    xi, yi, _, _ = seg._frame(S[i, m])
                    # Neighbouring segments share the joint: the same point.
                    apart = np.hypot(xi - fx[m], yi - fy[m]) > 1e-8 * (1.0 + d_best[m])
                    unique[np.flatnonzero(m)[apart]] = False
        return self._wrap(s_best), d_best, unique
