"""simulate_batch(signals=...): only chosen signals, or only metrics (issue 14, item 3).

References: the same batch with every signal kept (the kept rows, the peaks
and the metrics must be those of the full run, bitwise), the size of the
arrays (the memory budget), and the peak memory of one chunk simulated
alone (the working set that the batch may add to its result).
"""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from conftest import (
    CURVE_BATCH_KW,
    CURVE_GAINS_WITH_STOP,
    CURVE_SPEED,
    PAPER_VEHICLE,
    LosingClient,
    traced_peak,
)
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control as fws
from fws_control.paths import Arc
from fws_control.simulation import SIGNALS, options
from fws_control.simulation.engine import PEAK_SIGNALS

matplotlib.use("Agg")

VEH = PAPER_VEHICLE
PLANT = fws.LateralPlant(VEH, speed=CURVE_SPEED)
PATH = Arc(0.1)
# five designs of the paper's curve scenario and one that stops (conftest)
GAINS = CURVE_GAINS_WITH_STOP
KW = CURVE_BATCH_KW
ENGINES = ["numpy", "compiled"]


@pytest.fixture(scope="module", params=ENGINES)
def full(request):
    return fws.simulate_batch(PLANT, PATH, GAINS, engine=request.param, **KW)


def _batch(full, signals, **kw):
    return fws.simulate_batch(
        PLANT, PATH, GAINS, engine=full.engine, signals=signals, **{**KW, **kw}
    )


def test_the_scenario_has_a_stopped_run(full):
    # (otherwise the NaN tails and run_samples below would test nothing)
    assert full.status.tolist()[:5] == ["ok"] * 5
    assert full.status[5] == fws.simulation.STATUS_SINGULAR_STEERING
    assert 0 < np.count_nonzero(np.isfinite(full.s[5])) < full.t.size


@pytest.mark.parametrize(
    "names", [("e", "lateral_accel"), ("lateral_accel", "e"), ("s",), SIGNALS[::-1]]
)
def test_kept_signals_are_the_rows_of_the_full_run_bitwise(full, names):
    res = _batch(full, names)
    kept = tuple(k for k in SIGNALS if k in names)  # held in SIGNALS order
    assert res.signal_names == kept
    rows = [SIGNALS.index(k) for k in kept]
    assert res.signals.shape == (len(GAINS.k1), len(kept), full.t.size)
    np.testing.assert_array_equal(res.signals, full.signals[:, rows, :])
    for k in kept:
        np.testing.assert_array_equal(getattr(res, k), getattr(full, k))
        np.testing.assert_array_equal(res.signal(k), full.signal(k))
    np.testing.assert_array_equal(res.t, full.t)
    assert res.status.tolist() == full.status.tolist()
    assert res.message == full.message
    np.testing.assert_array_equal(res.t_stop, full.t_stop)
    # one run, squeezed: its samples up to its stop, as from the full run
    for i in (0, 5):
        np.testing.assert_array_equal(res[i].t, full[i].t)
        for k in kept:
            np.testing.assert_array_equal(res[i].signal(k), full[i].signal(k))


@pytest.mark.parametrize("signals", [("e",), ("delta_f", "theta"), "metrics"])
def test_peaks_and_metrics_are_those_of_the_full_run(full, signals):
    res = _batch(full, signals)
    p, q = res.peaks, full.peaks
    assert p.exact and q.exact  # both engines give exact peaks
    for name in PEAK_SIGNALS:
        np.testing.assert_array_equal(p[name].value, q[name].value)
        np.testing.assert_array_equal(p[name].time, q[name].time)
    m, ref = fws.tracking_metrics(res), fws.tracking_metrics(full)
    for field in fws.TrackingMetrics.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(m, field), getattr(ref, field))
    # the stopped run has NaN horizon metrics, not a number
    assert np.isnan(m.settling_time[5]) and np.isfinite(m.settling_time[0])
    # one run of it, squeezed: the batch's values of that run (bitwise) and,
    # to rounding, the metrics of that run computed alone (numpy sums a row
    # of a 2-D array in another order than a 1-D array)
    one, alone = fws.tracking_metrics(res[2]), fws.tracking_metrics(full[2])
    assert one.status == "ok"
    for field in ("settling_time", "overshoot", "rms_error", "steady_state_error"):
        assert getattr(one, field) == getattr(ref, field)[2]
        assert getattr(one, field) == pytest.approx(getattr(alone, field), rel=1e-14)


def test_metrics_only_holds_no_time_series(full):
    res = _batch(full, "metrics")
    assert res.signal_names == () and res.signals.nbytes == 0
    np.testing.assert_array_equal(
        res.run_samples, np.count_nonzero(np.isfinite(full.s), axis=1)
    )
    assert "signals=()" in repr(res)


