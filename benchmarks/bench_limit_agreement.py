"""Compiled and numpy engines on random rate-limited scenarios.

Draws ``--count`` (default 1000) scenarios with a fixed seed
(:func:`scenarios`): a vehicle with steering-angle and steering-rate limits
and no explicit actuator (so the simulators insert the default actuator,
``T = 0.05 s``), on a slalom (:func:`fws_control.slalom`), an open spline
through random waypoints, or an arc; random speed, design (double root,
ratio), limits and initial offset. Each is integrated (the states at
output times 0.05 s apart; ``integrate_compiled`` and ``engine.integrate``)
by

- the compiled DOP853 with its steps capped at ``3.2 T``: what
  :func:`fws_control.simulate` runs by default on such a vehicle;
- the compiled Radau;
- the numpy engine's DOP853 with its steps capped at ``3.2 T`` too
  (:class:`CappedDOP853`; the reference: its Radau and LSODA cost 10-60 s
  per slalom, whose curvature the numpy engine evaluates segment by
  segment),

at the default tolerances ``rtol = 1e-10``, ``atol = 1e-12``. Printed: per
variant the number of runs that end ``"failed"`` while another variant
finishes, and for every variant the largest and the 99 % quantile of the
difference in ``e`` [m] (over the output times both reach) to the numpy
engine's DOP853, with the number of runs beyond ``TOL``.

``TOL`` (1e-5 m) is the agreement asked of the two engines. Both locate
the switches of the clips as events and restart their methods there;
integrated across the clips' kinks instead (min/max in the right-hand side,
``engine.integrate(..., switching=False)``), DOP853's error estimate is not
that of a smooth solution, and the numpy engine was 3.5e-6 m off a tight
reference on scenario 690 (``--only 690`` prints it), 30 times its error
with the switches located. 1e-5 m is 1/50 of the 5e-4 m the compiled
engine was off when it integrated across a switch of the clips.

Run: ``python benchmarks/bench_limit_agreement.py [--count 1000] [--jobs 2]
[--only INDEX ...]`` (about 3 s of CPU per scenario, most of it the numpy
engine's; ``--jobs`` spreads the scenarios over worker processes, the
results are the same; ``--only`` runs the given scenarios of the drawn set
alone, and prints for each the difference of every variant, and of the
numpy engine's DOP853 with the clips as min/max (``numpy min/max``), to the
compiled Radau at ``rtol = 1e-12``, ``atol = 1e-14``, and their CPU time).
"""

from __future__ import annotations

import argparse
import math
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy.integrate import DOP853

import fws_control as fws
from fws_control.controllers import DEFAULT_ACTUATOR_TIME_CONSTANT
from fws_control.simulation.compiled import integrate_compiled
from fws_control.simulation.engine import SAFE_STEP, initial_path_state, integrate

RTOL, ATOL = 1e-10, 1e-12
#: Largest accepted difference in e [m] to the numpy engine.
TOL = 1e-5
#: The default actuator of a rate-limited vehicle [s].
TAU = DEFAULT_ACTUATOR_TIME_CONSTANT
VARIANTS = ("compiled DOP853", "compiled Radau", "numpy DOP853")
REFERENCE = "numpy DOP853"
KINDS = ("slalom", "spline", "arc")


class CappedDOP853(DOP853):
    """scipy's DOP853 with its steps held to ``SAFE_STEP * T``.

    As the compiled DOP853 runs here (and ``simulate`` on such a vehicle):
    beyond about ``6.4 T`` DOP853 is unstable on the actuator's mode, and
    where both clips hold their channels at the limits the error estimate
    does not see it (uncapped, the numpy engine's steps reached 0.83 s =
    17 T on scenario 163 and it ended 1.1e-5 m off).
    """

    def __init__(self, fun, t0, y0, t_bound, max_step=SAFE_STEP * TAU, **kw):
        super().__init__(fun, t0, y0, t_bound, max_step=max_step, **kw)


