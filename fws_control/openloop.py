r"""Open-loop tests of the dynamic single-track model (ISO 7401, ISO 4138).

Before a closed-loop comparison is trusted, the vehicle model is checked
with the open-loop manoeuvres of the standards: the steering input is
prescribed and the yaw rate and lateral acceleration are measured. The
model is that of :mod:`fws_control.dynamics` (constant longitudinal speed
:math:`u`, lateral velocity :math:`v_y` of the centre of gravity G, yaw rate
:math:`r`, linear or saturating "magic" tyres); its equations are called
from :mod:`fws_control.equations` (as in
:func:`~fws_control.dynamics.body_derivatives`), never written again here.

* :func:`steering_response_system`: the linear single-track model as a
  :class:`control.StateSpace` from the front angle to the yaw rate and the
  lateral acceleration, for front steering or :math:`\delta_r = a\,\delta_f`.
* :func:`step_steer`: ISO 7401 step steer (a ramp of a given rate, then
  held) with the characteristic values of the standard.
* :func:`steering_frequency_response`: gain and phase from the front angle
  to the yaw rate and the lateral acceleration, from the linear model or
  from stepped sines of the nonlinear model.
* :func:`steady_state_circle`: ISO 4138 steady-state circular driving on a
  constant radius: steering angle and understeer gradient against lateral
  acceleration, from the steady states of the nonlinear model.

Lateral acceleration here is that of G along the body's lateral axis,
:math:`a_y = \dot v_y + u r` (:math:`= u r` in a steady state).

Rear steering: `ratio` is a constant :math:`a` or a ratio schedule called
``ratio(vehicle, speed=u)``, e.g. :func:`fws_control.zero_sideslip_ratio`;
the rear angle is :math:`\delta_r = a(u)\,\delta_f` at every instant.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import KW_ONLY, dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from . import equations
from .dynamics import TYRES, axle_loads, path_jacobians, require_dynamics
from .hints import RatioLike, RealArrayLike
from .reprs import summary_repr
from .validation import MAX_SPEED, check_finite, check_magnitude, check_real
from .vehicle import Vehicle

if TYPE_CHECKING:
    import control as ct

    from .dynamics import DynamicVehicle

__all__ = [
    "MODELS",
    "ISO_STEER_RISE",
    "StepResponseMetrics",
    "StepSteerResponse",
    "SteeringFrequencyResponse",
    "SteadyStateCircle",
    "steering_response_system",
    "step_steer",
    "steering_frequency_response",
    "steady_state_circle",
]

#: Models of :func:`step_steer` and :func:`steering_frequency_response`:
#: the linear single-track model (:func:`steering_response_system`) or the
#: nonlinear one of :mod:`fws_control.dynamics`.
MODELS = ("linear", "nonlinear")

#: ISO 7401 step input: the steering angle goes from 10 % to 90 % of its
#: final value in at most this time [s]; :func:`step_steer`'s default rate
#: takes exactly this time.
ISO_STEER_RISE = 0.15

#: Output names of :func:`steering_response_system`.
OUTPUTS = ("r", "a_y")


# --------------------------------------------------------------------------
# argument checks


#: Lowest speed of the open-loop tests [m/s]: the model's matrices scale
#: with 1/u, and a walking pace is no driving test.
MIN_SPEED = 0.1


def _check_speed(speed: Any) -> float:
    v = check_magnitude("speed", speed, MAX_SPEED, "m/s")
    if np.ndim(v) != 0 or not float(v) >= MIN_SPEED:
        raise ValueError(
            f"speed must be a scalar in [{MIN_SPEED:g}, {MAX_SPEED:g}] m/s, "
            f"got {speed!r}"
        )
    return float(v)


def _check_choice(name: str, value: Any, choices: tuple[str, ...]) -> str:
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")
    return value


def _ratio_at(vehicle: Vehicle, ratio: RatioLike, speed: Any) -> Any:
    """The ratio a (a schedule evaluated at `speed`), finite, |a| <= 10."""
    value = ratio(vehicle, speed=speed) if callable(ratio) else ratio
    a = check_finite("ratio", value)
    if np.shape(a) != np.shape(speed) and np.ndim(a) != 0:
        raise ValueError(
            f"ratio must be a scalar (or a schedule ratio(vehicle, speed=...)), "
            f"got an array of shape {np.shape(a)}"
        )
    # |a| > 1 steers the rear more than the front; beyond 10 the "front
    # angle" no longer describes the input
    if np.any(np.abs(a) > 10.0):
        raise ValueError(f"ratio must be in [-10, 10], got {value!r}")
    return a


def _check_positive_scalar(name: str, value: Any, unit: str, upper: float) -> float:
    v = check_real(name, value)
    if v.ndim != 0 or not (math.isfinite(float(v)) and 0.0 < float(v) <= upper):
        raise ValueError(
            f"{name} must be a scalar in (0, {upper:g}] {unit}, got {value!r}"
        )
    return float(v)


def _check_grid(name: str, value: Any, unit: str, upper: float) -> np.ndarray:
    v = check_real(name, value)
    if v.ndim != 1 or v.size == 0:
        raise ValueError(
            f"{name} must be a non-empty 1-D array, got shape {np.shape(v)}"
        )
    if not np.all(np.isfinite(v)) or np.any(v <= 0.0) or np.any(v > upper):
        raise ValueError(
            f"{name} must be finite values in (0, {upper:g}] {unit}, got {value!r}"
        )
    if np.any(np.diff(v) <= 0.0):
        raise ValueError(f"{name} must be strictly increasing, got {value!r}")
    return v


# --------------------------------------------------------------------------
# the linear model


def steering_response_system(
    vehicle: Vehicle,
    *,
    speed: float,
    ratio: RatioLike = 0.0,
    name: str = "single_track",
) -> ct.StateSpace:
    r"""Linear single-track model: front angle to yaw rate and lateral acceleration.

    The dynamic single-track model linearised about straight driving
    (:func:`fws_control.dynamics.path_jacobians` at zero curvature), with the
    rear angle tied to the front one, :math:`\delta_r = a\,\delta_f`:

    .. math::
        \begin{bmatrix}\dot v_y\\ \dot r\end{bmatrix} =
        \begin{bmatrix}
          -\frac{C_f + C_r}{m u} & -u - \frac{l_f C_f - l_r C_r}{m u}\\
          -\frac{l_f C_f - l_r C_r}{I_z u} & -\frac{l_f^2 C_f + l_r^2 C_r}{I_z u}
        \end{bmatrix}
        \begin{bmatrix}v_y\\ r\end{bmatrix} +
        \begin{bmatrix}(C_f + a C_r)/m\\ (l_f C_f - a l_r C_r)/I_z\end{bmatrix}
        \delta_f,
        \qquad a_y = \dot v_y + u r .

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data (mass, yaw inertia, cornering stiffnesses
        :math:`C_f, C_r` per axle).
    speed : float
        Longitudinal speed :math:`u` [m/s], in [0.1, 1e6].
    ratio : float or callable, optional
        Rear-to-front ratio :math:`a`, in [-10, 10], or a schedule
        ``ratio(vehicle, speed=...)`` such as
        :func:`fws_control.zero_sideslip_ratio`. Default 0 (front steering).
    name : str, optional
        System name.

    Returns
    -------
    control.StateSpace
        States ``v_y, r``; input ``delta_f``; outputs ``r`` [rad/s] and
        ``a_y`` [m/s^2]. Parameters are not stored: build a new system for
        another speed.

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`.
    ValueError
        If the vehicle lacks the dynamic data, or `speed` or `ratio` is out
        of range.

    Examples
    --------
    The steady yaw-rate gain of front steering is :math:`u/(f + K_{us}u^2)`:

    >>> import fws_control as fws
    >>> veh = fws.vehicles.BMW_320I
    >>> sys = fws.steering_response_system(veh, speed=20.0)
    >>> sys.output_labels, sys.input_labels
    (['r', 'a_y'], ['delta_f'])
    >>> gain = sys.dcgain()
    >>> k_us = fws.understeer_gradient(veh)
    >>> round(float(gain[0, 0]), 6), round(20.0 / (veh.wheelbase + k_us * 20.0**2), 6)
    (7.755206, 7.755206)
    """
    import control as ct

    require_dynamics(vehicle)
    u = _check_speed(speed)
    a = float(_ratio_at(vehicle, ratio, u))
    jac_a, jac_b = path_jacobians(vehicle, speed=u, curvature=0.0)
    # body states v_y, r of the path-frame Jacobian (e, theta, v_y, r)
    A = jac_a[2:, 2:]
    B = jac_b[2:, :] @ np.array([[1.0], [a]])
    # a_y = v_y_dot + u r: the v_y row of (A, B) plus u on r
    C = np.vstack([[0.0, 1.0], A[0] + np.array([0.0, u])])
    D = np.vstack([[0.0], B[0]])
    return ct.ss(
        A, B, C, D, states=["v_y", "r"], inputs=["delta_f"], outputs=list(OUTPUTS),
        name=name,
    )  # fmt: skip


# --------------------------------------------------------------------------
# ISO 7401 characteristic values


@summary_repr
@dataclass(frozen=True, eq=False)
class StepResponseMetrics:
    r"""ISO 7401 characteristic values of one response to a step steer.

    Times are measured from the reference instant :math:`t = 0`, at which
    the steering angle reaches 50 % of its final value.

    Attributes
    ----------
    steady_state : float
        Steady-state value :math:`Y_{ss}` of the response to the final
        steering angle (from the model's steady state, not read off the
        record).
    response_time : float
        Time [s] from :math:`t = 0` to the first instant the response
        reaches 90 % of :math:`Y_{ss}`.
    rise_time : float
        Time [s] the response takes from 10 % to 90 % of :math:`Y_{ss}`
        (first crossings of each level).
    peak_response_time : float
        Time [s] from :math:`t = 0` to the largest value of the response,
        if that value exceeds :math:`Y_{ss}` within the record; ``inf``
        otherwise (no peak). The peak is the vertex of the parabola through
        the largest sample and its neighbours, the crossings are
        interpolated linearly between samples: all times to a small fraction
        of the output step.
    peak : float
        The largest value of the response (in the direction of
        :math:`Y_{ss}`); :math:`Y_{ss}` if there is no peak.
    overshoot : float
        :math:`(Y_{max} - Y_{ss})/Y_{ss}` [-]; 0 if there is no peak.

    Examples
    --------
    >>> import fws_control as fws
    >>> res = fws.step_steer(fws.vehicles.BMW_320I, speed=20.0, amplitude=0.01)
    >>> m = res.yaw_rate_metrics
    >>> round(m.steady_state, 5), round(m.response_time, 3), round(m.rise_time, 3)
    (0.07755, 0.229, 0.256)

    The rise time (10 % to 90 % of the response) exceeds the response time
    here: the response passes 10 % before the steering reaches 50 %.
    """

    _: KW_ONLY  # a result record: every field named at construction
    steady_state: float
    response_time: float
    rise_time: float
    peak_response_time: float
    peak: float
    overshoot: float


def _crossing(t: np.ndarray, y: np.ndarray, level: float, name: str) -> float:
    """First time `y` reaches `level` (y, level > 0), linear interpolation."""
    above = np.nonzero(y >= level)[0]
    if above.size == 0:
        raise ValueError(
            f"the {name} does not reach {level!r} within the record: increase "
            f"duration (now {float(t[-1])!r} s after the 50 % steering instant)"
        )
    i = int(above[0])
    if i == 0:
        return float(t[0])
    t0, t1, y0, y1 = t[i - 1], t[i], y[i - 1], y[i]
    return float(t0 + (level - y0) * (t1 - t0) / (y1 - y0))


def _metrics(
    t: np.ndarray, y: np.ndarray, steady: float, name: str
) -> StepResponseMetrics:
    if steady == 0.0:
        raise ValueError(
            f"the steady {name} is 0: the ISO 7401 values are relative to it "
            "(a ratio that cancels this response?)"
        )
    sign = math.copysign(1.0, steady)
    w = sign * y  # the response in the direction of its steady value
    ss = abs(steady)
    t90 = _crossing(t, w, 0.9 * ss, name)
    t10 = _crossing(t, w, 0.1 * ss, name)
    k = int(np.argmax(w))
    # a peak must stand clear of the solver noise on a monotone response
    if w[k] > ss * (1.0 + 1e-8) and 0 < k < w.size - 1:
        # vertex of the parabola through the three samples about the largest
        y0, y1, y2 = w[k - 1], w[k], w[k + 1]
        curv = y0 - 2.0 * y1 + y2
        shift = 0.5 * (y0 - y2) / curv if curv < 0.0 else 0.0
        dt = t[k + 1] - t[k]
        t_peak = float(t[k] + shift * dt)
        peak = float(y1 - 0.25 * (y0 - y2) * shift)
        over = (peak - ss) / ss
    else:
        # monotone within the record (or still rising at its end)
        t_peak, peak, over = math.inf, ss, 0.0
    return StepResponseMetrics(
        steady_state=steady,
        response_time=t90,
        rise_time=t90 - t10,
        peak_response_time=t_peak,
        peak=sign * peak,
        overshoot=over,
    )


# --------------------------------------------------------------------------
# the nonlinear model


def _body_rates(vehicle: DynamicVehicle, tyre: str, speed: Any) -> Callable[..., Any]:
    """``rates(v_y, r, delta_f, delta_r) -> (v_y_dot, r_dot)`` of one vehicle.

    :func:`fws_control.dynamics.body_derivatives` with the vehicle data
    read once: the stepped sines call it some 10^5 times.
    """
    l_f, l_r = vehicle.front_to_cg, vehicle.rear_to_cg
    m, iz = vehicle.mass, vehicle.yaw_inertia
    c_f, c_r = vehicle.cornering_front, vehicle.cornering_rear
    if tyre == "magic":
        fz_f, fz_r = axle_loads(vehicle)
        mu = cast(float, vehicle.friction)  # require_dynamics checked it
        d_f, d_r = mu * fz_f, mu * fz_r

        def forces(alpha_f, alpha_r):
            return (
                equations.magic_tyre_force(alpha_f, c_f, d_f),
                equations.magic_tyre_force(alpha_r, c_r, d_r),
            )
    else:

        def forces(alpha_f, alpha_r):
            return (
                equations.linear_tyre_force(alpha_f, c_f),
                equations.linear_tyre_force(alpha_r, c_r),
            )

    def rates(v_y, r, delta_f, delta_r):
        alpha_f, alpha_r = equations.slip_angles(
            speed, l_f, l_r, v_y, r, delta_f, delta_r
        )
        f_f, f_r = forces(alpha_f, alpha_r)
        return equations.body_derivatives(
            speed, m, iz, l_f, l_r, r, f_f, f_r, delta_f, delta_r
        )

    return rates


def _steady_body(
    vehicle: DynamicVehicle,
    delta_f: float,
    delta_r: float,
    speed: float,
    tyre: str,
    guess: tuple[float, float],
) -> tuple[float, float]:
    """``(v_y, r)`` with both body derivatives zero at fixed steering angles."""
    from scipy.optimize import root

    rates = _body_rates(vehicle, tyre, speed)

    def residual(x):
        vy_dot, r_dot = rates(x[0], x[1], delta_f, delta_r)
        return [float(vy_dot), float(r_dot)]

    sol = root(residual, guess, method="hybr", options={"xtol": 1e-14})
    scale = abs(speed * float(sol.x[1])) + abs(float(sol.x[0])) + 1e-300
    if not sol.success and np.max(np.abs(sol.fun)) > 1e-9 * max(scale, 1.0):
        raise ValueError(
            f"no steady state at delta_f={delta_f!r} rad, delta_r={delta_r!r} rad, "
            f"speed={speed!r} m/s with the {tyre} tyre: the lateral force needed "
            "exceeds what the tyres give (reduce the amplitude)"
        )
    return float(sol.x[0]), float(sol.x[1])


# --------------------------------------------------------------------------
# step steer


@summary_repr
@dataclass(frozen=True, eq=False)
class StepSteerResponse:
    r"""Response to an ISO 7401 step steer (result of :func:`step_steer`).

    Attributes
    ----------
    vehicle : Vehicle
        The vehicle.
    speed : float
        Longitudinal speed [m/s].
    ratio : float
        Rear-to-front ratio :math:`a` (a schedule evaluated at `speed`).
    amplitude : float
        Final front steering angle [rad].
    steer_rate : float
        Front steering rate of the ramp [rad/s] (``inf``: an ideal step).
    model : str
        ``"linear"`` or ``"nonlinear"``.
    tyre : str
        Tyre model of the nonlinear model.
    time : ndarray
        Time [s], 0 at the instant the steering angle reaches 50 % of
        `amplitude`; the ramp starts at ``time[0]``.
    delta_f, delta_r : ndarray
        Front and rear steering angle [rad].
    lateral_velocity : ndarray
        :math:`v_y` of G [m/s].
    yaw_rate : ndarray
        :math:`r` [rad/s].
    lateral_acceleration : ndarray
        :math:`a_y = \dot v_y + u r` of G [m/s^2].
    yaw_rate_metrics, lateral_acceleration_metrics : StepResponseMetrics
        The ISO 7401 characteristic values of the two responses.

    Examples
    --------
    >>> import fws_control as fws
    >>> res = fws.step_steer(fws.vehicles.BMW_320I, speed=20.0, amplitude=0.01)
    >>> round(res.lateral_acceleration_metrics.steady_state, 3)   # u r_ss
    1.551
    """

    vehicle: Vehicle
    _: KW_ONLY
    speed: float
    ratio: float
    amplitude: float
    steer_rate: float
    model: str
    tyre: str
    time: np.ndarray
    delta_f: np.ndarray
    delta_r: np.ndarray
    lateral_velocity: np.ndarray
    yaw_rate: np.ndarray
    lateral_acceleration: np.ndarray
    yaw_rate_metrics: StepResponseMetrics
    lateral_acceleration_metrics: StepResponseMetrics

    def plot(self, ax: Any = None) -> ct.ControlPlot:
        """Yaw rate and lateral acceleration against time, with the ISO values.

        Parameters
        ----------
        ax : array of two matplotlib.axes.Axes, optional
            Axes for the yaw rate and the lateral acceleration; a new
            figure if None.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> res = fws.step_steer(fws.vehicles.BMW_320I, speed=20.0, amplitude=0.01)
        >>> cplt = res.plot()
        >>> cplt.axes[1, 0].get_ylabel()
        'a_y [m/s^2]'
        >>> plt.close(cplt.figure)
        """
        import control as ct

        axes = _two_axes(ax, sharex=True)
        lines = []
        for a, y, m, label in (
            (axes[0], self.yaw_rate, self.yaw_rate_metrics, "r [rad/s]"),
            (axes[1], self.lateral_acceleration, self.lateral_acceleration_metrics,
             "a_y [m/s^2]"),
        ):  # fmt: skip
            # one colour per response, so that several fit in the same axes
            name = f"{self.model}, {self.tyre} tyre"
            (ln,) = a.plot(self.time, y, label=name)
            color = ln.get_color()
            lines.append(ln)
            lines.append(a.axhline(m.steady_state, color=color, ls="--", lw=0.8))
            lines.append(
                a.axvline(
                    m.response_time,
                    color=color,
                    ls=":",
                    lw=1.0,
                    label=f"response time {m.response_time:.3f} s",
                )  # fmt: skip
            )
            if math.isfinite(m.peak_response_time):
                (pk,) = a.plot(
                    m.peak_response_time, m.peak, "v", color=color,
                    label=f"peak {m.peak_response_time:.3f} s, "
                    f"overshoot {100 * m.overshoot:.1f} %",
                )  # fmt: skip
                lines.append(pk)
            a.set_ylabel(label)
            a.legend(loc="lower right", fontsize="small")
        axes[1].set_xlabel("time after 50 % steering [s]")
        axes[0].set_title(
            f"step steer {math.degrees(self.amplitude):.2f} deg at "
            f"{self.speed:g} m/s, a = {self.ratio:.3g}"
        )
        return ct.ControlPlot(
            np.array(lines, dtype=object), np.array(axes).reshape(2, 1),
            axes[0].figure,
        )  # fmt: skip


def _two_axes(ax: Any, *, sharex: bool) -> list:
    import matplotlib.pyplot as plt

    if ax is None:
        _, axs = plt.subplots(2, 1, figsize=(6.5, 5.5), sharex=sharex,
                              layout="constrained")  # fmt: skip
        return list(axs)
    axs = list(np.asarray(ax, dtype=object).ravel())
    if len(axs) != 2:
        raise ValueError(f"ax must be None or two Axes, got {len(axs)}")
    return axs


def step_steer(
    vehicle: Vehicle,
    *,
    speed: float,
    amplitude: float,
    ratio: RatioLike = 0.0,
    steer_rate: float | None = None,
    model: str = "linear",
    tyre: str = "linear",
    duration: float = 4.0,
    dt: float = 1e-3,
) -> StepSteerResponse:
    r"""ISO 7401 step steer of the single-track model, open loop.

    From straight driving at constant speed the front angle is turned at
    the constant rate `steer_rate` to `amplitude` and held (the rear angle
    follows as :math:`a\,\delta_f`). Time 0 is the instant the front angle
    reaches 50 % of `amplitude`. The characteristic values of ISO 7401:2011
    (:class:`StepResponseMetrics`) are computed for the yaw rate and the
    lateral acceleration:

    * response time: from 50 % steering to 90 % of the steady-state value;
    * rise time: from 10 % to 90 % of the steady-state value;
    * peak response time: from 50 % steering to the peak of the response;
    * overshoot: peak over steady-state value, minus 1.

    The standard asks for a steering input that goes from 10 % to 90 % of
    its final value in at most :data:`ISO_STEER_RISE` = 0.15 s; the default
    rate takes exactly that long.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data (friction too for ``tyre="magic"``).
    speed : float
        Longitudinal speed :math:`u` [m/s], in [0.1, 1e6].
    amplitude : float
        Final front angle [rad], nonzero, :math:`|\delta_f| \le 0.5`.
    ratio : float or callable, optional
        Rear-to-front ratio :math:`a` in [-10, 10] or a schedule
        ``ratio(vehicle, speed=...)``; default 0.
    steer_rate : float, optional
        Magnitude of the front steering rate of the ramp [rad/s], at least
        ``|amplitude| / (2 duration)`` (the ramp ends within the record);
        ``math.inf`` for an ideal step. Default: the ISO 7401 limit,
        ``0.8 * |amplitude| / 0.15``.
    model : {"linear", "nonlinear"}, optional
        ``"linear"``: :func:`steering_response_system`, solved exactly for
        the piecewise-linear input (:func:`control.forced_response`);
        ``"nonlinear"``: the model of :mod:`fws_control.dynamics`,
        integrated with :func:`scipy.integrate.solve_ivp` (``rtol=1e-10``).
    tyre : {"linear", "magic"}, optional
        Tyre of the nonlinear model; ``"magic"`` needs ``model="nonlinear"``.
    duration : float, optional
        Length of the record after the 50 % instant [s], in (0, 600].
    dt : float, optional
        Output step [s], in (0, 0.1]; the linear model's step is shortened
        so that the ramp's corners fall on samples.

    Returns
    -------
    StepSteerResponse

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`, or an argument is a bool or
        complex.
    ValueError
        If an argument is out of its range, the vehicle lacks the data, the
        tyres cannot hold the final angle in a steady state, or a response
        does not reach 90 % of its steady value within `duration`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.vehicles.BMW_320I
    >>> res = fws.step_steer(veh, speed=20.0, amplitude=0.01)
    >>> m = res.yaw_rate_metrics
    >>> round(m.response_time, 3), m.peak_response_time, m.overshoot
    (0.229, inf, 0.0)

    (This car is neutral steer: its yaw rate is a first-order response, with
    no peak.)

    The same step on the nonlinear model with the saturating tyre:

    >>> nl = fws.step_steer(veh, speed=20.0, amplitude=0.01, model="nonlinear",
    ...                     tyre="magic")
    >>> round(nl.yaw_rate_metrics.steady_state, 4)
    0.0776
    """
    vehicle = require_dynamics(vehicle, tyre=tyre)
    u = _check_speed(speed)
    amp_in = check_real("amplitude", amplitude)
    if amp_in.ndim != 0 or not (
        math.isfinite(float(amp_in)) and 0.0 < abs(float(amp_in)) <= 0.5
    ):
        raise ValueError(
            f"amplitude must be a nonzero scalar with |amplitude| <= 0.5 rad, "
            f"got {amplitude!r}"
        )
    amp = float(amp_in)
    a = float(_ratio_at(vehicle, ratio, u))
    if steer_rate is None:
        rate = 0.8 * abs(amp) / ISO_STEER_RISE
    else:
        r_ = check_real("steer_rate", steer_rate)
        if r_.ndim != 0 or math.isnan(float(r_)) or not float(r_) > 0.0:
            raise ValueError(
                f"steer_rate must be a scalar > 0 rad/s (inf for a step), "
                f"got {steer_rate!r}"
            )
        rate = float(r_)
    model = _check_choice("model", model, MODELS)
    if model == "linear" and tyre != "linear":
        raise ValueError(
            f"tyre={tyre!r} needs model='nonlinear': the linear model has the "
            "tyres' slope at zero slip"
        )
    duration = _check_positive_scalar("duration", duration, "s", 600.0)
    dt = _check_positive_scalar("dt", dt, "s", 0.1)
    if duration / dt > 2e6:
        raise ValueError(
            f"duration/dt must be at most 2e6 samples, got duration={duration!r} "
            f"s, dt={dt!r} s"
        )

    ramp = abs(amp) / rate  # duration of the ramp [s]
    if 0.5 * ramp > duration:
        raise ValueError(
            f"steer_rate={steer_rate!r} rad/s turns amplitude={amp!r} rad in "
            f"{ramp!r} s: the ramp must end within the record, so steer_rate must "
            f"be >= |amplitude| / (2 duration) = {abs(amp) / (2.0 * duration)!r} rad/s"
        )
    if (0.5 * ramp + duration) / dt > 2e6:
        raise ValueError(
            f"duration/dt must be at most 2e6 samples with the ramp, got "
            f"duration={duration!r} s, dt={dt!r} s, steer_rate={rate!r} rad/s"
        )
    if ramp > 0.0:
        # an even number of steps over the ramp puts 0 (50 %) and both
        # corners on samples; the linear solution is then exact
        n_half = max(1, math.ceil(0.5 * ramp / dt))
        step = 0.5 * ramp / n_half
    else:
        n_half, step = 0, dt
    n_after = math.ceil(duration / step)
    t = step * np.arange(-n_half, n_after + 1)
    delta_f = (
        amp * np.clip((t + 0.5 * ramp) / ramp, 0.0, 1.0)
        if ramp > 0.0
        else (np.full_like(t, amp))
    )
    delta_r = a * delta_f

    sys = steering_response_system(vehicle, speed=u, ratio=a)
    _check_stable(sys, u)
    if model == "linear":
        import control as ct

        out = ct.forced_response(sys, t - t[0], delta_f, return_states=True)
        v_y, r = out.states
        yaw, a_y = out.outputs
        gain = np.ravel(sys.dcgain())
        steady_r, steady_ay = float(gain[0]) * amp, float(gain[1]) * amp
    else:
        from scipy.integrate import solve_ivp

        rates = _body_rates(vehicle, tyre, u)

        def rhs(time, x, corner):
            df = (
                amp * min(max((time + 0.5 * ramp) / ramp, 0.0), 1.0)
                if (corner and ramp > 0.0)
                else amp
            )
            return rates(x[0], x[1], df, a * df)

        # the ramp, then the hold, split at the sample of the ramp's end
        # (index 2 n_half, not a comparison of rounded times)
        end = 2 * n_half
        pieces = (
            [(slice(0, end + 1), True), (slice(end, None), False)]
            if ramp > 0.0
            else [(slice(0, None), False)]
        )
        v_y, r = np.zeros_like(t), np.zeros_like(t)
        x0 = np.zeros(2)
        for mask, corner in pieces:
            ts = t[mask]
            sol = solve_ivp(
                rhs, (ts[0], ts[-1]), x0, t_eval=ts, args=(corner,), method="RK45",
                rtol=1e-10, atol=1e-13,
            )  # fmt: skip
            if not sol.success:
                raise ValueError(
                    f"the step steer did not integrate: {sol.message} "
                    f"(speed={u!r} m/s, amplitude={amp!r} rad)"
                )
            v_y[mask], r[mask] = sol.y
            x0 = sol.y[:, -1]
        vy_dot, _ = rates(v_y, r, delta_f, delta_r)
        yaw, a_y = r, vy_dot + u * r
        lin = np.ravel(sys.dcgain())
        # the linear steady state: v_y from the v_y row, a_y = u r there
        guess = (0.0, float(lin[0]) * amp)
        vy_ss, r_ss = _steady_body(vehicle, amp, a * amp, u, tyre, guess)
        steady_r, steady_ay = r_ss, u * r_ss
    if not (np.all(np.isfinite(yaw)) and np.all(np.isfinite(a_y))):
        raise ValueError(
            f"the step steer diverged (speed={u!r} m/s, amplitude={amp!r} rad): "
            "the model is unstable at this speed"
        )
    return StepSteerResponse(
        vehicle,
        speed=u,
        ratio=a,
        amplitude=amp,
        steer_rate=rate,
        model=model,
        tyre=tyre,
        time=t,
        delta_f=delta_f,
        delta_r=delta_r,
        lateral_velocity=np.asarray(v_y),
        yaw_rate=np.asarray(yaw),
        lateral_acceleration=np.asarray(a_y),
        yaw_rate_metrics=_metrics(t, np.asarray(yaw), steady_r, "yaw rate"),
        lateral_acceleration_metrics=_metrics(
            t, np.asarray(a_y), steady_ay, "lateral acceleration"
        ),
    )


def _check_stable(sys: Any, speed: float) -> None:
    poles = np.linalg.eigvals(sys.A)
    if np.any(poles.real >= 0.0):
        raise ValueError(
            f"speed={speed!r} m/s: the single-track model is unstable there "
            f"(poles {np.round(poles, 6).tolist()}); an open-loop test needs a "
            "speed below the critical speed of an oversteering vehicle"
        )


# --------------------------------------------------------------------------
# frequency response


@summary_repr
@dataclass(frozen=True, eq=False)
class SteeringFrequencyResponse:
    r"""Gain and phase from the front angle (:func:`steering_frequency_response`).

    Attributes
    ----------
    vehicle : Vehicle
        The vehicle.
    speed : float
        Longitudinal speed [m/s].
    ratio : float
        Rear-to-front ratio :math:`a` (a schedule evaluated at `speed`).
    model : str
        ``"linear"`` or ``"nonlinear"``.
    tyre : str
        Tyre model of the nonlinear model.
    amplitude : float
        Front-angle amplitude of the sines [rad] (0 for the linear model).
    omega : ndarray
        Angular frequencies [rad/s], shape ``(n,)``.
    yaw_rate_gain : ndarray
        :math:`|r/\delta_f|` [1/s].
    yaw_rate_phase : ndarray
        Phase of :math:`r` relative to :math:`\delta_f` [rad], unwrapped
        along `omega` from the branch (-pi, pi] at the lowest frequency.
    lateral_acceleration_gain : ndarray
        :math:`|a_y/\delta_f|` [m/s^2/rad].
    lateral_acceleration_phase : ndarray
        Phase of :math:`a_y` [rad], unwrapped likewise.

    Examples
    --------
    >>> import fws_control as fws
    >>> fr = fws.steering_frequency_response(fws.vehicles.BMW_320I, speed=20.0,
    ...                                      omega=[0.1, 10.0])
    >>> fr.yaw_rate_gain.round(3)
    array([7.755, 5.689])
    """

    vehicle: Vehicle
    _: KW_ONLY
    speed: float
    ratio: float
    model: str
    tyre: str
    amplitude: float
    omega: np.ndarray
    yaw_rate_gain: np.ndarray
    yaw_rate_phase: np.ndarray
    lateral_acceleration_gain: np.ndarray
    lateral_acceleration_phase: np.ndarray

    def plot(self, ax: Any = None, *, label: str | None = None) -> ct.ControlPlot:
        """Gain (normalised by its lowest-frequency value) and phase against frequency.

        Parameters
        ----------
        ax : array of two matplotlib.axes.Axes, optional
            Axes for the normalised gain and the phase; a new figure if None.
            Plot several responses into the same axes to compare them.
        label : str, optional
            Legend text; default names the model, tyre and amplitude.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, numpy as np, fws_control as fws
        >>> fr = fws.steering_frequency_response(
        ...     fws.vehicles.BMW_320I, speed=20.0, omega=np.geomspace(0.5, 30, 20))
        >>> cplt = fr.plot()
        >>> cplt.axes[1, 0].get_xlabel()
        'frequency [Hz]'
        >>> plt.close(cplt.figure)
        """
        import control as ct

        axes = _two_axes(ax, sharex=True)
        if label is None:
            label = (
                "linear model"
                if self.model == "linear"
                else (f"{self.tyre} tyre, {math.degrees(self.amplitude):.2g} deg")
            )
        hz = self.omega / (2.0 * math.pi)
        lines = []
        for y_gain, y_phase, what, style in (
            (self.yaw_rate_gain, self.yaw_rate_phase, "r", "-"),
            (self.lateral_acceleration_gain, self.lateral_acceleration_phase,
             "a_y", "--"),
        ):  # fmt: skip
            (g,) = axes[0].semilogx(
                hz, y_gain / y_gain[0], style, label=f"{what}: {label}"
            )
            (p,) = axes[1].semilogx(
                hz, np.degrees(y_phase), style, color=g.get_color(),
                label=f"{what}: {label}",
            )  # fmt: skip
            lines += [g, p]
        axes[0].set_ylabel("gain / low-frequency gain")
        axes[1].set_ylabel("phase [deg]")
        axes[1].set_xlabel("frequency [Hz]")
        axes[0].legend(fontsize="small")
        axes[0].set_title(f"steering frequency response at {self.speed:g} m/s")
        return ct.ControlPlot(
            np.array(lines, dtype=object), np.array(axes).reshape(2, 1),
            axes[0].figure,
        )  # fmt: skip


def _unwrap(h: np.ndarray) -> np.ndarray:
    return np.unwrap(np.angle(h))


def steering_frequency_response(
    vehicle: Vehicle,
    *,
    speed: float,
    omega: RealArrayLike,
    ratio: RatioLike = 0.0,
    model: str = "linear",
    tyre: str = "linear",
    amplitude: float = 1e-3,
    periods: int = 2,
    settle: float | None = None,
) -> SteeringFrequencyResponse:
    r"""Frequency response from the front angle to yaw rate and lateral acceleration.

    ``model="linear"``: :math:`H(j\omega) = C(j\omega I - A)^{-1}B + D` of
    :func:`steering_response_system`, all frequencies at once.

    ``model="nonlinear"``: stepped sines. For each frequency the nonlinear
    model starts from straight driving with :math:`\delta_f =`
    `amplitude` :math:`\sin\omega t` (and :math:`\delta_r = a\,\delta_f`);
    all frequencies are integrated together (classic Runge-Kutta with a
    fixed step of at most 1/60 of the shortest period and 0.1 of the
    fastest time constant). After `settle` seconds the first harmonic of each
    response is fitted by least squares over the last `periods` whole
    periods (with the harmonics 2 to 11, which a saturating tyre excites);
    gain and phase are those of the first harmonic relative to the input.
    At a small amplitude this is the linear response (the tests hold the
    two equal to 1e-6); at a large amplitude with ``tyre="magic"`` the gain drops as the
    tyres saturate.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data (friction too for ``tyre="magic"``).
    speed : float
        Longitudinal speed :math:`u` [m/s], in [0.1, 1e6].
    omega : array_like
        Angular frequencies [rad/s], 1-D, strictly increasing, in (0, 1e4].
    ratio : float or callable, optional
        Rear-to-front ratio :math:`a` in [-10, 10] or a schedule
        ``ratio(vehicle, speed=...)``; default 0.
    model : {"linear", "nonlinear"}, optional
        Default ``"linear"``.
    tyre : {"linear", "magic"}, optional
        Tyre of the nonlinear model; ``"magic"`` needs ``model="nonlinear"``.
    amplitude : float, optional
        Front-angle amplitude of the sines [rad], in (0, 0.5]; nonlinear
        model only.
    periods : int, optional
        Whole periods of each frequency in the fit, 1 to 100.
    settle : float, optional
        Time [s] before the fit windows start, in (0, 1000]; default 15
        time constants of the slowest pole of the linear model (its
        transient then decays to 3e-7).

    Returns
    -------
    SteeringFrequencyResponse

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`, or an argument is a bool or
        complex.
    ValueError
        If an argument is out of range, the vehicle lacks the data, the
        model is unstable at `speed`, or the stepped sines would need more
        than 2e6 steps.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.vehicles.BMW_320I
    >>> w = np.array([1.0, 5.0, 20.0])
    >>> lin = fws.steering_frequency_response(veh, speed=20.0, omega=w)
    >>> nl = fws.steering_frequency_response(veh, speed=20.0, omega=w,
    ...                                      model="nonlinear", amplitude=1e-4)
    >>> bool(np.allclose(nl.yaw_rate_gain, lin.yaw_rate_gain, rtol=1e-5))
    True

    At 0.06 rad (a steady 0.9 g) the saturating tyre loses gain:

    >>> big = fws.steering_frequency_response(veh, speed=20.0, omega=w,
    ...     model="nonlinear", tyre="magic", amplitude=0.06)
    >>> (big.lateral_acceleration_gain / lin.lateral_acceleration_gain).round(2)
    array([0.99, 0.92, 0.86])
    """
    vehicle = require_dynamics(vehicle, tyre=tyre)
    u = _check_speed(speed)
    w = _check_grid("omega", omega, "rad/s", 1e4)
    a = float(_ratio_at(vehicle, ratio, u))
    model = _check_choice("model", model, MODELS)
    if model == "linear" and tyre != "linear":
        raise ValueError(
            f"tyre={tyre!r} needs model='nonlinear': the linear model has the "
            "tyres' slope at zero slip"
        )
    amp = _check_positive_scalar("amplitude", amplitude, "rad", 0.5)
    if (
        isinstance(periods, (bool, np.bool_))
        or not isinstance(periods, (int, np.integer))
        or not 1 <= periods <= 100
    ):
        raise ValueError(f"periods must be an integer in [1, 100], got {periods!r}")
    sys = steering_response_system(vehicle, speed=u, ratio=a)
    _check_stable(sys, u)
    poles = np.linalg.eigvals(sys.A)
    if settle is None:
        settle_t = 15.0 / float(np.min(-poles.real))
    else:
        settle_t = _check_positive_scalar("settle", settle, "s", 1000.0)
    if model == "linear":
        # H(jw) = C (jw I - A)^-1 B + D, every frequency in one solve
        eye = np.eye(2)
        x = np.linalg.solve(1j * w[:, None, None] * eye - sys.A, sys.B[None, :, :])
        h = (sys.C[None] @ x)[..., 0] + sys.D[:, 0]
        return _frequency_result(vehicle, u, a, model, tyre, 0.0, w, h[:, 0], h[:, 1])

    period = 2.0 * math.pi / w
    end = settle_t + periods * float(period.max())
    step = min(float(period.min()) / 60.0, 0.1 / float(np.max(np.abs(poles))))
    n = math.ceil(end / step)
    if n > 2_000_000:
        raise ValueError(
            f"the stepped sines need {n} steps of {step:.3g} s (omega from "
            f"{w[0]!r} to {w[-1]!r} rad/s, settle {settle_t:.3g} s); at most 2e6: "
            "narrow omega or shorten settle"
        )
    step = end / n
    t = step * np.arange(n + 1)

    rates = _body_rates(vehicle, tyre, u)

    def rhs(time, x):
        df = amp * np.sin(w * time)
        return np.array(rates(x[0], x[1], df, a * df))

    # classic RK4 on all frequencies at once (x has shape (2, n_omega));
    # keep v_y, r at every step for the fit
    x = np.zeros((2, w.size))
    states = np.empty((n + 1, 2, w.size))
    states[0] = x
    for i in range(n):
        ti = t[i]
        k1 = rhs(ti, x)
        k2 = rhs(ti + 0.5 * step, x + 0.5 * step * k1)
        k3 = rhs(ti + 0.5 * step, x + 0.5 * step * k2)
        k4 = rhs(ti + step, x + step * k3)
        x = x + (step / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        states[i + 1] = x
    if not np.all(np.isfinite(states)):
        raise ValueError(
            f"the stepped sines diverged at speed={u!r} m/s, amplitude={amp!r} rad"
        )
    v_y, r = states[:, 0, :], states[:, 1, :]
    df = amp * np.sin(w * t[:, None])
    vy_dot, _ = rates(v_y, r, df, a * df)
    a_y = vy_dot + u * r
    h_r = np.empty(w.size, dtype=complex)
    h_a = np.empty(w.size, dtype=complex)
    for k in range(w.size):
        # the last `periods` whole periods of this frequency: the samples
        # span them exactly only up to a step, so fit on the samples inside
        window = t >= t[-1] - periods * period[k]
        tk = t[window]
        # the window holds whole periods only to within a step: harmonics 2
        # to 11 of a saturating response are fitted too, so that they do not
        # leak into the first one
        wt = w[k] * tk
        basis = np.column_stack(
            [np.sin(wt), np.cos(wt), np.ones_like(tk)]
            + [f(j * wt) for j in range(2, 12) for f in (np.sin, np.cos)]
        )
        coef, *_ = np.linalg.lstsq(
            basis, np.column_stack([r[window, k], a_y[window, k]]), rcond=None
        )
        # y = |H| A sin(wt + phi) = |H| A (cos phi sin wt + sin phi cos wt)
        h_r[k] = complex(coef[0, 0], coef[1, 0]) / amp
        h_a[k] = complex(coef[0, 1], coef[1, 1]) / amp
    return _frequency_result(vehicle, u, a, model, tyre, amp, w, h_r, h_a)


def _frequency_result(vehicle, u, a, model, tyre, amp, w, h_r, h_a):
    return SteeringFrequencyResponse(
        vehicle,
        speed=u,
        ratio=a,
        model=model,
        tyre=tyre,
        amplitude=amp,
        omega=w,
        yaw_rate_gain=np.abs(h_r),
        yaw_rate_phase=_unwrap(h_r),
        lateral_acceleration_gain=np.abs(h_a),
        lateral_acceleration_phase=_unwrap(h_a),
    )


# --------------------------------------------------------------------------
# ISO 4138 steady-state circular driving, constant radius


@summary_repr
@dataclass(frozen=True, eq=False)
class SteadyStateCircle:
    r"""Steady states on a circle of constant radius (:func:`steady_state_circle`).

    Attributes
    ----------
    vehicle : Vehicle
        The vehicle.
    radius : float
        Radius of the path of the centre of gravity G [m].
    tyre : str
        Tyre model.
    lateral_acceleration : ndarray
        :math:`a_y = u r` [m/s^2], shape ``(n,)``.
    speed : ndarray
        Longitudinal speed :math:`u` [m/s].
    ratio : ndarray
        Rear-to-front ratio :math:`a(u)` at each point.
    delta_f, delta_r : ndarray
        Front and rear steering angle [rad].
    lateral_velocity : ndarray
        :math:`v_y` of G [m/s].
    yaw_rate : ndarray
        :math:`r` [rad/s].
    sideslip : ndarray
        Sideslip angle of G, :math:`\beta = \operatorname{atan2}(v_y, u)`
        [rad].
    slip_front, slip_rear : ndarray
        Slip angles of the axles [rad].
    understeer_gradient : ndarray
        :math:`d\delta_f/da_y` at constant radius [rad s^2/m] (central
        difference of two more steady states at :math:`a_y(1 \pm 10^{-4})`).

    Examples
    --------
    >>> import fws_control as fws
    >>> c = fws.steady_state_circle(fws.vehicles.BMW_320I, radius=100.0,
    ...                             lateral_acceleration=[1.0, 8.0])
    >>> c.speed.round(3)
    array([10.   , 28.275])
    """

    vehicle: Vehicle
    _: KW_ONLY
    radius: float
    tyre: str
    lateral_acceleration: np.ndarray
    speed: np.ndarray
    ratio: np.ndarray
    delta_f: np.ndarray
    delta_r: np.ndarray
    lateral_velocity: np.ndarray
    yaw_rate: np.ndarray
    sideslip: np.ndarray
    slip_front: np.ndarray
    slip_rear: np.ndarray
    understeer_gradient: np.ndarray

    def plot(self, ax: Any = None, *, label: str | None = None) -> ct.ControlPlot:
        """Front steering angle and understeer gradient against lateral acceleration.

        Parameters
        ----------
        ax : array of two matplotlib.axes.Axes, optional
            Axes for the steering angle and the understeer gradient; a new
            figure if None.
        label : str, optional
            Legend text; default names the tyre and the mean ratio.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> c = fws.steady_state_circle(fws.vehicles.BMW_320I, radius=100.0,
        ...                             lateral_acceleration=[1.0, 4.0, 8.0])
        >>> cplt = c.plot()
        >>> cplt.axes[0, 0].get_ylabel()
        'front angle delta_f [deg]'
        >>> plt.close(cplt.figure)
        """
        import control as ct

        axes = _two_axes(ax, sharex=True)
        if label is None:
            label = f"{self.tyre} tyre"
        (ln1,) = axes[0].plot(
            self.lateral_acceleration, np.degrees(self.delta_f), label=label
        )
        (ln2,) = axes[1].plot(
            self.lateral_acceleration,
            np.degrees(self.understeer_gradient),
            color=ln1.get_color(),
            label=label,
        )
        axes[0].set_ylabel("front angle delta_f [deg]")
        axes[1].set_ylabel("d delta_f / d a_y [deg s^2/m]")
        axes[1].set_xlabel("lateral acceleration a_y [m/s^2]")
        axes[0].legend(fontsize="small")
        axes[0].set_title(f"steady-state circle, radius {self.radius:g} m")
        return ct.ControlPlot(
            np.array([ln1, ln2], dtype=object), np.array(axes).reshape(2, 1),
            axes[0].figure,
        )  # fmt: skip


def _rising_limit(vehicle: DynamicVehicle, tyre: str) -> tuple[float, float]:
    """Slip angles [rad] of the peak force of each axle (inf for linear tyres)."""
    if tyre == "linear":
        return math.inf, math.inf
    fz_f, fz_r = axle_loads(vehicle)
    out = []
    for c, fz in ((vehicle.cornering_front, fz_f), (vehicle.cornering_rear, fz_r)):
        b = c / (equations.MAGIC_SHAPE * cast(float, vehicle.friction) * fz)
        out.append(math.tan(math.pi / (2.0 * equations.MAGIC_SHAPE)) / b)
    return out[0], out[1]


def steady_state_circle(
    vehicle: Vehicle,
    *,
    lateral_acceleration: RealArrayLike,
    radius: float = 100.0,
    ratio: RatioLike = 0.0,
    tyre: str = "magic",
) -> SteadyStateCircle:
    r"""ISO 4138 steady-state circular driving on a constant radius.

    For each lateral acceleration :math:`a_y` the nonlinear single-track
    model drives steadily on a circle: the centre of gravity G moves on a
    circle of `radius` :math:`R` at the longitudinal speed :math:`u` (raised
    from point to point, as in the standard's constant-radius method), with
    the rear angle :math:`\delta_r = a(u)\,\delta_f`. The unknowns
    :math:`(u, v_y, \delta_f)` solve (:func:`scipy.optimize.root`)

    .. math::
        \dot v_y = 0,\qquad \dot r = 0,\qquad
        \sqrt{u^2 + v_y^2} = r R,\qquad r = a_y/u,

    with the body equations of :mod:`fws_control.dynamics`. Each point
    starts from the previous one (continuation in :math:`a_y`), so the
    solution follows the stable branch up to the tyres' limit.

    The understeer gradient is :math:`d\delta_f/da_y` at constant radius
    (the Ackermann angle :math:`f/R` does not change). For linear tyres and
    small angles it is :func:`fws_control.understeer_gradient`,
    :math:`K_{us} = \frac{m}{f}(\frac{l_r}{C_f} - \frac{l_f}{C_r})`, with the
    cornering stiffnesses :math:`C_f, C_r` of whole axles.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data (friction too for ``tyre="magic"``).
    lateral_acceleration : array_like
        :math:`a_y` [m/s^2], 1-D, strictly increasing, in (0, 100].
    radius : float, optional
        Radius of G's path [m], in [1, 1e7]; default 100 m (ISO 4138's
        preferred radius).
    ratio : float or callable, optional
        Rear-to-front ratio :math:`a` in [-10, 10] or a schedule
        ``ratio(vehicle, speed=...)`` evaluated at each point's speed, e.g.
        :func:`fws_control.zero_sideslip_ratio`; default 0.
    tyre : {"linear", "magic"}, optional
        Tyre model, default ``"magic"``.

    Returns
    -------
    SteadyStateCircle

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`, or an argument is a bool or
        complex.
    ValueError
        If an argument is out of range, the vehicle lacks the data, or a
        lateral acceleration is beyond what the tyres hold on this circle
        (the message names it and the last one that has a steady state).

    Examples
    --------
    The BMW 320i of CommonRoad is neutral steer in the linear range; the
    saturating tyre makes it understeer near the limit:

    >>> import fws_control as fws
    >>> c = fws.steady_state_circle(fws.vehicles.BMW_320I, radius=100.0,
    ...                             lateral_acceleration=[0.5, 9.0])
    >>> (c.understeer_gradient * 1e3).round(3)        # mrad per m/s^2
    array([0.003, 0.021])
    """
    from scipy.optimize import root

    vehicle = require_dynamics(vehicle, tyre=tyre)
    tyre = _check_choice("tyre", tyre, TYRES)
    a_y = _check_grid("lateral_acceleration", lateral_acceleration, "m/s^2", 100.0)
    rad = check_real("radius", radius)
    if rad.ndim != 0 or not (math.isfinite(float(rad)) and 1.0 <= float(rad) <= 1e7):
        raise ValueError(f"radius must be a scalar in [1, 1e7] m, got {radius!r}")
    big_r = float(rad)
    lim_f, lim_r = _rising_limit(vehicle, tyre)
    l_f, l_r = vehicle.front_to_cg, vehicle.rear_to_cg

    def ratio_at(u):
        return float(_ratio_at(vehicle, ratio, u))

    def solve(acc, guess):
        def residual(x):
            u, v_y, df = x
            if not u > 0.0:
                # keep the search on forward driving (atan2(., u) needs u > 0)
                return [1e6 * (1.0 - u), 0.0, 0.0]
            r = acc / u
            vy_dot, r_dot = _body_rates(vehicle, tyre, u)(v_y, r, df, ratio_at(u) * df)
            return [float(vy_dot), float(r_dot), math.hypot(u, v_y) - r * big_r]

        sol = root(residual, guess, method="hybr", options={"xtol": 1e-15})
        u, v_y, df = (float(v) for v in sol.x)
        ok = u > 0.0 and np.max(np.abs(sol.fun)) <= 1e-9 * max(1.0, acc)
        if ok:
            alpha = equations.slip_angles(
                u, l_f, l_r, v_y, acc / u, df, ratio_at(u) * df
            )
            ok = abs(float(alpha[0])) < lim_f and abs(float(alpha[1])) < lim_r
        return (u, v_y, df) if ok else None

    n = a_y.size
    out = np.empty((n, 3))
    grad = np.empty(n)
    prev = None
    for i, acc in enumerate(a_y):
        # continuation: each point from the previous one, scaled to the new
        # speed; the first from the kinematic turn
        if prev is None:
            u0 = math.sqrt(acc * big_r)
            guess = (u0, l_r * acc / u0, vehicle.wheelbase / big_r)
        else:
            scale = math.sqrt(acc / a_y[i - 1])
            guess = (prev[0] * scale, prev[1] * scale, prev[2])
        x = solve(acc, guess)
        if x is None:
            last = f"{a_y[i - 1]!r} m/s^2" if i > 0 else "none of them"
            raise ValueError(
                f"lateral_acceleration={float(acc)!r} m/s^2 has no steady state on "
                f"radius={big_r!r} m with the {tyre} tyre (ratio {ratio!r}): "
                f"beyond what the tyres hold; the last one with a steady state "
                f"is {last}"
            )
        out[i] = x
        prev = x
        h = 1e-4 * acc
        hi, lo = solve(acc + h, x), solve(acc - h, x)
        if hi is None or lo is None:
            raise ValueError(
                f"lateral_acceleration={float(acc)!r} m/s^2 on radius={big_r!r} m is "
                f"within 1e-4 of the limit of the {tyre} tyre: no understeer "
                "gradient there"
            )
        grad[i] = (hi[2] - lo[2]) / (2.0 * h)
    u, v_y, delta_f = out.T
    r = a_y / u
    a = np.array([ratio_at(v) for v in u])
    delta_r = a * delta_f
    alpha_f, alpha_r = equations.slip_angles(u, l_f, l_r, v_y, r, delta_f, delta_r)
    return SteadyStateCircle(
        vehicle,
        radius=big_r,
        tyre=tyre,
        lateral_acceleration=a_y,
        speed=u,
        ratio=a,
        delta_f=delta_f,
        delta_r=delta_r,
        lateral_velocity=v_y,
        yaw_rate=r,
        sideslip=np.arctan2(v_y, u),
        slip_front=np.asarray(alpha_f),
        slip_rear=np.asarray(alpha_r),
        understeer_gradient=grad,
    )
