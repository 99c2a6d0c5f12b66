r"""Every figure of the paper (Figs. 2-9) as PNG files, plus a summary.

:func:`reproduce` writes one PNG per figure and ``summary.md`` into a
directory; ``fws-control reproduce --out DIR`` calls it. Each figure also has
a function returning a :class:`matplotlib.figure.Figure`, listed in
:data:`FIGURES`, so that scripts and the documentation can draw a single one.

Figures 2-4 are stability charts (:mod:`fws_control.charts`); Figs. 5-9 are
simulations of the nonlinear closed loop (:mod:`fws_control.paper.scenarios`).
Three extra figures go beyond the paper: root loci, linear-versus-nonlinear
responses and the turning radius that the paper's conclusion is about.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import control as ct
import numpy as np

from ..files import atomic_write, lock_folder, remove_stale_temporaries
from ..hints import ModelName
from ..layout import grid_margins
from ..linear import closed_loop
from ..plant import LateralPlant
from ..pole_placement import UncontrollableError, double_root_gains
from ..turning import plot_turning_radius, turning_radius
from ..validation import check_model
from ..vehicle import Vehicle
from .actuator import delay_margin_table, plot_actuator
from .charts import plot_paper_figure
from .data import (
    ACTUATOR_SOURCE,
    PAPER_CURVED,
    PAPER_SPEEDS,
    PAPER_VEHICLE,
    REALISTIC_DELAY,
    TABLE_RATIOS,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "FigureSpec",
    "FIGURES",
    "make_figure",
    "gains_table",
    "ReproduceResult",
    "reproduce",
    "plot_root_loci",
    "plot_fig5",
]


@dataclass(frozen=True)
class FigureSpec:
    """One figure that :func:`reproduce` writes.

    Attributes
    ----------
    name : str
        File stem, e.g. ``"fig2"``.
    caption : str
        What the figure shows.
    make : callable
        ``make(model=..., quick=...) -> matplotlib.figure.Figure``.
    paper : bool
        True for the paper's figures, False for the extras.
    """

    name: str
    caption: str
    make: Callable = field(repr=False)
    paper: bool = True


def _chart_figure(n):
    def make(model: ModelName = "kinematic", quick: bool = False):
        return plot_paper_figure(n, model=model, npoints=201 if quick else 401).figure

    return make


def plot_root_loci(
    *,
    vehicle: Vehicle | None = None,
    model: ModelName = "kinematic",
    quick: bool = False,
    ax: Sequence[Axes] | np.ndarray | None = None,
) -> ct.ControlPlot:
    r"""Root loci of the :math:`\lambda_0 = -1` designs (extra figure).

    (a) Gain locus (:func:`gain_loop`): poles of ``g*(k1, k2)`` for the
    double-root designs at three values of ``V*kappa``; the square marks
    ``g = 1`` (the double root). For any double-root design the loop is
    :math:`L(s) = (-2\lambda_0 s + \lambda_0^2 - V^2\kappa^2)/(s^2 +
    V^2\kappa^2)`, the same for every ``a`` and either model. (b) Real
    parts of the exact-model poles that the *paper-model* gains produce as
    the curvature grows (:func:`parameter_locus` with
    ``design_model="paper"``): -1 on a straight path, then they split, and
    for large curvature one crosses into the right half plane (erratum 3).
    (c) Ratio locus at 20 m/s on a straight path with the gains of the
    ``a = 0.5`` design kept fixed.

    Parameters
    ----------
    vehicle : Vehicle, optional
        Default the paper's vehicle.
    model : {"kinematic", "paper"}, optional
        Linearisation of the designs in (a) and (c).
    quick : bool, optional
        Fewer points per locus.
    ax : sequence of 3 matplotlib.axes.Axes, optional
        Axes of panels (a)-(c); a new figure if None.

    Returns
    -------
    control.ControlPlot
        Axes of shape ``(1, 3)``.

    Examples
    --------
    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> from fws_control.paper.figures import plot_root_loci
    >>> cplt = plot_root_loci(quick=True)
    >>> cplt.axes.shape
    (1, 3)
    >>> plt.close(cplt.figure)
    """
    import matplotlib.pyplot as plt

    from ..rootlocus import gain_loop, parameter_locus, refined_scale

    vehicle = PAPER_VEHICLE if vehicle is None else vehicle
    if ax is None:
        size = (17, 5.2)
        fig, axes = plt.subplots(
            1,
            3,
            figsize=size,
            gridspec_kw=grid_margins(size, ncols=3, top=0.95, wgap=0.65),
        )
    else:
        axes = list(np.asarray(ax, dtype=object).ravel())
        if len(axes) != 3:
            raise ValueError(f"ax must hold 3 axes, got {len(axes)}")
        fig = axes[0].figure
    n = 200 if quick else 800

    panel = axes[0]
    # For any double-root design the loop is L(s) = (-2 l0 s + l0^2 - V^2 k^2)
    # / (s^2 + V^2 k^2): it depends on V*kappa only, not on a or the model.
    for i, (V, kap) in enumerate(((5.0, 0.0), (20.0, 0.01), (5.0, 0.1))):
        plant = LateralPlant(vehicle, speed=V, curvature=kap, model=model)
        g = double_root_gains(plant, ratio=-1.0, pole=-1.0)
        loop = gain_loop(plant, g)
        rl = ct.root_locus_map(loop, gains=refined_scale(0.0, 4.0, n))
        lab = rf"V = {V:g} m/s, $\kappa$ = {kap:g} 1/m"
        for j, branch in enumerate(rl.loci.T):
            panel.plot(
                branch.real, branch.imag, color=f"C{i}", label=lab if j == 0 else None
            )
        panel.plot(rl.loci[0].real, rl.loci[0].imag, "x", color=f"C{i}", ms=8)
        at1 = ct.root_locus_map(loop, gains=[1.0]).loci[0]
        panel.plot(at1.real, at1.imag, "s", color=f"C{i}", mec="k", ms=6)
        z = loop.zeros()
        panel.plot(z.real, z.imag, "o", mfc="none", color=f"C{i}", ms=8)
    panel.plot([], [], "x", color="0.3", label="g = 0 (open loop)")
    panel.plot([], [], "o", mfc="none", color="0.3", label="zero of L(s)")
    panel.plot([], [], "s", color="0.6", mec="k", label=r"g = 1 ($\lambda_0 = -1$)")
    panel.set_title(
        "(a) gain locus: poles of $g\\,(k_1, k_2)$, g in [0, 4], for the\n"
        r"$\lambda_0 = -1$ designs (the same for every a: L(s) depends on V$\kappa$)",
        fontsize=10,
    )
    panel.set_xlabel("Re [1/s]")
    panel.set_ylabel("Im [1/s]")

    panel = axes[1]
    kappas = np.linspace(0.0, 0.4, n)
    for i, a in enumerate((-1.0, 0.0, 0.5)):
        plant = LateralPlant(vehicle, speed=5.0, model="kinematic")
        g0 = double_root_gains(
            LateralPlant(vehicle, speed=5.0, model="paper"), ratio=a, pole=-1.0
        )
        pz = parameter_locus(
            plant,
            g0,
            parameter="curvature",
            values=kappas,
            redesign_pole=-1.0,
            design_model="paper",
        )
        for j, branch in enumerate(pz.loci.T):
            panel.plot(
                kappas,
                branch.real,
                color=f"C{i}",
                ls="-" if j == 0 else "--",
                label=f"a = {a:g}" if j == 0 else None,
            )
    panel.axhline(-1.0, color="k", lw=1.0, ls=":", label=r"target $\lambda_0 = -1$")
    panel.axvline(0.1, color="0.6", lw=0.8)
    panel.text(
        0.102,
        0.97,
        r"$\kappa$ = 0.1 (Fig. 7)",
        va="top",
        transform=panel.get_xaxis_transform(),
        fontsize=8,
    )
    panel.plot([], [], "k-", label="pole 1 (solid), pole 2 (dashed)")
    panel.set_title(
        "(b) real parts of the exact-model poles with the paper-model\n"
        r"$\lambda_0 = -1$ gains (eqs. 43-46), V = 5 m/s (parameter locus)",
        fontsize=10,
    )
    panel.set_xlabel(r"curvature $\kappa$ [1/m]")
    panel.set_ylabel("Re [1/s]")

    panel = axes[2]
    plant = LateralPlant(vehicle, speed=20.0, model=model)
    g = double_root_gains(plant, ratio=0.5, pole=-1.0)
    ratios = np.linspace(-1.5, 0.99, n)
    pz = parameter_locus(plant, g, parameter="ratio", values=ratios)
    for j, branch in enumerate(pz.loci.T):
        panel.plot(
            branch.real,
            branch.imag,
            color="C3",
            label="poles, a from -1.5 to 0.99" if j == 0 else None,
        )
    panel.plot(
        pz.loci[0].real, pz.loci[0].imag, "x", color="C3", ms=8, label="a = -1.5"
    )
    panel.plot(
        pz.loci[-1].real, pz.loci[-1].imag, ">", color="C3", ms=7, label="a = 0.99"
    )
    at05 = parameter_locus(plant, g, parameter="ratio", values=[0.5]).loci[0]
    panel.plot(at05.real, at05.imag, "s", color="C3", mec="k", label="a = 0.5 (design)")
    panel.set_title(
        f"(c) ratio locus, gains k1 = {float(g.k1):.3f}, k2 = {float(g.k2):.3f} "
        "fixed\nV = 20 m/s, straight path",
        fontsize=10,
    )
    panel.set_xlabel("Re [1/s]")
    panel.set_ylabel("Im [1/s]")
    for panel in axes:
        panel.axhline(0.0, color="0.5", lw=0.8)
        panel.grid(alpha=0.3)
        panel.legend(fontsize=8, loc="lower left" if panel is axes[1] else "upper left")
    fig.suptitle("Root loci of the structured 4WS loop", fontsize=13)
    lines = np.empty((1, 3), dtype=object)
    for i, a in enumerate(axes):
        lines[0, i] = list(a.get_lines())
    return ct.ControlPlot(lines, np.array([list(axes)], dtype=object), fig)


def _comparison_figure(model: ModelName = "kinematic", quick: bool = False):
    from ..linear_vs_nonlinear import compare_linear_nonlinear

    plant = LateralPlant(PAPER_VEHICLE, speed=5.0, curvature=0.1, model=model)
    g = double_root_gains(plant, ratio=-1.0, pole=-1.0)
    cmp = compare_linear_nonlinear(
        plant,
        g,
        initial_state=(0.0, -5.0, 0.0),
        duration=15.0,
        dt=0.05 if quick else 0.01,
    )
    return cmp.plot().figure


def _turning_figure(model: ModelName = "kinematic", quick: bool = False):
    return plot_turning_radius(PAPER_VEHICLE).figure


# --------------------------------------------------------------------------
# Simulation figures (Figs. 5-9), drawn from fws_control.paper.scenarios data.

_DEG = 180.0 / math.pi
_FIG5_TITLES = {
    "a": "(a) straight road, V = 5 m/s, feedback",
    "b": "(b) curve κ = 1/10 1/m, V = 5 m/s, feedforward + feedback",
    "c": "(c) straight road, V = 20 m/s, feedback",
    "d": "(d) curve κ = 1/100 1/m, V = 20 m/s, feedforward + feedback",
}


# Solver tolerances of the simulation figures (5-9). With rtol = 1e-8 the
# peaks of Fig. 5 stay within 1e-7 (relative) and the curves of Figs. 6-9
# within 1e-6 m of the default rtol = 1e-10 (tests/test_figures.py), far
# below a pixel, and without numba the runs take about 40 % less time.
_SIM_RTOL = 1e-8
_SIM_ATOL = 1e-10


@lru_cache(maxsize=4)
def _fig5_data(model: ModelName, quick: bool):
    from .data import FIG5_RATIOS
    from .scenarios import fig5_peak_lateral_accel

    ratios = np.linspace(-1.5, 1.5, 13) if quick else FIG5_RATIOS
    # Fig. 5 and its table use only the statuses and the exact peaks, which do
    # not depend on the output grid (tests/test_peaks.py): a coarse grid skips
    # computing samples nobody reads (same peaks to 1e-15 as with dt = 0.01).
    return fig5_peak_lateral_accel(
        model, ratios, dt=0.1, rtol=_SIM_RTOL, atol=_SIM_ATOL, progress=False
    )


@lru_cache(maxsize=4)
def _fig6_to_9_data(model: ModelName, quick: bool):
    from .scenarios import fig6_to_9_responses

    return fig6_to_9_responses(
        model,
        dt=0.05 if quick else 0.01,
        rtol=_SIM_RTOL,
        atol=_SIM_ATOL,
        progress=False,
    )


_G = 9.81  # m/s^2


def plot_fig5(model: ModelName = "kinematic", quick: bool = False) -> Figure:
    r"""Fig. 5: peak absolute lateral acceleration of G versus the ratio ``a``.

    One panel per scenario, one curve per double root :math:`\lambda_0`
    (``-1, -2`` at 5 m/s; ``-1, -2, -3`` at 20 m/s), log scale. Peaks above
    1 g lie in a shaded band with a note why they are so large (the static
    controller commands a full steering step at t = 0). Runs without a peak
    are marked in a strip above each panel, outside the data area, one row
    per :math:`\lambda_0`: ``x`` a run that stopped at a singular steering
    angle (:math:`|\delta_f| \to \pi/2`), ``|`` ``a = 1`` on a straight
    road (no design).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    data = _fig5_data(model, quick)
    size = (13, 10)
    fig = plt.figure(figsize=size)
    # A fixed layout (fws_control.layout): 2 x 2 cells, each a strip above
    # its panel, close together; the gap between the cells holds the panel's
    # tick labels and x label and the next strip's title.
    outer = fig.add_gridspec(
        2, 2, **grid_margins(size, nrows=2, ncols=2, bottom=0.95, wgap=0.75, hgap=0.8)
    )
    pairs = []
    for r in (0, 1):
        for c in (0, 1):
            cell = outer[r, c].subgridspec(2, 1, height_ratios=[0.16, 1.0], hspace=0.04)
            ax = fig.add_subplot(cell[1])
            pairs.append((fig.add_subplot(cell[0], sharex=ax), ax))
    ratios_all = np.concatenate([sw.ratios for sw in data.values()])
    xpad = 0.06 * float(np.ptp(ratios_all))
    for (strip, ax), (panel, sweep) in zip(pairs, data.items(), strict=True):
        npoles = len(sweep.poles)
        finite = sweep.peak_lateral_accel[np.isfinite(sweep.peak_lateral_accel)]
        for i, lam in enumerate(sweep.poles):
            color = f"C{i}"
            ax.plot(
                sweep.ratios,
                sweep.peak_lateral_accel[i],
                "o-",
                ms=3,
                color=color,
                label=rf"$\lambda_0$ = {lam:g}",
            )
            stopped = np.isin(sweep.status[i], ("ok", "uncontrollable"), invert=True)
            unc = sweep.status[i] == "uncontrollable"
            strip.plot(
                sweep.ratios[stopped],
                np.full(stopped.sum(), i),
                "x",
                color=color,
                ms=7,
                mew=1.8,
            )
            strip.plot(
                sweep.ratios[unc],
                np.full(unc.sum(), i),
                "|",
                color=color,
                ms=9,
                mew=1.8,
            )
        strip.set_yticks(range(npoles))
        strip.set_yticklabels([f"{lam:g}" for lam in sweep.poles], fontsize=7)
        strip.set_ylim(npoles - 0.4, -0.6)
        strip.set_ylabel(
            r"$\lambda_0$", fontsize=8, rotation=0, labelpad=8, va="center"
        )
        strip.tick_params(axis="x", labelbottom=False)
        strip.set_xlabel("ratio $a$ [-]")
        strip.xaxis.label.set_visible(False)
        strip.grid(alpha=0.3, axis="x")
        strip.axvline(0.0, color="0.6", lw=0.8)
        kinds = []
        if np.any(np.isin(sweep.status, ("ok", "uncontrollable"), invert=True)):
            kinds.append("x run stopped: singular steering (no peak)")
        if np.any(sweep.status == "uncontrollable"):
            kinds.append("| a = 1: no design (uncontrollable)")
        strip.text(
            0.005,
            0.5,
            "\n".join(kinds) if kinds else "every run finished",
            transform=strip.transAxes,
            ha="left",
            va="center",
            fontsize=7.5,
            color="0.25",
            bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1.0},
        )
        strip.set_title(_FIG5_TITLES[panel], fontsize=10)
        ax.set_yscale("log")
        hi = max(float(finite.max()) if finite.size else _G, 2 * _G) * 2.0
        lo = min(float(finite.min()) if finite.size else _G, _G) / 2.0
        ax.set_ylim(lo, hi)
        if hi > _G:
            ax.axhspan(_G, hi, color="C3", alpha=0.07, lw=0)
            ax.axhline(_G, color="C3", lw=0.8, ls="--")
            ax.text(
                0.99,
                _G * 1.08,
                "1 g",
                transform=ax.get_yaxis_transform(),
                ha="right",
                va="bottom",
                fontsize=8,
                color="C3",
            )
        ax.set_xlim(float(ratios_all.min()) - xpad, float(ratios_all.max()) + xpad)
        ax.set_xlabel("ratio $a$ [-]")
        ax.tick_params(axis="x", labelbottom=True)
        ax.set_ylabel(r"max $|a_G^{lat}|$ [m/s²]")
        ax.grid(alpha=0.3, which="both")
        ax.axvline(0.0, color="0.6", lw=0.8)
        ax.legend(fontsize=8, loc="upper left")
    fig.suptitle(
        f"Fig. 5: peak lateral acceleration of G, double-root gains ({model} "
        "model), nonlinear simulation",
        fontsize=13,
    )
    fig.supxlabel(
        "Shaded: peaks above 1 g, physically implausible. They are this large "
        "because the controller is static: at t = 0 it commands the full steering "
        "step for the initial error at once,\nand the kinematic model (no tyre "
        "limits, no actuator lag) follows it. Strips above the panels: runs "
        "without a peak, one row per double root.",
        fontsize=9,
        color="C3",
    )
    return fig


