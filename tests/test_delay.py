r"""Feedback delay: critical delay, rightmost roots, root counts, delayed charts.

The loop under test: the plant :math:`\dot x = A x + B_f\delta_f + B_r\delta_r`
with :math:`\delta_f(t) = -(k_1 e + k_2\theta)(t - \tau)` and
:math:`\delta_r = a\,\delta_f` (the delay acts on the steering command of both
axles). With :math:`b = B_f + a B_r` and :math:`C = k_1 c_e + k_2 c_\theta` it
is the single-input loop :math:`\dot x = A x - b C x(t - \tau)`, whose
characteristic function is :math:`D(s) = d(s) + e^{-s\tau} q(s)` with
:math:`d = \det(sI - A)` and :math:`q = \det(sI - A + bC) - d`.

Every reference is built here from matrices written out in this file
(DESIGN.md, "Verification"), never from the library's own polynomials:

* ``control.pade`` of order 10 in series with the single-input plant, unity
  negative feedback, closed-loop poles from python-control;
* an exact sampled-data model: ``control.sample_system`` (zero-order hold) of
  the plant plus an integer-sample shift register for the delay;
* ``numpy.poly`` / ``numpy.linalg.eigvals`` of the matrices above;
* the double-root loop on a road of constant curvature written out in closed
  form and solved with numpy/scipy.
"""

import math
from dataclasses import dataclass

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

import fws_control as fws
from fws_control.exceptions import UncontrollableError

F = 2.7  # wheelbase [m]
VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)


# --------------------------------------------------------------------------
# Hand-written plant and loop
# --------------------------------------------------------------------------


def kinematic_matrices(speed, curvature, lag=None, model="kinematic"):
    """A, B of the kinematic plant (paper eq. 33 with c = 1 + f^2 kappa^2).

    With a first-order steering lag T delta_act' = delta_cmd - delta_act per
    axle the wheel angles become states 3 and 4 and B feeds the commands.
    """
    c = 1.0 + (F * curvature) ** 2 if model == "kinematic" else 1.0
    A = np.array([[0.0, speed], [-speed * curvature**2, 0.0]])
    B = np.array([[0.0, speed], [c * speed / F, -speed / F]])
    if lag is None:
        return A, B
    t_f, t_r = (lag, lag) if np.ndim(lag) == 0 else lag
    A4 = np.zeros((4, 4))
    A4[:2, :2] = A
    A4[:2, 2:] = B
    A4[2, 2] = -1.0 / t_f
    A4[3, 3] = -1.0 / t_r
    B4 = np.zeros((4, 2))
    B4[2, 0] = 1.0 / t_f
    B4[3, 1] = 1.0 / t_r
    return A4, B4


@dataclass
class Loop:
    plant: object  # the library's plant
    gains: fws.SteeringGains
    A: np.ndarray
    b: np.ndarray  # single input B_f + a B_r
    C: np.ndarray  # k1 c_e + k2 c_theta


def make_loop(speed, curvature, ratio, *, pole=None, k1=None, k2=None, lag=None):
    """The library plant and the hand-written single-input loop.

    With `pole` the gains are the double-root design on the 2-state plant
    (also for a lagged plant: the paper's design under a real actuator).
    """
    if pole is not None:
        design_plant = fws.LateralPlant(VEH, speed=speed, curvature=curvature)
        g = fws.double_root_gains(design_plant, ratio=ratio, pole=pole)
        g = fws.SteeringGains(float(g.k1), float(g.k2), ratio)
    else:
        g = fws.SteeringGains(k1, k2, ratio)
    plant = fws.LateralPlant(VEH, speed=speed, curvature=curvature, steering_lag=lag)
    A, B = kinematic_matrices(speed, curvature, lag)
    # the library's plant is the plant written out above
    sys = plant.linearize()
    np.testing.assert_allclose(sys.A, A, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(sys.B, B, rtol=1e-15, atol=1e-15)
    n = A.shape[0]
    b = B[:, 0] + ratio * B[:, 1]
    C = float(g.k1) * np.eye(n)[0] + float(g.k2) * np.eye(n)[1]
    return Loop(plant, g, A, b, C)


def quasi_polynomial(A, b, C):
    """(d, q) of D(s) = d(s) + e^{-s tau} q(s), highest power first."""
    d = np.poly(A)
    q = np.poly(A - np.outer(b, C)) - d
    assert q[0] == 0.0  # both monic
    return d, q[1:]


def relative_residual(d, q, tau, s):
    """|D(s)| / (|d(s)| + |e^{-s tau} q(s)|).

    At a common root of d and q (a mode the steering cannot reach, e.g. the
    rear actuator lag with a = 0: s = -1/T_r is a root of det(sI - A) and of
    the closed loop) the ratio is 0/0; there both |d| and |e^{-s tau} q| are
    measured against the size of their terms (sum |c_k| |s|^k) and the
    larger of the two ratios is returned.
    """
    s = np.asarray(s)
    dv = np.polyval(d, s)
    qv = np.exp(-s * tau) * np.polyval(q, s)
    size = np.polyval(np.abs(d), np.abs(s)) + np.abs(np.exp(-s * tau)) * np.polyval(
        np.abs(q), np.abs(s)
    )
    common = np.abs(dv) + np.abs(qv) <= 1e-6 * size
    with np.errstate(divide="ignore", invalid="ignore"):
        regular = np.abs(dv + qv) / (np.abs(dv) + np.abs(qv))
    return np.where(common, np.maximum(np.abs(dv), np.abs(qv)) / size, regular)


# --------------------------------------------------------------------------
# Reference (a): control.pade in the linear loop
# --------------------------------------------------------------------------

PADE_ORDER = 10


def pade_rightmost_poles(loop, tau, order=PADE_ORDER):
    """Closed-loop poles of pade(tau) -> plant, unity negative feedback."""
    num, den = ct.pade(tau, order)
    plant = ct.ss(loop.A, loop.b[:, None], loop.C[None, :], 0.0)
    cl = ct.feedback(ct.series(ct.tf(num, den), plant), 1)
    p = np.asarray(cl.poles())
    return p[np.argsort(-p.real, kind="stable")]


def pade_critical_delay(loop, order=PADE_ORDER, step=0.005, tau_max=3.0):
    """First tau at which the Pade loop loses stability: scan, then bisection.

    Returns the delay and the rightmost pole just past it.
    """
    lo = 0.0
    hi = step
    while pade_rightmost_poles(loop, hi, order)[0].real < 0.0:
        lo, hi = hi, hi + step
        assert hi <= tau_max, "the Pade loop stays stable up to tau_max"
    while hi - lo > 1e-13 * hi:
        mid = 0.5 * (lo + hi)
        if pade_rightmost_poles(loop, mid, order)[0].real < 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi), pade_rightmost_poles(loop, hi, order)[0]


