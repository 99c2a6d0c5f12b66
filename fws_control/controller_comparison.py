r"""Lateral controllers side by side on one plant and one manoeuvre.

:func:`compare` simulates every controller on the same vehicle (same steering
angle and rate limits), the same course, speed, initial pose and optional
input delay and steering lag, and returns a :class:`ControllerComparison`: a
table of metrics per controller and a figure.

Every run starts at the entry of the first gate (on the centre line, or
with a lateral offset) and ends when R has passed the last gate (on a
course without gates, once it has covered the course's distance). Metrics
(per controller, over the run, of absolute values): peak lateral
acceleration of G [m/s²], max lateral error ``e`` [m], max ``delta_f`` and
``delta_r`` [deg] and their rates [deg/s] — all exact maxima of the
continuous solution (``result.peaks``), independent of
the output grid — the RMS of ``e`` [m] (trapezoidal on the output grid),
cones hit (:meth:`Manoeuvre.cones_hit`) and completion: the run did not
stop and passed the last gate, or, on a course without gates, covered its
:attr:`Manoeuvre.distance` along the path (every lap of a closed one).
For a vehicle with a friction coefficient :math:`\mu`
(:attr:`Vehicle.friction`) the table adds the friction use, peak
:math:`|a_y| / (\mu g)` with ``g =`` :data:`~fws_control.dynamics.GRAVITY`,
and whether the run left the friction circle (friction use > 1: a
kinematic or linear-tyre run that no tyre can drive; the saturating tyre,
``tyre="magic"``, caps the axle forces at :math:`\mu F_z`, so its runs
reach 1 at most). Whether the run left the lane
(:meth:`Manoeuvre.left_lane`: the wheel track crossed a cone line inside a
gate) is a column for every vehicle.

The plant is the simulated system of :func:`~fws_control.simulate`: the
kinematic model, or with ``LateralPlant(..., model="dynamic",
tyre="magic")`` the dynamic single-track model with saturating tyres.
Every row is the run of ``simulate(plant, manoeuvre.path, controller,
...)`` with the run's initial state and duration
(:attr:`ControllerComparison.initial_state`,
:attr:`ControllerComparison.duration`).
There is no jerk column: on a course of straight lines and clothoids the
curvature rate jumps at every joint, the feedforward steering rate with it,
and the kinematic model's lateral acceleration (eq. 13, which contains the
steering rate) jumps there too, so its time derivative is unbounded.

:func:`default_controllers` gives a fair starting set at a speed: the
paper's double-root law (front steering and a rear ratio), rear-wheel
feedback whose linearisation is that same front-steering design
(``K_e = k1/f``, ``K_theta = k2/f``), pure pursuit and Stanley with
commonly used parameters, and LQR with the paper's structure and with an
independent rear axle.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .baselines import (
    LQRController,
    PurePursuit,
    RearWheelFeedback,
    Stanley,
    StateFeedback,
)
from .deprecation import legacy_keyword, reject_unknown, warn_deprecated
from .dynamics import GRAVITY
from .gains import SteeringGains
from .lateral_controller import LateralController
from .manoeuvres import Manoeuvre
from .plant import LateralPlant
from .pole_placement import double_root_gains
from .simulation import STATUS_END_OF_PATH, SimulationResult, simulate
from .validation import check_bool, check_delay, check_scalar, check_type
from .vehicle import Vehicle

if TYPE_CHECKING:
    import control as ct
    import pandas as pd
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "ControllerComparison",
    "compare",
    "default_controllers",
    "COMPARISON_METRICS",
    "FRICTION_METRICS",
    "COMPARE_MAX_STEPS",
]

#: Column names of :attr:`ControllerComparison.table` (units in the names).
#: Peaks and maxima are of absolute values, exact (see the module docstring).
COMPARISON_METRICS = (
    "peak a_lat [m/s^2]",
    "RMS e [m]",
    "max e [m]",
    "max delta_f [deg]",
    "max delta_r [deg]",
    "max delta_f rate [deg/s]",
    "max delta_r rate [deg/s]",
    "cones hit",
    "completed",
    "left lane",
    "peak a_lat / (mu g) [-]",
    "beyond friction",
)

#: Columns that need the vehicle's friction coefficient (absent without it).
FRICTION_METRICS = ("peak a_lat / (mu g) [-]", "beyond friction")

#: Columns of yes/no values.
_FLAGS = ("completed", "left lane", "beyond friction")


def default_controllers(
    vehicle: Vehicle,
    *,
    speed: float,
    ratio: float = -0.3,
    pole: float = -1.0,
    delay: float = 0.0,
) -> dict[str, Any]:
    """A fair set of controllers designed for `speed` on a straight road.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed : float
        Design speed [m/s].
    ratio : float, optional
        Rear ratio of the four-wheel-steering designs (default -0.3).
    pole : float, optional
        Double root [1/s] of the paper's designs (default -1).
    delay : float, optional
        The input delay [s] the comparison will run with: the MPC (when its
        extra is installed) predicts over it, as deployed MPCs do; the other
        controllers have no delay model.

    Returns
    -------
    dict
        Label -> controller (or :class:`SteeringGains`).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sorted(fws.default_controllers(veh, speed=20.0))[:3]
    ['LQR (a = -0.3)', 'LQR (independent rear)', 'Stanley']
    """
    V = check_scalar("speed", speed)
    if V <= 0.0:
        raise ValueError(f"speed must be finite and > 0 m/s, got {speed!r}")
    ratio = check_scalar("ratio", ratio)
    pole = check_scalar("pole", pole)
    delay = check_delay(delay)
    plant = LateralPlant(vehicle, speed=V)
    g0 = double_root_gains(plant, ratio=0.0, pole=pole)
    ga = double_root_gains(plant, ratio=ratio, pole=pole)
    f = vehicle.wheelbase
    Q = np.diag([1.0, 4.0])
    return {
        "paper, a = 0": g0,
        f"paper, a = {ratio:g}": ga,
        "rear-wheel feedback": RearWheelFeedback(
            k_e=float(g0.k1) / f, k_theta=float(g0.k2) / f
        ),
        "pure pursuit": PurePursuit(lookahead=3.0, lookahead_time=1.0),
        "Stanley": Stanley(gain=1.0),
        f"LQR (a = {ratio:g})": LQRController(plant, Q=Q, R=4.0, ratio=ratio),
        "LQR (independent rear)": LQRController(plant, Q=Q, R=4.0 * np.eye(2)),
        **_mpc_controllers(Q, delay),
    }


def _mpc_controllers(Q: np.ndarray, delay: float) -> dict[str, Any]:
    """The LTV MPC with the LQR designs' weights, where its extra is installed."""
    import importlib.util

    if importlib.util.find_spec("osqp") is None:
        return {}
    from .mpc import MPCController

    # the weights of the LQR designs; about 25 Hz and a 2 s horizon; the
    # loop's delay predicted over, as a whole number of samples (the sample
    # time nearest 0.04 s that divides it)
    ts = 0.04 if delay == 0.0 else delay / max(1, round(delay / 0.04))
    return {
        "linear MPC (independent rear)": MPCController(
            sample_time=ts,
            horizon=round(2.0 / ts),
            Q=Q,
            R=4.0 * np.eye(2),
            delay=delay,
        )  # fmt: skip
    }


