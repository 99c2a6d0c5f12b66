"""The compiled Radau IIA port against scipy's Radau, step by step.

The engine's Radau driver (its single-run form
:func:`~fws_control.simulation.compiled.radau_run`) ports
:class:`scipy.integrate.Radau`: given the same right-hand side, Jacobian
(:func:`~fws_control.simulation.compiled.closed_loop_jac`, itself checked
against finite differences in ``test_compiled_jacobian.py``) and first
step, it must accept the same steps (times and states) and build the same
dense output. Not to 1e-12: on this loop scipy's own Radau moves its step
times by 2e-7 relative (states 1.6e-7 tolerance-scaled) when its Jacobian is
scaled by 1 + 4e-16 (measured at T = 0.05 s, rtol 1e-8, 463 steps): the
error estimate ``solve(M, f + Z E / h)`` cancels, and the step-size control
amplifies rounding. The port (same operations, different summation order
in its matrix products) differs by 2.9e-7 there, 6.2e-7 at T = 1 ms, 2.6e-8
with the limits: same step counts, agreement to 2e-6.
"""

import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import Radau, solve_ivp

import fws_control as fws

numba = pytest.importorskip(
    "numba", reason="numba is not installed: the compiled engine (extra 'fast') "
    "is not tested"
)  # fmt: skip

from fws_control.simulation import compiled  # noqa: E402
from fws_control.simulation.compiled import (  # noqa: E402
    DEFAULT_MARGIN,
    curvature_table,
    integrate_compiled,
    shared_parameters,
)
from fws_control.simulation.compiled_variants import variant  # noqa: E402

# The right-hand side and Jacobian of scipy's reference runs, as the engine
# compiles them for a call without a delay, the dynamic model, a
# controller's law or a varying speed (none of these tests uses one; the
# Radau driver runs only such calls): the code that runs, and a third of the
# full kernels' compilation, which no production call makes from Python.
closed_loop_jac, closed_loop_rhs = (
    variant(getattr(compiled, name), ())
    for name in ("closed_loop_jac", "closed_loop_rhs")
)


def _fun_jac(p, q, tab):
    """The compiled right-hand side and Jacobian of a 5-state run, for scipy."""

    def fun(t, y):
        out = np.empty(5)
        closed_loop_rhs(t, y, p, q, tab.breaks, tab.coefs, out)
        return out

    def jac(t, y):
        out = np.empty((5, 5))
        closed_loop_jac(t, y, p, q, tab.breaks, tab.coefs, out)
        return out

    return fun, jac


@pytest.mark.parametrize(
    ("tau", "limited", "rtol", "duration"),
    [(0.05, False, 1e-8, 40.0), (0.001, False, 1e-10, 15.0), (0.05, True, 1e-6, 40.0)],
)
def test_radau_port_takes_scipys_steps(tau, limited, rtol, duration):
    # the engine's Radau driver (integrate_compiled, its dense solution
    # kept: one record per accepted step) against scipy's Radau stepping on
    # the same right-hand side and Jacobian from the same initial state
    lim = dict(max_steer_front=0.6, max_steer_rear=0.3, max_steer_rate_front=0.4,
               max_steer_rate_rear=0.2) if limited else {}  # fmt: skip
    veh = fws.Vehicle(2.7, 1.35, **lim)
    tab = curvature_table(fws.Arc(0.1))
    q = shared_parameters(veh, tab, feedforward=True, time_constant=tau)
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-0.5, pole=-1.0)
    p = np.array([5.0, g.k1, g.k2, g.ratio, 0, 0, 0, 0.0])
    atol = rtol * 1e-2
    sol = []
    states, status, _, t_stop, stats = integrate_compiled(
        veh, tab, fws.SteeringGains(np.atleast_1d(g.k1), g.k2, g.ratio),
        speed=np.array([5.0]), feedforward=True,
        path_state=np.array([[0.0, -0.5 if limited else -5.0, 0.0]]),
        t_eval=np.array([0.0, duration]), time_constant=tau, rtol=rtol, atol=atol,
        switching=False, method="Radau", solution=sol,
    )  # fmt: skip
    assert (status[0], t_stop[0]) == ("ok", duration)
    records = sol[0].records
    steps = len(records)
    assert stats[0, 0] == steps  # (no step cut: no event, no switch)
    y_old, F = records[:, 2:7], records[:, 7:].reshape(steps, 7, 5)
    fun, jac = _fun_jac(p, q, tab)
    ref = Radau(fun, 0.0, y_old[0], duration, rtol=rtol, atol=atol, jac=jac)
    ts, ys, dense = [0.0], [y_old[0]], []
    while ref.status == "running":
        ref.step()
        ts.append(ref.t)
        ys.append(ref.y.copy())
        dense.append(ref.dense_output())
    assert ref.status == "finished"
    assert steps == len(ts) - 1, (steps, len(ts) - 1)
    # the same steps; the step times drift apart by rounding over the 40 s
    # runs (measured 5.1e-6 relative at the last steps with scipy 1.17)
    t_new = records[:, 0] + records[:, 1]
    np.testing.assert_allclose(np.append(records[:, 0], t_new[-1]), ts, rtol=1e-5,
                               atol=0)  # fmt: skip
    scale = np.max(np.abs(ys), axis=0) + atol
    np.testing.assert_allclose(np.vstack([y_old, states[:, 0, -1]]) / scale,
                               np.array(ys) / scale, rtol=0, atol=1e-5)  # fmt: skip
    # the same collocation polynomial on every step, at the same fractions
    # of each one's own step
    from fws_control.simulation import compiled_dop853

    out = np.empty(5)
    for k in range(steps):
        for x in (0.25, 0.5, 0.75):
            t = records[k, 0] + x * records[k, 1]
            compiled_dop853.dense_eval(t, records[k, 0], t_new[k], y_old[k], F[k],
                                       out)  # fmt: skip
            want = dense[k](ts[k] + x * (ts[k + 1] - ts[k]))
            np.testing.assert_allclose(out / scale, want / scale, rtol=0, atol=1e-5)


