r"""Plants: the operating-point object and how any python-control plant is read.

Every analysis utility of the library takes the plant first. A plant is

* a :class:`LateralPlant`: the kinematic 4WS vehicle at an operating point
  (speed, path curvature, linearisation model);
* a :class:`control.StateSpace` of any order whose inputs include
  ``delta_f`` and ``delta_r`` and whose outputs (or, failing that, states)
  include ``e`` and ``theta``; a 2-state, 2-input system that carries
  python-control's default names is read as states ``(e, theta)`` and
  inputs ``(delta_f, delta_r)``;
* a :class:`Vehicle` with the keyword-only ``speed=``, ``curvature=`` and
  ``model=``, a shorthand for the :class:`LateralPlant`.

:func:`loop_matrices` reduces each of them to the matrices of the structured
loop

.. math::
    \dot x = \mathbf A x + \mathbf B_f\,\delta_f + \mathbf B_r\,\delta_r,\qquad
    e = \mathbf c_e x,\quad \theta = \mathbf c_\theta x,

which the characteristic-polynomial engine (:mod:`fws_control.linear`) closes
with :math:`\delta_f = -k_1 e - k_2\theta`, :math:`\delta_r = a\,\delta_f`.
"""

from __future__ import annotations

import re
import sys
from dataclasses import KW_ONLY, dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .dynamics import TYRES, dynamic_feedforward, path_jacobians, require_dynamics
from .hints import ModelName, RealArrayLike, TyreName
from .kinematic_models import STEERING_INPUTS, feedforward_steering
from .reprs import summary_repr, value_repr
from .validation import (
    MAX_CURVATURE,
    MAX_SPEED,
    check_finite,
    check_magnitude,
    check_model,
    check_nonzero,
    check_positive,
    check_type,
)
from .vehicle import Vehicle

if TYPE_CHECKING:  # imported where needed: ~1 s of start-up (see _control_class)
    import control as ct

__all__ = [
    "LateralPlant",
    "LoopMatrices",
    "as_plant",
    "loop_matrices",
    "resolve_ratio",
    "LINEAR_STATES",
    "DYNAMIC_LINEAR_STATES",
    "PLANT_KEYWORDS",
]

#: Names of the states (and outputs) of the kinematic linear plant.
LINEAR_STATES = ("e", "theta")

#: Names of the states of the dynamic linear plant (``model="dynamic"``).
DYNAMIC_LINEAR_STATES = ("e", "theta", "v_y", "r")

#: The keywords that turn a :class:`Vehicle` into a :class:`LateralPlant`.
PLANT_KEYWORDS = ("speed", "curvature", "model")

# python-control's generated signal names: u[0], x[1], y[2], ...
_DEFAULT_NAME = re.compile(r"^[uxy]\[\d+\]$")


