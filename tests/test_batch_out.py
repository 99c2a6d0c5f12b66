"""simulate_batch(out=...): the signals written into a given array (issue 14, item 3).

References: the same batch without `out` (its signals, bitwise, NaN tails
included), a loop of scipy's ``solve_ivp`` on the closed loop written here
from the formulas (the lateral error of each run), ``numpy.load`` of the
memory-mapped file, the identity of the memory (``numpy.shares_memory``), and
tracemalloc's peak (a sweep written to a memory map does not hold its signals
in memory).
"""

from __future__ import annotations

import math
import re

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
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control.paths import Arc
from fws_control.simulation import SIGNALS, options

VEH = PAPER_VEHICLE
PLANT = fws.LateralPlant(VEH, speed=CURVE_SPEED)
PATH = Arc(0.1)
# five designs of the paper's curve scenario and one that stops (conftest)
GAINS = CURVE_GAINS_WITH_STOP
N = 6
KW = CURVE_BATCH_KW
T = 241  # output times of KW
ENGINES = ["numpy", "compiled"]


@pytest.fixture(scope="module", params=ENGINES)
def fresh(request):
    return fws.simulate_batch(PLANT, PATH, GAINS, engine=request.param, **KW)


def _e_from_the_formulas(i: int) -> np.ndarray:
    """Lateral error of run i: solve_ivp on the path-frame loop (eqs. 17-19)."""
    k1, k2, a = GAINS.k1[i], GAINS.k2[i], GAINS.ratio[i]
    f, kappa, V = VEH.wheelbase, 0.1, 5.0

    def rhs(t, y):
        s, e, th = y
        fb = -k1 * e - k2 * th
        df, dr = fb + math.atan(f * kappa), a * fb
        s_dot = V * math.cos(th + dr) / (1.0 - kappa * e)
        th_dot = -kappa * s_dot + V * math.sin(df - dr) / (f * math.cos(df))
        return [s_dot, V * math.sin(th + dr), th_dot]

    t = np.linspace(0.0, 12.0, T)
    sol = solve_ivp(rhs, (0.0, 12.0), [0.0, -5.0, 0.0], method="DOP853",
                    t_eval=t, rtol=1e-10, atol=1e-12)  # fmt: skip
    return sol.y[1]


@pytest.mark.parametrize("signals", [None, ("e", "lateral_accel")])
@pytest.mark.parametrize("chunk_size", [4, 64])  # two chunks; one
def test_out_receives_the_batch_bitwise_and_is_the_result(fresh, signals, chunk_size):
    kept = SIGNALS if signals is None else signals
    kw = {**KW, "chunk_size": chunk_size, "engine": fresh.engine}
    # (the numpy engine's runs share a chunk's steps: the same chunks)
    fresh = fws.simulate_batch(PLANT, PATH, GAINS, **kw)
    # stale values everywhere: every entry must be written, the NaN tail too
    out = np.full((N, len(kept), T), 7.0)
    res = fws.simulate_batch(PLANT, PATH, GAINS, signals=signals, out=out, **kw)
    rows = [SIGNALS.index(k) for k in kept]
    np.testing.assert_array_equal(out, fresh.signals[:, rows, :])
    assert np.shares_memory(res.signals, out)
    assert res.signals.shape == out.shape
    np.testing.assert_array_equal(res.run_peak, fresh.run_peak)
    assert res.status.tolist() == fresh.status.tolist()
    assert np.isnan(out[5, 0, -1]) and fresh.status[5] != "ok"  # the stopped run
    for i in range(5):  # the runs that finish, against the formulas
        np.testing.assert_allclose(out[i, kept.index("e")], _e_from_the_formulas(i),
                                   rtol=0, atol=1e-8)  # fmt: skip


def test_one_out_reused_for_another_sweep_holds_only_the_new_one(fresh):
    out = np.empty((N, len(SIGNALS), T))
    fws.simulate_batch(PLANT, PATH, GAINS, engine=fresh.engine, out=out, **KW)
    other = fws.SteeringGains(GAINS.k1[::-1], GAINS.k2[::-1], GAINS.ratio[::-1])
    res = fws.simulate_batch(PLANT, PATH, other, engine=fresh.engine, out=out, **KW)
    alone = fws.simulate_batch(PLANT, PATH, other, engine=fresh.engine, **KW)
    np.testing.assert_array_equal(out, alone.signals)
    if fresh.engine == "compiled":  # each run its own steps: the same runs
        np.testing.assert_array_equal(out, fresh.signals[::-1])
    np.testing.assert_array_equal(res.run_k1, GAINS.k1[::-1])


