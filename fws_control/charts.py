r"""Stability charts in the ``(k1, k2)`` gain plane, paper Figs. 2-4.

A chart evaluates the Routh-Hurwitz conditions (35)-(36) in closed form on a
whole grid of gains at once (:func:`characteristic_coefficients` is affine in
``k1, k2`` and broadcasts), so a 1000 x 1000 grid costs a few milliseconds
instead of a million eigenvalue problems. It also carries the two boundary
lines from :func:`stability_boundaries` and, when a double root
:math:`\lambda_0` is requested, the gains of :func:`double_root_gains`.

:func:`plot_paper_figure` redraws Figs. 2-4 of the paper. The paper does not
list the curvatures shown in Figs. 3 and 4; this module uses
:data:`PAPER_CURVATURES`: :math:`\kappa \in \{0, 0.05, 0.1, 0.2\}` 1/m at
5 m/s (Fig. 3) and :math:`\kappa \in \{0, 0.01, 0.02, 0.05\}` 1/m at 20 m/s
(Fig. 4), which include the curvatures of the simulations (0.1 and 0.01 1/m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validation import check_finite, check_model, check_nonzero, check_scalar
from .design import UncontrollableError, double_root_gains
from .gains import SteeringGains
from .stability import StabilityBoundary, is_stable, stability_boundaries
from .vehicle import Vehicle

__all__ = [
    "StabilityChart",
    "stability_chart",
    "ChartPanel",
    "paper_figure_panels",
    "plot_paper_figure",
    "PAPER_VEHICLE",
    "PAPER_CURVATURES",
]

#: The paper's vehicle, section 4.3: f = 2.7 m, d = 1.35 m.
PAPER_VEHICLE = Vehicle(wheelbase=2.7, rear_to_cg=1.35)

#: Curvatures [1/m] overlaid in each panel of Figs. 3 (V = 5) and 4 (V = 20).
#: The paper does not list them; these are this library's choice.
PAPER_CURVATURES = {3: (0.0, 0.05, 0.1, 0.2), 4: (0.0, 0.01, 0.02, 0.05)}

_DEFAULT_RANGE = (-1.0, 1.0)
_DEFAULT_POINTS = 401
_MAX_RANGE = (-2.0, 2.0)
# Line styles tell the two Routh-Hurwitz conditions apart in every chart.
_STYLE = {0: "-", 1: "--"}
_COND_LABEL = {0: r"$p_1 = 0$ (eq. 35)", 1: r"$p_0 = 0$ (eq. 36)"}
_HATCHES = (None, "//", "\\\\", "||", "--", "xx", "..")


def _axis(name: str, values) -> np.ndarray:
    if values is None:
        return np.linspace(*_DEFAULT_RANGE, _DEFAULT_POINTS)
    arr = np.asarray(check_finite(name, values), dtype=float)
    if arr.ndim != 1 or arr.size < 2:
        raise ValueError(
            f"{name} must be a 1-D array of at least 2 gains, got shape {arr.shape}"
        )
    if not (np.all(np.diff(arr) > 0) or np.all(np.diff(arr) < 0)):
        raise ValueError(f"{name} must be strictly monotonic")
    return arr


@dataclass(frozen=True, eq=False)
class StabilityChart:
    r"""Stable set of the linear closed loop on a ``(k1, k2)`` grid.

    Returned by :func:`stability_chart`; do not build it directly.

    Attributes
    ----------
    vehicle : Vehicle
    speed, curvature, ratio : float
        Operating point :math:`V` [m/s], :math:`\kappa_C` [1/m] and
        :math:`a`.
    model : str
        ``"exact"`` or ``"paper"``.
    k1, k2 : ndarray
        Grid axes [rad/m] and [-], 1-D.
    stable : ndarray of bool
        Shape ``(len(k2), len(k1))``: ``stable[i, j]`` is the Routh-Hurwitz
        verdict at ``(k1[j], k2[i])`` (rows follow ``k2``, as in
        :func:`numpy.meshgrid` and :meth:`matplotlib.axes.Axes.contourf`).
    boundaries : (StabilityBoundary, StabilityBoundary)
        The ``p1 = 0`` (eq. 35) and ``p0 = 0`` (eq. 36) lines.
    pole : float or None
        Requested double root :math:`\lambda_0` [1/s].
    design : SteeringGains or None
        Double-root gains for `pole`; None when no pole was requested or the
        design does not exist (then `design_error` says why).
    design_error : str or None
        The :class:`UncontrollableError` message when the design failed.
    """

    vehicle: Vehicle
    speed: float
    curvature: float
    ratio: float
    model: str
    k1: np.ndarray
    k2: np.ndarray
    stable: np.ndarray
    boundaries: tuple[StabilityBoundary, StabilityBoundary]
    pole: float | None = None
    design: SteeringGains | None = None
    design_error: str | None = None

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

    def notes(self, label: str = "") -> list[str]:
        """Remarks a reader needs that the drawing cannot show."""
        pre = f"{label}: " if label else ""
        out = []
        if self.empty:
            out.append(f"{pre}no stable gains on this grid")
        if self.design_error is not None:
            out.append(rf"{pre}no $\lambda_0$ design (uncontrollable)")
        elif self.design is not None and not self.design_on_chart:
            out.append(
                rf"{pre}$\lambda_0$ = {self.pole:g} gains off chart: "
                f"({float(self.design.k1):.3g}, {float(self.design.k2):.3g})"
            )
        return out

    def describe(self) -> str:
        """One-line description: a, V, kappa and the model."""
        return (
            f"a = {self.ratio:g}, V = {self.speed:g} m/s, "
            rf"$\kappa$ = {self.curvature:g} 1/m, {self.model} model"
        )

    def plot(
        self,
        ax=None,
        *,
        color: str = "C0",
        label: str | None = None,
        hatch: str | None = None,
        alpha: float = 0.3,
        boundaries: bool = True,
        design: bool = True,
        legend: bool = True,
        title: bool | str = True,
    ):
        r"""Draw the stable region, the boundary lines and the design point.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure is created if None.
        color : str, optional
            Colour of the region, lines and design marker.
        label : str, optional
            Legend label of the stable region (default ``"stable"``).
        hatch : str, optional
            Matplotlib hatch of the region, to tell overlaid charts apart.
        alpha : float, optional
            Opacity of the region.
        boundaries, design : bool, optional
            Whether to draw the boundary lines and the design point.
        legend : bool, optional
            Whether to add a legend.
        title : bool or str, optional
            True: :meth:`describe`; a string: that title; False: none.

        Returns
        -------
        matplotlib.axes.Axes
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(5.5, 4.8), layout="constrained")
        handles = self._draw(ax, color, label, hatch, alpha, boundaries, design)
        if title:
            ax.set_title(self.describe() if title is True else title, fontsize=10)
        if legend:
            ax.legend(handles=handles, fontsize=8, loc="best")
        _note_box(ax, self.notes())
        return ax

    def _draw(self, ax, color, label, hatch, alpha, boundaries, design) -> list:
        """Draw on `ax`; return the legend handles."""
        from matplotlib.colors import to_rgba
        from matplotlib.patches import Patch

        region_label = "stable" if label is None else label
        if not self.empty:
            z = self.stable.astype(float)
            ax.contourf(
                self.k1, self.k2, z, levels=[0.5, 1.5], colors=[color], alpha=alpha
            )
            if hatch:
                # A second, unfilled layer keeps the hatch opaque and in the
                # region's colour, so overlaid regions stay distinguishable.
                cs = ax.contourf(
                    self.k1,
                    self.k2,
                    z,
                    levels=[0.5, 1.5],
                    colors="none",
                    hatches=[hatch],
                )
                cs.set_edgecolor(color)
                cs.set_linewidth(0.0)
        # contourf makes no legend handle; a proxy patch stands in for it.
        handles = [
            Patch(
                facecolor=to_rgba(color, alpha if not self.empty else 0.0),
                hatch=hatch,
                edgecolor=color,
                label=region_label + (" (empty)" if self.empty else ""),
            )
        ]
        k1r = (float(self.k1.min()), float(self.k1.max()))
        k2r = (float(self.k2.min()), float(self.k2.max()))
        if boundaries:
            for i, b in enumerate(self.boundaries):
                seg = b.segment(k1r, k2r)
                if seg is None:
                    continue
                (line,) = ax.plot(
                    seg[:, 0],
                    seg[:, 1],
                    _STYLE[i],
                    color=color,
                    lw=1.6,
                    label=_COND_LABEL[i] if label is None else None,
                )
                if label is None:
                    handles.append(line)
        if design and self.design_on_chart:
            k1d, k2d = float(self.design.k1), float(self.design.k2)
            (pt,) = ax.plot(
                k1d,
                k2d,
                "o",
                color=color,
                mec="k",
                ms=7,
                label=rf"$\lambda_0$ = {self.pole:g}: ({k1d:.3f}, {k2d:.3f})",
                zorder=5,
            )
            if label is None:
                handles.append(pt)
        ax.set_xlim(*k1r)
        ax.set_ylim(*k2r)
        ax.set_xlabel(r"$k_1$ [rad/m]")
        ax.set_ylabel(r"$k_2$ [-]")
        ax.axhline(0.0, color="0.7", lw=0.5, zorder=0)
        ax.axvline(0.0, color="0.7", lw=0.5, zorder=0)
        return handles


