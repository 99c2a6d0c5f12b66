"""The fws-control command line, run as `python -m fws_control` in a subprocess.

A subprocess where the process is what is checked (the entry point, exit
status and stderr of a fresh interpreter, files a process writes); elsewhere
in-process through the same main(), as importing the library dominates a
subprocess.
"""

import csv
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from fws_control.cli import main

PNG = b"\x89PNG\r\n\x1a\n"
F = 2.7


def _popen(args, cwd=None):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.Popen(
        [sys.executable, "-m", "fws_control", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
        env=env,
    )


def _finish(proc):
    out, err = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def run(*args, cwd=None):
    return _finish(_popen(args, cwd))


def run_many(arg_lists, cwd=None):
    """Run several invocations two at a time (the interpreter start dominates)."""
    results = []
    for i in range(0, len(arg_lists), 2):
        procs = [_popen(a, cwd) for a in arg_lists[i : i + 2]]
        results += [_finish(p) for p in procs]
    return results


SUBCOMMANDS = ["gains", "chart", "rlocus", "simulate", "delay-margin", "reproduce"]


def test_help_subprocess():
    procs = run_many([["--help"], ["reproduce", "--help"]])
    for p in procs:
        assert p.returncode == 0, p.stderr
        assert p.stdout.startswith("usage: fws-control")
    assert "--out" in procs[1].stdout and "--quick" in procs[1].stdout


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_help_every_subcommand(sub, capsys):
    # In-process (the interpreter start dominates a subprocess); same parser.
    with pytest.raises(SystemExit) as exc:
        main([sub, "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: fws-control {sub}")


def test_gains_straight_matches_eq41():
    p = run("gains", "--speed", 5, "--curvature", 0, "--ratio", -0.5, "--pole", -1)
    assert p.returncode == 0, p.stderr
    k1 = F / (25 * 1.5)
    k2 = F / (5 * 1.5) * (2 + 0.5 * F / (5 * 1.5))
    m = re.search(r"k1 = (\S+) rad/m\s+k2 = (\S+)", p.stdout)
    assert float(m.group(1)) == pytest.approx(k1, abs=1e-6)
    assert float(m.group(2)) == pytest.approx(k2, abs=1e-6)
    m = re.search(r"k3 = (\S+) rad/m\s+k4 = (\S+)", p.stdout)
    assert float(m.group(1)) == pytest.approx(-0.5 * k1, abs=1e-6)
    poles = "closed-loop poles, kinematic linearisation: -1.000000, -1.000000"
    assert poles in p.stdout


def _in_process(args, capsys):
    """main() in this interpreter; returns a CompletedProcess-like result."""
    code = main([str(a) for a in args])
    cap = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, cap.out, cap.err)


def test_gains_curved_shows_paper_model_error(capsys):
    p = _in_process(
        ["gains", "--speed", 5, "--curvature", 0.1, "--ratio", 0, "--model", "paper"],
        capsys,
    )
    assert p.returncode == 0, p.stderr
    first = p.stdout.split("kinematic model")[0]
    # Paper eq. (44), a = 0: k1 = f (lambda0^2/V^2 - kappa^2), k2 = -2 lambda0 f / V.
    m = re.search(r"k1 = (\S+) rad/m\s+k2 = (\S+)", first)
    assert float(m.group(1)) == pytest.approx(F * (1 / 25 - 0.01), abs=1e-6)
    assert float(m.group(2)) == pytest.approx(2 * F / 5, abs=1e-6)
    # Those gains in the exact linearisation: lambda^2 + (V c k2/f) l + V^2 (c k1/f
    # + kappa^2), c = 1 + f^2 kappa^2.
    c = 1 + F**2 * 0.01
    ref = np.sort(np.roots([1, 5 * c * 2 / 5, 25 * (c * (1 / 25 - 0.01) + 0.01)]).real)
    line = re.search(
        r"paper model:.*?kinematic linearisation: ([^\n]+)", p.stdout, re.S
    )
    got = np.sort([float(x) for x in line.group(1).split(",")])
    np.testing.assert_allclose(got, ref, atol=1e-5)


def test_chart_rlocus_write_png(tmp_path, capsys):
    # In-process: a process writing a PNG is test_simulate_png_and_csv's.
    out = tmp_path / "c.png"
    p = _in_process(
        ["chart", "--speed", 20, "--curvature", 0.01, "--ratio", 0.5,
         "--points", 101, "--out", out],
        capsys,
    )  # fmt: skip
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == PNG
    p = _in_process(
        ["chart", "--paper-figure", 2, "--out", tmp_path / "f2.png"], capsys
    )
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "f2.png").read_bytes()[:8] == PNG
    p = _in_process(["rlocus", "--out", tmp_path / "r.png"], capsys)
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "r.png").read_bytes()[:8] == PNG
    # L(s) of a double-root design: (-2 l0 s + l0^2 - V^2 kappa^2)/(s^2 + V^2 kappa^2)
    num = re.search(r"L\(s\) = \[([^\]]+)\]", p.stdout).group(1)
    np.testing.assert_allclose([float(x) for x in num.split(",")], [2.0, 0.75])
    p = _in_process(
        [
            "rlocus",
            "--param",
            "curvature",
            "--redesign",
            "--design-model",
            "paper",
            "--points",
            50,
            "--out",
            tmp_path / "r2.png",
        ],
        capsys,
    )
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "r2.png").read_bytes()[:8] == PNG