def test_a_memory_map_streams_the_sweep_to_a_file(fresh, tmp_path):
    name = tmp_path / "sweep.npy"
    disk = np.lib.format.open_memmap(name, mode="w+", shape=(N, 1, T))
    res = fws.simulate_batch(
        PLANT, PATH, GAINS, engine=fresh.engine, signals=("e",), out=disk, **KW
    )
    disk.flush()
    del disk
    saved = np.load(name)
    np.testing.assert_array_equal(saved[:, 0], fresh.e)
    np.testing.assert_array_equal(res.e, fresh.e)


@pytest.mark.parametrize("engine_name", ENGINES)
def test_a_sweep_into_a_memory_map_holds_one_chunk_in_memory(engine_name, tmp_path):
    # tracemalloc traces numpy's allocations, not the file's mapped pages:
    # the peak is the chunk's working set, not the sweep's signals. 8 chunks:
    # the sweep's signals (15 MB) are twice a chunk's peak (measured: 7.7 MB
    # on the numpy engine, 3.0 MB compiled), which the first assertion checks
    n, chunk = 256, 32
    g = fws.double_root_gains(
        VEH, speed=5.0, curvature=0.1, ratio=np.linspace(-1.5, 0.6, n), pole=-1.0
    )
    kw = {"initial_state": (0.0, -5.0, 0.0), "duration": 5.0}
    kw |= {"engine": engine_name, "progress": False}
    one = fws.SteeringGains(g.k1[:chunk], g.k2[:chunk], g.ratio[:chunk])
    fws.simulate_batch(PLANT, PATH, one, **{**kw, "duration": 0.5})  # warm caches
    _, chunk_peak = traced_peak(lambda: fws.simulate_batch(PLANT, PATH, one, **kw))
    disk = np.lib.format.open_memmap(
        tmp_path / "big.npy", mode="w+", shape=(n, len(SIGNALS), 501)
    )
    res, peak = traced_peak(
        lambda: fws.simulate_batch(PLANT, PATH, g, chunk_size=chunk, out=disk, **kw)
    )
    assert res.ok.all()
    whole = n * len(SIGNALS) * 501 * 8
    assert 1.3 * chunk_peak < whole  # (so the bound tells the two apart)
    assert peak < 1.3 * chunk_peak, (peak / 1e6, chunk_peak / 1e6, whole / 1e6)


def test_the_budget_does_not_count_a_given_out(monkeypatch):
    n = 8
    kw = {"initial_state": (0.0, -5.0, 0.0), "duration": 1.0}
    g = fws.SteeringGains(np.full(n, 0.2), 0.9, -1.0)
    one_run = len(SIGNALS) * 101 * 8  # a chunk of one run, all signals
    monkeypatch.setattr(options, "MAX_OUTPUT_BYTES", one_run)
    with pytest.raises(ValueError, match="budget"):
        fws.simulate_batch(PLANT, PATH, g, chunk_size=1, **kw)
    out = np.empty((n, len(SIGNALS), 101))
    res = fws.simulate_batch(PLANT, PATH, g, chunk_size=1, out=out, **kw)
    assert res.ok.all() and np.shares_memory(res.signals, out)
    # the chunk's working set still counts: two runs at once are refused
    with pytest.raises(
        ValueError, match=r"chunk_size=2: a chunk computes all 15 signals before "
        "it writes them into out"
    ):  # fmt: skip
        fws.simulate_batch(PLANT, PATH, g, chunk_size=2, out=out, **kw)


# --------------------------------------------------------------------------
# Bad input: refused before any run, naming the argument and what it needs

_SHAPE = (N, len(SIGNALS), T)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    shape=st.tuples(st.integers(0, 8), st.integers(0, 16), st.integers(0, 300)).filter(
        lambda s: s != _SHAPE
    )
)
def test_an_out_of_another_shape_is_refused_naming_the_shape(shape):
    needed = re.escape(
        f"out must be a float64 array (native byte order) of shape {_SHAPE}"
    )
    with pytest.raises(
        ValueError, match=needed + ".*got float64 of shape " + re.escape(str(shape))
    ):
        fws.simulate_batch(PLANT, PATH, GAINS, out=np.empty(shape), **KW)


