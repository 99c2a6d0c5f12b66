"""The time-varying-speed certificate (fws_control.varying_speed).

References, all written here from the original formulas: the linearised
kinematic loop on a straight path,

    de/dt = V theta + V a delta_f,   dtheta/dt = (V/f)(1 - a) delta_f,
    delta_f = -k1 e - k2 theta,

with the schedule's interpolation of k1 V^2, k2 V and a (np.interp), a
solve_ivp simulation of that loop with the speed running up and down the
range at the given |dV/dt| (a triangle wave), and eigenvalues of the
frozen matrices.
"""

from __future__ import annotations

import bisect
import pathlib
import re
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import fws_control as fws

DOC = pathlib.Path(__file__).resolve().parents[1] / "docs" / "speed_certificate.md"
F = 2.7  # wheelbase of the paper's vehicle [m]


def loop_matrix(v, speeds, k1, k2, ratio, f=F):
    """Closed-loop A(V) of the schedule (nodes `speeds`), from the formula."""
    v = np.asarray(v, dtype=float)
    q1 = np.interp(v, speeds, np.asarray(k1) * np.asarray(speeds) ** 2)
    q2 = np.interp(v, speeds, np.asarray(k2) * np.asarray(speeds))
    a = np.interp(v, speeds, ratio)
    g1, g2 = q1 / v**2, q2 / v
    return np.stack(
        [
            np.stack([-v * a * g1, v * (1 - a * g2)], axis=-1),
            np.stack([-(v / f) * (1 - a) * g1, -(v / f) * (1 - a) * g2], axis=-1),
        ],
        axis=-2,
    )


def triangle(lo, hi, rate):
    """Speed running lo -> hi -> lo ... at |dV/dt| = rate."""
    period = 2.0 * (hi - lo) / rate

    def speed(t):
        s = (t % period) / period
        return lo + (hi - lo) * (2 * s if s < 0.5 else 2 - 2 * s)

    return speed


def scalar_loop(speeds, k1, k2, ratio, f=F):
    """The loop_matrix formula for one scalar speed, in plain floats.

    solve_ivp calls the right-hand side some 10^5 times; numpy's per-call
    overhead on 2 x 2 arrays made it the cost of the simulations below. The
    same interpolation (np.interp's segments, clamped at the ends) and the
    same entries; simulate_norm checks it against loop_matrix on a grid.
    """
    xs = [float(v) for v in speeds]
    ys1 = [float(k * v * v) for k, v in zip(k1, speeds, strict=True)]
    ys2 = [float(k * v) for k, v in zip(k2, speeds, strict=True)]
    ya = [float(a) for a in np.broadcast_to(ratio, np.shape(speeds))]
    last = len(xs) - 2

    def interp(v, i, ys):
        return ys[i] + (v - xs[i]) * (ys[i + 1] - ys[i]) / (xs[i + 1] - xs[i])

    def matrix(v):
        v = min(max(v, xs[0]), xs[-1])
        i = min(max(bisect.bisect_right(xs, v) - 1, 0), last)
        g1 = interp(v, i, ys1) / (v * v)
        g2 = interp(v, i, ys2) / v
        a = interp(v, i, ya)
        return ((-v * a * g1, v * (1 - a * g2)),
                (-(v / f) * (1 - a) * g1, -(v / f) * (1 - a) * g2))  # fmt: skip

    return matrix


def simulate_norm(lo, hi, rate, schedule, duration, x0=(1.0, 0.0), max_step=0.05):
    """|x(duration)| of dx/dt = A(V(t)) x, V a triangle wave at `rate`.

    `schedule` is (speeds, k1, k2, ratio[, f]) of loop_matrix.
    """
    matrix = scalar_loop(*schedule)
    v = np.linspace(lo, hi, 1001)
    np.testing.assert_allclose(
        [matrix(x) for x in v], loop_matrix(v, *schedule), rtol=1e-12, atol=1e-12
    )
    speed = triangle(lo, hi, rate)

    def rhs(t, x):
        (a00, a01), (a10, a11) = matrix(speed(t))
        return [a00 * x[0] + a01 * x[1], a10 * x[0] + a11 * x[1]]

    sol = solve_ivp(
        rhs,
        (0.0, duration),
        np.asarray(x0, dtype=float),
        max_step=max_step,
        rtol=1e-8,
        atol=1e-12,
    )
    assert sol.success
    return float(np.linalg.norm(sol.y[:, -1]))


