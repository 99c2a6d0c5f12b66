r"""The closed loop as a python-control interconnection: the reference.

A second, independent implementation of the loop that
:func:`~fws_control.simulation.simulate` integrates: the global-frame
vehicle (eqs. 8-10), a projection block that maps ``(x, y, psi)`` to the
path errors ``(s, e, theta)`` and the curvature (eqs. 14-16), the controller
(eqs. 24-29) and, if there is one, the steering actuator, joined
with :func:`control.interconnect` and simulated with
:func:`control.input_output_response`. It is slower than the engine (a
projection per right-hand-side call, signal passing between the blocks) and
serves as its reference in the tests, and as a composable starting point
for loops the engine does not cover.
"""

from __future__ import annotations

from typing import Any, cast

import control as ct
import numpy as np

from .. import equations
from ..controllers import path_tracking_controller, steering_actuator
from ..deprecation import legacy_keyword, reject_unknown
from ..dynamics import dynamic_global_model
from ..gains import SteeringGains
from ..hints import RealArrayLike, TyreName
from ..kinematic_models import global_frame_model
from ..lateral_controller import LateralController, saturate
from ..paths import Path
from ..validation import check_delay, check_nonzero, check_scalar, check_type
from ..vehicle import Vehicle
from .options import check_model, resolve_time_constant, split_initial_state

__all__ = [
    "closed_loop_system",
    "projection_system",
    "reference_initial_state",
    "simulate_reference",
    "DEFAULT_PADE_ORDER",
]

#: Order of the Pade approximation of an input delay in the reference.
DEFAULT_PADE_ORDER = 10


def projection_system(path: Path, *, name: str = "projection") -> ct.NonlinearIOSystem:
    r"""Static block projecting the global pose onto the path.

    Parameters
    ----------
    path : Path
        Reference path.
    name : str, optional
        System name for :func:`control.interconnect`.

    Returns
    -------
    control.NonlinearIOSystem
        No states; inputs ``x, y, psi``; outputs ``s, e, theta, curvature``
        from ``path.errors(x, y, psi)`` (closest-point projection,
        eqs. 14-16).

    Examples
    --------
    >>> import fws_control as fws
    >>> proj = fws.projection_system(fws.Arc(curvature=0.1))
    >>> proj.output(0.0, [], [0.0, -5.0, 0.0]).round(6)
    array([ 0. , -5. ,  0. ,  0.1])
    """
    check_type("path", path, Path, "a fws_control Path (e.g. fws.Straight())")

    def output(t, x, u, params):
        s, e, theta, kappa = path.errors(float(u[0]), float(u[1]), float(u[2]))
        return np.array([float(s), float(e), float(theta), float(kappa)])

    return ct.nlsys(
        None,
        output,
        inputs=["x", "y", "psi"],
        outputs=["s", "e", "theta", "curvature"],
        name=name,
    )


#: Shortest nonzero delay given a Pade block [s] (its coefficients scale as
#: 1/delay**order; 1e-9 s keeps them finite for orders below 30).
_MIN_PADE_DELAY = 1.0e-9


