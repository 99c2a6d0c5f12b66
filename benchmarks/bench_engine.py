"""Cost per run of simulate_batch's default engine against the references.

The paper's curve scenario (``curve_5``: V = 5 m/s, curvature 1/10,
R(0) = (0, -5 m), feedforward + feedback, 15 s, output step 0.01 s; double
root -1, ratios spread over [-1.5, 0.6] as in ``bench_simulation.py``),
DOP853 with rtol 1e-10, atol 1e-12 everywhere:

1. :func:`fws_control.simulate_batch` with its default engine (``"auto"``:
   the compiled per-run engine when numba is installed), all 15 signals and
   the exact peaks -- the issue's subject; one more run's CPU split into
   user and system time (the system share is chiefly the kernel providing
   the fresh memory of the result, at its first touch); and the same batch
   into one result array reused from call to call (``out=``);
2. the compiled per-run reference producing the same signals:
   :func:`fws_control.simulation.compiled.integrate_compiled` followed by
   :func:`~fws_control.simulation.compiled.compiled_outputs`, into
   preallocated reused arrays (the strict reference) and into fresh arrays
   (what a caller that returns the signals pays: the first touch of the
   output's pages); also followed by the numpy
   :func:`~fws_control.simulation.signals.compute_outputs`;
3. a loop of plain :func:`scipy.integrate.solve_ivp` with a scalar
   right-hand side written here from the formulas (on ``--loop-runs`` runs):
   the states only; and with the same 15 signals (the library's numpy
   ``compute_outputs`` per run), kept as a user collects them (fresh memory
   for every run, as the batch's fresh result) and dropped after each run
   (memory reused, as the batch into a reused ``out``);
4. the right-hand-side floor: the engine's own number of right-hand-side
   evaluations times the cost of one compiled evaluation in a tight loop
   (what any integrator needs for these steps, with no bookkeeping);
5. ``simulate_batch(engine="numpy")`` on ``--numpy-runs`` runs (context);
6. one run: the compiled engine, and :func:`fws_control.simulate` with its
   default engine (validation, projection, all signals, exact peaks; the
   target is <= 0.5 ms of CPU) and with ``engine="numpy"``.

Compile latency is measured in fresh processes: the first default
``simulate`` with an empty numba cache (compilation) and with the cache
filled (what every later process pays). Every time is the best of
``--repeat`` (>= 3) runs of the process's CPU time (the issue asks for CPU
per run; on a shared machine the wall clock also counts the waits for a
core); the machine load is printed before and after. The batch and the two
loops are timed in turn, round after round, so that their ratios do not
take up the drift of a virtual machine's speed over minutes. Accuracy: the largest
state difference to the ``solve_ivp`` loop and to a 100x tighter
``solve_ivp`` reference on the loop's runs, and the largest difference of
the default batch's peaks to the numpy engine's.

Run: ``python benchmarks/bench_engine.py [--runs 10000] [--loop-runs 100]``
(about two minutes at 10^4 runs).
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp
from timing import best_of_interleaved, machine_line

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE
from fws_control.paper.scenarios import paper_scenario
from fws_control.simulation.engine import SIGNALS, compute_outputs

try:
    import numba

    from fws_control.simulation.compiled import (
        closed_loop_rhs,
        compiled_outputs,
        curvature_table,
        integrate_compiled,
        shared_parameters,
    )
except ImportError as exc:  # pragma: no cover
    raise SystemExit(
        "this benchmark needs numba: pip install fws-control[fast]"
    ) from exc

TOL = {"rtol": 1e-10, "atol": 1e-12}


def best_of(fn, repeat: int = 3, number: int = 1) -> float:
    """Best CPU time per call of ``fn`` [s] over `repeat` runs of `number` calls.

    As ``timing.best_of``, but with the process's CPU clock: on a machine
    shared with other jobs the wall clock also counts the time this process
    waits for a core, and the issue asks for CPU per run.
    """
    if repeat < 3 or number < 1:
        raise ValueError(f"repeat must be >= 3 and number >= 1, got {repeat}, {number}")
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        for _ in range(number):
            fn()
        best = min(best, (time.process_time() - t0) / number)
    return best


_FIRST_CALL = """
import time, numpy as np
t0 = time.process_time()
import fws_control as fws
t1 = time.process_time()
veh, path = fws.Vehicle(2.7, 1.35), fws.Arc(0.1)
g = fws.SteeringGains(0.2, 0.9, -1.0)
plant = fws.LateralPlant(veh, speed=5.0)
res = fws.simulate(plant, path, g, initial_state=(0.0, -5.0, 0.0),
                   duration=15.0)
