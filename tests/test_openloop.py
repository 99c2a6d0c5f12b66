"""Open-loop tests (ISO 7401, ISO 4138) of the dynamic single-track model.

References, all independent of :mod:`fws_control.openloop`:

* the textbook linear single-track model, written here from its equations
  (Abe, *Vehicle Handling Dynamics*, ch. 3; axle cornering stiffnesses
  ``C_f, C_r`` of whole axles, the convention of :class:`fws_control.Vehicle`),
  and python-control's ``step_response``, ``forced_response`` and
  ``frequency_response`` of it;
* the exact step response ``C A^-1 (e^{At} - I) B + D`` (``scipy.linalg.expm``)
  with its level crossings and peak found by ``brentq``;
* ``scipy.integrate.solve_ivp`` of :func:`fws_control.dynamics.body_derivatives`
  and a first harmonic taken by quadrature (``np.trapezoid``);
* the closed-form understeer gradient ``m/f (l_r/C_f - l_f/C_r)`` and the
  zero-sideslip ratio written from its formula.
"""

from __future__ import annotations

import dataclasses
import math

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

import fws_control as fws
from fws_control.dynamics import body_derivatives

BMW = fws.vehicles.BMW_320I
#: An understeering car (l_r/C_f > l_f/C_r) whose yaw rate overshoots.
UNDER = fws.Vehicle(
    wheelbase=2.7,
    rear_to_cg=1.5,
    mass=1500.0,
    yaw_inertia=2600.0,
    cornering_front=8e4,
    cornering_rear=9.5e4,
    friction=1.0,
)


def textbook(veh: fws.Vehicle, u: float, a: float) -> ct.StateSpace:
    """Linear single-track model, states (v_y, r), input delta_f, outputs (r, a_y)."""
    m, iz = veh.mass, veh.yaw_inertia
    lr = veh.rear_to_cg
    lf = veh.wheelbase - lr
    cf, cr = veh.cornering_front, veh.cornering_rear
    A = np.array(
        [
            [-(cf + cr) / (m * u), -u - (lf * cf - lr * cr) / (m * u)],
            [-(lf * cf - lr * cr) / (iz * u), -(lf**2 * cf + lr**2 * cr) / (iz * u)],
        ]
    )
    B = np.array([[(cf + a * cr) / m], [(lf * cf - a * lr * cr) / iz]])
    # a_y = v_y_dot + u r
    C = np.array([[0.0, 1.0], [A[0, 0], A[0, 1] + u]])
    D = np.array([[0.0], [B[0, 0]]])
    return ct.ss(A, B, C, D)


def zero_sideslip(veh: fws.Vehicle, u: float) -> float:
    """a(V) of Sano et al. written from the formula."""
    m = veh.mass
    lr = veh.rear_to_cg
    f = veh.wheelbase
    lf = f - lr
    cf, cr = veh.cornering_front, veh.cornering_rear
    return (-lr + m * lf * u**2 / (f * cr)) / (lf + m * lr * u**2 / (f * cf))


CASES = [
    (BMW, 20.0, 0.0),
    (BMW, 20.0, "zero"),
    (UNDER, 30.0, 0.0),
    (UNDER, 15.0, "zero"),
]


def _ratio(veh, u, spec):
    """(argument passed to the library, value used in the textbook model)."""
    if spec == "zero":
        return fws.zero_sideslip_ratio, zero_sideslip(veh, u)
    return spec, spec


# --------------------------------------------------------------------------
# linear model


