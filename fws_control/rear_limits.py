r"""Production limits of the rear steering: the band of ratios, saturation on a run.

Production four-wheel-steering cars turn the rear wheels by a few degrees
only (2.8° to 10°). With the rear command :math:`\delta_r = a\,\delta_f`,
a rear limit :math:`L` allows at a front angle :math:`\delta_f` only the
ratios

.. math:: |a| \le L / |\delta_f|,

a band that narrows as the front angle grows
(:func:`rear_limit_band`). Whether a design's rear command saturates on a
given manoeuvre is a property of the run: :func:`rear_saturation` reads the
peak :math:`|\delta_r|` and the time spent above the limit from a
:class:`~fws_control.SimulationResult` (simulate with a vehicle without a
rear limit to see the command the design asks for; with the limit set the
simulator clips it and the time at the limit is reported).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from .hints import RealArrayLike
from .reprs import summary_repr
from .validation import check_finite, check_scalar
from .vehicle import Vehicle

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["RearLimitBand", "rear_limit_band", "RearSaturation", "rear_saturation"]


def _check_limit(rear_limit: Any, vehicle: Vehicle | None) -> float:
    if rear_limit is None:
        rear_limit = None if vehicle is None else vehicle.max_steer_rear
        if rear_limit is None:
            raise ValueError(
                "rear_limit must be given (in (0, pi/2) rad) when the vehicle "
                "sets no max_steer_rear"
            )
    lim = check_scalar("rear_limit", rear_limit)
    if not 0.0 < lim < 0.5 * math.pi:
        raise ValueError(f"rear_limit must be in (0, pi/2) rad, got {rear_limit!r}")
    return lim


@summary_repr
@dataclass(frozen=True, eq=False)
class RearLimitBand:
    r"""The ratios :math:`a` a rear steering limit allows at given front angles.

    Returned by :func:`rear_limit_band`.

    Attributes
    ----------
    front_angle : ndarray
        Front wheel angles :math:`\delta_f` [rad].
    rear_limit : float
        The rear angle limit :math:`L` [rad].
    low, high : ndarray
        The band :math:`-L/|\delta_f| \le a \le L/|\delta_f|` at each front
        angle (:math:`\mp\infty` at :math:`\delta_f = 0`).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> band = fws.rear_limit_band(veh, front_angle=np.radians(10.0),
    ...                            rear_limit=np.radians(5.0))
    >>> round(float(band.high), 12), bool(band.allows(-0.6))
    (0.5, False)
    """

    front_angle: np.ndarray
    rear_limit: float
    low: np.ndarray
    high: np.ndarray

    def allows(self, ratio: RealArrayLike) -> np.ndarray:
        """Whether :math:`|a\\,\\delta_f| \\le L` (broadcasts over front angles).

        Parameters
        ----------
        ratio : float or array_like
            Rear-to-front ratio(s) :math:`a` [-].

        Returns
        -------
        ndarray of bool

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> band = fws.rear_limit_band(veh, front_angle=[0.1, 0.2], rear_limit=0.05)
        >>> band.allows(0.4).tolist()
        [True, False]
        """
        a = np.asarray(check_finite("ratio", ratio), dtype=float)
        return np.abs(a * self.front_angle) <= self.rear_limit

    def plot(
        self, ax: Axes | None = None, *, ratio_range: tuple[float, float] = (-2.0, 2.0)
    ) -> ct.ControlPlot:
        """The band in the plane of front angle [deg] and ratio :math:`a`.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure if None.
        ratio_range : (float, float), optional
            The range of :math:`a` drawn.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import numpy as np, matplotlib.pyplot as plt, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> band = fws.rear_limit_band(veh, front_angle=np.radians(np.linspace(1, 35)),
        ...                            rear_limit=np.radians(5.0))
        >>> cplt = band.plot()
        >>> cplt.axes[0, 0].get_xlabel()
        'front wheel angle $\\\\delta_f$ [deg]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        lo, hi = (float(v) for v in ratio_range)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(
                f"ratio_range must be finite with low < high, got {ratio_range!r}"
            )
        if ax is None:
            _, ax = plt.subplots(figsize=(6.0, 4.0), layout="constrained")
        order = np.argsort(np.ravel(self.front_angle))
        x = np.degrees(np.ravel(self.front_angle))[order]
        low = np.clip(
            np.ravel(np.broadcast_to(self.low, np.shape(self.front_angle))), lo, hi
        )
        high = np.clip(
            np.ravel(np.broadcast_to(self.high, np.shape(self.front_angle))), lo, hi
        )
        fill = ax.fill_between(
            x, low[order], high[order], color="C2", alpha=0.3,
            label=f"|a $\\delta_f$| <= {math.degrees(self.rear_limit):.3g}°",
        )  # fmt: skip
        ax.set_ylim(lo, hi)
        ax.set_xlabel("front wheel angle $\\delta_f$ [deg]")
        ax.set_ylabel("ratio $a$ [-]")
        ax.set_title("ratios the rear limit allows")
        ax.grid(True, alpha=0.3)
        leg = ax.legend(loc="best", fontsize=8)
        return ct.ControlPlot([fill], np.array([[ax]]), ax.figure, legend=leg)


