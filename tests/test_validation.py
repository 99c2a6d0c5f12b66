"""Bad input raises an error naming the argument (never a NaN or a numpy error)."""

import numpy as np
import pytest

import fws_control as fws

VEH = fws.Vehicle(2.7, 1.35)
G = fws.SteeringGains(0.1, 0.5, 0.0)


@pytest.mark.parametrize(
    "call, exc, name",
    [
        (lambda: fws.Vehicle("a", 1.0), ValueError, "wheelbase"),
        (lambda: fws.Vehicle(None, 1.0), ValueError, "wheelbase"),
        (lambda: fws.Vehicle(True, 0.5), ValueError, "wheelbase"),
        (lambda: fws.Vehicle(2.7, "x"), ValueError, "rear_to_cg"),
        (
            lambda: fws.Vehicle(2.7, 1.0, max_steer_front="x"),
            ValueError,
            "max_steer_front",
        ),
        (lambda: fws.linearize(VEH, "fast"), ValueError, "speed"),
        (lambda: fws.linearize(VEH, [5.0, 6.0]), ValueError, "speed"),
        (lambda: fws.linearize(VEH, 5.0, [0.1, 0.2]), ValueError, "curvature"),
        (lambda: fws.linearize("veh", 5.0), TypeError, "vehicle"),
        (lambda: fws.global_frame_model(VEH, speed="x"), ValueError, "speed"),
        (lambda: fws.double_root_gains(VEH, 5.0, 0.1, -1.0, "x"), ValueError, "pole"),
        (lambda: fws.is_stable(VEH, 5.0, 0.1, np.nan, 0.5, -1.0), ValueError, "k1"),
        (lambda: fws.is_stable(VEH, 5.0, 0.1, 0.1, "x", -1.0), ValueError, "k2"),
        (
            lambda: fws.simulate(
                VEH, fws.Straight(), (0.1, 0.5, 0.0), 5.0, (0, 1, 0), 5.0
            ),
            TypeError,
            "gains",
        ),
        (lambda: fws.simulate(VEH, None, G, 5.0, (0, 1, 0), 5.0), TypeError, "path"),
        (
            lambda: fws.simulate(VEH, fws.Straight(), G, 5.0, "abc", 5.0),
            ValueError,
            "initial_state",
        ),
        (
            lambda: fws.simulate_batch(
                VEH, fws.Straight(), [1, 2], 5.0, (0, 1, 0), 5.0
            ),
            TypeError,
            "gains_list",
        ),
        (lambda: fws.stability_chart(VEH, 0.1, [-1.0, 0.0], 5.0), ValueError, "ratio"),
    ],
)
def test_error_names_the_argument(call, exc, name):
    with pytest.raises(exc, match=rf"^{name}\b"):
        call()


@pytest.mark.parametrize("speed", [5.0, -5.0])
def test_nearly_uncontrollable_design_says_so(speed):
    """Controllable in exact arithmetic, but the gains would be ~1e14."""
    with pytest.raises(fws.UncontrollableError, match="nearly uncontrollable"):
        fws.double_root_gains(VEH, speed, 0.0, 1.0 + 1e-7, -1.0)
    # a little further away the design exists and places the double root
    g = fws.double_root_gains(VEH, speed, 0.0, 1.0 + 1e-3, -1.0)
    np.testing.assert_allclose(
        fws.closed_loop(VEH, speed, 0.0, g).poles(), [-1.0, -1.0], atol=1e-4
    )
