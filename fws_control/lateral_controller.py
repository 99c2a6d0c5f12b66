r"""The interface of a lateral controller, :class:`LateralController`.

A lateral controller maps the path-frame state of the rear-axle centre R
(arc length ``s``, lateral error ``e``, heading error ``theta``), the path
curvature at ``s`` and the speed to the steering angles ``(delta_f,
delta_r)``, vectorised over runs. The fast engine
(:func:`~fws_control.simulate`) calls :meth:`~LateralController.steering` on
stacked arrays; the python-control reference wraps the same method in a
static :class:`control.NonlinearIOSystem` (:meth:`~LateralController.system`).
The vehicle's steering-angle limits are applied by the simulators after the
controller (:func:`saturate`). The paper's law and the baseline controllers
that implement it are in :mod:`fws_control.baselines`; the model predictive
controller is in :mod:`fws_control.mpc`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .equations import Real
from .hints import RealArrayLike
from .kinematic_models import STEERING_INPUTS, check_inputs
from .validation import check_type
from .vehicle import Vehicle

if TYPE_CHECKING:
    # python-control costs 0.7 s to import; a simulation of these
    # controllers does not need it, so it is imported where it is used
    import control as ct

    from .paths import Path

__all__ = ["LateralController", "saturate", "CONTROLLER_SIGNALS", "RATE_STEP"]

#: Inputs of :meth:`LateralController.system`: the projection's outputs.
CONTROLLER_SIGNALS = ("s", "e", "theta", "curvature")

#: Step [s] of the central difference along the motion that gives the
#: steering rate of controllers without an analytic rate
#: (:meth:`LateralController.steering_rate`; relative error about 1e-10).
RATE_STEP = 1e-6


def saturate(
    vehicle: Vehicle, delta_f: RealArrayLike, delta_r: RealArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Clip the steering angles to the vehicle's angle limits (where set).

    Parameters
    ----------
    vehicle : Vehicle
        Its ``max_steer_front`` / ``max_steer_rear`` [rad] (None: no limit).
    delta_f, delta_r : array_like
        Commanded angles [rad], real; a scalar must be finite, a
        non-finite array element gives a non-finite element in its place
        (as in :func:`~fws_control.steering_command`).

    Returns
    -------
    (ndarray, ndarray)

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(2.7, 1.35, max_steer_front=0.5)
    >>> [float(v) for v in fws.saturate(veh, 0.7, -0.7)]
    [0.5, -0.7]
    """
    check_type("vehicle", vehicle, Vehicle)
    # real numbers; a non-finite scalar refused, non-finite array elements
    # (stopped runs of a batch) kept in place, as in steering_command
    df, dr = check_inputs(delta_f=delta_f, delta_r=delta_r)
    if vehicle.max_steer_front is not None:
        df = np.clip(df, -vehicle.max_steer_front, vehicle.max_steer_front)
    if vehicle.max_steer_rear is not None:
        dr = np.clip(dr, -vehicle.max_steer_rear, vehicle.max_steer_rear)
    return df, dr


