r"""The paper's law and the baseline controllers, on one interface.

Every controller here implements
:class:`~fws_control.lateral_controller.LateralController`: it maps the
path-frame state of the rear-axle centre R — arc length ``s``, lateral error
``e``, heading error ``theta`` — the path curvature at ``s`` and the speed
to the steering angles ``(delta_f, delta_r)``, vectorised over runs. The
vehicle's steering-angle limits are applied by the simulators after the
controller (:func:`~fws_control.lateral_controller.saturate`).

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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from . import equations
from .controllers import FEEDFORWARDS
from .equations import Real
from .gains import SteeringGains
from .hints import FeedforwardLike, RealArrayLike

# the interface's other names, importable from here too
from .lateral_controller import CONTROLLER_SIGNALS as CONTROLLER_SIGNALS  # noqa: F401
from .lateral_controller import LateralController
from .lateral_controller import saturate as saturate  # noqa: F401
from .plant import LateralPlant, as_plant, loop_matrices
from .validation import check_finite, check_positive, check_scalar, check_type
from .vehicle import Vehicle

if TYPE_CHECKING:
    from .paths import Path

__all__ = [
    "StateFeedback",
    "LQRController",
    "PurePursuit",
    "Stanley",
    "RearWheelFeedback",
    "as_controller",
]


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
    def from_gains(
        cls, gains: SteeringGains, *, feedforward: bool = True
    ) -> StateFeedback:
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

    def subset(self, idx: Sequence[int] | np.ndarray) -> StateFeedback:  # noqa: D102 - K is shared by all runs
        return self

    def runs(self) -> int | None:  # noqa: D102
        return None

    def compiled_law(self) -> tuple[str, tuple[Any, ...]] | None:  # noqa: D102
        K = self.K
        ff = 1.0 if self.feedforward else 0.0
        params = (K[0, 0], K[0, 1], K[1, 0], K[1, 1], ff)
        return self._declared(StateFeedback, "state_feedback", params)

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
    ) -> tuple[Real, Real]:  # noqa: D102
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
    Q: RealArrayLike,
    R: RealArrayLike,
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
    """The LQR gain ``K = R^-1 B^T P``, its failures named by the arguments.

    ``P`` is the stabilising solution of the continuous algebraic Riccati
    equation (:func:`scipy.linalg.solve_continuous_are`): what
    :func:`control.lqr` computes without slycot, without importing
    python-control, which ``fws-control compare`` would otherwise import for
    its two LQR rows alone (``tests/test_baselines.py`` checks the gains
    against :func:`control.lqr`).
    """
    from scipy.linalg import solve_continuous_are

    for name, M in (("Q", Q), ("R", R)):
        if np.any(np.abs(M - M.T) > np.finfo(float).eps * max(1.0, np.max(np.abs(M)))):
            raise ValueError(f"{name} must be symmetric, got {M.tolist()!r}")
    try:
        P = solve_continuous_are(A, B, Q, R)
        K = np.linalg.solve(R, B.T @ P)
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

    def distance(self, speed: RealArrayLike) -> np.ndarray:
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
            ld = np.asarray(
                equations.lookahead_distance(ld, t_la, np.asarray(speed, dtype=float))
            )
        return np.broadcast_to(ld, np.shape(speed)) if np.ndim(speed) else ld

    def compiled_law(self) -> tuple[str, tuple[Any, ...]] | None:  # noqa: D102
        t_la = 0.0 if self.lookahead_time is None else self.lookahead_time
        params = (self.lookahead, t_la, self.ratio)
        return self._declared(PurePursuit, "pure_pursuit", params)

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
    ) -> tuple[Real, Real]:  # noqa: D102
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

    def compiled_law(self) -> tuple[str, tuple[Any, ...]] | None:  # noqa: D102
        params = (self.gain, self.softening, self.ratio)
        return self._declared(Stanley, "stanley", params)

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
    ) -> tuple[Real, Real]:  # noqa: D102
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

    def compiled_law(self) -> tuple[str, tuple[Any, ...]] | None:  # noqa: D102
        params = (self.k_e, self.k_theta, self.ratio)
        return self._declared(RearWheelFeedback, "rear_wheel_feedback", params)

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
    ) -> tuple[Real, Real]:  # noqa: D102
        df = equations.rear_wheel_feedback_angle(
            np.asarray(speed, dtype=float), vehicle.wheelbase,
            np.asarray(curvature, dtype=float), np.asarray(e, dtype=float),
            np.asarray(theta, dtype=float), np.asarray(self.k_e),
            np.asarray(self.k_theta),
        )  # fmt: skip
        return df, np.asarray(self.ratio) * df


def as_controller(
    gains: Any, *, feedforward: FeedforwardLike = True
) -> LateralController | SteeringGains:
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
