"""Fast engine vs python-control reference, eq. (13) vs finite differences,
singular runs, limits, and the result object."""

import math

import control as ct
import matplotlib.pyplot as plt
import numpy as np
import pytest
from conftest import PAPER_VEHICLE
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control.paths import AmbiguousProjectionError, Arc, Clothoid, Straight

VEH = PAPER_VEHICLE
TIGHT = {
    "solve_ivp_method": "DOP853",
    "solve_ivp_kwargs": {"rtol": 1e-10, "atol": 1e-12},
}

# The paper's scenarios (section 4.3): (speed, curvature, y0, feedforward)
SCENARIOS = {
    "straight_5": (5.0, 0.0, 2.0, False),
    "curve_5": (5.0, 0.1, -5.0, True),
    "straight_20": (20.0, 0.0, 2.0, False),
    "curve_20": (20.0, 0.01, -10.0, True),
}


def _path(kappa):
    return Straight() if kappa == 0 else Arc(curvature=kappa)


def _reference(vehicle, path, gains, speed, x0, t, feedforward=True, **kw):
    sys = fws.closed_loop_system(
        vehicle, path, gains, speed=speed, feedforward=feedforward, **kw
    )
    resp = ct.input_output_response(sys, t, initial_state=x0, **TIGHT)
    return dict(zip(sys.output_labels, resp.outputs, strict=True))


# On a straight (kappa = 0) the paper's model and the kinematic one coincide:
# the designs give the same gains, hence the same runs, so the "paper" design
# is run on the curves only.
@pytest.mark.parametrize(
    "name, model",
    [(name, "kinematic") for name in SCENARIOS]
    + [(name, "paper") for name in SCENARIOS if SCENARIOS[name][1] != 0.0],
)
def test_fast_engine_agrees_with_interconnected_reference(name, model):
    V, kappa, y0, ff = SCENARIOS[name]
    path = _path(kappa)
    ratios = [-1.0, -0.5, 0.0, 0.5] + ([1.0] if kappa else [])
    for a in ratios:
        g = fws.double_root_gains(
            VEH, speed=V, curvature=kappa, ratio=a, pole=-1.0, model=model
        )
        if kappa == 0.0:  # why the straight runs once (see above)
            paper = fws.double_root_gains(
                VEH, speed=V, curvature=kappa, ratio=a, pole=-1.0, model="paper"
            )
            assert paper == g
        res = fws.simulate(
            fws.LateralPlant(VEH, speed=V),
            path,
            g,
            initial_state=(0.0, y0, 0.0),
            # 8 s: |e| is down to 1e-3 of its start, and on the 5 m/s curve
            # psi has passed pi (3.5 rad), so its branch is still checked
            duration=8.0,
            feedforward=ff,
            dt=0.05,
        )
        if not res.ok:
            # a = 1 on the curves: huge gains drive |delta_f| to pi/2, at once at
            # 5 m/s (t_stop = 0) and after a few hundredths of a second at 20 m/s
            assert res.status == "singular_steering" and a == 1.0
            df0 = math.atan(2.7 * kappa) * ff - g.k1 * res.e[0] - g.k2 * res.theta[0]
            if res.t_stop == 0.0:
                assert abs(df0) >= math.pi / 2
                continue
            # the reference (global frame) heads for the same singularity
            t_ref = np.linspace(0.0, 0.999 * res.t_stop, 21)
            ref = _reference(VEH, path, g, V, [0.0, y0, 0.0], t_ref, ff)
            near = fws.simulate(
                fws.LateralPlant(VEH, speed=V),
                path,
                g,
                initial_state=(0.0, y0, 0.0),
                duration=t_ref[-1],
                feedforward=ff,
                t_eval=t_ref,
            )
            np.testing.assert_allclose(near.e, ref["e"], rtol=0, atol=1e-6)
            assert abs(ref["delta_f"][-1]) > math.pi / 2 - 0.1
            continue
        ref = _reference(VEH, path, g, V, [0.0, y0, 0.0], res.t, ff)
        np.testing.assert_allclose(res.e, ref["e"], rtol=0, atol=1e-6)
        np.testing.assert_allclose(res.theta, ref["theta"], rtol=0, atol=1e-6)
        np.testing.assert_allclose(res.x, ref["x"], rtol=0, atol=1e-6)
        np.testing.assert_allclose(res.y, ref["y"], rtol=0, atol=1e-6)
        # psi: continuous, same branch as the global model's integral
        np.testing.assert_allclose(res.psi, ref["psi"], rtol=0, atol=1e-8)
        np.testing.assert_allclose(res.delta_f, ref["delta_f"], rtol=0, atol=1e-7)
        np.testing.assert_allclose(res.delta_r, ref["delta_r"], rtol=0, atol=1e-7)


