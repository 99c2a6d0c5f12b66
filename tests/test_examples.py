"""The gallery examples and the documentation's code run as written.

Each ``examples/plot_*.py`` is run as a script (``MPLBACKEND=Agg``) in a
temporary directory; it must exit 0, and the numbers it prints are checked
against references computed here independently of the code under test
(python-control's numerical linearisation of the nonlinear model, the
paper's printed formulas in sympy, hand-derived values). The ```python``
blocks of the Markdown pages under ``docs/`` run in order, one namespace per
page.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from pathlib import Path

import control as ct
import numpy as np
import pytest

import fws_control as fws
from fws_control import symbolic as S

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("plot_*.py"))
VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


def run_example(name: str, tmp_path: Path) -> str:
    """Run examples/<name> as a script; return its standard output."""
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONWARNINGS="ignore")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "examples" / name)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, f"{name} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc.stdout


def numeric_jacobians(speed: float, curvature: float):
    """(A, B) of (e, theta) by python-control's finite-difference linearize."""
    sys_nl = fws.path_frame_model(VEH, speed=speed, curvature=curvature)
    delta_ff = math.atan(curvature * VEH.wheelbase)  # paper eq. (26)
    lin = ct.linearize(sys_nl, [0.0, 0.0, 0.0], [delta_ff, 0.0])
    return lin.A[1:, 1:], lin.B[1:, :]


def closed_loop_matrix(A, B, k1, k2, a):
    K = -np.array([[k1, k2], [a * k1, a * k2]])
    return A + B @ K


def floats_after(label: str, text: str) -> list[float]:
    line = next(ln for ln in text.splitlines() if label in ln)
    tail = line.split(label, 1)[1]
    return [float(v) for v in re.findall(r"-?\d+\.\d*(?:e[-+]?\d+)?", tail)]


def test_every_example_is_covered():
    tested = {
        "plot_any_plant.py",
        "plot_fws_vs_4ws.py",
        "plot_quick_start.py",
        "plot_ratio_sweep.py",
        "plot_root_loci.py",
        "plot_spline_course.py",
        "plot_stability_chart.py",
    }
    assert {p.name for p in EXAMPLES} == tested
    for path in EXAMPLES:
        head = path.read_text(encoding="utf-8").lstrip()
        # sphinx-gallery needs a docstring with a title underlined by '='.
        assert head.startswith('"""'), path.name
        assert re.search(r"\n=+\n", head.split('"""')[1]), path.name


def test_quick_start(tmp_path):
    out = run_example("plot_quick_start.py", tmp_path)
    k1, k2 = floats_after("k1 =", out)[:2]
    # The printed gains make trace = -2 and det = 1 (double root at -1) in
    # the numerically linearised nonlinear model.
    A, B = numeric_jacobians(5.0, 0.1)
    M = closed_loop_matrix(A, B, k1, k2, -1.0)
    assert np.trace(M) == pytest.approx(-2.0, abs=2e-3)
    assert np.linalg.det(M) == pytest.approx(1.0, abs=2e-3)
    assert "stable: True" in out
    assert "status: ok" in out
    assert abs(floats_after("final lateral error", out)[0]) < 1e-3
    # The paper's gains (eqs. 45-46, sympy) in the numeric linearisation.
    vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.1, S.a: -1.0, S.lam0: -1.0}
    paper = S.paper_gain_formulas()["45-46"]
    pk1, pk2 = (float(paper[k].subs(vals)) for k in (S.k1, S.k2))
    true = np.sort(np.linalg.eigvals(closed_loop_matrix(A, B, pk1, pk2, -1.0)).real)
    assert floats_after("paper's gains, true poles:", out) == pytest.approx(
        true, abs=2e-3
    )


