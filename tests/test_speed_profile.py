"""Speed profiles in the simulation, against references written here.

The references integrate the global-frame models with
:func:`scipy.integrate.solve_ivp`, written from the equations (paper eqs.
8-10 for the kinematic model; the single-track model with linear tyres for
the dynamic one), with the speed an input signal ``V(t)`` or ``V(s)``, the
path projection done by hand (straight line, circle) and the control law
eqs. (24)-(29) written out. Nothing of the library's simulation is reused.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator

import fws_control as fws
from fws_control.simulation.compiled import available as compiled_available

VEH = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, friction=0.9)
DYN = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.35,
    mass=1500.0,
    yaw_inertia=2500.0,
    cornering_front=8.0e4,
    cornering_rear=9.0e4,
    friction=0.9,
)
TOL = dict(rtol=1e-12, atol=1e-12, method="DOP853")


def _arc_errors(x, y, psi, kappa):
    """(s, e, theta) of R on the arc of curvature kappa (centre (0, 1/kappa))."""
    if kappa == 0.0:
        return x, y, psi
    R = 1.0 / kappa
    phi = math.atan2(x, R - y)
    e = R - math.hypot(x, y - R)
    return R * phi, e, math.remainder(psi - phi, 2 * math.pi)


def _law(e, theta, kappa, gains, f):
    k1, k2, a = gains
    u = -k1 * e - k2 * theta
    return math.atan(kappa * f) + u, a * u


def _kinematic_reference(speed_of, gains_of, kappa, x0, t, f=2.7):
    """Global-frame kinematic model (eqs. 8-10) with V(t, s) and gains(V)."""

    def rhs(tt, z):
        x, y, psi = z
        s, e, th = _arc_errors(x, y, psi, kappa)
        V = speed_of(tt, s)
        df, dr = _law(e, th, kappa, gains_of(V), f)
        return [
            V * math.cos(psi + dr),
            V * math.sin(psi + dr),
            V * math.sin(df - dr) / (f * math.cos(df)),
        ]

    sol = solve_ivp(rhs, (t[0], t[-1]), x0, t_eval=t, dense_output=True, **TOL)
    assert sol.success
    return sol


def _dynamic_reference(speed_of, gains, kappa, x0, t, veh=DYN):
    """Single-track model with linear tyres, R's position, u = V(t, s)."""
    f, l_r = veh.wheelbase, veh.rear_to_cg
    l_f = f - l_r
    m, iz = veh.mass, veh.yaw_inertia
    cf, cr = veh.cornering_front, veh.cornering_rear

    def rhs(tt, z):
        x, y, psi, vy, r = z
        s, e, th = _arc_errors(x, y, psi, kappa)
        u = speed_of(tt, s)
        df, dr = _law(e, th, kappa, gains, f)
        af = df - math.atan2(vy + l_f * r, u)
        ar = dr - math.atan2(vy - l_r * r, u)
        ff, fr = cf * af * math.cos(df), cr * ar * math.cos(dr)
        v_r = vy - l_r * r
        return [
            u * math.cos(psi) - v_r * math.sin(psi),
            u * math.sin(psi) + v_r * math.cos(psi),
            r,
            (ff + fr) / m - u * r,
            (l_f * ff - l_r * fr) / iz,
        ]

    s0, e0, th0 = _arc_errors(*x0, kappa)
    u0 = speed_of(0.0, s0)
    df0, dr0 = _law(e0, th0, kappa, gains, f)
    r0 = u0 * (math.tan(df0) - math.tan(dr0)) / f  # rolling without slip
    vy0 = u0 * math.tan(dr0) + l_r * r0
    sol = solve_ivp(rhs, (t[0], t[-1]), [*x0, vy0, r0], t_eval=t, **TOL)
    assert sol.success
    return sol


def _path(kappa):
    return fws.Straight() if kappa == 0.0 else fws.Arc(curvature=kappa)


# --------------------------------------------------------------------------
# Against the references (1e-8 m)


# both engines: the compiled one takes the same tables
ENGINES = [
    "numpy",
    pytest.param(
        "compiled",
        marks=pytest.mark.skipif(
            not compiled_available(), reason="numba is not installed"
        ),
    ),
]


TIME_TABLE = ([0.0, 3.0, 6.0, 10.0], [22.0, 16.0, 9.0, 12.0])
TIME_GAINS = (0.004, 0.12, -0.3)


