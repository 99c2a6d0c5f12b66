r"""Standard manoeuvres as paths with their cone gates.

Each manoeuvre is a :class:`Manoeuvre`: a :class:`~fws_control.paths.Path`
(the centre line to track, curvature continuous: straight segments joined by
clothoid S-bends) plus the cone gates a vehicle must pass, for plotting and
for the "cones hit" count (:meth:`Manoeuvre.cones_hit`).

Geometry (``b``: vehicle width [m]; ``x`` along the course, ``y`` to the
left; gate widths are between the cone lines):

ISO 3888-1 double lane change (:func:`double_lane_change`)
    ======= ================ =============== ============================
    section length [m]       width [m]       lateral position
    ======= ================ =============== ============================
    1       15               1.1 b + 0.25    entry lane, centred on y = 0
    2       30               —               transition
    3       25               1.2 b + 0.25    right cone line at y = 3.5 m
    4       25               —               transition
    5       15               1.3 b + 0.25    right line aligned with 1
    ======= ================ =============== ============================

ISO 3888-2 obstacle avoidance (:func:`obstacle_avoidance`)
    ======= ================ =============== ============================
    section length [m]       width [m]       lateral position
    ======= ================ =============== ============================
    1       12               1.1 b + 0.25    entry lane, centred on y = 0
    2       13.5             —               transition
    3       11               b + 1           right line 1 m left of 1's left
    4       12.5             —               transition
    5       12               3               right line aligned with 1
    ======= ================ =============== ============================

The lateral positions follow the layout of the standards' figures as
implemented in Project Chrono's ISO 3888 double-lane-change demo; the
centre line runs through the middle of each gate. Cones stand at both ends
and the middle of every gate line.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .hints import RealArrayLike
from .paths import Arc, Clothoid, Path, PathChain, Straight
from .reprs import value_repr
from .validation import check_finite, check_positive, check_scalar, check_type

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "Gate",
    "Manoeuvre",
    "double_lane_change",
    "obstacle_avoidance",
    "slalom",
    "constant_radius",
    "s_bend",
    "ISO3888_1_SECTIONS",
    "ISO3888_2_SECTIONS",
]

#: ISO 3888-1 sections: (length [m], width as (factor of b, + m) or None).
ISO3888_1_SECTIONS = (
    (15.0, (1.1, 0.25)),
    (30.0, None),
    (25.0, (1.2, 0.25)),
    (25.0, None),
    (15.0, (1.3, 0.25)),
)

#: ISO 3888-2 sections; the exit width is 3 m (b-independent).
ISO3888_2_SECTIONS = (
    (12.0, (1.1, 0.25)),
    (13.5, None),
    (11.0, (1.0, 1.0)),
    (12.5, None),
    (12.0, (0.0, 3.0)),
)


def _check_name(name) -> None:
    if not isinstance(name, str):
        raise TypeError(f"name must be a str, got {name!r} ({type(name).__name__})")


def _positive(name: str, value) -> float:
    """A finite real scalar > 0."""
    v = check_scalar(name, value)
    if v <= 0.0:
        raise ValueError(f"{name} must be finite and > 0 m, got {value!r}")
    return v


@value_repr
@dataclass(frozen=True)
class Gate:
    """A lane section between two lines of cones.

    Attributes
    ----------
    x_start, x_end : float
        Longitudinal extent [m].
    y_right, y_left : float
        Lateral positions of the right and left cone lines [m].
    name : str
        E.g. ``"section 1"``.

    Examples
    --------
    >>> from fws_control.manoeuvres import Gate
    >>> g = Gate(30.0, 45.0, -1.2, 1.2, "section 1")
    >>> round(g.width, 9), g.centre, g.cones().shape
    (2.4, 0.0, (6, 2))
    """

    x_start: float
    x_end: float
    y_right: float
    y_left: float
    name: str = ""

    def __post_init__(self) -> None:
        # finite real scalars (issue 13: NaN, inf and bools were stored)
        for f in ("x_start", "x_end", "y_right", "y_left"):
            object.__setattr__(self, f, check_scalar(f, getattr(self, f)))
        _check_name(self.name)

    @property
    def width(self) -> float:
        """Distance between the cone lines [m]."""
        return self.y_left - self.y_right

    @property
    def centre(self) -> float:
        """Lateral position of the gate's centre line [m]."""
        return 0.5 * (self.y_left + self.y_right)

    def cones(self) -> np.ndarray:
        """Cone positions, shape ``(6, 2)``: both lines at start, middle, end."""
        xs = (self.x_start, 0.5 * (self.x_start + self.x_end), self.x_end)
        return np.array([(x, y) for y in (self.y_right, self.y_left) for x in xs])