def pade_phase_error(tau, w, order=PADE_ORDER):
    """|arg pade(j w) - (-w tau)| (the Pade approximant is all-pass)."""
    num, den = ct.pade(tau, order)
    val = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
    assert abs(abs(val) - 1.0) < 1e-12
    return abs(np.angle(val * np.exp(1j * w * tau)))


# --------------------------------------------------------------------------
# Reference (b): exact sampled-data model with a shift register
# --------------------------------------------------------------------------


def sampled_data_radii(loop, h, m_max=200):
    """Spectral radii of the sampled loop for m = 0, 1, ... delay samples.

    x_{k+1} = Ad x_k + Bd u_{k-m}, u_k = -C x_k (ZOH, sample time h). The
    augmented state is [x_k, u_{k-1}, ..., u_{k-m}] (a shift register).
    Stops at the first m whose radius exceeds 1; returns (m, radii).
    """
    sd = ct.sample_system(
        ct.ss(loop.A, loop.b[:, None], loop.C[None, :], 0.0), h, method="zoh"
    )
    Ad, Bd = np.asarray(sd.A), np.asarray(sd.B)[:, 0]
    n = Ad.shape[0]
    radii = []
    for m in range(m_max):
        if m == 0:
            M = Ad - np.outer(Bd, loop.C)
        else:
            M = np.zeros((n + m, n + m))
            M[:n, :n] = Ad
            M[:n, -1] = Bd  # the oldest command u_{k-m} drives the plant
            M[n, :n] = -loop.C  # u_k enters the register
            M[n + 1 :, n:-1] = np.eye(m - 1)  # shift
        rho = float(np.max(np.abs(np.linalg.eigvals(M))))
        radii.append(rho)
        if rho > 1.0:
            return m, radii
    raise AssertionError(f"sampled loop stable up to {m_max} samples of delay")


# --------------------------------------------------------------------------
# 1. critical_delay against control.pade and the sampled-data model
# --------------------------------------------------------------------------

# (speed, curvature, pole, ratio, steering_lag). On a straight road the
# critical delay of a double-root design does not depend on a or V (test 6),
# so the ratios cycle through {-1, 0, 0.5} over the other parameters.
DESIGNS = [
    (V, kappa, lam, (-1.0, 0.0, 0.5)[i % 3], None)
    for i, (kappa, V, lam) in enumerate(
        (kappa, V, lam)
        for kappa in (0.0, 0.1)
        for V in (5.0, 20.0)
        for lam in (-1.0, -2.0, -3.0)
    )
] + [
    (5.0, 0.1, -1.0, 0.0, 0.27),
    (20.0, 0.0, -1.0, -1.0, (0.1, 0.3)),
    (5.0, 0.1, -1.0, 0.5, (0.1, 0.3)),
]


@pytest.mark.parametrize(("speed", "curvature", "pole", "ratio", "lag"), DESIGNS)
def test_critical_delay_against_pade_and_sampled_data(
    speed, curvature, pole, ratio, lag
):
    loop = make_loop(speed, curvature, ratio, pole=pole, lag=lag)
    cd = fws.critical_delay(loop.plant, loop.gains)
    tau_c, w_c = float(cd.delay), float(cd.frequency)
    eig0 = np.linalg.eigvals(loop.A - np.outer(loop.b, loop.C))
    assert cd.stable_without_delay and eig0.real.max() < 0
    assert 0.0 < tau_c < np.inf

    # (a) Pade(10). Its phase error at the crossing, w_c tau_c <= 1.4 rad,
    # is below 1e-15 rad (measured 3e-16, asserted 1e-12), so the Pade loop
    # crosses at tau_c to the resolution of the bisection on eigenvalue
    # signs. Measured:
    # |tau_pade - tau_c| / tau_c <= 5e-14 over these designs (order 8 gives
    # the same); asserted 1e-10.
    assert pade_phase_error(tau_c, w_c) <= 1e-12
    tau_p, crossing = pade_critical_delay(loop)
    rel = abs(tau_p - tau_c) / tau_c
    assert rel <= 1e-10, f"Pade({PADE_ORDER}): tau {tau_p!r} vs {tau_c!r}, rel {rel}"
    # the crossing pair of the Pade loop: measured <= 6e-14 relative
    assert abs(abs(crossing.imag) - w_c) <= 1e-9 * w_c

    # (b) Exact sampled-data model, h = 0.01 s. The zero-order hold adds on
    # average h/2 of delay, so m samples of delay act like tau = (m + 1/2) h:
    # stable at m - 1 and unstable at m brackets tau_c in [(m - 1/2) h,
    # (m + 1/2) h] up to O((w_c h)^2) terms. Asserted |tau_c - m h| <= h;
    # measured <= 0.47 h. Interpolating log(radius) linearly between m - 1
    # and m and adding h/2 refines the estimate: measured <= 0.011 h, asserted
    # 0.05 h.
    h = 0.01
    m, radii = sampled_data_radii(loop, h)
    assert m >= 1 and radii[m - 1] < 1.0 < radii[m]
    err = abs(tau_c - m * h)
    assert err <= h, f"sampled data: m = {m}, |tau_c - m h| = {err / h:.3f} h"
    lo, hi = math.log(radii[m - 1]), math.log(radii[m])
    tau_sd = (m - 1 - lo / (hi - lo) + 0.5) * h
    err_sd = abs(tau_c - tau_sd)
    assert err_sd <= 0.05 * h, f"refined sampled data: {err_sd / h:.4f} h"


