"""kinematic_design_limit against python-control closed loops."""

from dataclasses import replace

import control as ct
import matplotlib
import numpy as np
import pytest

import fws_control as fws

matplotlib.use("Agg")

# oversteering (K_us < 0): open-loop unstable above sqrt(f/|K_us|) = 78.5 m/s
VEH = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.2,
    mass=1500.0,
    yaw_inertia=2600.0,
    cornering_front=8.0e4,
    cornering_rear=9.5e4,
)


def _ct_poles(speed, ratio, pole, curvature=0.0, vehicle=VEH):
    """Closed-loop poles from python-control: design on the kinematic plant,
    close the loop on ct.linearize of the dynamic nlsys."""
    kin = fws.LateralPlant(vehicle, speed=speed, curvature=curvature)
    g = fws.double_root_gains(kin, ratio=ratio, pole=pole)
    nl = fws.dynamics.dynamic_path_model(vehicle, speed=speed, curvature=curvature)
    u0 = fws.dynamics.dynamic_feedforward(vehicle, speed=speed, curvature=curvature)
    x0 = [0.0, 0.0, 0.0, vehicle.rear_to_cg * curvature * speed, curvature * speed]
    lin = ct.linearize(nl, x0, u0)
    A, B = np.asarray(lin.A)[1:, 1:], np.asarray(lin.B)[1:]
    K = np.outer([1.0, ratio], [float(g.k1), float(g.k2)])
    return np.linalg.eigvals(A - B @ K @ np.eye(4)[:2])


@pytest.mark.parametrize("ratio", [-0.5, 0.0, 0.5])
def test_limits_against_python_control(ratio):
    lim = fws.kinematic_design_limit(
        VEH, ratio=ratio, pole=-1.0, speeds=np.arange(2.0, 120.0, 2.0)
    )
    for v, poles in zip(lim.speeds[::10], lim.poles[::10], strict=True):
        ref = _ct_poles(v, ratio, -1.0)
        np.testing.assert_allclose(
            np.sort_complex(poles), np.sort_complex(ref), rtol=1e-5, atol=1e-5
        )
    # the stability limit: the rightmost pole crosses zero there
    v = lim.unstable_speed
    assert 78.46 < v < 120.0  # above the open-loop critical speed
    assert np.max(_ct_poles(v - 1e-3, ratio, -1.0).real) < 0
    assert np.max(_ct_poles(v + 1e-3, ratio, -1.0).real) > 0
    # the drift limit: the two rightmost poles are tolerance*|pole| away
    v = lim.drift_speed
    p = _ct_poles(v, ratio, -1.0)
    dominant = p[np.argsort(-p.real)][:2]
    assert np.max(np.abs(dominant + 1.0)) == pytest.approx(0.25, abs=1e-5)
    assert lim.limit_speed == v
    assert np.all(lim.stable == (lim.speeds < lim.unstable_speed))


def test_schedule_plot_and_errors():
    veh = fws.vehicles.BMW_320I
    speeds = np.array([5.0, 15.0, 25.0, 35.0])
    lim = fws.kinematic_design_limit(
        veh, ratio=fws.zero_sideslip_ratio, pole=-1.0, speeds=speeds
    )
    np.testing.assert_array_equal(lim.ratio, fws.zero_sideslip_ratio(veh, speed=speeds))
    g = fws.double_root_gains(
        fws.LateralPlant(veh, speed=15.0), ratio=lim.ratio[1], pole=-1.0
    )
    assert lim.gains.k1[1] == pytest.approx(g.k1, rel=1e-12)
    cplt = lim.plot()
    assert isinstance(cplt, ct.ControlPlot)
    assert cplt.axes[0, 0].get_xlabel() == "speed V [m/s]"
    matplotlib.pyplot.close(cplt.figure)
    with pytest.raises(ValueError, match="pole must be finite and < 0"):
        fws.kinematic_design_limit(veh, ratio=0.0, pole=1.0)
    with pytest.raises(ValueError, match="speeds must be a non-empty, increasing"):
        fws.kinematic_design_limit(veh, ratio=0.0, pole=-1.0, speeds=[5.0, 3.0])
    with pytest.raises(ValueError, match="tolerance must be > 0"):
        fws.kinematic_design_limit(veh, ratio=0.0, pole=-1.0, tolerance=0.0)
    with pytest.raises(ValueError, match="mass"):
        fws.kinematic_design_limit(replace(veh, mass=None), ratio=0.0, pole=-1.0)
    with pytest.raises(TypeError):
        fws.kinematic_design_limit(veh, 0.0, -1.0)


@pytest.mark.parametrize(
    "kw, exc, arg",
    [
        (dict(speeds=[1e300]), ValueError, "speeds"),
        (dict(speeds=[1e-300, 5.0]), ValueError, "speeds"),
        (dict(tyre=np.array(["linear", "magic"])), ValueError, "tyre"),
        (dict(tyre=None), ValueError, "tyre"),
    ],
)
def test_bad_speeds_and_tyre_name_the_argument(kw, exc, arg):
    # issue 13: these failed without the argument's name (NaN tyre force,
    # an uncontrollable design at 1e-300 m/s, "truth value of an array")
    veh = fws.vehicles.BMW_320I
    with pytest.raises(exc, match=rf"\b{arg}\b"):
        fws.kinematic_design_limit(veh, ratio=0.0, pole=-2.0, **kw)