def test_metrics_with_other_settings_need_e_and_theta(full):
    res = _batch(full, ("e",))
    with pytest.raises(ValueError, match=r"window.*keep signals=\('e', 'theta'\)"):
        fws.tracking_metrics(res, window=2.0)
    # with e and theta kept, any settings work and agree with the full run
    both = _batch(full, ("e", "theta"))
    assert both.run_metrics is None
    np.testing.assert_array_equal(
        fws.tracking_metrics(both, window=2.0, fraction=0.05).settling_time,
        fws.tracking_metrics(full, window=2.0, fraction=0.05).settling_time,
    )


def test_a_dropped_signal_raises_naming_it_and_the_argument(full):
    res = _batch(full, ("e", "lateral_accel"))
    for read in (lambda: res.theta, lambda: res.signal("theta"), lambda: res[0].theta):
        with pytest.raises(fws.SignalNotKeptError, match=r"'theta'.*signals="):
            read()
    assert not hasattr(res, "theta") and getattr(res, "x", None) is None
    with pytest.raises(fws.SignalNotKeptError, match=r"'x' was not kept \(plot"):
        res.plot()
    with pytest.raises(ValueError, match="name must be one of"):
        res.signal("a_y")
    none = _batch(full, "metrics")
    for call in (none.to_time_response, none.plot):
        with pytest.raises(fws.SignalNotKeptError, match="no time series"):
            call()
    # (to_pandas of a metrics-only result is its table of runs:
    # tests/test_metrics.py)


def test_to_pandas_and_time_response_hold_the_kept_signals(full):
    pytest.importorskip("pandas")
    res = _batch(full, ("e", "lateral_accel"))
    df, ref = res.to_pandas(), full.to_pandas()
    assert [c for c in df.columns if c in SIGNALS] == ["e", "lateral_accel"]
    for c in ("run", "t", "e", "lateral_accel", "status", "k1"):
        np.testing.assert_array_equal(df[c].to_numpy(), ref[c].to_numpy())
    resp = res.to_time_response()
    assert resp.output_labels == ["e", "lateral_accel"]
    np.testing.assert_array_equal(resp.outputs[1], full.lateral_accel)


# --------------------------------------------------------------------------
# Bad values of signals=


@settings(derandomize=True, max_examples=40, deadline=None)
@given(bad=st.text(max_size=12).filter(lambda s: s not in SIGNALS))
def test_an_unknown_name_is_refused_naming_it_and_the_valid_names(bad):
    with pytest.raises(ValueError) as info:
        fws.simulate_batch(PLANT, PATH, GAINS, signals=("e", bad), **KW)
    msg = str(info.value)
    assert msg.startswith("signals") and repr(bad) in msg and repr(SIGNALS) in msg


@settings(derandomize=True, max_examples=30, deadline=None)
@given(
    bad=st.one_of(
        st.integers(),
        st.floats(allow_nan=True),
        st.none(),
        st.binary(max_size=4),
        st.lists(st.sampled_from(SIGNALS), min_size=1, max_size=2).map(tuple),
    )
)
def test_a_name_that_is_not_a_str_is_refused(bad):
    with pytest.raises(TypeError, match="signals must hold signal names"):
        fws.simulate_batch(PLANT, PATH, GAINS, signals=["e", bad], **KW)


@pytest.mark.parametrize(
    ("signals", "error", "match"),
    [
        ((), ValueError, "at least one signal.*signals='metrics'"),
        ([], ValueError, "at least one signal"),
        (("e", "e"), ValueError, "must not repeat"),
        ("e", ValueError, r"got the str 'e' \(for one signal: signals=\('e',\)\)"),
        ("all", ValueError, "got the str 'all'"),
        ("Metrics", ValueError, "got the str 'Metrics'"),
        (3, TypeError, "signals must be None, 'metrics' or a sequence"),
        (True, TypeError, "signals must be None, 'metrics' or a sequence"),
    ],
)
def test_bad_values_of_signals_are_refused(signals, error, match):
    with pytest.raises(error, match=match):
        fws.simulate_batch(PLANT, PATH, GAINS, signals=signals, **KW)


# --------------------------------------------------------------------------
# Memory


