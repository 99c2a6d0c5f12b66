"""The plant is the simulated system: simulate(LateralPlant(...), path, controller).

``simulate``, ``simulate_batch`` and ``compare`` take the same
:class:`~fws_control.LateralPlant` as the analysis. The plant-first call must
give *bit for bit* the results of the 0.2 calling form
``simulate(vehicle, path, gains, speed=..., model=..., tyre=...,
actuator_time_constant=...)`` -- still accepted, with a FutureWarning -- on
the paper's scenarios, with a delay, a steering lag, the dynamic model (both
tyres) and each baseline controller: the same runs, not runs within a
tolerance. The lagged and dynamic runs are also held against the
python-control interconnection (``simulate_reference``), an implementation
that shares no integration code with the engine.

The deprecated forms warn with a FutureWarning that names the new form and
return identical results; bad input raises naming the argument, its value
and the valid range.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control as fws
from fws_control.paper.data import PAPER_VEHICLE
from fws_control.paper.scenarios import PAPER_SCENARIOS, scenario_gains
from fws_control.simulation import simulate_reference

DYN = fws.Vehicle(
    wheelbase=2.7, rear_to_cg=1.2, mass=1500.0, yaw_inertia=2600.0,
    cornering_front=8.0e4, cornering_rear=9.5e4, friction=0.9,
)  # fmt: skip

NEW_FORM = "is removed in fws_control 0.4"


def _old(func, *args, **kwargs):
    """A 0.2 call: it must warn (FutureWarning, naming the new form)."""
    with pytest.warns(FutureWarning, match=NEW_FORM) as caught:
        out = func(*args, **kwargs)
    return out, [str(w.message) for w in caught]


def _identical(new, old):
    """Bit for bit: the same grid, signals (NaN tails included), stops, peaks."""
    assert new.engine == old.engine and new.method == old.method
    np.testing.assert_array_equal(new.t, old.t)
    assert np.array_equal(new.signals, old.signals, equal_nan=True)
    np.testing.assert_array_equal(new.status, old.status)
    np.testing.assert_array_equal(new.t_stop, old.t_stop)
    np.testing.assert_array_equal(new.run_peak, old.run_peak)
    np.testing.assert_array_equal(new.run_peak_time, old.run_peak_time)
    np.testing.assert_array_equal(new.speed, old.speed)
    assert (new.model, new.tyre) == (old.model, old.tyre)


def _design(name, ratio=0.5, pole=-1.0):
    sc = PAPER_SCENARIOS[name]
    k1, k2, ok = scenario_gains(sc, ratio, pole, "kinematic")
    assert bool(ok)
    return sc, fws.SteeringGains(float(k1), float(k2), ratio)


# --------------------------------------------------------------------------
# Bit for bit: the plant-first call is the 0.2 call


@pytest.mark.parametrize("name", sorted(PAPER_SCENARIOS))
def test_paper_scenarios_bit_for_bit(name):
    sc, g = _design(name)
    kw = dict(initial_state=sc.initial_state, duration=sc.duration,
              feedforward=sc.feedforward)  # fmt: skip
    # the design's own plant (its curvature, the linearisation point, is not
    # used: the path gives the curvature)
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed, curvature=sc.curvature)
    new = fws.simulate(plant, sc.path, g, **kw)
    old, _ = _old(fws.simulate, PAPER_VEHICLE, sc.path, g, speed=sc.speed, **kw)
    _identical(new, old)
    assert new.status == "ok" and new.e[0] == sc.initial_state[1]
    # "paper" and "kinematic" are two linearisations of one simulated model
    paper = dataclasses.replace(plant, model="paper")
    _identical(fws.simulate(paper, sc.path, g, **kw), new)


def test_a_batch_of_the_four_scenarios_speeds_bit_for_bit():
    # array speeds broadcast against the gains, as the per-run speed did
    speeds = np.array([sc.speed for sc in PAPER_SCENARIOS.values()])
    g = fws.double_root_gains(
        fws.LateralPlant(PAPER_VEHICLE, speed=speeds), ratio=0.5, pole=-1.0
    )
    kw = dict(initial_state=(0.0, 2.0, 0.0), duration=10.0, feedforward=False)
    new = fws.simulate_batch(fws.LateralPlant(PAPER_VEHICLE, speed=speeds),
                             fws.Straight(), g, **kw)  # fmt: skip
    old, _ = _old(fws.simulate_batch, PAPER_VEHICLE, fws.Straight(), g,
                  speed=speeds, **kw)  # fmt: skip
    _identical(new, old)
    np.testing.assert_array_equal(new.speed, speeds)


@pytest.mark.parametrize("delay", [0.1, 0.24])
def test_delay_bit_for_bit(delay):
    sc, g = _design("curve_20", ratio=0.5, pole=-1.0)
    kw = dict(initial_state=sc.initial_state, duration=6.0, dt=0.05, delay=delay)
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed)
    new = fws.simulate(plant, sc.path, g, **kw)
    old, _ = _old(fws.simulate, PAPER_VEHICLE, sc.path, g, speed=sc.speed, **kw)
    _identical(new, old)
    # the delay is the loop's: the command holds its initial value until then
    held = new.t <= delay
    assert np.all(new.delta_f[held] == new.delta_f[0])
    assert new.delta_f[np.argmin(held) + 1] != new.delta_f[0]


def test_steering_lag_bit_for_bit_and_against_the_python_control_loop():
    sc, g = _design("curve_5", ratio=-1.0, pole=-1.0)
    kw = dict(initial_state=sc.initial_state, duration=4.0, dt=0.1)
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed, steering_lag=0.27)
    assert plant.steering_lag == (0.27, 0.27)
    new = fws.simulate(plant, sc.path, g, **kw)
    old, messages = _old(fws.simulate, PAPER_VEHICLE, sc.path, g, speed=sc.speed,
                         actuator_time_constant=0.27, **kw)  # fmt: skip
    _identical(new, old)
    assert any("use steering_lag=" in m for m in messages)
    # the same lag as an equal (front, rear) pair
    pair = fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed, steering_lag=(0.27, 0.27))
    _identical(fws.simulate(pair, sc.path, g, **kw), new)
    # independent reference: the python-control interconnection with the
    # first-order actuator block
    ref = simulate_reference(PAPER_VEHICLE, sc.path, g, speed=sc.speed,
                             steering_lag=0.27, **kw)  # fmt: skip
    out = dict(zip(ref.output_labels, ref.outputs, strict=True))
    np.testing.assert_allclose(new.e, out["e"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(new.delta_f, out["delta_f"], rtol=0, atol=1e-6)
    # the lag is felt: the wheel angle trails the lag-free run's
    free = fws.simulate(fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed),
                        sc.path, g, **kw)  # fmt: skip
    assert np.max(np.abs(free.delta_f - new.delta_f)) > 1e-2


@pytest.mark.parametrize("tyre", ["linear", "magic"])
def test_dynamic_model_bit_for_bit_and_against_the_python_control_loop(tyre):
    g = fws.double_root_gains(DYN, speed=15.0, curvature=0.02, ratio=0.3, pole=-1.0)
    kw = dict(initial_state=(0.0, -1.0, 0.0), duration=4.0, dt=0.1)
    path = fws.Arc(curvature=0.02)
    plant = fws.LateralPlant(DYN, speed=15.0, curvature=0.02, model="dynamic",
                             tyre=tyre)  # fmt: skip
    new = fws.simulate(plant, path, g, **kw)
    old, _ = _old(fws.simulate, DYN, path, g, speed=15.0, model="dynamic",
                  tyre=tyre, **kw)  # fmt: skip
    _identical(new, old)
    assert new.model == "dynamic" and new.tyre == tyre
    ref = simulate_reference(DYN, path, g, speed=15.0, model="dynamic", tyre=tyre,
                             **kw)  # fmt: skip
    out = dict(zip(ref.output_labels, ref.outputs, strict=True))
    np.testing.assert_allclose(new.e, out["e"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(new.v_y, out["v_y"], rtol=0, atol=1e-6)
    # tyre slip: not the kinematic run
    kin = fws.simulate(fws.LateralPlant(DYN, speed=15.0), path, g, **kw)
    assert np.max(np.abs(kin.e - new.e)) > 1e-3


def _baselines():
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=20.0, curvature=0.01)
    return {
        "pure pursuit": fws.PurePursuit(lookahead=8.0, ratio=0.2),
        "Stanley": fws.Stanley(gain=1.0, softening=0.1),
        "rear-wheel feedback": fws.RearWheelFeedback(k_e=0.05, k_theta=0.3),
        "LQR": fws.LQRController(plant, Q=np.diag([0.01, 0.1]), R=1.0, ratio=0.3),
    }


@pytest.mark.parametrize("label", sorted(_baselines()))
def test_baseline_controllers_bit_for_bit(label):
    ctrl = _baselines()[label]
    sc = PAPER_SCENARIOS["curve_20"]
    kw = dict(initial_state=sc.initial_state, duration=3.0, dt=0.1)
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=sc.speed)
    new = fws.simulate(plant, sc.path, ctrl, **kw)
    old, _ = _old(fws.simulate, PAPER_VEHICLE, sc.path, ctrl, speed=sc.speed, **kw)
    _identical(new, old)
    assert new.status == "ok"
    # the controller acts: the error shrinks from its 10 m start
    assert abs(new.e[-1]) < abs(new.e[0])


def test_compare_bit_for_bit_and_its_table():
    course = fws.constant_radius(radius=40.0, turns=0.05)
    g = fws.double_root_gains(PAPER_VEHICLE, speed=10.0, ratio=0.0, pole=-1.0)
    ctrls = {"paper": g, "pure pursuit": fws.PurePursuit(lookahead=6.0)}
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=10.0, steering_lag=0.27)
    new = fws.compare(plant, course, ctrls, offset=0.3, delay=0.05)
    old, messages = _old(fws.compare, PAPER_VEHICLE, course, ctrls, speed=10.0,
                         offset=0.3, delay=0.05,
                         actuator_time_constant=0.27)  # fmt: skip
    assert any("LateralPlant" in m for m in messages)
    assert any("use steering_lag=" in m for m in messages)
    for a, b in zip(new.results, old.results, strict=True):
        _identical(a, b)
    for name in new.table:
        np.testing.assert_array_equal(new.table[name], old.table[name])
    # the row is the run simulate gives for that plant (the paper's law as
    # a state feedback there: the same law to rounding)
    run = new.results[0]
    ref = fws.simulate(plant, course.path, g, initial_state=(0.0, 0.3, 0.0),
                       duration=float(run.t[-1]), delay=0.05)  # fmt: skip
    np.testing.assert_allclose(run.e, ref.e, rtol=0, atol=1e-9)


# --------------------------------------------------------------------------
# One name per concept: steering_lag, model="kinematic"


def test_steering_actuator_takes_steering_lag():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_rate_front=0.5)
    act = fws.steering_actuator(veh, steering_lag=0.1)
    # T d' = cmd - d, then clipped at 0.5 rad/s: by hand
    np.testing.assert_allclose(act.dynamics(0.0, [0.0, 0.0], [0.2, 0.01]),
                               [min(0.2 / 0.1, 0.5), 0.01 / 0.1])  # fmt: skip
    old, messages = _old(fws.steering_actuator, veh, time_constant=0.1)
    assert messages == [
        "time_constant= is deprecated and is removed in fws_control 0.4; use "
        "steering_lag="
    ]
    x, u = [0.05, -0.02], [0.3, 0.1]
    np.testing.assert_array_equal(old.dynamics(0.0, x, u), act.dynamics(0.0, x, u))
    with pytest.raises(TypeError, match="time_constant= and steering_lag="):
        fws.steering_actuator(veh, steering_lag=0.1, time_constant=0.1)


def test_model_kinematic_is_the_exact_jacobian_and_exact_warns():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    assert plant.model == "kinematic"
    # B[1, 0] = V (1 + f^2 kappa^2) / f: the exact Jacobian (by hand)
    A, B = plant.matrices()
    assert B[1, 0] == pytest.approx(5.0 * (1 + (2.7 * 0.1) ** 2) / 2.7, rel=1e-15)
    with pytest.warns(FutureWarning, match="model='exact'.*use model='kinematic'"):
        old = fws.LateralPlant(veh, speed=5.0, curvature=0.1, model="exact")
    assert old.model == "kinematic"
    np.testing.assert_array_equal(old.matrices()[1], B)
    # the Vehicle shortcut of the analysis, the design and the symbolic oracle
    with pytest.warns(FutureWarning, match="model='kinematic'"):
        g_old = fws.double_root_gains(veh, speed=5.0, curvature=0.1, model="exact",
                                      ratio=-1.0, pole=-1.0)  # fmt: skip
    g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    assert (g_old.k1, g_old.k2) == (g.k1, g.k2)
    from fws_control import symbolic

    symbolic.jacobians.cache_clear()
    with pytest.warns(FutureWarning, match="model='kinematic'"):
        assert symbolic.jacobians("exact") == symbolic.jacobians("kinematic")


def test_cli_model_exact_warns_and_gives_the_kinematic_output(capsys):
    from fws_control.cli import main

    args = ["gains", "--speed", "5", "--curvature", "0.1", "--ratio", "-1",
            "--pole", "-1"]  # fmt: skip
    assert main([*args, "--model", "kinematic"]) == 0
    new = capsys.readouterr()
    assert main([*args, "--model", "exact"]) == 0
    old = capsys.readouterr()
    assert old.out == new.out and "kinematic model:" in new.out
    assert (
        "--model exact is deprecated and is removed in fws_control 0.4; use "
        "--model kinematic"
    ) in old.err
    assert "deprecated" not in new.err


def test_paper_scenarios_take_steering_lag():
    from fws_control.paper.scenarios import scenario_responses

    new = scenario_responses("curve_5", ratios=[0.5], duration=2.0, dt=0.1,
                             steering_lag=0.27)  # fmt: skip
    with pytest.warns(FutureWarning, match="use steering_lag="):
        old = scenario_responses("curve_5", ratios=[0.5], duration=2.0, dt=0.1,
                                 actuator_time_constant=0.27)  # fmt: skip
    _identical(new.result, old.result)
    sc, g = _design("curve_5", ratio=0.5)
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, steering_lag=0.27)
    one = fws.simulate(plant, sc.path, g, initial_state=sc.initial_state,
                       duration=2.0, dt=0.1)  # fmt: skip
    np.testing.assert_array_equal(new.result.e[0], one.e)


# --------------------------------------------------------------------------
# Deprecated forms: the warning names the new form and the user's line


def test_the_warning_points_at_the_callers_line():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fws.simulate(veh, fws.Straight(), fws.SteeringGains(0.1, 0.5, 0.0),
                     speed=5.0, initial_state=(0, 1, 0), duration=0.5)  # fmt: skip
        fws.LateralPlant(veh, speed=5.0, model="exact")
    future = [w for w in caught if issubclass(w.category, FutureWarning)]
    assert len(future) == 2
    assert all(w.filename == __file__ for w in future)
    assert "pass a fws.LateralPlant(vehicle, speed=..." in str(future[0].message)


def test_gains_keyword_names_controller():
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0)
    g = fws.SteeringGains(0.1, 0.5, 0.0)
    kw = dict(initial_state=(0.0, 1.0, 0.0), duration=1.0)
    with pytest.warns(FutureWarning, match="use controller="):
        old = fws.simulate(plant, fws.Straight(), gains=g, **kw)
    _identical(fws.simulate(plant, fws.Straight(), g, **kw), old)
    with pytest.warns(FutureWarning, match="use controllers="):
        fws.simulate_batch(plant, fws.Straight(), gains=g, **kw)
    with pytest.raises(TypeError, match="gains= and controller="):
        fws.simulate(plant, fws.Straight(), g, gains=g, **kw)
    with pytest.raises(TypeError, match="missing the argument 'controller'"):
        fws.simulate(plant, fws.Straight(), **kw)


def test_old_lag_keyword_with_the_new_one_is_refused():
    g = fws.SteeringGains(0.1, 0.5, 0.0)
    with pytest.warns(FutureWarning), pytest.raises(TypeError, match="give only"):
        fws.simulate(PAPER_VEHICLE, fws.Straight(), g, speed=5.0,
                     initial_state=(0, 1, 0), duration=1.0, steering_lag=0.1,
                     actuator_time_constant=0.1)  # fmt: skip


# --------------------------------------------------------------------------
# Bad input: named argument, value, valid range

G = fws.SteeringGains(0.1, 0.5, 0.0)
RUN = dict(initial_state=(0.0, 1.0, 0.0), duration=1.0)


@pytest.mark.parametrize("func", [fws.simulate, fws.simulate_batch])
def test_a_vehicle_without_speed_is_refused_naming_the_plant(func):
    with pytest.raises(TypeError, match=r"plant must be a fws\.LateralPlant.*speed="):
        func(PAPER_VEHICLE, fws.Straight(), G, **RUN)


def test_an_array_speed_plant_in_simulate_names_speed_and_simulate_batch():
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=[5.0, 20.0])
    with pytest.raises(
        ValueError,
        match=r"plant\.speed must be one speed .*shape \(2,\): \[ 5\. 20\.\]; use "
        r"simulate_batch",
    ):
        fws.simulate(plant, fws.Straight(), G, **RUN)
    # simulate_batch runs it: one run per speed
    res = fws.simulate_batch(plant, fws.Straight(), G, **RUN)
    np.testing.assert_array_equal(res.speed, [5.0, 20.0])


def test_a_pair_of_different_lags_is_refused_naming_steering_lag():
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, steering_lag=(0.1, 0.2))
    for func in (fws.simulate, fws.simulate_batch):
        with pytest.raises(ValueError, match=r"steering_lag .*\(0\.1, 0\.2\)"):
            func(plant, fws.Straight(), G, **RUN)
    with pytest.raises(ValueError, match=r"steering_lag .*front == rear"):
        fws.compare(plant, fws.constant_radius(), {"paper": G})


@pytest.mark.parametrize(
    "keyword, value",
    [("speed", 5.0), ("model", "dynamic"), ("tyre", "magic"),
     ("steering_lag", 0.1), ("actuator_time_constant", 0.1)],
)  # fmt: skip
def test_plant_keywords_with_a_plant_are_refused(keyword, value):
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0)
    with pytest.raises(TypeError, match=rf"{keyword}= applies only to the deprecated"):
        fws.simulate(plant, fws.Straight(), G, **RUN, **{keyword: value})


def test_compare_refuses_an_array_speed_and_a_speed_out_of_range():
    course = fws.constant_radius()
    with pytest.raises(ValueError, match=r"plant\.speed must be one speed in \[0\.1"):
        fws.compare(fws.LateralPlant(PAPER_VEHICLE, speed=[5.0, 6.0]), course,
                    {"paper": G})  # fmt: skip
    with pytest.raises(ValueError, match=r"speed must be in \[0\.1, 100\] m/s.*200"):
        fws.compare(fws.LateralPlant(PAPER_VEHICLE, speed=200.0), course,
                    {"paper": G})  # fmt: skip
    with pytest.raises(TypeError, match="plant must be a fws.LateralPlant"):
        fws.compare(PAPER_VEHICLE, course, {"paper": G})


_NOT_A_PLANT = st.one_of(
    st.none(),
    st.floats(allow_nan=True),
    st.text(max_size=5),
    st.tuples(st.floats(0.5, 5.0), st.floats(0.1, 2.0)),
    st.lists(st.floats(-10, 10), max_size=3),
    st.just(fws.SteeringGains(0.1, 0.5, 0.0)),
)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(plant=_NOT_A_PLANT)
def test_anything_but_a_plant_is_refused_naming_it(plant):
    for func in (fws.simulate, fws.simulate_batch, fws.compare):
        path = fws.constant_radius() if func is fws.compare else fws.Straight()
        ctrl = {"paper": G} if func is fws.compare else G
        kw = {} if func is fws.compare else RUN
        with pytest.raises(TypeError, match=r"plant must be a fws\.LateralPlant"):
            func(plant, path, ctrl, **kw)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    front=st.floats(1e-3, 10.0),
    rear=st.floats(1e-3, 10.0),
)
def test_unequal_lag_pairs_are_refused(front, rear):
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, steering_lag=(front, rear))
    if front == rear:
        return  # one time constant: runs (tested above)
    with pytest.raises(ValueError, match="steering_lag") as info:
        fws.simulate(plant, fws.Straight(), G, **RUN)
    assert repr(front) in str(info.value) and repr(rear) in str(info.value)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    name=st.from_regex(r"[a-z][a-z_]{0,12}", fullmatch=True).filter(
        lambda k: (
            k
            not in {
                "initial_state",
                "duration",
                "delay",
                "feedforward",
                "dt",
                "t_eval",
                "method",
                "rtol",
                "atol",
                "engine",
                "gains",
                "controller",
                "speed",
                "model",
                "tyre",
                "steering_lag",
                "actuator_time_constant",
            }
        )  # fmt: skip
    )
)
def test_unknown_keywords_are_refused_naming_them(name):
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0)
    with pytest.raises(TypeError, match=rf"unexpected keyword argument '{name}'"):
        fws.simulate(plant, fws.Straight(), G, **RUN, **{name: 1})


@settings(max_examples=30, deadline=None, derandomize=True)
@given(
    speeds=st.lists(st.floats(0.5, 50.0), min_size=2, max_size=4),
)
def test_array_speed_plants_are_refused_by_simulate(speeds):
    plant = fws.LateralPlant(PAPER_VEHICLE, speed=speeds)
    with pytest.raises(ValueError, match=r"plant\.speed must be one speed") as info:
        fws.simulate(plant, fws.Straight(), G, **RUN)
    assert f"shape ({len(speeds)},)" in str(info.value)
