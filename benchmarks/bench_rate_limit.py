"""Cost and accuracy of long rate-limited runs against an independent reference.

The paper's curve scenario (``curve_5``: V = 5 m/s, curvature 1/10,
R(0) = (0, -5 m), feedforward + feedback, double root -1; ratio
``a = --ratio``, default -0.5 so that both channels move), run for
``--duration`` (default 1500 s) with the rate-limited first-order steering
actuator of :func:`fws_control.steering_actuator`:

- no actuator (reference cost);
- ``T = 0.05 s`` without rate limits ("unlimited"), with rate limits of
  0.5 rad/s and of 0.2 rad/s (both channels; whether they bind is shown by
  the reference's steps refined at a limit and the compiled engine's switch
  count);
- ``T = 0.005 s`` (stiff) without and with 0.5 rad/s.

Each case runs through :func:`fws_control.simulate` (output step 0.1 s, all
signals) on the numpy engine with its default ``method="auto"`` and on
``engine="compiled"``, at the default tolerances ``rtol = 1e-10``,
``atol = 1e-12``. Printed per case: CPU time (best of ``--repeat`` >= 3; all
cases timed in turn, round after round, ``timing.best_of_interleaved``),
the method, the solver steps (numpy: counted by a subclass of the chosen
solver, in a separate untimed run; compiled: its statistics), the ratios
rate-limited / unlimited (the issue's target is <= 2) and / no actuator, and
the largest error of each state against the reference below, also in units
of the tolerance ``atol + rtol * max|y_i|`` (the engine "agrees" if every
state is within ``AGREE`` = 100 such units: a local tolerance bounds the
global error only up to such a factor; ``tests/test_rate_limit_reference.py``
measured 7-35 units for accurate methods at rtol 1e-8).

The reference is written here from the paper's model (eqs. 17-19 with the
speed factor in eq. 17, eqs. 24-29), the actuator
``d' = clip((d_cmd - d)/T, -r, r)`` and nothing from the library: classical
RK4 with the fixed step ``--step`` (default 1e-3 s; at most ``T / 40`` in the
first second, the actuator's initial layer), compiled with numba,
Kahan-compensated state sums (1.5e6 steps of ``s`` ~ 7500 m would otherwise
lose ~1e-9 to rounding). The clip is min/max inside the right-hand side; a
step that may hold a kink of it (the gap ``|u| - r`` to a limit changes
sign over the step's five evaluations, or comes closer to 0 than it varies
over them; RK4's local error across a kink is only O(h^2)) is redone as 32
substeps, and such a substep as 32 more, so that the kinks cost ~1e-12. Its own
error is estimated by Richardson extrapolation from the step halved
(``|y_h/2 - y_h| / 15``, RK4 being of order 4) and printed: it must be
below a tenth of the tolerance being checked.

With ``--methods`` the numpy engine also integrates the unlimited and the
0.5 rad/s case at ``T = 0.05 s`` with each of DOP853, LSODA, BDF and Radau
(best of 3 each; DOP853 and BDF take ~5 s per run at 1500 s, Radau ~11 s).

Run: ``python benchmarks/bench_rate_limit.py [--duration 1500] [--methods]``
(about a minute; with ``--methods`` about five).
"""

from __future__ import annotations

import argparse
import dataclasses
import math

import numpy as np
from timing import best_of, best_of_interleaved, machine_line

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE
from fws_control.paper.scenarios import paper_scenario
from fws_control.simulation.engine import SAFE_STEP, SOLVERS

try:
    import numba

    from fws_control.simulation.compiled import integrate_compiled
except ImportError as exc:  # pragma: no cover
    raise SystemExit(
        "this benchmark needs numba: pip install fws-control[fast]"
    ) from exc

RTOL, ATOL = 1e-10, 1e-12
#: An engine agrees with the reference if every state's largest error is
#: within this many units of ``atol + rtol * max|y_i|``.
AGREE = 100.0
DT_OUT = 0.1
STATES = ("s", "e", "theta", "delta_f", "delta_r")


# --------------------------------------------------------------------------
# Independent reference: fixed-step RK4 on the closed loop, from the paper


