"""Figures of the paper and the reproduce summary."""

import re

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control as fws
from fws_control.layout import grid_margins
from fws_control.paper import FIGURES, gains_table, make_figure, reproduce
from fws_control.paper.data import PAPER_VEHICLE as DATA_VEHICLE
from fws_control.paper.figures import plot_root_loci
from fws_control.paths import Arc, Straight

PNG = b"\x89PNG\r\n\x1a\n"
F, LAM = 2.7, -1.0


def _eq41(V, a):
    """Paper eq. (41): straight-path gains (valid in both models)."""
    k1 = F * LAM**2 / (V**2 * (1 - a))
    k2 = -LAM * F / (V * (1 - a)) * (2 + LAM * a * F / (V * (1 - a)))
    return k1, k2


def _rows(table):
    out = []
    for line in table.splitlines()[2:]:
        out.append([c.strip() for c in line.strip("|").split("|")])
    return out


def test_gains_table_straight_rows_match_eq41():
    table = gains_table(ratios=[-1.5, -0.5, 0.5, 1.0], cases=[(5.0, 0.0), (20.0, 0.0)])
    rows = _rows(table)
    assert len(rows) == 8
    for row in rows:
        V, _, a = (float(x) for x in row[:3])
        if a == 1.0:
            assert "uncontrollable" in row[-1]
            continue
        k1, k2 = _eq41(V, a)
        for col in (3, 5):  # exact and paper agree on a straight path
            assert float(row[col]) == pytest.approx(k1, abs=1e-5)
            assert float(row[col + 1]) == pytest.approx(k2, abs=1e-5)
        assert row[-1] == "-1.000, -1.000"


def test_gains_table_curved_row_poles():
    (row,) = _rows(gains_table(ratios=[0.0], cases=[(5.0, 0.1)]))
    # Paper eq. (44) for a = 0; then the exact characteristic polynomial
    # lambda^2 + (V c k2/f) lambda + V^2 (c k1/f + kappa^2), c = 1 + f^2 kappa^2.
    V, kap = 5.0, 0.1
    k1 = F * (LAM**2 / V**2 - kap**2)
    k2 = -2 * LAM * F / V
    assert float(row[5]) == pytest.approx(k1, abs=1e-5)
    assert float(row[6]) == pytest.approx(k2, abs=1e-5)
    c = 1 + F**2 * kap**2
    ref = np.sort(np.roots([1, V * c * k2 / F, V**2 * (c * k1 / F + kap**2)]).real)
    got = np.sort([float(x) for x in row[-1].split(",")])
    np.testing.assert_allclose(got, ref, atol=1e-3)


@pytest.fixture(scope="module")
def quick_figure():
    """``make_figure(name, quick=True)``, each figure made once for the module.

    Making the quick figures takes a few seconds of CPU in all, and most are
    checked by several tests below. Those tests only read a figure (the
    layout test sets the dpi and draws it, which changes no data, label,
    legend or limit), so they can share it.
    """
    made = {}

    def get(name):
        if name not in made:
            made[name] = make_figure(name, quick=True)
        return made[name]

    yield get
    for fig in made.values():
        plt.close(fig)


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_every_figure_draws(name, quick_figure):
    fig = quick_figure(name)
    assert len(fig.axes) >= 1
    for ax in fig.axes:
        if ax.has_data():
            assert ax.get_xlabel() and ax.get_ylabel()


def test_make_figure_bad_name():
    with pytest.raises(ValueError, match="name must be one of"):
        make_figure("fig1")
    with pytest.raises(ValueError, match="model"):
        make_figure("fig2", model="linear")


