r"""docs/delay.md quotes delay margins and charts: keep its numbers in step.

The table of critical delays on the page is recomputed twice: with the
library (:func:`fws_control.paper.actuator.delay_margin_table`, compared
line by line) and with references written out here that share nothing with
the library's method (crossing frequencies of the quasi-polynomial):

* the closed form of a double-root design on the kinematic plant. The design
  makes ``d + q = (s - lam)^2`` with ``d = s^2 + nu^2``, ``nu = V kappa``, so
  ``D(s) = s^2 + nu^2 + e^{-s tau}(-2 lam s + lam^2 - nu^2)``;
  ``|d(jw)| = |q(jw)|`` is a quadratic in ``w^2`` and ``w tau = arg q(jw)``.
  On a straight road it is ``tau_c |lam| = atan(2 w)/w``, ``w^2 = 2 + sqrt 5``;
* for the rows with a steering lag, a bisection on the delay of the loop
  with a ``control.pade`` block of order 10 in front of the hand-written
  4-state plant (kinematic plant plus a first-order lag per axle), stable
  when every closed-loop pole has a negative real part.

The other numbers of the page that are cheap to recompute (the closed form,
the delayed stable fractions, the largest surviving double roots, the
rightmost roots with the realistic actuator, the peak lateral accelerations
of Figs. 6-9 with and without it) are checked the same way.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import control as ct
import numpy as np
import pytest

import fws_control as fws
from fws_control.paper.actuator import delay_margin_table
from fws_control.paper.data import PAPER_VEHICLE, REALISTIC_DELAY

PAGE = Path(__file__).resolve().parents[1] / "docs" / "delay.md"
F = 2.7  # wheelbase [m]
LAG = 0.27  # steering time constant [s]
U = math.sqrt(2.0 + math.sqrt(5.0))  # crossing frequency of lam = -1, straight
UNIT = math.atan(2.0 * U) / U  # tau_c |lam| on a straight road: 0.6474


@pytest.fixture(scope="module")
def text():
    return PAGE.read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def prose(text):
    """The page with every run of white space made one blank (for phrases)."""
    return " ".join(text.split())


def _table_lines(text: str) -> list[str]:
    start = text.index("| V [m/s] | kappa [1/m] | lambda0 [1/s] |")
    lines = []
    for line in text[start:].splitlines():
        if not line.startswith("|"):
            break
        lines.append(line)
    return lines


def _rows(text: str) -> list[list[str]]:
    return [
        [c.strip() for c in line.strip("|").split("|")]
        for line in _table_lines(text)[2:]  # skip the header and the separator
    ]


def _matches(printed: str, value: float) -> bool:
    """True if `value` rounds to the printed decimal string."""
    decimals = len(printed.split(".")[1]) if "." in printed else 0
    return math.isclose(round(value, decimals), float(printed), abs_tol=1e-12)


# --------------------------------------------------------------------------
# Independent references


def closed_form_margin(speed: float, curvature: float, pole: float) -> float:
    """Critical delay of the double-root design on the kinematic plant."""
    nu2, lam = (speed * curvature) ** 2, pole
    c = nu2 + 2.0 * lam**2
    w = math.sqrt(c + math.sqrt(c**2 - nu2**2 + (lam**2 - nu2) ** 2))
    return math.atan2(-2.0 * lam * w, lam**2 - nu2) / w


def lagged_loop(speed: float, curvature: float, pole: float, lag: float = LAG):
    """(A, b, K) of the 4-state loop x = (e, theta, delta_f_act, delta_r_act).

    Exact linearisation of the kinematic plant (c = 1 + f^2 kappa^2), ratio
    a = 0, a first-order lag on both axles; the gains put a double root at
    `pole` on the plant without lag: det(A - b K) = V^2 kappa^2 + c V^2 k1 / f
    = pole^2 and trace(A - b K) = -c V k2 / f = 2 pole.
    """
    c = 1.0 + (F * curvature) ** 2
    k1 = F * (pole**2 - (speed * curvature) ** 2) / (c * speed**2)
    k2 = -2.0 * pole * F / (c * speed)
    A = np.zeros((4, 4))
    A[0, 1], A[1, 0] = speed, -speed * curvature**2
    A[0, 3] = speed  # e' = V theta + V delta_r
    A[1, 2], A[1, 3] = c * speed / F, -speed / F
    A[2, 2] = A[3, 3] = -1.0 / lag
    b = np.array([0.0, 0.0, 1.0 / lag, 0.0])
    return A, b, np.array([k1, k2, 0.0, 0.0])


def pade_poles(A, b, K, tau, order=10):
    """Closed-loop poles of pade(tau) -> (A, b, K) with unity negative feedback."""
    num, den = ct.pade(tau, order)
    plant = ct.ss(A, b[:, None], K[None, :], 0.0)
    p = np.asarray(ct.feedback(ct.series(ct.tf(num, den), plant), 1).poles())
    return p[np.argsort(-p.real, kind="stable")]


def pade_margin(A, b, K, step=0.01, tol=1e-9):
    """First delay at which the Pade(10) loop loses stability: scan, bisection."""
    lo, hi = 0.0, step
    while pade_poles(A, b, K, hi)[0].real < 0.0:
        lo, hi = hi, hi + step
        assert hi < 3.0, "stable up to 3 s"
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if pade_poles(A, b, K, mid)[0].real < 0.0 else (lo, mid)
    return 0.5 * (lo + hi)


# --------------------------------------------------------------------------
# The table


def test_table_is_the_librarys(text):
    assert _table_lines(text) == delay_margin_table().splitlines()


def test_table_against_closed_form_and_pade(text):
    rows = _rows(text)
    assert len(rows) == 12
    straight = 0
    for V, kap, lam, ideal, lagged, survives in rows:
        V, kap, lam = float(V), float(kap), float(lam)
        ref = closed_form_margin(V, kap, lam)
        if kap == 0.0:  # the straight rows: tau_c |lam| = atan(2w)/w
            assert ref == pytest.approx(UNIT / abs(lam), rel=1e-14)
            straight += 1
        assert _matches(ideal, ref), (V, kap, lam, ideal, ref)
        # survival is the lagged margin against the realistic delay
        assert survives == ("yes" if float(lagged) > REALISTIC_DELAY else "no")
    assert straight == 6
    # Pade(10) bisection for a straight and a curved lagged row
    for V, kap, lam in ((5.0, 0.0, -2.0), (20.0, 0.01, -1.0)):
        row = next(r for r in rows if tuple(map(float, r[:3])) == (V, kap, lam))
        ref = pade_margin(*lagged_loop(V, kap, lam))
        assert _matches(row[4], ref), (V, kap, lam, row[4], ref)


# --------------------------------------------------------------------------
# Numbers in the text


def test_closed_form_numbers(prose):
    # tau_c = 0.6474 s and w_c = 2.0582 rad/s for lambda0 = -1
    assert f"$\\tau_c = {UNIT:.4f}$ s" in prose
    assert f"$\\omega_c = w|\\lambda_0| = {U:.4f}$ rad/s" in prose
    # the margins on the curves quoted next to it
    assert f"to {closed_form_margin(5.0, 0.1, -1.0):.4f} s" in prose
    assert f"to {closed_form_margin(20.0, 0.01, -1.0):.4f} s" in prose


def test_delayed_stable_fractions(prose, text):
    """10.08 %, 5.08 %, 1.67 % of the default grid: chart and Pade(10).

    The page's code block prints each chart's fraction and undecided
    points: its comment lines are those the charts give.

    The chart's fraction is the quoted one; the chart's verdicts are checked
    point by point against the eigenvalues of a Pade(10) loop at 4,000 grid
    points drawn with a fixed seed (all 160,801 points cost over a minute of
    eigenvalues and check the same verdicts), away from the boundary where
    the Pade approximation itself is the less accurate of the two.
    """
    m = re.search(
        r"shrinks from ([\d.]+) % of the grid without delay to ([\d.]+) % at "
        r"0\.24 s and ([\d.]+) % at 0\.5 s",
        prose,
    )
    quoted = [float(v) for v in m.groups()]
    (block,) = [
        b
        for b in re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
        if "ch.undecided" in b
    ]
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, curvature=0.1)
    # hand-written plant, a = -1: b = B [1, a]
    c = 1.0 + (F * 0.1) ** 2
    A = np.array([[0.0, 5.0], [-5.0 * 0.01, 0.0]])
    b = np.array([-5.0, (c + 1.0) * 5.0 / F])
    for tau, q in zip((0.0, 0.24, 0.5), quoted, strict=True):
        ch = fws.stability_chart(plant, ratio=-1.0, delay=tau)
        assert _matches(f"{q:.2f}", 100.0 * ch.stable_fraction), (tau, q)
        printed = (
            f"# delay {tau:4.2f} s: stable fraction {ch.stable_fraction:.4f}, "
            f"{ch.undecided} undecided points"
        )
        assert printed in block.splitlines(), printed
        K = np.stack(np.meshgrid(ch.k1, ch.k2), axis=-1)
        pick = np.random.default_rng(173).choice(K.shape[0] * K.shape[1], 4000)
        rows, cols = np.unravel_index(pick, K.shape[:2])
        K = K[rows, cols]
        verdict = np.asarray(ch.stable)[rows, cols]
        if tau == 0.0:
            M = A - b[:, None] * K[..., None, :]
        else:
            num, den = ct.pade(tau, 10)
            P = ct.ss(ct.tf(num, den))
            Ap, Bp, Cp, Dp = (np.asarray(x, dtype=float) for x in (P.A, P.B, P.C, P.D))
            M = np.zeros(K.shape[:-1] + (12, 12))
            M[..., :2, :2] = A - Dp[0, 0] * b[:, None] * K[..., None, :]
            M[..., :2, 2:] = b[:, None] * Cp[0]
            M[..., 2:, :2] = -Bp[:, 0][:, None] * K[..., None, :]
            M[..., 2:, 2:] = Ap
        top = np.max(np.linalg.eigvals(M).real, axis=-1)
        clear = np.abs(top) > 1e-3  # not on the boundary
        assert np.count_nonzero(clear) > 3900
        assert np.count_nonzero(verdict[clear] != (top[clear] < 0.0)) == 0, tau
        # the sample holds stable points, not only the unstable bulk
        assert np.count_nonzero(top[clear] < 0.0) > 20


def test_largest_surviving_double_roots(prose):
    """|lambda0| = 1.6096 with the lag and 2.6975 without, on a straight road."""
    m = re.search(
        r"\$\|\\lambda_0\| = 1\.61\$ 1/s on a straight road \(([\d.]+);", prose
    )
    with_lag = float(m[1])
    m = re.search(r"\$0\.6474/0\.24 = 2\.70\$ 1/s \(([\d.]+)\)", prose)
    free = float(m[1])
    assert _matches(f"{free:.4f}", UNIT / REALISTIC_DELAY)
    # the Pade margin of the lagged loop crosses 0.24 s within 1e-4 of it
    above = pade_margin(*lagged_loop(20.0, 0.0, -(with_lag - 1e-4)))
    below = pade_margin(*lagged_loop(20.0, 0.0, -(with_lag + 1e-4)))
    assert below < REALISTIC_DELAY < above


def test_rightmost_roots_with_the_realistic_actuator(prose):
    """-0.54 +- 2.09j (straight) and -0.56 +- 2.18j (5 m/s curve), lambda0 = -1."""
    for (V, kap), quoted in (
        ((20.0, 0.0), "$-0.54 \\pm 2.09j$"),
        ((5.0, 0.1), "$-0.56 \\pm 2.18j$"),
    ):
        assert quoted in prose
        top = pade_poles(*lagged_loop(V, kap, -1.0), REALISTIC_DELAY)[0]
        assert f"$-{-top.real:.2f} \\pm {abs(top.imag):.2f}j$" == quoted


def test_figs_6_to_9_peaks_with_the_actuator(text):
    """The peak table: fig6_to_9_responses with and without the actuator."""
    from fws_control.paper.scenarios import fig6_to_9_responses

    start = text.index("| scenario | $a = -1$ |")
    table = []
    for line in text[start:].splitlines()[2:]:
        if not line.startswith("|"):
            break
        table.append([c.strip() for c in line.strip("|").split("|")])
    assert len(table) == 4
    runs = {
        kind: fig6_to_9_responses(pole=-1.0, duration=30.0, **kw)
        for kind, kw in (
            ("ideal", {}),
            ("real", {"delay": REALISTIC_DELAY, "steering_lag": LAG}),
        )
    }
    for cells in table:
        name = cells[0].strip("`")
        for kind_index, kind in enumerate(("ideal", "real")):
            resp = next(r for r in runs[kind].values() if r.scenario.name == name)
            peaks = fws.tracking_metrics(resp.result).peak_lateral_accel
            for j, a in enumerate((-1.0, -0.5, 0.0, 0.5)):
                assert resp.ratios[j] == a
                printed = cells[1 + j].split("/")[kind_index].strip()
                # exact peak of the solution; 1e-4 of slack for the sampled one
                assert abs(float(printed) - peaks[j]) <= 5e-4 + 1e-4, (
                    name,
                    kind,
                    a,
                    printed,
                    peaks[j],
                )


def test_method_of_steps_against_the_pade_reference(text):
    """The printed max |e - e_ref| of the page's code block, recomputed.

    The reference is python-control's simulation of the loop with Pade blocks
    (``simulate_reference``); the largest difference is where the Pade blocks
    ring, before t = delay, so the block's first second holds it.
    """
    from fws_control.simulation import simulate_reference

    m = re.search(r"^# max \|e - e_ref\| = ([\d.e+-]+) m$", text, flags=re.M)
    assert m is not None
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
    g = fws.double_root_gains(
        fws.LateralPlant(veh, speed=5.0, curvature=0.1), ratio=-1.0, pole=-1.0
    )
    path = fws.Arc(curvature=0.1)
    kw = dict(initial_state=(0.0, -5.0, 0.0), duration=1.0, dt=0.05)
    fast = fws.simulate(fws.LateralPlant(veh, speed=5.0), path, g, delay=0.2, **kw)
    ref = simulate_reference(veh, path, g, speed=5.0, delay=0.2, **kw)
    gap = np.abs(fast.e - ref.outputs[list(ref.output_labels).index("e")])
    assert f"{gap.max():.1e}" == m[1]
    assert fast.t[np.argmax(gap)] < 0.2