def test_front_steering_matches_independent_kinematic_single_track():
    """Global-frame model with delta_r = 0 vs psi' = V tan(delta)/f."""
    V, f = 7.0, VEH.wheelbase

    def delta(t):
        return 0.4 * np.sin(0.8 * t) + 0.1

    def single_track(t, z):
        return [V * np.cos(z[2]), V * np.sin(z[2]), V * np.tan(delta(t)) / f]

    t = np.linspace(0.0, 12.0, 241)
    z0 = [1.0, -2.0, 0.3]
    ind = solve_ivp(single_track, (0, 12), z0, t_eval=t, rtol=1e-11, atol=1e-12)
    sys = fws.global_frame_model(VEH, speed=V)
    u = np.vstack([delta(t), np.zeros_like(t)])
    # the input is interpolated linearly by python-control: use a fine grid
    tf = np.linspace(0.0, 12.0, 48001)
    uf = np.vstack([delta(tf), np.zeros_like(tf)])
    # (the response evaluated at the 241 times of the reference only: its
    # output at every one of the 48001 input times costs seconds)
    resp = ct.input_output_response(
        sys, tf, inputs=uf, initial_state=z0, evaluation_times=t, **TIGHT
    )
    assert u.shape == (2, t.size)
    np.testing.assert_allclose(resp.time, t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(resp.states, ind.y, atol=2e-6)


def _fd_lateral_accel(res, d):
    """Lateral acceleration of G from 5-point second differences of its position.

    Returns values at ``res.t[2:-2]``.
    """
    xg = res.x + d * np.cos(res.psi)
    yg = res.y + d * np.sin(res.psi)
    h = res.t[1] - res.t[0]

    def d2(z):
        return (-z[4:] + 16 * z[3:-1] - 30 * z[2:-2] + 16 * z[1:-3] - z[:-4]) / (
            12 * h**2
        )

    psi = res.psi[2:-2]
    return -d2(xg) * np.sin(psi) + d2(yg) * np.cos(psi)


@pytest.mark.parametrize(
    "path, V, x0, ff",
    [
        (Arc(curvature=0.1), 5.0, (0.0, -5.0, 0.0), True),
        (Straight(), 20.0, (0.0, 2.0, 0.0), False),
        # varying curvature: exercises the f*kappa'(s)*s_dot term of the rate
        (Clothoid(0.0, 0.08, length=200.0), 6.0, (1.0, -1.5, 0.2), True),
    ],
)
def test_lateral_acceleration_and_rates_match_finite_differences(path, V, x0, ff):
    g = fws.SteeringGains(k1=0.15, k2=0.8, ratio=-0.5)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=V),
        path,
        g,
        initial_state=x0,
        duration=8.0,
        feedforward=ff,
        dt=2e-3,
    )
    assert res.ok
    fd = _fd_lateral_accel(res, VEH.rear_to_cg)
    scale = np.max(np.abs(res.lateral_accel))
    np.testing.assert_allclose(res.lateral_accel[2:-2], fd, atol=1e-6 * scale + 5e-6)
    for name in ("delta_f", "delta_r"):
        sig = getattr(res, name)
        # 4th-order central difference
        fd_rate = (-sig[4:] + 8 * sig[3:-1] - 8 * sig[1:-3] + sig[:-4]) / (12 * 2e-3)
        rate = getattr(res, f"{name}_rate")[2:-2]
        np.testing.assert_allclose(rate, fd_rate, atol=1e-6 * np.max(np.abs(rate)))


