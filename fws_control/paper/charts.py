r"""The paper's stability-chart figures (Figs. 2-4) from :func:`stability_chart`.

The paper does not list the curvatures shown in Figs. 3 and 4; this module
uses :data:`~fws_control.paper.data.PAPER_CURVATURES`:
:math:`\kappa \in \{0, 0.05, 0.1, 0.2\}` 1/m at 5 m/s (Fig. 3) and
:math:`\kappa \in \{0, 0.01, 0.02, 0.05\}` 1/m at 20 m/s (Fig. 4), which
include the curvatures of the simulations (0.1 and 0.01 1/m).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from ..charts import StabilityChart, stability_chart
from ..exceptions import UncontrollableError
from ..hints import ModelName
from ..layout import grid_margins
from ..plant import LateralPlant
from ..pole_placement import double_root_gains
from ..reprs import summary_repr
from ..validation import check_model
from ..vehicle import Vehicle
from .data import PAPER_CURVATURES, PAPER_VEHICLE

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["ChartPanel", "paper_figure_panels", "plot_paper_figure"]

_DEFAULT_RANGE = (-1.0, 1.0)
_DEFAULT_POINTS = 401
_MAX_RANGE = (-2.0, 2.0)


@summary_repr
@dataclass(frozen=True, eq=False)
class ChartPanel:
    r"""One panel of a paper figure: overlaid charts with their labels.

    Attributes
    ----------
    title : str
        Panel title, e.g. ``"(a) V = 5 m/s, $\kappa$ = 0"``.
    charts : tuple of StabilityChart
    labels : tuple of str
        Legend label of each chart (the quantity that varies in the panel).

    Examples
    --------
    >>> from fws_control.paper import paper_figure_panels
    >>> panel = paper_figure_panels(2, npoints=51)[0]
    >>> print(panel.title)
    (a) V = 5 m/s, $\kappa$ = 0
    >>> [(lab, round(c.stable_fraction, 3))
    ...  for lab, c in zip(panel.labels, panel.charts)]
    [('a = -1.5', 0.105), ('a = -1', 0.127), ('a = -0.5', 0.176), ('a = 0', 0.279)]
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


def _designs(vehicle, specs, model, pole):
    designs = []
    for _, V, kap, a in specs:
        try:
            plant = LateralPlant(vehicle, speed=V, curvature=kap, model=model)
            designs.append(double_root_gains(plant, ratio=a, pole=pole))
        except UncontrollableError:
            designs.append(None)
    return designs


def _build_panel(
    vehicle, title, specs, model, pole, npoints, ranges=None
) -> ChartPanel:
    """specs: list of (label, speed, curvature, ratio)."""
    if ranges is None:
        ranges = _panel_ranges(_designs(vehicle, specs, model, pole))
    (k1lo, k1hi), (k2lo, k2hi) = ranges
    k1 = np.linspace(k1lo, k1hi, npoints)
    k2 = np.linspace(k2lo, k2hi, npoints)
    charts = tuple(
        stability_chart(
            LateralPlant(vehicle, speed=V, curvature=kap, model=model),
            ratio=a,
            k1=k1,
            k2=k2,
            pole=pole,
        )
        for _, V, kap, a in specs
    )
    return ChartPanel(title, charts, tuple(s[0] for s in specs))