def test_stability_chart(tmp_path):
    out = run_example("plot_stability_chart.py", tmp_path)
    # Brute force: eigenvalues of the numerically linearised closed loop on
    # the example's 301 x 301 grid.
    A, B = numeric_jacobians(5.0, 0.1)
    g = np.linspace(-1.0, 1.0, 301)
    K1, K2 = np.meshgrid(g, g)
    Bu = B @ np.array([1.0, -1.0])  # delta_r = a*delta_f, a = -1
    M = A - Bu[:, None] * np.stack([K1, K2], axis=-1)[..., None, :]
    stable = np.all(np.linalg.eigvals(M).real < 0, axis=-1)
    printed = floats_after("stable fraction of the grid:", out)[0]
    assert printed == pytest.approx(stable.mean(), abs=2e-3)
    # Both models' designs: exact gains satisfy eqs. (39)-(40) of the sympy
    # exact model, the paper's those of eq. (34) as printed.
    for model in ("exact", "paper"):
        k1, k2 = floats_after(f"{model}: design", out)
        p = S.characteristic_polynomial(model).all_coeffs()
        vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.2, S.a: 0.5, S.k1: k1, S.k2: k2}
        assert float(p[1].subs(vals)) == pytest.approx(2.0, abs=5e-3)
        assert float(p[2].subs(vals)) == pytest.approx(1.0, abs=5e-3)


def test_root_loci(tmp_path):
    out = run_example("plot_root_loci.py", tmp_path)
    assert floats_after("poles at g = 1:", out) == pytest.approx([-1.0, -1.0])
    # Paper's gains (eqs. 45-46) at a = 0.5 in the numeric linearisation.
    vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.1, S.a: 0.5, S.lam0: -1.0}
    paper = S.paper_gain_formulas()["45-46"]
    pk1, pk2 = (float(paper[k].subs(vals)) for k in (S.k1, S.k2))
    A, B = numeric_jacobians(5.0, 0.1)
    true = np.sort(np.linalg.eigvals(closed_loop_matrix(A, B, pk1, pk2, 0.5)).real)
    printed = np.sort(floats_after("put the true poles at", out))
    assert printed == pytest.approx(true, abs=2e-3)


def test_any_plant(tmp_path):
    out = run_example("plot_any_plant.py", tmp_path)
    # Run as a script on the Agg backend, the example saves its figure.
    assert (tmp_path / "any_plant_charts.png").stat().st_size > 10_000
    # The 4-state plant built here from the numerical linearisation and the
    # two lags written out by hand: x = (e, theta, delta_f_act, delta_r_act),
    # commands u = [1, a] (-k1 e - k2 theta).
    A, B = numeric_jacobians(5.0, 0.1)
    tau_f, tau_r, a = 0.1, 0.2, -1.0
    A4 = np.zeros((4, 4))
    A4[:2, :2], A4[:2, 2:] = A, B
    A4[2, 2], A4[3, 3] = -1.0 / tau_f, -1.0 / tau_r
    b4 = np.array([0.0, 0.0, 1.0 / tau_f, a / tau_r])

    def eigs(k1, k2):
        row = np.stack([k1, k2, np.zeros_like(k1), np.zeros_like(k1)], axis=-1)
        return np.linalg.eigvals(A4 - b4[:, None] * row[..., None, :])

    # Brute force on a 201 x 201 subgrid of the example's 401 x 401 grid.
    g = np.linspace(-1.0, 1.0, 201)
    K1, K2 = np.meshgrid(g, g)
    frac4 = np.mean(np.all(eigs(K1, K2).real < 0, axis=-1))
    M2 = A - (B @ [1.0, a])[:, None] * np.stack([K1, K2], axis=-1)[..., None, :]
    frac2 = np.mean(np.all(np.linalg.eigvals(M2).real < 0, axis=-1))
    assert floats_after("stable fraction of the grid, 4 states:", out)[0] == (
        pytest.approx(frac4, abs=5e-3)
    )
    assert floats_after("stable fraction of the grid, 2 states:", out)[0] == (
        pytest.approx(frac2, abs=5e-3)
    )
    assert frac4 < frac2  # the lags shrink the stable set
    # The printed 2-state design, with the lags: stable, poles as printed.
    k1, k2 = floats_after("2-state design for lambda0 = -1: k1 =", out)[:2]
    poles = eigs(np.array(k1), np.array(k2))
    assert np.all(poles.real < 0)
    assert "stable with the lags: True" in out
    # The printed boundary point has closed-loop eigenvalues +-j omega.
    omega, bk1, bk2 = floats_after("boundary at omega =", out)[:3]
    lam = eigs(np.array(bk1), np.array(bk2))
    j = np.argmax(lam.real)
    assert abs(lam[j].real) < 1e-3
    assert abs(abs(lam[j].imag) - omega) < 1e-2


