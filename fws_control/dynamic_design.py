r"""Design questions of the dynamic single-track model.

* :func:`steady_state_offset`: the lateral and heading error that the
  paper's controller with the *kinematic* feedforward leaves on a curve when
  the tyres slip (closed form, linear tyres);
* :func:`zero_sideslip_ratio`: the classic speed-dependent rear-to-front
  ratio :math:`a(V)` with zero steady sideslip at the centre of gravity;
* :func:`understeer_gradient`;
* :func:`kinematic_design_limit`: the speed above which a double-root
  design made on the kinematic plant leaves the stable region of the
  dynamic plant, or its dominant poles move far from the design.

Small-angle model of the closed forms: first order in the steering angles,
the lateral velocity, the yaw rate, the errors and the curvature (the
:math:`-\kappa^2 V e` of :math:`\dot\theta` kept, as in the exact kinematic
linearisation); :func:`fws_control.symbolic.dynamic_steady_state` derives it
from Newton-Euler, and the tests hold the numeric formulas here equal to it
and to the nonlinear steady state (``scipy.optimize.fsolve``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import KW_ONLY, dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np
from scipy.optimize import brentq

from .dynamics import TYRES, dynamic_feedforward, require_dynamics
from .gains import SteeringGains
from .hints import RealArrayLike
from .plant import LateralPlant, resolve_ratio
from .pole_placement import double_root_gains
from .reprs import summary_repr
from .validation import (
    MAX_CURVATURE,
    MAX_SPEED,
    check_magnitude,
    check_scalar,
    check_type,
)
from .vehicle import Vehicle

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "understeer_gradient",
    "zero_sideslip_ratio",
    "steady_state_offset",
    "KinematicDesignLimit",
    "kinematic_design_limit",
    "DEFAULT_DESIGN_SPEEDS",
    "DEFAULT_POLE_TOLERANCE",
]

#: Default speed grid of :func:`kinematic_design_limit` [m/s].
DEFAULT_DESIGN_SPEEDS = np.arange(1.0, 60.01, 0.5)

#: Default tolerance of the dominant-pole drift, relative to the design pole.
DEFAULT_POLE_TOLERANCE = 0.25


def _check_speed(speed) -> np.ndarray | float:
    v = check_magnitude("speed", speed, MAX_SPEED, "m/s")
    if np.any(np.asarray(v) <= 0.0):
        raise ValueError(
            f"speed must be finite and > 0 m/s (at most {MAX_SPEED:g}), got {speed!r}"
        )
    return v


def _axle_data(vehicle: Vehicle) -> tuple[float, float, float, float, float]:
    """``m, l_f, l_r, C_f, C_r`` of a vehicle that passes require_dynamics."""
    require_dynamics(vehicle)
    m, c_f, c_r = vehicle.mass, vehicle.cornering_front, vehicle.cornering_rear
    assert m is not None and c_f is not None and c_r is not None  # checked above
    l_r = vehicle.cg_distance(needed_by="the dynamic model")
    return m, vehicle.wheelbase - l_r, l_r, c_f, c_r


def understeer_gradient(vehicle: Vehicle) -> float:
    r"""Understeer gradient :math:`K_{us}` [rad s^2/m] of the linear tyres.

    .. math:: K_{us} = \frac{m}{f}\left(\frac{l_r}{C_f} - \frac{l_f}{C_r}\right)

    In a steady front-steered turn :math:`\delta_f = f\kappa + K_{us}
    a_y` with :math:`a_y = V^2\kappa`; > 0 understeer, < 0 oversteer (then
    the vehicle is unstable above the critical speed
    :math:`\sqrt{-f/K_{us}}`).

    Parameters
    ----------
    vehicle : Vehicle
        With mass and cornering stiffnesses.

    Returns
    -------
    float

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, mass=1500.0,
    ...                   yaw_inertia=2600.0, cornering_front=8e4,
    ...                   cornering_rear=9.5e4)
    >>> round(fws.understeer_gradient(veh), 6)     # 1500/2.7*(1.2/8e4 - 1.5/9.5e4)
    -0.000439
    """
    require_dynamics(vehicle)
    m, l_f, l_r, c_f, c_r = _axle_data(vehicle)
    return m / vehicle.wheelbase * (l_r / c_f - l_f / c_r)


def zero_sideslip_ratio(
    vehicle: Vehicle, *, speed: RealArrayLike
) -> float | np.ndarray:
    r"""Ratio :math:`a(V) = \delta_r/\delta_f` with zero steady sideslip at G.

    .. math::
        a(V) = \frac{-l_r + \dfrac{m l_f V^2}{f C_r}}
                    {l_f + \dfrac{m l_r V^2}{f C_f}}

    (linear tyres, small angles). Counter-phase (:math:`a < 0`, tighter
    turns) below :math:`V_0 = \sqrt{f C_r l_r/(m l_f)}`, in phase above it;
    :math:`a \to -l_r/l_f` as :math:`V \to 0` and :math:`a \to C_f l_f/(C_r
    l_r)` as :math:`V \to \infty`. This is the classic proportional
    four-wheel-steering ratio of Sano, Furukawa and Shiraishi (SAE 860625,
    1986), derived e.g. in M. Abe, *Vehicle Handling Dynamics*, 2nd ed.,
    Butterworth-Heinemann 2015, section 8.2 (with :math:`C = 2K` per axle).
    :func:`fws_control.symbolic.zero_sideslip_ratio` derives it.

    Its call ``(vehicle, speed=...)`` is that of a ratio schedule: pass it
    as ``ratio=`` where a design or chart takes a ratio to evaluate it at
    the plant's speed.

    Parameters
    ----------
    vehicle : Vehicle
        With mass and cornering stiffnesses.
    speed : float or array_like
        Longitudinal speed :math:`V` [m/s], finite and > 0.

    Returns
    -------
    float or ndarray
        :math:`a(V)` [-], broadcast over `speed`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, mass=1500.0,
    ...                   yaw_inertia=2600.0, cornering_front=8e4,
    ...                   cornering_rear=9.5e4)
    >>> [round(float(a), 4) for a in fws.zero_sideslip_ratio(veh, speed=[5.0, 30.0])]
    [-0.5741, 0.7439]
    """
    require_dynamics(vehicle)
    v = np.asarray(_check_speed(speed), dtype=float)
    m, l_f, l_r, c_f, c_r = _axle_data(vehicle)
    f = vehicle.wheelbase
    num = -l_r + m * l_f * v**2 / (f * c_r)
    den = l_f + m * l_r * v**2 / (f * c_f)
    out = num / den
    return float(out) if out.ndim == 0 else out


def steady_state_offset(
    vehicle: Vehicle,
    gains: SteeringGains,
    *,
    speed: Any,
    curvature: Any,
) -> tuple[float | np.ndarray, float | np.ndarray]:
    r"""Steady lateral and heading error of the paper's loop on the dynamic model.

    The controller of the paper, :math:`\delta_f = \arctan(\kappa f) - k_1 e
    - k_2\theta`, :math:`\delta_r = a(-k_1 e - k_2\theta)`, designed for the
    kinematic model, steers the dynamic model (linear tyres) on a circle of
    curvature :math:`\kappa` at speed :math:`V`. The tyres need slip angles
    the kinematic feedforward does not supply, so the loop settles at

    .. math::
        e_{ss} = \frac{\kappa\left(P_f(1 - a k_2) - P_r(1 - k_2)\right)}{\Delta},
        \qquad
        \theta_{ss} = \frac{\kappa\left((a k_1 + P_r\kappa^2) P_f
            - (k_1 + (f + P_f)\kappa^2) P_r\right)}{\Delta},

    .. math::
        \Delta = (1 - k_2)(a k_1 + P_r\kappa^2)
                 - (1 - a k_2)(k_1 + (f + P_f)\kappa^2),\qquad
        P_f = \frac{m V^2 l_r}{f C_f},\ P_r = \frac{m V^2 l_f}{f C_r}

    (:math:`P\kappa` is the slip angle each axle needs). Without the
    :math:`\kappa^2` terms, :math:`\Delta = -k_1(1 - a)` and
    :math:`e_{ss} = \kappa(P_r(1-k_2) - P_f(1-a k_2))/(k_1(1-a))`: for front
    steering (:math:`a = 0`), :math:`-\kappa(K_{us}V^2 + k_2 P_r)/k_1`.

    This is the steady state of the small-angle model (module docstring),
    exact to first order in the angles; the nonlinear model with linear
    tyres differs by terms of relative order :math:`\kappa^2` (0.29 % of
    the offset for the example below, 20 m/s on a 100 m radius, solved with
    ``scipy.optimize.fsolve`` in ``tests/test_dynamic_steady.py``); for the
    double-root design of :data:`~fws_control.vehicles.BMW_320I`
    (:math:`\lambda_0 = -1`, ``ratio=0``) 0.34 % at 20 m/s on a 100 m
    radius and 10 % at 5 m/s on a 10 m radius (``tests/test_doc_numbers.py``):
    use it where the steering and slip angles are small. It is reached
    only if the closed loop is stable (:func:`fws_control.is_stable` on
    ``LateralPlant(..., model="dynamic")``). Saturating tyres need a
    numeric solution.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry, mass and cornering stiffnesses.
    gains : SteeringGains
        ``k1, k2, ratio``; arrays broadcast.
    speed : float or array_like
        Longitudinal speed :math:`V` [m/s], finite and > 0.
    curvature : float or array_like
        Path curvature :math:`\kappa` [1/m], finite.

    Returns
    -------
    e, theta : float or ndarray
        Steady lateral error [m] (positive left of the path) and heading
        error [rad] of the rear-axle point R.

    Raises
    ------
    ValueError
        For missing vehicle data, a non-positive speed, a non-finite
        curvature, a curve the tyres cannot hold at that speed (as
        ``LateralPlant(..., model="dynamic")``), a loop with no steady state
        (:math:`\Delta = 0`, a closed-loop pole at 0: e.g. ``k1 = 0``, or
        ``ratio = 1`` with :math:`K_{us} \ne 0`), or a solution outside the
        range of the path-frame errors (:math:`1 - \kappa e \le 0` or
        :math:`|\theta| \ge \pi/2`), where the small-angle model holds no
        steady state.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2, mass=1500.0,
    ...                   yaw_inertia=2600.0, cornering_front=8e4,
    ...                   cornering_rear=9.5e4)
    >>> g = fws.SteeringGains(k1=0.02, k2=0.3, ratio=0.0)
    >>> e, th = fws.steady_state_offset(veh, g, speed=20.0, curvature=0.01)
    >>> round(e, 4), round(th, 5)
    (-0.4309, 0.03494)
    """
    require_dynamics(vehicle)
    check_type("gains", gains, SteeringGains)
    v = np.asarray(_check_speed(speed), dtype=float)
    kappa = np.asarray(
        check_magnitude("curvature", curvature, MAX_CURVATURE, "1/m"), dtype=float
    )
    # the operating point must exist (the tyres can hold the curve), as for
    # LateralPlant(model="dynamic"): the same check, the same message
    dynamic_feedforward(vehicle, speed=v, curvature=kappa)
    m, l_f, l_r, c_f, c_r = _axle_data(vehicle)
    f = vehicle.wheelbase
    k1, k2, a = (np.asarray(x, dtype=float) for x in (gains.k1, gains.k2, gains.ratio))
    p_f = m * v**2 * l_r / (f * c_f)
    p_r = m * v**2 * l_f / (f * c_r)
    k_sq = kappa**2
    # the two steady equations, linear in (e, theta):
    #   -(k1 + (f + P_f) kappa^2) e + (1 - k2) theta = P_f kappa
    #   -(a k1 + P_r kappa^2) e + (1 - a k2) theta = P_r kappa
    m11, m12 = -(k1 + (f + p_f) * k_sq), 1.0 - k2
    m21, m22 = -(a * k1 + p_r * k_sq), 1.0 - a * k2
    det = m11 * m22 - m12 * m21
    scale = np.abs(m11 * m22) + np.abs(m12 * m21)
    if np.any(np.abs(det) <= 1e-12 * scale):
        raise ValueError(
            "the loop has no steady state for these gains (a closed-loop pole at "
            f"s = 0): k1={gains.k1!r}, k2={gains.k2!r}, ratio={gains.ratio!r}; "
            "k1 must be nonzero and ratio = 1 is uncontrollable"
        )
    e = kappa * (p_f * m22 - m12 * p_r) / det
    theta = kappa * (m11 * p_r - m21 * p_f) / det
    # The closed form is a first-order answer: outside the range where the
    # path-frame errors mean anything (R on the path's side of the centre,
    # |theta| < pi/2) it is a number with no steady state behind it.
    bad = ~((1.0 - kappa * e > 0.0) & (np.abs(theta) < 0.5 * math.pi))
    if np.any(bad):
        i = np.unravel_index(int(np.argmax(bad)), np.shape(bad)) if np.ndim(bad) else ()
        # the first such point, each argument at that point (bounded message)
        vi, ki, g1, g2, ga, ei, thi = (
            float(np.broadcast_to(x, np.shape(bad))[i])
            for x in (v, kappa, k1, k2, a, e, theta)
        )
        raise ValueError(
            f"no steady state near the path at speed={vi!r} m/s, curvature={ki!r} "
            f"1/m with k1={g1!r}, k2={g2!r}, ratio={ga!r}: the small-angle "
            f"solution e={ei:.4g} m, theta={thi:.4g} rad lies outside the range "
            "of the path-frame model (1 - curvature*e > 0, |theta| < pi/2)"
        )
    if np.ndim(e) == 0:
        return float(e), float(theta)
    return e, theta


def _design_poles(vehicle, ratio, pole, curvature, tyre, speeds):
    """Kinematic double-root designs and the poles they give the dynamic plant."""
    dyn = LateralPlant(
        vehicle, speed=speeds, curvature=curvature, model="dynamic", tyre=tyre
    )
    kin = LateralPlant(vehicle, speed=speeds, curvature=curvature, model="kinematic")
    a = np.broadcast_to(
        np.asarray(resolve_ratio(dyn, ratio), dtype=float), speeds.shape
    )
    gains = double_root_gains(kin, ratio=a, pole=pole)
    A, B = dyn.matrices()
    # closed loop of the structured law [delta_f, delta_r] = [1, a] (-k1 e - k2 theta)
    b = B[..., 0] + a[..., np.newaxis] * B[..., 1]
    k = np.zeros(speeds.shape + (A.shape[-1],))
    k[..., 0], k[..., 1] = gains.k1, gains.k2
    poles = np.linalg.eigvals(A - b[..., :, np.newaxis] * k[..., np.newaxis, :])
    order = np.argsort(-poles.real, axis=-1, kind="stable")
    poles = np.take_along_axis(poles, order, axis=-1)
    # the two rightmost poles are the ones the design placed at lambda_0
    drift = np.max(np.abs(poles[..., :2] - pole), axis=-1) / abs(pole)
    return a, gains, poles, drift


def _first_crossing(speeds, values, fun):
    """First speed where `values` turns > 0, refined by bisection on `fun`."""
    above = values > 0.0
    if not np.any(above):
        return math.inf
    i = int(np.argmax(above))
    if i == 0:
        return float(speeds[0])
    return float(brentq(fun, speeds[i - 1], speeds[i], xtol=1e-9, rtol=1e-12))


@summary_repr
@dataclass(frozen=True, eq=False)
class KinematicDesignLimit:
    r"""Where a kinematic double-root design stops describing the dynamic plant.

    Result of :func:`kinematic_design_limit`.

    Attributes
    ----------
    vehicle : Vehicle
        The vehicle.
    pole : float
        Design double root :math:`\lambda_0` [1/s].
    curvature : float
        Path curvature [1/m] of the operating points.
    tyre : str
        Tyre model of the dynamic plant.
    tolerance : float
        Allowed drift of the dominant poles, relative to :math:`|\lambda_0|`.
    speeds : ndarray
        Speed grid [m/s], shape ``(n,)``.
    ratio : ndarray
        Ratio :math:`a` at each speed (a schedule evaluated), shape ``(n,)``.
    gains : SteeringGains
        The kinematic designs, arrays of shape ``(n,)``.
    poles : ndarray
        Closed-loop poles of the dynamic plant, shape ``(n, 4)``, rightmost
        first.
    drift : ndarray
        :math:`\max |p_i - \lambda_0|/|\lambda_0|` over the two rightmost
        poles, shape ``(n,)``.
    unstable_speed : float
        Lowest speed at which the closed loop is unstable (bisection between
        grid points); ``inf`` if stable on the whole grid.
    drift_speed : float
        Lowest speed at which `drift` exceeds `tolerance`; ``inf`` if never.

    Examples
    --------
    >>> import fws_control as fws
    >>> lim = fws.kinematic_design_limit(fws.vehicles.BMW_320I, ratio=0.5,
    ...                                  pole=-1.0, speeds=[10.0, 30.0, 50.0])
    >>> lim.poles.shape, bool(lim.stable.all()), round(lim.limit_speed, 1)
    ((3, 4), True, 34.3)
    """

    vehicle: Vehicle
    _: KW_ONLY  # a result record: every field named at construction
    pole: float
    curvature: float
    tyre: str
    tolerance: float
    speeds: np.ndarray
    ratio: np.ndarray
    gains: SteeringGains
    poles: np.ndarray
    drift: np.ndarray
    unstable_speed: float
    drift_speed: float

    @property
    def stable(self) -> np.ndarray:
        """Boolean mask of the grid speeds at which the closed loop is stable."""
        return np.all(self.poles.real < 0.0, axis=-1)

    @property
    def limit_speed(self) -> float:
        """The lower of :attr:`unstable_speed` and :attr:`drift_speed` [m/s]."""
        return min(self.unstable_speed, self.drift_speed)

    def plot(self, ax: Axes | None = None) -> ct.ControlPlot:
        """Dominant-pole drift against speed, with the limit speeds marked.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure if None.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> lim = fws.kinematic_design_limit(fws.vehicles.BMW_320I, ratio=0.0,
        ...                                  pole=-2.0, speeds=[5.0, 20.0, 40.0])
        >>> cplt = lim.plot()
        >>> cplt.axes[0, 0].get_xlabel()
        'speed V [m/s]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6.5, 4.2), layout="constrained")
        lines = []
        (ln,) = ax.plot(self.speeds, self.drift, "-", color="C0", label="pole drift")
        lines.append(ln)
        lines.append(
            ax.axhline(
                self.tolerance,
                color="k",
                ls="--",
                lw=1.0,
                label=f"tolerance {self.tolerance:g}",
            )  # fmt: skip
        )
        unstable = ~self.stable
        if np.any(unstable):
            (m,) = ax.plot(
                self.speeds[unstable], self.drift[unstable], "x", color="C3",
                label="unstable",
            )  # fmt: skip
            lines.append(m)
        for speed, what, color in (
            (self.drift_speed, "drift limit", "C1"),
            (self.unstable_speed, "stability limit", "C3"),
        ):
            if math.isfinite(speed):
                lines.append(
                    ax.axvline(
                        speed,
                        color=color,
                        lw=1.0,
                        label=f"{what} {speed:.1f} m/s",
                    )  # fmt: skip
                )
        ax.set_xlabel("speed V [m/s]")
        ax.set_ylabel(r"max $|p - \lambda_0| / |\lambda_0|$ (two dominant poles)")
        ax.grid(alpha=0.3)
        ax.set_title(
            rf"kinematic design $\lambda_0$ = {self.pole:g} 1/s on the dynamic "
            "plant,\n"
            rf"$\kappa$ = {self.curvature:g} 1/m, {self.tyre} tyres",
            fontsize=10,
        )
        leg = ax.legend(fontsize=8)
        arr = np.empty((1, 1), dtype=object)
        arr[0, 0] = lines
        return ct.ControlPlot(arr, np.array([[ax]]), ax.figure, legend=leg)


