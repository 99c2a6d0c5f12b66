"""Stability charts: the closed-form mask against eigenvalues, plots, Figs. 2-4."""

import math

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest

import fws_control as fws
from fws_control.paper import paper_figure_panels, plot_paper_figure
from fws_control.paper.data import PAPER_CURVATURES


def _eig_mask(veh, speed, curvature, ratio, k1, k2, model):
    """Reference: max real part of eig(A + B K) at every grid point.

    A and B come from ct.linearize of the nonlinear path-frame model for the
    exact model (independent of linear.py) and from eq. (33) for the paper's.
    """
    if model == "kinematic":
        sys = fws.path_frame_model(veh, speed=speed, curvature=curvature)
        u0 = [math.atan(curvature * veh.wheelbase), 0.0]
        lin = ct.linearize(sys, [0.0, 0.0, 0.0], u0)
        A, B = lin.A[1:, 1:], lin.B[1:, :]
    else:
        f = veh.wheelbase
        A = np.array([[0.0, speed], [-speed * curvature**2, 0.0]])
        B = np.array([[0.0, speed], [speed / f, -speed / f]])
    K1, K2 = np.meshgrid(k1, k2)
    b = B @ np.array([1.0, ratio])
    # A - b [k1 k2] for every grid point, stacked: shape (n2, n1, 2, 2).
    M = A - b[:, None] * np.stack([K1, K2], axis=-1)[..., None, :]
    return np.linalg.eigvals(M).real.max(axis=-1)


CASES = [
    (5.0, 0.0, -1.0, "kinematic"),
    (5.0, 0.1, -1.0, "kinematic"),
    (5.0, 0.1, -1.0, "paper"),
    (20.0, 0.01, 0.5, "kinematic"),
    (5.0, 0.2, 1.0, "kinematic"),
    (5.0, 0.1, 1.0, "paper"),
    (5.0, 0.0, 1.5, "kinematic"),
    (20.0, 0.05, 1.5, "paper"),
    (-5.0, 0.1, -0.5, "kinematic"),  # reversing: condition (35) flips
    (-3.0, 0.0, 0.0, "paper"),
]


@pytest.mark.parametrize("speed, curvature, ratio, model", CASES)
def test_mask_matches_eigenvalues(veh, speed, curvature, ratio, model):
    k1 = np.linspace(-2.0, 2.0, 83)
    k2 = np.linspace(-3.0, 2.5, 71)  # non-square on purpose: checks orientation
    plant = fws.LateralPlant(veh, speed=speed, curvature=curvature, model=model)
    ch = fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2)
    assert ch.stable.shape == (71, 83)
    assert ch.plant is plant and ch.order == 2
    assert (ch.speed, ch.curvature, ch.model) == (speed, curvature, model)
    re = _eig_mask(veh, speed, curvature, ratio, k1, k2, model)
    clear = np.abs(re) > 1e-7  # points on a boundary are decided by rounding
    assert clear.mean() > 0.9
    np.testing.assert_array_equal(ch.stable[clear], (re < 0)[clear])


def test_hand_derived_front_steering(veh):
    # a = 0, kappa = 0: p1 = V k2 / f, p0 = V^2 k1 / f.
    k = np.linspace(-1, 1, 41)
    ch = fws.stability_chart(veh, speed=5.0, curvature=0.0, ratio=0.0, k1=k, k2=k)
    K1, K2 = np.meshgrid(k, k)
    np.testing.assert_array_equal(ch.stable, (K1 > 0) & (K2 > 0))
    rev = fws.stability_chart(veh, speed=-5.0, ratio=0.0, k1=k, k2=k)
    np.testing.assert_array_equal(rev.stable, (K1 > 0) & (K2 < 0))