def test_critical_delay_zero_when_unstable_and_inf_when_small_gain():
    # Unstable without delay: delay 0, and the eigenvalues agree.
    loop = make_loop(5.0, 0.1, 0.0, k1=-0.5, k2=0.3)
    assert np.linalg.eigvals(loop.A - np.outer(loop.b, loop.C)).real.max() > 0
    cd = fws.critical_delay(loop.plant, loop.gains)
    assert cd.delay == 0.0 and not cd.stable_without_delay

    # A stable open loop with |q(jw)| < |d(jw)| for all w (small gain): no
    # delay destabilises. Reference: the ratio on a dense grid, and Pade
    # loops (all-pass, so the small-gain argument holds for them too) stable
    # at delays up to 100 s.
    A = np.array([[-1.0, 0.5], [0.0, -2.0]])
    B = np.array([[1.0, 0.0], [0.2, 1.0]])
    sys = ct.ss(
        A, B, np.eye(2), 0.0, states=["e", "theta"],
        inputs=["delta_f", "delta_r"], outputs=["e", "theta"],
    )  # fmt: skip
    g = fws.SteeringGains(0.5, 0.3, 0.0)
    ref = Loop(sys, g, A, B[:, 0], np.array([0.5, 0.3]))
    d, q = quasi_polynomial(ref.A, ref.b, ref.C)
    w = np.geomspace(1e-4, 1e4, 20001)
    assert np.max(np.abs(np.polyval(q, 1j * w)) / np.abs(np.polyval(d, 1j * w))) < 1
    for tau in (0.1, 1.0, 10.0, 100.0):
        assert pade_rightmost_poles(ref, tau)[0].real < 0
    cd = fws.critical_delay(sys, g)
    assert cd.delay == np.inf and cd.stable_without_delay and np.isnan(cd.frequency)


# --------------------------------------------------------------------------
# 2. rightmost_roots
# --------------------------------------------------------------------------

ROOT_CASES = [
    (5.0, 0.1, -1.0, -1.0, None),
    (20.0, 0.1, -2.0, 0.5, None),
    (5.0, 0.1, -1.0, 0.0, 0.27),
    (20.0, 0.0, -1.0, -1.0, (0.1, 0.3)),
]


@pytest.mark.parametrize(("speed", "curvature", "pole", "ratio", "lag"), ROOT_CASES)
def test_rightmost_roots(speed, curvature, pole, ratio, lag):
    loop = make_loop(speed, curvature, ratio, pole=pole, lag=lag)
    d, q = quasi_polynomial(loop.A, loop.b, loop.C)
    cd = fws.critical_delay(loop.plant, loop.gains)
    tau_c, w_c = float(cd.delay), float(cd.frequency)

    # At tau_c the rightmost pair is on the imaginary axis at +-j w_c, and
    # every returned root is a root of D (relative residual; measured
    # <= 3e-15). Measured |Re| of the pair <= 4e-16, |Im| = w_c to 1e-16.
    r = fws.rightmost_roots(loop.plant, loop.gains, delay=tau_c, n=4)
    assert r.shape == (4,)
    assert np.all(np.diff(r.real) <= 0.0)
    assert np.all(np.abs(r[:2].real) <= 1e-8)
    np.testing.assert_allclose(np.abs(r[:2].imag), w_c, rtol=1e-9)
    assert r[0].imag * r[1].imag < 0  # the conjugate pair
    assert np.all(r[2:].real < -1e-3)
    assert np.all(relative_residual(d, q, tau_c, r) <= 1e-9)

    # At half and 1.2x the critical delay: the two rightmost roots are those
    # of the Pade(10) loop (a second method, matrix eigenvalues), roots of D,
    # on the correct side of the axis. Measured agreement <= 5e-15
    # relative, asserted 1e-10.
    for tau in (0.5 * tau_c, 1.2 * tau_c):
        r = fws.rightmost_roots(loop.plant, loop.gains, delay=tau, n=2, nodes=10)
        assert np.all(relative_residual(d, q, tau, r) <= 1e-9)
        pade = pade_rightmost_poles(loop, tau)[:2]
        for root in r:
            assert np.min(np.abs(pade - root)) <= 1e-10 * abs(root)
        assert (r[0].real < 0) == (tau < tau_c)

    # tau = 0: the eigenvalues of the undelayed closed loop.
    n = loop.A.shape[0]
    eig = np.linalg.eigvals(loop.A - np.outer(loop.b, loop.C))
    r0 = fws.rightmost_roots(loop.plant, loop.gains, delay=0.0, n=n)
    assert r0.shape == (n,)
    for root in r0:
        assert np.min(np.abs(eig - root)) <= 1e-10 * max(1.0, abs(root))
    for lam in eig:
        assert np.min(np.abs(r0 - lam)) <= 1e-10 * max(1.0, abs(lam))

    # Convergence: nodes=20 and nodes=60 give the same rightmost roots.
    tau = 0.8 * tau_c
    r20 = fws.rightmost_roots(loop.plant, loop.gains, delay=tau, n=3, nodes=20)
    r60 = fws.rightmost_roots(loop.plant, loop.gains, delay=tau, n=3, nodes=60)
    assert np.all(np.abs(r20 - r60) <= 1e-10 * np.maximum(1.0, np.abs(r60)))


# --------------------------------------------------------------------------
# 3. Delayed chart against the rightmost root, point by point
# --------------------------------------------------------------------------