def s_bend(offset: float, length: float) -> list[Clothoid]:
    r"""Four clothoids that shift the path by `offset` over `length` in x.

    Curvature ``0 -> k -> 0 -> -k -> 0`` linear in arc length: the path
    leaves and rejoins straight lines with continuous heading and curvature.
    The bend's shape depends only on its peak heading ``k * seg`` (``seg``
    the length of each clothoid) and its size scales with ``seg``: the peak
    heading is solved so that the ratio of lateral shift to longitudinal
    extent is ``|offset| / length`` (regula falsi with the Illinois
    correction, to a step of 4 eps relative; below a ratio of 5e-9 the
    small-angle limit, peak heading twice the ratio, is exact to double
    precision), and ``seg`` then scales the bend to `length`.

    Parameters
    ----------
    offset : float
        Lateral shift [m] (positive: to the left).
    length : float
        Longitudinal extent [m], > 0.

    Returns
    -------
    list of Clothoid

    Raises
    ------
    ValueError
        If `offset` is not finite, `length` is not positive and finite, or
        ``|offset| >= length / 2``.

    Examples
    --------
    >>> from fws_control.manoeuvres import s_bend
    >>> from fws_control.paths import PathChain
    >>> chain = PathChain(s_bend(3.0, 30.0))
    >>> [round(float(v), 9) for v in chain.position(chain.length)]
    [30.0, 3.0]
    """
    offset = float(check_finite("offset", offset))
    length = float(check_positive("length", length))
    if offset == 0.0:
        return [Clothoid(0.0, 0.0, length)]
    if abs(offset) >= 0.5 * length:
        raise ValueError(
            f"offset must be below half the length, got {offset!r} over {length!r} m"
        )

    def pieces(k, seg):
        return [
            Clothoid(0.0, k, seg),
            Clothoid(k, 0.0, seg),
            Clothoid(0.0, -k, seg),
            Clothoid(-k, 0.0, seg),
        ]

    def unit_end(theta):
        # the end of the bend with seg = 1 and peak heading theta
        chain = PathChain(pieces(theta, 1.0))
        x, y = chain.position(chain.length)
        return float(x), float(y)

    def excess(theta):
        x, y = unit_end(theta)
        return y / x - ratio

    # y / x = (theta / 2) (1 + theta^2 / 12 + ...) grows with the peak
    # heading theta to 1 at a quarter turn (there the heading's symmetric
    # profile makes x = y), and (y / x) / theta stays within [1/2, 2/pi]:
    # the root lies between ratio and 4 ratio, and below pi/2 for every
    # ratio below 1/2. Where theta^2 / 12 is below double precision the
    # limit theta = 2 ratio is exact, and solving the computed y / x, whose
    # rounding is absolute, would only lose digits.
    ratio = abs(offset) / length
    if ratio <= _SMALL_BEND:
        theta = 2.0 * ratio
    else:
        theta = _regula_falsi(excess, ratio, min(4.0 * ratio, 0.5 * math.pi))
    seg = length / unit_end(theta)[0]
    return pieces(math.copysign(theta / seg, offset), seg)


