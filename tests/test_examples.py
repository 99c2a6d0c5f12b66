"""The gallery examples' numbers, and the documentation's code, checked.

The examples (``examples/plot_*.py``) run end to end in the documentation
build: sphinx-gallery executes each one and ``sphinx -W`` fails on an
exception. What the examples show is checked here, cheaply: each test
makes the library calls its example makes, at the example's parameters
(kept equal by hand: a change of an example's scenario changes its test),
on a smaller gain grid where the number is a fraction of a grid checked
point by point, and compares the values the example prints against
references computed here independently of the code under test
(python-control's numerical linearisation of the nonlinear model, the
paper's printed formulas in sympy, hand-derived values). One example, the
cheapest, is also run as a script (``MPLBACKEND=Agg``), the branch the
documentation build does not take: it must save its figures to PNG files
and print their names. The ```python`` blocks of the Markdown pages under
``docs/`` run in order, one namespace per page (the documentation build
does not run them).
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
from conftest import PAPER_VEHICLE
from scipy.optimize import brentq

import fws_control as fws
from fws_control import symbolic as S
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG
from fws_control.paths import Arc, Spline, Straight
from fws_control.turning import turning_radius

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("plot_*.py"))
VEH = PAPER_VEHICLE


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
    # Without a display (Agg) the example saves its figures and says where:
    # every file it names exists, is a PNG image with content, and nothing
    # else was written.
    saved = [
        f.strip()
        for line in proc.stdout.splitlines()
        if line.startswith("saved ")
        for f in line[len("saved ") :].split(",")
    ]
    assert saved, f"{name} saved no figure on the Agg backend"
    for f in saved:
        data = (tmp_path / f).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000, (name, f)
    assert {p.name for p in tmp_path.glob("*.png")} == set(saved), name
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
        "plot_any_plant.py",  # (also run as a script, below)
        "plot_delay.py",
        "plot_design_delay.py",
        "plot_dynamic.py",
        "plot_fws_vs_4ws.py",
        "plot_openloop.py",
        "plot_quick_start.py",
        "plot_ratio_sweep.py",
        "plot_root_loci.py",
        "plot_spline_course.py",
        "plot_stability_chart.py",
        "plot_varying_speed.py",  # (its table: tests/test_varying_speed_doc.py)
    }
    assert {p.name for p in EXAMPLES} == tested
    script_mode = re.compile(
        r'^if "sphinx_gallery" not in (?:sys\.)?modules and '
        r"matplotlib\.get_backend\(\)\.lower\(\) in \(",
        flags=re.M,
    )
    for path in EXAMPLES:
        text = path.read_text(encoding="utf-8")
        head = text.lstrip()
        # sphinx-gallery needs a docstring with a title underlined by '='.
        assert head.startswith('"""'), path.name
        assert re.search(r"\n=+\n", head.split('"""')[1]), path.name
        # Every example ends in the script-mode block that test_any_plant
        # runs: save the figures and name them, or show them.
        block = script_mode.search(text)
        assert block, path.name
        tail = text[block.start() :]
        assert ".savefig(" in tail and 'print("saved ' in tail, path.name
        assert tail.rstrip().endswith("plt.show()"), path.name


def test_quick_start():
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    # The gains make trace = -2 and det = 1 (double root at -1) in the
    # numerically linearised nonlinear model.
    A, B = numeric_jacobians(5.0, 0.1)
    M = closed_loop_matrix(A, B, g.k1, g.k2, -1.0)
    assert np.trace(M) == pytest.approx(-2.0, abs=2e-3)
    assert np.linalg.det(M) == pytest.approx(1.0, abs=2e-3)
    assert fws.is_stable(plant, g) and np.all(np.linalg.eigvals(M).real < 0)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(curvature=0.1),
        g,
        initial_state=(0.0, -5.0, 0.0),
        duration=15.0,
    )
    assert res.status == "ok"
    assert abs(res.e[-1]) < 1e-3
    # The paper's gains (eqs. 45-46, sympy) in the numeric linearisation.
    paper_plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, model="paper")
    g_paper = fws.double_root_gains(paper_plant, ratio=-1.0, pole=-1.0)
    vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.1, S.a: -1.0, S.lam0: -1.0}
    paper = S.paper_gain_formulas()["45-46"]
    pk1, pk2 = (float(paper[k].subs(vals)) for k in (S.k1, S.k2))
    true = np.sort(np.linalg.eigvals(closed_loop_matrix(A, B, pk1, pk2, -1.0)).real)
    poles = np.sort(fws.closed_loop(plant, g_paper).poles().real)
    assert poles == pytest.approx(true, abs=2e-3)