@dataclass(frozen=True, eq=False)
class ControllerComparison:
    """Runs and metrics of several controllers on one plant and course.

    Attributes
    ----------
    manoeuvre : Manoeuvre
        The course.
    speed : float
        Speed [m/s].
    delay : float
        Input delay [s] of every run.
    labels : tuple of str
        Controller names, in order.
    results : tuple of SimulationResult
        One run per controller.
    table : dict
        Metric name -> ndarray, one value per controller: the names of
        :data:`COMPARISON_METRICS` (those of :data:`FRICTION_METRICS` only
        for a vehicle with a friction coefficient), in :attr:`columns`
        order.
    plant : LateralPlant or None
        The simulated system (vehicle, speed, model, tyre, steering lag).
    duration : float
        Final time of every run [s].
    initial_state : tuple of float
        ``(x_R, y_R, psi)`` of every run [m, m, rad].

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> m = fws.double_lane_change()
    >>> plant = fws.LateralPlant(veh, speed=10.0)
    >>> cmp = fws.compare(plant, m, {"Stanley": fws.Stanley(gain=1.0)}, offset=0.3)
    >>> cmp.labels, bool(cmp.table["completed"][0])
    (('Stanley',), True)
    >>> bool(cmp.table["left lane"][0])      # 0.3 + 0.9 m > 1.115 m at the start
    True
    """

    manoeuvre: Manoeuvre
    speed: float
    delay: float
    labels: tuple[str, ...]
    results: tuple[SimulationResult, ...]
    table: dict[str, np.ndarray]
    plant: LateralPlant | None = None
    duration: float = math.nan
    initial_state: tuple[float, float, float] | None = None

    def __repr__(self) -> str:
        model = ""
        if self.plant is not None:
            model = f"model={self.plant.model!r}, "
            if self.plant.model == "dynamic":
                model += f"tyre={self.plant.tyre!r}, "
        return (
            f"ControllerComparison({self.manoeuvre.name!r}, speed={self.speed:g} m/s, "
            f"{model}delay={self.delay:g} s, controllers={list(self.labels)})"
        )

    @property
    def columns(self) -> tuple[str, ...]:
        """Names of the table's columns, in order (units in the names)."""
        return tuple(n for n in COMPARISON_METRICS if n in self.table)

    def to_pandas(self) -> pd.DataFrame:
        """The table as a :class:`pandas.DataFrame`, one row per controller.

        The index holds the labels (named ``controller``); the columns are
        :attr:`columns`, numbers as floats, ``cones hit`` as integers and
        the yes/no columns as booleans.

        Returns
        -------
        pandas.DataFrame

        Raises
        ------
        ImportError
            If pandas is not installed (``pip install fws-control[pandas]``).

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, friction=1.0)
        >>> cmp = fws.compare(fws.LateralPlant(veh, speed=10.0),
        ...                   fws.double_lane_change(),
        ...                   {"pure pursuit": fws.PurePursuit(lookahead=5.0)})
        >>> df = cmp.to_pandas()
        >>> df.index.name, df["cones hit"].dtype.kind, df["beyond friction"].dtype
        ('controller', 'i', dtype('bool'))
        """
        try:
            import pandas as pd
        except ImportError as exc:  # the optional extra "pandas"
            raise ImportError(
                "ControllerComparison.to_pandas needs pandas: pip install "
                "'fws-control[pandas]'"
            ) from exc
        data = {}
        for name in self.columns:
            v = np.asarray(self.table[name])
            if name in _FLAGS:
                v = v.astype(bool)
            elif name == "cones hit":
                v = v.astype(np.int64)
            else:
                v = v.astype(float)
            data[name] = v
        return pd.DataFrame(data, index=pd.Index(list(self.labels), name="controller"))

    def to_markdown(self, *, digits: int = 3) -> str:
        """The table as Markdown, one row per controller.

        Parameters
        ----------
        digits : int, optional
            Significant digits of the numbers.

        Returns
        -------
        str
        """
        cols = self.columns
        head = "| controller | " + " | ".join(cols) + " |"
        rows = [head, "|---" * (len(cols) + 1) + "|"]
        for i, lab in enumerate(self.labels):
            cells = []
            for name in cols:
                v = self.table[name][i]
                if name in _FLAGS:
                    cells.append("yes" if v else "no")
                elif name == "cones hit":
                    cells.append(str(int(v)))
                else:
                    cells.append(f"{v:.{digits}g}" if math.isfinite(v) else "—")
            rows.append(f"| {lab} | " + " | ".join(cells) + " |")
        return "\n".join(rows)

    def plot(self, ax: Sequence[Axes] | np.ndarray | None = None) -> ct.ControlPlot:
        """Trajectories with the gates, lateral error, front steering, a_lat.

        The lateral-acceleration panel marks the friction limit
        :math:`\\pm\\mu g` for a vehicle with a friction coefficient.

        Parameters
        ----------
        ax : sequence of 4 matplotlib.axes.Axes, optional
            Axes of the panels; a new figure if None.

        Returns
        -------
        control.ControlPlot
            Axes of shape ``(1, 4)``.

        See Also
        --------
        draw : the same panels without python-control.

        Examples
        --------
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> cmp = fws.compare(fws.LateralPlant(veh, speed=10.0),
        ...                   fws.double_lane_change(),
        ...                   {"Stanley": fws.Stanley(gain=1.0)})
        >>> cplt = cmp.plot()
        >>> cplt.axes[0, 1].get_ylabel()
        'lateral error e [m]'
        """
        import control as ct

        fig = self.draw(ax=ax)
        axes = (
            fig.axes[:4] if ax is None else list(np.asarray(ax, dtype=object).ravel())
        )
        lines = np.empty((1, 4), dtype=object)
        for i, a in enumerate(axes):
            lines[0, i] = list(a.get_lines())
        return ct.ControlPlot(lines, np.array([axes], dtype=object), fig)

    def draw(self, *, ax: Sequence[Axes] | np.ndarray | None = None) -> Figure:
        """The panels of :meth:`plot` on a matplotlib figure.

        Without importing python-control (with its scipy.signal and
        scipy.stats): what ``fws-control compare`` saves.

        Parameters
        ----------
        ax : sequence of 4 matplotlib.axes.Axes, optional
            Axes of the panels; a new figure if None.

        Returns
        -------
        matplotlib.figure.Figure
            The figure of the panels (that of `ax` if given).

        Examples
        --------
        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> cmp = fws.compare(fws.LateralPlant(veh, speed=10.0),
        ...                   fws.double_lane_change(),
        ...                   {"Stanley": fws.Stanley(gain=1.0)})
        >>> [a.get_xlabel() for a in cmp.draw().axes]
        ['x [m]', 'time t [s]', 'time t [s]', 'time t [s]']
        """
        import matplotlib.pyplot as plt

        if ax is None:
            fig = plt.figure(figsize=(14, 8), layout="constrained")
            gs = fig.add_gridspec(2, 3)
            axes = [
                fig.add_subplot(gs[0, :]),
                fig.add_subplot(gs[1, 0]),
                fig.add_subplot(gs[1, 1]),
                fig.add_subplot(gs[1, 2]),
            ]
        else:
            axes = list(np.asarray(ax, dtype=object).ravel())
            if len(axes) != 4:
                raise ValueError(f"ax must hold 4 axes, got {len(axes)}")
            fig = cast("Figure", axes[0].figure)  # drawn into; a SubFigure works too
        a_xy, a_e, a_df, a_acc = axes
        self.manoeuvre.draw_gates(a_xy)
        deg = 180.0 / math.pi
        for i, (lab, r) in enumerate(zip(self.labels, self.results, strict=True)):
            color = f"C{i % 10}"
            a_xy.plot(r.x, r.y, color=color, lw=1.2, label=lab)
            a_e.plot(r.t, r.e, color=color, lw=1.0)
            a_df.plot(r.t, deg * r.delta_f, color=color, lw=1.0)
            a_acc.plot(r.t, r.lateral_accel, color=color, lw=1.0)
        mu = None if self.plant is None else self.plant.vehicle.friction
        if mu is not None:
            for sign in (1.0, -1.0):
                a_acc.axhline(
                    sign * mu * GRAVITY,
                    color="k",
                    ls=":",
                    lw=0.8,
                    label="±μg" if sign > 0 else None,
                )
            a_acc.legend(fontsize=8, loc="lower right")
        s = np.linspace(0.0, self.manoeuvre.path.length, 800)
        px, py = self.manoeuvre.path.position(s)
        a_xy.plot(px, py, "k--", lw=0.8, label="centre line")
        a_xy.set_xlabel("x [m]")
        a_xy.set_ylabel("y [m]")
        a_xy.legend(fontsize=8, ncol=4, loc="upper left")
        model = ""
        if self.plant is not None:
            model = f", {self.plant.model} model"
            if self.plant.model == "dynamic":
                model += f", {self.plant.tyre} tyre"
        a_xy.set_title(
            f"{self.manoeuvre.name} at {self.speed:g} m/s{model}"
            + (f", input delay {self.delay:g} s" if self.delay else ""),
            fontsize=11,
        )
        for a, lab in (
            (a_e, "lateral error e [m]"),
            (a_df, "front steering δf [deg]"),
            (a_acc, "lateral acceleration of G [m/s²]"),
        ):
            a.set_xlabel("time t [s]")
            a.set_ylabel(lab)
            a.grid(alpha=0.3)
        a_xy.grid(alpha=0.3)
        return fig


