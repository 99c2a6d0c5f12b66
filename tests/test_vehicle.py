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


# --- a vehicle without a centre of gravity --------------------------------


def test_rear_to_cg_is_optional_and_compares():
    v = fws.Vehicle(wheelbase=2.7)
    assert v.rear_to_cg is None and not v.has_dynamics
    assert v != fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    assert hash(v) == hash(fws.Vehicle(2.7))
    assert repr(v) == "Vehicle(wheelbase=2.7)"
    assert fws.Vehicle(2.7, 1.2).cg_distance(needed_by="x") == 1.2
    assert fws.Vehicle(2.7, 1.2).front_to_cg == pytest.approx(1.5, abs=1e-15)


def test_gains_and_stability_need_no_cg():
    """The design of a vehicle without G places its double root at the pole
    (the eigenvalues of the closed loop of a vehicle with G, any G: the
    path-frame model of R does not contain d)."""
    import numpy as np

    bare = fws.Vehicle(wheelbase=2.7)
    for speed, kappa, a in [(5.0, 0.1, -1.0), (20.0, 0.0, 0.5), (10.0, 0.05, 0.0)]:
        g = fws.double_root_gains(
            bare, speed=speed, curvature=kappa, ratio=a, pole=-1.0
        )
        for d in (0.0, 1.35, 2.7):
            plant = fws.LateralPlant(fws.Vehicle(2.7, d), speed=speed, curvature=kappa)
            poles = np.linalg.eigvals(fws.closed_loop(plant, g).A)
            np.testing.assert_allclose(poles, [-1.0, -1.0], atol=1e-6)
        bare_plant = fws.LateralPlant(bare, speed=speed, curvature=kappa)
        assert fws.is_stable(bare_plant, g)
        np.testing.assert_array_equal(
            fws.closed_loop(bare_plant, g).A, fws.closed_loop(plant, g).A
        )
    chart = fws.stability_chart(
        fws.LateralPlant(bare, speed=5.0, curvature=0.1), ratio=-1.0
    )
    assert chart.plot() is not None


@pytest.mark.parametrize(
    "call, what",
    [
        (lambda v: v.front_to_cg, "front_to_cg"),
        (
            lambda v: fws.lateral_acceleration(v, 0.1, 0.0, 0.0, 0.0, speed=5.0),
            "lateral_acceleration",
        ),
        (lambda v: fws.steady_turn(v, 0.1, 0.0), "steady_turn"),
        (
            lambda v: fws.turning_radius(v, ratio=0.0, max_steer_front=0.5),
            "steady_turn",
        ),
        (
            lambda v: fws.simulate(
                fws.LateralPlant(v, speed=5.0),
                fws.Straight(),
                fws.SteeringGains(0.1, 0.5, 0.0),
                initial_state=(0.0, 1.0, 0.0),
                duration=1.0,
            ),
            "a simulation",
        ),
        (
            lambda v: fws.simulate_batch(
                fws.LateralPlant(v, speed=5.0),
                fws.Straight(),
                fws.SteeringGains(0.1, 0.5, 0.0),
                initial_state=(0.0, 1.0, 0.0),
                duration=1.0,
                signals=("e",),
            ),
            "a simulation",
        ),
    ],
)
def test_what_needs_the_cg_says_so(call, what):
    with pytest.raises(ValueError, match=rf"^rear_to_cg is None, but {what}.* G"):
        call(fws.Vehicle(wheelbase=2.7))


def test_dynamic_model_lists_rear_to_cg():
    dyn = dict(
        mass=1500.0, yaw_inertia=2600.0, cornering_front=8e4, cornering_rear=9.5e4
    )
    bare = fws.Vehicle(wheelbase=2.7, **dyn)
    assert not bare.has_dynamics
    assert fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, **dyn).has_dynamics
    for call in (
        lambda: fws.understeer_gradient(bare),
        lambda: fws.LateralPlant(bare, speed=10.0, model="dynamic"),
    ):
        with pytest.raises(ValueError, match=r"needs Vehicle fields rear_to_cg \[m\]"):
            call()
