"""The command line's output forms: figure formats and ``--json``.

References: the library's functions called directly with the same
arguments (``double_root_gains``, the closed-loop eigenvalues from
numpy, ``critical_delay``, ``rightmost_roots``, ``simulate`` on the same
course), each file's own magic bytes, and the standard library's JSON
parser (which refuses NaN and infinity only with ``parse_constant``).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import fws_control as fws
from fws_control.cli import main
from fws_control.paper.figures import reproduce

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "svg": b"<?xml", "pdf": b"%PDF-"}


def _strict_json(text: str):
    def refuse(name):
        raise AssertionError(f"not JSON: {name}")

    return json.loads(text, parse_constant=refuse)


def _run(args, capsys):
    code = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("fmt", ["png", "svg", "pdf"])
def test_figure_format_follows_the_suffix(fmt, tmp_path, capsys):
    out = tmp_path / f"chart.{fmt}"
    code, text, _ = _run(["chart", "--points", 21, "--out", out], capsys)
    assert code == 0
    assert out.read_bytes().startswith(MAGIC[fmt])
    assert text.strip().endswith(f"wrote {out}")


def test_an_unknown_figure_suffix_names_the_formats(tmp_path, capsys):
    code, _, err = _run(["rlocus", "--out", tmp_path / "r.tiff"], capsys)
    assert code == 2
    assert "--out must be a .png, .svg, .pdf file" in err and "r.tiff" in err
    assert not list(tmp_path.iterdir())


def test_gains_json_matches_the_library(capsys):
    args = ["--speed", 5, "--curvature", 0.1, "--ratio", -0.5, "--pole", -1.5]
    code, text, _ = _run(["gains", *args, "--json"], capsys)
    assert code == 0
    data = _strict_json(text)
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    for model in ("kinematic", "paper"):
        plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1, model=model)
        g = fws.double_root_gains(plant, ratio=-0.5, pole=-1.5)
        d = data["designs"][model]
        assert (d["k1"], d["k2"], d["k3"], d["k4"]) == (
            float(g.k1), float(g.k2), float(g.k3), float(g.k4),
        )  # fmt: skip
        # its own linearisation puts both poles at lambda0 (a double root:
        # split by ~sqrt(eps) in floating point)
        poles = np.array([complex(*p) for p in d["poles"][model]])
        assert np.allclose(poles, -1.5, atol=1e-6)
        # the other: the eigenvalues of the closed loop, written out here
        other = "paper" if model == "kinematic" else "kinematic"
        lin = fws.LateralPlant(
            veh, speed=5.0, curvature=0.1, model=other
        ).linearize()  # python-control StateSpace: inputs (delta_f, delta_r)
        k = np.array([[float(g.k1), float(g.k2)]])
        b = lin.B @ np.array([[1.0], [-0.5]])
        eig = np.sort_complex(np.linalg.eigvals(lin.A - b @ k @ lin.C))
        got = np.array([complex(*p) for p in d["poles"][other]])
        assert np.allclose(got, eig, atol=1e-9)
    # the table prints the same numbers
    code, table, _ = _run(["gains", *args], capsys)
    assert code == 0
    assert f"k1 = {data['designs']['kinematic']['k1']:.6f}" in table


def test_delay_margin_json_matches_the_library(capsys):
    code, text, _ = _run(
        ["delay-margin", "--speed", 20, "--curvature", 0.0, "--ratio", -0.3,
         "--steering-lag", 0.27, "--delay", 0.2, "--json"],
        capsys,
    )  # fmt: skip
    assert code == 0
    data = _strict_json(text)
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=20.0, curvature=0.0, steering_lag=0.27)
    g = fws.double_root_gains(
        fws.LateralPlant(veh, speed=20.0, curvature=0.0), ratio=-0.3, pole=-1.0
    )
    cd = fws.critical_delay(plant, g)
    assert data["critical_delay"] == cd.delay and data["frequency"] == cd.frequency
    assert data["steering_lag"] == [0.27, 0.27]
    roots = fws.rightmost_roots(plant, g, delay=0.2, n=2)
    got = np.array([complex(*p) for p in data["rightmost_roots"]])
    assert np.allclose(got, np.sort_complex(roots), atol=1e-12)
    assert data["stable_at_delay"] is bool(roots[0].real < 0) is (0.2 < cd.delay)


def test_delay_margin_json_has_no_infinity(capsys):
    # without lag or delay the kinematic loop's margin is finite; with k1 = 0
    # and k2 = 0 no delay destabilises it (no feedback): the margin is
    # infinite, which JSON writes as null
    code, text, _ = _run(
        ["delay-margin", "--speed", 10, "--k1", 0, "--k2", 0, "--json"], capsys
    )
    data = _strict_json(text)
    cd = fws.critical_delay(
        fws.LateralPlant(fws.Vehicle(2.7, 1.35), speed=10.0, curvature=0.1),
        fws.SteeringGains(0.0, 0.0, -1.0),
    )
    if math.isinf(cd.delay):
        assert data["critical_delay"] is None
    else:
        assert data["critical_delay"] == cd.delay


@pytest.mark.parametrize("course", ["lane-change", "slalom"])
def test_simulate_a_course_matches_simulate(course, tmp_path, capsys):
    out = tmp_path / "run.svg"
    code, text, _ = _run(
        ["simulate", "--path", course, "--speed", 12, "--ratio", -0.3,
         "--y0", 0.4, "--out", out, "--json"],
        capsys,
    )  # fmt: skip
    assert code == 0
    assert out.read_bytes().startswith(MAGIC["svg"])
    data = _strict_json(text)
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    m = fws.double_lane_change() if course == "lane-change" else fws.slalom()
    plant = fws.LateralPlant(veh, speed=12.0)
    g = fws.double_root_gains(plant, ratio=-0.3, pole=-1.0)
    res = fws.simulate(
        plant, m.path, g, initial_state=(0.0, 0.4, 0.0),
        duration=m.path.length / 12.0,
    )  # fmt: skip
    assert data["status"] == str(res.status)
    assert data["max_abs_e"] == pytest.approx(np.max(np.abs(res.e)), rel=1e-9)
    assert data["peak_lateral_accel"] == pytest.approx(
        np.max(np.abs(res.lateral_accel)), rel=1e-9
    )
    assert data["cones_hit"] == m.cones_hit(res.x, res.y, res.psi, wheelbase=2.7)
    assert data["k1"] == float(g.k1) and data["k2"] == float(g.k2)


def test_reproduce_writes_the_format_asked(tmp_path):
    # the cheapest figure (fig2 draws three times as long): the format is
    # what is checked
    name = "extra_turning_radius"
    res = reproduce(tmp_path, quick=True, progress=False, names=[name], format="svg")
    assert [p.name for p in res.figures] == [f"{name}.svg"]
    assert res.figures[0].read_bytes().startswith(MAGIC["svg"])
    with pytest.raises(ValueError, match=r"format must be one of .*'png'.*got 'jpg'"):
        reproduce(tmp_path, quick=True, progress=False, names=["fig2"], format="jpg")


def test_compare_runs_the_controllers_named(tmp_path, capsys):
    code, text, _ = _run(
        ["compare", "--speed", 15, "--controllers", "paper, a = 0",
         "--out", tmp_path / "c.pdf"],
        capsys,
    )  # fmt: skip
    assert code == 0
    assert (tmp_path / "c.pdf").read_bytes().startswith(MAGIC["pdf"])
    rows = [r for r in text.splitlines() if r.startswith("| paper")]
    assert len(rows) == 1 and len([r for r in text.splitlines() if r[:2] == "| "]) == 2
    # the same row from the library
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=15.0)
    g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    cmp = fws.compare(plant, fws.double_lane_change(), {"paper, a = 0": g})
    assert rows[0] == cmp.to_markdown().splitlines()[-1]


def test_compare_refuses_an_unknown_controller(tmp_path, capsys):
    code, _, err = _run(
        ["compare", "--controllers", "Stanley", "nope", "--out", tmp_path / "c.png"],
        capsys,
    )
    assert code == 2 and "--controllers must name" in err and "'nope'" in err
    assert not list(tmp_path.iterdir())


def test_default_mpc_predicts_over_the_comparison_delay():
    pytest.importorskip("osqp", reason="the extra 'mpc' (OSQP)")
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    for delay, ts in ((0.0, 0.04), (0.24, 0.04), (0.1, 0.05), (0.03, 0.03)):
        mpc = fws.default_controllers(veh, speed=20.0, delay=delay)[
            "linear MPC (independent rear)"
        ]
        assert mpc.delay == delay
        assert mpc.sample_time == pytest.approx(ts, rel=1e-12)
        # a whole number of samples over the delay, a 2 s horizon
        assert round(delay / mpc.sample_time) * mpc.sample_time == pytest.approx(delay)
        assert mpc.horizon * mpc.sample_time == pytest.approx(2.0, abs=ts / 2)
