"""Sampled controllers on the compiled engine (simulation.compiled_sampled).

The compiled engine integrates a sampled controller's run held command by
held command (the law ``"held"``). References: the closed-form motion under
a constant command, the actuator's exponential, and the numpy engine's run
of the same controller (itself checked against a piecewise solve_ivp in
``tests/test_mpc.py``, on both engines).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

import fws_control as fws
from fws_control.simulation.compiled import available, integrate_compiled
from fws_control.simulation.compiled_sampled import HeldCommand

pytestmark = pytest.mark.skipif(
    not available(), reason="numba is not installed: no compiled engine"
)

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
BMW = fws.vehicles.BMW_320I


def test_held_law_follows_the_closed_form_circle():
    """Under a constant command on a straight path the heading error grows
    at the yaw rate of eq. (10) and e is its closed-form integral."""
    V, df, dr, T = 8.0, 0.12, -0.04, 1.5
    t = np.linspace(0.0, T, 31)
    z0 = np.array([[0.0, 0.3, 0.05]])
    states, status, *_ = integrate_compiled(
        VEH, fws.Straight(), HeldCommand([df], [dr]), speed=np.array([V]),
        feedforward=False, path_state=z0, t_eval=t, time_constant=None,
        rtol=1e-12, atol=1e-13,
    )  # fmt: skip
    w = V * math.sin(df - dr) / (VEH.wheelbase * math.cos(df))
    phase = 0.05 + dr
    e = 0.3 + V / w * (np.cos(phase) - np.cos(phase + w * t))
    s = V / w * (np.sin(phase + w * t) - np.sin(phase))
    assert status.tolist() == ["ok"]
    np.testing.assert_allclose(states[2, 0], 0.05 + w * t, rtol=0, atol=1e-10)
    np.testing.assert_allclose(states[1, 0], e, rtol=0, atol=1e-9)
    np.testing.assert_allclose(states[0, 0], s, rtol=0, atol=1e-9)


def test_actuator_state_starts_the_actuator_there():
    """From a given actuator state the angles relax to the held command as
    ``c + (delta_0 - c) exp(-t / T)`` (no rate limit)."""
    T_act, c = 0.2, np.array([0.1, -0.03])
    t = np.linspace(0.0, 1.0, 11)
    act0 = np.array([[-0.05, 0.02]])
    states, *_ = integrate_compiled(
        VEH, fws.Straight(), HeldCommand([c[0]], [c[1]]), speed=np.array([5.0]),
        feedforward=False, path_state=np.array([[0.0, 0.0, 0.0]]), t_eval=t,
        time_constant=T_act, actuator_state=act0, rtol=1e-12, atol=1e-13,
    )  # fmt: skip
    for row, j in ((3, 0), (4, 1)):
        want = c[j] + (act0[0, j] - c[j]) * np.exp(-t / T_act)
        np.testing.assert_allclose(states[row, 0], want, rtol=0, atol=1e-10)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (dict(actuator_state=np.zeros((2, 2)), time_constant=0.1), r"\(1, 2\)"),
        (dict(actuator_state=np.zeros((1, 2)), time_constant=None), "time_constant"),
    ],
)
def test_bad_actuator_state_refused(kw, match):
    with pytest.raises(ValueError, match=r"actuator_state.*" + match):
        integrate_compiled(
            VEH, fws.Straight(), HeldCommand([0.0], [0.0]), speed=np.array([5.0]),
            feedforward=False, path_state=np.zeros((1, 3)),
            t_eval=np.linspace(0.0, 1.0, 3), **kw,
        )  # fmt: skip


# (plant options, MPC options, delay [s], vehicle): the cases of compare's
# MPC row, each model with and without the actuator and the delay
CASES = [
    ({}, dict(sample_time=0.04, horizon=20), 0.0, VEH),
    ({"steering_lag": 0.1}, dict(sample_time=0.05, horizon=20, delay=0.1), 0.1, VEH),
    ({"model": "dynamic"}, dict(sample_time=0.04, horizon=20), 0.0, BMW),
    (
        {"model": "dynamic", "tyre": "magic", "steering_lag": 0.05},
        dict(sample_time=0.03, horizon=15, delay=0.06),
        0.06,
        BMW,
    ),
]


@pytest.mark.parametrize(("plant_kw", "mpc_kw", "delay", "veh"), CASES)
def test_mpc_runs_as_on_the_numpy_engine(plant_kw, mpc_kw, delay, veh):
    """The compiled run of the MPC through the lane change equals the numpy
    engine's: each engine integrates the same held segments with DOP853 at
    rtol 1e-10, so the states agree to the tolerance's scale (measured: at
    most 4e-11 m and rad; the lateral acceleration, 20-50 m/s^2, to 9e-8),
    and the commands, which OSQP computes from those states, alike."""
    plant = fws.LateralPlant(veh, speed=20.0, **plant_kw)
    lane = fws.double_lane_change(vehicle_width=1.8)
    kw = dict(initial_state=(0.0, 0.3, 0.0), duration=3.0, delay=delay)
    mpc = fws.MPCController(**mpc_kw)
    got = fws.simulate(plant, lane.path, mpc, **kw)
    ref = fws.simulate(plant, lane.path, mpc, engine="numpy", **kw)
    assert got.engine == "compiled" and ref.engine == "numpy"
    assert got.status == ref.status == "ok"
    for name in ("x", "y", "psi", "s", "e", "theta", "delta_f", "delta_r"):
        np.testing.assert_allclose(
            getattr(got, name), getattr(ref, name), rtol=0, atol=1e-9, err_msg=name
        )
    for name in ("lateral_accel", "yaw_rate", "v_y", "delta_f_rate", "delta_r_rate"):
        np.testing.assert_allclose(
            getattr(got, name), getattr(ref, name), rtol=1e-8, atol=1e-7,
            err_msg=name,
        )  # fmt: skip
    np.testing.assert_allclose(got.run_peak, ref.run_peak, rtol=1e-8, atol=1e-9)


@dataclass(frozen=True, eq=False)
class ConstantTurn(fws.LateralController):
    """A sampled controller that steers by a fixed angle per run's offset
    sign; it drives each run off the end of a short straight."""

    sample_time: float = 0.1
    angle: float = 0.2
    label = "constant turn"

    def start(self, vehicle, path, *, speed):
        angle = self.angle

        class Run:
            def step(self, *, s, e, theta):
                return (angle if e <= 0 else -angle), 0.0

        return Run()


def test_stops_inside_a_segment_end_that_run_only():
    """Two runs on a 12 m straight: the one that starts 3.3 m along leaves
    the path in the middle of a held segment (end_of_path), the other
    completes; status, stop time and signals are the numpy engine's."""
    path = fws.Straight(length=12.0)
    plant = fws.LateralPlant(VEH, speed=5.0)
    x0 = np.array([[3.3, 0.5, 0.0], [0.0, -0.3, 0.0]])
    kw = dict(initial_state=x0, duration=2.0, dt=0.05)
    got = fws.simulate_batch(plant, path, ConstantTurn(), **kw)
    ref = fws.simulate_batch(plant, path, ConstantTurn(), engine="numpy", **kw)
    assert got.engine == "compiled"
    assert got.status.tolist() == ref.status.tolist() == ["end_of_path", "ok"]
    assert 0.1 < got.t_stop[0] < 2.0
    assert 1e-3 < got.t_stop[0] % 0.1 < 0.1 - 1e-3  # inside a held segment
    np.testing.assert_allclose(got.t_stop, ref.t_stop, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(np.isnan(got.e), np.isnan(ref.e))
    np.testing.assert_allclose(got.e, ref.e, rtol=0, atol=1e-9)
    np.testing.assert_allclose(got.delta_f, ref.delta_f, rtol=0, atol=0)


@pytest.mark.parametrize("engine", ["compiled", "numpy"])
def test_a_run_of_one_instant_shows_the_first_command(engine):
    """A single output time: the run is the initial instant, whose sample
    shows the command measured there (e = 0.5 > 0: -0.2 rad)."""
    plant = fws.LateralPlant(VEH, speed=10.0)
    res = fws.simulate(
        plant, fws.Straight(), ConstantTurn(), initial_state=(0.0, 0.5, 0.0),
        duration=1.0, t_eval=[0.0], engine=engine,
    )  # fmt: skip
    assert res.engine == engine and res.status == "ok"
    assert np.ravel(res.e).tolist() == [0.5]
    assert np.ravel(res.delta_f).tolist() == [-0.2]


def test_out_receives_the_sampled_runs_signals():
    """simulate_batch(out=) of a sampled controller on the compiled engine
    writes the signals into the given array: equal to the run without it,
    NaN after a stop, and the kept-signals subset alike."""
    path = fws.Straight(length=12.0)
    plant = fws.LateralPlant(VEH, speed=5.0)
    x0 = np.array([[3.3, 0.5, 0.0], [0.0, -0.3, 0.0]])
    kw = dict(initial_state=x0, duration=2.0, dt=0.05)
    ref = fws.simulate_batch(plant, path, ConstantTurn(), **kw)
    out = np.full((2, 15, ref.t.size), 7.0)
    got = fws.simulate_batch(plant, path, ConstantTurn(), out=out, **kw)
    assert got.engine == "compiled" and np.shares_memory(got.signals, out)
    np.testing.assert_array_equal(out, ref.signals)
    assert np.isnan(out[0, :, -1]).all()  # run 0 left the path before the end
    one = np.full((2, 1, ref.t.size), 7.0)
    kept = fws.simulate_batch(
        plant, path, ConstantTurn(), signals=("e",), out=one, **kw
    )
    np.testing.assert_array_equal(one[:, 0], ref.e)
    np.testing.assert_array_equal(kept.e, ref.e)