@functools.cache
def _time_profile_reference(kappa):
    """The reference of the test below (the same for both engines)."""
    pchip = PchipInterpolator(*TIME_TABLE)
    return _kinematic_reference(
        lambda tt, s: float(pchip(min(tt, 10.0))), lambda V: TIME_GAINS, kappa,
        [0.0, -1.5, 0.05], np.linspace(0.0, 10.0, 201),
    )  # fmt: skip


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("kappa", [0.0, 0.02])
def test_kinematic_time_profile_matches_reference(kappa, engine):
    t_pts, v_pts = TIME_TABLE
    prof = fws.SpeedProfile.from_time(t_pts, v_pts)
    pchip = PchipInterpolator(t_pts, v_pts)
    gains = TIME_GAINS
    t = np.linspace(0.0, 10.0, 201)
    ref = _time_profile_reference(kappa)
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=22.0), _path(kappa), fws.SteeringGains(*gains),
        initial_state=(0.0, -1.5, 0.05), duration=10.0, t_eval=t,
        speed=prof, rtol=1e-12, atol=1e-12, method="DOP853", engine=engine,
    )  # fmt: skip
    assert res.status == "ok" and res.engine == engine
    assert np.max(np.abs(res.x - ref.y[0])) < 1e-8
    assert np.max(np.abs(res.y - ref.y[1])) < 1e-8
    e_ref = [_arc_errors(*ref.y[:, k], kappa)[1] for k in range(t.size)]
    assert np.max(np.abs(res.e - e_ref)) < 1e-8
    np.testing.assert_allclose(res.longitudinal_speed, pchip(t), rtol=1e-14)
    np.testing.assert_allclose(res.longitudinal_accel, pchip(t, 1), atol=1e-12)


def test_kinematic_lateral_accel_with_varying_speed():
    """a_y of G = d(v_y)/dt + v_x r, by a central difference of the reference."""
    prof = fws.SpeedProfile.from_function(
        lambda t: 15.0 - 4.0 * np.tanh(t - 2.0),
        rate=lambda t: -4.0 / np.cosh(t - 2.0) ** 2,
    )
    gains = (0.01, 0.2, 0.4)
    t = np.linspace(0.0, 6.0, 61)
    ref = _kinematic_reference(
        lambda tt, s: 15.0 - 4.0 * math.tanh(tt - 2.0), lambda V: gains, 0.0,
        [0.0, 1.0, 0.0], t,
    )  # fmt: skip
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=15.0), fws.Straight(), fws.SteeringGains(*gains),
        initial_state=(0.0, 1.0, 0.0), duration=6.0, t_eval=t, speed=prof,
        rtol=1e-12, atol=1e-12,
    )  # fmt: skip
    f, d = 2.7, 1.35

    def body(tt):
        x, y, psi = ref.sol(tt)
        V = 15.0 - 4.0 * np.tanh(tt - 2.0)
        df, dr = (
            -gains[0] * y - gains[1] * psi,
            gains[2] * (-gains[0] * y - gains[1] * psi),
        )
        r = V * np.sin(df - dr) / (f * np.cos(df))
        return V * np.sin(dr) + d * r, V * np.cos(dr), r

    h = 1e-4
    tt = t[1:-1]
    vy_dot = (body(tt + h)[0] - body(tt - h)[0]) / (2 * h)
    _, vx, r = body(tt)
    expected = vy_dot + vx * r
    np.testing.assert_allclose(res.lateral_accel[1:-1], expected, atol=1e-6)
    # the acceleration term dV/dt v_y / V matters: eq. (13) alone misses it
    V_dot = -4.0 / np.cosh(tt - 2.0) ** 2
    assert np.max(np.abs(V_dot * body(tt)[0] / (15.0 - 4.0 * np.tanh(tt - 2.0)))) > 1e-3


DISTANCE_TABLE = ([0.0, 40.0, 90.0, 150.0], [8.0, 14.0, 14.0, 20.0])
DISTANCE_GAINS = (0.01, 0.25, -0.2)


@functools.cache
def _distance_profile_reference():
    """The reference of the test below (the same for both engines)."""
    pchip = PchipInterpolator(*DISTANCE_TABLE)

    def V(tt, s):
        return float(pchip(min(max(s, 0.0), 150.0)))

    return _kinematic_reference(
        V, lambda v: DISTANCE_GAINS, 0.01, [0.0, 0.8, 0.0], np.linspace(0.0, 8.0, 81)
    )


