r"""Speed schedules of the most-stable gains: k1(V), k2(V), a(V).

The best gains depend on the speed (the lateral-error gain falls about as
:math:`1/V^2`, the heading gain as :math:`1/V`). A :class:`GainSchedule`
holds the most-stable design
(:func:`~fws_control.most_stable_gains`) at each speed of a grid and gives
gains at any speed in between.

Interpolation
-------------
For the kinematic loop on a straight path with :math:`a = 0` the
characteristic polynomial is

.. math:: s^2 + \frac{V k_2}{f}\, s + \frac{V^2 k_1}{f},

so the scaled gains :math:`k_1 V^2` [rad m/s²] and :math:`k_2 V` [rad m/s]
fix the roots at every speed (with an input delay too: the quasi-polynomial
:math:`s^2 + e^{-s\tau}(V k_2 s + V^2 k_1)/f` holds the same products):
constant scaled gains are the exact speed schedule of that loop, and of
the loop with a steering lag :math:`T` (which multiplies :math:`d(s)` by
:math:`Ts + 1`). A ratio :math:`a \ne 0`, a curved path or a tyre model
make the best scaled gains vary with the speed, while :math:`k_1` itself
falls about as :math:`1/V^2`. :meth:`GainSchedule.at` therefore interpolates
:math:`k_1 V^2`, :math:`k_2 V` and :math:`a` piecewise linearly in
:math:`V` and divides back; at the grid speeds it returns the designed gains
exactly. It does not extrapolate: a speed outside the grid is refused.

During a simulation with a varying speed (``speed=`` a
:class:`~fws_control.SpeedProfile`), a schedule passed as the controller
is read at the current speed at every step (the angle limits of the
vehicle clip its command, and its rate limits act through the actuator,
after the schedule). :meth:`GainSchedule.double_root` tabulates the
double-root rule, with a fixed ratio or a ratio schedule such as
:func:`~fws_control.zero_sideslip_ratio`; any function ``speed ->
SteeringGains`` is a schedule too (evaluated exactly, at every step).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from .delay_design import most_stable_gains
from .equations import unscaled_gains
from .gains import SteeringGains
from .hints import RealArrayLike
from .plant import LateralPlant
from .pole_placement import double_root_gains
from .reprs import summary_repr
from .validation import check_delay, check_finite
from .vehicle import Vehicle

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from .delay_design import MostStableDesign

__all__ = ["GainSchedule", "schedule_gains"]


@summary_repr
@dataclass(frozen=True, eq=False)
class GainSchedule:
    r"""Gains designed at a grid of speeds, interpolated in between.

    Parameters
    ----------
    speeds : array_like
        The grid speeds [m/s], strictly increasing, all of one sign (no 0).
    k1 : array_like
        Lateral-error gain at each speed [rad/m].
    k2 : array_like
        Heading-error gain at each speed [rad/rad].
    ratio : array_like
        Rear-to-front ratio :math:`a` at each speed [-].
    abscissa : array_like, optional
        Spectral abscissa of the design at each speed [1/s] (None: not
        known).
    critical_delay : array_like, optional
        Critical delay of the design at each speed [s] (``inf``: none;
        None: not known).
    delay : float, optional
        The input delay the gains were designed for [s] (None: not known).
    designs : tuple of MostStableDesign, optional
        The designs (from :func:`schedule_gains`).

    Raises
    ------
    ValueError
        If the arrays differ in length, have fewer than 2 speeds, the
        speeds are not strictly increasing, include 0 or change sign, or a
        gain is not finite.

    Examples
    --------
    >>> import fws_control as fws
    >>> sch = fws.GainSchedule(speeds=[10.0, 20.0], k1=[0.01, 0.004],
    ...                        k2=[0.3, 0.2], ratio=[0.0, 0.0])
    >>> g = sch.at(15.0)   # k1 V^2: 1.0 and 1.6 -> 1.3; k2 V: 3 and 4 -> 3.5
    >>> round(g.k1 * 15.0**2, 12), round(g.k2 * 15.0, 12)
    (1.3, 3.5)
    """

    speeds: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    ratio: np.ndarray
    abscissa: np.ndarray | None = None
    critical_delay: np.ndarray | None = None
    delay: float | None = None
    designs: tuple[MostStableDesign, ...] = ()

    def __post_init__(self) -> None:
        v = np.atleast_1d(np.asarray(check_finite("speeds", self.speeds), dtype=float))
        if v.ndim != 1 or v.size < 2:
            raise ValueError(
                f"speeds must be a 1-d grid of at least 2 speeds, got {self.speeds!r}"
            )
        if np.any(v == 0.0) or not (np.all(v > 0) or np.all(v < 0)):
            raise ValueError(
                f"speeds must be nonzero and of one sign, got {v.tolist()}"
            )
        if np.any(np.diff(v) <= 0):
            raise ValueError(f"speeds must be strictly increasing, got {v.tolist()}")
        object.__setattr__(self, "speeds", v)
        for name in ("k1", "k2", "ratio"):
            arr = np.atleast_1d(np.asarray(check_finite(name, getattr(self, name))))
            if arr.shape != v.shape:
                raise ValueError(
                    f"{name} must have one value per speed ({v.size}), got shape "
                    f"{arr.shape}"
                )
            object.__setattr__(self, name, arr.astype(float))
        for name in ("abscissa", "critical_delay"):
            val = getattr(self, name)
            if val is None:
                continue
            if name == "abscissa":
                arr = np.atleast_1d(np.asarray(check_finite(name, val), dtype=float))
            else:  # inf: no delay destabilises the design
                arr = np.atleast_1d(np.asarray(val, dtype=float))
                if np.any(np.isnan(arr) | (arr < 0)):
                    raise ValueError(f"{name} must be >= 0 s (or inf), got {val!r}")
            if arr.shape != v.shape:
                raise ValueError(
                    f"{name} must have one value per speed ({v.size}), got shape "
                    f"{arr.shape}"
                )
            object.__setattr__(self, name, arr)
        if self.delay is not None:
            object.__setattr__(self, "delay", check_delay(self.delay))
        object.__setattr__(self, "designs", tuple(self.designs))

    @classmethod
    def double_root(
        cls,
        plant: Vehicle | LateralPlant,
        *,
        speeds: Any,
        pole: float,
        ratio: Any = 0.0,
    ) -> GainSchedule:
        r"""The double-root gains (:func:`~fws_control.double_root_gains`) on a grid.

        At each speed of `speeds` the gains that put both poles of the
        plant at `pole`, with the ratio `ratio` (a number, or a schedule
        ``ratio(vehicle, speed=...)`` such as
        :func:`~fws_control.zero_sideslip_ratio`, read at each speed).
        Between the grid speeds :meth:`at` interpolates (exact for the
        kinematic straight-road plant with a fixed ratio, whose
        :math:`k_1 V^2` and :math:`k_2 V` do not depend on the speed).

        Parameters
        ----------
        plant : Vehicle or LateralPlant
            A vehicle (the kinematic straight-road plant at each speed) or
            a plant whose speed is replaced.
        speeds : array_like
            The grid [m/s], strictly increasing, of one sign, at least 2.
        pole : float
            Double root :math:`\lambda_0` [1/s], < 0.
        ratio : float or callable, optional
            The ratio :math:`a` (default 0), or a ratio schedule.

        Returns
        -------
        GainSchedule

        Raises
        ------
        ValueError
            As :func:`~fws_control.double_root_gains` (the message names
            the speed) or for a bad grid.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> sch = fws.GainSchedule.double_root(veh, speeds=[5.0, 20.0], pole=-1.0)
        >>> g = sch.at(10.0)        # between the grid speeds: still the double root
        >>> import numpy as np
        >>> A = fws.closed_loop(fws.LateralPlant(veh, speed=10.0), g).A
        >>> np.poly(A).round(9).tolist()     # s^2 + 2 s + 1
        [1.0, 2.0, 1.0]
        """
        v = np.atleast_1d(np.asarray(check_finite("speeds", speeds), dtype=float))
        if v.ndim != 1 or v.size < 2:
            raise ValueError(
                f"speeds must be a 1-d grid of at least 2 speeds, got {speeds!r}"
            )
        designs = []
        for speed in v.tolist():
            p = _plant_at(plant, speed, None, None, None)
            try:
                designs.append(double_root_gains(p, ratio=ratio, pole=pole))
            except ValueError as exc:
                raise ValueError(f"at speed {speed:g} m/s: {exc}") from exc
        return cls(
            speeds=v,
            k1=np.array([float(g.k1) for g in designs]),
            k2=np.array([float(g.k2) for g in designs]),
            ratio=np.array([float(g.ratio) for g in designs]),
        )

    @property
    def scaled_k1(self) -> np.ndarray:
        r""":math:`k_1 V^2` at the grid speeds [rad m/s²], the interpolated values.

        Examples
        --------
        >>> import fws_control as fws
        >>> sch = fws.GainSchedule(speeds=[10.0, 20.0], k1=[0.01, 0.004],
        ...                        k2=[0.3, 0.2], ratio=[0.0, 0.0])
        >>> [round(float(v), 12) for v in sch.scaled_k1]
        [1.0, 1.6]
        """
        return self.k1 * self.speeds**2

    @property
    def scaled_k2(self) -> np.ndarray:
        r""":math:`k_2 V` at the grid speeds [rad m/s], the interpolated values.

        Examples
        --------
        >>> import fws_control as fws
        >>> sch = fws.GainSchedule(speeds=[10.0, 20.0], k1=[0.01, 0.004],
        ...                        k2=[0.3, 0.2], ratio=[0.0, 0.0])
        >>> [round(float(v), 12) for v in sch.scaled_k2]
        [3.0, 4.0]
        """
        return self.k2 * self.speeds

    def at(self, speed: RealArrayLike) -> SteeringGains:
        r"""The gains at `speed` (scalar or array), interpolated.

        :math:`k_1 V^2`, :math:`k_2 V` and :math:`a` are interpolated
        piecewise linearly in :math:`V` (see :mod:`fws_control.schedule`).

        Parameters
        ----------
        speed : float or array_like
            Speed(s) [m/s] within the grid.

        Returns
        -------
        SteeringGains
            Scalar gains for a scalar speed, arrays for an array.

        Raises
        ------
        ValueError
            For a speed outside ``[speeds[0], speeds[-1]]`` or not finite.

        Examples
        --------
        >>> import fws_control as fws
        >>> sch = fws.GainSchedule(speeds=[10.0, 30.0], k1=[0.01, 0.001],
        ...                        k2=[0.3, 0.1], ratio=[0.0, 0.2])
        >>> sch.at(10.0)
        SteeringGains(k1=0.01, k2=0.3, ratio=0.0)
        >>> round(sch.at(20.0).ratio, 12)
        0.1
        """
        v = np.asarray(check_finite("speed", speed), dtype=float)
        lo, hi = self.speeds[0], self.speeds[-1]
        if np.any((v < lo) | (v > hi)):
            raise ValueError(
                f"speed must lie in the schedule's range [{lo:g}, {hi:g}] m/s "
                f"(no extrapolation), got {speed!r}"
            )
        V = self.speeds
        k1, k2 = unscaled_gains(
            v, np.interp(v, V, self.scaled_k1), np.interp(v, V, self.scaled_k2)
        )
        a = np.interp(v, V, self.ratio)
        if v.ndim == 0:
            return SteeringGains(float(k1), float(k2), float(a))
        return SteeringGains(k1, k2, a)

    def plot(self, ax: Sequence[Axes] | np.ndarray | None = None) -> ct.ControlPlot:
        """Draw k1, k2, a and the abscissa against the speed.

        Lines: the interpolation of :meth:`at`; markers: the designs.

        Parameters
        ----------
        ax : array of four matplotlib.axes.Axes, optional
            Axes to draw on (k1, k2, a, abscissa); a new 2 x 2 figure if None.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> sch = fws.GainSchedule(speeds=[10.0, 30.0], k1=[0.01, 0.001],
        ...                        k2=[0.3, 0.1], ratio=[0.0, 0.0])
        >>> cplt = sch.plot()
        >>> cplt.axes[1, 1].get_xlabel()
        'speed V [m/s]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        if ax is None:
            fig, axes = plt.subplots(
                2, 2, figsize=(8.0, 5.5), layout="constrained", sharex=True
            )
        else:
            axes = np.asarray(ax, dtype=object)
            if axes.size != 4:
                raise ValueError(f"ax must hold four axes, got {axes.size}")
            axes = axes.reshape(2, 2)
            fig = axes[0, 0].figure
        v = np.linspace(self.speeds[0], self.speeds[-1], 200)
        g = self.at(v)
        lines = []
        panels = (
            (axes[0, 0], g.k1, self.k1, "$k_1$ [rad/m]"),
            (axes[0, 1], g.k2, self.k2, "$k_2$ [rad/rad]"),
            (axes[1, 0], g.ratio * np.ones_like(v), self.ratio, "ratio $a$ [-]"),
            (
                axes[1, 1],
                None,
                np.full(self.speeds.shape, np.nan)
                if self.abscissa is None
                else self.abscissa,
                r"abscissa $\alpha$ [1/s]",
            ),
        )  # fmt: skip
        for a, curve, points, label in panels:
            if curve is not None:
                (ln,) = a.plot(v, curve, "-", color="C0")
                lines.append(ln)
            (mk,) = a.plot(
                self.speeds, points, "o", color="C1" if curve is None else "C0"
            )
            lines.append(mk)
            a.set_ylabel(label)
            a.grid(True, alpha=0.3)
        for a in axes[1]:
            a.set_xlabel("speed V [m/s]")
        title = "gain schedule"
        if self.delay is not None:
            title += f", delay {self.delay:g} s"
        axes[0, 0].set_title(title)
        return ct.ControlPlot(lines, axes, fig)


