import math

import pytest

import fws_control as fws


def test_fields_and_defaults():
    v = fws.Vehicle(wheelbase=3, rear_to_cg=1)
    assert v.wheelbase == 3.0 and isinstance(v.wheelbase, float)
    assert v.max_steer_front is None and not v.has_limits


def test_frozen():
    v = fws.Vehicle(2.7, 1.35)
    with pytest.raises(AttributeError):
        v.wheelbase = 3.0


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"wheelbase": 0.0, "rear_to_cg": 0.0}, "wheelbase"),
        ({"wheelbase": -1.0, "rear_to_cg": 0.0}, "wheelbase"),
        ({"wheelbase": math.nan, "rear_to_cg": 0.0}, "wheelbase"),
        ({"wheelbase": math.inf, "rear_to_cg": 0.0}, "wheelbase"),
        ({"wheelbase": 2.7, "rear_to_cg": -0.1}, "rear_to_cg"),
        ({"wheelbase": 2.7, "rear_to_cg": 2.8}, "rear_to_cg"),
        (
            {"wheelbase": 2.7, "rear_to_cg": 1.0, "max_steer_front": 0.0},
            "max_steer_front",
        ),
        (
            {"wheelbase": 2.7, "rear_to_cg": 1.0, "max_steer_rear": math.pi / 2},
            "max_steer_rear",
        ),
        (
            {"wheelbase": 2.7, "rear_to_cg": 1.0, "max_steer_rate_front": -1.0},
            "max_steer_rate_front",
        ),
        (
            {"wheelbase": 2.7, "rear_to_cg": 1.0, "max_steer_rate_rear": math.nan},
            "max_steer_rate_rear",
        ),
    ],
)
def test_invalid_fields_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=f"^{field} "):
        fws.Vehicle(**kwargs)


def test_limits_accepted():
    v = fws.Vehicle(2.7, 1.35, max_steer_front=0.6, max_steer_rate_rear=0.5)
    assert v.has_limits and v.max_steer_front == 0.6
    assert fws.Vehicle(2.7, 0.0).rear_to_cg == 0.0
    assert fws.Vehicle(2.7, 2.7).rear_to_cg == 2.7
