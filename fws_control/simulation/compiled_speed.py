r"""Speed profiles and gain schedules on the compiled engine.

A run with a varying speed (a :class:`~fws_control.SpeedProfile`) reads
its speed, and with a :class:`~fws_control.GainSchedule` its gains, at every
evaluation of the right-hand side, of the stop events and of the clip
switches of :mod:`~fws_control.simulation.compiled`. The profile and the
schedule travel to the kernels as tables appended to the curvature table's
``breaks`` and ``coefs`` (one row per point, the rows of each table after a
padding row), with their first row and their piece count in the shared
parameter vector ``q``:

======  ==============================================================
``q``   meaning
======  ==============================================================
36      breaks of the curvature table (0: no table appended)
37      0: constant speed; 1: a profile of the time; 2: of the arc length
38, 39  first row and number of pieces of the profile
40      1: the profile is linear (the end value exact, as ``np.interp``)
41, 42  first row and number of pieces of the schedule (0: fixed gains)
======  ==============================================================

and ``p[18]`` (per run) the time at which the events read the speed.

The profile's rows hold the local power-basis coefficients of its
interpolant: PCHIP's (:class:`scipy.interpolate.PchipInterpolator`, the
same polynomials :class:`~fws_control.SpeedProfile` evaluates), or the
value and slope of each segment of a linear table; before the first point
and after the last one the end speed is held, as the profile does. The
schedule's rows hold :math:`k_1 V^2`, :math:`k_2 V` and :math:`a` at the
grid speeds, interpolated as :func:`numpy.interp` does (the same
operations, so the same numbers as :meth:`~fws_control.GainSchedule.at`),
and divided back by :func:`~fws_control.equations.unscaled_gains`. The
angle and rate limits of the vehicle act after the schedule, as on the
numpy engine.

Only tables compile: a :meth:`~fws_control.SpeedProfile.from_function`
profile and a gain schedule given as a Python function are evaluated in
Python (:func:`compiled_speed_reason` says so, ``engine="auto"`` runs them
on the numpy engine). A profile whose speeds leave the schedule's grid is
refused for the same reason (the numpy engine raises where the run meets
such a speed). The integration is compiled; the output signals and exact
peaks of a varying-speed run are computed on its compiled dense output
(:class:`~fws_control.simulation.dense.CompiledDense`) by the numpy
engine's own functions, so the longitudinal signals and the scheduled
command's rate are the numpy engine's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .. import equations
from ..speed_profile import SpeedProfile
from .compilation import jit
from .compiled_layout import table_piece

if TYPE_CHECKING:
    from ..schedule import GainSchedule

__all__ = [
    "Q_CURVATURE_BREAKS",
    "Q_PROFILE",
    "Q_PROFILE_ROW",
    "Q_PROFILE_PIECES",
    "Q_PROFILE_LINEAR",
    "Q_SCHEDULE_ROW",
    "Q_SCHEDULE_PIECES",
    "P_SPEED_TIME",
    "PROFILE_OF_TIME",
    "PROFILE_OF_DISTANCE",
    "compiled_speed_reason",
    "speed_tables",
    "speed_and_gains",
]

#: Slots of the shared parameter vector ``q`` (see the module notes).
Q_CURVATURE_BREAKS = 36
Q_PROFILE = 37
Q_PROFILE_ROW, Q_PROFILE_PIECES, Q_PROFILE_LINEAR = 38, 39, 40
Q_SCHEDULE_ROW, Q_SCHEDULE_PIECES = 41, 42
#: Slot of the per run parameters: the time of the state the events and
#: clip switches evaluate (they take no time; a profile of the time needs it).
P_SPEED_TIME = 18
#: Values of ``q[Q_PROFILE]``.
PROFILE_OF_TIME, PROFILE_OF_DISTANCE = 1.0, 2.0

_unscaled_gains = jit(equations.unscaled_gains, inline="always")


def compiled_speed_reason(
    profile: SpeedProfile | None, schedule: Any = None, *, method: Any = "DOP853"
) -> str | None:
    """Why the compiled engine cannot run this varying speed, or None.

    Parameters
    ----------
    profile : SpeedProfile or None
        The run's speed (None or a constant one: nothing to say).
    schedule : optional
        The gain schedule read at the current speed (None: fixed gains).
    method : str or scipy.integrate.OdeSolver, optional
        The integration method: a varying speed is compiled with DOP853.

    Returns
    -------
    str or None

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled_speed import compiled_speed_reason
    >>> prof = fws.SpeedProfile.braking(20.0, 4.0)
    >>> compiled_speed_reason(prof) is None
    True
    >>> fun = fws.SpeedProfile.from_function(lambda t: 5.0 + t)
    >>> compiled_speed_reason(fun).startswith("a SpeedProfile.from_function is")
    True
    """
    if profile is None or profile.is_constant:
        return None
    if profile.function is not None or profile.speeds is None:
        return (
            "a SpeedProfile.from_function is evaluated in Python, not compiled (a "
            "table of SpeedProfile.from_time or from_distance is)"
        )
    name = method if isinstance(method, str) else getattr(method, "__name__", "")
    if name != "DOP853":
        return f"a varying speed is compiled with method='DOP853' only, got {method!r}"
    if schedule is None:
        return None
    # imported here: schedule.py imports python-control (0.7 s), which a
    # simulation does not need
    from ..schedule import GainSchedule

    if not isinstance(schedule, GainSchedule):
        return (
            "a gain schedule given as a function is evaluated in Python, not "
            "compiled (a GainSchedule table is)"
        )
    lo, hi = float(np.min(profile.speeds)), float(np.max(profile.speeds))
    g_lo, g_hi = float(schedule.speeds[0]), float(schedule.speeds[-1])
    if lo < g_lo or hi > g_hi:
        return (
            f"the profile's speeds [{lo:g}, {hi:g}] m/s leave the schedule's range "
            f"[{g_lo:g}, {g_hi:g}] m/s"
        )
    return None


def speed_tables(
    breaks: np.ndarray,
    coefs: np.ndarray,
    profile: SpeedProfile,
    schedule: GainSchedule | None,
    q: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The curvature table's arrays with the profile and schedule appended.

    Writes the slots of the module notes into `q` (in place).

    Parameters
    ----------
    breaks, coefs : ndarray
        The curvature table's (``(K + 1,)`` and ``(K, 4)``).
    profile : SpeedProfile
        A table (:meth:`~fws_control.SpeedProfile.from_time` or
        :meth:`~fws_control.SpeedProfile.from_distance`).
    schedule : GainSchedule or None
        Gains read at the current speed (None: the run's fixed gains).
    q : ndarray
        The shared parameters (at least 43 entries).

    Returns
    -------
    breaks, coefs : ndarray
        The extended arrays.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled_speed import speed_tables
    >>> prof = fws.SpeedProfile.braking(20.0, 4.0)        # 20 -> 0 m/s in 5 s
    >>> q = np.zeros(44)
    >>> br, co = speed_tables(np.array([0.0, 1.0]), np.zeros((1, 4)), prof, None, q)
    >>> br.tolist(), co[2].tolist(), q[37:41].tolist()
    ([0.0, 1.0, 0.0, 5.0], [20.0, -4.0, 0.0, 0.0], [1.0, 2.0, 1.0, 1.0])
    """
    if profile.points is None or profile.speeds is None:
        raise ValueError(
            f"profile must be a table (from_time or from_distance), got {profile!r}"
        )
    x, v = profile.points, profile.speeds
    if profile.interpolation == "pchip":
        from scipy.interpolate import PchipInterpolator

        c = PchipInterpolator(x, v).c  # (4, pieces), highest power first
        rows = c[::-1].T
    else:
        rows = np.zeros((x.size - 1, 4))
        rows[:, 0] = v[:-1]
        rows[:, 1] = np.diff(v) / np.diff(x)
    end = np.array([[v[-1], 0.0, 0.0, 0.0]])
    b_parts = [np.asarray(breaks, dtype=float), x]
    c_parts = [np.asarray(coefs, dtype=float), np.zeros((1, 4)), rows, end]
    k = coefs.shape[0]
    q[Q_CURVATURE_BREAKS] = k + 1
    q[Q_PROFILE] = PROFILE_OF_TIME if profile.of == "time" else PROFILE_OF_DISTANCE
    q[Q_PROFILE_ROW] = k + 1
    q[Q_PROFILE_PIECES] = x.size - 1
    q[Q_PROFILE_LINEAR] = 1.0 if profile.interpolation == "linear" else 0.0
    q[Q_SCHEDULE_ROW] = 0.0
    q[Q_SCHEDULE_PIECES] = 0.0
    if schedule is not None:
        q[Q_SCHEDULE_ROW] = k + 1 + x.size
        q[Q_SCHEDULE_PIECES] = schedule.speeds.size - 1
        rows = np.zeros((schedule.speeds.size, 4))
        rows[:, 0] = schedule.scaled_k1
        rows[:, 1] = schedule.scaled_k2
        rows[:, 2] = schedule.ratio
        b_parts.append(schedule.speeds)
        c_parts.append(rows)
    return (
        np.ascontiguousarray(np.concatenate(b_parts)),
        np.ascontiguousarray(np.concatenate(c_parts)),
    )


