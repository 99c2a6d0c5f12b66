"""Verdicts of ``stability_verdict`` against extended-precision eigenvalues.

Random plants of order 2 to 8 whose open-loop poles spread over up to eight
decades (real poles and complex pairs, a few unstable; eigenvector basis a
random Gaussian matrix), random inputs and outputs, and one gain point per
plant: a third random, a third placing a closed-loop root at a distance of
1e-4 to 1e-1 of the slowest pole's scale from the imaginary axis (either
side), a third at 1e-12 to 1e-6 of it (near the boundary). Each verdict of
:func:`fws_control.stability_verdict` is compared with the closed-loop
eigenvalues of :math:`A - (b_f + a b_r)(k_1 c_e + k_2 c_\\theta)`:

* in double precision first, each eigenvalue with the radius
  ``10 * 2 * eta * kappa`` (the library's first-order bound, ten times wider);
* where that radius leaves the sign of the rightmost real part open (a
  decided point near the axis): exactly, by the Routh array in rational
  arithmetic on the characteristic polynomial of the closed-loop matrix
  formed exactly from the doubles (sympy's ``DomainMatrix.charpoly`` over the
  integers, an algorithm independent of the library's); where that array has
  a zero pivot, and wherever an undecided point's bound must be checked, by
  mpmath eigenvalues (50 digits).

A decided verdict must agree with the sign of the rightmost eigenvalue; an
undecided one must come with a bound ``B >= |Re lambda_max|``. Prints the
counts (plants, decided, undecided, wrong stable, wrong unstable, undecided
outside their bound, exact Routh tests, mpmath calls).

Run: ``python benchmarks/verdict_check.py [plants] [seed]`` (default 100000
plants, seed 0; about 10 minutes on one core).
"""

from __future__ import annotations

import sys
import time
from fractions import Fraction

import control as ct
import mpmath as mp
import numpy as np

import fws_control as fws

EPS = float(np.finfo(float).eps)


def random_plant(rng: np.random.Generator):
    """One random plant and gain point: ``(sys, gains, A_cl pieces)``."""
    n = int(rng.integers(2, 9))
    decades = rng.uniform(0.0, 8.0)
    low = rng.uniform(-4.0, 1.0)
    mags = 10.0 ** (low + decades * rng.uniform(0.0, 1.0, n))
    poles = []
    i = 0
    while i < n:
        if i + 1 < n and rng.uniform() < 0.3:  # complex pair
            re = -mags[i] * rng.uniform(0.05, 1.0)
            im = mags[i] * rng.uniform(0.1, 2.0)
            poles += [complex(re, im), complex(re, -im)]
            i += 2
        else:
            poles.append(-mags[i] if rng.uniform() < 0.9 else mags[i])
            i += 1
    # real block-diagonal form, then a random change of basis
    D = np.zeros((n, n))
    j = 0
    while j < n:
        z = poles[j]
        if isinstance(z, complex):
            D[j : j + 2, j : j + 2] = [[z.real, z.imag], [-z.imag, z.real]]
            j += 2
        else:
            D[j, j] = z
            j += 1
    V = rng.normal(size=(n, n))
    A = V @ D @ np.linalg.inv(V)
    B = rng.normal(size=(n, 2))
    C = rng.normal(size=(2, n))
    sys_ = ct.ss(A, B, C, np.zeros((2, 2)), inputs=["delta_f", "delta_r"],
                 outputs=["e", "theta"])  # fmt: skip
    ratio = float(rng.choice([0.0, rng.uniform(-2.0, 2.0)]))
    b = B[:, 0] + ratio * B[:, 1]
    kind = int(rng.integers(0, 3))
    t = rng.normal()
    if kind == 0:
        scale = float(np.max(np.abs(poles))) / max(np.linalg.norm(b), 1e-300)
        k1, k2 = rng.normal(size=2) * scale / max(np.linalg.norm(C), 1e-300)
    else:
        # a closed-loop root near sigma: p(sigma) = 0 along k2 = t k1 (in
        # double precision: near the axis the root lands within rounding of
        # sigma, which is the regime to test)
        lo, hi = (-4.0, -1.0) if kind == 1 else (-12.0, -6.0)
        sigma = float(np.min(mags)) * 10.0 ** rng.uniform(lo, hi)
        sigma *= 1.0 if rng.uniform() < 0.5 else -1.0
        x = np.linalg.solve(sigma * np.eye(n) - A, b)  # p = d (1 + k c x)
        k1 = -1.0 / float(C[0] @ x + t * (C[1] @ x))
        k2 = t * k1
    return sys_, fws.SteeringGains(float(k1), float(k2), ratio=ratio), (A, B, C)


def closed_loop_matrix(A, B, C, g):
    """The closed-loop matrix, and its entrywise term scale."""
    b = B[:, 0] + g.ratio * B[:, 1]
    kc = g.k1 * C[0] + g.k2 * C[1]
    S = np.abs(A) + np.outer(
        np.abs(B[:, 0]) + abs(g.ratio) * np.abs(B[:, 1]),
        abs(g.k1) * np.abs(C[0]) + abs(g.k2) * np.abs(C[1]),
    )
    return A - np.outer(b, kc), S


