r"""The model and control-law equations, each written once.

Small plain functions of numbers: no argument checks, no objects, no
package imports (only numpy), so that every layer of the package can call
them. Each function works in two worlds with the same text:

- on numpy arrays, broadcasting, in the analysis and in the numpy engine
  (:mod:`fws_control.simulation.engine`);
- compiled unchanged by ``numba.njit`` on float scalars, in the compiled
  engine (:mod:`fws_control.simulation.compiled`), which therefore computes
  the same operations in the same order.

The results are equal bit for bit where numpy's elementary functions round
as the C library does, which numba calls. numpy's own AVX-512 loops for
``arctan``, ``tan``, ``exp`` and ``arctan2`` differ from the C library by
1 ulp on some arguments (0.2-7 % of random ones on a Cascade Lake CPU), so
on such a CPU the two engines agree to rounding, as any two integrations
do, not bit for bit; ``NPY_DISABLE_CPU_FEATURES`` set to numpy's dispatched
targets before numpy's import restores the C library's rounding
(``tests/test_equations.py`` compares that way).

For that they use only operations that both numpy and numba give for arrays
and scalars alike (``np.sin``, ``np.cos``, ``np.arctan``, ``np.arctan2``,
arithmetic) and no Python ``if`` on a value. The checks (finite inputs, the
singular steering angle :math:`|\delta_f| = \pi/2`, the centre of curvature
:math:`1 - \kappa e = 0`) belong to the callers.
:mod:`fws_control.symbolic` re-derives the equations with sympy and is the
independent reference for them (``tests/test_equations.py``).

Symbols (paper names): :math:`V` `speed`, :math:`f` `wheelbase`, :math:`d`
(:math:`l_r`) `rear_to_cg`, :math:`l_f` `front_to_cg`, :math:`\kappa_C`
`curvature`, :math:`e_C, \theta_C` `e`, `theta`, :math:`a` `ratio`.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np

#: A float, or an array of them broadcasting with the other arguments (numba
#: compiles the same functions on float scalars).
Real: TypeAlias = "float | np.ndarray"

__all__ = [
    "MAGIC_SHAPE",
    "yaw_rate",
    "global_frame_derivatives",
    "path_frame_derivatives",
    "cg_lateral_velocity",
    "yaw_acceleration",
    "lateral_acceleration",
    "feedforward_angle",
    "feedforward_angle_rate",
    "feedback_angle",
    "feedback_command",
    "unscaled_gains",
    "steering_law",
    "steering_law_rate",
    "rear_axle_point",
    "front_axle_point",
    "wrap_angle",
    "lookahead_distance",
    "lookahead_offset",
    "pure_pursuit_angle",
    "stanley_angle",
    "rear_wheel_feedback_angle",
    "clip_switch_margin",
    "no_slip_body_state",
    "slip_angles",
    "linear_tyre_force",
    "magic_tyre_force",
    "body_derivatives",
    "dynamic_path_kinematics",
    "dynamic_global_kinematics",
]

#: Shape factor :math:`c` of the simplified magic formula
#: :math:`F = D\sin(c\arctan(B\alpha))` (:func:`magic_tyre_force`).
MAGIC_SHAPE = 1.3


# --------------------------------------------------------------------------
# Kinematic single-track model


def yaw_rate(speed: Real, wheelbase: Real, delta_f: Real, delta_r: Real) -> Real:
    r"""Yaw rate of the kinematic model, paper eq. (10).

    .. math:: \dot\psi = \frac{V\sin(\delta_f-\delta_r)}{f\cos\delta_f}

    Examples
    --------
    >>> from fws_control.equations import yaw_rate
    >>> round(float(yaw_rate(5.0, 2.7, 0.1, 0.0)), 6)    # V tan(0.1) / f
    0.185805
    """
    return speed * np.sin(delta_f - delta_r) / (wheelbase * np.cos(delta_f))


def global_frame_derivatives(
    speed: Real, wheelbase: Real, psi: Real, delta_f: Real, delta_r: Real
) -> tuple[Real, Real, Real]:
    r"""Rear-axle point R in the global frame, paper eqs. (8)-(10).

    .. math::
        \dot x_R = V\cos(\psi+\delta_r),\quad
        \dot y_R = V\sin(\psi+\delta_r),\quad
        \dot\psi = \frac{V\sin(\delta_f-\delta_r)}{f\cos\delta_f}

    Returns ``(x_dot, y_dot, psi_dot)``.

    Examples
    --------
    >>> from fws_control.equations import global_frame_derivatives
    >>> [round(float(v), 6) for v in global_frame_derivatives(5.0, 2.7, 0.0, 0.0, 0.0)]
    [5.0, 0.0, 0.0]
    """
    return (
        speed * np.cos(psi + delta_r),
        speed * np.sin(psi + delta_r),
        yaw_rate(speed, wheelbase, delta_f, delta_r),
    )


def path_frame_derivatives(
    speed: Real,
    wheelbase: Real,
    curvature: Real,
    e: Real,
    theta: Real,
    delta_f: Real,
    delta_r: Real,
) -> tuple[Real, Real, Real]:
    r"""Path-frame kinematics, the corrected paper eqs. (17)-(19).

    .. math::
        \dot s = \frac{V\cos(\theta+\delta_r)}{1-\kappa e},\quad
        \dot e = V\sin(\theta+\delta_r),\quad
        \dot\theta = -\kappa\dot s + \frac{V\sin(\delta_f-\delta_r)}{f\cos\delta_f}

    (the paper's eq. (17) lacks the factor :math:`V`). Returns ``(s_dot,
    e_dot, theta_dot)``.

    Examples
    --------
    >>> from fws_control.equations import path_frame_derivatives
    >>> out = path_frame_derivatives(5.0, 2.7, 0.1, 0.0, 0.0, 0.0, 0.0)
    >>> [round(float(v), 6) for v in out]     # s_dot = V, theta_dot = -kappa V
    [5.0, 0.0, -0.5]
    """
    s_dot = speed * np.cos(theta + delta_r) / (1.0 - curvature * e)
    e_dot = speed * np.sin(theta + delta_r)
    theta_dot = -curvature * s_dot + yaw_rate(speed, wheelbase, delta_f, delta_r)
    return s_dot, e_dot, theta_dot


def cg_lateral_velocity(
    speed: Real, rear_to_cg: Real, delta_r: Real, yaw_rate: Real
) -> Real:
    r"""Lateral velocity of G in the vehicle frame, from paper eq. (11).

    G moves with the velocity of R, :math:`V(\cos\delta_r, \sin\delta_r)`
    in the vehicle frame, plus :math:`\dot\psi\times(d, 0)`:

    .. math:: v_y = V\sin\delta_r + d\,\dot\psi

    Examples
    --------
    >>> from fws_control.equations import cg_lateral_velocity
    >>> float(cg_lateral_velocity(5.0, 1.35, 0.0, 0.2))
    0.27
    """
    return speed * np.sin(delta_r) + rear_to_cg * yaw_rate


def yaw_acceleration(
    speed: Real,
    wheelbase: Real,
    delta_f: Real,
    delta_r: Real,
    delta_f_rate: Real,
    delta_r_rate: Real,
) -> Real:
    r"""Time derivative of the yaw rate of eq. (10) at constant speed.

    .. math::
        \ddot\psi = \frac{V}{f}\left(
        \frac{\cos\delta_r}{\cos^2\delta_f}\dot\delta_f
        - \frac{\cos(\delta_f-\delta_r)}{\cos\delta_f}\dot\delta_r\right)

    Examples
    --------
    >>> from fws_control.equations import yaw_acceleration
    >>> round(float(yaw_acceleration(5.0, 2.7, 0.0, 0.0, 0.27, 0.0)), 6)
    0.5
    """
    cf = np.cos(delta_f)
    return (speed / wheelbase) * (
        np.cos(delta_r) / cf**2 * delta_f_rate
        - np.cos(delta_f - delta_r) / cf * delta_r_rate
    )


def lateral_acceleration(
    speed: Real,
    rear_to_cg: Real,
    delta_r: Real,
    delta_r_rate: Real,
    yaw_rate: Real,
    yaw_acceleration: Real,
) -> Real:
    r"""Lateral acceleration of the centre of gravity G, paper eq. (13).

    .. math:: a_G^{lat} = V(\dot\psi + \dot\delta_r)\cos\delta_r + d\,\ddot\psi

    for the yaw rate :math:`\dot\psi` (eq. 10, :func:`yaw_rate`) and its
    derivative :math:`\ddot\psi` (:func:`yaw_acceleration`), at constant
    speed.

    Examples
    --------
    Steady cornering on a radius of 10 m with front steering only gives
    :math:`V^2/R`:

    >>> import numpy as np
    >>> from fws_control.equations import lateral_acceleration, yaw_rate
    >>> r = yaw_rate(5.0, 2.7, np.arctan(0.1 * 2.7), 0.0)
    >>> round(float(lateral_acceleration(5.0, 0.0, 0.0, 0.0, r, 0.0)), 9)
    2.5
    """
    return (
        speed * (yaw_rate + delta_r_rate) * np.cos(delta_r)
        + rear_to_cg * yaw_acceleration
    )


# --------------------------------------------------------------------------
# The paper's control law


def feedforward_angle(wheelbase: Real, curvature: Real) -> Real:
    r"""Front feedforward angle, paper eq. (26): :math:`\delta_f^{FF} =
    \arctan(\kappa_C f)` (and :math:`\delta_r^{FF} = 0`, eq. 27).

    Examples
    --------
    >>> from fws_control.equations import feedforward_angle
    >>> round(float(feedforward_angle(2.7, 0.1)), 6)
    0.263712
    """
    return np.arctan(wheelbase * curvature)


def feedforward_angle_rate(
    wheelbase: Real, curvature: Real, curvature_rate: Real
) -> Real:
    r"""Time derivative of :func:`feedforward_angle`.

    .. math:: \dot\delta_f^{FF} = \frac{f\dot\kappa}{1 + (f\kappa)^2}

    with :math:`\dot\kappa = \kappa'(s)\dot s`; with the slope
    :math:`\kappa'(s)` for `curvature_rate` it is the derivative along the
    path instead.

    Examples
    --------
    >>> from fws_control.equations import feedforward_angle_rate
    >>> float(feedforward_angle_rate(2.0, 0.0, 0.5))
    1.0
    """
    fk = wheelbase * curvature
    return wheelbase * curvature_rate / (1.0 + fk**2)


def feedback_angle(e: Real, theta: Real, k_e: Real, k_theta: Real) -> Real:
    r"""Linear feedback angle of paper eqs. (28)-(29).

    .. math:: \delta^{FB} = -k_e e_C - k_\theta\theta_C

    (:math:`k_1, k_2` for the front, :math:`k_3, k_4` for the rear angle.)

    Examples
    --------
    >>> from fws_control.equations import feedback_angle
    >>> float(feedback_angle(2.0, 0.0, 0.1, 0.5))
    -0.2
    """
    return -k_e * e - k_theta * theta


def feedback_command(
    e: Real, theta: Real, k1: Real, k2: Real, ratio: Real
) -> tuple[Real, Real]:
    r"""The feedback part of the law with :math:`\delta_r = a\delta_f`.

    .. math::
        \delta_f^{FB} = -k_1 e_C - k_2\theta_C,\qquad
        \delta_r^{FB} = a\,\delta_f^{FB}

    (eqs. 28-29 with :math:`k_3 = a k_1`, :math:`k_4 = a k_2`). Returns
    ``(delta_f_fb, delta_r_fb)``. Applied to the rates :math:`(\dot e,
    \dot\theta)` it gives the rates of the feedback angles.

    Examples
    --------
    >>> from fws_control.equations import feedback_command
    >>> [float(v) for v in feedback_command(2.0, 0.0, 0.1, 0.5, -1.0)]
    [-0.2, 0.2]
    """
    fb = feedback_angle(e, theta, k1, k2)
    return fb, ratio * fb


def unscaled_gains(speed: Real, k1_scaled: Real, k2_scaled: Real) -> tuple[Real, Real]:
    r"""The gains :math:`k_1, k_2` from the speed-scaled gains of a schedule.

    .. math:: k_1 = \frac{k_1 V^2}{V^2},\qquad k_2 = \frac{k_2 V}{V}

    A gain schedule interpolates :math:`k_1 V^2` and :math:`k_2 V` (the
    products that fix the kinematic straight-road loop's roots at every
    speed, see :mod:`fws_control.schedule`) and divides back at the
    current speed. Returns ``(k1, k2)``.

    Examples
    --------
    >>> from fws_control.equations import unscaled_gains
    >>> [float(v) for v in unscaled_gains(10.0, 2.0, 3.0)]
    [0.02, 0.3]
    """
    return k1_scaled / speed**2, k2_scaled / speed


def steering_law(
    e: Real,
    theta: Real,
    curvature: Real,
    wheelbase: Real,
    k1: Real,
    k2: Real,
    ratio: Real,
) -> tuple[Real, Real]:
    r"""The paper's law with the curvature feedforward, eqs. (24)-(29).

    .. math::
        \delta_f = \arctan(\kappa_C f) - k_1 e_C - k_2\theta_C,\qquad
        \delta_r = a(-k_1 e_C - k_2\theta_C)

    unclipped. Returns ``(delta_f, delta_r)``; without the feedforward the
    law is :func:`feedback_command`.

    Examples
    --------
    >>> from fws_control.equations import steering_law
    >>> out = steering_law(1.0, 0.0, 0.1, 2.7, 0.1, 0.5, -1.0)
    >>> [round(float(v), 6) for v in out]
    [0.163712, 0.1]
    """
    fb_f, fb_r = feedback_command(e, theta, k1, k2, ratio)
    return fb_f + feedforward_angle(wheelbase, curvature), fb_r


def steering_law_rate(
    e_rate: Real,
    theta_rate: Real,
    curvature: Real,
    curvature_rate: Real,
    wheelbase: Real,
    k1: Real,
    k2: Real,
    ratio: Real,
) -> tuple[Real, Real]:
    r"""Time derivative of :func:`steering_law` (chain rule).

    .. math::
        \dot\delta_f = \frac{f\dot\kappa}{1+(f\kappa)^2} - k_1\dot e
        - k_2\dot\theta,\qquad \dot\delta_r = a(-k_1\dot e - k_2\dot\theta)

    Without the feedforward the rate is :func:`feedback_command` of the
    rates.

    Examples
    --------
    >>> from fws_control.equations import steering_law_rate
    >>> out = steering_law_rate(-1.0, 0.0, 0.0, 0.0, 2.7, 0.1, 0.5, -1.0)
    >>> [round(float(v), 6) for v in out]
    [0.1, -0.1]
    """
    rate_f, rate_r = feedback_command(e_rate, theta_rate, k1, k2, ratio)
    return rate_f + feedforward_angle_rate(wheelbase, curvature, curvature_rate), rate_r


# --------------------------------------------------------------------------
# The baseline laws (fws_control.baselines)


def rear_axle_point(x: Real, y: Real, heading: Real, e: Real) -> tuple[Real, Real]:
    r"""Global position of R from its path point C and lateral error.

    .. math:: x_R = x_C - e\sin\psi_C,\qquad y_R = y_C + e\cos\psi_C

    for the path point :math:`(x_C, y_C)` at ``s`` and its heading
    :math:`\psi_C`. Returns ``(x_R, y_R)``.

    Examples
    --------
    >>> from fws_control.equations import rear_axle_point
    >>> [float(v) for v in rear_axle_point(1.0, 0.0, 0.0, 2.0)]
    [1.0, 2.0]
    """
    return x - e * np.sin(heading), y + e * np.cos(heading)


def front_axle_point(
    x: Real, y: Real, heading: Real, e: Real, theta: Real, wheelbase: Real
) -> tuple[Real, Real, Real]:
    r"""Global position of the front axle centre F and the vehicle heading.

    F lies a wheelbase ahead of R (:func:`rear_axle_point`) along the
    heading :math:`\psi = \theta + \psi_C`. Returns ``(x_F, y_F, psi)``.

    Examples
    --------
    >>> from fws_control.equations import front_axle_point
    >>> [float(v) for v in front_axle_point(0.0, 0.0, 0.0, 1.0, 0.0, 2.7)]
    [2.7, 1.0, 0.0]
    """
    xr, yr = rear_axle_point(x, y, heading, e)
    psi = theta + heading
    return xr + wheelbase * np.cos(psi), yr + wheelbase * np.sin(psi), psi


def wrap_angle(angle: Real) -> Real:
    r"""`angle` wrapped to :math:`(-\pi, \pi]`: ``atan2(sin, cos)``.

    Examples
    --------
    >>> import math
    >>> from fws_control.equations import wrap_angle
    >>> round(float(wrap_angle(1.5 * math.pi)), 12)
    -1.570796326795
    """
    return np.arctan2(np.sin(angle), np.cos(angle))


def lookahead_distance(lookahead: Real, lookahead_time: Real, speed: Real) -> Real:
    r"""Look-ahead distance of pure pursuit :math:`L_d = \max(L, t_{la}|V|)`.

    A look-ahead time of 0 gives the fixed distance `lookahead`.

    Examples
    --------
    >>> from fws_control.equations import lookahead_distance
    >>> float(lookahead_distance(5.0, 0.6, 20.0))
    12.0
    >>> float(lookahead_distance(5.0, 0.0, 20.0))
    5.0
    """
    return np.maximum(lookahead, lookahead_time * np.abs(speed))


def lookahead_offset(lookahead: Real, e: Real) -> Real:
    r"""Arc length from ``s`` to the look-ahead point, :math:`\sqrt{L_d^2 - e^2}`
    (0 where :math:`|e| > L_d`): on a straight path the point at distance
    :math:`L_d` from R.

    Examples
    --------
    >>> from fws_control.equations import lookahead_offset
    >>> float(lookahead_offset(5.0, 3.0)), float(lookahead_offset(5.0, 6.0))
    (4.0, 0.0)
    """
    return np.sqrt(np.maximum(lookahead * lookahead - e * e, 0.0))


def pure_pursuit_angle(
    wheelbase: Real,
    lookahead: Real,
    x_r: Real,
    y_r: Real,
    psi: Real,
    x_p: Real,
    y_p: Real,
) -> Real:
    r"""Pure pursuit's front angle (Coulter 1992).

    .. math:: \alpha = \operatorname{atan2}(y_P - y_R, x_P - x_R) - \psi,
              \qquad \delta_f = \arctan\frac{2 f\sin\alpha}{L_d}

    for the rear axle R at heading :math:`\psi` and the look-ahead point P.

    Examples
    --------
    >>> from fws_control.equations import pure_pursuit_angle
    >>> round(float(pure_pursuit_angle(2.7, 5.0, 0.0, 1.0, 0.0, 4.899, 0.0)), 4)
    -0.2127
    """
    alpha = np.arctan2(y_p - y_r, x_p - x_r) - psi
    return np.arctan2(2.0 * wheelbase * np.sin(alpha), lookahead)


def stanley_angle(
    theta_f: Real, e_f: Real, gain: Real, softening: Real, speed: Real
) -> Real:
    r"""Stanley's front angle (Thrun et al. 2006).

    .. math:: \delta_f = -\theta_f - \arctan\frac{k\,e_f}{k_s + |V|}

    for the heading error :math:`\theta_f` and lateral error :math:`e_f` of
    the front axle centre relative to its own nearest path point.

    Examples
    --------
    >>> from fws_control.equations import stanley_angle
    >>> round(float(stanley_angle(0.0, 1.0, 1.0, 0.0, 5.0)), 6)   # -atan(1/5)
    -0.197396
    """
    return -theta_f - np.arctan(gain * e_f / (softening + np.abs(speed)))


def rear_wheel_feedback_angle(
    speed: Real,
    wheelbase: Real,
    curvature: Real,
    e: Real,
    theta: Real,
    k_e: Real,
    k_theta: Real,
) -> Real:
    r"""Rear-wheel feedback's front angle (Samson 1995).

    .. math::
        \omega = \frac{V\kappa\cos\theta}{1-\kappa e} - K_\theta |V|\theta
                 - K_e V e\,\frac{\sin\theta}{\theta},\qquad
        \delta_f = \arctan\frac{f\,\omega}{V}

    Examples
    --------
    >>> from fws_control.equations import rear_wheel_feedback_angle
    >>> round(float(rear_wheel_feedback_angle(5.0, 2.7, 0.0, 0.0, 0.1, 0.1, 0.5)), 6)
    -0.134189
    """
    sinc = np.sinc(theta / np.pi)  # sin(theta)/theta, 1 at theta = 0
    omega = (
        speed * curvature * np.cos(theta) / (1.0 - curvature * e)
        - k_theta * np.abs(speed) * theta
        - k_e * speed * e * sinc
    )
    return np.arctan(wheelbase * omega / speed)


# --------------------------------------------------------------------------
# Steering limits as switched modes


def clip_switch_margin(value: Real, limit: Real, mode: Real, released: Real) -> Real:
    r"""Event function of a steering clip's switch (it switches at <= 0).

    A clip of `value` (a steering angle command or an actuator rate) to
    :math:`[-L, L]` (`limit`) is integrated as modes switched at located
    events, so that the right-hand side is smooth between them: `mode` 0
    (free: the value passes) or :math:`\pm 1` (held at :math:`\pm L`). Its
    event function is

    .. math::
        g = \begin{cases}
        m\,v - L & m = \pm 1 \text{ (held: leaves the limit when } g < 0)\\
        L - |v| & m = 0,\ r = 0 \text{ (free: reaches either limit)}\\
        L + r\,v & m = 0,\ r = \pm 1 \text{ (released from } r L
        \text{: only } -r L \text{ switches it)}
        \end{cases}

    with `released` :math:`r` the held mode a free clip was released from at
    the start of the current step (it starts there at that limit, up to the
    rounding of the located switch, and can only move away from it; with
    :math:`L - |v|` it would be switched back at once). Written without a
    branch on the value (held :math:`= m^2`), so that an infinite `limit`
    (no clip) of a free clip gives :math:`+\infty`, never NaN.

    Examples
    --------
    >>> from fws_control.equations import clip_switch_margin
    >>> [float(clip_switch_margin(0.3, 0.5, m, r)) for m, r in
    ...  ((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.0, -1.0))]
    [0.2, -0.2, 0.8, 0.2]
    """
    held = mode * mode
    free = (1.0 - held) * (
        released * value - (1.0 - released * released) * np.abs(value)
    )
    return limit * (1.0 - 2.0 * held) + held * mode * value + free


# --------------------------------------------------------------------------
# Dynamic single-track model (see fws_control.dynamics for the conventions)


def no_slip_body_state(
    speed: Real, wheelbase: Real, rear_to_cg: Real, delta_f: Real, delta_r: Real
) -> tuple[Real, Real]:
    r"""Lateral velocity of G and yaw rate with both slip angles zero.

    .. math::
        r = \frac{u(\tan\delta_f - \tan\delta_r)}{f},\qquad
        v_y = u\tan\delta_r + l_r r

    (R moves along its wheel plane, F along its own.) Returns ``(v_y, r)``.

    Examples
    --------
    >>> from fws_control.equations import no_slip_body_state
    >>> vy, r = no_slip_body_state(10.0, 2.7, 1.35, 0.1, 0.0)
    >>> round(float(r), 6), round(float(vy), 6)     # 10 tan(0.1) / 2.7, 1.35 r
    (0.37161, 0.501673)
    """
    tan_f, tan_r = np.tan(delta_f), np.tan(delta_r)
    r = speed * (tan_f - tan_r) / wheelbase
    return speed * tan_r + rear_to_cg * r, r


def slip_angles(
    speed: Real,
    front_to_cg: Real,
    rear_to_cg: Real,
    v_y: Real,
    yaw_rate: Real,
    delta_f: Real,
    delta_r: Real,
) -> tuple[Real, Real]:
    r"""Slip angles ``(alpha_f, alpha_r)`` of the front and rear axle [rad].

    .. math::
        \alpha_f = \delta_f - \operatorname{atan2}(v_y + l_f r, u),\qquad
        \alpha_r = \delta_r - \operatorname{atan2}(v_y - l_r r, u)

    Examples
    --------
    >>> from fws_control.equations import slip_angles
    >>> [float(v) for v in slip_angles(10.0, 1.35, 1.35, 0.0, 0.0, 0.1, -0.1)]
    [0.1, -0.1]
    """
    alpha_f = delta_f - np.arctan2(v_y + front_to_cg * yaw_rate, speed)
    alpha_r = delta_r - np.arctan2(v_y - rear_to_cg * yaw_rate, speed)
    return alpha_f, alpha_r


def linear_tyre_force(slip: Real, stiffness: Real) -> Real:
    r"""Linear axle force :math:`F = C\alpha` [N].

    Examples
    --------
    >>> from fws_control.equations import linear_tyre_force
    >>> float(linear_tyre_force(0.01, 8e4))
    800.0
    """
    return stiffness * slip


def magic_tyre_force(slip: Real, stiffness: Real, peak: Real) -> Real:
    r"""Saturating axle force, the simplified magic formula [N].

    .. math:: F = D\sin(c\arctan(B\alpha)),\qquad B = \frac{C}{cD}

    with :math:`D` = `peak`, :math:`c` = :data:`MAGIC_SHAPE`: slope
    `stiffness` at zero slip, saturating at `peak`.

    Examples
    --------
    >>> from fws_control.equations import magic_tyre_force
    >>> round(float(magic_tyre_force(1e-6, 8e4, 5e3)), 6)    # C alpha
    0.08
    """
    b = stiffness / (MAGIC_SHAPE * peak)
    return peak * np.sin(MAGIC_SHAPE * np.arctan(b * slip))


def body_derivatives(
    speed: Real,
    mass: Real,
    yaw_inertia: Real,
    front_to_cg: Real,
    rear_to_cg: Real,
    yaw_rate: Real,
    force_f: Real,
    force_r: Real,
    delta_f: Real,
    delta_r: Real,
) -> tuple[Real, Real]:
    r"""Lateral and yaw equations of motion ``(v_y_dot, r_dot)``.

    .. math::
        m(\dot v_y + u r) = F_f\cos\delta_f + F_r\cos\delta_r, \qquad
        I_z \dot r = l_f F_f\cos\delta_f - l_r F_r\cos\delta_r

    for the axle forces :math:`F_f, F_r` (normal to the wheel planes) of
    the slip angles of :func:`slip_angles`.

    Examples
    --------
    >>> from fws_control.equations import body_derivatives
    >>> out = body_derivatives(10.0, 1500.0, 2500.0, 1.35, 1.35, 0.0, 800.0,
    ...                        0.0, 0.0, 0.0)
    >>> [round(float(v), 6) for v in out]         # F_f/m, l_f F_f/I_z
    [0.533333, 0.432]
    """
    lat_f = force_f * np.cos(delta_f)
    lat_r = force_r * np.cos(delta_r)
    vy_dot = (lat_f + lat_r) / mass - speed * yaw_rate
    r_dot = (front_to_cg * lat_f - rear_to_cg * lat_r) / yaw_inertia
    return vy_dot, r_dot


def dynamic_path_kinematics(
    speed: Real,
    rear_to_cg: Real,
    curvature: Real,
    e: Real,
    theta: Real,
    v_y: Real,
    yaw_rate: Real,
) -> tuple[Real, Real, Real]:
    r"""Path-frame errors of R for the dynamic model ``(s_dot, e_dot, theta_dot)``.

    R moves with the body-frame velocity :math:`(u, v_y - l_r r)`:

    .. math::
        \dot s = \frac{u\cos\theta - (v_y - l_r r)\sin\theta}{1 - \kappa e},
        \quad \dot e = u\sin\theta + (v_y - l_r r)\cos\theta,
        \quad \dot\theta = r - \kappa\dot s

    Examples
    --------
    >>> from fws_control.equations import dynamic_path_kinematics
    >>> out = dynamic_path_kinematics(10.0, 1.35, 0.0, 0.0, 0.0, 0.0, 0.0)
    >>> [float(v) for v in out]
    [10.0, 0.0, 0.0]
    """
    v_r = v_y - rear_to_cg * yaw_rate  # lateral velocity of R
    sin_t, cos_t = np.sin(theta), np.cos(theta)
    s_dot = (speed * cos_t - v_r * sin_t) / (1.0 - curvature * e)
    e_dot = speed * sin_t + v_r * cos_t
    theta_dot = yaw_rate - curvature * s_dot
    return s_dot, e_dot, theta_dot


def dynamic_global_kinematics(
    speed: Real, rear_to_cg: Real, psi: Real, v_y: Real, yaw_rate: Real
) -> tuple[Real, Real]:
    r"""Global velocity of R for the dynamic model ``(x_dot, y_dot)``.

    .. math::
        \dot x = u\cos\psi - (v_y - l_r r)\sin\psi,\quad
        \dot y = u\sin\psi + (v_y - l_r r)\cos\psi

    Examples
    --------
    >>> from fws_control.equations import dynamic_global_kinematics
    >>> [float(v) for v in dynamic_global_kinematics(10.0, 1.35, 0.0, 0.0, 0.0)]
    [10.0, 0.0]
    """
    v_r = v_y - rear_to_cg * yaw_rate  # lateral velocity of R
    sin_p, cos_p = np.sin(psi), np.cos(psi)
    return speed * cos_p - v_r * sin_p, speed * sin_p + v_r * cos_p
