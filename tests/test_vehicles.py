"""Named vehicles transcribed from CommonRoad, held against the package."""

import numpy as np
import pytest

import fws_control as fws
from fws_control import dynamics, vehicles

vm = pytest.importorskip(
    "vehiclemodels",
    reason="commonroad-vehicle-models is a test dependency "
    "(pip install commonroad-vehicle-models)",
)
from vehiclemodels.parameters_vehicle1 import parameters_vehicle1  # noqa: E402
from vehiclemodels.parameters_vehicle2 import parameters_vehicle2  # noqa: E402
from vehiclemodels.parameters_vehicle3 import parameters_vehicle3  # noqa: E402
from vehiclemodels.vehicle_dynamics_st import vehicle_dynamics_st  # noqa: E402

SETS = {1: parameters_vehicle1, 2: parameters_vehicle2, 3: parameters_vehicle3}


@pytest.mark.parametrize("n", [1, 2, 3])
def test_transcribed_values_are_the_package_values(n):
    p = SETS[n]()
    veh = vehicles.COMMONROAD_VEHICLES[n]
    assert veh.wheelbase == pytest.approx(p.a + p.b, rel=1e-15)
    assert veh.rear_to_cg == p.b
    assert veh.mass == p.m
    assert veh.yaw_inertia == p.I_z
    assert veh.friction == p.tire.p_dy1
    # forces mu*C_S*F_z*alpha of vehicle_dynamics_st (C_S = -p_ky1/p_dy1)
    c_s = -p.tire.p_ky1 / p.tire.p_dy1
    load_f = p.m * 9.81 * p.b / (p.a + p.b)
    load_r = p.m * 9.81 * p.a / (p.a + p.b)
    assert veh.cornering_front == pytest.approx(p.tire.p_dy1 * c_s * load_f, rel=1e-14)
    assert veh.cornering_rear == pytest.approx(p.tire.p_dy1 * c_s * load_r, rel=1e-14)
    assert vehicles.from_commonroad(n) == veh
    assert vehicles.COMMONROAD_STEERING[n] == (p.steering.max, p.steering.v_max)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_body_dynamics_match_commonroad_single_track(n):
    # The linear range of CommonRoad's vehicle_dynamics_st (states at the
    # centre of gravity: speed v, sideslip beta, yaw rate) against this
    # library's body_derivatives with the transcribed stiffnesses: with
    # v_y = v sin(beta), u = v cos(beta), v_y_dot = v cos(beta) beta_dot at
    # constant v. Small angles: the two differ by the O(angle^2) of
    # CommonRoad's small-angle force law (1e-5 here; a stiffness 4 % off gives
    # 2e-2).
    p = SETS[n]()
    veh = vehicles.COMMONROAD_VEHICLES[n]
    v, beta, r, delta = 15.0, 0.002, 0.01, 0.004
    f = vehicle_dynamics_st([0.0, 0.0, delta, v, 0.0, r, beta], [0.0, 0.0], p)
    r_dot_cr, beta_dot = f[5], f[6]
    u = v * np.cos(beta)
    vy_dot, r_dot = dynamics.body_derivatives(
        veh, v * np.sin(beta), r, delta, 0.0, speed=u
    )
    assert r_dot == pytest.approx(r_dot_cr, rel=1e-4)
    assert vy_dot == pytest.approx(v * np.cos(beta) * beta_dot, rel=1e-4)


def test_neutral_steer_and_errors():
    # equal normalised stiffness on both axles: C_f/l_r = C_r/l_f
    for veh in vehicles.COMMONROAD_VEHICLES.values():
        assert abs(fws.understeer_gradient(veh)) < 1e-15
    with pytest.raises(ValueError, match="vehicle_id must be 1, 2 or 3"):
        vehicles.from_commonroad(4)
    with pytest.raises(ValueError, match="vehicle_id must be 1, 2 or 3"):
        vehicles.from_commonroad(True)
