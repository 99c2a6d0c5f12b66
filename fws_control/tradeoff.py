r"""The trade-off of a delayed loop: decay rate against delay margin and effort.

The most-stable gains (:func:`~fws_control.most_stable_gains`) decay
fastest, but they are not the gains that tolerate the most delay: the
critical delay grows without bound as the gains go to zero, and so does the
decay time. Between the two lies the **Pareto front**: gains where more
delay margin (or less steering effort) costs decay rate, and no gains do
better in both.

Method: epsilon-constraint
--------------------------
The front is computed point by point, each the solution of

.. math::
    \max_{k}\; -\alpha(k; \tau) \quad\text{subject to}\quad
    \tau_c(k) \ge \tau_i,

for a grid of margins :math:`\tau_i` from the critical delay of the
most-stable design (the knee of the front, where the constraint starts to
bind) upwards. Scalarisation (a weighted sum of the two objectives) would
miss the parts of the front that are not convex; the epsilon constraint
finds every part. Above the knee the constraint is active, so the search
runs along the level curve :math:`\tau_c(k) = \tau_i`: it is parametrised by
rays from the origin of the gain plane through the quadrant of the knee's
gains (the critical delay is infinite at zero gain and falls along each ray;
the crossing is found on a grid of the ray and refined by vectorised
subdivision of :func:`~fws_control.critical_delay`), and the abscissa along
it (one :func:`~fws_control.rightmost_roots` call per point) is minimised
over the ray angle by a scan and a bounded Brent search, which needs no
gradient at the kinks of the spectral abscissa.

Steering effort is :math:`|k_1|`, the step the front command takes for a
1 m step of the lateral error (the rear command takes :math:`a` times it).
Through a first-order steering lag :math:`T` the steering rate just after
that step is :math:`|k_1| e_0/T`, so the effort also ranks the steering
rates a step of the error asks for; a norm of :math:`(k_1, k_2)` would add
numbers of different units. For a cap :math:`|k_1| \le c_j`
below the knee's, the constraint is active and the decay is maximised over
:math:`k_2` alone (scan and Brent).

The returned points are checked for non-dominance: a point that another
returned point beats in both objectives is dropped (and counted).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from .delay import critical_delay, rightmost_roots
from .delay_design import MostStableDesign, most_stable_gains
from .gains import SteeringGains
from .plant import as_plant
from .reprs import summary_repr
from .validation import check_delay, check_scalar

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["ParetoFront", "pareto_front"]

#: Ray lengths (in units of the knee's gains) scanned for the margin level.
_RAY = np.geomspace(1e-3, 8.0, 241)


@summary_repr
@dataclass(frozen=True, eq=False)
class ParetoFront:
    r"""Pareto fronts of decay rate against delay margin and steering effort.

    Returned by :func:`pareto_front`; do not build it directly. Both fronts
    start at the most-stable design (the knee).

    Attributes
    ----------
    design : MostStableDesign
        The most-stable design the fronts start from.
    delay : float
        The delay :math:`\tau` [s] the decay rates are for.
    ratio : float
        The rear-to-front ratio :math:`a` of every point.
    margin_gains : SteeringGains
        Gains of the decay/delay-margin front (arrays), by rising margin.
    margin_decay : ndarray
        Their decay rates :math:`-\alpha` [1/s] at `delay`.
    margin : ndarray
        Their critical delays [s] (the delay margin).
    effort_gains : SteeringGains
        Gains of the decay/effort front (arrays), by falling effort.
    effort_decay : ndarray
        Their decay rates :math:`-\alpha` [1/s] at `delay`.
    effort : ndarray
        Their steering effort :math:`|k_1|` [rad/m].
    dropped : int
        Computed points dropped as dominated by another one.
    evaluations : int
        Rightmost-root computations the fronts took (the knee's search not
        included).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0)
    >>> front = fws.pareto_front(plant, delay=0.24, points=3, grid=6)
    >>> [round(float(v), 3) for v in front.margin_decay]
    [2.441, 0.656, 0.404]
    >>> [round(float(v), 3) for v in front.margin]
    [0.606, 1.211, 1.817]
    """

    design: MostStableDesign
    delay: float
    ratio: float
    margin_gains: SteeringGains
    margin_decay: np.ndarray
    margin: np.ndarray
    effort_gains: SteeringGains
    effort_decay: np.ndarray
    effort: np.ndarray
    dropped: int
    evaluations: int

    def plot(self, ax: Sequence[Axes] | np.ndarray | None = None) -> ct.ControlPlot:
        """Both fronts: decay rate against delay margin and against effort.

        Parameters
        ----------
        ax : array of two matplotlib.axes.Axes, optional
            Axes to draw on (margin front, effort front); a new figure if
            None.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> plant = fws.LateralPlant(veh, speed=20.0, steering_lag=0.27)
        >>> front = fws.pareto_front(plant, delay=0.24, points=3, grid=6)
        >>> cplt = front.plot()
        >>> cplt.axes[0, 0].get_xlabel()
        'delay margin (critical delay) [s]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        if ax is None:
            fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.8), layout="constrained")
        else:
            axes = np.ravel(np.asarray(ax, dtype=object))
            if axes.size != 2:
                raise ValueError(f"ax must hold two axes, got {axes.size}")
            fig = axes[0].figure
        lines = []
        xlabels = (
            "delay margin (critical delay) [s]",
            "steering effort $|k_1|$ [rad/m]",
        )
        for a, x, y, xl in (
            (axes[0], self.margin, self.margin_decay, xlabels[0]),
            (axes[1], self.effort, self.effort_decay, xlabels[1]),
        ):
            (ln,) = a.plot(x, y, "o-", color="C0", label="Pareto front")
            (kn,) = a.plot(x[0], y[0], "r*", ms=12, label="most stable")
            lines += [ln, kn]
            a.set_xlabel(xl)
            a.set_ylabel(r"decay rate $-\alpha$ [1/s]")
            a.grid(True, alpha=0.3)
        # efforts of 1e-4 rad/m would print as long decimals that overlap
        axes[1].ticklabel_format(axis="x", style="sci", scilimits=(-2, 3))
        axes[0].set_title(f"delay {self.delay:g} s, a = {self.ratio:.3g}")
        axes[1].set_title("effort: front command per metre of error")
        leg = axes[0].legend(loc="best", fontsize=8)
        return ct.ControlPlot(lines, np.array([list(axes)]), fig, legend=leg)


