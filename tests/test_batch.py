"""Batch engine and the multi-run result: agreement with simulate, per-run
stops, broadcasting, Dask, indexing, pandas, python-control and plots."""

import math

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws
from fws_control.paths import Arc, Straight
from fws_control.simulation import SIGNALS
from fws_control.simulation.result import expand_runs

VEH = PAPER_VEHICLE


def _gains(speed, curvature, ratio, pole=-1.0):
    return fws.double_root_gains(
        VEH, speed=speed, curvature=curvature, ratio=ratio, pole=pole
    )


def _single(i, batch, path, feedforward=True, duration=10.0, dt=0.05):
    return fws.simulate(
        fws.LateralPlant(VEH, speed=float(batch.speed[i])),
        path,
        fws.SteeringGains(batch.k1[i], batch.k2[i], batch.ratio[i]),
        initial_state=batch.initial_state[i],
        duration=duration,
        feedforward=feedforward,
        dt=dt,
    )


def test_batch_agrees_with_simulate_with_per_run_gains_speeds_and_states():
    ratios = np.array([-1.0, -0.5, 0.0, 0.5, -0.8, 0.2])
    speeds = np.array([5.0, 8.0, 12.0, 20.0, 3.0, 15.0])
    g = _gains(speeds, 0.02, ratios)
    x0 = np.column_stack(
        [np.zeros(6), np.linspace(-8, 4, 6), np.linspace(-0.3, 0.3, 6)]
    )
    path = Arc(0.02)
    batch = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=speeds),
        path,
        g,
        initial_state=x0,
        duration=10.0,
        dt=0.05,
    )
    assert batch.e.shape == (6, 201) and len(batch) == 6
    assert batch.status.tolist() == ["ok"] * 6
    for i in range(6):
        single = _single(i, batch, path)
        for name in ("e", "theta", "x", "y", "psi"):
            np.testing.assert_allclose(
                getattr(batch, name)[i], getattr(single, name), rtol=0, atol=1e-6
            )
        np.testing.assert_allclose(
            batch.lateral_accel[i], single.lateral_accel, rtol=0, atol=1e-6
        )


#: When run 2 of _stopping_batch stops: it heads from e = 5 m straight at the
#: centre (e = 10 m) at 5 m/s; 1 - e/10 = 0 at t = 1 s, and = 1e-3 (the
#: compiled engine's margin) at e = 9.99 m, t = 0.998 s.
# 5 m at 5 m/s to 1 - kappa e = 0 is t = 1 s; both engines stop at their
# margin 1 - kappa e = 1e-3, 0.01 m earlier
_CENTRE_STOP = 0.998


def _stopping_batch():
    # run 0: |delta_f| > pi/2 at t = 0; run 1: k2 < 0 drives delta_f to pi/2
    # during the run; run 2: heads into the centre of curvature; run 3: fine.
    gains = [
        fws.SteeringGains(1.0, 0.5, 0.0),
        fws.SteeringGains(0.02, -0.5, 0.0),
        fws.SteeringGains(0.0, 0.0, 0.0),
        _gains(5.0, 0.0, -1.0),
    ]
    x0 = [(0.0, -5.0, 0.0), (0.0, -1.0, 0.0), (0.0, 5.0, math.pi / 2), (0.0, -5.0, 0.0)]
    batch = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(0.1),
        gains,
        initial_state=x0,
        duration=6.0,
        dt=0.01,
        feedforward=False,
    )
    return batch


def test_singular_runs_stop_and_the_others_continue():
    batch = _stopping_batch()
    path = batch.path
    assert batch.status.tolist() == [
        "singular_steering",
        "singular_steering",
        "singular_curvature",
        "ok",
    ]
    assert batch.singular.tolist() == [True, True, True, False]
    assert batch.t_stop[0] == 0.0
    assert 0.0 < batch.t_stop[1] < 6.0
    assert batch.t_stop[2] == pytest.approx(_CENTRE_STOP, abs=1e-9)
    assert batch.t_stop[3] == 6.0
    for i in range(3):
        after = batch.t > batch.t_stop[i]
        assert np.all(np.isnan(batch.e[i, after]))
        assert np.all(np.isfinite(batch.e[i, ~after]))
        assert batch.message[i]
    # every run agrees with its own single simulation, including the stops
    for i in range(4):
        single = _single(i, batch, path, False, duration=6.0, dt=0.01)
        assert single.status == batch.status[i]
        assert single.t_stop == pytest.approx(batch.t_stop[i], abs=1e-8)
        run = batch[i]
        np.testing.assert_array_equal(run.t, single.t)
        np.testing.assert_allclose(run.e, single.e, rtol=0, atol=1e-6)