def test_simulate_png_and_csv(tmp_path):
    out, data = tmp_path / "s.png", tmp_path / "s.csv"
    p = run(
        "simulate",
        "--path",
        "straight",
        "--speed",
        5,
        "--ratio",
        -1,
        "--y0",
        2,
        "--psi0",
        10,
        "--duration",
        10,
        "--out",
        out,
        "--csv",
        data,
    )
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == PNG
    with open(data) as fh:
        rows = list(csv.DictReader(fh))
    # Units in the header; angles in degrees, as the CLI reads and prints them.
    assert list(rows[0])[:4] == ["t [s]", "x [m]", "y [m]", "psi [deg]"]
    assert "delta_f_rate [deg/s]" in rows[0] and list(rows[0])[-1] == "status"
    assert float(rows[0]["e [m]"]) == pytest.approx(2.0)
    assert float(rows[0]["theta [deg]"]) == pytest.approx(10.0)
    assert float(rows[-1]["t [s]"]) == pytest.approx(10.0)
    # lambda0 = -1 double root: after 10 s the error is ~ (1 + t) e^-t small.
    assert abs(float(rows[-1]["e [m]"])) < 0.02
    assert {r["status"] for r in rows} == {"ok"}
    assert "status: ok" in p.stdout


def test_simulate_stopped_run_exits_3_and_says_so(tmp_path, capsys):
    """a = 1 on the 0.1 1/m arc: |delta_f| > 90 deg at t = 0 (singular)."""
    out, data = tmp_path / "s.png", tmp_path / "s.csv"
    p = _in_process(
        ["simulate", "--ratio", 1, "--duration", 2, "--out", out, "--csv", data],
        capsys,
    )
    assert p.returncode == 3
    assert "singular_steering" in p.stdout
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "exit status 3" in err[0]
    assert out.read_bytes()[:8] == PNG
    with open(data) as fh:
        rows = list(csv.DictReader(fh))
    assert rows[0]["status"] == "singular_steering"


def test_one_default_curvature_and_out_defaults_in_help(capsys):
    from fws_control.cli import DEFAULT_CURVATURE, build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a.choices, dict)).choices
    for name in ("gains", "chart", "rlocus", "simulate", "delay-margin"):
        assert sub[name].parse_args([]).curvature == DEFAULT_CURVATURE, name
    for name, default in (
        ("chart", "chart.png"),
        ("rlocus", "rlocus.png"),
        ("simulate", "simulation.png"),
        ("reproduce", "figures"),
    ):
        text = " ".join(sub[name].format_help().split())
        assert f"--out OUT figure file: .png, .svg or .pdf ({default})" in text or (
            f"--out OUT directory ({default})" in text
        ), name


