r"""The output signals of the runs, from their path-frame states.

:func:`compute_outputs` turns the states that
:func:`~fws_control.simulation.engine.integrate` returns into every signal
of :data:`~fws_control.simulation.outcomes.SIGNALS`: the global pose, the
steering and its rates, the lateral acceleration and the body motion.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import equations
from ..acceleration import lateral_acceleration
from ..dynamics import (
    slip_angles,
)
from ..gains import SteeringGains
from ..kinematic_models import yaw_rate
from ..paths import Path
from ..vehicle import Vehicle
from .loop import ClosedLoop, hold_row, is_sampled
from .outcomes import SIGNALS

__all__ = [
    "compute_outputs",
]


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


def compute_outputs(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: np.ndarray,
    feedforward: bool,
    time_constant: float | None,
    states: np.ndarray,
    initial_heading: np.ndarray,
    delay: float = 0.0,
    model: str = "kinematic",
    tyre: str = "linear",
    profile: Any = None,
    schedule: Any = None,
    times: np.ndarray | None = None,
) -> np.ndarray:
    """All signals of :data:`~fws_control.simulation.outcomes.SIGNALS` from the
    path-frame states.

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, time_constant
        As given to :func:`~fws_control.simulation.engine.integrate`.
    states : ndarray
        Its states, shape ``(m, n, T)``, NaN after a run's stop.
    initial_heading : ndarray
        Per run initial ``psi`` [rad], shape ``(n,)``: ``psi`` is unwrapped in
        time and put on the branch of this value.
    delay : float, optional
        The input delay given to :func:`~fws_control.simulation.engine.integrate` [s];
        its six extra rows of `states` then give the applied (delayed) steering command
        (for a sampled controller the held rows give it: no extra rows).
    model, tyre, profile, schedule : optional
        As given to :func:`~fws_control.simulation.engine.integrate`.
    times : ndarray, optional
        The times of the states, ``(T,)`` or ``(n, T)`` [s]; needed with a
        `profile` (the speed at each sample).

    Returns
    -------
    ndarray
        Shape ``(n, len(SIGNALS), T)``, NaN where `states` is NaN. The rates
        are exact (chain rule through the controller and the path's
        curvature derivative, or the actuator's rates). ``lateral_accel`` is
        the acceleration of the centre of gravity G along the vehicle's
        lateral axis: eq. (13) for the kinematic model, ``dv_y/dt + u r``
        for the dynamic one; NaN where ``|delta_f| >= pi/2``. ``v_y`` is the
        lateral velocity of G in the vehicle's frame and ``yaw_rate`` the
        yaw rate (for the kinematic model ``V sin(delta_r) + l_r r`` and
        eq. (10)); ``slip_front``, ``slip_rear`` are the slip angles of the
        dynamic model (0 for the kinematic one, which has no slip).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> from fws_control.simulation.outcomes import SIGNALS
    >>> from fws_control.simulation.signals import compute_outputs
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, 0.0)
    >>> states = np.array([0.0, 2.0, 0.0]).reshape(3, 1, 1)   # s, e, theta
    >>> out = compute_outputs(veh, fws.Straight(), g, speed=np.array([5.0]),
    ...                       feedforward=False, time_constant=None,
    ...                       states=states, initial_heading=np.array([0.0]))
    >>> float(out[0, SIGNALS.index("delta_f"), 0])   # -k1 * e
    -0.2
    """
    tau = time_constant
    psi0 = np.asarray(initial_heading, dtype=float)
    delayed = None
    # (a sampled controller's held rows already hold the delayed command)
    if delay > 0.0 and not is_sampled(gains):
        delayed, states = states[-6:], states[:-6]
    m, n, T = states.shape
    valid = np.isfinite(states[0])
    out = {name: np.full((n, T), np.nan) for name in SIGNALS}
    if not np.any(valid):
        return np.stack([out[name] for name in SIGNALS], axis=1)
    run_idx = np.broadcast_to(np.arange(n)[:, None], (n, T))[valid]
    Y = states[:, valid]
    if isinstance(gains, SteeringGains):
        k1, k2, a = (
            np.broadcast_to(np.asarray(v, dtype=float), (n,))[run_idx]
            for v in (gains.k1, gains.k2, gains.ratio)
        )
        g = SteeringGains(k1, k2, a)
    else:
        g = gains.subset(run_idx) if gains.runs() else gains
    V = speed[run_idx]
    eng = ClosedLoop(
        vehicle, path, g, V, feedforward, tau, model=model, tyre=tyre,
        hold=hold_row(gains, tau), profile=profile, schedule=schedule,
    )  # fmt: skip
    t_s = 0.0
    if profile is not None:
        if times is None:
            raise ValueError("times are needed to evaluate a speed profile")
        t_s = np.broadcast_to(np.asarray(times, dtype=float), (n, T))[valid]
        V = eng.speed_at(t_s, Y[0])
    if delayed is not None:
        Yd, Ydd = delayed[:3, valid], delayed[3:, valid]
        eng.delayed = Yd
    Ydot, kappa, df, dr = eng.derivatives(Y, t_s)
    if tau is None and delayed is not None:
        # The applied steering is the command of the delayed measurements.
        rf, rr = eng.command_rate(Yd, Ydd, eng.curvature(Yd[0]))
    elif tau is None:
        rf, rr = eng.command_rate(Y, Ydot, kappa, t_s)
    else:
        rf, rr = Ydot[3], Ydot[4]
    ok = np.abs(df) < math.pi / 2
    acc = np.full(df.shape, np.nan)
    if eng.dynamic:
        v_y, r = Y[-2], Y[-1]
        slip_f, slip_r = slip_angles(vehicle, v_y, r, df, dr, speed=V)
        # body-frame acceleration of G: d(v_y)/dt + u r
        acc[ok] = (Ydot[-2] + V * r)[ok]
    else:
        r = np.full(df.shape, np.nan)
        r[ok] = yaw_rate(vehicle, df[ok], dr[ok], speed=V[ok])
        # G moves with R's velocity V (cos dr, sin dr) plus r x (l_r, 0)
        l_r = vehicle.cg_distance(needed_by="the signals at G (a_y, v_y)")
        v_y = equations.cg_lateral_velocity(V, l_r, dr, r)
        slip_f = slip_r = np.where(ok, 0.0, np.nan)
        acc[ok] = lateral_acceleration(
            vehicle,
            df[ok],
            dr[ok],
            np.asarray(rf)[ok],
            np.asarray(rr)[ok],
            speed=V[ok],
        )
        if profile is not None:
            # eq. (13) holds V constant; d(v_y)/dt adds dV/dt v_y / V, and
            # v_y / V = sin(dr) + l_r sin(df - dr) / (f cos df) (no 0/0 at
            # a stop)
            V_dot = eng.speed_rate(t_s, Y[0], Ydot[0])[ok]
            acc[ok] += V_dot * (
                np.sin(dr[ok])
                + l_r * np.sin(df[ok] - dr[ok]) / (vehicle.wheelbase * np.cos(df[ok]))
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
        ("v_y", v_y),
        ("yaw_rate", r),
        ("slip_front", slip_f),
        ("slip_rear", slip_r),
        ("x", np.asarray(px) - Y[1] * np.sin(heading)),
        ("y", np.asarray(py) + Y[1] * np.cos(heading)),
        ("psi", Y[2] + heading),
    ):
        out[name][valid] = val
    psi = _unwrap_time(out["psi"])
    # Put psi on the branch of the given initial heading.
    shift = 2 * math.pi * np.round((psi0 - psi[:, 0]) / (2 * math.pi))
    out["psi"] = psi + shift[:, None]
    return np.stack([out[name] for name in SIGNALS], axis=1)
