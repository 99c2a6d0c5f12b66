r"""The closed loop as a python-control interconnection: the reference.

A second, independent implementation of the loop that
:func:`~fws_control.simulation.simulate` integrates: the global-frame
vehicle (eqs. 8-10), a projection block that maps ``(x, y, psi)`` to the
path errors ``(s, e, theta)`` and the curvature (eqs. 14-16), the controller
(eqs. 24-29) and, for a rate-limited vehicle, the steering actuator, joined
with :func:`control.interconnect` and simulated with
:func:`control.input_output_response`. It is slower than the engine (a
projection per right-hand-side call, signal passing between the blocks) and
serves as its reference in the tests, and as a composable starting point
for loops the engine does not cover.
"""

from __future__ import annotations

import control as ct
import numpy as np

from ..controllers import path_tracking_controller, steering_actuator
from ..gains import SteeringGains
from ..models import global_frame_model
from ..paths import Path
from ..validation import check_nonzero, check_scalar, check_type
from ..vehicle import Vehicle
from .engine import resolve_time_constant

__all__ = ["closed_loop_system", "projection_system"]


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


def closed_loop_system(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains,
    *,
    speed: float,
    feedforward: bool = True,
    actuator_time_constant: float | None = None,
) -> ct.InterconnectedSystem:
    r"""The closed loop as a python-control interconnection (the reference).

    Blocks: :func:`~fws_control.global_frame_model` (states ``x, y, psi``),
    :func:`projection_system`, :func:`~fws_control.path_tracking_controller`
    and, if the vehicle has a steering-rate limit,
    :func:`~fws_control.steering_actuator` (states ``delta_f, delta_r``
    appended after the vehicle's).

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
    feedforward : bool, optional
        Include the curvature feedforward (default), as in
        :func:`~fws_control.simulation.simulate`.
    actuator_time_constant : float, optional
        Actuator lag [s] for a rate-limited vehicle, as in
        :func:`~fws_control.simulation.simulate`.

    Returns
    -------
    control.InterconnectedSystem
        No inputs; outputs ``x, y, psi, s, e, theta, curvature, delta_f,
        delta_r``. Simulate it with :func:`control.input_output_response`;
        the initial state is ``(x_R, y_R, psi)`` (followed by the initial
        steering angles when an actuator is present).

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
    check_type("vehicle", vehicle, Vehicle)
    speed = check_scalar("speed", check_nonzero("speed", speed))
    tau = resolve_time_constant(vehicle, actuator_time_constant)
    veh_sys = global_frame_model(vehicle, speed=speed, name="vehicle")
    proj = projection_system(path, name="projection")
    ctrl = path_tracking_controller(
        vehicle, gains, feedforward=bool(feedforward), name="controller"
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
    if tau is None:
        steer = "controller"
    else:
        syslist.append(steering_actuator(vehicle, time_constant=tau, name="actuator"))
        connections += [
            ["actuator.delta_f_cmd", "controller.delta_f"],
            ["actuator.delta_r_cmd", "controller.delta_r"],
        ]
        steer = "actuator"
    connections += [
        ["vehicle.delta_f", f"{steer}.delta_f"],
        ["vehicle.delta_r", f"{steer}.delta_r"],
    ]
    outlist = [
        "vehicle.x",
        "vehicle.y",
        "vehicle.psi",
        "projection.s",
        "projection.e",
        "projection.theta",
        "projection.curvature",
        f"{steer}.delta_f",
        f"{steer}.delta_r",
    ]
    return ct.interconnect(
        syslist,
        connections=connections,
        inplist=[],
        outlist=outlist,
        outputs=["x", "y", "psi", "s", "e", "theta", "curvature", "delta_f", "delta_r"],
        name="closed_loop",
    )
