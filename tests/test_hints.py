"""The type aliases of fws_control.hints name exactly what the checks accept."""

import typing

import pytest

from fws_control import controllers, dynamics, hints, validation
from fws_control.plant import LateralPlant
from fws_control.vehicle import Vehicle


def _literals(alias) -> set:
    """The literal values of an alias (a Literal, or a union holding one)."""
    out = set()
    for arg in typing.get_args(alias):
        if typing.get_origin(arg) is typing.Literal:
            out |= set(typing.get_args(arg))
        elif not isinstance(arg, type):
            out.add(arg)
    return out


def test_model_and_tyre_names_are_the_runtime_choices():
    # the static aliases and the runtime checks list the same options
    assert _literals(hints.ModelName) == set(validation.MODELS)
    assert _literals(hints.TyreName) == set(dynamics.TYRES)
    assert _literals(hints.FeedforwardLike) == set(controllers.FEEDFORWARDS)
    assert bool in typing.get_args(hints.FeedforwardLike)


@pytest.mark.parametrize("model", sorted(validation.MODELS))
def test_every_model_name_builds_a_plant(model):
    veh = Vehicle(
        2.7,
        1.35,
        mass=1500.0,
        yaw_inertia=2500.0,
        cornering_front=8e4,
        cornering_rear=8e4,
    )
    assert LateralPlant(veh, speed=10.0, model=model).model == model


def test_a_name_outside_the_alias_is_refused_at_run_time():
    with pytest.raises(ValueError, match="model must be one of"):
        LateralPlant(Vehicle(2.7, 1.35), speed=5.0, model="linear")
    with pytest.raises(ValueError, match="tyre must be one of"):
        dynamics.require_dynamics(Vehicle(2.7, 1.35), tyre="pacejka")