def _responses_figure(n: int, model: ModelName, quick: bool):
    import matplotlib.pyplot as plt

    sr = _fig6_to_9_data(model, quick)[n]
    res, sc = sr.result, sr.scenario
    curved = sc.curvature != 0.0
    if curved:
        size = (16, 9)
        fig, axs = plt.subplots(
            2, 3, figsize=size, gridspec_kw=grid_margins(size, nrows=2, ncols=3)
        )
        panels = [
            (axs[0, 0], "e", 1.0, "(a) lateral error e [m]"),
            (axs[0, 1], "theta", _DEG, "(b) yaw angle error θ [deg]"),
            (axs[0, 2], None, None, "(c) trajectory"),
            (axs[1, 0], "delta_f", _DEG, "(d) front steering angle δf [deg]"),
            (axs[1, 1], "delta_r", _DEG, "(e) rear steering angle δr [deg]"),
            (axs[1, 2], "lateral_accel", 1.0, "(f) lateral acceleration [m/s²]"),
        ]
    else:
        size = (13, 9)
        fig, axs = plt.subplots(
            2,
            2,
            figsize=size,
            gridspec_kw=grid_margins(size, nrows=2, ncols=2, left=0.8, wgap=0.9),
        )
        panels = [
            (axs[0, 0], "y", 1.0, "(a) lateral position $y_R$ [m]"),
            (axs[0, 1], "lateral_accel", 1.0, "(b) lateral acceleration [m/s²]"),
            (axs[1, 0], "delta_f", _DEG, "(c) front steering angle δf [deg]"),
            (axs[1, 1], "delta_r", _DEG, "(d) rear steering angle δr [deg]"),
        ]
    undrawn = []
    for i, a in enumerate(sr.ratios):
        color = f"C{i}"
        status = res.status[i]
        label = f"a = {a:g}"
        if status == "uncontrollable":
            label += ": no design (uncontrollable)"
        elif status != "ok":
            label += f": stopped at {res.t_stop[i]:.2f} s ({status})"
        for ax, name, scale, _ in panels:
            if name is None:
                x, y = res.x[i], res.y[i]
            else:
                x, y = res.t, scale * getattr(res, name)[i]
            lab = label if name == panels[0][1] else None
            good = np.isfinite(y)
            if good.sum() <= 1:
                # Not simulated, or stopped at t = 0 with only its invalid
                # initial command: a note says so (the legend lists only drawn
                # curves); drawing the point would only stretch the axes.
                if lab is not None:
                    undrawn.append(label + ", not drawn")
                continue
            ax.plot(x, y, color=color, label=lab)
            if status != "ok":
                j = np.flatnonzero(good)[-1]
                ax.plot(x[j], y[j], "x", color=color, ms=8)
    ok = res.status == "ok"
    for ax, name, scale, title in panels:
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
        if name is not None and ok.any() and not ok.all():
            # Scale to the runs that finished: a run that diverges towards a
            # singular steering angle would otherwise flatten every curve.
            vals = scale * getattr(res, name)[ok]
            lo, hi = float(np.nanmin(vals)), float(np.nanmax(vals))
            pad = 0.08 * max(hi - lo, 1e-9)
            every = scale * getattr(res, name)
            if np.nanmax(every) > hi + pad or np.nanmin(every) < lo - pad:
                ax.set_ylim(lo - pad, hi + pad)
                ax.text(
                    0.99,
                    0.98,
                    "stopped runs clipped",
                    transform=ax.transAxes,
                    ha="right",
                    va="top",
                    fontsize=7,
                    color="0.4",
                )
        if name == "lateral_accel" and ok.any():
            # then the finished runs' own spike at t = 0, if it dwarfs the rest
            _clip_initial_spike(ax, res.t, getattr(res, name)[ok], sr.ratios[ok])
        if name is None:
            s = res.s[np.isfinite(res.s)]
            ss = np.linspace(0.0, float(s.max()) if s.size else 1.0, 400)
            px, py = sc.path.position(ss)
            ax.plot(px, py, "k--", lw=1.0, label="path")
            ax.set_xlabel("x [m]")
            ax.set_ylabel("y [m]")
            ax.set_aspect("equal", adjustable="datalim")
            ax.legend(fontsize=8, loc="best")
        else:
            ax.set_xlabel("time t [s]")
            ax.set_ylabel(title.split(") ", 1)[1])
    # Steering angles share one range: the panels are compared side by side.
    steer = [ax for ax, name, _, _ in panels if name in ("delta_f", "delta_r")]
    lims = [ax.get_ylim() for ax in steer]
    for ax in steer:
        ax.set_ylim(min(lo for lo, _ in lims), max(hi for _, hi in lims))
    panels[0][0].legend(fontsize=8, loc="best")
    if undrawn:
        panels[0][0].text(
            0.99,
            0.5,
            "\n".join(undrawn),
            transform=panels[0][0].transAxes,
            ha="right",
            va="center",
            fontsize=8,
            bbox={"fc": "white", "ec": "0.7", "alpha": 0.9},
        )
    ctrl = "feedforward + feedback" if sr.feedforward else "feedback"
    road = f"curved road κ = {sc.curvature:g} 1/m" if curved else "straight road"
    x0, y0, _ = sc.initial_state
    fig.suptitle(
        f"Fig. {n}: {road}, {ctrl}, V = {sc.speed:g} m/s, "
        rf"$\lambda_0$ = {sr.pole:g} ({model}-model gains), R(0) = ({x0:g}, {y0:g}) m",
        fontsize=13,
    )
    return fig