def test_default_grid_and_large_grid(veh):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    ch = fws.stability_chart(plant, ratio=-1.0)
    assert ch.k1[0] == -1.0 and ch.k1[-1] == 1.0 and ch.stable.shape == (401, 401)
    np.testing.assert_array_equal(ch.k1, np.linspace(-1, 1, 401))
    np.testing.assert_array_equal(ch.k2, np.linspace(-1, 1, 401))
    k = np.linspace(-1, 1, 1000)
    big = fws.stability_chart(plant, ratio=-1.0, k1=k, k2=k)
    assert big.stable.shape == (1000, 1000)
    # Same verdict as the eigenvalues of A + BK on a strided subsample.
    lin = fws.linearize(plant)
    b = lin.B @ np.array([[1.0], [-1.0]])
    for i in range(0, 1000, 37):
        for j in range(0, 1000, 41):
            poles = np.linalg.eigvals(lin.A - b @ np.array([[k[j], k[i]]]))
            if abs(poles.real.max()) > 1e-9:
                assert big.stable[i, j] == (poles.real.max() < 0)


@pytest.mark.parametrize(
    "speed, curvature, ratio, model",
    [
        (5.0, 0.1, -1.0, "kinematic"),
        (20.0, 0.01, 0.5, "paper"),
        (5.0, 0.1, 1.0, "paper"),
    ],
)
def test_boundaries_are_zero_sets(veh, speed, curvature, ratio, model):
    plant = fws.LateralPlant(veh, speed=speed, curvature=curvature, model=model)
    ch = fws.stability_chart(plant, ratio=ratio)
    assert ch.boundaries.lines == tuple(ch.boundaries)
    for b, which in zip(ch.boundaries, (1, 2), strict=True):
        seg = b.segment((-1, 1), (-1, 1))
        assert seg is not None
        for t in np.linspace(0, 1, 5):
            k1, k2 = seg[0] + t * (seg[1] - seg[0])
            g = fws.SteeringGains(k1, k2, ratio)
            poly = fws.characteristic_polynomial_coefficients(plant, g)
            assert abs(poly[which]) < 1e-9 * max(1.0, speed**2)


def test_design_point_gives_double_root(veh):
    ch = fws.stability_chart(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    g = ch.design
    assert ch.design_error is None and ch.design_on_chart
    poles = np.linalg.eigvals(fws.closed_loop(ch.plant, g).A)
    # A double root is sensitive: eigenvalues move by sqrt(rounding).
    np.testing.assert_allclose(poles, [-1.0, -1.0], atol=1e-6)
    # And the design lies inside the stable region of its own chart.
    i = np.searchsorted(ch.k2, float(g.k2))
    j = np.searchsorted(ch.k1, float(g.k1))
    assert ch.stable[i, j]


def test_uncontrollable_design_is_recorded_not_marked(veh):
    ch = fws.stability_chart(veh, speed=20.0, ratio=1.0, pole=-1.0)
    assert ch.design is None
    assert "uncontrollable" in ch.design_error
    # p0 is identically zero: a pole at the origin, never asymptotically stable.
    assert ch.empty
    assert ch.boundaries.lines[1].degenerate
    cplt = ch.plot()
    ax = cplt.axes[0, 0]
    assert not any(line.get_marker() == "o" for line in ax.lines)
    texts = " ".join(t.get_text() for t in ax.texts)
    assert "uncontrollable" in texts and "no stable gains" in texts
    plt.close(cplt.figure)


def test_plot_labels_legend_and_marker(veh):
    ch = fws.stability_chart(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    cplt = ch.plot()
    assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == (1, 1)
    ax = cplt.axes[0, 0]
    assert cplt.figure is ax.figure
    assert ax.get_xlabel() == "$k_1$ [rad/m]" and ax.get_ylabel() == "$k_2$ [-]"
    assert cplt.legend is ax.get_legend()
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("eq. 35" in s for s in labels) and any("eq. 36" in s for s in labels)
    assert "a = -1" in ax.get_title() and "V = 5" in ax.get_title()
    (marker,) = [line for line in ax.lines if line.get_marker() == "o"]
    np.testing.assert_allclose(marker.get_xydata()[0], [ch.design.k1, ch.design.k2])
    # every drawn artist is listed in .lines
    assert marker in cplt.lines[0, 0]
    plt.close(cplt.figure)
    # ax= draws into given axes and returns them
    fig, given = plt.subplots()
    assert ch.plot(ax=given).axes[0, 0] is given
    assert [ln.get_marker() for ln in given.lines].count("o") == 1
    plt.close(fig)


def test_vertical_and_horizontal_boundaries_are_drawn(veh):
    # Paper model, a = 1, curved path: k1 = 0 (eq. 38) and k2 = 1 (erratum 4).
    ch = fws.stability_chart(veh, speed=5.0, curvature=0.1, ratio=1.0, model="paper")
    b1, b0 = ch.boundaries
    assert b1.vertical
    np.testing.assert_allclose(b0.k2_at([-0.5, 0.5]), [1.0, 1.0])
    cplt = ch.plot()
    ax = cplt.axes[0, 0]
    xs = [line.get_xdata() for line in ax.lines if line.get_linestyle() == "-"]
    assert any(np.allclose(x, 0.0) for x in xs)
    plt.close(cplt.figure)
    K1, K2 = np.meshgrid(ch.k1, ch.k2)
    np.testing.assert_array_equal(ch.stable, (K1 > 0) & (K2 < 1.0))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"speed": 0.0}, "speed"),
        ({"k1": np.zeros((3, 3))}, "k1"),
        ({"k2": [0.0, 1.0, 0.5]}, "k2"),
        ({"model": "linear"}, "model"),
        ({"pole": 1.0}, "pole"),
        ({"curvature": np.nan}, "curvature"),
    ],
)
def test_bad_input(veh, kwargs, match):
    args = {"curvature": 0.1, "ratio": -1.0, "speed": 5.0} | kwargs
    with pytest.raises(ValueError, match=match):
        fws.stability_chart(veh, **args)