def test_stability_chart():
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
    g = np.linspace(-1.0, 1.0, 301)
    chart = fws.stability_chart(plant, ratio=-1.0, k1=g, k2=g, pole=-1.0)
    # Brute force: eigenvalues of the numerically linearised closed loop on
    # the example's 301 x 301 grid.
    A, B = numeric_jacobians(5.0, 0.1)
    K1, K2 = np.meshgrid(g, g)
    Bu = B @ np.array([1.0, -1.0])  # delta_r = a*delta_f, a = -1
    M = A - Bu[:, None] * np.stack([K1, K2], axis=-1)[..., None, :]
    stable = np.all(np.linalg.eigvals(M).real < 0, axis=-1)
    assert chart.stable_fraction == pytest.approx(stable.mean(), abs=2e-3)
    # Both models' designs: exact gains satisfy eqs. (39)-(40) of the sympy
    # exact model, the paper's those of eq. (34) as printed.
    for model in ("kinematic", "paper"):
        ch = fws.stability_chart(
            fws.LateralPlant(VEH, speed=5.0, curvature=0.2, model=model),
            ratio=0.5,
            k1=g,
            k2=np.linspace(-1.0, 2.0, 451),
            pole=-1.0,
        )
        p = S.characteristic_polynomial(model).all_coeffs()
        vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.2, S.a: 0.5}
        vals.update({S.k1: ch.design.k1, S.k2: ch.design.k2})
        assert float(p[1].subs(vals)) == pytest.approx(2.0, abs=5e-3)
        assert float(p[2].subs(vals)) == pytest.approx(1.0, abs=5e-3)


def test_root_loci():
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    poles = ct.root_locus_map(fws.gain_loop(plant, g), gains=[1.0]).loci[0]
    assert poles == pytest.approx([-1.0, -1.0], abs=1e-6)
    # Paper's gains (eqs. 45-46) at a = 0.5 in the numeric linearisation.
    vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.1, S.a: 0.5, S.lam0: -1.0}
    paper = S.paper_gain_formulas()["45-46"]
    pk1, pk2 = (float(paper[k].subs(vals)) for k in (S.k1, S.k2))
    A, B = numeric_jacobians(5.0, 0.1)
    true = np.linalg.eigvals(closed_loop_matrix(A, B, pk1, pk2, 0.5))
    locus = fws.parameter_locus(
        plant,
        g,
        parameter="ratio",
        values=[0.5],
        redesign_pole=-1.0,
        design_model="paper",
    )
    assert np.sort_complex(locus.loci[0]) == pytest.approx(
        np.sort_complex(true), abs=2e-3
    )


def test_any_plant(tmp_path):
    """The example run as a script, and the numbers it prints."""
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


def _as_printed(value: float) -> float:
    """The value as the examples print it, to two decimals."""
    return float(f"{value:.2f}")


def test_fws_vs_4ws():
    # Steady turning radius of R with the front wheels at 35 degrees:
    # f / tan(35 deg) for a = 0 and f / (2 sin(35 deg)) for a = -1.
    lim = math.radians(35.0)
    r0, r1 = turning_radius(VEH, ratio=[0.0, -1.0], max_steer_front=lim).rear_axle
    assert r0 == pytest.approx(2.7 / math.tan(lim), abs=6e-3)
    assert r1 == pytest.approx(2.7 / (2 * math.sin(lim)), abs=6e-3)

    def run(speed, curvature, e0, ratios):  # the example's runs
        plant = fws.LateralPlant(VEH, speed=speed, curvature=curvature)
        return fws.simulate_batch(
            fws.LateralPlant(VEH, speed=speed),
            Arc(curvature=curvature),
            fws.double_root_gains(plant, ratio=np.array(ratios), pole=-1.0),
            initial_state=(0.0, e0, 0.0),
            duration=15.0,
            dt=0.02,
            progress=False,
        )

    # Low speed: counter-steering needs a smaller front angle but raises the
    # peak lateral acceleration above the steady-state V^2 kappa = 2.5.
    low = run(5.0, 0.1, -5.0, [0.0, -0.5, -1.0])
    high = run(20.0, 0.01, -10.0, [0.0, 0.5])
    for batch, steady in ((low, 2.5), (high, 4.0)):  # 4.0 = 20^2 * 0.01
        for r in batch:
            assert _as_printed(np.max(np.abs(r.lateral_accel))) >= steady - 1e-6
    (one,) = run(20.0, 0.01, -10.0, [1.0])  # a = 1 at 20 m/s
    assert one.status == "singular_steering"


