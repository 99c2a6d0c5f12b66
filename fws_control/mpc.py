r"""Linear time-varying model predictive control with input-delay compensation.

:class:`MPCController` is the lateral MPC that production stacks deploy
(Autoware's ``mpc_lateral_controller``, Apollo's ``mpc_controller``), on the
four-wheel-steering plant: both axle angles as inputs, or the paper's ratio
structure :math:`\delta_r = a(\delta_f - \delta_{ff})`.

Formulation
-----------
The model is the kinematic path-frame model linearised along the reference:
at horizon step ``j`` the path curvature :math:`\kappa_j = \kappa(s + V j
T_s)` gives the operating point :math:`e = \theta = 0`, :math:`\delta =
(\arctan(\kappa_j f), 0)` (the curvature feedforward) and the Jacobians
:math:`A(\kappa_j), B(\kappa_j)` of :meth:`LateralPlant.matrices
<fws_control.LateralPlant.matrices>`. Each step is discretised with the
exact zero-order hold (the matrix exponential of
:math:`[[A, B], [0, 0]] T_s`, in closed form: :math:`A^2 = -(V\kappa_j)^2
I`), so

.. math::
    x_{j+1} = A_{d,j} x_j + B_{d,j} G v_j,\qquad
    \delta_j = \delta_{ff,j} + G v_j,

with :math:`x = (e, \theta)`, :math:`G = I_2` (independent axles) or
:math:`G = [1, a]^T` (ratio structure). The quadratic programme

.. math::
    \min_v \sum_{j=1}^{N} x_j^T Q x_j + \sum_{j=0}^{N-1} v_j^T R v_j

is subject to the dynamics, the angle limits :math:`|\delta_j| \le
\delta_{max}` and the rate limits :math:`|\delta_j - \delta_{j-1}| \le
\dot\delta_{max} T_s` per axle (:math:`\delta_{-1}` the last command sent).
It is solved by OSQP (optional extra ``mpc``), warm-started from the
previous solution shifted by one step.

Delay compensation
------------------
With an input delay :math:`\tau_d = N_d T_s`, the commands computed at the
last :math:`N_d` samples are sent but not yet applied. They are the states
of the prediction over the delay: from the measurement at :math:`t_k` the
model is run through them to :math:`t_k + \tau_d`, and the horizon starts
there, as in Autoware's ``mpc_lateral_controller``. The first input of the
solution is the command applied at :math:`t_k + \tau_d`.

Sampling
--------
The controller is sampled: :func:`~fws_control.simulate` holds each command
for one sample time (zero-order hold), on either engine (see
:attr:`LateralController.sample_time
<fws_control.LateralController.sample_time>`); the compiled engine
integrates the held commands (:mod:`~fws_control.simulation.compiled_sampled`).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NoReturn

import numpy as np

from .hints import RealArrayLike
from .lateral_controller import LateralController
from .paths import Path
from .plant import LateralPlant
from .validation import (
    MAX_SPEED,
    check_delay,
    check_finite,
    check_scalar,
    check_type,
)
from .vehicle import Vehicle

__all__ = ["MPCController", "MPCStep", "MPCRun", "zoh_discretize"]

#: Relative slack with which a delay counts as a whole number of samples.
_WHOLE_SAMPLES = 1e-9
#: OSQP's iteration limit per step (the QP of a 50-step horizon takes 25-200).
_MAX_ITER = 20_000
#: Longest horizon [steps]: the QP has about 10 variables and rows per step.
MAX_HORIZON = 2000
#: Range of the sample time [s]: lateral controllers run at 1 to 10,000 Hz.
MIN_SAMPLE_TIME, MAX_SAMPLE_TIME = 1e-4, 1.0
#: Largest rear-to-front ratio magnitude of the ratio structure (production
#: 4WS stays within 1).
MAX_RATIO = 10.0


def _import_osqp():
    try:
        import osqp
    except ImportError as exc:  # pragma: no cover - the extra is installed in CI
        raise ImportError(
            "MPCController needs the QP solver OSQP: install the optional extra "
            "'mpc' (pip install 'fws-control[mpc]')"
        ) from exc
    return osqp


def zoh_discretize(
    A: RealArrayLike, B: RealArrayLike, sample_time: float
) -> tuple[np.ndarray, np.ndarray]:
    r"""Exact zero-order-hold discretisation, broadcast over leading axes.

    :math:`A_d = e^{A T_s}`, :math:`B_d = \int_0^{T_s} e^{A\tau}\,d\tau\,B`,
    both read off the matrix exponential of :math:`[[A, B], [0, 0]] T_s`.

    Parameters
    ----------
    A : array_like
        Shape ``(..., n, n)``.
    B : array_like
        Shape ``(..., n, m)``.
    sample_time : float
        :math:`T_s` [s], > 0.

    Returns
    -------
    (ndarray, ndarray)
        ``Ad`` of shape ``(..., n, n)`` and ``Bd`` of shape ``(..., n, m)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.mpc import zoh_discretize
    >>> Ad, Bd = zoh_discretize(np.array([[0.0, 5.0], [0.0, 0.0]]),
    ...                         np.array([[0.0], [1.0]]), 0.1)
    >>> Ad.tolist(), Bd.round(6).tolist()     # double integrator: V Ts^2/2
    ([[1.0, 0.5], [0.0, 1.0]], [[0.025], [0.1]])
    """
    from scipy.linalg import expm

    ts = check_scalar("sample_time", sample_time)
    if not ts > 0.0:
        raise ValueError(f"sample_time must be > 0 s, got {sample_time!r}")
    A = np.asarray(check_finite("A", A), dtype=float)
    B = np.asarray(check_finite("B", B), dtype=float)
    if A.ndim < 2 or A.shape[-1] != A.shape[-2]:
        raise ValueError(f"A must have shape (..., n, n), got {A.shape}")
    n = A.shape[-1]
    if B.ndim < 2 or B.shape[-2] != n:
        raise ValueError(f"B must have shape (..., {n}, m), got {B.shape}")
    m = B.shape[-1]
    lead = np.broadcast_shapes(A.shape[:-2], B.shape[:-2])
    M = np.zeros((*lead, n + m, n + m))
    M[..., :n, :n] = A * ts
    M[..., :n, n:] = B * ts
    E = expm(M)
    return E[..., :n, :n], E[..., :n, n:]


def _kinematic_zoh(
    A: np.ndarray, B: np.ndarray, ts: float
) -> tuple[np.ndarray, np.ndarray]:
    r""":func:`zoh_discretize` of the kinematic path-frame model, in closed form.

    The kinematic Jacobian :math:`A = [[0, V], [-V\kappa^2, 0]]` squares to
    :math:`-\omega^2 I` with :math:`\omega = |V\kappa|`, so
    :math:`e^{AT} = \cos(\omega T) I + \sin(\omega T)/\omega\,A` and
    :math:`\int_0^T e^{A\tau}d\tau = \sin(\omega T)/\omega\,I +
    (1 - \cos\omega T)/\omega^2\,A`, written with ``sinc`` (no 0/0 on a
    straight). Elementwise on a stack ``(k, 2, 2)``: no matrix exponential
    and no LAPACK call per sample (a stack of small matrix exponentials costs
    a millisecond, and far more where BLAS threads busy-wait).
    """
    omega = np.sqrt(np.maximum(-A[..., 0, 1] * A[..., 1, 0], 0.0))
    x = omega * ts
    c = np.cos(x)
    s1 = ts * np.sinc(x / math.pi)  # sin(w T) / w
    s2 = 0.5 * ts * ts * np.sinc(x / (2.0 * math.pi)) ** 2  # (1 - cos w T) / w^2
    eye = np.eye(2)
    Ad = c[..., None, None] * eye + s1[..., None, None] * A
    W = s1[..., None, None] * eye + s2[..., None, None] * A
    Bd = np.einsum("...ij,...jk->...ik", W, B)
    return Ad, Bd


@dataclass(frozen=True, eq=False)
class MPCStep:
    """One sample of :class:`MPCRun`: the measurement, the prediction, the plan.

    Attributes
    ----------
    s, e, theta : float
        The measured path-frame state [m, m, rad].
    sent : ndarray
        Shape ``(N_d, 2)``: the commands ``(delta_f, delta_r)`` [rad] sent
        before this sample and applied over the delay, oldest first.
    delay_states : ndarray
        Shape ``(N_d + 1, 2)``: ``(e, theta)`` predicted at ``t_k + j T_s``,
        ``j = 0..N_d``, from the measurement and `sent` only (row 0 is the
        measurement).
    states : ndarray
        Shape ``(N + 1, 2)``: ``(e, theta)`` predicted over the horizon from
        ``t_k + delay`` (row 0 is the last row of `delay_states`).
    inputs : ndarray
        Shape ``(N, 2)``: the planned commands [rad]; row 0 is the command
        returned, applied at ``t_k + delay``.
    curvature : ndarray
        Shape ``(N_d + N,)``: the path curvature of each model step [1/m].
    status : str
        OSQP's status (``"solved"``).
    iterations : int
        OSQP's iterations.
    solve_time : float
        OSQP's solve time [s] (its update of the QP's data excluded).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> mpc = fws.MPCController(sample_time=0.04, horizon=20, delay=0.08)
    >>> run = mpc.start(veh, fws.Straight(), speed=10.0)
    >>> cmd = run.step(s=0.0, e=0.5, theta=0.0)
    >>> step = run.last
    >>> step.sent.shape, step.delay_states.shape, step.inputs.shape, step.status
    ((2, 2), (3, 2), (20, 2), 'solved')
    """

    s: float
    e: float
    theta: float
    sent: np.ndarray
    delay_states: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    curvature: np.ndarray
    status: str
    iterations: int
    solve_time: float


def _optional_limit(name: str, value: Any) -> float | None:
    if value is None:
        return None
    v = check_scalar(name, value)
    if not v > 0.0:
        raise ValueError(f"{name} must be > 0 (or None: no limit), got {value!r}")
    return v


@dataclass(frozen=True, eq=False, kw_only=True)
class MPCController(LateralController):
    r"""Lateral LTV-MPC of the 4WS vehicle, with input-delay compensation.

    The formulation, the delay compensation and the solver are described in
    :mod:`fws_control.mpc`. A sampled controller:
    :func:`~fws_control.simulate` calls it every `sample_time` and holds the
    command in between (zero-order hold).

    Parameters
    ----------
    sample_time : float, optional
        :math:`T_s` [s], in ``[1e-4, 1]`` (default 0.04).
    horizon : int, optional
        Prediction horizon :math:`N` [steps], 1 to :data:`MAX_HORIZON`
        (default 50).
    Q : array_like, optional
        2 x 2 weight on ``(e, theta)``, symmetric positive semidefinite
        (default ``diag(1, 4)``).
    R : float or array_like, optional
        Weight on the steering deviation from the feedforward, positive
        definite: 2 x 2 for independent axles, a scalar with `ratio`
        (default 4, times the identity for independent axles).
    ratio : float, optional
        The paper's structure ``delta_r = ratio (delta_f - delta_ff)`` (one
        input), ``|ratio| <= 10``. ``None`` (default): both axles
        independent.
    delay : float, optional
        Input delay :math:`\tau_d` [s] compensated by prediction, >= 0 and
        a whole number of sample times (default 0).
    max_steer_front, max_steer_rear : float, optional
        Angle limits [rad], > 0. ``None``: the vehicle's limit where set,
        else none. Where both are set the smaller holds.
    max_rate_front, max_rate_rear : float, optional
        Rate limits [rad/s], > 0, on the change between samples
        (:math:`|\delta_j - \delta_{j-1}| \le \dot\delta_{max} T_s`).
        ``None``: the vehicle's rate limit where set, else none.
    tolerance : float, optional
        OSQP's absolute and relative tolerance, in ``[1e-12, 1e-2]``
        (default 1e-7); the solution is polished.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=10.0)
    >>> mpc = fws.MPCController(sample_time=0.05, horizon=40)
    >>> res = fws.simulate(plant, fws.Straight(), mpc,
    ...                    initial_state=(0.0, 1.0, 0.0), duration=8.0)
    >>> res.status, abs(float(res.e[-1])) < 0.01
    ('ok', True)
    """

    sample_time: float = 0.04
    horizon: int = 50
    Q: Any = None
    R: Any = None
    ratio: float | None = None
    delay: float = 0.0
    max_steer_front: float | None = None
    max_steer_rear: float | None = None
    max_rate_front: float | None = None
    max_rate_rear: float | None = None
    tolerance: float = 1e-7
    label = "MPC"

    def __post_init__(self) -> None:
        _import_osqp()
        ts = check_scalar("sample_time", self.sample_time)
        if not MIN_SAMPLE_TIME <= ts <= MAX_SAMPLE_TIME:
            raise ValueError(
                f"sample_time must be in [{MIN_SAMPLE_TIME:g}, {MAX_SAMPLE_TIME:g}] "
                f"s, got {self.sample_time!r}"
            )
        object.__setattr__(self, "sample_time", ts)
        h = self.horizon
        if (
            isinstance(h, (bool, np.bool_))
            or not isinstance(h, (int, np.integer))
            or not 1 <= h <= MAX_HORIZON
        ):
            raise ValueError(
                f"horizon must be an integer in [1, {MAX_HORIZON}] steps, got {h!r}"
            )
        object.__setattr__(self, "horizon", int(h))
        Q = np.diag([1.0, 4.0]) if self.Q is None else self.Q
        Q = np.asarray(check_finite("Q", Q), dtype=float)
        if Q.shape != (2, 2) or not np.allclose(Q, Q.T, rtol=0.0, atol=1e-12):
            raise ValueError(f"Q must be a symmetric 2 x 2 matrix, got {self.Q!r}")
        if np.min(np.linalg.eigvalsh(Q)) < -1e-12 * max(1.0, np.max(np.abs(Q))):
            raise ValueError(f"Q must be positive semidefinite, got {self.Q!r}")
        object.__setattr__(self, "Q", Q)
        if self.ratio is not None:
            a = check_scalar("ratio", self.ratio)
            if abs(a) > MAX_RATIO:
                raise ValueError(
                    f"ratio must be in [-{MAX_RATIO:g}, {MAX_RATIO:g}], got "
                    f"{self.ratio!r}"
                )
            object.__setattr__(self, "ratio", a)
            r = 4.0 if self.R is None else check_scalar("R", self.R)
            if not r > 0.0:
                raise ValueError(f"R must be > 0 with ratio=, got {self.R!r}")
            R = np.array([[r]])
        else:
            R = 4.0 * np.eye(2) if self.R is None else self.R
            R = np.asarray(check_finite("R", R), dtype=float)
            if R.shape != (2, 2) or not np.allclose(R, R.T, rtol=0.0, atol=1e-12):
                raise ValueError(
                    f"R must be a symmetric 2 x 2 matrix without ratio=, got {self.R!r}"
                )
            if not np.min(np.linalg.eigvalsh(R)) > 0.0:
                raise ValueError(f"R must be positive definite, got {self.R!r}")
        object.__setattr__(self, "R", R)
        d = check_delay(self.delay)
        steps = d / ts
        if abs(steps - round(steps)) > _WHOLE_SAMPLES * max(1.0, steps):
            raise ValueError(
                f"delay must be a whole number of sample times (>= 0), got "
                f"delay={self.delay!r} s with sample_time={ts!r} s ({steps:.6g} "
                "samples)"
            )
        object.__setattr__(self, "delay", d)
        for name in (
            "max_steer_front",
            "max_steer_rear",
            "max_rate_front",
            "max_rate_rear",
        ):
            object.__setattr__(self, name, _optional_limit(name, getattr(self, name)))
        tol = check_scalar("tolerance", self.tolerance)
        if not 1e-12 <= tol <= 1e-2:
            raise ValueError(f"tolerance must be in [1e-12, 1e-2], got {tol!r}")
        object.__setattr__(self, "tolerance", tol)

    @property
    def delay_steps(self) -> int:
        """The delay in samples, :math:`N_d = \\tau_d / T_s`."""
        return round(self.delay / self.sample_time)

    def runs(self) -> int | None:  # noqa: D102 - one controller for all runs
        return None

    def subset(self, idx: Sequence[int] | np.ndarray) -> MPCController:  # noqa: D102
        return self

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
    ) -> NoReturn:
        """Not a static law: an MPC is sampled (use :meth:`start`).

        Parameters
        ----------
        vehicle, path, s, e, theta, curvature, speed
            As in :meth:`LateralController.steering
            <fws_control.LateralController.steering>`.

        Raises
        ------
        TypeError
            Always.
        """
        raise TypeError(
            "MPCController is a sampled controller with internal state (the "
            "commands sent over the delay, the warm start): it has no static "
            "law steering(); fws.simulate runs it at its sample_time, and "
            "MPCController.start(vehicle, path, speed=...).step(s=, e=, theta=) "
            "computes one command"
        )

    def system(
        self, vehicle: Vehicle, path: Path, *, speed: float, name: str = "controller"
    ) -> NoReturn:
        """Not available: the python-control reference runs static laws only.

        Parameters
        ----------
        vehicle, path, speed, name
            As in :meth:`LateralController.system
            <fws_control.LateralController.system>`.

        Raises
        ------
        TypeError
            Always.
        """
        raise TypeError(
            "MPCController is sampled: it has no static control.NonlinearIOSystem; "
            "simulate it with fws.simulate"
        )

    def start(self, vehicle: Vehicle, path: Path, *, speed: float) -> MPCRun:
        """A run of the controller: its state (commands sent, warm start).

        Parameters
        ----------
        vehicle : Vehicle
            Geometry and (optional) steering limits.
        path : Path
            The reference path (its curvature ahead is the feedforward).
        speed : float
            Speed :math:`V` [m/s], nonzero.

        Returns
        -------
        MPCRun
        """
        return MPCRun(self, vehicle, path, speed=speed)


def _limit(own: float | None, vehicle: float | None) -> float:
    given = [v for v in (own, vehicle) if v is not None]
    return min(given) if given else math.inf


class MPCRun:
    """The state of one run of an :class:`MPCController` (mutable).

    Create it with :meth:`MPCController.start`; call :meth:`step` once per
    sample, in time order. The commands it returns are the ones it assumes
    sent: after its first call the prediction over the delay uses exactly
    them (before it, the feedforward at the first measurement).

    Parameters
    ----------
    controller : MPCController
        Its parameters.
    vehicle : Vehicle
        Geometry and (optional) steering limits.
    path : Path
        The reference path.
    speed : float
        Speed :math:`V` [m/s], nonzero.

    Attributes
    ----------
    last : MPCStep or None
        The prediction and plan of the latest :meth:`step`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> run = fws.MPCController(horizon=20).start(veh, fws.Straight(), speed=10.0)
    >>> df, dr = run.step(s=0.0, e=0.0, theta=0.0)
    >>> abs(df) < 1e-9 and abs(dr) < 1e-9       # on the path: no command
    True
    """

    def __init__(
        self, controller: MPCController, vehicle: Vehicle, path: Path, *, speed: float
    ) -> None:
        check_type("controller", controller, MPCController)
        check_type("vehicle", vehicle, Vehicle)
        check_type("path", path, Path, "a fws_control Path (e.g. fws.Straight())")
        V = check_scalar("speed", speed)
        if V == 0.0 or abs(V) > MAX_SPEED:
            raise ValueError(
                f"speed must be nonzero with magnitude <= {MAX_SPEED:g} m/s, got "
                f"{speed!r}"
            )
        self.controller = controller
        self.vehicle = vehicle
        self.path = path
        self.speed = V
        self.last: MPCStep | None = None
        c = controller
        N = c.horizon
        self._G = np.eye(2) if c.ratio is None else np.array([[1.0], [c.ratio]])
        nu = self._G.shape[1]
        self._nu = nu
        lo = np.array(
            [
                _limit(c.max_steer_front, vehicle.max_steer_front),
                _limit(c.max_steer_rear, vehicle.max_steer_rear),
            ]
        )
        self._angle = lo
        self._step_limit = c.sample_time * np.array(
            [
                _limit(c.max_rate_front, vehicle.max_steer_rate_front),
                _limit(c.max_rate_rear, vehicle.max_steer_rate_rear),
            ]
        )
        length = float(getattr(path, "length", math.inf))
        self._open = length if math.isfinite(length) and not path.closed else None
        self._pending: deque[np.ndarray] = deque()
        self._sent_last: np.ndarray | None = None
        self._kappa: np.ndarray | None = None
        self._model: tuple[np.ndarray, ...] | None = None
        # the previous solution shifted by one step (the next warm start)
        self._warm: np.ndarray | None = None
        self._setup_qp(N, nu)

    # -- the QP's fixed structure --------------------------------------------

    def _setup_qp(self, N: int, nu: int) -> None:
        import scipy.sparse as sp

        c = self.controller
        nx = 2
        self._nX = nX = nx * N
        nz = nX + nu * N
        P = sp.block_diag(
            [sp.csc_matrix(c.Q)] * N + [sp.csc_matrix(c.R)] * N, format="csc"
        )
        self._P = sp.triu(P, format="csc")
        G = self._G
        rows, cols, const = [], [], []

        def block(r0, c0, M):
            rr, cc = np.meshgrid(
                np.arange(M.shape[0]), np.arange(M.shape[1]), indexing="ij"
            )
            rows.append((r0 + rr).ravel())
            cols.append((c0 + cc).ravel())
            return np.asarray(M, dtype=float).ravel()

        # constant entries: x_{j+1} in each dynamics row block; G in the
        # angle rows; G and -G in the rate rows
        for j in range(N):
            const.append(block(nx * j, nx * j, np.eye(nx)))
        rA, rR = nx * N, nx * N + 2 * N
        for j in range(N):
            const.append(block(rA + 2 * j, nX + nu * j, G))
            const.append(block(rR + 2 * j, nX + nu * j, G))
            if j:
                const.append(block(rR + 2 * j, nX + nu * (j - 1), -G))
        self._const = np.concatenate(const)
        # varying entries, in this order: -Ad_j (j >= 1), then -Bd_j G
        for j in range(1, N):
            block(nx * j, nx * (j - 1), np.zeros((nx, nx)))
        for j in range(N):
            block(nx * j, nX + nu * j, np.zeros((nx, nu)))
        r = np.concatenate(rows)
        cc = np.concatenate(cols)
        ids = np.arange(1, r.size + 1, dtype=float)
        A = sp.coo_matrix((ids, (r, cc)), shape=(rR + 2 * N, nz)).tocsc()
        # position in the CSC data of each entry, in the order listed above
        self._perm = A.data.astype(np.int64) - 1
        self._A = A
        self._nz = nz
        self._rows = rR + 2 * N
        self._qp = None

    def _constraint_data(self, Ad: np.ndarray, BdG: np.ndarray) -> np.ndarray:
        vals = np.concatenate([self._const, -Ad[1:].ravel(), -BdG.ravel()])
        return vals[self._perm]

    # -- the model along the path ---------------------------------------------

    def _curvatures(self, s: float, steps: int) -> np.ndarray:
        ahead = s + self.speed * self.controller.sample_time * np.arange(steps)
        if self._open is not None:
            ahead = np.clip(ahead, 0.0, self._open)
        kappa = np.asarray(self.path.curvature(ahead), dtype=float)
        return np.broadcast_to(kappa, ahead.shape).copy()

    def _discrete_model(self, kappa: np.ndarray):
        if self._kappa is not None and np.array_equal(kappa, self._kappa):
            return self._model
        plant = LateralPlant(
            self.vehicle, speed=self.speed, curvature=kappa, model="kinematic"
        )
        A, B = plant.matrices()
        Ad, Bd = _kinematic_zoh(A, B, self.controller.sample_time)
        ff = np.zeros((kappa.size, 2))
        ff[:, 0] = np.arctan(self.vehicle.wheelbase * kappa)
        self._kappa, self._model = kappa, (Ad, Bd, Bd @ self._G, ff)
        return self._model

    # -- one sample -----------------------------------------------------------

    def step(self, *, s: float, e: float, theta: float) -> tuple[float, float]:
        """The command for the measurement ``(s, e, theta)`` of this sample.

        Parameters
        ----------
        s, e, theta : float
            Path-frame state of the rear-axle centre [m, m, rad].

        Returns
        -------
        (float, float)
            ``(delta_f, delta_r)`` [rad], applied after the controller's
            delay and held for one sample; within the angle limits and, from
            the previous command, the rate limits.

        Raises
        ------
        RuntimeError
            If OSQP does not solve the QP (its status is named).
        """
        c = self.controller
        s, e, theta = (
            check_scalar(n, v) for n, v in (("s", s), ("e", e), ("theta", theta))
        )
        N, Nd = c.horizon, c.delay_steps
        kappa = self._curvatures(s, Nd + N)
        Ad, Bd, BdG, ff = self._discrete_model(kappa)
        if self._sent_last is None:
            # before the first command: the feedforward at the measurement,
            # within the angle limits, sent over the whole delay
            first = np.clip(ff[0], -self._angle, self._angle)
            self._sent_last = first
            self._pending.extend([first] * Nd)
        sent = np.array(self._pending).reshape(Nd, 2)
        # prediction over the delay: only the commands already sent
        xs = np.empty((Nd + 1, 2))
        xs[0] = (e, theta)
        for j in range(Nd):
            xs[j + 1] = Ad[j] @ xs[j] + Bd[j] @ (sent[j] - ff[j])
        x0 = xs[Nd]
        h = slice(Nd, Nd + N)
        X, v, status, iters, solve_time = self._solve(x0, Ad[h], BdG[h], ff[h])
        G = self._G
        cmd = ff[Nd:] + v @ G.T  # (N, 2) absolute commands
        # OSQP meets the bounds to its tolerance: the command sent meets them
        # exactly
        u0 = np.clip(
            cmd[0],
            self._sent_last - self._step_limit,
            self._sent_last + self._step_limit,
        )
        u0 = np.clip(u0, -self._angle, self._angle)
        # the QP's own state variables (the model holds to OSQP's tolerance)
        states = np.vstack([x0, X])
        self.last = MPCStep(
            s, e, theta, sent, xs, states, cmd, kappa, status, iters, solve_time
        )
        if Nd:
            self._pending.popleft()
            self._pending.append(u0)
        self._sent_last = u0
        return float(u0[0]), float(u0[1])

    def _solve(self, x0, Ad, BdG, ff):
        c = self.controller
        N, nu, nx = c.horizon, self._nu, 2
        inf = math.inf
        l_dyn = np.zeros(nx * N)
        l_dyn[:nx] = Ad[0] @ x0
        ang = np.broadcast_to(self._angle, (N, 2))
        l_ang = (-ang - ff).ravel()
        u_ang = (ang - ff).ravel()
        step = np.broadcast_to(self._step_limit, (N, 2))
        dff = np.empty((N, 2))
        dff[0] = ff[0] - self._sent_last
        dff[1:] = ff[1:] - ff[:-1]
        l_rate = (-step - dff).ravel()
        u_rate = (step - dff).ravel()
        lo = np.concatenate([l_dyn, l_ang, l_rate])
        up = np.concatenate([l_dyn, u_ang, u_rate])
        lo[~np.isfinite(lo)] = -inf
        up[~np.isfinite(up)] = inf
        Ax = self._constraint_data(Ad, BdG)
        if self._qp is None:
            osqp = _import_osqp()
            import scipy.sparse as sp

            A = sp.csc_matrix(
                (Ax, self._A.indices, self._A.indptr), shape=self._A.shape
            )
            # OSQP 1.0 renamed "polish" and made solve() raise on failure
            # optional (its default to change): the status is checked here
            new_api = int(str(osqp.__version__).split(".")[0]) >= 1
            self._solve_kw = {"raise_error": False} if new_api else {}
            self._qp = osqp.OSQP()
            self._qp.setup(
                self._P,
                np.zeros(self._nz),
                A,
                lo,
                up,
                eps_abs=c.tolerance,
                eps_rel=c.tolerance,
                max_iter=_MAX_ITER,
                verbose=False,
                **{"polishing" if new_api else "polish": True},
            )
            self._Ax = Ax
        else:
            if not np.array_equal(Ax, self._Ax):
                self._qp.update(Ax=Ax, l=lo, u=up)
                self._Ax = Ax
            else:
                self._qp.update(l=lo, u=up)
            if self._warm is not None:
                self._qp.warm_start(x=self._warm)
        res = self._qp.solve(**self._solve_kw)
        status = str(res.info.status)
        if status not in ("solved", "solved inaccurate") or res.x is None:
            raise RuntimeError(
                f"MPCController: OSQP did not solve the QP at this sample "
                f"(status {status!r} after {res.info.iter} iterations; "
                f"horizon={N}, tolerance={c.tolerance:g})"
            )
        z = np.asarray(res.x, dtype=float)
        # warm start of the next sample: the solution shifted by one step
        X = z[: self._nX].reshape(N, nx)
        V = z[self._nX :].reshape(N, nu)
        self._warm = np.concatenate(
            [np.vstack([X[1:], X[-1:]]).ravel(), np.vstack([V[1:], V[-1:]]).ravel()]
        )
        return X, V, status, int(res.info.iter), float(res.info.solve_time)