def stability_chart(
    vehicle: Vehicle,
    curvature: float,
    ratio: float,
    speed: float,
    k1=None,
    k2=None,
    model: str = "exact",
    pole: float | None = None,
) -> StabilityChart:
    r"""Routh-Hurwitz stability of the linear closed loop on a gain grid.

    Note the argument order ``(vehicle, curvature, ratio, speed, ...)``,
    which follows the paper's charts (one chart per curvature and ratio);
    pass them by keyword when in doubt.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    curvature : float
        Path curvature :math:`\kappa_C` [1/m].
    ratio : float
        Rear-to-front steering ratio :math:`a`.
    speed : float
        Speed :math:`V` [m/s], nonzero; for ``V < 0`` condition (35) flips
        side (see :mod:`fws_control.stability`).
    k1, k2 : array_like, optional
        Strictly monotonic 1-D grid axes [rad/m], [-]; default 401 points on
        ``[-1, 1]`` each.
    model : {"exact", "paper"}, optional
        Linearisation, see :func:`linearize`.
    pole : float, optional
        Double root :math:`\lambda_0 < 0` whose gains
        (:func:`double_root_gains`) are stored and marked. If that design is
        uncontrollable (``a = 1`` on a straight path) the chart records the
        reason in :attr:`StabilityChart.design_error` instead of failing.

    Returns
    -------
    StabilityChart
        ``stable`` has shape ``(len(k2), len(k1))``.

    Raises
    ------
    ValueError
        For a zero speed, non-finite arguments, a non-negative `pole`, an
        unknown `model` or grid axes that are not 1-D monotonic arrays.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> ch = fws.stability_chart(veh, curvature=0.0, ratio=-1.0, speed=5.0,
    ...                          k1=np.linspace(-1, 1, 1000),
    ...                          k2=np.linspace(-1, 1, 800), pole=-1.0)
    >>> ch.stable.shape
    (800, 1000)
    >>> round(float(ch.design.k1), 4), round(float(ch.design.k2), 4)
    (0.054, 0.6129)
    >>> bool(ch.stable[np.searchsorted(ch.k2, 0.6), np.searchsorted(ch.k1, 0.05)])
    True
    >>> fws.stability_chart(veh, 0.0, 1.0, 5.0, pole=-1.0).design_error
    'ratio=1.0 with curvature=0.0 makes delta_r = delta_f: ...'
    """
    check_model(model)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    curvature = check_scalar("curvature", curvature)
    ratio = check_scalar("ratio", ratio)
    k1a = _axis("k1", k1)
    k2a = _axis("k2", k2)
    # Outer broadcasting (k2 down the rows, k1 across) avoids a meshgrid.
    stable = is_stable(
        vehicle, speed, curvature, k1a[np.newaxis, :], k2a[:, np.newaxis], ratio, model
    )
    bounds = stability_boundaries(vehicle, speed, curvature, ratio, model)
    design = err = None
    if pole is not None:
        pole = float(check_finite("pole", pole))
        try:
            g = double_root_gains(vehicle, speed, curvature, ratio, pole, model)
            design = SteeringGains(float(g.k1), float(g.k2), ratio)
        except UncontrollableError as exc:
            err = str(exc)
    return StabilityChart(
        vehicle=vehicle,
        speed=speed,
        curvature=curvature,
        ratio=ratio,
        model=model,
        k1=k1a,
        k2=k2a,
        stable=stable,
        boundaries=bounds,
        pole=pole,
        design=design,
        design_error=err,
    )


