r"""Lateral controllers on one interface: the paper's law and the baselines.

Every controller maps the path-frame state of the rear-axle centre R — arc
length ``s``, lateral error ``e``, heading error ``theta`` — the path
curvature at ``s`` and the speed to the steering angles ``(delta_f,
delta_r)``, vectorised over runs (:class:`LateralController`). The fast
engine (:func:`~fws_control.simulate`) calls :meth:`~LateralController.steering`
on stacked arrays; the python-control reference wraps the same method in a
static :class:`control.NonlinearIOSystem` (:meth:`~LateralController.system`).
The vehicle's steering-angle limits are applied by the simulators after the
controller (:func:`saturate`).

Controllers (front steering with an optional rear ratio ``delta_r = ratio *
delta_f`` unless said otherwise):

:class:`StateFeedback`
    ``delta = delta_ff - K [e, theta]`` with a 2 x 2 ``K`` in python-control's
    sign and the curvature feedforward of eqs. (26)-(27). With ``K =
    gains.K`` it is the paper's law (:class:`~fws_control.SteeringGains` is
    accepted directly as its shorthand); with a full ``K`` it steers the
    rear axle independently (four-wheel-steering state feedback).
:class:`LQRController`
    :func:`control.lqr` on the linearised plant, with the paper's structure
    (one input ``B [1, a]^T``: a :class:`StateFeedback` of rank one) or with
    both steering inputs independent.
:class:`PurePursuit`
    Coulter (1992), *Implementation of the pure pursuit path tracking
    algorithm*, CMU-RI-TR-92-01: steer the rear axle's circle through a
    look-ahead point, ``delta_f = atan(2 f sin(alpha) / L_d)``.
:class:`Stanley`
    Thrun et al. (2006), *Stanley: the robot that won the DARPA Grand
    Challenge*, J. Field Robotics 23(9): front-axle heading and cross-track
    error, ``delta_f = -theta_f - atan(k e_f / (k_s + V))``.
:class:`RearWheelFeedback`
    Samson (1995), *Control of chained systems...*, IEEE TAC 40(1), as in
    PythonRobotics' ``rear_wheel_feedback``: a yaw-rate law at R,
    ``omega = V kappa cos(theta)/(1 - kappa e) - K_theta abs(V) theta -
    K_e V e sin(theta)/theta``, ``delta_f = atan(f omega / V)``.

Signs follow the library: ``e`` positive left of the path, ``theta = psi -
psi_C``, positive steering turns left.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from . import equations
from .controllers import FEEDFORWARDS
from .gains import SteeringGains
from .models import STEERING_INPUTS, check_inputs
from .plant import LateralPlant, as_plant, loop_matrices
from .validation import check_finite, check_positive, check_scalar, check_type
from .vehicle import Vehicle

if TYPE_CHECKING:
    # python-control costs 0.7 s to import; a simulation of these
    # controllers does not need it, so it is imported where it is used
    import control as ct

__all__ = [
    "LateralController",
    "StateFeedback",
    "LQRController",
    "PurePursuit",
    "Stanley",
    "RearWheelFeedback",
    "saturate",
    "as_controller",
    "CONTROLLER_SIGNALS",
]

#: Inputs of :meth:`LateralController.system`: the projection's outputs.
CONTROLLER_SIGNALS = ("s", "e", "theta", "curvature")

# Step of the central difference along the motion for the steering rate of
# controllers without an analytic rate (relative error ~1e-10).
_RATE_STEP = 1e-6


def saturate(vehicle: Vehicle, delta_f, delta_r) -> tuple[np.ndarray, np.ndarray]:
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
    #: ``k * sample_time + delay`` (zero-order hold), on the numpy engine.
    sample_time: float | None = None

    def compiled_law(self) -> tuple[str, tuple] | None:
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

    def _declared(self, cls, name: str, parameters: tuple) -> tuple[str, tuple] | None:
        # the compiled law of `cls`, unless a subclass changed the law
        if type(self).steering is not cls.steering:
            return None
        return name, parameters

    def steering(self, vehicle, path, *, s, e, theta, curvature, speed):
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
        self, vehicle, path, *, s, e, theta, curvature, speed, s_dot, e_dot, theta_dot
    ):
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
        h = _RATE_STEP
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

    def subset(self, idx) -> LateralController:
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
        self, vehicle: Vehicle, path, *, speed: float, name: str = "controller"
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


def _ratio_field(value) -> float | np.ndarray:
    return check_finite("ratio", value)


def _per_run(name: str, value, positive: bool = False):
    v = check_positive(name, value) if positive else check_finite(name, value)
    if np.ndim(v) > 1:
        raise ValueError(f"{name} must be a scalar or 1-D (one per run)")
    return v


@dataclass(frozen=True, eq=False)
class StateFeedback(LateralController):
    r"""Linear feedback on ``(e, theta)`` with the curvature feedforward.

    .. math::
        \begin{bmatrix}\delta_f\\ \delta_r\end{bmatrix} =
        \begin{bmatrix}\arctan(\kappa f)\\ 0\end{bmatrix}
        - \mathbf K\begin{bmatrix}e\\ \theta\end{bmatrix}

    (python-control's sign, ``u = -K y``). ``K = gains.K`` is the paper's
    law, eqs. (24)-(29); a full ``K`` steers the rear axle independently.

    Parameters
    ----------
    K : array_like
        Shape ``(2, 2)``: rows ``delta_f, delta_r``, columns ``e, theta``
        [rad/m, rad/rad].
    feedforward : bool, optional
        Add :math:`\arctan(\kappa f)` to the front angle (default True).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> g = fws.SteeringGains(0.1, 0.5, ratio=-1.0)
    >>> ctrl = fws.StateFeedback(g.K)
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> df, dr = ctrl.steering(veh, fws.Straight(), s=0.0, e=1.0, theta=0.0,
    ...                        curvature=0.0, speed=5.0)
    >>> float(df), float(dr)
    (-0.1, 0.1)
    """

    K: np.ndarray
    feedforward: bool = True
    label = "state feedback"

    def __post_init__(self) -> None:
        K = np.asarray(check_finite("K", self.K), dtype=float)
        if K.shape != (2, 2):
            raise ValueError(f"K must have shape (2, 2), got {K.shape}")
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "feedforward", bool(self.feedforward))

    @classmethod
    def from_gains(cls, gains: SteeringGains, *, feedforward: bool = True):
        """The paper's law with these (scalar) gains.

        Parameters
        ----------
        gains : SteeringGains
            Scalar gains.
        feedforward : bool, optional
            Curvature feedforward (default True).

        Returns
        -------
        StateFeedback
        """
        check_type("gains", gains, SteeringGains)
        return cls(np.asarray(gains.K, dtype=float), feedforward=feedforward)

    def subset(self, idx) -> StateFeedback:  # noqa: D102 - K is shared by all runs
        return self

    def runs(self) -> int | None:  # noqa: D102
        return None

    def compiled_law(self) -> tuple[str, tuple] | None:  # noqa: D102
        K = self.K
        ff = 1.0 if self.feedforward else 0.0
        params = (K[0, 0], K[0, 1], K[1, 0], K[1, 1], ff)
        return self._declared(StateFeedback, "state_feedback", params)

    def steering(self, vehicle, path, *, s, e, theta, curvature, speed):  # noqa: D102
        e = np.asarray(e, dtype=float)
        theta = np.asarray(theta, dtype=float)
        K = self.K
        df = equations.feedback_angle(e, theta, K[0, 0], K[0, 1])
        dr = equations.feedback_angle(e, theta, K[1, 0], K[1, 1])
        if self.feedforward:
            kappa = np.asarray(curvature, dtype=float)
            df = df + equations.feedforward_angle(vehicle.wheelbase, kappa)
        return df, dr

    def steering_rate(  # noqa: D102 - exact: linear law plus the feedforward's rate
        self, vehicle, path, *, s, e, theta, curvature, speed, s_dot, e_dot, theta_dot
    ):
        K = self.K
        e_dot = np.asarray(e_dot, dtype=float)
        theta_dot = np.asarray(theta_dot, dtype=float)
        rf = equations.feedback_angle(e_dot, theta_dot, K[0, 0], K[0, 1])
        rr = equations.feedback_angle(e_dot, theta_dot, K[1, 0], K[1, 1])
        if self.feedforward:
            s_arr = np.asarray(s, dtype=float)
            length = float(getattr(path, "length", math.inf))
            if math.isfinite(length) and not path.closed:
                s_arr = np.clip(s_arr, 0.0, length)
            kappa = np.asarray(curvature, dtype=float)
            kdot = np.asarray(path.curvature_rate(s_arr), dtype=float) * s_dot
            rf = rf + equations.feedforward_angle_rate(vehicle.wheelbase, kappa, kdot)
        return rf, rr


def LQRController(  # noqa: N802 - a constructor in the issue's naming
    plant: Any,
    *,
    Q,
    R,
    ratio: float | None = None,
    feedforward: bool = True,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> StateFeedback:
    r"""LQR state feedback from :func:`control.lqr` on the linearised plant.

    Minimises :math:`\int x^T Q x + u^T R u\,dt` with ``x = (e, theta)``.

    * ``ratio`` given: the paper's structure, one input
      :math:`\mathbf b = \mathbf B [1, a]^T`, ``R`` a scalar (or 1 x 1); the
      result is the paper's law with LQR gains (``K = [1, a]^T [k1, k2]``).
    * ``ratio=None``: both steering inputs independent, ``R`` 2 x 2; the
      result steers the rear axle with its own gains — a four-wheel-steering
      state feedback the paper's structure cannot express.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        A 2-state plant with states ``e, theta`` (see
        :mod:`fws_control.plant`).
    Q : array_like
        2 x 2 state weight (symmetric, >= 0).
    R : float or array_like
        Input weight (> 0): scalar with `ratio`, 2 x 2 without.
    ratio : float, optional
        Rear-to-front ratio of the structured design.
    feedforward : bool, optional
        Curvature feedforward (default True).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`~fws_control.linearize`.

    Returns
    -------
    StateFeedback
        ``K`` in python-control's sign; ``.label`` names the design.

    Examples
    --------
    >>> import numpy as np, control as ct, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0)
    >>> c = fws.LQRController(plant, Q=np.diag([1.0, 1.0]), R=np.eye(2))
    >>> sys = plant.linearize()
    >>> bool(np.all(np.linalg.eigvals(sys.A - sys.B @ c.K).real < 0))
    True
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    lm = loop_matrices(p)
    if lm.order != 2 or (isinstance(p, LateralPlant) and p.shape != ()):
        raise ValueError(
            "LQRController needs one operating point of a 2-state plant (e, theta)"
        )
    A = np.asarray(lm.A, dtype=float)
    B = np.column_stack([lm.B_front, lm.B_rear])
    Q = np.asarray(check_finite("Q", Q), dtype=float)
    if Q.shape != (2, 2):
        raise ValueError(f"Q must be 2 x 2, got shape {Q.shape}")
    if ratio is None:
        R = np.asarray(check_finite("R", R), dtype=float)
        if R.shape != (2, 2):
            raise ValueError(f"R must be 2 x 2 without ratio=, got shape {R.shape}")
        K = _lqr(A, B, Q, R, ratio)
        label = "LQR, independent rear"
    else:
        a = check_scalar("ratio", ratio)
        r = check_scalar("R", R)
        if r <= 0.0:
            raise ValueError(f"R must be a scalar > 0 with ratio=, got {R!r}")
        row = _lqr(A, B @ np.array([[1.0], [a]]), Q, np.array([[r]]), ratio)
        K = np.outer([1.0, a], np.asarray(row).ravel())
        label = f"LQR, a = {a:g}"
    ctrl = StateFeedback(np.asarray(K, dtype=float), feedforward=feedforward)
    object.__setattr__(ctrl, "label", label)
    return ctrl


