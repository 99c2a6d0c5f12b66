r"""Most-stable gains of the delayed loop: minimal spectral abscissa.

With an input delay :math:`\tau` the characteristic quasi-polynomial of the
structured loop is

.. math::
    D(s) = d(s) + e^{-s\tau}\bigl(k_1 n_1(s; a) + k_2 n_2(s; a)\bigr),

affine in :math:`(k_1, k_2)` and, through the input column
:math:`\mathbf b = \mathbf B_f + a\mathbf B_r`, in the ratio :math:`a` for
fixed gains. Its spectral abscissa :math:`\alpha = \max \operatorname{Re}
s` over the roots is the decay rate of the slowest mode. :math:`\alpha` is
nonsmooth: at the optimum, roots of different branches have the same real
part (they collide or coalesce) and the gradient jumps there. The search
therefore follows Lewis and Overton (*Math. Program.* 141, 2013): BFGS with
a weak-Wolfe line search that brackets by bisection and doubling, which
keeps descending along the valleys of a nonsmooth function where a smooth
optimiser stops at the first kink, restarted from the best points of a grid
of the gain plane (the delayed stability chart).

The gradient of :math:`\alpha` at a simple rightmost root :math:`s^*` is
:math:`\operatorname{Re}(-\partial_x D / \partial_s D)` at :math:`s^*`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from .delay import critical_delay, rightmost_roots, unstable_root_count
from .gains import SteeringGains
from .linear import affine_characteristic_polynomial, horner
from .plant import as_plant, loop_matrices
from .validation import check_delay, check_scalar

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["MostStableDesign", "most_stable_gains"]


@dataclass(frozen=True, kw_only=True)
class MostStableDesign:
    r"""Gains of minimal spectral abscissa of a delayed loop, with a certificate.

    Attributes
    ----------
    gains : SteeringGains
        The most-stable gains :math:`(k_1, k_2, a)`.
    abscissa : float
        Spectral abscissa :math:`\alpha` [1/s], the real part of the
        rightmost root (the slowest decay is :math:`e^{\alpha t}`).
    roots : ndarray of complex
        The roots with real part in :math:`[\alpha - m, \alpha]`
        (`m` the margin asked for), rightmost first, each polished by
        Newton's method on :math:`D(s)`.
    residual : float
        Largest :math:`|D(s)| / (|d(s)| + |e^{-s\tau} q(s)|)` over `roots`.
    roots_right : int
        Roots with real part above :math:`\alpha + \varepsilon` counted by
        the argument principle (0 certifies that no root was missed).
    epsilon : float
        The :math:`\varepsilon` [1/s] of `roots_right`.
    critical_delay : float
        The delay margin [s] of the design (``inf``: none).
    delay : float
        The delay [s] the design is for.
    evaluations : int
        Rightmost-root computations the search took.
    k1, k2, abscissa_grid : ndarray
        The start grid and the abscissa on it, for :meth:`plot`.
    grid_ratio : float
        The ratio of the start grid (the starting ratio).
    plant : LateralPlant or control.StateSpace
        The plant the design is for.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0, steering_lag=0.27)
    >>> best = fws.most_stable_gains(plant, delay=0.24, ratio=0.0, grid=6)
    >>> round(best.abscissa, 3), best.roots_right
    (-0.916, 0)
    """

    gains: SteeringGains
    abscissa: float
    roots: np.ndarray
    residual: float
    roots_right: int
    epsilon: float
    critical_delay: float
    delay: float
    evaluations: int
    k1: np.ndarray
    k2: np.ndarray
    abscissa_grid: np.ndarray
    grid_ratio: float
    plant: Any

    @property
    def certified(self) -> bool:
        """Whether the roots solve D (residual <= 1e-9) and none was missed."""
        return bool(self.residual <= 1e-9 and self.roots_right == 0)

    def plot(self, ax: Axes | None = None) -> ct.ControlPlot:
        """The delayed stability chart with contours of the abscissa and the optimum.

        Chart and contours are at the ratio of the start grid; with a free
        ratio the optimum may lie at another ratio (its value is in the
        legend).

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
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> plant = fws.LateralPlant(veh, speed=20.0, steering_lag=0.27)
        >>> best = fws.most_stable_gains(plant, delay=0.24, ratio=0.0, grid=6)
        >>> cplt = best.plot()
        >>> cplt.axes[0, 0].get_xlabel()
        '$k_1$ [rad/m]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        from .charts import stability_chart

        if ax is None:
            _, ax = plt.subplots(figsize=(6.5, 4.6), layout="constrained")
        ratio = self.grid_ratio
        k1 = np.linspace(self.k1[0], self.k1[-1], 121)
        k2 = np.linspace(self.k2[0], self.k2[-1], 121)
        chart = stability_chart(self.plant, ratio=ratio, k1=k1, k2=k2, delay=self.delay)
        chart.plot(ax=ax, design=False, notes=False, title=False, legend=False)
        levels = np.linspace(self.abscissa, 0.0, 8)
        cs = ax.contour(
            self.k1, self.k2, self.abscissa_grid, levels=levels, cmap="viridis"
        )
        ax.clabel(cs, fmt="%.2f", fontsize=7)
        (mark,) = ax.plot(
            float(self.gains.k1), float(self.gains.k2), "r*", ms=12,
            label=(
                f"most stable: $\\alpha$ = {self.abscissa:.3f} 1/s, "
                f"a = {float(self.gains.ratio):.3g}"
            ),
        )  # fmt: skip
        ax.set_xlabel("$k_1$ [rad/m]")
        ax.set_ylabel("$k_2$ [rad/rad]")
        ax.set_title(
            f"delay {self.delay:g} s, a = {ratio:.3g}: contours of the abscissa [1/s]"
        )
        leg = ax.legend(loc="best", fontsize=8)
        return ct.ControlPlot([cs, mark], np.array([[ax]]), ax.figure, legend=leg)