def scenarios(count: int, *, seed: int = 20261127) -> list[dict]:
    """``count`` random rate-limited scenarios (keyword sets of simulate).

    Ranges: speed 5-30 m/s, front angle limit 0.2-0.6 rad, rear 0.1-0.4
    rad, rate limits 0.2-2 rad/s (each channel), double root -0.5 to -3
    1/s, ratio -0.6 to 0.4, initial lateral offset -3 to 3 m and heading
    offset -0.3 to 0.3 rad; slaloms of pitch 14-24 m and amplitude 0.5-1.5
    m; splines through 5-8 waypoints 15-30 m apart with lateral steps of up
    to 8 m; arcs of curvature -0.2 to 0.2 1/m. Duration: to the end of the
    open path (at most 12 s), 6 s on an arc.
    """
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        kind = KINDS[i % len(KINDS)]
        shape = {}
        speed = float(rng.uniform(5.0, 30.0))
        veh = fws.Vehicle(
            2.7,
            1.35,
            max_steer_front=float(rng.uniform(0.2, 0.6)),
            max_steer_rear=float(rng.uniform(0.1, 0.4)),
            max_steer_rate_front=float(rng.uniform(0.2, 2.0)),
            max_steer_rate_rear=float(rng.uniform(0.2, 2.0)),
        )
        pole = float(rng.uniform(-3.0, -0.5))
        ratio = float(rng.uniform(-0.6, 0.4))
        e0 = float(rng.uniform(-3.0, 3.0))
        th0 = float(rng.uniform(-0.3, 0.3))
        if kind == "slalom":
            pitch = float(rng.uniform(14.0, 24.0))
            amp = float(rng.uniform(0.5, min(1.5, 0.24 * pitch)))
            path = fws.slalom(pitch=pitch, amplitude=amp, cones=6).path
            shape = dict(pitch=pitch, amplitude=amp)
            duration = min(12.0, 0.95 * path.length / speed)
        elif kind == "spline":
            n = int(rng.integers(5, 9))
            x = np.cumsum(rng.uniform(15.0, 30.0, n))
            y = np.cumsum(rng.uniform(-8.0, 8.0, n))
            path = fws.Spline(np.stack([x - x[0], y - y[0]], axis=1))
            duration = min(12.0, 0.95 * path.length / speed)
        else:
            kappa = float(rng.uniform(-0.2, 0.2))
            path = fws.Arc(kappa)
            duration = 6.0
        # the start pose: e0 to the left of the path 2 m after its start,
        # heading offset th0
        (px,), (py,) = path.position([2.0])
        (h,) = path.heading([2.0])
        x0 = (px - e0 * math.sin(h), py + e0 * math.cos(h), h + th0)
        gains = fws.double_root_gains(veh, ratio=ratio, pole=pole, speed=speed)
        out.append(
            dict(
                index=i,
                kind=kind,
                shape=shape,
                vehicle=veh,
                path=path,
                gains=gains,
                speed=speed,
                initial_state=x0,
                duration=duration,
            )
        )
    return out


def run(sc: dict, variant: str):
    """Integrate one scenario with one variant: ``(e, status, t_stop)``.

    ``compiled DOP853`` is what ``simulate`` runs by default on a
    rate-limited vehicle (DOP853, steps capped at ``SAFE_STEP * T``).
    """
    z0 = initial_path_state(sc["path"], np.array([sc["initial_state"]]))
    t = np.linspace(0.0, sc["duration"], int(round(sc["duration"] / 0.05)) + 1)
    kw = dict(
        speed=np.array([sc["speed"]]),
        feedforward=True,
        path_state=z0,
        t_eval=t,
        time_constant=TAU,
        rtol=RTOL,
        atol=ATOL,
    )
    args = (sc["vehicle"], sc["path"], sc["gains"])
    if variant == "compiled DOP853":
        r = integrate_compiled(*args, max_step=SAFE_STEP * TAU, **kw)
    elif variant == "compiled Radau":
        r = integrate_compiled(*args, method="Radau", **kw)
    else:
        # "numpy min/max": the clips inside the steps (not located)
        switching = None if variant == "numpy DOP853" else False
        r = integrate(*args, method=CappedDOP853, switching=switching, **kw)
    return r[0][1, 0], str(r[1][0]), float(r[3][0])