@dataclass(frozen=True, eq=False)
class ChartPanel:
    """One panel of a paper figure: overlaid charts with their labels.

    Attributes
    ----------
    title : str
        Panel title, e.g. ``"(a) V = 5 m/s, kappa = 0"``.
    charts : tuple of StabilityChart
    labels : tuple of str
        Legend label of each chart (the quantity that varies in the panel).
    """

    title: str
    charts: tuple[StabilityChart, ...]
    labels: tuple[str, ...]


def _panel_ranges(designs, base=_DEFAULT_RANGE, cap=_MAX_RANGE):
    """Grid range covering ``base`` and the design points, with a margin.

    The range grows at most to ``cap``: a design with huge gains (``a`` near
    1 on a gently curved path) would otherwise squash every region into a
    sliver. Designs left outside are listed in the panel instead.
    """
    k1s = [float(g.k1) for g in designs if g is not None]
    k2s = [float(g.k2) for g in designs if g is not None]
    out = []
    for vals in (k1s, k2s):
        lo, hi = base
        width = hi - lo
        vals = [v for v in vals if cap[0] <= v <= cap[1]]
        if vals:
            lo = max(cap[0], min(lo, min(vals) - 0.1 * width))
            hi = min(cap[1], max(hi, max(vals) + 0.1 * width))
        out.append((lo, hi))
    return out


