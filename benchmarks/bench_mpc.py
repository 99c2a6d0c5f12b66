"""Cost of one step of :class:`fws_control.MPCController`, per sample.

The controller of the docs (``docs/mpc.md``): independent axles, sample time
0.04 s, horizon 50 (2 s), delay 0.24 s compensated (6 samples), rear angle
limit 2.8 deg and rate limits 0.6 / 0.2 rad/s, at 10 m/s. Each case replays
the measurements of one closed-loop run (``fws.simulate`` with the same
controller and the 0.24 s delay) through a fresh ``MPCRun`` and times every
``step`` (CPU time, one BLAS thread as in the tests); printed are the median
and the maximum microseconds per step, each the best of 3 replays, with
OSQP's own median solve time, the machine load before and after.

* ``arc``: constant curvature 0.05 1/m from 1 m off the path; the
  discretised model is the same at every step (computed once);
* ``lane change``: the ISO 3888-1 double lane change, curvature varying
  along the horizon, so every step discretises 56 models (in closed form,
  elementwise on the stack).

Run: ``python benchmarks/bench_mpc.py``
"""

from __future__ import annotations

import math
import os

# one BLAS thread, as in the test suite (tests/conftest.py): scipy's expm of
# a stack of 4 x 4 matrices busy-waits in OpenBLAS threads otherwise
# (measured at load 10 on 2 cores: 1.3 s instead of 1 ms for 56 matrices)
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import time  # noqa: E402

import numpy as np  # noqa: E402
from timing import machine_line  # noqa: E402

import fws_control as fws  # noqa: E402

SPEED = 10.0
TS = 0.04
DELAY = 0.24
REPEAT = 3


def controller() -> fws.MPCController:
    return fws.MPCController(
        sample_time=TS,
        horizon=50,
        delay=DELAY,
        max_steer_rear=math.radians(2.8),
        max_rate_front=0.6,
        max_rate_rear=0.2,
    )


def cases():
    lane = fws.double_lane_change()
    return {
        "arc": (fws.Arc(curvature=0.05), (0.0, -1.0, 0.0), 10.0),
        "lane change": (lane.path, (lane.start_x, 0.3, 0.0), 8.0),
    }


def replay(mpc, veh, path, samples) -> tuple[np.ndarray, np.ndarray]:
    """CPU seconds of each step and OSQP's solve times, over one run."""
    run = mpc.start(veh, path, speed=SPEED)
    cost, solve = [], []
    for s, e, theta in samples:
        t0 = time.process_time()
        run.step(s=s, e=e, theta=theta)
        cost.append(time.process_time() - t0)
        solve.append(run.last.solve_time)
    return np.array(cost), np.array(solve)


def main() -> None:
    print(machine_line())
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=SPEED)
    mpc = controller()
    nd = mpc.delay_steps
    print(
        f"MPC: Ts = {TS:g} s, horizon {mpc.horizon}, delay {DELAY:g} s "
        f"({nd} samples), V = {SPEED:g} m/s"
    )
    for name, (path, x0, duration) in cases().items():
        k = round(duration / TS)
        t = TS * np.arange(k + 1)
        res = fws.simulate(
            plant,
            path,
            mpc,
            initial_state=x0,
            duration=float(t[-1]),
            t_eval=t,
            delay=DELAY,
        )
        first = (float(res.s[0]), float(res.e[0]), float(res.theta[0]))
        # the samples before the start measure the initial state
        samples = [first] * nd + list(
            zip(res.s.tolist(), res.e.tolist(), res.theta.tolist(), strict=True)
        )
        med, top, osqp_med = math.inf, math.inf, math.inf
        for _ in range(REPEAT):
            cost, solve = replay(mpc, veh, path, samples)
            # the first step builds the QP and OSQP's factorisation: not a
            # per-sample cost
            med = min(med, float(np.median(cost[1:])))
            top = min(top, float(np.max(cost[1:])))
            osqp_med = min(osqp_med, float(np.median(solve[1:])))
        print(
            f"{name:12s} status {res.status}: {len(samples) - 1} steps, median "
            f"{med * 1e6:.0f} us, max {top * 1e6:.0f} us per step (OSQP's solve "
            f"{osqp_med * 1e6:.0f} us median); first step {cost[0] * 1e3:.1f} ms"
        )
    print(machine_line())


if __name__ == "__main__":
    main()