def test_gains_sequence_equals_array_gains_and_broadcasting():
    ratios = np.array([-1.0, 0.0, 0.5])
    g = _gains(20.0, 0.0, ratios)
    seq = [fws.SteeringGains(g.k1[i], g.k2[i], g.ratio[i]) for i in range(3)]
    kw = {"duration": 5.0, "feedforward": False, "dt": 0.1}
    a = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=20.0),
        Straight(),
        g,
        initial_state=(0.0, 2.0, 0.0),
        **kw,
    )
    b = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=[20.0] * 3),
        Straight(),
        seq,
        initial_state=[(0.0, 2.0, 0.0)] * 3,
        **kw,
    )
    np.testing.assert_array_equal(a.e, b.e)
    # one gain, several initial states
    c = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=20.0),
        Straight(),
        seq[0],
        initial_state=[(0.0, 1.0, 0.0), (0.0, 2.0, 0.0)],
        **kw,
    )
    assert c.e.shape == (2, 51)
    np.testing.assert_allclose(c.e[1], a.e[0], atol=1e-9)
    base = {"initial_state": (0, 2, 0), "duration": 5.0}
    plant = fws.LateralPlant(VEH, speed=5.0)
    two = fws.LateralPlant(VEH, speed=[5.0, 20.0])
    with pytest.raises(ValueError, match="same number of runs"):
        fws.simulate_batch(two, Straight(), g, **base)
    with pytest.raises(TypeError, match="SteeringGains"):
        fws.simulate_batch(plant, Straight(), [(0.1, 0.2, 0.0)], **base)
    with pytest.raises(ValueError, match="chunk_size"):
        fws.simulate_batch(plant, Straight(), g, **base, chunk_size=0)
    with pytest.raises(ValueError, match="chunk_size"):
        fws.simulate_batch(plant, Straight(), g, **base, chunk_size=1.5)
    # options are keyword-only
    with pytest.raises(TypeError):
        fws.simulate_batch(plant, Straight(), g, (0, 2, 0), 5.0)


def test_chunks_give_the_same_runs():
    ratios = np.linspace(-1.0, 0.5, 5)
    g = _gains(5.0, 0.1, ratios)
    kw = {"initial_state": (0, -5, 0), "duration": 8.0, "dt": 0.05}
    plant = fws.LateralPlant(VEH, speed=5.0)
    one = fws.simulate_batch(plant, Arc(0.1), g, **kw)
    split = fws.simulate_batch(plant, Arc(0.1), g, **kw, chunk_size=2)
    np.testing.assert_allclose(split.e, one.e, rtol=0, atol=1e-6)


def test_dask_local_cluster_matches_local_run(dask_client):
    ratios = np.linspace(-1.0, 0.5, 5)
    g = _gains(5.0, 0.1, ratios)
    kw = {"initial_state": (0, -5, 0), "duration": 8.0, "dt": 0.05, "chunk_size": 2}
    plant = fws.LateralPlant(VEH, speed=5.0)
    local = fws.simulate_batch(plant, Arc(0.1), g, **kw)
    remote = fws.simulate_batch(plant, Arc(0.1), g, client=dask_client, **kw)
    # same chunks, same arithmetic: identical, and in the original run order
    np.testing.assert_array_equal(remote.e, local.e)
    np.testing.assert_array_equal(remote.ratio, ratios)
    assert remote.status.tolist() == local.status.tolist()


def test_progress_bar_only_when_asked(capsys):
    g = _gains(20.0, 0.0, np.array([-1.0, 0.0]))
    kw = {
        "initial_state": (0.0, 2.0, 0.0),
        "duration": 2.0,
        "feedforward": False,
        "chunk_size": 1,
    }
    plant = fws.LateralPlant(VEH, speed=20.0)
    fws.simulate_batch(plant, Straight(), g, **kw)  # pytest: no TTY
    assert capsys.readouterr().err == ""
    fws.simulate_batch(plant, Straight(), g, **kw, progress=True)
    err = capsys.readouterr().err
    assert "simulate_batch" in err and "2/2" in err