def exact_rightmost(A, B, C, g, dps: int = 50) -> float:
    """Largest real part of the exact closed-loop eigenvalues (mpmath)."""
    with mp.workdps(dps):
        M = mp.matrix(A.tolist())
        b = mp.matrix((B[:, 0]).tolist()) + mp.mpf(g.ratio) * mp.matrix(
            (B[:, 1]).tolist()
        )
        kc = mp.mpf(g.k1) * mp.matrix([C[0].tolist()]) + mp.mpf(g.k2) * mp.matrix(
            [C[1].tolist()]
        )
        ev = mp.eig(M - b * kc, left=False, right=False)
        return float(max(mp.re(e) for e in ev))


def exact_stable(A, B, C, g) -> bool | None:
    """Exact Hurwitz test of the closed loop; None for a zero Routh pivot."""
    from sympy import ZZ
    from sympy.polys.matrices import DomainMatrix

    n = A.shape[0]
    a, k1, k2 = (Fraction(float(v)) for v in (g.ratio, g.k1, g.k2))
    b = [Fraction(float(B[i, 0])) + a * Fraction(float(B[i, 1])) for i in range(n)]
    kc = [
        k1 * Fraction(float(C[0, j])) + k2 * Fraction(float(C[1, j])) for j in range(n)
    ]
    M = [[Fraction(float(A[i, j])) - b[i] * kc[j] for j in range(n)] for i in range(n)]
    den = max(x.denominator for row in M for x in row)  # powers of two
    Z = DomainMatrix([[ZZ(int(x * den)) for x in row] for row in M], (n, n), ZZ)
    coeffs = [Fraction(int(c), den**k) for k, c in enumerate(Z.charpoly())]
    if any(c <= 0 for c in coeffs):
        return False
    upper, lower = coeffs[0::2], coeffs[1::2]
    for _ in range(n):
        pivot = lower[0]
        if pivot == 0:
            return None
        if pivot < 0:
            return False  # a sign change after positive pivots
        q = upper[0] / pivot
        new = [
            upper[j + 1] - q * (lower[j + 1] if j + 1 < len(lower) else 0)
            for j in range(len(upper) - 1)
        ]
        upper, lower = lower, new if new else [Fraction(0)]
    return True


def reference_interval(A, B, C, g) -> tuple[float, float]:
    """Bounds ``(lo, hi)`` on the rightmost real part, from double eig."""
    Acl, S = closed_loop_matrix(A, B, C, g)
    n = A.shape[0]
    lam, X = np.linalg.eig(Acl)
    with np.errstate(all="ignore"):
        try:
            kappa = np.linalg.norm(X, axis=0) * np.linalg.norm(np.linalg.inv(X), axis=1)
        except np.linalg.LinAlgError:
            kappa = np.full(n, np.inf)
        eta = 4.0 * (n + 2) * EPS * np.linalg.norm(S)
        rad = 10.0 * 2.0 * eta * kappa
    rad = np.where(np.isfinite(rad), rad, np.inf)
    return float(np.max(lam.real - rad)), float(np.max(lam.real + rad))


def check(plants: int, seed: int = 0, *, verbose: bool = False) -> dict:
    """Counts of the comparison over `plants` random plants."""
    rng = np.random.default_rng(seed)
    names = ("plants", "decided", "undecided", "wrong_stable", "wrong_unstable",
             "undecided_outside_bound", "exact", "mpmath")  # fmt: skip
    out = dict.fromkeys(names, 0)
    for i in range(plants):
        if verbose and i and i % 10_000 == 0:
            print("after", i, "plants:", out, flush=True)
        sys_, g, (A, B, C) = random_plant(rng)
        v = fws.stability_verdict(sys_, g)
        code, bound = int(v.code), float(v.bound)
        lo, hi = reference_interval(A, B, C, g)
        out["plants"] += 1
        if code == fws.stability.UNDECIDED:
            out["undecided"] += 1
            if max(abs(lo), abs(hi)) <= bound:
                continue
            out["mpmath"] += 1
            mu = exact_rightmost(A, B, C, g)
            if abs(mu) > bound:
                out["undecided_outside_bound"] += 1
                if verbose:
                    print("undecided outside bound", mu, bound, g)
            continue
        out["decided"] += 1
        if lo > 0.0 or hi < 0.0:
            truth_stable = hi < 0.0
        else:
            out["exact"] += 1
            truth_stable = exact_stable(A, B, C, g)
            if truth_stable is None:
                out["mpmath"] += 1
                truth_stable = exact_rightmost(A, B, C, g) < 0.0
        if code == fws.stability.STABLE and not truth_stable:
            out["wrong_stable"] += 1
            if verbose:
                print("wrong stable", g, A.shape)
        if code == fws.stability.NOT_STABLE and truth_stable:
            out["wrong_unstable"] += 1
            if verbose:
                print("wrong unstable", g, A.shape)
    return out


def main() -> None:
    plants = int(sys.argv[1]) if len(sys.argv) > 1 else 100_000
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    t0 = time.perf_counter()
    counts = check(plants, seed, verbose=True)
    dt = time.perf_counter() - t0
    print(", ".join(f"{k} {v}" for k, v in counts.items()), f"({dt:.0f} s)")


if __name__ == "__main__":
    main()