def closed_loop_system(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: float,
    feedforward: bool = True,
    steering_lag: float | None = None,
    delay: float = 0.0,
    pade_order: int = DEFAULT_PADE_ORDER,
    model: str = "kinematic",
    tyre: TyreName = "linear",
    **kwargs: Any,
) -> ct.InterconnectedSystem:
    r"""The closed loop as a python-control interconnection (the reference).

    Blocks: :func:`~fws_control.global_frame_model` (states ``x, y, psi``),
    :func:`projection_system`, :func:`~fws_control.path_tracking_controller`
    with a delay, a :func:`control.pade` block per steering channel, and, if
    there is an actuator (see
    :func:`~fws_control.simulation.options.resolve_time_constant`),
    :func:`~fws_control.steering_actuator` (states ``delta_f, delta_r``
    appended last).

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and optional steering limits.
    path : Path
        Reference path.
    gains : SteeringGains
        Scalar ``k1, k2, ratio``.
    speed : float
        Speed :math:`V` [m/s], nonzero.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        Curvature feedforward (default ``True``), as in
        :func:`~fws_control.simulation.simulate`.
    steering_lag : float, optional
        Time constant [s] of the first-order steering actuator (the
        plant's ``steering_lag`` in :func:`~fws_control.simulation.simulate`;
        ``actuator_time_constant=`` is its former name, accepted until 0.4
        with a FutureWarning).
    delay : float, optional
        Input delay [s] on the steering commands, as in
        :func:`~fws_control.simulation.simulate`, approximated here by a
        :func:`control.pade` block of order `pade_order` on each channel,
        between the controller and the vehicle (or actuator).
    pade_order : int, optional
        Order of the Pade approximation (>= 1); default
        :data:`DEFAULT_PADE_ORDER`.
    model : {"kinematic", "dynamic"}, optional
        Vehicle block: :func:`~fws_control.global_frame_model` (default) or
        :func:`~fws_control.dynamics.dynamic_global_model` (states ``x, y,
        psi, v_y, r``; `speed` is its longitudinal speed, > 0), as in
        :func:`~fws_control.simulation.simulate`.
    tyre : {"linear", "magic"}, optional
        Tyre model of ``model="dynamic"``.

    Returns
    -------
    control.InterconnectedSystem
        No inputs; outputs ``x, y, psi, s, e, theta, curvature, delta_f,
        delta_r`` (the applied angles), and ``v_y, yaw_rate`` for the
        dynamic model. Simulate it with
        :func:`control.input_output_response`; the initial state is
        ``(x_R, y_R, psi)`` (and ``v_y, r`` for the dynamic model), followed
        by the states of the Pade blocks (front, rear) and of the actuator
        (:func:`reference_initial_state` builds it).

    Examples
    --------
    >>> import numpy as np, control as ct, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0,
    ...                           pole=-1.0)
    >>> sys = fws.closed_loop_system(veh, fws.Arc(curvature=0.1), g, speed=5.0)
    >>> sys.state_labels
    ['vehicle_x', 'vehicle_y', 'vehicle_psi']
    >>> resp = ct.input_output_response(
    ...     sys, np.linspace(0, 15, 151), initial_state=[0.0, -5.0, 0.0],
    ...     solve_ivp_method="DOP853",
    ...     solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-12})
    >>> round(float(resp.outputs[4, -1]), 5)   # e [m] at t = 15 s
    -3e-05
    """
    steering_lag = legacy_keyword(
        kwargs, "actuator_time_constant", "steering_lag", steering_lag
    )
    reject_unknown("closed_loop_system", kwargs)
    check_type("vehicle", vehicle, Vehicle)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    if steering_lag is not None:
        steering_lag = check_scalar("steering_lag", steering_lag)
    tau = resolve_time_constant(vehicle, steering_lag)
    model, _ = check_model(vehicle, model, tyre)  # tyre is returned unchanged
    if model == "dynamic":
        veh_sys = dynamic_global_model(vehicle, speed=speed, tyre=tyre, name="vehicle")
    else:
        veh_sys = global_frame_model(vehicle, speed=speed, name="vehicle")
    proj = projection_system(path, name="projection")
    if isinstance(gains, LateralController):
        ctrl = gains.system(vehicle, path, speed=speed, name="controller")
    else:
        ctrl = path_tracking_controller(
            vehicle,
            gains,
            feedforward=feedforward,
            speed=speed,
            tyre=tyre,
            name="controller",
        )
    delay = check_delay(delay)
    if 0.0 < delay < _MIN_PADE_DELAY:
        # the Pade coefficients grow as 1/delay**order: 1e-300 s divides by 0
        raise ValueError(
            f"delay must be 0 or >= {_MIN_PADE_DELAY:g} s for the Pade "
            f"approximation, got {delay!r}"
        )
    syslist = [veh_sys, proj, ctrl]
    connections = [
        ["projection.x", "vehicle.x"],
        ["projection.y", "vehicle.y"],
        ["projection.psi", "vehicle.psi"],
        ["controller.e", "projection.e"],
        ["controller.theta", "projection.theta"],
        ["controller.curvature", "projection.curvature"],
    ]
    if isinstance(gains, LateralController):
        connections.append(["controller.s", "projection.s"])
    cmd = "controller"
    if delay > 0.0:
        for wheel in ("f", "r"):
            syslist.append(_pade_block(delay, pade_order, f"delay_{wheel}"))
            connections.append([f"delay_{wheel}.u", f"controller.delta_{wheel}"])
        cmd = "delay"
    src = {
        "f": "delay_f.y" if cmd == "delay" else "controller.delta_f",
        "r": "delay_r.y" if cmd == "delay" else "controller.delta_r",
    }
    if tau is None:
        applied = src
    else:
        syslist.append(steering_actuator(vehicle, steering_lag=tau, name="actuator"))
        connections += [
            ["actuator.delta_f_cmd", src["f"]],
            ["actuator.delta_r_cmd", src["r"]],
        ]
        applied = {"f": "actuator.delta_f", "r": "actuator.delta_r"}
    connections += [
        ["vehicle.delta_f", applied["f"]],
        ["vehicle.delta_r", applied["r"]],
    ]
    outlist = [
        "vehicle.x",
        "vehicle.y",
        "vehicle.psi",
        "projection.s",
        "projection.e",
        "projection.theta",
        "projection.curvature",
        applied["f"],
        applied["r"],
    ]
    outputs = ["x", "y", "psi", "s", "e", "theta", "curvature", "delta_f", "delta_r"]
    if model == "dynamic":
        outlist += ["vehicle.v_y", "vehicle.r"]
        outputs += ["v_y", "yaw_rate"]
    return ct.interconnect(
        syslist,
        connections=connections,
        inplist=[],
        outlist=outlist,
        outputs=outputs,
        name="closed_loop",
    )


