r"""The paper's simulation scenarios (sections 4.3 and 5) as data.

Every function here returns plain data (frozen dataclasses holding numpy
arrays and :class:`~fws_control.SimulationResult` batches); figures are drawn from them
elsewhere. The closed loop is always the **nonlinear** kinematic model; the
``model`` argument only selects the linearisation used to design the
double-root gains (``"kinematic"``: the exact Jacobian or the ``"paper"``'s eq. 33).

Scenarios (paper section 4.3; ``f = 2.7 m``, ``d = 1.35 m``, zero initial
heading error):

========================  =====  ==========  ============  ===========  ======
name                      V      path        R(0)          controller   figure
========================  =====  ==========  ============  ===========  ======
``"straight_5"``          5      straight    (0, 2 m)      feedback     6
``"curve_5"``             5      κ = 1/10    (0, -5 m)     FF + FB      7
``"straight_20"``         20     straight    (0, 2 m)      feedback     8
``"curve_20"``            20     κ = 1/100   (0, -10 m)    FF + FB      9
========================  =====  ==========  ============  ===========  ======

Designs that do not exist are kept in the data, never dropped: ``ratio = 1``
on a straight road has no double-root gains (the heading is uncontrollable,
:class:`UncontrollableError`), so its run has status ``"uncontrollable"``
and NaN signals and gains. Runs that reach a singular steering angle stop
there with status ``"singular_steering"`` (see :func:`simulate`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..deprecation import legacy_keyword, reject_unknown
from ..gains import SteeringGains
from ..hints import ModelName, RealArrayLike
from ..paths import Arc, Straight
from ..plant import LateralPlant
from ..pole_placement import UncontrollableError, double_root_gains
from ..reprs import summary_repr
from ..simulation import STATUS_UNCONTROLLABLE, SimulationResult, simulate_batch
from ..simulation.engine import time_grid
from ..simulation.result import expand_runs
from ..validation import check_finite, check_model
from ..vehicle import Vehicle
from .data import FIG5_POLES, FIG5_RATIOS, FIG6_TO_9_RATIOS, PAPER_VEHICLE

__all__ = [
    "Scenario",
    "PAPER_SCENARIOS",
    "paper_scenario",
    "scenario_gains",
    "ScenarioResponses",
    "scenario_responses",
    "fig6_to_9_responses",
    "PeakSweep",
    "fig5_peak_lateral_accel",
    "SteadyState",
    "feedback_only_steady_state",
    "FeedbackOnlyResponses",
    "feedback_only_curve",
]


@dataclass(frozen=True)
class Scenario:
    """One of the paper's simulation set-ups.

    Attributes
    ----------
    name : str
    speed : float
        V [m/s].
    curvature : float
        Path curvature [1/m]; 0 is the straight road (the x-axis).
    initial_state : tuple of float
        ``(x_R, y_R, psi)`` at t = 0 [m, m, rad].
    feedforward : bool
        The paper uses feedback only on the straight road and feedforward +
        feedback on the curves.
    duration : float
        Simulated time [s] (the paper does not state it; 15 s lets the
        ``pole = -1`` designs settle: :math:`(1+t)e^{-t} < 10^{-5}` at 15 s).
    figure : int
        The paper's figure with these time responses.
    """

    name: str
    speed: float
    curvature: float
    initial_state: tuple[float, float, float]
    feedforward: bool
    duration: float
    figure: int

    @property
    def path(self) -> Straight | Arc:
        """The reference path: ``Straight()`` or ``Arc(curvature)``."""
        if self.curvature == 0.0:
            return Straight()
        return Arc(curvature=self.curvature)


PAPER_SCENARIOS: dict[str, Scenario] = {
    "straight_5": Scenario("straight_5", 5.0, 0.0, (0.0, 2.0, 0.0), False, 15.0, 6),
    "curve_5": Scenario("curve_5", 5.0, 0.1, (0.0, -5.0, 0.0), True, 15.0, 7),
    "straight_20": Scenario("straight_20", 20.0, 0.0, (0.0, 2.0, 0.0), False, 15.0, 8),
    "curve_20": Scenario("curve_20", 20.0, 0.01, (0.0, -10.0, 0.0), True, 15.0, 9),
}


def paper_scenario(name: Scenario | str) -> Scenario:
    """The scenario called `name` (see :data:`PAPER_SCENARIOS`).

    Examples
    --------
    >>> from fws_control.paper.scenarios import paper_scenario
    >>> sc = paper_scenario("curve_5")
    >>> sc.speed, sc.curvature, sc.initial_state, sc.feedforward
    (5.0, 0.1, (0.0, -5.0, 0.0), True)
    """
    if isinstance(name, Scenario):
        return name
    try:
        return PAPER_SCENARIOS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"name must be one of {sorted(PAPER_SCENARIOS)}, got {name!r}"
        ) from None


def scenario_gains(
    scenario: Scenario | str,
    ratios: RealArrayLike,
    pole: RealArrayLike,
    model: ModelName = "kinematic",
    vehicle: Vehicle = PAPER_VEHICLE,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Double-root gains for each ratio, with uncontrollable designs marked.

    Parameters
    ----------
    scenario : Scenario or str
    ratios : array_like
        Rear-to-front ratios ``a``.
    pole : float or array_like
        Double root :math:`\\lambda_0` [1/s]; broadcasts with `ratios`.
    model : {"kinematic", "paper"}
        Linearisation used for the design.
    vehicle : Vehicle, optional

    Returns
    -------
    k1, k2 : ndarray
        Gains, NaN where no design exists.
    controllable : ndarray of bool
        False where :func:`double_root_gains` raises
        :class:`UncontrollableError` (``ratio = 1`` on a straight road).

    Examples
    --------
    >>> from fws_control.paper.scenarios import scenario_gains
    >>> k1, k2, ok = scenario_gains("straight_5", [0.0, 1.0], -1.0)
    >>> k1.round(4).tolist(), ok.tolist()
    ([0.108, nan], [True, False])
    """
    sc = paper_scenario(scenario)
    model = check_model(model)
    a, lam = np.broadcast_arrays(
        np.asarray(check_finite("ratios", ratios), dtype=float),
        np.asarray(check_finite("pole", pole), dtype=float),
    )
    plant = LateralPlant(vehicle, speed=sc.speed, curvature=sc.curvature, model=model)
    a_flat, lam_flat = a.ravel(), lam.ravel()
    k1: np.ndarray = np.full(a_flat.shape, np.nan)
    k2: np.ndarray = np.full(a_flat.shape, np.nan)
    ok: np.ndarray = np.ones(a_flat.shape, dtype=bool)

    def design(idx: np.ndarray) -> None:
        # One vectorised design for all of idx; double_root_gains refuses
        # the whole array if one design is uncontrollable, so then halve it
        # (a sweep through ratio = 1 on a straight road costs about
        # 2 log2(n) calls instead of n).
        try:
            g = double_root_gains(plant, ratio=a_flat[idx], pole=lam_flat[idx])
        except UncontrollableError:
            if idx.size == 1:
                ok[idx] = False
                return
            for half in np.array_split(idx, 2):
                design(half)
            return
        k1[idx], k2[idx] = g.k1, g.k2

    if a_flat.size:
        design(np.arange(a_flat.size))
    k1, k2, ok = k1.reshape(a.shape), k2.reshape(a.shape), ok.reshape(a.shape)
    return k1, k2, ok


