r"""Most-stable gains of the delayed loop (:func:`fws_control.most_stable_gains`).

References written here: the plant matrices of the kinematic model with a
first-order steering lag (paper eq. 33 plus the actuator), the
quasi-polynomial from ``numpy.poly`` of them, its roots by Newton's method
from a dense grid of starts, and a delayed nonlinear simulation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import fws_control as fws
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG

F = 2.7
VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
V = 20.0
TAU = REALISTIC_DELAY  # 0.24 s
LAG = REALISTIC_STEERING_LAG  # 0.27 s


def lagged_matrices(speed, lag):
    """A, B of the straight-road kinematic plant with a lag on each axle."""
    A = np.zeros((4, 4))
    A[0, 1] = speed
    A[0, 3] = speed  # e' = V theta + V delta_r
    A[1, 2] = speed / F  # theta' = V/f (delta_f - delta_r)
    A[1, 3] = -speed / F
    A[2, 2] = A[3, 3] = -1.0 / lag
    B = np.zeros((4, 2))
    B[2, 0] = B[3, 1] = 1.0 / lag
    return A, B


def quasi(k1, k2, a):
    A, B = lagged_matrices(V, LAG)
    b = B[:, 0] + a * B[:, 1]
    C = np.array([k1, k2, 0.0, 0.0])
    d = np.poly(A)
    q = (np.poly(A - np.outer(b, C)) - d)[1:]
    return d, q


def dense_newton_abscissa(d, q, tau):
    """Largest real part of the roots found by Newton from a dense grid."""
    re, im = np.linspace(-8.0, 2.0, 101), np.linspace(0.0, 15.0, 151)
    s = (re[None, :] + 1j * im[:, None]).ravel()
    dd, dq = np.polyder(d), np.polyder(q)
    # Up to 100 Newton steps per start; a start stops once its step is below
    # 1e-15 relative (converged: further steps move it by rounding only) or
    # it is no longer finite. Nearly all starts converge within 30 steps,
    # so the later steps run on a handful of points.
    active = np.arange(s.size)
    with np.errstate(all="ignore"):
        for _ in range(100):
            z = s[active]
            e = np.exp(-z * tau)
            f = np.polyval(d, z) + e * np.polyval(q, z)
            df = np.polyval(dd, z) + e * (np.polyval(dq, z) - tau * np.polyval(q, z))
            step = f / df
            z = z - step
            s[active] = z
            active = active[np.isfinite(z) & ~(np.abs(step) <= 1e-15 * np.abs(z))]
            if active.size == 0:
                break
        e = np.exp(-s * tau)
        f = np.polyval(d, s) + e * np.polyval(q, s)
        size = np.abs(np.polyval(d, s)) + np.abs(e * np.polyval(q, s))
        ok = np.isfinite(s) & (np.abs(f) <= 1e-12 * size)
    return float(np.max(s[ok].real))


@pytest.fixture(scope="module")
def design():
    plant = fws.LateralPlant(VEH, speed=V, steering_lag=LAG)
    return fws.most_stable_gains(plant, delay=TAU, ratio=0.0)


def test_the_library_plant_is_the_written_one():
    sys = fws.LateralPlant(VEH, speed=V, steering_lag=LAG).linearize()
    A, B = lagged_matrices(V, LAG)
    np.testing.assert_allclose(sys.A, A, atol=1e-14)
    np.testing.assert_allclose(sys.B, B, atol=1e-14)


def test_double_root_design_numbers_of_the_20_m_s_case():
    # lambda0 = -1: k1 = 0.00675, k2 = 0.27; rightmost -0.540 +- 2.086j
    g = fws.double_root_gains(fws.LateralPlant(VEH, speed=V), ratio=0.0, pole=-1.0)
    assert float(g.k1) == pytest.approx(0.00675, rel=1e-12)
    assert float(g.k2) == pytest.approx(0.27, rel=1e-12)
    alpha = dense_newton_abscissa(*quasi(float(g.k1), float(g.k2), 0.0), TAU)
    assert alpha == pytest.approx(-0.5397383, abs=1e-6)


def test_most_stable_abscissa_against_dense_newton(design):
    g = design.gains
    assert g.ratio == 0.0
    ref = dense_newton_abscissa(*quasi(float(g.k1), float(g.k2), 0.0), TAU)
    # at the optimum three roots share the abscissa (a real root and a
    # pair): each is found only to about eps^(1/3)
    assert design.abscissa == pytest.approx(ref, abs=2e-5)
    assert design.certified
    assert design.roots_right == 0 and design.residual <= 1e-9
    assert np.all(design.roots.real <= design.abscissa + 1e-12)
    assert design.roots.size >= 2


def test_most_stable_beats_the_double_root_family(design):
    plant2 = fws.LateralPlant(VEH, speed=V)
    family = []
    for pole in np.linspace(-1.5, -0.5, 41):
        g = fws.double_root_gains(plant2, ratio=0.0, pole=pole)
        family.append(dense_newton_abscissa(*quasi(float(g.k1), float(g.k2), 0.0), TAU))
    best_family = min(family)
    # lambda0 = -0.9 gives -0.592 (its real root); the family's best sits
    # where that real root meets the pair, near lambda0 = -0.94: -0.606
    g = fws.double_root_gains(plant2, ratio=0.0, pole=-0.9)
    at_09 = dense_newton_abscissa(*quasi(float(g.k1), float(g.k2), 0.0), TAU)
    assert at_09 == pytest.approx(-0.5919, abs=1e-4)
    assert best_family == pytest.approx(-0.606, abs=2e-3)
    assert design.abscissa < best_family - 0.25  # measured -0.9156


def test_most_stable_is_a_local_minimum(design):
    # no gain pair within 5 % does better (dense Newton at each)
    rng = np.random.default_rng(7)
    k = np.array([float(design.gains.k1), float(design.gains.k2)])
    for _ in range(12):
        trial = k * (1.0 + rng.uniform(-0.05, 0.05, 2))
        alpha = dense_newton_abscissa(*quasi(*trial, 0.0), TAU)
        assert alpha >= design.abscissa - 1e-6, (trial, alpha)


def test_critical_delay_of_the_design(design):
    # the design stays stable up to its critical delay and not beyond it:
    # dense Newton at 0.98 and 1.02 of it
    tc = design.critical_delay
    assert 1.0 < tc < 2.0  # measured 1.2299 s (0.455 s for lambda0 = -1)
    d, q = quasi(float(design.gains.k1), float(design.gains.k2), 0.0)
    assert dense_newton_abscissa(d, q, 0.98 * tc) < 0.0
    assert dense_newton_abscissa(d, q, 1.02 * tc) > 0.0


def test_delayed_nonlinear_simulation_decays_at_the_abscissa(design):
    # From a 1 cm error, the delayed and lagged nonlinear run. At the optimum
    # three roots meet at the abscissa (a real root and a pair with an
    # imaginary part of a few 1e-3), so e(t) is a quadratic in t times
    # e^{r t}: the rate r that makes e(t) e^{-r t} best fit a quadratic on
    # [8, 25] s (least squares, scanned on a 1e-3 grid) is the decay rate.
    assert np.sum(design.roots.real >= design.abscissa - 1e-4) == 3
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=V, steering_lag=LAG), fws.Straight(), design.gains,
        initial_state=(0.0, 0.01, 0.0), duration=30.0, delay=TAU,
        feedforward=False, dt=0.01,
    )  # fmt: skip
    assert res.ok, res.message
    m = (res.t >= 8.0) & (res.t <= 25.0)
    t, e = res.t[m], res.e[m]
    X = np.vander(t, 3)

    def misfit(r):
        y = e * np.exp(-r * t)
        c, *_ = np.linalg.lstsq(X, y, rcond=None)
        return np.linalg.norm(X @ c - y) / np.linalg.norm(y)

    rates = np.arange(-1.5, -0.3, 1e-3)
    fits = np.array([misfit(r) for r in rates])
    rate = rates[np.argmin(fits)]
    assert fits.min() < 1e-3  # measured 1.5e-5: the model fits
    assert rate == pytest.approx(design.abscissa, rel=0.05)  # measured 0.1 %
    # the plain envelope ratio over 10 s is slower by the t^2 factor alone
    e10, e20 = (abs(res.e[np.argmin(abs(res.t - x))]) for x in (10.0, 20.0))
    assert math.log(e20 / e10) / 10.0 == pytest.approx(
        design.abscissa + 2.0 * math.log(2.0) / 10.0, rel=0.05
    )


def test_free_ratio_does_at_least_as_well(design):
    plant = fws.LateralPlant(VEH, speed=V, steering_lag=LAG)
    free = fws.most_stable_gains(plant, delay=TAU, ratio=0.0, ratio_bounds=(-0.5, 0.5))
    assert -0.5 <= free.gains.ratio <= 0.5
    # at least as well, to the abscissa's own accuracy: at the optimum three
    # roots meet, each found to about eps^(1/3) (the 2e-5 of the dense
    # Newton comparisons here). Where the nonsmooth search ends depends on
    # the rounding of the CPU's linear algebra: measured 2.3e-6 above the
    # fixed ratio's design on a Cascade Lake CPU, within 1e-6 on others
    assert free.abscissa <= design.abscissa + 2e-5
    ref = dense_newton_abscissa(
        *quasi(float(free.gains.k1), float(free.gains.k2), float(free.gains.ratio)),
        TAU,
    )
    assert free.abscissa == pytest.approx(ref, abs=2e-5)


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        (dict(delay=0.0), "delay"),
        (dict(delay=-1.0), "delay"),
        (dict(grid=2), "grid"),
        (dict(grid=True), "grid"),
        (dict(margin=0.0), "margin"),
        (dict(ratio=math.nan), "ratio"),
        (dict(ratio_bounds=(1.0, -1.0)), "ratio_bounds"),
        (dict(ratio=2.0, ratio_bounds=(-1.0, 1.0)), "ratio"),
        (dict(k1_bounds=(0.1,)), "k1_bounds"),
        (dict(k2_bounds=(0.0, math.inf)), "k2_bounds"),
    ],
)
def test_bad_input_is_refused(kw, name):
    plant = fws.LateralPlant(VEH, speed=V, steering_lag=LAG)
    with pytest.raises(ValueError, match=name):
        fws.most_stable_gains(plant, **{"delay": TAU, **kw})