def _build_panel(vehicle, title, specs, model, pole, npoints):
    """specs: list of (label, speed, curvature, ratio)."""
    designs = []
    for _, V, kap, a in specs:
        try:
            designs.append(double_root_gains(vehicle, V, kap, a, pole, model))
        except UncontrollableError:
            designs.append(None)
    (k1lo, k1hi), (k2lo, k2hi) = _panel_ranges(designs)
    k1 = np.linspace(k1lo, k1hi, npoints)
    k2 = np.linspace(k2lo, k2hi, npoints)
    charts = tuple(
        stability_chart(vehicle, kap, a, V, k1, k2, model=model, pole=pole)
        for _, V, kap, a in specs
    )
    return ChartPanel(title, charts, tuple(s[0] for s in specs))


def paper_figure_panels(
    n: int,
    model: str = "exact",
    vehicle: Vehicle | None = None,
    pole: float = -1.0,
    curvatures=None,
    npoints: int = _DEFAULT_POINTS,
) -> list[ChartPanel]:
    r"""The data behind Figs. 2, 3 or 4 of the paper.

    Fig. 2: straight path; (a) ``a`` in {-1.5, -1, -0.5, 0} at 5 m/s, (b) ``a``
    in {-1.5, -1, -0.5} at 20 m/s, (c) ``a`` in {0, 0.5, 1, 1.5} at 20 m/s.
    Figs. 3 (5 m/s) and 4 (20 m/s): one panel per ``a`` in {-1.5, -1, -0.5,
    0, 0.5, 1, 1.5}, each overlaying the curvatures of
    :data:`PAPER_CURVATURES` (or `curvatures`).

    Each panel's grid covers ``[-1, 1]^2`` (the paper's range), widened where
    needed (up to ``[-2, 2]``) so that the :math:`\lambda_0` design points are
    visible; designs outside that are listed in the panel.

    Parameters
    ----------
    n : {2, 3, 4}
        Figure number.
    model : {"exact", "paper"}, optional
        Linearisation. On a straight path (Fig. 2) both agree.
    vehicle : Vehicle, optional
        Default :data:`PAPER_VEHICLE`.
    pole : float, optional
        Double root of the marked gains, default -1.
    curvatures : sequence of float, optional
        Curvatures for Figs. 3-4 instead of :data:`PAPER_CURVATURES`.
    npoints : int, optional
        Grid points per axis.

    Returns
    -------
    list of ChartPanel

    Examples
    --------
    >>> import fws_control as fws
    >>> panels = fws.paper_figure_panels(2, npoints=51)
    >>> [p.labels for p in panels]
    [('a = -1.5', 'a = -1', 'a = -0.5', 'a = 0'), ('a = -1.5', 'a = -1', 'a = -0.5'),
     ('a = 0', 'a = 0.5', 'a = 1', 'a = 1.5')]
    """
    check_model(model)
    vehicle = PAPER_VEHICLE if vehicle is None else vehicle
    if n == 2:
        groups = [
            ("(a) V = 5 m/s", 5.0, (-1.5, -1.0, -0.5, 0.0)),
            ("(b) V = 20 m/s", 20.0, (-1.5, -1.0, -0.5)),
            ("(c) V = 20 m/s", 20.0, (0.0, 0.5, 1.0, 1.5)),
        ]
        return [
            _build_panel(
                vehicle,
                rf"{t}, $\kappa$ = 0",
                [(f"a = {a:g}", V, 0.0, a) for a in ratios],
                model,
                pole,
                npoints,
            )
            for t, V, ratios in groups
        ]
    if n in (3, 4):
        V = 5.0 if n == 3 else 20.0
        kappas = PAPER_CURVATURES[n] if curvatures is None else tuple(curvatures)
        panels = []
        ratios = (-1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5)
        for letter, a in zip("abcdefg", ratios, strict=True):
            panels.append(
                _build_panel(
                    vehicle,
                    f"({letter}) a = {a:g}, V = {V:g} m/s",
                    [(rf"$\kappa$ = {k:g} 1/m", V, k, a) for k in kappas],
                    model,
                    pole,
                    npoints,
                )
            )
        return panels
    raise ValueError(f"n must be 2, 3 or 4 (the paper's chart figures), got {n!r}")


