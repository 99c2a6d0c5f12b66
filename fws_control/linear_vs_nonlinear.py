r"""Linear versus nonlinear closed-loop responses from the same initial errors.

The linear prediction is :func:`control.initial_response` of
:func:`closed_loop` (states ``e, theta`` about the feedforward operating
point); the nonlinear one is :func:`simulate` of the kinematic model on the
path. Both start from the same lateral and heading errors, so the gap between
them is the linearisation error: small for small initial errors, growing with
them (the steering angles and ``sin(theta + delta_r)`` leave their linear
range).

Without feedforward on a curved path the feedforward angle is missing from
the input; the linear prediction then adds it as a constant steering
disturbance :math:`w = (-\delta_f^{FF}, 0)` (:func:`control.forced_response`),
which gives the steady-state offset of the feedback-only controller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import control as ct
import numpy as np

from .gains import SteeringGains
from .kinematic_models import feedforward_steering
from .layout import grid_margins
from .linear import check_gains, closed_loop
from .paths import Arc, Straight
from .plant import LateralPlant, as_plant
from .reprs import summary_repr
from .simulation import SimulationResult, simulate
from .validation import (
    MAX_ANGLE,
    check_bool,
    check_finite,
    check_positive,
    check_scalar,
)

__all__ = ["LinearNonlinearComparison", "compare_linear_nonlinear"]

#: Output samples of one comparison beyond which the request is refused
#: (each signal of both responses is held in memory; 1e7 samples of the
#: ~15 signals are about 1.2 GB).
_MAX_SAMPLES = 10_000_000


@summary_repr
@dataclass(frozen=True, eq=False)
class LinearNonlinearComparison:
    """Linear and nonlinear responses of one closed loop.

    Attributes
    ----------
    linear : control.TimeResponseData
        Response of :func:`closed_loop`; outputs ``e, theta, delta_f,
        delta_r`` (steering as deviations from the feedforward angles).
    nonlinear : SimulationResult
        :func:`simulate` of the nonlinear closed loop.
    speed, curvature : float
        Operating point [m/s], [1/m].
    gains : SteeringGains
    model : str
        Linearisation of the linear prediction.
    feedforward : bool
        Whether the curvature feedforward was used.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    >>> cmp = fws.compare_linear_nonlinear(plant, g, duration=2.0)
    >>> cmp.initial_errors          # default: e0 = 2 m, theta0 = 0
    (2.0, 0.0)
    >>> round(cmp.max_difference()["e"], 4)   # linearisation error [m]
    0.0012
    """

    linear: ct.TimeResponseData
    nonlinear: SimulationResult
    speed: float
    curvature: float
    gains: SteeringGains
    model: str
    feedforward: bool

    @property
    def initial_errors(self) -> tuple[float, float]:
        """``(e0, theta0)`` [m, rad] shared by both responses."""
        return float(self.nonlinear.e[0]), float(self.nonlinear.theta[0])

    def _linear_steering(self):
        y = self.linear.outputs
        ff = feedforward_steering(self.nonlinear.vehicle, curvature=self.curvature)
        return y[2] + (ff if self.feedforward else 0.0), y[3]

    def max_difference(self) -> dict[str, float]:
        """Largest gap between the two responses over the common time span.

        Returns
        -------
        dict
            ``{"e": [m], "theta": [rad], "delta_f": [rad], "delta_r": [rad]}``.

        Raises
        ------
        ValueError
            If the nonlinear run did not reach the end (its status is not
            ``"ok"``, e.g. it stopped at a singular state at t = 0): the gap
            over the part it ran would understate the linearisation error
            (at t = 0 both start from the same state, so it is zero). The
            message gives the status and the stop time; the partial run is
            still in :attr:`nonlinear` and :meth:`plot` shows it.
        """
        nl = self.nonlinear
        status = str(np.asarray(nl.status).item())
        if status != "ok":
            raise ValueError(
                f"the nonlinear run stopped at t = {float(nl.t[-1]):.6g} s with "
                f"status {status!r}, so the responses cannot be compared over the "
                "duration: max_difference would only measure the part before the "
                "stop (zero for a stop at t = 0). Use smaller initial errors or "
                "look at .nonlinear"
            )
        n = self.nonlinear.t.size
        y = self.linear.outputs[:, :n]
        df, dr = self._linear_steering()
        return {
            "e": float(np.nanmax(np.abs(y[0] - nl.e))),
            "theta": float(np.nanmax(np.abs(y[1] - nl.theta))),
            "delta_f": float(np.nanmax(np.abs(df[:n] - nl.delta_f))),
            "delta_r": float(np.nanmax(np.abs(dr[:n] - nl.delta_r))),
        }

    def plot(self, ax=None) -> ct.ControlPlot:
        """Overlay both responses: errors, trajectory, steering angles.

        Parameters
        ----------
        ax : sequence of 5 matplotlib.axes.Axes, optional
            Axes for lateral error, heading error, front and rear steering
            (over time) and the trajectory; a new figure if None.

        Returns
        -------
        control.ControlPlot
            Axes of shape ``(1, 5)``: four panels over time (lateral error
            [m], heading error [deg], front and rear steering [deg];
            nonlinear solid, linear dashed) and the trajectory of R with the
            path.

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> plant = fws.LateralPlant(veh, speed=5.0)
        >>> g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
        >>> cmp = fws.compare_linear_nonlinear(plant, g, duration=2.0)
        >>> cplt = cmp.plot()
        >>> cplt.axes.shape
        (1, 5)
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        if ax is None:
            size = (12, 7.5)
            fig = plt.figure(figsize=size)
            gs = fig.add_gridspec(
                2,
                3,
                **grid_margins(size, nrows=2, ncols=3, left=0.65, top=0.5, hgap=0.55),
            )
            axes = [
                fig.add_subplot(gs[0, 0]),
                fig.add_subplot(gs[0, 1]),
                fig.add_subplot(gs[1, 0]),
                fig.add_subplot(gs[1, 1]),
            ]
            ax_xy = fig.add_subplot(gs[:, 2])
        else:
            given = list(np.asarray(ax, dtype=object).ravel())
            if len(given) != 5:
                raise ValueError(f"ax must hold 5 axes, got {len(given)}")
            axes, ax_xy = given[:4], given[4]
            fig = ax_xy.figure
        nl, lin = self.nonlinear, self.linear
        df_lin, dr_lin = self._linear_steering()
        deg = 180.0 / math.pi
        rows = (
            ("lateral error e [m]", nl.e, lin.outputs[0], 1.0),
            ("heading error θ [deg]", nl.theta, lin.outputs[1], deg),
            ("front steering δf [deg]", nl.delta_f, df_lin, deg),
            ("rear steering δr [deg]", nl.delta_r, dr_lin, deg),
        )
        for ax, (label, y_nl, y_lin, scale) in zip(axes, rows, strict=True):
            ax.plot(nl.t, scale * y_nl, "-", color="C0", label="nonlinear (simulate)")
            ax.plot(
                lin.time,
                scale * y_lin,
                "--",
                color="C1",
                label=f"linear ({self.model} model, closed_loop)",
            )
            ax.set_xlabel("time t [s]")
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=8)
        ax_xy.plot(nl.x, nl.y, color="C0", label="R, nonlinear")
        path = nl.path
        if path is not None and nl.s.size:
            ss = np.linspace(np.nanmin(nl.s), np.nanmax(nl.s), 300)
            px, py = path.position(ss)
            ax_xy.plot(px, py, "k--", lw=1.0, label="path")
        ax_xy.set_aspect("equal", adjustable="datalim")
        ax_xy.set_xlabel("x [m]")
        ax_xy.set_ylabel("y [m]")
        ax_xy.grid(alpha=0.3)
        ax_xy.legend(fontsize=8)
        e0, th0 = self.initial_errors
        g = self.gains
        fig.suptitle(
            f"linear vs nonlinear: V = {self.speed:g} m/s, κ = {self.curvature:g} 1/m, "
            f"a = {float(g.ratio):g}, k1 = {float(g.k1):.4f}, k2 = {float(g.k2):.4f}, "
            f"e0 = {e0:g} m, θ0 = {math.degrees(th0):g}°"
            + ("" if self.feedforward else ", feedback only"),
            fontsize=11,
        )
        all_axes = [*axes, ax_xy]
        lines = np.empty((1, 5), dtype=object)
        for i, a in enumerate(all_axes):
            lines[0, i] = list(a.get_lines())
        return ct.ControlPlot(lines, np.array([all_axes], dtype=object), fig)