@pytest.mark.parametrize("engine", ENGINES)
def test_kinematic_distance_profile_matches_reference(engine):
    s_pts, v_pts = DISTANCE_TABLE
    prof = fws.SpeedProfile.from_distance(s_pts, v_pts)
    pchip = PchipInterpolator(s_pts, v_pts)
    kappa = 0.01
    gains = DISTANCE_GAINS
    t = np.linspace(0.0, 8.0, 81)
    ref = _distance_profile_reference()
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=8.0), _path(kappa), fws.SteeringGains(*gains),
        initial_state=(0.0, 0.8, 0.0), duration=8.0, t_eval=t, speed=prof,
        rtol=1e-12, atol=1e-12, method="DOP853", engine=engine,
    )  # fmt: skip
    assert res.status == "ok" and res.engine == engine
    assert np.max(np.hypot(res.x - ref.y[0], res.y - ref.y[1])) < 1e-8
    s_ref = np.array([_arc_errors(*ref.y[:, k], kappa)[0] for k in range(t.size)])
    np.testing.assert_allclose(res.longitudinal_speed, pchip(s_ref), rtol=1e-10)
    # dV/dt = V'(s) ds/dt, ds/dt by a central difference of the reference
    h = 1e-4
    sp = [_arc_errors(*ref.sol(tt + h), kappa)[0] for tt in t[1:-1]]
    sm = [_arc_errors(*ref.sol(tt - h), kappa)[0] for tt in t[1:-1]]
    s_dot = (np.array(sp) - np.array(sm)) / (2 * h)
    np.testing.assert_allclose(
        res.longitudinal_accel[1:-1], pchip(s_ref[1:-1], 1) * s_dot, atol=1e-7
    )


DYNAMIC_TABLES = {
    "time": ([0.0, 4.0, 8.0], [20.0, 14.0, 17.0]),
    "distance": ([0.0, 60.0, 150.0], [20.0, 12.0, 16.0]),
}
DYNAMIC_GAINS = (0.005, 0.15, 0.2)


@functools.cache
def _dynamic_profile_reference(kind):
    """The reference of the test below (the same for both engines)."""
    pts, vals = DYNAMIC_TABLES[kind]
    pchip = PchipInterpolator(pts, vals)

    def V(tt, s):
        x = tt if kind == "time" else s
        return float(pchip(min(max(x, pts[0]), pts[-1])))

    t = np.linspace(0.0, 8.0, 81)
    return _dynamic_reference(V, DYNAMIC_GAINS, 0.02, [0.0, 0.5, 0.0], t)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("kind", ["time", "distance"])
def test_dynamic_profile_matches_reference(kind, engine):
    kappa = 0.02
    gains = DYNAMIC_GAINS
    pts, vals = DYNAMIC_TABLES[kind]
    pchip = PchipInterpolator(pts, vals)
    prof = fws.SpeedProfile(kind, points=pts, speeds=vals)
    t = np.linspace(0.0, 8.0, 81)
    ref = _dynamic_profile_reference(kind)
    plant = fws.LateralPlant(DYN, speed=20.0, model="dynamic")
    res = fws.simulate(
        plant, _path(kappa), fws.SteeringGains(*gains),
        initial_state=(0.0, 0.5, 0.0), duration=8.0, t_eval=t, speed=prof,
        rtol=1e-12, atol=1e-12, method="DOP853", engine=engine,
    )  # fmt: skip
    assert res.status == "ok" and res.model == "dynamic" and res.engine == engine
    assert np.max(np.hypot(res.x - ref.y[0], res.y - ref.y[1])) < 1e-8
    np.testing.assert_allclose(res.v_y, ref.y[3], atol=1e-9)
    np.testing.assert_allclose(res.yaw_rate, ref.y[4], atol=1e-9)
    # longitudinal force m dV/dt and the friction circle, from the reference
    if kind == "time":
        np.testing.assert_allclose(
            res.longitudinal_force, DYN.mass * pchip(t, 1), rtol=1e-12, atol=1e-9
        )
    usage = np.hypot(res.longitudinal_accel, res.lateral_accel) / (0.9 * 9.81)
    np.testing.assert_allclose(res.friction_usage, usage, rtol=1e-14)
    assert res.friction_exceeded == bool(np.any(usage > 1.0))