def test_spline_course():
    waypoints = 2.0 * np.array(
        [[0, 0], [30, 0], [55, 8], [70, 30], [60, 55], [35, 60], [20, 45],
         [5, 50], [-15, 40], [-20, 15], [0, 0]],
        dtype=float,
    )  # fmt: skip
    course = Spline(waypoints)
    assert course.closed
    g = fws.double_root_gains(fws.LateralPlant(VEH, speed=6.0), ratio=-0.5, pole=-1.0)
    late = {}
    for ff in (True, False):
        r = fws.simulate(
            fws.LateralPlant(VEH, speed=6.0),
            course,
            g,
            initial_state=(0.0, -3.0, 0.2),
            duration=course.length / 6.0,
            feedforward=ff,
            dt=0.05,
        )
        assert r.status == "ok"
        late[ff] = np.max(np.abs(r.e[r.t > 10.0]))
    # In the kinematic model the feedforward arctan(kappa f) keeps R exactly
    # on any smooth path once the errors have decayed (exp(-10) of 3 m);
    # feedback alone leaves an error that follows the curvature.
    assert late[True] < 1e-3
    assert late[False] > 0.1


def test_ratio_sweep():
    ratios = np.linspace(-1.5, 1.5, 46)  # the example's sweep

    def sweep(speed, kappa, e0, pole):
        """(peak |lateral accel|, valid) of each run, as the example."""
        plant = fws.LateralPlant(VEH, speed=speed, curvature=kappa)
        batch = fws.simulate_batch(
            fws.LateralPlant(VEH, speed=speed),
            Straight() if kappa == 0.0 else Arc(curvature=kappa),
            fws.double_root_gains(plant, ratio=ratios, pole=pole),
            initial_state=(0.0, e0, 0.0),
            duration=15.0,
            feedforward=kappa != 0.0,
            dt=0.02,
            progress=False,
        )
        steer = np.where(np.isnan(batch.delta_f), 0.0, np.abs(batch.delta_f))
        valid = batch.ok & np.all(steer < np.pi / 2, axis=1)
        acc = np.where(valid[:, None], np.abs(batch.lateral_accel), 0.0)
        return np.where(valid, acc.max(axis=1), np.nan), valid

    # At 20 m/s on the straight road the lambda0 = -1 gains are small
    # (k1 = f lam0^2 / (V^2 (1 - a)) < 0.03 rad/m for the swept a), so every
    # run keeps |delta_f| far below 90 deg and must complete.
    _, valid = sweep(20.0, 0.0, 2.0, -1.0)
    assert np.all(valid)
    # On the curves every run ends in steady cornering, so its peak is at
    # least V^2 kappa: 2.5 m/s^2 at 5 m/s, 4 m/s^2 at 20 m/s.
    for speed, kappa, e0, bound in ((5.0, 0.1, -5.0, 2.5), (20.0, 0.01, -10.0, 4.0)):
        for pole in (-1.0, -2.0):
            peak, _ = sweep(speed, kappa, e0, pole)
            assert _as_printed(np.nanmin(peak)) >= bound - 1e-3, (speed, pole)


def _pade_loop_abscissa(A, b, K, tau, order=10):
    """Largest real part of the poles of pade(tau) -> (A, b, K), unity feedback.

    The loop x' = A x + b u, u = -K x(t - tau) with the delay replaced by
    control.pade of the given order. A and b may carry leading grid axes
    (vectorised over gain points through numpy eigenvalues).
    """
    if tau == 0.0:
        M = A - b[..., :, None] * K[..., None, :]
        return np.max(np.linalg.eigvals(M).real, axis=-1)
    num, den = ct.pade(tau, order)
    P = ct.ss(ct.tf(num, den))
    Ap, Bp, Cp, Dp = (np.asarray(m, dtype=float) for m in (P.A, P.B, P.C, P.D))
    n, m = A.shape[-1], Ap.shape[0]
    shape = np.broadcast_shapes(A.shape[:-2], K.shape[:-1])
    M = np.zeros(shape + (n + m, n + m))
    # command v = -K x enters the Pade block; its output drives the plant
    M[..., :n, :n] = A - Dp[0, 0] * b[..., :, None] * K[..., None, :]
    M[..., :n, n:] = b[..., :, None] * Cp[0]
    M[..., n:, :n] = -Bp[:, 0][:, None] * K[..., None, :]
    M[..., n:, n:] = Ap
    return np.max(np.linalg.eigvals(M).real, axis=-1)