def test_singular_steering_at_start_is_reported_not_raised():
    # paper gains at 5 m/s, a = 0.5, pole -2: k1*e0 > pi/2
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.0, ratio=0.5, pole=-2.0)
    assert g.k1 * 2.0 > math.pi / 2
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Straight(),
        g,
        initial_state=(0.0, 2.0, 0.0),
        duration=10.0,
        feedforward=False,
    )
    assert res.status == "singular_steering" and res.singular and not res.ok
    assert res.t_stop == 0.0 and res.t.tolist() == [0.0]
    assert res.delta_f[0] == pytest.approx(-g.k1 * 2.0)
    assert np.isnan(res.lateral_accel[0])  # eq. (13) is undefined there
    assert "pi/2" in res.message


def test_singular_steering_during_run_stops_there():
    # k2 < 0 feeds the heading back positively: delta_f runs to pi/2
    g = fws.SteeringGains(k1=0.1, k2=-0.5, ratio=0.0)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Straight(),
        g,
        initial_state=(0.0, 1.0, 0.0),
        duration=10.0,
        feedforward=False,
    )
    assert res.status == "singular_steering"
    assert 0.0 < res.t_stop < 10.0
    assert res.t[-1] <= res.t_stop < res.t[-1] + 0.01 + 1e-12
    assert np.all(np.abs(res.delta_f) < math.pi / 2)
    # the data before the stop are the reference's
    ref = _reference(VEH, Straight(), g, 5.0, [0.0, 1.0, 0.0], res.t[:-5], False)
    np.testing.assert_allclose(res.e[:-5], ref["e"], atol=1e-6)


def test_singular_curvature_when_driving_into_the_centre():
    # no steering, heading +y from (0, 5) towards the centre (0, 10) of the
    # circle: 1 - kappa*e = 0 after 5 m, i.e. at t = 1 s; both engines stop
    # at the margin 1 - kappa e = 1e-3, after 4.99 m: t = 0.998 s
    g = fws.SteeringGains(0.0, 0.0, 0.0)
    from fws_control.simulation.compiled import available

    engines = [("numpy", 0.998)]
    if available():  # numba (extra "fast")
        engines.append(("compiled", 0.998))
    else:
        print("numba is not installed: the compiled engine's stop not tested")
    for engine, stop in engines:
        res = fws.simulate(
            fws.LateralPlant(VEH, speed=5.0),
            Arc(0.1),
            g,
            initial_state=(0.0, 5.0, math.pi / 2),
            duration=3.0,
            feedforward=False,
            engine=engine,
        )
        assert res.status == "singular_curvature"
        assert res.t_stop == pytest.approx(stop, abs=1e-9)
    np.testing.assert_allclose(res.y, 5.0 + 5.0 * res.t, atol=1e-9)


def test_end_of_open_path():
    g = fws.SteeringGains(0.0, 0.0, 0.0)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Straight(length=20.0),
        g,
        initial_state=(0.0, 1.0, 0.0),
        duration=10.0,
        feedforward=False,
    )
    assert res.status == "end_of_path"
    assert res.t_stop == pytest.approx(4.0, abs=1e-6)  # s = V t reaches 20 m
    np.testing.assert_allclose(res.s, 5.0 * res.t, atol=1e-9)