@pytest.mark.parametrize("veh, u, spec", CASES)
def test_system_is_the_textbook_model(veh, u, spec):
    arg, a = _ratio(veh, u, spec)
    sys = fws.steering_response_system(veh, speed=u, ratio=arg)
    ref = textbook(veh, u, a)
    for name in "ABCD":
        got, want = getattr(sys, name), getattr(ref, name)
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("veh, u, spec", CASES)
def test_linear_step_equals_step_response(veh, u, spec):
    arg, a = _ratio(veh, u, spec)
    amp = 0.02
    res = fws.step_steer(
        veh, speed=u, amplitude=amp, ratio=arg, steer_rate=math.inf, duration=3.0
    )
    assert res.time[0] == 0.0 and np.all(res.delta_f == amp)
    ref = ct.step_response(textbook(veh, u, a), T=res.time)
    r_ref, ay_ref = amp * ref.outputs[0, 0], amp * ref.outputs[1, 0]
    assert np.max(np.abs(res.yaw_rate - r_ref)) <= 1e-9 * np.max(np.abs(r_ref))
    assert np.max(np.abs(res.lateral_acceleration - ay_ref)) <= 1e-9 * np.max(
        np.abs(ay_ref)
    )
    assert np.allclose(res.delta_r, a * res.delta_f, rtol=1e-14, atol=0.0)


@pytest.mark.parametrize("veh, u, spec", CASES)
def test_linear_ramp_equals_forced_response(veh, u, spec):
    arg, a = _ratio(veh, u, spec)
    amp, rate = -0.03, 0.4
    res = fws.step_steer(veh, speed=u, amplitude=amp, ratio=arg, steer_rate=rate)
    # the ramp written here: from 0 at -T/2 to amp at T/2, T = |amp|/rate
    ramp = abs(amp) / rate
    delta = amp * np.clip((res.time + ramp / 2) / ramp, 0.0, 1.0)
    assert np.allclose(res.delta_f, delta, rtol=0.0, atol=1e-15)
    assert res.time[0] == pytest.approx(-ramp / 2, rel=1e-12)
    assert np.min(np.abs(res.time)) < 1e-12  # 50 % of the angle at t = 0
    ref = ct.forced_response(textbook(veh, u, a), res.time - res.time[0], delta)
    for got, want in ((res.yaw_rate, ref.outputs[0]), (res.lateral_acceleration,
                                                       ref.outputs[1])):  # fmt: skip
        assert np.max(np.abs(got - want)) <= 1e-9 * np.max(np.abs(want))


def _exact_metrics(sys: ct.StateSpace, row: int, amp: float):
    """ISO values of an ideal step from the exact solution (expm, brentq)."""
    A, B, C, D = sys.A, sys.B, sys.C[row], sys.D[row, 0]
    a_inv = np.linalg.inv(A)

    def y(t):
        return amp * float(C @ a_inv @ (expm(A * t) - np.eye(2)) @ B[:, 0] + D)

    def dy(t):
        return amp * float(C @ expm(A * t) @ B[:, 0])

    ss = amp * float(-C @ a_inv @ B[:, 0] + D)
    t_grid = np.linspace(0.0, 4.0, 4001)
    # The grid only brackets the crossings and the peak that brentq then
    # finds with y and dy (expm). On the grid, e^{At} of the 2x2 matrix in
    # closed form, vectorised (8000 expm calls cost seconds): with s = tr/2,
    # q = sqrt(s^2 - det), e^{At} = e^{st} (cosh(qt) I + sinh(qt)/q (A - sI)).
    s = 0.5 * np.trace(A)
    q = np.sqrt(complex(s * s - np.linalg.det(A)))
    qt = q * t_grid[:, None, None]
    phi = np.exp(s * t_grid)[:, None, None] * (
        np.cosh(qt) * np.eye(2) + np.sinh(qt) / q * (A - s * np.eye(2))
    )
    vals = amp * ((C @ a_inv) @ (phi.real - np.eye(2)) @ B[:, 0] + D) / ss
    # ... and it is the same function as y (expm) on a few of its points
    some = t_grid[::500]
    assert np.allclose(vals[::500], [y(t) / ss for t in some], rtol=0, atol=1e-12)

    def first(level):
        i = int(np.argmax(vals >= level))
        if i == 0:
            return 0.0
        return brentq(lambda t: y(t) / ss - level, t_grid[i - 1], t_grid[i],
                      xtol=1e-14)  # fmt: skip

    t90, t10 = first(0.9), first(0.1)
    k = int(np.argmax(vals))
    if vals[k] > 1.0 + 1e-6 and 0 < k < t_grid.size - 1:
        tp = brentq(dy, t_grid[k - 1], t_grid[k + 1], xtol=1e-14)
        over = y(tp) / ss - 1.0
    else:
        tp, over = math.inf, 0.0
    return ss, t90, t90 - t10, tp, over


