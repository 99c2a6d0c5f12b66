r"""Speed profiles: a speed that varies along a simulated run.

A :class:`SpeedProfile` gives the speed :math:`V` [m/s] as a function of
the time :math:`t` or of the path's arc length :math:`s` (the
projection of the rear-axle centre R, the simulation's state ``s``), and
its derivative, from which the simulation reports the longitudinal
acceleration :math:`\dot V = dV/dt` (for a distance profile
:math:`\dot V = V'(s)\,\dot s`). Pass it to
:func:`~fws_control.simulate` or :func:`~fws_control.simulate_batch` as
``speed=``; the plant then gives the vehicle, model, tyre and lag, and
its own `speed` is its linearisation point only, as its `curvature` is.

Interpolation
-------------
A table of points ``(t, v)`` or ``(s, v)`` is interpolated by PCHIP
(:class:`scipy.interpolate.PchipInterpolator`, the piecewise cubic Hermite
interpolant of Fritsch and Carlson): it is C1, so the acceleration
:math:`\dot V` is continuous and the closed loop's right-hand side has no
jump for the solver to meet, and it is shape-preserving: between two
points the speed stays between their values (a C2 cubic spline overshoots
near a sharp change). A table of speeds of one sign therefore never
reverses or stops between its points, and a table that brakes
monotonically never accelerates. Before the first point and after the
last one the speed is held at the end value (acceleration zero).

:meth:`SpeedProfile.braking` is the exception: a constant deceleration is
interpolated linearly (its acceleration is the step of the braking
manoeuvre itself).

Sign
----
All speeds of a profile have one sign (a profile may end at 0, a stop):
reversing through zero speed is refused, since the path-frame errors of the
rear-axle centre change meaning with the direction of travel. The dynamic
single-track model needs :math:`V > 0` everywhere (its slip angles divide
by :math:`u`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from .validation import MAX_SPEED, check_finite

__all__ = ["SpeedProfile", "PROFILE_ARGUMENTS", "INTERPOLATIONS"]

#: What a profile is a function of: the time ``t`` [s] or the path's arc
#: length ``s`` [m].
PROFILE_ARGUMENTS = ("time", "distance")

#: Interpolations of a table: PCHIP (C1, shape-preserving) or linear.
INTERPOLATIONS = ("pchip", "linear")

# Relative step of the central difference that gives the derivative of a
# user function without its own `rate` (error ~ h^2 |V'''| / 6: about 1e-12
# of the speed for a profile that varies on a scale of one second or metre).
_DIFF_STEP = 1e-6


def _short(value: Any) -> str:
    return np.array2string(np.asarray(value), threshold=8, precision=6)


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    r"""A speed that varies in time or along the path, for a simulation.

    Build one with :meth:`from_time`, :meth:`from_distance`,
    :meth:`constant`, :meth:`braking` or :meth:`from_function`.

    Parameters
    ----------
    of : {"time", "distance"}
        The argument of the profile: the time :math:`t` [s] or the path's
        arc length :math:`s` [m].
    points : array_like or None
        The table's abscissae (times or arc lengths), strictly increasing,
        finite, at least 2; None for a constant or a function.
    speeds : array_like or None
        The speeds at the points [m/s], finite, ``|v| <= 1e6``, all of one
        sign (0 allowed: a stop); a single nonzero speed for a constant.
    function : callable or None
        ``function(x) -> speed`` for an array ``x`` of times or arc lengths
        (vectorised), instead of a table.
    rate : callable or None
        ``rate(x) -> dV/dx`` of `function`; None: a central difference of
        `function` (relative step 1e-6).
    interpolation : {"pchip", "linear"}, optional
        Of the table (see :mod:`fws_control.speed_profile`).

    Raises
    ------
    ValueError
        For an unknown `of` or `interpolation`, a non-monotone or
        non-finite table, speeds that change sign or exceed 1e6 m/s, or an
        inconsistent combination of the fields; the message names the
        argument, the value and the valid range.
    TypeError
        If `function` or `rate` is not callable.

    Examples
    --------
    >>> import fws_control as fws
    >>> prof = fws.SpeedProfile.from_time([0.0, 4.0], [20.0, 12.0])
    >>> float(prof(0.0)), float(prof(4.0)), float(prof(10.0))   # held after
    (20.0, 12.0, 12.0)
    >>> float(prof.derivative(2.0))           # PCHIP of two points: a line
    -2.0
    """

    of: str
    points: np.ndarray | None = None
    speeds: np.ndarray | None = None
    function: Callable[[Any], Any] | None = None
    rate: Callable[[Any], Any] | None = None
    interpolation: str = "pchip"
    _interp: Any = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.of not in PROFILE_ARGUMENTS:
            raise ValueError(f"of must be one of {PROFILE_ARGUMENTS}, got {self.of!r}")
        if self.interpolation not in INTERPOLATIONS:
            raise ValueError(
                f"interpolation must be one of {INTERPOLATIONS}, got "
                f"{self.interpolation!r}"
            )
        if self.function is not None:
            if not callable(self.function):
                raise TypeError(
                    f"function must be callable (x -> speed), got "
                    f"{type(self.function).__name__}"
                )
            if self.rate is not None and not callable(self.rate):
                raise TypeError(
                    f"rate must be callable (x -> dV/dx) or None, got "
                    f"{type(self.rate).__name__}"
                )
            if self.points is not None or self.speeds is not None:
                raise ValueError(
                    "a SpeedProfile holds a table (points, speeds) or a function, "
                    "not both"
                )
            return
        if self.rate is not None:
            raise ValueError("rate applies to a function profile only")
        if self.speeds is None:
            raise ValueError("a SpeedProfile needs speeds (a table) or a function")
        v = np.atleast_1d(np.asarray(check_finite("speeds", self.speeds), dtype=float))
        if v.ndim != 1:
            raise ValueError(f"speeds must be 1-D, got shape {v.shape}")
        big = np.flatnonzero(np.abs(v) > MAX_SPEED)
        if big.size:
            raise ValueError(
                f"speeds must lie in [-{MAX_SPEED:g}, {MAX_SPEED:g}] m/s, got "
                f"{float(v[big[0]])!r} at index {int(big[0])}"
            )
        if self.points is None:
            if v.size != 1 or v[0] == 0.0:
                raise ValueError(
                    "a constant SpeedProfile needs one nonzero speed in "
                    f"[-{MAX_SPEED:g}, {MAX_SPEED:g}] m/s, got {_short(v)}"
                )
            object.__setattr__(self, "speeds", v)
            return
        x = np.atleast_1d(np.asarray(check_finite("points", self.points), dtype=float))
        if x.ndim != 1 or x.size < 2:
            raise ValueError(
                f"points must be a 1-D table of at least 2 {self._unit_name()}, got "
                f"shape {x.shape}"
            )
        if v.shape != x.shape:
            raise ValueError(
                f"speeds must have one value per point ({x.size}), got shape {v.shape}"
            )
        steps = np.diff(x)
        bad = np.flatnonzero(~(steps > 0.0))
        if bad.size:
            i = int(bad[0])
            raise ValueError(
                f"points ({self._unit_name()}) must be strictly increasing, got "
                f"{float(x[i])!r} then {float(x[i + 1])!r} at indices {i}, {i + 1}"
            )
        if np.any(v > 0.0) and np.any(v < 0.0):
            i = int(np.flatnonzero(np.sign(v) != np.sign(v[np.flatnonzero(v)[0]]))[0])
            raise ValueError(
                "speeds must not change sign (reversing through zero speed is not "
                "simulated: every speed >= 0 or every speed <= 0), got "
                f"{float(v[i])!r} at index {i} in {_short(v)}"
            )
        if not np.any(v):
            raise ValueError(f"speeds must not all be 0, got {_short(v)}")
        object.__setattr__(self, "points", x)
        object.__setattr__(self, "speeds", v)
        if self.interpolation == "pchip":
            from scipy.interpolate import PchipInterpolator

            object.__setattr__(self, "_interp", PchipInterpolator(x, v))

    def _unit_name(self) -> str:
        return "times [s]" if self.of == "time" else "arc lengths [m]"

    # ------------------------------------------------------------------
    # constructors

    @classmethod
    def from_time(cls, t: Any, v: Any, *, interpolation: str = "pchip") -> SpeedProfile:
        """A table of speeds `v` [m/s] at times `t` [s], interpolated.

        Parameters
        ----------
        t : array_like
            Times [s], strictly increasing, finite, at least 2.
        v : array_like
            Speeds [m/s] at `t`: finite, of one sign, ``|v| <= 1e6``.
        interpolation : {"pchip", "linear"}, optional
            PCHIP (default: C1 and shape-preserving) or linear.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> import fws_control as fws
        >>> prof = fws.SpeedProfile.from_time([0.0, 2.0, 5.0], [10.0, 14.0, 14.0])
        >>> float(prof(2.0)), float(prof.derivative(5.0))
        (14.0, 0.0)
        """
        return cls("time", points=t, speeds=v, interpolation=interpolation)

    @classmethod
    def from_distance(
        cls, s: Any, v: Any, *, interpolation: str = "pchip"
    ) -> SpeedProfile:
        """A table of speeds `v` [m/s] at arc lengths `s` [m] of the path.

        Parameters
        ----------
        s : array_like
            Arc lengths of the path [m] (the projection of the rear-axle
            centre), strictly increasing, finite, at least 2.
        v : array_like
            Speeds [m/s] at `s`: finite, of one sign, ``|v| <= 1e6``.
        interpolation : {"pchip", "linear"}, optional
            PCHIP (default: C1 and shape-preserving) or linear.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> import fws_control as fws
        >>> prof = fws.SpeedProfile.from_distance([0.0, 50.0], [8.0, 16.0])
        >>> float(prof(25.0)), prof.of
        (12.0, 'distance')
        """
        return cls("distance", points=s, speeds=v, interpolation=interpolation)

    @classmethod
    def constant(cls, v: float) -> SpeedProfile:
        """A constant speed `v` [m/s] (nonzero): the same run as ``plant.speed = v``.

        Parameters
        ----------
        v : float
            The speed [m/s], finite, nonzero, ``|v| <= 1e6``.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> import fws_control as fws
        >>> prof = fws.SpeedProfile.constant(15.0)
        >>> prof.is_constant, float(prof(3.0)), float(prof.derivative(3.0))
        (True, 15.0, 0.0)
        """
        return cls("time", speeds=np.array([check_finite("v", v)], dtype=float))

    @classmethod
    def braking(
        cls, v0: float, decel: float, *, start: float = 0.0, final: float = 0.0
    ) -> SpeedProfile:
        r"""Constant speed `v0`, then a constant deceleration from time `start`.

        .. math:: V(t) = \max(v_0 - d\,(t - t_0)^+,\ v_{final})

        Interpolated linearly (exactly this function).

        Parameters
        ----------
        v0 : float
            Initial speed [m/s], > 0.
        decel : float
            Deceleration :math:`d` [m/s²], > 0.
        start : float, optional
            Time the braking begins [s], >= 0.
        final : float, optional
            Speed at which the braking ends and is held [m/s], in ``[0, v0)``.

        Examples
        --------
        >>> import fws_control as fws
        >>> prof = fws.SpeedProfile.braking(80 / 3.6, 4.0, start=1.0, final=5.0)
        >>> round(float(prof(2.0)), 6), float(prof.derivative(2.0))
        (18.222222, -4.0)
        >>> float(prof(60.0))
        5.0
        """
        for name, value in (("v0", v0), ("decel", decel), ("start", start)):
            if np.ndim(value) != 0:
                raise ValueError(f"{name} must be a scalar, got {value!r}")
        v0 = float(check_finite("v0", v0))
        decel = float(check_finite("decel", decel))
        start = float(check_finite("start", start))
        final = float(check_finite("final", final))
        if not 0.0 < v0 <= MAX_SPEED:
            raise ValueError(f"v0 must be in (0, {MAX_SPEED:g}] m/s, got {v0!r}")
        if not decel > 0.0:
            raise ValueError(f"decel must be > 0 m/s^2, got {decel!r}")
        if not start >= 0.0:
            raise ValueError(f"start must be >= 0 s, got {start!r}")
        if not 0.0 <= final < v0:
            raise ValueError(f"final must be in [0, v0={v0!r}) m/s, got {final!r}")
        end = start + (v0 - final) / decel
        if not math.isfinite(end) or end <= start:
            raise ValueError(
                f"decel={decel!r} m/s^2 is too small or too large for v0={v0!r} "
                "m/s: the braking time is not a finite positive number"
            )
        if start > 0.0:
            return cls.from_time(
                [0.0, start, end], [v0, v0, final], interpolation="linear"
            )
        return cls.from_time([0.0, end], [v0, final], interpolation="linear")

    @classmethod
    def from_function(
        cls,
        function: Callable[[Any], Any],
        *,
        of: str = "time",
        rate: Callable[[Any], Any] | None = None,
    ) -> SpeedProfile:
        """A user function ``x -> speed`` of the time or the arc length.

        The function takes and returns arrays (vectorised). Without `rate`
        its derivative is a central difference. A function drives forward:
        the simulation checks the speeds it meets, and a non-finite or
        negative speed (for the dynamic model also 0) raises
        :class:`ValueError`.

        Parameters
        ----------
        function : callable
            ``function(x) -> speed`` [m/s] for an array of times or arc
            lengths.
        of : {"time", "distance"}, optional
            What `x` is: the time [s] (default) or the arc length [m].
        rate : callable, optional
            ``rate(x) -> dV/dx``; None: a central difference.

        Returns
        -------
        SpeedProfile

        Examples
        --------
        >>> import numpy as np, fws_control as fws
        >>> prof = fws.SpeedProfile.from_function(lambda t: 10.0 + np.sin(t))
        >>> round(float(prof.derivative(0.0)), 8)     # cos(0)
        1.0
        """
        return cls(of, function=function, rate=rate)

    # ------------------------------------------------------------------
    # evaluation

    @property
    def is_constant(self) -> bool:
        """True for :meth:`constant` (one speed, no table, no function)."""
        return self.function is None and self.points is None

    @property
    def initial_sign(self) -> float:
        """+1 or -1: the direction of a table or a constant (0: a function)."""
        if self.speeds is None:
            return 0.0
        return float(np.sign(self.speeds[np.flatnonzero(self.speeds)[0]]))

    def __call__(self, x: Any) -> np.ndarray:
        """The speed [m/s] at `x` (times or arc lengths), broadcast.

        Parameters
        ----------
        x : float or array_like
            Times [s] or arc lengths [m]; outside the table the end speed
            is held.

        Returns
        -------
        ndarray
        """
        x = np.asarray(x, dtype=float)
        if self.function is not None:
            return np.broadcast_to(
                np.asarray(self.function(x), dtype=float), x.shape
            ).copy()
        # without a function, __post_init__ has stored the table as arrays
        points, speeds = cast(np.ndarray, self.points), cast(np.ndarray, self.speeds)
        if self.is_constant:
            return np.full(x.shape, speeds[0])
        xc = np.clip(x, points[0], points[-1])
        if self._interp is not None:
            return np.asarray(self._interp(xc), dtype=float)
        return np.interp(xc, points, speeds)

    def derivative(self, x: Any) -> np.ndarray:
        """``dV/dt`` [m/s²] (time) or ``dV/ds`` [1/s] (distance) at `x`.

        Parameters
        ----------
        x : float or array_like
            Times [s] or arc lengths [m]; outside the table the derivative
            is 0 (the speed is held).

        Returns
        -------
        ndarray

        Examples
        --------
        >>> import fws_control as fws
        >>> float(fws.SpeedProfile.braking(20.0, 4.0).derivative(1.0))
        -4.0
        """
        x = np.asarray(x, dtype=float)
        if self.is_constant:
            return np.zeros(x.shape)
        if self.function is not None:
            if self.rate is not None:
                return np.broadcast_to(
                    np.asarray(self.rate(x), dtype=float), x.shape
                ).copy()
            h = _DIFF_STEP * np.maximum(1.0, np.abs(x))
            up = np.asarray(self.function(x + h), dtype=float)
            down = np.asarray(self.function(x - h), dtype=float)
            return np.broadcast_to((up - down) / (2.0 * h), x.shape).copy()
        # without a function, __post_init__ has stored the table as arrays
        points, speeds = cast(np.ndarray, self.points), cast(np.ndarray, self.speeds)
        outside = (x < points[0]) | (x > points[-1])
        if self._interp is not None:
            d = np.asarray(self._interp(x, 1), dtype=float)
        else:
            # the slope of the segment on the right (the braking step starts
            # at its time)
            k = np.clip(
                np.searchsorted(points, x, side="right") - 1,
                0,
                points.size - 2,
            )
            d = np.diff(speeds)[k] / np.diff(points)[k]
        return np.where(outside, 0.0, d)

    def __repr__(self) -> str:
        if self.is_constant:
            return f"SpeedProfile.constant({float(cast(np.ndarray, self.speeds)[0])!r})"
        if self.function is not None:
            return f"SpeedProfile.from_function({self.function!r}, of={self.of!r})"
        return (
            f"SpeedProfile(of={self.of!r}, points={_short(self.points)}, "
            f"speeds={_short(self.speeds)}, interpolation={self.interpolation!r})"
        )
