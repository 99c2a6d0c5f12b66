"""MPCController against independent references.

* the exact ZOH discretisation against ``control.sample_system``, and the
  controller's own (closed-form) models along varying curvature too;
* the plans with the closed-form models against those with the matrix
  exponential's, to OSQP's tolerance;
* unconstrained, undelayed, long horizon: the first input equals the
  discrete LQR of the same weights (``control.dlqr``);
* the prediction over the delay equals a simulation of the linear discrete
  plant written here, and the library's delayed nonlinear simulation;
* angle and rate limits hold where the unconstrained run exceeds them;
* the zero-order hold of a sampled controller in ``simulate`` against a
  piecewise ``solve_ivp`` of the kinematic model written here;
* bad input refused (hypothesis).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import control as ct
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import fws_control as fws
from fws_control.mpc import zoh_discretize
from fws_control.simulation.compiled import available as compiled_available

# both engines run a sampled controller (the compiled one held command by
# held command, fws_control.simulation.compiled_sampled)
ENGINES = [
    "numpy",
    pytest.param(
        "compiled",
        marks=pytest.mark.skipif(
            not compiled_available(),
            reason="numba is not installed: no compiled engine",
        ),
    ),
]

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
F = VEH.wheelbase


def kinematic_matrices(speed, curvature):
    """Jacobian of the path-frame model at the feedforward point (DESIGN.md)."""
    V, k = speed, curvature
    c = 1.0 + (F * k) ** 2
    A = np.array([[0.0, V], [-V * k**2, 0.0]])
    B = np.array([[0.0, V], [c * V / F, -V / F]])
    return A, B


def discrete(speed, curvature, ts):
    A, B = kinematic_matrices(speed, curvature)
    sysd = ct.sample_system(ct.ss(A, B, np.eye(2), 0), ts, method="zoh")
    return np.asarray(sysd.A), np.asarray(sysd.B)


def test_zoh_matches_control_sample_system():
    rng = np.random.default_rng(3)
    for _ in range(5):
        A = rng.normal(size=(3, 3))
        B = rng.normal(size=(3, 2))
        Ad, Bd = zoh_discretize(A, B, 0.07)
        ref = ct.sample_system(ct.ss(A, B, np.eye(3), 0), 0.07, method="zoh")
        np.testing.assert_allclose(Ad, ref.A, rtol=0, atol=1e-13)
        np.testing.assert_allclose(Bd, ref.B, rtol=0, atol=1e-13)


@pytest.mark.parametrize("curvature", [0.0, 0.05])
@pytest.mark.parametrize("ratio", [None, -0.5])
def test_long_horizon_equals_dlqr(curvature, ratio):
    V, ts = 10.0, 0.05
    Q = np.diag([1.0, 3.0])
    Ad, Bd = discrete(V, curvature, ts)
    # 100 samples is a long horizon here: the LQR loop's poles have
    # |z| <= 0.78, so the finite-horizon first gain differs from the
    # infinite-horizon one by O(0.78^200) ~ 1e-22 (measured: the same inputs
    # to 4e-15 with 100, 150, 200 and 400 samples)
    horizon = 100
    if ratio is None:
        R = np.array([[2.0, 0.3], [0.3, 5.0]])
        K, _, E = ct.dlqr(Ad, Bd, Q, R)
        G = np.eye(2)
        mpc = fws.MPCController(
            sample_time=ts, horizon=horizon, Q=Q, R=R, tolerance=1e-9
        )
    else:
        G = np.array([[1.0], [ratio]])
        K, _, E = ct.dlqr(Ad, Bd @ G, Q, np.array([[3.0]]))
        mpc = fws.MPCController(
            sample_time=ts, horizon=horizon, Q=Q, R=3.0, ratio=ratio, tolerance=1e-9
        )
    assert np.max(np.abs(E)) ** (2 * horizon) < 1e-15
    path = fws.Arc(curvature=curvature) if curvature else fws.Straight()
    ff = np.array([math.atan(F * curvature), 0.0])
    rng = np.random.default_rng(7)
    for x in rng.normal(scale=[0.5, 0.05], size=(4, 2)):
        run = mpc.start(VEH, path, speed=V)
        u = np.array(run.step(s=3.0, e=x[0], theta=x[1]))
        ref = ff + G @ (-K @ x)
        assert run.last.status == "solved"
        np.testing.assert_allclose(u, ref, rtol=0, atol=1e-6)


def test_delay_prediction_equals_linear_discrete_plant():
    """Predicted states over the delay = the linear discrete plant, sample by
    sample, on an arc (the plant simulated here with the commands applied
    N_d samples after they were computed)."""
    V, ts, kappa, nd = 8.0, 0.04, 0.05, 6
    mpc = fws.MPCController(sample_time=ts, horizon=30, delay=nd * ts)
    assert mpc.delay_steps == nd
    Ad, Bd = discrete(V, kappa, ts)
    ff = np.array([math.atan(F * kappa), 0.0])
    run = mpc.start(VEH, fws.Arc(curvature=kappa), speed=V)
    x = np.array([0.4, -0.03])
    sent = [ff] * nd  # before the first command: the feedforward
    xs, worst = [x], 0.0
    steps = 40
    preds = []
    for k in range(steps):
        u = np.array(run.step(s=V * ts * k, e=x[0], theta=x[1]))
        np.testing.assert_allclose(run.last.sent, np.array(sent[-nd:]), atol=0)
        preds.append(run.last.delay_states.copy())
        sent.append(u)
        # the command applied over [t_k, t_k+1) was sent nd samples earlier
        x = Ad @ x + Bd @ (sent[k] - ff)
        xs.append(x)
    xs = np.array(xs)
    for k, pred in enumerate(preds):
        if k + nd <= steps:
            worst = max(worst, float(np.max(np.abs(pred - xs[k : k + nd + 1]))))
    assert worst < 1e-9, worst


@pytest.mark.parametrize("speed", [0.5, 20.0, -8.0, 100.0])
def test_delay_prediction_along_varying_curvature_equals_sample_system(speed):
    """Along the lane change's clothoids every model step has its own
    curvature: the prediction over the delay equals the linear plant of
    each step's own ``control.sample_system`` model (ZOH of the Jacobians
    written here), with the commands sent over the delay; from walking pace
    to 100 m/s (``V kappa T_s`` up to 0.16 rad), forwards and backwards."""
    ts, nd = 0.04, 12
    lane = fws.double_lane_change()
    mpc = fws.MPCController(sample_time=ts, horizon=5, delay=nd * ts)
    run = mpc.start(VEH, lane.path, speed=speed)
    x0 = np.array([0.3, -0.02])
    # inside the first clothoid (45 to 52.6 m; curvature 0 to 0.0407 1/m)
    run.step(s=48.0, e=x0[0], theta=x0[1])
    step = run.last
    kappa = step.curvature[:nd]
    assert np.ptp(kappa) > 1e-3 * min(1.0, abs(speed))  # the steps differ
    x, worst = x0, 0.0
    for j in range(nd):
        Ad, Bd = discrete(speed, kappa[j], ts)
        ff = np.array([math.atan(F * kappa[j]), 0.0])
        x = Ad @ x + Bd @ (step.sent[j] - ff)
        worst = max(worst, float(np.max(np.abs(x - step.delay_states[j + 1]))))
    assert worst < 1e-12 * max(1.0, float(np.max(np.abs(step.delay_states)))), worst


def test_closed_form_discretisation_keeps_the_expm_plans(monkeypatch):
    """The MPC's plans with its closed-form ZOH equal, to OSQP's tolerance,
    the plans of the same controller whose models come from the matrix
    exponential (:func:`zoh_discretize`), step by step along the lane change
    (curvature varying along the horizon) with the delay compensated."""
    import fws_control.mpc as mpc_module

    lane = fws.double_lane_change()
    mpc = fws.MPCController(sample_time=0.04, horizon=50, delay=0.08)

    def plans():
        run = mpc.start(VEH, lane.path, speed=20.0)
        out = []
        for k in range(40):
            run.step(s=10.0 + 0.8 * k, e=0.3 * math.sin(0.2 * k),
                     theta=0.02 * math.cos(0.3 * k))  # fmt: skip
            assert run.last.status == "solved"
            out.append(run.last.inputs.copy())
        return np.array(out)

    closed = plans()
    monkeypatch.setattr(mpc_module, "_kinematic_zoh", zoh_discretize)
    expm = plans()
    assert np.max(np.abs(closed)) > 0.01  # the plans steer
    np.testing.assert_allclose(closed, expm, rtol=0, atol=10 * mpc.tolerance)


@pytest.mark.parametrize("engine", ENGINES)
def test_delay_prediction_equals_delayed_simulation(engine):
    """On a straight path with a small offset (the model's nonlinearity is
    cubic there), the prediction over the 0.24 s delay equals the library's
    delayed nonlinear simulation to 1e-6 m; the samples align with the
    output times, so the run is replayed step by step from its outputs."""
    V, ts, nd = 10.0, 0.04, 6
    delay = nd * ts
    mpc = fws.MPCController(sample_time=ts, horizon=40, delay=delay)
    plant = fws.LateralPlant(VEH, speed=V)
    K = 100
    t = ts * np.arange(K + 1)
    res = fws.simulate(
        plant,
        fws.Straight(),
        mpc,
        initial_state=(0.0, 0.02, 0.0),
        duration=float(t[-1]),
        t_eval=t,
        delay=delay,
        engine=engine,
    )
    assert res.engine == engine and res.status == "ok"
    replay = mpc.start(VEH, fws.Straight(), speed=V)
    # the samples before the start measure the initial state
    for _ in range(nd):
        replay.step(s=0.0, e=0.02, theta=0.0)
    worst_u = worst_e = worst_theta = 0.0
    for k in range(K + 1 - nd):
        u = replay.step(s=res.s[k], e=res.e[k], theta=res.theta[k])
        # applied from t_k + delay (the output there shows the new command)
        worst_u = max(worst_u, abs(u[0] - res.delta_f[k + nd]))
        worst_u = max(worst_u, abs(u[1] - res.delta_r[k + nd]))
        pred = replay.last.delay_states
        span = slice(k, k + nd + 1)
        worst_e = max(worst_e, float(np.max(np.abs(pred[:, 0] - res.e[span]))))
        worst_theta = max(
            worst_theta, float(np.max(np.abs(pred[:, 1] - res.theta[span])))
        )
    assert worst_u < 1e-8, worst_u
    assert worst_e < 1e-6, worst_e
    assert worst_theta < 1e-6, worst_theta
    # the run converges: the compensated loop is stable at this delay
    assert abs(res.e[-1]) < 0.02 * 0.2


def _max_step(res, ts, channel):
    sig = getattr(res, channel)
    k = np.round(res.t / ts).astype(int)
    samples = sig[np.r_[True, np.diff(k) > 0]]
    return float(np.max(np.abs(np.diff(samples))))


def test_limits_hold_where_the_unconstrained_run_exceeds_them():
    V, ts = 12.0, 0.04
    plant = fws.LateralPlant(VEH, speed=V)
    path = fws.Arc(curvature=0.04)
    kw = dict(initial_state=(0.0, -1.5, 0.0), duration=6.0, dt=ts, delay=0.12)
    base = dict(sample_time=ts, horizon=40, delay=0.12, Q=np.diag([2.0, 1.0]))
    limits = dict(
        max_steer_front=0.12,
        max_steer_rear=math.radians(2.8),
        max_rate_front=0.6,
        max_rate_rear=0.2,
    )
    free = fws.simulate(plant, path, fws.MPCController(**base), **kw)
    held = fws.simulate(plant, path, fws.MPCController(**base, **limits), **kw)
    # the unconstrained run violates every limit ...
    assert np.max(np.abs(free.delta_f)) > 0.12 * 1.2
    assert np.max(np.abs(free.delta_r)) > math.radians(2.8) * 1.2
    assert _max_step(free, ts, "delta_f") > 0.6 * ts * 1.2
    assert _max_step(free, ts, "delta_r") > 0.2 * ts * 1.2
    # ... the constrained one none, at every sample
    assert held.status == "ok"
    assert np.max(np.abs(held.delta_f)) <= 0.12 + 1e-12
    assert np.max(np.abs(held.delta_r)) <= math.radians(2.8) + 1e-12
    assert _max_step(held, ts, "delta_f") <= 0.6 * ts + 1e-12
    assert _max_step(held, ts, "delta_r") <= 0.2 * ts + 1e-12
    # the limits bind, and the run still converges to the path
    assert np.max(np.abs(held.delta_r)) > math.radians(2.8) - 1e-9
    assert abs(held.e[-1]) < 0.05


def test_vehicle_limits_are_the_default_limits():
    veh = fws.Vehicle(2.7, 1.35, max_steer_front=0.1, max_steer_rear=0.02)
    run = fws.MPCController(horizon=20).start(veh, fws.Straight(), speed=10.0)
    df, dr = run.step(s=0.0, e=-4.0, theta=0.0)
    assert (df, abs(dr)) == (0.1, 0.02)
    assert np.all(np.abs(run.last.inputs[:, 0]) <= 0.1 + 1e-6)


def test_ratio_structure_steers_the_rear_in_proportion():
    run = fws.MPCController(horizon=30, ratio=-0.4).start(
        VEH, fws.Arc(curvature=0.1), speed=6.0
    )
    df, dr = run.step(s=0.0, e=0.5, theta=0.02)
    assert dr == pytest.approx(-0.4 * (df - math.atan(F * 0.1)), abs=1e-12)


@dataclass(frozen=True, eq=False)
class SampledP(fws.LateralController):
    """A sampled proportional law, to check the hold against solve_ivp."""

    sample_time: float = 0.1
    k: float = 0.2
    label = "sampled P"

    def start(self, vehicle, path, *, speed):
        law = self

        class Run:
            def step(self, *, s, e, theta):
                return -law.k * e - 0.5 * theta, 0.3 * law.k * e

        return Run()


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("delay", [0.0, 0.25])
def test_zero_order_hold_against_piecewise_solve_ivp(delay, engine):
    """Samples at k Ts measure the state (the initial one before t = 0);
    each command applies from k Ts + delay until the next: the reference
    integrates the kinematic path-frame model piece by piece here."""
    V, ts, T = 5.0, 0.1, 3.0
    ctrl = SampledP(sample_time=ts)
    plant = fws.LateralPlant(VEH, speed=V)
    t = np.linspace(0.0, T, 61)
    res = fws.simulate(
        plant,
        fws.Straight(),
        ctrl,
        initial_state=(0.0, 1.0, 0.1),
        duration=T,
        t_eval=t,
        delay=delay,
        rtol=1e-11,
        atol=1e-12,
        engine=engine,
    )
    assert res.engine == engine

    def rhs(_, z, df, dr):
        s, e, th = z
        yaw = V * math.sin(df - dr) / (F * math.cos(df))
        return [V * math.cos(th + dr), V * math.sin(th + dr), yaw]

    def law(z):
        return -0.2 * z[1] - 0.5 * z[2], 0.3 * 0.2 * z[1]

    z = np.array([0.0, 1.0, 0.1])
    # commands by application time: sample k measured at max(k ts, 0)
    nd = delay / ts
    k0 = math.floor(-nd)
    switches = [(max((k + nd) * ts, 0.0), k) for k in range(k0, 100)]
    switches = [(tt, k) for tt, k in switches if tt < T]
    measured = {}
    samples = {}
    t_cur = 0.0
    cmd = None
    ref_e = {}
    events = sorted({tt for tt, _ in switches} | {k * ts for k in range(31)})
    for tt in events:
        if tt > t_cur:
            sol = solve_ivp(
                rhs, (t_cur, tt), z, args=cmd, rtol=1e-12, atol=1e-13, dense_output=True
            )
            for tj in t[(t > t_cur) & (t <= tt + 1e-12)]:
                ref_e[round(tj, 9)] = sol.sol(tj)[1]
            z, t_cur = sol.y[:, -1], tt
        for k in range(k0, 100):
            if abs(max(k * ts, 0.0) - tt) < 1e-12 and k not in measured:
                measured[k] = True
                samples[k] = law(z)
        for sw, k in switches:
            if abs(sw - tt) < 1e-12:
                cmd = samples[k]
    got = np.array([res.e[j] for j in range(1, t.size)])
    want = np.array([ref_e[round(tj, 9)] for tj in t[1:]])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-8)


def test_batch_runs_each_keep_their_own_controller_state():
    mpc = fws.MPCController(sample_time=0.05, horizon=20, delay=0.1)
    plant = fws.LateralPlant(VEH, speed=8.0)
    x0 = np.array([[0.0, 1.0, 0.0], [0.0, -0.5, 0.05]])
    batch = fws.simulate_batch(
        plant, fws.Straight(), mpc, initial_state=x0, duration=2.0, delay=0.1
    )
    for i in range(2):
        one = fws.simulate(
            plant, fws.Straight(), mpc, initial_state=x0[i], duration=2.0, delay=0.1
        )
        np.testing.assert_allclose(batch.e[i], one.e, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.delta_r[i], one.delta_r, rtol=0, atol=1e-12)


def test_default_controllers_include_the_mpc():
    ctrls = fws.default_controllers(VEH, speed=10.0)
    mpcs = [c for c in ctrls.values() if isinstance(c, fws.MPCController)]
    assert len(mpcs) == 1


def test_missing_extra_names_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "osqp", None)
    with pytest.raises(ImportError, match="'mpc'"):
        fws.MPCController()


def test_static_interfaces_refuse():
    mpc = fws.MPCController()
    with pytest.raises(TypeError, match="sampled"):
        mpc.steering(VEH, fws.Straight(), s=0, e=0, theta=0, curvature=0, speed=5)
    with pytest.raises(TypeError, match="sampled"):
        mpc.system(VEH, fws.Straight(), speed=5.0)
    # the compiled engine holds its commands with DOP853 only
    with pytest.raises(
        ValueError, match="engine='compiled' cannot run.*sampled.*DOP853.*Radau"
    ):
        fws.simulate(
            fws.LateralPlant(VEH, speed=5.0),
            fws.Straight(),
            mpc,
            initial_state=(0, 1, 0),
            duration=1.0,
            engine="compiled",
            method="Radau",
        )


@given(st.integers(max_value=0) | st.integers(min_value=2001))
def test_bad_horizon_refused(h):
    with pytest.raises(ValueError, match=rf"horizon.*{h}"):
        fws.MPCController(horizon=h)


@given(st.floats(max_value=0.0) | st.floats(min_value=1.0, exclude_min=True))
def test_bad_sample_time_refused(ts):
    with pytest.raises(ValueError, match="sample_time"):
        fws.MPCController(sample_time=ts)


@given(
    st.sampled_from(
        ["max_steer_front", "max_steer_rear", "max_rate_front", "max_rate_rear"]
    ),
    st.floats(max_value=0.0) | st.just(math.nan) | st.just(math.inf),
)
def test_bad_limits_refused(name, value):
    with pytest.raises(ValueError, match=name):
        fws.MPCController(**{name: value})


@given(st.floats(min_value=0.001, max_value=1.0))
def test_delay_not_whole_samples_refused(delay):
    steps = delay / 0.04
    if abs(steps - round(steps)) < 1e-6:
        return  # a whole number of samples: valid (checked below)
    with pytest.raises(ValueError, match="delay"):
        fws.MPCController(sample_time=0.04, delay=delay)


def test_delay_whole_samples_accepted():
    assert fws.MPCController(sample_time=0.04, delay=0.24).delay_steps == 6
    with pytest.raises(ValueError, match="delay"):
        fws.MPCController(delay=-0.04)


@given(st.sampled_from(["Q", "R"]), st.sampled_from([-1.0, 0.0]))
def test_bad_weights_refused(name, sign):
    bad = np.diag([1.0, sign])
    if name == "Q" and sign == 0.0:
        fws.MPCController(Q=bad)  # semidefinite: valid
        return
    with pytest.raises(ValueError, match=name):
        fws.MPCController(**{name: bad})


def test_a_stopped_run_leaves_the_others_running():
    """On an open path the run that leaves it stops there (its status says
    so); the other run of the batch goes on as it does alone."""
    mpc = fws.MPCController(sample_time=0.05, horizon=20)
    plant = fws.LateralPlant(VEH, speed=10.0)
    path = fws.Straight(length=20.0)
    x0 = np.array([[1.0, 0.5, 0.0], [14.0, -0.5, 0.0]])
    kw = dict(duration=1.0, dt=0.01)
    batch = fws.simulate_batch(plant, path, mpc, initial_state=x0, **kw)
    assert list(batch.status) == ["ok", "end_of_path"]
    # the second run's rear axle reaches s = 20 after about 0.6 s
    assert 0.5 < batch.t_stop[1] < 0.7
    for i in range(2):
        one = fws.simulate(plant, path, mpc, initial_state=x0[i], **kw)
        assert one.status == batch.status[i]
        assert one.t_stop == pytest.approx(batch.t_stop[i], abs=1e-9)
        n = len(one.e)
        np.testing.assert_allclose(batch.e[i][:n], one.e, rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", ["s", "e", "theta"])
def test_step_refuses_non_finite_measurements(name):
    run = fws.MPCController(horizon=5).start(VEH, fws.Straight(), speed=5.0)
    meas = dict(s=0.0, e=0.1, theta=0.0) | {name: math.nan}
    with pytest.raises(ValueError, match=name):
        run.step(**meas)


@pytest.mark.parametrize("ts", [1e-300, -0.1, math.nan, math.inf])
def test_bad_sample_time_of_any_sampled_controller_refused(ts):
    with pytest.raises(ValueError, match="sample_time"):
        fws.simulate(
            fws.LateralPlant(VEH, speed=5.0),
            fws.Straight(),
            SampledP(sample_time=ts),
            initial_state=(0.0, 1.0, 0.0),
            duration=10.0,
        )


def test_compensation_keeps_the_delayed_lane_change_on_course():
    """docs/mpc.md: the compensating MPC completes the course with the
    largest |e| printed there; without compensation it does not complete."""
    import re
    from pathlib import Path

    text = " ".join(
        (Path(__file__).resolve().parents[1] / "docs" / "mpc.md").read_text().split()
    )
    printed = re.search(r"largest lateral error of ([\d.]+) m", text)[1]
    Q = np.diag([1.0, 4.0])
    ctrls = {
        tau: fws.MPCController(
            sample_time=0.04, horizon=50, Q=Q, R=4.0 * np.eye(2), delay=tau
        )
        for tau in (0.24, 0.0)
    }
    plant = fws.LateralPlant(VEH, speed=10.0)
    cmp = fws.compare(plant, fws.double_lane_change(), ctrls, delay=0.24)
    done = [bool(c) for c in cmp.table["completed"]]
    assert done == [True, False]
    worst = float(cmp.table["max e [m]"][0])
    assert round(worst, len(printed.split(".")[1])) == float(printed), worst