def test_angle_saturation_agrees_with_reference():
    lim = fws.Vehicle(2.7, 1.35, max_steer_front=0.15, max_steer_rear=0.05)
    g = fws.double_root_gains(lim, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    res = fws.simulate(
        fws.LateralPlant(lim, speed=5.0),
        Arc(0.1),
        g,
        initial_state=(0.0, -5.0, 0.0),
        duration=10.0,
        dt=0.05,
    )
    assert res.ok
    assert np.max(res.delta_f) == pytest.approx(0.15)  # saturation is active
    assert np.min(res.delta_r) == pytest.approx(-0.05)
    ref = _reference(lim, Arc(0.1), g, 5.0, [0.0, -5.0, 0.0], res.t)
    np.testing.assert_allclose(res.e, ref["e"], atol=1e-6)


def test_rate_limited_actuator_agrees_with_reference_and_limits_rates():
    lim = fws.Vehicle(2.7, 1.35, max_steer_rate_front=0.2, max_steer_rate_rear=0.1)
    g = fws.double_root_gains(lim, speed=5.0, curvature=0.0, ratio=-0.5, pole=-1.0)
    x0 = (0.0, 2.0, 0.0)
    res = fws.simulate(
        fws.LateralPlant(lim, speed=5.0, steering_lag=0.1),
        Straight(),
        g,
        initial_state=x0,
        # 5 s: the rates are clipped from 0.12 s to 0.62 s, then decay freely
        duration=5.0,
        feedforward=False,
        dt=1e-3,
    )
    assert res.ok
    assert np.max(np.abs(res.delta_f_rate)) == pytest.approx(0.2)
    assert np.max(np.abs(res.delta_r_rate)) == pytest.approx(0.1)
    # actuator starts at the command: delta(0) = command(0)
    assert res.delta_f[0] == pytest.approx(-g.k1 * 2.0)
    # reference: actuator block states appended after the vehicle's
    x0_ref = [*x0, -g.k1 * 2.0, -g.ratio * g.k1 * 2.0]
    ref = _reference(
        lim, Straight(), g, 5.0, x0_ref, res.t[::50], False, steering_lag=0.1
    )
    np.testing.assert_allclose(res.e[::50], ref["e"], atol=1e-6)
    fd = _fd_lateral_accel(res, lim.rear_to_cg)
    # eq. (13) uses the actuator rates; the rate is only piecewise smooth, so
    # compare away from the switching instants of the clip
    rf = res.delta_f_rate[2:-2]
    rr = res.delta_r_rate[2:-2]
    smooth = (np.abs(np.abs(rf) - 0.2) > 1e-3) & (np.abs(np.abs(rr) - 0.1) > 1e-3)
    np.testing.assert_allclose(res.lateral_accel[2:-2][smooth], fd[smooth], atol=1e-4)


def test_psi_keeps_the_given_branch_and_is_continuous():
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    psi0 = 2 * math.pi + 0.1
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(0.1),
        g,
        initial_state=(0.0, -5.0, psi0),
        duration=20.0,
    )
    assert res.psi[0] == pytest.approx(psi0)
    assert np.max(np.abs(np.diff(res.psi))) < 0.05
    assert res.theta[0] == pytest.approx(0.1)
    # more than one lap (heading of the path wraps); psi grows like kappa*V*t
    assert res.psi[-1] - res.psi[0] > 2 * math.pi


