"""Speed profiles and gain schedules on the compiled engine.

(a) The compiled tables against references written here: the speed of a
PCHIP table against :class:`scipy.interpolate.PchipInterpolator` built in
the test, of a linear table against the braking formula, and the
scheduled gains against :func:`numpy.interp` of the scaled gains (the
schedule's definition, written out). (b) The three scenarios of
``docs/varying_speed.md`` (braking lane change, accelerating curve exit,
parking-lot phase switch) on both engines: the two integrations are
independent (each its own solver and steps), so their agreement to the
tolerance is a check of each. (c) Engine choice and refusals. The
compiled runs against the ``solve_ivp`` references of
``tests/test_speed_profile.py`` are in that file.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import PchipInterpolator

import fws_control as fws
from fws_control.simulation import compiled

pytestmark = pytest.mark.skipif(
    not compiled.available(), reason="numba is not installed: no compiled engine"
)

ROOT = Path(__file__).resolve().parents[1]
VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, friction=0.9)


def _example():
    """examples/plot_varying_speed.py as a module (its scenarios)."""
    spec = importlib.util.spec_from_file_location(
        "plot_varying_speed_module", ROOT / "examples" / "plot_varying_speed.py"
    )
    module = importlib.util.module_from_spec(spec)
    # only the definitions: the script's runs and figure follow its functions
    source = (ROOT / "examples" / "plot_varying_speed.py").read_text()
    head = source.split("\nresults = run_all()")[0]
    sys.modules.setdefault("plot_varying_speed_module", module)
    exec(compile(head, str(spec.origin), "exec"), module.__dict__)
    return module


# --------------------------------------------------------------------------
# (a) the tables


def _tables(profile, schedule=None):
    from fws_control.simulation.compiled_speed import speed_tables

    q = np.zeros(44)
    br, co = speed_tables(np.array([0.0, 1.0]), np.zeros((1, 4)), profile, schedule, q)
    return q, br, co


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    st.lists(st.floats(0.5, 40.0), min_size=2, max_size=7),
    st.sampled_from(["time", "distance"]),
)
def test_pchip_table_speed_against_scipy(speeds, of):
    from fws_control.simulation.compiled_speed import speed_and_gains

    x = np.cumsum(np.linspace(1.0, 2.0, len(speeds)))
    prof = fws.SpeedProfile(of, points=x, speeds=speeds)
    ref = PchipInterpolator(x, speeds)
    q, br, co = _tables(prof)
    for xx in np.linspace(x[0] - 1.0, x[-1] + 1.0, 57):
        t, s = (xx, -7.0) if of == "time" else (-7.0, xx)
        V = speed_and_gains(t, s, q, br, co)[0]
        want = float(ref(min(max(xx, x[0]), x[-1])))
        assert abs(V - want) <= 1e-13 * max(speeds)


def test_linear_table_speed_is_the_braking_formula():
    from fws_control.simulation.compiled_speed import speed_and_gains

    prof = fws.SpeedProfile.braking(22.0, 4.0, start=1.5, final=6.0)
    q, br, co = _tables(prof)
    for t in np.linspace(-1.0, 10.0, 221):
        want = max(22.0 - 4.0 * max(t - 1.5, 0.0), 6.0)
        assert abs(speed_and_gains(t, 0.0, q, br, co)[0] - want) <= 1e-14 * 22.0
    # the end value exactly (np.interp's), after and at the last point
    assert speed_and_gains(5.5, 0.0, q, br, co)[0] == 6.0


@settings(max_examples=25, deadline=None, derandomize=True)
@given(st.integers(2, 8), st.floats(-0.5, 0.5), st.data())
def test_schedule_gains_against_interp(n, ratio_slope, data):
    """k1 V^2, k2 V and a interpolated linearly, as the schedule defines them."""
    from fws_control.simulation.compiled_speed import speed_and_gains

    V = np.linspace(4.0, 30.0, n)
    k1 = data.draw(st.lists(st.floats(1e-4, 0.1), min_size=n, max_size=n))
    k2 = data.draw(st.lists(st.floats(0.01, 1.0), min_size=n, max_size=n))
    a = ratio_slope * (V - 15.0)
    sch = fws.GainSchedule(speeds=V, k1=k1, k2=k2, ratio=a)
    prof = fws.SpeedProfile.from_time([0.0, 10.0], [4.0, 30.0])
    q, br, co = _tables(prof, sch)
    for t in np.linspace(0.0, 10.0, 41):
        v = float(prof(t))
        got = speed_and_gains(t, 0.0, q, br, co)
        assert got[4] and got[0] == v
        want = (
            np.interp(v, V, np.asarray(k1) * V**2) / v**2,
            np.interp(v, V, np.asarray(k2) * V) / v,
            np.interp(v, V, a),
        )
        np.testing.assert_allclose(got[1:4], want, rtol=1e-15, atol=1e-18)


# --------------------------------------------------------------------------
# (b) the scenarios of docs/varying_speed.md on both engines


# Each run ends shortly after its scenario's last event (the example runs
# 12, 9 and 18 s): the lane change's last curved piece ends at 10.0 s
# (braking ends at 4.85 s); the curve exit's clothoid ends at 7.25 s, the
# speed rising on its PCHIP piece throughout; the parking-lot exit's a(V)
# changes sign at 15.0 s and its speed reaches the table's held end value
# (22 m/s) at 15.6 s.
DURATIONS = {
    "braking lane change": 10.5,
    "accelerating curve exit": 7.5,
    "parking-lot exit": 16.0,
}


# "scheduled" (ratio 0) goes through the same schedule tables as
# "scheduled + a(V)" (the gains k1 V^2, k2 V and the ratio column, here
# zeros): it is checked on one scenario, the other two controllers on all.
@pytest.mark.parametrize(
    ("scenario", "label"),
    [
        ("braking lane change", "fixed"),
        ("braking lane change", "scheduled + a(V)"),
        ("accelerating curve exit", "fixed"),
        ("accelerating curve exit", "scheduled"),
        ("accelerating curve exit", "scheduled + a(V)"),
        ("parking-lot exit", "fixed"),
        ("parking-lot exit", "scheduled + a(V)"),
    ],
)
def test_scenarios_agree_with_the_numpy_engine(scenario, label):
    ex = _example()
    path, profile, x0, full = ex.scenarios()[scenario]
    assert DURATIONS[scenario] < full
    v_start = float(profile(0.0))
    plant = fws.LateralPlant(ex.VEH, speed=v_start, model="dynamic")
    kw = dict(initial_state=x0, duration=DURATIONS[scenario], speed=profile, dt=0.05)
    ctrl = ex.controllers(v_start)[label]
    a = fws.simulate(plant, path, ctrl, engine="compiled", **kw)
    b = fws.simulate(plant, path, ctrl, engine="numpy", **kw)
    assert a.engine == "compiled" and b.engine == "numpy"
    assert a.status == b.status == "ok", (label, a.message, b.message)
    # positions to 1e-6 m over 80-130 m of path (rtol 1e-10 each)
    err = np.max(np.hypot(a.x - b.x, a.y - b.y))
    assert err < 1e-6, (label, err)
    assert np.max(np.abs(a.e - b.e)) < 1e-7
    np.testing.assert_allclose(a.longitudinal_speed, b.longitudinal_speed,
                               rtol=1e-9)  # fmt: skip
    np.testing.assert_allclose(a.longitudinal_accel, b.longitudinal_accel,
                               rtol=1e-9, atol=1e-9)  # fmt: skip
    # friction usage |a| / (mu g): the engines' lateral accelerations differ
    # most in the parking-lot exit's transient at 1.7-2.1 s, by up to 1.2e-6
    # m/s^2 (measured on a Cascade Lake CPU: up to 1.1e-7 of usage; 4.8e-8
    # with numpy's and OpenBLAS's SIMD loops off), the tyre forces amplifying
    # a difference of the body's states that each rtol of 1e-10 allows
    np.testing.assert_allclose(a.friction_usage, b.friction_usage, rtol=1e-7, atol=5e-7)
    assert np.array_equal(a.friction_exceeded, b.friction_exceeded)
    np.testing.assert_allclose(a.delta_r_rate, b.delta_r_rate, atol=1e-7)
    for name in ("e", "lateral_accel", "delta_r"):
        pa, pb = getattr(a.peaks, name), getattr(b.peaks, name)
        assert abs(pa.value - pb.value) <= 1e-7 * (1.0 + abs(pb.value)), name


def test_phase_switch_is_compiled():
    """The parking-lot exit's rear steering changes phase on the compiled run."""
    ex = _example()
    path, profile, x0, duration = ex.scenarios()["parking-lot exit"]
    sch = ex.controllers(3.0)["scheduled + a(V)"]
    res = fws.simulate(
        fws.LateralPlant(ex.VEH, speed=3.0, model="dynamic"), path, sch,
        initial_state=x0, duration=duration, speed=profile, engine="compiled",
    )  # fmt: skip
    V = res.longitudinal_speed
    # the applied ratio is a(V) of the current speed (away from 0/0)
    kappa = np.asarray(path.curvature(res.s), dtype=float)
    u = res.delta_f - np.arctan(ex.VEH.wheelbase * kappa)
    delta_r = res.delta_r
    big = np.abs(u) > 1e-7
    want = np.interp(V, sch.speeds, sch.ratio)
    np.testing.assert_allclose(delta_r[big] / u[big], want[big], rtol=1e-6)
    # counter-phase at the start, in-phase on the road (there e and theta
    # have converged below the 0/0 of the applied ratio)
    assert want.min() < 0.0 < want.max()