#: Largest ratio |offset| / length at which s_bend takes the small-angle
#: limit: there theta^2 / 12 <= 1e-16.
_SMALL_BEND = 5e-9


def _regula_falsi(f: Callable[[float], float], lo: float, hi: float) -> float:
    """s_bend's peak heading: a root of `f` between `lo` > 0 and `hi`.

    Regula falsi with the Illinois correction (an end kept twice has its
    value halved), which converges superlinearly on a smooth monotonic `f`;
    it stops when a step is below ``4 eps |x|`` (brentq's default relative
    tolerance, here on the step where brentq tests the bracket's width). A
    few lines here instead of
    ``scipy.optimize.brentq``: its import (about 0.3 s of CPU beyond
    scipy.linalg) cost a process building a course ten times the solve.
    """
    f_lo, f_hi = f(lo), f(hi)
    if f_lo == 0.0:
        return lo
    if f_hi == 0.0:
        return hi
    if (f_lo > 0.0) == (f_hi > 0.0):
        raise ValueError(
            f"the bend has no solution between {lo!r} and {hi!r} rad of peak "
            f"heading (the function is {f_lo!r} and {f_hi!r} there)"
        )
    rtol = 4.0 * np.finfo(float).eps
    x = lo
    kept = 0  # +1: hi was kept last time, -1: lo was
    for _ in range(200):
        x_new = (lo * f_hi - hi * f_lo) / (f_hi - f_lo)
        step = abs(x_new - x)
        x = x_new
        f_x = f(x)
        if f_x == 0.0 or step <= rtol * abs(x):
            return x
        if (f_x > 0.0) == (f_hi > 0.0):
            hi, f_hi = x, f_x
            if kept == -1:
                f_lo *= 0.5
            kept = -1
        else:
            lo, f_lo = x, f_x
            if kept == 1:
                f_hi *= 0.5
            kept = 1
    raise RuntimeError(f"regula falsi did not converge between {lo!r} and {hi!r}")