# --------------------------------------------------------------------------
# A constant profile is today's constant-speed run


@pytest.mark.parametrize("engine", ["numpy", "auto"])
@pytest.mark.parametrize("model", ["kinematic", "dynamic"])
def test_constant_profile_is_the_constant_speed_run(engine, model):
    if model == "dynamic" and engine == "auto":
        engine = "numpy"  # (the dynamic model runs on numpy either way)
    plant = fws.LateralPlant(DYN, speed=12.0, model=model)
    g = fws.SteeringGains(0.01, 0.25, -0.5)
    kw = dict(initial_state=(0.0, -1.0, 0.1), duration=5.0, engine=engine)
    a = fws.simulate(plant, fws.Arc(curvature=0.05), g, **kw)
    b = fws.simulate(
        plant, fws.Arc(curvature=0.05), g, speed=fws.SpeedProfile.constant(12.0), **kw
    )
    assert a.engine == b.engine
    assert np.array_equal(a.signals, b.signals)
    assert a.peaks.lateral_accel.value == b.peaks.lateral_accel.value


def test_flat_table_is_the_constant_speed_run():
    """A table of equal speeds runs the varying-speed code: 1e-12 of today."""
    plant = fws.LateralPlant(VEH, speed=12.0)
    g = fws.SteeringGains(0.01, 0.25, -0.5)
    kw = dict(initial_state=(0.0, -1.0, 0.1), duration=5.0, engine="numpy")
    a = fws.simulate(plant, fws.Arc(curvature=0.05), g, **kw)
    b = fws.simulate(
        plant, fws.Arc(curvature=0.05), g,
        speed=fws.SpeedProfile.from_time([0.0, 5.0], [12.0, 12.0]), **kw,
    )  # fmt: skip
    assert np.max(np.abs(a.signals - b.signals)) <= 1e-12
    assert np.all(b.longitudinal_accel == 0.0)


def test_batch_with_profile_matches_single_runs():
    plant = fws.LateralPlant(VEH, speed=20.0)
    prof = fws.SpeedProfile.braking(20.0, 3.0, start=1.0, final=6.0)
    g = fws.SteeringGains(np.array([0.005, 0.01]), np.array([0.15, 0.2]), 0.0)
    kw = dict(duration=6.0, speed=prof, engine="numpy", method="DOP853")
    batch = fws.simulate_batch(
        plant, fws.Straight(), g, initial_state=(0.0, 1.0, 0.0), chunk_size=1, **kw
    )
    for i in range(2):
        one = fws.simulate(
            plant, fws.Straight(), fws.SteeringGains(g.k1[i], g.k2[i], 0.0),
            initial_state=(0.0, 1.0, 0.0), **kw,
        )  # fmt: skip
        assert np.array_equal(batch[i].signals, one.signals)
    assert batch.speed.tolist() == [20.0, 20.0]


# --------------------------------------------------------------------------
# Engines and refusals


def test_engine_choice_with_varying_speed():
    plant = fws.LateralPlant(VEH, speed=10.0)
    prof = fws.SpeedProfile.from_time([0.0, 2.0], [10.0, 12.0])
    kw = dict(initial_state=(0.0, 1.0, 0.0), duration=2.0, speed=prof)
    g = fws.SteeringGains(0.01, 0.2, 0.0)
    # a table compiles (tests/test_compiled_speed.py): "auto" chooses it
    expected = "compiled" if compiled_available() else "numpy"
    assert fws.simulate(plant, fws.Straight(), g, **kw).engine == expected
    with pytest.raises(ValueError, match="delay must be 0 with a varying speed"):
        fws.simulate(plant, fws.Straight(), g, delay=0.1, **kw)
    with pytest.raises(ValueError, match="feedforward='dynamic'"):
        fws.simulate(plant, fws.Straight(), g, feedforward="dynamic", **kw)
    with pytest.raises(ValueError, match="PurePursuit"):
        fws.simulate(plant, fws.Straight(), fws.PurePursuit(lookahead=5.0), **kw)
    with pytest.raises(TypeError, match="speed= must be None or a fws.SpeedProfile"):
        fws.simulate(plant, fws.Straight(), g, **{**kw, "speed": 12.0})