def _curve_run(**kw):
    g = fws.double_root_gains(VEH, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    args = {"initial_state": (0.0, -5.0, 0.0), "duration": 5.0}
    args.update(kw)
    return g, fws.simulate(fws.LateralPlant(VEH, speed=5.0), Arc(0.1), g, **args)


def test_simulate_is_a_squeezed_batch_of_one():
    g, res = _curve_run(dt=0.1)
    batch = fws.simulate_batch(
        fws.LateralPlant(VEH, speed=5.0),
        Arc(0.1),
        g,
        initial_state=(0.0, -5.0, 0.0),
        duration=5.0,
        dt=0.1,
    )
    # simulate squeezes; simulate_batch never does, even for one run
    assert res.squeeze and not batch.squeeze
    assert len(res) == len(batch) == 1
    assert (
        res.signals.shape == batch.signals.shape == (1, len(fws.simulation.SIGNALS), 51)
    )
    for name in fws.simulation.SIGNALS:
        assert getattr(res, name).shape == (51,)
        assert getattr(batch, name).shape == (1, 51)
        np.testing.assert_array_equal(getattr(res, name), getattr(batch, name)[0])
    assert res.status == "ok" and isinstance(res.status, str)
    assert batch.status.tolist() == ["ok"]
    assert res.ok is True and batch.ok.tolist() == [True]
    assert isinstance(res.t_stop, float) and res.t_stop == 5.0
    assert (res.speed, res.k1, res.k2, res.ratio) == (5.0, g.k1, g.k2, g.ratio)
    assert res.gains == g and res.message == ""
    np.testing.assert_array_equal(res.initial_state, [0.0, -5.0, 0.0])
    assert batch.initial_state.shape == (1, 3)
    # indexing a squeezed result gives the run again
    np.testing.assert_array_equal(res[0].e, res.e)
    np.testing.assert_array_equal(res[-1].t, res.t)
    assert [r.status for r in res] == ["ok"] and len(res.runs) == 1
    with pytest.raises(IndexError):
        res[1]


def test_squeezed_stopped_run_ends_at_its_stop_and_the_batch_keeps_the_grid():
    g = fws.SteeringGains(k1=0.1, k2=-0.5, ratio=0.0)  # delta_f runs to pi/2
    kw = {"initial_state": (0.0, 1.0, 0.0), "duration": 10.0}
    plant = fws.LateralPlant(VEH, speed=5.0)
    res = fws.simulate(plant, Straight(), g, feedforward=False, **kw)
    batch = fws.simulate_batch(plant, Straight(), g, feedforward=False, **kw)
    assert res.status == "singular_steering"
    grid = np.linspace(0.0, 10.0, 1001)
    np.testing.assert_array_equal(batch.t, grid)
    # the squeezed run keeps exactly the output times up to its stop
    np.testing.assert_array_equal(res.t, grid[grid <= res.t_stop])
    n = res.t.size
    np.testing.assert_array_equal(res.e, batch.e[0, :n])
    assert np.all(np.isnan(batch.e[0, n:])) and np.all(np.isfinite(res.e))


def test_to_pandas_of_one_run():
    g, res = _curve_run(dt=0.1)
    df = res.to_pandas()
    signals = list(fws.simulation.SIGNALS)
    assert list(df.columns) == [
        "run",
        "t",
        *signals,
        "status",
        "t_stop",
        "speed",
        "k1",
        "k2",
        "ratio",
        "message",
        "feedforward",
        "method",
    ]
    assert len(df) == res.t.size == 51
    np.testing.assert_array_equal(df["t"], res.t)
    for name in signals:
        np.testing.assert_array_equal(df[name], getattr(res, name))
    assert set(df["run"]) == {0} and set(df["status"]) == {"ok"}
    assert set(df["speed"]) == {5.0} and set(df["t_stop"]) == {5.0}
    assert (set(df["k1"]), set(df["k2"]), set(df["ratio"])) == (
        {g.k1},
        {g.k2},
        {g.ratio},
    )
    assert df.attrs["feedforward"] is True
    assert set(df["feedforward"]) == {True} and set(df["method"]) == {"DOP853"}
    assert set(df["message"]) == {""}


def test_plot_of_one_run_returns_controlplot_and_reuses_axes():
    g, res = _curve_run(dt=0.1)
    cplt = res.plot(labels="a=-1")
    try:
        assert isinstance(cplt, ct.ControlPlot)
        assert cplt.axes.shape == (3, 2) and cplt.lines.shape == (3, 2)
        ylabels = [ax.get_ylabel() for ax in cplt.axes.flat]
        assert ylabels[0] == "lateral error e [m]"
        assert ylabels[3] == "front steering δf [deg]"
        # steering is drawn in degrees, over time
        line = cplt.lines[1, 1][0]
        np.testing.assert_allclose(line.get_xdata(), res.t)
        np.testing.assert_allclose(line.get_ydata(), np.degrees(res.delta_f))
        # the trajectory panel: the run's (x, y) and the dashed path
        xy = cplt.lines[1, 0]
        np.testing.assert_allclose(xy[0].get_ydata(), res.y)
        assert xy[-1].get_label() == "path"
        legend = [t.get_text() for t in cplt.axes[0, 0].get_legend().get_texts()]
        assert legend == ["a=-1"]
        # overlay a second run into the same axes
        _, other = _curve_run(dt=0.1, initial_state=(0.0, -3.0, 0.0))
        again = other.plot(ax=cplt.axes, labels="e0=-3")
        assert again.figure is cplt.figure
        assert all(a is b for a, b in zip(again.axes.flat, cplt.axes.flat, strict=True))
        np.testing.assert_allclose(again.lines[0, 0][0].get_ydata(), other.e)
        assert len(cplt.axes[0, 0].get_lines()) == 2
        with pytest.raises(ValueError, match="6 matplotlib axes"):
            res.plot(ax=cplt.axes.flat[:5])
        with pytest.raises(ValueError, match="one label per run"):
            res.plot(labels=["a", "b"])
    finally:
        plt.close("all")


def test_to_time_response_matches_the_python_control_reference():
    # 2.5 s: the conversion does not depend on the duration, and the
    # reference costs seconds per simulated second
    g, res = _curve_run(dt=0.05, duration=2.5)
    resp = res.to_time_response()
    assert isinstance(resp, ct.TimeResponseData)
    assert resp.output_labels == list(fws.simulation.SIGNALS)
    n_signals = len(fws.simulation.SIGNALS)
    assert resp.ntraces == 0 and resp.outputs.shape == (n_signals, res.t.size)
    assert resp.success and resp.params["k1"] == g.k1
    np.testing.assert_array_equal(resp.time, res.t)
    # the same signals, by name, as the interconnected reference's response
    ref_sys = fws.closed_loop_system(VEH, Arc(0.1), g, speed=5.0)
    ref = ct.input_output_response(ref_sys, res.t, initial_state=[0, -5, 0], **TIGHT)
    for name in ("x", "y", "psi", "s", "e", "theta", "delta_f", "delta_r"):
        mine = resp.outputs[resp.output_labels.index(name)]
        theirs = ref.outputs[ref.output_labels.index(name)]
        np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-6)
    # python-control plots it: one panel per signal, the data of the result
    cplt = ct.time_response_plot(resp)
    try:
        assert isinstance(cplt, ct.ControlPlot) and cplt.axes.shape == (n_signals, 1)
        e_row = resp.output_labels.index("e")
        np.testing.assert_allclose(cplt.lines[e_row, 0][0].get_ydata(), res.e)
    finally:
        plt.close("all")


