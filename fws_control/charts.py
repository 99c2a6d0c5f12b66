r"""Stability charts in the ``(k1, k2)`` gain plane, for plants of any order.

A chart evaluates stability on a whole grid of gains at once: the
characteristic polynomial is affine in ``k1, k2``
(:func:`~fws_control.affine_characteristic_polynomial`), so its coefficients on
the grid are one broadcast expression and the test is the closed form
:math:`p_1 > 0,\ p_0 > 0` (two states, eqs. 35-36) or the vectorised
Routh-Hurwitz test, both run in interval arithmetic on the coefficients'
error bounds (:func:`~fws_control.stability_verdict`); only the points that
test leaves open (near a boundary) go to stacked eigenvalue problems, and
points that even those cannot separate from the axis are drawn as
"undecided". A 1000 x 1000 grid costs a fraction of a second instead of a
million eigenvalue problems.
The chart also carries the D-subdivision boundaries
(:func:`stability_boundaries`) and, for a 2-state plant and a requested
double root :math:`\lambda_0`, the gains of :func:`double_root_gains`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from .delay import critical_delay
from .exceptions import UncontrollableError
from .gains import SteeringGains
from .hints import RatioLike, RealArrayLike
from .linear import AffinePolynomial, affine_characteristic_polynomial, horner
from .plant import LateralPlant, as_plant, loop_matrices, resolve_ratio
from .pole_placement import double_root_gains
from .reprs import summary_repr
from .stability import (
    STABLE,
    UNDECIDED,
    BoundaryCurve,
    StabilityBoundaries,
    complex_root_curve,
    default_frequencies,
    stability_boundaries,
    stability_verdict,
)
from .validation import (
    MAX_RATIO,
    check_delay,
    check_finite,
    check_magnitude,
    check_scalar,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from .vehicle import Vehicle

__all__ = [
    "StabilityChart",
    "stability_chart",
    "DelayMarginChart",
    "delay_margin_chart",
    "note_box",
    "DEFAULT_GAIN_AXIS",
]

#: Largest design pole magnitude of delay_margin_chart [1/s] (gains grow as
#: pole^2: 1e300 overflowed).
_MAX_POLE = 1.0e6

#: Default grid axis of k1 and k2: 401 points on [-1, 1].
DEFAULT_GAIN_AXIS = np.linspace(-1.0, 1.0, 401)

# Line styles tell the boundaries apart in every chart.
_STYLE = {"p1 > 0": "-", "p0 > 0": "--", "complex": "-"}
_LABEL = {
    "p1 > 0": r"$p_1 = 0$",
    "p0 > 0": r"$p_0 = 0$ (root at $s = 0$)",
    "complex": r"roots at $\pm j\omega$",
}
_EQ = {"p1 > 0": " (eq. 35)", "p0 > 0": " (eq. 36)"}


def _axis(name: str, values) -> np.ndarray:
    if values is None:
        return DEFAULT_GAIN_AXIS.copy()
    arr = np.asarray(check_finite(name, values), dtype=float)
    if arr.ndim != 1 or arr.size < 2:
        raise ValueError(
            f"{name} must be a 1-D array of at least 2 gains, got shape {arr.shape}"
        )
    if not (np.all(np.diff(arr) > 0) or np.all(np.diff(arr) < 0)):
        raise ValueError(f"{name} must be strictly monotonic")
    return arr


def _curve_in_box(
    cp: AffinePolynomial, k1r, k2r, delay: float = 0.0, passes: int = 8
) -> BoundaryCurve:
    """The complex-root curve, sampled densely where it crosses the box.

    Starts from :func:`default_frequencies` and bisects (geometrically) every
    interval whose end points are both finite, one of them near the box, and
    farther apart than 1 % of the box: a smooth curve inside the chart at a
    bounded number of points.
    """
    w = default_frequencies(cp, num=1201)
    span = np.array([k1r[1] - k1r[0], k2r[1] - k2r[0]])
    lo = np.array([k1r[0], k2r[0]]) - span
    hi = np.array([k1r[1], k2r[1]]) + span
    for _ in range(passes):
        c = complex_root_curve(cp, w, delay)
        pts = np.column_stack([c.k1, c.k2])
        near = np.all((pts >= lo) & (pts <= hi), axis=1)
        gap = np.hypot(*((np.diff(pts, axis=0)) / span).T)
        split = (near[:-1] | near[1:]) & (gap > 0.01)
        split &= np.isfinite(gap)
        if not np.any(split) or w.size > 40_000:
            return c
        mid = np.sqrt(w[:-1][split] * w[1:][split])
        w = np.sort(np.concatenate([w, mid]))
    return complex_root_curve(cp, w, delay)


#: Most gain points times frequency points of a delayed chart's count
#: (:func:`~fws_control.delay.unstable_root_count` resolves the delay's
#: phase on the imaginary axis: ``8 delay w / pi`` points up to the frequency
#: bound ``w`` of the loop, plus 320 for the polynomials). Measured on the
#: paper's plant at 5 m/s (w = 32 rad/s): the default 401 x 401 grid at a
#: 1 s delay is 6.4e7 of them, 9.5 s of CPU; at 10 s, 1.8e8 (about 200 s);
#: at 1000 s, 1.3e10.
_MAX_DELAY_WORK = 1.0e8


def _check_delay_work(cp: AffinePolynomial, k1a, k2a, delay: float) -> None:
    """Refuse a delayed chart whose root count would take minutes or more."""
    d_c, n1_c, n2_c = (
        np.asarray(c, dtype=float).reshape(-1) for c in (cp.open_loop, cp.n1, cp.n2)
    )
    K1, K2 = float(np.max(np.abs(k1a))), float(np.max(np.abs(k2a)))
    roots = np.roots(d_c) if d_c.size > 1 else np.array([])
    # frequency beyond which the gains' terms are below half the open loop's
    # (the bound the count's grid goes up to)
    w = max(1.0, 2.0 * float(np.max(np.abs(roots), initial=0.0)) + 1.0)
    for _ in range(200):
        s = 1j * w * np.geomspace(1.0, 1e3, 64)
        bound = K1 * np.abs(horner(n1_c, s)) + K2 * np.abs(horner(n2_c, s))
        if np.all(bound < 0.5 * np.abs(horner(d_c, s))):
            break
        w *= 2.0
    work = k1a.size * k2a.size * (8.0 * delay * w / math.pi + 320.0)
    if work > _MAX_DELAY_WORK:
        raise ValueError(
            f"delay={delay!r} s on a {k2a.size} x {k1a.size} grid needs about "
            f"{work:.3g} evaluations of the characteristic function (gain points x "
            f"frequency points up to {w:.3g} rad/s), beyond the budget of "
            f"{_MAX_DELAY_WORK:.3g}; use a coarser k1/k2 grid (the work is "
            "proportional to the number of points and, for long delays, to the delay)"
        )


@summary_repr
@dataclass(frozen=True, eq=False)
class StabilityChart:
    r"""Stable set of the linear closed loop on a ``(k1, k2)`` grid.

    Returned by :func:`stability_chart`; do not build it directly.

    Attributes
    ----------
    plant : LateralPlant or control.StateSpace
        The plant (one operating point).
    ratio : float
        Rear-to-front steering ratio :math:`a`.
    k1, k2 : ndarray
        Grid axes [rad/m] and [-], 1-D.
    stable : ndarray of bool
        Shape ``(len(k2), len(k1))``: ``stable[i, j]`` is the verdict at
        ``(k1[j], k2[i])`` (rows follow ``k2``, as in :func:`numpy.meshgrid`
        and :meth:`matplotlib.axes.Axes.contourf`).
    boundaries : StabilityBoundaries
        D-subdivision boundaries; ``boundaries.lines`` are the straight ones.
    curve : BoundaryCurve
        The complex-root boundary sampled densely inside the grid (for
        drawing).
    pole : float or None
        Requested double root :math:`\lambda_0` [1/s].
    delay : float
        Input delay on the steering command [s] (0: none). With a delay the
        verdict of each point is the count of right-half-plane roots of the
        quasi-polynomial (:func:`~fws_control.delay.unstable_root_count`).
    undecided : int
        Grid points whose verdict could not be decided: without delay, the
        rightmost pole within the rounding bound of the imaginary axis
        (:func:`~fws_control.stability_verdict`); with a delay, a root on or
        within the frequency resolution of the axis. They are not in
        `stable`, and :meth:`plot` draws them as their own grey hatched class.
    design : SteeringGains or None
        Double-root gains for `pole`; None when no pole was requested or the
        design does not exist (then `design_error` says why).
    design_error : str or None
        Why the design failed (:class:`UncontrollableError`).
    design_model : str or None
        The model of the plant the design was placed on when it is not the
        chart's: ``"kinematic"`` (the kinematic plant at the same operating
        point) for a chart of a ``LateralPlant(model="dynamic")``; None when
        the design is the chart plant's own.
    verdict : ndarray of int8 or None
        Same shape as `stable`: 1 stable, 0 not stable, -1 undecided (the
        codes of :class:`~fws_control.StabilityVerdict`); None means the
        chart was built without it (every point decided, as `stable`).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> ch = fws.stability_chart(fws.LateralPlant(veh, speed=5.0), ratio=0.0,
    ...                          k1=np.linspace(-1, 1, 5), k2=np.linspace(-1, 1, 5))
    >>> round(ch.stable_fraction, 2), ch.order
    (0.16, 2)
    """

    plant: Any
    ratio: float
    k1: np.ndarray
    k2: np.ndarray
    stable: np.ndarray
    boundaries: StabilityBoundaries
    curve: BoundaryCurve
    pole: float | None = None
    delay: float = 0.0
    undecided: int = 0
    design: SteeringGains | None = None
    design_error: str | None = None
    verdict: np.ndarray | None = None
    design_model: str | None = None

    @property
    def undecided_mask(self) -> np.ndarray:
        """Boolean grid of the undecided points (shape of `stable`)."""
        if self.verdict is None:
            return np.zeros(np.shape(self.stable), dtype=bool)
        return np.asarray(self.verdict) == -1

    @property
    def order(self) -> int:
        """Order of the closed loop."""
        return self.boundaries.order

    @property
    def lateral(self) -> bool:
        """True when the plant is the kinematic :class:`LateralPlant`."""
        return isinstance(self.plant, LateralPlant)

    @property
    def speed(self) -> float:
        """Speed [m/s] of a :class:`LateralPlant` (NaN otherwise)."""
        return float(self.plant.speed) if self.lateral else math.nan

    @property
    def curvature(self) -> float:
        """Curvature [1/m] of a :class:`LateralPlant` (NaN otherwise)."""
        return float(self.plant.curvature) if self.lateral else math.nan

    @property
    def model(self) -> str | None:
        """Linearisation model of a :class:`LateralPlant` (None otherwise)."""
        return self.plant.model if self.lateral else None

    @property
    def vehicle(self) -> Vehicle | None:
        """Vehicle of a :class:`LateralPlant` (None otherwise)."""
        return self.plant.vehicle if self.lateral else None

    @property
    def stable_fraction(self) -> float:
        """Fraction of grid points that are stable."""
        return float(np.mean(self.stable))

    @property
    def empty(self) -> bool:
        """True when no grid point is stable."""
        return not bool(np.any(self.stable))

    @property
    def design_on_chart(self) -> bool:
        """True when the design point exists and lies inside the grid."""
        if self.design is None:
            return False
        k1d, k2d = float(self.design.k1), float(self.design.k2)
        return bool(
            self.k1.min() <= k1d <= self.k1.max()
            and self.k2.min() <= k2d <= self.k2.max()
        )

    def notes(self, *, label: str = "") -> list[str]:
        """Remarks a reader needs that the drawing cannot show.

        Parameters
        ----------
        label : str, optional
            Prefix naming the chart (e.g. its curvature) in an overlay.

        Returns
        -------
        list of str
        """
        pre = f"{label}: " if label else ""
        out = []
        if self.empty:
            out.append(f"{pre}no stable gains on this grid")
        if self.undecided:
            why = (
                "root count undecided (a root near the axis)"
                if self.delay
                else "a pole within rounding of the axis"
            )
            out.append(f"{pre}{self.undecided} undecided points: {why}")
        if self.design_error is not None:
            out.append(rf"{pre}no $\lambda_0$ design (uncontrollable)")
        elif self.design is not None and not self.design_on_chart:
            out.append(
                rf"{pre}$\lambda_0$ = {self.pole:g} gains off chart: "
                f"({float(self.design.k1):.3g}, {float(self.design.k2):.3g})"
            )
        return out

    def describe(self) -> str:
        """One-line description: a and the operating point or the plant."""
        tau = f", delay {self.delay:g} s" if self.delay else ""
        if self.lateral:
            return (
                f"a = {self.ratio:g}, V = {self.speed:g} m/s, "
                rf"$\kappa$ = {self.curvature:g} 1/m, {self.model} model{tau}"
            )
        return f"a = {self.ratio:g}, {self.order}-state plant{tau}"

    def plot(
        self,
        ax: Axes | None = None,
        *,
        color: str = "C0",
        label: str | None = None,
        hatch: str | None = None,
        alpha: float = 0.3,
        boundaries: bool = True,
        design: bool = True,
        outline: bool = False,
        legend: bool = True,
        notes: bool = True,
        title: bool | str = True,
        mark: Any = None,
    ) -> ct.ControlPlot:
        r"""Draw the stable region, the boundaries and the design point.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure is created if None.
        color : str, optional
            Colour of the region, lines and design marker.
        label : str, optional
            Legend label of the stable region (default ``"stable"``). With a
            label, the boundary lines get no legend entries of their own, so
            that overlaid charts share one legend for the line styles.
        hatch : str, optional
            Matplotlib hatch of the region, to tell overlaid charts apart.
        alpha : float, optional
            Opacity of the region.
        boundaries, design : bool, optional
            Whether to draw the boundaries and the design point. A design off
            the grid is marked by a hollow arrowhead on the frame.
        outline : bool, optional
            Whether to trace the edge of the region with a broad translucent
            band, which keeps overlaid light fills apart.
        legend : bool, optional
            Whether to add a legend.
        notes : bool, optional
            Whether to write :meth:`notes` into the axes, prefixed with
            `label`; the notes of charts overlaid on one axes go into one box.
        title : bool or str, optional
            True: :meth:`describe`; a string: that title; False: none.
        mark : SteeringGains or (k1, k2), optional
            Gains of one's own to mark with a star (several if `k1`, `k2` are
            arrays), e.g. a design from another tool; a SteeringGains must
            have the chart's ratio. Points outside the grid are clipped.

        Returns
        -------
        control.ControlPlot
            ``.lines[0, 0]`` holds the drawn artists, ``.axes[0, 0]`` the
            axes.

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, numpy as np, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> ch = fws.stability_chart(veh, speed=5.0, ratio=-1.0, pole=-1.0,
        ...                          k1=np.linspace(-1, 1, 51),
        ...                          k2=np.linspace(-1, 1, 51))
        >>> cplt = ch.plot()
        >>> cplt.axes[0, 0].get_xlabel()
        '$k_1$ [rad/m]'
        >>> plt.close(cplt.figure)

        Marking one's own gains:

        >>> cplt = ch.plot(mark=(0.2, 0.5))
        >>> star = cplt.lines[0, 0][-1]
        >>> star.get_xydata().tolist(), star.get_label()
        ([[0.2, 0.5]], 'marked: (0.200, 0.500)')
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        points = None if mark is None else self._mark_points(mark)
        if ax is None:
            _, ax = plt.subplots(figsize=(5.5, 4.8), layout="constrained")
        artists, handles = self._draw(
            ax, color, label, hatch, alpha, boundaries, design, outline, points
        )
        if title:
            ax.set_title(self.describe() if title is True else title, fontsize=10)
        leg = ax.legend(handles=handles, fontsize=8, loc="best") if legend else None
        if notes:
            note_box(ax, self.notes(label=label or ""))
        lines = np.empty((1, 1), dtype=object)
        lines[0, 0] = artists
        return ct.ControlPlot(lines, np.array([[ax]]), ax.figure, legend=leg)

    def _mark_points(self, mark: Any) -> tuple[np.ndarray, np.ndarray]:
        """The ``(k1, k2)`` arrays of `mark` (see :meth:`plot`), checked."""
        if isinstance(mark, SteeringGains):
            if not np.all(np.asarray(mark.ratio) == self.ratio):
                raise ValueError(
                    f"mark must have the chart's ratio {self.ratio!r}, got gains "
                    f"with ratio {mark.ratio!r}: on another ratio the chart does "
                    "not show their stability"
                )
            pair: Any = (mark.k1, mark.k2)
        else:
            pair = mark
        if not isinstance(pair, (tuple, list, np.ndarray)) or len(pair) != 2:
            raise ValueError(
                f"mark must be SteeringGains or a (k1, k2) pair, got {mark!r}"
            )
        k1m, k2m = (
            np.ravel(np.asarray(check_finite(f"mark {n}", v), dtype=float))
            for n, v in zip(("k1", "k2"), pair, strict=True)
        )
        try:
            k1m, k2m = np.broadcast_arrays(k1m, k2m)
        except ValueError:
            raise ValueError(
                f"mark: k1 and k2 must broadcast, got {k1m.size} and {k2m.size} values"
            ) from None
        return k1m, k2m

    def _draw(
        self,
        ax,
        color,
        label,
        hatch,
        alpha,
        boundaries,
        design,
        outline=False,
        mark=None,
    ):
        """Draw on `ax`; return ``(artists, legend handles)``."""
        from matplotlib.colors import to_rgba
        from matplotlib.patches import Patch

        artists = []
        region_label = "stable" if label is None else label
        if not self.empty:
            fill, edge = _region_paths(self.k1, self.k2, self.stable)
            # What contourf(levels=[0.5, 1.5]) and contour(levels=[0.5]) of the
            # mask draw, built from the same contour paths without their
            # per-call overhead (most of the cost of a many-panel figure).
            artists.append(
                _add_paths(
                    ax, fill, facecolors=[color], edgecolors="none", alpha=alpha,
                    antialiaseds=False, zorder=1,
                )
            )  # fmt: skip
            if hatch:
                # A second, unfilled layer keeps the hatch opaque and in the
                # region's colour, so overlaid regions stay distinguishable.
                artists.append(
                    _add_paths(
                        ax, fill, facecolors="none", edgecolors=[color],
                        linewidths=0.0, hatch=hatch, antialiaseds=False, zorder=1,
                    )
                )  # fmt: skip
            if outline:
                # A broad translucent band along the inside of the region's
                # edge: overlaid regions stay readable where fills overlap.
                artists.append(
                    _add_paths(
                        ax, edge, facecolors="none", edgecolors=[color],
                        linewidths=4.0, alpha=0.45, zorder=2,
                    )
                )  # fmt: skip
        undecided = self.undecided_mask
        if np.any(undecided):
            fill, _ = _region_paths(self.k1, self.k2, undecided)
            artists.append(
                _add_paths(
                    ax, fill, facecolors=["0.75"], edgecolors=["0.35"],
                    linewidths=0.0, hatch="xx", alpha=0.8, zorder=3,
                )
            )  # fmt: skip
        # contourf makes no legend handle; a proxy patch stands in for it.
        handles = [
            Patch(
                facecolor=to_rgba(color, alpha if not self.empty else 0.0),
                hatch=hatch,
                edgecolor=color,
                label=region_label + (" (empty)" if self.empty else ""),
            )
        ]
        if np.any(undecided):
            handles.append(
                Patch(
                    facecolor="0.75",
                    edgecolor="0.35",
                    hatch="xx",
                    label=f"undecided ({int(np.count_nonzero(undecided))} points)",
                )
            )
        k1r = (float(self.k1.min()), float(self.k1.max()))
        k2r = (float(self.k2.min()), float(self.k2.max()))
        if boundaries:
            for b in self.boundaries.lines:
                seg = b.segment(k1r, k2r)
                if seg is None:
                    continue
                text = _LABEL[b.condition] + (_EQ[b.condition] if self.lateral else "")
                (line,) = ax.plot(
                    seg[:, 0],
                    seg[:, 1],
                    _STYLE[b.condition],
                    color=color,
                    lw=1.6,
                    label=text if label is None else None,
                )
                artists.append(line)
                if label is None:
                    handles.append(line)
            if self.order > 2 or self.delay > 0:
                first = True
                for br in self.curve.branches():
                    (line,) = ax.plot(
                        br[:, 1],
                        br[:, 2],
                        _STYLE["complex"],
                        color=color,
                        lw=2.2,
                        alpha=0.6,
                        label=_LABEL["complex"] if (label is None and first) else None,
                    )
                    artists.append(line)
                    if label is None and first:
                        handles.append(line)
                    first = False
        if design and self.design_on_chart:
            k1d, k2d = float(self.design.k1), float(self.design.k2)
            kin = " (kinematic design)" if self.design_model == "kinematic" else ""
            (pt,) = ax.plot(
                k1d,
                k2d,
                "o",
                color=color,
                mec="k",
                ms=7,
                label=rf"$\lambda_0$ = {self.pole:g}{kin}: ({k1d:.3f}, {k2d:.3f})",
                zorder=5,
            )
            artists.append(pt)
            if label is None:
                handles.append(pt)
        elif design and self.design is not None:
            # Off the chart: a hollow arrowhead on the frame points at it (the
            # notes give its coordinates).
            k1d, k2d = float(self.design.k1), float(self.design.k2)
            px, py = min(max(k1d, k1r[0]), k1r[1]), min(max(k2d, k2r[0]), k2r[1])
            marker = (
                ">"
                if k1d > k1r[1]
                else "<"
                if k1d < k1r[0]
                else "^"
                if k2d > k2r[1]
                else "v"
            )
            (pt,) = ax.plot(
                px,
                py,
                marker,
                color=color,
                mfc="white",
                mew=2.0,
                ms=10,
                clip_on=False,
                zorder=6,
            )
            artists.append(pt)
        if mark is not None:
            k1m, k2m = mark
            text = (
                f"marked: ({k1m[0]:.3f}, {k2m[0]:.3f})"
                if k1m.size == 1
                else f"marked gains ({k1m.size})"
            )
            (pt,) = ax.plot(
                k1m, k2m, "*", color=color, mec="k", ms=12, ls="none", label=text,
                zorder=6,
            )  # fmt: skip
            artists.append(pt)
            handles.append(pt)
        ax.set_xlim(*k1r)
        ax.set_ylim(*k2r)
        ax.set_xlabel(r"$k_1$ [rad/m]")
        ax.set_ylabel(r"$k_2$ [-]")
        ax.axhline(0.0, color="0.7", lw=0.5, zorder=0)
        ax.axvline(0.0, color="0.7", lw=0.5, zorder=0)
        return artists, handles

    def draw(self, ax: Axes, **kwargs: Any) -> list[Any]:
        """Draw into `ax` without title, legend or notes; return legend handles.

        For figures that overlay several charts and build one legend (see
        :mod:`fws_control.paper.charts`).

        Parameters
        ----------
        ax : matplotlib.axes.Axes
            Axes to draw on.
        **kwargs
            `color`, `label`, `hatch`, `alpha`, `boundaries`, `design`,
            `outline`, `mark` as in :meth:`plot`.

        Returns
        -------
        list
            Legend handles.
        """
        opts: dict[str, Any] = {
            "color": "C0",
            "label": None,
            "hatch": None,
            "alpha": 0.3,
            "boundaries": True,
            "design": True,
            "outline": False,
            "mark": None,
        }
        unknown = set(kwargs) - set(opts)
        if unknown:
            raise TypeError(
                f"draw() got unexpected keyword arguments {sorted(unknown)}"
            )
        opts.update(kwargs)
        if opts["mark"] is not None:
            opts["mark"] = self._mark_points(opts["mark"])
        return self._draw(ax, **opts)[1]