def test_chart_needs_one_operating_point(veh):
    plant = fws.LateralPlant(veh, speed=[5.0, 20.0])
    with pytest.raises(ValueError, match=r"one operating point.*\(2,\)"):
        fws.stability_chart(plant, ratio=-1.0)
    with pytest.raises(ValueError, match="ratio"):
        fws.stability_chart(veh, speed=5.0, ratio=[-1.0, 0.0])


def test_paper_figure_panels_contents():
    p2 = paper_figure_panels(2, npoints=21)
    assert [[c.ratio for c in p.charts] for p in p2] == [
        [-1.5, -1.0, -0.5, 0.0],
        [-1.5, -1.0, -0.5],
        [0.0, 0.5, 1.0, 1.5],
    ]
    assert [p.charts[0].speed for p in p2] == [5.0, 20.0, 20.0]
    assert all(c.curvature == 0.0 and c.pole == -1.0 for p in p2 for c in p.charts)
    for n, V in ((3, 5.0), (4, 20.0)):
        panels = paper_figure_panels(n, model="paper", npoints=21)
        assert [p.charts[0].ratio for p in panels] == [-1.5, -1, -0.5, 0, 0.5, 1, 1.5]
        for p in panels:
            assert tuple(c.curvature for c in p.charts) == PAPER_CURVATURES[n]
            assert all(c.speed == V and c.model == "paper" for c in p.charts)
    with pytest.raises(ValueError, match="n must be 2, 3 or 4"):
        paper_figure_panels(5)


def test_paper_panels_show_the_designs_in_range():
    # The paper: the lambda0 = -1 gains lie in [-1, 1] for a <= 0 at 5 m/s
    # except a = 0 (k2 = 2*f/V = 1.08), which the grid must still show.
    (pa, _, _) = paper_figure_panels(2, npoints=21)
    a0 = pa.charts[-1]
    assert a0.design_on_chart
    np.testing.assert_allclose(float(a0.design.k2), 2 * 2.7 / 5.0)


@pytest.mark.parametrize(
    "n, naxes, shape", [(2, 3, (1, 3)), (3, 8, (2, 4)), (4, 8, (2, 4))]
)
def test_plot_paper_figure(n, naxes, shape, tmp_path):
    cplt = plot_paper_figure(n, npoints=41)
    assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == shape
    fig = cplt.figure
    assert len(fig.axes) == naxes
    assert list(cplt.axes.flat) == fig.axes
    assert f"Fig. {n}" in fig.get_suptitle()
    for ax in fig.axes[: 7 if n > 2 else 3]:
        assert ax.get_xlabel() == "$k_1$ [rad/m]"
    out = tmp_path / f"fig{n}.png"
    fig.savefig(out, dpi=40)
    plt.close(fig)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --- marking gains of one's own; pole= on a 4-state plant -------------------