def _pade_critical_delay(A, b, K, step=0.01, tol=1e-8):
    """First delay at which the Pade(10) loop loses stability (scan + bisection)."""
    lo, hi = 0.0, step
    while _pade_loop_abscissa(A, b, K, hi) < 0.0:
        lo, hi = hi, hi + step
        assert hi < 5.0
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _pade_loop_abscissa(A, b, K, mid) < 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


def _lagged_straight_loop(speed, pole, lag):
    """Kinematic straight-road plant with a first-order lag T on both axles.

    x = (e, theta, delta_f_act, delta_r_act), ratio a = 0, written out by hand;
    the double-root gains of the lag-free plant with a = 0 solve
    det(A - b K) = V^2 k1 / f = lambda0^2 and trace = -V k2 / f = 2 lambda0.
    """
    f = VEH.wheelbase
    k1, k2 = f * pole**2 / speed**2, -2.0 * pole * f / speed
    A = np.zeros((4, 4))
    A[0, 1] = speed
    A[0, 3] = speed  # e' = V theta + V delta_r
    A[1, 2], A[1, 3] = speed / f, -speed / f  # theta' = V (delta_f - delta_r) / f
    A[2, 2] = A[3, 3] = -1.0 / lag
    b = np.array([0.0, 0.0, 1.0 / lag, 0.0])  # delta_r = a delta_f = 0
    return A, b, np.array([k1, k2, 0.0, 0.0])


def test_delay():
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    # The design: a double root at -1 of the numerically linearised
    # nonlinear model on the 5 m/s curve.
    A, B = numeric_jacobians(5.0, 0.1)
    M = closed_loop_matrix(A, B, g.k1, g.k2, -1.0)
    assert np.trace(M) == pytest.approx(-2.0, abs=2e-3)
    assert np.linalg.det(M) == pytest.approx(1.0, abs=2e-3)
    # Its critical delay in closed form: with the double root the loop is
    # D(s) = s^2 + nu^2 + e^{-s tau}(-2 lam s + lam^2 - nu^2), nu = V kappa;
    # |d(jw)| = |q(jw)| is a quadratic in w^2, and w tau = arg q(jw).
    lam, nu = -1.0, 5.0 * 0.1
    c = nu**2 + 2 * lam**2
    w = math.sqrt(c + math.sqrt(c**2 - nu**4 + (lam**2 - nu**2) ** 2))
    tau_c = math.atan2(-2 * lam * w, lam**2 - nu**2) / w
    cd = fws.critical_delay(plant, g)
    assert cd.delay == pytest.approx(tau_c, abs=1e-4)
    assert cd.frequency == pytest.approx(w, abs=1e-4)
    # The delayed charts, point by point against the loop with a Pade(10)
    # block in the numerically linearised plant (eigenvalues at every grid
    # point), on a 61 x 61 subgrid of the example's 301 x 301 grid; a point
    # may differ on the boundary (a root within the frequency resolution of
    # the axis, or the Pade block's error there).
    g1, g2 = np.linspace(-0.1, 0.8, 61), np.linspace(-0.1, 1.5, 61)
    K = np.stack(np.meshgrid(g1, g2), axis=-1)  # (k2 rows, k1 columns, 2)
    b = B @ np.array([1.0, -1.0])
    for tau in (0.0, REALISTIC_DELAY, 0.5):
        ch = fws.stability_chart(plant, ratio=-1.0, k1=g1, k2=g2, delay=tau, pole=-1.0)
        ref = _pade_loop_abscissa(A, b, K, tau) < 0.0
        assert np.mean(ch.stable != ref) <= 2e-3, tau
        assert 0 < np.count_nonzero(ch.stable) < ch.stable.size  # both classes
    # Delay margins on the straight road: closed form without the lag,
    # tau_c |lambda0| = atan(2 w)/w with w^2 = 2 + sqrt(5); a Pade(10)
    # bisection on the hand-written 4-state lagged loop with it.
    assert (REALISTIC_DELAY, REALISTIC_STEERING_LAG) == (0.24, 0.27)
    straight = fws.LateralPlant(VEH, speed=20.0)
    lagged = fws.LateralPlant(VEH, speed=20.0, steering_lag=REALISTIC_STEERING_LAG)

    def margin(pole, with_lag):  # the example's
        on = lagged if with_lag else straight
        ch = fws.delay_margin_chart(on, ratio=0.0, pole=pole, design_plant=straight)
        return float(ch.delay[0, 0])

    w0 = math.sqrt(2.0 + math.sqrt(5.0))
    unit = math.atan(2.0 * w0) / w0
    for lam in (-1.0, -2.0, -3.0):
        assert margin(lam, False) == pytest.approx(unit / abs(lam), abs=1e-4)
        ref = _pade_critical_delay(*_lagged_straight_loop(20.0, lam, 0.27))
        assert margin(lam, True) == pytest.approx(ref, abs=1e-4), lam
    # The largest surviving |lambda0| (the example's root search): 0.24 s is
    # the closed-form margin there, and the Pade margin of the lagged loop
    # crosses 0.24 s within -/+ 0.002 of it.
    free, with_lag = (
        brentq(lambda m, w=w: margin(-m, w) - REALISTIC_DELAY, 0.3, 4.0)
        for w in (False, True)
    )
    assert free == pytest.approx(unit / 0.24, abs=1e-4)
    above = _pade_critical_delay(*_lagged_straight_loop(20.0, -(with_lag - 2e-3), 0.27))
    below = _pade_critical_delay(*_lagged_straight_loop(20.0, -(with_lag + 2e-3), 0.27))
    assert below < 0.24 < above


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
    gains = S.double_root_gains("kinematic")
    vals = {S.V: 5.0, S.f: 2.7, S.kappa: 0.1, S.a: -1.0, S.lam0: -1.0}
    k1 = float(gains[S.k1].subs(vals))
    k2 = float(gains[S.k2].subs(vals))
    assert f"{k1:.4f}" in text and f"{k2:.4f}" in text