def check_lyapunov(cert, matrix, rate):
    """Independent check: P(V) > 0 and A^T P + P A +- rate dP/dV < 0 on a grid."""
    lo, hi = cert.speed_range
    v = np.linspace(lo, hi, 1501)[1:-1]
    P = cert.P_at(v)
    assert np.linalg.eigvalsh(P)[:, 0].min() > 0.0
    # dP/dV by a central difference (exact for the piecewise-affine P away
    # from the nodes; a node between the two points gives a mean slope)
    h = 1e-6
    dP = (cert.P_at(np.minimum(v + h, hi)) - cert.P_at(np.maximum(v - h, lo))) / (2 * h)
    A = np.array([matrix(x) for x in v])
    for sign in (1.0, -1.0):
        M = np.swapaxes(A, 1, 2) @ P + P @ A + sign * rate * dP
        assert np.linalg.eigvalsh(M)[:, -1].max() < 0.0


# --- the counterexample: stiffness pumped by the speed ---------------------
# a = 0: in y = e the loop is y'' + (q2/f - V'/V) y' + (q1/f) y = 0. The
# schedule alternates q1/f = omega^2 between 1 and 9 1/s^2 from one node to
# the next (1 m/s apart) with constant damping q2/f = 0.4 1/s: every frozen
# loop is stable (roots with real part -0.2), but a speed sweeping the nodes
# at |dV/dt| = rho modulates the stiffness with period 2 (1 m/s)/rho; near
# half the natural period (rho = 2 omega0/pi with omega0^2 ~ 5, about 1.4)
# the loop resonates parametrically (a Mathieu instability) and diverges.
CX_SPEEDS = np.arange(10.0, 20.5, 1.0)
CX_W2 = np.where(np.arange(CX_SPEEDS.size) % 2 == 0, 1.0, 9.0)
CX_K1 = CX_W2 * F / CX_SPEEDS**2
CX_K2 = 0.4 * F / CX_SPEEDS
CX_RATIO = np.zeros_like(CX_SPEEDS)
CX_FAST, CX_SLOW = 1.4, 0.1  # [m/s^2]
CX_SCHEDULE = (CX_SPEEDS, CX_K1, CX_K2, CX_RATIO)


def cx_matrix(v):
    return loop_matrix(v, CX_SPEEDS, CX_K1, CX_K2, CX_RATIO)


@pytest.fixture(scope="module")
def counterexample():
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
    sch = fws.GainSchedule(speeds=CX_SPEEDS, k1=CX_K1, k2=CX_K2, ratio=CX_RATIO)
    # cells=10: one cell per interval of the schedule, so P(V) bends at its
    # nodes; it certifies the slow rate as finer cells do (check_lyapunov
    # verifies P independently)
    fast = fws.speed_certificate(veh, sch, rate=CX_FAST, cells=10)
    slow = fws.speed_certificate(veh, sch, rate=CX_SLOW, cells=10)
    return fast, slow


def test_counterexample_is_stable_at_every_frozen_speed():
    v = np.linspace(10.0, 20.0, 4001)
    abscissa = np.linalg.eigvals(cx_matrix(v)).real.max(axis=-1)
    # damping 0.4 1/s: both roots have real part -0.2 (complex) at every speed
    np.testing.assert_allclose(abscissa, -0.2, atol=1e-9)


def test_counterexample_diverges_fast_and_is_refused(counterexample):
    fast, _ = counterexample
    grown = simulate_norm(10.0, 20.0, CX_FAST, CX_SCHEDULE, duration=150.0)
    assert grown > 1e6  # from |x0| = 1
    assert fast.certified is False
    assert "not proved" in fast.message
    assert fast.rate_bracket[1] == CX_FAST


def test_counterexample_certified_slow_and_converges(counterexample):
    _, slow = counterexample
    assert slow.certified is True
    assert slow.certified_rate == CX_SLOW
    check_lyapunov(slow, cx_matrix, CX_SLOW)
    assert simulate_norm(10.0, 20.0, CX_SLOW, CX_SCHEDULE, duration=150.0) < 1e-6


# --- the paper's double-root schedule ---------------------------------------


def doc_number(key: str) -> float:
    """A number of docs/speed_certificate.md, written `key = <number>`."""
    m = re.search(rf"`{re.escape(key)} = ([0-9.eE+-]+)`", DOC.read_text())
    assert m is not None, f"{key} not found in {DOC}"
    return float(m.group(1))