@numba.njit(cache=True)
def _rhs(y, p, out, gap):
    """Closed loop (eqs. 17-19, 24-29) with the rate-clipped actuator.

    ``p = (V, f, kappa, k1, k2, a, T, r_f, r_r)``; writes ``|u_j| - r_j``
    (the unclipped rate's distance to the limit, > 0 where it clips) of
    each channel into `gap`, for the kink detection.
    """
    V, f, kappa, k1, k2, a, T = p[0], p[1], p[2], p[3], p[4], p[5], p[6]
    s_dot = V * math.cos(y[2] + y[4]) / (1.0 - kappa * y[1])
    fb = -k1 * y[1] - k2 * y[2]
    cmd_f = math.atan(kappa * f) + fb  # eq. (26) + (28)
    cmd_r = a * fb  # eq. (27) + (29) with k3 = a k1, k4 = a k2
    out[0] = s_dot
    out[1] = V * math.sin(y[2] + y[4])
    out[2] = -kappa * s_dot + V * math.sin(y[3] - y[4]) / (f * math.cos(y[3]))
    for j, (cmd, r) in enumerate(((cmd_f, p[7]), (cmd_r, p[8]))):
        u = (cmd - y[3 + j]) / T
        out[3 + j] = min(max(u, -r), r)
        gap[j] = abs(u) - r


@numba.njit(cache=True)
def _rk4(y, h, p, k, inc):
    """Increment of one RK4 step in `inc`; True if a kink may lie in it.

    A kink: the gap to a limit changes sign between the five evaluations
    (four stages and the end), or comes closer to 0 than it varies over
    them (a brief clip, or a brief release, between two evaluations).
    """
    tmp = np.empty(5)
    gap = np.empty(2)
    lo = np.full(2, np.inf)
    hi = np.full(2, -np.inf)
    for st, c in ((0, 0.0), (1, 0.5), (2, 0.5), (3, 1.0), (4, 1.0)):
        if st == 4:
            for i in range(5):
                inc[i] = h / 6.0 * (k[0, i] + 2.0 * k[1, i] + 2.0 * k[2, i] + k[3, i])
                tmp[i] = y[i] + inc[i]
            _rhs(tmp, p, np.empty(5), gap)
        else:
            for i in range(5):
                tmp[i] = y[i] + c * h * k[st - 1, i] if st > 0 else y[i]
            _rhs(tmp, p, k[st], gap)
        for j in range(2):
            lo[j] = min(lo[j], gap[j])
            hi[j] = max(hi[j], gap[j])
    for j in range(2):
        if lo[j] <= 0.0 <= hi[j] or min(abs(lo[j]), abs(hi[j])) < hi[j] - lo[j]:
            return True
    return False


@numba.njit(cache=True)
def _add(y, c, inc):
    # Kahan summation: y + inc with the lost low-order bits carried in c
    for i in range(5):
        d = inc[i] - c[i]
        t = y[i] + d
        c[i] = (t - y[i]) - d
        y[i] = t


@numba.njit(cache=True)
def _advance(y, c, h, p, k, inc):
    """One step of h; a step with a kink as 32 substeps, and such a substep
    as 32 more (loops, not recursion: numba's cache of a recursive function
    crashed on reload). Returns 1 for a step with a kink."""
    if not _rk4(y, h, p, k, inc):
        _add(y, c, inc)
        return 0
    for _ in range(32):
        if not _rk4(y, h / 32.0, p, k, inc):
            _add(y, c, inc)
            continue
        for _ in range(32):
            _rk4(y, h / 1024.0, p, k, inc)
            _add(y, c, inc)
    return 1


@numba.njit(cache=True)
def rk4_reference(y0, p, h, n_out, every, n_start, split):
    """States at ``n_out`` times ``every * h`` apart; and the kink steps.

    The first `n_start` output intervals take steps of ``h / split``.
    """
    y = y0.copy()
    c = np.zeros(5)
    k = np.empty((4, 5))
    inc = np.empty(5)
    out = np.empty((n_out, 5))
    out[0] = y
    kinks = 0
    for j in range(1, n_out):
        m = split if j <= n_start else 1
        for _ in range(every * m):
            kinks += _advance(y, c, h / m, p, k, inc)
        out[j] = y
    return out, kinks