class _Abscissa:
    """alpha(k1, k2) at one plant, delay and ratio; counts the evaluations."""

    def __init__(self, plant, tau: float, ratio: float):
        self.plant, self.tau, self.ratio = plant, tau, ratio
        self.evaluations = 0

    def __call__(self, k1: float, k2: float) -> float:
        self.evaluations += 1
        g = SteeringGains(float(k1), float(k2), self.ratio)
        try:
            return float(
                rightmost_roots(self.plant, g, delay=self.tau, n=1, nodes=10)[0].real
            )
        except RuntimeError:  # not converged: counts as no improvement
            return math.inf


def _check_count(name: str, value: Any, low: int, high: int) -> int:
    if (
        isinstance(value, (bool, np.bool_))
        or not isinstance(value, (int, np.integer))
        or not low <= value <= high
    ):
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


def _level_crossing(plant, ratio: float, u: np.ndarray, level: float):
    """Largest gain ``r u`` on the ray whose critical delay stays >= `level`.

    The first crossing below `level` from the origin, bracketed on
    :data:`_RAY` and narrowed by three passes of 64 points; None if the ray
    starts below the level or never falls below it within the scan.
    """
    r = _RAY
    for _ in range(4):
        cd = np.asarray(
            critical_delay(plant, SteeringGains(r * u[0], r * u[1], ratio)).delay
        )
        below = np.flatnonzero(~(cd >= level))
        if below.size == 0:
            return None if r is _RAY else r[-1]
        j = int(below[0])
        if j == 0:
            return None if r is _RAY else r[0]
        lo, hi = r[j - 1], r[j]
        r = np.linspace(lo, hi, 64)
    return float(lo)