@pytest.mark.parametrize("caller_froze", [False, True])
@pytest.mark.parametrize("enabled", [True, False])
def test_reproduce_restores_the_garbage_collector(tmp_path, monkeypatch, enabled,
                                                 caller_froze):  # fmt: skip
    """reproduce pauses the collector while drawing and leaves it as it was
    (enabled or not, the caller's frozen objects still frozen), also when a
    figure fails; each closed figure is freed before the next is made."""
    import gc
    import weakref

    import fws_control.paper.figures as figures

    seen, made = [], []
    make = figures._make

    def spy(name, model, quick):
        # collector state, and how many earlier figures are still alive
        seen.append((gc.isenabled(), sum(r() is not None for r in made)))
        if name == "extra_turning_radius":
            raise RuntimeError("figure failed")
        fig = make(name, model, quick)
        made.append(weakref.ref(fig))
        return fig

    monkeypatch.setattr(figures, "_make", spy)
    # The cases vary the caller's collector. That each kind of figure (a
    # chart, a response, the root loci) is freed is checked once, with the
    # collector as a caller usually has it; the other cases make the cheapest
    # figure (a response) twice, which still checks the freeing between two
    # figures and between the two calls.
    if enabled and not caller_froze:
        names, before_failure = ["fig2", "fig6", "extra_root_loci"], ["fig2"]
    else:
        names, before_failure = ["fig8"], ["fig8"]
    was = gc.isenabled()
    try:
        if caller_froze:
            gc.freeze()
        frozen = gc.get_freeze_count()
        (gc.enable if enabled else gc.disable)()
        reproduce(tmp_path / "ok", quick=True, progress=False, dpi=40,
                  names=names)  # fmt: skip
        # (frozen objects can still die: the count may only fall, not to 0)
        assert gc.isenabled() == enabled
        assert (
            (0 < gc.get_freeze_count() <= frozen)
            if caller_froze
            else (gc.get_freeze_count() == 0)
        )
        with pytest.raises(RuntimeError, match="figure failed"):
            reproduce(tmp_path / "bad", quick=True, progress=False, dpi=40,
                      names=[*before_failure, "extra_turning_radius"])  # fmt: skip
        assert gc.isenabled() == enabled
        assert (
            (0 < gc.get_freeze_count() <= frozen)
            if caller_froze
            else (gc.get_freeze_count() == 0)
        )
    finally:
        gc.unfreeze()
        (gc.enable if was else gc.disable)()
    assert seen == [(False, 0)] * (len(names) + len(before_failure) + 1)


def test_reproduce_subset_writes_pngs_and_summary(tmp_path):
    res = reproduce(
        tmp_path / "out",
        quick=True,
        progress=False,
        dpi=40,
        names=["fig2", "extra_turning_radius"],
    )
    assert [p.name for p in res.figures] == ["fig2.png", "extra_turning_radius.png"]
    for p in res.figures:
        assert p.read_bytes()[:8] == PNG
    text = res.summary.read_text()
    assert "fig2.png" in text and "Double-root gains" in text
    # The a = -1 straight row of the summary gives eq. (41) at 5 m/s.
    k1, k2 = _eq41(5.0, -1.0)
    assert re.search(rf"\| 5 \| 0 \| -1 \| {k1:.5f} \| {k2:.5f} \|", text)
    with pytest.raises(ValueError, match="names"):
        reproduce(tmp_path / "x", names=["fig99"], progress=False)


def test_reproduce_draws_text_without_hinting(tmp_path):
    """reproduce's PNG is the figure drawn with ``text.hinting =
    "no_hinting"``: pixel for pixel the figure of make_figure saved under
    that setting, and not the one saved under matplotlib's default hinting
    (so the setting is what makes the difference). Any figure with text
    shows it: the cheapest to make and draw (0.3 s of CPU, fig2 1.4 s)."""
    import io

    from PIL import Image

    name = "extra_turning_radius"
    res = reproduce(tmp_path / "out", quick=True, progress=False, dpi=60, names=[name])
    with Image.open(res.figures[0]) as im:
        got = np.asarray(im)

    def drawn(hinting):
        fig = make_figure(name, quick=True)
        buf = io.BytesIO()
        try:
            with plt.rc_context({"text.hinting": hinting}):
                fig.savefig(buf, format="png", dpi=60)
        finally:
            plt.close(fig)
        with Image.open(buf) as im:
            return np.asarray(im)

    unhinted, hinted = drawn("no_hinting"), drawn("default")
    assert got.shape == unhinted.shape == hinted.shape
    assert np.array_equal(got, unhinted)
    # glyph edges only: a small share of the pixels, but some
    changed = np.any(got != hinted, axis=-1).mean()
    assert 0.0 < changed < 0.1