def pade_chart_abscissa(speed, curvature, lag, ratio, k1, k2, tau, order=PADE_ORDER):
    """Rightmost pole of the Pade loop for each gain pair (k1, k2: 1-D).

    The hand-written plant, its steering delayed by a ``control.pade``
    block (z' = Ap z - Bp C x, u = Cp z - Dp C x); all gain pairs in one
    batch of numpy eigenvalue problems.
    """
    A, B = kinematic_matrices(speed, curvature, lag)
    n = A.shape[0]
    b = B[:, 0] + ratio * B[:, 1]
    C = k1[:, None] * np.eye(n)[0] + k2[:, None] * np.eye(n)[1]  # (N, n)
    P = ct.ss(ct.tf(*ct.pade(tau, order)))
    Ap, Bp, Cp, Dp = (np.asarray(m, dtype=float) for m in (P.A, P.B, P.C, P.D))
    M = np.zeros((k1.size, n + order, n + order))
    M[:, :n, :n] = A - Dp[0, 0] * b[:, None] * C[:, None, :]
    M[:, :n, n:] = b[:, None] * Cp[0]
    M[:, n:, :n] = -Bp[:, 0][:, None] * C[:, None, :]
    M[:, n:, n:] = Ap
    return np.linalg.eigvals(M).real.max(axis=-1)


def check_chart_against_rightmost_root(
    curvature, lag, ratio, k1, k2, tau, points, seed, pade_points=10_000
):
    """Sample grid points of a delayed chart (5 m/s); check their verdicts.

    Two references, both passing over points with |Re| <= 1e-3 (near the
    boundary): the real part of the rightmost root (``rightmost_roots``,
    about 1.5-2.5 ms each, benchmarks/bench_rightmost.py) at `points` random
    grid points, and the rightmost pole of the Pade(10) loop (batched
    eigenvalues, milliseconds for thousands) at `pade_points` random grid
    points. Returns the stable fraction of the first sample.
    """
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=curvature, steering_lag=lag)
    A, _ = kinematic_matrices(5.0, curvature, lag)
    np.testing.assert_allclose(plant.linearize().A, A, rtol=1e-15, atol=1e-15)
    ch = fws.stability_chart(plant, ratio=ratio, k1=k1, k2=k2, delay=tau)
    assert ch.stable.shape == (len(k2), len(k1))
    rng = np.random.default_rng(seed)
    order = rng.permutation(ch.stable.size)
    checked = stable = 0
    wrong = []
    for flat in order:
        i, j = np.unravel_index(flat, ch.stable.shape)
        g = fws.SteeringGains(float(ch.k1[j]), float(ch.k2[i]), ratio)
        re = fws.rightmost_roots(plant, g, delay=tau, n=1, nodes=6)[0].real
        if abs(re) <= 1e-3:
            continue
        checked += 1
        stable += re < 0
        if bool(ch.stable[i, j]) != (re < 0):
            wrong.append((g.k1, g.k2, re, bool(ch.stable[i, j])))
        if checked == points:
            break
    assert checked == points
    assert not wrong, f"{len(wrong)} disagreements, e.g. {wrong[:5]}"
    fraction = stable / points
    assert 0.2 < fraction < 0.8  # both verdicts are well represented

    # Pade(10) is converged on these charts: its rightmost pole agrees with
    # that of Pade(16) to 3e-11 over all their grid points, far below the
    # 1e-3 band passed over
    flat = rng.choice(ch.stable.size, pade_points, replace=False)
    i, j = np.unravel_index(flat, ch.stable.shape)
    top = pade_chart_abscissa(5.0, curvature, lag, ratio, ch.k1[j], ch.k2[i], tau)
    # an undecided point (verdict -1, documented: never in `stable`) has a
    # root near the axis: measured |Re| <= 1.2e-3 over these three charts
    undecided = ch.verdict[i, j] == -1
    assert np.all(np.abs(top[undecided]) <= 5e-3)
    clear = (np.abs(top) > 1e-3) & ~undecided
    assert np.count_nonzero(clear) > 0.95 * pade_points
    verdict = ch.stable[i, j][clear]
    bad = np.flatnonzero(verdict != (top[clear] < 0.0))
    assert bad.size == 0, (ch.k1[j][clear][bad[:5]], ch.k2[i][clear][bad[:5]])
    assert 0.2 < np.mean(top[clear] < 0.0) < 0.8
    return fraction


def test_delayed_chart_two_state_curved_against_rightmost_root():
    # 500 random points against the rightmost root and 10,000 against the
    # Pade loop, 0 disagreements. The chart's verdict is point by point (the
    # argument-principle count), so a 151 x 151 grid checks it as a finer
    # one does, at a quarter of the chart's cost.
    check_chart_against_rightmost_root(
        0.1, None, -1.0, np.linspace(-0.05, 0.4, 151), np.linspace(0.0, 1.8, 151),
        tau=0.3, points=500, seed=1,
    )  # fmt: skip


@pytest.mark.parametrize(("ratio", "tau", "seed"), [(0.0, 0.24, 2), (0.5, 0.1, 3)])
def test_delayed_chart_lagged_against_rightmost_root(ratio, tau, seed):
    # The 4-state plant with the Autoware-like lag 0.27 s; 2 x 300 random
    # points against the rightmost root and 2 x 10,000 against the Pade
    # loop, 0 disagreements (151 x 151 grid: see the two-state test)
    k1 = np.linspace(-0.05, 0.35, 151)
    k2 = np.linspace(-0.2, 1.5, 151) if ratio == 0.0 else np.linspace(-1, 1.5, 151)
    check_chart_against_rightmost_root(
        0.1, 0.27, ratio, k1, k2, tau=tau, points=300, seed=seed
    )


# --------------------------------------------------------------------------
# 4. unstable_root_count
# --------------------------------------------------------------------------


