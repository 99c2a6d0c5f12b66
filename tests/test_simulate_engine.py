"""simulate / simulate_batch with engine="compiled" (the numba DOP853 port).

References: the numpy engine (an independent implementation of the same
closed loop, itself checked against python-control in test_simulation.py),
the same run integrated alone, and maxima of the samples computed here.
"""

import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws
from fws_control.simulation.engine import PEAK_SIGNALS, SIGNALS

pytest.importorskip(
    "numba", reason="numba is not installed: engine='compiled' (extra 'fast') "
    "is not tested"
)  # fmt: skip

VEH = PAPER_VEHICLE
ARC = fws.Arc(curvature=0.1)
#: The paper's curve scenario: V = 5 m/s, kappa = 1/10, R(0) = (0, -5 m).
PLANT = fws.LateralPlant(VEH, speed=5.0)
CURVE = dict(initial_state=(0.0, -5.0, 0.0), duration=15.0)

# Both engines integrate with DOP853 at rtol 1e-10, atol 1e-12; each one's
# error to the exact solution is below 3e-10 on this scenario
# (docs/performance.md: 2.8e-10 against solve_ivp at rtol 1e-12), so their
# difference is at most twice that. 1e-9 (relative to 1 + |signal|) bounds it.
TOL = 1e-9


def _close(a, b, tol):
    """NaN where the other is NaN, else |a - b| <= tol (1 + |b|)."""
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = np.isfinite(b)
    assert np.all(np.abs(a[ok] - b[ok]) <= tol * (1.0 + np.abs(b[ok])))


@pytest.mark.parametrize("ratio", [-1.5, -1.0, 0.0, 0.6])
@pytest.mark.parametrize("feedforward", [True, False])
def test_compiled_equals_numpy_engine_on_the_curve(ratio, feedforward):
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=ratio, pole=-1.0)
    ref = fws.simulate(PLANT, ARC, g, **CURVE, feedforward=feedforward, engine="numpy")
    got = fws.simulate(
        PLANT, ARC, g, **CURVE, feedforward=feedforward, engine="compiled"
    )
    assert got.engine == "compiled" and ref.engine == "numpy"
    assert got.status == ref.status == "ok"
    assert got.t_stop == ref.t_stop == 15.0
    np.testing.assert_array_equal(got.t, ref.t)
    assert got.signals.shape == ref.signals.shape == (1, len(SIGNALS), 1501)
    _close(got.signals, ref.signals, TOL)
    # the kinematic model has no slip; the yaw rate is eq. (10)
    assert np.all(got.slip_front == 0.0) and np.all(got.slip_rear == 0.0)
    r10 = 5.0 * np.sin(got.delta_f - got.delta_r) / (2.7 * np.cos(got.delta_f))
    np.testing.assert_allclose(got.yaw_rate, r10, rtol=1e-13, atol=1e-15)


def test_compiled_with_rate_limited_actuator_against_tight_reference():
    """Limits that bind: the compiled engine switches them as events, the
    numpy engine clips with min/max. Reference: the numpy engine at rtol
    1e-13, atol 1e-15. The angles and the pose are states (or functions of
    them): within 10x the tolerance TOL. The rates (cmd - delta) / T
    amplify a state error by 1/T = 20 and the lateral acceleration
    differentiates them once more: 1e-6 for those (measured 8e-8 for the
    compiled engine, 3e-7 for the numpy engine at default tolerances)."""
    veh = fws.Vehicle(
        wheelbase=2.7,
        rear_to_cg=1.35,
        max_steer_front=0.3,
        max_steer_rear=0.2,
        max_steer_rate_front=0.3,
        max_steer_rate_rear=0.2,
    )
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-2.0)
    kw = dict(CURVE, initial_state=(0.0, -1.0, 0.0))
    plant = fws.LateralPlant(veh, speed=5.0, steering_lag=0.05)
    ref = fws.simulate(plant, ARC, g, **kw, rtol=1e-13, atol=1e-15, engine="numpy")
    got = fws.simulate(plant, ARC, g, **kw, engine="compiled")
    assert got.status == ref.status == "ok"
    # the limits bind (otherwise this would not test the switching)
    # (front angle and rate limits, rear rate limit)
    assert np.max(np.abs(ref.delta_f)) == pytest.approx(0.3, abs=1e-9)
    assert np.max(np.abs(ref.delta_f_rate)) == pytest.approx(0.3, abs=1e-9)
    assert np.max(np.abs(ref.delta_r_rate)) == pytest.approx(0.2, abs=1e-9)
    derived = [SIGNALS.index(name) for name in
               ("delta_f_rate", "delta_r_rate", "lateral_accel", "v_y")]  # fmt: skip
    states = [i for i in range(len(SIGNALS)) if i not in derived]
    _close(got.signals[:, states], ref.signals[:, states], 10 * TOL)
    _close(got.signals[:, derived], ref.signals[:, derived], 1e-6)