# --------------------------------------------------------------------------
# The multi-run result


def _two_ratio_batch(dt=0.1, duration=3.0):
    g = _gains(5.0, 0.1, np.array([-1.0, 0.0]))
    batch = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(0.1),
        g,
        initial_state=(0, -5, 0),
        duration=duration,
        dt=dt,
    )
    return g, batch


def test_batch_is_never_squeezed_and_runs_are():
    g = _gains(5.0, 0.1, -1.0)
    one = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(0.1),
        g,
        initial_state=(0, -5, 0),
        duration=3.0,
        dt=0.1,
    )
    # a batch of one run keeps its run axis, for every per-run attribute
    assert not one.squeeze and len(one) == 1
    assert one.e.shape == (1, 31) and one.t.shape == (31,)
    assert one.status.tolist() == ["ok"] and one.message == ("",)
    assert one.t_stop.shape == one.speed.shape == one.k1.shape == (1,)
    assert one.initial_state.shape == (1, 3) and one.ok.tolist() == [True]
    assert np.shape(one.gains.k1) == (1,)
    assert fws.tracking_metrics(one).settling_time.shape == (1,)
    # its run is squeezed
    run = one[0]
    assert run.squeeze and run.e.shape == (31,) and run.status == "ok"
    assert np.ndim(fws.tracking_metrics(run).settling_time) == 0


def test_batch_indexing_slices_masks_and_iteration():
    g, batch = _two_ratio_batch()
    runs = batch.runs
    assert len(runs) == 2 and runs[1].gains == fws.SteeringGains(g.k1[1], g.k2[1], 0.0)
    assert [r.ratio for r in batch] == [-1.0, 0.0]
    np.testing.assert_array_equal(batch[-1].e, batch.e[1])
    with pytest.raises(IndexError):
        batch[2]
    with pytest.raises(TypeError, match="run index"):
        batch["e"]
    # slices, index arrays and masks give batches on the same grid
    for sub, idx in (
        (batch[1:], [1]),
        (batch[np.array([1, 0])], [1, 0]),
        (batch[np.array([False, True])], [1]),
    ):
        assert not sub.squeeze and len(sub) == len(idx)
        np.testing.assert_array_equal(sub.t, batch.t)
        np.testing.assert_array_equal(sub.e, batch.e[idx])
        np.testing.assert_array_equal(sub.ratio, batch.ratio[idx])
    assert "runs=2" in repr(batch) and "'ok': 2" in repr(batch)


def test_batch_to_time_response_and_time_response_plot():
    batch = _stopping_batch()[np.array([1, 3])]  # one stopped run, one ok
    resp = batch.to_time_response()
    assert isinstance(resp, ct.TimeResponseData)
    assert resp.output_labels == list(SIGNALS)
    assert resp.ntraces == 2 and resp.outputs.shape == (len(SIGNALS), 2, batch.t.size)
    # trace labels name what differs between the runs
    assert resp.trace_labels == ["a=0, R0=(0, -1, 0)", "a=-1, R0=(0, -5, 0)"]
    assert not resp.success and "pi/2" in resp.message
    np.testing.assert_array_equal(resp.time, batch.t)
    for j, name in enumerate(SIGNALS):
        np.testing.assert_array_equal(resp.outputs[j], getattr(batch, name))
    np.testing.assert_array_equal(resp.params["speed"], [5.0, 5.0])
    # python-control's own conversion of the same data
    df = resp.to_pandas()
    mine = batch.to_pandas()
    np.testing.assert_array_equal(
        df.loc[df["trace"] == resp.trace_labels[0], "e"].dropna(),
        mine.loc[mine["run"] == 0, "e"],
    )
    cplt = ct.time_response_plot(resp)
    try:
        assert isinstance(cplt, ct.ControlPlot)
        assert cplt.axes.shape == (len(SIGNALS), 2)  # a column per run
        e_row = SIGNALS.index("e")
        for j in range(2):
            ydata = cplt.lines[e_row, j][0].get_ydata()
            np.testing.assert_array_equal(ydata, batch.e[j])
    finally:
        plt.close("all")