@pytest.mark.parametrize("veh, u, spec", CASES)
def test_iso_values_of_an_ideal_step(veh, u, spec):
    arg, a = _ratio(veh, u, spec)
    amp = 0.01
    res = fws.step_steer(
        veh, speed=u, amplitude=amp, ratio=arg, steer_rate=math.inf, duration=4.0
    )
    sys = textbook(veh, u, a)
    for row, m in ((0, res.yaw_rate_metrics), (1, res.lateral_acceleration_metrics)):
        ss, t90, rise, tp, over = _exact_metrics(sys, row, amp)
        assert m.steady_state == pytest.approx(ss, rel=1e-12)
        assert m.response_time == pytest.approx(t90, abs=2e-6)
        assert m.rise_time == pytest.approx(rise, abs=2e-6)
        if math.isinf(tp):
            assert math.isinf(m.peak_response_time) and m.overshoot == 0.0
        else:
            # the parabola through three samples: a flat peak is found to
            # about dt^2 / (10 ms)
            assert m.peak_response_time == pytest.approx(tp, abs=1e-5)
            assert m.overshoot == pytest.approx(over, abs=1e-8)
            assert m.peak == pytest.approx(ss * (1.0 + over), rel=1e-8)


def test_understeering_car_overshoots():
    """The understeering car's yaw rate peaks (complex poles) -- not vacuous."""
    res = fws.step_steer(UNDER, speed=30.0, amplitude=0.01, steer_rate=math.inf)
    poles = np.linalg.eigvals(textbook(UNDER, 30.0, 0.0).A)
    assert np.all(np.abs(poles.imag) > 0.5)
    assert res.yaw_rate_metrics.overshoot > 0.01
    assert math.isfinite(res.yaw_rate_metrics.peak_response_time)


def test_default_ramp_is_the_iso_limit():
    amp = 0.02
    res = fws.step_steer(BMW, speed=20.0, amplitude=amp)
    # 10 % and 90 % of the angle, 0.15 s apart (ISO 7401's largest time)
    t10 = np.interp(0.1 * amp, res.delta_f[res.time < 0.5], res.time[res.time < 0.5])
    t90 = np.interp(0.9 * amp, res.delta_f[res.time < 0.5], res.time[res.time < 0.5])
    assert t90 - t10 == pytest.approx(0.15, rel=1e-9)
    assert res.steer_rate == pytest.approx(0.8 * amp / 0.15, rel=1e-14)


# --------------------------------------------------------------------------
# nonlinear model


def _solve_ivp_step(veh, u, amp, a, ramp, tyre, t):
    def rhs(time, x):
        df = amp * min(max((time + ramp / 2) / ramp, 0.0), 1.0)
        return body_derivatives(veh, x[0], x[1], df, a * df, speed=u, tyre=tyre)

    # not stiff (poles near -11 1/s at 20 m/s): the explicit DOP853 with the
    # same tolerances agrees with Radau to 3e-11 relative at a quarter of the
    # cost; max_step still resolves the ramp's corners
    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0], t_eval=t, method="DOP853",
                    rtol=1e-11, atol=1e-14, max_step=ramp / 50)  # fmt: skip
    return sol.y


