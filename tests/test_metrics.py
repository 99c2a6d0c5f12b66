"""Metrics against closed-form signals and brute-force definitions."""

import math

import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from hypothesis import given
from hypothesis import strategies as st

import fws_control as fws
from fws_control.paths import Arc, Straight

VEH = PAPER_VEHICLE
T = np.linspace(0.0, 10.0, 2001)


@given(rate=st.floats(0.5, 3.0), fraction=st.floats(0.005, 0.2))
def test_settling_time_of_exponential(rate, fraction):
    # |exp(-r t)| <= fraction from t = -ln(fraction)/r on
    expect = -math.log(fraction) / rate
    got = fws.settling_time(T, 3.0 * np.exp(-rate * T), fraction=fraction)
    if expect < T[-1]:
        assert got == pytest.approx(expect, abs=2e-4)
    else:
        assert got == math.inf


def test_settling_time_brute_force_with_band_and_batch():
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.normal(size=(4, 200)), axis=1) * np.exp(-np.linspace(0, 8, 200))
    t = np.linspace(0.0, 8.0, 200)
    band = 0.05
    got = fws.settling_time(t, x, band=band)
    for i in range(4):
        outside = np.flatnonzero(np.abs(x[i]) > band)
        if outside.size == 0:
            assert got[i] == 0.0
        elif outside[-1] == t.size - 1:
            assert got[i] == math.inf
        else:
            # between the last sample outside and the next one
            assert t[outside[-1]] <= got[i] <= t[outside[-1] + 1]


def test_overshoot_and_nan_handling():
    x = (1 - T) * np.exp(-T)  # minimum -exp(-2) at t = 2
    assert fws.overshoot(x) == pytest.approx(math.exp(-2), abs=1e-12)
    assert fws.overshoot(-2 * x, relative=True) == pytest.approx(math.exp(-2))
    assert fws.overshoot(np.exp(-T)) == 0.0  # monotone decay
    assert math.isnan(fws.overshoot(np.zeros(5)))  # no initial error
    y = np.vstack([x, np.where(T < 5, x, np.nan)])
    np.testing.assert_allclose(fws.overshoot(y), [math.exp(-2), np.nan])


def test_rms_and_steady_state_closed_forms():
    t = np.linspace(0.0, 2 * np.pi, 4001)
    assert fws.rms(t, 2 * np.sin(t)) == pytest.approx(math.sqrt(2), rel=1e-6)
    # mean of 0.3 + exp(-t) over [9, 10]: 0.3 + (e^-9 - e^-10)
    expect = 0.3 + math.exp(-9) - math.exp(-10)
    assert fws.steady_state(T, 0.3 + np.exp(-T), window=1.0) == pytest.approx(
        expect, rel=1e-7
    )
    # rms from t_start: constant 2 after 5 s
    assert fws.rms(T, np.where(T < 5, 10.0, 2.0), t_start=5.0) == pytest.approx(2.0)
    with pytest.raises(ValueError, match="window"):
        fws.steady_state(T, T, window=0.0)
    with pytest.raises(ValueError, match="last axis"):
        fws.rms(T, np.zeros(3))


def test_peak_abs_ignores_nan_tail():
    x = np.array([[1.0, -4.0, 2.0], [0.5, np.nan, np.nan], [np.nan] * 3])
    np.testing.assert_array_equal(fws.peak_abs(x), [4.0, 0.5, np.nan])


def test_tracking_metrics_single_and_batch_agree_with_direct_computation():
    ratios = np.array([-1.0, 0.0, 0.5])
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=ratios, pole=-1.0)
    batch = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(0.1),
        g,
        initial_state=(0, -5, 0),
        duration=15.0,
        dt=0.01,
    )
    m = fws.tracking_metrics(batch)
    assert m.status.tolist() == ["ok"] * 3
    # the peaks are the exact maxima of the continuous solution: never below
    # the samples' maxima, and above them by at most what a 10 ms grid misses
    for got, sig in (
        (m.peak_lateral_accel, batch.lateral_accel),
        (m.peak_delta_r_rate, batch.delta_r_rate),
        (m.peak_delta_f, batch.delta_f),
    ):
        sampled = np.max(np.abs(sig), axis=1)
        assert np.all(got >= sampled * (1 - 1e-12))
        np.testing.assert_allclose(got, sampled, rtol=1e-2)
    np.testing.assert_array_equal(m.peak_lateral_accel, batch.peaks.lateral_accel.value)
    np.testing.assert_array_equal(m.peak_error, batch.peaks.e.value)
    # |e| peaks at |e0| = 5 m, except for a = -1, whose opposite rear steering
    # first moves R outwards
    np.testing.assert_allclose(m.peak_error[1:], 5.0, rtol=1e-12)
    assert m.peak_error[0] >= np.max(np.abs(batch.e[0])) > 5.0
    for i in range(3):
        single = fws.tracking_metrics(batch[i])
        assert single.settling_time == pytest.approx(m.settling_time[i])
        assert single.rms_error == pytest.approx(m.rms_error[i])
        # a squeezed run gives floats; the metric functions on its arrays agree
        assert isinstance(single.settling_time, float) and single.status == "ok"
        run = batch[i]
        assert single.overshoot == fws.overshoot(run.e)
        assert single.steady_state_heading_error == fws.steady_state(
            run.t, run.theta, window=1.0
        )
    # with feedforward the error converges: steady-state mean over the last
    # second is far below the 2 % band of e0 = -5 m
    assert np.all(np.abs(m.steady_state_error) < 1e-3)


