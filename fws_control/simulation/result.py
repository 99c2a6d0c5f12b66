r"""The result of a closed-loop simulation: one type for one run or many.

:class:`SimulationResult` holds a run axis, as
:class:`control.TimeResponseData` holds one trace or many: every signal is
stored as an array of shape ``(runs, time)`` on a common time grid, with NaN
after a run's stop. :func:`~fws_control.simulation.simulate` returns a batch
of one run; :func:`~fws_control.simulation.simulate_batch` a batch of any
size.

**Squeeze rule.** A result is *squeezed* (``result.squeeze`` is True) when it
comes from :func:`~fws_control.simulation.simulate` or from indexing a run,
``result[i]``; a result from :func:`~fws_control.simulation.simulate_batch`
is never squeezed, whatever its number of runs (so code written for a batch
does not change shape when a sweep happens to hold one run). A squeezed
result holds exactly one run, its time grid ends at the run's last sample
(no NaN tail), and every per-run attribute drops the run axis:

================================  ==========================  ======================
attribute                         squeezed (one run)          not squeezed
================================  ==========================  ======================
``t``                             ``(time,)``                 ``(time,)``
``x, y, ..., lateral_accel``      ``(time,)``                 ``(runs, time)``
``status``                        ``str``                     ndarray of str
``message``                       ``str``                     tuple of str
``t_stop, speed, k1, k2, ratio``  ``float``                   ndarray ``(runs,)``
``initial_state``                 ``(3,)``                    ``(runs, 3)``
``ok``, ``singular``              ``bool``                    ndarray of bool
``gains``                         SteeringGains of floats     SteeringGains of arrays
================================  ==========================  ======================

The stored fields (:attr:`~SimulationResult.signals` and the ``run_*``
fields) always keep the run axis.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Literal, cast, overload

import numpy as np

from ..dynamics import GRAVITY
from ..exceptions import SignalNotKeptError
from ..gains import SteeringGains
from ..metrics import HORIZON_METRICS
from ..paths import Path
from ..reprs import brief, html_table, import_pandas
from ..vehicle import Vehicle
from .options import MODELS
from .outcomes import (
    PEAK_SIGNALS,
    SIGNALS,
    STATUS_OK,
    STATUS_SINGULAR_CURVATURE,
    STATUS_SINGULAR_STEERING,
    STATUS_UNCONTROLLABLE,
)

if TYPE_CHECKING:
    # python-control costs 0.7 s to import; a result needs it only for
    # to_time_response and plot, which import it
    import control as ct
    import pandas as pd

__all__ = ["Peak", "Peaks", "SimulationResult", "expand_runs"]

_DEG = 180.0 / math.pi


class _Signal:
    """Read-only attribute giving one signal of :data:`SIGNALS`, squeezed."""

    def __init__(self, doc: str) -> None:
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name: str = name
        self.index: int = SIGNALS.index(name)

    @overload
    def __get__(self, obj: None, objtype: type | None = None) -> _Signal: ...
    @overload
    def __get__(
        self, obj: SimulationResult, objtype: type | None = None
    ) -> np.ndarray: ...
    def __get__(
        self, obj: SimulationResult | None, objtype: type | None = None
    ) -> _Signal | np.ndarray:
        if obj is None:
            return self
        return obj.signal(self.name)


def _not_kept(
    name: str, kept: tuple[str, ...], what: str | None = None
) -> SignalNotKeptError:
    held = f"only {', '.join(kept)}" if kept else "no time series ('metrics')"
    need = f" ({what} needs it)" if what else ""
    return SignalNotKeptError(
        f"signal {name!r} was not kept{need}: simulate_batch ran with "
        f"signals= keeping {held}; run it with signals=None (all) or with "
        f"{name!r} among them"
    )


@dataclass(frozen=True)
class Peak:
    """Peak of ``|signal|`` of one signal: its value and when it occurs.

    Floats for one run (a squeezed result), arrays ``(runs,)`` for a batch.
    """

    value: float | np.ndarray
    time: float | np.ndarray


@dataclass(frozen=True, repr=False)
class Peaks:
    r"""Peaks ``max |signal|`` of a result's runs, one :class:`Peak` per signal.

    With ``exact=True`` (every result of the runners, either engine) they
    are the maxima of the continuous solution over each run's integrated
    interval ``[0, t_stop]``, located on the solver's dense output (see
    :func:`~fws_control.simulation.peaks.exact_peaks` and
    :func:`~fws_control.simulation.compiled.compiled_peaks`): they do not
    depend on the output grid. ``exact=False`` (a result built from samples
    only) marks the maxima of the output samples. A
    rate or the lateral acceleration of a run stopped at a singular state
    diverges there: its exact peak is ``inf``.

    Attributes
    ----------
    e, delta_f, delta_r, delta_f_rate, delta_r_rate, lateral_accel : Peak
        Value [m, rad, rad/s or m/s^2] and time [s] per run.
    exact : bool
        Maxima of the continuous solution (True) or of the samples (False).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=0.0)
    >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                    initial_state=(0.0, 1.0, 0.0), duration=10.0, dt=1.0)
    >>> p = res.peaks
    >>> p.exact, round(p.e.value, 6), p.e.time     # |e| is largest at the start
    (True, 1.0, 0.0)
    >>> p["delta_f_rate"].time > 0.0               # between the 1 s samples
    True
    """

    e: Peak
    delta_f: Peak
    delta_r: Peak
    delta_f_rate: Peak
    delta_r_rate: Peak
    lateral_accel: Peak
    exact: bool = True

    def __getitem__(self, name: str) -> Peak:
        if name not in PEAK_SIGNALS:
            raise KeyError(f"no peak of {name!r}; peaks exist for {PEAK_SIGNALS}")
        return getattr(self, name)

    def __repr__(self) -> str:
        parts = []
        for name in PEAK_SIGNALS:
            v = np.asarray(self[name].value)
            parts.append(
                f"{name}={float(v):.4g}" if v.ndim == 0 else f"{name}=<{v.size} runs>"
            )
        return f"Peaks({', '.join(parts)}, exact={self.exact})"

    def _repr_html_(self) -> str:
        rows = [
            (name, f"{brief(self[name].value)} at t = {brief(self[name].time)} s")
            for name in PEAK_SIGNALS
        ]
        return html_table(f"Peaks (exact={self.exact})", rows)


@dataclass(frozen=True, eq=False, repr=False)
class SimulationResult:
    r"""Time responses of one or more closed-loop runs.

    Built by :func:`~fws_control.simulation.simulate` (one run, squeezed) and
    :func:`~fws_control.simulation.simulate_batch` (any number of runs, not
    squeezed); see the module documentation for the squeeze rule.
    ``len(result)`` is the number of runs, ``result[i]`` the run ``i`` as a
    squeezed result holding its data up to its stop, ``result[i:j]`` (or an
    index array or boolean mask) a batch of the selected runs, and iterating
    gives the runs one by one.

    Parameters
    ----------
    t : ndarray
        Output times [s], shape ``(time,)``.
    signals : ndarray
        The kept signals, shape ``(runs, len(signal_names), time)`` in the
        order of `signal_names` (by default all of
        :data:`~fws_control.simulation.SIGNALS`); NaN after a run's stop.
    run_status : ndarray of str
        Per run ``"ok"`` or why it stopped: ``"singular_steering"``,
        ``"singular_curvature"``, ``"end_of_path"``, ``"failed"`` or
        ``"uncontrollable"`` (no design, not simulated: NaN signals).
    run_message : tuple of str
        Per run explanation ("" for ``"ok"``).
    run_t_stop : ndarray
        Per run end time [s]; NaN for runs that were not simulated.
    run_speed : ndarray
        Per run speed :math:`V` [m/s].
    run_k1, run_k2, run_ratio : ndarray
        Per run gains; ``k1, k2`` are NaN for a design that does not exist.
    run_initial_state : ndarray
        Per run ``(x_R, y_R, psi)``, shape ``(runs, 3)``.
    feedforward : bool or "dynamic", optional
        Whether the curvature feedforward was used (all runs): True (eq. 26),
        False, or ``"dynamic"`` (:func:`~fws_control.dynamics.dynamic_feedforward`).
    squeeze : bool, optional
        Drop the run axis from every per-run attribute; only for one run.
    vehicle : Vehicle, optional
        The simulated vehicle.
    path : Path, optional
        The reference path; :meth:`plot` draws it.
    run_peak, run_peak_time : ndarray, optional
        Per run and signal of
        :data:`~fws_control.simulation.outcomes.PEAK_SIGNALS`, shape
        ``(runs, len(PEAK_SIGNALS))``: the exact peaks ``max |signal|`` of
        the continuous solution and their times (see :attr:`peaks`). None
        (both): :attr:`peaks` falls back to the samples, marked
        ``exact=False``.
    method : str, optional
        The solver that integrated the runs (what ``method="auto"`` chose:
        ``"DOP853"`` or, for a stiff actuator, ``"Radau"`` or ``"LSODA"``); None
        if unknown.
    model : str, optional
        The vehicle model simulated, ``"kinematic"`` (default) or
        ``"dynamic"`` (:data:`~fws_control.simulation.options.MODELS`).
    tyre : str, optional
        Its tyre model, ``"linear"`` (default) or ``"magic"``.
    engine : str, optional
        The engine that integrated the runs: ``"numpy"`` (default) or
        ``"compiled"`` (see :func:`~fws_control.simulate`).
    signal_names : tuple of str, optional
        The signals `signals` holds, a subset of
        :data:`~fws_control.simulation.SIGNALS` in its order (default: all;
        ``()`` for ``simulate_batch(..., signals="metrics")``). Reading
        another one raises :class:`~fws_control.SignalNotKeptError`.
    run_samples : ndarray of int, optional
        Per run, the number of output samples up to its stop (the samples
        after it are NaN). Default: counted from the signal ``s``, which
        must then be kept.
    run_metrics : ndarray, optional
        Per run, the metrics of :data:`~fws_control.metrics.HORIZON_METRICS`
        computed by :func:`~fws_control.simulate_batch` (with the default
        settings of :func:`~fws_control.tracking_metrics`) before it dropped
        ``e`` or ``theta``, shape ``(runs, len(HORIZON_METRICS))``; None
        when the result keeps both.
    peaks_exact : bool, optional
        Whether `run_peak` holds the peaks of the continuous solution
        (default, every result of the runners) or of the output samples.
    speed_profile : SpeedProfile, optional
        The speed that varied along the runs (None: the constant
        ``run_speed``); :attr:`longitudinal_speed` and
        :attr:`longitudinal_accel` read it.

    Attributes
    ----------
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
        Lateral acceleration of the centre of gravity G along the vehicle's
        lateral axis [m/s^2]: eq. (13) for the kinematic model,
        :math:`\dot v_y + u r` for the dynamic one.
    v_y, yaw_rate : ndarray
        Lateral velocity of G in the vehicle's frame [m/s] and yaw rate
        [rad/s] (kinematic model: :math:`V\sin\delta_r + l_r\dot\psi` and
        eq. (10)).
    slip_front, slip_rear : ndarray
        Slip angles of the front and rear axle [rad] (dynamic model; 0 for
        the kinematic one).
    status, message, t_stop, speed, k1, k2, ratio, initial_state
        The ``run_*`` fields, squeezed (see the module documentation).
    gains : SteeringGains or None
        The per-run gains; None if a run has no design (its ``k1``, ``k2``
        are NaN, which a SteeringGains cannot hold).
    ok : bool or ndarray of bool
        The run reached the final time.
    runs : list of SimulationResult
        Every run, squeezed.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=20.0, ratio=np.array([-1.0, 0.0]),
    ...                           pole=-1.0)
    >>> batch = fws.simulate_batch(fws.LateralPlant(veh, speed=20.0), fws.Straight(), g,
    ...                            initial_state=(0.0, 2.0, 0.0), duration=5.0,
    ...                            feedforward=False)
    >>> len(batch), batch.e.shape, batch.status.tolist()
    (2, (2, 501), ['ok', 'ok'])
    >>> run = batch[1]                    # one run: squeezed
    >>> run.e.shape, run.status, run.ratio
    ((501,), 'ok', 0.0)
    """

    t: np.ndarray
    signals: np.ndarray
    run_status: np.ndarray
    run_message: tuple[str, ...]
    run_t_stop: np.ndarray
    run_speed: np.ndarray
    run_k1: np.ndarray
    run_k2: np.ndarray
    run_ratio: np.ndarray
    run_initial_state: np.ndarray
    feedforward: bool | Literal["dynamic"] = True
    squeeze: bool = False
    vehicle: Vehicle | None = None
    path: Path | None = None
    run_peak: np.ndarray | None = None
    run_peak_time: np.ndarray | None = None
    method: str | None = None
    model: str = "kinematic"
    tyre: str = "linear"
    engine: str = "numpy"
    signal_names: tuple[str, ...] = SIGNALS
    run_samples: np.ndarray | None = None
    run_metrics: np.ndarray | None = None
    peaks_exact: bool = True
    speed_profile: Any = None

    x: ClassVar[_Signal] = _Signal("Global x of the rear-axle centre R [m].")
    y: ClassVar[_Signal] = _Signal("Global y of the rear-axle centre R [m].")
    psi: ClassVar[_Signal] = _Signal("Heading [rad], continuous in time from psi(0).")
    s: ClassVar[_Signal] = _Signal("Arclength of the projection point on the path [m].")
    e: ClassVar[_Signal] = _Signal("Lateral error [m], positive left of the path.")
    theta: ClassVar[_Signal] = _Signal("Heading error theta = psi - psi_C [rad].")
    delta_f: ClassVar[_Signal] = _Signal("Front steering angle on the vehicle [rad].")
    delta_r: ClassVar[_Signal] = _Signal("Rear steering angle on the vehicle [rad].")
    delta_f_rate: ClassVar[_Signal] = _Signal("Front steering rate [rad/s].")
    delta_r_rate: ClassVar[_Signal] = _Signal("Rear steering rate [rad/s].")
    lateral_accel: ClassVar[_Signal] = _Signal(
        "Lateral acceleration of G along the vehicle's lateral axis [m/s^2] "
        "(eq. (13) for the kinematic model, dv_y/dt + u r for the dynamic one)."
    )
    v_y: ClassVar[_Signal] = _Signal("Lateral velocity of G, vehicle frame [m/s].")
    yaw_rate: ClassVar[_Signal] = _Signal("Yaw rate [rad/s].")
    slip_front: ClassVar[_Signal] = _Signal("Front slip angle [rad] (0: kinematic).")
    slip_rear: ClassVar[_Signal] = _Signal("Rear slip angle [rad] (0: kinematic).")

    def __post_init__(self) -> None:
        t = np.asarray(self.t, dtype=float)
        sig = np.asarray(self.signals, dtype=float)
        names = tuple(self.signal_names)
        if names != SIGNALS and (
            any(not isinstance(k, str) for k in names)
            or names != tuple(k for k in SIGNALS if k in names)
        ):
            raise ValueError(
                f"signal_names must be distinct names of SIGNALS in its order "
                f"{SIGNALS}, got {names!r}"
            )
        if t.ndim != 1 or sig.ndim != 3 or sig.shape[1:] != (len(names), t.size):
            raise ValueError(
                f"signals must have shape (runs, {len(names)}, {t.size}) for "
                f"t of shape {t.shape} and {len(names)} signal_names, got "
                f"{sig.shape}"
            )
        n = sig.shape[0]
        if self.run_samples is None:
            if "s" not in names:
                raise ValueError(
                    "run_samples must be given when signal 's' is not kept "
                    f"(signal_names={names!r})"
                )
            count = np.count_nonzero(np.isfinite(sig[:, names.index("s"), :]), axis=1)
        else:
            count = np.array(self.run_samples)
            if (
                count.shape != (n,)
                or not np.issubdtype(count.dtype, np.integer)
                or np.any((count < 0) | (count > t.size))
            ):
                raise ValueError(
                    f"run_samples must hold one integer in [0, {t.size}] per run, "
                    f"shape ({n},), got {self.run_samples!r}"
                )
        if self.run_metrics is not None:
            metrics = np.array(self.run_metrics, dtype=float)
            if metrics.shape != (n, len(HORIZON_METRICS)):
                raise ValueError(
                    f"run_metrics must have shape ({n}, {len(HORIZON_METRICS)}) "
                    f"(runs, HORIZON_METRICS), got {metrics.shape}"
                )
            object.__setattr__(self, "run_metrics", metrics)
        # Small per-run arrays are copied (they may be broadcast views).
        per_run = {
            "run_status": np.array(self.run_status, dtype=str),
            "run_t_stop": np.array(self.run_t_stop, dtype=float),
            "run_speed": np.array(self.run_speed, dtype=float),
            "run_k1": np.array(self.run_k1, dtype=float),
            "run_k2": np.array(self.run_k2, dtype=float),
            "run_ratio": np.array(self.run_ratio, dtype=float),
        }
        for name, value in per_run.items():
            if value.shape != (n,):
                raise ValueError(
                    f"{name} must have one entry per run, shape ({n},), got "
                    f"{value.shape}"
                )
        x0 = np.array(self.run_initial_state, dtype=float)
        if x0.shape != (n, 3):
            raise ValueError(
                f"run_initial_state must have shape ({n}, 3), got {x0.shape}"
            )
        message = tuple(str(m) for m in self.run_message)
        if len(message) != n:
            raise ValueError(
                f"run_message must hold one str per run ({n}), got {len(message)}"
            )
        if self.model not in MODELS or self.tyre not in ("linear", "magic"):
            raise ValueError(
                f"model must be one of {MODELS} and tyre 'linear' or 'magic', "
                f"got {self.model!r}, {self.tyre!r}"
            )
        if self.engine not in ("numpy", "compiled"):
            raise ValueError(
                f"engine must be 'numpy' or 'compiled', got {self.engine!r}"
            )
        if self.squeeze and n != 1:
            raise ValueError(f"squeeze=True needs exactly one run, got {n}")
        if (self.run_peak is None) != (self.run_peak_time is None):
            raise ValueError("run_peak and run_peak_time must be given together")
        if self.run_peak is not None:
            for name in ("run_peak", "run_peak_time"):
                value = np.array(getattr(self, name), dtype=float)
                if value.shape != (n, len(PEAK_SIGNALS)):
                    raise ValueError(
                        f"{name} must have shape ({n}, {len(PEAK_SIGNALS)}) "
                        f"(runs, PEAK_SIGNALS), got {value.shape}"
                    )
                object.__setattr__(self, name, value)
        for name, value in (
            ("t", t),
            ("signals", sig),
            ("run_initial_state", x0),
            ("run_message", message),
            (
                "feedforward",
                "dynamic" if self.feedforward == "dynamic" else bool(self.feedforward),
            ),
            ("squeeze", bool(self.squeeze)),
            ("signal_names", names),
            ("run_samples", count.astype(np.int64)),
            ("peaks_exact", bool(self.peaks_exact)),
            ("method", None if self.method is None else str(self.method)),
            *per_run.items(),
        ):
            object.__setattr__(self, name, value)

    # ------------------------------------------------------------------
    # Runs

    def __len__(self) -> int:
        return int(self.signals.shape[0])

    def __iter__(self) -> Iterator[SimulationResult]:
        return (self[i] for i in range(len(self)))

    def __getitem__(self, index: Any) -> SimulationResult:
        """Run `index` (an int) squeezed, or a batch of the selected runs."""
        n = len(self)
        if isinstance(index, (int, np.integer)) and not isinstance(index, bool):
            if not -n <= index < n:
                raise IndexError(f"run index {index} out of range for {n} runs")
            i = int(index) % n
            # Keep the samples up to the stop.
            return self._select([i], int(self._samples[i]), squeeze=True)
        if isinstance(index, slice):
            return self._select(np.arange(n)[index], self.t.size, squeeze=False)
        idx = np.asarray(index)
        if idx.dtype == bool:
            if idx.shape != (n,):
                raise IndexError(
                    f"a boolean run mask must have shape ({n},), got {idx.shape}"
                )
            idx = np.flatnonzero(idx)
        elif idx.ndim != 1 or not np.issubdtype(idx.dtype, np.integer):
            raise TypeError(
                "run index must be an int, a slice, an integer array or a boolean "
                f"mask, got {index!r}"
            )
        if idx.size and not (np.all(idx < n) and np.all(idx >= -n)):
            raise IndexError(f"run indices {idx.tolist()} out of range for {n} runs")
        return self._select(idx % n if n else idx, self.t.size, squeeze=False)

    def _select(self, idx, count: int, *, squeeze: bool) -> SimulationResult:
        times = self.run_peak_time
        idx = np.asarray(idx, dtype=int)
        return SimulationResult(
            t=self.t[:count].copy(),
            signals=self.signals[idx, :, :count].copy(),
            run_status=self.run_status[idx],
            run_message=tuple(self.run_message[i] for i in idx),
            run_t_stop=self.run_t_stop[idx],
            run_speed=self.run_speed[idx],
            run_k1=self.run_k1[idx],
            run_k2=self.run_k2[idx],
            run_ratio=self.run_ratio[idx],
            run_initial_state=self.run_initial_state[idx],
            feedforward=self.feedforward,
            squeeze=squeeze,
            vehicle=self.vehicle,
            path=self.path,
            run_peak=None if self.run_peak is None else self.run_peak[idx],
            run_peak_time=None if times is None else times[idx],
            method=self.method,
            model=self.model,
            tyre=self.tyre,
            engine=self.engine,
            signal_names=self.signal_names,
            run_samples=np.minimum(self._samples[idx], count),
            run_metrics=None if self.run_metrics is None else self.run_metrics[idx],
            peaks_exact=self.peaks_exact,
            speed_profile=self.speed_profile,
        )

    def signal(self, name: str) -> np.ndarray:
        """The time series `name` of :data:`SIGNALS`, squeezed like ``result.e``.

        Parameters
        ----------
        name : str
            One of :data:`~fws_control.simulation.SIGNALS`.

        Returns
        -------
        ndarray
            Shape ``(time,)`` for a squeezed result, ``(runs, time)``
            otherwise (a view of :attr:`signals`).

        Raises
        ------
        ValueError
            For a name that is not a signal.
        SignalNotKeptError
            For a signal the simulation did not keep (``signals=`` of
            :func:`~fws_control.simulate_batch`).

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> res = fws.simulate_batch(fws.LateralPlant(veh, speed=5.0), fws.Straight(),
        ...                          fws.SteeringGains(0.1, 0.5, 0.0),
        ...                          initial_state=(0.0, 1.0, 0.0), duration=1.0,
        ...                          signals=("e", "delta_f"))
        >>> res.signal_names, res.signal("e").shape
        (('e', 'delta_f'), (1, 101))
        >>> res.signal("x")
        Traceback (most recent call last):
        ...
        fws_control.exceptions.SignalNotKeptError: signal 'x' was not kept: ...
        """
        if not isinstance(name, str) or name not in SIGNALS:
            raise ValueError(f"name must be one of {SIGNALS}, got {name!r}")
        if name not in self.signal_names:
            raise _not_kept(name, self.signal_names)
        values = self.signals[:, self.signal_names.index(name), :]
        return values[0] if self.squeeze else values

    def _require(self, names: Any, what: str) -> None:
        """Raise SignalNotKeptError if a signal `what` needs was not kept."""
        for name in names:
            if name not in self.signal_names:
                raise _not_kept(name, self.signal_names, what)

    @property
    def _samples(self) -> np.ndarray:
        # run_samples after __post_init__: always an array of sample counts
        return cast(np.ndarray, self.run_samples)

    @property
    def peaks(self) -> Peaks:
        """Peaks ``max |signal|`` per run, with their times (:class:`Peaks`).

        Exact maxima of the continuous solution for every result of the
        runners (either engine); a result built without them
        (``run_peak=None``) gives the maxima of its samples, marked
        ``exact=False``.
        """
        if self.run_peak is not None:
            values, times = self.run_peak, cast(np.ndarray, self.run_peak_time)
            exact = self.peaks_exact
        else:
            self._require(PEAK_SIGNALS, "peaks from the samples")
            rows = [self.signal_names.index(name) for name in PEAK_SIGNALS]
            x = np.abs(self.signals[:, rows, :])
            valid = np.isfinite(x)
            filled = np.where(valid, x, -np.inf)
            k = np.argmax(filled, axis=2)
            values = np.where(np.any(valid, axis=2), np.max(filled, axis=2), np.nan)
            times = np.where(np.any(valid, axis=2), self.t[k], np.nan)
            exact = False
        fields = {
            name: Peak(
                self._per_run(values[:, j], float), self._per_run(times[:, j], float)
            )
            for j, name in enumerate(PEAK_SIGNALS)
        }
        return Peaks(**fields, exact=exact)

    @property
    def runs(self) -> list[SimulationResult]:
        """Every run as a squeezed result (data up to its stop)."""
        return list(self)

    def __repr__(self) -> str:
        counts: dict[str, int] = {}
        for s in self.run_status.tolist():
            counts[s] = counts.get(s, 0) + 1
        span = f"[{self.t[0]:g}, {self.t[-1]:g}] s" if self.t.size else "[]"
        kept = "" if self.signal_names == SIGNALS else f"signals={self.signal_names}, "
        return (
            f"SimulationResult(runs={len(self)}, samples={self.t.size} over {span}, "
            f"{kept}status={counts}, squeeze={self.squeeze})"
        )

    def _repr_html_(self) -> str:
        counts: dict[str, int] = {}
        for s in self.run_status.tolist():
            counts[s] = counts.get(s, 0) + 1
        span = f"[{self.t[0]:g}, {self.t[-1]:g}] s" if self.t.size else "[]"
        rows = [
            ("runs", str(len(self))),
            ("samples", f"{self.t.size} over {span}"),
            ("status", ", ".join(f"{k}: {v}" for k, v in counts.items())),
            ("speed [m/s]", brief(self.speed)),
            ("ratio a", brief(self.ratio)),
            ("feedforward", str(self.feedforward)),
            (
                "model",
                self.model
                if self.model == "kinematic"
                else f"{self.model} ({self.tyre} tyres)",
            ),
            ("signals", ", ".join(self.signal_names) or "none (metrics only)"),
        ]
        return html_table("SimulationResult", rows)

    # ------------------------------------------------------------------
    # Per-run attributes (squeezed)

    def _per_run(self, values: np.ndarray, kind: type) -> Any:
        return kind(values[0]) if self.squeeze else values

    @property
    def status(self) -> str | np.ndarray:
        """``"ok"`` or why the run stopped (see ``run_status``)."""
        return self._per_run(self.run_status, str)

    @property
    def message(self) -> str | tuple[str, ...]:
        """Why the run stopped ("" for ``"ok"``)."""
        return self.run_message[0] if self.squeeze else self.run_message

    @property
    def t_stop(self) -> float | np.ndarray:
        """Time at which the run ended [s] (the final time for ``"ok"``)."""
        return self._per_run(self.run_t_stop, float)

    @property
    def speed(self) -> float | np.ndarray:
        """Speed :math:`V` [m/s] (with a varying speed: at the start; see
        :attr:`longitudinal_speed`)."""
        return self._per_run(self.run_speed, float)

    # ------------------------------------------------------------------
    # Longitudinal motion (a constant speed or a SpeedProfile)

    def _squeezed(self, values: np.ndarray) -> np.ndarray:
        return values[0] if self.squeeze else values

    def _path_speed(self, what: str) -> np.ndarray:
        """``ds/dt`` of the runs ``(runs, time)`` from the kept signals."""
        need = ["s", "e", "theta"]
        need += ["v_y", "yaw_rate"] if self.model == "dynamic" else ["delta_r"]
        self._require(need, what)
        if self.path is None or self.vehicle is None:
            raise ValueError(f"{what} needs the result's path and vehicle, got None")
        sig = {k: self.signals[:, self.signal_names.index(k), :] for k in need}
        V = self._speed_values(sig["s"])
        with np.errstate(invalid="ignore"):
            s = np.where(np.isfinite(sig["s"]), sig["s"], 0.0)
            length = getattr(self.path, "length", math.inf)
            if math.isfinite(length) and not self.path.closed:
                s = np.clip(s, 0.0, length)
            kappa = np.asarray(self.path.curvature(s), dtype=float)
            kappa = np.broadcast_to(kappa, s.shape)
            th = sig["theta"]
            if self.model == "dynamic":
                v_r = sig["v_y"] - self.vehicle.rear_to_cg * sig["yaw_rate"]
                along = V * np.cos(th) - v_r * np.sin(th)
            else:
                along = V * np.cos(th + sig["delta_r"])
            return along / (1.0 - kappa * sig["e"])

    def _speed_values(self, s: np.ndarray) -> np.ndarray:
        """The speed ``(runs, time)`` at the samples (NaN after a stop)."""
        prof = self.speed_profile
        if prof is None:
            V = np.broadcast_to(self.run_speed[:, None], s.shape).astype(float)
        elif prof.of == "time":
            V = np.broadcast_to(prof(self.t), s.shape).astype(float)
        else:
            V = prof(np.where(np.isfinite(s), s, 0.0))
        return np.where(np.isfinite(s), V, np.nan)

    @property
    def longitudinal_speed(self) -> np.ndarray:
        r"""Speed :math:`V(t)` of the run at the output times [m/s].

        The constant speed, or the :class:`~fws_control.SpeedProfile`'s at
        each sample (of the time, or of the arc length ``s``); NaN after a
        run's stop. Squeezed like ``result.e``.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> res = fws.simulate(fws.LateralPlant(veh, speed=20.0), fws.Straight(),
        ...                    fws.SteeringGains(0.01, 0.2, 0.0),
        ...                    initial_state=(0.0, 0.5, 0.0), duration=4.0,
        ...                    speed=fws.SpeedProfile.braking(20.0, 4.0))
        >>> float(res.longitudinal_speed[0]), float(res.longitudinal_speed[-1])
        (20.0, 4.0)
        """
        self._require(["s"], "longitudinal_speed")
        return self._squeezed(self._speed_values(self._s()))

    def _s(self) -> np.ndarray:
        return self.signals[:, self.signal_names.index("s"), :]

    @property
    def longitudinal_accel(self) -> np.ndarray:
        r"""Longitudinal acceleration :math:`\dot V` the speed profile implies [m/s²].

        :math:`dV/dt` of a profile of the time; :math:`V'(s)\,\dot s` of a
        profile of the arc length (with :math:`\dot s` of the model at each
        sample); 0 at a constant speed. NaN after a run's stop. Squeezed
        like ``result.e``.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> res = fws.simulate(fws.LateralPlant(veh, speed=20.0), fws.Straight(),
        ...                    fws.SteeringGains(0.01, 0.2, 0.0),
        ...                    initial_state=(0.0, 0.5, 0.0), duration=2.0,
        ...                    speed=fws.SpeedProfile.braking(20.0, 4.0))
        >>> float(res.longitudinal_accel[0])
        -4.0
        """
        self._require(["s"], "longitudinal_accel")
        s = self._s()
        prof = self.speed_profile
        if prof is None:
            out = np.where(np.isfinite(s), 0.0, np.nan)
        elif prof.of == "time":
            out = np.where(np.isfinite(s), prof.derivative(self.t)[None, :], np.nan)
        else:
            s_dot = self._path_speed("longitudinal_accel")
            out = prof.derivative(np.where(np.isfinite(s), s, 0.0)) * s_dot
            out = np.where(np.isfinite(s), out, np.nan)
        return self._squeezed(out)

    @property
    def longitudinal_force(self) -> np.ndarray:
        r"""Longitudinal force :math:`m\dot V` the speed profile needs [N].

        The vehicle's mass times :attr:`longitudinal_accel` (the drive or
        brake force along the direction of travel; the body-frame term
        :math:`-m v_y r` of a turn is not included).

        Raises
        ------
        ValueError
            If the vehicle has no mass.
        """
        mass = None if self.vehicle is None else self.vehicle.mass
        if mass is None:
            raise ValueError(
                "longitudinal_force needs the vehicle's mass [kg], got mass=None"
            )
        return mass * self.longitudinal_accel

    @property
    def friction_usage(self) -> np.ndarray:
        r"""Share of the friction circle the run uses at each sample [-].

        .. math::

            \frac{\sqrt{(m\dot V)^2 + (m a_y)^2}}{\mu m g}
            = \frac{\sqrt{\dot V^2 + a_y^2}}{\mu g}

        with :math:`a_y` = ``lateral_accel``, :math:`\mu` the vehicle's
        ``friction`` and :math:`g = 9.81` m/s² (a point-mass friction
        circle). Above 1 the tyres cannot supply the combined force.

        Raises
        ------
        ValueError
            If the vehicle has no friction coefficient.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, friction=0.8)
        >>> res = fws.simulate(fws.LateralPlant(veh, speed=20.0), fws.Straight(),
        ...                    fws.SteeringGains(0.01, 0.2, 0.0),
        ...                    initial_state=(0.0, 0.0, 0.0), duration=2.0,
        ...                    speed=fws.SpeedProfile.braking(20.0, 9.0))
        >>> round(float(res.friction_usage[0]), 6)       # 9 / (0.8 * 9.81)
        1.146789
        >>> res.friction_exceeded
        True
        """
        mu = None if self.vehicle is None else self.vehicle.friction
        if mu is None:
            raise ValueError(
                "friction_usage needs the vehicle's friction coefficient mu, got "
                "friction=None"
            )
        self._require(["lateral_accel"], "friction_usage")
        a_y = self.signals[:, self.signal_names.index("lateral_accel"), :]
        a_x = self.longitudinal_accel
        a_x = a_x[None, :] if self.squeeze else a_x
        return self._squeezed(np.hypot(a_x, a_y) / (mu * GRAVITY))

    @property
    def friction_exceeded(self) -> bool | np.ndarray:
        """True for a run whose :attr:`friction_usage` exceeds 1 at a sample."""
        usage = self.friction_usage
        usage = usage[None, :] if self.squeeze else usage
        with np.errstate(invalid="ignore"):
            over = np.any(usage > 1.0, axis=1)
        return self._per_run(over, bool)

    @property
    def k1(self) -> float | np.ndarray:
        """Lateral-error gain [rad/m]; NaN where no design exists."""
        return self._per_run(self.run_k1, float)

    @property
    def k2(self) -> float | np.ndarray:
        """Heading-error gain [rad/rad]; NaN where no design exists."""
        return self._per_run(self.run_k2, float)

    @property
    def ratio(self) -> float | np.ndarray:
        """Rear-to-front steering ratio :math:`a`."""
        return self._per_run(self.run_ratio, float)

    @property
    def initial_state(self) -> np.ndarray:
        """``(x_R, y_R, psi)`` at t = 0, shape ``(3,)`` or ``(runs, 3)``."""
        return self.run_initial_state[0] if self.squeeze else self.run_initial_state

    @property
    def gains(self) -> SteeringGains | None:
        """The gains as one :class:`SteeringGains`; None if a run has no design."""
        values = (self.run_k1, self.run_k2, self.run_ratio)
        if not all(np.all(np.isfinite(v)) for v in values):
            return None
        if self.squeeze:
            return SteeringGains(*(float(v[0]) for v in values))
        return SteeringGains(*(v.copy() for v in values))

    @property
    def ok(self) -> bool | np.ndarray:
        """True for a run that reached the final time."""
        return self._per_run(self.run_status == STATUS_OK, bool)

    @property
    def singular(self) -> bool | np.ndarray:
        """True for a run that stopped at a singular state of the model."""
        mask = np.isin(
            self.run_status, (STATUS_SINGULAR_STEERING, STATUS_SINGULAR_CURVATURE)
        )
        return self._per_run(mask, bool)

    # ------------------------------------------------------------------
    # Conversions

    def _default_labels(self) -> list[str | None]:
        """Legend labels naming what differs between the runs.

        The ratio, speed and initial pose that differ; the gains too if those
        do not tell the runs apart (the gains of a design follow from its
        ratio and speed); ``run i`` if nothing differs.
        """
        n = len(self)
        if n == 1:
            return [None]

        def differing(items):
            out = [[] for _ in range(n)]
            for values, fmt in items:
                if np.unique(values, axis=0).shape[0] > 1:
                    for i in range(n):
                        out[i].append(fmt(values[i]))
            return out

        parts = differing(
            (
                (self.run_ratio, "a={:g}".format),
                (self.run_speed, "V={:g}".format),
                (
                    self.run_initial_state,
                    lambda x0: f"R0=({x0[0]:g}, {x0[1]:g}, {x0[2]:g})",
                ),
            )
        )
        if len({tuple(p) for p in parts}) < n:
            gains = differing(
                ((self.run_k1, "k1={:.4g}".format), (self.run_k2, "k2={:.4g}".format))
            )
            parts = [p + q for p, q in zip(parts, gains, strict=True)]
        if all(parts):
            return [", ".join(p) for p in parts]
        return [f"run {i}" for i in range(n)]

    def _labels(self, labels: Any) -> list[str | None]:
        n = len(self)
        if labels is None:
            return self._default_labels()
        if isinstance(labels, str):
            labels = [labels]
        labels = list(labels)
        if len(labels) != n:
            raise ValueError(
                f"labels must hold one label per run ({n}), got {len(labels)}: "
                f"{labels!r}"
            )
        return [None if lab is None else str(lab) for lab in labels]

    def to_time_response(self) -> ct.TimeResponseData:
        """The signals as a :class:`control.TimeResponseData`.

        Outputs are the signals of :data:`~fws_control.simulation.SIGNALS`
        (with those names), the traces are the runs. A squeezed result gives
        a single-trace response (outputs of shape ``(signals, time)``), a
        batch a multi-trace one (``(signals, runs, time)``, trace labels as
        in :meth:`plot`), so :func:`control.time_response_plot` draws it.
        ``success`` is True if every run reached the final time;
        ``message`` joins the runs' messages; ``params`` holds the per-run
        ``speed, k1, k2, ratio`` and ``feedforward``.

        Returns
        -------
        control.TimeResponseData
            Its outputs are the kept signals (:attr:`signal_names`).

        Raises
        ------
        SignalNotKeptError
            For a result that keeps no time series (``signals="metrics"``).

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=0.0)
        >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
        ...                    initial_state=(0.0, 1.0, 0.0), duration=2.0)
        >>> resp = res.to_time_response()
        >>> resp.output_labels[4], resp.outputs.shape, resp.ntraces
        ('e', (15, 201), 0)
        """
        params = {
            "speed": self.speed,
            "k1": self.k1,
            "k2": self.k2,
            "ratio": self.ratio,
            "feedforward": self.feedforward,
        }
        if not self.signal_names:
            raise _not_kept(SIGNALS[0], (), "to_time_response")
        if self.squeeze:
            outputs = self.signals[0]
            trace_labels = None
        else:
            outputs = np.transpose(self.signals, (1, 0, 2))
            trace_labels = [
                lab if lab is not None else f"run {i}"
                for i, lab in enumerate(self._default_labels())
            ]
        notes = [m for m in self.run_message if m]
        import control as ct

        return ct.TimeResponseData(
            self.t,
            outputs,
            output_labels=list(self.signal_names),
            issiso=False,
            multi_trace=not self.squeeze,
            trace_labels=trace_labels,
            title="closed-loop path tracking",
            sysname="closed_loop",
            plot_inputs=False,
            params=params,
            success=bool(np.all(self.run_status == STATUS_OK)),
            message="; ".join(notes) if notes else None,
        )

    def to_pandas(self) -> pd.DataFrame:
        """Long-format :class:`pandas.DataFrame`, one row per run and sample.

        Columns ``run, t``, the signals of
        :data:`~fws_control.simulation.SIGNALS` that the result keeps
        (:attr:`signal_names`), then the per-run ``status,
        t_stop, speed, k1, k2, ratio, message`` and the batch's
        ``feedforward, method`` (repeated on each of the run's rows, so that
        a CSV file keeps them). A run's rows are its samples up to its stop;
        a run without any sample (e.g. ``"uncontrollable"``, not simulated)
        keeps one row with NaN ``t`` and signals, so that no run is dropped.
        ``attrs`` holds ``feedforward`` and ``method`` too.

        Returns
        -------
        pandas.DataFrame

        A result that keeps no time series (``signals="metrics"``) gives
        one row per run instead: ``run``, the per-run and batch columns
        above, and the exact peaks ``peak_e``, ``peak_delta_f``,
        ``peak_delta_r``, ``peak_delta_f_rate``, ``peak_delta_r_rate`` and
        ``peak_lateral_accel`` (see :attr:`peaks`;
        :meth:`fws_control.TrackingMetrics.to_pandas` adds the horizon
        metrics).

        Raises
        ------
        ImportError
            If pandas is not installed.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> g = fws.SteeringGains(k1=[0.1, 0.2], k2=0.5, ratio=0.0)
        >>> plant = fws.LateralPlant(veh, speed=5.0)
        >>> res = fws.simulate_batch(plant, fws.Straight(), g,
        ...                          initial_state=(0.0, 1.0, 0.0), duration=1.0,
        ...                          dt=0.5)
        >>> res.to_pandas()[["run", "t", "e", "k1", "status"]]
           run    t         e   k1 status
        0    0  0.0  1.000000  0.1     ok
        1    0  0.5  0.901922  0.1     ok
        2    0  1.0  0.676418  0.1     ok
        3    1  0.0  1.000000  0.2     ok
        4    1  0.5  0.806609  0.2     ok
        5    1  1.0  0.398119  0.2     ok
        """
        pd = import_pandas()
        if not self.signal_names:
            return self._runs_to_pandas(pd)
        names = self.signal_names
        n = len(self)
        # a run's samples up to its stop
        have = np.arange(self.t.size)[None, :] < self._samples[:, None]
        rows_run, rows_k = np.nonzero(have)
        # A run without samples keeps one row of NaN, so that it is not lost.
        empty = np.setdiff1d(np.arange(n), rows_run)
        run = np.concatenate([rows_run, empty])
        t = np.concatenate([self.t[rows_k], np.full(empty.size, np.nan)])
        values = np.concatenate(
            [
                self.signals[rows_run, :, rows_k],
                np.full((empty.size, len(names)), np.nan),
            ]
        )
        order = np.argsort(run, kind="stable")
        run, t, values = run[order], t[order], values[order]
        data: dict[str, Any] = {"run": run, "t": t}
        data.update({name: values[:, j] for j, name in enumerate(names)})
        for name, per_run in (
            ("status", self.run_status),
            ("t_stop", self.run_t_stop),
            ("speed", self.run_speed),
            ("k1", self.run_k1),
            ("k2", self.run_k2),
            ("ratio", self.run_ratio),
            ("message", np.array(self.run_message, dtype=object)),
        ):
            data[name] = per_run[run]
        # (as columns, not only in attrs: a CSV file keeps no attrs)
        data["feedforward"] = np.full(run.size, self.feedforward)
        data["method"] = np.full(run.size, self.method or "", dtype=object)
        df = pd.DataFrame(data)
        df.attrs["feedforward"] = self.feedforward
        df.attrs["method"] = self.method
        return df

    def _runs_to_pandas(self, pd):
        """One row per run: the run's data and its exact peaks."""
        n = len(self)
        data: dict[str, Any] = {
            "run": np.arange(n),
            "status": self.run_status,
            "t_stop": self.run_t_stop,
            "speed": self.run_speed,
            "k1": self.run_k1,
            "k2": self.run_k2,
            "ratio": self.run_ratio,
            "message": np.array(self.run_message, dtype=object),
        }
        peaks = self.peaks
        for name in PEAK_SIGNALS:
            data[f"peak_{name}"] = np.broadcast_to(peaks[name].value, (n,))
        data["feedforward"] = np.full(n, self.feedforward)
        data["method"] = np.full(n, self.method or "", dtype=object)
        df = pd.DataFrame(data)
        df.attrs["feedforward"] = self.feedforward
        df.attrs["method"] = self.method
        return df

    # ------------------------------------------------------------------
    # Plot

    def plot(
        self,
        ax: Any = None,
        *,
        labels: str | Sequence[str | None] | None = None,
        title: str | None = None,
    ) -> ct.ControlPlot:
        """Plot every run: errors, trajectory, steering, lateral acceleration.

        Parameters
        ----------
        ax : array_like of 6 matplotlib.axes.Axes, optional
            Axes to draw into, in the order lateral error, heading error,
            trajectory, front steering, rear steering, lateral acceleration
            (e.g. the ``axes`` of an earlier call, to overlay results). A new
            figure with a 3 x 2 grid if None.
        labels : str or sequence of str, optional
            Legend label per run (a str for a single run). Default: none for
            one run; for several, the per-run values that differ (``a=...``,
            ``V=...``, ...).
        title : str, optional
            Figure title.

        Returns
        -------
        control.ControlPlot
            ``axes``: the shape of `ax` (one row of 6 for a flat sequence;
            ``(3, 2)`` when created) and ``lines``: per axes, the lines
            drawn. Panels: ``e`` [m], ``theta`` [deg], the trajectory of R
            with the reference path [m], ``delta_f`` and ``delta_r`` [deg],
            lateral acceleration of G [m/s^2]. A run that
            stopped early is marked with an ``x`` at its last sample and its
            status in the legend; a run that was not simulated appears only
            in the legend.

        Raises
        ------
        ValueError
            If `ax` does not hold 6 axes or `labels` not one label per run.
        SignalNotKeptError
            If a signal it draws (``x, y, s, e, theta, delta_f, delta_r,
            lateral_accel``) was not kept (``simulate_batch(...,
            signals=...)``).

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> g = fws.SteeringGains(k1=0.1, k2=0.5, ratio=0.0)
        >>> res = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
        ...                    initial_state=(0.0, 1.0, 0.0), duration=2.0)
        >>> cplt = res.plot(labels="a = 0")
        >>> cplt.axes.shape
        (3, 2)
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        self._require(
            ("x", "y", "s", "e", "theta", "delta_f", "delta_r", "lateral_accel"),
            "plot",
        )
        names = self._labels(labels)
        if ax is None:
            fig = plt.figure(figsize=(11, 9), layout="constrained")
            axes = np.empty((3, 2), dtype=object)
            axes[...] = fig.subplots(3, 2)
        else:
            axes = np.empty(np.shape(ax), dtype=object)
            axes[...] = ax
            if axes.size != 6:
                raise ValueError(
                    f"ax must hold 6 matplotlib axes (e, theta, trajectory, "
                    f"delta_f, delta_r, lateral_accel), got {axes.size}"
                )
            # ControlPlot keeps its axes 2-D; keep the lines in the same shape.
            axes = axes.reshape(1, 6) if axes.ndim < 2 else axes
            fig = axes.flat[0].figure
        flat = list(axes.flat)
        ax_e, ax_th, ax_xy, ax_df, ax_dr, ax_a = flat
        before = [len(a.get_lines()) for a in flat]
        panels = (
            (ax_e, "e", 1.0, "lateral error e [m]"),
            (ax_th, "theta", _DEG, "heading error θ [deg]"),
            (ax_df, "delta_f", _DEG, "front steering δf [deg]"),
            (ax_dr, "delta_r", _DEG, "rear steering δr [deg]"),
            (ax_a, "lateral_accel", 1.0, "lateral acceleration of G [m/s²]"),
        )
        row = self.signal_names.index
        index = {name: row(name) for name in ("x", "y")}
        legend_needed = False
        # per panel: the stop markers, and the values that set its scale
        stops: dict[Any, list] = {a: [] for a, *_ in panels}
        bulk: dict[Any, list] = {a: [] for a, *_ in panels}
        for i in range(len(self)):
            status = self.run_status[i]
            text = names[i] or ""
            if status == STATUS_UNCONTROLLABLE:
                text = f"{text} (uncontrollable: not simulated)".strip()
            elif status != STATUS_OK:
                text = f"{text} ({status} at t={self.run_t_stop[i]:.3g} s)".strip()
            legend_needed |= bool(text)
            label = text or None
            count = int(self._samples[i])
            t = self.t[:count]
            color = None
            for a, name, scale, _ in panels:
                y = scale * self.signals[i, row(name), :count]
                (line,) = a.plot(t, y, label=label, color=color)
                color = line.get_color()
                if status != STATUS_OK and count:
                    (stop,) = a.plot(t[-1], y[-1], "x", color=color)
                    stops[a].append(stop)
                bulk[a].append(_bulk(y, stopped=status != STATUS_OK))
            xs = self.signals[i, index["x"], :count]
            ys = self.signals[i, index["y"], :count]
            ax_xy.plot(xs, ys, color=color, label=label)
            if status != STATUS_OK and count:
                ax_xy.plot(xs[-1], ys[-1], "x", color=color)
        s = self.signals[:, row("s"), :]
        if self.path is not None and np.any(np.isfinite(s)):
            s_lo, s_hi = float(np.nanmin(s)), float(np.nanmax(s))
            span = max(s_hi - s_lo, 1.0)
            ss = np.linspace(s_lo - 0.05 * span, s_hi + 0.05 * span, 400)
            if not self.path.closed:
                ss = np.clip(ss, 0.0, self.path.length)
            px, py = self.path.position(ss)
            # one "path" entry when results are overlaid on these axes
            drawn = any(line.get_label() == "path" for line in ax_xy.get_lines())
            ax_xy.plot(px, py, "k--", lw=1.0, label="_path" if drawn else "path")
            ax_xy.legend(fontsize="small")
        for a, _, _, ylabel in panels:
            a.set_xlabel("time t [s]")
            a.set_ylabel(ylabel)
            a.grid(True, alpha=0.3)
            _clip_spikes(a, bulk[a], stops[a])
        ax_xy.set_xlabel("x [m]")
        ax_xy.set_ylabel("y [m]")
        _trajectory_aspect(ax_xy)
        ax_xy.grid(True, alpha=0.3)
        legend = ax_e.legend(fontsize="small") if legend_needed else None
        lines = np.empty(axes.shape, dtype=object)
        for k, a in enumerate(flat):
            lines.flat[k] = list(a.get_lines()[before[k] :])
        if title is not None:
            # fig.suptitle, not ControlPlot.set_plot_title: the latter
            # switches a constrained layout to a tight one.
            fig.suptitle(title)
        import control as ct

        return ct.ControlPlot(lines, axes, fig, legend=legend)


#: A stopped run's last samples left out of a panel's scale: the steering
#: and the lateral acceleration diverge at a singular stop.
_STOP_TAIL = 0.1

#: A panel whose values reach beyond this multiple of the scale set by the
#: runs' bulk is clipped to that scale (the divergent end is marked).
_SPIKE = 3.0

#: Below this ratio of the y span to the x span the trajectory is drawn
#: with its own y scale instead of equal axes (a straight road would be a
#: flat line).
_FLAT = 0.05


def _bulk(y: np.ndarray, *, stopped: bool) -> tuple[float, float]:
    """Range of a run's values without a stopped run's divergent end."""
    if stopped:
        y = y[: max(1, int(len(y) * (1.0 - _STOP_TAIL)))]
    y = y[np.isfinite(y)]
    return (float(y.min()), float(y.max())) if y.size else (np.nan, np.nan)


def _clip_spikes(ax, bulk: list, stops: list) -> None:
    """Scale a panel to its runs' bulk when a stopped run's end would squash it.

    The stop markers outside the new limits move onto the limit and turn
    into triangles pointing off the axes.
    """
    ranges = np.array(bulk, dtype=float).reshape(-1, 2)
    if not stops or not np.isfinite(ranges).any():
        return
    lo, hi = np.nanmin(ranges[:, 0]), np.nanmax(ranges[:, 1])
    ylo, yhi = ax.get_ylim()
    span = max(hi - lo, 1e-12)
    if (yhi - ylo) <= _SPIKE * span:
        return
    lo, hi = lo - 0.1 * span, hi + 0.1 * span
    ax.set_ylim(max(ylo, lo), min(yhi, hi))
    for stop in stops:
        y = float(stop.get_ydata()[0])
        if y > hi or y < lo:
            stop.set_ydata([min(max(y, lo), hi)])
            stop.set_marker("^" if y > hi else "v")
    ax.text(
        0.99, 0.98, "stopped runs' divergent ends off scale (triangles)",
        transform=ax.transAxes, ha="right", va="top", fontsize="x-small",
    )  # fmt: skip


def _trajectory_aspect(ax) -> None:
    """Equal axes, unless the trajectory is too flat to read with them."""
    (x0, y0), (x1, y1) = ax.dataLim.get_points()
    if (y1 - y0) >= _FLAT * (x1 - x0):
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title("trajectory of R")
    else:
        ax.set_aspect("auto")
        ax.set_title("trajectory of R (y not to scale)")


def expand_runs(
    result: SimulationResult | None,
    *,
    positions: Any,
    k1: Any,
    k2: Any,
    ratio: Any,
    speed: Any,
    initial_state: Any,
    t: np.ndarray,
    feedforward: bool | Literal["dynamic"],
    vehicle: Vehicle | None,
    path: Path | None,
    status: str = STATUS_UNCONTROLLABLE,
    message: str = "",
) -> SimulationResult:
    """Place `result`'s runs among runs that were not simulated.

    For designs that cannot be simulated (e.g. no gains exist, status
    ``"uncontrollable"``) but must stay in the data instead of being
    dropped: the batch has ``len(ratio)`` runs; the runs of `result` go to
    `positions`, every other run gets NaN signals and ``t_stop``, `status`
    and `message`.

    Parameters
    ----------
    result : SimulationResult or None
        The simulated runs (not squeezed, on the time grid `t`); None if no
        run was simulated.
    positions : array_like of int
        Run index of each run of `result` in the expanded batch.
    k1, k2, ratio, speed : array_like
        Per run values of the expanded batch, shape ``(runs,)``; ``k1, k2``
        NaN where no design exists.
    initial_state : array_like
        Per run ``(x_R, y_R, psi)``, shape ``(runs, 3)``.
    t : ndarray
        Output times (those of `result`).
    feedforward : bool
        Controller of all runs.
    vehicle : Vehicle or None
        The simulated vehicle.
    path : Path or None
        The reference path.
    status : str, optional
        Status of the runs that were not simulated.
    message : str, optional
        Their explanation.

    Returns
    -------
    SimulationResult
        Not squeezed, ``len(ratio)`` runs.

    Raises
    ------
    ValueError
        If `result` does not have one run per position or another time grid.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.result import expand_runs
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, 0.0)
    >>> res = fws.simulate_batch(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                          initial_state=(0.0, 1.0, 0.0), duration=1.0)
    >>> full = expand_runs(res, positions=[1], k1=[np.nan, 0.1],
    ...                    k2=[np.nan, 0.5], ratio=[1.0, 0.0], speed=[5.0, 5.0],
    ...                    initial_state=[(0.0, 1.0, 0.0)] * 2, t=res.t,
    ...                    feedforward=True, vehicle=veh, path=fws.Straight(),
    ...                    message="no design")
    >>> full.status.tolist(), bool(np.all(np.isnan(full.e[0])))
    (['uncontrollable', 'ok'], True)
    """
    k1 = np.asarray(k1, dtype=float)
    n = k1.size
    t = np.asarray(t, dtype=float)
    positions = np.asarray(positions, dtype=int).ravel()
    names = SIGNALS if result is None else result.signal_names
    signals = np.full((n, len(names), t.size), np.nan)
    samples = np.zeros(n, dtype=np.int64)
    metrics = None
    run_status = np.full(n, status, dtype=object)
    run_message = [str(message)] * n
    t_stop = np.full(n, np.nan)
    # Runs that were not simulated have NaN peaks.
    peak = np.full((n, len(PEAK_SIGNALS)), np.nan)
    peak_time = np.full((n, len(PEAK_SIGNALS)), np.nan)
    peaks_known = True
    if result is not None:
        if len(result) != positions.size or result.t.shape != t.shape:
            raise ValueError(
                f"result must hold one run per position ({positions.size}) on the "
                f"time grid t ({t.size} samples), got {len(result)} runs and "
                f"{result.t.size} samples"
            )
        signals[positions] = result.signals
        samples[positions] = result.run_samples
        if result.run_metrics is not None:
            metrics = np.full((n, result.run_metrics.shape[1]), np.nan)
            metrics[positions] = result.run_metrics
        run_status[positions] = result.run_status
        for p, m in zip(positions, result.run_message, strict=True):
            run_message[p] = m
        t_stop[positions] = result.run_t_stop
        if result.run_peak is None:
            peaks_known = False
        else:
            peak[positions] = result.run_peak
            peak_time[positions] = result.run_peak_time
    elif positions.size:
        raise ValueError(f"positions must be empty without a result, got {positions}")
    return SimulationResult(
        t=t,
        signals=signals,
        run_status=run_status.astype(str),
        run_message=tuple(run_message),
        run_t_stop=t_stop,
        run_speed=np.broadcast_to(np.asarray(speed, dtype=float), (n,)),
        run_k1=k1,
        run_k2=np.asarray(k2, dtype=float),
        run_ratio=np.asarray(ratio, dtype=float),
        run_initial_state=np.broadcast_to(
            np.asarray(initial_state, dtype=float), (n, 3)
        ),
        feedforward=feedforward,
        squeeze=False,
        vehicle=vehicle,
        path=path,
        run_peak=peak if peaks_known else None,
        run_peak_time=peak_time if peaks_known else None,
        method=None if result is None else result.method,
        engine="numpy" if result is None else result.engine,
        # the simulated runs' model: a dynamic batch stays dynamic
        model="kinematic" if result is None else result.model,
        tyre="linear" if result is None else result.tyre,
        signal_names=names,
        run_samples=samples,
        run_metrics=metrics,
        peaks_exact=True if result is None else result.peaks_exact,
    )