def test_peaks_are_exact_and_at_least_the_sample_maxima():
    """The compiled result carries exact peaks (tests/test_compiled_peaks.py
    compares them with the numpy engine's on many cases): here the paper's
    curve at the default output step, to 1e-9 of the numpy engine's, and
    never below the largest sample."""
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    ref = fws.simulate(PLANT, ARC, g, **CURVE, engine="numpy")
    got = fws.simulate(PLANT, ARC, g, **CURVE, engine="compiled")
    assert ref.peaks.exact and got.peaks.exact
    for name in PEAK_SIGNALS:
        x = np.abs(got.signals[0, SIGNALS.index(name)])
        assert getattr(got.peaks, name).value >= np.max(x)
        assert getattr(got.peaks, name).value == pytest.approx(
            getattr(ref.peaks, name).value, rel=TOL
        )


def test_mixed_batch_runs_are_identical_to_runs_alone():
    """Poles -0.2 and -5 (step sizes 25x apart) and a run that stops: each
    run of the batch is bitwise the same run simulated alone, whatever the
    chunk size; the stop ends only that run."""
    fast = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-5.0)
    slow = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=0.5, pole=-0.2)
    stops = fws.SteeringGains(0.5, -1.0, 0.0)  # positive feedback on theta
    gains = [fast, slow, stops, slow, fast]
    x0 = np.array([[0.0, -0.5, 0.0], [0.0, -2.0, 0.3], [0.0, -1.0, 0.0],
                   [0.0, 1.0, 0.0], [0.0, 0.3, -0.05]])  # fmt: skip
    kw = dict(initial_state=x0, duration=15.0, engine="compiled")
    batch = fws.simulate_batch(PLANT, ARC, gains, **kw)
    chunked = fws.simulate_batch(PLANT, ARC, gains, **kw, chunk_size=2)
    np.testing.assert_array_equal(batch.signals, chunked.signals)
    assert batch.engine == "compiled" and batch.peaks.exact
    assert batch.status.tolist() == ["ok", "ok", "singular_steering", "ok", "ok"]
    for i, g in enumerate(gains):
        alone = fws.simulate(
            fws.LateralPlant(VEH, speed=5.0),
            ARC, g, initial_state=x0[i], duration=15.0,
            engine="compiled",
        )  # fmt: skip
        T = alone.t.size
        np.testing.assert_array_equal(batch.signals[i, :, :T], alone.signals[0])
        assert np.all(np.isnan(batch.signals[i, :, T:]))
        assert batch.status[i] == alone.status
        assert batch.t_stop[i] == alone.t_stop
        assert batch.message[i] == alone.message
    # the stop is where the numpy engine stops too: both stop 1e-3 rad before
    # |delta_f| = pi/2, the compiled engine no later (to a few ulp)
    ref = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        ARC,
        stops,
        initial_state=x0[2],
        duration=15.0,
        engine="numpy",
    )
    assert ref.status == "singular_steering"
    assert batch.t_stop[2] == pytest.approx(ref.t_stop, abs=1e-4)
    assert batch.t_stop[2] <= ref.t_stop + 1e-12


DYN = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.2,
    mass=1500.0,
    yaw_inertia=2600.0,
    cornering_front=8.0e4,
    cornering_rear=9.5e4,
)


@pytest.mark.parametrize(
    ("vehicle", "gains", "kwargs", "reason"),
    [
        (VEH, None, {"delay": 0.1, "method": "Radau"}, "delay"),
        (VEH, None, {"method": "RK45"}, "DOP853"),
        (VEH, fws.PurePursuit(lookahead=5.0), {"method": "Radau"}, "compiled law"),
        (DYN, None, {"model": "dynamic", "method": "Radau"}, "model='dynamic'"),
        (DYN, None, {"feedforward": "dynamic"}, "feedforward='dynamic'"),
    ],
)
def test_unsupported_cases_raise(vehicle, gains, kwargs, reason):
    if gains is None:
        gains = fws.double_root_gains(
            vehicle, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0
        )
    kwargs = dict(kwargs)
    plant = fws.LateralPlant(vehicle, speed=5.0, model=kwargs.pop("model", "kinematic"))
    kw = dict(CURVE, duration=1.0, **kwargs)
    # the default engine ("auto") runs it on the numpy engine
    assert fws.simulate(plant, ARC, gains, **kw).engine == "numpy"
    for run in (fws.simulate, fws.simulate_batch):
        with pytest.raises(ValueError, match="engine='compiled'") as info:
            run(plant, ARC, gains, **kw, engine="compiled")
        assert reason in str(info.value)


def test_unknown_engine_and_missing_numba_raise(monkeypatch):
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    with pytest.raises(ValueError, match=r"engine must be one of .*'fast'"):
        fws.simulate(PLANT, ARC, g, **CURVE, engine="fast")
    from fws_control.simulation import compiled

    monkeypatch.setattr(compiled, "numba", None)
    with pytest.raises(ValueError, match="engine='compiled'.*numba is not installed"):
        fws.simulate(PLANT, ARC, g, **CURVE, engine="compiled")


def test_indexing_keeps_the_engine():
    g = fws.double_root_gains(
        VEH, speed=5.0, curvature=0.1, ratio=np.array([-1.0, 0.0]), pole=-1.0
    )
    res = fws.simulate_batch(PLANT, ARC, g, **CURVE, engine="compiled")
    assert res[1].engine == "compiled" and res[1].peaks.exact is True
    with pytest.raises(ValueError, match="engine must be 'numpy' or 'compiled'"):
        import dataclasses

        dataclasses.replace(res, engine="gpu")