def test_dynamic_model_refuses_a_stop():
    plant = fws.LateralPlant(DYN, speed=10.0, model="dynamic")
    with pytest.raises(
        ValueError, match=r"speeds must lie in \(0, inf\).*0\.0 at index 1"
    ):
        fws.simulate(
            plant, fws.Straight(), fws.SteeringGains(0.01, 0.2, 0.0),
            initial_state=(0.0, 1.0, 0.0), duration=5.0,
            speed=fws.SpeedProfile.braking(10.0, 4.0),
        )  # fmt: skip


def test_function_profile_that_reverses_is_refused_mid_run():
    prof = fws.SpeedProfile.from_function(lambda t: 3.0 - t)
    with pytest.raises(ValueError, match=r"reversing through zero speed.*\[0, inf\)"):
        fws.simulate(
            fws.LateralPlant(VEH, speed=3.0), fws.Straight(),
            fws.SteeringGains(0.01, 0.2, 0.0), initial_state=(0.0, 1.0, 0.0),
            duration=5.0, speed=prof,
        )  # fmt: skip


def test_braking_to_a_stop_kinematic():
    """The kinematic model stops: s reaches v0^2/(2 d) on a straight line."""
    res = fws.simulate(
        fws.LateralPlant(VEH, speed=10.0), fws.Straight(),
        fws.SteeringGains(0.01, 0.2, 0.0), initial_state=(0.0, 0.0, 0.0),
        duration=4.0, speed=fws.SpeedProfile.braking(10.0, 4.0),
    )  # fmt: skip
    assert res.status == "ok"
    assert abs(res.s[-1] - 10.0**2 / (2 * 4.0)) < 1e-8
    assert res.longitudinal_speed[-1] == 0.0


# --------------------------------------------------------------------------
# Bad profiles (hypothesis)

finite = st.floats(-1e3, 1e3, allow_nan=False)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.lists(st.floats(0.1, 50.0), min_size=2, max_size=6), st.data())
def test_sign_change_is_refused(speeds, data):
    i = data.draw(st.integers(0, len(speeds) - 1))
    bad = list(speeds)
    bad[i] = -data.draw(st.floats(0.1, 50.0))
    with pytest.raises(ValueError, match=r"speeds must not change sign.*at index"):
        fws.SpeedProfile.from_time(np.arange(len(bad), dtype=float), bad)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.lists(finite, min_size=2, max_size=6, unique=True))
def test_non_monotone_table_is_refused(points):
    pts = sorted(points)[::-1]  # strictly decreasing
    with pytest.raises(
        ValueError, match=r"points \(times \[s\]\) must be strictly increasing"
    ):
        fws.SpeedProfile.from_time(pts, [5.0] * len(pts))


@settings(max_examples=40, deadline=None, derandomize=True)
@given(
    st.integers(2, 6),
    st.sampled_from([math.nan, math.inf, -math.inf]),
    st.booleans(),
    st.data(),
)
def test_non_finite_table_is_refused(n, value, in_speeds, data):
    i = data.draw(st.integers(0, n - 1))
    pts, vals = list(np.arange(n, dtype=float)), [5.0] * n
    (vals if in_speeds else pts)[i] = value
    name = "speeds" if in_speeds else "points"
    with pytest.raises(ValueError, match=name):
        fws.SpeedProfile.from_distance(pts, vals)


@settings(
    max_examples=30, deadline=None, derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)  # fmt: skip
@given(
    st.one_of(
        st.floats(allow_nan=True, allow_infinity=True).filter(
            lambda v: not (0.0 < v <= 1e6)
        ),
    ),
    st.floats(0.1, 20.0),
)
def test_bad_braking_is_refused(v0, decel):
    with pytest.raises(ValueError, match="v0"):
        fws.SpeedProfile.braking(v0, decel)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(st.floats(allow_nan=True, allow_infinity=True).filter(lambda v: not v > 0.0))
def test_bad_deceleration_is_refused(decel):
    with pytest.raises(ValueError, match="decel"):
        fws.SpeedProfile.braking(20.0, decel)