def _simulate_designs(
    sc: Scenario,
    vehicle: Vehicle,
    ratios: np.ndarray,
    k1: np.ndarray,
    k2: np.ndarray,
    ok: np.ndarray,
    feedforward: bool,
    duration: float,
    dt: float,
    client,
    progress,
    delay: float = 0.0,
    steering_lag: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> SimulationResult:
    """Simulate the controllable designs; keep the others as marked runs."""
    n = ratios.size
    positions = np.flatnonzero(ok)
    sub = None
    if positions.size:
        sub = simulate_batch(
            LateralPlant(vehicle, speed=sc.speed, steering_lag=steering_lag),
            sc.path,
            SteeringGains(k1[positions], k2[positions], ratios[positions]),
            initial_state=sc.initial_state,
            duration=duration,
            delay=delay,
            feedforward=feedforward,
            dt=dt,
            rtol=rtol,
            atol=atol,
            client=client,
            progress=progress,
        )
    return expand_runs(
        sub,
        positions=positions,
        k1=k1,
        k2=k2,
        ratio=ratios,
        speed=np.full(n, sc.speed),
        initial_state=np.broadcast_to(
            np.asarray(sc.initial_state, dtype=float), (n, 3)
        ),
        t=time_grid(duration, dt=dt) if sub is None else sub.t,
        feedforward=feedforward,
        vehicle=vehicle,
        path=sc.path,
        status=STATUS_UNCONTROLLABLE,
        message="no double-root gains exist: ratio = 1 on a straight path makes "
        "delta_r = delta_f, the yaw rate is identically zero and the heading is "
        "uncontrollable (not simulated)",
    )


@summary_repr
@dataclass(frozen=True)
class ScenarioResponses:
    """Time responses of one scenario for several ratios.

    Attributes
    ----------
    scenario : Scenario
    ratios : ndarray
        ``a`` per run, shape ``(runs,)``.
    pole : float
        Double root used for the design.
    model : str
        Linearisation used for the design.
    feedforward : bool
        Controller used in the simulation.
    result : SimulationResult
        All runs (a batch, not squeezed), in the order of `ratios`.
        ``result.status`` marks ``"uncontrollable"`` designs (not simulated;
        NaN signals) and runs that stopped at a singular state;
        ``result.k1``, ``result.k2`` hold the gains (NaN where no design
        exists).
    """

    scenario: Scenario
    ratios: np.ndarray
    pole: float
    model: ModelName
    feedforward: bool
    result: SimulationResult = field(repr=False)


def scenario_responses(
    scenario: Scenario | str,
    ratios: Sequence[float] = FIG6_TO_9_RATIOS,
    pole: float = -1.0,
    model: ModelName = "kinematic",
    *,
    feedforward: bool | None = None,
    duration: float | None = None,
    dt: float = 0.01,
    vehicle: Vehicle = PAPER_VEHICLE,
    delay: float = 0.0,
    steering_lag: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    client: Any = None,
    progress: bool | None = None,
    **kwargs: Any,
) -> ScenarioResponses:
    """Simulate a scenario for several ratios with double-root gains.

    Parameters
    ----------
    scenario : Scenario or str
        E.g. ``"curve_5"``.
    ratios : sequence of float, optional
        Default ``(-1, -0.5, 0, 0.5, 1)`` as in Figs. 6-9.
    pole : float, optional
        Double root :math:`\\lambda_0` [1/s] (default -1, as in Figs. 6-9).
    model : {"kinematic", "paper"}, optional
        Linearisation used to compute the gains.
    feedforward : bool, optional
        Override the scenario's controller (e.g. ``False`` on a curve).
    duration : float, optional
        Override the scenario's duration [s].
    dt : float, optional
        Output spacing [s].
    vehicle : Vehicle, optional
        Default :data:`PAPER_VEHICLE`.
    delay, steering_lag : float, optional
        Input delay [s] of the loop and steering lag [s] of the simulated
        plant (:func:`~fws_control.simulate`); the gains are designed
        without them, as in the paper.
    rtol, atol : float, optional
        Solver tolerances, as in :func:`simulate_batch`.
    client, progress
        Passed to :func:`simulate_batch`.
    **kwargs
        ``actuator_time_constant=``, the former name of `steering_lag`,
        accepted with a :class:`FutureWarning` until fws_control 0.4; any
        other keyword raises :class:`TypeError`.

    Returns
    -------
    ScenarioResponses

    Examples
    --------
    >>> from fws_control.paper.scenarios import scenario_responses
    >>> r = scenario_responses("straight_5", ratios=[0.0, 1.0], duration=5.0)
    >>> r.result.status.tolist()
    ['ok', 'uncontrollable']
    >>> round(float(r.result.e[0, 0]), 6)
    2.0
    """
    sc = paper_scenario(scenario)
    a = np.atleast_1d(np.asarray(check_finite("ratios", ratios), dtype=float))
    ff = sc.feedforward if feedforward is None else bool(feedforward)
    dur = sc.duration if duration is None else duration
    steering_lag = legacy_keyword(
        kwargs, "actuator_time_constant", "steering_lag", steering_lag
    )
    reject_unknown("scenario_responses", kwargs)
    k1, k2, ok = scenario_gains(sc, a, pole, model, vehicle)
    res = _simulate_designs(
        sc, vehicle, a, k1, k2, ok, ff, dur, dt, client, progress,
        delay, steering_lag, rtol, atol,
    )  # fmt: skip
    return ScenarioResponses(sc, a, float(pole), model, ff, res)


def fig6_to_9_responses(
    model: ModelName = "kinematic",
    ratios: Sequence[float] = FIG6_TO_9_RATIOS,
    pole: float = -1.0,
    *,
    duration: float | None = None,
    dt: float = 0.01,
    vehicle: Vehicle = PAPER_VEHICLE,
    delay: float = 0.0,
    steering_lag: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    progress: bool | None = None,
    **kwargs: Any,
) -> dict[int, ScenarioResponses]:
    """The time responses of Figs. 6-9 (e, theta, trajectory, steering, a_lat).

    Parameters
    ----------
    model, ratios, pole, duration, dt, vehicle, delay, steering_lag, progress
        As in :func:`scenario_responses`.
    rtol, atol : float, optional
        Solver tolerances, as in :func:`simulate_batch`.
    **kwargs
        ``actuator_time_constant=``, the former name of `steering_lag`,
        accepted with a :class:`FutureWarning` until fws_control 0.4.

    Returns
    -------
    dict
        ``{6: straight_5, 7: curve_5, 8: straight_20, 9: curve_20}`` as
        :class:`ScenarioResponses` (feedback only on the straight roads,
        feedforward + feedback on the curves, as in the paper).

    Examples
    --------
    >>> from fws_control.paper.scenarios import fig6_to_9_responses
    >>> figs = fig6_to_9_responses(duration=2.0, dt=0.1)
    >>> sorted(figs), figs[7].scenario.name, figs[6].result.status.tolist()[-1]
    ([6, 7, 8, 9], 'curve_5', 'uncontrollable')
    """
    steering_lag = legacy_keyword(
        kwargs, "actuator_time_constant", "steering_lag", steering_lag
    )
    reject_unknown("fig6_to_9_responses", kwargs)
    out = {}
    for sc in PAPER_SCENARIOS.values():
        out[sc.figure] = scenario_responses(
            sc,
            ratios,
            pole,
            model,
            duration=duration,
            dt=dt,
            vehicle=vehicle,
            delay=delay,
            steering_lag=steering_lag,
            rtol=rtol,
            atol=atol,
            progress=progress,
        )
    return dict(sorted(out.items()))


@summary_repr
@dataclass(frozen=True)
class PeakSweep:
    """Peak lateral acceleration over a sweep of ratios and double roots.

    Attributes
    ----------
    scenario : Scenario
    model : str
        Linearisation used for the design.
    ratios : ndarray
        Shape ``(n,)``.
    poles : ndarray
        Shape ``(p,)``.
    peak_lateral_accel : ndarray
        Peak absolute lateral acceleration of G [m/s^2], shape ``(p, n)``; NaN
        where the status is not ``"ok"``. Exact maxima of the continuous
        solution (:attr:`~fws_control.SimulationResult.peaks`), independent
        of the output step ``dt``.
    peak_time : ndarray
        When that peak occurs [s], shape ``(p, n)``; NaN where not ``"ok"``.
    peak_delta_f, peak_delta_r : ndarray
        Peak absolute steering angles [rad], shape ``(p, n)``, NaN where not ``"ok"``.
    status : ndarray of str
        Shape ``(p, n)``: ``"ok"``, ``"uncontrollable"`` (no design),
        ``"singular_steering"`` etc. (the run stopped at ``t_stop``).
    t_stop : ndarray
        Shape ``(p, n)`` [s]; NaN for designs that were not simulated.
    k1, k2 : ndarray
        The gains, shape ``(p, n)``; NaN where no design exists.
    """

    scenario: Scenario
    model: ModelName
    ratios: np.ndarray
    poles: np.ndarray
    peak_lateral_accel: np.ndarray
    peak_time: np.ndarray
    peak_delta_f: np.ndarray
    peak_delta_r: np.ndarray
    status: np.ndarray
    t_stop: np.ndarray
    k1: np.ndarray
    k2: np.ndarray


def fig5_peak_lateral_accel(
    model: ModelName = "kinematic",
    ratios: RealArrayLike = FIG5_RATIOS,
    poles: Mapping[float, Sequence[float]] | None = None,
    *,
    duration: float | None = None,
    dt: float = 0.01,
    vehicle: Vehicle = PAPER_VEHICLE,
    delay: float = 0.0,
    steering_lag: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    client: Any = None,
    progress: bool | None = None,
    **kwargs: Any,
) -> dict[str, PeakSweep]:
    """Fig. 5: peak absolute lateral acceleration versus the ratio ``a``.

    One :func:`simulate_batch` call per panel over all ``(pole, ratio)``
    pairs.

    Parameters
    ----------
    model : {"kinematic", "paper"}, optional
        Linearisation used for the design.
    ratios : array_like, optional
        Default :data:`FIG5_RATIOS` (-1.5 to 1.5 step 0.05).
    poles : dict, optional
        Double roots per speed; default ``{5: (-1, -2), 20: (-1, -2, -3)}``
        as in the paper.
    duration, dt, vehicle, delay, steering_lag, rtol, atol, client, progress
        As in :func:`scenario_responses`.
    **kwargs
        ``actuator_time_constant=``, the former name of `steering_lag`,
        accepted with a :class:`FutureWarning` until fws_control 0.4.

    Returns
    -------
    dict
        Panels ``"a"`` (straight, 5 m/s, feedback), ``"b"`` (curve 1/10,
        5 m/s, FF + FB), ``"c"`` (straight, 20 m/s), ``"d"`` (curve 1/100,
        20 m/s) as :class:`PeakSweep`.

    Examples
    --------
    >>> from fws_control.paper.scenarios import fig5_peak_lateral_accel
    >>> fig5 = fig5_peak_lateral_accel(ratios=[-1.0, 1.0], duration=3.0)
    >>> fig5["a"].status.tolist()
    [['ok', 'uncontrollable'], ['ok', 'uncontrollable']]
    >>> fig5["a"].peak_lateral_accel.round(3).tolist()
    [[1.984, nan], [7.041, nan]]
    """
    model = check_model(model)
    steering_lag = legacy_keyword(
        kwargs, "actuator_time_constant", "steering_lag", steering_lag
    )
    reject_unknown("fig5_peak_lateral_accel", kwargs)
    ratios = np.atleast_1d(np.asarray(check_finite("ratios", ratios), dtype=float))
    poles = FIG5_POLES if poles is None else poles
    out = {}
    for panel, name in zip(
        "abcd", ("straight_5", "curve_5", "straight_20", "curve_20"), strict=True
    ):
        sc = PAPER_SCENARIOS[name]
        lam = np.asarray(poles[sc.speed], dtype=float)
        A, L = np.meshgrid(ratios, lam)  # (p, n)
        k1, k2, ok = scenario_gains(sc, A, L, model, vehicle)
        dur = sc.duration if duration is None else duration
        res = _simulate_designs(
            sc,
            vehicle,
            A.ravel(),
            k1.ravel(),
            k2.ravel(),
            ok.ravel(),
            sc.feedforward,
            dur,
            dt,
            client,
            progress,
            delay,
            steering_lag,
            rtol,
            atol,
        )
        good = res.status == "ok"
        exact = res.peaks  # maxima of the continuous solution

        def peak(name, good=good, exact=exact):
            return np.where(good, exact[name].value, np.nan)

        shape = A.shape
        out[panel] = PeakSweep(
            scenario=sc,
            model=model,
            ratios=ratios,
            poles=lam,
            peak_lateral_accel=peak("lateral_accel").reshape(shape),
            peak_time=np.where(good, exact.lateral_accel.time, np.nan).reshape(shape),
            peak_delta_f=peak("delta_f").reshape(shape),
            peak_delta_r=peak("delta_r").reshape(shape),
            status=np.asarray(res.status).reshape(shape),
            t_stop=np.asarray(res.t_stop).reshape(shape),
            k1=k1,
            k2=k2,
        )
    return out


@summary_repr
@dataclass(frozen=True)
class SteadyState:
    r"""Equilibrium of the feedback-only loop on a circle (nonlinear model).

    Attributes
    ----------
    e, theta : float or ndarray
        Steady lateral [m] and heading [rad] errors; NaN where no
        equilibrium exists (see `exists`).
    delta_f, delta_r : float or ndarray
        Steady steering angles [rad].
    exists : bool or ndarray
        False where the loop has no equilibrium with :math:`|\delta_f| <
        \pi/2` and :math:`1-\kappa e>0` (e.g. ``ratio = 1``: the vehicle
        cannot yaw).
    """

    e: float | np.ndarray
    theta: float | np.ndarray
    delta_f: float | np.ndarray
    delta_r: float | np.ndarray
    exists: bool | np.ndarray


def _steady_state_scalar(f, kappa, k1, k2, a):
    if k1 == 0.0:
        return None

    def e_of(u):
        return -u * (1.0 - a * k2) / k1

    def F(u):
        return (
            math.sin((1.0 - a) * u) / (f * math.cos(u)) * (1.0 - kappa * e_of(u))
            - kappa
        )

    # F is written without the 1/(1 - kappa e) pole; keep only roots where
    # 1 - kappa e > 0. Scan, then refine every sign change.
    u = np.linspace(-0.5 * math.pi + 1e-9, 0.5 * math.pi - 1e-9, 20001)
    Fu = np.array([F(v) for v in u])
    roots = []
    for i in np.flatnonzero(np.sign(Fu[:-1]) * np.sign(Fu[1:]) <= 0):
        r = brentq(F, u[i], u[i + 1], xtol=1e-15) if Fu[i] != Fu[i + 1] else u[i]
        if 1.0 - kappa * e_of(r) > 0.0 and abs(F(r)) < 1e-9:
            roots.append(r)
    if not roots:
        return None
    # the equilibrium connected to the small-error one of the linear model
    lin = f * kappa / (1.0 - a) if a != 1.0 else 0.0
    r = min(roots, key=lambda v: abs(v - lin))
    # + 0.0 turns the -0.0 of a = 0 into 0.0
    return e_of(r), -a * r + 0.0, r, a * r + 0.0


def feedback_only_steady_state(
    vehicle: Vehicle, gains: SteeringGains, *, curvature: RealArrayLike
) -> SteadyState:
    r"""Steady state of the feedback-only controller on a circle.

    With :math:`\delta_f = u = -k_1 e - k_2\theta`, :math:`\delta_r = a u`,
    the equilibria of the corrected eqs. (18)-(19) satisfy
    :math:`\sin(\theta+\delta_r) = 0`, i.e. :math:`\theta = -a u`, hence
    :math:`e = -u(1 - a k_2)/k_1`, and

    .. math:: \frac{\sin((1-a)u)}{f\cos u} = \frac{\kappa}{1-\kappa e(u)},

    solved for :math:`u\in(-\pi/2, \pi/2)` with :math:`1-\kappa e > 0`. Of
    several roots the one nearest the linear estimate :math:`u \approx f\kappa
    /(1-a)` is returned. Without feedforward the steering needed to turn must
    come from a standing error, which is why the paper's Fig. 7 needs the
    feedforward term.

    Parameters
    ----------
    vehicle : Vehicle
    curvature : float
        Path curvature :math:`\kappa` [1/m].
    gains : SteeringGains
        Scalar or array gains (one equilibrium per design).

    Returns
    -------
    SteadyState

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.paper.scenarios import feedback_only_steady_state
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=0.0,
    ...                           pole=-1.0)
    >>> ss = feedback_only_steady_state(veh, g, curvature=0.1)
    >>> round(ss.e, 4), round(ss.theta, 4), round(ss.delta_f, 4)
    (-2.7617, 0.0, 0.2085)
    """
    kappa = float(check_finite("curvature", curvature))
    k1, k2, a = np.broadcast_arrays(
        np.asarray(gains.k1, dtype=float),
        np.asarray(gains.k2, dtype=float),
        np.asarray(gains.ratio, dtype=float),
    )
    out = np.full((4, *k1.shape), np.nan)
    exists = np.zeros(k1.shape, dtype=bool)
    for idx in np.ndindex(k1.shape):
        r = _steady_state_scalar(vehicle.wheelbase, kappa, k1[idx], k2[idx], a[idx])
        if r is not None:
            out[(slice(None),) + idx] = r
            exists[idx] = True

    def cast(v):
        return float(v) if np.ndim(v) == 0 else v

    return SteadyState(
        e=cast(out[0]),
        theta=cast(out[1]),
        delta_f=cast(out[2]),
        delta_r=cast(out[3]),
        exists=bool(exists) if exists.ndim == 0 else exists,
    )


@summary_repr
@dataclass(frozen=True)
class FeedbackOnlyResponses:
    """Feedback-only control on a curve, with the analytic steady state.

    Attributes
    ----------
    responses : ScenarioResponses
        Simulation with ``feedforward=False``.
    steady_state : SteadyState
        Equilibrium of the nonlinear loop per ratio (NaN where none exists).
    """

    responses: ScenarioResponses
    steady_state: SteadyState


def feedback_only_curve(
    scenario: Scenario | str = "curve_5",
    ratios: Sequence[float] = FIG6_TO_9_RATIOS,
    pole: float = -1.0,
    model: ModelName = "kinematic",
    *,
    duration: float | None = None,
    dt: float = 0.01,
    vehicle: Vehicle = PAPER_VEHICLE,
) -> FeedbackOnlyResponses:
    """The curve scenario with the feedback-only controller (paper section 5).

    The gains are the same double-root designs as with feedforward; only the
    feedforward term is removed, which leaves a steady-state error.

    Examples
    --------
    >>> from fws_control.paper.scenarios import feedback_only_curve
    >>> fb = feedback_only_curve("curve_5", ratios=[0.0], duration=30.0)
    >>> e_sim = fb.responses.result.e[0, -1]      # simulated e at t = 30 s
    >>> round(float(e_sim), 4), round(float(fb.steady_state.e[0]), 4)
    (-2.7617, -2.7617)
    """
    sc = paper_scenario(scenario)
    if sc.curvature == 0.0:
        raise ValueError(f"scenario must be a curve, got {sc.name!r}")
    resp = scenario_responses(
        sc,
        ratios,
        pole,
        model,
        feedforward=False,
        duration=duration,
        dt=dt,
        vehicle=vehicle,
    )
    g = resp.result
    k1, k2, a = np.asarray(g.k1), np.asarray(g.k2), np.asarray(g.ratio)
    ok = np.isfinite(k1)
    ss_all = SteadyState(
        np.full(k1.shape, np.nan),
        np.full(k1.shape, np.nan),
        np.full(k1.shape, np.nan),
        np.full(k1.shape, np.nan),
        exists=np.zeros(k1.shape, dtype=bool),
    )
    if np.any(ok):
        ss = feedback_only_steady_state(
            vehicle,
            SteeringGains(k1[ok], k2[ok], a[ok]),
            curvature=sc.curvature,
        )
        for name in ("e", "theta", "delta_f", "delta_r", "exists"):
            getattr(ss_all, name)[ok] = getattr(ss, name)
    return FeedbackOnlyResponses(resp, ss_all)