def test_dynamic():
    # The example's charts on a 51 x 51 subgrid of its 201 x 201 grid,
    # against brute force there: eigenvalues of the closed loop built on
    # control.linearize of the nonlinear dynamic path model (straight path,
    # ratio 0).
    veh = fws.vehicles.BMW_320I
    k1 = np.linspace(-0.2, 0.6, 51)
    k2 = np.linspace(-0.5, 1.5, 51)
    K1, K2 = np.meshgrid(k1, k2)
    for speed in (10.0, 20.0, 30.0):
        plant = fws.LateralPlant(veh, speed=speed, model="dynamic")
        chart = fws.stability_chart(plant, ratio=0.0, k1=k1, k2=k2)
        nl = fws.dynamics.dynamic_path_model(veh, speed=speed)
        lin = ct.linearize(nl, np.zeros(5), [0.0, 0.0])
        A, b = np.asarray(lin.A)[1:, 1:], np.asarray(lin.B)[1:, 0]
        row = np.stack([K1, K2, 0 * K1, 0 * K1], axis=-1)
        eig = np.linalg.eigvals(A - b[:, None] * row[..., None, :])
        frac = np.mean(np.all(eig.real < 0, axis=-1))
        assert chart.stable_fraction == pytest.approx(frac, abs=0.01)
    # drift speed: the dominant poles of the kinematic design on the dynamic
    # plant are 25 % of |lambda0| away there (python-control eigenvalues)
    v = fws.kinematic_design_limit(veh, ratio=0.0, pole=-1.0).drift_speed
    for speed, side in ((v - 0.1, -1), (v + 0.1, 1)):
        g = fws.double_root_gains(
            fws.LateralPlant(veh, speed=speed), ratio=0.0, pole=-1.0
        )
        lin = ct.linearize(fws.dynamics.dynamic_path_model(veh, speed=speed),
                           np.zeros(5), [0.0, 0.0])  # fmt: skip
        A, b = np.asarray(lin.A)[1:, 1:], np.asarray(lin.B)[1:, 0]
        p = np.linalg.eigvals(A - np.outer(b, [g.k1, g.k2, 0.0, 0.0]))
        drift = np.max(np.abs(p[np.argsort(-p.real)][:2] + 1.0))
        assert side * (drift - 0.25) > 0


