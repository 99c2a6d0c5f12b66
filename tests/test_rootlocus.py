"""Root loci: gain loop and parameter loci against closed-loop eigenvalues."""

import math

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from hypothesis import given
from hypothesis import strategies as st

import fws_control as fws
from fws_control.rootlocus import quadratic_roots


def _sorted(z):
    z = np.asarray(z, dtype=complex)
    return z[np.lexsort((z.imag, z.real))]


def _plant(veh, speed, curvature, ratio):
    """Single-input exact plant (A, b) from ct.linearize of the nonlinear model."""
    sys = fws.path_frame_model(veh, speed=speed, curvature=curvature)
    u0 = [math.atan(curvature * veh.wheelbase), 0.0]
    lin = ct.linearize(sys, [0.0, 0.0, 0.0], u0)
    return lin.A[1:, 1:], lin.B[1:, :] @ np.array([1.0, ratio])


@pytest.mark.parametrize(
    "speed, curvature, ratio, k1, k2",
    [
        (5.0, 0.1, -1.0, 0.05, 0.6),
        (20.0, 0.01, 0.5, 0.02, 0.4),
        (5.0, 0.0, 0.0, 0.1, 1.0),
        (-5.0, 0.1, 0.5, 0.1, -0.5),
    ],
)
def test_gain_loop_matches_state_space(veh, speed, curvature, ratio, k1, k2):
    A, b = _plant(veh, speed, curvature, ratio)
    ref = ct.ss(A, b[:, None], [[k1, k2]], [[0.0]])
    plant = fws.LateralPlant(veh, speed=speed, curvature=curvature)
    loop = fws.gain_loop(plant, fws.SteeringGains(k1, k2, ratio))
    assert loop.issiso() and loop.input_labels == ["delta_f"]
    assert loop.output_labels == ["k_x"]
    for s in (0.3j, 1.0 + 2.0j, -0.7 + 0.1j, 4.0):
        # ct.linearize differentiates numerically: ~1e-7 relative accuracy.
        np.testing.assert_allclose(loop(s), ref(s), rtol=1e-5)
    # Root locus at several scales = eig(A - g b k).
    scales = np.array([0.0, 0.3, 1.0, 2.5])
    rl = ct.root_locus_map(loop, gains=scales)
    for g, row in zip(scales, rl.loci, strict=True):
        ev = np.linalg.eigvals(A - g * np.outer(b, [k1, k2]))
        np.testing.assert_allclose(_sorted(row), _sorted(ev), atol=1e-5)


@pytest.mark.parametrize("model", ["kinematic", "paper"])
def test_gain_locus_at_one_is_closed_loop(veh, model):
    plant = fws.LateralPlant(veh, speed=20.0, curvature=0.01, model=model)
    g = fws.double_root_gains(plant, ratio=0.5, pole=-2.0)
    g = fws.SteeringGains(float(g.k1) * 1.3, float(g.k2) * 0.8, 0.5)  # distinct poles
    pz = fws.gain_locus(plant, g, scale=[1.0])
    cl = fws.closed_loop(plant, g)
    np.testing.assert_allclose(_sorted(pz.loci[0]), _sorted(cl.poles()), atol=1e-10)
    # the Vehicle convenience keywords give the same locus
    pz2 = fws.gain_locus(
        veh, g, scale=[0.5, 1.0], speed=20.0, curvature=0.01, model=model
    )
    np.testing.assert_allclose(_sorted(pz2.loci[1]), _sorted(cl.poles()), atol=1e-10)
    np.testing.assert_array_equal(pz2.gains, [0.5, 1.0])


def test_gain_locus_default_gains_and_plot(veh):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    loop = fws.gain_loop(plant, g)
    # Open-loop poles +-j V kappa: the A matrix of eq. (33) (hand-derived).
    np.testing.assert_allclose(_sorted(loop.poles()), [-0.5j, 0.5j], atol=1e-12)
    cplt = ct.root_locus_plot(loop, grid=False, initial_gain=1.0)
    xlim = cplt.axes[0, 0].get_xlim()
    assert -10 < xlim[0] < -1 and xlim[1] < 10  # no spurious far-away zero
    plt.close(cplt.figure)


CASES = [
    ("ratio", np.linspace(-1.5, 0.9, 25), 5.0, 0.1),
    ("speed", np.linspace(1.0, 30.0, 25), 5.0, 0.1),
    ("speed", np.linspace(-10.0, -1.0, 7), 5.0, 0.0),
    ("curvature", np.linspace(0.0, 0.3, 25), 5.0, 0.1),
    ("k1", np.linspace(-0.2, 0.5, 25), 20.0, 0.01),
    ("k2", np.linspace(-1.0, 2.0, 25), 20.0, 0.01),
]