def rear_limit_band(
    vehicle: Vehicle, *, front_angle: RealArrayLike, rear_limit: float | None = None
) -> RearLimitBand:
    r"""The band of ratios :math:`|a| \le L/|\delta_f|` a rear limit allows.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle; its ``max_steer_rear`` is the limit unless `rear_limit`
        is given.
    front_angle : float or array_like
        Front wheel angle(s) :math:`\delta_f` [rad], magnitude below pi/2.
    rear_limit : float, optional
        Rear angle limit :math:`L` [rad], in (0, pi/2).

    Returns
    -------
    RearLimitBand

    Raises
    ------
    ValueError
        For a front angle not finite or of magnitude pi/2 or more, a limit
        outside (0, pi/2), or no limit at all.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35,
    ...                   max_steer_rear=np.radians(2.8))
    >>> band = fws.rear_limit_band(veh, front_angle=np.radians(20.0))
    >>> round(float(band.high), 4)
    0.14
    """
    if not isinstance(vehicle, Vehicle):
        raise TypeError(f"vehicle must be a Vehicle, got {type(vehicle).__name__}")
    lim = _check_limit(rear_limit, vehicle)
    df = np.asarray(check_finite("front_angle", front_angle), dtype=float)
    if np.any(np.abs(df) >= 0.5 * math.pi):
        raise ValueError(
            f"front_angle must have magnitude below pi/2 rad, got {front_angle!r}"
        )
    with np.errstate(divide="ignore"):
        high = np.where(df == 0.0, np.inf, lim / np.abs(df))
    return RearLimitBand(front_angle=df, rear_limit=lim, low=-high, high=high)


@summary_repr
@dataclass(frozen=True, eq=False)
class RearSaturation:
    r"""Whether and how long the rear angle of a run exceeds a limit.

    Returned by :func:`rear_saturation`.

    Attributes
    ----------
    rear_limit : float
        The limit :math:`L` [rad].
    peak : float
        Peak :math:`|\delta_r|` of the run [rad].
    peak_time : float
        Its time [s].
    time_above : float
        Time with :math:`|\delta_r| > L` [s] (crossings interpolated
        linearly between samples); for a run clipped at :math:`L`, the time
        at the limit.
    saturates : bool
        Whether :math:`|\delta_r|` reaches the limit (to 1e-9 relative).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(fws.LateralPlant(veh, speed=5.0), ratio=-1.0,
    ...                           pole=-1.0)
    >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                    initial_state=(0.0, 0.5, 0.0), duration=8.0)
    >>> sat = fws.rear_saturation(res, rear_limit=0.02)
    >>> sat.saturates, round(sat.peak, 4), round(sat.time_above, 2)
    (True, 0.027, 0.14)
    """

    rear_limit: float
    peak: float
    peak_time: float
    time_above: float
    saturates: bool


def rear_saturation(result: Any, *, rear_limit: float | None = None) -> RearSaturation:
    r"""Peak rear angle of a run and the time it spends above a rear limit.

    Parameters
    ----------
    result : SimulationResult
        One run (from :func:`~fws_control.simulate`; with a batch, one of
        its runs ``result[i]``).
    rear_limit : float, optional
        Rear angle limit :math:`L` [rad], in (0, pi/2); default the
        simulated vehicle's ``max_steer_rear``.

    Returns
    -------
    RearSaturation

    Raises
    ------
    ValueError
        For a result of several runs, a run without a rear angle, or a bad
        or missing limit.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, ratio=0.5)
    >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                    initial_state=(0.0, 0.1, 0.0), duration=5.0)
    >>> sat = fws.rear_saturation(res, rear_limit=0.01)
    >>> round(sat.peak, 6)   # |a k1 e0| at t = 0
    0.005
    >>> sat.saturates
    False
    """
    from .simulation import SimulationResult

    if not isinstance(result, SimulationResult):
        raise TypeError(
            f"result must be a SimulationResult, got {type(result).__name__}"
        )
    if len(result) != 1:
        raise ValueError(f"result must hold one run, got {len(result)}: pass result[i]")
    lim = _check_limit(rear_limit, result.vehicle)
    run = result if result.squeeze else result[0]
    t = np.asarray(run.t, dtype=float)
    r = np.abs(np.asarray(run.delta_r, dtype=float))
    ok = np.isfinite(r)
    if not ok.any():
        raise ValueError("result holds no rear angle (the run was not simulated)")
    t, r = t[ok], r[ok]
    peaks = run.peaks
    peak = float(np.max(r))
    peak_time = float(t[np.argmax(r)])
    if peaks.exact:
        exact = float(np.squeeze(peaks.delta_r.value))
        if math.isfinite(exact) and exact >= peak:
            peak, peak_time = exact, float(np.squeeze(peaks.delta_r.time))
    # a clipped run sits at L to rounding: count it as at the limit
    y = r - lim * (1.0 - 1e-9)
    y0, y1 = y[:-1], y[1:]
    dt = np.diff(t)
    both = (y0 > 0) & (y1 > 0)
    cross = (y0 > 0) != (y1 > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(cross, np.maximum(y0, y1) / np.abs(y1 - y0), 0.0)
    above = float(np.sum(dt * both) + np.sum(dt * frac))
    return RearSaturation(
        rear_limit=lim,
        peak=peak,
        peak_time=peak_time,
        time_above=above,
        saturates=bool(peak >= lim * (1.0 - 1e-9)),
    )