def test_design_delay():
    plant = fws.LateralPlant(VEH, speed=20.0, steering_lag=REALISTIC_STEERING_LAG)
    best = fws.most_stable_gains(plant, delay=REALISTIC_DELAY, ratio=0.0, grid=6)
    k1, k2, alpha = best.gains.k1, best.gains.k2, best.abscissa
    # the gains' rightmost root, by a 12th-order Pade loop written here
    # (straight kinematic plant at 20 m/s, 0.27 s lag on each axle, a = 0)
    V, f, lag, tau = 20.0, 2.7, 0.27, 0.24
    A = np.zeros((4, 4))
    A[0, 1] = A[0, 3] = V
    A[1, 2], A[1, 3] = V / f, -V / f
    A[2, 2] = A[3, 3] = -1.0 / lag
    b = np.array([0.0, 0.0, 1.0 / lag, 0.0])
    P = ct.ss(ct.tf(*ct.pade(tau, 12)))
    K = np.array([k1, k2, 0.0, 0.0])
    top = np.hstack([A - P.D[0, 0] * np.outer(b, K), np.outer(b, P.C[0])])
    bottom = np.hstack([-np.outer(P.B[:, 0], K), P.A])
    ref = np.max(np.linalg.eigvals(np.vstack([top, bottom])).real)
    assert alpha == pytest.approx(ref, abs=2e-4)
    assert alpha == pytest.approx(-0.9156, abs=1e-4)  # docs/design_delay.md
    assert best.certified
    # the front: margins from the knee to three times it, and the decay
    # rates of docs/design_delay.md at 2.460 s and 3.690 s
    front = fws.pareto_front(plant, delay=REALISTIC_DELAY, points=3, design=best)
    assert front.margin == pytest.approx([1.230, 2.460, 3.690], abs=1e-3)
    assert front.margin_decay == pytest.approx([0.9156, 0.2912, 0.1858], abs=1e-4)


def test_openloop():
    """The numbers of plot_openloop.py against the textbook linear model."""
    veh = fws.vehicles.BMW_320I
    u = 20.0
    m, iz, f = veh.mass, veh.yaw_inertia, veh.wheelbase
    lr = veh.rear_to_cg
    lf = f - lr
    cf, cr = veh.cornering_front, veh.cornering_rear
    a_zero = (-lr + m * lf * u**2 / (f * cr)) / (lf + m * lr * u**2 / (f * cf))
    for ratio, a in ((0.0, 0.0), (fws.zero_sideslip_ratio, a_zero)):
        # steady yaw rate of the textbook model: -C A^-1 B for 0.02 rad
        A = np.array(
            [
                [-(cf + cr) / (m * u), -u - (lf * cf - lr * cr) / (m * u)],
                [
                    -(lf * cf - lr * cr) / (iz * u),
                    -(lf**2 * cf + lr**2 * cr) / (iz * u),
                ],
            ]
        )
        B = np.array([(cf + a * cr) / m, (lf * cf - a * lr * cr) / iz])
        r_ss = -np.linalg.solve(A, B)[1] * 0.02
        linear, nonlinear = (
            fws.step_steer(
                veh, speed=u, amplitude=0.02, ratio=ratio, model=model, tyre=tyre
            ).yaw_rate_metrics.steady_state
            for model, tyre in (("linear", "linear"), ("nonlinear", "magic"))
        )
        assert linear == pytest.approx(r_ss, abs=6e-5)
        assert nonlinear == pytest.approx(r_ss, rel=2e-3)
    # Frequency responses at every sixth frequency of the example's sweep
    # (both ends included): the small-amplitude nonlinear sweep is the
    # linear model's; at 0.06 rad the saturating tyre loses gain.
    omega = 2 * math.pi * np.geomspace(0.1, 5.0, 25)[::6]
    lin = fws.steering_frequency_response(veh, speed=u, omega=omega)
    small = fws.steering_frequency_response(
        veh, speed=u, omega=omega, model="nonlinear", amplitude=1e-4
    )
    big = fws.steering_frequency_response(
        veh, speed=u, omega=omega, model="nonlinear", tyre="magic", amplitude=0.06
    )
    assert np.max(np.abs(small.yaw_rate_gain / lin.yaw_rate_gain - 1.0)) < 1e-6
    kept = big.lateral_acceleration_gain / lin.lateral_acceleration_gain
    assert kept.min() < 0.95
    # on the 100 m circle at low a_y the front angle is the Ackermann f/R
    circle = fws.steady_state_circle(
        veh, radius=100.0, lateral_acceleration=np.linspace(0.5, 10.0, 39), ratio=0.0
    )
    assert math.degrees(circle.delta_f[0]) == pytest.approx(
        math.degrees(f / 100.0), abs=2e-3
    )