def reference(vehicle, g, sc, tau, rate, duration, h):
    """(states (T, 5), Richardson error estimate per state, kink steps)."""
    r = math.inf if rate is None else rate
    p = np.array([sc.speed, vehicle.wheelbase, sc.curvature, float(g.k1),
                  float(g.k2), float(g.ratio), tau, r, r])  # fmt: skip
    e0 = sc.initial_state[1]  # R(0) = (0, e0) projects to s = 0, e = e0
    fb = -float(g.k1) * e0
    y0 = np.array([0.0, e0, 0.0, math.atan(sc.curvature * vehicle.wheelbase) + fb,
                   float(g.ratio) * fb])  # fmt: skip
    n_out = int(round(duration / DT_OUT)) + 1
    every = int(round(DT_OUT / h))
    # The first second (the actuator's initial layer, time scale T) at a
    # step of at most T / 40: where a rate limit engages within it, the
    # clipped channel stops contracting and keeps RK4's error of the fast
    # transient (at h = T / 5 it was ~1e-8, not yet in RK4's h^4 regime).
    split = max(1, math.ceil(40 * h / tau))
    n_start = int(round(1.0 / DT_OUT))
    coarse, _ = rk4_reference(y0, p, h, n_out, every, n_start, split)
    fine, kinks = rk4_reference(y0, p, h / 2, n_out, 2 * every, n_start, split)
    return fine, np.max(np.abs(fine - coarse), axis=0) / 15.0, kinks


# --------------------------------------------------------------------------