def _lqr(A, B, Q, R, ratio):
    """control.lqr, its numerical failures named by the arguments."""
    import control as ct

    try:
        K, _, _ = ct.lqr(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        # e.g. R = 1e300: the Hamiltonian pencil has eigenvalues on the axis
        raise ValueError(
            f"no stabilising LQR solution for Q={Q.tolist()!r}, R={R.tolist()!r}, "
            f"ratio={ratio!r}: {exc}"
        ) from exc
    return K


@dataclass(frozen=True, eq=False, kw_only=True)
class PurePursuit(LateralController):
    r"""Pure pursuit (Coulter 1992) on the rear axle.

    The look-ahead point P is the path point at arc length
    :math:`s + \sqrt{L_d^2 - e^2}` (at distance :math:`L_d` from R on a
    straight path; PythonRobotics takes the first path sample at least
    :math:`L_d` away), :math:`\alpha` the angle of P seen from R relative to
    the heading, and

    .. math:: \delta_f = \arctan\frac{2 f \sin\alpha}{L_d},\qquad
              \delta_r = a\,\delta_f.

    Parameters
    ----------
    lookahead : float or array_like, optional
        Fixed look-ahead distance :math:`L_d` [m] (> 0), or the minimum when
        `lookahead_time` is given. Default 5 m.
    lookahead_time : float or array_like, optional
        Look-ahead time [s]: :math:`L_d = \max(\text{lookahead},\
        t_{la} |V|)`.
    ratio : float or array_like, optional
        Rear-to-front ratio :math:`a` (default 0: front steering).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> pp = fws.PurePursuit(lookahead=5.0)
    >>> df, dr = pp.steering(veh, fws.Straight(), s=0.0, e=1.0, theta=0.0,
    ...                      curvature=0.0, speed=5.0)
    >>> round(float(df), 6)     # atan(2 f sin(alpha)/L), sin(alpha) = -1/5
    -0.212732
    """

    lookahead: float | np.ndarray = 5.0
    lookahead_time: float | np.ndarray | None = None
    ratio: float | np.ndarray = 0.0
    label = "pure pursuit"

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "lookahead", _per_run("lookahead", self.lookahead, positive=True)
        )
        if self.lookahead_time is not None:
            object.__setattr__(
                self,
                "lookahead_time",
                _per_run("lookahead_time", self.lookahead_time, positive=True),
            )
        object.__setattr__(self, "ratio", _per_run("ratio", self.ratio))

    def distance(self, speed) -> np.ndarray:
        """Look-ahead distance :math:`L_d` [m] at `speed` [m/s].

        Parameters
        ----------
        speed : array_like
            Speed [m/s].

        Returns
        -------
        ndarray
        """
        ld = np.asarray(self.lookahead, dtype=float)
        if self.lookahead_time is not None:
            t_la = np.asarray(self.lookahead_time)
            ld = equations.lookahead_distance(ld, t_la, speed)
        return np.broadcast_to(ld, np.shape(speed)) if np.ndim(speed) else ld

    def compiled_law(self) -> tuple[str, tuple] | None:  # noqa: D102
        t_la = 0.0 if self.lookahead_time is None else self.lookahead_time
        params = (self.lookahead, t_la, self.ratio)
        return self._declared(PurePursuit, "pure_pursuit", params)

    def steering(self, vehicle, path, *, s, e, theta, curvature, speed):  # noqa: D102
        s = np.asarray(s, dtype=float)
        e = np.asarray(e, dtype=float)
        theta = np.asarray(theta, dtype=float)
        ld = self.distance(np.asarray(speed, dtype=float))
        sp = s + np.sign(speed) * equations.lookahead_offset(ld, e)
        length = float(getattr(path, "length", math.inf))
        if math.isfinite(length) and not path.closed:
            sp = np.clip(sp, 0.0, length)
            s = np.clip(s, 0.0, length)
        px, py = path.position(sp)
        cx, cy = path.position(s)
        h = np.asarray(path.heading(s), dtype=float)
        rx, ry = equations.rear_axle_point(np.asarray(cx), np.asarray(cy), h, e)
        df = equations.pure_pursuit_angle(
            vehicle.wheelbase, ld, rx, ry, theta + h, np.asarray(px), np.asarray(py)
        )
        return df, np.asarray(self.ratio) * df


