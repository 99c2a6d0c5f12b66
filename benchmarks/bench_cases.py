"""CPU per run of each closed-loop case, as a ratio to the paper's law.

On the ISO 3888-1 double lane change (:func:`fws_control.double_lane_change`,
vehicle width 1.8 m) at 20 m/s, from 0.5 m beside the path, over the
course, output step 0.01 s, all signals and exact peaks,
:func:`fws_control.simulate_batch` with its default engine (``"auto"``) and
method, rtol 1e-10, atol 1e-12:

1. the paper's law (double root -2, ratios spread over [-0.5, 0.5]) on the
   kinematic model;
2. the same with the input delay 0.24 s;
3. the same with the delay and the steering lag 0.27 s;
4. the paper's law on the dynamic single-track model with the saturating
   ("magic") tyre;
5. Stanley (gain 2, ratios as 1.);
6. pure pursuit (look-ahead 0.6 s, at least 5 m);
7. Stanley as 5. with ``engine="numpy"``.
8. the braking lane change of ``docs/varying_speed.md`` (entered at 80
   km/h, braking at 4 m/s² from the entry gate down to 30 km/h; dynamic
   model, BMW 320i data, linear tyre; the double-root schedule with the
   zero-sideslip ratio a(V); lateral offsets spread over [-0.5, 0.5] m,
   12 s) on the compiled engine;
9. the same on the numpy engine (``--numpy-runs`` runs).

Each line gives the engine that ran the case, the CPU per run (best of
``--repeat`` >= 3 rounds, the cases timed in turn every round so that a
drift of the machine's speed does not enter the ratios) and the ratio to
case 1. Cases on the numpy engine cost seconds per run: they run
``--numpy-runs`` runs (default 2), the baselines on the compiled engine
``--baseline-runs`` (default: as many as ``--runs``), the other compiled
ones ``--runs`` (default 100). The machine load is printed before and
after.

With ``--breakdown``, each compiled case is run once more with the
compiled engine's three stages timed (the integration, the signals, the
exact peaks; CPU per run) and the integration's statistics averaged over
the runs (accepted and rejected steps, right-hand-side evaluations): the
ratios split into the steps a case takes and the cost of each evaluation
of its law. Column ``< 1 ms`` counts the accepted steps shorter than
1 ms after each run's first step (from each run's kept dense output): an
indicator of the steps DOP853 takes where the right-hand side has a
corner in time, as where the course's curvature has a corner (the
junctions of its clothoids where the curvature's slope jumps); not every
such corner shortens a step below 1 ms (``bench_corners.py`` counts what
the corners cost). The breakdown's stages are the best of 3 rounds, each
round running every compiled case in turn.

Run: ``python benchmarks/bench_cases.py [--runs 100] [--numpy-runs 2]``
``[--only "braking lane change"] [--breakdown]`` (the cases whose name
starts so, and the paper's law)
(several minutes: the numpy cases dominate).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from timing import best_of_interleaved, machine_line

import fws_control as fws
from fws_control.paper.data import REALISTIC_DELAY, REALISTIC_STEERING_LAG

SPEED = 20.0
DYNAMIC = fws.Vehicle(
    wheelbase=2.7, rear_to_cg=1.2, mass=1500.0, yaw_inertia=2600.0,
    cornering_front=8.0e4, cornering_rear=9.5e4, friction=1.0,
)  # fmt: skip


def cases(n_compiled: int, n_numpy: int, n_baseline: int = 10, only: str = "") -> dict:
    """name -> (number of runs, function running the batch, its engine)."""
    course = fws.double_lane_change(vehicle_width=1.8)
    path = course.path
    duration = float(path.length) / SPEED
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)

    def laws(n, vehicle):
        return fws.double_root_gains(
            vehicle, speed=SPEED, curvature=0.0,
            ratio=np.linspace(-0.5, 0.5, n), pole=-2.0,
        )  # fmt: skip

    def batch(plant, ctrl, n, **kw):
        def run():
            return fws.simulate_batch(
                plant, path, ctrl, initial_state=(0.0, 0.5, 0.0),
                duration=duration, dt=0.01, progress=False, **kw,
            )  # fmt: skip

        return run

    kin = fws.LateralPlant(veh, speed=SPEED)
    lag = fws.LateralPlant(veh, speed=SPEED, steering_lag=REALISTIC_STEERING_LAG)
    dyn = fws.LateralPlant(DYNAMIC, speed=SPEED, model="dynamic", tyre="magic")
    ratios = np.linspace(-0.5, 0.5, n_baseline)
    table = {
        "paper law": (kin, laws(n_compiled, veh), {}),
        "+ delay 0.24 s": (kin, laws(n_compiled, veh), {"delay": REALISTIC_DELAY}),
        "+ lag 0.27 s": (lag, laws(n_compiled, veh), {"delay": REALISTIC_DELAY}),
        "dynamic, magic tyre": (dyn, laws(n_compiled, DYNAMIC), {}),
        "Stanley": (kin, fws.Stanley(gain=2.0, ratio=ratios), {}),
        "pure pursuit": (
            kin, fws.PurePursuit(lookahead=5.0, lookahead_time=0.6, ratio=ratios), {}
        ),
        "Stanley, numpy": (
            kin, fws.Stanley(gain=2.0, ratio=np.linspace(-0.5, 0.5, n_numpy)),
            {"engine": "numpy"},
        ),
    }  # fmt: skip
    runs = {
        name: batch(plant, ctrl, n_compiled, **kw)
        for name, (plant, ctrl, kw) in table.items()
    }
    runs["braking lane change"] = braking(course, n_compiled, "compiled")
    runs["braking lane change, numpy"] = braking(course, n_numpy, "numpy")
    out = {}
    for name, run in runs.items():
        # (the paper's law always: the ratios are to it)
        if not name.startswith(only) and name != "paper law":
            continue
        res = run()  # also the first (compiling) call
        out[name] = (res.signals.shape[0], run, res.engine)
    return out


def braking(course, n: int, engine: str):
    """The braking lane change of docs/varying_speed.md, `n` runs on `engine`."""
    veh = fws.vehicles.BMW_320I
    v_in = 80.0 / 3.6
    profile = fws.SpeedProfile.braking(
        v_in, 4.0, start=course.start_x / v_in, final=30.0 / 3.6
    )
    plant = fws.LateralPlant(veh, speed=v_in, model="dynamic")
    schedule = fws.GainSchedule.double_root(
        veh, speeds=np.linspace(1.0, 30.0, 59), pole=-1.5,
        ratio=fws.zero_sideslip_ratio,
    )  # fmt: skip
    x0 = np.zeros((n, 3))
    x0[:, 1] = np.linspace(-0.5, 0.5, n)

    def run():
        return fws.simulate_batch(
            plant, course.path, schedule, initial_state=x0, duration=12.0,
            dt=0.01, speed=profile, engine=engine, progress=False,
        )  # fmt: skip

    return run


def breakdown(table: dict) -> None:
    """Print each compiled case's stages and integration statistics."""
    import fws_control.simulation.compiled as compiled

    stages = ("integrate_compiled", "compiled_outputs", "compiled_peaks")
    spent: dict[str, float] = {}
    stats: list[np.ndarray] = []
    short: list[np.ndarray] = []
    originals = {name: getattr(compiled, name) for name in stages}

    def timed(name):
        def call(*args, **kwargs):
            t0 = time.process_time()
            out = originals[name](*args, **kwargs)
            spent[name] = spent.get(name, 0.0) + time.process_time() - t0
            if name == "integrate_compiled":
                stats.append(out[4])
                for sol in kwargs.get("solution") or ():
                    # accepted steps shorter than 1 ms per run, each run's
                    # first step (DOP853's initial step) left out
                    rec, off = sol.records, sol.offsets
                    mask = rec[:, 1] < 1e-3
                    mask[off[:-1][np.diff(off) > 0]] = False
                    counts = np.r_[0, np.cumsum(mask)][off]
                    short.append(np.diff(counts))
            return out

        return call

    print("compiled stages, CPU per run [ms]; integration statistics per run")
    print(f"  {'case':26s} {'integrate':>9s} {'signals':>8s} {'peaks':>6s}"
          f" {'steps':>6s} {'< 1 ms':>6s} {'rejected':>8s} {'rhs':>6s}"
          f" {'us/rhs':>7s}")  # fmt: skip
    try:
        # (the runners look the stages up in compiled at every call; a
        # sampled controller's segments, which compiled_sampled runs with
        # the names it imported, would not be seen: none is a case here)
        for name in stages:
            setattr(compiled, name, timed(name))
        compiled_cases = {k: v for k, v in table.items() if v[2] == "compiled"}
        best: dict[str, dict[str, float]] = {name: {} for name in compiled_cases}
        seen: dict[str, tuple[np.ndarray, float]] = {}
        for _ in range(3):  # best of 3 per stage, the cases in turn
            for name, (_, run, _) in compiled_cases.items():
                spent.clear()
                stats.clear()
                short.clear()
                run()
                for k, v in spent.items():
                    best[name][k] = min(best[name].get(k, np.inf), v)
                if stats:  # (else no stage of this case was seen)
                    seen[name] = (
                        np.concatenate(stats).mean(axis=0),
                        np.concatenate(short).mean() if short else np.nan,
                    )
        for name, (n, _, _) in compiled_cases.items():
            if name not in seen:
                continue
            st, n_short = seen[name]
            # "-": a stage this case computes otherwise (a varying speed's
            # signals and peaks are the numpy engine's functions)
            ms = [
                f"{1e3 * best[name][k] / n:.3f}" if k in best[name] else "-"
                for k in stages
            ]
            us_rhs = 1e6 * best[name]["integrate_compiled"] / n / st[2]
            print(f"  {name:26s} {ms[0]:>9s} {ms[1]:>8s} {ms[2]:>6s}"
                  f" {st[0]:6.0f} {n_short:6.0f} {st[1]:8.0f} {st[2]:6.0f}"
                  f" {us_rhs:7.3f}")  # fmt: skip
    finally:
        for name, fn in originals.items():
            setattr(compiled, name, fn)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--numpy-runs", type=int, default=2)
    ap.add_argument("--baseline-runs", type=int, default=None)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--only", default="", help="cases whose name starts so")
    ap.add_argument(
        "--breakdown", action="store_true", help="time the compiled stages too"
    )
    args = ap.parse_args()
    print(machine_line())
    n_baseline = args.runs if args.baseline_runs is None else args.baseline_runs
    table = cases(args.runs, args.numpy_runs, n_baseline, args.only)
    best = best_of_interleaved(
        {name: run for name, (_, run, _) in table.items()}, repeat=args.repeat
    )
    first = next(iter(table))
    base = best[first] / table[first][0]
    print(f"ISO 3888-1 at {SPEED:g} m/s; CPU per run, best of {args.repeat}")
    for name, (n, _, engine) in table.items():
        per_run = best[name] / n
        print(
            f"  {name:26s} {engine:9s} {n:4d} runs  {per_run * 1e3:10.2f} ms  "
            f"{per_run / base:8.1f}x"
        )
    if args.breakdown:
        breakdown(table)
    print(machine_line())


if __name__ == "__main__":
    main()