@pytest.mark.parametrize("tyre", ["linear", "magic"])
def test_nonlinear_step_against_solve_ivp(tyre):
    u, amp = 20.0, 0.05
    a = zero_sideslip(BMW, u)
    res = fws.step_steer(
        BMW, speed=u, amplitude=amp, ratio=fws.zero_sideslip_ratio,
        model="nonlinear", tyre=tyre, duration=2.0, dt=2e-3,
    )  # fmt: skip
    ramp = amp / res.steer_rate
    v_y, r = _solve_ivp_step(BMW, u, amp, a, ramp, tyre, res.time)
    assert np.max(np.abs(res.yaw_rate - r)) <= 1e-7 * np.max(np.abs(r))
    assert np.max(np.abs(res.lateral_velocity - v_y)) <= 1e-7 * np.max(np.abs(r)) * u
    # a_y = v_y_dot + u r of the reference states
    vy_dot, _ = body_derivatives(
        BMW, v_y, r, res.delta_f, res.delta_r, speed=u, tyre=tyre
    )
    ay = vy_dot + u * r
    assert np.max(np.abs(res.lateral_acceleration - ay)) <= 1e-6 * np.max(ay)
    # the steady values: body derivatives zero at the final angles (fsolve)
    v_ss, r_ss = fsolve(
        lambda x: body_derivatives(BMW, x[0], x[1], amp, a * amp, speed=u, tyre=tyre),
        [v_y[-1], r[-1]],
        xtol=1e-14,
    )
    assert res.yaw_rate_metrics.steady_state == pytest.approx(r_ss, rel=1e-10)
    assert res.lateral_acceleration_metrics.steady_state == pytest.approx(
        u * r_ss, rel=1e-10
    )


def test_small_nonlinear_step_is_linear():
    amp = 1e-5
    lin = fws.step_steer(UNDER, speed=30.0, amplitude=amp, steer_rate=math.inf)
    nl = fws.step_steer(UNDER, speed=30.0, amplitude=amp, steer_rate=math.inf,
                        model="nonlinear")  # fmt: skip
    scale = np.max(np.abs(lin.yaw_rate))
    assert np.max(np.abs(nl.yaw_rate - lin.yaw_rate)) <= 1e-6 * scale
    for name in ("response_time", "rise_time", "peak_response_time"):
        assert getattr(nl.yaw_rate_metrics, name) == pytest.approx(
            getattr(lin.yaw_rate_metrics, name), abs=1e-5
        )


# --------------------------------------------------------------------------
# frequency response

OMEGA = np.array([0.5, 2.0, 8.0, 25.0])


@pytest.mark.parametrize("veh, u, spec", CASES)
def test_linear_frequency_response_equals_python_control(veh, u, spec):
    arg, a = _ratio(veh, u, spec)
    w = np.geomspace(0.1, 100.0, 40)
    fr = fws.steering_frequency_response(veh, speed=u, omega=w, ratio=arg)
    ref = ct.frequency_response(textbook(veh, u, a), w)
    h = ref.complex  # (outputs, inputs, omega)
    for k, (gain, phase) in enumerate(
        (
            (fr.yaw_rate_gain, fr.yaw_rate_phase),
            (fr.lateral_acceleration_gain, fr.lateral_acceleration_phase),
        )
    ):
        want = h[k, 0]
        assert np.allclose(gain, np.abs(want), rtol=1e-9, atol=0.0)
        got = gain * np.exp(1j * phase)
        assert np.max(np.abs(got - want) / np.abs(want)) <= 1e-9
        # unwrapped: continuous along omega, on (-pi, pi] at the first point
        assert -math.pi < phase[0] <= math.pi
        assert np.all(np.abs(np.diff(phase)) < math.pi)


#: Stated tolerance of the stepped sines at small amplitude against the
#: linear model (RK4 at 60 steps per period, 15 time constants of settling):
#: measured about 1e-7.
SWEEP_RTOL = 1e-6


@pytest.mark.parametrize("spec", [0.0, "zero"])
def test_small_sweep_matches_linear(spec):
    u = 20.0
    arg, _ = _ratio(BMW, u, spec)
    lin = fws.steering_frequency_response(BMW, speed=u, omega=OMEGA, ratio=arg)
    nl = fws.steering_frequency_response(
        BMW, speed=u, omega=OMEGA, ratio=arg, model="nonlinear", amplitude=1e-5
    )
    for g_nl, g_lin in ((nl.yaw_rate_gain, lin.yaw_rate_gain),
                        (nl.lateral_acceleration_gain,
                         lin.lateral_acceleration_gain)):  # fmt: skip
        assert np.allclose(g_nl, g_lin, rtol=SWEEP_RTOL, atol=0.0)
    for p_nl, p_lin in ((nl.yaw_rate_phase, lin.yaw_rate_phase),
                        (nl.lateral_acceleration_phase,
                         lin.lateral_acceleration_phase)):  # fmt: skip
        assert np.allclose(p_nl, p_lin, rtol=0.0, atol=SWEEP_RTOL)