def compare_linear_nonlinear(
    plant: Any,
    gains: SteeringGains,
    *,
    initial_state=None,
    initial_errors=None,
    duration: float = 15.0,
    feedforward: bool = True,
    dt: float = 0.01,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> LinearNonlinearComparison:
    r"""Linear and nonlinear responses from the same initial errors.

    Parameters
    ----------
    plant : LateralPlant or Vehicle
        The kinematic plant at one operating point (the nonlinear run needs
        its vehicle): speed [m/s] and curvature [1/m]; curvature 0 is the
        straight path along the x-axis, otherwise the :class:`Arc` that
        starts at the origin heading +x. Its model is the linearisation of
        the linear prediction.
    gains : SteeringGains
        Scalar gains.
    initial_state : array_like, optional
        ``(x_R, y_R, psi)`` [m, m, rad] of the rear-axle centre; default
        ``(0, 2, 0)``, the paper's straight-road start.
    initial_errors : (float, float), optional
        ``(e0, theta0)`` [m, rad] instead of `initial_state`: the vehicle
        starts at the normal of the path's start point.
    duration : float, optional
        [s].
    feedforward : bool, optional
        Curvature feedforward on (default) or off.
    dt : float, optional
        Output time step [s] of both responses.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    LinearNonlinearComparison

    Raises
    ------
    ValueError
        For both `initial_state` and `initial_errors`, or invalid values.
    TypeError
        For `gains` that are not :class:`SteeringGains`, a plant that is not
        kinematic, or a `feedforward` that is not a bool (``"False"`` would
        read as true).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    >>> g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    >>> small = fws.compare_linear_nonlinear(plant, g, initial_errors=(0.05, 0.0))
    >>> small.max_difference()["e"] < 1e-3
    True
    """
    gains = check_gains(gains, scalar=True)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    if not isinstance(p, LateralPlant):
        raise TypeError(
            "compare_linear_nonlinear needs a fws.LateralPlant (or a Vehicle with "
            f"speed=): the nonlinear run needs the vehicle, got {type(p).__name__}"
        )
    if p.shape != ():
        raise ValueError(
            f"plant must be one operating point, got speed/curvature of shape {p.shape}"
        )
    if p.model == "dynamic" or p.steering_lag is not None:
        # the nonlinear run here is the kinematic model without actuator
        raise ValueError(
            "compare_linear_nonlinear compares the kinematic models ('kinematic', "
            f"'paper') without a steering lag, got model={p.model!r}, "
            f"steering_lag={p.steering_lag!r}"
        )
    vehicle, speed, curvature = p.vehicle, float(p.speed), float(p.curvature)
    duration = check_scalar("duration", check_positive("duration", duration))
    feedforward = check_bool("feedforward", feedforward)
    dt = check_scalar("dt", check_positive("dt", dt))
    if dt > duration:
        raise ValueError(
            f"dt must be <= duration = {duration:g} s (at least two output "
            f"samples), got dt={dt:g}"
        )
    if duration / dt > _MAX_SAMPLES:
        raise ValueError(
            f"duration/dt = {duration:g}/{dt:g} asks for more than {_MAX_SAMPLES:.0e} "
            "output samples: use a larger dt or a shorter duration"
        )
    path = Straight() if curvature == 0.0 else Arc(curvature=curvature)
    if initial_state is not None and initial_errors is not None:
        raise ValueError("give initial_state or initial_errors, not both")
    if initial_errors is not None:
        errs = np.ravel(check_finite("initial_errors", initial_errors))
        if errs.size != 2:
            raise ValueError(
                f"initial_errors must be a pair (e0, theta0), got {initial_errors!r}"
            )
        e0, th0 = (float(v) for v in errs)
        if abs(th0) > MAX_ANGLE:
            raise ValueError(
                f"initial_errors theta0 must have magnitude <= {MAX_ANGLE:g} rad "
                f"(it is used modulo 2 pi), got {initial_errors!r}"
            )
        px, py = path.position(0.0)
        h = float(path.heading(0.0))
        initial_state = (
            float(px) - e0 * math.sin(h),
            float(py) + e0 * math.cos(h),
            h + th0,
        )
    elif initial_state is None:
        initial_state = (0.0, 2.0, 0.0)
    t = np.arange(0.0, duration + 0.5 * dt, dt)
    t = t[t <= duration]
    nl = simulate(
        p,  # the kinematic models (both linearisations) simulate alike
        path,
        gains,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        t_eval=t,
    )
    x0 = [float(nl.e[0]), float(nl.theta[0])]
    cl = closed_loop(p, gains)
    if feedforward or curvature == 0.0:
        lin = ct.initial_response(cl, T=t, X0=x0)
    else:
        w = -feedforward_steering(vehicle, curvature=curvature)
        U = np.vstack([np.full_like(t, w), np.zeros_like(t)])
        lin = ct.forced_response(cl, T=t, U=U, X0=x0)
    return LinearNonlinearComparison(
        lin, nl, speed, curvature, gains, p.model, bool(feedforward)
    )