def test_fig5_points_match_direct_simulation(quick_figure):
    fig = quick_figure("fig5")
    # Each panel has a strip above it (runs without a peak); the data axes are
    # the log-scale ones, in panel order.
    ax_a = [ax for ax in fig.axes if ax.get_yscale() == "log"][0]
    (line,) = [ln for ln in ax_a.lines if ln.get_label() == r"$\lambda_0$ = -1"]
    a, peak = line.get_xdata(), line.get_ydata()
    veh = PAPER_VEHICLE
    for ratio in (-1.0, 0.0):
        g = fws.double_root_gains(veh, speed=5.0, ratio=ratio, pole=-1.0)
        res = fws.simulate(
            fws.LateralPlant(veh, speed=5.0),
            Straight(),
            g,
            initial_state=(0.0, 2.0, 0.0),
            duration=15.0,
            feedforward=False,
            dt=0.02,
        )
        j = int(np.argmin(np.abs(a - ratio)))
        assert peak[j] == pytest.approx(np.max(np.abs(res.lateral_accel)), rel=1e-6)
    # a = 1 on the straight road: no point is drawn (no design).
    assert np.isnan(peak[np.argmin(np.abs(a - 1.0))])
    assert ax_a.get_yscale() == "log"


@pytest.mark.parametrize("n, curvature, y0", [(6, 0.0, 2.0), (7, 0.1, -5.0)])
def test_response_figures_match_direct_simulation(n, curvature, y0, quick_figure):
    fig = quick_figure(f"fig{n}")
    ax = fig.axes[0]
    (line,) = [ln for ln in ax.lines if ln.get_label() == "a = -0.5"]
    veh = PAPER_VEHICLE
    g = fws.double_root_gains(
        veh, speed=5.0, curvature=curvature, ratio=-0.5, pole=-1.0
    )
    path = Straight() if curvature == 0.0 else Arc(curvature=curvature)
    res = fws.simulate(
        fws.LateralPlant(veh, speed=5.0),
        path,
        g,
        initial_state=(0.0, y0, 0.0),
        duration=15.0,
        feedforward=curvature != 0.0,
        t_eval=line.get_xdata(),
    )
    ref = res.y if n == 6 else res.e  # panel (a): lateral position / error
    np.testing.assert_allclose(line.get_ydata(), ref, atol=1e-6)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    # The legend lists drawn curves only; a = 1 stops at t = 0 and is named in
    # a note instead (marked, not hidden).
    assert not any(s.startswith("a = 1") for s in labels)
    notes = [t.get_text() for t in ax.texts]
    assert any(s.startswith("a = 1:") and "not drawn" in s for s in notes)


def test_fig5_marks_stopped_runs_outside_the_data_and_explains_1g(quick_figure):
    fig = quick_figure("fig5")
    logs = [ax for ax in fig.axes if ax.get_yscale() == "log"]
    strips = [ax for ax in fig.axes if ax.get_yscale() != "log"]
    assert len(logs) == len(strips) == 4
    # Panel (b) (5 m/s curve) has stopped runs: x markers in its strip only.
    assert any(ln.get_marker() == "x" and len(ln.get_xdata()) for ln in strips[1].lines)
    assert not any(ln.get_marker() == "x" for ln in logs[1].lines)
    assert "1 g" in " ".join(t.get_text() for t in logs[1].texts)
    assert "full steering" in fig._supxlabel.get_text()


def test_fig7_lateral_accel_not_squashed_and_steering_panels_share_limits(
    quick_figure,
):
    fig = quick_figure("fig7")
    by_title = {ax.get_title(): ax for ax in fig.axes}
    acc = next(ax for t, ax in by_title.items() if t.startswith("(f)"))
    lo, hi = acc.get_ylim()
    assert lo > -10.0  # the t = 0 spike of a = 0.5 reaches about -42 m/s^2
    assert any("clipped" in t.get_text() for t in acc.texts)
    df = next(ax for t, ax in by_title.items() if t.startswith("(d)"))
    dr = next(ax for t, ax in by_title.items() if t.startswith("(e)"))
    assert df.get_ylim() == dr.get_ylim()