def test_constant_zero_and_too_fast_are_refused():
    with pytest.raises(ValueError, match="one nonzero speed"):
        fws.SpeedProfile.constant(0.0)
    with pytest.raises(ValueError, match=r"speeds must lie in \[-1e\+06, 1e\+06\]"):
        fws.SpeedProfile.from_time([0.0, 1.0], [5.0, 2e6])
    with pytest.raises(TypeError, match="function must be callable"):
        fws.SpeedProfile("time", function=3.0)
    with pytest.raises(ValueError, match="of must be one of"):
        fws.SpeedProfile("space", speeds=[3.0])


def test_pchip_stays_within_the_table():
    """Shape preservation: no overshoot, so no reversal between the points."""
    pts = [0.0, 1.0, 1.2, 5.0, 5.1, 9.0]
    vals = [10.0, 10.0, 0.0, 0.0, 20.0, 20.0]
    prof = fws.SpeedProfile.from_time(pts, vals)
    x = np.linspace(-1.0, 10.0, 20001)
    v = prof(x)
    assert v.min() >= 0.0 and v.max() <= 20.0
    # C1: the derivative is continuous at the points (one-sided limits)
    for p in pts[1:-1]:
        assert abs(prof.derivative(p - 1e-9) - prof.derivative(p + 1e-9)) < 1e-3


# --------------------------------------------------------------------------
# Gains that follow the speed during the run


def _table_gains(speeds, k1, k2, a):
    """GainSchedule.at written out: k1 V^2, k2 V and a linear in V."""
    sp = np.asarray(speeds)

    def gains_of(V):
        return (
            np.interp(V, sp, np.asarray(k1) * sp**2) / V**2,
            np.interp(V, sp, np.asarray(k2) * sp) / V,
            np.interp(V, sp, np.asarray(a)),
        )

    return gains_of


def _braking_schedule():
    """The zero-sideslip double-root schedule and the braking of the test below."""
    sch = fws.GainSchedule.double_root(
        DYN, speeds=np.linspace(6.0, 24.0, 10), pole=-1.2,
        ratio=fws.zero_sideslip_ratio,
    )  # fmt: skip
    prof = fws.SpeedProfile.braking(22.0, 4.0, start=0.5, final=8.0)
    return sch, prof, _table_gains(sch.speeds, sch.k1, sch.k2, sch.ratio)


@functools.cache
def _braking_schedule_reference():
    """The reference of the test below (the same for both engines)."""
    _, prof, gains_of = _braking_schedule()
    return _kinematic_reference(
        lambda tt, s: float(prof(tt)), lambda V: tuple(map(float, gains_of(V))),
        0.02, [0.0, -1.0, 0.0], np.linspace(0.0, 5.0, 501),
    )  # fmt: skip


@pytest.mark.parametrize("engine", ENGINES)
def test_gain_schedule_during_the_run_matches_reference(engine):
    """A braking run with gains and a(V) of the zero-sideslip double root."""
    sch, prof, gains_of = _braking_schedule()
    # a(V) changes sign inside the run: the 4WS phase switches
    assert sch.ratio[0] < 0.0 < sch.ratio[-1]
    t = np.linspace(0.0, 5.0, 501)
    kappa = 0.02
    ref = _braking_schedule_reference()
    res = fws.simulate(
        fws.LateralPlant(DYN, speed=22.0), _path(kappa), sch,
        initial_state=(0.0, -1.0, 0.0), duration=5.0, t_eval=t, speed=prof,
        rtol=1e-12, atol=1e-12, method="DOP853", engine=engine,
    )  # fmt: skip
    assert res.status == "ok" and res.engine == engine
    assert np.max(np.hypot(res.x - ref.y[0], res.y - ref.y[1])) < 1e-8
    # the applied ratio follows a(V(t)) (away from e = theta = 0, where
    # delta_r / (delta_f - feedforward) is 0/0)
    u = res.delta_f - math.atan(kappa * 2.7)
    big = np.abs(u) > 1e-3
    np.testing.assert_allclose(
        (res.delta_r / u)[big], gains_of(res.longitudinal_speed)[2][big], rtol=1e-9
    )
    # the recorded gains are the schedule's at the initial speed
    assert res.ratio == pytest.approx(float(gains_of(22.0)[2]), rel=1e-14)
    # the rate includes d(gains)/dt: a central difference of the samples
    rate_fd = np.gradient(res.delta_r, t, edge_order=2)
    inner = slice(5, -5)
    # dV/dt jumps where the braking starts and ends
    kinks = (np.abs(t - 0.5) < 0.03) | (np.abs(t - 4.0) < 0.03)
    ok = ~kinks[inner]
    np.testing.assert_allclose(
        res.delta_r_rate[inner][ok], rate_fd[inner][ok], atol=2e-5
    )


