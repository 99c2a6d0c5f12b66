r"""Performance metrics of closed-loop time responses.

The functions take arrays with time on the **last** axis, so that a signal
of a batch :class:`~fws_control.SimulationResult` (from
:func:`~fws_control.simulate_batch`, shape ``(runs, time)``) gives one value
per run, and the signal of a single run (from :func:`~fws_control.simulate`
or ``result[i]``, shape ``(time,)``) gives a scalar.

Two kinds of metric:

* **Peaks**: :func:`peak_abs` of an array uses the samples that exist (a
  run that stopped early, NaN tail in a batch, reports its peak up to the
  stop; a run with no valid sample gives NaN). Given a
  :class:`~fws_control.SimulationResult` and a signal name it returns the
  exact peak of the continuous solution (``result.peaks``), which does not
  depend on the output grid; :func:`tracking_metrics` reports those.
* **Horizon metrics** (:func:`settling_time`, :func:`overshoot`,
  :func:`rms`, :func:`steady_state`) describe the whole simulated horizon;
  a run with missing samples gives NaN, so an incomplete run is never
  mistaken for a converged one.

:func:`tracking_metrics` collects all of them for a
:class:`~fws_control.SimulationResult` of one run or many, with the run
status alongside.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from .hints import RealArrayLike
from .reprs import import_pandas, summary_repr
from .validation import (
    check_bool,
    check_finite,
    check_positive,
    check_real,
    check_scalar,
)

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "peak_abs",
    "settling_time",
    "overshoot",
    "rms",
    "steady_state",
    "TrackingMetrics",
    "tracking_metrics",
    "HORIZON_METRICS",
]

#: The fields of :class:`TrackingMetrics` that need the whole time series of
#: ``e`` and ``theta`` (the others are peaks or the status). A result of
#: :func:`~fws_control.simulate_batch` that keeps neither (``signals=``) holds
#: them per run, in this order, in ``run_metrics``.
HORIZON_METRICS = (
    "settling_time",
    "overshoot",
    "rms_error",
    "steady_state_error",
    "steady_state_heading_error",
)
# the settings with which simulate_batch computes the stored ones
_DEFAULT_SETTINGS = {"band": None, "fraction": 0.02, "window": 1.0}


def _scalar(out):
    out = np.asarray(out, dtype=float)
    return float(out) if out.ndim == 0 else out


def _signal(signal) -> np.ndarray:
    """`signal` as a float array ``(..., time)``: real, NaN allowed, no inf.

    NaN samples are data (a stopped run is padded with NaN); an infinite
    sample is not.
    """
    x = check_real("signal", signal)
    if x.ndim == 0 or x.shape[-1] == 0:
        raise ValueError(
            f"signal must have at least one sample on its last (time) axis, got "
            f"shape {x.shape}"
        )
    if np.any(np.isinf(x)):
        raise ValueError("signal must hold finite samples or NaN, got +-inf")
    return x


def _overflow(out, x, what: str) -> None:
    # finite, NaN-free samples that give a non-finite metric: extreme values
    bad = ~np.isfinite(out) & ~np.any(np.isnan(x), axis=-1)
    if np.any(bad):
        raise ValueError(
            f"signal's magnitude (up to {np.nanmax(np.abs(x)):.3g}) overflows the "
            f"{what}: rescale the signal"
        )


def _time_and_signal(t, signal):
    t = check_finite("t", t)
    t = np.asarray(t, dtype=float)
    x = _signal(signal)
    if t.ndim != 1 or x.shape[-1:] != t.shape:
        raise ValueError(
            f"signal must have time on its last axis matching t (length {t.size}), "
            f"got shape {x.shape}"
        )
    if t.size < 2 or np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing with at least 2 samples")
    return t, x


def peak_abs(signal: RealArrayLike, *, name: str | None = None) -> float | np.ndarray:
    """Largest absolute value over time: of samples, or exact for a result.

    Parameters
    ----------
    signal : array_like or SimulationResult
        Samples of shape ``(..., time)`` (NaN samples ignored), or a
        simulation result, whose exact peak of the continuous solution
        (``result.peaks[name].value``) is returned.
    name : str, optional
        With a result: the signal, one of
        :data:`~fws_control.simulation.outcomes.PEAK_SIGNALS` (``"e"``,
        ``"delta_f"``, ``"delta_r"``, ``"delta_f_rate"``, ``"delta_r_rate"``,
        ``"lateral_accel"``).

    Returns
    -------
    float or ndarray
        Shape ``(...)`` (per run for a result); NaN where a run has no valid
        sample.

    Raises
    ------
    ValueError
        For a result without `name`, or a `name` with an array.

    Examples
    --------
    >>> from fws_control.metrics import peak_abs
    >>> peak_abs([0.5, -2.0, 1.0])
    2.0
    >>> peak_abs([[1.0, -3.0], [0.2, float("nan")]]).tolist()
    [3.0, 0.2]

    On a result the peak lies between the samples where the solution has it:

    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=0.0)
    >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                    initial_state=(0.0, 1.0, 0.0), duration=10.0, dt=1.0)
    >>> bool(peak_abs(res, name="delta_f_rate") > peak_abs(res.delta_f_rate))
    True
    """
    if hasattr(signal, "peaks") and hasattr(signal, "signals"):
        if name is None:
            raise ValueError(
                "name must name a signal (e.g. 'lateral_accel') when peak_abs is "
                "given a SimulationResult"
            )
        try:
            return signal.peaks[name].value
        except KeyError as exc:
            raise ValueError(str(exc.args[0])) from None
    if name is not None:
        raise ValueError(
            f"name={name!r} is only for a SimulationResult; got an array of samples"
        )
    x = np.abs(_signal(signal))
    valid = np.isfinite(x)
    out = np.max(np.where(valid, x, -np.inf), axis=-1)
    return _scalar(np.where(np.any(valid, axis=-1), out, np.nan))


def settling_time(
    t: RealArrayLike,
    signal: RealArrayLike,
    *,
    band: RealArrayLike | None = None,
    fraction: float = 0.02,
) -> float | np.ndarray:
    r"""Time after which ``|signal|`` stays within a band around zero.

    The last crossing of ``|signal| = band`` is located by linear
    interpolation between the samples around it.

    Parameters
    ----------
    t : array_like
        Sample times [s], shape ``(time,)``.
    signal : array_like
        Shape ``(..., time)``, converging to 0 (e.g. the lateral error).
    band : float or array_like, optional
        Half-width of the band, in the signal's units, finite and > 0;
        broadcasts with ``signal[..., 0]``. Default: ``fraction *
        |signal[..., 0]|``.
    fraction : float, optional
        Relative band used when `band` is not given (default 2 %).

    Returns
    -------
    float or ndarray
        Settling time [s]: 0 if the signal never leaves the band, ``inf`` if it
        is outside the band at the last sample, NaN if any sample is NaN.

    Raises
    ------
    ValueError
        If `band` is not finite and > 0 (NaN would read as "settled at
        once"), `fraction` is not finite and > 0, or `t` and `signal` do not
        fit.

    Examples
    --------
    >>> import math, numpy as np
    >>> from fws_control.metrics import settling_time
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> round(settling_time(t, np.exp(-t)), 3), round(math.log(50.0), 3)
    (3.912, 3.912)
    """
    ts, x = _time_and_signal(t, signal)
    mag = np.abs(x)
    share = check_positive("fraction", fraction)  # checked even if unused
    if band is None:
        level: Any = share * mag[..., 0]
    else:
        # NaN would compare False everywhere ("settled at once") and a
        # negative band can never be entered: both are refused, by name.
        level = check_positive("band", band)
    try:
        level = np.broadcast_to(np.asarray(level, dtype=float), mag.shape[:-1])
    except ValueError:
        raise ValueError(
            f"band must broadcast with signal[..., 0] of shape {mag.shape[:-1]}, "
            f"got shape {np.shape(level)}"
        ) from None
    outside = mag > level[..., None]
    T = ts.size
    # index of the last sample outside the band (-1: never outside)
    last = np.where(
        np.any(outside, axis=-1), T - 1 - np.argmax(outside[..., ::-1], -1), -1
    )
    out = np.zeros(mag.shape[:-1])
    inside_end = last < T - 1
    i = np.clip(last, 0, T - 2)
    m0 = np.take_along_axis(mag, i[..., None], -1)[..., 0]
    m1 = np.take_along_axis(mag, (i + 1)[..., None], -1)[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.clip((m0 - level) / (m0 - m1), 0.0, 1.0)
    crossing = ts[i] + frac * (ts[i + 1] - ts[i])
    out = np.where(last >= 0, crossing, 0.0)
    out = np.where(inside_end, out, np.inf)
    out = np.where(np.any(np.isnan(x), axis=-1), np.nan, out)
    return _scalar(out)


def overshoot(signal: RealArrayLike, *, relative: bool = False) -> float | np.ndarray:
    """Largest excursion past zero, on the side opposite to the start.

    For an error that starts at ``x0 != 0`` and should decay to zero, this is
    ``max(0, max(-sign(x0) * x))``.

    Parameters
    ----------
    signal : array_like
        Shape ``(..., time)``.
    relative : bool, optional
        Divide by ``|x0|`` (a fraction, not percent).

    Returns
    -------
    float or ndarray
        In the signal's units (or relative); NaN if any sample is NaN or
        ``x0 == 0``.

    Examples
    --------
    >>> import math, numpy as np
    >>> from fws_control.metrics import overshoot
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> round(overshoot((1 - t) * np.exp(-t)), 6), round(math.exp(-2.0), 6)
    (0.135335, 0.135335)
    """
    x = _signal(signal)
    relative = check_bool("relative", relative)
    x0 = x[..., 0]
    sign = np.sign(x0)
    out = np.maximum(np.max(-sign[..., None] * x, axis=-1), 0.0)
    if relative:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            out = out / np.abs(x0)
        _overflow(np.where(sign == 0, 0.0, out), x, "relative overshoot")
    out = np.where((sign == 0) | np.any(np.isnan(x), axis=-1), np.nan, out)
    return _scalar(out)


def rms(
    t: RealArrayLike, signal: RealArrayLike, *, t_start: float = 0.0
) -> float | np.ndarray:
    r"""Root mean square over time, :math:`\sqrt{\frac{1}{T}\int x^2\,dt}`.

    Trapezoidal rule over the samples with ``t >= t_start``.

    Parameters
    ----------
    t : array_like
        Sample times [s].
    signal : array_like
        Shape ``(..., time)``.
    t_start : float, optional
        Start of the averaging window [s].

    Returns
    -------
    float or ndarray
        NaN if any sample in the window is NaN.

    Examples
    --------
    >>> import math, numpy as np
    >>> from fws_control.metrics import rms
    >>> t = np.linspace(0.0, 2 * np.pi, 2001)
    >>> round(rms(t, np.sin(t)), 6), round(1 / math.sqrt(2), 6)
    (0.707107, 0.707107)
    """
    t, x = _time_and_signal(t, signal)
    t_start = check_scalar("t_start", t_start)
    with np.errstate(over="ignore"):
        out = np.sqrt(_time_average(t, x**2, t_start, "t_start"))
    _overflow(out, x, "rms")
    return _scalar(out)


def steady_state(
    t: RealArrayLike, signal: RealArrayLike, *, window: float = 1.0
) -> float | np.ndarray:
    """Time average of the signal over the last `window` seconds.

    Parameters
    ----------
    t : array_like
        Sample times [s].
    signal : array_like
        Shape ``(..., time)``.
    window : float, optional
        Length of the final averaging window [s], > 0.

    Returns
    -------
    float or ndarray
        NaN if any sample in the window is NaN.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.metrics import steady_state
    >>> t = np.linspace(0.0, 10.0, 1001)
    >>> round(steady_state(t, 0.3 + np.exp(-5 * t)), 9)
    0.3
    """
    ts, x = _time_and_signal(t, signal)
    window = check_scalar("window", check_positive("window", window))
    with np.errstate(over="ignore", invalid="ignore"):
        out = _time_average(ts, x, ts[-1] - window, "window")
    _overflow(out, x, "time average")
    return _scalar(out)


def _time_average(t, x, t_start, name):
    """Trapezoidal time average of `x` over ``t >= t_start`` (checked arrays)."""
    # tolerate rounding in t[-1] - window
    sel = t >= t_start - 1e-9 * max(1.0, abs(t_start))
    if np.count_nonzero(sel) < 2:
        raise ValueError(
            f"{name}: the averaging window from t={t_start!r} s must hold at least "
            f"2 samples of t in [{t[0]}, {t[-1]}] s"
        )
    ts, xs = t[sel], x[..., sel]
    return np.trapezoid(xs, ts, axis=-1) / (ts[-1] - ts[0])


@summary_repr
@dataclass(frozen=True)
class TrackingMetrics:
    """Metrics of one run (floats) or of a batch (arrays of shape ``(runs,)``).

    Returned by :func:`tracking_metrics`: floats for a squeezed
    :class:`~fws_control.SimulationResult` (from :func:`~fws_control.simulate`
    or ``result[i]``), arrays for a batch (from
    :func:`~fws_control.simulate_batch`).

    Attributes
    ----------
    peak_lateral_accel : float or ndarray
        Peak absolute lateral acceleration of G [m/s^2] over ``[0, t_stop]``:
        the exact maximum of the continuous solution (``result.peaks``), not
        of the output samples; ``inf`` where a run stopped at a singular
        state, where it diverges.
    settling_time : float or ndarray
        Settling time of the lateral error ``e`` [s] (see
        :func:`settling_time`); NaN for runs that stopped early.
    overshoot : float or ndarray
        Overshoot of ``e`` past zero [m].
    rms_error : float or ndarray
        RMS of ``e`` over the horizon [m].
    steady_state_error : float or ndarray
        Mean of ``e`` over the final window [m].
    steady_state_heading_error : float or ndarray
        Mean of ``theta`` over the final window [rad].
    peak_delta_f, peak_delta_r : float or ndarray
        Peak absolute steering angle [rad] (exact, up to the stop).
    peak_delta_f_rate, peak_delta_r_rate : float or ndarray
        Peak absolute steering rate [rad/s] (exact, up to the stop).
    peak_error : float or ndarray
        Peak absolute lateral error ``|e|`` [m] (exact, up to the stop).
    status : str or ndarray of str
        The run status; horizon metrics are NaN unless it is ``"ok"``.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=[0.1, -0.1], k2=0.5, ratio=0.0)
    >>> batch = fws.simulate_batch(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                            initial_state=(0.0, 1.0, 0.0), duration=10.0)
    >>> m = fws.tracking_metrics(batch)     # k1 < 0: e does not settle
    >>> m.status.tolist(), m.settling_time.round(2).tolist()
    (['ok', 'ok'], [8.54, inf])
    """

    peak_lateral_accel: float | np.ndarray
    settling_time: float | np.ndarray
    overshoot: float | np.ndarray
    rms_error: float | np.ndarray
    steady_state_error: float | np.ndarray
    steady_state_heading_error: float | np.ndarray
    peak_delta_f: float | np.ndarray
    peak_delta_r: float | np.ndarray
    peak_delta_f_rate: float | np.ndarray
    peak_delta_r_rate: float | np.ndarray
    status: str | np.ndarray
    peak_error: float | np.ndarray = np.nan

    def to_pandas(self) -> pd.DataFrame:
        """A :class:`pandas.DataFrame` with one row per run.

        Columns: ``run`` and every metric (the attributes above, in SI units
        and radians); one row for the metrics of a single run.

        Returns
        -------
        pandas.DataFrame

        Raises
        ------
        ImportError
            If pandas is not installed (extra ``fws-control[pandas]``).

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> g = fws.SteeringGains(k1=[0.1, 0.2], k2=0.5, ratio=0.0)
        >>> plant = fws.LateralPlant(veh, speed=5.0)
        >>> batch = fws.simulate_batch(plant, fws.Straight(), g,
        ...                            initial_state=(0.0, 1.0, 0.0),
        ...                            duration=10.0, signals="metrics")
        >>> df = fws.tracking_metrics(batch).to_pandas()
        >>> df[["run", "settling_time", "status"]].round(2)
           run  settling_time status
        0    0           8.54     ok
        1    1           8.13     ok
        """
        pd = import_pandas()
        columns = {
            name: np.atleast_1d(np.asarray(getattr(self, name)))
            for name in self.__dataclass_fields__
        }
        n = max(v.size for v in columns.values())
        data: dict[str, Any] = {"run": np.arange(n)}
        data.update({k: np.broadcast_to(v, (n,)) for k, v in columns.items()})
        return pd.DataFrame(data)


class _Result(Protocol):
    # What tracking_metrics reads of a fws_control.SimulationResult. A
    # protocol rather than the class: the simulation package imports this
    # module (for the batch's horizon metrics), so importing it back, even
    # for an annotation, would make an import cycle.
    # (read-only attributes; optional ones, read with getattr:
    # signal_names, run_metrics)
    @property
    def t(self) -> Any: ...

    @property
    def status(self) -> Any: ...

    @property
    def e(self) -> Any: ...

    @property
    def theta(self) -> Any: ...

    @property
    def peaks(self) -> Any: ...


def tracking_metrics(
    result: _Result,
    *,
    band: RealArrayLike | None = None,
    fraction: float = 0.02,
    window: float = 1.0,
) -> TrackingMetrics:
    """All metrics of a :class:`~fws_control.SimulationResult`.

    Parameters
    ----------
    result : SimulationResult
        One run (squeezed: from :func:`~fws_control.simulate` or
        ``result[i]``) or a batch (from :func:`~fws_control.simulate_batch`).
        A batch that kept only some signals (``signals=``) without ``e`` or
        ``theta`` gives the horizon metrics it computed before dropping them
        (:data:`HORIZON_METRICS`, with the default `band`, `fraction` and
        `window`; other settings raise :class:`ValueError` then).
    band, fraction
        Settling band of the lateral error, see :func:`settling_time`.
    window : float, optional
        Final window [s] of the steady-state averages.

    Returns
    -------
    TrackingMetrics
        Floats for a squeezed result, arrays of shape ``(runs,)`` for a
        batch (whatever its number of runs).
        Horizon metrics are NaN for runs whose status is not ``"ok"``.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.paths import Arc
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0,
    ...                           pole=-1.0)
    >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), Arc(curvature=0.1), g,
    ...                    initial_state=(0.0, -5.0, 0.0), duration=15.0)
    >>> m = fws.tracking_metrics(res)
    >>> m.status, round(m.peak_lateral_accel, 2), round(m.settling_time, 2)
    ('ok', 5.37, 6.23)
    """
    # (peaks looked up on the type: on a result without stored peaks the
    # property computes them from the samples)
    if not (
        all(hasattr(result, n) for n in ("t", "status", "signals"))
        and hasattr(type(result), "peaks")
    ):
        raise TypeError(
            "result must be a fws_control.SimulationResult, got "
            f"{type(result).__name__}"
        )
    if band is not None:
        band = check_positive("band", band)
    check_positive("fraction", fraction)
    check_positive("window", window)
    t = np.asarray(result.t, dtype=float)
    status = np.asarray(result.status)
    ok = status == "ok"

    def horizon(values):
        return _scalar(np.where(ok, values, np.nan))

    kept = getattr(result, "signal_names", ("e", "theta"))
    if "e" in kept and "theta" in kept:
        e = np.asarray(result.e, dtype=float)
        theta = np.asarray(result.theta, dtype=float)
        if t.size >= 2:
            settle = horizon(settling_time(t, e, band=band, fraction=fraction))
            ovs = horizon(overshoot(e))
            rms_e = horizon(rms(t, e))
            ss_e = horizon(steady_state(t, e, window=window))
            ss_th = horizon(steady_state(t, theta, window=window))
        else:  # a run that stopped at t = 0
            settle = ovs = rms_e = ss_e = ss_th = np.nan
    else:
        settle, ovs, rms_e, ss_e, ss_th = _stored_horizon(
            result, kept, band=band, fraction=fraction, window=window
        )
    peaks = result.peaks
    return TrackingMetrics(
        peak_lateral_accel=peaks.lateral_accel.value,
        settling_time=settle,
        overshoot=ovs,
        rms_error=rms_e,
        steady_state_error=ss_e,
        steady_state_heading_error=ss_th,
        peak_delta_f=peaks.delta_f.value,
        peak_delta_r=peaks.delta_r.value,
        peak_delta_f_rate=peaks.delta_f_rate.value,
        peak_delta_r_rate=peaks.delta_r_rate.value,
        status=status.item() if status.ndim == 0 else status,
        peak_error=peaks.e.value,
    )


def _stored_horizon(result, kept, *, band, fraction, window):
    """The horizon metrics a result without ``e`` or ``theta`` stores."""
    missing = [name for name in ("e", "theta") if name not in kept]
    stored = getattr(result, "run_metrics", None)
    if stored is None:
        raise ValueError(
            f"result holds no {' and no '.join(missing)} (kept signals: "
            f"{tuple(kept)}) and no stored metrics: simulate with signals= "
            "including 'e' and 'theta', or signals='metrics'"
        )
    if (
        band is not None
        or np.any(np.asarray(fraction) != _DEFAULT_SETTINGS["fraction"])
        or np.any(np.asarray(window) != _DEFAULT_SETTINGS["window"])
    ):
        raise ValueError(
            f"band, fraction, window = {band!r}, {fraction!r}, {window!r}: the "
            f"result holds no {' and no '.join(missing)} (signals={tuple(kept)}), "
            "only the metrics simulate_batch computed with the defaults "
            f"{_DEFAULT_SETTINGS}; keep signals=('e', 'theta') for other settings"
        )
    stored = np.asarray(stored, dtype=float)
    if np.ndim(result.status) == 0:  # squeezed: one run
        return tuple(float(v) for v in stored[0])
    return tuple(stored[:, j].copy() for j in range(stored.shape[1]))