def test_paper_vehicle_is_the_papers():
    """paper.data holds the paper's vehicle: f = 2.7 m, d = 1.35 m, no limits."""
    assert DATA_VEHICLE == PAPER_VEHICLE
    assert (DATA_VEHICLE.wheelbase, DATA_VEHICLE.rear_to_cg) == (2.7, 1.35)
    assert not DATA_VEHICLE.has_limits


def test_root_loci_figure_panels_match_the_loci():
    """Panel (a): the g = 1 square of each design is its double root -1."""
    cplt = plot_root_loci(quick=True)
    assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == (1, 3)
    squares = [
        ln
        for ln in cplt.axes[0, 0].lines
        if ln.get_marker() == "s" and len(ln.get_xdata())
    ]
    assert len(squares) == 3  # one per operating point
    for ln in squares:
        np.testing.assert_allclose(ln.get_xdata(), -1.0, atol=1e-6)
        np.testing.assert_allclose(ln.get_ydata(), 0.0, atol=1e-6)
    plt.close(cplt.figure)


# --------------------------------------------------------------------------
# Fixed layouts (fws_control.layout): nothing overlaps, nothing is cut off.
# The reference is computed from the drawn figure: the window extents that
# matplotlib's renderer gives every tick label, axis label, title, legend
# and figure title.


def _in_view(axis, lim):
    """The visible tick labels of `axis` whose ticks lie within `lim`."""
    lo, hi = sorted(lim)
    span = hi - lo
    out = []
    for ticks, locs in (
        (axis.get_major_ticks(), axis.get_majorticklocs()),
        (axis.get_minor_ticks(), axis.get_minorticklocs()),
    ):
        for tick, loc in zip(ticks, locs, strict=False):
            if lo - 1e-9 * span <= loc <= hi + 1e-9 * span:
                out += [tick.label1, tick.label2]
    return out


def _outer_texts(ax, renderer):
    """(kind, bbox) of the labelled items of `ax` drawn outside its frame."""
    items = []
    if ax.axison:
        for lab in _in_view(ax.xaxis, ax.get_xlim()):
            items.append(("xtick", lab))
        for lab in _in_view(ax.yaxis, ax.get_ylim()):
            items.append(("ytick", lab))
        items += [("xlabel", ax.xaxis.label), ("ylabel", ax.yaxis.label)]
        items += [
            ("offset", ax.xaxis.get_offset_text()),
            ("offset", ax.yaxis.get_offset_text()),
        ]
    items.append(("title", ax.title))
    out = [
        (kind, t.get_window_extent(renderer))
        for kind, t in items
        if t.get_visible() and t.get_text().strip()
    ]
    frame = ax.get_window_extent(renderer)
    leg = ax.get_legend()
    if leg is not None:
        box = leg.get_window_extent(renderer)
        # A legend inside its own axes is part of the panel.
        if not (
            frame.contains(box.x0 + 1, box.y0 + 1)
            and frame.contains(box.x1 - 1, box.y1 - 1)
        ):
            out.append(("legend", box))
    return out


def _overlap(a, b, tol=0.5):
    """True if the boxes share more than `tol` pixels in both directions."""
    return (
        min(a.x1, b.x1) - max(a.x0, b.x0) > tol
        and min(a.y1, b.y1) - max(a.y0, b.y0) > tol
    )


