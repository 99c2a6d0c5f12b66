"""Reliability of the simulation under bad input, faults and huge requests
(issue 13): no hang, no silent garbage, no lost run."""

import contextlib
import math
import signal

import numpy as np
import pytest

import fws_control as fws
from fws_control.paths import Arc, Straight
from fws_control.simulation import SIGNALS, simulate_reference

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
EPS = np.finfo(float).eps


@contextlib.contextmanager
def time_limit(seconds):
    """Fail (instead of hanging the suite) if the block runs too long."""

    def on_alarm(signum, frame):
        raise TimeoutError(f"took longer than {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _paper_gains():
    return fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)


PAPER = {"speed": 5.0, "initial_state": (0.0, -5.0, 0.0), "duration": 15.0}


# --------------------------------------------------------------------------
# Item 1: tolerances that made the solver loop for ever are refused at once


@pytest.mark.parametrize(
    ("rtol", "atol", "bad"),
    [
        (1e-10, 0.0, "atol"),
        (1e-10, math.nan, "atol"),
        (math.nan, 1e-12, "rtol"),
        (math.inf, 1e-12, "rtol"),
        (0.0, 0.0, "rtol"),
        (10.0, 1e-12, "rtol"),  # accepted before: strode across singular states
        (1e-16, 1e-12, "rtol"),  # below scipy's floor 100 eps (silently raised)
        (1e-10, -1e-12, "atol"),
        (1e-10, True, "atol"),
        (1e-10, 1e-300, "atol"),  # overflows scipy's error norm at t = 0
    ],
)
def test_bad_tolerances_are_refused_promptly_naming_argument_value_range(
    rtol, atol, bad
):
    g = _paper_gains()
    value = {"rtol": rtol, "atol": atol}[bad]
    span = "[1e-20, 0.1]" if bad == "atol" else f"[{100 * EPS:.3g}, 0.1]"
    calls = (
        lambda: fws.simulate(VEH, Arc(0.1), g, **PAPER, rtol=rtol, atol=atol),
        lambda: fws.simulate_batch(VEH, Arc(0.1), g, **PAPER, rtol=rtol, atol=atol),
        lambda: simulate_reference(VEH, Arc(0.1), g, **PAPER, rtol=rtol, atol=atol),
    )
    with time_limit(20):
        for call in calls:
            with pytest.raises(ValueError) as info:
                call()
            msg = str(info.value)
            assert msg.startswith(f"{bad} must be") and repr(value) in msg
            assert span in msg


def test_tolerances_at_the_ends_of_their_ranges_are_accepted():
    g = _paper_gains()
    kw = {**PAPER, "duration": 5.0}
    ref = simulate_reference(VEH, Arc(0.1), g, **kw, rtol=1e-12, atol=1e-14)
    e_ref = ref.outputs[ref.output_labels.index("e")]
    with time_limit(20):
        tight = fws.simulate(VEH, Arc(0.1), g, **kw, rtol=100 * EPS, atol=1e-20)
        loose = fws.simulate(VEH, Arc(0.1), g, **kw, rtol=0.1, atol=0.1)
    assert tight.ok and loose.ok
    np.testing.assert_allclose(tight.e, e_ref, rtol=0, atol=1e-9)
    # a 10 % tolerance still follows the solution to within its tolerance
    assert np.max(np.abs(loose.e - e_ref)) < 0.1 * np.max(np.abs(e_ref))
