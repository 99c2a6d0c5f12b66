"""The compiled engine with steering-angle and steering-rate limits.

A vehicle with angle and rate limits and no explicit actuator gets the
default actuator (``T = 0.05 s``); ``simulate`` then runs the compiled
DOP853 with its steps capped at ``SAFE_STEP * T``, the clips' switches
located as events. References: the numpy engine (scipy's DOP853, its
switches located by its own loop) and the compiled Radau (an implicit
method with other steps and its own located switches).

Tolerances of the agreement: ``TOL = 1e-6`` m in ``e`` between the
compiled DOP853 and Radau, both with the switches located: two accurate
integrations at ``rtol = 1e-10``, ``atol = 1e-12`` each stay within 10-100
local tolerances (``|e| <= 5`` m: ~5e-10 m each) of the exact solution plus
the switches' roots (4 eps relative); 1e-6 m leaves a factor of ~1000 for
the error growth over a run (measured: <= 4.1e-7 m on the first 40
scenarios of :func:`_scenarios`). The same ``TOL`` against the numpy
engine, which locates the switches too; integrated across the clips' kinks
inside its steps (min/max in the right-hand side), where DOP853's error
estimate is not that of a smooth solution, it was up to 1.03e-6 m off both
compiled methods, which agree to 3.9e-8 m there. Both are far below the
1e-4 to 3e-3 m of a run integrated across a missed switch.
``benchmarks/bench_limit_agreement.py`` runs 1000 such scenarios.
"""

import math

import numpy as np
import pytest

import fws_control as fws
from fws_control.controllers import DEFAULT_ACTUATOR_TIME_CONSTANT
from fws_control.simulation.engine import SAFE_STEP, initial_path_state, integrate

pytest.importorskip("numba", reason="the compiled engine needs numba")

from fws_control.simulation.compiled import integrate_compiled  # noqa: E402

TAU = DEFAULT_ACTUATOR_TIME_CONSTANT
TOL = 1e-6
KW = dict(feedforward=True, time_constant=TAU, rtol=1e-10, atol=1e-12)


def _runs(veh, path, gains, speed, pose, duration, *, numpy=True):
    """e of the default compiled DOP853, the compiled Radau and numpy DOP853."""
    z0 = initial_path_state(path, np.array([pose]))
    t = np.linspace(0.0, duration, int(round(duration / 0.05)) + 1)
    kw = dict(KW, speed=np.array([speed]), path_state=z0, t_eval=t)
    out = {
        "DOP853": integrate_compiled(veh, path, gains, max_step=SAFE_STEP * TAU, **kw),
        "Radau": integrate_compiled(veh, path, gains, method="Radau", **kw),
    }
    if numpy:
        out["numpy"] = integrate(veh, path, gains, method="DOP853", **kw)
    return {k: (r[0][1, 0], r[1][0], float(r[3][0])) for k, r in out.items()}


def test_rate_limited_arc_finishes_and_agrees_with_radau():
    """An arc at 24 m/s where the front rate clip, released at its lower
    limit, reaches its upper one within the next step: the compiled DOP853
    used to switch the clip back at once, for ever ("failed" at t = 1.548 s
    after 100,000 switches), while its Radau and the numpy engine finish.
    (The numpy engine costs ~50 s of CPU on this arc: the random scenarios
    below compare with it.)"""
    veh = fws.Vehicle(
        2.7, 1.35, max_steer_front=0.36776410870848925,
        max_steer_rear=0.13052095651685824,
        max_steer_rate_front=0.4088917484312825,
        max_steer_rate_rear=1.6946760000226333,
    )  # fmt: skip
    g = fws.SteeringGains(0.05979258349776821, 0.909652674447719, 0.3496068670563145)
    pose = (2.1483846365871435, -1.4668137740062281, -0.11955507186839875)
    r = _runs(
        veh, fws.Arc(0.048301143578173555), g, 24.270710307492635, pose, 6.0,
        numpy=False,
    )  # fmt: skip
    for name, (_e, status, t_stop) in r.items():
        assert (status, t_stop) == ("ok", 6.0), name
    assert np.max(np.abs(r["DOP853"][0] - r["Radau"][0])) < TOL
    # the default engine through simulate finishes too
    res = fws.simulate(
        fws.LateralPlant(veh, speed=24.270710307492635),
        fws.Arc(0.048301143578173555), g,
        initial_state=pose,
        duration=6.0,
    )  # fmt: skip
    assert res.status == "ok"