# --------------------------------------------------------------------------
# (c) engine choice and refusals


def test_auto_and_batch_compile_a_table_profile():
    plant = fws.LateralPlant(VEH, speed=20.0)
    prof = fws.SpeedProfile.braking(20.0, 4.0, start=1.0, final=8.0)
    sch = fws.GainSchedule.double_root(VEH, speeds=[5.0, 25.0], pole=-1.0)
    kw = dict(duration=4.0, speed=prof)
    one = fws.simulate(plant, fws.Straight(), sch, initial_state=(0, 1.0, 0), **kw)
    assert one.engine == "compiled"
    batch = fws.simulate_batch(
        plant, fws.Straight(), sch,
        initial_state=np.array([[0.0, 1.0, 0.0], [0.0, -0.5, 0.1]]), **kw,
    )  # fmt: skip
    assert batch.engine == "compiled"
    # each run is its own integration: the batch's first run is the single one
    assert np.array_equal(batch[0].signals, one.signals)
    assert np.array_equal(batch.run_peak[0], one.run_peak[0])
    two = fws.simulate(plant, fws.Straight(), sch, initial_state=(0, -0.5, 0.1), **kw)
    assert np.array_equal(batch[1].signals, two.signals)


def test_function_profile_and_schedule_run_on_numpy():
    plant = fws.LateralPlant(VEH, speed=10.0)
    kw = dict(initial_state=(0.0, 1.0, 0.0), duration=1.0)
    fun = fws.SpeedProfile.from_function(lambda t: 10.0 + t)
    g = fws.SteeringGains(0.01, 0.2, 0.0)
    assert fws.simulate(plant, fws.Straight(), g, speed=fun, **kw).engine == "numpy"
    with pytest.raises(ValueError, match="engine='compiled'.*from_function"):
        fws.simulate(plant, fws.Straight(), g, speed=fun, engine="compiled", **kw)
    table = fws.SpeedProfile.from_time([0.0, 1.0], [10.0, 11.0])

    def rule(V):
        return fws.SteeringGains(1.0 / np.asarray(V) ** 2, 2.0 / np.asarray(V), 0.0)

    with pytest.warns(RuntimeWarning, match="not compiled and runs on the numpy"):
        res = fws.simulate(plant, fws.Straight(), rule, speed=table, **kw)
    assert res.engine == "numpy"
    with pytest.raises(ValueError, match="engine='compiled'.*function"):
        fws.simulate(plant, fws.Straight(), rule, speed=table, engine="compiled", **kw)