class LateralController:
    """Interface of a lateral controller (subclasses are frozen dataclasses).

    A static law implements :meth:`steering`; it may override
    :meth:`steering_rate` with an analytic rate (the default is a central
    difference along the motion). Array-valued parameters hold one value per
    run and are indexed by :meth:`subset`. A sampled controller declares a
    :attr:`sample_time` instead.

    Examples
    --------
    A proportional law on the lateral error only:

    >>> from dataclasses import dataclass
    >>> import fws_control as fws
    >>> @dataclass(frozen=True)
    ... class LateralOnly(fws.LateralController):
    ...     k: float = 0.1
    ...     def steering(self, vehicle, path, *, s, e, theta, curvature, speed):
    ...         return -self.k * e, 0.0 * e
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> res = fws.simulate(plant, fws.Straight(), LateralOnly(),
    ...                    initial_state=(0.0, 1.0, 0.0), duration=1.0)
    >>> round(float(res.delta_f[0]), 6)
    -0.1
    """

    #: Short name used in tables and legends.
    label = "controller"

    #: Sample time [s] of a sampled controller; ``None`` (here): a static law,
    #: evaluated at every solver stage. A sampled controller (e.g.
    #: :class:`~fws_control.MPCController`) sets it and implements
    #: ``start(vehicle, path, *, speed)``, which returns the state of one run
    #: with a method ``step(*, s, e, theta) -> (delta_f, delta_r)``.
    #: :func:`~fws_control.simulate` calls ``step`` with the state at the
    #: sample times ``k * sample_time`` (the initial state for the samples at
    #: or before the start) and holds each command for one sample time from
    #: ``k * sample_time + delay`` (zero-order hold), on either engine.
    sample_time: float | None = None

    def compiled_law(self) -> tuple[str, tuple[Any, ...]] | None:
        """The law as the compiled engine runs it, or None (numpy engine).

        A controller whose :meth:`steering` is one of the compiled laws
        declares it here as ``(name, parameters)``: `name` one of
        :data:`fws_control.simulation.compiled_laws.LAWS`, `parameters` a
        tuple of at most six numbers or arrays of shape ``(n,)`` (one value
        per run), in that law's order. The compiled law and :meth:`steering`
        are written with the same functions of :mod:`fws_control.equations`;
        the compiled engine reads the path's position and heading from a
        table (:func:`~fws_control.simulation.compiled_laws.geometry_table`).
        A subclass that overrides :meth:`steering` without declaring its own
        compiled law gets None. Default: None.

        Returns
        -------
        tuple or None

        Examples
        --------
        >>> import fws_control as fws
        >>> fws.Stanley(gain=2.0).compiled_law()
        ('stanley', (2.0, 0.1, 0.0))
        """
        return None

    def _declared(
        self, cls: type[LateralController], name: str, parameters: tuple[Any, ...]
    ) -> tuple[str, tuple[Any, ...]] | None:
        # the compiled law of `cls`, unless a subclass changed the law
        if type(self).steering is not cls.steering:
            return None
        return name, parameters

    def steering(
        self,
        vehicle: Vehicle,
        path: Path,
        *,
        s: RealArrayLike,
        e: RealArrayLike,
        theta: RealArrayLike,
        curvature: RealArrayLike,
        speed: RealArrayLike,
    ) -> tuple[Real, Real]:
        """Steering angles ``(delta_f, delta_r)`` [rad], before saturation.

        Parameters
        ----------
        vehicle : Vehicle
            Geometry (wheelbase ``f``).
        path : Path
            The reference path (look-ahead controllers read its geometry).
        s, e, theta : ndarray
            Path-frame state of R: arc length [m], lateral error [m], heading
            error [rad]; one entry per run.
        curvature : ndarray
            Path curvature at ``s`` [1/m].
        speed : ndarray
            Speed [m/s].

        Returns
        -------
        (ndarray, ndarray)
        """
        raise NotImplementedError

    def steering_rate(
        self,
        vehicle: Vehicle,
        path: Path,
        *,
        s: RealArrayLike,
        e: RealArrayLike,
        theta: RealArrayLike,
        curvature: RealArrayLike,
        speed: RealArrayLike,
        s_dot: RealArrayLike,
        e_dot: RealArrayLike,
        theta_dot: RealArrayLike,
    ) -> tuple[Real, Real]:
        """Time derivative of :meth:`steering` along the motion [rad/s].

        Default: a central difference of :meth:`steering` at ``state ± h
        state_dot`` with ``h = 1e-6 s`` (the curvature re-read at the moved
        ``s``).

        Parameters
        ----------
        vehicle, path, s, e, theta, curvature, speed
            As in :meth:`steering`.
        s_dot, e_dot, theta_dot : ndarray
            Time derivatives of the path-frame state.

        Returns
        -------
        (ndarray, ndarray)
        """
        h = RATE_STEP
        s = np.asarray(s, dtype=float)
        s_dot = np.asarray(s_dot, dtype=float)
        length = float(getattr(path, "length", math.inf))
        open_path = math.isfinite(length) and not getattr(path, "closed", False)
        # one-sided at the ends of an open path, where the other point would
        # be clipped onto the end (and the arc-length part of the rate lost)
        fwd = bwd = np.ones(np.shape(s), dtype=bool)
        if open_path:
            fwd = s + h * np.abs(s_dot) <= length
            bwd = s - h * np.abs(s_dot) >= 0.0
        vals = {}
        for step in (-1.0, 0.0, 1.0):
            ss = s + step * h * s_dot
            vals[step] = self.steering(
                vehicle,
                path,
                s=ss,
                e=np.asarray(e) + step * h * np.asarray(e_dot),
                theta=np.asarray(theta) + step * h * np.asarray(theta_dot),
                curvature=_curvature_at(path, ss),
                speed=speed,
            )
        out = []
        for ch in (0, 1):
            fp, f0, fm = (
                np.asarray(vals[k][ch], dtype=float) for k in (1.0, 0.0, -1.0)
            )
            central = (fp - fm) / (2 * h)
            if open_path:
                ahead = s_dot >= 0
                # which neighbour lies off the path: use the other one-sidedly
                lost_fp = np.where(ahead, ~fwd, ~bwd)
                lost_fm = np.where(ahead, ~bwd, ~fwd)
                central = np.where(lost_fp, (f0 - fm) / h, central)
                central = np.where(lost_fm & ~lost_fp, (fp - f0) / h, central)
            out.append(central)
        return out[0], out[1]

    def subset(self, idx: Sequence[int] | np.ndarray) -> LateralController:
        """The controller of the runs `idx` (array parameters indexed).

        Parameters
        ----------
        idx : array_like of int
            Run indices.

        Returns
        -------
        LateralController
        """
        changes = {}
        for f in fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            if isinstance(v, np.ndarray) and v.ndim == 1:
                changes[f.name] = v[idx]
        return replace(self, **changes) if changes else self  # type: ignore[type-var]

    def runs(self) -> int | None:
        """Number of runs the array parameters hold (None: scalars only)."""
        sizes = {
            getattr(self, f.name).shape[0]
            for f in fields(self)  # type: ignore[arg-type]
            if isinstance(getattr(self, f.name), np.ndarray)
            and getattr(self, f.name).ndim == 1
        }
        if len(sizes) > 1:
            raise ValueError(f"array parameters of different lengths {sorted(sizes)}")
        return sizes.pop() if sizes else None

    def system(
        self, vehicle: Vehicle, path: Path, *, speed: float, name: str = "controller"
    ) -> ct.NonlinearIOSystem:
        """The controller as a static :class:`control.NonlinearIOSystem`.

        Inputs ``s, e, theta, curvature`` (the outputs of
        :func:`~fws_control.simulation.projection_system`); outputs
        ``delta_f, delta_r`` (saturated to the vehicle's angle limits).

        Parameters
        ----------
        vehicle : Vehicle
            Geometry and limits.
        path : Path
            The reference path.
        speed : float
            Speed [m/s].
        name : str, optional
            System name.

        Returns
        -------
        control.NonlinearIOSystem
        """

        def output(t, x, u, params):
            df, dr = self.steering(
                vehicle,
                path,
                s=np.array([u[0]]),
                e=np.array([u[1]]),
                theta=np.array([u[2]]),
                curvature=np.array([u[3]]),
                speed=np.array([speed]),
            )
            df, dr = saturate(vehicle, df, dr)
            return np.array([float(np.ravel(df)[0]), float(np.ravel(dr)[0])])

        import control as ct

        return ct.nlsys(
            None,
            output,
            inputs=list(CONTROLLER_SIGNALS),
            outputs=list(STEERING_INPUTS),
            name=name,
        )


def _curvature_at(path, s):
    s = np.asarray(s, dtype=float)
    length = float(getattr(path, "length", math.inf))
    if math.isfinite(length) and not getattr(path, "closed", False):
        s = np.clip(s, 0.0, length)
    return np.broadcast_to(np.asarray(path.curvature(s), dtype=float), s.shape)
