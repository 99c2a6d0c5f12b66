"""Certified stability verdicts: no false "stable" on any plant.

Every reference here is independent of the library's polynomial: mpmath
eigenvalues (50-60 digits) of the closed-loop matrix, an exact rational
Routh array (sympy ``DomainMatrix.charpoly``), or the same computation done
in the test from the matrices.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import control as ct
import matplotlib
import mpmath as mp
import numpy as np
import pytest
from conftest import PAPER_VEHICLE

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

import fws_control as fws  # noqa: E402

# the codes of StabilityVerdict.code, as documented
STABLE, NOT_STABLE, UNDECIDED = 1, 0, -1

VEH = PAPER_VEHICLE
DYN = fws.Vehicle(
    2.7, 1.35, mass=1500.0, yaw_inertia=2500.0,
    cornering_front=8e4, cornering_rear=8e4,
)  # fmt: skip


def _mp_affine(A, b, c1, c2):
    """d, n1, n2 of (A, b, c) by Faddeev-LeVerrier in 60-digit arithmetic."""
    n = A.shape[0]
    with mp.workdps(60):
        Am, bm = mp.matrix(A.tolist()), mp.matrix(b.tolist())
        M, d, Ms = mp.zeros(n, n), [mp.mpf(1)], []
        for k in range(1, n + 1):
            M = Am * M + d[-1] * mp.eye(n)
            Ms.append(M)
            d.append(-sum((Am * M)[i, i] for i in range(n)) / k)

        def num(c):
            cm = mp.matrix([c.tolist()])
            return [mp.mpf(0)] + [(cm * Mk * bm)[0, 0] for Mk in Ms]

        return d, num(c1), num(c2)


def _mp_rightmost(A, b, kc) -> float:
    with mp.workdps(60):
        M = mp.matrix(A.tolist()) - mp.matrix(b.tolist()) * mp.matrix([kc.tolist()])
        return float(max(mp.re(e) for e in mp.eig(M, left=False, right=False)))


def _spread_plant(seed: int):
    """Order-6 plant, open-loop poles -1e-3 .. -1e3 (random factors 0.5-2),
    and gains (ratio 0) that put a closed-loop root at +sigma, sigma from
    the 60-digit polynomial."""
    rng = np.random.default_rng(seed)
    n = 6
    lam = -np.logspace(-3, 3, n) * rng.uniform(0.5, 2, n)
    V = rng.normal(size=(n, n))
    A = V @ np.diag(lam) @ np.linalg.inv(V)
    B = rng.normal(size=(n, 2))
    C = rng.normal(size=(2, n))
    sys = ct.ss(A, B, C, 0, inputs=["delta_f", "delta_r"], outputs=["e", "theta"])
    d, n1, n2 = _mp_affine(A, B[:, 0], C[0], C[1])
    sigma = 10 ** rng.uniform(-4, -1)
    t = rng.normal()
    with mp.workdps(60):
        k1 = float(
            -mp.polyval(d, sigma) / (mp.polyval(n1, sigma) + t * mp.polyval(n2, sigma))
        )
    return sys, A, B, C, fws.SteeringGains(k1, t * k1, ratio=0.0), sigma


@pytest.mark.parametrize("seed", [253, 5])
def test_order6_spread_poles_unstable_root_is_not_stable(seed):
    """Two order-6 plants with a closed-loop eigenvalue at +0.0125 and
    +0.0081 (60 digits): the floating-point Faddeev-LeVerrier polynomial
    called them stable."""
    sys, A, B, C, g, sigma = _spread_plant(seed)
    kc = g.k1 * C[0] + g.k2 * C[1]
    mu = _mp_rightmost(A, B[:, 0], kc)
    assert mu == pytest.approx(sigma, rel=1e-9) and mu > 0.008
    assert not fws.is_stable(sys, g)
    assert fws.stability_verdict(sys, g).code == NOT_STABLE
    # the polynomial's roots are the eigenvalues, to 1e-9 relative
    with mp.workdps(60):
        M = mp.matrix(A.tolist()) - mp.matrix(B[:, 0].tolist()) * mp.matrix(
            [kc.tolist()]
        )
        ev = sorted(
            (complex(e) for e in mp.eig(M, left=False, right=False)),
            key=lambda z: (z.real, z.imag),
        )
    roots = sorted(
        np.roots(fws.characteristic_polynomial_coefficients(sys, g)),
        key=lambda z: (z.real, z.imag),
    )
    for r, e in zip(roots, ev, strict=True):
        assert abs(r - e) <= 1e-9 * abs(e)


def test_coefficients_are_correctly_rounded_against_60_digits():
    sys, A, B, C, _, _ = _spread_plant(253)
    cp = fws.affine_characteristic_polynomial(sys, ratio=0.0)
    d, n1, n2 = _mp_affine(A, B[:, 0], C[0], C[1])
    for got, ref, err in (
        (cp.open_loop, d, cp.open_loop_error),
        (cp.n1, n1, cp.n1_error),
        (cp.n2, n2, cp.n2_error),
    ):
        for j, r in enumerate(ref):
            # rounded once: within half an ulp, and inside the stated bound
            assert abs(mp.mpf(float(got[j])) - r) <= 0.5 * np.spacing(abs(float(r)))
            assert abs(mp.mpf(float(got[j])) - r) <= err[j] + 1e-300


@pytest.mark.parametrize("matrix", ["A", "B", "C", "D"])
def test_non_finite_plant_refused_once_in_as_plant(matrix):
    mats = {
        "A": np.array([[0.0, 5.0], [0.0, 0.0]]),
        "B": np.array([[0.0, 5.0], [1.85, -1.85]]),
        "C": np.eye(2),
        "D": np.zeros((2, 2)),
    }
    mats[matrix][1, 0] = np.nan
    sys = ct.ss(*mats.values(), states=["e", "theta"], inputs=["delta_f", "delta_r"],
                outputs=["e", "theta"])  # fmt: skip
    g = fws.SteeringGains(0.1, 0.5, ratio=0.0)
    calls = [
        lambda: fws.as_plant(sys),
        lambda: fws.is_stable(sys, g),
        lambda: fws.stability_verdict(sys, g),
        lambda: fws.closed_loop(sys, g),
        lambda: fws.characteristic_polynomial_coefficients(sys, g),
        lambda: fws.critical_delay(sys, g),
        lambda: fws.gain_locus(sys, g),
        lambda: fws.rightmost_roots(sys, g, delay=0.1),
        lambda: fws.stability_chart(sys, ratio=0.0, delay=0.1),
        lambda: fws.double_root_gains(sys, ratio=-0.5, pole=-1.0),
    ]
    for call in calls:
        with pytest.raises(ValueError, match=rf"{matrix}\[1, 0\] = nan"):
            call()


def test_stiff_steering_lag_verdicts_against_mpmath():
    """steering_lag=1e-12 (poles at -1e12): every chart verdict agrees with
    60-digit eigenvalues; double-precision eigenvalues do not (they put
    stable points at Re ~ +1e-4)."""
    k = np.linspace(-1.0, 1.0, 5)
    plant = fws.LateralPlant(
        DYN, speed=1.0, curvature=0.05, model="dynamic", steering_lag=1e-12
    )
    ratio = 0.9
    ch = fws.stability_chart(plant, ratio=ratio, k1=k, k2=k)
    v = fws.stability_verdict(
        plant, fws.SteeringGains(k[None, :], k[:, None], ratio=ratio)
    )
    lm = fws.loop_matrices(plant)
    b = lm.input_vector(ratio)
    wrong_double = 0
    for i, k2 in enumerate(k):
        for j, k1 in enumerate(k):
            kc = k1 * lm.c_e + k2 * lm.c_theta
            mu = _mp_rightmost(lm.A, b, kc)
            dbl = np.linalg.eigvals(lm.A - np.outer(b, kc)).real.max()
            wrong_double += (mu < 0) != (dbl < 0)
            if v.code[i, j] == UNDECIDED:
                assert abs(mu) <= v.bound[i, j]
                assert not ch.stable[i, j]
            else:
                assert (v.code[i, j] == STABLE) == (mu < 0)
                assert ch.stable[i, j] == (mu < 0)
    assert np.count_nonzero(ch.stable) > 0
    assert wrong_double > 0  # why the reference must be extended precision


def test_delayed_chart_shows_undecided_points():
    """Roots at +-j V kappa for k = (0, 0): the count is undecided and the
    chart says so, in `verdict`, `undecided`, the legend and the notes."""
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.01)
    k = np.linspace(-1.0, 1.0, 5)
    ch = fws.stability_chart(plant, ratio=0.0, k1=k, k2=k, delay=0.1)
    # reference: the closed loop at k = 0 is the open loop, eigenvalues
    # +-j V kappa (written out here), whatever the delay
    ev = np.linalg.eigvals(np.array([[0.0, 5.0], [-5.0 * 0.01**2, 0.0]]))
    assert np.allclose(ev.real, 0.0) and np.allclose(abs(ev.imag), 0.05)
    assert ch.verdict[2, 2] == UNDECIDED and not ch.stable[2, 2]
    assert ch.undecided == np.count_nonzero(ch.verdict == UNDECIDED) >= 1
    cplt = ch.plot()
    labels = [t.get_text() for t in cplt.legend.get_texts()]
    assert any(t.startswith("undecided (") for t in labels)
    assert any("undecided" in n for n in ch.notes())
    plt.close(cplt.figure)


def test_root_at_zero_is_not_stable_with_any_delay():
    """Straight path, k1 = 0: p(0) = 0 exactly, a root at s = 0 for every
    delay; the argument principle cannot count it, the verdict is decided."""
    plant = fws.LateralPlant(VEH, speed=5.0)
    k2 = np.linspace(-1.0, 1.0, 5)
    v = fws.stability_verdict(plant, fws.SteeringGains(0.0, k2, ratio=0.0), delay=0.1)
    # reference: A - b k has a zero first column when k1 = 0 (e = 0 is not fed
    # back and A's first column is 0), so s = 0 is an eigenvalue
    lm = fws.loop_matrices(plant)
    for kk in k2:
        Acl = lm.A - np.outer(lm.input_vector(0.0), kk * lm.c_theta)
        assert np.min(abs(np.linalg.eigvals(Acl))) == 0.0
    assert np.all(v.code == NOT_STABLE)


def test_interval_routh_on_boundary_points_is_never_stable():
    """Points on p1 = 0 (roots at +-j omega, exact in floating point for
    ratio 0): undecided or not stable, never stable."""
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
    v = fws.stability_verdict(
        plant, fws.SteeringGains(np.linspace(0.1, 1, 10), 0.0, ratio=0.0)
    )
    assert not np.any(v.stable)
    # reference: p(s) = s^2 + V^2 (c k1 + f kappa^2)/f has imaginary roots
    c = 1 + (2.7 * 0.1) ** 2
    w2 = 25.0 * (c * np.linspace(0.1, 1, 10) + 2.7 * 0.01) / 2.7
    assert np.all(w2 > 0)


def _verdict_check():
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "verdict_check.py"
    spec = importlib.util.spec_from_file_location("verdict_check", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_random_spread_plants_no_wrong_verdict():
    """A fixed-seed sample of benchmarks/verdict_check.py's generator (the
    full run: 1e5 plants): 0 wrong verdicts, every undecided point within
    its bound."""
    counts = _verdict_check().check(150, seed=7)
    assert counts["plants"] == 150
    assert counts["wrong_stable"] == 0
    assert counts["wrong_unstable"] == 0
    assert counts["undecided_outside_bound"] == 0
    assert counts["decided"] + counts["undecided"] == 150
    assert counts["exact"] > 0  # near-axis points reached the exact reference


def test_exact_reference_agrees_with_mpmath_near_the_axis():
    """The benchmark's exact Routh reference against 50-digit eigenvalues on
    the near-axis points it is used for."""
    vc = _verdict_check()
    rng = np.random.default_rng(11)
    checked = 0
    while checked < 6:
        sys, g, (A, B, C) = vc.random_plant(rng)
        lo, hi = vc.reference_interval(A, B, C, g)
        if lo > 0 or hi < 0 or A.shape[0] > 5:
            continue
        ex = vc.exact_stable(A, B, C, g)
        if ex is None:
            continue
        assert ex == (vc.exact_rightmost(A, B, C, g) < 0)
        assert ex == fws.is_stable(sys, g)
        checked += 1