def _brent(f, x0: float, lo: float, hi: float, tol: float) -> tuple[float, float]:
    """Bounded Brent minimisation of `f` on [lo, hi]; the better of it and x0."""
    from scipy.optimize import minimize_scalar

    f0 = f(x0)
    res = minimize_scalar(
        f, bounds=(lo, hi), method="bounded", options={"xatol": tol, "maxiter": 30}
    )
    if res.fun < f0:
        return float(res.x), float(res.fun)
    return x0, f0


def _non_dominated(decay: np.ndarray, other: np.ndarray, *, more: bool) -> np.ndarray:
    """Mask of points no other point beats in decay and in `other`."""
    o = other if more else -other
    keep = np.ones(decay.size, dtype=bool)
    for i in range(decay.size):
        better = (decay >= decay[i]) & (o >= o[i])
        strictly = (decay > decay[i] * (1 + 1e-12) + 1e-15) | (
            o > o[i] + 1e-12 * abs(o[i])
        )
        better[i] = False
        keep[i] = not np.any(better & strictly)
    return keep


def pareto_front(
    plant: Any,
    *,
    delay: float,
    ratio: float = 0.0,
    points: int = 8,
    max_margin: float | None = None,
    min_effort: float | None = None,
    directions: int = 9,
    grid: int = 10,
    design: MostStableDesign | None = None,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> ParetoFront:
    r"""Pareto fronts of decay rate against delay margin and steering effort.

    Epsilon-constraint (see :mod:`fws_control.tradeoff`): for each margin
    :math:`\tau_i` of a uniform grid from the most-stable design's critical
    delay to `max_margin`, the gains of largest decay rate
    :math:`-\alpha` at `delay` with a critical delay of at least
    :math:`\tau_i`; for each effort cap :math:`c_j` of a uniform grid from
    the most-stable :math:`|k_1|` down to `min_effort`, the gains of largest
    decay rate with :math:`|k_1| = c_j`. The ratio is held fixed.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant, any order, as in :func:`most_stable_gains`.
    delay : float
        Input delay :math:`\tau` [s] the decay rate is for, in (0, 1000].
    ratio : float, optional
        Rear-to-front ratio :math:`a` (ignored with `design`, whose ratio is
        used).
    points : int, optional
        Points per front (the knee included), 2 to 40.
    max_margin : float, optional
        Largest delay margin [s], above the knee's critical delay; default
        three times it.
    min_effort : float, optional
        Smallest effort :math:`|k_1|` [rad/m], in (0, knee's); default a
        tenth of the knee's.
    directions : int, optional
        Ray angles scanned per margin before the Brent search, 5 to 101.
    grid : int, optional
        Start grid of the most-stable search (as in
        :func:`most_stable_gains`), when `design` is not given.
    design : MostStableDesign, optional
        The most-stable design of this plant and delay, if already computed.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    ParetoFront

    Raises
    ------
    ValueError
        For a bad argument, a `design` for another delay, a design whose
        gain is 0 (no ray through it) or no delay margin (the knee tolerates
        any delay).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0)
    >>> front = fws.pareto_front(plant, delay=0.24, points=3, grid=6)
    >>> [round(float(v), 5) for v in front.effort]
    [0.00927, 0.0051, 0.00093]
    """
    tau = check_delay(delay)
    if not 0.0 < tau <= 1e3:
        raise ValueError(f"delay must be in (0, 1000] s, got {delay!r}")
    n_points = _check_count("points", points, 2, 40)
    n_dir = _check_count("directions", directions, 5, 101)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    if design is None:
        design = most_stable_gains(p, delay=tau, ratio=ratio, grid=grid)
    elif not isinstance(design, MostStableDesign):
        raise TypeError(
            f"design must be a MostStableDesign, got {type(design).__name__}"
        )
    elif not math.isclose(design.delay, tau, rel_tol=1e-12):
        raise ValueError(
            f"design is for delay {design.delay!r} s, not delay={delay!r} s"
        )
    g0 = design.gains
    a = float(g0.ratio)
    k1s, k2s = float(g0.k1), float(g0.k2)
    if k1s == 0.0 or k2s == 0.0:
        raise ValueError(
            f"the most-stable gains (k1={k1s!r}, k2={k2s!r}) must both be nonzero "
            "to span the rays of the front"
        )
    tc0 = float(design.critical_delay)
    if not math.isfinite(tc0):
        raise ValueError(
            "the most-stable design tolerates any delay (critical delay inf): "
            "there is no trade-off with the delay margin"
        )
    top = 3.0 * tc0 if max_margin is None else check_scalar("max_margin", max_margin)
    if not top > tc0:
        raise ValueError(
            f"max_margin must exceed the most-stable critical delay {tc0:.6g} s, "
            f"got {max_margin!r}"
        )
    low = (
        abs(k1s) / 10.0
        if min_effort is None
        else check_scalar("min_effort", min_effort)
    )
    if not 0.0 < low < abs(k1s):
        raise ValueError(
            f"min_effort must be in (0, {abs(k1s):.6g}) rad/m (the most-stable "
            f"|k1|), got {min_effort!r}"
        )
    alpha = _Abscissa(p, tau, a)
    scale = math.sqrt(2.0)
    step = 0.5 * math.pi / n_dir
    phis = (np.arange(n_dir) + 0.5) * step

    def ray(phi: float) -> np.ndarray:
        return scale * np.array([k1s * math.cos(phi), k2s * math.sin(phi)])

    # the margin front: maximise the decay on the level curve tau_c = level
    m_k1, m_k2, m_alpha = [k1s], [k2s], [design.abscissa]
    for level in np.linspace(tc0, top, n_points)[1:]:
        cache: dict[float, tuple[float, np.ndarray]] = {}

        def on_level(phi: float, level=level, cache=cache) -> float:
            u = ray(phi)
            r = _level_crossing(p, a, u, level)
            if r is None:
                return math.inf
            k = r * u
            value = alpha(k[0], k[1])
            cache[float(phi)] = (value, k)
            return value

        scan = np.array([on_level(f) for f in phis])
        if not np.isfinite(scan).any():
            continue
        j = int(np.argmin(scan))
        phi, _ = _brent(
            on_level, float(phis[j]), max(phis[j] - step, 1e-6),
            min(phis[j] + step, 0.5 * math.pi - 1e-6), 1e-5 * step,
        )  # fmt: skip
        value, k = cache[float(phi)]
        m_k1.append(float(k[0]))
        m_k2.append(float(k[1]))
        m_alpha.append(value)
    # the effort front: |k1| = cap, maximise the decay over k2
    e_k1, e_k2, e_alpha = [k1s], [k2s], [design.abscissa]
    lk2 = np.linspace(math.log(abs(k2s) / 20.0), math.log(3.0 * abs(k2s)), n_dir)
    dl = lk2[1] - lk2[0]
    for cap in np.linspace(abs(k1s), low, n_points)[1:]:
        c = math.copysign(cap, k1s)

        def at_cap(lk: float, c=c) -> float:
            return alpha(c, math.copysign(math.exp(lk), k2s))

        scan = np.array([at_cap(v) for v in lk2])
        if not np.isfinite(scan).any():
            continue
        j = int(np.argmin(scan))
        lk, value = _brent(at_cap, float(lk2[j]), lk2[j] - dl, lk2[j] + dl, 1e-6)
        e_k1.append(c)
        e_k2.append(math.copysign(math.exp(lk), k2s))
        e_alpha.append(value)

    m_gains = SteeringGains(np.array(m_k1), np.array(m_k2), a)
    margin = np.asarray(critical_delay(p, m_gains).delay, dtype=float)
    m_decay = -np.array(m_alpha)
    e_decay = -np.array(e_alpha)
    effort = np.abs(np.array(e_k1))
    keep_m = _non_dominated(m_decay, margin, more=True)
    keep_e = _non_dominated(e_decay, effort, more=False)
    dropped = int(np.sum(~keep_m) + np.sum(~keep_e))
    return ParetoFront(
        design=design,
        delay=tau,
        ratio=a,
        margin_gains=SteeringGains(
            np.asarray(m_gains.k1)[keep_m], np.asarray(m_gains.k2)[keep_m], a
        ),
        margin_decay=m_decay[keep_m],
        margin=margin[keep_m],
        effort_gains=SteeringGains(np.array(e_k1)[keep_e], np.array(e_k2)[keep_e], a),
        effort_decay=e_decay[keep_e],
        effort=effort[keep_e],
        dropped=dropped,
        evaluations=alpha.evaluations,
    )
