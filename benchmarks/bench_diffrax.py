"""The diffrax candidate: the paper's curve scenario with diffrax on JAX (CPU).

Measures, for comparison with ``bench_engine.py`` (see docs/performance.md):
the import time, the compile latency (first call of the jitted, vmapped
solve), the cost per run of a vmapped batch and of a single run, and the
largest state difference to :func:`scipy.integrate.solve_ivp` (DOP853,
rtol 1e-10, atol 1e-12). Diffrax's ``Dopri8`` with a PID controller at the
same tolerances (its error norm is also an RMS norm over the run's states
under ``vmap``, so each run keeps its own steps), ``SaveAt`` at the 1501
output times, float64. Stop events and the output signals are not included.

Needs ``pip install jax diffrax`` (not a dependency of fws_control).
Run: ``python benchmarks/bench_diffrax.py [--runs 1000]``
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from scipy.integrate import solve_ivp
from timing import best_of, machine_line


def best_cpu(fn, repeat=3, number=1):
    """Best CPU time per call [s] (all threads of the process)."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.process_time()
        for _ in range(number):
            fn()
        best = min(best, (time.process_time() - t0) / number)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    args = parser.parse_args()
    print(machine_line())
    t0 = time.process_time()
    import diffrax
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    print(
        f"import jax + diffrax: {time.process_time() - t0:.2f} CPU s "
        f"(jax {jax.__version__}, diffrax {diffrax.__version__})"
    )

    f, kappa, V = 2.7, 0.1, 5.0
    n = args.runs
    # double-root gains, pole -1, ratios over [-1.5, 0.6] (bench_engine.py)
    import fws_control as fws

    veh = fws.Vehicle(2.7, 1.35)
    g = fws.double_root_gains(
        veh, speed=V, curvature=kappa, ratio=np.linspace(-1.5, 0.6, n), pole=-1.0
    )
    params = jnp.stack([jnp.asarray(g.k1), jnp.asarray(g.k2), jnp.asarray(g.ratio)], 1)
    ts = jnp.linspace(0.0, 15.0, 1501)

    def rhs(t, y, p):
        s, e, th = y
        k1, k2, a = p
        fb = -k1 * e - k2 * th
        cf = fb + jnp.arctan(kappa * f)
        cr = a * fb
        s_dot = V * jnp.cos(th + cr) / (1 - kappa * e)
        return jnp.stack(
            [
                s_dot,
                V * jnp.sin(th + cr),
                -kappa * s_dot + V * jnp.sin(cf - cr) / (f * jnp.cos(cf)),
            ]
        )

    def solve(p):
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs),
            diffrax.Dopri8(),
            0.0,
            15.0,
            None,
            jnp.array([0.0, -5.0, 0.0]),
            args=p,
            saveat=diffrax.SaveAt(ts=ts),
            stepsize_controller=diffrax.PIDController(rtol=1e-10, atol=1e-12),
            max_steps=100_000,
        )
        return sol.ys

    batch = jax.jit(jax.vmap(solve))
    one = jax.jit(solve)
    t0 = time.process_time()
    ys = batch(params).block_until_ready()
    print(
        f"compile + first call, vmapped batch of {n}: "
        f"{time.process_time() - t0:.2f} CPU s"
    )
    t0 = time.process_time()
    one(params[0]).block_until_ready()
    print(f"compile + first call, single run: {time.process_time() - t0:.2f} CPU s")
    t_batch = best_of(lambda: batch(params).block_until_ready(), repeat=3) / n
    t_one = best_of(lambda: one(params[0]).block_until_ready(), repeat=5, number=5)
    c_batch = best_cpu(lambda: batch(params).block_until_ready()) / n
    c_one = best_cpu(lambda: one(params[0]).block_until_ready(), 5, 5)
    print(
        f"per run in the vmapped batch: wall {t_batch * 1e6:.1f} us, CPU "
        f"{c_batch * 1e6:.1f} us; single run: wall {t_one * 1e3:.3f} ms, CPU "
        f"{c_one * 1e3:.3f} ms (CPU: all threads of the process)"
    )

    d = 0.0
    for i in np.linspace(0, n - 1, 5).astype(int):
        k1, k2, a = (float(v) for v in params[i])

        def ref_rhs(t, y, k1=k1, k2=k2, a=a):
            s, e, th = y
            fb = -k1 * e - k2 * th
            cf, cr = fb + math.atan(kappa * f), a * fb
            sd = V * math.cos(th + cr) / (1 - kappa * e)
            return [
                sd,
                V * math.sin(th + cr),
                -kappa * sd + V * math.sin(cf - cr) / (f * math.cos(cf)),
            ]

        ref = solve_ivp(
            ref_rhs,
            (0, 15),
            [0.0, -5.0, 0.0],
            method="DOP853",
            t_eval=np.asarray(ts),
            rtol=1e-10,
            atol=1e-12,
        )
        d = max(d, float(np.max(np.abs(np.asarray(ys[i]).T - ref.y))))
    print(f"max |state difference| to solve_ivp (5 runs): {d:.2e}")


if __name__ == "__main__":
    main()