def _harmonic_ivp(veh, u, amp, a, w, tyre, settle, periods):
    """First harmonic of r and a_y by solve_ivp and quadrature over whole periods."""
    period = 2 * math.pi / w
    t_end = settle + periods * period

    def rhs(time, x):
        df = amp * math.sin(w * time)
        return body_derivatives(veh, x[0], x[1], df, a * df, speed=u, tyre=tyre)

    t = np.linspace(t_end - periods * period, t_end, 4001)
    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0], t_eval=t, method="DOP853",
                    rtol=1e-12, atol=1e-14)  # fmt: skip
    v_y, r = sol.y
    df = amp * np.sin(w * t)
    vy_dot, _ = body_derivatives(veh, v_y, r, df, a * df, speed=u, tyre=tyre)
    out = []
    for y in (r, vy_dot + u * r):
        s = 2 / (periods * period) * np.trapezoid(y * np.sin(w * t), t)
        c = 2 / (periods * period) * np.trapezoid(y * np.cos(w * t), t)
        out.append(complex(s, c) / amp)
    return out


def test_large_sweep_against_solve_ivp_and_gain_drop():
    u, amp = 20.0, 0.06
    w = np.array([8.0, 25.0])
    lin = fws.steering_frequency_response(BMW, speed=u, omega=w)
    nl = fws.steering_frequency_response(
        BMW, speed=u, omega=w, model="nonlinear", tyre="magic", amplitude=amp,
        settle=3.0,
    )  # fmt: skip
    for k in range(w.size):
        h_r, h_a = _harmonic_ivp(BMW, u, amp, 0.0, w[k], "magic", 3.0, 2)
        assert nl.yaw_rate_gain[k] == pytest.approx(abs(h_r), rel=1e-5)
        assert nl.lateral_acceleration_gain[k] == pytest.approx(abs(h_a), rel=1e-5)
        assert np.angle(np.exp(1j * (nl.yaw_rate_phase[k] - np.angle(h_r)))) == (
            pytest.approx(0.0, abs=1e-5)
        )
    # the saturating tyre: the lateral-acceleration gain drops by over 5 %
    drop = nl.lateral_acceleration_gain / lin.lateral_acceleration_gain
    assert np.all(drop < 0.95)
    # ... and the linear tyre at the same amplitude does not lose 1 %
    same = fws.steering_frequency_response(
        BMW, speed=u, omega=w, model="nonlinear", amplitude=amp, settle=3.0
    )
    assert np.all(np.abs(same.lateral_acceleration_gain / lin.lateral_acceleration_gain
                         - 1.0) < 0.01)  # fmt: skip


# --------------------------------------------------------------------------
# ISO 4138 constant radius


def _k_closed_form(veh):
    m, f = veh.mass, veh.wheelbase
    lr = veh.rear_to_cg
    return m / f * (lr / veh.cornering_front - (f - lr) / veh.cornering_rear)


@pytest.mark.parametrize(
    "veh",
    [
        UNDER,
        dataclasses.replace(UNDER, rear_to_cg=1.2),  # oversteer
        BMW,  # neutral: the closed form is 0 up to rounding
    ],
)
def test_understeer_gradient_closed_form(veh):
    k = _k_closed_form(veh)
    c = fws.steady_state_circle(
        veh, radius=1e6, lateral_acceleration=[1e-3], tyre="linear"
    )
    # each term of the closed form sets the scale of the tolerance
    scale = veh.mass * veh.rear_to_cg / (veh.wheelbase * veh.cornering_front)
    assert abs(c.understeer_gradient[0] - k) <= 1e-9 * scale
    if abs(k) > 1e-6 * scale:
        assert c.understeer_gradient[0] == pytest.approx(k, rel=1e-9)


