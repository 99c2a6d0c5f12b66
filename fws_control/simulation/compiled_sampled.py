"""Sampled controllers (zero-order hold) on the compiled engine.

A sampled controller (one with a
:attr:`~fws_control.LateralController.sample_time`, such as
:class:`~fws_control.MPCController`) computes its command in Python from
the state at the measurement times ``k * sample_time`` and holds it from
``k * sample_time + delay`` to the next switch
(:func:`~fws_control.simulation.options.sample_events`). Between two such
times the loop is the vehicle under a constant command: the compiled
engine integrates each of these segments with the law ``"held"`` of
:mod:`~fws_control.simulation.compiled_laws` (each run alone, DOP853
restarted at every measurement and switch time, as the numpy engine
restarts its solver there), computes the segment's signals and exact peaks
on the segment's dense output, and carries every state, the actuator's and
the body's included, into the next segment.

An output time within :data:`~fws_control.simulation.options.AT_SWITCH`
sample times of a switch shows the new command (the hold is
right-continuous), as on the numpy engine; the state there is the one at
the switch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..lateral_controller import LateralController, saturate
from ..paths import Path
from ..vehicle import Vehicle
from .compiled import (
    compiled_outputs,
    compiled_peaks,
    integrate_compiled,
    pose_signals,
)
from .compiled_layout import NSIG
from .options import AT_SWITCH, sample_events
from .outcomes import PEAK_SIGNALS, STATUS_OK

__all__ = ["HeldCommand", "run_sampled"]


@dataclass(frozen=True, eq=False)
class HeldCommand(LateralController):
    """The compiled law ``"held"``: one constant command per run.

    Parameters
    ----------
    delta_f, delta_r : array_like
        Front and rear command of each run [rad], shape ``(n,)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.simulation.compiled_sampled import HeldCommand
    >>> HeldCommand(np.array([0.1]), np.array([-0.02])).compiled_law()[0]
    'held'
    """

    delta_f: Any
    delta_r: Any
    label = "held command"

    def __post_init__(self) -> None:
        object.__setattr__(self, "delta_f", np.asarray(self.delta_f, dtype=float))
        object.__setattr__(self, "delta_r", np.asarray(self.delta_r, dtype=float))

    def compiled_law(self) -> tuple[str, tuple[Any, ...]]:
        """The law as the compiled engine runs it: ``("held", (df, dr))``."""
        return "held", (self.delta_f, self.delta_r)

    def steering(
        self, vehicle: Vehicle, path: Path, *, s: Any, e: Any, theta: Any,
        curvature: Any, speed: Any,
    ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """The held command, whatever the state (the initial command)."""
        return self.delta_f, self.delta_r


def run_sampled(
    vehicle: Vehicle,
    path: Path,
    controller: Any,
    *,
    speed: np.ndarray,
    path_state: np.ndarray,
    initial_heading: np.ndarray,
    t_eval: np.ndarray,
    time_constant: float | None,
    table: Any,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    max_step: float = math.inf,
    delay: float = 0.0,
    model: str = "kinematic",
    tyre: str = "linear",
    body_state: np.ndarray | None = None,
    out: np.ndarray | None = None,
) -> tuple[np.ndarray, ...]:
    """Signals, statuses and exact peaks of sampled runs, compiled.

    Parameters
    ----------
    vehicle, path : Vehicle, Path
        As :func:`~fws_control.simulation.compiled.integrate_compiled`.
    controller : LateralController
        A sampled controller: ``controller.start(vehicle, path, speed=V)``
        gives each run's object whose ``step(s=, e=, theta=)`` returns the
        command of a measurement.
    speed : ndarray
        Speed of each run [m/s], shape ``(n,)``.
    path_state : ndarray
        Initial ``(s, e, theta)`` per run, shape ``(n, 3)``.
    initial_heading : ndarray
        Initial global heading per run [rad] (the branch of ``psi``).
    t_eval : ndarray
        Output times [s], increasing, shared by the runs.
    time_constant : float or None
        Steering actuator's time constant [s] (None: ideal steering).
    table : CurvatureTable
        The path's curvature table
        (:func:`~fws_control.simulation.compiled.curvature_table`).
    rtol, atol, max_step : float, optional
        Solver settings of every segment (DOP853).
    delay : float, optional
        Input delay [s]: in the switch times.
    model, tyre : str, optional
        Vehicle model and tyre.
    body_state : ndarray, optional
        Initial ``(v_y, r)`` per run of the dynamic model (NaN: the no-slip
        motion at the first command).
    out : ndarray, optional
        Float64 array of shape ``(n, 15, T)`` that receives the signals (a
        chunk's rows of a batch's result, or a memory map).

    Returns
    -------
    signals : ndarray
        Shape ``(n, 15, T)``, the signals of
        :data:`~fws_control.simulation.outcomes.SIGNALS` (NaN after a stop).
    status, message, t_stop : ndarray
        Per run, as :func:`~fws_control.simulation.compiled.integrate_compiled`.
    peaks, peak_times : ndarray
        Shape ``(n, 6)``: the largest ``|signal|`` of
        :data:`~fws_control.simulation.outcomes.PEAK_SIGNALS` over the run
        and when (the largest of the segments' exact peaks).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.compiled import curvature_table
    >>> from fws_control.simulation.compiled_sampled import run_sampled
    >>> path = fws.Straight()
    >>> sig, status, *_ = run_sampled(
    ...     fws.Vehicle(2.7, 1.35), path, fws.MPCController(sample_time=0.1),
    ...     speed=np.array([10.0]), path_state=np.array([[0.0, 0.5, 0.0]]),
    ...     initial_heading=np.zeros(1), t_eval=np.linspace(0.0, 2.0, 21),
    ...     time_constant=None, table=curvature_table(path))
    >>> sig.shape, status.tolist()
    ((1, 15, 21), ['ok'])
    >>> bool(abs(sig[0, 4, -1]) < 0.1)       # e [m]: the offset closed
    True
    """
    tau = time_constant
    n, T = speed.size, t_eval.size
    dyn = model == "dynamic"
    m = (3 if tau is None else 5) + (2 if dyn else 0)
    tol = AT_SWITCH * float(controller.sample_time)
    if out is None:
        signals = np.full((n, NSIG, T), np.nan)
    elif out.shape != (n, NSIG, T) or out.dtype != np.float64:
        raise ValueError(
            f"out must be a float64 array of shape {(n, NSIG, T)}, got "
            f"{out.dtype} {out.shape}"
        )
    else:
        signals = out
        signals.fill(np.nan)  # (the samples after a stop stay NaN)
    peaks = np.zeros((n, len(PEAK_SIGNALS)))
    peak_times = np.full((n, len(PEAK_SIGNALS)), float(t_eval[0]))
    status = np.full(n, STATUS_OK, dtype=object)
    message = np.full(n, "", dtype=object)
    t_stop = np.full(n, float(t_eval[-1]))
    runs = [controller.start(vehicle, path, speed=float(v)) for v in speed]
    Y = np.full((n, m), np.nan)  # every run's state at t_cur
    Y[:, :3] = path_state
    if dyn and body_state is not None:
        Y[:, m - 2 :] = body_state  # (NaN: the no-slip motion, in the first)
    heading0 = np.asarray(initial_heading, dtype=float)
    cmd = np.zeros((n, 2))  # the command held from t_cur
    pending: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    active = np.arange(n)
    t_cur, t_end = float(t_eval[0]), float(t_eval[-1])
    events = sample_events(t_cur, t_end, float(controller.sample_time), delay)
    nxt = next(events, None)
    first_segment = True
    while True:
        while nxt is not None and nxt[0] <= t_cur:
            _, kind, k = nxt
            nxt = next(events, None)
            if kind == 0:  # a measurement: the command of sample k
                c = np.array(
                    [runs[i].step(s=Y[i, 0], e=Y[i, 1], theta=Y[i, 2]) for i in active]
                ).reshape(active.size, 2)
                pending[k] = (active, np.stack(saturate(vehicle, c[:, 0], c[:, 1]), 1))
            else:  # its switch
                rows, c = pending.pop(k)
                cmd[rows] = c
        # (one output time: a segment of that instant, whose initial state
        # is checked against the stops)
        if active.size == 0 or (t_cur >= t_end and not first_segment):
            break
        last = nxt is None or nxt[0] >= t_end
        seg_end = t_end if nxt is None or last else float(nxt[0])
        # the segment's output samples: from its start (within the switch
        # tolerance) to before the next switch, or to the end; its times
        # start at the switch and end at the next one
        lo = int(np.searchsorted(t_eval, t_cur - tol, side="left"))
        hi = T if last else int(np.searchsorted(t_eval, seg_end - tol, side="left"))
        times = np.maximum(t_eval[lo:hi], t_cur)
        at_start = times.size > 0 and times[0] == t_cur
        if not at_start:
            times = np.concatenate([[t_cur], times])
        if times[-1] < seg_end:
            times = np.append(times, seg_end)
        held = HeldCommand(cmd[active, 0], cmd[active, 1])
        kw: dict[str, Any] = dict(
            speed=speed[active], feedforward=False, time_constant=tau, model=model,
            tyre=tyre,
        )  # fmt: skip
        sol: list = []
        # (the table, not the path: the held law reads no position, and
        # the table is what the kernels take)
        states, st, msg, ts, _ = integrate_compiled(
            vehicle, table, held, path_state=Y[active, :3], t_eval=times,
            rtol=rtol, atol=atol, max_step=max_step, method="DOP853",
            solution=sol, body_state=Y[active, m - 2 :] if dyn else None,
            actuator_state=(
                None if tau is None or first_segment else Y[active, 3:5]
            ),
            **kw,
        )  # fmt: skip
        # (the pose once for the whole runs, below)
        sig = compiled_outputs(
            vehicle, path, held, states=states, initial_heading=heading0[active],
            table=table, solution=sol[0], t_eval=times, pose=False, **kw,
        )  # fmt: skip
        skip = 0 if at_start else 1
        signals[active, :, lo:hi] = sig[:, :, skip : skip + hi - lo]
        val, when = compiled_peaks(
            vehicle, table, held, solution=sol[0], t_eval=times, signals=sig,
            t_stop=ts, **kw,
        )  # fmt: skip
        better = val > peaks[active]
        peaks[active] = np.where(better, val, peaks[active])
        peak_times[active] = np.where(better, when, peak_times[active])
        ok = st == STATUS_OK
        for j in np.flatnonzero(~ok):
            i = active[j]
            status[i], message[i], t_stop[i] = st[j], msg[j], ts[j]
        Y[active[ok]] = states[:, ok, -1].T
        active = active[ok]
        t_cur = seg_end
        first_segment = False
    pose_signals(path, table, signals, heading0)
    return signals, status, message, t_stop, peaks, peak_times