@value_repr
@dataclass(frozen=True, eq=False)
class LateralPlant:
    r"""The 4WS vehicle at an operating point (a plant).

    The operating point is the feedforward equilibrium on a path of constant
    curvature: ``e = theta = 0``, :math:`\delta_f = \arctan(\kappa f)`,
    :math:`\delta_r = 0` (paper eqs. 26-27) for the kinematic models. The
    kinematic linearisation is

    .. math::
        \mathbf A = \begin{bmatrix}0 & V\\ -V\kappa^2 & 0\end{bmatrix},\quad
        \mathbf B = \begin{bmatrix}0 & V\\ cV/f & -V/f\end{bmatrix},

    with :math:`c = 1 + f^2\kappa^2` for ``model="kinematic"`` (the Jacobian
    of eqs. 18-19) and :math:`c = 1` for ``model="paper"`` (eq. 33, exact only
    on a straight path).

    ``model="dynamic"`` linearises the dynamic single-track model
    (:mod:`fws_control.dynamics`, tyre slip, states ``e, theta, v_y, r``) at
    its own equilibrium ``e = theta = 0`` on the curve, reached with the
    front *and* rear angles of :func:`~fws_control.dynamics.dynamic_feedforward`
    (the kinematic feedforward leaves an offset there); inputs are deviations
    from those angles. The matrices are
    :func:`~fws_control.dynamics.path_jacobians`. The paper's controller with
    the kinematic feedforward adds a constant input offset to this plant; its
    steady state is :func:`~fws_control.steady_state_offset`.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed : float or array_like
        Speed :math:`V` [m/s], nonzero with magnitude <= ``MAX_SPEED``
        (1e6 m/s; negative: reversing).
    curvature : float or array_like, optional
        Path curvature :math:`\kappa_C` [1/m], default 0 (straight path),
        magnitude <= ``MAX_CURVATURE`` (1e6 1/m).
    model : {"kinematic", "paper", "dynamic"}, optional
        Linearisation, default ``"kinematic"`` (the exact Jacobian of the
        kinematic model). ``"paper"`` and ``"kinematic"`` are two
        linearisations of the same nonlinear kinematic model, which is what
        :func:`~fws_control.simulate` integrates for either. ``"dynamic"``
        needs the vehicle's mass, yaw inertia and cornering stiffnesses and a
        `speed` > 0 (forward driving). The former name ``"exact"`` of
        ``"kinematic"`` is accepted with a :class:`FutureWarning` until
        fws_control 0.4 (the plant's `model` then reads ``"kinematic"``).
    steering_lag : float or (float, float) or None, optional
        Time constants :math:`T_f, T_r` [s] of a first-order lag between the
        steering command and the wheel angle,
        :math:`T\dot\delta = \delta_{cmd} - \delta`; one number for both
        axles, a pair for (front, rear), ``None`` (default) for none. With a
        lag the plant has four states ``e, theta, delta_f_act, delta_r_act``
        (the wheel angles) and its inputs ``delta_f, delta_r`` are the
        commands; the analysis then goes through the general engine (no
        double-root design: two gains cannot place four poles). Rate limits
        remain a matter of the simulation, which runs one time constant for
        both axles (a pair of different lags raises there). ``None`` in the
        simulation: an actuator only if the vehicle has a rate limit, with
        :data:`~fws_control.controllers.DEFAULT_ACTUATOR_TIME_CONSTANT`.
    tyre : {"linear", "magic"}, optional
        Tyre model of ``model="dynamic"`` (default ``"linear"``; ``"magic"``
        needs the vehicle's friction). The kinematic models take only
        ``"linear"`` (they have no tyres).

    Raises
    ------
    TypeError
        If `vehicle` is not a :class:`Vehicle`.
    ValueError
        For a zero or non-finite `speed`, a non-finite `curvature`, an
        unknown `model` or `tyre`, or (``model="dynamic"``) missing vehicle
        data, a negative speed or a curve the tyres cannot hold.

    Notes
    -----
    `speed` and `curvature` broadcast against each other (and against the
    gains in the analysis functions), like the fields of
    :class:`SteeringGains`: one object can hold a whole sweep of operating
    points.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    >>> sys = plant.linearize()
    >>> sys.input_labels, sys.output_labels
    (['delta_f', 'delta_r'], ['e', 'theta'])
    >>> sys.B.round(4)
    array([[ 0.    ,  5.    ],
           [ 1.9869, -1.8519]])
    >>> round(plant.input_gain_factor, 4)
    1.0729
    """

    vehicle: Vehicle
    speed: float | np.ndarray
    # after the speed every field is keyword-only: LateralPlant(veh, 5.0, 0.1)
    # must not silently mean a curvature
    _: KW_ONLY
    curvature: float | np.ndarray = 0.0
    model: ModelName = "kinematic"
    steering_lag: float | tuple[float, float] | None = None
    tyre: TyreName = "linear"

    def __post_init__(self) -> None:
        check_type("vehicle", self.vehicle, Vehicle)
        object.__setattr__(self, "model", check_model(self.model))
        if not isinstance(self.tyre, str) or self.tyre not in TYRES:
            raise ValueError(f"tyre must be one of {TYRES}, got {self.tyre!r}")
        if self.model == "dynamic":
            require_dynamics(self.vehicle, tyre=self.tyre)
        elif self.tyre != "linear":
            raise ValueError(
                f"tyre={self.tyre!r} applies only to model='dynamic'; the "
                f"{self.model!r} model is kinematic (no tyres)"
            )
        if self.steering_lag is not None:
            lag = self.steering_lag
            pair = (lag, lag) if np.ndim(lag) == 0 else tuple(np.ravel(lag))
            if len(pair) != 2:
                raise ValueError(
                    "steering_lag must be one time constant or a (front, rear) "
                    f"pair [s], got {lag!r}"
                )
            pair = tuple(float(check_positive("steering_lag", v)) for v in pair)
            object.__setattr__(self, "steering_lag", pair)
        # magnitudes bounded so that V^2 kappa^2 and the entries of A, B stay
        # finite (validation.MAX_SPEED, MAX_CURVATURE)
        speed = check_nonzero("speed", self.speed)
        speed = check_magnitude("speed", speed, MAX_SPEED, "m/s")
        curvature = check_magnitude("curvature", self.curvature, MAX_CURVATURE, "1/m")
        try:
            np.broadcast_shapes(np.shape(speed), np.shape(curvature))
        except ValueError:
            raise ValueError(
                "speed and curvature must broadcast, got shapes "
                f"{np.shape(speed)} and {np.shape(curvature)}"
            ) from None
        if self.model == "dynamic":
            # the operating point must exist: raises for a curve the tyres
            # cannot hold, or a speed <= 0
            dynamic_feedforward(
                self.vehicle, speed=speed, curvature=curvature, tyre=self.tyre
            )
        object.__setattr__(self, "speed", speed)
        object.__setattr__(self, "curvature", curvature)

    @property
    def shape(self) -> tuple[int, ...]:
        """Broadcast shape of `speed` and `curvature` (``()`` for one point)."""
        return np.broadcast_shapes(np.shape(self.speed), np.shape(self.curvature))

    @property
    def input_gain_factor(self) -> float | np.ndarray:
        r"""Factor :math:`c` of the front-steering entry :math:`cV/f` of B.

        :math:`c = 1 + f^2\kappa^2` (kinematic) or 1 (paper, eq. 33).

        Raises
        ------
        ValueError
            For ``model="dynamic"``, whose B has no such entry.
        """
        if self.model == "dynamic":
            raise ValueError(
                "input_gain_factor is defined for model='kinematic' or 'paper', "
                "not for model='dynamic' (its B comes from the tyre forces)"
            )
        kappa = np.asarray(self.curvature, dtype=float)
        if self.model == "paper":
            out = np.ones_like(kappa)
        else:
            out = 1.0 + (self.vehicle.wheelbase * kappa) ** 2
        return float(out) if out.ndim == 0 else out

    @property
    def feedforward(self) -> float | np.ndarray:
        r"""Feedforward front angle :math:`\arctan(\kappa f)` [rad], eq. (26)."""
        return feedforward_steering(self.vehicle, curvature=self.curvature)

    @property
    def operating_point(self) -> tuple[float | np.ndarray, float | np.ndarray]:
        r"""Steering angles ``(delta_f, delta_r)`` [rad] of the operating point.

        :math:`(\arctan(\kappa f), 0)` for the kinematic models, the
        :func:`~fws_control.dynamics.dynamic_feedforward` angles for
        ``model="dynamic"``. The plant's inputs are deviations from them.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> [round(x, 6) for x in fws.LateralPlant(veh, speed=5.0,
        ...                                        curvature=0.1).operating_point]
        [0.263712, 0.0]
        """
        if self.model == "dynamic":
            return dynamic_feedforward(
                self.vehicle, speed=self.speed, curvature=self.curvature, tyre=self.tyre
            )
        ff = self.feedforward
        return ff, 0.0 * ff

    @property
    def states(self) -> tuple[str, ...]:
        """State names: ``e, theta`` (``v_y, r`` for the dynamic model, the
        wheel angles ``delta_f_act, delta_r_act`` with a lag)."""
        base = DYNAMIC_LINEAR_STATES if self.model == "dynamic" else LINEAR_STATES
        if self.steering_lag is None:
            return base
        return (*base, "delta_f_act", "delta_r_act")

    @property
    def order(self) -> int:
        """Number of states of the linearisation.

        Examples
        --------
        >>> import fws_control as fws
        >>> fws.LateralPlant(fws.Vehicle(2.7, 1.35), speed=5.0).order
        2
        """
        return len(self.states)

    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``(A, B)`` of the linearisation, shapes ``(..., n, n)``, ``(..., n, 2)``.

        Broadcast over `speed` and `curvature`; columns of B are ``delta_f,
        delta_r``; ``n = 2`` (kinematic) or 4 (dynamic), plus 2 with a
        steering lag.
        """
        if self.model == "dynamic":
            A, B = path_jacobians(
                self.vehicle, speed=self.speed, curvature=self.curvature, tyre=self.tyre
            )
        else:
            A, B = self._kinematic_matrices()
        if self.steering_lag is None:
            return A, B
        # the wheel angles become states; the commands drive them through the
        # lag
        n = A.shape[-1]
        # __post_init__ has made the lag a (front, rear) pair
        lag = cast("tuple[float, float]", self.steering_lag)
        inv = np.diag([1.0 / t for t in lag])
        shape = A.shape[:-2]
        A_lag = np.zeros(shape + (n + 2, n + 2))
        A_lag[..., :n, :n] = A
        A_lag[..., :n, n:] = B
        A_lag[..., n:, n:] = -inv
        B_lag = np.zeros(shape + (n + 2, 2))
        B_lag[..., n:, :] = inv
        return A_lag, B_lag

    def _kinematic_matrices(self) -> tuple[np.ndarray, np.ndarray]:
        V, kappa, c = np.broadcast_arrays(
            np.asarray(self.speed, dtype=float),
            np.asarray(self.curvature, dtype=float),
            np.asarray(self.input_gain_factor, dtype=float),
        )
        f = self.vehicle.wheelbase
        zero = np.zeros_like(V)
        A = np.stack(
            [np.stack([zero, V], -1), np.stack([-V * kappa**2 + 0.0, zero], -1)], -2
        )
        B = np.stack([np.stack([zero, V], -1), np.stack([c * V / f, -V / f], -1)], -2)
        return A, B

    def linearize(self) -> ct.StateSpace:
        """The linearisation as a named :class:`control.StateSpace`.

        States :attr:`states` and outputs ``e, theta`` (deviations from the
        operating point); inputs ``delta_f, delta_r`` (deviations from the
        feedforward angles, :attr:`operating_point`).

        Raises
        ------
        ValueError
            If `speed` or `curvature` hold several operating points.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> fws.LateralPlant(veh, speed=5.0).linearize().A
        array([[0., 5.],
               [0., 0.]])
        """
        if self.shape != ():
            raise ValueError(
                "linearize needs one operating point, but speed and curvature "
                f"have shape {self.shape}; index them first"
            )
        import control as ct

        A, B = self.matrices()
        n = A.shape[-1]
        return ct.ss(
            A,
            B,
            np.eye(n)[:2],  # e and theta are the first two states
            np.zeros((2, 2)),
            states=list(self.states),
            inputs=list(STEERING_INPUTS),
            outputs=list(LINEAR_STATES),
            name=f"linear_{self.model}",
        )


def _control_class(name: str) -> type | tuple[()]:
    """A python-control class for isinstance, without importing python-control.

    An instance of it cannot exist unless python-control was imported, so
    until then ``()`` (which matches nothing) stands in for it.
    """
    ct = sys.modules.get("control")
    return () if ct is None else getattr(ct, name)


def as_plant(
    plant: Any,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> LateralPlant | ct.StateSpace:
    """Resolve the plant argument of an analysis function.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant; a :class:`Vehicle` needs `speed` (and optionally
        `curvature`, `model`) to become a :class:`LateralPlant`.
    speed, curvature, model : optional
        Only with a :class:`Vehicle`: the operating point and linearisation
        (defaults: curvature 0, ``"kinematic"``).

    Returns
    -------
    LateralPlant or control.StateSpace

    Raises
    ------
    TypeError
        For any other kind of plant, for `speed`/`curvature`/`model` given
        with a plant that already fixes them, or for a Vehicle without
        `speed`.
    ValueError
        For a state space with a non-finite entry in A, B, C or D (the
        message names the matrix and the entry).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> fws.as_plant(veh, speed=5.0).speed
    5.0
    >>> import control as ct, numpy as np
    >>> fws.as_plant(ct.ss([[0.0, 1.0], [0.0, np.nan]], np.eye(2), np.eye(2), 0))
    Traceback (most recent call last):
    ...
    ValueError: plant matrix A has the non-finite entry A[1, 1] = nan; ...
    """
    given = {
        k: v
        for k, v in (("speed", speed), ("curvature", curvature), ("model", model))
        if v is not None
    }
    if isinstance(plant, Vehicle):
        if "speed" not in given:
            raise TypeError(
                "a Vehicle plant needs the keyword speed= (and optionally "
                "curvature=, model=); or pass a fws.LateralPlant"
            )
        return LateralPlant(
            plant,
            speed=speed,
            curvature=0.0 if curvature is None else curvature,
            model="kinematic" if model is None else model,
        )
    if isinstance(plant, (LateralPlant, _control_class("StateSpace"))):
        if given:
            raise TypeError(
                f"{', '.join(k + '=' for k in given)} applies only to a Vehicle "
                f"plant; a {type(plant).__name__} already fixes its operating point"
            )
        if not isinstance(plant, LateralPlant):
            _check_finite_matrices(plant)
        return plant
    if isinstance(plant, _control_class("InputOutputSystem")):
        raise TypeError(
            f"plant must be a fws.LateralPlant, a control.StateSpace or a "
            f"fws.Vehicle, got {type(plant).__name__}: linearise a nonlinear "
            "system first (control.linearize) or convert a transfer function "
            "with control.ss"
        )
    raise TypeError(
        "plant must be a fws.LateralPlant, a control.StateSpace or a fws.Vehicle "
        f"(with speed=), got {type(plant).__name__}"
    )


@summary_repr
@dataclass(frozen=True, eq=False)
class LoopMatrices:
    r"""Matrices of the structured steering loop of a plant.

    Attributes
    ----------
    A : ndarray
        State matrix, shape ``(..., n, n)``.
    B_front, B_rear : ndarray
        Columns of the inputs ``delta_f`` and ``delta_r``, shape ``(..., n)``.
    c_e, c_theta : ndarray
        Rows that measure ``e`` and ``theta``, shape ``(..., n)``.
    states : tuple of str
        State names.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> loop = fws.loop_matrices(fws.LateralPlant(veh, speed=5.0))
    >>> loop.states, loop.order
    (('e', 'theta'), 2)
    >>> loop.A
    array([[0., 5.],
           [0., 0.]])
    >>> loop.B_rear.round(6)     # [V, -V/f]
    array([ 5.      , -1.851852])
    """

    A: np.ndarray
    B_front: np.ndarray
    B_rear: np.ndarray
    c_e: np.ndarray
    c_theta: np.ndarray
    states: tuple[str, ...]

    @property
    def order(self) -> int:
        """Number of states ``n``."""
        return int(self.A.shape[-1])

    def input_vector(self, ratio: RealArrayLike) -> np.ndarray:
        r"""Input column of the loop, :math:`\mathbf b = \mathbf B_f + a\mathbf B_r`.

        With :math:`\delta_r = a\,\delta_f` the two steering inputs act as
        one, :math:`\dot x = \mathbf A x + \mathbf b\,\delta_f`.

        Parameters
        ----------
        ratio : float or array_like
            Rear-to-front steering ratio :math:`a` [-], finite (0:
            front-wheel steering); broadcasts with the leading dimensions of
            the matrices.

        Returns
        -------
        ndarray
            :math:`\mathbf b`, shape ``(..., n)``.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> loop = fws.loop_matrices(fws.LateralPlant(veh, speed=5.0))
        >>> loop.input_vector(-1.0).round(6)     # [-V, 2V/f]
        array([-5.      ,  3.703704])
        >>> loop.input_vector([0.0, -1.0]).shape
        (2, 2)
        """
        a = np.asarray(ratio, dtype=float)[..., np.newaxis]
        return self.B_front + a * self.B_rear


def _check_finite_matrices(sys: ct.StateSpace) -> None:
    """Refuse a state space with a NaN or infinite entry, naming it."""
    for name in ("A", "B", "C", "D"):
        m = np.asarray(getattr(sys, name), dtype=float)
        bad = np.argwhere(~np.isfinite(m))
        if bad.size:
            i, j = (int(v) for v in bad[0])
            more = f" ({len(bad)} such entries)" if len(bad) > 1 else ""
            raise ValueError(
                f"plant matrix {name} has the non-finite entry {name}[{i}, {j}] = "
                f"{float(m[i, j])!r}{more}; every entry of A, B, C and D must be finite"
            )


def _index(labels: list[str], name: str) -> int | None:
    return labels.index(name) if name in labels else None


def _statespace_loop(sys: ct.StateSpace) -> LoopMatrices:
    if not sys.isctime():
        raise ValueError(
            f"plant must be a continuous-time system, got sampling time dt={sys.dt}"
        )
    A, B, C, D = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C, sys.D))
    if A.shape[0] == 0:
        raise ValueError("plant must have at least one state, got a static gain")
    _check_finite_matrices(sys)
    inputs, outputs, states = (
        list(sys.input_labels),
        list(sys.output_labels),
        list(sys.state_labels),
    )
    unnamed = all(_DEFAULT_NAME.match(n) for n in inputs + outputs + states)
    if unnamed and A.shape[0] == 2 and B.shape[1] == 2:
        # python-control's default names: read as (e, theta; delta_f, delta_r),
        # feedback on the states.
        eye = np.eye(2)
        return LoopMatrices(A, B[:, 0], B[:, 1], eye[0], eye[1], ("e", "theta"))
    cols = []
    for name in STEERING_INPUTS:
        j = _index(inputs, name)
        if j is None:
            raise ValueError(
                f"plant has no input named {name!r} (inputs: {inputs}); name the "
                "steering inputs delta_f and delta_r"
            )
        cols.append(j)
    rows = []
    for name in LINEAR_STATES:
        i = _index(outputs, name)
        if i is not None:
            if np.any(D[i, cols] != 0.0):
                raise ValueError(
                    f"plant output {name!r} has a direct feedthrough D from the "
                    "steering inputs: the feedback loop would be algebraic and the "
                    "characteristic polynomial not affine in the gains"
                )
            rows.append(C[i])
            continue
        i = _index(states, name)
        if i is None:
            raise ValueError(
                f"plant has no output or state named {name!r} (outputs: {outputs}, "
                f"states: {states}); the feedback needs e and theta"
            )
        rows.append(np.eye(A.shape[0])[i])
    return LoopMatrices(
        A, B[:, cols[0]], B[:, cols[1]], rows[0], rows[1], tuple(states)
    )


def loop_matrices(plant: LateralPlant | ct.StateSpace) -> LoopMatrices:
    """The matrices of the structured loop of a resolved plant.

    Parameters
    ----------
    plant : LateralPlant or control.StateSpace
        A plant resolved by :func:`as_plant`.

    Returns
    -------
    LoopMatrices
        Broadcast over the operating points of a :class:`LateralPlant`.

    Raises
    ------
    ValueError
        If a state space lacks the named signals, has a feedthrough from the
        steering inputs to ``e``/``theta`` or is discrete-time.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> lm = fws.loop_matrices(fws.LateralPlant(veh, speed=5.0))
    >>> lm.order, lm.B_rear
    (2, array([ 5.        , -1.85185185]))
    """
    if isinstance(plant, LateralPlant):
        A, B = plant.matrices()
        eye = np.broadcast_to(np.eye(A.shape[-1]), A.shape)
        return LoopMatrices(
            A, B[..., 0], B[..., 1], eye[..., 0, :], eye[..., 1, :], plant.states
        )
    if isinstance(plant, _control_class("StateSpace")):
        return _statespace_loop(plant)
    raise TypeError(
        f"plant must be a LateralPlant or a control.StateSpace, got "
        f"{type(plant).__name__}"
    )


def resolve_ratio(plant: Any, ratio: Any) -> Any:
    """A ratio, or a ratio schedule evaluated at the plant's speed.

    A callable `ratio` is a schedule :math:`a(V)`, called as
    ``ratio(vehicle, speed=speed)`` with the vehicle and the speed of a
    :class:`LateralPlant` (e.g. :func:`fws_control.zero_sideslip_ratio`);
    anything else is returned unchanged (the caller checks it).

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        A resolved plant (:func:`as_plant`).
    ratio : float, array_like or callable
        Ratio or schedule.

    Returns
    -------
    float or ndarray or the given `ratio`

    Raises
    ------
    TypeError
        For a schedule with a plant that has no vehicle and speed.
    ValueError
        If the schedule returns a value that is not finite.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.plant import resolve_ratio
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=[5.0, 20.0])
    >>> resolve_ratio(plant, lambda vehicle, speed: 0.01 * speed - 0.1)
    array([-0.05,  0.1 ])
    """
    if not callable(ratio):
        return ratio
    if not isinstance(plant, LateralPlant):
        raise TypeError(
            "a ratio schedule ratio(vehicle, speed=...) needs a fws.LateralPlant "
            f"(or a Vehicle with speed=), got a {type(plant).__name__}"
        )
    value = ratio(plant.vehicle, speed=plant.speed)
    return check_finite(f"ratio (returned by the schedule {ratio!r})", value)