def test_circle_states_are_steady_on_the_circle():
    ay = np.array([1.0, 4.0, 7.0, 9.5])
    for ratio in (0.0, fws.zero_sideslip_ratio):
        c = fws.steady_state_circle(
            BMW, radius=100.0, lateral_acceleration=ay, ratio=ratio
        )
        a = c.ratio
        if ratio is not fws.zero_sideslip_ratio:
            assert np.all(a == 0.0)
        else:
            assert np.allclose(a, [zero_sideslip(BMW, v) for v in c.speed], rtol=1e-12)
        assert np.allclose(c.delta_r, a * c.delta_f, rtol=1e-14)
        for i in range(ay.size):
            d = body_derivatives(
                BMW, c.lateral_velocity[i], c.yaw_rate[i], c.delta_f[i],
                c.delta_r[i], speed=c.speed[i], tyre="magic",
            )  # fmt: skip
            assert np.max(np.abs(d)) <= 1e-9
        assert np.allclose(c.speed * c.yaw_rate, ay, rtol=1e-14)
        assert np.allclose(
            np.hypot(c.speed, c.lateral_velocity), c.yaw_rate * 100.0, rtol=1e-12
        )
        # the understeer gradient is the slope of delta_f(a_y): a finite
        # difference of a second, denser solve agrees
        dense = fws.steady_state_circle(
            BMW, radius=100.0, lateral_acceleration=[6.99, 7.01], ratio=ratio
        )
        slope = np.diff(dense.delta_f)[0] / 0.02
        assert c.understeer_gradient[2] == pytest.approx(slope, rel=1e-4)


def test_zero_sideslip_ratio_cancels_sideslip_at_small_acceleration():
    ay = [1e-3]
    front = fws.steady_state_circle(
        UNDER, radius=1e5, lateral_acceleration=ay, tyre="linear"
    )
    zero = fws.steady_state_circle(
        UNDER, radius=1e5, lateral_acceleration=ay, tyre="linear",
        ratio=fws.zero_sideslip_ratio,
    )  # fmt: skip
    assert abs(front.sideslip[0]) > 1e-6
    assert abs(zero.sideslip[0]) <= 1e-7 * abs(front.sideslip[0])


def test_circle_beyond_the_limit_is_refused():
    with pytest.raises(ValueError, match="lateral_acceleration=12.0"):
        fws.steady_state_circle(BMW, radius=100.0, lateral_acceleration=[5.0, 12.0])


def test_step_beyond_the_tyres_is_refused():
    # 0.2 rad at 20 m/s needs about 3 g
    with pytest.raises(ValueError, match="no steady state"):
        fws.step_steer(BMW, speed=20.0, amplitude=0.2, model="nonlinear",
                       tyre="magic")  # fmt: skip


def test_unstable_speed_is_refused():
    over = dataclasses.replace(UNDER, rear_to_cg=1.2)
    v_crit = math.sqrt(-over.wheelbase / _k_closed_form(over))
    with pytest.raises(ValueError, match="unstable"):
        fws.steering_frequency_response(over, speed=1.1 * v_crit, omega=[1.0])
    with pytest.raises(ValueError, match="unstable"):
        fws.step_steer(over, speed=1.1 * v_crit, amplitude=0.001)


# --------------------------------------------------------------------------
# bad input

BAD = st.sampled_from(
    [math.nan, math.inf, -1.0, 0.0, 1e300, True, 1 + 2j, None, "1", [1.0, 2.0]]
)


