"""Results print a one-line summary, not their arrays.

Each repr must name the class, stay short (no array of a 5 s simulation
printed), and describe an array field by its true shape; the HTML repr is a
small table.
"""

import functools

import numpy as np
import pytest
from conftest import PAPER_VEHICLE

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE as VEH
from fws_control.paper.scenarios import (
    feedback_only_curve,
    fig5_peak_lateral_accel,
    scenario_responses,
)

K = np.linspace(-1.0, 1.0, 201)


@functools.cache
def _plant():
    return fws.LateralPlant(VEH, speed=5.0, curvature=0.1)


@functools.cache
def _gains():
    return fws.double_root_gains(_plant(), ratio=-1.0, pole=-1.0)


@functools.cache
def _chart():
    return fws.stability_chart(_plant(), ratio=-1.0, k1=K, k2=K, pole=-1.0)


@functools.cache
def _run():
    return fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        fws.Arc(0.1),
        _gains(),
        initial_state=(0, -5, 0),
        duration=5.0,
    )


def _batch():
    g = _gains()
    return fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0),
        fws.Arc(0.1), fws.SteeringGains([g.k1, g.k1], g.k2, -1.0),
        initial_state=(0, -5, 0), duration=5.0,
    )  # fmt: skip


# Each object is made by the test that prints it, not at import: under
# pytest-xdist every worker imports the module, and making them all there
# (simulations, a 201 x 201 chart, the paper's sweeps) cost each worker
# seconds of CPU before its first test.
OBJECTS = {
    "SimulationResult": (_run, "samples=501"),
    "Peaks": (lambda: _run().peaks, "exact=True"),
    "TrackingMetrics": (lambda: fws.tracking_metrics(_batch()), "status=['ok', 'ok']"),
    "StabilityChart": (_chart, "stable=<array (201, 201) bool>"),
    "StabilityBoundaries": (lambda: _chart().boundaries, "lines=<tuple of 2>"),
    "BoundaryCurve": (lambda: _chart().curve, "omega=<array ("),
    "DelayMarginChart": (
        lambda: fws.delay_margin_chart(
            fws.LateralPlant(VEH, speed=20.0), ratio=[-1.0, 0.5], pole=[-1.0, -2.0]
        ),
        "<array (2, 2) float64>",
    ),
    "LinearNonlinearComparison": (
        lambda: fws.compare_linear_nonlinear(_plant(), _gains(), duration=5.0),
        "linear=<TimeResponseData>",
    ),
    "AffinePolynomial": (
        lambda: fws.affine_characteristic_polynomial(_plant(), ratio=0.0),
        "AffinePolynomial(",
    ),
    "LoopMatrices": (lambda: fws.loop_matrices(_plant()), "LoopMatrices("),
    "ScenarioResponses": (
        lambda: scenario_responses("curve_5", duration=5.0),
        "ratios=<array (5,) float64>",
    ),
    "PeakSweep": (
        lambda: fig5_peak_lateral_accel(ratios=[-1.0, 0.0], duration=2.0)["a"],
        "peak_lateral_accel=<array (2, 2) float64>",
    ),
    "FeedbackOnlyResponses": (
        lambda: feedback_only_curve("curve_5", duration=5.0),
        "FeedbackOnlyResponses(",
    ),
}


@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_short_repr_and_small_html(name):
    make, expected = OBJECTS[name]
    obj = make()
    text = repr(obj)
    assert text.startswith(name) and "\n" not in text
    assert len(text) < 600, (name, len(text))
    assert expected in text, (name, text)
    html = obj._repr_html_()
    assert html.startswith("<table>") and name in html
    assert len(html) < 4000, (name, len(html))


# Inputs a user writes print as a short constructor call (value_repr)


def test_computed_gains_print_without_float_noise():
    g = fws.SteeringGains(0.1 + 0.2 - 0.282, 0.27, ratio=0.0)
    assert repr(0.1 + 0.2 - 0.282) != "0.018"  # the noise is there ...
    assert repr(g) == "SteeringGains(k1=0.018, k2=0.27, ratio=0.0)"  # ... not shown
    # 12 significant digits: a typed value survives unchanged
    assert eval(repr(fws.SteeringGains(0.123456789012, -2.5, 1.0)), vars(fws)) == (
        fws.SteeringGains(0.123456789012, -2.5, 1.0)
    )


def test_vehicle_and_plant_reprs_leave_out_defaults():
    veh = PAPER_VEHICLE
    assert repr(veh) == "Vehicle(wheelbase=2.7, rear_to_cg=1.35)"
    limited = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_front=0.5)
    assert repr(limited) == (
        "Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_front=0.5)"
    )
    assert eval(repr(limited), vars(fws)) == limited
    plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    assert repr(plant) == (
        "LateralPlant(vehicle=Vehicle(wheelbase=2.7, rear_to_cg=1.35), "
        "speed=5.0, curvature=0.1)"
    )


@pytest.mark.parametrize("make", [fws.slalom, fws.double_lane_change])
def test_manoeuvre_repr_is_short_and_names_its_parts(make):
    m = make()
    text = repr(m)
    assert text.startswith("Manoeuvre(name=") and "\n" not in text
    assert len(text) < 300, len(text)
    assert f"<tuple of {len(m.gates)}>" in text
    assert f"<tuple of {len(m.path.segments)}>" in text