def test_rlocus_prints_no_float_noise(capsys):
    import fws_control.cli as cli

    assert cli._fmt_coeffs([2.0000000000000004, 0.7499999999999999]) == "[2, 0.75]"
    assert cli._fmt_coeffs([1.0, 0.0, 0.25]) == "[1, 0, 0.25]"


def test_extreme_inputs_warn_one_line_each(tmp_path, capsys):
    p = _in_process(["gains", "--curvature", 5, "--speed", 5, "--ratio", -1], capsys)
    assert p.returncode == 0, p.stderr
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "warning" in err[0] and "--curvature 5" in err[0]
    p = _in_process(
        ["rlocus", "--k1", 0.1, "--k2", 30, "--out", tmp_path / "r.png"], capsys
    )
    assert p.returncode == 0, p.stderr
    err = p.stderr.strip().splitlines()
    assert len(err) == 1 and "--k2 30" in err[0]
    # A plain run prints no warning.
    p = _in_process(["gains"], capsys)
    assert p.returncode == 0 and p.stderr == ""


def test_delay_margin_closed_form_and_bad_lags(capsys):
    """`delay-margin` prints the closed-form margin of a straight-road design.

    With the double root lambda0 the straight-road loop with an input delay is
    D(s) = s^2 + e^{-s tau}(-2 lambda0 s + lambda0^2) for every speed, ratio
    and model: |d(jw)| = |q(jw)| gives w^2 = (2 + sqrt(5)) lambda0^2 and the
    phase w tau = atan(2 w / |lambda0|), so tau_c |lambda0| = atan(2 u)/u with
    u^2 = 2 + sqrt(5) (0.6474 s for lambda0 = -1).
    """
    u = math.sqrt(2.0 + math.sqrt(5.0))
    for speed, ratio, pole in ((5, -1, -1), (20, 0.5, -2), (5, 1.5, -3)):
        p = _in_process(
            ["delay-margin", "--speed", speed, "--curvature", 0, "--ratio", ratio,
             "--pole", pole],
            capsys,
        )  # fmt: skip
        assert p.returncode == 0 and p.stderr == "", p.stderr
        assert "steering lag: none" in p.stdout
        m = re.search(r"critical delay: (\S+) s \(crossing at (\S+) rad/s", p.stdout)
        assert float(m[1]) == pytest.approx(math.atan(2 * u) / u / abs(pole), rel=1e-5)
        assert float(m[2]) == pytest.approx(u * abs(pole), rel=1e-5)
    # --delay reports the rightmost roots: stable just below the margin,
    # unstable just above it (0.6474 s for lambda0 = -1)
    for delay, verdict in ((0.64, "stable"), (0.66, "unstable")):
        p = _in_process(
            ["delay-margin", "--curvature", 0, "--pole", -1, "--delay", delay], capsys
        )
        assert p.returncode == 0, p.stderr
        assert f"at delay {delay:g} s: {verdict};" in p.stdout
    # a steering lag shrinks the margin (0.4552 s for a 0.27 s lag)
    p = _in_process(["delay-margin", "--curvature", 0, "--steering-lag", 0.27], capsys)
    assert "steering lag: 0.27 s front, 0.27 s rear" in p.stdout
    lagged = float(re.search(r"critical delay: (\S+) s", p.stdout)[1])
    assert 0.24 < lagged < math.atan(2 * u) / u
    # bad lags: exit status 2, nothing on stdout, one line on stderr
    for args, fragment in (
        (["--steering-lag", 0.1, 0.2, 0.3], "--steering-lag takes one or two"),
        (["--steering-lag", -0.27], "steering_lag must be > 0"),
        (["--steering-lag", 0.27, -0.1], "steering_lag must be > 0"),
    ):
        p = _in_process(["delay-margin", *args], capsys)
        assert p.returncode == 2, args
        assert p.stdout == "", args
        err = p.stderr.strip().splitlines()
        assert len(err) == 1, (args, p.stderr)
        assert err[0].startswith("fws-control delay-margin: error:"), err
        assert fragment in err[0], err