def _region_paths(k1, k2, stable):
    """Paths of ``contourf(k1, k2, stable, levels=[0.5, 1.5])`` and of its edge.

    The contour generator and its settings are matplotlib's own (its
    ``contour.algorithm`` and ``contour.corner_mask``), so the paths are those
    that ``contourf``/``contour`` would draw.
    """
    import contourpy
    import matplotlib as mpl
    from matplotlib.path import Path as MplPath

    gen = contourpy.contour_generator(
        k1,
        k2,
        np.asarray(stable, dtype=float),
        name=mpl.rcParams["contour.algorithm"],
        corner_mask=mpl.rcParams["contour.corner_mask"],
        line_type=contourpy.LineType.SeparateCode,
        fill_type=contourpy.FillType.OuterCode,
    )

    def joined(parts):
        vertices, codes = parts
        if not len(vertices):
            return MplPath(np.empty((0, 2)))
        return MplPath(np.concatenate(vertices), np.concatenate(codes))

    return joined(gen.filled(0.5, 1.5)), joined(gen.lines(0.5))


def _add_paths(ax, path, **kwargs):
    """Add one path in data coordinates as a collection (as contourf does)."""
    from matplotlib.collections import PathCollection

    coll = PathCollection([path], transform=ax.transData, **kwargs)
    ax.add_collection(coll, autolim=False)
    return coll