@dataclass(frozen=True, eq=False, kw_only=True)
class Stanley(LateralController):
    r"""Stanley controller (Thrun et al. 2006) on the front axle.

    With :math:`e_f, \theta_f` the lateral and heading errors of the front
    axle centre F relative to its own nearest path point,

    .. math:: \delta_f = -\theta_f - \arctan\frac{k\,e_f}{k_s + |V|},
              \qquad \delta_r = a\,\delta_f.

    Parameters
    ----------
    gain : float or array_like, optional
        Cross-track gain :math:`k` [1/s], > 0 (default 1).
    softening : float, optional
        :math:`k_s` [m/s], >= 0, keeps the law finite at low speed
        (default 0.1).
    ratio : float or array_like, optional
        Rear-to-front ratio :math:`a` (default 0).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> st = fws.Stanley(gain=1.0, softening=0.0)
    >>> df, _ = st.steering(veh, fws.Straight(), s=0.0, e=1.0, theta=0.0,
    ...                     curvature=0.0, speed=5.0)
    >>> round(float(df), 6)      # -atan(1 * 1 / 5)
    -0.197396
    """

    gain: float | np.ndarray = 1.0
    softening: float = 0.1
    ratio: float | np.ndarray = 0.0
    label = "Stanley"

    def __post_init__(self) -> None:
        object.__setattr__(self, "gain", _per_run("gain", self.gain, positive=True))
        soft = check_scalar("softening", self.softening)
        if soft < 0:
            raise ValueError(f"softening must be >= 0 m/s, got {self.softening!r}")
        object.__setattr__(self, "softening", soft)
        object.__setattr__(self, "ratio", _per_run("ratio", self.ratio))

    def compiled_law(self) -> tuple[str, tuple] | None:  # noqa: D102
        params = (self.gain, self.softening, self.ratio)
        return self._declared(Stanley, "stanley", params)

    def steering(self, vehicle, path, *, s, e, theta, curvature, speed):  # noqa: D102
        s = np.asarray(s, dtype=float)
        e = np.asarray(e, dtype=float)
        theta = np.asarray(theta, dtype=float)
        length = float(getattr(path, "length", math.inf))
        open_path = math.isfinite(length) and not path.closed
        s_c = np.clip(s, 0.0, length) if open_path else s
        cx, cy = path.position(s_c)
        h = np.asarray(path.heading(s_c), dtype=float)
        f = vehicle.wheelbase
        fx, fy, psi = equations.front_axle_point(
            np.asarray(cx), np.asarray(cy), h, e, theta, f
        )
        # the projection's Newton iteration starts a wheelbase ahead
        guess = s_c + f * np.cos(theta)
        if open_path:
            guess = np.clip(guess, 0.0, length)
        proj = path.project(fx, fy, s_guess=guess)
        theta_f = equations.wrap_angle(psi - np.asarray(proj.heading))
        df = equations.stanley_angle(
            theta_f, proj.e, np.asarray(self.gain), self.softening,
            np.asarray(speed, dtype=float),
        )  # fmt: skip
        return df, np.asarray(self.ratio) * df