@value_repr
@dataclass(frozen=True, eq=False)
class Manoeuvre:
    """A course: the path to track and its cone gates.

    Attributes
    ----------
    name : str
        E.g. ``"ISO 3888-1 double lane change"``.
    path : Path
        Centre line (starts at the origin heading +x).
    gates : tuple of Gate
        Lane sections with cones (empty for manoeuvres without cones).
    vehicle_width : float
        Width ``b`` [m] the gates were sized for.
    start_x : float
        x of the first gate's entry [m] (the path starts `start_x` before it).
    laps : float
        Number of times a course without gates drives its closed path
        (finite and > 0; default 1); an open path is driven once (1).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> m = fws.obstacle_avoidance()
    >>> m.start_x, m.end_x, m.cones().shape
    (30.0, 91.0, (18, 2))
    >>> m.cones_hit(np.array([0.0]), np.array([0.0]), np.array([0.0]),
    ...             wheelbase=2.7)
    0
    """

    name: str
    path: Path
    gates: tuple[Gate, ...]
    vehicle_width: float
    start_x: float = 0.0
    laps: float = 1.0

    def __post_init__(self) -> None:
        _check_name(self.name)
        check_type("path", self.path, Path, "a fws_control Path")
        gates = self.gates
        if not isinstance(gates, (tuple, list)) or not all(
            isinstance(g, Gate) for g in gates
        ):
            raise TypeError(
                f"gates must be a tuple of fws_control.manoeuvres.Gate, got {gates!r}"
            )
        object.__setattr__(self, "gates", tuple(gates))
        # 0 for a course without cones (constant_radius)
        width = check_scalar("vehicle_width", self.vehicle_width)
        if width < 0.0:
            raise ValueError(
                f"vehicle_width must be finite and >= 0 m, got {self.vehicle_width!r}"
            )
        object.__setattr__(self, "vehicle_width", width)
        object.__setattr__(self, "start_x", check_scalar("start_x", self.start_x))
        laps = check_scalar("laps", self.laps)
        if laps <= 0.0:
            raise ValueError(f"laps must be finite and > 0, got {self.laps!r}")
        if laps != 1.0 and (self.gates or not self.path.closed):
            # an open path ends; gates are passed once, by x
            raise ValueError(
                f"laps must be 1 for an open path or a course with gates, got "
                f"{self.laps!r}"
            )
        object.__setattr__(self, "laps", laps)

    @property
    def distance(self) -> float:
        """Arc length along the path [m] that a course without gates covers.

        ``laps`` times the length of the path.
        """
        return self.laps * float(self.path.length)

    @property
    def end_x(self) -> float:
        """x of the last gate's exit [m] (the path's end for no gates)."""
        return self.gates[-1].x_end if self.gates else float(self.path.length)

    def cones(self) -> np.ndarray:
        """All cone positions, shape ``(n, 2)`` [m]."""
        if not self.gates:
            return np.empty((0, 2))
        return np.unique(np.vstack([g.cones() for g in self.gates]), axis=0)

    def cones_hit(
        self,
        x: RealArrayLike,
        y: RealArrayLike,
        psi: RealArrayLike,
        *,
        wheelbase: float,
    ) -> int:
        """Number of cones the vehicle's wheel track sweeps over.

        The footprint is the rectangle between the axles (rear axle centre R
        to front axle) and ``±b/2`` sideways. A cone counts as hit if it lies
        inside the footprint at any sample; stopped runs count what they
        swept.

        Parameters
        ----------
        x, y, psi : array_like
            Pose of R over time [m, m, rad] (NaN samples are skipped).
        wheelbase : float
            Distance from R to the front axle [m].

        Returns
        -------
        int
        """
        cones = self.cones()
        if cones.size == 0:
            return 0
        xs, ys, ps = (np.asarray(v, dtype=float).ravel() for v in (x, y, psi))
        ok = np.isfinite(xs) & np.isfinite(ys) & np.isfinite(ps)
        xs, ys, ps = xs[ok], ys[ok], ps[ok]
        dx = cones[None, :, 0] - xs[:, None]
        dy = cones[None, :, 1] - ys[:, None]
        c, s = np.cos(ps)[:, None], np.sin(ps)[:, None]
        lon = c * dx + s * dy
        lat = -s * dx + c * dy
        inside = (
            (lon >= 0.0) & (lon <= wheelbase) & (np.abs(lat) <= self.vehicle_width / 2)
        )
        return int(np.count_nonzero(np.any(inside, axis=0)))

    def left_lane(
        self,
        x: RealArrayLike,
        y: RealArrayLike,
        psi: RealArrayLike,
        *,
        wheelbase: float,
    ) -> bool:
        """Whether the vehicle's wheel track crosses a cone line inside a gate.

        The footprint is the rectangle of :meth:`cones_hit` (rear axle centre
        R to front axle, ``±b/2`` sideways). The vehicle leaves the lane if,
        at any sample, part of the footprint that lies within a gate's
        length (``x_start <= x <= x_end``) is right of the gate's right cone
        line or left of its left one. The transitions between gates have no
        lane; a course without gates has none to leave (False). Stopped runs
        count what they swept.

        Parameters
        ----------
        x, y, psi : array_like
            Pose of R over time [m, m, rad] (NaN samples are skipped).
        wheelbase : float
            Distance from R to the front axle [m], >= 0.

        Returns
        -------
        bool

        Examples
        --------
        >>> import numpy as np, fws_control as fws
        >>> m = fws.double_lane_change()       # entry gate: |y| <= 1.115 m
        >>> x = np.array([m.start_x + 5.0])
        >>> m.left_lane(x, [0.2], [0.0], wheelbase=2.7)   # left edge at 1.1 m
        False
        >>> m.left_lane(x, [0.3], [0.0], wheelbase=2.7)   # left edge at 1.2 m
        True
        """
        wheelbase = check_scalar("wheelbase", wheelbase)
        if wheelbase < 0.0:
            raise ValueError(f"wheelbase must be finite and >= 0 m, got {wheelbase!r}")
        if not self.gates:
            return False
        xs, ys, ps = (np.asarray(v, dtype=float).ravel() for v in (x, y, psi))
        if not xs.shape == ys.shape == ps.shape:
            raise ValueError(
                f"x, y and psi must have the same length, got {xs.size}, "
                f"{ys.size} and {ps.size}"
            )
        ok = np.isfinite(xs) & np.isfinite(ys) & np.isfinite(ps)
        xs, ys, ps = xs[ok], ys[ok], ps[ok]
        c, s = np.cos(ps)[:, None], np.sin(ps)[:, None]
        half = self.vehicle_width / 2.0
        # corners in order around the rectangle: (lon, lat)
        lon = np.array([0.0, wheelbase, wheelbase, 0.0])
        lat = np.array([-half, -half, half, half])
        cx = xs[:, None] + c * lon - s * lat  # (samples, 4)
        cy = ys[:, None] + s * lon + c * lat
        # edges P -> Q of the rectangle
        px, py = cx, cy
        qx, qy = np.roll(cx, -1, axis=1), np.roll(cy, -1, axis=1)
        for g in self.gates:
            # the footprint within the gate's length is convex: its lateral
            # extreme lies at a corner inside that length or where an edge
            # crosses the gate's entry or exit line
            inside = (cx >= g.x_start) & (cx <= g.x_end)
            ys_in = [np.where(inside, cy, np.nan)]
            for x0 in (g.x_start, g.x_end):
                dx = qx - px
                crosses = ((px - x0) * (qx - x0) <= 0.0) & (dx != 0.0)
                w = np.divide(x0 - px, dx, out=np.zeros_like(dx), where=dx != 0.0)
                ys_in.append(np.where(crosses, py + w * (qy - py), np.nan))
            yy = np.concatenate(ys_in, axis=1)
            with np.errstate(invalid="ignore"):
                if np.any((yy < g.y_right) | (yy > g.y_left)):
                    return True
        return False

    def draw_gates(self, ax: Axes) -> list[Any]:
        """Draw the cone lines and cones on `ax`; return the artists.

        Parameters
        ----------
        ax : matplotlib.axes.Axes
            Axes in the x-y plane [m].

        Returns
        -------
        list
        """
        out = []
        for g in self.gates:
            for yy in (g.y_right, g.y_left):
                (ln,) = ax.plot([g.x_start, g.x_end], [yy, yy], "-", color="0.5", lw=1)
                out.append(ln)
        cones = self.cones()
        if cones.size:
            (pts,) = ax.plot(cones[:, 0], cones[:, 1], "^", color="tab:orange", ms=5)
            out.append(pts)
        return out


