"""The compiled kernels: their cache entries and their specialised copies.

Two ways a call could run other code than the code its parameters ask for:

- numba's cache files. numba names a new entry's data file after the first
  number free in the index it has just read and writes the index first;
  two processes that save different overloads of one function at once take
  the same number, and one key's index entry can then point at the other's
  code. The DOP853 and the Radau driver are such overloads (closures of one
  function), compiled side by side by the test suite's precompile step: a
  Radau call returned DOP853's steps (145 accepted steps where Radau takes
  397). ``compilation._KernelCacheFile`` names each data file after its key
  and writes the data before the index.
- the kernels specialised to a call's features
  (:mod:`~fws_control.simulation.compiled_variants`): their branches left
  out are those the call's parameters switch off, so they must compute bit
  for bit what the full kernels compute.
"""

import pickle

import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws

numba = pytest.importorskip(
    "numba", reason="numba is not installed: the compiled engine (extra 'fast') "
    "is not tested"
)  # fmt: skip

from fws_control.simulation import compilation, compiled  # noqa: E402
from fws_control.simulation.compiled_variants import (  # noqa: E402
    FEATURES,
    kernels,
    variant,
)

STAMP = (("compiled.py", 1.0, 10),)


def _save_at_once(cls, folder):
    # Process A saves key_a; process B, which read the index before A
    # wrote it, saves key_b completely right after A's index write (before
    # A writes its data, in numba's order). Returns what a later process
    # loads for each key.
    folder.mkdir()

    def make():
        return cls(
            cache_path=str(folder), filename_base="kernel-1.py311", source_stamp=STAMP
        )

    a, b = make(), make()
    stale = a._load_index()
    real_save_index = a._save_index

    def then_b_saves(overloads):
        real_save_index(overloads)
        b._load_index = lambda: dict(stale)
        b.save(KEY_B, DATA_B)

    a._save_index = then_b_saves
    a.save(KEY_A, DATA_A)
    later = make()
    return later.load(KEY_A), later.load(KEY_B)


KEY_A = ("sig", "machine", ("code", "method 0"))
KEY_B = ("sig", "machine", ("code", "method 1"))
DATA_A, DATA_B = ("dop853 code",), ("radau code",)


def test_two_processes_saving_at_once_keep_their_overloads_apart(tmp_path):
    # each key loads its own data or nothing (a lost entry is compiled
    # again), never the other key's
    got_a, got_b = _save_at_once(compilation._KernelCacheFile, tmp_path / "ours")
    assert got_a in (DATA_A, None) and got_b in (DATA_B, None)
    assert (got_a, got_b) != (None, None)  # the last writer's entry survives
    # numba's own files, in the same interleaving, give B's key A's code
    got_a, got_b = _save_at_once(
        compilation._caching.IndexDataCacheFile, tmp_path / "numba"
    )
    assert got_b == DATA_A


def test_an_entry_is_named_after_its_key_in_every_process(tmp_path):
    # a second process (a new object) saving the same key writes the same
    # file, and the index of a stale stamp is not read
    key = ("sig", "machine", ("code", "cells"))
    make = compilation._KernelCacheFile
    first, second = (
        make(
            cache_path=str(tmp_path), filename_base="kernel-1.py311", source_stamp=STAMP
        )
        for _ in range(2)
    )
    first.save(key, ("old",))
    second.save(key, ("new",))
    assert first.data_name(key) == second.data_name(key)
    assert len(list(tmp_path.glob("*.nbc"))) == 1
    assert second.load(key) == ("new",)
    with open(tmp_path / "kernel-1.py311.nbi", "rb") as f:
        pickle.load(f)  # numba's version
        stamp, overloads = pickle.loads(f.read())
    assert stamp == STAMP and overloads == {key: first.data_name(key)}
    restamped = compilation._KernelCacheFile(
        cache_path=str(tmp_path), filename_base="kernel-1.py311",
        source_stamp=(("compiled.py", 2.0, 10),),
    )  # fmt: skip
    assert restamped.load(key) is None


def _integrate(method, features, monkeypatch, limits):
    # integrate_compiled with the top kernels of `features` forced
    def stage(q):
        compiled._call.features = features
        return kernels(features)

    monkeypatch.setattr(compiled, "_stage_kernels", stage)
    lim = dict(max_steer_front=0.2, max_steer_rear=0.08, max_steer_rate_front=0.15,
               max_steer_rate_rear=0.1) if limits else {}  # fmt: skip
    veh = fws.Vehicle(PAPER_VEHICLE.wheelbase, PAPER_VEHICLE.rear_to_cg, **lim)
    tab = compiled.curvature_table(fws.Arc(0.1))
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-0.5, pole=-1.0)
    return compiled.integrate_compiled(
        veh, tab, fws.SteeringGains(np.array([g.k1, 0.9 * g.k1]), g.k2, g.ratio),
        speed=np.array([5.0, 6.0]), feedforward=True,
        path_state=np.array([[0.0, -2.0, 0.1], [0.0, 1.0, -0.2]]),
        t_eval=np.linspace(0.0, 6.0, 61), time_constant=0.05, rtol=1e-8,
        atol=1e-10, method=method,
    )  # fmt: skip


# DOP853 only: Radau runs only calls without a feature (compiled_support),
# so its kernels of every feature are never compiled outside this test (44 s
# of CPU here); its featureless kernels, the ones that run, take scipy's
# Radau steps (test_compiled_radau.test_engine_radau_takes_scipys_steps).
@pytest.mark.parametrize("limits", [False, True], ids=["free", "rate-limited"])
@pytest.mark.parametrize("method", ["DOP853"])
def test_the_featureless_kernels_compute_what_the_full_kernels_compute(
    method, limits, monkeypatch
):
    plain = _integrate(method, frozenset(), monkeypatch, limits)
    full = _integrate(method, frozenset(FEATURES), monkeypatch, limits)
    states, status, _, t_stop, stats = plain
    assert list(status) == ["ok", "ok"]
    np.testing.assert_array_equal(states, full[0])
    np.testing.assert_array_equal(t_stop, full[3])
    np.testing.assert_array_equal(stats, full[4])
    if limits:
        assert stats[:, 4].max() > 0  # a clip switched (events located)


def test_variant_of_a_kernel_is_the_copy_its_drivers_inline():
    # variant(k, features) is the copy of k that the variant's own drivers
    # call (their globals hold it), k itself with every feature, and an
    # error naming the argument for anything else
    step = variant(compiled.dop853_step, ())
    assert step is not compiled.dop853_step
    drivers = kernels(()).solve_batch.py_func.__globals__
    assert drivers["dop853_step"] is step
    assert step.py_func.__code__ is compiled.dop853_step.py_func.__code__
    assert variant(compiled.dop853_step, FEATURES) is compiled.dop853_step
    assert variant(compiled.dop853_step, ["delay"]) is not step
    with pytest.raises(ValueError, match="kernel must be a kernel"):
        variant(np.hypot, ())
    with pytest.raises(ValueError, match=r"features must be in .*'bogus'"):
        variant(compiled.dop853_step, ["bogus"])
