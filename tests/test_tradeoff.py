r"""Pareto fronts of decay rate against delay margin and effort (:func:`pareto_front`).

References written here: the plant matrices of the kinematic model with a
first-order steering lag; the rightmost root of the delayed loop from a
12th-order :func:`control.pade` approximation of the delay and the
eigenvalues of the closed loop; the critical delay from a frequency scan of
:math:`|d(j\omega)| - |q(j\omega)|` (brentq at each sign change) and the
phase condition; and a brute-force grid of gains evaluated with both.
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from scipy.optimize import brentq

import fws_control as fws
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG

F = 2.7
V = 20.0
TAU = REALISTIC_DELAY  # 0.24 s
LAG = REALISTIC_STEERING_LAG  # 0.27 s
VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
POINTS = 5


def lagged_matrices(speed, lag):
    """A, b (a = 0) of the straight-road kinematic plant, a lag on each axle."""
    A = np.zeros((4, 4))
    A[0, 1] = speed
    A[0, 3] = speed
    A[1, 2] = speed / F
    A[1, 3] = -speed / F
    A[2, 2] = A[3, 3] = -1.0 / lag
    b = np.array([0.0, 0.0, 1.0 / lag, 0.0])
    return A, b


A, B = lagged_matrices(V, LAG)
_num, _den = ct.pade(TAU, 12)
_P = ct.ss(ct.tf(_num, _den))
PA, PB, PC, PD = (np.asarray(m) for m in (_P.A, _P.B, _P.C, _P.D))


def pade_decay(k1, k2):
    """-max Re of the closed loop with the delay replaced by Pade(12)."""
    K = np.array([k1, k2, 0.0, 0.0])
    top = np.hstack([A - PD[0, 0] * np.outer(B, K), np.outer(B, PC[0])])
    bottom = np.hstack([-np.outer(PB[:, 0], K), PA])
    return -float(np.max(np.linalg.eigvals(np.vstack([top, bottom])).real))


def critical_delay_scan(k1, k2):
    """Smallest delay with a root on the imaginary axis (frequency scan)."""
    d = np.poly(A)
    q = (np.poly(A - np.outer(B, [k1, k2, 0.0, 0.0])) - d)[1:]

    def gap(w):
        return abs(np.polyval(d, 1j * w)) - abs(np.polyval(q, 1j * w))

    w = np.geomspace(1e-4, 60.0, 6000)
    f = np.abs(np.polyval(d, 1j * w)) - np.abs(np.polyval(q, 1j * w))
    best = math.inf
    for i in np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:])):
        wc = brentq(gap, w[i], w[i + 1], xtol=1e-15, rtol=1e-15)
        phase = np.angle(-np.polyval(q, 1j * wc) / np.polyval(d, 1j * wc))
        best = min(best, np.mod(phase, 2 * math.pi) / wc)
    return best


@pytest.fixture(scope="module")
def front():
    plant = fws.LateralPlant(VEH, speed=V, steering_lag=LAG)
    return fws.pareto_front(plant, delay=TAU, points=POINTS, grid=6)


def test_the_plant_is_the_written_one():
    sys = fws.LateralPlant(VEH, speed=V, steering_lag=LAG).linearize()
    np.testing.assert_allclose(sys.A, A, atol=1e-14)
    np.testing.assert_allclose(sys.B[:, 0], B, atol=1e-14)


def test_front_points_recomputed_independently(front):
    assert front.dropped == 0
    assert front.margin.size == POINTS and front.effort.size == POINTS
    for g, decay, margin in zip(
        zip(front.margin_gains.k1, front.margin_gains.k2, strict=True),
        front.margin_decay,
        front.margin,
        strict=True,
    ):
        assert pade_decay(*g) == pytest.approx(decay, abs=1e-6)
        assert critical_delay_scan(*g) == pytest.approx(margin, rel=1e-8)
    for k1, k2, decay in zip(
        front.effort_gains.k1, front.effort_gains.k2, front.effort_decay, strict=True
    ):
        assert pade_decay(k1, k2) == pytest.approx(decay, abs=1e-6)


def test_the_constraints_bind_at_their_grid(front):
    # epsilon-constraint: the margins are the levels asked for (the knee's
    # critical delay up to three times it), the efforts the caps
    tc0 = front.design.critical_delay
    np.testing.assert_allclose(
        front.margin, np.linspace(tc0, 3 * tc0, POINTS), rtol=1e-6
    )
    k1s = abs(float(front.design.gains.k1))
    np.testing.assert_allclose(
        front.effort, np.linspace(k1s, k1s / 10, POINTS), rtol=1e-12
    )
    np.testing.assert_allclose(front.effort, np.abs(front.effort_gains.k1), rtol=1e-12)
    # the knee is the most-stable design: -0.9156 1/s, 1.230 s (design_delay.md)
    assert front.margin_decay[0] == pytest.approx(0.91562, abs=1e-5)
    assert tc0 == pytest.approx(1.2299, abs=1e-4)
    # the fronts of docs/design_delay.md
    np.testing.assert_allclose(
        front.margin_decay, [0.9156, 0.4126, 0.2912, 0.2266, 0.1858], atol=1e-4
    )
    np.testing.assert_allclose(
        front.effort_decay, [0.9156, 0.6138, 0.4648, 0.3272, 0.1652], atol=1e-4
    )
    # more margin and less effort each cost decay
    assert np.all(np.diff(front.margin_decay) < 0)
    assert np.all(np.diff(front.effort_decay) < 0)


def test_no_front_point_is_dominated_by_a_brute_force_grid(front):
    k1s, k2s = float(front.design.gains.k1), float(front.design.gains.k2)
    k1 = k1s * np.geomspace(0.05, 2.0, 13)
    k2 = k2s * np.geomspace(0.1, 3.0, 13)
    grid = np.array(
        [(a, b, pade_decay(a, b), critical_delay_scan(a, b)) for a in k1 for b in k2]
    )
    stable = grid[:, 2] > 0
    assert stable.sum() > 50  # the grid reaches the front's region
    tol = 1e-6
    for decay, margin in zip(front.margin_decay, front.margin, strict=True):
        beats = (grid[:, 2] > decay + tol) & (grid[:, 3] > margin * (1 + tol))
        assert not beats.any(), grid[beats][:3]
    for decay, effort in zip(front.effort_decay, front.effort, strict=True):
        beats = (grid[:, 2] > decay + tol) & (np.abs(grid[:, 0]) < effort * (1 - tol))
        assert not beats.any(), grid[beats][:3]


def test_two_state_front_decay_is_speed_invariant_in_scaled_gains():
    # s^2 + e^{-s tau}(V k2 s + V^2 k1)/f: the front at 10 m/s is the one at
    # 20 m/s with k1 V^2 and k2 V held. points=2: the knee (unconstrained)
    # and the front's far end, a margin constraint that binds (3x the
    # knee's critical delay); a level in between is a binding constraint too
    fr = {
        v: fws.pareto_front(fws.LateralPlant(VEH, speed=v), delay=TAU, points=2, grid=6)
        for v in (10.0, 20.0)
    }
    np.testing.assert_allclose(fr[10.0].margin_decay, fr[20.0].margin_decay, rtol=1e-5)
    np.testing.assert_allclose(fr[10.0].margin, fr[20.0].margin, rtol=1e-5)
    np.testing.assert_allclose(
        fr[10.0].margin_gains.k1 * 100.0, fr[20.0].margin_gains.k1 * 400.0, rtol=1e-4
    )


def test_plot_draws_both_fronts(front):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cplt = front.plot()
    try:
        left, right = cplt.axes[0]
        np.testing.assert_allclose(left.lines[0].get_xdata(), front.margin)
        np.testing.assert_allclose(right.lines[0].get_ydata(), front.effort_decay)
        assert "[s]" in left.get_xlabel() and "[rad/m]" in right.get_xlabel()
    finally:
        plt.close(cplt.figure)


@pytest.mark.parametrize(
    ("kwargs", "exc", "words"),
    [
        ({"points": 1}, ValueError, "points"),
        ({"directions": 2}, ValueError, "directions"),
        ({"max_margin": 0.5}, ValueError, "max_margin"),
        ({"min_effort": 1.0}, ValueError, "min_effort"),
        ({"delay": 0.0}, ValueError, "delay"),
        ({"design": "no"}, TypeError, "design"),
    ],
)
def test_bad_arguments_are_named(front, kwargs, exc, words):
    plant = fws.LateralPlant(VEH, speed=V, steering_lag=LAG)
    call = {"delay": TAU, "design": front.design, **kwargs}
    with pytest.raises(exc, match=words):
        fws.pareto_front(plant, **call)


def test_a_design_for_another_delay_is_refused(front):
    plant = fws.LateralPlant(VEH, speed=V, steering_lag=LAG)
    with pytest.raises(ValueError, match=r"design is for delay 0\.24"):
        fws.pareto_front(plant, delay=0.3, design=front.design)