@pytest.mark.parametrize("engine_name", ENGINES)
@pytest.mark.parametrize("dtype", [np.float32, np.int64, np.complex128, ">f8"])
def test_an_out_of_another_dtype_is_refused(dtype, engine_name):
    # (a kept subset: no later check of the compiled outputs would catch it)
    out = np.empty((N, 1, T), dtype=dtype)
    with pytest.raises(ValueError, match=r"out must be a float64 array \(native"):
        fws.simulate_batch(
            PLANT, PATH, GAINS, signals=("e",), engine=engine_name, out=out, **KW
        )


def test_a_strided_or_read_only_out_is_refused():
    with pytest.raises(ValueError, match="out must be C-contiguous"):
        fws.simulate_batch(PLANT, PATH, GAINS, out=np.empty(_SHAPE, order="F"), **KW)
    with pytest.raises(ValueError, match="out must be C-contiguous"):
        wide = np.empty((N, len(SIGNALS), 2 * T))[:, :, ::2]
        fws.simulate_batch(PLANT, PATH, GAINS, out=wide, **KW)
    frozen = np.empty(_SHAPE)
    frozen.flags.writeable = False
    with pytest.raises(ValueError, match="out must be writeable"):
        fws.simulate_batch(PLANT, PATH, GAINS, out=frozen, **KW)


def test_an_out_that_is_not_an_array_or_with_metrics_only_is_refused():
    with pytest.raises(TypeError, match="out must be a numpy.ndarray.*got list"):
        fws.simulate_batch(PLANT, PATH, GAINS, out=np.empty(_SHAPE).tolist(), **KW)
    # a masked array's mask would not follow the chunks' writes
    masked = np.ma.masked_array(np.empty(_SHAPE), mask=True)
    with pytest.raises(TypeError, match="or a numpy.memmap, got MaskedArray"):
        fws.simulate_batch(PLANT, PATH, GAINS, out=masked, **KW)
    with pytest.raises(ValueError, match="out must be None with signals='metrics'"):
        fws.simulate_batch(
            PLANT, PATH, GAINS, signals="metrics", out=np.empty((N, 0, T)), **KW
        )


def test_out_on_dask_receives_the_chunks_of_the_cluster(dask_client):
    local = fws.simulate_batch(PLANT, PATH, GAINS, signals=("e", "theta"), **KW)
    out = np.full((N, 2, T), 7.0)
    res = fws.simulate_batch(
        PLANT, PATH, GAINS, signals=("e", "theta"), client=dask_client, out=out, **KW
    )
    np.testing.assert_array_equal(out, local.signals)
    assert np.shares_memory(res.signals, out)


def test_an_out_that_holds_t_eval_gives_the_batch_and_its_times(fresh):
    # t_eval is copied: the chunks' writes into out cannot move the grid
    out = np.empty((N, len(SIGNALS), T))
    grid = out[0, 0, :]
    grid[:] = fresh.t
    res = fws.simulate_batch(
        PLANT, PATH, GAINS, engine=fresh.engine, out=out, t_eval=grid,
        **{k: v for k, v in KW.items() if k != "dt"},
    )  # fmt: skip
    np.testing.assert_array_equal(res.t, fresh.t)
    np.testing.assert_array_equal(out, fresh.signals)
    assert not np.shares_memory(res.t, out)


def test_lost_dask_tasks_leave_nan_in_out_not_stale_values(dask_client):
    local = fws.simulate_batch(PLANT, PATH, GAINS, signals=("e",), **KW)
    out = np.full((N, 1, T), 7.0)
    with pytest.warns(RuntimeWarning, match="2 runs of 1 lost"):
        res = fws.simulate_batch(
            PLANT, PATH, GAINS, signals=("e",), client=LosingClient(dask_client),
            out=out, **KW,
        )  # fmt: skip
    np.testing.assert_array_equal(out[:4], local.signals[:4])
    assert np.all(np.isnan(out[4:])) and res.status.tolist()[4:] == ["failed"] * 2