def _course(name, sections, offsets, vehicle_width, approach, exit_length):
    """Gates and centre line of an ISO course.

    `offsets[k](w, w1)` gives the right cone line of the k-th gate of width
    ``w`` (``w1``: the entry gate's width).
    """
    b = _positive("vehicle_width", vehicle_width)
    approach = _positive("approach", approach)
    exit_length = _positive("exit_length", exit_length)
    w1 = sections[0][1][0] * b + sections[0][1][1]
    gates = []
    # lay out the gates first
    x = approach
    centres = []
    k = 0
    for i, (length, width_rule) in enumerate(sections):
        if width_rule is None:
            x += length
            continue
        fac, add = width_rule
        w = fac * b + add
        y_right = offsets[k](w, w1)
        gates.append(Gate(x, x + length, y_right, y_right + w, f"section {i + 1}"))
        centres.append(y_right + 0.5 * w)
        x += length
        k += 1
    # centre line: straight through each gate, S-bends over the transitions
    segments: list[Path] = [Straight(length=approach)]
    y_prev = centres[0]
    # the path starts at y = 0: the entry gate is centred on 0
    for i, (length, width_rule) in enumerate(sections):
        if width_rule is None:
            nxt = centres[len([s for s in sections[:i] if s[1] is not None])]
            try:
                segments += s_bend(nxt - y_prev, length)
            except ValueError as exc:
                # the lane offsets grow with the width: a bend too sharp
                raise ValueError(
                    f"vehicle_width={b!r} m is too wide for this course: {exc}"
                ) from exc
            y_prev = nxt
        else:
            segments.append(Straight(length=length))
    segments.append(Straight(length=exit_length))
    return Manoeuvre(name, PathChain(segments), tuple(gates), b, approach)