def test_paper_schedule_a0_certified_at_documented_bound():
    """a = 0, lambda0 = -1 on 5-30 m/s: k1 V^2 = f, k2 V = 2f are exact."""
    rho = doc_number("rate_a0")
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=np.array([5.0, 30.0]))
    g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    # the double-root rule written out: k1 = lambda0^2 f / V^2, k2 = -2 lambda0 f / V
    np.testing.assert_allclose(g.k1, F / np.array([25.0, 900.0]), rtol=1e-12)
    np.testing.assert_allclose(g.k2, 2 * F / np.array([5.0, 30.0]), rtol=1e-12)
    sch = fws.GainSchedule(speeds=[5.0, 30.0], k1=g.k1, k2=g.k2, ratio=[0.0, 0.0])
    cert = fws.speed_certificate(veh, sch, rate=rho, cells=int(doc_number("cells")))
    assert cert.certified, cert.message

    def matrix(v):
        return loop_matrix(v, [5.0, 30.0], g.k1, g.k2, [0.0, 0.0])

    check_lyapunov(cert, matrix, rho)
    # the speed sweeping 5 -> 30 -> 5 m/s at the bound: the loop converges
    sched = ([5.0, 30.0], g.k1, g.k2, [0.0, 0.0])
    assert simulate_norm(5.0, 30.0, rho, sched, 20.0, max_step=0.002) < 1e-5


def test_paper_schedule_zero_sideslip_certified_at_documented_bound():
    """a = a(V) (zero sideslip, BMW 320i), lambda0 = -1 on 5-30 m/s."""
    rho = doc_number("rate_zero_sideslip")
    cells = int(doc_number("cells"))
    veh = fws.vehicles.BMW_320I

    def gains(v):
        p = fws.LateralPlant(veh, speed=v)
        return fws.double_root_gains(p, ratio=fws.zero_sideslip_ratio, pole=-1.0)

    cert = fws.speed_certificate(
        veh, gains, speed_range=(5.0, 30.0), rate=rho, cells=cells
    )
    assert cert.certified, cert.message
    # the certified object: the gains tabulated at the nodes, interpolated
    nodes = cert.nodes
    np.testing.assert_allclose(nodes, np.linspace(5.0, 30.0, cells + 1))
    g = gains(nodes)
    a = fws.zero_sideslip_ratio(veh, speed=nodes)
    np.testing.assert_allclose(g.ratio, a, rtol=1e-14)

    def matrix(v):
        return loop_matrix(v, nodes, g.k1, g.k2, a, f=veh.wheelbase)

    # at the nodes the frozen loop has the double root -1
    lam = np.linalg.eigvals(matrix(nodes))
    np.testing.assert_allclose(lam.real, -1.0, atol=1e-5)
    check_lyapunov(cert, matrix, rho)
    sched = (nodes, g.k1, g.k2, a, veh.wheelbase)
    assert simulate_norm(5.0, 30.0, rho, sched, 20.0, max_step=0.002) < 1e-5


# --- frozen-speed sanity ------------------------------------------------------


# seed 0 is frozen-unstable at an end node (10 m/s), seed 5 in a pocket at the
# middle node; seeds 1 and 7 are stable, their abscissa largest at the middle
# node (1) and at an end node (7, the closer to the axis: -0.074 1/s). (Seed 6,
# stable with its largest abscissa at the end node too, repeated seed 7.)
@pytest.mark.parametrize("seed", [0, 1, 5, 7])
def test_rate_zero_certificate_iff_frozen_hurwitz(seed):
    rng = np.random.default_rng(seed)
    speeds = np.array([10.0, 12.0, 14.0])
    w2 = rng.uniform(0.2, 4.0, 3)
    damping = rng.uniform(-0.1, 1.0, 3)
    k1, k2 = w2 * F / speeds**2, damping * F / speeds
    v = np.linspace(10.0, 14.0, 8001)
    abscissa = np.linalg.eigvals(loop_matrix(v, speeds, k1, k2, np.zeros(3))).real.max()
    assert abs(abscissa) > 0.02, "choose seeds away from the stability boundary"
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
    sch = fws.GainSchedule(speeds=speeds, k1=k1, k2=k2, ratio=np.zeros(3))
    cert = fws.speed_certificate(veh, sch, rate=0.0, cells=12)
    assert cert.certified == (abscissa < 0.0), (seed, abscissa, cert.message)
    np.testing.assert_allclose(cert.frozen_abscissa, abscissa, atol=1e-3)
    if cert.certified:
        check_lyapunov(cert, lambda x: loop_matrix(x, speeds, k1, k2, np.zeros(3)), 0.0)
    else:
        assert cert.P is None and cert.max_rate is None
        assert "unstable" in cert.message


# --- the steering lag and the polynomial form ---------------------------------


