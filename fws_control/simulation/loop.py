r"""The closed loop's vectorised right-hand side, :class:`ClosedLoop`.

The path-frame model (eqs. 17-19, corrected, with the path's curvature
:math:`\kappa(s)` at the arclength state) closed with the controller of
eqs. (24)-(29) (or a lateral controller), for ``n`` runs at once: the
layout of the stacked state, the command and its rate, the steering
actuator, the dynamic single-track body and the margins to the singular
states at which a run stops. A varying speed (a
:class:`~fws_control.SpeedProfile`) and a gain schedule
(:func:`scheduled_gains`) are read at the current speed.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from .. import equations
from ..controllers import (
    actuator_rate,
    steering_command,
    steering_command_rate,
)
from ..dynamics import (
    dynamic_path_derivatives,
)
from ..gains import SteeringGains
from ..lateral_controller import saturate
from ..paths import Arc, Path, Straight
from .outcomes import STOP_MARGIN

__all__ = [
    "ClosedLoop",
    "scheduled_gains",
    "is_sampled",
    "hold_row",
]


def _curvature_function(path):
    """``s -> kappa(s)`` for `path`, with the constant cases short-cut."""
    if isinstance(path, (Arc, Straight)):
        k = float(Path.curvature(path, 0.0))
        return lambda s: np.full(np.shape(s), k)
    return path.curvature


#: Relative step in the speed of the central difference that gives the
#: rate of a scheduled command, ``(d command/dV) dV/dt`` (error ~ h^2 of the
#: schedule's third derivative; at a knot of a piecewise linear
#: :class:`~fws_control.GainSchedule` the mean of the two slopes).
_SCHEDULE_STEP = 1e-6


def scheduled_gains(schedule: Any, speed: Any) -> SteeringGains:
    """The gains of a schedule at `speed` (``schedule.at`` or the function).

    A schedule is an object with a method ``at(speed)`` (e.g.
    :class:`~fws_control.GainSchedule`) or a function ``speed ->
    SteeringGains``, vectorised over an array of speeds.

    Raises
    ------
    TypeError
        If it returns something else than a SteeringGains.
    """
    at = getattr(schedule, "at", None)
    gains = at(speed) if callable(at) else schedule(speed)
    if not isinstance(gains, SteeringGains):
        raise TypeError(
            "a gain schedule must return a SteeringGains at a speed, got "
            f"{type(gains).__name__} from {schedule!r}"
        )
    return gains


def _check_profile_values(profile, V, x, dynamic: bool) -> None:
    """Refuse what a user's speed function returns mid-run: NaN or reversing."""
    V = np.asarray(V)
    bad = ~np.isfinite(V)
    what = "time [s]" if profile.of == "time" else "arc length [m]"
    xs = np.broadcast_to(np.asarray(x, dtype=float), V.shape)
    if np.any(bad):
        i = int(np.flatnonzero(bad.ravel())[0])
        raise ValueError(
            f"speed: the SpeedProfile function returned {float(V.ravel()[i])!r} at "
            f"{what} {float(xs.ravel()[i])!r}; it must return finite speeds [m/s]"
        )
    # (a function drives forward: its sign cannot be checked ahead of the run)
    low = V <= 0.0 if dynamic else V < 0.0
    if np.any(low):
        i = int(np.flatnonzero(low.ravel())[0])
        rng = "(0, inf) for model='dynamic'" if dynamic else "[0, inf)"
        raise ValueError(
            f"speed: the SpeedProfile function returned {float(V.ravel()[i])!r} m/s at "
            f"{what} {float(xs.ravel()[i])!r}: reversing through zero speed is not "
            f"simulated; speeds must lie in {rng}"
        )