def _named(exc, name):
    assert name in str(exc.value), str(exc.value)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(
    name=st.sampled_from(
        ["speed", "amplitude", "steer_rate", "duration", "dt", "ratio", "model", "tyre"]
    ),  # fmt: skip
    value=BAD,
)
def test_step_steer_bad_input(name, value):
    kw = dict(speed=20.0, amplitude=0.01, duration=1.0)
    kw[name] = value
    if name == "steer_rate" and value == 1e300:
        return  # a valid, very fast ramp
    if name == "ratio" and value in (-1.0, 0.0):
        return  # valid ratios
    with pytest.raises((ValueError, TypeError)) as exc:
        fws.step_steer(BMW, **kw)
    _named(exc, name)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(
    name=st.sampled_from(
        ["speed", "omega", "amplitude", "periods", "settle", "ratio", "model"]
    ),  # fmt: skip
    value=BAD,
)
def test_frequency_response_bad_input(name, value):
    kw = dict(speed=20.0, omega=[1.0, 5.0])
    kw[name] = value
    if name == "ratio" and value in (-1.0, 0.0):
        return
    if name == "omega" and isinstance(value, list):
        return  # a valid grid
    with pytest.raises((ValueError, TypeError)) as exc:
        fws.steering_frequency_response(BMW, **kw)
    _named(exc, name)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(
    name=st.sampled_from(["lateral_acceleration", "radius", "ratio", "tyre"]),
    value=BAD,
)
def test_circle_bad_input(name, value):
    kw = dict(lateral_acceleration=[1.0, 2.0], radius=100.0)
    kw[name] = value
    if name == "ratio" and value in (-1.0, 0.0):
        return
    with pytest.raises((ValueError, TypeError)) as exc:
        fws.steady_state_circle(BMW, **kw)
    _named(exc, name)


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda: fws.step_steer(BMW, speed=20.0, amplitude=0.01, tyre="magic"),
         "tyre"),
        (lambda: fws.steering_frequency_response(BMW, speed=20.0, omega=[2.0, 1.0]),
         "omega"),
        (lambda: fws.steering_frequency_response(BMW, speed=20.0, omega=[[1.0]]),
         "omega"),
        (lambda: fws.steady_state_circle(BMW, lateral_acceleration=[2.0, 2.0]),
         "lateral_acceleration"),
        (lambda: fws.step_steer(BMW, speed=20.0, amplitude=0.01, ratio=11.0),
         "ratio"),
        (lambda: fws.steering_response_system(fws.Vehicle(wheelbase=2.7), speed=5.0),
         "mass"),
        (lambda: fws.step_steer(BMW, speed=20.0, amplitude=0.01, duration=600.0,
                                dt=1e-6), "duration"),
        (lambda: fws.step_steer(BMW, speed=20.0, amplitude=0.01,
                                steer_rate=1e-300), "steer_rate"),
    ],
)  # fmt: skip
def test_targeted_bad_input(call, name):
    with pytest.raises((ValueError, TypeError)) as exc:
        call()
    _named(exc, name)


def test_results_are_frozen():
    res = fws.step_steer(BMW, speed=20.0, amplitude=0.01, duration=1.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.speed = 1.0  # type: ignore[misc]


def test_nonlinear_step_equals_the_library_nlsys():
    """The same ramp through ct.input_output_response of dynamic_global_model."""
    u, amp = 20.0, 0.04
    a = zero_sideslip(BMW, u)
    res = fws.step_steer(
        BMW, speed=u, amplitude=amp, ratio=a, model="nonlinear", tyre="magic",
        duration=1.5, dt=2e-3,
    )  # fmt: skip
    sys = fws.dynamics.dynamic_global_model(BMW, speed=u, tyre="magic")
    # the ramp's corners are samples, so linear interpolation of U is exact
    out = ct.input_output_response(
        sys, res.time - res.time[0], np.vstack([res.delta_f, a * res.delta_f]),
        # DOP853: not stiff (see _solve_ivp_step); agrees with Radau to 3e-12
        X0=np.zeros(5), solve_ivp_method="DOP853",
        solve_ivp_kwargs=dict(rtol=1e-11, atol=1e-14, max_step=0.005),
    )  # fmt: skip
    v_y, r = out.states[3], out.states[4]
    assert np.max(np.abs(res.yaw_rate - r)) <= 1e-7 * np.max(np.abs(r))
    assert np.max(np.abs(res.lateral_velocity - v_y)) <= 1e-7 * u * np.max(np.abs(r))
