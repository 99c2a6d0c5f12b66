"""The zero-sideslip ratio a(V) and ratio schedules in designs and charts."""

import control as ct
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import fsolve

import fws_control as fws
from fws_control import dynamics
from fws_control import symbolic as S

VEH = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.2,
    mass=1500.0,
    yaw_inertia=2600.0,
    cornering_front=8.0e4,
    cornering_rear=9.5e4,
)


def _sideslip(ratio, u, delta_f=0.01):
    """Steady sideslip v_y/u of the nonlinear body equations, delta_r = a delta_f."""

    def rates(z):
        return np.array(
            dynamics.body_derivatives(
                VEH, z[0], z[1], delta_f, ratio * delta_f, speed=u
            ),
            dtype=float,
        )

    z = fsolve(rates, [0.0, 0.0])
    # residual far below the rates of a 0.01 rad step (~1 m/s^2, ~1 rad/s^2)
    assert np.abs(rates(z)).max() < 1e-12
    assert abs(z[1]) > 0  # a real turn
    return z[0] / u


@pytest.mark.parametrize("u", [3.0, 10.0, 20.0, 40.0])
def test_zero_sideslip_at_the_cg(u):
    a = fws.zero_sideslip_ratio(VEH, speed=u)
    beta = _sideslip(a, u)
    beta_fws = _sideslip(0.0, u)
    # zero to first order in the steering angle: the remainder is of order
    # delta^3 relative to the front-steered sideslip, which is of order delta
    assert abs(beta) < 1e-4 * abs(beta_fws)
    assert abs(beta_fws) > 1e-4


def test_matches_the_symbolic_derivation_and_the_limits():
    expr = S.zero_sideslip_ratio()
    sym = {**S.SYMBOLS, **S.DYNAMIC_SYMBOLS}
    f = sp.lambdify(
        [sym[n] for n in ("speed", "wheelbase", "rear_to_cg", "mass")]
        + [sym["cornering_front"], sym["cornering_rear"]],
        expr,
    )
    speeds = np.array([1.0, 7.0, 25.0, 60.0])
    ref = f(speeds, 2.7, 1.2, 1500.0, 8.0e4, 9.5e4)
    np.testing.assert_allclose(
        fws.zero_sideslip_ratio(VEH, speed=speeds), ref, rtol=1e-13
    )
    # counter-phase -l_r/l_f at low speed, C_f l_f/(C_r l_r) at high speed,
    # sign change at sqrt(f C_r l_r/(m l_f))
    assert fws.zero_sideslip_ratio(VEH, speed=1e-3) == pytest.approx(-1.2 / 1.5)
    assert fws.zero_sideslip_ratio(VEH, speed=1e5) == pytest.approx(
        8.0e4 * 1.5 / (9.5e4 * 1.2), rel=1e-6
    )
    v0 = np.sqrt(2.7 * 9.5e4 * 1.2 / (1500.0 * 1.5))
    assert fws.zero_sideslip_ratio(VEH, speed=v0) == pytest.approx(0.0, abs=1e-15)


@settings(derandomize=True, max_examples=15, deadline=None)
@given(u=st.floats(2.0, 40.0), kappa=st.floats(-0.05, 0.05))
def test_schedule_in_designs_and_charts(u, kappa):
    plant = fws.LateralPlant(VEH, speed=u, curvature=kappa)
    a = fws.zero_sideslip_ratio(VEH, speed=u)
    g_s = fws.double_root_gains(plant, ratio=fws.zero_sideslip_ratio, pole=-1.5)
    g_v = fws.double_root_gains(plant, ratio=a, pole=-1.5)
    assert (g_s.k1, g_s.k2, g_s.ratio) == (g_v.k1, g_v.k2, g_v.ratio)
    # the design places the double root (eigenvalues of python-control's
    # closed loop)
    poles = ct.ss(plant.linearize()).A - plant.linearize().B @ np.outer(
        [1.0, a], [g_s.k1, g_s.k2]
    )
    np.testing.assert_allclose(np.linalg.eigvals(poles), [-1.5, -1.5], atol=2e-4)
    dyn = fws.LateralPlant(VEH, speed=u, curvature=kappa, model="dynamic")
    cp_s = fws.affine_characteristic_polynomial(dyn, ratio=fws.zero_sideslip_ratio)
    cp_v = fws.affine_characteristic_polynomial(dyn, ratio=a)
    np.testing.assert_array_equal(cp_s.n1, cp_v.n1)


def test_schedule_broadcasts_and_is_checked():
    speeds = np.array([5.0, 20.0, 35.0])
    plant = fws.LateralPlant(VEH, speed=speeds)
    g = fws.double_root_gains(plant, ratio=fws.zero_sideslip_ratio, pole=-1.0)
    np.testing.assert_array_equal(g.ratio, fws.zero_sideslip_ratio(VEH, speed=speeds))
    ch = fws.stability_chart(
        fws.LateralPlant(VEH, speed=20.0), ratio=fws.zero_sideslip_ratio, pole=-1.0
    )
    assert ch.ratio == fws.zero_sideslip_ratio(VEH, speed=20.0)
    with pytest.raises(TypeError, match="needs a fws.LateralPlant"):
        fws.affine_characteristic_polynomial(
            fws.LateralPlant(VEH, speed=5.0).linearize(), ratio=fws.zero_sideslip_ratio
        )
    with pytest.raises(ValueError, match="returned by the schedule"):
        fws.double_root_gains(
            fws.LateralPlant(VEH, speed=5.0), ratio=lambda v, speed: np.nan, pole=-1.0
        )
    with pytest.raises(ValueError, match="mass"):
        fws.zero_sideslip_ratio(fws.Vehicle(2.7, 1.2), speed=5.0)
    with pytest.raises(ValueError, match="speed must be finite and > 0"):
        fws.zero_sideslip_ratio(VEH, speed=-1.0)


def test_huge_speed_refused_with_range():
    # issue 13: 1e300 m/s gave inf/inf = NaN; refused above MAX_SPEED
    with pytest.raises(ValueError, match="speed must be finite with magnitude"):
        fws.zero_sideslip_ratio(VEH, speed=1e300)
    g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=0.0)
    with pytest.raises(ValueError, match="speed must be finite with magnitude"):
        fws.steady_state_offset(VEH, g, speed=1e300, curvature=0.01)
    with pytest.raises(ValueError, match="curvature must be finite with magnitude"):
        fws.steady_state_offset(VEH, g, speed=20.0, curvature=-1e300)
    # at the bound the ratio is its high-speed limit C_f l_f / (C_r l_r)
    a = fws.zero_sideslip_ratio(VEH, speed=fws.validation.MAX_SPEED)
    lim = VEH.cornering_front * VEH.front_to_cg / (VEH.cornering_rear * VEH.rear_to_cg)
    assert a == pytest.approx(lim, rel=1e-9)