# Each kind of failure once through a real subprocess (reproduce: a fresh
# process importing the whole figure stack still prints one line) ...
BAD = [
    (["gains", "--speed", "abc"], "--speed"),  # argparse type error
    (["gains", "--speed", "0"], "speed"),  # ValueError from the library
    (["gains", "--ratio", "1", "--curvature", "0"], "uncontrollable"),
    (["reproduce", "--only", "fig99", "--no-progress"], "fig99"),
    (["nonsense"], "invalid choice"),
]

# ... and the other cases in-process through the same main().
BAD_IN_PROCESS = [
    # a ValueError of the command line itself, as "--speed 0" above is one of
    # the library (a subprocess of chart imports matplotlib before the check)
    (["chart", "--out", "chart.txt"], ".png"),
    (["gains", "--speed", "nan"], "--speed"),
    (["gains", "--pole", "1"], "pole"),
    (["gains", "--model", "linear"], "--model"),
    (["rlocus", "--k1", "0.1"], "--k2"),
    (["rlocus", "--param", "k1", "--redesign"], "redesign"),
    (["rlocus", "--param", "speed", "--range", "0", "10"], "speed"),
    (["simulate", "--duration", "-1"], "duration"),
    (["chart", "--points", "1"], "--points"),
    ([], "COMMAND"),
]


def test_bad_input_one_line_error(tmp_path):
    procs = run_many([args for args, _ in BAD], cwd=tmp_path)
    for (args, fragment), p in zip(BAD, procs, strict=True):
        assert p.returncode == 2, args
        assert "Traceback" not in p.stderr, args
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1, (args, p.stderr)
        assert fragment in lines[0] and "error" in lines[0], (args, lines)
    assert not list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("args, fragment", BAD_IN_PROCESS)
def test_bad_input_in_process(args, fragment, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    try:
        code = main(args)
    except SystemExit as exc:  # argparse errors exit from parse_args
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and fragment in err[0] and "error" in err[0], err
    assert not list(tmp_path.glob("*.png"))


def test_reproduce_quick_writes_every_figure(tmp_path, capsys):
    # In-process: a reproduce process is checked by test_bad_input_one_line_error
    # here and by the interrupt and lock tests of test_cli_reliability.py.
    out = tmp_path / "figures"
    p = _in_process(
        ["reproduce", "--out", out, "--quick", "--no-progress", "--dpi", 40], capsys
    )
    assert p.returncode == 0, p.stderr
    expected = [f"fig{n}.png" for n in range(2, 10)] + [
        "extra_actuator.png",
        "extra_linear_vs_nonlinear.png",
        "extra_root_loci.png",
        "extra_turning_radius.png",
    ]
    assert sorted(f.name for f in out.glob("*.png")) == sorted(expected)
    for name in expected:
        data = (out / name).read_bytes()
        assert data[:8] == PNG and len(data) > 5000
    summary = (out / "summary.md").read_text()
    assert "Double-root gains" in summary and "Fig. 5: peak lateral" in summary
    # Fig. 5 table, panel (d): the peak cannot be below the steady-state
    # centripetal acceleration V^2 kappa = 4 m/s^2 on the 1/100 curve.
    part = summary.split("**(d) curve")[1].split("##")[0]
    vals = [float(v) for v in re.findall(r"\| (\d+\.?\d*(?:e[+-]\d+)?) ", part)]
    assert vals and min(vals) >= 4.0 - 1e-6