@settings(max_examples=40, derandomize=True, deadline=None)
@given(
    speed=st.one_of(st.floats(1.0, 30.0), st.floats(-30.0, -1.0)),
    curvature=st.floats(-0.2, 0.2),
    ratio=st.floats(-2.0, 2.0),
    lag=st.sampled_from([None, 0.27, (0.1, 0.3)]),
    seed=st.integers(0, 2**32 - 1),
)
def test_unstable_root_count_without_delay_is_eigenvalue_count(
    speed, curvature, ratio, lag, seed
):
    rng = np.random.default_rng(seed)
    k1, k2 = rng.uniform(-2.0, 2.0, (2, 200))
    A, B = kinematic_matrices(speed, curvature, lag)
    n = A.shape[0]
    b = B[:, 0] + ratio * B[:, 1]
    C = k1[:, None] * np.eye(n)[0] + k2[:, None] * np.eye(n)[1]  # (200, n)
    eig = np.linalg.eigvals(A - b[None, :, None] * C[:, None, :])
    scale = np.maximum(1.0, np.abs(eig).max(axis=1))
    away = np.min(np.abs(eig.real), axis=1) > 1e-3 * scale
    plant = fws.LateralPlant(VEH, speed=speed, curvature=curvature, steering_lag=lag)
    count = fws.unstable_root_count(plant, fws.SteeringGains(k1, k2, ratio))
    assert count.shape == (200,)
    np.testing.assert_array_equal(count[away], (eig.real > 0).sum(axis=1)[away])
    # Undecided (-1) is allowed only for a root near the axis (documented);
    # e.g. V = 1, a = 0, a pair at 2e-5 +- 0.254j is reported -1. Where it
    # decides closer to the axis than 1e-3 the count is still right; a root
    # within rounding of the axis (e.g. a = 1 on a straight path, where s = 0
    # is a root for all gains) may be counted on either side.
    near = np.min(np.abs(eig.real), axis=1) <= 1e-3 * scale
    assert np.all(near[count < 0])
    decided = count >= 0
    tiny = 1e-9 * scale[:, None]
    assert np.all((eig.real > tiny).sum(axis=1)[decided] <= count[decided])
    assert np.all(count[decided] <= (eig.real > -tiny).sum(axis=1)[decided])


@pytest.mark.parametrize(
    ("lag", "ratio", "tau"), [(None, -1.0, 0.3), (None, 0.5, 0.8), (0.27, 0.0, 0.24)]
)
def test_unstable_root_count_with_delay_is_rightmost_root_count(lag, ratio, tau):
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, steering_lag=lag)
    rng = np.random.default_rng(11)
    k1, k2 = rng.uniform(-1.5, 1.5, (2, 300))
    count = fws.unstable_root_count(plant, fws.SteeringGains(k1, k2, ratio), delay=tau)
    checked = 0
    seen = set()
    for a1, a2, c in zip(k1, k2, count, strict=True):
        # n = 4: the right-half-plane roots of these gains are among the
        # four rightmost.
        r = fws.rightmost_roots(
            plant, fws.SteeringGains(a1, a2, ratio), delay=tau, n=4, nodes=8
        )
        # all right-half-plane roots are among the four; none near the axis
        if r[-1].real >= 0 or np.min(np.abs(r.real)) <= 1e-3:
            continue
        checked += 1
        assert c == np.count_nonzero(r.real > 0), (a1, a2, r)
        seen.add(int(c))
    assert checked >= 250
    assert len(seen) >= 3  # stable points and several unstable counts


# --------------------------------------------------------------------------
# 5. D-subdivision curve with delay
# --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("lag", "ratio", "tau"), [(None, -1.0, 0.3), (None, 0.5, 1.0), (0.27, 0.0, 0.24)]
)
def test_delayed_boundary_curve_is_a_root_of_d(lag, ratio, tau):
    A, B = kinematic_matrices(5.0, 0.1, lag)
    n = A.shape[0]
    b = B[:, 0] + ratio * B[:, 1]
    d = np.poly(A)
    n1 = (np.poly(A - np.outer(b, np.eye(n)[0])) - d)[1:]
    n2 = (np.poly(A - np.outer(b, np.eye(n)[1])) - d)[1:]
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=0.1, steering_lag=lag)
    curve = fws.stability_boundaries(plant, ratio=ratio, delay=tau).complex_root
    ok = np.isfinite(curve.k1) & np.isfinite(curve.k2)
    assert ok.mean() > 0.9
    # q per point, coefficients down axis 0 (numpy.polyval broadcasts).
    q = curve.k1[ok] * n1[:, None] + curve.k2[ok] * n2[:, None]
    residual = relative_residual(d, q, tau, 1j * curve.omega[ok])
    # |D(jw)| / (|d| + |q|), except at w = V kappa (in the default grid),
    # where d(jw) = 0 and the curve passes through k = (0, 0): D = d there
    # and both terms are rounding-sized (relative_residual handles it).
    assert residual.max() <= 1e-9, residual.max()  # measured <= 2e-13


# --------------------------------------------------------------------------
# 6. delay_margin_chart and the double-root design's delay margin
# --------------------------------------------------------------------------


@pytest.mark.parametrize(("curvature", "lag"), [(0.0, None), (0.1, None), (0.0, 0.27)])
def test_delay_margin_chart_equals_critical_delay_per_design(curvature, lag):
    ratios = np.array([-1.0, 0.0, 0.5, 1.0])
    poles = np.array([-0.5, -1.0, -2.0, -3.0])
    design_plant = fws.LateralPlant(VEH, speed=5.0, curvature=curvature)
    plant = fws.LateralPlant(VEH, speed=5.0, curvature=curvature, steering_lag=lag)
    ch = fws.delay_margin_chart(
        plant, ratio=ratios, pole=poles, design_plant=design_plant
    )
    assert ch.delay.shape == ch.frequency.shape == (4, 4)
    for i, a in enumerate(ratios):
        for j, lam in enumerate(poles):
            try:
                g = fws.double_root_gains(design_plant, ratio=a, pole=lam)
            except UncontrollableError:
                # a = 1 on a straight road: no design, NaN in the chart
                assert a == 1.0 and curvature == 0.0
                assert np.isnan(ch.delay[i, j]) and np.isnan(ch.frequency[i, j])
                continue
            cd = fws.critical_delay(plant, g)
            assert ch.delay[i, j] == cd.delay
            assert ch.frequency[i, j] == cd.frequency or (
                np.isnan(ch.frequency[i, j]) and np.isnan(cd.frequency)
            )
            assert np.isfinite(ch.delay[i, j]) and ch.delay[i, j] > 0
    assert np.isnan(ch.delay).sum() == (4 if curvature == 0.0 else 0)


