r"""Closed-loop simulation of the 4WS path-tracking controller.

Two independent implementations of the same closed loop:

:func:`closed_loop_system`
    The composable reference: the global-frame vehicle (eqs. 8-10), a
    projection block that maps ``(x, y, psi)`` to the path errors
    ``(s, e, theta)`` and the curvature, and the controller (eqs. 24-29),
    joined with :func:`control.interconnect` and simulated with
    :func:`control.input_output_response`.

:func:`simulate`
    The fast engine: the path-frame model (eqs. 17-19, corrected, with the
    path's curvature :math:`\kappa(s)` at the arclength state) closed with the
    controller in one vectorised right-hand side, integrated with
    :func:`scipy.integrate.solve_ivp`. No projection is needed during the
    integration; the global pose is reconstructed afterwards as
    ``position(s) + e * normal(s)``, ``psi = theta + heading(s)``. The same
    engine integrates many runs at once in :func:`fws_control.simulate_batch`.

A run stops, and is marked in its result rather than raising, when the model
becomes singular: a front steering angle :math:`|\delta_f| = \pi/2` (the yaw
rate of eq. 10 diverges), :math:`1-\kappa e = 0` (the vehicle reaches the
centre of curvature and the projection is lost) or the end of an open path.
The data up to that time are kept.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import Any

import control as ct
import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, OdeSolver, Radau
from scipy.optimize import brentq

from .acceleration import lateral_acceleration
from .controllers import (
    DEFAULT_ACTUATOR_TIME_CONSTANT,
    actuator_rate,
    path_tracking_controller,
    steering_actuator,
    steering_command,
    steering_command_rate,
)
from .gains import SteeringGains
from .models import global_frame_model, path_frame_derivatives
from .paths import Arc, Path, Straight
from .validation import check_finite, check_nonzero, check_positive, check_type
from .vehicle import Vehicle


def check_path(path: Any) -> None:
    """Refuse anything that is not a :class:`~fws_control.paths.Path`."""
    if not isinstance(path, Path):
        raise TypeError(f"path must be a fws_control Path, got {type(path).__name__}")


__all__ = [
    "SimulationResult",
    "simulate",
    "closed_loop_system",
    "projection_system",
    "STATUS_OK",
    "STATUS_SINGULAR_STEERING",
    "STATUS_SINGULAR_CURVATURE",
    "STATUS_END_OF_PATH",
    "STATUS_FAILED",
    "STATUS_UNCONTROLLABLE",
]

#: The run reached the final time.
STATUS_OK = "ok"
#: The front steering angle reached :math:`|\delta_f| = \pi/2`.
STATUS_SINGULAR_STEERING = "singular_steering"
#: :math:`1 - \kappa e` reached 0: the vehicle is at the centre of curvature.
STATUS_SINGULAR_CURVATURE = "singular_curvature"
#: The projection left an open path of finite length.
STATUS_END_OF_PATH = "end_of_path"
#: The ODE solver failed (its message is kept).
STATUS_FAILED = "failed"
#: No gains exist for the requested design (used by the scenario functions
#: for ``ratio = 1`` on a straight road); the run was not simulated.
STATUS_UNCONTROLLABLE = "uncontrollable"

_SOLVERS = {
    "DOP853": DOP853,
    "RK45": RK45,
    "RK23": RK23,
    "Radau": Radau,
    "BDF": BDF,
    "LSODA": LSODA,
}

_STOP_KINDS = (STATUS_SINGULAR_STEERING, STATUS_SINGULAR_CURVATURE, STATUS_END_OF_PATH)

#: Names of the time series of a result, in order.
SIGNALS = (
    "x",
    "y",
    "psi",
    "s",
    "e",
    "theta",
    "delta_f",
    "delta_r",
    "delta_f_rate",
    "delta_r_rate",
    "lateral_accel",
)


# --------------------------------------------------------------------------
# Result


@dataclass(frozen=True, eq=False)
class SimulationResult:
    r"""Time response of one closed-loop run.

    Attributes
    ----------
    t : ndarray
        Time [s], shape ``(n,)``.
    x, y, psi : ndarray
        Global pose of the rear-axle centre R [m, m, rad]; ``psi`` is
        continuous (not wrapped) and starts at the given initial heading.
    s, e, theta : ndarray
        Arclength of the projection point [m], lateral error [m] (positive
        left of the path) and heading error :math:`\theta = \psi - \psi_C`
        [rad].
    delta_f, delta_r : ndarray
        Front and rear steering angles [rad] applied to the vehicle.
    delta_f_rate, delta_r_rate : ndarray
        Their time derivatives [rad/s], exact (chain rule through the
        controller and the path's curvature derivative).
    lateral_accel : ndarray
        Lateral acceleration of the centre of gravity G, eq. (13) [m/s^2].
    status : str
        ``"ok"`` or why the run stopped early (``"singular_steering"``,
        ``"singular_curvature"``, ``"end_of_path"``, ``"failed"``,
        ``"uncontrollable"``).
    message : str
        Human-readable explanation when `status` is not ``"ok"``.
    t_stop : float
        Time at which the run ended [s] (the final time for ``"ok"``). The
        data hold the output times up to `t_stop`.
    speed : float
        Speed :math:`V` [m/s].
    gains : SteeringGains or None
        The controller gains.
    feedforward : bool
        Whether the curvature feedforward was used.
    vehicle : Vehicle or None
    path : path object or None
        Used by :meth:`plot` to draw the reference path.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    s: np.ndarray
    e: np.ndarray
    theta: np.ndarray
    delta_f: np.ndarray
    delta_r: np.ndarray
    delta_f_rate: np.ndarray
    delta_r_rate: np.ndarray
    lateral_accel: np.ndarray
    status: str = STATUS_OK
    message: str = ""
    t_stop: float = math.nan
    speed: float = math.nan
    gains: SteeringGains | None = None
    feedforward: bool = True
    vehicle: Vehicle | None = field(default=None, repr=False)
    path: Any = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        """True if the run reached the final time."""
        return self.status == STATUS_OK

    @property
    def singular(self) -> bool:
        """True if the run stopped at a singular state of the model."""
        return self.status in (STATUS_SINGULAR_STEERING, STATUS_SINGULAR_CURVATURE)

    def plot(self, fig=None, label: str | None = None):
        """Plot the response: errors, trajectory, steering, lateral acceleration.

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Figure to draw into (its axes are reused if it has six); a new one
            is created otherwise.
        label : str, optional
            Legend label of this run.

        Returns
        -------
        matplotlib.figure.Figure
            Six panels: lateral error ``e`` [m], heading error ``theta``
            [deg], trajectory ``y`` over ``x`` [m] with the reference path,
            ``delta_f`` and ``delta_r`` [deg], lateral acceleration
            [m/s^2]. A run that stopped early is marked with an ``x`` at its
            last point and its status in the legend.
        """
        return plot_responses([self], [label], fig=fig)

    def to_pandas(self):
        """The time series as a :class:`pandas.DataFrame` indexed by ``t``.

        The status, message and stop time are in ``DataFrame.attrs``.

        Raises
        ------
        ImportError
            If pandas is not installed.
        """
        pd = _import_pandas()
        df = pd.DataFrame({name: getattr(self, name) for name in SIGNALS})
        df.index = pd.Index(self.t, name="t")
        df.attrs.update(
            status=self.status,
            message=self.message,
            t_stop=self.t_stop,
            speed=self.speed,
            feedforward=self.feedforward,
        )
        return df


def _import_pandas():
    try:
        import pandas as pd
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "to_pandas() needs pandas; install it with `pip install pandas` "
            "(or the extra `fws-control[test]`)"
        ) from exc
    return pd