def double_lane_change(
    *, vehicle_width: float = 1.8, approach: float = 30.0, exit_length: float = 60.0
) -> Manoeuvre:
    """ISO 3888-1 double lane change (severe lane change), see the module table.

    Parameters
    ----------
    vehicle_width : float, optional
        Vehicle width ``b`` [m] (default 1.8 m, a mid-size car).
    approach : float, optional
        Straight before the entry gate [m].
    exit_length : float, optional
        Straight after the exit gate [m] (default 60 m: room for a
        look-ahead point beyond the last gate).

    Returns
    -------
    Manoeuvre

    Examples
    --------
    >>> import fws_control as fws
    >>> m = fws.double_lane_change(vehicle_width=2.0)
    >>> [(g.x_end - g.x_start, round(g.width, 2)) for g in m.gates]
    [(15.0, 2.45), (25.0, 2.65), (15.0, 2.85)]
    >>> m.gates[1].y_right, round(m.gates[2].y_right, 3) == round(m.gates[0].y_right, 3)
    (3.5, True)
    """
    offsets = (
        lambda w, w1: -w / 2,
        lambda w, w1: 3.5,
        lambda w, w1: -w1 / 2,  # right lines of sections 1 and 5 aligned
    )
    return _course(
        "ISO 3888-1 double lane change",
        ISO3888_1_SECTIONS,
        offsets,
        vehicle_width,
        approach,
        exit_length,
    )


def obstacle_avoidance(
    *, vehicle_width: float = 1.8, approach: float = 30.0, exit_length: float = 60.0
) -> Manoeuvre:
    """ISO 3888-2 obstacle avoidance (moose test), see the module table.

    Parameters
    ----------
    vehicle_width : float, optional
        Vehicle width ``b`` [m].
    approach : float, optional
        Straight before the entry gate [m].
    exit_length : float, optional
        Straight after the exit gate [m] (default 60 m: room for a
        look-ahead point beyond the last gate).

    Returns
    -------
    Manoeuvre

    Examples
    --------
    >>> import fws_control as fws
    >>> m = fws.obstacle_avoidance(vehicle_width=2.0)
    >>> [(g.x_end - g.x_start, round(g.width, 2)) for g in m.gates]
    [(12.0, 2.45), (11.0, 3.0), (12.0, 3.0)]
    >>> round(m.gates[1].y_right - m.gates[0].y_left, 9)   # 1 m offset
    1.0
    """
    offsets = (
        lambda w, w1: -w / 2,
        lambda w, w1: w1 / 2 + 1.0,  # 1 m left of the entry's left line
        lambda w, w1: -w1 / 2,
    )
    return _course(
        "ISO 3888-2 obstacle avoidance",
        ISO3888_2_SECTIONS,
        offsets,
        vehicle_width,
        approach,
        exit_length,
    )