_DYN = dict(mass=1500.0, yaw_inertia=2600.0, cornering_front=8e4, cornering_rear=9.5e4)


def test_mark_is_drawn_at_the_given_gains(veh):
    axis = np.linspace(-1.0, 1.0, 41)
    ch = fws.stability_chart(veh, speed=5.0, ratio=-1.0, k1=axis, k2=axis)
    cplt = ch.plot(mark=(0.25, -0.4))
    star = cplt.lines[0, 0][-1]
    assert star.get_marker() == "*" and star.axes is cplt.axes[0, 0]
    np.testing.assert_array_equal(star.get_xydata(), [[0.25, -0.4]])
    legend = [t.get_text() for t in cplt.axes[0, 0].get_legend().get_texts()]
    assert legend[-1] == star.get_label() == "marked: (0.250, -0.400)"
    plt.close(cplt.figure)
    # several points, from SteeringGains with the chart's ratio, via draw()
    fig, ax = plt.subplots()
    g = fws.SteeringGains(k1=[0.1, 0.2, 0.3], k2=0.5, ratio=-1.0)
    handles = ch.draw(ax, mark=g)
    assert handles[-1].get_label() == "marked gains (3)"
    np.testing.assert_array_equal(
        handles[-1].get_xydata(), [[0.1, 0.5], [0.2, 0.5], [0.3, 0.5]]
    )
    plt.close(fig)


@pytest.mark.parametrize(
    "mark, match",
    [
        ("k1k2", "a \\(k1, k2\\) pair"),
        (0.3, "a \\(k1, k2\\) pair"),
        ((0.1, 0.2, 0.3), "a \\(k1, k2\\) pair"),
        ((math.nan, 0.2), "mark k1 must be finite"),
        (([0.1, 0.2], [0.1, 0.2, 0.3]), "mark: k1 and k2 must broadcast"),
        (fws.SteeringGains(0.1, 0.2, 0.5), "chart's ratio -1.0"),
    ],
)
def test_bad_mark_is_refused_before_drawing(veh, mark, match):
    axis = np.linspace(-1.0, 1.0, 11)
    ch = fws.stability_chart(veh, speed=5.0, ratio=-1.0, k1=axis, k2=axis)
    n = len(plt.get_fignums())
    with pytest.raises(ValueError, match=f"^mark.*{match}|{match}"):
        ch.plot(mark=mark)
    assert len(plt.get_fignums()) == n  # no figure left behind


def test_pole_on_the_dynamic_plant_marks_the_kinematic_design():
    """The marked point is the gains whose kinematic closed loop (python-
    control's state space of the exact model) has its double root at the pole."""
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, **_DYN)
    dyn = fws.LateralPlant(veh, speed=10.0, curvature=0.02, model="dynamic")
    axis = np.linspace(-1.0, 1.0, 41)
    ch = fws.stability_chart(dyn, ratio=0.0, pole=-1.0, k1=axis, k2=axis)
    assert ch.design_model == "kinematic" and ch.order == 4
    cplt = ch.plot()
    dot = next(a for a in cplt.lines[0, 0] if "kinematic design" in str(a.get_label()))
    (k1d, k2d), = dot.get_xydata()  # fmt: skip
    kin = fws.LateralPlant(veh, speed=10.0, curvature=0.02, model="kinematic")
    A = fws.closed_loop(kin, fws.SteeringGains(k1d, k2d, 0.0)).A
    np.testing.assert_allclose(np.linalg.eigvals(A), [-1.0, -1.0], atol=1e-5)
    plt.close(cplt.figure)


def test_pole_on_another_four_state_plant_says_what_to_pass():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, **_DYN)
    ss = fws.linearize(veh, speed=10.0, model="dynamic")
    assert ss.nstates == 4
    with pytest.raises(ValueError, match=r"^pole=-1.0 needs a 2-state plant.*mark="):
        fws.stability_chart(ss, ratio=0.0, pole=-1.0)