def test_tracking_metrics_of_stopped_run_has_nan_horizon_metrics():
    g = fws.SteeringGains(0.1, -0.5, 0.0)  # runs into |delta_f| = pi/2
    kw = {"initial_state": (0, 1, 0), "duration": 10.0}
    plant = fws.LateralPlant(VEH, speed=5.0)
    res = fws.simulate(plant, Straight(), g, feedforward=False, **kw)
    m = fws.tracking_metrics(res)
    assert m.status == "singular_steering"
    assert math.isnan(m.settling_time) and math.isnan(m.rms_error)
    # the exact peak covers [0, t_stop]: the run stops where |delta_f| reaches
    # pi/2 - 1e-3 (the stop margin of both engines), beyond the last sample
    assert np.max(np.abs(res.delta_f)) < m.peak_delta_f
    assert m.peak_delta_f == pytest.approx(math.pi / 2 - 1e-3, abs=1e-9)
    # the same run in a batch (NaN tail after the stop): the same metrics, up
    # to the integration (the batch shares one solver's steps between its runs)
    both = fws.simulate_batch(
        plant,
        Straight(),
        [g, fws.SteeringGains(0.1, 0.5, 0.0)],
        feedforward=False,
        **kw,
    )
    mb = fws.tracking_metrics(both)
    assert mb.status.tolist() == ["singular_steering", "ok"]
    assert math.isnan(mb.settling_time[0]) and np.isfinite(mb.settling_time[1])
    assert mb.peak_delta_f[0] == pytest.approx(m.peak_delta_f, rel=1e-6)


@pytest.mark.parametrize("band", [float("nan"), -0.1, 0.0, float("inf"), True, 1j])
def test_settling_band_must_be_finite_and_positive(band):
    # Issue 13 item 6: band=nan compared False everywhere and reported 0.0
    # ("settled at once") even for a constant signal; a negative band was
    # accepted. The constant signal 1 never enters a band of 0.5:
    assert fws.settling_time(T, np.ones_like(T), band=0.5) == math.inf
    with pytest.raises((ValueError, TypeError), match="band"):
        fws.settling_time(T, np.ones_like(T), band=band)


def test_tracking_metrics_checks_band_and_result_type():
    g = fws.SteeringGains(0.1, 0.5, ratio=0.0)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Straight(),
        g,
        initial_state=(0, 1, 0),
        duration=2.0,
    )
    with pytest.raises(ValueError, match="band"):
        fws.tracking_metrics(res, band=float("nan"))
    with pytest.raises(ValueError, match="band"):
        fws.tracking_metrics(res, band=-1.0)
    with pytest.raises(
        TypeError, match="result must be a fws_control.SimulationResult"
    ):
        fws.tracking_metrics(res.e)


def _sweep(signals):
    g = fws.SteeringGains(k1=[0.1, 0.2, -0.1], k2=[0.5, 0.5, 0.4], ratio=0.0)
    return fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0), Straight(), g, initial_state=(0.0, 1.0, 0.0),
        duration=10.0, dt=0.001, signals=signals,
    )  # fmt: skip


def test_metrics_table_has_one_row_per_run_with_each_runs_metrics():
    pytest.importorskip("pandas", reason="to_pandas needs the extra pandas")
    batch = _sweep(None)
    df = fws.tracking_metrics(batch).to_pandas()
    assert df["run"].tolist() == [0, 1, 2]
    for i in range(3):
        # reference: the metrics of the run alone
        one = fws.tracking_metrics(batch[i])
        for name in ("settling_time", "rms_error", "peak_error", "peak_delta_f"):
            np.testing.assert_allclose(df[name][i], getattr(one, name), rtol=1e-12)
        assert df["status"][i] == one.status == "ok"
        # and from the samples: RMS of e by the trapezoid rule, written here
        e, t = batch.e[i], batch.t
        rms = math.sqrt(np.trapezoid(e**2, t) / (t[-1] - t[0]))
        np.testing.assert_allclose(df["rms_error"][i], rms, rtol=1e-6)
    # a single run's metrics: one row
    assert len(fws.tracking_metrics(batch[1]).to_pandas()) == 1


def test_a_metrics_only_sweep_tabulates_its_runs_and_exact_peaks():
    pytest.importorskip("pandas", reason="to_pandas needs the extra pandas")
    dense = _sweep(None)
    df = _sweep("metrics").to_pandas()
    assert df["run"].tolist() == [0, 1, 2]
    np.testing.assert_array_equal(df["k1"], [0.1, 0.2, -0.1])
    assert df["status"].tolist() == ["ok"] * 3
    # reference: the largest sample of the 1 ms output of the same runs;
    # the exact peak is at least that and within the samples' curvature
    for name in ("e", "delta_f", "lateral_accel"):
        sampled = np.nanmax(np.abs(getattr(dense, name)), axis=-1)
        peak = df[f"peak_{name}"].to_numpy()
        assert np.all(peak >= sampled - 1e-12)
        np.testing.assert_allclose(peak, sampled, rtol=1e-5)