def test_to_pandas_keeps_gains_speed_status_and_runs_without_samples():
    speeds = np.array([4.0, 6.0])
    ratios = np.array([-0.5, 0.5])
    g = _gains(speeds, 0.1, ratios)
    sub = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=speeds),
        Arc(0.1),
        g,
        initial_state=[(0, -2, 0), (0, -3, 0.1)],
        duration=2.0,
        dt=0.5,
    )
    # three runs: the middle one has no design and is not simulated
    k1 = np.array([g.k1[0], np.nan, g.k1[1]])
    k2 = np.array([g.k2[0], np.nan, g.k2[1]])
    ratio = np.array([-0.5, 1.0, 0.5])
    speed = np.array([4.0, 5.0, 6.0])
    x0 = np.array([(0, -2, 0), (0, -4, 0), (0, -3, 0.1)], dtype=float)
    full = expand_runs(
        sub,
        positions=[0, 2],
        k1=k1,
        k2=k2,
        ratio=ratio,
        speed=speed,
        initial_state=x0,
        t=sub.t,
        feedforward=True,
        vehicle=VEH,
        path=Arc(0.1),
        message="no design",
    )
    assert full.status.tolist() == ["ok", "uncontrollable", "ok"]
    assert full.gains is None  # a SteeringGains cannot hold the missing design
    assert full[1].gains is None and full[1].t.size == 0
    np.testing.assert_array_equal(full.e[[0, 2]], sub.e)
    df = full.to_pandas()
    assert list(df["run"]) == [0] * 5 + [1] + [2] * 5
    for i in range(3):
        rows = df[df["run"] == i]
        # every row of a run carries the run's own values, as passed in
        assert set(rows["speed"]) == {speed[i]}
        assert set(rows["ratio"]) == {ratio[i]}
        assert set(rows["status"]) == {full.status[i]}
        np.testing.assert_array_equal(rows["k1"], np.full(len(rows), k1[i]))
        np.testing.assert_array_equal(rows["k2"], np.full(len(rows), k2[i]))
    empty = df[df["run"] == 1]
    assert len(empty) == 1 and math.isnan(empty["t"].iloc[0])
    assert empty[list(SIGNALS)].isna().all(axis=None)
    assert math.isnan(empty["t_stop"].iloc[0])
    for i, j in ((0, 0), (2, 1)):
        rows = df[df["run"] == i]
        np.testing.assert_array_equal(rows["t"], sub.t)
        np.testing.assert_array_equal(rows["e"], sub.e[j])
        np.testing.assert_array_equal(rows["lateral_accel"], sub.lateral_accel[j])


def test_to_pandas_of_stopped_runs_holds_their_samples_up_to_the_stop():
    batch = _stopping_batch()
    df = batch.to_pandas()
    for i in range(len(batch)):
        rows = df[df["run"] == i]
        expect_t = batch.t[batch.t <= batch.t_stop[i]]
        np.testing.assert_array_equal(rows["t"], expect_t)
        np.testing.assert_array_equal(rows["e"], batch.e[i, : expect_t.size])
        assert set(rows["status"]) == {batch.status[i]}


def test_batch_plot_returns_controlplot_with_default_labels_and_accepts_ax():
    _, batch = _two_ratio_batch()
    cplt = batch.plot(title="two ratios")
    try:
        assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == (3, 2)
        legend = [t.get_text() for t in cplt.axes[0, 0].get_legend().get_texts()]
        assert legend == ["a=-1", "a=0"]
        assert cplt.figure._suptitle.get_text() == "two ratios"
        # one line per run in the e panel, in run order, with the batch's data
        e_lines = cplt.lines[0, 0]
        assert len(e_lines) == 2
        for j in range(2):
            np.testing.assert_array_equal(e_lines[j].get_ydata(), batch.e[j])
        # a list of six axes works too, and draws only into them
        fig, axs = plt.subplots(2, 3)
        again = batch.plot(ax=list(axs.flat), labels=["first", "second"])
        assert again.axes.shape == again.lines.shape == (1, 6)
        assert again.figure is fig
        legend = [t.get_text() for t in axs[0, 0].get_legend().get_texts()]
        assert legend == ["first", "second"]
    finally:
        plt.close("all")