def kinematic_design_limit(
    vehicle: Vehicle,
    *,
    ratio: float | Callable[..., Any],
    pole: float,
    curvature: float = 0.0,
    speeds: Any = None,
    tolerance: float = DEFAULT_POLE_TOLERANCE,
    tyre: str = "linear",
) -> KinematicDesignLimit:
    r"""Speed above which a kinematic double-root design fails on the dynamic plant.

    At every speed of the grid the gains are designed on the kinematic
    plant (``LateralPlant(..., model="kinematic")``, :func:`double_root_gains`,
    both poles at :math:`\lambda_0`) and applied to the dynamic plant
    (``model="dynamic"``, 4 states). The result records where the closed
    loop becomes unstable and where its two dominant poles drift more than
    ``tolerance * |pole|`` from :math:`\lambda_0`; both speeds are refined
    between grid points by bisection (:func:`scipy.optimize.brentq`).

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and dynamic data.
    ratio : float or callable
        Rear-to-front ratio :math:`a`, or a schedule ``ratio(vehicle,
        speed=...)`` such as :func:`zero_sideslip_ratio`.
    pole : float
        Design double root :math:`\lambda_0` [1/s], finite and < 0.
    curvature : float, optional
        Path curvature [1/m] of the operating points (default 0, straight).
    speeds : array_like, optional
        Increasing 1-D grid of speeds [m/s], > 0; default
        :data:`DEFAULT_DESIGN_SPEEDS` (1 to 60 m/s in steps of 0.5).
    tolerance : float, optional
        Allowed relative drift of the dominant poles, > 0 (default 0.25).
    tyre : {"linear", "magic"}, optional
        Tyre model of the dynamic plant.

    Returns
    -------
    KinematicDesignLimit

    Raises
    ------
    ValueError
        For missing vehicle data, a non-negative `pole`, a bad speed grid
        or tolerance, or an uncontrollable kinematic design.

    Examples
    --------
    >>> import fws_control as fws
    >>> lim = fws.kinematic_design_limit(fws.vehicles.BMW_320I, ratio=0.0,
    ...                                  pole=-2.0)
    >>> round(lim.drift_speed, 1), lim.unstable_speed
    (17.2, inf)
    """
    require_dynamics(vehicle, tyre=tyre)
    if not isinstance(tyre, str) or tyre not in TYRES:
        raise ValueError(f"tyre must be one of {TYRES}, got {tyre!r}")
    pole = check_scalar("pole", pole)
    if pole >= 0.0:
        raise ValueError(f"pole must be finite and < 0, got {pole!r}")
    curvature = check_scalar("curvature", curvature)
    tolerance = check_scalar("tolerance", tolerance)
    if tolerance <= 0.0:
        raise ValueError(f"tolerance must be > 0, got {tolerance!r}")
    grid = DEFAULT_DESIGN_SPEEDS if speeds is None else speeds
    grid = np.atleast_1d(
        np.asarray(check_magnitude("speeds", grid, MAX_SPEED, "m/s"), dtype=float)
    )
    if (
        grid.ndim != 1
        or grid.size == 0
        or np.any(grid <= 0)
        or np.any(np.diff(grid) <= 0)
    ):
        raise ValueError(
            "speeds must be a non-empty, increasing 1-D grid of speeds > 0 m/s, "
            f"got {speeds!r}"
        )
    if not callable(ratio):
        ratio = check_scalar("ratio", ratio)
    try:
        a, gains, poles, drift = _design_poles(
            vehicle, ratio, pole, curvature, tyre, grid
        )
    except ValueError as exc:
        # a grid speed at which no design or operating point exists (a speed
        # of 1e-300 m/s, a curve the tyres cannot hold): say which argument
        raise ValueError(
            f"speeds: no kinematic design on the dynamic plant over {speeds!r}: {exc}"
        ) from exc

    def at(speed):
        return _design_poles(vehicle, ratio, pole, curvature, tyre, np.array([speed]))

    unstable = _first_crossing(
        grid, np.max(poles.real, axis=-1), lambda v: float(np.max(at(v)[2].real))
    )
    drifted = _first_crossing(
        grid, drift - tolerance, lambda v: float(at(v)[3][0]) - tolerance
    )
    return KinematicDesignLimit(
        vehicle=vehicle,
        pole=pole,
        curvature=curvature,
        tyre=tyre,
        tolerance=tolerance,
        speeds=grid,
        ratio=a,
        gains=gains,
        poles=poles,
        drift=drift,
        unstable_speed=unstable,
        drift_speed=drifted,
    )