def _pade_block(delay: float, order: int, name: str) -> ct.StateSpace:
    if isinstance(order, bool) or int(order) != order or order < 1:
        raise ValueError(f"pade_order must be an integer >= 1, got {order!r}")
    num, den = ct.pade(delay, int(order))
    return ct.ss(ct.tf(num, den), inputs="u", outputs="y", name=name)


def reference_initial_state(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    initial_state: RealArrayLike,
    speed: float | None = None,
    feedforward: bool = True,
    steering_lag: float | None = None,
    delay: float = 0.0,
    pade_order: int = DEFAULT_PADE_ORDER,
    model: str = "kinematic",
    tyre: TyreName = "linear",
    **kwargs: Any,
) -> np.ndarray:
    """Initial state of :func:`closed_loop_system` matching the fast engine's.

    The vehicle starts at `initial_state`; the Pade blocks start at their
    steady state for the initial command (the held initial history of
    :func:`~fws_control.simulation.simulate`), and the actuator at the
    initial command. The dynamic model starts with the given ``(v_y, r)``
    or, as in the engine, rolling without tyre slip at the initial
    command.

    Parameters
    ----------
    vehicle, path, gains
        As in :func:`closed_loop_system`.
    initial_state : array_like
        ``(x_R, y_R, psi)`` [m, m, rad]; for the dynamic model also
        ``(x_R, y_R, psi, v_y, r)``.
    speed : float, optional
        Speed [m/s]; needed when `gains` is a controller (its law may
        depend on the speed) and for the dynamic model.
    feedforward, steering_lag, delay, pade_order, model, tyre : optional
        As in :func:`closed_loop_system`.

    Returns
    -------
    ndarray
        The full initial state vector.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation import reference_initial_state
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.1, 0.5, ratio=0.0)
    >>> x0 = reference_initial_state(veh, fws.Straight(), g,
    ...                              initial_state=(0.0, 2.0, 0.0), delay=0.2,
    ...                              pade_order=2)
    >>> x0.shape
    (7,)
    """
    steering_lag = legacy_keyword(
        kwargs, "actuator_time_constant", "steering_lag", steering_lag
    )
    reject_unknown("reference_initial_state", kwargs)
    from ..controllers import steering_command

    if model not in ("kinematic", "dynamic"):
        raise ValueError(f"model must be 'kinematic' or 'dynamic', got {model!r}")
    full = split_initial_state(initial_state, model=model)
    if full.shape[0] != 1:
        raise ValueError(
            f"initial_state must hold one run, got shape {np.shape(initial_state)}"
        )
    x0, body = full[0, :3], full[0, 3:]
    s, e, theta, kappa = path.errors(*x0, strict=True)
    if isinstance(gains, LateralController):
        if speed is None:
            raise TypeError("reference_initial_state needs speed= for a controller")
        u0 = np.array(
            saturate(
                vehicle,
                *gains.steering(
                    vehicle,
                    path,
                    s=np.array([float(s)]),
                    e=np.array([float(e)]),
                    theta=np.array([float(theta)]),
                    curvature=np.array([float(kappa)]),
                    speed=np.array([float(speed)]),
                ),
            ),
            dtype=float,
        ).ravel()
    else:
        u0 = np.array(
            steering_command(
                vehicle,
                gains,
                float(e),
                float(theta),
                curvature=float(kappa),
                feedforward=feedforward,
                speed=speed,
                tyre=tyre,
            ),
            dtype=np.float64,
        )
    parts = [x0]
    if model == "dynamic":
        if speed is None:
            raise TypeError("reference_initial_state needs speed= for model='dynamic'")
        if not np.all(np.isfinite(body)):  # rolling without slip, as the engine
            body = np.array(
                equations.no_slip_body_state(
                    speed,
                    vehicle.wheelbase,
                    # the dynamic model has required it
                    cast(float, vehicle.rear_to_cg),
                    u0[0],
                    u0[1],
                ),
                dtype=float,
            )
        parts.append(body)
    if check_delay(delay) > 0.0:
        for u in u0:
            blk = _pade_block(delay, pade_order, "d")
            parts.append(-np.linalg.solve(blk.A, blk.B[:, 0] * u))
    if resolve_time_constant(vehicle, steering_lag) is not None:
        parts.append(u0)
    return np.concatenate(parts)