def _plant_at(plant, speed: float, steering_lag, curvature, model):
    if isinstance(plant, Vehicle):
        return LateralPlant(
            plant,
            speed=speed,
            curvature=0.0 if curvature is None else curvature,
            model="kinematic" if model is None else model,
            steering_lag=steering_lag,
        )
    if isinstance(plant, LateralPlant):
        changes: dict[str, Any] = {"speed": speed}
        if steering_lag is not None:
            changes["steering_lag"] = steering_lag
        if curvature is not None:
            changes["curvature"] = curvature
        if model is not None:
            changes["model"] = model
        return dataclasses.replace(plant, **changes)
    return plant(speed)


def schedule_gains(
    plant: Vehicle | LateralPlant | Callable[[float], Any],
    *,
    speeds: RealArrayLike,
    delay: float,
    ratio: float = 0.0,
    ratio_bounds: tuple[float, float] | None = None,
    steering_lag: Any = None,
    curvature: float | None = None,
    model: str | None = None,
    grid: int = 6,
) -> GainSchedule:
    r"""The most-stable gains at each speed of a grid, as a :class:`GainSchedule`.

    Calls :func:`most_stable_gains` once per speed (each certified).

    Parameters
    ----------
    plant : Vehicle, LateralPlant or callable
        A vehicle (a :class:`LateralPlant` is built at each speed with
        `steering_lag`, `curvature`, `model`), a plant whose speed is
        replaced (and the options given), or a function ``speed -> plant``
        (any plant :func:`most_stable_gains` takes).
    speeds : array_like
        The speeds [m/s], strictly increasing, at least 2.
    delay : float
        Input delay [s], in (0, 1000].
    ratio : float, optional
        Rear-to-front ratio :math:`a` (fixed; the start with `ratio_bounds`).
    ratio_bounds : (float, float), optional
        Let :math:`a` vary within these bounds at each speed.
    steering_lag : float or (float, float), optional
        Steering lag [s] of the plants built from a vehicle (or replacing the
        plant's).
    curvature : float, optional
        Path curvature [1/m] (default 0 for a vehicle).
    model : str, optional
        ``"kinematic"`` (default for a vehicle) or ``"paper"``.
    grid : int, optional
        Start grid of each most-stable search, 4 to 40.

    Returns
    -------
    GainSchedule

    Raises
    ------
    ValueError
        For bad speeds or delay, or when a most-stable search fails at a
        speed (the message names the speed).
    TypeError
        If `plant` is none of the three kinds.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sch = fws.schedule_gains(veh, speeds=[10.0, 20.0], delay=0.24)
    >>> [round(float(a), 3) for a in sch.abscissa]
    [-2.441, -2.441]
    >>> [round(float(k * v), 4) for k, v in zip(sch.k2, sch.speeds)]
    [5.188, 5.188]
    """
    if not (isinstance(plant, (Vehicle, LateralPlant)) or callable(plant)):
        raise TypeError(
            "plant must be a Vehicle, a LateralPlant or a function speed -> plant, "
            f"got {type(plant).__name__}"
        )
    tau = check_delay(delay)
    if not 0.0 < tau <= 1e3:
        raise ValueError(f"delay must be in (0, 1000] s, got {delay!r}")
    v = np.atleast_1d(np.asarray(check_finite("speeds", speeds), dtype=float))
    if v.ndim != 1 or v.size < 2 or np.any(np.diff(v) <= 0) or np.any(v == 0):
        raise ValueError(
            "speeds must be a strictly increasing 1-d grid of at least 2 nonzero "
            f"speeds [m/s], got {speeds!r}"
        )
    designs = []
    for speed in v:
        p = _plant_at(plant, float(speed), steering_lag, curvature, model)
        try:
            designs.append(
                most_stable_gains(
                    p, delay=tau, ratio=ratio, ratio_bounds=ratio_bounds, grid=grid
                )
            )
        except ValueError as exc:
            raise ValueError(f"at speed {speed:g} m/s: {exc}") from exc
    return GainSchedule(
        speeds=v,
        k1=np.array([float(d.gains.k1) for d in designs]),
        k2=np.array([float(d.gains.k2) for d in designs]),
        ratio=np.array([float(d.gains.ratio) for d in designs]),
        abscissa=np.array([d.abscissa for d in designs]),
        critical_delay=np.array([d.critical_delay for d in designs]),
        delay=tau,
        designs=tuple(designs),
    )