def _note_box(ax, notes) -> None:
    if notes:
        ax.text(
            0.02,
            0.02,
            "\n".join(notes),
            transform=ax.transAxes,
            fontsize=7,
            va="bottom",
            bbox={"fc": "white", "ec": "0.7", "alpha": 0.9},
            zorder=10,
        )


def _draw_panel(ax, panel: ChartPanel, legend: bool = True) -> list:
    from matplotlib.lines import Line2D

    handles = []
    notes = []
    for i, (ch, lab) in enumerate(zip(panel.charts, panel.labels, strict=True)):
        color = f"C{i}"
        handles += ch._draw(
            ax,
            color=color,
            label=lab,
            hatch=_HATCHES[i % len(_HATCHES)],
            alpha=0.1,
            boundaries=True,
            design=True,
        )
        notes += ch.notes(lab)
    handles += [
        Line2D([], [], color="0.3", ls=_STYLE[0], label=_COND_LABEL[0]),
        Line2D([], [], color="0.3", ls=_STYLE[1], label=_COND_LABEL[1]),
        Line2D(
            [],
            [],
            marker="o",
            ls="",
            color="0.6",
            mec="k",
            label=rf"$\lambda_0$ = {panel.charts[0].pole:g} gains",
        ),
    ]
    _note_box(ax, notes)
    ax.set_title(panel.title, fontsize=10)
    if legend:
        # Below the axes: inside, it would hide regions and design points.
        ax.legend(
            handles=handles,
            fontsize=8,
            loc="upper center",
            bbox_to_anchor=(0.5, -0.13),
            ncol=3,
            frameon=False,
        )
    return handles


def plot_paper_figure(
    n: int,
    model: str = "exact",
    vehicle: Vehicle | None = None,
    pole: float = -1.0,
    curvatures=None,
    npoints: int = _DEFAULT_POINTS,
):
    r"""Redraw Fig. 2, 3 or 4 of the paper as one matplotlib figure.

    Every panel overlays the stable regions (hatched, translucent) of the
    charts listed in :func:`paper_figure_panels`, their boundary lines
    (solid: eq. 35, dashed: eq. 36) and the :math:`\lambda_0` gains.

    Parameters
    ----------
    n, model, vehicle, pole, curvatures, npoints
        See :func:`paper_figure_panels`.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt, fws_control as fws
    >>> fig = fws.plot_paper_figure(2, npoints=101)
    >>> len(fig.axes)
    3
    >>> plt.close(fig)
    """
    import matplotlib.pyplot as plt

    panels = paper_figure_panels(n, model, vehicle, pole, curvatures, npoints)
    if n == 2:
        fig, axes = plt.subplots(1, 3, figsize=(15, 6.2), layout="constrained")
        axes = list(axes)
    else:
        fig, axs = plt.subplots(2, 4, figsize=(19, 9.5), layout="constrained")
        axes = list(axs.flat)
    for ax, panel in zip(axes, panels, strict=False):
        handles = _draw_panel(ax, panel, legend=n == 2)
    if n != 2:
        # The eighth slot holds the shared legend.
        spare = axes[-1]
        spare.axis("off")
        spare.legend(handles=handles, loc="center", fontsize=10, title="legend")
    V = {2: "5 and 20", 3: "5", 4: "20"}[n]
    fig.suptitle(
        f"Fig. {n}: stable gains (shaded), V = {V} m/s, {model} model", fontsize=13
    )
    return fig