def _clip_initial_spike(ax, t, values, ratios, frac: float = 0.03) -> None:
    """Clip a t = 0 spike that would squash the rest of a panel; say so.

    The limits follow the samples after ``frac`` of the duration; if the
    first samples reach on one side more than twice as far as everything
    else spans, that side is clipped and a note gives the extreme value, its
    time and its run.
    """
    t = np.asarray(t, dtype=float)
    v = np.asarray(values, dtype=float).reshape(-1, t.size)
    late = t >= t[0] + frac * (t[-1] - t[0])
    lo, hi = float(np.nanmin(v[:, late])), float(np.nanmax(v[:, late]))
    all_lo, all_hi = float(np.nanmin(v)), float(np.nanmax(v))
    below, above = lo - all_lo, all_hi - hi
    # Clip only the side that holds the spike, and only if it dwarfs the rest.
    if below >= above:
        if below <= 2.0 * (hi - lo + above):
            return
        top = all_hi
        bottom = lo - 0.15 * (top - lo)
        k = np.unravel_index(np.nanargmin(v), v.shape)
    else:
        if above <= 2.0 * (hi - lo + below):
            return
        bottom = all_lo
        top = hi + 0.15 * (hi - bottom)
        k = np.unravel_index(np.nanargmax(v), v.shape)
    pad = 0.05 * (top - bottom)
    ax.set_ylim(
        bottom - (pad if below < above else 0), top + (pad if below >= above else 0)
    )
    ax.text(
        0.99,
        0.04,
        f"axis clipped {'below' if below >= above else 'above'}: a = "
        f"{ratios[k[0]]:g} reaches {v[k]:.3g} at t = {t[k[1]]:.2f} s,\n"
        "the response to the full steering step at t = 0",
        transform=ax.transAxes,
        ha="right",
        va="bottom",
        fontsize=7.5,
        color="0.3",
        bbox={"fc": "white", "ec": "0.7", "alpha": 0.9},
    )


