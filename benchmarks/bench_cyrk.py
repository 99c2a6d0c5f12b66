"""The CyRK candidate: the paper's curve scenario with CyRK's C++ DOP853.

Measures, for the candidates table of docs/performance.md, against the
library's compiled engine (scipy's DOP853 ported to numba) on the same runs:
the import time of CyRK, its first call (the numba C callback of the
right-hand side and the numba entry point compiled), the CPU per run of a
batch (``nbsolve2_ivp`` called from a numba-compiled loop over the runs, so
no Python call per run) and the largest state difference to
:func:`scipy.integrate.solve_ivp` (DOP853, rtol 1e-10, atol 1e-12) and to the
port. The runs are those of ``bench_engine.py``: ``curve_5`` (V = 5 m/s,
curvature 1/10, R(0) = (0, -5 m), feedforward + feedback, 15 s, 1501
output times), double root -1, ratios spread over [-1.5, 0.6]; the states
only (CyRK's numba entry point has no events, so no stop conditions and no
signals on either side).

Needs ``pip install CyRK`` (not a dependency of fws_control).
Run: ``python benchmarks/bench_cyrk.py [--runs 1000]``
"""

from __future__ import annotations

import argparse
import math
import time

import numba
import numpy as np
from scipy.integrate import solve_ivp
from timing import machine_line

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE
from fws_control.paper.scenarios import paper_scenario
from fws_control.simulation.compiled import curvature_table, integrate_compiled

TOL = dict(rtol=1e-10, atol=1e-12)


def best_cpu(fn, repeat: int = 3) -> float:
    """Best CPU time of one call [s] (all threads of the process)."""
    best = math.inf
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def rhs_formula(V: float, f: float, kappa: float):
    """The closed loop written here from eqs. (17)-(19) and (24)-(29)."""
    ff = math.atan(kappa * f)

    def rhs(t, y, k1, k2, a):
        s, e, th = y
        fb = -k1 * e - k2 * th
        df, dr = ff + fb, a * fb
        s_dot = V * math.cos(th + dr) / (1.0 - kappa * e)
        return [
            s_dot,
            V * math.sin(th + dr),
            -kappa * s_dot + V * math.sin(df - dr) / (f * math.cos(df)),
        ]

    return rhs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(machine_line())
    t0 = time.process_time()
    import CyRK
    from CyRK import cyjit, nbsolve2_ivp

    print(f"import CyRK {CyRK.__version__}: {time.process_time() - t0:.2f} CPU s")

    veh = PAPER_VEHICLE
    sc = paper_scenario("curve_5")
    V, f, kappa = sc.speed, veh.wheelbase, sc.curvature
    n = args.runs
    g = fws.double_root_gains(
        veh, speed=V, curvature=kappa, ratio=np.linspace(-1.5, 0.6, n), pole=-1.0
    )
    P = np.ascontiguousarray(np.stack([g.k1, g.k2, g.ratio], 1), dtype=float)
    t_eval = np.linspace(0.0, sc.duration, 1501)
    y0 = np.array([0.0, sc.initial_state[1], 0.0])
    ff = math.atan(kappa * f)

    t0 = time.process_time()

    @cyjit
    def diffeq(dy, t, y, p):
        fb = -p[0] * y[1] - p[1] * y[2]
        df = ff + fb
        dr = p[2] * fb
        s_dot = V * math.cos(y[2] + dr) / (1.0 - kappa * y[1])
        dy[0] = s_dot
        dy[1] = V * math.sin(y[2] + dr)
        dy[2] = -kappa * s_dot + V * math.sin(df - dr) / (f * math.cos(df))

    address = diffeq.address

    @numba.njit
    def batch(P, y0, t_eval, out, rtol, atol):
        for i in range(P.shape[0]):
            r = nbsolve2_ivp(
                address, (0.0, t_eval[-1]), y0, method="DOP853", t_eval=t_eval,
                args=P[i], rtol=rtol, atol=atol,
            )  # fmt: skip
            y = r.y
            for j in range(3):
                for k in range(t_eval.size):
                    out[i, j, k] = y[j, k]

    out = np.empty((n, 3, t_eval.size))
    batch(P[:1], y0, t_eval, out[:1], TOL["rtol"], TOL["atol"])
    first = time.process_time() - t0
    print(f"CyRK first call (callback + entry point): {first:.2f} CPU s")

    table = curvature_table(sc.path)
    port = {}
    kw = dict(speed=np.full(n, V), feedforward=True, path_state=np.tile(y0, (n, 1)),
              t_eval=t_eval, time_constant=None)  # fmt: skip

    def run_port():
        port["y"] = integrate_compiled(veh, table, g, **kw, **TOL)[0]

    run_port()  # compile or load the cache
    t_cyrk = best_cpu(lambda: batch(P, y0, t_eval, out, TOL["rtol"], TOL["atol"]),
                      args.repeat) / n  # fmt: skip
    t_port = best_cpu(run_port, args.repeat) / n
    rhs = rhs_formula(V, f, kappa)
    worst_ref = worst_port = 0.0
    for i in np.linspace(0, n - 1, min(n, 20)).astype(int):
        ref = solve_ivp(rhs, (0.0, sc.duration), y0, method="DOP853", t_eval=t_eval,
                        args=tuple(P[i]), **TOL).y  # fmt: skip
        worst_ref = max(worst_ref, float(np.abs(out[i] - ref).max()))
        worst_port = max(worst_port, float(np.abs(out[i] - port["y"][:, i]).max()))
    print(f"{n} runs, states at {t_eval.size} times, DOP853 rtol 1e-10 atol 1e-12")
    print(f"CPU per run: CyRK {t_cyrk * 1e6:.1f} us, port {t_port * 1e6:.1f} us, "
          f"ratio CyRK/port {t_cyrk / t_port:.2f}")  # fmt: skip
    print(f"largest state difference: to solve_ivp {worst_ref:.3g}, "
          f"to the port {worst_port:.3g} (20 runs)")  # fmt: skip
    print(machine_line())


if __name__ == "__main__":
    main()