def tight(sc: dict) -> None:
    """Print each variant's difference in e to a tight compiled Radau, and CPU.

    The reference: the compiled Radau at ``rtol = 1e-12``, ``atol = 1e-14``
    (its switches located). For the scenarios of ``--only``.
    """
    z0 = initial_path_state(sc["path"], np.array([sc["initial_state"]]))
    t = np.linspace(0.0, sc["duration"], int(round(sc["duration"] / 0.05)) + 1)
    ref = integrate_compiled(
        sc["vehicle"], sc["path"], sc["gains"], method="Radau", rtol=1e-12,
        atol=1e-14, speed=np.array([sc["speed"]]), feedforward=True,
        path_state=z0, t_eval=t, time_constant=TAU,
    )[0][1, 0]  # fmt: skip
    print(
        f"scenario {sc['index']} ({sc['kind']}, V={sc['speed']:.1f}): difference in "
        "e to the compiled Radau at rtol=1e-12, atol=1e-14 [m], CPU [s]"
    )
    for v in (*VARIANTS, "numpy min/max"):
        start = time.process_time()
        e, status, _ = run(sc, v)
        cpu = time.process_time() - start
        both = np.isfinite(e) & np.isfinite(ref)
        d = float(np.max(np.abs(e[both] - ref[both])))
        print(f"{v:>18} {d:10.3g} {cpu:7.2f}  {status}", flush=True)


def run_all(sc: dict) -> list:
    """Every variant on one scenario (one task of ``--jobs``)."""
    return [run(sc, v) for v in VARIANTS]


def compare(results) -> tuple[list[float], list[str]]:
    """Largest difference in e to the reference per variant, and statuses."""
    e_ref = results[VARIANTS.index(REFERENCE)][0]
    diffs, status = [], []
    for e, st, _ in results:
        status.append(st)
        both = np.isfinite(e) & np.isfinite(e_ref)
        diffs.append(
            float(np.max(np.abs(e[both] - e_ref[both]))) if both.any() else 0.0
        )
    return diffs, status


def summary(scs, D, failed_alone, worst) -> None:
    """Print the counts and the differences of the scenarios done so far."""
    n = len(scs)
    print(
        f"{n} scenarios ({', '.join(KINDS)}), rtol={RTOL:g}, atol={ATOL:g}; "
        f"difference in e to {REFERENCE} [m]; TOL={TOL:g} m"
    )
    print(
        f"{'variant':>18} {'failed':>7} {'max':>10} {'q99':>10} {'> TOL':>6}"
        "  worst scenario"
    )
    for j, name in enumerate(VARIANTS):
        col = D[:n, j]
        w = scs[worst[j]]
        print(
            f"{name:>18} {failed_alone[j]:7d} {col.max():10.3g} "
            f"{np.quantile(col, 0.99):10.3g} {int((col > TOL).sum()):6d}  "
            f"{w['index']} ({w['kind']}, V={w['speed']:.1f})",
            flush=True,
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--count", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=20261127)
    ap.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    ap.add_argument(
        "--only",
        type=int,
        nargs="+",
        metavar="INDEX",
        help="run only these scenario indices (drawn as in the full set)",
    )
    args = ap.parse_args()
    scs = scenarios(args.count, seed=args.seed)
    if args.only:
        scs = [scs[i] for i in args.only]
        for sc in scs:
            tight(sc)
    D = np.zeros((len(scs), len(VARIANTS)))
    failed_alone = np.zeros(len(VARIANTS), dtype=int)
    worst = [0] * len(VARIANTS)
    if args.jobs > 1:
        pool = ProcessPoolExecutor(args.jobs)
        results = pool.map(run_all, scs, chunksize=4)
    else:
        pool, results = None, map(run_all, scs)
    for i, (sc, res) in enumerate(zip(scs, results, strict=True)):
        d, st = compare(res)
        D[i] = d
        for j, s in enumerate(st):
            if s == "failed" and any(o != "failed" for o in st):
                failed_alone[j] += 1
                print(
                    f"  scenario {sc['index']} ({sc['kind']}, V={sc['speed']:.1f}): "
                    f"{VARIANTS[j]} failed at t={res[j][2]:.4g} s",
                    flush=True,
                )
            if d[j] > D[worst[j], j]:
                worst[j] = i
        if (i + 1) % 100 == 0 and i + 1 < len(scs):
            summary(scs[: i + 1], D, failed_alone, worst)
    summary(scs, D, failed_alone, worst)
    if pool is not None:
        pool.shutdown()


if __name__ == "__main__":
    main()