def _metrics(
    result: SimulationResult, manoeuvre: Manoeuvre, wheelbase: float, friction
):
    pk = result.peaks
    deg = 180.0 / math.pi
    e = np.asarray(result.e, dtype=float)
    t = np.asarray(result.t, dtype=float)
    ok = np.isfinite(e)
    rms = (
        float(np.sqrt(np.trapezoid(e[ok] ** 2, t[ok]) / (t[ok][-1] - t[ok][0])))
        if np.count_nonzero(ok) > 1
        else math.nan
    )
    if manoeuvre.gates:
        finished = bool(result.ok) and bool(np.nanmax(result.x) >= manoeuvre.end_x)
    else:
        # a closed course returns to its start: x cannot tell a lap driven,
        # the arc length covered along the path can (s is not wrapped); an
        # open one ends where the run stops at the far end of its path
        s = np.asarray(result.s, dtype=float)
        s = s[np.isfinite(s)]
        if str(result.status) == STATUS_END_OF_PATH:
            finished = s.size > 0 and bool(s[-1] > 0.5 * float(manoeuvre.path.length))
        else:
            finished = bool(result.ok) and bool(s[-1] - s[0] >= manoeuvre.distance)
    return (
        float(pk.lateral_accel.value),
        rms,
        float(pk.e.value),
        deg * float(pk.delta_f.value),
        deg * float(pk.delta_r.value),
        deg * float(pk.delta_f_rate.value),
        deg * float(pk.delta_r_rate.value),
        manoeuvre.cones_hit(result.x, result.y, result.psi, wheelbase=wheelbase),
        finished,
        manoeuvre.left_lane(result.x, result.y, result.psi, wheelbase=wheelbase),
    ) + _friction_metrics(float(pk.lateral_accel.value), friction)