def double_root_delay_margin(pole, vk):
    """Critical delay of the loop closed to (s - pole)^2 on V kappa = vk.

    d(s) = s^2 + vk^2 (A = [[0, V], [-V kappa^2, 0]]) and the closed loop is
    (s - pole)^2, so q(s) = -2 pole s + pole^2 - vk^2 whatever a, V, the
    model or the vehicle. Crossing frequencies: |d(jw)|^2 = |q(jw)|^2,
    i.e. (vk^2 - w^2)^2 = (pole^2 - vk^2)^2 + 4 pole^2 w^2, bracketed and
    solved with scipy; delay: e^{-j w tau} = -d/q.
    """

    def gap(w):
        return (vk**2 - w**2) ** 2 - (pole**2 - vk**2) ** 2 - 4 * pole**2 * w**2

    # gap is a quadratic in x = w^2 with positive leading coefficient and
    # gap(vk) = -(pole^2 + vk^2)^2 < 0: exactly one crossing above vk; a
    # second one below vk exists iff gap(0) = pole^2 (2 vk^2 - pole^2) > 0,
    # which the values used here exclude.
    assert 2 * vk**2 < pole**2
    w = brentq(gap, 1e-9 + abs(vk), 100.0 * (abs(pole) + abs(vk)), xtol=1e-15)
    s = 1j * w
    phase = np.angle(-(-2 * pole * s + pole**2 - vk**2) / (s**2 + vk**2))
    return np.mod(phase, 2 * np.pi) / w


def test_double_root_delay_margin_depends_only_on_pole_and_speed_times_curvature():
    # Straight road: D(s) = s^2 + e^{-s tau}(-2 lam s + lam^2). With
    # z = s/|lam|, T = tau |lam| it is z^2 + e^{-zT}(2z + 1): tau_c |lam| is
    # one constant. |d| = |q| gives w^4 = 4 w^2 + 1, w^2 = 2 + sqrt(5); the
    # phase gives T = atan(2 w)/w.
    w_star = math.sqrt(2.0 + math.sqrt(5.0))
    t_star = math.atan(2.0 * w_star) / w_star
    assert double_root_delay_margin(-1.0, 0.0) == pytest.approx(t_star, rel=1e-13)
    for V in (2.0, 5.0, 20.0, -5.0):
        plant = fws.LateralPlant(VEH, speed=V)
        for a in (-1.0, -0.5, 0.0, 0.5, 2.0):
            for lam in (-0.5, -1.0, -3.0):
                g = fws.double_root_gains(plant, ratio=a, pole=lam)
                cd = fws.critical_delay(plant, g)
                assert cd.delay * abs(lam) == pytest.approx(t_star, rel=1e-10)
                assert cd.frequency / abs(lam) == pytest.approx(w_star, rel=1e-10)

    # Curved road: the margin depends on lam and V kappa only (not on a, V,
    # the linearisation model) and equals the closed-form loop solved above;
    # it scales as tau_c(lam, V kappa) = tau_c(lam/c, V kappa/c) / c.
    for lam, vk in ((-1.5, 1.0), (-1.0, 0.5), (-3.0, 2.0)):
        ref = double_root_delay_margin(lam, vk)
        assert double_root_delay_margin(2 * lam, 2 * vk) == pytest.approx(
            ref / 2, rel=1e-12
        )
        for V, model, a in ((5.0, "kinematic", -1.0), (10.0, "paper", 0.0),
                            (20.0, "kinematic", 0.5),
                            (-10.0, "kinematic", 1.0)):  # fmt: skip
            plant = fws.LateralPlant(VEH, speed=V, curvature=vk / V, model=model)
            g = fws.double_root_gains(plant, ratio=a, pole=lam)
            cd = fws.critical_delay(plant, g)
            assert cd.delay == pytest.approx(ref, rel=1e-10), (lam, vk, V, model, a)


# --------------------------------------------------------------------------
# 7. Bad input
# --------------------------------------------------------------------------

PLANT = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
GAINS = fws.SteeringGains(0.2, 0.6, -1.0)
BAD_DELAYS = [
    (-0.1, ValueError),
    (float("nan"), ValueError),
    (float("inf"), ValueError),
    (-float("inf"), ValueError),
    (True, TypeError),
    (False, TypeError),
    (np.True_, TypeError),
    ([0.1, 0.2], ValueError),
    ("0.1", ValueError),
    (None, ValueError),
]

DELAY_CALLS = {
    "is_stable": lambda tau: fws.is_stable(PLANT, GAINS, delay=tau),
    "stability_boundaries": lambda tau: fws.stability_boundaries(
        PLANT, ratio=-1.0, delay=tau
    ),
    "stability_chart": lambda tau: fws.stability_chart(
        PLANT, ratio=-1.0, k1=[0.0, 0.5], k2=[0.0, 1.0], delay=tau
    ),
    "rightmost_roots": lambda tau: fws.rightmost_roots(PLANT, GAINS, delay=tau),
    "unstable_root_count": lambda tau: fws.unstable_root_count(PLANT, GAINS, delay=tau),
}


@pytest.mark.parametrize("call", sorted(DELAY_CALLS))
@pytest.mark.parametrize(("delay", "error"), BAD_DELAYS)
def test_bad_delay_is_refused_naming_delay(call, delay, error):
    with pytest.raises(error, match="delay"):
        DELAY_CALLS[call](delay)


@pytest.mark.parametrize(
    "kwargs",
    [{"n": 0}, {"n": -1}, {"n": 1.5}, {"n": True}, {"nodes": 2}, {"nodes": 3},
     {"nodes": 10.5}],
)  # fmt: skip
def test_rightmost_roots_refuses_bad_n_and_nodes(kwargs):
    name = next(iter(kwargs))
    with pytest.raises(ValueError, match=name):
        fws.rightmost_roots(PLANT, GAINS, delay=0.2, **kwargs)


_P13 = fws.LateralPlant(VEH, speed=5.0, curvature=0.1)
_G13 = fws.double_root_gains(_P13, ratio=-1.0, pole=-1.0)


