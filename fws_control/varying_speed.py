r"""Stability of a speed-scheduled loop while the speed changes.

A gain schedule :math:`k_1(V)`, :math:`k_2(V)`, :math:`a(V)` that is stable
at every frozen speed need not be stable when the speed moves: the
closed-loop matrix :math:`\mathbf A(V(t))` changes with time, and a fast
enough change can pump energy into the loop (see
:doc:`/speed_certificate`). :func:`speed_certificate` decides stability of
the time-varying linearised loop

.. math:: \dot x = \mathbf A(V(t))\,x,\qquad V(t) \in [V_{min}, V_{max}],
    \qquad |\dot V(t)| \le \rho,

for *every* such speed history, with a parameter-dependent quadratic
Lyapunov function :math:`\mathcal V(x, V) = x^T \mathbf P(V) x`.

Method
------
*Certificate.* :math:`\mathbf P(V)` is continuous and piecewise affine on a
grid of speeds :math:`V_0 < \dots < V_m` (the schedule's own speeds and a
uniform refinement), with :math:`\mathbf P(V_j) \succeq \mathbf I`. On each
cell :math:`[V_i, V_{i+1}]` the schedule's :math:`k_1 V^2`, :math:`k_2 V`
and :math:`a` are affine in :math:`V` (the interpolation of
:class:`~fws_control.GainSchedule`), and for a plant whose matrices are
affine in :math:`V` (the kinematic models) the scaled matrix
:math:`\mathbf W(V) = (V/V_{max})^2\,\mathbf A(V)` is a polynomial of degree
4 in :math:`V`. For both signs :math:`s = \pm 1` of the acceleration,

.. math::
    \mathbf N_s(V) = \mathbf W^T\mathbf P + \mathbf P\mathbf W
        + s\,\rho\,(V/V_{max})^2\,\frac{\mathbf P(V_{i+1}) -
        \mathbf P(V_i)}{V_{i+1} - V_i}

is a matrix polynomial of degree 5 on the cell, and the semidefinite
program asks for the Lukács (sum-of-squares) form on :math:`t \in [0, 1]`
(:math:`V = V_i + t (V_{i+1} - V_i)`):

.. math:: -\mathbf N_s(t) - \varepsilon\mathbf I
    = t\,\mathbf S_1(t) + (1 - t)\,\mathbf S_2(t),

with :math:`\mathbf S_1`, :math:`\mathbf S_2` sums of squares (positive
semidefinite Gram matrices on the basis :math:`1, t, t^2`). That identity
makes :math:`\mathbf N_s(t) \preceq -\varepsilon\mathbf I` on the whole
cell, not only on grid points. The program is solved with cvxpy and
Clarabel (the optional extra ``certificates``).

*A posteriori proof, in numpy.* The solver's answer is not trusted: for the
returned :math:`\mathbf P_j`, every :math:`\mathbf P(V_j)` must be positive
definite (then so is the affine :math:`\mathbf P(V)` between them); the
Gram matrices are projected onto the semidefinite cone and the residual
:math:`\mathbf R(t) = \sum_k \mathbf R_k t^k` of the identity above is
computed coefficient by coefficient, so that on :math:`[0, 1]`
:math:`\lambda_{max}(\mathbf N_s(t)) \le -\varepsilon + \sum_k
\lVert\mathbf R_k\rVert_2`, which must be negative on every cell. As an
independent check, the largest eigenvalue of :math:`\mathbf A^T\mathbf P +
\mathbf P\mathbf A \pm \rho\,\mathbf P'` with the library's closed-loop
matrix (:func:`~fws_control.loop_matrices`) must be negative on a grid of
4001 speeds. The polynomial :math:`\mathbf W` is checked against that
matrix between its fitting points before the program is built (to
:math:`10^{-8}`; a plant whose matrices are not affine in the speed is
refused).

*Why it proves stability.* Along any absolutely continuous :math:`V(t)`
in the range with :math:`|\dot V| \le \rho`,
:math:`\mathcal V(t) = x^T\mathbf P(V(t))x` is absolutely continuous and,
for almost every :math:`t`,
:math:`\dot{\mathcal V} = x^T(\mathbf A^T\mathbf P + \mathbf P\mathbf A +
\dot V\,\mathbf P'(V))x`, affine in :math:`\dot V`, hence at most its value
at :math:`\dot V = \pm\rho`, i.e. :math:`(V_{max}/V)^2 x^T\mathbf N_\pm x
< 0`. With :math:`\mathbf I \preceq \mathbf P \preceq p_{max}\mathbf I`
the loop is uniformly exponentially stable.

*Largest rate.* The program is affine in :math:`\mathbf P` for a fixed
:math:`\rho`; :func:`speed_certificate` bisects on :math:`\rho` for the
largest certified acceleration bound. A certificate is sufficient, not
necessary: a refused rate is "not proved", and the counterexample of
:doc:`/speed_certificate` shows that refusals can be real.

At :math:`\rho = 0` the certificate proves that every frozen
:math:`\mathbf A(V)` is Hurwitz; it exists, for a fine enough grid, exactly
when they are.

The input delay is not covered (a delayed loop needs a
Lyapunov–Krasovskii functional): a nonzero ``delay`` is refused.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import control as ct
import numpy as np

from .gains import SteeringGains
from .hints import RealArrayLike
from .plant import LateralPlant, loop_matrices
from .reprs import summary_repr
from .schedule import GainSchedule
from .validation import check_finite
from .vehicle import Vehicle

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["SpeedCertificate", "speed_certificate"]

#: Degree of W(V) = (V/Vmax)^2 A(V) on a cell (see the module docstring).
_DEGREE = 4


def _require_cvxpy():
    """cvxpy, or an ImportError that names the optional extra."""
    try:
        import cvxpy as cp
    except ImportError as exc:  # pragma: no cover - exercised by monkeypatch
        raise ImportError(
            "speed_certificate needs cvxpy with the Clarabel solver: install the "
            "optional extra 'certificates' (pip install 'fws-control[certificates]')"
        ) from exc
    if "CLARABEL" not in cp.installed_solvers():
        raise ImportError(
            "speed_certificate needs the Clarabel solver for cvxpy: install the "
            "optional extra 'certificates' (pip install 'fws-control[certificates]')"
        )
    return cp


@summary_repr
@dataclass(frozen=True, eq=False, kw_only=True)
class SpeedCertificate:
    r"""Result of :func:`speed_certificate`.

    Attributes
    ----------
    speed_range : tuple of float
        :math:`[V_{min}, V_{max}]` [m/s].
    rate : float or None
        The acceleration bound asked about [m/s²] (None: only the largest
        certified one was searched).
    certified : bool
        True if a certificate was found and verified at `rate` (with
        ``rate=None``: at `max_rate`, which exists).
    max_rate : float or None
        Largest acceleration bound :math:`\rho` [m/s²] with a verified
        certificate: the lower end of the bisection (without the search:
        `rate` if certified, else 0); None if there is none, not even at
        :math:`\rho = 0`.
    rate_bracket : tuple of float
        The last interval [m/s²]: certified at the lower end, refused at
        the upper (``inf``: nothing refused, e.g. certified up to the
        search's cap).
    nodes : ndarray
        Speeds :math:`V_j` of the piecewise-affine :math:`\mathbf P` [m/s].
    P : ndarray or None
        :math:`\mathbf P(V_j)`, shape ``(len(nodes), n, n)``, of the
        certificate at `rate` (at `max_rate` with ``rate=None``); None
        without one.
    certified_rate : float or None
        The :math:`\rho` [m/s²] that `P` certifies.
    margin : float or None
        Verified bound :math:`\max_{V, s} \lambda_{max}(\mathbf N_s(V))`
        (negative) of the certificate [1/s].
    frozen_abscissa : float
        Largest real part of the frozen closed-loop eigenvalues on the check
        grid [1/s] (information: it proves nothing about the moving speed).
    states : tuple of str
        Names of the states of :math:`x`.
    message : str
        The verdict in words.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sch = fws.GainSchedule(speeds=[5.0, 10.0], k1=[2.7 / 25, 2.7 / 100],
    ...                        k2=[5.4 / 5, 5.4 / 10], ratio=[0.0, 0.0])
    >>> cert = fws.speed_certificate(veh, sch, rate=0.5, cells=2)
    >>> cert.nodes
    array([ 5. ,  7.5, 10. ])
    >>> cert.P.shape, cert.certified_rate
    ((3, 2, 2), 0.5)
    """

    speed_range: tuple[float, float]
    rate: float | None
    certified: bool
    max_rate: float | None
    rate_bracket: tuple[float, float]
    nodes: np.ndarray
    P: np.ndarray | None
    certified_rate: float | None
    margin: float | None
    frozen_abscissa: float
    states: tuple[str, ...]
    message: str
    # the loop's matrices, for plot(); set by speed_certificate
    _cells: Any = dataclasses.field(default=None, init=False, repr=False)

    def P_at(self, speed: RealArrayLike) -> np.ndarray:
        r""":math:`\mathbf P(V)` at `speed` (piecewise affine between nodes).

        Parameters
        ----------
        speed : float or array_like
            Speed(s) [m/s] within `speed_range`.

        Returns
        -------
        ndarray
            Shape ``(*speed.shape, n, n)``.

        Raises
        ------
        ValueError
            Without a certificate, or for a speed outside the range.
        """
        if self.P is None:
            raise ValueError(f"no certificate to evaluate: {self.message}")
        v = np.asarray(check_finite("speed", speed), dtype=float)
        lo, hi = self.speed_range
        if np.any((v < lo) | (v > hi)):
            raise ValueError(
                f"speed must lie in the certificate's range [{lo:g}, {hi:g}] m/s, "
                f"got {speed!r}"
            )
        i = np.clip(np.searchsorted(self.nodes, v, side="right") - 1, 0,
                    self.nodes.size - 2)  # fmt: skip
        t = (v - self.nodes[i]) / (self.nodes[i + 1] - self.nodes[i])
        t = t[..., np.newaxis, np.newaxis]
        return (1.0 - t) * self.P[i] + t * self.P[i + 1]

    def plot(self, ax: Sequence[Axes] | np.ndarray | None = None) -> ct.ControlPlot:
        r"""Draw the certificate: :math:`\mathbf P(V)` and its decay.

        Left: the eigenvalues of :math:`\mathbf P(V)` [-]. Right: the
        largest eigenvalue of :math:`\mathbf A^T\mathbf P + \mathbf P\mathbf
        A \pm \rho\,\mathbf P'` divided by the largest of
        :math:`\mathbf P` [1/s], for both signs of the acceleration (negative
        everywhere: certified). Without a certificate the right panel shows
        the frozen spectral abscissa and the title says so.

        Parameters
        ----------
        ax : pair of matplotlib.axes.Axes, optional
            A new 1 x 2 figure if None.

        Returns
        -------
        control.ControlPlot

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> sch = fws.GainSchedule(speeds=[5.0, 10.0], k1=[2.7 / 25, 2.7 / 100],
        ...                        k2=[5.4 / 5, 5.4 / 10], ratio=[0.0, 0.0])
        >>> cert = fws.speed_certificate(veh, sch, rate=0.5, cells=4)
        >>> cplt = cert.plot()
        >>> cplt.axes[0, 1].get_xlabel()
        'speed V [m/s]'
        >>> plt.close(cplt.figure)
        """
        import matplotlib.pyplot as plt

        if ax is None:
            fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.6), layout="constrained")
        else:
            axes = np.asarray(ax, dtype=object).ravel()
            if axes.size != 2:
                raise ValueError(f"ax must hold two axes, got {axes.size}")
            fig = axes[0].figure
        v = np.linspace(*self.speed_range, 400)
        cells = self._cells
        lines = []
        if self.P is not None:
            eig_p = np.linalg.eigvalsh(self.P_at(v))
            lines += axes[0].plot(v, eig_p, color="C0")
            for s, style in ((1.0, "-"), (-1.0, "--")):
                lam = cells.derivative_bound(self.P, self.certified_rate, s, v)
                lam = lam / eig_p[:, -1]
                lines += axes[1].plot(
                    v, lam, style, color="C1",
                    label=rf"$\dot V = {'+' if s > 0 else '-'}\rho$",
                )  # fmt: skip
            axes[1].axhline(0.0, color="k", lw=0.8)
            axes[1].set_ylabel(r"$\lambda_{max}(\dot{\mathbf{P}}$-form$)/"
                               r"\lambda_{max}(\mathbf{P})$ [1/s]")  # fmt: skip
            axes[1].legend()
            title = (
                rf"certified for $|dV/dt| \leq {self.certified_rate:.4g}$ m/s$^2$"
                f" (largest found: {self.max_rate:.4g} m/s$^2$)"
            )
        else:
            lines += axes[1].plot(v, cells.frozen_abscissa(v), color="C3")
            axes[1].axhline(0.0, color="k", lw=0.8)
            axes[1].set_ylabel("frozen spectral abscissa [1/s]")
            title = "no certificate found"
        axes[0].set_ylabel(r"eigenvalues of $\mathbf{P}(V)$ [-]")
        for a in axes:
            a.set_xlabel("speed V [m/s]")
            a.grid(True, alpha=0.3)
        fig.suptitle(title)
        return ct.ControlPlot(lines, np.asarray(axes).reshape(1, 2), fig)


class _Cells:
    """The loop on each cell: W(t) coefficients and the direct A(V)."""

    def __init__(self, plant: LateralPlant, schedule: GainSchedule, nodes):
        self.plant = plant
        self.schedule = schedule
        self.nodes = nodes
        self.vref = float(nodes[-1])
        self.h = np.diff(nodes)
        deg = _DEGREE
        # Chebyshev points: a well-conditioned exact fit of a degree-4 polynomial
        tc = 0.5 * (1.0 - np.cos(np.pi * (np.arange(deg + 1) + 0.5) / (deg + 1)))
        vand = tc[:, np.newaxis] ** np.arange(deg + 1)
        vals = self.scaled(nodes[:-1, np.newaxis] + tc * self.h[:, np.newaxis])
        n = vals.shape[-1]
        coef = np.linalg.solve(vand, np.moveaxis(vals, 1, 0).reshape(deg + 1, -1))
        self.W = np.moveaxis(coef.reshape(deg + 1, -1, n, n), 0, 1)  # (cells, k, n, n)
        self.n = n
        # W must be a polynomial of degree 4 on each cell (plant matrices
        # affine in V): checked between the fitting points
        t = np.linspace(0.0, 1.0, 17)
        direct = self.scaled(nodes[:-1, np.newaxis] + t * self.h[:, np.newaxis])
        poly = np.einsum(
            "tk,ckij->ctij", t[:, np.newaxis] ** np.arange(deg + 1), self.W
        )
        fit = float(np.abs(direct - poly).max())
        if fit > 1e-8 * max(1.0, float(np.abs(direct).max())):
            raise ValueError(
                f"plant: its closed loop is not a degree-{deg} polynomial in the "
                f"speed on a cell (fit error {fit:.3g}): the plant's matrices must "
                "be affine in the speed (the kinematic models)"
            )
        # (V/vref)^2 on a cell, in t: c0 + c1 t + c2 t^2
        v0, h = nodes[:-1] / self.vref, self.h / self.vref
        self.q = np.stack([v0**2, 2 * v0 * h, h**2], axis=1)

    def matrix(self, v) -> np.ndarray:
        """Closed-loop A(V) from the library's loop matrices, shape (*v, n, n)."""
        v = np.asarray(v, dtype=float)
        p = dataclasses.replace(self.plant, speed=v)
        loop = loop_matrices(p)
        g = self.schedule.at(np.clip(v, self.schedule.speeds[0],
                                     self.schedule.speeds[-1]))  # fmt: skip
        b = loop.input_vector(g.ratio)
        k = (np.asarray(g.k1)[..., np.newaxis] * loop.c_e
             + np.asarray(g.k2)[..., np.newaxis] * loop.c_theta)  # fmt: skip
        return loop.A - b[..., :, np.newaxis] * k[..., np.newaxis, :]

    def scaled(self, v) -> np.ndarray:
        v = np.asarray(v, dtype=float)
        return (v / self.vref)[..., np.newaxis, np.newaxis] ** 2 * self.matrix(v)

    def frozen_abscissa(self, v) -> np.ndarray:
        return np.linalg.eigvals(self.matrix(v)).real.max(axis=-1)

    def n_coefficients(self, P: np.ndarray, rate: float, sign: float) -> np.ndarray:
        """Coefficients of N_s(t) per cell, shape (cells, 6, n, n)."""
        P0, dP = P[:-1], np.diff(P, axis=0)
        Pc = np.stack([P0, dP], axis=1)  # P(t) = P0 + t dP
        ncell, n = self.W.shape[0], self.n
        N = np.zeros((ncell, _DEGREE + 2, n, n))
        for k in range(_DEGREE + 1):
            for j in range(2):
                WP = np.swapaxes(self.W[:, k], -1, -2) @ Pc[:, j]
                N[:, k + j] += WP + np.swapaxes(WP, -1, -2)
        D = dP / self.h[:, np.newaxis, np.newaxis]
        for k in range(3):
            N[:, k] += sign * rate * self.q[:, k, np.newaxis, np.newaxis] * D
        return N

    def derivative_bound(self, P, rate, sign, v) -> np.ndarray:
        r"""lambda_max(A^T P + P A + s rho P') at speeds v (direct, no polynomial)."""
        v = np.asarray(v, dtype=float)
        i = np.clip(np.searchsorted(self.nodes, v, side="right") - 1, 0,
                    self.nodes.size - 2)  # fmt: skip
        t = ((v - self.nodes[i]) / self.h[i])[:, np.newaxis, np.newaxis]
        Pv = (1.0 - t) * P[i] + t * P[i + 1]
        D = (P[i + 1] - P[i]) / self.h[i][:, np.newaxis, np.newaxis]
        A = self.matrix(v)
        M = np.swapaxes(A, -1, -2) @ Pv + Pv @ A + sign * rate * D
        return np.linalg.eigvalsh(M)[..., -1]

    def verify(
        self, P: np.ndarray, grams: np.ndarray, rate: float, eps: float
    ) -> tuple[bool, float, str]:
        """The a posteriori proof: (passed, margin, reason).

        `grams` holds the solver's Gram matrices, shape (cells, 2 signs, 2,
        3n, 3n); they are projected onto the PSD cone here, and the
        identity -N - eps I = t S1 + (1 - t) S2 is checked coefficient by
        coefficient: its residual R(t) obeys ||R(t)|| <= sum_k ||R_k|| on
        [0, 1], so lambda_max(N(t)) <= -eps + sum_k ||R_k|| everywhere on
        the cell.
        """
        if not (np.all(np.isfinite(P)) and np.all(np.isfinite(grams))):
            return False, math.nan, "the solver returned a non-finite certificate"
        if np.linalg.eigvalsh(P)[:, 0].min() <= 0.0:
            return False, math.nan, "P(V) is not positive definite at a node"
        n = self.n
        lam, vec = np.linalg.eigh(0.5 * (grams + np.swapaxes(grams, -1, -2)))
        psd = (vec * np.maximum(lam, 0.0)[..., np.newaxis, :]) @ np.swapaxes(
            vec, -1, -2
        )
        blocks = psd.reshape(*psd.shape[:-2], 3, n, 3, n)
        # coefficients of S(t) = sum_{a+b=k} S_ab t^k, k = 0..4
        S = np.zeros((*psd.shape[:-2], _DEGREE + 1, n, n))
        for a in range(3):
            for b in range(3):
                S[..., a + b, :, :] += blocks[..., a, :, b, :]
        worst = -math.inf
        for si, sign in enumerate((1.0, -1.0)):
            N = self.n_coefficients(P, rate, sign)
            S1, S2 = S[:, si, 0], S[:, si, 1]
            rhs = np.zeros_like(N)
            rhs[:, 1:] += S1 - S2
            rhs[:, :-1] += S2
            R = -N - rhs
            R[:, 0] -= eps * np.eye(n)
            res = np.linalg.norm(R, 2, axis=(-2, -1)).sum(axis=1)
            worst = max(worst, float((res - eps).max()))
        if worst >= 0.0:
            return (
                False,
                worst,
                (
                    "the solver's certificate failed the a posteriori check "
                    f"(bound {worst:.3g} >= 0)"
                ),
            )
        # independent check on a dense grid, with the library's matrices
        v = np.linspace(self.nodes[0], self.nodes[-1], 4001)
        v = np.union1d(v, self.nodes)
        for sign in (1.0, -1.0):
            grid = self.derivative_bound(P, rate, sign, v)
            if grid.max() >= 0.0:
                return (
                    False,
                    float(grid.max()),
                    (
                        "the Lyapunov derivative is not negative on the check grid "
                        f"(largest eigenvalue {grid.max():.3g} at "
                        f"{v[np.argmax(grid)]:.4g} m/s)"
                    ),
                )
        return True, worst, ""


class _Program:
    """The semidefinite program of one grid; rho is a cvxpy Parameter."""

    def __init__(self, cells: _Cells, eps: float):
        cp = _require_cvxpy()
        self.cp = cp
        n, m = cells.n, cells.nodes.size
        eye = np.eye(n)
        self.rho = cp.Parameter(nonneg=True)
        P = [cp.Variable((n, n), symmetric=True) for _ in range(m)]
        gamma = cp.Variable()
        cons = []
        for Pj in P:
            cons += [Pj >> eye, Pj << gamma * eye]
        W, q, h = cells.W, cells.q, cells.h
        grams: list = []
        for i in range(m - 1):
            P0, dP = P[i], P[i + 1] - P[i]
            Pc = (P0, dP)
            base = []
            for k in range(_DEGREE + 2):
                term = 0
                for j in range(2):
                    kk = k - j
                    if 0 <= kk <= _DEGREE:
                        term = term + W[i, kk].T @ Pc[j] + Pc[j] @ W[i, kk]
                base.append(term)
            D = dP / h[i]
            for sign in (1.0, -1.0):
                N = list(base)
                for k in range(3):
                    N[k] = N[k] + sign * float(q[i, k]) * self.rho * D
                S1 = cp.Variable((3 * n, 3 * n), PSD=True)
                S2 = cp.Variable((3 * n, 3 * n), PSD=True)
                grams.append((S1, S2))

                def coef(S, k):
                    # coefficient of t^k of [1, t, t^2] (x) I  S  (...)^T
                    out = 0
                    for a in range(3):
                        b = k - a
                        if 0 <= b < 3:
                            out = out + S[a * n : (a + 1) * n, b * n : (b + 1) * n]
                    return out

                for k in range(_DEGREE + 2):
                    rhs = 0
                    if k >= 1:
                        rhs = rhs + coef(S1, k - 1) - coef(S2, k - 1)
                    if k <= 4:
                        rhs = rhs + coef(S2, k)
                    lhs = -N[k] - (eps * eye if k == 0 else 0)
                    cons.append(lhs == rhs)
        self.P = P
        self.grams = grams
        self.eps = eps
        self.problem = cp.Problem(cp.Minimize(gamma), cons)

    def solve(self, rate: float) -> tuple[np.ndarray, np.ndarray] | None:
        cp = self.cp
        self.rho.value = rate
        try:
            with warnings.catch_warnings():
                # an inaccurate solution is judged by the a posteriori check
                warnings.simplefilter("ignore", UserWarning)
                self.problem.solve(solver=cp.CLARABEL)
        except cp.error.SolverError:
            return None
        if self.problem.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            return None
        P = np.array([Pj.value for Pj in self.P])
        g = np.array([[S.value for S in pair] for pair in self.grams])
        return P, g.reshape(P.shape[0] - 1, 2, 2, *g.shape[-2:])


def _scalar(name: str, value: Any) -> float:
    if isinstance(value, (bool, np.bool_)) or np.ndim(value) != 0:
        raise ValueError(f"{name} must be a real number, got {value!r}")
    try:
        out = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a real number, got {value!r}") from exc
    return float(check_finite(name, out))


def _as_schedule(gains, lo: float, hi: float, nodes: np.ndarray) -> GainSchedule:
    if isinstance(gains, GainSchedule):
        return gains
    if callable(gains):
        g = gains(nodes)
        if not isinstance(g, SteeringGains):
            raise TypeError(
                "gains must be a GainSchedule or a function speed -> SteeringGains, "
                f"got a function that returns {type(g).__name__}"
            )
        k1, k2, a = (np.broadcast_to(np.asarray(x, dtype=float), nodes.shape)
                     for x in (g.k1, g.k2, g.ratio))  # fmt: skip
        return GainSchedule(speeds=nodes, k1=k1, k2=k2, ratio=a)
    raise TypeError(
        "gains must be a GainSchedule or a function speed -> SteeringGains, got "
        f"{type(gains).__name__}"
    )


def speed_certificate(
    plant: Vehicle | LateralPlant,
    gains: GainSchedule | Callable[[np.ndarray], SteeringGains],
    *,
    speed_range: tuple[float, float] | None = None,
    rate: float | None = None,
    cells: int = 24,
    delay: float = 0.0,
    search: bool | None = None,
    rtol: float = 0.02,
    max_rate: float = 1e3,
) -> SpeedCertificate:
    r"""Certify the scheduled loop for speeds changing at most at `rate`.

    Decides, with a parameter-dependent Lyapunov function
    :math:`x^T\mathbf P(V)x`, whether the linearised loop
    :math:`\dot x = \mathbf A(V(t))x` is exponentially stable for every
    speed history in `speed_range` with :math:`|\dot V| \le` `rate`, and
    finds the largest such rate by bisection. The method and the proof are
    in :mod:`fws_control.varying_speed`: a sum-of-squares program on
    each cell of a speed grid, then an independent numpy check (eigenvalues
    on a dense grid plus a Lipschitz bound of the polynomial residual). A
    refused rate is not a proof of instability.

    Parameters
    ----------
    plant : Vehicle or LateralPlant
        The loop's plant; its speed is replaced by the scheduled one. A
        vehicle gives the kinematic plant on a straight path; a
        :class:`LateralPlant` keeps its model (``"kinematic"`` or
        ``"paper"``: matrices affine in the speed), curvature and
        `steering_lag` (the lag's states join :math:`x`).
    gains : GainSchedule or callable
        The schedule, or a function ``speed -> SteeringGains`` (arrays in,
        arrays out; e.g. ``lambda v: fws.SteeringGains(k1(v), k2(v),
        a(v))``). A function is tabulated at the certificate's nodes into a
        :class:`GainSchedule` (interpolating :math:`k_1V^2`, :math:`k_2V`,
        :math:`a`), and that schedule is what is certified.
    speed_range : (float, float), optional
        :math:`[V_{min}, V_{max}]` [m/s], within the schedule's speeds and
        > 0 (default: the schedule's range; required for a function).
    rate : float, optional
        The acceleration bound :math:`\rho` to decide [m/s²], >= 0. None:
        only the largest certified bound is searched.
    cells : int, optional
        Number of cells of the uniform part of the grid of
        :math:`\mathbf P` (the schedule's speeds are added), 1 to 400.
        More cells make the certificate less conservative and the program
        larger.
    delay : float, optional
        Input delay [s]; only 0 is supported.
    search : bool, optional
        Bisect for the largest certified rate (default: only when `rate` is
        None). Without the search, `max_rate` is the largest rate tried
        with success (`rate` or 0).
    rtol : float, optional
        Relative width of the final bisection interval on :math:`\rho`, in
        (0, 1).
    max_rate : float, optional
        Cap of the search [m/s²], > 0.

    Returns
    -------
    SpeedCertificate

    Raises
    ------
    ValueError
        For a nonzero `delay` (no certificate with delay), a speed range
        that is not inside the schedule's or not positive, a negative
        `rate`, bad `cells`, `rtol` or `max_rate`, a dynamic plant (matrices
        not affine in the speed).
    TypeError
        For a `plant` or `gains` of the wrong kind.
    ImportError
        Without cvxpy and Clarabel (the extra ``certificates``).

    Examples
    --------
    The double-root schedule of :math:`\lambda_0 = -1` with :math:`a = 0`
    (:math:`k_1V^2 = f`, :math:`k_2V = 2f`) on 5-10 m/s:

    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> sch = fws.GainSchedule(speeds=[5.0, 10.0], k1=[2.7 / 25, 2.7 / 100],
    ...                        k2=[5.4 / 5, 5.4 / 10], ratio=[0.0, 0.0])
    >>> cert = fws.speed_certificate(veh, sch, rate=0.5, cells=4)
    >>> cert.certified
    True
    >>> cert.message
    'stable for every speed history in [5, 10] m/s with |dV/dt| <= 0.5 m/s^2'
    >>> fws.speed_certificate(veh, sch, delay=0.1)
    Traceback (most recent call last):
        ...
    ValueError: delay=0.1 s: ...
    """
    if delay != 0.0:
        raise ValueError(
            f"delay={delay!r} s: speed_certificate covers the undelayed loop only "
            "(delay must be 0); a delayed time-varying loop needs a "
            "Lyapunov-Krasovskii functional, which this certificate does not build"
        )
    if isinstance(plant, Vehicle):
        plant = LateralPlant(plant, speed=1.0, model="kinematic")
    elif not isinstance(plant, LateralPlant):
        raise TypeError(
            f"plant must be a Vehicle or a LateralPlant, got {type(plant).__name__}"
        )
    if plant.model == "dynamic":
        raise ValueError(
            "plant: model='dynamic' has matrices that are not affine in the speed; "
            "speed_certificate takes model='kinematic' or 'paper'"
        )
    if np.ndim(plant.curvature) != 0:
        raise ValueError(
            f"plant must have one curvature, got an array of shape "
            f"{np.shape(plant.curvature)}"
        )
    if not (isinstance(gains, GainSchedule) or callable(gains)):
        raise TypeError(
            "gains must be a GainSchedule or a function speed -> SteeringGains, "
            f"got {type(gains).__name__}"
        )
    if speed_range is None:
        if not isinstance(gains, GainSchedule):
            raise ValueError("speed_range is required when gains is a function")
        speed_range = (float(gains.speeds[0]), float(gains.speeds[-1]))
    try:
        lo, hi = (float(x) for x in speed_range)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"speed_range must be two speeds (Vmin, Vmax) [m/s], got {speed_range!r}"
        ) from exc
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise ValueError(
            f"speed_range must satisfy 0 < Vmin < Vmax < inf [m/s], got {speed_range!r}"
        )
    if isinstance(gains, GainSchedule) and (
        lo < gains.speeds[0] or hi > gains.speeds[-1]
    ):
        raise ValueError(
            f"speed_range {speed_range!r} must lie within the schedule's speeds "
            f"[{gains.speeds[0]:g}, {gains.speeds[-1]:g}] m/s"
        )
    if rate is not None:
        rate = _scalar("rate", rate)
        if rate < 0.0:
            raise ValueError(f"rate must be >= 0 m/s^2, got {rate!r}")
    if search is None:
        search = rate is None
    elif not isinstance(search, (bool, np.bool_)):
        raise TypeError(f"search must be True, False or None, got {search!r}")
    if isinstance(cells, bool) or not isinstance(cells, (int, np.integer)):
        raise TypeError(f"cells must be an int, got {cells!r}")
    if not 1 <= cells <= 400:
        raise ValueError(f"cells must be in 1..400, got {cells!r}")
    rtol = _scalar("rtol", rtol)
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"rtol must be in (0, 1), got {rtol!r}")
    max_rate = _scalar("max_rate", max_rate)
    if not max_rate > 0.0:
        raise ValueError(f"max_rate must be > 0 m/s^2, got {max_rate!r}")

    nodes = np.linspace(lo, hi, int(cells) + 1)
    if isinstance(gains, GainSchedule):
        inner = gains.speeds[(gains.speeds > lo) & (gains.speeds < hi)]
        nodes = np.union1d(nodes, inner)
        # merge nodes closer than a tiny fraction of the range (round-off)
        keep = np.concatenate([[True], np.diff(nodes) > 1e-9 * (hi - lo)])
        nodes = nodes[keep]
        nodes[-1] = hi
    schedule = _as_schedule(gains, lo, hi, nodes)
    cl = _Cells(plant, schedule, nodes)
    states = tuple(plant.states)

    v_check = np.linspace(lo, hi, 2001)
    frozen = float(cl.frozen_abscissa(v_check).max())
    eps = 1e-4 * max(float(np.abs(cl.W).max()), 1e-12)
    program = _Program(cl, eps)

    def attempt(r: float):
        sol = program.solve(r)
        if sol is None:
            return None
        P, grams = sol
        ok, margin, _ = cl.verify(P, grams, r, eps)
        return (P, margin) if ok else None

    def finish(**kw) -> SpeedCertificate:
        out = SpeedCertificate(
            speed_range=(lo, hi), rate=rate, nodes=nodes, states=states,
            frozen_abscissa=frozen, **kw,
        )  # fmt: skip
        object.__setattr__(out, "_cells", cl)
        return out

    base = attempt(0.0)
    if base is None:
        why = (
            f"the frozen loop is unstable (spectral abscissa {frozen:.3g} 1/s >= 0)"
            if frozen >= 0.0
            else "no Lyapunov function of this form was found even for a constant "
            "speed (try more cells)"
        )
        return finish(
            certified=False, max_rate=None, rate_bracket=(0.0, 0.0), P=None,
            certified_rate=None, margin=None,
            message=f"no certificate on [{lo:g}, {hi:g}] m/s: {why}; "
            "stability while the speed changes is not proved",
        )  # fmt: skip
    good, best, bad = 0.0, base, math.inf
    at_rate = None
    if rate is not None and rate > 0.0:
        at_rate = attempt(rate)
        if at_rate is None:
            bad = rate
        else:
            good, best = rate, at_rate
    elif rate == 0.0:
        at_rate = base
    if search:
        # bracket [good, bad], then bisection on rho
        r = 0.1 if good == 0.0 else 4.0 * good
        while bad == math.inf and good < max_rate:
            r = min(r, max_rate)
            res = attempt(r)
            if res is None:
                bad = r
            else:
                good, best = r, res
                r *= 4.0
        while bad < math.inf and bad - good > rtol * bad and bad > 1e-9:
            mid = 0.5 * (good + bad) if good > 0.0 else bad / 4.0
            res = attempt(mid)
            if res is None:
                bad = mid
            else:
                good, best = mid, res
    rng = f"[{lo:g}, {hi:g}] m/s"
    top = "the search's cap" if bad == math.inf else f"{bad:.4g} m/s^2 refused"
    if rate is None:
        certified = good > 0.0
        cert, cert_rate = best, good
        if certified:
            msg = (
                f"stable for every speed history in {rng} with |dV/dt| <= "
                f"{good:.4g} m/s^2 (largest certified; {top})"
            )
        else:
            msg = (
                f"every frozen speed in {rng} is stable, but no acceleration "
                f"bound > 0 was certified (down to {bad:.3g} m/s^2): stability "
                "while the speed changes is not proved"
            )
    elif at_rate is not None:
        cert, cert_rate, certified = at_rate, rate, True
        msg = f"stable for every speed history in {rng} with |dV/dt| <= {rate:g} m/s^2"
    else:
        cert, cert_rate, certified = best, good, False
        msg = (
            f"no certificate for |dV/dt| <= {rate:g} m/s^2 on {rng}: stability is "
            f"not proved (largest certified: {good:.4g} m/s^2)"
        )
    return finish(
        certified=certified, max_rate=good, rate_bracket=(good, bad), P=cert[0],
        certified_rate=cert_rate, margin=cert[1], message=msg,
    )  # fmt: skip
