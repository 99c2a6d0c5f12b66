"""Batch engine: agreement with simulate, per-run stops, broadcasting, Dask."""

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

import fws_control as fws
from fws_control.paths import Arc, Straight

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


def _single(i, batch, path, feedforward=True, duration=10.0, dt=0.05):
    return fws.simulate(
        VEH,
        path,
        fws.SteeringGains(batch.k1[i], batch.k2[i], batch.ratio[i]),
        float(batch.speed[i]),
        batch.initial_state[i],
        duration,
        feedforward=feedforward,
        dt=dt,
    )


def test_batch_agrees_with_simulate_with_per_run_gains_speeds_and_states():
    ratios = np.array([-1.0, -0.5, 0.0, 0.5, -0.8, 0.2])
    speeds = np.array([5.0, 8.0, 12.0, 20.0, 3.0, 15.0])
    g = fws.double_root_gains(VEH, speeds, 0.02, ratios, -1.0)
    x0 = np.column_stack(
        [np.zeros(6), np.linspace(-8, 4, 6), np.linspace(-0.3, 0.3, 6)]
    )
    path = Arc(0.02)
    batch = fws.simulate_batch(VEH, path, g, speeds, x0, 10.0, dt=0.05)
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


def test_singular_runs_stop_and_the_others_continue():
    # run 0: |delta_f| > pi/2 at t = 0; run 1: k2 < 0 drives delta_f to pi/2
    # during the run; run 2: heads into the centre of curvature; run 3: fine.
    gains = [
        fws.SteeringGains(1.0, 0.5, 0.0),
        fws.SteeringGains(0.02, -0.5, 0.0),
        fws.SteeringGains(0.0, 0.0, 0.0),
        fws.double_root_gains(VEH, 5.0, 0.0, -1.0, -1.0),
    ]
    x0 = [(0.0, -5.0, 0.0), (0.0, -1.0, 0.0), (0.0, 5.0, math.pi / 2), (0.0, -5.0, 0.0)]
    path = Arc(0.1)
    batch = fws.simulate_batch(
        VEH, path, gains, 5.0, x0, 6.0, dt=0.01, feedforward=False
    )
    assert batch.status.tolist() == [
        "singular_steering",
        "singular_steering",
        "singular_curvature",
        "ok",
    ]
    assert batch.t_stop[0] == 0.0
    assert 0.0 < batch.t_stop[1] < 6.0
    assert batch.t_stop[2] == pytest.approx(1.0, abs=1e-9)  # 5 m at 5 m/s
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
    g = fws.double_root_gains(VEH, 20.0, 0.0, ratios, -1.0)
    seq = [fws.SteeringGains(g.k1[i], g.k2[i], g.ratio[i]) for i in range(3)]
    kw = {"feedforward": False, "dt": 0.1}
    a = fws.simulate_batch(VEH, Straight(), g, 20.0, (0.0, 2.0, 0.0), 5.0, **kw)
    b = fws.simulate_batch(
        VEH, Straight(), seq, [20.0] * 3, [(0.0, 2.0, 0.0)] * 3, 5.0, **kw
    )
    np.testing.assert_array_equal(a.e, b.e)
    # one gain, several initial states
    c = fws.simulate_batch(
        VEH, Straight(), seq[0], 20.0, [(0.0, 1.0, 0.0), (0.0, 2.0, 0.0)], 5.0, **kw
    )
    assert c.e.shape == (2, 51)
    np.testing.assert_allclose(c.e[1], a.e[0], atol=1e-9)
    with pytest.raises(ValueError, match="same number of runs"):
        fws.simulate_batch(VEH, Straight(), g, [5.0, 20.0], (0, 2, 0), 5.0)
    with pytest.raises(TypeError, match="SteeringGains"):
        fws.simulate_batch(VEH, Straight(), [(0.1, 0.2, 0.0)], 5.0, (0, 2, 0), 5.0)
    with pytest.raises(ValueError, match="chunk_size"):
        fws.simulate_batch(VEH, Straight(), g, 5.0, (0, 2, 0), 5.0, chunk_size=0)


def test_chunks_give_the_same_runs():
    ratios = np.linspace(-1.0, 0.5, 5)
    g = fws.double_root_gains(VEH, 5.0, 0.1, ratios, -1.0)
    one = fws.simulate_batch(VEH, Arc(0.1), g, 5.0, (0, -5, 0), 8.0, dt=0.05)
    split = fws.simulate_batch(
        VEH, Arc(0.1), g, 5.0, (0, -5, 0), 8.0, dt=0.05, chunk_size=2
    )
    np.testing.assert_allclose(split.e, one.e, rtol=0, atol=1e-6)


def test_dask_local_cluster_matches_local_run():
    distributed = pytest.importorskip(
        "dask.distributed", reason="the extra 'distributed' is not installed"
    )
    ratios = np.linspace(-1.0, 0.5, 5)
    g = fws.double_root_gains(VEH, 5.0, 0.1, ratios, -1.0)
    kw = {"dt": 0.05, "chunk_size": 2}
    local = fws.simulate_batch(VEH, Arc(0.1), g, 5.0, (0, -5, 0), 8.0, **kw)
    with (
        distributed.LocalCluster(
            processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        remote = fws.simulate_batch(
            VEH, Arc(0.1), g, 5.0, (0, -5, 0), 8.0, client=client, **kw
        )
    # same chunks, same arithmetic: identical, and in the original run order
    np.testing.assert_array_equal(remote.e, local.e)
    np.testing.assert_array_equal(remote.ratio, ratios)
    assert remote.status.tolist() == local.status.tolist()


def test_progress_bar_only_when_asked(capsys):
    g = fws.double_root_gains(VEH, 20.0, 0.0, [-1.0, 0.0], -1.0)
    args = (VEH, Straight(), g, 20.0, (0.0, 2.0, 0.0), 2.0)
    fws.simulate_batch(*args, feedforward=False, chunk_size=1)  # pytest: no TTY
    assert capsys.readouterr().err == ""
    fws.simulate_batch(*args, feedforward=False, chunk_size=1, progress=True)
    err = capsys.readouterr().err
    assert "simulate_batch" in err and "2/2" in err


def test_batch_result_accessors():
    g = fws.double_root_gains(VEH, 5.0, 0.1, [-1.0, 0.0], -1.0)
    batch = fws.simulate_batch(VEH, Arc(0.1), g, 5.0, (0, -5, 0), 3.0, dt=0.1)
    runs = batch.runs
    assert len(runs) == 2 and runs[1].gains == fws.SteeringGains(g.k1[1], g.k2[1], 0.0)
    np.testing.assert_array_equal(batch[-1].e, batch.e[1])
    with pytest.raises(IndexError):
        batch[2]
    df = batch.to_pandas()
    assert len(df) == 2 * 31 and set(df["run"]) == {0, 1}
    np.testing.assert_array_equal(df.loc[df["run"] == 1, "e"].to_numpy(), batch.e[1])
    fig = batch.plot()
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend == ["a=-1", "a=0"]
    plt.close(fig)