def _layout_problems(fig) -> list[str]:
    """What overlaps or leaves the canvas in `fig`, drawn as it is now."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    canvas = fig.bbox
    axes = [ax for ax in fig.axes if ax.get_visible()]
    texts = {ax: _outer_texts(ax, renderer) for ax in axes}
    frames = {ax: ax.get_window_extent(renderer) for ax in axes}
    figure_texts = [
        t.get_window_extent(renderer)
        for t in (fig._suptitle, fig._supxlabel)
        if t is not None and t.get_text()
    ]
    problems = []
    for ax in axes:
        for kind, box in texts[ax]:
            inside = (
                box.x0 >= canvas.x0 - 0.5
                and box.y0 >= canvas.y0 - 0.5
                and box.x1 <= canvas.x1 + 0.5
                and box.y1 <= canvas.y1 + 0.5
            )
            if not inside:
                problems.append(f"{kind} of {ax.get_title()!r} leaves the canvas")
            for other in axes:
                if other is ax:
                    continue
                if _overlap(box, frames[other]):
                    problems.append(
                        f"{kind} of {ax.get_title()!r} overlaps the panel "
                        f"{other.get_title()!r}"
                    )
                for kind2, box2 in texts[other]:
                    if _overlap(box, box2):
                        problems.append(
                            f"{kind} of {ax.get_title()!r} overlaps {kind2} of "
                            f"{other.get_title()!r}"
                        )
            for ftext in figure_texts:
                if _overlap(box, ftext):
                    problems.append(
                        f"{kind} of {ax.get_title()!r} overlaps a figure title"
                    )
        # Within a panel: the axis labels and the title clear the tick labels.
        own = texts[ax]
        for kind, box in own:
            for kind2, box2 in own:
                pair = {kind, kind2}
                if pair in (
                    {"xlabel", "xtick"},
                    {"ylabel", "ytick"},
                    {"title", "xtick"},
                    {"title", "ytick"},
                    {"title", "ylabel"},
                ) and _overlap(box, box2):
                    problems.append(f"{kind} overlaps {kind2} in {ax.get_title()!r}")
    for ftext in figure_texts:
        for ax in axes:
            if _overlap(ftext, frames[ax]):
                problems.append(f"a figure title overlaps the panel {ax.get_title()!r}")
        if not (
            canvas.x0 - 0.5 <= ftext.x0
            and ftext.x1 <= canvas.x1 + 0.5
            and canvas.y0 - 0.5 <= ftext.y0
            and ftext.y1 <= canvas.y1 + 0.5
        ):
            problems.append("a figure title leaves the canvas")
    return problems


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_layout_nothing_overlaps_or_leaves_the_canvas(name, quick_figure):
    fig = quick_figure(name)
    fig.set_dpi(110)  # reproduce's default resolution
    # reproduce draws without hinting (figures._DRAW_RC), make_figure's
    # callers with matplotlib's default: the text sizes differ slightly
    problems = []
    for hinting in ("default", "no_hinting"):
        with plt.rc_context({"text.hinting": hinting}):
            problems += [f"{hinting}: {p}" for p in _layout_problems(fig)]
    axes = [ax for ax in fig.axes if ax.get_visible()]
    # Labelled axes and legends are there.
    for ax in axes:
        if ax.has_data():
            assert ax.get_xlabel().strip() and ax.get_ylabel().strip(), ax.get_title()
    legends = [ax.get_legend() for ax in axes if ax.get_legend() is not None]
    assert legends and all(t.get_text() for leg in legends for t in leg.get_texts())
    assert not problems, "\n".join(sorted(set(problems)))


def test_layout_check_detects_an_overlap():
    """The check above fails for a layout that is too tight (it can fail)."""
    fig, axs = plt.subplots(
        1,
        2,
        figsize=(6, 3),
        gridspec_kw=grid_margins((6, 3), ncols=2, wgap=0.05),
    )
    for ax in axs:
        ax.plot([0, 1e4], [0, 1e4])
        ax.set_ylabel("a long y label [m/s²]")
    fig.set_dpi(110)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    right_labels = _outer_texts(axs[1], renderer)
    left_frame = axs[0].get_window_extent(renderer)
    assert any(_overlap(box, left_frame) for _, box in right_labels)
    # and the whole check reports it, with either hinting
    for hinting in ("default", "no_hinting"):
        with plt.rc_context({"text.hinting": hinting}):
            assert any("overlaps the panel" in p for p in _layout_problems(fig))
    plt.close(fig)


@pytest.fixture(scope="module")
def actuator_plot():
    """``plot_actuator(quick=True)``, drawn once for both of its panels."""
    from fws_control.paper.actuator import plot_actuator

    cplt = plot_actuator(quick=True)
    yield cplt
    plt.close(cplt.figure)


@pytest.mark.parametrize("panel, pole", [(1, -1.0), (2, -2.0)])
def test_actuator_responses_match_simulate_at_default_tolerance(
    panel, pole, actuator_plot
):
    """Panels (b), (c) (one batch, rtol 1e-8) agree with single runs at 1e-10."""
    ax = actuator_plot.axes[0, panel]
    veh = PAPER_VEHICLE
    g = fws.double_root_gains(veh, speed=20.0, curvature=0.01, ratio=0.5, pole=pole)
    styles = {ln.get_linestyle(): ln for ln in ax.lines}
    for style, lag, act in (
        ("--", None, {}),
        ("-", 0.27, {"delay": 0.24}),
    ):
        line = styles[style]
        ref = fws.simulate(
            fws.LateralPlant(veh, speed=20.0, steering_lag=lag),
            Arc(curvature=0.01),
            g,
            initial_state=(0.0, -10.0, 0.0),
            duration=10.0,
            feedforward=True,
            dt=0.02,
            **act,
        )
        y = np.asarray(line.get_ydata(), dtype=float)
        e = np.asarray(ref.e, dtype=float)
        n = min(y.size, e.size)  # a run that stops returns fewer samples alone
        good = np.isfinite(y[:n]) & np.isfinite(e[:n])
        assert good.sum() > 100
        np.testing.assert_allclose(y[:n][good], e[:n][good], atol=1e-6)
        # and the curve ends where the single run ends
        assert np.isfinite(y).sum() == np.isfinite(e).sum()
        if ref.status != "ok":  # pole -2 with delay and lag: the legend says so
            assert ref.status in line.get_label()


@settings(derandomize=True, max_examples=25, deadline=None)
@given(
    w=st.floats(4.0, 20.0),
    h=st.floats(3.0, 12.0),
    nrows=st.integers(1, 3),
    ncols=st.integers(1, 4),
    margins=st.lists(st.floats(0.0, 0.9), min_size=6, max_size=6),
)
def test_grid_margins_gives_the_requested_inches(w, h, nrows, ncols, margins):
    """matplotlib's GridSpec, fed the fractions, puts the axes where asked."""
    from matplotlib.gridspec import GridSpec

    left, right, bottom, top, wgap, hgap = margins
    kw = grid_margins(
        (w, h), nrows=nrows, ncols=ncols, left=left, right=right,
        bottom=bottom, top=top, wgap=wgap, hgap=hgap,
    )  # fmt: skip
    fig = plt.figure(figsize=(w, h))
    b, t, lft, rgt = GridSpec(nrows, ncols, figure=fig, **kw).get_grid_positions(fig)
    plt.close(fig)
    np.testing.assert_allclose(lft[0] * w, left, atol=1e-9)
    np.testing.assert_allclose((1.0 - rgt[-1]) * w, right, atol=1e-9)
    np.testing.assert_allclose(b[-1] * h, bottom, atol=1e-9)
    np.testing.assert_allclose((1.0 - t[0]) * h, top, atol=1e-9)
    np.testing.assert_allclose((lft[1:] - rgt[:-1]) * w, wgap, atol=1e-9)
    np.testing.assert_allclose((b[:-1] - t[1:]) * h, hgap, atol=1e-9)
    widths = (rgt - lft) * w
    np.testing.assert_allclose(
        widths, (w - left - right - (ncols - 1) * wgap) / ncols, rtol=1e-9
    )


def test_grid_margins_rejects_what_leaves_no_room():
    with pytest.raises(ValueError, match="no room for the axes"):
        grid_margins((4.0, 3.0), ncols=2, left=2.0, right=1.0, wgap=1.0)
    with pytest.raises(ValueError, match=r"figsize\[0\] must be > 0"):
        grid_margins((0.0, 3.0))
    with pytest.raises(ValueError, match="figsize must be"):
        grid_margins(5.0)
    with pytest.raises(ValueError, match="ncols must be an int >= 1, got 0"):
        grid_margins((4.0, 3.0), ncols=0)
    with pytest.raises(ValueError, match="left must be >= 0 in, got -0.1"):
        grid_margins((4.0, 3.0), left=-0.1)
    with pytest.raises(ValueError, match="wgap"):
        grid_margins((4.0, 3.0), wgap=float("nan"))
