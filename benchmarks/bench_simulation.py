"""Speed of the batch engine against python-control and a loop of simulate.

Simulates the paper's curved-road scenario (V = 5 m/s, curvature 1/10,
R(0) = (0, -5 m), feedforward + feedback, 15 s) for ``--runs`` double-root
designs (ratios spread over [-1.5, 0.6], pole -1, exact linearisation):

1. :func:`fws_control.simulate_batch` (one stacked integration),
2. a loop of :func:`fws_control.simulate` (the same engine, one run at a
   time),
3. a loop of :func:`control.input_output_response` on
   :func:`fws_control.closed_loop_system` (global-frame vehicle + projection
   + controller via ``ct.interconnect``), with the same solver and
   tolerances (DOP853, rtol 1e-10, atol 1e-12) so that the comparison is at
   equal accuracy. Building the interconnection is included, as in a user's
   loop.

Each time is the best of three runs in CPU seconds, the three timed in turn
round after round (``timing.best_of_interleaved``); the
python-control loop, about 2 s per run, is timed on the first ``--ct-runs``
designs (default 5) and extrapolated to ``--runs``. Prints the machine load,
the times, the speed-up ratios (target >= 50x against python-control) and
the largest difference in the lateral error e between the engines.

Run: ``python benchmarks/bench_simulation.py [--runs 120] [--ct-runs 5]``
"""

from __future__ import annotations

import argparse

import control as ct
import numpy as np
from timing import best_of_interleaved, machine_line

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE
from fws_control.paper.scenarios import paper_scenario

TOL = {"rtol": 1e-10, "atol": 1e-12}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=120, help="number of designs")
    parser.add_argument(
        "--ct-runs", type=int, default=5, help="python-control runs timed (5)"
    )
    args = parser.parse_args()
    if args.runs < 1 or not 1 <= args.ct_runs <= args.runs:
        parser.error("need --runs >= 1 and 1 <= --ct-runs <= --runs")
    print(machine_line())

    veh = PAPER_VEHICLE
    sc = paper_scenario("curve_5")
    path = sc.path
    ratios = np.linspace(-1.5, 0.6, args.runs)
    plant = fws.LateralPlant(veh, speed=sc.speed, curvature=sc.curvature)
    g = fws.double_root_gains(plant, ratio=ratios, pole=-1.0)
    t = np.linspace(0.0, sc.duration, 1501)
    x0 = list(sc.initial_state)
    print(
        f"scenario {sc.name}: V={sc.speed} m/s, curvature={sc.curvature} 1/m, "
        f"R(0)=({x0[0]}, {x0[1]}) m, {sc.duration} s, {args.runs} runs, "
        f"{t.size} output times"
    )

    kw = {"initial_state": x0}
    plant = fws.LateralPlant(veh, speed=sc.speed)
    fws.simulate_batch(plant, path, g, **kw, duration=1.0, progress=False)  # warm-up

    def run_batch():
        return fws.simulate_batch(
            plant, path, g, **kw, duration=sc.duration, t_eval=t, progress=False
        )

    def run_singles():
        return [
            fws.simulate(
                plant,
                path,
                fws.SteeringGains(g.k1[i], g.k2[i], g.ratio[i]),
                **kw,
                duration=sc.duration,
                t_eval=t,
            )
            for i in range(args.runs)
        ]

    def run_ct():
        refs = []
        for i in range(args.ct_runs):
            sys = fws.closed_loop_system(
                veh,
                path,
                fws.SteeringGains(g.k1[i], g.k2[i], g.ratio[i]),
                speed=sc.speed,
            )
            resp = ct.input_output_response(
                sys,
                t,
                initial_state=x0,
                solve_ivp_method="DOP853",
                solve_ivp_kwargs=TOL,
            )
            refs.append(resp.outputs[sys.find_output("e")])
        return refs

    # in turn, round after round: the ratios do not take up the machine's drift
    best = best_of_interleaved(
        {"batch": run_batch, "singles": run_singles, "ct": run_ct}
    )
    t_batch, t_loop = best["batch"], best["singles"]
    t_ct = best["ct"] * args.runs / args.ct_runs
    batch = run_batch()
    if not np.all(batch.ok):
        raise SystemExit(f"unexpected stopped runs: {set(batch.status)}")
    singles = run_singles()
    refs = run_ct()

    e_loop = np.array([r.e for r in singles])
    e_ct = np.array(refs)
    d_loop = np.max(np.abs(batch.e - e_loop))
    d_ct = np.max(np.abs(batch.e[: args.ct_runs] - e_ct))
    print(f"  simulate_batch                   : {t_batch:8.3f} s CPU")
    print(f"  loop of simulate                 : {t_loop:8.3f} s CPU")
    print(
        f"  loop of ct.input_output_response : {t_ct:8.3f} s CPU (extrapolated from "
        f"{args.ct_runs} runs)"
    )
    print(
        f"simulate_batch vs python-control loop: {t_ct / t_batch:7.1f}x faster "
        f"(target >= 50x), max |e_batch - e_ct| = {d_ct:.2e} m"
    )
    print(
        f"simulate_batch vs simulate loop      : {t_loop / t_batch:7.1f}x faster, "
        f"max |e_batch - e_simulate| = {d_loop:.2e} m"
    )
    print(machine_line())


if __name__ == "__main__":
    main()