@pytest.mark.parametrize(
    "kw, arg",
    [
        (dict(n=math.inf), "n"),
        (dict(n=[1, 2]), "n"),
        (dict(n="2"), "n"),
        (dict(n=None), "n"),
        (dict(nodes=1e300), "nodes"),
        (dict(nodes=math.nan), "nodes"),
        (dict(nodes=np.eye(2)), "nodes"),
        (dict(delay=1e-300), "delay"),
        (dict(delay=1e300), "delay"),
    ],
)
def test_issue13_rightmost_roots_bad_counts_and_delays(kw, arg):
    # before: OverflowError/TypeError without the name, a huge allocation
    # for nodes=1e300, NaN roots at 1e300 s, a RuntimeError at 1e-300 s
    with pytest.raises(ValueError, match=rf"\b{arg} must be"):
        fws.rightmost_roots(_P13, _G13, **{"delay": 0.2, **kw})


def test_issue13_unstable_root_count_long_delay_refused():
    # before: 1e300 s asked numpy for a grid beyond memory; the refusal names
    # the delay and the longest one the grid allows
    for f in (fws.unstable_root_count, fws.is_stable):
        with pytest.raises(
            ValueError, match=r"delay=1e\+300 s needs .* delay must be <="
        ):
            f(_P13, _G13, delay=1e300)
    # a delay under the stated bound is still answered, and agrees with the
    # rightmost roots (independent Chebyshev discretisation)
    r = fws.rightmost_roots(_P13, _G13, delay=0.2, n=2)
    c = fws.unstable_root_count(_P13, _G13, delay=0.2)
    assert int(c) == np.count_nonzero(r.real > 0)


# --------------------------------------------------------------------------
# 8. rightmost_roots: cost on a lagged plant, tiny delays
# --------------------------------------------------------------------------


def dense_newton_roots(d, q, tau, re, im, steps=80):
    """Roots of d(s) + e^{-s tau} q(s) by Newton from every point of a grid.

    Starts on re x im (upper half plane); returns the distinct converged
    roots (relative residual <= 1e-12, merged within 1e-7), both halves.
    """
    s = (re[None, :] + 1j * im[:, None]).ravel()
    dd, dq = np.polyder(d), np.polyder(q)
    with np.errstate(all="ignore"):
        for _ in range(steps):
            e = np.exp(-s * tau)
            f = np.polyval(d, s) + e * np.polyval(q, s)
            df = np.polyval(dd, s) + e * (np.polyval(dq, s) - tau * np.polyval(q, s))
            s = s - f / df
        ok = np.isfinite(s) & (relative_residual(d, q, tau, s) <= 1e-12)
    roots = []
    for z in sorted(s[ok], key=lambda z: (-z.real, -abs(z.imag))):
        z = complex(z.real, abs(z.imag))
        if all(abs(z - r) > 1e-7 * (1 + abs(z)) for r in roots):
            roots.append(z)
    roots = np.array(roots)
    return np.concatenate([roots, np.conj(roots[roots.imag > 1e-9])])


def test_rightmost_roots_lagged_plant_small_discretisation(monkeypatch):
    # The lagged plant (5 m/s, kappa 0.1, lag 0.27 s, a = 0) where the
    # default call used to double its 40 nodes up to 1280 (a 5124 x 5124
    # eigenproblem, 17 s): the rightmost roots converge with 16-64 nodes.
    loop = make_loop(5.0, 0.1, 0.0, k1=0.005, k2=0.1, lag=0.27)
    d, q = quasi_polynomial(loop.A, loop.b, loop.C)
    sizes = []
    real_eigvals = np.linalg.eigvals

    def counting_eigvals(M):
        sizes.append(np.shape(M)[-1])
        return real_eigvals(M)

    monkeypatch.setattr(np.linalg, "eigvals", counting_eigvals)
    r = fws.rightmost_roots(loop.plant, loop.gains, delay=0.24)
    monkeypatch.undo()
    # the history of the delayed scalar only: n_states + nodes, measured 8,
    # 16, 32, 64 nodes
    assert max(sizes) <= 4 + 64
    ref = dense_newton_roots(
        d, q, 0.24, np.linspace(-40.0, 2.0, 85), np.linspace(0.0, 60.0, 121)
    )
    ref = ref[np.lexsort((-ref.imag, -ref.real))][:6]
    np.testing.assert_allclose(r, ref, rtol=1e-9, atol=1e-12)


def test_rightmost_roots_of_two_plants_at_alternating_ratios_as_fresh_plants():
    # A search calls rightmost_roots on one plant object at many gains (its
    # matrices and polynomial are kept per plant and ratio): two plant
    # objects at alternating ratios, the same ratio on both in turn, give
    # what new, equal plants give, and roots of D written out in the test.
    speeds = (20.0, 12.0)
    plants = [
        fws.LateralPlant(VEH, speed=v, curvature=0.02, steering_lag=0.27)
        for v in speeds
    ]
    for ratio in (0.0, -0.5, 0.0, 0.4, -0.5):
        g = fws.SteeringGains(0.002, 0.12, ratio)
        for v, plant in zip(speeds, plants, strict=True):
            r = fws.rightmost_roots(plant, g, delay=0.24, n=3)
            fresh = fws.LateralPlant(VEH, speed=v, curvature=0.02, steering_lag=0.27)
            np.testing.assert_array_equal(
                r, fws.rightmost_roots(fresh, g, delay=0.24, n=3)
            )
            loop = make_loop(v, 0.02, ratio, k1=0.002, k2=0.12, lag=0.27)
            d, q = quasi_polynomial(loop.A, loop.b, loop.C)
            assert np.all(relative_residual(d, q, 0.24, r) <= 1e-9)


def chebyshev_collocation(N):
    """Nodes cos(pi j/N) and Trefethen's differentiation matrix (Spectral
    Methods in MATLAB, cheb.m), written out from its formula."""
    x = np.cos(np.pi * np.arange(N + 1) / N)
    c = np.array([2.0] + [1.0] * (N - 1) + [2.0]) * (-1.0) ** np.arange(N + 1)
    D = np.zeros((N + 1, N + 1))
    for i in range(N + 1):
        for j in range(N + 1):
            if i != j:
                D[i, j] = c[i] / c[j] / (x[i] - x[j])
        D[i, i] = -sum(D[i, j] for j in range(N + 1) if j != i)
    return x, D