@jit
def _interp(x, breaks, coefs, row, pieces, col):
    """``np.interp(x, breaks[rows], coefs[rows, col])`` with its operations."""
    last = row + pieces
    if x > breaks[last] or x == breaks[last]:
        return coefs[last, col]
    if x < breaks[row]:
        return coefs[row, col]
    j = table_piece(x, breaks, row, pieces)
    if x == breaks[j]:
        return coefs[j, col]
    slope = (coefs[j + 1, col] - coefs[j, col]) / (breaks[j + 1] - breaks[j])
    return slope * (x - breaks[j]) + coefs[j, col]


@jit
def _profile_speed(x, q, breaks, coefs):
    """The profile's speed at `x` (time or arc length), the end speeds held."""
    row, pieces = int(q[Q_PROFILE_ROW]), int(q[Q_PROFILE_PIECES])
    lo, hi = breaks[row], breaks[row + pieces]
    xc = min(max(x, lo), hi)
    if q[Q_PROFILE_LINEAR] != 0.0 and xc == hi:
        return coefs[row + pieces, 0]  # np.interp's end value
    k = table_piece(xc, breaks, row, pieces)
    d = xc - breaks[k]
    return coefs[k, 0] + d * (coefs[k, 1] + d * (coefs[k, 2] + d * coefs[k, 3]))