def test_schedule_range_and_radau_refused_on_compiled():
    plant = fws.LateralPlant(VEH, speed=20.0)
    prof = fws.SpeedProfile.from_time([0.0, 2.0], [20.0, 4.0])
    sch = fws.GainSchedule.double_root(VEH, speeds=[5.0, 25.0], pole=-1.0)
    kw = dict(initial_state=(0.0, 1.0, 0.0), duration=1.0, speed=prof)
    msg = r"profile's speeds \[4, 20\] m/s leave the schedule's range \[5, 25\]"
    with pytest.raises(ValueError, match=msg):
        fws.simulate(plant, fws.Straight(), sch, engine="compiled", **kw)
    g = fws.SteeringGains(0.01, 0.2, 0.0)
    with pytest.raises(ValueError, match="method='DOP853' only, got 'Radau'"):
        fws.simulate(plant, fws.Straight(), g, engine="compiled", method="Radau", **kw)
    # a stiff actuator under method="auto": capped DOP853, not Radau
    # (Radau beyond 2500 capped steps of 3.2 T: 8 s at T = 1 ms)
    lag = fws.LateralPlant(VEH, speed=20.0, steering_lag=0.001)
    res = fws.simulate(lag, fws.Straight(), g, **{**kw, "duration": 10.0})
    assert res.engine == "compiled" and res.method == "DOP853"
    assert math.isfinite(res.e[-1])