@pytest.mark.parametrize("model", ["kinematic", "paper"])
@pytest.mark.parametrize("name, values, speed, curvature", CASES)
def test_parameter_locus_equals_closed_loop(veh, name, values, speed, curvature, model):
    g0 = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    plant = fws.LateralPlant(veh, speed=speed, curvature=curvature, model=model)
    pz = fws.parameter_locus(plant, g0, parameter=name, values=values)
    assert pz.loci.shape == (len(values), 2)
    np.testing.assert_array_equal(pz.gains, values)
    for v, row in zip(values, pz.loci, strict=True):
        p = {
            "speed": speed,
            "curvature": curvature,
            "ratio": -1.0,
            "k1": 0.05,
            "k2": 0.6,
        }
        p[name] = v
        g = fws.SteeringGains(p["k1"], p["k2"], p["ratio"])
        cl = fws.closed_loop(
            veh, g, speed=p["speed"], curvature=p["curvature"], model=model
        )
        np.testing.assert_allclose(_sorted(row), _sorted(cl.poles()), atol=1e-9)


def test_ratio_locus_keeps_k1_k2_fixed(veh):
    g0 = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    plant = fws.LateralPlant(veh, speed=5.0)
    pz = fws.parameter_locus(plant, g0, parameter="ratio", values=[0.0])
    # a = 0, kappa = 0: lambda^2 + (V k2/f) lambda + V^2 k1/f (hand-derived).
    ref = np.roots([1.0, 5.0 * 0.6 / 2.7, 25.0 * 0.05 / 2.7])
    np.testing.assert_allclose(_sorted(pz.loci[0]), _sorted(ref), atol=1e-12)


def test_redesign_and_cross_model(veh):
    g0 = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    kap = np.linspace(0.0, 0.25, 11)
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.0, model="kinematic")
    same = fws.parameter_locus(
        plant, g0, parameter="curvature", values=kap, redesign_pole=-1.0
    )
    np.testing.assert_allclose(same.loci, -1.0, atol=1e-6)
    cross = fws.parameter_locus(
        plant,
        g0,
        parameter="curvature",
        values=kap,
        redesign_pole=-1.0,
        design_model="paper",
    )
    for k, row in zip(kap, cross.loci, strict=True):
        gp = fws.double_root_gains(
            veh, speed=5.0, curvature=k, ratio=-1.0, pole=-1.0, model="paper"
        )
        cl = fws.closed_loop(veh, gp, speed=5.0, curvature=k, model="kinematic")
        np.testing.assert_allclose(_sorted(row), _sorted(cl.poles()), atol=1e-9)
    # On a straight path both models agree; with curvature they do not.
    np.testing.assert_allclose(cross.loci[0], -1.0, atol=1e-6)
    assert np.abs(cross.loci[-1] + 1.0).max() > 0.05


def test_branches_are_continuous(veh):
    g0 = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    vals = np.linspace(-0.2, 2.0, 2001)  # crosses real/complex transitions
    pz = fws.parameter_locus(
        veh, g0, parameter="k1", values=vals, speed=5.0, curvature=0.1
    )
    # The swapped assignment would jump by the gap between the branches.
    swapped = np.abs(pz.loci[1:, ::-1] - pz.loci[:-1]).max(axis=1)
    direct = np.abs(pz.loci[1:] - pz.loci[:-1]).max(axis=1)
    assert np.all(direct <= swapped + 1e-12)
    # Near a double root the roots move like sqrt(step); elsewhere the branch
    # steps are tiny while the swapped assignment jumps by the branch gap.
    assert np.median(direct) < 0.01 and swapped.max() > 1.0


def test_parameter_locus_plot(veh):
    g0 = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    pz = fws.parameter_locus(
        plant, g0, parameter="ratio", values=np.linspace(-1.5, 0.9, 50)
    )
    cplt = pz.plot(grid=False)
    loci_lines = cplt.lines[0, 2]
    assert len(loci_lines) == 2
    np.testing.assert_allclose(loci_lines[0].get_xdata(), pz.loci[:, 0].real)
    plt.close(cplt.figure)
    # The default call (python-control's s-plane grid) accepts it too.
    cplt = pz.plot()
    np.testing.assert_allclose(cplt.lines[0, 2][1].get_ydata(), pz.loci[:, 1].imag)
    plt.close(cplt.figure)


@given(st.floats(-50, 50), st.floats(-50, 50))
def test_quadratic_roots_against_numpy(p1, p0):
    r = quadratic_roots(p1, p0)
    np.testing.assert_allclose(
        _sorted(r),
        _sorted(np.roots([1.0, p1, p0])),
        atol=1e-7 * (1 + abs(p1) + abs(p0)),
    )


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"parameter": "mass"}, "parameter must be one of"),
        ({"values": []}, "values"),
        ({"values": [np.nan]}, "values"),
        ({"parameter": "speed", "values": [-1.0, 0.0, 1.0]}, "speed"),
        ({"parameter": "k1", "redesign_pole": -1.0}, "redesign_pole"),
        ({"model": "nonsense"}, "model"),
        ({"design_model": "nonsense"}, "model"),
    ],
)
def test_parameter_locus_bad_input(veh, kwargs, match):
    args = {
        "parameter": "ratio",
        "values": [0.0, 0.5],
        "speed": 5.0,
        "curvature": 0.1,
    } | kwargs
    with pytest.raises(ValueError, match=match):
        fws.parameter_locus(veh, fws.SteeringGains(0.05, 0.6, -1.0), **args)


