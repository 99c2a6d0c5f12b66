"""compare() refuses, before any run, requests beyond its work budget.

Each refused request ran for minutes or forever before (over 40 s of CPU for
one controller, see :data:`~fws_control.controller_comparison.COMPARE_MAX_STEPS`).
The estimate in the message is recomputed here from the course's geometry
and the loop's time scales written from their formulas.
"""

from __future__ import annotations

import math
import re
import time

import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws
from fws_control.controller_comparison import COMPARE_MAX_STEPS

VEH = PAPER_VEHICLE
COURSE = fws.double_lane_change()


def _duration(speed):
    # compare() runs from the first gate's entry to past the last gate
    return 1.1 * (COURSE.end_x - COURSE.start_x) / speed + 0.5


def _plant(kw):
    """The plant of a request (speed and steering lag) and its other options."""
    kw = dict(kw)
    lag = kw.pop("steering_lag", None)
    return fws.LateralPlant(VEH, speed=kw.pop("speed"), steering_lag=lag), kw


def _refusal(controllers, **kw):
    plant, kw = _plant(kw)
    start = time.process_time()
    with pytest.raises(ValueError, match="max_steps=1000") as info:
        fws.compare(plant, COURSE, controllers, **kw)
    assert time.process_time() - start < 1.0  # refused up front
    return str(info.value)


def _number(pattern, text):
    return float(re.search(pattern, text).group(1))


@pytest.mark.parametrize(
    "controllers, kw, scale",
    [
        # actuator lag: the loop's time scale is T
        ("default", dict(speed=20.0, steering_lag=1e-3), 1e-3),
        # a 0.1 s delay at 1 m/s: steps at most the delay over 122 s
        ("default", dict(speed=1.0, delay=0.1), 0.1),
        # pure pursuit: dtheta/dt = -2 V theta / L_d
        ({"pp": fws.PurePursuit(lookahead=1e-3)}, dict(speed=20.0), 1e-3 / 40.0),
        # Stanley: de/dt = -k V e / (k_s + V)
        ({"st": fws.Stanley(gain=1e6)}, dict(speed=20.0), 20.1 / (1e6 * 20.0)),
    ],
)
def test_stiff_requests_refused_with_the_estimate(controllers, kw, scale):
    if controllers == "default":
        controllers = fws.default_controllers(VEH, speed=kw["speed"])
    msg = _refusal(controllers, **kw)
    steps = _duration(kw["speed"]) / scale
    assert steps > COMPARE_MAX_STEPS
    assert _number(r"compare: ([0-9.e+]+) solver steps", msg) == pytest.approx(
        steps, rel=5e-3
    )


@pytest.mark.parametrize("kw", [dict(speed=20.0, dt=1e-5), dict(speed=0.1)])
def test_many_samples_refused_with_the_estimate(kw):
    msg = _refusal(fws.default_controllers(VEH, speed=kw["speed"]), **kw)
    samples = _duration(kw["speed"]) / kw.get("dt", 0.01)
    assert samples > 100 * COMPARE_MAX_STEPS
    assert _number(r"([0-9.e+]+) output samples", msg) == pytest.approx(
        samples, rel=5e-3
    )


def test_max_steps_raises_the_budget():
    course = fws.constant_radius(radius=40.0, turns=0.05)
    g = {"paper": fws.double_root_gains(VEH, speed=10.0, ratio=0.0, pole=-1.0)}
    kw = dict(delay=0.05)
    plant = fws.LateralPlant(VEH, speed=10.0)
    with pytest.raises(ValueError, match="max_steps=5 steps"):
        fws.compare(plant, course, g, max_steps=5, **kw)
    cmp = fws.compare(plant, course, g, max_steps=1e4, **kw)
    # the run is the one simulate gives for the same request
    res = cmp.results[0]
    ref = fws.simulate(
        fws.LateralPlant(VEH, speed=10.0),
        course.path, g["paper"], initial_state=(0.0, 0.0, 0.0),
        duration=float(res.t[-1]), delay=0.05,
    )  # fmt: skip
    np.testing.assert_allclose(res.e, ref.e, atol=1e-9)


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan])
def test_max_steps_range(bad):
    g = {"st": fws.Stanley()}
    with pytest.raises(ValueError, match="max_steps"):
        fws.compare(fws.LateralPlant(VEH, speed=20.0), COURSE, g, max_steps=bad)


def test_stability_chart_refuses_a_delay_beyond_its_budget():
    plant = fws.LateralPlant(VEH, speed=5.0)
    start = time.process_time()
    with pytest.raises(
        ValueError, match=r"delay=1000\.0 s on a 401 x 401 grid"
    ) as info:
        fws.stability_chart(plant, ratio=-1.0, delay=1e3)
    assert time.process_time() - start < 1.0
    # the estimate is at least the grid times the delay's phase points up to
    # 1 rad/s (8 delay / pi each), already beyond the budget of 1e8
    work = _number(r"needs about ([0-9.e+]+) evaluations", str(info.value))
    assert work >= 401 * 401 * 8 * 1e3 / math.pi > 1e8


def test_cli_compare_slow_and_delayed_is_refused_at_once(tmp_path, capsys):
    from fws_control.cli import main

    out = tmp_path / "c.png"
    start = time.process_time()
    status = main(["compare", "--speed", "1", "--delay", "0.1", "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2 and not out.exists()
    assert time.process_time() - start < 20.0  # (imports and designs only)
    # 1.1 x the course's x-span / 1 m/s + 0.5 s, over the 0.1 s delay
    steps = _number(r"compare: ([0-9.e+]+) solver steps", err)
    assert steps == pytest.approx(_duration(1.0) / 0.1, rel=5e-3)
    assert "max_steps=1000" in err
