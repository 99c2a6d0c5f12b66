"""The compiled engine's per-run dense output and the exact peaks on it.

:class:`~fws_control.simulation.dense.CompiledDense` evaluates every run of
a compiled integration on that run's own steps. References:

(a) the integrator's own output samples (the kernels evaluate the same
    DOP853 interpolant, so the values agree to rounding);
(b) each run's ``t_stop`` from the integrator, which its last step must
    reach;
(c) a brute-force maximum: ``|signal|`` sampled on 20 001 points of each
    run's solution with :func:`compute_outputs` (the numpy engine's
    formulas), which the exact peaks may exceed only by what the samples
    miss between them, and never fall short of.
"""

from __future__ import annotations

import numpy as np
import pytest

import fws_control as fws
from fws_control.simulation import compiled
from fws_control.simulation.dense import CompiledDense
from fws_control.simulation.outcomes import PEAK_SIGNALS, SIGNALS
from fws_control.simulation.signals import compute_outputs

pytestmark = pytest.mark.skipif(
    not compiled.available(), reason="numba is not installed: no compiled engine"
)

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


def _integration(n=5, duration=6.0):
    # runs that start at different offsets take different step counts; the
    # last starts so far off on a tight arc that it stops early (1 - kappa e)
    e0 = np.linspace(-2.0, 2.0, n)
    e0[-1] = 9.9
    path_state = np.column_stack([np.zeros(n), e0, np.zeros(n)])
    t = np.linspace(0.0, duration, 61)
    sol = []
    states, status, _, t_stop, _ = compiled.integrate_compiled(
        VEH, fws.Arc(0.1), fws.SteeringGains(0.3, 1.2, -0.4),
        speed=np.full(n, 5.0), feedforward=True, path_state=path_state,
        t_eval=t, time_constant=None, solution=sol,
    )  # fmt: skip
    return states, status, t_stop, t, sol[0]


def test_states_are_the_integrators_samples_on_each_runs_steps():
    states, status, t_stop, t, sol = _integration()
    counts = np.diff(sol.offsets)
    assert len(set(counts.tolist())) > 1  # the runs took steps of their own
    dense = CompiledDense(sol.records, sol.offsets, sol.initial_state, 0.0)
    n = t_stop.size
    runs = np.repeat(np.arange(n), t.size)
    got = dense.states(runs, np.tile(t, n)).reshape(3, n, t.size)
    live = np.isfinite(states)
    assert np.array_equal(np.isfinite(got), np.ones_like(live))
    np.testing.assert_allclose(got[live], states[live], rtol=0, atol=1e-13)
    # each run's steps reach its stop; the bounds start at t0, ascend, pad NaN
    bounds = dense.step_bounds()
    for i in range(n):
        row = bounds[i][np.isfinite(bounds[i])]
        assert row[0] == 0.0 and np.all(np.diff(row) > 0.0)
        assert row[-1] == pytest.approx(t_stop[i], rel=0, abs=1e-12)
        assert np.all(np.isnan(bounds[i][row.size :]))
    assert status[-1] != "ok" and t_stop[-1] < t[-1]


def test_split_partitions_the_runs_within_the_step_budget():
    _, _, _, t, sol = _integration(n=7)
    dense = CompiledDense(sol.records, sol.offsets, sol.initial_state, 0.0)
    counts = np.diff(sol.offsets)
    budget = int(counts.max()) + 1  # at least one run each, rarely two
    blocks = dense.split(budget)
    assert [lo for lo, _, _ in blocks] == [0, *[hi for _, hi, _ in blocks[:-1]]]
    assert blocks[-1][1] == counts.size
    probe = np.linspace(0.0, t[-1], 17)
    for lo, hi, part in blocks:
        assert hi - lo == 1 or counts[lo:hi].sum() <= budget
        for j in range(hi - lo):
            run = np.full(probe.size, j)
            assert np.array_equal(
                part.states(run, probe), dense.states(run + lo, probe)
            )


RATIOS = np.linspace(-0.4, 0.4, 4)


@pytest.mark.parametrize(
    "controller",
    [fws.Stanley(gain=2.0, ratio=RATIOS),
     fws.PurePursuit(lookahead=4.0, lookahead_time=0.4, ratio=RATIOS)],
    ids=["stanley", "pure_pursuit"],
)  # fmt: skip
def test_batch_peaks_bound_a_brute_force_maximum(controller):
    plant = fws.LateralPlant(VEH, speed=12.0)
    path = fws.double_lane_change(vehicle_width=1.8).path
    res = fws.simulate_batch(
        plant, path, controller, initial_state=(0.0, 0.4, 0.05), duration=3.0,
        dt=0.1, engine="compiled", progress=False,
    )  # fmt: skip
    assert res.engine == "compiled"
    # the brute force on the runs' own integration (bitwise the batch's)
    n = 4
    sol = []
    path_state = np.stack([res.s, res.e, res.theta])  # (3, n, T)
    z0 = path_state[:, :, 0].T  # (n, 3): the projected start
    t = res.t
    states, _, _, t_stop, _ = compiled.integrate_compiled(
        VEH, path, controller, speed=np.full(n, 12.0), feedforward=True,
        path_state=z0, t_eval=t, time_constant=None, solution=sol,
    )  # fmt: skip
    np.testing.assert_array_equal(states, path_state)
    dense = CompiledDense(sol[0].records, sol[0].offsets, sol[0].initial_state, 0.0)
    fine = np.linspace(0.0, float(t_stop.min()), 20_001)
    st = dense.states(np.repeat(np.arange(n), fine.size), np.tile(fine, n))
    sig = compute_outputs(
        VEH, path, controller, speed=np.full(n, 12.0),
        states=st.reshape(3, n, fine.size), initial_heading=np.zeros(n),
        feedforward=True, time_constant=None, times=np.tile(fine, (n, 1)),
    )  # fmt: skip
    rows = [SIGNALS.index(name) for name in PEAK_SIGNALS]
    brute = np.max(np.abs(sig[:, rows, :]), axis=2)
    peaks = res.run_peak
    # never below a sample of the continuous solution ...
    assert np.all(peaks >= brute - 1e-12 * (1.0 + brute))
    # ... and above it only by what 1.5e-4 s between samples can hide
    assert np.all(peaks <= brute * (1.0 + 1e-4) + 1e-9), peaks - brute
    # (the output samples, 0.1 s apart, miss some peaks by more than that)
    samples = np.max(np.abs(res.signals[:, rows, :]), axis=2)
    assert np.any(samples < brute * (1.0 - 1e-3))