@pytest.mark.parametrize(("lag", "tau"), [(None, 0.3), (0.27, 0.24), ((0.1, 0.3), 0.5)])
def test_discretisation_is_the_full_state_collocation_less_the_bare_transport(
    monkeypatch, lag, tau
):
    # The first eigenproblem rightmost_roots solves (8 nodes) against the
    # collocation of the whole state's history on the same nodes: x' = A X_0
    # + A1 X_N, X_j' = (2/tau) sum_l D_jl X_l. Its spectrum is the library's
    # plus (n - 1) copies of the bare transport's, (2/tau) D[1:, 1:] (the
    # history components the feedback row does not see). Measured agreement
    # 2.0e-13 to 2.7e-13 relative (the transport's eigenvalues are
    # ill-conditioned), asserted 1e-9.
    loop = make_loop(20.0, 0.0, 0.0, k1=0.002, k2=0.12, lag=lag)
    n = loop.A.shape[0]
    captured = []
    real_eigvals = np.linalg.eigvals

    def capturing_eigvals(M):
        captured.append(np.array(M))
        return real_eigvals(M)

    monkeypatch.setattr(np.linalg, "eigvals", capturing_eigvals)
    fws.rightmost_roots(loop.plant, loop.gains, delay=tau, n=2, nodes=8)
    monkeypatch.undo()
    reduced = next(M for M in captured if M.shape[0] == n + 8)
    _, D = chebyshev_collocation(8)
    full = np.kron(D * (2.0 / tau), np.eye(n))
    full[:n, :] = 0.0
    full[:n, :n] = loop.A
    full[:n, -n:] = -np.outer(loop.b, loop.C)
    lam_full = real_eigvals(full)
    transport = real_eigvals(D[1:, 1:] * (2.0 / tau))
    expected = np.concatenate([real_eigvals(reduced)] + [transport] * (n - 1))
    assert lam_full.size == expected.size
    # match the two multisets greedily, nearest first
    left = list(expected)
    for lam in lam_full[np.argsort(-np.abs(lam_full))]:
        i = int(np.argmin(np.abs(np.array(left) - lam)))
        assert abs(left[i] - lam) <= 1e-9 * (1.0 + abs(lam)), (lam, left[i])
        left.pop(i)


@pytest.mark.parametrize("tau", [1e-6, 1e-5, 1e-4])
@pytest.mark.parametrize(
    ("speed", "curvature", "ratio", "pole"),
    [(20.0, 0.0, 0.0, -1.0), (5.0, 0.1, -1.0, -2.0)],
)
def test_rightmost_roots_tiny_delay_splits_the_double_root(
    tau, speed, curvature, ratio, pole
):
    # The double-root design: d + q = (s - pole)^2 with d = s^2 + (V kappa)^2
    # (written out in the test). A delay tau splits the double root: with
    # D = (s - pole)^2 - s tau q(s) + O(tau^2), s = pole + delta,
    # delta^2 = tau pole q(pole) = -tau pole (pole^2 + v^2) > 0: two real
    # roots pole -+ sqrt(tau |pole| (pole^2 + v^2)) + O(tau). The old
    # discretisation raised "did not converge with 1280 Chebyshev nodes".
    loop = make_loop(speed, curvature, ratio, pole=pole)
    d, q = quasi_polynomial(loop.A, loop.b, loop.C)
    v = speed * curvature
    np.testing.assert_allclose(d, [1.0, 0.0, v**2], atol=1e-12)
    np.testing.assert_allclose(q, [-2 * pole, pole**2 - v**2], rtol=1e-9)
    delta = math.sqrt(tau * abs(pole) * (pole**2 + v**2))
    first_order = np.array([pole + delta, pole - delta])
    r = fws.rightmost_roots(loop.plant, loop.gains, delay=tau, n=2)
    assert np.all(r.imag == 0.0)
    # O(tau) from the first-order split (measured <= 3 tau pole^2)
    np.testing.assert_allclose(r.real, first_order, atol=10 * tau * pole**2)
    # and Newton from a dense grid around the double root finds the same two
    ref = dense_newton_roots(
        d, q, tau,
        pole + np.linspace(-5 * delta, 5 * delta, 101), np.linspace(0, delta, 11),
    )  # fmt: skip
    ref = np.sort(ref.real)[::-1]
    assert ref.size == 2
    np.testing.assert_allclose(r.real, ref, rtol=1e-10)
    # n = 3: the third is the rightmost of the far roots, a real root of
    # s^2 + v^2 + e^{-s tau} q(s) = 0 with s tau of about -10...-16 (by
    # brentq on its log form), with no complex root right of it (dense
    # Newton in z = s tau).
    r3 = fws.rightmost_roots(loop.plant, loop.gains, delay=tau, n=3)
    np.testing.assert_allclose(r3[:2], r, rtol=1e-12)

    def log_gap(x):  # log|d(x)| - log|e^{-x tau} q(x)| for x << 0
        return math.log(x * x + v**2) - (
            -x * tau + math.log(abs(-2 * pole * x + pole**2 - v**2))
        )

    far = brentq(log_gap, -100.0 / tau, -1.0 / tau, xtol=1e-12 / tau)
    assert r3[2] == pytest.approx(far, rel=1e-9)
    scaled = dense_newton_roots(
        np.array([1.0, 0.0, (v * tau) ** 2]),
        np.array([-2 * pole * tau, (pole**2 - v**2) * tau**2]),
        1.0, np.linspace(-40.0, -1.0, 79), np.linspace(0.0, 40.0, 81),
    )  # fmt: skip
    scaled = scaled[scaled.real < -0.5]  # not the pair near z = pole tau
    assert np.max(scaled.real) == pytest.approx(far * tau, rel=1e-9)