def paper_figure_panels(
    n: int,
    *,
    model: ModelName = "kinematic",
    vehicle: Vehicle | None = None,
    pole: float = -1.0,
    curvatures: Sequence[float] | None = None,
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
    visible; designs outside that are listed in the panel and marked by an
    arrowhead on its frame. The panels of Figs. 3-4 share one range.

    Parameters
    ----------
    n : {2, 3, 4}
        Figure number.
    model : {"kinematic", "paper"}, optional
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
    >>> from fws_control.paper import paper_figure_panels
    >>> panels = paper_figure_panels(2, npoints=51)
    >>> [p.labels for p in panels]
    [('a = -1.5', 'a = -1', 'a = -0.5', 'a = 0'), ('a = -1.5', 'a = -1', 'a = -0.5'),
     ('a = 0', 'a = 0.5', 'a = 1', 'a = 1.5')]
    """
    model = check_model(model)
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
        specs = {
            a: [(rf"$\kappa$ = {k:g} 1/m", V, k, a) for k in kappas] for a in ratios
        }
        # One range for every panel, so that the panels compare at a glance.
        designs = [d for a in ratios for d in _designs(vehicle, specs[a], model, pole)]
        ranges = _panel_ranges(designs)
        for letter, a in zip("abcdefg", ratios, strict=True):
            panels.append(
                _build_panel(
                    vehicle,
                    f"({letter}) a = {a:g}, V = {V:g} m/s",
                    specs[a],
                    model,
                    pole,
                    npoints,
                    ranges,
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
            fontsize=8,
            va="bottom",
            bbox={"fc": "white", "ec": "0.7", "alpha": 0.9},
            zorder=10,
        )


def _wrap_notes(notes, width: float, fontsize: float) -> list[str]:
    """Break each of `notes` at spaces into lines at most `width` points wide.

    The rule of matplotlib's ``Text(wrap=True)`` (as many words per line as
    fit), with a line's width taken as the sum of its words' widths and its
    spaces' instead of a layout of every candidate line: matplotlib measures
    each prefix of each line again, and a prefix holding mathtext
    (``$\\kappa$``) is parsed anew each time, which made the notes of Fig. 4
    about two fifths of its drawing time. Widths are the font's unhinted
    advances (:data:`matplotlib.textpath.text_to_path`), independent of the
    resolution.
    """
    from matplotlib import cbook
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import text_to_path

    prop = FontProperties(size=fontsize)
    widths: dict[str, float] = {}

    def measure(word: str) -> float:
        if word not in widths:
            ismath = cbook.is_math_text(word)
            widths[word] = text_to_path.get_text_width_height_descent(
                word, prop, ismath=ismath
            )[0]
        return widths[word]

    space = measure("x x") - measure("xx")
    lines = []
    for note in notes:
        line: list[str] = []
        used = 0.0
        for word in note.split(" "):
            w = measure(word)
            if line and used + space + w > width:
                lines.append(" ".join(line))
                line, used = [], 0.0
            used += (space if line else 0.0) + w
            line.append(word)
        lines.append(" ".join(line))
    return lines


#: One hatch per overlaid chart: where the stable regions of several
#: curvatures overlap, their hatches cross instead of their light fills
#: blending into one colour.
_HATCHES = ("//", "\\\\", "||", "--", "++", "..")


_UNDECIDED = re.compile(r"^(\(\w\) .*?): (\d+) undecided points: (.*)$")


def _gather_undecided(notes: list[str]) -> list[str]:
    """The undecided-point notes of every panel as one note (same reason).

    One line per chart and curvature ran under the legend of Figs. 3-4; the
    counts stay, after the panel and curvature they belong to.
    """
    found = [(m, note) for note in notes if (m := _UNDECIDED.match(note))]
    reasons = {m.group(3) for m, _ in found}
    if len(found) < 2 or len(reasons) != 1:
        return notes
    counts = ", ".join(f"{m.group(1)}: {m.group(2)}" for m, _ in found)
    gathered = f"undecided points ({reasons.pop()}): {counts}"
    return [note for note in notes if not _UNDECIDED.match(note)] + [gathered]


def _draw_panel(ax, panel: ChartPanel, legend: bool = True, notes_here: bool = True):
    """Draw one panel; return its legend handles and its notes.

    With `notes_here` the notes go into a box in the panel; otherwise the
    caller places them (Figs. 3-4 gather them beside the legend, where
    they hide no region).
    """
    from matplotlib.lines import Line2D

    handles = []
    notes = []
    for i, (ch, lab) in enumerate(zip(panel.charts, panel.labels, strict=True)):
        color = f"C{i}"
        # Light fills, a hatch each and an outline band: overlapping regions
        # show every hatch that covers them, and each edge keeps its colour.
        handles += ch.draw(
            ax,
            color=color,
            label=lab,
            alpha=0.08,
            hatch=_HATCHES[i % len(_HATCHES)],
            outline=True,
            boundaries=True,
            design=True,
        )
        notes += ch.notes(label=lab)
    # one legend entry for the undecided points of all overlaid charts (each
    # chart's count is in the notes)
    undecided = [h for h in handles if h.get_label().startswith("undecided")]
    handles = [h for h in handles if h not in undecided]
    if undecided:
        undecided[0].set_label("undecided (hatched)")
        handles.append(undecided[0])
    handles += [
        Line2D([], [], color="0.3", ls="-", label=r"$p_1 = 0$ (eq. 35)"),
        Line2D([], [], color="0.3", ls="--", label=r"$p_0 = 0$ (eq. 36)"),
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
    if any(ch.design is not None and not ch.design_on_chart for ch in panel.charts):
        handles.append(
            Line2D(
                [],
                [],
                marker=">",
                ls="",
                color="0.3",
                mfc="white",
                mew=2.0,
                label="gains off chart (arrow on the frame; values in the notes)",
            )
        )
    if notes_here:
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
    return handles, notes


def plot_paper_figure(
    n: int,
    *,
    model: ModelName = "kinematic",
    vehicle: Vehicle | None = None,
    pole: float = -1.0,
    curvatures: Sequence[float] | None = None,
    npoints: int = _DEFAULT_POINTS,
    ax: Sequence[Axes] | np.ndarray | None = None,
) -> ct.ControlPlot:
    r"""Redraw Fig. 2, 3 or 4 of the paper as one matplotlib figure.

    Every panel overlays the stable regions (light fill, outlined) of the
    charts listed in :func:`paper_figure_panels`, their boundary lines
    (solid: eq. 35, dashed: eq. 36) and the :math:`\lambda_0` gains.

    Parameters
    ----------
    n : {2, 3, 4}
        Figure number.
    model, vehicle, pole, curvatures, npoints : optional
        See :func:`paper_figure_panels`.
    ax : array of matplotlib.axes.Axes, optional
        Axes to draw into: 3 for Fig. 2, 8 for Figs. 3-4 (the last holds the
        legend). A new figure is created if None.

    Returns
    -------
    control.ControlPlot
        ``.figure`` is the figure; ``.axes`` the panels (shape ``(1, 3)`` or
        ``(2, 4)``).

    Examples
    --------
    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> from fws_control.paper import plot_paper_figure
    >>> cplt = plot_paper_figure(2, npoints=101)
    >>> cplt.axes.shape
    (1, 3)
    >>> plt.close(cplt.figure)
    """
    import matplotlib.pyplot as plt

    panels = paper_figure_panels(
        n,
        model=model,
        vehicle=vehicle,
        pole=pole,
        curvatures=curvatures,
        npoints=npoints,
    )
    shape = (1, 3) if n == 2 else (2, 4)
    if ax is None:
        # Fixed layout (fws_control.layout): Fig. 2 keeps room below the
        # panels for their legends.
        size, margins = (
            ((15, 6.2), {"bottom": 1.3, "right": 0.3, "wgap": 1.0})
            if n == 2
            else ((19, 9.5), {"left": 0.8, "right": 0.3, "wgap": 1.0})
        )
        fig, axs = plt.subplots(
            *shape,
            figsize=size,
            gridspec_kw=grid_margins(size, nrows=shape[0], ncols=shape[1], **margins),
        )
    else:
        axs = np.asarray(ax, dtype=object)
        if axs.size != shape[0] * shape[1]:
            raise ValueError(
                f"ax must hold {shape[0] * shape[1]} axes for Fig. {n}, got {axs.size}"
            )
        axs = axs.reshape(shape)
        fig = axs.flat[0].figure
    axes = list(axs.flat)
    lines = np.empty(shape, dtype=object)
    handles: list[Any] = []
    all_notes = []
    for i, (a, panel) in enumerate(zip(axes, panels, strict=False)):
        drawn, notes = _draw_panel(a, panel, legend=n == 2, notes_here=n == 2)
        # "(f) a = 1, V = 5 m/s" -> "(f)": the notes name their panel
        all_notes += [f"{panel.title.split(' ', 1)[0]} {note}" for note in notes]
        for h in drawn:
            base = h.get_label().removesuffix(" (empty)")
            if base not in [k.get_label().removesuffix(" (empty)") for k in handles]:
                handles.append(h)
        lines.flat[i] = list(a.get_lines())
    if n != 2:
        # The eighth slot holds the shared legend.
        spare = axes[-1]
        spare.axis("off")
        # The legend is wider than its slot: anchored a little inside the
        # figure's right edge (centred, it reached past the canvas with
        # matplotlib 3.8's wider text), vertically centred on the slot.
        from matplotlib.transforms import blended_transform_factory

        to_edge = blended_transform_factory(fig.transFigure, spare.transAxes)
        spare.legend(
            handles=handles, loc="upper right", bbox_to_anchor=(0.995, 1.0),
            bbox_transform=to_edge, fontsize=10, title="legend",
        )  # fmt: skip
        if all_notes:
            # the panels' notes, under the legend: in the panels they hid
            # data. Broken at spaces to end within the figure, as
            # Text(wrap=True) would break them, but measured word by word
            # (see _wrap_notes).
            room = (1.0 - spare.get_position().x0) * fig.get_figwidth() * 72.0
            all_notes = _gather_undecided(all_notes)
            spare.text(
                0.0, 0.0, "\n".join(_wrap_notes(["notes:", *all_notes], room, 9)),
                transform=spare.transAxes, ha="left", va="bottom", fontsize=9,
            )  # fmt: skip
        lines.flat[-1] = []
    V = {2: "5 and 20", 3: "5", 4: "20"}[n]
    fig.suptitle(
        f"Fig. {n}: stable gains (shaded), V = {V} m/s, {model} model", fontsize=13
    )
    return ct.ControlPlot(lines, axs, fig)
