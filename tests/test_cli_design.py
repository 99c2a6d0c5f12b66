"""``fws-control design``: its numbers are those of the library calls."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import fws_control as fws
from fws_control.cli import main

PNG = b"\x89PNG\r\n\x1a\n"
VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


def _run(args, capsys):
    try:
        code = main([str(a) for a in args])
    except SystemExit as exc:  # argparse's refusal of an option value
        code = exc.code
    cap = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, cap.out, cap.err)


@pytest.fixture
def calls(monkeypatch):
    """The library's design calls the command makes: (args, kwargs, result).

    The command's numbers are checked against the very object the library
    returned for the arguments the command passed (asserted below), not a
    second run of the same deterministic search: each search costs seconds.
    """
    import fws_control.delay_design
    import fws_control.robust

    seen = []

    def spy(module, name):
        func = getattr(module, name)

        def wrapper(*args, **kwargs):
            out = func(*args, **kwargs)
            seen.append((args, kwargs, out))
            return out

        monkeypatch.setattr(module, name, wrapper)

    spy(fws_control.delay_design, "most_stable_gains")
    spy(fws_control.robust, "robust_gains")
    return seen


def _most_stable_call(calls):
    """The one most_stable_gains call: the plant and options of the command."""
    ((args, kwargs, design),) = calls
    (plant,) = args
    ref = fws.LateralPlant(VEH, speed=20.0, curvature=0.0, steering_lag=0.27)
    assert repr(plant) == repr(ref)
    assert kwargs == {"delay": 0.24, "ratio": 0.0, "grid": 6}
    return design


def test_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["design", "--help"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("usage: fws-control design")


def test_json_matches_most_stable_gains(capsys, calls, tmp_path):
    out = tmp_path / "design.png"
    p = _run(["design", "--speed", 20, "--grid", 6, "--json", "--out", out], capsys)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)  # one JSON line, nothing else on stdout
    d = _most_stable_call(calls)
    assert data["method"] == "most-stable"
    assert data["k1"] == float(d.gains.k1) and data["k2"] == float(d.gains.k2)
    assert data["abscissa"] == d.abscissa
    assert data["critical_delay"] == d.critical_delay
    assert data["certified"] is True
    # the 20 m/s case of docs/design_delay.md
    assert data["abscissa"] == pytest.approx(-0.9156, abs=1e-4)
    assert out.read_bytes().startswith(PNG)


def test_table_prints_the_same_numbers(capsys, calls):
    p = _run(["design", "--speed", 20, "--grid", 6], capsys)
    assert p.returncode == 0, p.stderr
    d = _most_stable_call(calls)
    rows = dict(line.split(None, 1) for line in p.stdout.strip().splitlines())
    assert float(rows["k1"]) == pytest.approx(float(d.gains.k1), rel=1e-5)
    assert float(rows["abscissa"]) == pytest.approx(d.abscissa, rel=1e-5)
    assert float(rows["critical_delay"]) == pytest.approx(d.critical_delay, rel=1e-5)


def test_robust_matches_robust_gains(capsys, calls):
    # without delay the inner maximum is over eigenvalues: the command's
    # plumbing checked in seconds (with a delay the same search costs ~10x;
    # tests/test_robust.py checks the delayed search itself)
    args = ["design", "--method", "robust", "--speed", 10, 30, "--grid", 6]
    args += ["--delay", 0]
    p = _run([*args, "--json"], capsys)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout)
    box = {
        "speed": (10.0, 30.0),
        "delay": (0.0, 0.0),
        "steering_lag": 0.27,
        "curvature": 0.0,
    }
    ((call_args, kwargs, r),) = calls
    assert call_args == (VEH,)
    assert sorted(kwargs) == ["box", "k1", "k2", "ratio"]
    assert kwargs["ratio"] == 0.0 and kwargs["box"] == box
    np.testing.assert_array_equal(kwargs["k1"], np.linspace(0.0, 0.015, 6))
    np.testing.assert_array_equal(kwargs["k2"], np.linspace(0.0, 0.5, 6))
    assert data["k1"] == float(r.gains.k1) and data["k2"] == float(r.gains.k2)
    assert data["abscissa"] == r.abscissa
    assert data["worst"] == r.worst
    assert data["abscissa"] < 0.0


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--speed", 10, 20], "--speed takes one speed"),
        (["--method", "robust", "--speed", 20], "--speed takes LOW HIGH"),
        (["--grid", 2], "--grid"),
        (["--out", "x.tiff"], "--out must be a .png, .svg, .pdf file"),
    ],
)
def test_bad_input_is_one_line_and_status_2(capsys, args, words):
    p = _run(["design", *args], capsys)
    assert p.returncode == 2
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1