@jit
def speed_and_gains(t, s, q, breaks, coefs):
    """``(V, k1, k2, ratio, scheduled)`` at time `t` and arc length `s`.

    The speed of the profile in `q`, breaks and coefs (see the module
    notes); with a schedule its gains at that speed (``scheduled`` True),
    else ``k1 = k2 = ratio = 0`` and ``scheduled`` False.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled_speed import speed_and_gains, speed_tables
    >>> prof = fws.SpeedProfile.from_time([0.0, 4.0], [20.0, 12.0])
    >>> sch = fws.GainSchedule(speeds=[10.0, 20.0], k1=[0.01, 0.004],
    ...                        k2=[0.3, 0.2], ratio=[0.0, 0.2])
    >>> q = np.zeros(44)
    >>> br, co = speed_tables(np.array([0.0, 1.0]), np.zeros((1, 4)), prof, sch, q)
    >>> V, k1, k2, a, _ = speed_and_gains(2.0, 0.0, q, br, co)
    >>> g = sch.at(16.0)
    >>> V, (k1, k2, a) == (g.k1, g.k2, g.ratio)
    (16.0, True)
    """
    x = t if q[Q_PROFILE] == PROFILE_OF_TIME else s
    V = _profile_speed(x, q, breaks, coefs)
    pieces = int(q[Q_SCHEDULE_PIECES])
    if pieces == 0:
        return V, 0.0, 0.0, 0.0, False
    row = int(q[Q_SCHEDULE_ROW])
    k1, k2 = _unscaled_gains(
        V,
        _interp(V, breaks, coefs, row, pieces, 0),
        _interp(V, breaks, coefs, row, pieces, 1),
    )
    return V, k1, k2, _interp(V, breaks, coefs, row, pieces, 2), True