def test_fws_vs_4ws(tmp_path):
    out = run_example("plot_fws_vs_4ws.py", tmp_path)
    # Steady turning radius of R with the front wheels at 35 degrees:
    # f / tan(35 deg) for a = 0 and f / (2 sin(35 deg)) for a = -1.
    r0, r1 = floats_after("turning radius of R at a 35° limit:", out)[-2:]
    lim = math.radians(35.0)
    assert r0 == pytest.approx(2.7 / math.tan(lim), abs=6e-3)
    assert r1 == pytest.approx(2.7 / (2 * math.sin(lim)), abs=6e-3)
    lines = [ln for ln in out.splitlines() if ln.startswith("a =")]
    assert len(lines) == 6
    # Low speed: counter-steering needs a smaller front angle but raises the
    # peak lateral acceleration above the steady-state V^2 kappa = 2.5.
    peaks = [float(re.search(r"peak \|a_lat\| = +([\d.]+)", ln)[1]) for ln in lines]
    assert all(p >= 2.5 - 1e-6 for p in peaks[:3])
    assert all(p >= 4.0 - 1e-6 for p in peaks[3:5])  # 20^2 * 0.01
    assert "status = singular_steering" in lines[5]  # a = 1 at 20 m/s


def test_spline_course(tmp_path):
    out = run_example("plot_spline_course.py", tmp_path)
    assert "closed: True" in out
    ff = floats_after("feedforward + feedback: status ok, max |e| after 10 s =", out)
    fb = floats_after("feedback only: status ok, max |e| after 10 s =", out)
    # In the kinematic model the feedforward arctan(kappa f) keeps R exactly
    # on any smooth path once the errors have decayed (exp(-10) of 3 m);
    # feedback alone leaves an error that follows the curvature.
    assert ff[0] < 1e-3
    assert fb[0] > 0.1


def test_ratio_sweep(tmp_path):
    out = run_example("plot_ratio_sweep.py", tmp_path)
    # At 20 m/s on the straight road the lambda0 = -1 gains are small
    # (k1 = f lam0^2 / (V^2 (1 - a)) < 0.03 rad/m for the swept a), so every
    # run keeps |delta_f| far below 90 deg and must complete.
    line = next(
        ln
        for ln in out.splitlines()
        if ln.startswith("V = 20 m/s, straight") and "lambda0 = -1:" in ln
    )
    valid, total = map(int, re.search(r"(\d+)/(\d+) runs valid", line).groups())
    assert total > 10 and valid == total, line
    # On the curves every run ends in steady cornering, so its peak is at
    # least V^2 kappa: 2.5 m/s^2 at 5 m/s, 4 m/s^2 at 20 m/s.
    for label, bound in (("V = 5 m/s, \\kappa", 2.5), ("V = 20 m/s, \\kappa", 4.0)):
        for line in out.splitlines():
            if line.startswith(label) and "lowest peak" in line:
                peak = float(re.search(r"lowest peak ([\d.]+)", line)[1])
                assert peak >= bound - 1e-3, line


# --------------------------------------------------------------------------
# Code blocks of the documentation pages


def _python_blocks(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


DOC_PAGES = [
    p
    for p in sorted((ROOT / "docs").rglob("*.md"))
    if "_build" not in p.parts and _python_blocks(p)
]


@pytest.mark.parametrize("page", DOC_PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_doc_code_blocks_run(page, tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__docs__"}
    try:
        for i, block in enumerate(_python_blocks(page)):
            code = compile(block, f"{page.name}[block {i}]", "exec")
            exec(code, namespace)  # noqa: S102 - running the docs is the test
    finally:
        plt.close("all")


def test_getting_started_numbers():
    """The numbers quoted in docs/getting_started.md, from sympy."""
    text = (ROOT / "docs" / "getting_started.md").read_text(encoding="utf-8")
    gains = S.double_root_gains("exact")
    vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.1, S.a: -1.0, S.lam0: -1.0}
    k1 = float(gains[S.k1].subs(vals))
    k2 = float(gains[S.k2].subs(vals))
    assert f"{k1:.4f}" in text and f"{k2:.4f}" in text