def _friction_metrics(peak_accel: float, friction) -> tuple:
    """``(peak |a_y| / (mu g), beyond the limit)``; ``()`` without a friction."""
    if friction is None:
        return ()
    use = peak_accel / (float(friction) * GRAVITY)
    # a stopped run's peak may be infinite: that is beyond the limit too
    return (use, bool(not use <= 1.0))


#: Speed range of :func:`compare` [m/s], the largest start offset [m] and the
#: shortest actuator time constant [s] (see the checks there).
_MIN_SPEED, _MAX_SPEED = 0.1, 100.0
_MAX_OFFSET = 10.0
_MIN_TIME_CONSTANT = 1.0e-3

#: Work budget of one run of :func:`compare` (the default of its `max_steps`):
#: the run's duration over the loop's fastest time scale -- the actuator
#: time constant, the input delay (the solver's steps are at most the delay),
#: Stanley's cross-track time ``(softening + V) / (gain V)`` and pure
#: pursuit's ``L_d / (2 V)`` -- a count of steps that the solver cannot
#: avoid; and 100 output samples per such step (``duration / dt``). Measured
#: per controller on the ISO 3888-1 course with the numpy engine (CPU):
#: at 20 m/s with an actuator of 0.01 s (660 steps) the paper's law 4.7 s
#: and Stanley 15 s, with 1e-3 s (6,600) 12 s and over 40 s; at 1 m/s with a
#: 0.1 s delay (1,215 steps) the default set runs past 600 s; 121,000
#: samples (0.1 m/s) keep Stanley busy for over 40 s.
COMPARE_MAX_STEPS = 1000