class _Loop:
    """D(s; k1, k2, a) of one plant and delay, its abscissa and gradient."""

    def __init__(self, plant, tau: float):
        self.plant = plant
        self.tau = tau
        cp0 = affine_characteristic_polynomial(plant, ratio=0.0)
        cp1 = affine_characteristic_polynomial(plant, ratio=1.0)
        self.d = np.asarray(cp0.open_loop, dtype=float)
        # n1, n2 are linear in the ratio (the input column is)
        self.n1 = np.asarray(cp0.n1, dtype=float)
        self.n2 = np.asarray(cp0.n2, dtype=float)
        self.dn1 = np.asarray(cp1.n1, dtype=float) - self.n1
        self.dn2 = np.asarray(cp1.n2, dtype=float) - self.n2
        self.evaluations = 0

    def q(self, k1, k2, a):
        return k1 * (self.n1 + a * self.dn1) + k2 * (self.n2 + a * self.dn2)

    def root(self, k1, k2, a) -> complex:
        self.evaluations += 1
        g = SteeringGains(float(k1), float(k2), float(a))
        return complex(rightmost_roots(self.plant, g, delay=self.tau, n=1)[0])

    def trial(self, k1, k2, a) -> complex | None:
        """The rightmost root at a search point, None where it is not found.

        A start-grid or line-search point where :func:`rightmost_roots` does
        not converge counts as no improvement (the search backs off); the
        returned design is certified on its own.
        """
        try:
            return self.root(k1, k2, a)
        except RuntimeError:
            return None

    def gradient(self, k1, k2, a, s) -> np.ndarray:
        """d(Re s)/d(k1, k2, a) at a simple root s."""
        tau = self.tau
        q = self.q(k1, k2, a)
        e = np.exp(-s * tau)
        dD = horner(np.polyder(self.d), s) + e * (
            horner(np.polyder(q), s) - tau * horner(q, s)
        )
        parts = (
            horner(self.n1 + a * self.dn1, s),
            horner(self.n2 + a * self.dn2, s),
            horner(k1 * self.dn1 + k2 * self.dn2, s),
        )
        return np.array([(-e * p / dD).real for p in parts])


def _bfgs(f, x0: np.ndarray, *, max_iter: int = 60, tol: float = 1e-9):
    """Minimise a nonsmooth `f` (returns value, gradient) by BFGS.

    Lewis and Overton's weak-Wolfe line search (bisection and doubling),
    stopped when the line search cannot descend or the step is below `tol`.
    """
    x = np.asarray(x0, dtype=float)
    fx, gx = f(x)
    H = np.eye(x.size)
    for _ in range(max_iter):
        p = -H @ gx
        slope = float(gx @ p)
        if not slope < 0.0:
            H = np.eye(x.size)
            p = -gx
            slope = float(gx @ p)
            if not slope < 0.0:
                break
        lo, hi, t = 0.0, math.inf, 1.0
        found = None
        for _ls in range(40):
            xt = x + t * p
            ft, gt = f(xt)
            if not (ft <= fx + 1e-4 * t * slope):  # not enough decrease
                hi = t
            elif float(gt @ p) < 0.5 * slope:  # still steep: go further
                lo = t
                found = (xt, ft, gt)
            else:
                found = (xt, ft, gt)
                break
            t = 2.0 * lo if hi == math.inf else 0.5 * (lo + hi)
            if hi - lo < 1e-12:
                break
        if found is None or found[1] >= fx:
            break
        xn, fn, gn = found
        sk, yk = xn - x, gn - gx
        x, fx, gx = xn, fn, gn
        sy = float(sk @ yk)
        if sy > 1e-16 * float(np.linalg.norm(sk) * np.linalg.norm(yk)):
            rho = 1.0 / sy
            V = np.eye(x.size) - rho * np.outer(sk, yk)
            H = V @ H @ V.T + rho * np.outer(sk, sk)
        if np.linalg.norm(sk) <= tol * (1.0 + np.linalg.norm(x)):
            break
    return x, fx