def test_plot_marks_stopped_and_unsimulated_runs():
    batch = _stopping_batch()
    unsimulated = expand_runs(
        None,
        positions=[],
        k1=[np.nan],
        k2=[np.nan],
        ratio=[1.0],
        speed=[5.0],
        initial_state=[(0.0, 2.0, 0.0)],
        t=batch.t,
        feedforward=False,
        vehicle=VEH,
        path=Straight(),
        message="no design",
    )
    assert unsimulated.status.tolist() == ["uncontrollable"]
    cplt = batch.plot(labels=["r0", "r1", "r2", "r3"])
    try:
        texts = [t.get_text() for t in cplt.axes[0, 0].get_legend().get_texts()]
        assert texts[0] == "r0 (singular_steering at t=0 s)"
        assert texts[2] == "r2 (singular_curvature at t=0.998 s)"
        assert texts[3] == "r3"
        # a stopped run gets an 'x' at its last sample
        marks = [ln for ln in cplt.lines[0, 0] if ln.get_marker() == "x"]
        n1 = int(np.count_nonzero(np.isfinite(batch.e[1])))
        assert any(float(m.get_ydata()[0]) == batch.e[1, n1 - 1] for m in marks)
        more = unsimulated.plot(ax=cplt.axes, labels="a=1")
        texts = [t.get_text() for t in more.axes[0, 0].get_legend().get_texts()]
        assert texts[-1] == "a=1 (uncontrollable: not simulated)"
        assert more.lines[0, 0][0].get_xdata().size == 0
    finally:
        plt.close("all")


def test_expand_runs_keeps_the_model_and_tyre_of_the_simulated_runs():
    # a dynamic batch expanded with an unsimulated run stays a dynamic result:
    # its lateral acceleration and tyre model belong to the simulated runs
    car = fws.vehicles.BMW_320I
    g = fws.double_root_gains(car, speed=20.0, ratio=0.0, pole=-1.0)
    sub = fws.simulate_batch(
        fws.LateralPlant(car, speed=20.0, model="dynamic", tyre="magic"),
        Straight(), g, initial_state=(0.0, 1.0, 0.0),
        duration=2.0, dt=0.5,
    )  # fmt: skip
    full = expand_runs(
        sub, positions=[1], k1=[np.nan, g.k1], k2=[np.nan, g.k2],
        ratio=[1.0, 0.0], speed=[20.0, 20.0], initial_state=[(0, 1, 0)] * 2,
        t=sub.t, feedforward=True, vehicle=car, path=Straight(),
    )  # fmt: skip
    assert (full.model, full.tyre) == (sub.model, sub.tyre) == ("dynamic", "magic")
    np.testing.assert_array_equal(full.lateral_accel[1], sub.lateral_accel[0])
    assert full.status.tolist() == ["uncontrollable", "ok"]


def test_plot_keeps_the_bulk_visible_when_a_stopped_run_diverges():
    batch = _stopping_batch()
    cplt = batch.plot()
    try:
        ax_a = cplt.axes.flat[5]  # lateral acceleration
        lo, hi = ax_a.get_ylim()
        a = batch.lateral_accel
        ok = np.abs(a[3])
        # the finished run is wholly visible ...
        assert lo <= np.min(a[3]) and np.max(a[3]) <= hi
        # ... and not squashed by run 1's divergent end (thousands of m/s^2)
        assert np.nanmax(np.abs(a[1])) > 100 * ok.max()
        assert hi - lo < 50 * ok.max()
        # run 1's stop marker sits on the limit, pointing off the axes
        marks = [m for m in ax_a.get_lines() if m.get_marker() in ("^", "v")]
        assert len(marks) == 1
        assert float(marks[0].get_ydata()[0]) in (lo, hi)
    finally:
        plt.close("all")


def test_plot_of_a_straight_road_is_not_a_flat_line_and_overlays_one_path():
    g = fws.SteeringGains(0.1, 0.5, 0.0)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Straight(),
        g,
        initial_state=(0.0, 1.0, 0.0),
        duration=15.0,
    )
    other = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Straight(),
        g,
        initial_state=(0.0, -1.0, 0.0),
        duration=15.0,
    )
    cplt = res.plot(labels="e0 = 1 m")
    try:
        ax_xy = cplt.axes.flat[2]
        lo, hi = ax_xy.get_ylim()
        y_span = np.ptp(res.y)
        x_span = np.ptp(res.x)
        assert x_span > 50 * y_span  # 75 m along, 1 m across
        # y drawn at its own scale, not stretched to the x span
        assert hi - lo < 2 * y_span
        assert "not to scale" in ax_xy.get_title()
        other.plot(ax=cplt.axes, labels="e0 = -1 m")
        texts = [t.get_text() for t in ax_xy.get_legend().get_texts()]
        assert texts.count("path") == 1
    finally:
        plt.close("all")