#: Output samples per step of :data:`COMPARE_MAX_STEPS`.
_SAMPLES_PER_STEP = 100


def _time_scales(controllers: dict, *, speed: float, delay: float, tau) -> list:
    """``(time scale [s], what)`` of the loop's fast dynamics that bound steps."""
    scales = []
    if tau is not None:
        scales.append((tau, f"lag {tau:g} s"))
    if delay > 0.0:
        scales.append((delay, f"steps <= delay {delay:g} s"))
    for label, c in controllers.items():
        if isinstance(c, Stanley):
            # cross-track error of the front axle: de/dt = -V k e / (k_s + V)
            k = float(np.min(c.gain))
            scales.append(
                ((c.softening + speed) / (k * speed), f"Stanley {label!r} gain")
            )
        elif isinstance(c, PurePursuit):
            # heading error: dtheta/dt = -2 V theta / L_d (small errors)
            ld = float(np.min(c.distance(speed)))
            scales.append((ld / (2.0 * speed), f"{label!r} look-ahead"))
    return scales


def _resolve_plant(plant: Any, kwargs: dict) -> tuple:
    """``(vehicle, speed, steering lag, plant or None)`` of a :func:`compare`
    call; None for the deprecated Vehicle form (built after the checks)."""
    if isinstance(plant, LateralPlant):
        given = [
            k
            for k in ("speed", "steering_lag", "actuator_time_constant")
            if k in kwargs
        ]
        if given:
            raise TypeError(
                f"compare(): {', '.join(k + '=' for k in given)} applies only to "
                "the deprecated Vehicle form; the LateralPlant already holds its "
                "speed and steering lag"
            )
        reject_unknown("compare", kwargs)
        if np.ndim(plant.speed) != 0:
            raise ValueError(
                "plant.speed must be one speed in [0.1, 100] m/s for compare (one "
                f"row per controller), got an array of shape {np.shape(plant.speed)}: "
                f"{np.array2string(np.asarray(plant.speed), threshold=6)}"
            )
        # LateralPlant holds the lag as a (front, rear) pair
        lag = cast("tuple[float, float] | None", plant.steering_lag)
        if lag is not None:
            if lag[0] != lag[1]:
                raise ValueError(
                    "plant.steering_lag must hold one time constant for both "
                    f"axles in the simulation (front == rear >= 0.001 s), got {lag!r}"
                )
            return plant.vehicle, plant.speed, lag[0], plant
        return plant.vehicle, plant.speed, lag, plant
    if isinstance(plant, Vehicle):
        if "speed" not in kwargs:
            raise TypeError(
                "compare(): plant must be a fws.LateralPlant (vehicle, speed, "
                "steering lag), got a Vehicle without speed=; pass "
                "fws.LateralPlant(vehicle, speed=...)"
            )
        warn_deprecated(
            "compare(vehicle, manoeuvre, controllers, speed=...)",
            "compare(plant, manoeuvre, controllers) and pass a "
            "fws.LateralPlant(vehicle, speed=..., steering_lag=...) as the plant",
        )
        speed = kwargs.pop("speed")
        lag = legacy_keyword(
            kwargs, "actuator_time_constant", "steering_lag",
            kwargs.pop("steering_lag", None),
        )  # fmt: skip
        reject_unknown("compare", kwargs)
        return plant, speed, lag, None
    raise TypeError(
        "compare(): plant must be a fws.LateralPlant (vehicle, speed, steering "
        f"lag), got {type(plant).__name__}"
    )