def slalom(
    *,
    pitch: float = 18.0,
    amplitude: float = 1.0,
    cones: int = 6,
    approach: float = 30.0,
    vehicle_width: float = 1.8,
) -> Manoeuvre:
    """Slalom through a line of cones (e.g. an 18 m handling slalom).

    Cones stand on ``y = 0`` every `pitch` metres; the centre line weaves
    ``±amplitude`` between them with S-bends (continuous curvature),
    passing each cone at the full amplitude. The gates are the cones
    themselves (zero-length "gates" with the cone on the far side).

    Parameters
    ----------
    pitch : float, optional
        Cone spacing [m].
    amplitude : float, optional
        Lateral distance of the centre line from the cone line at a cone [m].
    cones : int, optional
        Number of cones (>= 2).
    approach : float, optional
        Straight before the first cone [m].
    vehicle_width : float, optional
        Vehicle width [m] (for the cones-hit count).

    Returns
    -------
    Manoeuvre

    Examples
    --------
    >>> import fws_control as fws
    >>> m = fws.slalom(pitch=18.0, amplitude=1.0, cones=4)
    >>> m.cones()[:, 0].tolist()
    [30.0, 48.0, 66.0, 84.0]
    """
    p = _positive("pitch", pitch)
    amp = _positive("amplitude", amplitude)
    if (
        isinstance(cones, (bool, np.bool_))
        or not isinstance(cones, (int, np.integer, float, np.floating))
        or not math.isfinite(cones)
        or int(cones) != cones
        or not 2 <= cones <= 10_000
    ):
        raise ValueError(f"cones must be an integer in [2, 10000], got {cones!r}")
    a = _positive("approach", approach)
    b = _positive("vehicle_width", vehicle_width)
    # the S-bends between cones: an offset 2 amplitude over the pitch must
    # stay below half of it; the entry half-bend must fit the approach
    if not amp < p / 4.0:
        raise ValueError(
            f"amplitude must be < pitch/4, got amplitude={amplitude!r} m, "
            f"pitch={pitch!r} m"
        )
    if not p / 2.0 < a:
        raise ValueError(
            f"pitch must be < 2 approach, got pitch={pitch!r} m, "
            f"approach={approach!r} m"
        )
    n = int(cones)
    # enter with a half S-bend to +amplitude before the first cone
    segments: list[Path] = [Straight(length=a - p / 2)]
    segments += s_bend(amp, p / 2)
    y = amp
    for _ in range(n - 1):
        segments += s_bend(-2 * y, p)
        y = -y
    segments += s_bend(-y, p / 2)
    segments.append(Straight(length=a))
    gates = tuple(
        Gate(a + i * p, a + i * p, 0.0, 0.0, f"cone {i + 1}") for i in range(n)
    )
    return Manoeuvre(f"slalom, {n} cones, {p:g} m", PathChain(segments), gates, b, a)


def constant_radius(*, radius: float = 40.0, turns: float = 1.0) -> Manoeuvre:
    """Steady-state circular driving (ISO 4138) on a circle of `radius`.

    Parameters
    ----------
    radius : float, optional
        Radius [m] (left turn).
    turns : float, optional
        Number of laps to drive (> 0). Below 1 the path is an open arc of
        that fraction of the circle; from 1 on it is the closed circle,
        driven `turns` times (:attr:`Manoeuvre.laps`).

    Returns
    -------
    Manoeuvre

    Examples
    --------
    >>> import fws_control as fws
    >>> m = fws.constant_radius(radius=40.0)
    >>> round(float(m.path.curvature(10.0)), 6), m.gates
    (0.025, ())
    >>> m3 = fws.constant_radius(radius=40.0, turns=3)
    >>> m3.laps, round(m3.distance / m3.path.length, 12)
    (3.0, 3.0)
    """
    r = _positive("radius", radius)
    t = check_scalar("turns", turns)
    if t <= 0.0:
        raise ValueError(f"turns must be finite and > 0, got {turns!r}")
    if t < 1.0:
        return Manoeuvre(
            f"constant radius {r:g} m",
            Arc(1.0 / r, length=2 * math.pi * r * t),
            (),
            0.0,
            0.0,
        )
    name = f"constant radius {r:g} m" + (f", {t:g} laps" if t != 1.0 else "")
    return Manoeuvre(name, Arc(curvature=1.0 / r), (), 0.0, 0.0, laps=t)