def test_the_budget_counts_the_kept_signals_only(monkeypatch):
    n, T = 8, 101  # 8 runs, duration 1 s at dt 0.01
    kw = {"initial_state": (0.0, -5.0, 0.0), "duration": 1.0}
    g = fws.SteeringGains(np.full(n, 0.2), 0.9, -1.0)
    two = n * 2 * T * 8  # e and theta of all runs [bytes]
    one_run = 1 * len(SIGNALS) * T * 8  # a chunk of one run, all signals
    assert one_run < two < n * len(SIGNALS) * T * 8
    monkeypatch.setattr(options, "MAX_OUTPUT_BYTES", two)
    with pytest.raises(ValueError, match="budget"):
        fws.simulate_batch(PLANT, PATH, g, **kw)  # all signals: refused
    res = fws.simulate_batch(PLANT, PATH, g, signals=("e", "theta"), chunk_size=1, **kw)
    assert res.signals.nbytes == two and res.ok.all()
    # a third signal is over the budget again
    with pytest.raises(ValueError, match="budget"):
        fws.simulate_batch(
            PLANT, PATH, g, signals=("e", "theta", "x"), chunk_size=1, **kw
        )
    # the working set of a chunk counts all its signals: 8 runs at once refused
    with pytest.raises(
        ValueError, match=r"chunk_size=8: a chunk computes all 15.*for each of 8 runs"
    ):
        fws.simulate_batch(PLANT, PATH, g, signals=("e", "theta"), chunk_size=8, **kw)
    # only the metrics: no signal bytes at all
    monkeypatch.setattr(options, "MAX_OUTPUT_BYTES", one_run)
    assert fws.simulate_batch(
        PLANT, PATH, g, signals="metrics", chunk_size=1, **kw
    ).ok.all()


def test_peak_memory_is_the_kept_data_and_one_chunk():
    # 8 chunks (each costs ~0.7 s of CPU under tracemalloc): the bound below
    # (~21 MB) is 1.5x under what keeping every signal holds (a batch doing
    # so peaks at that plus a chunk, 2.2x over it), two chunks' working sets
    # held at once are 1.7x over it and all 8 about 6x (one chunk's peak is
    # ~15 MB); a leak of ~70 kB per chunk exceeds its slack, as with 16
    n, chunk = 512, 64
    g = fws.double_root_gains(
        VEH, speed=5.0, curvature=0.1, ratio=np.linspace(-1.5, 0.6, n), pole=-1.0
    )
    kw = {"initial_state": (0.0, -5.0, 0.0), "duration": 5.0}
    kw |= {"engine": "numpy", "progress": False}
    one = fws.SteeringGains(g.k1[:chunk], g.k2[:chunk], g.ratio[:chunk])
    fws.simulate_batch(PLANT, PATH, one, **{**kw, "duration": 0.5})  # warm caches
    # the working set of one chunk: the peak of simulating it alone with all
    # its signals (its full signals, states, dense solution, peaks)
    _, chunk_peak = traced_peak(lambda: fws.simulate_batch(PLANT, PATH, one, **kw))
    res, peak = traced_peak(
        lambda: fws.simulate_batch(
            PLANT, PATH, g, signals=("e", "lateral_accel"), chunk_size=chunk, **kw
        )
    )
    kept = res.signals.nbytes
    assert kept == n * 2 * 501 * 8
    full = n * len(SIGNALS) * 501 * 8  # what keeping everything would hold
    bound = 1.3 * kept + chunk_peak
    assert bound < full  # (so the bound tells a reduced batch from a full one)
    assert peak < bound, (peak / 1e6, kept / 1e6, chunk_peak / 1e6)


# --------------------------------------------------------------------------
# Dask: reduced on the worker, same result


def test_signals_on_dask_equal_the_local_run(dask_client):
    local = fws.simulate_batch(PLANT, PATH, GAINS, signals=("e",), **KW)
    res = fws.simulate_batch(
        PLANT, PATH, GAINS, signals=("e",), client=dask_client, **KW
    )
    np.testing.assert_array_equal(res.e, local.e)
    np.testing.assert_array_equal(res.run_metrics, local.run_metrics)
    np.testing.assert_array_equal(res.run_peak, local.run_peak)


def test_lost_dask_tasks_keep_the_reduced_shape(dask_client):
    with pytest.warns(RuntimeWarning, match="2 runs of 1 lost"):
        res = fws.simulate_batch(
            PLANT, PATH, GAINS, signals=("e",), client=LosingClient(dask_client), **KW
        )
    local = fws.simulate_batch(PLANT, PATH, GAINS, signals=("e",), **KW)
    assert res.signals.shape == (6, 1, local.t.size)
    np.testing.assert_array_equal(res.e[:4], local.e[:4])
    assert res.status.tolist()[4:] == ["failed", "failed"]
    assert np.all(np.isnan(res.e[4:])) and np.all(np.isnan(res.run_metrics[4:]))
    assert res.run_samples[4:].tolist() == [0, 0]