def compare(
    plant: LateralPlant,
    manoeuvre: Manoeuvre,
    controllers: dict[str, Any],
    *,
    offset: float = 0.0,
    delay: float = 0.0,
    dt: float = 0.01,
    max_steps: float = COMPARE_MAX_STEPS,
    progress: bool | None = None,
    **kwargs: Any,
) -> ControllerComparison:
    r"""Run every controller on the same plant and course; tabulate metrics.

    Parameters
    ----------
    plant : LateralPlant
        The simulated system shared by all runs, as in
        :func:`~fws_control.simulate`: the vehicle (geometry and steering
        limits), one speed in [0.1, 100] m/s, the model and tyre, and the
        steering lag (None, or one time constant >= 1e-3 s for both axles;
        rate limits of the vehicle apply through it). Its curvature is not
        used.
    manoeuvre : Manoeuvre
        The course (e.g. :func:`~fws_control.double_lane_change`).
    controllers : dict
        Label -> :class:`SteeringGains` (the paper's law with feedforward) or
        a :class:`~fws_control.LateralController`.
    offset : float, optional
        Lateral offset [m] of R from the centre line at the start (the entry
        of the first gate, heading along the course); positive left; at
        most 10 m either way.
    delay : float, optional
        Input delay on the steering command [s] (all runs); 0 or at least
        the run's duration / 1e4 (see :func:`~fws_control.simulate`): a
        property of the loop, not of the plant.
    dt : float, optional
        Output spacing [s], > 0 and at most a tenth of the run's duration.
    max_steps : float, optional
        Work budget of each run (default :data:`COMPARE_MAX_STEPS`, 1000):
        the run's duration over its fastest time scale (actuator time
        constant, delay, Stanley's ``(softening + V) / (gain V)``, pure
        pursuit's ``L_d / (2 V)``) may not exceed it, nor ``duration / dt``
        100 times it. A larger request raises ValueError before any run,
        saying the estimate; pass a larger `max_steps` to run it anyway
        (minutes to hours).
    progress : bool or None, optional
        Show a tqdm progress bar over the controllers on standard error.
        ``None`` (default): only if standard error is a terminal (no bar
        in logs or captured output).
    **kwargs
        Deprecated calling form, accepted until fws_control 0.4 with a
        :class:`FutureWarning`: a :class:`~fws_control.Vehicle` as `plant`
        with ``speed=`` and ``steering_lag=`` (formerly
        ``actuator_time_constant=``). Any other keyword raises
        :class:`TypeError`.

    Returns
    -------
    ControllerComparison
        With :attr:`~ControllerComparison.table`,
        :meth:`~ControllerComparison.to_pandas` and
        :meth:`~ControllerComparison.plot`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> cmp = fws.compare(fws.LateralPlant(veh, speed=10.0),
    ...                   fws.double_lane_change(),
    ...                   {"pure pursuit": fws.PurePursuit(lookahead=5.0)})
    >>> int(cmp.table["cones hit"][0])
    0

    On the dynamic model with saturating tyres (BMW 320i of CommonRoad,
    :math:`\mu` = 1.0489) the lateral acceleration stays within
    :math:`\mu g`:

    >>> bmw = fws.vehicles.BMW_320I
    >>> plant = fws.LateralPlant(bmw, speed=10.0, model="dynamic", tyre="magic")
    >>> cmp = fws.compare(plant, fws.double_lane_change(),
    ...                   {"pure pursuit": fws.PurePursuit(lookahead=5.0)})
    >>> bool(cmp.table["peak a_lat / (mu g) [-]"][0] <= 1.0)
    True
    """
    vehicle, speed, lag, plant = _resolve_plant(plant, kwargs)
    check_type("manoeuvre", manoeuvre, Manoeuvre)
    if not isinstance(controllers, dict) or not controllers:
        raise TypeError("controllers must be a non-empty dict of label -> controller")
    V = check_scalar("speed", speed)
    if not _MIN_SPEED <= V <= _MAX_SPEED:
        raise ValueError(
            f"speed must be in [{_MIN_SPEED:g}, {_MAX_SPEED:g}] m/s for a "
            f"manoeuvre (walking pace to 360 km/h), got {speed!r}"
        )
    path = manoeuvre.path
    offset = check_scalar("offset", offset)
    if abs(offset) > _MAX_OFFSET:
        # beyond a few lane widths the start projects onto another part of
        # the course (or nowhere unique)
        raise ValueError(
            f"offset must be within +-{_MAX_OFFSET:g} m of the centre line, "
            f"got {offset!r}"
        )
    if lag is not None:
        tau = check_scalar("steering_lag", lag)
        if tau < _MIN_TIME_CONSTANT:
            # a faster actuator is none: the stiff lag then breaks the solver
            # (1e-300 s: "Factor is exactly singular"); None models none
            raise ValueError(
                f"steering_lag must be None or >= {_MIN_TIME_CONSTANT:g} s, got {lag!r}"
            )
    if plant is None:  # the deprecated Vehicle form, checked above
        plant = LateralPlant(vehicle, speed=V, steering_lag=lag)
    # Start at the first gate's entry (the approach is straight, so a delay's
    # held initial history is the straight-road command) and stop once R has
    # passed the last gate: the run covers the course and nothing else.
    x0 = manoeuvre.start_x if manoeuvre.gates else 0.0
    initial_state = (x0, offset, 0.0)
    span = (manoeuvre.end_x - x0) if manoeuvre.gates else manoeuvre.distance
    duration = 1.1 * span / V + 0.5  # the path is longer than its x-span
    dt = check_scalar("dt", dt)
    if not 0.0 < dt <= duration / 10.0:
        # the metrics need samples over the course
        raise ValueError(
            f"dt must be > 0 and <= duration/10 = {duration / 10.0:.3g} s for "
            f"this course and speed, got {dt!r}"
        )
    budget = check_scalar("max_steps", max_steps)
    if not budget > 0.0:
        raise ValueError(f"max_steps must be > 0, got {max_steps!r}")
    tau_d = check_delay(delay)
    tau_a = None if lag is None else tau
    scales = _time_scales(controllers, speed=V, delay=tau_d, tau=tau_a)
    steps, what = max(
        ((duration / h, f"{w}: {duration:.3g} / {h:.3g} s") for h, w in scales),
        default=(0.0, ""),
        key=lambda p: p[0],
    )
    samples = duration / dt
    if steps > budget or samples > _SAMPLES_PER_STEP * budget:
        need = f"{steps:.3g} solver steps ({what}) and " if steps > budget else ""
        raise ValueError(
            f"compare: {need}{samples:.3g} output samples per run ({duration:.3g} "
            f"s at dt={dt:g} s), beyond the budget of max_steps={budget:g} steps "
            f"and {_SAMPLES_PER_STEP * budget:.3g} samples; pass a larger "
            "max_steps to run it anyway (minutes or more)"
        )
    if progress is None:
        try:
            progress = sys.stderr.isatty()
        except (AttributeError, ValueError):  # closed or replaced stderr
            progress = False
    progress = check_bool("progress", progress)
    labels, results = [], []
    if progress:
        from tqdm.auto import tqdm

        items = tqdm(controllers.items(), total=len(controllers), desc="compare",
                     unit="controller")  # fmt: skip
    else:
        items = controllers.items()
    for label, c in items:
        if not isinstance(c, (SteeringGains, LateralController)):
            raise TypeError(
                f"controllers[{label!r}] must be a SteeringGains or a lateral "
                f"controller, got {type(c).__name__}"
            )
        if isinstance(c, SteeringGains):
            shapes = {n: np.shape(getattr(c, n)) for n in ("k1", "k2", "ratio")}
            if any(shapes.values()):
                # a row of the table is one run: a sweep has no single row
                given = ", ".join(f"{n} of shape {s}" for n, s in shapes.items() if s)
                raise ValueError(
                    f"controllers[{label!r}] holds an array of designs ({given}): "
                    "compare needs one design (scalar k1, k2, ratio) per label; "
                    "use simulate_batch for sweeps"
                )
            c = StateFeedback.from_gains(c)
        res = simulate(
            plant,
            path,
            c,
            initial_state=initial_state,
            duration=duration,
            dt=dt,
            delay=delay,
        )
        labels.append(str(label))
        results.append(res)
    rows = [
        _metrics(r, manoeuvre, vehicle.wheelbase, vehicle.friction) for r in results
    ]
    names = [
        n
        for n in COMPARISON_METRICS
        if vehicle.friction is not None or n not in FRICTION_METRICS
    ]
    table = {name: np.array([row[j] for row in rows]) for j, name in enumerate(names)}
    return ControllerComparison(
        manoeuvre,
        V,
        float(delay),
        tuple(labels),
        tuple(results),
        table,
        plant=plant,
        duration=duration,
        initial_state=initial_state,
    )