def test_rate_limited_slalom_finishes_as_radau():
    """The slalom of the issue's kind (24.3 m/s): the compiled DOP853 used to
    stop "failed" at t = 1.006 s; it now reaches the end and agrees with the
    compiled Radau (the numpy engine costs ~8 s here; the arc above and the
    random scenarios below compare with it)."""
    veh = fws.Vehicle(
        2.7, 1.35, max_steer_front=0.2909094796559325,
        max_steer_rear=0.2652355867124915,
        max_steer_rate_front=0.693359648037918,
        max_steer_rate_rear=0.6943369767668026,
    )  # fmt: skip
    g = fws.SteeringGains(
        0.014890868165339908, 0.3803483672052601, -0.14137513403969337
    )
    pose = (2.0, -2.9864710330512705, 0.20931745973493526)
    path = fws.slalom(pitch=14.834693678982653, amplitude=0.9821000168048606).path
    r = _runs(veh, path, g, 24.27791319292762, pose, 5.5, numpy=False)
    for name, (_e, status, t_stop) in r.items():
        assert (status, t_stop) == ("ok", 5.5), name
    assert np.max(np.abs(r["DOP853"][0] - r["Radau"][0])) < TOL


def _scenarios(count, seed):
    """Random rate-limited scenarios: arcs and slaloms (as the benchmark)."""
    rng = np.random.default_rng(seed)
    for i in range(count):
        speed = float(rng.uniform(5.0, 30.0))
        veh = fws.Vehicle(
            2.7, 1.35, max_steer_front=float(rng.uniform(0.2, 0.6)),
            max_steer_rear=float(rng.uniform(0.1, 0.4)),
            max_steer_rate_front=float(rng.uniform(0.2, 2.0)),
            max_steer_rate_rear=float(rng.uniform(0.2, 2.0)),
        )  # fmt: skip
        g = fws.double_root_gains(
            veh, ratio=float(rng.uniform(-0.6, 0.4)),
            pole=float(rng.uniform(-3.0, -0.5)), speed=speed,
        )  # fmt: skip
        e0, th0 = float(rng.uniform(-3.0, 3.0)), float(rng.uniform(-0.3, 0.3))
        if i % 2:
            pitch = float(rng.uniform(14.0, 24.0))
            amp = float(rng.uniform(0.5, min(1.5, 0.24 * pitch)))
            path = fws.slalom(pitch=pitch, amplitude=amp, cones=6).path
            duration = min(6.0, 0.95 * path.length / speed)
        else:
            path = fws.Arc(float(rng.uniform(-0.2, 0.2)))
            duration = 6.0
        (px,), (py,) = path.position([2.0])
        (h,) = path.heading([2.0])
        pose = (px - e0 * math.sin(h), py + e0 * math.cos(h), h + th0)
        yield veh, path, g, speed, pose, duration


def test_random_rate_limited_scenarios_agree_and_none_fails():
    """24 random scenarios (fixed seed): the compiled DOP853 and Radau agree
    with each other to TOL and end as they do; on the arcs (cheap there)
    both also agree with the numpy engine to TOL."""
    worst, worst_numpy = 0.0, 0.0
    for veh, path, g, speed, pose, duration in _scenarios(24, 7):
        arc = isinstance(path, fws.Arc)
        r = _runs(veh, path, g, speed, pose, duration, numpy=arc)
        for name, (e, status, t_stop) in r.items():
            for ref_name in ("numpy", "Radau"):
                if ref_name == name or ref_name not in r:
                    continue
                e_ref, status_ref, t_ref = r[ref_name]
                assert status == status_ref, (name, status, status_ref, speed)
                assert abs(t_stop - t_ref) <= 1e-6, (name, t_stop, t_ref)
                both = np.isfinite(e) & np.isfinite(e_ref)
                d = float(np.max(np.abs(e[both] - e_ref[both])))
                if ref_name == "numpy":
                    worst_numpy = max(worst_numpy, d)
                else:
                    worst = max(worst, d)
    assert worst < TOL
    assert worst_numpy < TOL