def test_invalid_arguments():
    g = fws.SteeringGains(0.1, 0.5, 0.0)
    kw = {"initial_state": (0, 1, 0), "duration": 5.0}
    plant = fws.LateralPlant(VEH, speed=5.0)
    # everything after the gains is keyword-only: a positional call fails
    with pytest.raises(TypeError):
        fws.simulate(plant, Straight(), g, (0, 1, 0), 5.0)
    with pytest.raises(TypeError):
        fws.closed_loop_system(VEH, Straight(), g, 5.0)
    with pytest.raises(TypeError, match="path"):
        fws.simulate(plant, "straight", g, **kw)
    with pytest.raises(TypeError, match="plant"):
        fws.simulate((2.7, 1.35), Straight(), g, **kw)
    with pytest.raises(ValueError, match="speed"):
        fws.simulate(fws.LateralPlant(VEH, speed=0.0), Straight(), g, **kw)
    with pytest.raises(ValueError, match="duration"):
        fws.simulate(plant, Straight(), g, **{**kw, "duration": -1.0})
    with pytest.raises(ValueError, match="initial_state"):
        fws.simulate(plant, Straight(), g, **{**kw, "initial_state": (0, 1)})
    with pytest.raises(ValueError, match="simulate_batch"):
        fws.simulate(plant, Straight(), fws.SteeringGains([0.1, 0.2], 0.5, 0.0), **kw)
    with pytest.raises(ValueError, match="simulate_batch"):
        fws.simulate(fws.LateralPlant(VEH, speed=[5.0, 6.0]), Straight(), g, **kw)
    with pytest.raises(ValueError, match="simulate_batch"):
        fws.simulate(plant, Straight(), g, **{**kw, "initial_state": [(0, 1, 0)] * 2})
    with pytest.raises(ValueError, match="t_eval"):
        fws.simulate(plant, Straight(), g, **kw, t_eval=[0.0, 6.0])
    with pytest.raises(ValueError, match="method must be one of"):
        fws.simulate(plant, Straight(), g, **kw, method="Euler")
    with pytest.raises(ValueError, match="rtol"):
        fws.simulate(plant, Straight(), g, **kw, rtol=0.0)
    with pytest.raises(AmbiguousProjectionError):
        fws.simulate(
            plant, Arc(0.1), g, **{**kw, "initial_state": (0.0, 10.0, 0.0)}
        )  # the centre of the circle