class ClosedLoop:
    """Vectorised closed-loop right-hand side for ``n`` runs.

    The state is laid out as ``(m, n)`` flattened row-major: rows ``s, e,
    theta``, with a steering actuator ``delta_f, delta_r``, and with the
    dynamic model ``v_y, r`` last.
    """

    def __init__(
        self, vehicle, path, gains, speed, feedforward, tau, delay=0.0, history=None,
        runs=None, model="kinematic", tyre="linear", hold=None, profile=None,
        schedule=None, modes=None,
    ):  # fmt: skip
        # hold: first of the two rows of a sampled controller's held command
        # (None: a static law, evaluated at every stage)
        self.hold = hold
        self.delay = delay
        # a SpeedProfile (None: the constant per-run `speed`) and a gain
        # schedule read at the current speed (None: the fixed `gains`)
        self.profile = profile
        self.schedule = schedule
        self.history = history
        self.runs = runs
        self.delayed = None
        self.vehicle = vehicle
        self.path = path
        self.gains = gains
        self.speed = speed
        self.ff = feedforward
        self.tau = tau
        self.dynamic = model == "dynamic"
        self.tyre = tyre
        self.m = (
            (3 if tau is None else 5)
            + (0 if hold is None else 2)
            + (2 if self.dynamic else 0)
        )
        self._kappa = _curvature_function(path)
        length = float(getattr(path, "length", math.inf))
        self.open_length = (
            length if (math.isfinite(length) and not path.closed) else None
        )
        # The clips as switched modes (None: min/max in the right-hand side):
        # rows front/rear angle, front/rear rate, one column per run, -1, 0
        # or +1 (held at the lower limit, free, held at the upper one); and
        # the held mode each clip was released from at the solver's restart
        # (0 once a step has been accepted since). Between the located
        # switches (switch_margins) the right-hand side is then smooth.
        self.modes = None
        self.released = None
        if modes is not None:
            self.modes = np.array(modes, dtype=float).reshape(4, -1)
            self.released = np.zeros_like(self.modes)
            # the raw (unclipped) law and actuator: the vehicle without limits
            self._free = dataclasses.replace(
                vehicle,
                max_steer_front=None,
                max_steer_rear=None,
                max_steer_rate_front=None,
                max_steer_rate_rear=None,
            )
            # the limits of the four clips (inf: none)
            limits = (
                vehicle.max_steer_front,
                vehicle.max_steer_rear,
                vehicle.max_steer_rate_front if tau is not None else None,
                vehicle.max_steer_rate_rear if tau is not None else None,
            )
            self.limits = np.array([math.inf if v is None else v for v in limits])

    def clip(self, s):
        # Trial stages of the solver may step slightly past the end of an open
        # path, where the path refuses to evaluate; the end-of-path event stops
        # the run there, so clipping only affects rejected or final stages.
        if self.open_length is None:
            return s
        return np.clip(s, 0.0, self.open_length)

    def curvature(self, s):
        return np.broadcast_to(
            np.asarray(self._kappa(self.clip(s)), dtype=float), s.shape
        )

    def speed_at(self, t, s):
        """Speed of each column: the constant ``speed`` or the profile's."""
        if self.profile is None:
            return self.speed
        x = t if self.profile.of == "time" else s
        V = self.profile(np.broadcast_to(np.asarray(x, dtype=float), np.shape(s)))
        if self.profile.function is not None:
            _check_profile_values(self.profile, V, x, self.dynamic)
        return V

    def speed_rate(self, t, s, s_dot):
        """``dV/dt`` of each column (0 at a constant speed)."""
        if self.profile is None:
            return np.zeros(np.shape(s))
        if self.profile.of == "time":
            return self.profile.derivative(np.broadcast_to(t, np.shape(s)))
        return self.profile.derivative(s) * s_dot

    def gains_at(self, V):
        """The gains of the paper's law at the speeds `V` (scheduled or fixed)."""
        if self.schedule is None:
            return self.gains
        return scheduled_gains(self.schedule, V)

    def command(self, Y, kappa, t, V=None):
        """Controller output at time `t`, from the measurements at ``t - delay``."""
        if self.hold is not None:
            # a sampled controller: the command held since its last sample
            # (already delayed and saturated when it was set)
            return Y[self.hold], Y[self.hold + 1]
        if V is None:
            V = self.speed_at(t, Y[0])
        if self.delayed is not None:  # delayed states given (output stage)
            Y, kappa = self.delayed, self.curvature(self.delayed[0])
        elif self.delay > 0.0 and self.history is not None:
            # (no history yet only at the start, where the delayed state is the
            # initial one: the current Y)
            Yd = self.history.state(t - self.delay, self.runs)
            Y, kappa = Yd, self.curvature(Yd[0])
        if self.modes is not None:
            return self._held(*self._raw_command(Y, kappa, V), 0)
        if not isinstance(self.gains, SteeringGains):  # a LateralController
            df, dr = self.gains.steering(
                self.vehicle,
                self.path,
                s=self.clip(Y[0]),
                e=Y[1],
                theta=Y[2],
                curvature=kappa,
                speed=V,
            )
            return saturate(self.vehicle, df, dr)
        return self._law(self.vehicle, Y, kappa, V)

    def _law(self, vehicle, Y, kappa, V):
        """The paper's law (eqs. 24-29) clipped to `vehicle`'s angle limits."""
        return steering_command(
            vehicle,
            self.gains_at(V),
            Y[1],
            Y[2],
            curvature=kappa,
            feedforward=self.ff,
            # (used by feedforward="dynamic" only)
            speed=V,
            tyre=self.tyre,
        )

    def _raw_command(self, Y, kappa, V):
        """The law's command before the angle clips (switching modes only)."""
        if not isinstance(self.gains, SteeringGains):
            return self.gains.steering(
                self.vehicle, self.path, s=self.clip(Y[0]), e=Y[1], theta=Y[2],
                curvature=kappa, speed=V,
            )  # fmt: skip
        return self._law(self._free, Y, kappa, V)

    def _held(self, front, rear, row):
        """Channels `front`, `rear` with the held ones at their limits.

        Clips ``row``, ``row + 1`` of :attr:`modes` (0: the angles, 2: the
        actuator's rates): a held channel is ``mode * limit``.
        """
        mf, mr = self.modes[row], self.modes[row + 1]
        lf, lr = self.limits[row], self.limits[row + 1]
        # (copysign: mode * limit, without 0 * inf where a free clip has none)
        return (
            np.where(mf != 0.0, np.copysign(lf, mf), front),
            np.where(mr != 0.0, np.copysign(lr, mr), rear),
        )

    def clip_values(self, Y, t=0.0):
        """The four clipped quantities before their clips, shape ``(4, n)``.

        Rows: the law's front and rear angle commands, the actuator's front
        and rear rates (from the command with the held angle clips; zero
        without an actuator). Switching modes only.
        """
        kappa = self.curvature(Y[0])
        V = self.speed_at(t, Y[0])
        raw = np.zeros((4, Y.shape[1]))
        raw[0], raw[1] = self._raw_command(Y, kappa, V)
        if self.tau is not None:
            cmd = self._held(raw[0], raw[1], 0)
            raw[2], raw[3] = actuator_rate(
                self._free, cmd, (Y[3], Y[4]), time_constant=self.tau
            )
        return raw

    def switch_margins(self, Y, t=0.0):
        """Event functions of the clips' switches, shape ``(4, n)``.

        :func:`~fws_control.equations.clip_switch_margin` of each clip (rows
        as :attr:`modes`): a clip switches where its margin reaches <= 0.
        """
        return equations.clip_switch_margin(
            self.clip_values(Y, t), self.limits[:, None], self.modes, self.released
        )

    def start_modes(self, Y, t, rows):
        """Hold the clips `rows` that are beyond their limits in state `Y`."""
        raw = self.clip_values(Y, t)
        for j in rows:
            beyond = np.abs(raw[j]) > self.limits[j]
            self.modes[j] = np.where(beyond, np.sign(raw[j]), 0.0)

    def switch(self, Y, t, clip, run):
        """Switch clip `clip` of column `run` at state `Y` (a located event).

        A held clip is released (and remembers the limit it left, for the
        next step); a free one is held at the limit its value crossed. A
        clip released before and now inside its limits watches both limits
        again.
        """
        raw = self.clip_values(Y, t)
        inside = np.abs(raw) < self.limits[:, None]
        self.released[(self.released != 0.0) & inside] = 0.0
        if self.modes[clip, run] != 0.0:
            self.released[clip, run] = self.modes[clip, run]
            self.modes[clip, run] = 0.0
        else:
            self.modes[clip, run] = 1.0 if raw[clip, run] > 0.0 else -1.0
            self.released[clip, run] = 0.0

    def command_rate(self, Y, Ydot, kappa, t=0.0):
        """Time derivative of the command for (delayed) states and their rates."""
        if self.hold is not None:
            # piecewise constant: no rate between the samples (its jumps are
            # not rates)
            zero = np.zeros(np.shape(Y[0]))
            return zero, zero.copy()
        kappa_rate = (
            np.asarray(self.path.curvature_rate(self.clip(Y[0])), dtype=float) * Ydot[0]
        )
        if isinstance(self.gains, SteeringGains):
            V = self.speed_at(t, Y[0])
            rf, rr = steering_command_rate(
                self.vehicle,
                self.gains_at(V),
                Y[1],
                Y[2],
                Ydot[1],
                Ydot[2],
                curvature=kappa,
                curvature_rate=kappa_rate,
                feedforward=self.ff,
                speed=V,
                tyre=self.tyre,
            )
            if self.schedule is None:
                return rf, rr
            # gains that follow the speed add (d command/dV) dV/dt: a central
            # difference in V of the command (clipped where it is), at the
            # state of the sample
            V_dot = self.speed_rate(t, Y[0], Ydot[0])
            h = _SCHEDULE_STEP * np.maximum(1.0, np.abs(V))
            v_up, v_down = V + h, V - h
            # a table does not extrapolate: one-sided at the ends of its range
            speeds = getattr(self.schedule, "speeds", None)
            if speeds is not None:
                v_up = np.minimum(v_up, np.max(speeds))
                v_down = np.maximum(v_down, np.min(speeds))
            up = self.command(Y, kappa, t, v_up)
            down = self.command(Y, kappa, t, v_down)
            return (
                rf + (up[0] - down[0]) / (v_up - v_down) * V_dot,
                rr + (up[1] - down[1]) / (v_up - v_down) * V_dot,
            )
        ctrl = self.gains
        kw = dict(
            s=self.clip(Y[0]), e=Y[1], theta=Y[2], curvature=kappa, speed=self.speed
        )
        raw_f, raw_r = ctrl.steering(self.vehicle, self.path, **kw)
        rf, rr = ctrl.steering_rate(
            self.vehicle, self.path, s_dot=Ydot[0], e_dot=Ydot[1], theta_dot=Ydot[2],
            **kw,
        )  # fmt: skip
        # a saturated channel does not move
        lim_f = self.vehicle.max_steer_front
        lim_r = self.vehicle.max_steer_rear
        if lim_f is not None:
            rf = np.where(np.abs(raw_f) > lim_f, 0.0, rf)
        if lim_r is not None:
            rr = np.where(np.abs(raw_r) > lim_r, 0.0, rr)
        return rf, rr

    def steering(self, Y, kappa, t=0.0):
        if self.tau is None:
            return self.command(Y, kappa, t)
        return Y[3], Y[4]

    def derivatives(self, Y, t=0.0):
        """Return ``(Ydot, kappa, delta_f, delta_r)`` for states ``Y (m, n)``."""
        s, e, th = Y[0], Y[1], Y[2]
        kappa = self.curvature(s)
        V = self.speed_at(t, s)
        df, dr = self.command(Y, kappa, t, V) if self.tau is None else (Y[3], Y[4])
        body = ()
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.dynamic:
                # v_y, r are the last two rows (after the actuator's)
                s_dot, e_dot, th_dot, *body = dynamic_path_derivatives(
                    self.vehicle, kappa, e, th, Y[-2], Y[-1], df, dr,
                    speed=V, tyre=self.tyre,
                )  # fmt: skip
            else:
                s_dot, e_dot, th_dot = equations.path_frame_derivatives(
                    V, self.vehicle.wheelbase, kappa, e, th, df, dr
                )
        held = () if self.hold is None else (np.zeros_like(s_dot),) * 2
        if self.tau is None:
            Ydot = np.stack([s_dot, e_dot, th_dot, *held, *body])
        else:
            cmd = self.command(Y, kappa, t, V)
            if self.modes is None:
                rf, rr = actuator_rate(
                    self.vehicle, cmd, (df, dr), time_constant=self.tau
                )
            else:
                rf, rr = self._held(
                    *actuator_rate(self._free, cmd, (df, dr), time_constant=self.tau),
                    2,
                )
            Ydot = np.stack([s_dot, e_dot, th_dot, rf, rr, *held, *body])
        return Ydot, kappa, df, dr

    def rhs(self, t, y):
        Y = y.reshape(self.m, -1)
        return self.derivatives(Y, t)[0].ravel()

    def margins(self, Y, t=0.0):
        """Distance to each stop condition, shape ``(3, n)``; stop where <= 0."""
        kappa = self.curvature(Y[0])
        df, _ = self.steering(Y, kappa, t)
        out = np.full((3, Y.shape[1]), np.inf)
        out[0] = (0.5 * math.pi - STOP_MARGIN) - np.abs(df)
        out[1] = (1.0 - kappa * Y[1]) - STOP_MARGIN
        if self.open_length is not None:
            # The offset lets a run start exactly at s = 0 (or at the end).
            out[2] = np.minimum(Y[0], self.open_length - Y[0]) / self.open_length + 1e-9
        return out

    def event(self, t, y):
        return float(np.min(self.margins(y.reshape(self.m, -1), t)))


def is_sampled(controller: Any) -> bool:
    """True for a sampled controller (one that declares a ``sample_time``)."""
    return getattr(controller, "sample_time", None) is not None


def hold_row(controller: Any, time_constant: float | None) -> int | None:
    """First state row of a sampled controller's held command (else None).

    The rows follow ``s, e, theta`` and the actuator's ``delta_f, delta_r``
    (with a lag) and precede the dynamic model's ``v_y, r``.
    """
    if not is_sampled(controller):
        return None
    return 3 if time_constant is None else 5
