"""Readability of the reproduced figures: axis ranges, hatches, notes.

References: the data the figure itself draws (the finished runs' curves
against the stopped run's), and the notes each chart writes
(``StabilityChart.notes``), which must all appear, once, outside the
panels.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from fws_control.paper import charts as charts_module  # noqa: E402
from fws_control.paper import make_figure, paper_figure_panels  # noqa: E402


def test_fig9_acceleration_axis_follows_the_finished_runs():
    # (the full run: the quick one samples too coarsely to catch the spike)
    fig = make_figure("fig9")
    try:
        ax = fig.axes[5]
        assert "lateral acceleration" in ax.get_title()
        curves = [ln for ln in ax.get_lines() if ln.get_xdata().size > 1]
        peaks = [float(np.nanmax(np.abs(ln.get_ydata()))) for ln in curves]
        # the a = 1 run stops at singular steering with a spike that dwarfs
        # the finished runs (hundreds of m/s^2 against about ten)
        stopped, finished = max(peaks), sorted(peaks)[-2]
        assert stopped > 10 * finished
        low, high = ax.get_ylim()
        assert finished <= high < 2 * finished
        texts = [t.get_text() for t in ax.texts]
        assert "stopped runs clipped" in texts
    finally:
        plt.close(fig)


def test_fig3_hatches_apart_and_notes_beside_the_legend():
    fig = make_figure("fig3", quick=True)
    try:
        panels = fig.axes[:7]
        for ax in panels:
            hatches = [c.get_hatch() for c in ax.collections if c.get_hatch()]
            hatches = [h for h in hatches if h != "xx"]  # the undecided points'
            # one hatch per overlaid region with stable gains, none twice
            assert hatches and len(hatches) == len(set(hatches)), hatches
            assert not [t for t in ax.texts if "gains off chart" in t.get_text()]
        notes = []
        for panel in paper_figure_panels(3, npoints=201):
            letter = panel.title.split(" ", 1)[0]
            for ch, lab in zip(panel.charts, panel.labels, strict=True):
                notes += [f"{letter} {n}" for n in ch.notes(label=lab)]
        spare = fig.axes[7].texts
        assert len(spare) == 1
        lines = spare[0].get_text().split("\n")
        assert lines[0] == "notes:" and lines[1:] == notes
        assert spare[0].get_fontsize() >= 9
    finally:
        plt.close(fig)


def test_fig4_notes_break_where_matplotlib_wraps_them():
    # Reference: matplotlib's own Text(wrap=True) on the unbroken notes, at
    # the same place, drawn at two resolutions.
    fig = make_figure("fig4", quick=True)
    try:
        (text,) = fig.axes[7].texts
        notes = []
        for panel in paper_figure_panels(4, npoints=201):
            letter = panel.title.split(" ", 1)[0]
            for ch, lab in zip(panel.charts, panel.labels, strict=True):
                notes += [f"{letter} {n}" for n in ch.notes(label=lab)]
        # the undecided-point notes gathered into one (checked below)
        notes = ["notes:", *charts_module._gather_undecided(notes)]
        got = text.get_text().split("\n")
        # every note, in order, and some too long for one line
        assert " ".join(got) == " ".join(notes) and len(got) > len(notes)
        ref = fig.axes[7].text(
            *text.get_position(), "\n".join(notes), transform=text.get_transform(),
            ha="left", va="bottom", fontsize=text.get_fontsize(), wrap=True,
        )  # fmt: skip
        for dpi in (110, 300):
            fig.set_dpi(dpi)
            fig.canvas.draw()
            # the lines Text.draw printed (private: matplotlib keeps no copy)
            assert ref._get_wrapped_text().split("\n") == got
    finally:
        plt.close(fig)


def test_undecided_notes_are_gathered_with_their_counts():
    notes = [
        "(a) κ = 0 1/m: 2 undecided points: a pole within rounding of the axis",
        "(f) κ = 0 1/m: no stable gains on this grid",
        "(g) κ = 0.01 1/m: 1 undecided points: a pole within rounding of the axis",
    ]
    assert charts_module._gather_undecided(notes) == [
        "(f) κ = 0 1/m: no stable gains on this grid",
        "undecided points (a pole within rounding of the axis): "
        "(a) κ = 0 1/m: 2, (g) κ = 0.01 1/m: 1",
    ]
    # a single one, or different reasons, are left as they are
    assert charts_module._gather_undecided(notes[:2]) == notes[:2]
    other = [*notes[:1], notes[2].replace("rounding", "the bound")]
    assert charts_module._gather_undecided(other) == other