def test_loci_need_one_operating_point_and_scalar_gains(veh):
    g = fws.SteeringGains(0.05, 0.6, -1.0)
    many = fws.LateralPlant(veh, speed=[5.0, 20.0])
    for call in (
        lambda: fws.gain_loop(many, g),
        lambda: fws.parameter_locus(many, g, parameter="ratio", values=[0.0]),
    ):
        with pytest.raises(ValueError, match=r"one operating point.*\(2,\)"):
            call()
    with pytest.raises(ValueError, match="scalar"):
        fws.gain_loop(veh, fws.SteeringGains([0.1, 0.2], 0.6, -1.0), speed=5.0)


def test_uncontrollable_redesign_raises(veh):
    with pytest.raises(fws.UncontrollableError):
        fws.parameter_locus(
            fws.LateralPlant(veh, speed=5.0, curvature=0.0),
            fws.SteeringGains(0.05, 0.6, -1.0),
            parameter="ratio",
            values=[0.5, 1.0],
            redesign_pole=-1.0,
        )


_P13 = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, curvature=0.1)
_G13 = fws.double_root_gains(_P13, ratio=-1.0, pole=-1.0)


@pytest.mark.parametrize(
    "make, arg, exc",
    [
        (lambda: fws.gain_locus(_P13, _G13, scale=np.array([])), "scale", ValueError),
        (
            lambda: fws.parameter_locus(_P13, _G13, parameter=np.eye(2), values=[1.0]),
            "parameter",
            ValueError,
        ),  # fmt: skip
        (
            lambda: fws.parameter_locus(_P13, _G13, parameter="speed", values=[0.0]),
            "values",
            ValueError,
        ),  # fmt: skip
        (
            lambda: fws.parameter_locus(
                _P13, _G13, parameter="curvature", values=[1e300]
            ),
            "values",
            ValueError,
        ),  # fmt: skip
    ],
)
def test_issue13_locus_arguments_named(make, arg, exc):
    # before: "need at least one array to concatenate", the truth value of
    # an array, and a swept value refused under the plant's name only
    with pytest.raises(exc, match=rf"\b{arg}\b"):
        make()


def test_gain_locus_plot_draws_on_its_own_figure_and_marks_the_design(
    veh,
):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    grid = np.linspace(-1.0, 1.0, 21)
    chart = fws.stability_chart(plant, ratio=-1.0, k1=grid, k2=grid).plot()
    chart_lines = len(chart.axes[0, 0].lines)
    try:
        cplt = fws.gain_locus(plant, g).plot()
        # not drawn into the k1-k2 chart (python-control would reuse a
        # current figure with one axes)
        assert cplt.figure is not chart.figure
        assert len(chart.axes[0, 0].lines) == chart_lines
        # the design's roots are marked: the marker points are the
        # eigenvalues of the closed loop at scale g = 1
        ax = cplt.axes[0, 0]
        marked = [
            complex(x, y)
            for line in ax.lines
            if line.get_marker() == "s"
            for x, y in zip(line.get_xdata(), line.get_ydata(), strict=True)
        ]
        expected = fws.closed_loop(plant, g).poles()
        assert len(marked) == len(expected) == 2
        np.testing.assert_allclose(
            sorted(marked, key=lambda z: (z.real, z.imag)),
            sorted(expected, key=lambda z: (z.real, z.imag)),
            atol=1e-6,
        )
        # no mark on request; ax= overlays on the given axes
        bare = fws.gain_locus(plant, g).plot(initial_gain=None, ax=ax)
        assert bare.figure is cplt.figure
        before = len(marked)
        assert sum(line.get_marker() == "s" for line in ax.lines) == before
    finally:
        plt.close("all")


def test_parameter_locus_plot_draws_on_its_own_figure(veh):
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    grid = np.linspace(-1.0, 1.0, 11)
    try:
        chart = fws.stability_chart(plant, ratio=-1.0, k1=grid, k2=grid).plot()
        speeds = np.linspace(2.0, 10.0, 9)
        cplt = fws.parameter_locus(plant, g, parameter="speed", values=speeds).plot()
        assert cplt.figure is not chart.figure
        # the drawn branches (python-control's columns: poles, zeros,
        # loci) are the closed-loop eigenvalues at each speed
        drawn = np.sort_complex(
            np.concatenate(
                [line.get_xdata() + 1j * line.get_ydata() for line in cplt.lines[0, 2]]
            )
        )
        ref = np.sort_complex(
            np.concatenate(
                [
                    fws.closed_loop(
                        fws.LateralPlant(veh, speed=v, curvature=0.1), g
                    ).poles()
                    for v in speeds
                ]
            )
        )
        np.testing.assert_allclose(drawn, ref, atol=1e-9)
    finally:
        plt.close("all")