def test_steering_lag_adds_states_and_is_certified():
    """Lagged plant: 4 states; the closed loop is checked against linearize."""
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=10.0, steering_lag=0.1)
    sch = fws.GainSchedule(
        speeds=[10.0, 20.0], k1=[F / 100, F / 400], k2=[2 * F / 10, 2 * F / 20],
        ratio=[0.0, 0.0],
    )  # fmt: skip
    cert = fws.speed_certificate(plant, sch, rate=1.0, cells=4)
    assert cert.states == ("e", "theta", "delta_f_act", "delta_r_act")
    assert cert.certified, cert.message
    # independent: the lagged closed loop from the library's named state space
    v = np.linspace(10.0, 20.0, 301)
    P = cert.P_at(v)
    dP = np.gradient(P, v, axis=0)
    for i, x in enumerate(v):
        g = sch.at(x)
        cl = fws.closed_loop(fws.LateralPlant(veh, speed=x, steering_lag=0.1), g)
        A = np.asarray(cl.A)
        for sign in (1.0, -1.0):
            M = A.T @ P[i] + P[i] @ A + sign * 1.0 * dP[i]
            assert np.linalg.eigvalsh(M)[-1] < 0.0


# --- input checks -------------------------------------------------------------

VEH = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
SCH = fws.GainSchedule(
    speeds=[5.0, 10.0], k1=[F / 25, F / 100], k2=[2 * F / 5, 2 * F / 10],
    ratio=[0.0, 0.0],
)  # fmt: skip


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        (dict(delay=0.1), "delay=0.1"),
        (dict(speed_range=(4.0, 10.0)), r"speed_range \(4.0, 10.0\) must lie"),
        (dict(speed_range=(8.0, 6.0)), "speed_range must satisfy"),
        (dict(speed_range=(5.0, np.nan)), "speed_range must satisfy"),
        (dict(rate=-1.0), "rate must be >= 0"),
        (dict(rate=np.inf), "rate"),
        (dict(cells=0), "cells must be in 1..400, got 0"),
        (dict(rtol=1.5), "rtol must be in"),
        (dict(max_rate=0.0), "max_rate must be > 0"),
    ],
)
def test_bad_input_raises_value_error(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        fws.speed_certificate(VEH, SCH, **kwargs)


def test_bad_kinds_raise():
    with pytest.raises(TypeError, match="plant must be"):
        fws.speed_certificate("car", SCH)
    with pytest.raises(TypeError, match="gains must be"):
        fws.speed_certificate(VEH, 3.0)
    with pytest.raises(TypeError, match="cells must be an int"):
        fws.speed_certificate(VEH, SCH, cells=2.5)
    with pytest.raises(ValueError, match="speed_range is required"):
        fws.speed_certificate(VEH, SCH.at)
    dyn = fws.LateralPlant(fws.vehicles.BMW_320I, speed=10.0, model="dynamic")
    with pytest.raises(ValueError, match="model='dynamic'"):
        fws.speed_certificate(dyn, SCH)


def test_missing_extra_names_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "cvxpy", None)
    with pytest.raises(ImportError, match="certificates"):
        fws.speed_certificate(VEH, SCH, rate=0.1, cells=1)


def test_plot_labels():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cert = fws.speed_certificate(VEH, SCH, rate=0.5, cells=2)
    cplt = cert.plot()
    ax0, ax1 = cplt.axes[0]
    assert ax0.get_xlabel() == ax1.get_xlabel() == "speed V [m/s]"
    assert "[1/s]" in ax1.get_ylabel()
    assert "0.5" in cplt.figure._suptitle.get_text()
    # the drawn decay is negative everywhere (certified)
    for line in ax1.get_lines()[:2]:
        assert np.max(line.get_ydata()) < 0.0
    plt.close(cplt.figure)


def test_paper_schedule_nonlinear_loop_converges_at_the_documented_bound():
    """The nonlinear kinematic loop, its speed oscillating over the whole
    range 5-30 m/s with the largest |dV/dt| the page certifies (a = 0):
    the error decays. The schedule's table spans exactly the range, so the
    rate of the scheduled command is one-sided at its ends."""
    rho = doc_number("rate_a0")
    veh = fws.Vehicle(wheelbase=F, rear_to_cg=1.35)
    w = rho / 12.5  # V = 17.5 - 12.5 cos(w t): |dV/dt| <= 12.5 w = rho
    prof = fws.SpeedProfile.from_function(lambda t: 17.5 - 12.5 * np.cos(w * t))
    plant = fws.LateralPlant(veh, speed=5.0)
    sch = fws.GainSchedule.double_root(
        plant, speeds=np.linspace(5.0, 30.0, 25), pole=-1.0, ratio=0.0
    )
    res = fws.simulate(
        plant, fws.Straight(), sch, initial_state=(0.0, 0.5, 0.0), duration=8.0,
        speed=prof,
    )  # fmt: skip
    # 8 s: the speed has swept the range some 90 times, and the error
    # (0.5 m at the start, double root at -1 1/s) is down to 1.4e-4 m
    assert res.status == "ok"
    v = np.asarray(res.longitudinal_speed)
    assert v.min() == pytest.approx(5.0, abs=1e-3) and v.max() > 29.9
    assert abs(res.e[-1]) < 1e-3 * 0.5 and abs(res.theta[-1]) < 1e-3