def simulate_reference(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: float,
    initial_state: RealArrayLike,
    duration: float,
    feedforward: bool = True,
    dt: float = 0.01,
    steering_lag: float | None = None,
    delay: float = 0.0,
    pade_order: int = DEFAULT_PADE_ORDER,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    model: str = "kinematic",
    tyre: TyreName = "linear",
    **kwargs: Any,
) -> ct.TimeResponseData:
    """Simulate :func:`closed_loop_system` with :func:`control.input_output_response`.

    The python-control reference of :func:`~fws_control.simulation.simulate`
    (DOP853, the given tolerances), started from
    :func:`reference_initial_state`. No stop at singular states: use it on
    runs that stay regular.

    Parameters
    ----------
    vehicle, path, gains, speed, feedforward, steering_lag, delay
        As in :func:`closed_loop_system`.
    initial_state : array_like
        ``(x_R, y_R, psi)`` [m, m, rad]; for the dynamic model also
        ``(x_R, y_R, psi, v_y, r)``.
    duration : float
        Final time [s].
    dt : float, optional
        Output spacing [s] (``round(duration / dt)`` intervals).
    pade_order : int, optional
        Order of the Pade approximation of the delay.
    rtol, atol : float, optional
        Solver tolerances, in the ranges of
        :func:`~fws_control.simulation.options.check_tolerances`.
    model, tyre : str, optional
        Vehicle and tyre model, as in :func:`closed_loop_system`.

    Returns
    -------
    control.TimeResponseData
        Outputs ``x, y, psi, s, e, theta, curvature, delta_f, delta_r`` (and
        ``v_y, yaw_rate`` for the dynamic model).

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation import simulate_reference
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=5.0, ratio=0.0, pole=-1.0)
    >>> ref = simulate_reference(veh, fws.Straight(), g, speed=5.0,
    ...                          initial_state=(0.0, 2.0, 0.0), duration=5.0,
    ...                          delay=0.2)
    >>> fast = fws.simulate(fws.LateralPlant(veh, speed=5.0), fws.Straight(), g,
    ...                     initial_state=(0.0, 2.0, 0.0), duration=5.0, delay=0.2)
    >>> bool(abs(ref.outputs[4] - fast.e).max() < 1e-3)
    True
    """
    steering_lag = legacy_keyword(
        kwargs, "actuator_time_constant", "steering_lag", steering_lag
    )
    reject_unknown("simulate_reference", kwargs)
    from .options import check_tolerances, time_grid

    rtol, atol = check_tolerances(rtol, atol)

    sys = closed_loop_system(
        vehicle,
        path,
        gains,
        speed=speed,
        feedforward=feedforward,
        steering_lag=steering_lag,
        delay=delay,
        pade_order=pade_order,
        model=model,
        tyre=tyre,
    )
    x0 = reference_initial_state(
        vehicle,
        path,
        gains,
        initial_state=initial_state,
        speed=speed,
        feedforward=feedforward,
        steering_lag=steering_lag,
        delay=delay,
        pade_order=pade_order,
        model=model,
        tyre=tyre,
    )
    t = time_grid(duration, dt=dt)
    return ct.input_output_response(
        sys,
        t,
        initial_state=x0,
        solve_ivp_method="DOP853",
        solve_ivp_kwargs={"rtol": rtol, "atol": atol},
    )