@dataclass(frozen=True, eq=False, kw_only=True)
class RearWheelFeedback(LateralController):
    r"""Rear-wheel feedback (Samson 1995; PythonRobotics' rear_wheel_feedback).

    .. math::
        \omega = \frac{V\kappa\cos\theta}{1-\kappa e} - K_\theta |V|\theta
                 - K_e V e\,\frac{\sin\theta}{\theta},\qquad
        \delta_f = \arctan\frac{f\,\omega}{V},\qquad \delta_r = a\,\delta_f.

    Linearised on a straight road it is the paper's ``a = 0`` law with
    ``k1 = f K_e``, ``k2 = f K_theta``.

    Parameters
    ----------
    k_e : float or array_like, optional
        Lateral-error gain :math:`K_e` [1/m^2], > 0 (default 0.05).
    k_theta : float or array_like, optional
        Heading gain :math:`K_\theta` [1/m], > 0 (default 0.2).
    ratio : float or array_like, optional
        Rear-to-front ratio :math:`a` (default 0).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> rw = fws.RearWheelFeedback(k_e=0.1, k_theta=0.5)
    >>> df, _ = rw.steering(veh, fws.Straight(), s=0.0, e=0.0, theta=0.1,
    ...                     curvature=0.0, speed=5.0)
    >>> round(float(df), 6)      # atan(f * (-K_theta * V * 0.1) / V)
    -0.134189
    """

    k_e: float | np.ndarray = 0.05
    k_theta: float | np.ndarray = 0.2
    ratio: float | np.ndarray = 0.0
    label = "rear-wheel feedback"

    def __post_init__(self) -> None:
        object.__setattr__(self, "k_e", _per_run("k_e", self.k_e, positive=True))
        object.__setattr__(
            self, "k_theta", _per_run("k_theta", self.k_theta, positive=True)
        )
        object.__setattr__(self, "ratio", _per_run("ratio", self.ratio))

    def compiled_law(self) -> tuple[str, tuple] | None:  # noqa: D102
        params = (self.k_e, self.k_theta, self.ratio)
        return self._declared(RearWheelFeedback, "rear_wheel_feedback", params)

    def steering(self, vehicle, path, *, s, e, theta, curvature, speed):  # noqa: D102
        df = equations.rear_wheel_feedback_angle(
            np.asarray(speed, dtype=float), vehicle.wheelbase,
            np.asarray(curvature, dtype=float), np.asarray(e, dtype=float),
            np.asarray(theta, dtype=float), np.asarray(self.k_e),
            np.asarray(self.k_theta),
        )  # fmt: skip
        return df, np.asarray(self.ratio) * df


def as_controller(gains: Any, *, feedforward: bool = True):
    """Return `gains` unchanged if it is a controller or SteeringGains.

    Parameters
    ----------
    gains : LateralController or SteeringGains
        The controller argument of the simulators.
    feedforward : bool, optional
        Unused for controllers (they carry their own); kept for the
        simulators' uniform call.

    Returns
    -------
    LateralController or SteeringGains

    Raises
    ------
    TypeError
        For anything else.

    Examples
    --------
    >>> import fws_control as fws
    >>> fws.as_controller(fws.PurePursuit()).label
    'pure pursuit'
    """
    if not (
        isinstance(feedforward, (bool, np.bool_))
        or (isinstance(feedforward, str) and feedforward in FEEDFORWARDS)
    ):
        raise TypeError(
            f"feedforward must be True, False or one of {FEEDFORWARDS}, got "
            f"{feedforward!r}"
        )
    if isinstance(gains, (LateralController, SteeringGains)):
        return gains
    raise TypeError(
        "gains must be a SteeringGains or a lateral controller (e.g. "
        f"fws.PurePursuit()), got {type(gains).__name__}"
    )