t2 = time.process_time()
assert res.engine == "compiled", res.engine
fws.simulate(plant, path, g, initial_state=(0.0, -5.0, 0.0),
             duration=15.0)
t3 = time.process_time()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def first_call(cache_dir: str) -> tuple[float, float, float]:
    """CPU s of (import, first simulate, second simulate) in a new process."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    out = subprocess.run(
        [sys.executable, "-c", _FIRST_CALL],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return tuple(float(v) for v in out.stdout.split())


_FIRST_TOUCH = """
import sys, time, numpy as np
from numpy._core.multiarray import _set_madvise_hugepage
_set_madvise_hugepage(sys.argv[1] == "1")  # numpy's advice for large arrays
best = float("inf")
for _ in range(3):
    t0 = time.process_time()
    a = np.empty(int(sys.argv[2]) // 8)
    a.fill(1.0)
    best = min(best, time.process_time() - t0)
    del a
    time.sleep(2.0)  # (freed memory goes back as it would between batches)
print(best)
"""


def _anon_huge_pages() -> str:
    """The kernel's count of transparent huge pages in use (Linux), or '?'."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("AnonHugePages:"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "?"


def first_touch(nbytes: int, hugepage: bool) -> float:
    """CPU s to allocate and first write `nbytes` (best of 3, new process).

    With and without numpy's ``MADV_HUGEPAGE`` advice for large arrays (a
    private numpy switch, used here only to measure): the batch's result is
    such a fresh array. On the project's virtual machine the kernel grants
    the huge pages (``thp_fault_alloc`` in ``/proc/vmstat``, no fallback)
    and still the advice makes the first touch dearer and far more variable.
    """
    out = subprocess.run(
        [sys.executable, "-c", _FIRST_TOUCH, "1" if hugepage else "0", str(nbytes)],
        capture_output=True,
        text=True,
        check=True,
    )
    return float(out.stdout)


def scalar_rhs(k1, k2, a, V, f, kappa):
    """The closed loop of one run, from the formulas (math only)."""

    def rhs(t, y):
        s, e, th = y
        fb = -k1 * e - k2 * th
        cf = fb + math.atan(kappa * f)
        cr = a * fb
        s_dot = V * math.cos(th + cr) / (1 - kappa * e)
        return [
            s_dot,
            V * math.sin(th + cr),
            -kappa * s_dot + V * math.sin(cf - cr) / (f * math.cos(cf)),
        ]

    return rhs


# Not cached: numba would reuse the cached loop after a change of the
# library's kernels (it checks this file only), and the right-hand side,
# inlined into the loop, takes the loop's error model: the engine's own.
@numba.njit(error_model="numpy")
def _rhs_loop(n, y0, p, q, breaks, coefs):
    # n evaluations on states that change (so nothing is hoisted)
    out = np.empty(3)
    y = y0.copy()
    acc = 0.0
    for i in range(n):
        y[1] = y0[1] + 1e-9 * i
        closed_loop_rhs(0.0, y, p, q, breaks, coefs, out)
        acc += out[2]
    return acc


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10_000)
    parser.add_argument("--loop-runs", type=int, default=100)
    parser.add_argument("--numpy-runs", type=int, default=500)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument(
        "--skip-compile", action="store_true", help="skip the compile latency"
    )
    args = parser.parse_args()
    if args.repeat < 3:
        parser.error("--repeat must be >= 3 (best of at least three)")
    print(machine_line())
    print(f"numba {numba.__version__}, numpy {np.__version__}")

    if not args.skip_compile:
        with tempfile.TemporaryDirectory() as tmp:
            imp, cold, second = first_call(tmp)
            _, warm, _ = first_call(tmp)
        print(
            f"first fws.simulate (CPU s, fresh process): {cold:.2f} with an empty "
            f"numba cache (compilation), {warm:.3f} from the cache, {second:.4f} "
            f"the second call; import fws_control {imp:.3f}"
        )

    veh = PAPER_VEHICLE
    sc = paper_scenario("curve_5")
    n = args.runs
    ratios = np.linspace(-1.5, 0.6, n)
    g = fws.double_root_gains(veh, speed=sc.speed, curvature=sc.curvature,
                              ratio=ratios, pole=-1.0)  # fmt: skip
    t = np.linspace(0.0, sc.duration, 1501)
    x0 = np.array(sc.initial_state, dtype=float)
    z0 = np.tile([0.0, x0[1], 0.0], (n, 1))  # (0, -5, 0) projects to s=0, e=-5
    V = np.full(n, sc.speed)
    table = curvature_table(sc.path)
    kw = dict(speed=V, feedforward=True, path_state=z0, t_eval=t, time_constant=None)
    print(
        f"scenario {sc.name}: V={sc.speed} m/s, curvature={sc.curvature} 1/m, "
        f"{sc.duration} s, {n} runs, {t.size} output times"
    )

    # 2. the compiled per-run reference: integration + compiled outputs
    buf = np.empty((n, 3, t.size))
    sig = np.empty((n, len(SIGNALS), t.size))
    res = {}

    def compiled():
        res["c"] = integrate_compiled(veh, table, g, out=buf, **kw, **TOL)

    t_comp = best_of(compiled, repeat=args.repeat) / n
    states, status, _, _, stats = res["c"]
    assert np.all(status == "ok"), set(status)

    def with_compiled_outputs():
        compiled_outputs(veh, sc.path, g, speed=V, feedforward=True,
                         time_constant=None, states=states,
                         initial_heading=np.zeros(n), table=table,
                         out=sig)  # fmt: skip

    t_cout = best_of(with_compiled_outputs, repeat=args.repeat) / n
    t_ref = t_comp + t_cout

    def reference_fresh():
        st = integrate_compiled(veh, table, g, **kw, **TOL)[0]
        compiled_outputs(veh, sc.path, g, speed=V, feedforward=True,
                         time_constant=None, states=st,
                         initial_heading=np.zeros(n), table=table)  # fmt: skip

    t_ref_fresh = best_of(reference_fresh, repeat=args.repeat) / n

    def with_outputs():
        compute_outputs(veh, sc.path, g, speed=V, feedforward=True,
                        time_constant=None, states=states,
                        initial_heading=np.zeros(n))  # fmt: skip

    t_out = best_of(with_outputs, repeat=args.repeat) / n

    # 4. right-hand-side floor
    p = np.array([sc.speed, g.k1[0], g.k2[0], g.ratio[0]])
    q = shared_parameters(veh, table, feedforward=True, time_constant=None)
    m_eval = 1_000_000
    _rhs_loop(10, z0[0], p, q, table.breaks, table.coefs)
    t_rhs = (
        best_of(
            lambda: _rhs_loop(m_eval, z0[0], p, q, table.breaks, table.coefs),
            repeat=args.repeat,
        )
        / m_eval
    )
    nfev = float(np.mean(stats[:, 2]))
    t_floor = nfev * t_rhs

    # 1. simulate_batch, default engine (all signals, exact peaks)
    plant = fws.LateralPlant(veh, speed=sc.speed)
    batch_kw = dict(initial_state=x0, duration=sc.duration,
                    t_eval=t, progress=False)  # fmt: skip
    g4 = fws.SteeringGains(g.k1[:4], g.k2[:4], g.ratio[:4])  # warm-up
    fws.simulate_batch(plant, sc.path, g4, **{**batch_kw, "t_eval": t[:101]})
    out_b = {}

    def batch():
        out_b["r"] = fws.simulate_batch(plant, sc.path, g, **batch_kw)

    reused = np.empty((n, len(SIGNALS), t.size))

    def batch_out():
        fws.simulate_batch(plant, sc.path, g, **batch_kw, out=reused)

    # 3. loop of solve_ivp with a scalar right-hand side
    idx = np.linspace(0, n - 1, min(args.loop_runs, n)).astype(int)
    refs = {}

    def loop():
        for i in idx:
            rhs = scalar_rhs(g.k1[i], g.k2[i], g.ratio[i], sc.speed,
                             veh.wheelbase, sc.curvature)  # fmt: skip
            refs[i] = solve_ivp(rhs, (0.0, sc.duration), z0[i], method="DOP853",
                                t_eval=t, **TOL).y  # fmt: skip

    def loop_signals(keep):
        # the same loop producing the same 15 signals: each run's states
        # through the library's numpy compute_outputs (no peaks); kept (each
        # run's signals in fresh memory) or dropped (malloc reuses it)
        kept = []
        for i in idx:
            rhs = scalar_rhs(g.k1[i], g.k2[i], g.ratio[i], sc.speed,
                             veh.wheelbase, sc.curvature)  # fmt: skip
            y = solve_ivp(rhs, (0.0, sc.duration), z0[i], method="DOP853",
                          t_eval=t, **TOL).y  # fmt: skip
            gi = fws.SteeringGains(g.k1[i : i + 1], g.k2[i : i + 1],
                                   g.ratio[i : i + 1])  # fmt: skip
            sig_i = compute_outputs(veh, sc.path, gi, speed=V[:1], feedforward=True,
                                    time_constant=None, states=y[:, None, :],
                                    initial_heading=np.zeros(1))  # fmt: skip
            if keep:
                kept.append(sig_i)
        return kept

    # the batches and the loops in turn (timing.best_of_interleaved): their
    # ratios are the target, and this machine's speed drifts
    best = best_of_interleaved(
        {
            "batch": batch,
            "batch_out": batch_out,
            "loop": loop,
            "loop_signals": lambda: loop_signals(True),
            "loop_signals_dropped": lambda: loop_signals(False),
        },
        repeat=args.repeat,
    )
    t_batch = best["batch"] / n
    t_batch_out = best["batch_out"] / n
    rb = out_b.pop("r")
    # one more batch with its CPU split: user (the engine) and system (the
    # kernel, chiefly zeroing the fresh result's pages at their first touch);
    # the previous result is kept alive meanwhile, so that its freeing (also
    # system time: 121 ms for 1.8 GB of 4 kB pages) is not in the split
    ru0 = resource.getrusage(resource.RUSAGE_SELF)
    extra = fws.simulate_batch(plant, sc.path, g, **batch_kw)
    ru1 = resource.getrusage(resource.RUSAGE_SELF)
    del extra
    split = ((ru1.ru_utime - ru0.ru_utime) / n, (ru1.ru_stime - ru0.ru_stime) / n,
             ru1.ru_minflt - ru0.ru_minflt)  # fmt: skip
    t_loop = best["loop"] / idx.size
    t_loop_sig = best["loop_signals"] / idx.size
    t_loop_drop = best["loop_signals_dropped"] / idx.size
    engine_used = rb.engine
    assert rb.peaks.exact
    d_batch_states = float(np.max(np.abs(rb.e - states[1])))

    # 5. the numpy engine on fewer runs (context), and its peaks
    nn = min(args.numpy_runs, n)
    sel = np.linspace(0, n - 1, nn).astype(int)
    gn = fws.SteeringGains(g.k1[sel], g.k2[sel], g.ratio[sel])
    out_n = {}

    def numpy_batch():
        out_n["r"] = fws.simulate_batch(plant, sc.path, gn, **batch_kw, engine="numpy")

    t_numpy = best_of(numpy_batch, repeat=args.repeat) / nn
    d_peaks = float(np.max(np.abs(rb.run_peak[sel] - out_n["r"].run_peak)
                           / np.abs(out_n["r"].run_peak)))  # fmt: skip

    d_loop = max(float(np.max(np.abs(states[:, i, :] - refs[i]))) for i in idx)
    d_tight = 0.0
    for i in idx[:10]:
        rhs = scalar_rhs(g.k1[i], g.k2[i], g.ratio[i], sc.speed, veh.wheelbase,
                         sc.curvature)  # fmt: skip
        tight = solve_ivp(rhs, (0.0, sc.duration), z0[i], method="DOP853",
                          t_eval=t, rtol=1e-12, atol=1e-14).y  # fmt: skip
        d_tight = max(d_tight, float(np.max(np.abs(states[:, i, :] - tight))))

    # 6. one run
    one = dict(speed=V[:1], feedforward=True, path_state=z0[:1], t_eval=t,
               time_constant=None)  # fmt: skip
    g1 = fws.SteeringGains(g.k1[:1], g.k2[:1], g.ratio[:1])
    t_one = best_of(lambda: integrate_compiled(veh, table, g1, **one, **TOL),
                    repeat=max(args.repeat, 5), number=20)  # fmt: skip

    def one_full():
        st1 = integrate_compiled(veh, table, g1, **one, **TOL)[0]
        compiled_outputs(veh, sc.path, g1, speed=V[:1], feedforward=True,
                         time_constant=None, states=st1, table=table,
                         initial_heading=np.zeros(1))  # fmt: skip

    t_one_full = best_of(one_full, repeat=max(args.repeat, 5), number=20)
    sg = fws.SteeringGains(float(g.k1[0]), float(g.k2[0]), float(g.ratio[0]))
    sim_kw = dict(initial_state=x0, duration=sc.duration)
    one_default = fws.simulate(plant, sc.path, sg, **sim_kw)  # warm-up
    t_sim = best_of(lambda: fws.simulate(plant, sc.path, sg, **sim_kw),
                    repeat=max(args.repeat, 5), number=20)  # fmt: skip
    one_numpy = fws.simulate(plant, sc.path, sg, **sim_kw, engine="numpy")
    d_sim = float(np.nanmax(np.abs(one_default.signals - one_numpy.signals)))
    t_sim_n = best_of(lambda: fws.simulate(plant, sc.path, sg, **sim_kw,
                                           engine="numpy"),
                      repeat=args.repeat, number=3)  # fmt: skip

    # 7. stops: half the runs diverge (k2 < 0) and stop near |delta_f| = pi/2;
    # per-run integration: the batch costs what its two halves cost apart
    nb = min(n, 1000)
    even = np.arange(nb) % 2 == 0  # front steering only, k2 < 0: diverge
    k2s = np.where(even, -2.0, g.k2[:nb])
    a_s = np.where(even, 0.0, g.ratio[:nb])
    gs = fws.SteeringGains(g.k1[:nb], k2s, a_s)
    kws = dict(speed=V[:nb], feedforward=True, path_state=z0[:nb], t_eval=t,
               time_constant=None)  # fmt: skip
    halves = [np.arange(0, nb, 2), np.arange(1, nb, 2)]
    parts = [
        (fws.SteeringGains(g.k1[h], k2s[h], a_s[h]),
         dict(kws, speed=V[h], path_state=z0[h]))
        for h in halves
    ]  # fmt: skip
    res_s = {}

    def with_stops():
        res_s["s"] = integrate_compiled(veh, table, gs, **kws, **TOL)

    t_stops = best_of(with_stops, repeat=args.repeat)
    t_parts = sum(
        best_of(lambda gp=gp, kp=kp: integrate_compiled(veh, table, gp, **kp, **TOL),
                repeat=args.repeat)
        for gp, kp in parts
    )  # fmt: skip
    n_stop = int(np.sum(res_s["s"][1] != "ok"))

    us = 1e6
    print(f"\nCPU per run (best of {args.repeat}), {n} runs:")
    print(f"  simulate_batch, default engine ({engine_used}), 15 signals + "
          f"exact peaks {t_batch * us:9.1f} us")  # fmt: skip
    print(f"    one more run, split: user {split[0] * us:.1f} us + system "
          f"{split[1] * us:.1f} us ({split[2]} page faults: the kernel's first "
          f"touch of the fresh {n * len(SIGNALS) * t.size * 8 / 1e9:.2f} GB "
          "result)")  # fmt: skip
    print(f"  simulate_batch into a reused out=   {t_batch_out * us:9.1f} us "
          "(the same, no fresh memory)")  # fmt: skip
    print("  reference: integrate_compiled + compiled_outputs (15 signals)")
    print(f"    into reused arrays              {t_ref * us:9.1f} us "
          f"(states {t_comp * us:.1f} + outputs {t_cout * us:.1f})")  # fmt: skip
    print(f"    into fresh arrays               {t_ref_fresh * us:9.1f} us")
    print(f"  compiled + numpy compute_outputs  {(t_comp + t_out) * us:9.1f} us")
    print(f"  right-hand-side floor             {t_floor * us:9.1f} us "
          f"({nfev:.0f} evaluations x {t_rhs * 1e9:.0f} ns)")  # fmt: skip
    print(f"  simulate_batch(engine='numpy')    {t_numpy * us:9.1f} us "
          f"({nn} runs)")  # fmt: skip
    print(f"  solve_ivp loop, scalar RHS        {t_loop * us:9.1f} us "
          f"({idx.size} runs, states only)")  # fmt: skip
    print(f"  solve_ivp loop + compute_outputs  {t_loop_sig * us:9.1f} us "
          f"({idx.size} runs, the same 15 signals kept, no peaks)")  # fmt: skip
    print(f"    each run's signals dropped      {t_loop_drop * us:9.1f} us "
          "(memory reused)")  # fmt: skip
    nbytes = n * len(SIGNALS) * t.size * 8
    touch = {hp: first_touch(nbytes, hp) for hp in (True, False)}
    print(f"  first touch of a fresh result of that size ({nbytes / 1e9:.2f} GB, "
          f"new process): {touch[True] / n * us:.1f} us with numpy's huge-page "
          f"advice, {touch[False] / n * us:.1f} us without "
          f"(AnonHugePages {_anon_huge_pages()})")  # fmt: skip
    print("ratios:")
    print(f"  simulate_batch / reference (reused arrays) {t_batch / t_ref:6.2f}  "
          "(target <= 2)")  # fmt: skip
    print(f"  simulate_batch / reference (fresh arrays)  "
          f"{t_batch / t_ref_fresh:6.2f}")  # fmt: skip
    print(f"  solve_ivp loop / simulate_batch            {t_loop / t_batch:6.1f}  "
          "(the loop gives states only)")  # fmt: skip
    print(f"  solve_ivp loop + outputs / simulate_batch  "
          f"{t_loop_sig / t_batch:6.1f}  (target >= 20 with the same signals; "
          "both in fresh memory)")  # fmt: skip
    print(f"    dropped / into a reused out=             "
          f"{t_loop_drop / t_batch_out:6.1f}  (both reusing memory)")  # fmt: skip
    print(f"  simulate_batch numpy / default engine      {t_numpy / t_batch:6.1f}")
    print(f"  integrate_compiled / RHS floor             {t_comp / t_floor:6.2f}")
    print(f"  accepted steps per run: mean {np.mean(stats[:, 0]):.0f}, "
          f"max {np.max(stats[:, 0])}")  # fmt: skip
    print(f"stops: {nb} runs, {n_stop} stop early: {t_stops / t_parts:.2f}x the "
          "stopping and the other runs integrated apart (target < 1.5)")  # fmt: skip
    print("single run (the paper's 15 s scenario):")
    print(f"  compiled engine, states           {t_one * 1e3:9.3f} ms")
    print(f"  compiled + compiled_outputs (15)  {t_one_full * 1e3:9.3f} ms")
    print(f"  fws.simulate, default engine ({one_default.engine}) "
          f"{t_sim * 1e3:7.3f} ms  (target <= 0.5 ms: {t_sim / 0.5e-3:.2f} x the "
          "target; checks, projection, 15 signals, exact peaks)")  # fmt: skip
    print(f"  fws.simulate(engine='numpy')      {t_sim_n * 1e3:9.3f} ms  "
          f"({t_sim_n / t_sim:.0f} x the default)")  # fmt: skip
    print("accuracy:")
    print(f"  max |state difference| vs solve_ivp loop (same tolerances)  "
          f"{d_loop:.2e}")  # fmt: skip
    print(f"  max |state difference| vs solve_ivp at rtol 1e-12, atol 1e-14  "
          f"{d_tight:.2e}")  # fmt: skip
    print(f"  max |e difference| default batch vs integrate_compiled      "
          f"{d_batch_states:.2e}")  # fmt: skip
    print(f"  max relative peak difference, default batch vs numpy engine "
          f"{d_peaks:.2e} ({nn} runs)")  # fmt: skip
    print(f"  max |signal difference| of simulate, default vs numpy       "
          f"{d_sim:.1e}")  # fmt: skip
    print(machine_line())


if __name__ == "__main__":
    main()