def count_steps(method: str, run) -> int:
    """Steps of `method` in ``run(method_class)`` (a counting subclass)."""
    n = [0]

    class Counting(SOLVERS[method]):
        def _step_impl(self):
            n[0] += 1
            return super()._step_impl()

    run(Counting)
    return n[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=1500.0)
    parser.add_argument("--ratio", type=float, default=-0.5)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--methods", action="store_true")
    args = parser.parse_args()
    if args.repeat < 3:
        parser.error("--repeat must be >= 3 (best of at least three)")
    print(machine_line())
    sc = paper_scenario("curve_5")
    veh0 = PAPER_VEHICLE
    g = fws.double_root_gains(veh0, speed=sc.speed, curvature=sc.curvature,
                              ratio=args.ratio, pole=-1.0)  # fmt: skip
    D = args.duration
    print(
        f"scenario {sc.name}, ratio a = {args.ratio}, pole -1, {D:g} s, output "
        f"step {DT_OUT} s; rtol {RTOL:g}, atol {ATOL:g}; reference: RK4, step "
        f"{args.step:g} s and {args.step / 2:g} s (Richardson; <= T/40 in the "
        "first second)"
    )

    def vehicle(rate):
        if rate is None:
            return veh0
        return dataclasses.replace(
            veh0, max_steer_rate_front=rate, max_steer_rate_rear=rate
        )

    def simulate(tau, rate, engine, method="auto"):
        return fws.simulate(
            fws.LateralPlant(vehicle(rate), speed=sc.speed, steering_lag=tau),
            sc.path, g, initial_state=sc.initial_state,
            duration=D, dt=DT_OUT, engine=engine,
            method=method, rtol=RTOL, atol=ATOL,
        )  # fmt: skip

    def states(res, tau):
        rows = [res.s, res.e, res.theta]
        rows += [res.delta_f, res.delta_r]
        return np.stack(rows, axis=1)[:, : 3 if tau is None else 5]

    cases = [
        ("no actuator", None, None),
        ("T=0.05 unlimited", 0.05, None),
        ("T=0.05 rate 0.5", 0.05, 0.5),
        ("T=0.05 rate 0.2", 0.05, 0.2),
        ("T=0.005 unlimited", 0.005, None),
        ("T=0.005 rate 0.5", 0.005, 0.5),
    ]
    # every case on both engines first (a failure is reported below, not
    # timed), then all timed in turn, round after round, so that the ratios
    # rate-limited / unlimited do not take up the machine's drift
    engines = ("numpy", "compiled")
    runs, timers = {}, {}
    for name, tau, rate in cases:
        for engine in engines:
            try:
                runs[name, engine] = res = simulate(tau, rate, engine)
            except Exception as exc:  # noqa: BLE001 - reported, not hidden
                runs[name, engine] = exc
                continue
            if res.status == "ok":
                timers[name, engine] = lambda tau=tau, rate=rate, engine=engine: (
                    simulate(tau, rate, engine)
                )
    cost = best_of_interleaved(timers, args.repeat)
    for name, tau, rate in cases:
        if tau is not None:
            ref, own, kinks = reference(veh0, g, sc, tau, rate, D, args.step)
            tol = ATOL + RTOL * np.max(np.abs(ref), axis=0)
            ok_ref = bool(np.all(own < 0.1 * tol))
            print(
                f"\n{name}: reference self-error {np.array2string(own, precision=1)}"
                f" ({'<' if ok_ref else 'NOT <'} 0.1 tolerance); steps refined at "
                f"a limit: {kinks} (0: the limits never bind)"
            )
        else:
            print(f"\n{name}:")
        for engine in engines:
            res = runs[name, engine]
            if isinstance(res, Exception):
                print(f"  {engine:8s}: {type(res).__name__}: {res}")
                continue
            if res.status != "ok":
                print(f"  {engine:8s}: {res.method} status {res.status}: {res.message}")
                continue
            cpu = cost[name, engine]
            if engine == "numpy":
                steps = count_steps(
                    res.method,
                    lambda cls, tau=tau, rate=rate, e=engine: simulate(
                        tau, rate, e, cls
                    ),
                )
                extra = ""
            else:
                # the statistics of the run timed above: with an actuator,
                # method="auto" on the compiled engine holds DOP853's steps to
                # SAFE_STEP * T, or takes Radau (checked: the same states)
                capped = tau is not None and res.method == "DOP853"
                cap = SAFE_STEP * tau if capped else math.inf
                out = integrate_compiled(
                    vehicle(rate), sc.path, g, speed=np.array([sc.speed]),
                    feedforward=True, path_state=np.array([[0.0, sc.initial_state[1],
                    0.0]]), t_eval=res.t, time_constant=tau, rtol=RTOL, atol=ATOL,
                    max_step=cap, method=res.method,
                )  # fmt: skip
                if not np.array_equal(out[0][:, 0, :].T, states(res, tau)):
                    raise SystemExit(f"{name}: the statistics' run is not the timed")
                st = out[4][0]
                steps = int(st[0])
                extra = f", {int(st[4])} switches, stiff flag {int(st[3])}"
            line = f"  {engine:8s}: {res.method:6s} {cpu * 1e3:8.1f} ms CPU, "
            line += f"{steps} steps{extra}"
            if tau is not None:
                err = np.max(np.abs(states(res, tau) - ref), axis=0)
                units = err / tol
                line += (
                    f"; error {np.array2string(err, precision=1)}, "
                    f"= {np.array2string(units, precision=1)} tolerances: "
                    + ("agrees" if np.all(units <= AGREE) else "DOES NOT agree")
                )
            base = cost.get(("no actuator", engine))
            free_cost = cost.get((name.split(" rate")[0] + " unlimited", engine))
            if "rate" in name and free_cost:
                line += f"\n            rate-limited / unlimited {cpu / free_cost:.2f}"
            if tau is not None and base:
                line += f"; / no actuator {cpu / base:.2f}"
            print(line)

    if args.methods:
        print("\nnumpy engine, T = 0.05 s, each method (best of 3):")
        for rate in (None, 0.5):
            ref, _, _ = reference(veh0, g, sc, 0.05, rate, D, args.step)
            tol = ATOL + RTOL * np.max(np.abs(ref), axis=0)
            for m in ("DOP853", "LSODA", "BDF", "Radau"):
                res = simulate(0.05, rate, "numpy", m)
                cpu = best_of(lambda m=m, r=rate: simulate(0.05, r, "numpy", m), 3)
                steps = count_steps(
                    m, lambda cls, r=rate: simulate(0.05, r, "numpy", cls)
                )
                units = np.max(np.abs(states(res, 0.05) - ref), axis=0) / tol
                print(
                    f"  rate {rate}: {m:6s} {cpu * 1e3:8.1f} ms, {steps} steps, "
                    f"largest error {units.max():.1f} tolerances"
                )
    print(f"\n{machine_line()}")


if __name__ == "__main__":
    main()