# --------------------------------------------------------------------------
# Plotting shared with BatchResult


def plot_responses(results, labels=None, fig=None):
    """Overlay the responses of several :class:`SimulationResult` objects.

    Parameters
    ----------
    results : sequence of SimulationResult
    labels : sequence of str or None, optional
        Legend labels, one per result.
    fig : matplotlib.figure.Figure, optional
        Figure to draw into.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    results = list(results)
    labels = [None] * len(results) if labels is None else list(labels)
    if fig is None:
        fig = plt.figure(figsize=(11, 9), layout="constrained")
    axes = fig.axes if len(fig.axes) == 6 else fig.subplots(3, 2).ravel()
    ax_e, ax_th, ax_xy, ax_df, ax_dr, ax_a = axes
    panels = (
        (ax_e, "e", 1.0, "lateral error e [m]"),
        (ax_th, "theta", 180 / math.pi, "heading error θ [deg]"),
        (ax_df, "delta_f", 180 / math.pi, "front steering δf [deg]"),
        (ax_dr, "delta_r", 180 / math.pi, "rear steering δr [deg]"),
        (ax_a, "lateral_accel", 1.0, "lateral acceleration of G [m/s²]"),
    )
    s_lo, s_hi = math.inf, -math.inf
    for res, lab in zip(results, labels, strict=True):
        text = lab if lab is not None else ""
        if res.status == STATUS_UNCONTROLLABLE:
            text = f"{text} (uncontrollable: not simulated)".strip()
        elif not res.ok:
            text = f"{text} ({res.status} at t={res.t_stop:.3g} s)".strip()
        color = None
        for ax, name, scale, _ in panels:
            (line,) = ax.plot(
                res.t, scale * getattr(res, name), label=text or None, color=color
            )
            color = line.get_color()
            if not res.ok and res.t.size:
                ax.plot(res.t[-1], scale * getattr(res, name)[-1], "x", color=color)
        ax_xy.plot(res.x, res.y, color=color, label=text or None)
        if not res.ok and res.t.size:
            ax_xy.plot(res.x[-1], res.y[-1], "x", color=color)
        if res.s.size and np.any(np.isfinite(res.s)):
            s_lo = min(s_lo, float(np.nanmin(res.s)))
            s_hi = max(s_hi, float(np.nanmax(res.s)))
    path = next((r.path for r in results if r.path is not None), None)
    if path is not None and math.isfinite(s_lo):
        span = max(s_hi - s_lo, 1.0)
        ss = np.linspace(s_lo - 0.05 * span, s_hi + 0.05 * span, 400)
        if not getattr(path, "closed", False):
            ss = np.clip(ss, 0.0, getattr(path, "length", math.inf))
        px, py = path.position(ss)
        ax_xy.plot(px, py, "k--", lw=1.0, label="path")
    for ax, _, _, ylabel in panels:
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    ax_xy.set_xlabel("x [m]")
    ax_xy.set_ylabel("y [m]")
    ax_xy.set_title("trajectory of R")
    ax_xy.set_aspect("equal", adjustable="datalim")
    ax_xy.grid(True, alpha=0.3)
    if any(lab is not None for lab in labels) or any(not r.ok for r in results):
        ax_e.legend(fontsize="small")
    if path is not None:
        ax_xy.legend(fontsize="small")
    return fig


# --------------------------------------------------------------------------
# Fast engine (shared with simulate_batch)


def _as_runs(value, n: int, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    try:
        return np.broadcast_to(arr, (n,)).copy()
    except ValueError:
        raise ValueError(
            f"{name} must be a scalar or have one value per run ({n}), got shape "
            f"{arr.shape}"
        ) from None


def _initial_path_state(path, initial_state: np.ndarray) -> np.ndarray:
    """Project global initial poses ``(N, 3)`` onto the path -> ``(N, 3)``."""
    out = np.empty_like(initial_state)
    for i, (x0, y0, psi0) in enumerate(initial_state):
        p = path.project(float(x0), float(y0), strict=True)
        theta0 = math.remainder(float(psi0) - float(p.heading), 2 * math.pi)
        out[i] = (float(p.s), float(p.e), theta0)
    return out


def _time_grid(duration, dt, t_eval) -> np.ndarray:
    duration = float(check_positive("duration", duration))
    if t_eval is None:
        dt = float(check_positive("dt", dt))
        n = max(int(round(duration / dt)), 1)
        return np.linspace(0.0, duration, n + 1)
    t = np.asarray(check_finite("t_eval", t_eval), dtype=float).ravel()
    if t.size < 1 or t[0] != 0.0 or np.any(np.diff(t) <= 0) or t[-1] > duration:
        raise ValueError(
            "t_eval must be strictly increasing, start at 0 and end at or before "
            f"duration={duration}, got {t_eval!r}"
        )
    return t


def _curvature_function(path):
    """``s -> kappa(s)`` for `path`, with the constant cases short-cut."""
    if isinstance(path, (Arc, Straight)):
        k = float(Path.curvature(path, 0.0))
        return lambda s: np.full(np.shape(s), k)
    return path.curvature


class _Engine:
    """Vectorised closed-loop right-hand side for ``n`` runs.

    The state is laid out as ``(m, n)`` flattened row-major: rows ``s, e,
    theta`` and, with a steering actuator, ``delta_f, delta_r``.
    """

    def __init__(self, vehicle, path, gains, speed, feedforward, tau):
        self.vehicle = vehicle
        self.path = path
        self.gains = gains
        self.speed = speed
        self.ff = feedforward
        self.tau = tau
        self.m = 3 if tau is None else 5
        self._kappa = _curvature_function(path)
        length = float(getattr(path, "length", math.inf))
        self.open_length = (
            length if (math.isfinite(length) and not path.closed) else None
        )

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

    def steering(self, Y, kappa):
        if self.tau is None:
            return steering_command(
                self.vehicle, self.gains, Y[1], Y[2], kappa, self.ff
            )
        return Y[3], Y[4]

    def derivatives(self, Y):
        """Return ``(Ydot, kappa, delta_f, delta_r)`` for states ``Y (m, n)``."""
        s, e, th = Y[0], Y[1], Y[2]
        kappa = self.curvature(s)
        df, dr = self.steering(Y, kappa)
        with np.errstate(divide="ignore", invalid="ignore"):
            s_dot, e_dot, th_dot = path_frame_derivatives(
                self.speed, self.vehicle.wheelbase, kappa, e, th, df, dr
            )
        if self.tau is None:
            Ydot = np.stack([s_dot, e_dot, th_dot])
        else:
            cmd = steering_command(self.vehicle, self.gains, e, th, kappa, self.ff)
            rf, rr = actuator_rate(self.vehicle, cmd, (df, dr), self.tau)
            Ydot = np.stack([s_dot, e_dot, th_dot, rf, rr])
        return Ydot, kappa, df, dr

    def rhs(self, t, y):
        Y = y.reshape(self.m, -1)
        return self.derivatives(Y)[0].ravel()

    def margins(self, Y):
        """Distance to each stop condition, shape ``(3, n)``; stop where <= 0."""
        kappa = self.curvature(Y[0])
        df, _ = self.steering(Y, kappa)
        out = np.full((3, Y.shape[1]), np.inf)
        out[0] = 0.5 * math.pi - np.abs(df)
        out[1] = 1.0 - kappa * Y[1]
        if self.open_length is not None:
            # The offset lets a run start exactly at s = 0 (or at the end).
            out[2] = np.minimum(Y[0], self.open_length - Y[0]) / self.open_length + 1e-9
        return out

    def event(self, t, y):
        return float(np.min(self.margins(y.reshape(self.m, -1))))


_STOP_MESSAGES = {
    STATUS_SINGULAR_STEERING: "front steering angle reached |delta_f| = pi/2, where "
    "the yaw rate V*sin(delta_f - delta_r)/(f*cos(delta_f)) is singular",
    STATUS_SINGULAR_CURVATURE: "1 - curvature*e reached 0: the vehicle is at the "
    "path's centre of curvature and the projection is lost",
    STATUS_END_OF_PATH: "the projection point left the open path",
}


#: A solver failure is attributed to a singular state when a run is this
#: close to it (``pi/2 - |delta_f|``, ``1 - kappa*e`` or the relative distance
#: to the end of the path).
_COLLAPSE_MARGIN = 1e-3


def _solver_class(method):
    if isinstance(method, type) and issubclass(method, OdeSolver):
        return method
    try:
        return _SOLVERS[method]
    except KeyError:
        raise ValueError(
            f"method must be one of {sorted(_SOLVERS)} or an OdeSolver class, "
            f"got {method!r}"
        ) from None


@dataclass
class _Segment:
    y_eval: np.ndarray  # states at the requested output times reached
    outcome: str  # "done", "event" or "failed"
    t_last: float
    y_last: np.ndarray
    message: str = ""


def _solve_segment(eng, solver_cls, t0, y0, t_end, t_eval, rtol, atol) -> _Segment:
    """Step `solver_cls` from `t0`; stop at the first sign change of the margin.

    Same stepping, dense output and event location as
    :func:`scipy.integrate.solve_ivp` with a terminal event, but the last
    accepted state is kept when the solver fails, so that a collapse of the
    step size at a singular state can be attributed to the run that caused it.
    """
    solver = solver_cls(eng.rhs, t0, y0, t_end, rtol=rtol, atol=atol)
    g_old = eng.event(t0, y0)
    recorded: list[np.ndarray] = []
    k = 0  # next output time
    while True:
        msg = solver.step()
        if solver.status == "failed":
            y_eval = np.stack(recorded, axis=1) if recorded else np.empty((y0.size, 0))
            return _Segment(y_eval, "failed", float(solver.t), solver.y.copy(), msg)
        t_old, t_new = solver.t_old, solver.t
        g_new = eng.event(t_new, solver.y)
        dense = None
        t_hit = None
        if g_old > 0.0 and g_new <= 0.0:
            dense = solver.dense_output()
            t_hit = brentq(
                lambda tt, d=dense: eng.event(tt, d(tt)),
                t_old,
                t_new,
                xtol=4 * np.finfo(float).eps * max(1.0, abs(t_new)),
            )
        upto = t_new if t_hit is None else t_hit
        k_end = int(np.searchsorted(t_eval, upto, side="right"))
        if k_end > k:
            if dense is None:
                dense = solver.dense_output()
            y_k = dense(t_eval[k:k_end])
            recorded.extend(y_k.T)
            k = k_end
        y_eval = None
        if t_hit is not None:
            y_eval = np.stack(recorded, axis=1) if recorded else np.empty((y0.size, 0))
            return _Segment(y_eval, "event", float(t_hit), dense(t_hit))
        if solver.status == "finished":
            y_eval = np.stack(recorded, axis=1) if recorded else np.empty((y0.size, 0))
            return _Segment(y_eval, "done", float(t_new), solver.y.copy())
        g_old = g_new


def _integrate(
    vehicle: Vehicle,
    path,
    gains: SteeringGains,
    speed: np.ndarray,
    feedforward: bool,
    z0: np.ndarray,
    t_eval: np.ndarray,
    tau: float | None,
    method: str,
    rtol: float,
    atol: float,
):
    """Integrate ``n`` runs together; stopped runs leave the stacked state.

    Returns ``(states (m, n, T) with NaN after a stop, status, message,
    t_stop)``.
    """
    n = speed.size
    T = t_eval.size
    m = 3 if tau is None else 5
    k1, k2, a = (
        np.broadcast_to(np.asarray(v, dtype=float), (n,))
        for v in (gains.k1, gains.k2, gains.ratio)
    )
    out = np.full((m, n, T), np.nan)
    status = np.full(n, STATUS_OK, dtype=object)
    message = np.full(n, "", dtype=object)
    t_stop = np.full(n, t_eval[-1])

    def engine_for(idx):
        return _Engine(
            vehicle,
            path,
            SteeringGains(k1[idx], k2[idx], a[idx]),
            speed[idx],
            feedforward,
            tau,
        )

    active = np.arange(n)
    eng = engine_for(active)
    Y = np.empty((m, n))
    Y[:3] = z0.T
    if tau is not None:
        Y[3:] = np.stack(
            steering_command(
                vehicle, eng.gains, Y[1], Y[2], eng.curvature(Y[0]), feedforward
            )
        )
    out[:, :, 0] = Y
    marg = eng.margins(Y)
    bad = np.min(marg, axis=0) <= 0.0
    for i in np.flatnonzero(bad):
        kind = _STOP_KINDS[int(np.argmin(marg[:, i]))]
        status[i], t_stop[i] = kind, t_eval[0]
        message[i] = f"initial state: {_STOP_MESSAGES[kind]}"
    active = active[~bad]
    Y = Y[:, ~bad]
    t0 = float(t_eval[0])
    t_end = float(t_eval[-1])
    solver_cls = _solver_class(method)
    while active.size and t0 < t_end:
        eng = engine_for(active)
        first = int(np.searchsorted(t_eval, t0, side="right"))
        seg = _solve_segment(
            eng, solver_cls, t0, Y.ravel(), t_end, t_eval[first:], rtol, atol
        )
        nt = seg.y_eval.shape[1]
        if nt:
            out[:, active, first : first + nt] = seg.y_eval.reshape(m, active.size, nt)
        if seg.outcome == "done":
            break
        Y_last = seg.y_last.reshape(m, active.size)
        marg = eng.margins(Y_last)
        j = int(np.argmin(np.min(marg, axis=0)))
        kind = _STOP_KINDS[int(np.argmin(marg[:, j]))]
        if seg.outcome == "event":
            note = _STOP_MESSAGES[kind]
        elif np.min(marg[:, j]) < _COLLAPSE_MARGIN:
            # Near |delta_f| = pi/2 the solution has a square-root singularity
            # (d delta_f/dt ~ 1/cos delta_f): the step size collapses before
            # any accepted step crosses it, so the event cannot fire.
            note = (
                f"{_STOP_MESSAGES[kind]} (the solver's step size collapsed "
                f"{float(np.min(marg[:, j])):.2g} away from it)"
            )
        else:
            for i in active:
                status[i], t_stop[i] = STATUS_FAILED, seg.t_last
                message[i] = (
                    f"at t={seg.t_last:.6g} s the ODE solver failed: {seg.message}"
                )
            break
        i = active[j]
        status[i], t_stop[i] = kind, seg.t_last
        message[i] = f"at t={seg.t_last:.6g} s: {note}"
        keep = np.arange(active.size) != j
        active, Y, t0 = active[keep], Y_last[:, keep], seg.t_last
    return out, status, message, t_stop


def _unwrap_time(psi: np.ndarray) -> np.ndarray:
    """Unwrap along the last axis, ignoring the NaN tail of stopped runs."""
    filled = psi.copy()
    nan = np.isnan(filled)
    if np.any(nan):
        # Forward-fill so that np.unwrap sees no NaN; the tail is reset below.
        idx = np.where(~nan, np.arange(psi.shape[-1]), 0)
        np.maximum.accumulate(idx, axis=-1, out=idx)
        filled = np.take_along_axis(filled, idx, axis=-1)
        filled = np.nan_to_num(filled)
    out = np.unwrap(filled, axis=-1)
    out[nan] = np.nan
    return out


def _outputs(
    vehicle, path, gains, speed, feedforward, tau, states, psi0
) -> dict[str, np.ndarray]:
    """All signals of SIGNALS from the path-frame states ``(m, n, T)``."""
    m, n, T = states.shape
    valid = np.isfinite(states[0])
    out = {name: np.full((n, T), np.nan) for name in SIGNALS}
    if not np.any(valid):
        return out
    run_idx = np.broadcast_to(np.arange(n)[:, None], (n, T))[valid]
    Y = states[:, valid]
    k1, k2, a = (
        np.broadcast_to(np.asarray(v, dtype=float), (n,))[run_idx]
        for v in (gains.k1, gains.k2, gains.ratio)
    )
    g = SteeringGains(k1, k2, a)
    V = speed[run_idx]
    eng = _Engine(vehicle, path, g, V, feedforward, tau)
    Ydot, kappa, df, dr = eng.derivatives(Y)
    if tau is None:
        kappa_rate = (
            np.asarray(path.curvature_rate(eng.clip(Y[0])), dtype=float) * Ydot[0]
        )
        rf, rr = steering_command_rate(
            vehicle, g, Y[1], Y[2], kappa, Ydot[1], Ydot[2], kappa_rate, feedforward
        )
    else:
        rf, rr = Ydot[3], Ydot[4]
    ok = np.abs(df) < math.pi / 2
    acc = np.full(df.shape, np.nan)
    acc[ok] = lateral_acceleration(
        vehicle, V[ok], df[ok], dr[ok], np.asarray(rf)[ok], np.asarray(rr)[ok]
    )
    rf = np.where(ok, rf, np.nan)
    rr = np.where(ok, rr, np.nan)
    s_path = eng.clip(Y[0])
    heading = np.asarray(path.heading(s_path), dtype=float)
    px, py = path.position(s_path)
    for name, val in (
        ("s", Y[0]),
        ("e", Y[1]),
        ("theta", Y[2]),
        ("delta_f", df),
        ("delta_r", dr),
        ("delta_f_rate", rf),
        ("delta_r_rate", rr),
        ("lateral_accel", acc),
        ("x", np.asarray(px) - Y[1] * np.sin(heading)),
        ("y", np.asarray(py) + Y[1] * np.cos(heading)),
        ("psi", Y[2] + heading),
    ):
        out[name][valid] = val
    psi = _unwrap_time(out["psi"])
    # Put psi on the branch of the given initial heading.
    shift = 2 * math.pi * np.round((psi0 - psi[:, 0]) / (2 * math.pi))
    out["psi"] = psi + shift[:, None]
    return out


def _prepare_limits(vehicle: Vehicle, actuator_time_constant) -> float | None:
    has_rate = (
        vehicle.max_steer_rate_front is not None
        or vehicle.max_steer_rate_rear is not None
    )
    if not has_rate:
        return None
    if actuator_time_constant is None:
        return DEFAULT_ACTUATOR_TIME_CONSTANT
    return float(check_positive("actuator_time_constant", actuator_time_constant))


def _check_initial_state(initial_state, n: int | None = None) -> np.ndarray:
    arr = np.asarray(check_finite("initial_state", initial_state), dtype=float)
    if arr.shape[-1:] != (3,) or arr.ndim > 2:
        raise ValueError(
            "initial_state must be (x_R, y_R, psi) or an array of shape (runs, 3), "
            f"got shape {arr.shape}"
        )
    return np.atleast_2d(arr)


def simulate(
    vehicle: Vehicle,
    path,
    gains: SteeringGains,
    speed: float,
    initial_state,
    duration: float,
    *,
    feedforward: bool = True,
    dt: float = 0.01,
    t_eval=None,
    actuator_time_constant: float | None = None,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> SimulationResult:
    r"""Simulate the closed loop with the fast path-frame engine.

    Integrates the corrected path-frame model (eqs. 17-19 with the curvature
    :math:`\kappa(s)` of the path at the projection point) closed with the
    controller of eqs. (24)-(29) in one right-hand side with
    :func:`scipy.integrate.solve_ivp`. The initial pose is projected onto the
    path once; the global pose is reconstructed from ``(s, e, theta)``.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and optional steering limits. Angle limits clip the
        commands; rate limits insert the actuator of
        :func:`steering_actuator`.
    path : path object
        Reference path (e.g. :class:`Straight`, :class:`Arc`).
    gains : SteeringGains
        Scalar ``k1, k2, ratio``.
    speed : float
        Speed :math:`V` [m/s], nonzero (negative: reversing).
    initial_state : array_like
        ``(x_R, y_R, psi)`` of the rear-axle centre [m, m, rad].
    duration : float
        Final time [s], > 0.
    feedforward : bool, optional
        Include the curvature feedforward (default ``True``); ``False`` is
        the feedback-only controller.
    dt : float, optional
        Nominal spacing of the output times [s] (the solver chooses its own
        steps). The grid is ``linspace(0, duration, round(duration/dt) + 1)``,
        so the actual spacing is ``duration/round(duration/dt)`` (at least
        one interval): pass `t_eval` for exact times.
    t_eval : array_like, optional
        Output times instead of `dt`; increasing, from 0 to at most
        `duration`.
    actuator_time_constant : float, optional
        Lag :math:`\tau` [s] of the rate-limited actuator, used only when the
        vehicle has a rate limit (default
        :data:`DEFAULT_ACTUATOR_TIME_CONSTANT`).
    method, rtol, atol : optional
        Integration method (a :class:`scipy.integrate.OdeSolver` name) and
        tolerances. The engine steps that solver itself, as
        :func:`scipy.integrate.solve_ivp` would, so that it can stop a run at
        a singular state.

    Returns
    -------
    SimulationResult
        If the run meets a singular state it stops there; ``status`` and
        ``message`` say why and the data end at the last output time before
        ``t_stop``.

    Raises
    ------
    ValueError
        For non-scalar gains, a zero speed, a non-positive duration, or an
        initial position whose projection is ambiguous.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.paths import Arc
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, 5.0, 0.1, ratio=-1.0, pole=-1.0)
    >>> res = fws.simulate(veh, Arc(curvature=0.1), g, speed=5.0,
    ...                    initial_state=(0.0, -5.0, 0.0), duration=15.0)
    >>> res.status, round(float(res.e[0]), 6), round(float(res.e[-1]), 5)
    ('ok', -5.0, -3e-05)
    """
    from .batch import _normalise_gains

    check_type("vehicle", vehicle, Vehicle)
    check_path(path)
    g = _normalise_gains(gains, "gains")
    if g.k1.size != 1:
        raise ValueError(
            f"gains must be scalar for simulate (got {g.k1.size} designs); use "
            "simulate_batch for several runs"
        )
    speed_arr = np.atleast_1d(np.asarray(check_nonzero("speed", speed), dtype=float))
    if speed_arr.size != 1:
        raise ValueError(f"speed must be a scalar for simulate, got {speed!r}")
    x0 = _check_initial_state(initial_state)
    if x0.shape[0] != 1:
        raise ValueError(
            f"initial_state must be (x_R, y_R, psi) for simulate, got shape {x0.shape}"
        )
    t = _time_grid(duration, dt, t_eval)
    tau = _prepare_limits(vehicle, actuator_time_constant)
    z0 = _initial_path_state(path, x0)
    states, status, message, t_stop = _integrate(
        vehicle, path, g, speed_arr, bool(feedforward), z0, t, tau, method, rtol, atol
    )
    sig = _outputs(
        vehicle, path, g, speed_arr, bool(feedforward), tau, states, x0[:, 2]
    )
    return _single_result(
        t,
        {k: v[0] for k, v in sig.items()},
        status[0],
        message[0],
        t_stop[0],
        float(speed_arr[0]),
        SteeringGains(float(g.k1[0]), float(g.k2[0]), float(g.ratio[0])),
        bool(feedforward),
        vehicle,
        path,
    )


def _single_result(t, sig, status, message, t_stop, speed, gains, ff, vehicle, path):
    n = int(np.count_nonzero(np.isfinite(sig["s"])))
    return SimulationResult(
        t=t[:n].copy(),
        **{k: np.asarray(v[:n]).copy() for k, v in sig.items()},
        status=str(status),
        message=str(message),
        t_stop=float(t_stop),
        speed=speed,
        gains=gains,
        feedforward=ff,
        vehicle=vehicle,
        path=path,
    )


# --------------------------------------------------------------------------
# Reference: python-control interconnection


def projection_system(path, name: str = "projection") -> ct.NonlinearIOSystem:
    r"""Static block projecting the global pose onto the path.

    Inputs ``x, y, psi``; outputs ``s, e, theta, curvature`` from
    ``path.errors(x, y, psi)`` (closest-point projection, eqs. 14-16).

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.paths import Arc
    >>> proj = fws.projection_system(Arc(curvature=0.1))
    >>> proj.output(0.0, [], [0.0, -5.0, 0.0]).round(6)
    array([ 0. , -5. ,  0. ,  0.1])
    """

    def output(t, x, u, params):
        s, e, theta, kappa = path.errors(float(u[0]), float(u[1]), float(u[2]))
        return np.array([float(s), float(e), float(theta), float(kappa)])

    return ct.nlsys(
        None,
        output,
        inputs=["x", "y", "psi"],
        outputs=["s", "e", "theta", "curvature"],
        name=name,
    )


def closed_loop_system(
    vehicle: Vehicle,
    path,
    gains: SteeringGains,
    speed: float,
    feedforward: bool = True,
    actuator_time_constant: float | None = None,
) -> ct.InterconnectedSystem:
    r"""The closed loop as a python-control interconnection (the reference).

    Blocks: :func:`global_frame_model` (states ``x, y, psi``),
    :func:`projection_system`, :func:`path_tracking_controller` and, if the
    vehicle has a steering-rate limit, :func:`steering_actuator` (states
    ``delta_f, delta_r`` appended after the vehicle's).

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, actuator_time_constant
        As in :func:`simulate`.

    Returns
    -------
    control.InterconnectedSystem
        No inputs; outputs ``x, y, psi, s, e, theta, curvature, delta_f,
        delta_r``. Simulate it with :func:`control.input_output_response`;
        the initial state is ``(x_R, y_R, psi)`` (followed by the initial
        steering angles when an actuator is present).

    Examples
    --------
    >>> import numpy as np, control as ct, fws_control as fws
    >>> from fws_control.paths import Arc
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, 5.0, 0.1, ratio=-1.0, pole=-1.0)
    >>> sys = fws.closed_loop_system(veh, Arc(curvature=0.1), g, speed=5.0)
    >>> sys.state_labels
    ['vehicle_x', 'vehicle_y', 'vehicle_psi']
    >>> resp = ct.input_output_response(
    ...     sys, np.linspace(0, 15, 151), initial_state=[0.0, -5.0, 0.0],
    ...     solve_ivp_method="DOP853",
    ...     solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})
    >>> round(float(resp.outputs[4, -1]), 5)   # e [m] at t = 15 s
    -3e-05
    """
    speed = float(check_nonzero("speed", speed))
    tau = _prepare_limits(vehicle, actuator_time_constant)
    veh_sys = global_frame_model(vehicle, speed, name="vehicle")
    proj = projection_system(path, name="projection")
    ctrl = path_tracking_controller(vehicle, gains, feedforward, name="controller")
    syslist = [veh_sys, proj, ctrl]
    connections = [
        ["projection.x", "vehicle.x"],
        ["projection.y", "vehicle.y"],
        ["projection.psi", "vehicle.psi"],
        ["controller.e", "projection.e"],
        ["controller.theta", "projection.theta"],
        ["controller.curvature", "projection.curvature"],
    ]
    if tau is None:
        steer = "controller"
    else:
        syslist.append(steering_actuator(vehicle, tau, name="actuator"))
        connections += [
            ["actuator.delta_f_cmd", "controller.delta_f"],
            ["actuator.delta_r_cmd", "controller.delta_r"],
        ]
        steer = "actuator"
    connections += [
        ["vehicle.delta_f", f"{steer}.delta_f"],
        ["vehicle.delta_r", f"{steer}.delta_r"],
    ]
    outlist = [
        "vehicle.x",
        "vehicle.y",
        "vehicle.psi",
        "projection.s",
        "projection.e",
        "projection.theta",
        "projection.curvature",
        f"{steer}.delta_f",
        f"{steer}.delta_r",
    ]
    return ct.interconnect(
        syslist,
        connections=connections,
        inplist=[],
        outlist=outlist,
        outputs=["x", "y", "psi", "s", "e", "theta", "curvature", "delta_f", "delta_r"],
        name="closed_loop",
    )


def _stderr_is_tty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False