def _scipy_radau_run(veh, tab, g, tau, y0, t_eval, rtol, atol, events=None):
    """scipy's Radau on the compiled right-hand side and Jacobian."""
    q = shared_parameters(veh, tab, feedforward=True, time_constant=tau)
    p = np.array([5.0, g.k1, g.k2, g.ratio, 0, 0, 0, 0.0], dtype=float)
    fun, jac = _fun_jac(p, q, tab)
    return solve_ivp(fun, (t_eval[0], t_eval[-1]), y0, method="Radau", jac=jac,
                     rtol=rtol, atol=atol, t_eval=t_eval, dense_output=True,
                     events=events)  # fmt: skip


@pytest.mark.parametrize(
    ("tau", "rtol", "duration"), [(0.05, 1e-8, 40.0), (0.001, 1e-10, 15.0)]
)
def test_engine_radau_takes_scipys_steps(tau, rtol, duration):
    # integrate_compiled(method="Radau"): scipy's first step (its rule for
    # order 3), the steps of _radau_step, the outputs from the collocation
    # polynomial written in DOP853's form -- the same steps and outputs as
    # solve_ivp's Radau given the same Jacobian
    veh = PAPER_VEHICLE
    tab = curvature_table(fws.Arc(0.1))
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-0.5, pole=-1.0)
    t_eval = np.linspace(0.0, duration, 401)
    atol = rtol * 1e-2
    states, status, _, _, stats = integrate_compiled(
        veh, tab, fws.SteeringGains(np.atleast_1d(g.k1), g.k2, g.ratio),
        speed=np.array([5.0]), feedforward=True,
        path_state=np.array([[0.0, -5.0, 0.0]]), t_eval=t_eval,
        time_constant=tau, rtol=rtol, atol=atol, switching=False, method="Radau",
    )  # fmt: skip
    assert status[0] == "ok"
    y = states[:, 0, :]
    ref = _scipy_radau_run(veh, tab, g, tau, y[:, 0], t_eval, rtol, atol)
    assert stats[0, 0] == ref.sol.ts.size - 1  # accepted steps
    scale = np.max(np.abs(ref.y), axis=1) + atol
    np.testing.assert_allclose(y / scale[:, None], ref.y / scale[:, None], rtol=0,
                               atol=2e-6)  # fmt: skip


def test_engine_radau_stops_where_scipys_event_does():
    # diverging gains (k2 < 0): |delta_f| (the actuator state) reaches
    # pi/2 - margin; the compiled Radau locates it on its dense output as
    # scipy's terminal event does on its own
    veh = PAPER_VEHICLE
    tab = curvature_table(fws.Arc(0.1))
    g = fws.SteeringGains(0.2, -0.5, 0.0)
    tau, rtol, atol = 0.05, 1e-10, 1e-12
    t_eval = np.linspace(0.0, 20.0, 201)
    states, status, _, t_stop, _ = integrate_compiled(
        veh, tab, fws.SteeringGains(np.array([0.2]), -0.5, 0.0),
        speed=np.array([5.0]), feedforward=True,
        path_state=np.array([[0.0, -1.0, 0.0]]), t_eval=t_eval, time_constant=tau,
        rtol=rtol, atol=atol, switching=False, method="Radau",
    )  # fmt: skip
    assert status[0] == "singular_steering"

    def steer(t, y):
        return (0.5 * np.pi - DEFAULT_MARGIN) - abs(y[3])

    steer.terminal, steer.direction = True, -1
    y0 = states[:, 0, 0]
    ref = _scipy_radau_run(veh, tab, g, tau, y0, t_eval, rtol, atol, events=[steer])
    assert ref.status == 1
    assert t_stop[0] == pytest.approx(ref.t_events[0][0], rel=1e-9, abs=1e-9)
    done = t_eval <= t_stop[0]
    np.testing.assert_allclose(states[:, 0, done], ref.y, rtol=1e-7, atol=1e-9)
    assert np.all(np.isnan(states[:, 0, ~done]))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    q=st.lists(st.floats(-1e3, 1e3), min_size=15, max_size=15),
    x=st.floats(0.0, 1.0),
)
def test_radau_dense_output_in_dop853_form_is_scipys_polynomial(q, x):
    # scipy's RadauDenseOutput: y_old + Q @ (x, x^2, x^3); the engine
    # writes Q as DOP853's coefficients F and evaluates dense_eval
    from fws_control.simulation import compiled_dop853, compiled_radau

    Q = np.array(q).reshape(5, 3)
    y_old = np.linspace(-1.0, 1.0, 5)
    F = np.empty((7, 5))
    compiled_radau.radau_dense(Q, F)
    out = np.empty(5)
    compiled_dop853.dense_eval(2.0 + 0.5 * x, 2.0, 2.5, y_old, F, out)
    want = y_old + Q @ np.array([x, x**2, x**3])
    np.testing.assert_allclose(out, want, rtol=1e-12, atol=1e-9)