def note_box(ax: Axes, notes: Sequence[str]) -> None:
    """Write remarks into the top-left corner of `ax` (nothing if none).

    Called again on the same axes (overlaid charts), it appends to the box
    already there instead of drawing a second box on top of it.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to write into.
    notes : sequence of str
        One remark per line.
    """
    if not notes:
        return
    box = getattr(ax, "_fws_note_box", None)
    if box is not None and box.axes is ax:
        old = box.get_text().split("\n")
        box.set_text("\n".join(old + [n for n in notes if n not in old]))
        return
    ax._fws_note_box = ax.text(  # type: ignore[attr-defined]
        0.02,
        0.98,
        "\n".join(notes),
        transform=ax.transAxes,
        va="top",
        ha="left",
        fontsize=7,
        bbox={"fc": "white", "ec": "0.7", "alpha": 0.9},
        zorder=10,
    )


def stability_chart(
    plant: Any,
    *,
    ratio: float | Callable[..., Any],
    k1: RealArrayLike | None = None,
    k2: RealArrayLike | None = None,
    delay: float = 0.0,
    pole: float | None = None,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> StabilityChart:
    r"""Stability of the linear closed loop on a gain grid.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        One operating point of a plant of any order (see
        :mod:`fws_control.plant`).
    ratio : float or callable
        Rear-to-front steering ratio :math:`a`, or a schedule
        ``ratio(vehicle, speed=...)`` evaluated at the plant's speed.
    k1, k2 : array_like, optional
        Strictly monotonic 1-D grid axes [rad/m], [-]; default
        :data:`DEFAULT_GAIN_AXIS` (401 points on ``[-1, 1]``).
    delay : float, optional
        Input delay on the steering command [s], >= 0. Without delay the
        verdict is :func:`~fws_control.stability_verdict` (Routh-Hurwitz in
        interval arithmetic on exact coefficients, eigenvalues with
        perturbation bounds near the boundary); with a delay it is the
        number of right-half-plane roots of the quasi-polynomial (argument
        principle, :func:`~fws_control.delay.unstable_root_count`), and the
        boundaries are the D-subdivision curves of all crossing frequencies.
        Undecided points are counted in ``undecided`` and marked in
        ``verdict``, never in ``stable``.
    pole : float, optional
        Double root :math:`\lambda_0 < 0` whose gains
        (:func:`double_root_gains`) are stored and marked. If that design is
        uncontrollable (``a = 1`` on a straight path) the chart records the
        reason in :attr:`StabilityChart.design_error` instead of failing.
        Two gains place a double root only in a 2-state loop: on a chart of
        ``LateralPlant(model="dynamic")`` the marked gains are the kinematic
        plant's design at the same operating point (``model="kinematic"``,
        recorded in :attr:`StabilityChart.design_model`), so the chart shows
        where that design lands on the dynamic plant; another plant of more
        than two states raises a ValueError (mark gains of one's own with
        ``chart.plot(mark=(k1, k2))``).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`. For ``V < 0``
        condition (35) flips side (see :mod:`fws_control.stability`).

    Returns
    -------
    StabilityChart
        ``stable`` has shape ``(len(k2), len(k1))``.

    Raises
    ------
    TypeError
        For positional arguments after the plant, or an unknown plant.
    ValueError
        For a non-finite or array `ratio`, a non-negative `pole`, a `pole`
        with a plant of more than two states other than a dynamic
        :class:`LateralPlant`, or grid axes that are not 1-D monotonic arrays.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> ch = fws.stability_chart(plant, ratio=-1.0, pole=-1.0,
    ...                          k1=np.linspace(-1, 1, 1000),
    ...                          k2=np.linspace(-1, 1, 800))
    >>> ch.stable.shape
    (800, 1000)
    >>> round(float(ch.design.k1), 4), round(float(ch.design.k2), 4)
    (0.054, 0.6129)
    >>> bool(ch.stable[np.searchsorted(ch.k2, 0.6), np.searchsorted(ch.k1, 0.05)])
    True
    >>> fws.stability_chart(plant, ratio=1.0, pole=-1.0).design_error
    'ratio=1.0 with curvature=0.0 makes delta_r = delta_f: ...'
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    if isinstance(p, LateralPlant) and p.shape != ():
        raise ValueError(
            f"stability_chart needs one operating point, got speed/curvature of "
            f"shape {p.shape}"
        )
    ratio = check_scalar("ratio", resolve_ratio(p, ratio))
    check_magnitude("ratio", ratio, MAX_RATIO)
    k1a = _axis("k1", k1)
    k2a = _axis("k2", k2)
    design = err = design_model = None
    if pole is not None:  # before the grid: a refused pole costs nothing
        pole = check_scalar("pole", pole)
        dp = p
        order = loop_matrices(p).order
        if order > 2 and isinstance(p, LateralPlant) and p.model == "dynamic":
            dp, design_model = replace(p, model="kinematic"), "kinematic"
        elif order > 2:
            raise ValueError(
                f"pole={pole!r} needs a 2-state plant, got one of order {order}: "
                "two gains cannot place a double root there. Pick (k1, k2) from "
                "the chart (pole=None) and mark them with chart.plot(mark=(k1, "
                "k2)); a LateralPlant(model='dynamic') marks its kinematic design"
            )
        try:
            g = double_root_gains(dp, ratio=ratio, pole=pole)
            design = SteeringGains(float(g.k1), float(g.k2), ratio)
        except UncontrollableError as exc:
            err = str(exc)
    # Outer broadcasting (k2 down the rows, k1 across) avoids a meshgrid.
    grid = SteeringGains(k1a[np.newaxis, :], k2a[:, np.newaxis], ratio)
    tau = check_delay(delay)
    if tau > 0.0:
        _check_delay_work(
            affine_characteristic_polynomial(p, ratio=ratio), k1a, k2a, tau
        )
    verdict = stability_verdict(p, grid, delay=tau).code
    stable = verdict == STABLE
    undecided = int(np.count_nonzero(verdict == UNDECIDED))
    bounds = stability_boundaries(p, ratio=ratio, delay=tau)
    k1r = (float(k1a.min()), float(k1a.max()))
    k2r = (float(k2a.min()), float(k2a.max()))
    if bounds.order > 2 or tau > 0.0:
        cp = affine_characteristic_polynomial(p, ratio=ratio)
        curve = _curve_in_box(cp, k1r, k2r, tau)
    else:
        curve = bounds.complex_root
    return StabilityChart(
        plant=p,
        ratio=ratio,
        k1=k1a,
        k2=k2a,
        stable=stable,
        boundaries=bounds,
        curve=curve,
        pole=pole,
        delay=tau,
        undecided=undecided,
        design=design,
        design_error=err,
        verdict=verdict,
        design_model=design_model,
    )


@summary_repr
@dataclass(frozen=True, eq=False)
class DelayMarginChart:
    r"""Critical delay of double-root designs over ratios and poles.

    Returned by :func:`delay_margin_chart`. A design tolerates every delay
    below its critical delay, so in the (pole, delay) or (ratio, delay)
    plane the stable designs lie *below* each curve.

    Attributes
    ----------
    plant : LateralPlant or control.StateSpace
        The plant the delay margins are computed on.
    design_plant : LateralPlant or control.StateSpace
        The 2-state plant the gains were designed on.
    ratio, pole : ndarray
        1-D axes: ratios :math:`a` and double roots :math:`\lambda_0` [1/s].
    delay : ndarray
        Critical delays [s], shape ``(len(ratio), len(pole))``; ``inf`` where
        no delay destabilises, 0 where the design is unstable on `plant`
        without delay, NaN where no design exists (uncontrollable).
    frequency : ndarray
        Crossing frequencies [rad/s] at the critical delays (same shape).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> ch = fws.delay_margin_chart(fws.LateralPlant(veh, speed=20.0),
    ...                             ratio=[-1.0, 0.5], pole=[-1.0, -2.0])
    >>> ch.delay.round(4)
    array([[0.6474, 0.3237],
           [0.6474, 0.3237]])
    """

    plant: Any
    design_plant: Any
    ratio: np.ndarray
    pole: np.ndarray
    delay: np.ndarray
    frequency: np.ndarray

    def tolerates(self, delay: float) -> np.ndarray:
        """Boolean mask of the designs stable with an input delay of `delay` [s].

        Parameters
        ----------
        delay : float
            Input delay [s].

        Returns
        -------
        ndarray of bool
            Shape ``(len(ratio), len(pole))``.
        """
        tau = check_delay(delay)
        return np.nan_to_num(self.delay, nan=-1.0) > tau

    def plot(
        self,
        ax: Axes | None = None,
        *,
        against: str = "pole",
        delay: float | None = None,
    ) -> ct.ControlPlot:
        """Critical delay against the pole (one curve per ratio) or the ratio.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure if None.
        against : {"pole", "ratio"}, optional
            The horizontal axis; one curve per value of the other.
        delay : float, optional
            Draw this delay [s] as a horizontal reference line (e.g. a
            measured loop delay): designs whose curve lies above it survive.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> ch = fws.delay_margin_chart(fws.LateralPlant(veh, speed=5.0),
        ...                             ratio=[-1.0, 0.0], pole=[-1.0, -2.0, -3.0])
        >>> cplt = ch.plot(delay=0.24)
        >>> cplt.axes[0, 0].get_ylabel()
        'critical delay [s]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        if against not in ("pole", "ratio"):
            raise ValueError(f"against must be 'pole' or 'ratio', got {against!r}")
        if ax is None:
            _, ax = plt.subplots(figsize=(6.5, 4.6), layout="constrained")
        if against == "pole":
            x, curves, names = self.pole, self.delay, self.ratio
            xlabel, what = r"double root $\lambda_0$ [1/s]", "a = {:g}"
        else:
            x, curves, names = self.ratio, self.delay.T, self.pole
            xlabel, what = "ratio $a$ [-]", r"$\lambda_0$ = {:g} 1/s"
        finite = self.delay[np.isfinite(self.delay)]
        top = float(np.max(finite)) * 1.1 if finite.size else 1.0
        lines = []
        for i, (name, y) in enumerate(zip(names, curves, strict=True)):
            (ln,) = ax.plot(
                x, np.where(np.isinf(y), np.nan, y), "o-", ms=3, color=f"C{i % 10}",
                label=what.format(name),
            )  # fmt: skip
            lines.append(ln)
            inf = np.isinf(y)
            if np.any(inf):
                (m,) = ax.plot(
                    x[inf], np.full(inf.sum(), top), "^", color=ln.get_color()
                )
                lines.append(m)
        if delay is not None:
            lines.append(
                ax.axhline(
                    check_delay(delay),
                    color="k",
                    ls="--",
                    lw=1.0,
                    label=f"delay {delay:g} s",
                )  # fmt: skip
            )
        ax.set_xlabel(xlabel)
        ax.set_ylabel("critical delay [s]")
        ax.set_ylim(0.0, top * 1.05)
        ax.grid(alpha=0.3)
        where = (
            f"V = {float(self.plant.speed):g} m/s, "
            rf"$\kappa$ = {float(self.plant.curvature):g} 1/m"
            if isinstance(self.plant, LateralPlant)
            else f"{loop_matrices(self.plant).order}-state plant"
        )
        ax.set_title(
            f"delay margin of the double-root designs ({where});\n"
            "stable below each curve, ▲: no delay destabilises",
            fontsize=10,
        )
        leg = ax.legend(fontsize=8)
        arr = np.empty((1, 1), dtype=object)
        arr[0, 0] = lines
        return ct.ControlPlot(arr, np.array([[ax]]), ax.figure, legend=leg)


def delay_margin_chart(
    plant: Any,
    *,
    ratio: RatioLike,
    pole: RealArrayLike,
    design_plant: Any = None,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> DelayMarginChart:
    r"""Critical delays of double-root designs over ratios and poles.

    For every ratio :math:`a` and double root :math:`\lambda_0` the gains of
    :func:`double_root_gains` are designed on `design_plant` (a 2-state
    plant; default `plant`) and their delay margin
    (:func:`~fws_control.critical_delay`) is computed on `plant` — which may
    carry a steering lag (``LateralPlant(..., steering_lag=...)``), so that
    the chart answers which of the paper's designs survive a real actuator.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant the margins are computed on (one operating point).
    ratio, pole : float or array_like
        1-D ratios and double roots (< 0) [1/s].
    design_plant : LateralPlant or control.StateSpace, optional
        2-state plant for the design; default `plant`.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    DelayMarginChart

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> lagged = fws.LateralPlant(veh, speed=20.0, steering_lag=0.27)
    >>> ch = fws.delay_margin_chart(lagged, ratio=0.0, pole=[-1.0, -3.0],
    ...                             design_plant=fws.LateralPlant(veh, speed=20.0))
    >>> ch.delay.round(3)
    array([[0.455, 0.09 ]])
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    dp = p if design_plant is None else as_plant(design_plant)
    a = np.atleast_1d(check_magnitude("ratio", ratio, MAX_RATIO)).astype(float)
    # |pole| bounded as the ratio: 1e300 1/s overflowed the gains (k ~ pole^2)
    lam = np.atleast_1d(check_magnitude("pole", pole, _MAX_POLE, "1/s")).astype(float)
    if a.ndim != 1 or lam.ndim != 1:
        raise ValueError("ratio and pole must be scalars or 1-D arrays")
    delay = np.full((a.size, lam.size), np.nan)
    freq = np.full((a.size, lam.size), np.nan)
    for i, ai in enumerate(a):
        try:
            g = double_root_gains(dp, ratio=ai, pole=lam)
        except UncontrollableError:
            continue  # no design: stays NaN
        cd = critical_delay(p, g)
        delay[i] = cd.delay
        freq[i] = cd.frequency
    return DelayMarginChart(
        plant=p, design_plant=dp, ratio=a, pole=lam, delay=delay, frequency=freq
    )