def _response_maker(n):
    def make(model: ModelName = "kinematic", quick: bool = False):
        return _responses_figure(n, model, quick)

    return make


def _fig5_table(model: ModelName, quick: bool) -> str:
    data = _fig5_data(model, quick)
    show = (-1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5)
    lines = []
    for panel, sweep in data.items():
        lines += [f"**{_FIG5_TITLES[panel]}**", ""]
        head = "| λ0 | " + " | ".join(f"a = {a:g}" for a in show) + " | min over a |"
        lines += [head, "|---" * (len(show) + 2) + "|"]
        for i, lam in enumerate(sweep.poles):
            cells = []
            for a in show:
                j = int(np.argmin(np.abs(sweep.ratios - a)))
                st = sweep.status[i, j]
                if st == "ok":
                    cells.append(f"{sweep.peak_lateral_accel[i, j]:.3g}")
                elif st == "uncontrollable":
                    cells.append("no design")
                else:
                    cells.append("singular")
            row = sweep.peak_lateral_accel[i]
            if np.any(np.isfinite(row)):
                k = int(np.nanargmin(row))
                cells.append(f"{row[k]:.3g} at a = {sweep.ratios[k]:g}")
            else:
                cells.append("—")
            lines.append(f"| {lam:g} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


FIGURES: dict[str, FigureSpec] = {
    "fig2": FigureSpec(
        "fig2",
        "Stable gains on a straight path: (a) a = -1.5..0 at 5 m/s, "
        "(b) a = -1.5..-0.5 at 20 m/s, (c) a = 0..1.5 at 20 m/s",
        _chart_figure(2),
    ),
    "fig3": FigureSpec(
        "fig3",
        "Stable gains at 5 m/s for a = -1.5..1.5, curvatures 0, 0.05, 0.1, 0.2 1/m",
        _chart_figure(3),
    ),
    "fig4": FigureSpec(
        "fig4",
        "Stable gains at 20 m/s for a = -1.5..1.5, curvatures 0, 0.01, 0.02, 0.05 1/m",
        _chart_figure(4),
    ),
    "fig5": FigureSpec(
        "fig5",
        "Peak lateral acceleration of G versus a: (a) straight 5 m/s, (b) curve "
        "1/10 at 5 m/s, (c) straight 20 m/s, (d) curve 1/100 at 20 m/s",
        plot_fig5,
    ),
    "fig6": FigureSpec(
        "fig6",
        "Straight road, 5 m/s, feedback, lambda0 = -1: lateral position, lateral "
        "acceleration, front and rear steering",
        _response_maker(6),
    ),
    "fig7": FigureSpec(
        "fig7",
        "Curve 1/10, 5 m/s, feedforward + feedback, lambda0 = -1: errors, "
        "trajectory, steering, lateral acceleration",
        _response_maker(7),
    ),
    "fig8": FigureSpec(
        "fig8",
        "Straight road, 20 m/s, feedback, lambda0 = -1: lateral position, lateral "
        "acceleration, front and rear steering",
        _response_maker(8),
    ),
    "fig9": FigureSpec(
        "fig9",
        "Curve 1/100, 20 m/s, feedforward + feedback, lambda0 = -1: errors, "
        "trajectory, steering, lateral acceleration",
        _response_maker(9),
    ),
    "extra_linear_vs_nonlinear": FigureSpec(
        "extra_linear_vs_nonlinear",
        "Linear (control.initial_response of closed_loop) versus nonlinear "
        "response, curve 1/10 at 5 m/s, a = -1, from e0 = -5 m",
        _comparison_figure,
        paper=False,
    ),
    "extra_root_loci": FigureSpec(
        "extra_root_loci",
        "Root loci: gain scaling, paper gains versus curvature, ratio",
        lambda model="kinematic", quick=False: (
            plot_root_loci(model=model, quick=quick).figure
        ),
        paper=False,
    ),
    "extra_actuator": FigureSpec(
        "extra_actuator",
        "The paper's designs with a 0.24 s input delay and a 0.27 s steering lag "
        "(Autoware's defaults): delay margin versus lambda0, responses in Fig. 9's "
        "scenario for lambda0 = -1 and -2",
        lambda model="kinematic", quick=False: (
            plot_actuator(model=model, quick=quick).figure
        ),
        paper=False,
    ),
    "extra_turning_radius": FigureSpec(
        "extra_turning_radius",
        "Steady turning radius of R and G at the front steering limit versus a",
        _turning_figure,
        paper=False,
    ),
}


def make_figure(
    name: str, *, model: ModelName = "kinematic", quick: bool = False
) -> Figure:
    """Draw one figure of :data:`FIGURES` by name.

    Parameters
    ----------
    name : str
        Key of :data:`FIGURES`, e.g. ``"fig3"``.
    model : {"kinematic", "paper"}, optional
        Linearisation used for the designs and charts.
    quick : bool, optional
        Coarser grids and shorter sweeps (for tests).

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> from fws_control.paper import make_figure
    >>> fig = make_figure("fig2", quick=True)
    >>> len(fig.axes)
    3
    >>> plt.close(fig)
    """
    model = check_model(model)
    if name not in FIGURES:
        raise ValueError(f"name must be one of {sorted(FIGURES)}, got {name!r}")
    return _make(name, model, quick)


def _make(name: str, model: ModelName, quick: bool):
    """``FIGURES[name].make`` with the titles at a fixed height.

    Matplotlib lifts an axes title above top tick labels and a y offset
    text ("1e-3"); to find them it measures every y axis once more before
    each draw (a fifth of the drawing time of these figures). None of them
    has either, so the titles stay at the top of their axes
    (``axes.titley = 1``); tests/test_figures.py checks that no title
    overlaps anything.
    """
    import matplotlib.pyplot as plt

    with plt.rc_context({"axes.titley": 1.0}):
        return FIGURES[name].make(model=model, quick=quick)


def _fmt_poles(p) -> str:
    p = np.sort_complex(np.asarray(p, dtype=complex))
    out = []
    for z in p:
        # A double root splits by ~sqrt(eps) in floating point: show it as real.
        if abs(z.imag) < 1e-6:
            out.append(f"{z.real:.3f}")
        else:
            out.append(f"{z.real:.3f}{z.imag:+.3f}j")
    return ", ".join(out)


def gains_table(
    *,
    vehicle: Vehicle | None = None,
    pole: float = -1.0,
    ratios: Sequence[float] = TABLE_RATIOS,
    cases: Sequence[tuple[float, float]] | None = None,
) -> str:
    r"""Markdown table of the double-root gains in both linearisations.

    For every speed/curvature case and ratio ``a``: the gains ``k1, k2`` of
    the exact and of the paper's model (eq. 33) and the closed-loop poles
    that the *paper's* gains give in the exact linearisation (on a curved
    path they miss the requested double root, erratum 3). ``a = 1`` on a
    straight path has no design (erratum 5).

    Parameters
    ----------
    vehicle : Vehicle, optional
        Default: the paper's vehicle.
    pole : float, optional
        Double root :math:`\lambda_0`.
    ratios : sequence of float, optional
    cases : sequence of (speed, curvature), optional
        Default: the paper's scenarios, (5, 0), (5, 0.1), (20, 0), (20, 0.01).

    Returns
    -------
    str

    Examples
    --------
    >>> from fws_control.paper import gains_table
    >>> table = gains_table(ratios=[-1.0], cases=[(5.0, 0.0)])
    >>> print(table.splitlines()[-1])
    | 5 | 0 | -1 | 0.05400 | 0.61290 | 0.05400 | 0.61290 | -1.000, -1.000 |
    """
    vehicle = PAPER_VEHICLE if vehicle is None else vehicle
    if cases is None:
        cases = [(V, k) for V in PAPER_SPEEDS for k in (0.0, PAPER_CURVED[V])]
    head = (
        "| V [m/s] | kappa [1/m] | a | k1 exact | k2 exact | k1 paper | k2 paper "
        "| paper gains: exact poles |\n|---|---|---|---|---|---|---|---|"
    )
    rows = [head]
    for V, kap in cases:
        for a in ratios:
            cells = [f"{V:g}", f"{kap:g}", f"{a:g}"]
            try:
                exact = LateralPlant(vehicle, speed=V, curvature=kap)
                paper = LateralPlant(vehicle, speed=V, curvature=kap, model="paper")
                ge = double_root_gains(exact, ratio=a, pole=pole)
                gp = double_root_gains(paper, ratio=a, pole=pole)
            except UncontrollableError:
                cells += ["—"] * 4 + ["no design (uncontrollable)"]
                rows.append("| " + " | ".join(cells) + " |")
                continue
            poles = closed_loop(exact, gp).poles()
            cells += [
                f"{float(ge.k1):.5f}",
                f"{float(ge.k2):.5f}",
                f"{float(gp.k1):.5f}",
                f"{float(gp.k2):.5f}",
                _fmt_poles(poles),
            ]
            rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _turning_table(vehicle: Vehicle) -> str:
    ratios = (-1.5, -1.0, -0.5, 0.0, 0.5)
    rows = [
        "| front limit | " + " | ".join(f"a = {a:g}" for a in ratios) + " |",
        "|---" * (len(ratios) + 1) + "|",
    ]
    for deg in (20.0, 30.0, 40.0):
        r = turning_radius(
            vehicle, ratio=np.array(ratios), max_steer_front=math.radians(deg)
        )
        rows.append(
            f"| {deg:.0f}° | "
            + " | ".join(
                f"{rr:.2f} / {rg:.2f}" for rr, rg in zip(r.rear_axle, r.cg, strict=True)
            )
            + " |"
        )
    return "\n".join(rows)


@dataclass(frozen=True)
class ReproduceResult:
    """Files written by :func:`reproduce`.

    Attributes
    ----------
    out : pathlib.Path
        Output directory.
    figures : tuple of pathlib.Path
        PNG files, in the order of :data:`FIGURES`.
    summary : pathlib.Path
        ``summary.md``.
    """

    out: Path
    figures: tuple[Path, ...]
    summary: Path


class _QuietStream:
    """A text stream that forwards to ``stream`` until writing to it fails.

    The progress bar is a courtesy: a closed or broken standard error
    (``2>&-``, a pipe whose reader went away) must not stop the figures.
    """

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        if self._stream is not None:
            try:
                return self._stream.write(text)
            except (OSError, ValueError):  # ValueError: I/O on a closed file
                self._stream = None
        return len(text)

    def flush(self):
        if self._stream is not None:
            try:
                self._stream.flush()
            except (OSError, ValueError):
                self._stream = None


def _progress(iterable, enabled, total=None, desc=None):
    if not enabled or sys.stderr is None:
        return iterable
    from tqdm.auto import tqdm

    return tqdm(
        iterable, total=total, desc=desc, file=_QuietStream(sys.stderr), unit="fig"
    )


#: The file formats :func:`reproduce` writes.
FORMATS = ("png", "svg", "pdf")

# zlib level 3 instead of PIL's 6: the same pixels, encoded in about 30 %
# less time (0.42 s instead of 0.61 s for the twelve figures), files 8 %
# larger (2.4 instead of 2.2 MB); measured on this machine with PIL.
_PNG_OPTIONS = {"compress_level": 3}

# Glyphs drawn without FreeType hinting, as every vector backend (PDF, SVG)
# draws them: the text keeps its outlines' exact positions instead of
# snapping them to the pixel grid. Matplotlib's default ("default": the
# font's native hinter, else FreeType's auto-hinter) hints every glyph it
# draws. Measured on 2 cores with the twelve figures made afresh each
# round, best of 4 interleaved rounds: savefig 3.08 s with hinting, 2.69 s
# without (ratio 0.87). 2.3 % of the pixels of Fig. 3 change, all of them
# within the glyphs (stems and positions snap differently to the pixel
# grid). Applied to reproduce's own PNGs only: make_figure returns the
# figure and leaves its drawing to the caller's settings.
_DRAW_RC = {"text.hinting": "no_hinting"}

#: Largest resolution :func:`reproduce` accepts: at 600 dpi the widest figure
#: (17 x 5.2 in) is 10200 x 3120 pixels, about 130 MB of RGBA while drawing.
_MAX_DPI = 600


@contextlib.contextmanager
def _collector_per_figure():
    """Collect young garbage once per figure instead of on allocation counts.

    Matplotlib allocates container objects (artists, transforms, paths) fast
    enough to trigger about 950 young, 86 middle and 7 full collections of
    Python's cyclic garbage collector during :func:`reproduce`; the full
    ones traverse every object of the imported modules again. Here the
    automatic collector is paused; the caller drops its last reference to
    each closed figure and collects the youngest generation -- the objects
    allocated since the previous figure -- which frees that figure's
    reference cycles, so memory stays bounded by about one figure.
    Measured on 2 cores, three runs each: 5.15-5.43 s of CPU for the twelve
    figures after the imports, against 5.70-5.96 s with the automatic
    collector (collecting all generations after each figure saved nothing).
    The collector's enabled state is restored on exit, also on an error.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def reproduce(
    out: str | os.PathLike[str],
    *,
    model: ModelName = "kinematic",
    quick: bool = False,
    progress: bool = True,
    dpi: int = 110,
    names: Sequence[str] | None = None,
    format: str = "png",
) -> ReproduceResult:
    """Write every figure of :data:`FIGURES` (PNG, SVG or PDF) and ``summary.md``.

    Parameters
    ----------
    out : path-like
        Output directory; created if needed.
    model : {"kinematic", "paper"}, optional
        Linearisation used for the charts and designs.
    quick : bool, optional
        Coarser grids and fewer sweep points (for tests).
    progress : bool, optional
        Show a tqdm progress bar on stderr.
    dpi : int, optional
        Resolution of the PNG files, 1 to 600 (a higher one would need
        gigabytes of memory for the widest figure); of the raster parts
        only, in SVG and PDF.
    names : sequence of str, optional
        Subset of :data:`FIGURES` to write; default all.
    format : {"png", "svg", "pdf"}, optional
        File format of the figures: raster for screens, vector for papers.

    Returns
    -------
    ReproduceResult

    Raises
    ------
    fws_control.files.FolderInUseError
        Another process is writing into ``out`` (it holds the folder's lock,
        :func:`fws_control.files.lock_folder`); nothing is written.

    Notes
    -----
    Every file is written to a temporary file in ``out`` and renamed onto
    its final name (:func:`fws_control.files.atomic_write`), so an
    interrupted run (Ctrl-C, ``kill``, even ``kill -9``) leaves the files it
    finished, complete, and no partial one; ``summary.md`` is written last.
    Temporary files of a run killed with ``SIGKILL`` are removed by the next
    run into the same folder. The folder keeps the empty lock file
    ``.fws-control.lock``.

    Text is drawn without FreeType hinting (``text.hinting =
    "no_hinting"``, as in PDF or SVG output; it costs about an eighth less
    drawing time, see the performance notes), so a PNG differs from
    ``make_figure(name).savefig(...)`` under matplotlib's default only
    within its glyphs (their stems and positions snap differently to the
    pixel grid).

    Examples
    --------
    >>> import tempfile
    >>> import matplotlib; matplotlib.use("Agg")
    >>> from fws_control.paper import reproduce
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     res = reproduce(tmp, quick=True, progress=False, names=["fig2"], dpi=40)
    ...     [p.name for p in res.figures], res.summary.name, res.summary.is_file()
    (['fig2.png'], 'summary.md', True)
    """
    import matplotlib.pyplot as plt

    model = check_model(model)
    names = list(FIGURES) if names is None else list(names)
    for name in names:
        if name not in FIGURES:
            raise ValueError(f"names must be in {sorted(FIGURES)}, got {name!r}")
    if isinstance(dpi, bool) or not isinstance(dpi, (int, np.integer)):
        raise TypeError(f"dpi must be an int, got {type(dpi).__name__} {dpi!r}")
    if not 1 <= dpi <= _MAX_DPI:
        raise ValueError(f"dpi must be in 1..{_MAX_DPI}, got {dpi}")
    if not isinstance(format, str) or format not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}, got {format!r}")
    # the PNG encoder's options mean nothing to the vector backends
    options = {"pil_kwargs": _PNG_OPTIONS} if format == "png" else {}
    out = Path(out)
    with lock_folder(out):
        # Holding the lock, no live writer owns a temporary file here: any
        # left is from a run that was killed.
        remove_stale_temporaries(out)
        written = []
        with _collector_per_figure():
            for name in _progress(names, progress, total=len(names), desc="figures"):
                fig = _make(name, model, quick)
                path = out / f"{name}.{format}"
                try:
                    with atomic_write(path) as fh, plt.rc_context(cast(Any, _DRAW_RC)):
                        fig.savefig(fh, format=format, dpi=int(dpi), **options)
                finally:
                    plt.close(fig)
                # the closed figure's reference cycles, freed now (see
                # _collector_per_figure): no reference may keep it alive, or
                # it would be promoted past the youngest generation and stay
                del fig
                gc.collect(0)
                written.append(path)
        summary = out / "summary.md"
        text = _summary_text(model, written, quick)
        with atomic_write(summary, mode="w") as fh:
            fh.write(text)
    return ReproduceResult(out, tuple(written), summary)


def _summary_text(model: ModelName, written, quick: bool = False) -> str:
    lines = [
        "# fws-control reproduce: summary",
        "",
        f"Charts and designs use the **{model}** linearisation. Vehicle: "
        f"f = {PAPER_VEHICLE.wheelbase} m, d = {PAPER_VEHICLE.rear_to_cg} m.",
        "",
        "## Figures",
        "",
    ]
    for p in written:
        spec = FIGURES[p.stem]
        tag = "" if spec.paper else " (extra, not in the paper)"
        lines.append(f"- `{p.name}`{tag}: {spec.caption}")
    lines += [
        "",
        "## Double-root gains, lambda0 = -1",
        "",
        "Gains from the exact Jacobian and from the paper's eq. (33); the last "
        "column gives the closed-loop poles that the paper's gains produce in "
        "the exact linearisation.",
        "",
        gains_table(),
        "",
        "## Fig. 5: peak lateral acceleration of G [m/s²]",
        "",
        "Nonlinear simulation with the double-root gains of the "
        f"{model} model; 'singular' = the run reached |delta_f| = 90 deg and "
        "stopped; 'no design' = a = 1 on a straight road (uncontrollable)."
        + (" Quick mode: coarse ratio grid." if quick else ""),
        "",
        _fig5_table(model, quick),
        "## Delay margin of the paper's designs",
        "",
        f"Critical input delay (fws_control.critical_delay) of the double-root "
        f"designs, ideal steering and with a first-order steering lag; "
        f"'survives' = stable with a {REALISTIC_DELAY:g} s delay and the lag. "
        f"Values: {ACTUATOR_SOURCE}.",
        "",
        delay_margin_table(),
        "",
        "## Turning radius at the front steering limit",
        "",
        "Radius of the rear-axle centre R / centre of gravity G [m] with "
        "delta_r = a * delta_f_max (no rear limit).",
        "",
        _turning_table(PAPER_VEHICLE),
        "",
    ]
    return "\n".join(lines)
