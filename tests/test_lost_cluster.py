"""simulate_batch on a Dask cluster whose workers are all gone.

Without a nanny nothing restarts a killed worker, and the scheduler keeps
the pending tasks forever. The reference is the same batch run here
(client=None): the call raises ClusterLostError within a bounded wait
instead of waiting forever; the result it carries keeps the chunk that
finished before the workers went bitwise, and marks the other failed with
NaN data.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from conftest import (
    CURVE_BATCH_KW,
    CURVE_GAINS_WITH_STOP,
    CURVE_SPEED,
    PAPER_VEHICLE,
    dask_distributed,
)

import fws_control as fws
from fws_control.paths import Arc
from fws_control.simulation import cluster as dask_chunks
from fws_control.simulation import runners

VEH = PAPER_VEHICLE
PLANT = fws.LateralPlant(VEH, speed=CURVE_SPEED)


# Opened by the test once it is done: the chunks after the first wait for
# it on the (in-process) worker, so that they cannot finish before the
# workers are gone. Module-level: Dask pickles the task by reference.
_GATE = threading.Event()


def _gated(run, *args):
    _GATE.wait(60.0)
    return run(*args)


class _GatedClient:
    """Submits every chunk after the first behind the gate."""

    def __init__(self, client):
        self.client = client
        self.count = 0

    def submit(self, run, *args, **kwargs):
        self.count += 1
        if self.count > 1:
            return self.client.submit(_gated, run, *args, **kwargs)
        return self.client.submit(run, *args, **kwargs)

    def scheduler_info(self, **kwargs):
        return self.client.scheduler_info(**kwargs)


def test_cluster_without_workers_raises_after_a_bounded_wait(monkeypatch):
    distributed = dask_distributed()
    monkeypatch.setattr(dask_chunks, "LOST_CLUSTER_WAIT", 1.0)
    monkeypatch.setattr(dask_chunks, "POLL_INTERVAL", 0.1)
    kw = dict(CURVE_BATCH_KW, engine="numpy")  # two chunks of 4 and 2 runs
    local = fws.simulate_batch(PLANT, Arc(0.1), CURVE_GAINS_WITH_STOP, **kw)
    box = {}
    _GATE.clear()
    with (
        distributed.LocalCluster(
            processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):

        class KillingBar:
            # simulate_batch calls update() once a chunk is kept: after the
            # first, every worker goes (closed, nothing restarts it)
            def update(self, n=1):
                cluster.scale(0)
                deadline = time.monotonic() + 30.0
                while client.scheduler_info()["workers"]:
                    assert time.monotonic() < deadline, "the worker did not close"
                    time.sleep(0.05)

            def close(self):
                pass

        monkeypatch.setattr(runners, "_NoBar", KillingBar)

        def call():
            try:
                with pytest.raises(
                    fws.ClusterLostError, match="no worker for 1 s: .*; 2 pending runs"
                ) as info:
                    fws.simulate_batch(
                        PLANT, Arc(0.1), CURVE_GAINS_WITH_STOP,
                        client=_GatedClient(client), **kw,
                    )  # fmt: skip
                box["res"] = info.value.result
            except BaseException as exc:  # reported by the main thread
                box["error"] = exc

        worker = threading.Thread(target=call, daemon=True)
        start = time.monotonic()
        worker.start()
        worker.join(timeout=60.0)
        waited = time.monotonic() - start
        _GATE.set()
        assert not worker.is_alive(), "simulate_batch still waits after 60 s"
    if "error" in box:
        raise box["error"]
    res = box["res"]
    assert waited < 60.0
    # the chunk that finished is kept, bitwise that of the local run
    np.testing.assert_array_equal(res.signals[:4], local.signals[:4])
    assert res.status.tolist()[:4] == local.status.tolist()[:4]
    # the chunk left without a worker: failed, NaN, and the message says why
    assert res.status.tolist()[4:] == ["failed", "failed"]
    assert np.all(np.isnan(res.signals[4:]))
    assert all("no worker" in m for m in res.message[4:])