@pytest.mark.parametrize("kappa", [0.0, 0.05])
def test_reversing_agrees_with_interconnected_reference(kappa):
    """V < 0: gains designed for reversing; both engines must agree."""
    V, path = -3.0, _path(kappa)
    g = fws.double_root_gains(VEH, speed=V, curvature=kappa, ratio=-0.5, pole=-0.8)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=V),
        path,
        g,
        initial_state=(0.0, -1.0, 0.1),
        duration=8.0,
        dt=0.05,
    )
    assert res.ok and res.s[-1] < -10.0  # it really drove backwards
    ref = _reference(VEH, path, g, V, [0.0, -1.0, 0.1], res.t)
    np.testing.assert_allclose(res.e, ref["e"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(res.theta, ref["theta"], rtol=0, atol=1e-6)
    # the reversing design converges: |e| decays like exp(-0.8 t) * poly(t)
    assert abs(res.e[-1]) < 0.05 * abs(res.e[0])


_G13 = fws.SteeringGains(0.1, 0.5, ratio=0.0)


@pytest.mark.parametrize(
    "func, kw, exc, arg",
    [
        (fws.simulate, dict(duration=[1.0, 2.0]), ValueError, "duration"),
        (fws.simulate, dict(dt=np.eye(2)), ValueError, "dt"),
        # a (front, rear) pair of different lags: one time constant is simulated
        (fws.simulate, dict(steering_lag=[0.1, 0.2]), ValueError, "steering_lag"),
        (fws.simulate, dict(delay=1e-300), ValueError, "delay"),
        (fws.simulate_batch, dict(chunk_size=math.inf), ValueError, "chunk_size"),
        (fws.simulate_batch, dict(chunk_size=math.nan), ValueError, "chunk_size"),
        (fws.simulate_batch, dict(progress=1 + 2j), TypeError, "progress"),
        (
            fws.simulate_batch,
            dict(progress=np.array([True, False])),
            TypeError,
            "progress",
        ),  # fmt: skip
        (fws.closed_loop_system, dict(delay=1e-300), ValueError, "delay"),
        (
            fws.closed_loop_system,
            dict(steering_lag=[0.1]),
            ValueError,
            "steering_lag",
        ),  # fmt: skip
    ],
)
def test_issue13_bad_run_options_name_the_argument(func, kw, exc, arg):
    # before: float() of an array, OverflowError for chunk_size=inf, a
    # progress flag read by its truth value, a hang (simulate) or a
    # ZeroDivisionError in control.pade (closed_loop_system) for 1e-300 s
    if func is fws.closed_loop_system:
        with pytest.raises(exc, match=rf"\b{arg}\b"):
            func(VEH, Straight(), _G13, speed=5.0, **kw)
        return
    kw = dict(kw)
    plant = fws.LateralPlant(VEH, speed=5.0, steering_lag=kw.pop("steering_lag", None))
    base = dict(initial_state=(0.0, 1.0, 0.0), duration=2.0, dt=0.1)
    with pytest.raises(exc, match=rf"\b{arg}\b"):
        func(plant, Straight(), _G13, **{**base, **kw})


def test_delay_floor_is_duration_over_1e4():
    # the floor is duration / 1e4 (each forced step costs about 1.7 ms of
    # Python right-hand sides: 1e4 steps about 17 s): 2 s / 1e4 = 2e-4 s
    kw = dict(initial_state=(0.0, 1.0, 0.0), duration=2.0, dt=0.1)
    with pytest.raises(
        ValueError, match=r"delay must be 0 or >= duration/10000 = 0.0002 s"
    ):
        fws.simulate(
            fws.LateralPlant(VEH, speed=5.0), Straight(), _G13, delay=1.9e-4, **kw
        )