def test_user_function_schedule_with_rear_limit():
    """A user's gain function, clipped by the rear angle limit after it."""
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, max_steer_rear=0.01)

    def rule(V):
        V = np.asarray(V, dtype=float)
        return fws.SteeringGains(1.5 / V**2, 3.0 / V, 0.9 - 0.05 * V)

    prof = fws.SpeedProfile.from_time([0.0, 6.0], [6.0, 24.0])
    t = np.linspace(0.0, 6.0, 121)

    def law(e, th, V):
        g = rule(V)
        u = -g.k1 * e - g.k2 * th
        return float(u), float(np.clip(g.ratio * u, -0.01, 0.01))

    pchip = PchipInterpolator([0.0, 6.0], [6.0, 24.0])

    def rhs(tt, z):
        x, y, psi = z
        V = float(pchip(tt))
        df, dr = law(y, psi, V)
        return [
            V * math.cos(psi + dr),
            V * math.sin(psi + dr),
            V * math.sin(df - dr) / (2.7 * math.cos(df)),
        ]

    ref = solve_ivp(rhs, (0.0, 6.0), [0.0, 1.5, 0.0], t_eval=t, **TOL)
    with pytest.warns(RuntimeWarning, match="not compiled and runs on the numpy"):
        res = fws.simulate(
            fws.LateralPlant(veh, speed=6.0), fws.Straight(), rule,
            initial_state=(0.0, 1.5, 0.0), duration=6.0, t_eval=t, speed=prof,
            rtol=1e-12, atol=1e-12, method="DOP853",
        )  # fmt: skip
    assert res.engine == "numpy"
    assert np.max(np.abs(res.y - ref.y[1])) < 1e-8
    assert np.max(np.abs(res.delta_r)) == pytest.approx(0.01, abs=1e-15)
    # the ratio a(V) = 0.9 - 0.05 V changes sign at 18 m/s
    assert np.any(res.delta_r > 0.0) and np.any(res.delta_r < 0.0)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    st.lists(st.floats(0.5, 40.0), min_size=2, max_size=5),
    st.floats(-40.0, 0.0),
    st.data(),
)
def test_dynamic_model_refuses_non_positive_speeds(speeds, low, data):
    """u > 0 everywhere: a 0 or a negative table is refused, naming its index."""
    i = data.draw(st.integers(0, len(speeds) - 1))
    vals = [low] * len(speeds) if low < 0.0 else list(speeds)
    vals[i] = low
    prof = fws.SpeedProfile.from_time(np.arange(len(vals), dtype=float), vals)
    first = int(np.flatnonzero(np.asarray(vals) <= 0.0)[0])
    with pytest.raises(ValueError, match=rf"\(0, inf\).* at index {first}"):
        fws.simulate(
            fws.LateralPlant(DYN, speed=10.0, model="dynamic"), fws.Straight(),
            fws.SteeringGains(0.01, 0.2, 0.0), initial_state=(0.0, 1.0, 0.0),
            duration=1.0, speed=prof,
        )  # fmt: skip


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_function_profile_returning_non_finite_is_refused(bad):
    prof = fws.SpeedProfile.from_function(lambda t: np.where(t < 0.5, 5.0, bad))
    with pytest.raises(ValueError, match=rf"returned {bad!r} at time \[s\]"):
        fws.simulate(
            fws.LateralPlant(VEH, speed=5.0), fws.Straight(),
            fws.SteeringGains(0.01, 0.2, 0.0), initial_state=(0.0, 1.0, 0.0),
            duration=1.0, speed=prof,
        )  # fmt: skip


def test_batch_refuses_an_array_plant_speed_with_a_profile():
    with pytest.raises(ValueError, match="plant.speed must be one number"):
        fws.simulate_batch(
            fws.LateralPlant(VEH, speed=np.array([5.0, 6.0])), fws.Straight(),
            fws.SteeringGains(0.01, 0.2, 0.0), initial_state=(0.0, 1.0, 0.0),
            duration=1.0, speed=fws.SpeedProfile.from_time([0, 1], [5.0, 6.0]),
        )  # fmt: skip