def _check_bounds(name: str, value) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (low, high), got {value!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} must be finite with low < high, got {value!r}")
    return lo, hi


def most_stable_gains(
    plant: Any,
    *,
    delay: float,
    ratio: float = 0.0,
    ratio_bounds: tuple[float, float] | None = None,
    k1_bounds: tuple[float, float] | None = None,
    k2_bounds: tuple[float, float] | None = None,
    grid: int = 10,
    margin: float = 0.5,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> MostStableDesign:
    r"""Gains that minimise the spectral abscissa of the delayed loop.

    The abscissa (real part of the rightmost root of the quasi-polynomial,
    :func:`rightmost_roots`) is evaluated on a ``grid x grid`` start grid of
    the gain plane; BFGS with a nonsmooth line search (see the module
    docstring) descends from the two best grid points, over
    :math:`(k_1, k_2)` and, with `ratio_bounds`, the ratio :math:`a`. The
    result is certified: the rightmost roots are polished by Newton's method
    and the argument principle (:func:`unstable_root_count` on the loop
    shifted by :math:`\alpha + \varepsilon`) counts no root right of the
    abscissa.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant, any order (a steering lag, a dynamic tyre model, a
        user's state-space model with the named states ``e``, ``theta``).
    delay : float
        Input delay :math:`\tau` [s], in (0, 1e3].
    ratio : float, optional
        Rear-to-front ratio :math:`a` (held fixed without `ratio_bounds`;
        the start of the search with it).
    ratio_bounds : (float, float), optional
        Let :math:`a` vary within these bounds.
    k1_bounds, k2_bounds : (float, float), optional
        The start grid of the gains (geometric when the bounds are positive
        and a decade apart or more, else uniform). Default: from ``g / 50``
        to ``2 g``, with ``g`` the gain that makes :math:`|k\,n(j\omega)| =
        |d(j\omega)|` at :math:`\omega = 1/(4\tau)`.
    grid : int, optional
        Points per gain axis of the start grid, 4 to 40.
    margin : float, optional
        Roots within this distance [1/s] of the abscissa are reported.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    MostStableDesign

    Raises
    ------
    ValueError
        For a bad argument, or when no start point of the grid is stable.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0, steering_lag=0.27)
    >>> best = fws.most_stable_gains(plant, delay=0.24, ratio=0.0)
    >>> round(best.abscissa, 3), best.certified
    (-0.916, True)
    """
    tau = check_delay(delay)
    if not 0.0 < tau <= 1e3:
        raise ValueError(f"delay must be in (0, 1000] s, got {delay!r}")
    if (
        isinstance(grid, bool)
        or not isinstance(grid, (int, np.integer))
        or not (4 <= grid <= 40)
    ):
        raise ValueError(f"grid must be an integer in [4, 40], got {grid!r}")
    margin = check_scalar("margin", margin)
    if not margin > 0:
        raise ValueError(f"margin must be a finite number > 0, got {margin!r}")
    a0 = check_scalar("ratio", ratio)
    a_lo = a_hi = a0
    if ratio_bounds is not None:
        a_lo, a_hi = _check_bounds("ratio_bounds", ratio_bounds)
        if not a_lo <= a0 <= a_hi:
            raise ValueError(
                f"ratio must lie in ratio_bounds {ratio_bounds!r}, got {ratio!r}"
            )
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    loop = _Loop(p, tau)
    if loop.d.ndim != 1:
        raise ValueError("most_stable_gains needs one operating point")
    s0 = 0.25j / tau
    with np.errstate(over="ignore", invalid="ignore"):  # tiny delays: refused below
        dmag = abs(horner(loop.d, s0))
    scale = []
    for name, bounds, n in (
        ("k1_bounds", k1_bounds, loop.n1 + a0 * loop.dn1),
        ("k2_bounds", k2_bounds, loop.n2 + a0 * loop.dn2),
    ):
        if bounds is None:
            with np.errstate(over="ignore", invalid="ignore"):
                nm = abs(horner(n, s0))
            if nm == 0.0:
                raise ValueError(
                    f"the gain of {name[:2]} does not reach the loop at ratio "
                    f"{a0!r}; give {name}"
                )
            # two decades up to twice the gain of unit loop gain at 1/(4 tau)
            # (a delay allows a bandwidth of a fraction of 1/tau); zero gain
            # would leave the plant's own poles at the origin
            top = 2.0 * dmag / nm
            if not (math.isfinite(top) and top > 0.0):
                raise ValueError(
                    f"delay={delay!r} s is too small for a start grid of the gains "
                    f"(its scale {top!r} is not finite); give {name}, or design "
                    "without the delay (double_root_gains, stability_chart)"
                )
            bounds = (float(top) / 100.0, float(top))
        scale.append(_check_bounds(name, bounds))
    (k1_lo, k1_hi), (k2_lo, k2_hi) = scale
    spaced = [
        np.geomspace(lo, hi, grid)
        if lo > 0 and hi / lo >= 10
        else np.linspace(lo, hi, grid)
        for lo, hi in scale
    ]
    k1, k2 = spaced
    alpha = np.empty((grid, grid))
    for i, b in enumerate(k2):
        for j, c in enumerate(k1):
            s = loop.trial(c, b, a0)
            alpha[i, j] = math.inf if s is None else s.real
    order = np.argsort(alpha, axis=None)
    # search in units of the grid box, so that k1 and k2 weigh alike
    unit = np.array([k1_hi - k1_lo, k2_hi - k2_lo, max(a_hi - a_lo, 1.0)])
    free = ratio_bounds is not None

    def f(x):
        a = x[2] if free else a0
        if free and not a_lo <= a <= a_hi:
            return math.inf, np.zeros(x.size)
        g1, g2 = x[0] * unit[0], x[1] * unit[1]
        s = loop.trial(g1, g2, a)
        if s is None:
            return math.inf, np.zeros(x.size)
        grad = loop.gradient(g1, g2, a, s) * unit
        return s.real, grad[: x.size]

    best = None
    for flat in order[:2]:
        i, j = np.unravel_index(flat, alpha.shape)
        x0 = [k1[j] / unit[0], k2[i] / unit[1]] + ([a0 / unit[2]] if free else [])
        x, fx = _bfgs(f, np.array(x0))
        if best is None or fx < best[1]:
            best = (x, fx)
    if best is None or not best[1] < 0.0:
        raise ValueError(
            "no stable gains found on the start grid; give k1_bounds/k2_bounds "
            "around a stable design"
        )
    x, _ = best
    a_opt = float(x[2] * unit[2]) if free else a0
    gains = SteeringGains(float(x[0] * unit[0]), float(x[1] * unit[1]), a_opt)
    return _certify(p, loop, gains, tau, margin, k1, k2, alpha, a0)


def _certify(
    p, loop, gains, tau, margin, k1, k2, alpha_grid, grid_ratio
) -> MostStableDesign:
    n = 4
    while True:
        roots = rightmost_roots(p, gains, delay=tau, n=n)
        abscissa = float(roots[0].real)
        if roots[-1].real < abscissa - margin or n >= 8:
            break
        n *= 2
    near = roots[roots.real >= abscissa - margin]
    q = loop.q(float(gains.k1), float(gains.k2), float(gains.ratio))
    e = np.exp(-near * tau)
    dv, qv = horner(loop.d, near), horner(q, near)
    residual = float(np.max(np.abs(dv + e * qv) / (np.abs(dv) + np.abs(e * qv))))
    # roots right of sigma: D(sigma + z) is the quasi-polynomial of the loop
    # with A - sigma I and input e^{-sigma tau} b, counted by the argument
    # principle on the imaginary axis
    eps = 1e-3 * (1.0 + abs(abscissa))
    sigma = abscissa + eps
    lm = loop_matrices(p)
    n_x = np.asarray(lm.A).shape[-1]
    B = np.column_stack([lm.B_front, lm.B_rear]) * math.exp(-sigma * tau)
    C = np.vstack([lm.c_e, lm.c_theta])
    shifted = ct.ss(
        np.asarray(lm.A) - sigma * np.eye(n_x), B, C, np.zeros((2, 2)),
        states=list(lm.states), inputs=["delta_f", "delta_r"],
        outputs=["e", "theta"],
    )  # fmt: skip
    right = int(unstable_root_count(shifted, gains, delay=tau))
    cd = critical_delay(p, gains)
    return MostStableDesign(
        gains=gains,
        abscissa=abscissa,
        roots=near,
        residual=residual,
        roots_right=right,
        epsilon=eps,
        critical_delay=float(cd.delay),
        delay=tau,
        evaluations=loop.evaluations,
        k1=k1,
        k2=k2,
        abscissa_grid=alpha_grid,
        grid_ratio=grid_ratio,
        plant=p,
    )
