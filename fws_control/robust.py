r"""Robust stability over a parameter box: the robust gain region and design.

A real vehicle does not drive at one operating point: the speed, the delay
of the loop, the lag of the steering actuator and (for the dynamic model)
the cornering stiffnesses and the mass each lie somewhere in an interval.
For a box :math:`B` of such parameters the **robust stable set** is

.. math:: R = \bigcap_{p \in B} S(p),

the gains :math:`(k_1, k_2)` that are stable at every parameter point, and a
**robust design** is a point of :math:`R` whose worst-case decay over
:math:`B` is the best.

The method (parameter space approach)
-------------------------------------
With the input delay :math:`\tau` the characteristic quasi-polynomial is

.. math:: D(s) = d(s; p) + e^{-s\tau}\bigl(k_1 n_1(s; p) + k_2 n_2(s; p)\bigr),

affine in the gains (:func:`~fws_control.affine_characteristic_polynomial`). A
root can leave the left half plane only through the imaginary axis
(the equation is retarded: no root comes from infinity), so a gain point is
in :math:`R` when it is stable at one parameter point and no parameter of
the box puts a root on the axis: :math:`R` is bounded by pieces of the
D-subdivision curves :math:`D(j\omega) = 0` of parameter points of the box.
The parameters are treated in two ways.

**The delay is handled in closed form.** For fixed gains and plant
parameters a root sits on the axis only at the crossing frequencies
:math:`|d(j\omega)| = |q(j\omega)|` (a polynomial of degree ``n`` in
:math:`\omega^2`) and then only at the delays
:math:`\tau_m = (\arg(-q/d) \bmod 2\pi + 2\pi m)/\omega`, crossing to the
right where the polynomial rises (:math:`F'(\omega^2) > 0`, Cooke and van
den Driessche) and to the left where it falls. The number of unstable roots
at the lower end :math:`\tau_{lo}` of the delay interval is the delay-free
count plus two per crossing below it, signed; the gain point is stable over
the whole interval :math:`[\tau_{lo}, \tau_{hi}]` when that number is 0 and
no crossing delay falls in the interval. No delay is sampled.

**The other parameters** (speed, curvature, lag, cornering stiffnesses,
mass), which enter :math:`d, n_1, n_2` nonlinearly, are sampled on a grid
that contains every vertex of the box and is refined adaptively: an
interval between two samples is bisected as long as its midpoint removes a
gain point from the region, from a base of ``samples`` points per axis.

The boundary :attr:`RobustRegion.boundary` is *computed*, not traced on the
grid: it consists of the D-subdivision curves :math:`k(\omega)` (2 x 2
linear system per frequency, :func:`~fws_control.stability.complex_root_curve`)
and the real-root lines :math:`p(0) = 0` at every parameter sample, at the
two ends of the delay interval, plus the **envelope** of the family of
curves over the delay (where :math:`\det[\partial k/\partial\omega,
\partial k/\partial\tau] = 0`: the crossing frequencies merge, a root
touches the axis at an interior delay). Of these candidate curves the
pieces that separate robustly stable from robustly unstable gains are kept
(tested a quarter of a grid step to either side), each point with the
parameter point whose curve it is.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .gains import SteeringGains
from .hints import RealArrayLike
from .linear import (
    AffinePolynomial,
    affine_characteristic_polynomial,
    check_gains,
    horner,
)
from .plant import LateralPlant, as_plant, resolve_ratio
from .reprs import summary_repr
from .stability import complex_root_curve, default_frequencies, hurwitz_columns
from .validation import (
    MAX_CURVATURE,
    MAX_RATIO,
    MAX_SPEED,
    check_finite,
    check_magnitude,
    check_scalar,
)
from .vehicle import Vehicle

if TYPE_CHECKING:
    import control as ct
    from matplotlib.axes import Axes

__all__ = [
    "ParameterBox",
    "BoundaryPiece",
    "RobustRegion",
    "RobustDesign",
    "robust_region",
    "robust_stable",
    "robust_gains",
    "BOX_PARAMETERS",
]

#: Parameters a :class:`ParameterBox` can hold, with their units.
BOX_PARAMETERS = {
    "speed": "m/s",
    "curvature": "1/m",
    "delay": "s",
    "steering_lag": "s",
    "cornering_front": "N/rad",
    "cornering_rear": "N/rad",
    "mass": "kg",
}
#: Largest delay of a box [s] (the crossing delays are closed form; the
#: bound keeps the rightmost-root checks of the design within their range).
_MAX_DELAY = 1.0e3
#: The plant parameters of the vehicle (dynamic model only).
_VEHICLE_FIELDS = ("cornering_front", "cornering_rear", "mass")


def _check_entry(name: str, value: Any) -> float | tuple[float, float] | None:
    """One box entry: None, a number, or an interval ``(lo, hi)`` with lo <= hi."""
    unit = BOX_PARAMETERS[name]
    if value is None:
        return None
    is_pair = isinstance(value, (tuple, list, np.ndarray)) and np.ndim(value) == 1
    if is_pair and len(value) != 2:
        raise ValueError(
            f"{name} must be a number or an interval (low, high) [{unit}], got "
            f"{value!r}"
        )
    parts = list(value) if is_pair else [value]
    out = []
    for v in parts:
        if isinstance(v, (bool, np.bool_, str)) or not isinstance(
            v, (int, float, np.integer, np.floating)
        ):
            raise TypeError(
                f"{name} must be a number or an interval (low, high) of numbers "
                f"[{unit}], got {value!r}"
            )
        v = float(v)
        ok = math.isfinite(v)
        if name == "speed":
            ok = ok and v != 0.0 and abs(v) <= MAX_SPEED
            rng = f"nonzero with magnitude <= {MAX_SPEED:g}"
        elif name == "curvature":
            ok = ok and abs(v) <= MAX_CURVATURE
            rng = f"magnitude <= {MAX_CURVATURE:g}"
        elif name == "delay":
            ok = ok and 0.0 <= v <= _MAX_DELAY
            rng = f"in [0, {_MAX_DELAY:g}]"
        else:
            ok = ok and v > 0.0
            rng = "finite and > 0"
        if not ok:
            raise ValueError(f"{name} must be {rng} {unit}, got {value!r}")
        out.append(v)
    if len(out) == 1:
        return out[0]
    lo, hi = out
    if lo > hi:
        raise ValueError(
            f"{name} must be an interval (low, high) with low <= high [{unit}], "
            f"got {value!r}"
        )
    if name == "speed" and lo < 0.0 < hi:
        raise ValueError(
            f"speed interval must not contain 0 m/s (the loop has no speed "
            f"there), got {value!r}"
        )
    return out[0] if lo == hi else (lo, hi)


@dataclass(frozen=True)
class ParameterBox:
    r"""A box of plant parameters: each one fixed or an interval.

    A number fixes the parameter, a pair ``(low, high)`` makes it an
    interval, None takes the value of the plant the box is applied to.

    Parameters
    ----------
    speed : float or (float, float), optional
        Speed :math:`V` [m/s], nonzero; an interval must not contain 0.
    curvature : float or (float, float), optional
        Path curvature :math:`\kappa` [1/m].
    delay : float or (float, float), optional
        Input delay :math:`\tau` [s] in [0, 1000]; default 0 (none).
    steering_lag : float or (float, float), optional
        Time constant of the steering actuator [s], > 0 (both axles).
    cornering_front, cornering_rear : float or (float, float), optional
        Cornering stiffnesses [N/rad], > 0 (``model="dynamic"`` only).
    mass : float or (float, float), optional
        Mass [kg], > 0 (``model="dynamic"`` only; the yaw inertia is kept).

    Raises
    ------
    ValueError
        For a value outside its range, an interval with ``low > high`` or a
        speed interval containing 0.
    TypeError
        For a value that is not a number or a pair of numbers.

    Examples
    --------
    >>> import fws_control as fws
    >>> box = fws.ParameterBox(speed=(10.0, 30.0), delay=(0.0, 0.24),
    ...                        steering_lag=0.27, curvature=0.0)
    >>> box.intervals
    {'speed': (10.0, 30.0), 'delay': (0.0, 0.24)}
    """

    speed: float | tuple[float, float] | None = None
    curvature: float | tuple[float, float] | None = None
    delay: float | tuple[float, float] = 0.0
    steering_lag: float | tuple[float, float] | None = None
    cornering_front: float | tuple[float, float] | None = None
    cornering_rear: float | tuple[float, float] | None = None
    mass: float | tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in BOX_PARAMETERS:
            object.__setattr__(self, name, _check_entry(name, getattr(self, name)))
        if self.delay is None:
            object.__setattr__(self, "delay", 0.0)

    @property
    def intervals(self) -> dict[str, tuple[float, float]]:
        """The parameters that vary, ``{name: (low, high)}``."""
        return {
            n: getattr(self, n)
            for n in BOX_PARAMETERS
            if isinstance(getattr(self, n), tuple)
        }

    @property
    def delay_range(self) -> tuple[float, float]:
        """``(low, high)`` of the delay [s] (equal ends for a fixed delay)."""
        d = self.delay
        return d if isinstance(d, tuple) else (d, d)

    def _range(self, name: str) -> tuple[float, float] | None:
        """``(low, high)`` of a set parameter (equal ends if fixed), else None."""
        v = getattr(self, name)
        if v is None:
            return None
        return v if isinstance(v, tuple) else (v, v)


def _as_box(box: Any) -> ParameterBox:
    if isinstance(box, ParameterBox):
        return box
    if isinstance(box, dict):
        unknown = sorted(set(box) - set(BOX_PARAMETERS))
        if unknown:
            raise ValueError(
                f"box has unknown parameters {unknown}; valid: {list(BOX_PARAMETERS)}"
            )
        return ParameterBox(**box)
    raise TypeError(
        f"box must be a fws.ParameterBox or a dict of its fields, got "
        f"{type(box).__name__}"
    )


class _Family:
    """The plants of a box: builds the plant at one parameter point."""

    def __init__(self, plant: Any, box: ParameterBox, model: Any):
        self.box = box
        if isinstance(plant, Vehicle):
            speed = box._range("speed")
            if speed is None:
                raise TypeError(
                    "a Vehicle plant needs the speed in the box (box={'speed': ...})"
                )
            self.template = LateralPlant(
                plant,
                speed=speed[0],
                curvature=0.0,
                model="kinematic" if model is None else model,
            )
        else:
            if model is not None:
                raise TypeError(
                    "model= applies only to a Vehicle plant; a "
                    f"{type(plant).__name__} already fixes its model"
                )
            self.template = as_plant(plant)
        lateral = isinstance(self.template, LateralPlant)
        if not lateral:
            fixed = [n for n in BOX_PARAMETERS if n != "delay" and getattr(box, n)]
            if fixed:
                raise ValueError(
                    f"box parameters {fixed} need a fws.LateralPlant or a Vehicle; "
                    f"a {type(self.template).__name__} has only the delay"
                )
        elif self.template.shape != ():
            raise ValueError(
                "plant must be one operating point (the box gives the ranges), got "
                f"speed/curvature of shape {self.template.shape}"
            )
        if lateral and self.template.model != "dynamic":
            extra = [n for n in _VEHICLE_FIELDS if getattr(box, n) is not None]
            if extra:
                raise ValueError(
                    f"box parameters {extra} apply only to model='dynamic', got "
                    f"model={self.template.model!r}"
                )
        self.axes = {n: r for n, r in box.intervals.items() if n != "delay"}
        self._plants: dict[tuple, Any] = {}

    def fixed(self) -> dict[str, float]:
        """The parameter values that do not vary."""
        out = {}
        for name in BOX_PARAMETERS:
            v = getattr(self.box, name)
            if name != "delay" and v is not None and not isinstance(v, tuple):
                out[name] = v
        return out

    def plant(self, values: dict[str, float]) -> Any:
        if not isinstance(self.template, LateralPlant):
            return self.template
        # the same point gives the same (frozen) plant object, so that the
        # search's calls at one point share its matrices and polynomials
        # (rightmost_roots keeps them per plant object and ratio)
        key = tuple(sorted(values.items()))
        if key not in self._plants:
            self._plants[key] = self._new_plant(values)
        return self._plants[key]

    def _new_plant(self, values: dict[str, float]) -> Any:
        """The template with the point's values (and the fixed ones) set."""
        t = self.template
        vals = {**self.fixed(), **values}
        veh = t.vehicle
        vfields = {n: vals[n] for n in _VEHICLE_FIELDS if n in vals}
        if vfields:
            # (mypy reads the KW_ONLY marker as a field of that type)
            veh = dataclasses.replace(veh, **cast(dict[str, Any], vfields))
        lag = vals.get("steering_lag", t.steering_lag)
        return LateralPlant(
            veh,
            speed=vals.get("speed", t.speed),
            curvature=vals.get("curvature", t.curvature),
            model=t.model,
            steering_lag=lag,
            tyre=t.tyre,
        )

    def nominal(self) -> dict[str, float]:
        """Mid-point of every interval (the delay included)."""
        return {n: 0.5 * (lo + hi) for n, (lo, hi) in self.box.intervals.items()}


# ---------------------------------------------------------------------------
# the delay interval in closed form


def _even_odd(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``p(jw) = R(w^2) + j w I(w^2)``: coefficients of R, I in ``x = w^2``."""
    asc = c[..., ::-1]
    m = asc.shape[-1]
    even = asc[..., 0::2] * (-1.0) ** np.arange((m + 1) // 2)
    odd = asc[..., 1::2] * (-1.0) ** np.arange(m // 2)
    return even[..., ::-1], odd[..., ::-1]


def _polymul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    shape = np.broadcast_shapes(a.shape[:-1], b.shape[:-1])
    out = np.zeros(shape + (a.shape[-1] + b.shape[-1] - 1,))
    for i in range(a.shape[-1]):
        out[..., i : i + b.shape[-1]] += a[..., i : i + 1] * b
    return out


def _modulus_in_x(c: np.ndarray) -> np.ndarray:
    r""":math:`|p(j\omega)|^2` as a polynomial in :math:`x = \omega^2`."""
    re, im = _even_odd(c)
    rr = _polymul(re, re)
    if im.shape[-1] == 0:
        return rr
    ii = np.concatenate([_polymul(im, im), np.zeros(im.shape[:-1] + (1,))], -1)
    n = max(rr.shape[-1], ii.shape[-1])
    pad = [
        np.concatenate([np.zeros(p.shape[:-1] + (n - p.shape[-1],)), p], -1)
        for p in (rr, ii)
    ]
    return pad[0] + pad[1]


def _unstable_at_zero_delay(coeffs: np.ndarray) -> np.ndarray:
    """Roots with real part >= 0 of monic polynomials ``(N, n+1)`` (counts)."""
    n = coeffs.shape[-1] - 1
    comp = np.zeros(coeffs.shape[:-1] + (n, n))
    comp[..., 0, :] = -coeffs[..., 1:]
    if n > 1:
        comp[..., np.arange(1, n), np.arange(n - 1)] = 1.0
    return np.count_nonzero(np.linalg.eigvals(comp).real >= 0.0, axis=-1)


def _delay_verdict(
    cp: AffinePolynomial, k1: np.ndarray, k2: np.ndarray, tlo: float, thi: float
) -> tuple[np.ndarray, np.ndarray]:
    """Stability for every delay in ``[tlo, thi]``, and the delay that fails.

    Returns ``(ok, failing_delay)`` for 1-D gain arrays; ``failing_delay``
    is ``tlo`` where the loop is unstable at the lower end and the first
    crossing delay in the interval otherwise (inf where ``ok``).
    """
    d = np.asarray(cp.open_loop, dtype=float).reshape(-1)
    n1 = np.asarray(cp.n1, dtype=float).reshape(-1)
    n2 = np.asarray(cp.n2, dtype=float).reshape(-1)
    q = k1[:, None] * n1 + k2[:, None] * n2
    closed = d + q
    cols = [closed[:, j] for j in range(d.size)]
    # a coefficient within rounding of zero counts as zero (boundary point)
    scale = np.abs(d) + np.abs(k1[:, None] * n1) + np.abs(k2[:, None] * n2)
    stable0 = hurwitz_columns(cols)
    stable0 &= np.all(closed[:, 1:] > 8 * np.finfo(float).eps * scale[:, 1:], axis=1)
    F = _modulus_in_x(d[None, :]) - _modulus_in_x(q)[:, -d.size :]
    n = F.shape[-1] - 1
    # F is monic of degree n in x = w^2 (deg q < deg d)
    comp = np.zeros((k1.size, n, n))
    comp[:, 0, :] = -F[:, 1:]
    if n > 1:
        comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    x = np.linalg.eigvals(comp)
    pos = (np.abs(x.imag) <= 1e-9 * np.maximum(1.0, np.abs(x))) & (x.real > 0.0)
    xr = np.where(pos, x.real, 1.0)
    # two Newton steps on F restore the precision the companion matrix loses
    dF = F[:, :-1] * np.arange(n, 0, -1)
    for _ in range(2):
        f = horner(F[:, None, :], xr)
        fp = horner(dF[:, None, :], xr)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(pos & (fp != 0), f / fp, 0.0)
        xr = np.where(np.abs(step) < 1e-3 * xr, xr - step, xr)
    w = np.sqrt(xr)
    s = 1j * w
    dv = horner(d, s)
    qv = horner(q[:, None, :], s)
    with np.errstate(divide="ignore", invalid="ignore"):
        tau0 = np.mod(np.angle(-qv / dv), 2 * math.pi) / w
    period = 2 * math.pi / w
    direction = np.sign(horner(dF[:, None, :], xr))
    pos &= np.isfinite(tau0)
    if tlo > 0.0:
        # crossings below tlo change the count by two each, signed
        below = np.where(pos, np.ceil(np.maximum(tlo - tau0, 0.0) / period), 0.0)
        unstable = np.where(stable0, 0, _unstable_at_zero_delay(closed)) + 2 * np.sum(
            below * direction, axis=1
        )
        stable_lo = unstable == 0
    else:
        below = np.zeros_like(tau0)
        stable_lo = stable0
    first = tau0 + below * period  # first crossing delay >= tlo
    hit = pos & (first <= thi)
    first = np.where(hit, first, np.inf)
    fail_at = np.min(first, axis=1)
    ok = stable_lo & ~np.any(hit, axis=1)
    failing = np.where(ok, np.inf, np.where(stable_lo, fail_at, tlo))
    return ok, failing


# ---------------------------------------------------------------------------
# the parameter grid


class _Sweep:
    """Robust verdicts of a set of gains over the adaptively refined grid."""

    def __init__(self, family: _Family, ratio: Any, samples: int, depth: int):
        self.family = family
        self.ratio = ratio
        self.samples = samples
        self.depth = depth
        self.tlo, self.thi = family.box.delay_range
        self.cache: dict[tuple, AffinePolynomial] = {}
        self.evaluations = 0

    def poly(self, point: tuple[tuple[str, float], ...]) -> AffinePolynomial:
        cp = self.cache.get(point)
        if cp is None:
            plant = self.family.plant(dict(point))
            ratio = resolve_ratio(plant, self.ratio)
            cp = affine_characteristic_polynomial(plant, ratio=ratio)
            self.cache[point] = cp
        return cp

    def run(self, k1: np.ndarray, k2: np.ndarray):
        """Verdicts, the failing parameter point index and delay, the samples."""
        axes = self.family.axes
        names = list(axes)
        grid = {
            n: list(np.linspace(lo, hi, self.samples if hi > lo else 1))
            for n, (lo, hi) in axes.items()
        }
        ok = np.ones(k1.size, dtype=bool)
        fail_point = np.full(k1.size, -1)
        fail_delay = np.full(k1.size, np.inf)
        points: list[tuple[tuple[str, float], ...]] = []

        def evaluate(values: dict[str, float]) -> int:
            key = tuple((n, float(values[n])) for n in names)
            if key in seen:
                return 0
            seen.add(key)
            idx = np.flatnonzero(ok)
            if idx.size == 0:
                return 0
            self.evaluations += 1
            good, tau = _delay_verdict(
                self.poly(key), k1[idx], k2[idx], self.tlo, self.thi
            )
            bad = idx[~good]
            if bad.size:
                points.append(key)
                ok[bad] = False
                fail_point[bad] = len(points) - 1
                fail_delay[bad] = tau[~good]
            return int(bad.size)

        seen: set = set()

        def combos(fixed_name=None, fixed_value=None):
            lists = [[fixed_value] if n == fixed_name else grid[n] for n in names]
            for vals in _product(lists):
                yield dict(zip(names, vals, strict=True))

        # vertices first: they remove most points, so later samples test few
        verts = [[axes[n][0], axes[n][1]] for n in names]
        for vals in _product(verts):
            evaluate(dict(zip(names, vals, strict=True)))
        for values in combos():
            evaluate(values)
        active = {n: list(zip(grid[n][:-1], grid[n][1:], strict=True)) for n in names}
        for _ in range(self.depth):
            changed = False
            for n in names:
                nxt = []
                for lo, hi in active[n]:
                    mid = 0.5 * (lo + hi)
                    removed = sum(evaluate(v) for v in combos(n, mid))
                    grid[n] = sorted(set(grid[n]) | {mid})
                    if removed:
                        nxt += [(lo, mid), (mid, hi)]
                        changed = True
                active[n] = nxt
            if not changed:
                break
        all_points = [tuple((n, float(v[n])) for n in names) for v in combos()]
        return ok, fail_point, fail_delay, points, all_points, grid


def _product(lists):
    if not lists:
        yield ()
        return
    for v in lists[0]:
        for rest in _product(lists[1:]):
            yield (v, *rest)


# ---------------------------------------------------------------------------
# boundary pieces


@summary_repr
@dataclass(frozen=True, eq=False)
class BoundaryPiece:
    r"""A computed piece of the boundary of a robust region.

    Every point lies on the D-subdivision curve of its own parameter point:
    at those parameters (and delay) the loop has a root on the imaginary
    axis there, and just outside the region the root is in the right half
    plane.

    Attributes
    ----------
    kind : str
        ``"complex"`` (roots at :math:`\pm j\omega`), ``"real"`` (a root at
        ``s = 0``, the line :math:`p(0) = 0`) or ``"envelope"`` (the
        envelope over the delay of the complex curves: a root touches the
        axis at an interior delay).
    k1, k2 : ndarray
        Points of the piece [rad/m], [-].
    omega : ndarray
        Crossing frequency [rad/s] at each point (0 on a real piece).
    parameters : dict of str to ndarray
        The parameter point of each point, ``delay`` included.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> reg = fws.robust_region(veh, ratio=0.0, box={"speed": (10.0, 30.0)},
    ...                         k1=np.linspace(-0.1, 0.3, 41),
    ...                         k2=np.linspace(-0.2, 1.0, 41))
    >>> sorted({p.kind for p in reg.boundary})
    ['complex', 'real']
    """

    kind: str
    k1: np.ndarray
    k2: np.ndarray
    omega: np.ndarray
    parameters: dict[str, np.ndarray]


def _frequencies(cp: AffinePolynomial, delay: float) -> np.ndarray:
    w = default_frequencies(cp, num=801)
    if delay > 0.0:
        # resolve the delay's phase (about 16 points per turn) up to the top
        lin = np.linspace(w[0], w[-1], int(min(20_000, 8 * delay * w[-1] / math.pi)))
        w = np.unique(np.concatenate([w, lin]))
    return w


def _refine_curve(cp, w, delay, box_lo, box_hi, span, passes=6):
    """The complex curve, bisected where it crosses the window coarsely."""
    for _ in range(passes):
        c = complex_root_curve(cp, w, delay)
        pts = np.column_stack([c.k1, c.k2])
        near = np.all((pts >= box_lo) & (pts <= box_hi), axis=1)
        gap = np.hypot(*(np.diff(pts, axis=0) / span).T)
        split = (near[:-1] | near[1:]) & np.isfinite(gap) & (gap > 0.002)
        if not np.any(split) or w.size > 60_000:
            return c
        w = np.sort(np.concatenate([w, 0.5 * (w[:-1][split] + w[1:][split])]))
    return complex_root_curve(cp, w, delay)


def _envelope_over_delay(cp, w, tlo, thi, m=48):
    """Points ``(omega, tau)`` where the curves of the delays touch their envelope.

    The curve of delay tau solves ``k1 n1 + k2 n2 = -d e^{j w tau}`` at
    ``s = j w``; the envelope of the family is where the Jacobian of
    ``(w, tau) -> k`` is singular. Its zero set on a ``(w, tau)`` grid is
    traced by contourpy and mapped to the gains exactly.
    """
    import contourpy

    taus = np.linspace(tlo, thi, m)
    d, n1, n2 = cp.polynomials_at(1j * w)
    det = n1.real * n2.imag - n2.real * n1.imag

    def gains(wv, tv):
        dd, a1, a2 = cp.polynomials_at(1j * wv)
        t = -dd * np.exp(1j * wv * tv)
        dt = np.where(a1.real * a2.imag - a2.real * a1.imag == 0, np.nan, 1.0)
        de = (a1.real * a2.imag - a2.real * a1.imag) * dt
        g1 = (t.real * a2.imag - t.imag * a2.real) / de
        g2 = (a1.real * t.imag - a1.imag * t.real) / de
        return g1, g2

    W, T = np.meshgrid(w, taus)
    with np.errstate(divide="ignore", invalid="ignore"):
        g1, g2 = gains(W, T)
        # d k / d tau in closed form: the target rotates, d t / d tau = j w t
        t = -d * np.exp(1j * W * T)
        dt = 1j * W * t
        dk1 = (dt.real * n2.imag - dt.imag * n2.real) / det
        dk2 = (n1.real * dt.imag - n1.imag * dt.real) / det
        lw = np.log(w)
        ek1 = np.gradient(g1, lw, axis=1)
        ek2 = np.gradient(g2, lw, axis=1)
        jac = ek1 * dk2 - ek2 * dk1
    jac = np.where(np.isfinite(jac), jac, np.nan)
    if not np.any(np.isfinite(jac)):
        return []
    gen = contourpy.contour_generator(lw, taus, jac)
    out = []
    for line in gen.lines(0.0):
        line = np.asarray(line)
        if len(line) < 2:
            continue
        wv, tv = np.exp(line[:, 0]), line[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            a, b = gains(wv, tv)
        out.append((wv, tv, a, b))
    return out


def _boundary(
    sweep: _Sweep, points, k1a, k2a, stable, verdict
) -> tuple[BoundaryPiece, ...]:
    """Candidate curves at every parameter sample; the pieces on the boundary."""
    span = np.array([k1a[-1] - k1a[0], k2a[-1] - k2a[0]])
    lo = np.array([k1a[0], k2a[0]])
    hi = np.array([k1a[-1], k2a[-1]])
    step = span / np.array([k1a.size - 1, k2a.size - 1])
    tlo, thi = sweep.tlo, sweep.thi
    cands = []  # (kind, k1, k2, omega, params)
    for key in points:
        cp = sweep.poly(key)
        base = dict(key)
        # the real-root line p(0) = 0, drawn across the window
        a, b, c = (float(np.ravel(v)[-1]) for v in (cp.n1, cp.n2, cp.open_loop))
        if abs(a) * span[0] + abs(b) * span[1] > 0:
            if abs(b) * span[1] >= abs(a) * span[0]:
                x = np.linspace(lo[0], hi[0], 400)
                y = -(a * x + c) / b
            else:
                y = np.linspace(lo[1], hi[1], 400)
                x = -(b * y + c) / a
            for tau in {tlo, thi}:
                cands.append(("real", x, y, np.zeros_like(x), {**base, "delay": tau}))
        for tau in sorted({tlo, thi}):
            w = _frequencies(cp, tau)
            cur = _refine_curve(cp, w, tau, lo - span, hi + span, span)
            cands.append(("complex", cur.k1, cur.k2, cur.omega, {**base, "delay": tau}))
        if thi > tlo:
            w = _frequencies(cp, thi)[::4]
            for wv, tv, a1, a2 in _envelope_over_delay(cp, w, tlo, thi):
                cands.append(("envelope", a1, a2, wv, {**base, "delay": tv}))
    # Only curve points near a change of the grid verdict can be on the
    # boundary (to the grid's resolution): the others are not tested.
    change = np.zeros(stable.shape, dtype=bool)
    change[:, 1:] |= stable[:, 1:] != stable[:, :-1]
    change[:, :-1] |= stable[:, 1:] != stable[:, :-1]
    change[1:, :] |= stable[1:, :] != stable[:-1, :]
    change[:-1, :] |= stable[1:, :] != stable[:-1, :]
    for _ in range(2):  # two cells of margin
        grown = change.copy()
        grown[:, 1:] |= change[:, :-1]
        grown[:, :-1] |= change[:, 1:]
        grown[1:, :] |= change[:-1, :]
        grown[:-1, :] |= change[1:, :]
        change = grown
    tests = []  # (candidate, indices, offsets)
    for n, (_, x, y, _, _) in enumerate(cands):
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        with np.errstate(invalid="ignore"):
            inside = np.isfinite(x) & np.isfinite(y)
            inside &= (x >= lo[0]) & (x <= hi[0]) & (y >= lo[1]) & (y <= hi[1])
        if np.count_nonzero(inside) < 2:
            continue
        j = np.clip(
            np.rint((np.where(inside, x, lo[0]) - lo[0]) / step[0]), 0, k1a.size - 1
        )
        i = np.clip(
            np.rint((np.where(inside, y, lo[1]) - lo[1]) / step[1]), 0, k2a.size - 1
        )
        inside &= change[i.astype(int), j.astype(int)]
        # unit normals in grid-step units; offsets of 1e-4 of a step
        tx = np.gradient(x / step[0])
        ty = np.gradient(y / step[1])
        with np.errstate(divide="ignore", invalid="ignore"):
            norm = np.hypot(tx, ty)
            nx, ny = -ty / norm * step[0] * 1e-4, tx / norm * step[1] * 1e-4
        idx = np.flatnonzero(inside & np.isfinite(nx) & np.isfinite(ny))
        if idx.size:
            tests.append(
                (
                    n,
                    idx,
                    x[idx] + nx[idx],
                    y[idx] + ny[idx],
                    x[idx] - nx[idx],
                    y[idx] - ny[idx],
                )
            )
    if not tests:
        return ()
    px = np.concatenate([t[2] for t in tests] + [t[4] for t in tests])
    py = np.concatenate([t[3] for t in tests] + [t[5] for t in tests])
    res = verdict(px, py)
    half = res.size // 2
    plus, minus = res[:half], res[half:]
    pieces = []
    seen: list[np.ndarray] = []
    at = 0
    for n, idx, *_ in tests:
        kind, x, y, w, params = cands[n]
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        keep = np.zeros(x.size, dtype=bool)
        keep[idx] = plus[at : at + idx.size] != minus[at : at + idx.size]
        at += idx.size
        edges = np.flatnonzero(np.diff(np.concatenate([[0], keep, [0]])))
        for s, e in zip(edges[::2], edges[1::2], strict=True):
            if e - s < 2:
                continue
            pts = np.column_stack([x[s:e], y[s:e]]) / step
            # the same curve from another parameter point (k1 = 0 at every
            # speed), to half a grid step: keep the first
            if any(
                np.max(np.min(np.hypot(*(pts[:, None, :] - o[None, :, :]).T), 0)) < 0.5
                for o in seen
            ):
                continue
            seen.append(pts)
            par = {
                k: (np.asarray(v)[s:e] if np.ndim(v) else np.full(e - s, float(v)))
                for k, v in params.items()
            }
            pieces.append(
                BoundaryPiece(
                    kind=kind,
                    k1=x[s:e].copy(),
                    k2=y[s:e].copy(),
                    omega=np.asarray(w, dtype=float)[s:e].copy(),
                    parameters=par,
                )
            )
    return tuple(pieces)


# ---------------------------------------------------------------------------
# public API


@summary_repr
@dataclass(frozen=True, eq=False)
class RobustRegion:
    r"""The gains stable at every parameter point of a box, on a grid.

    Returned by :func:`robust_region`; do not build it directly.

    Attributes
    ----------
    plant : LateralPlant or control.StateSpace
        The plant the box is applied to (its other parameters are kept).
    box : ParameterBox
        The parameter box.
    ratio : float or callable
        Rear-to-front steering ratio :math:`a` (or schedule).
    k1, k2 : ndarray
        Grid axes [rad/m] and [-], 1-D.
    stable : ndarray of bool
        Shape ``(len(k2), len(k1))``: robustly stable grid points.
    boundary : tuple of BoundaryPiece
        The computed boundary pieces.
    worst_parameters : tuple of dict
        Parameter points (without the delay) that remove grid points;
        :attr:`failing_point` indexes them.
    failing_point : ndarray of int
        Per grid point (shape of `stable`): index into `worst_parameters` of
        a parameter point at which the gains are unstable, -1 where stable.
    failing_delay : ndarray
        Per grid point: the delay [s] at which it fails there (``inf`` where
        stable).
    samples : dict of str to ndarray
        The samples of each interval parameter (delay excluded) after the
        adaptive refinement.
    evaluations : int
        Number of parameter points evaluated.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> reg = fws.robust_region(veh, ratio=0.0, box={"speed": (10.0, 30.0)},
    ...                         k1=np.linspace(-1, 1, 5), k2=np.linspace(-1, 1, 5))
    >>> reg.stable.astype(int)
    array([[0, 0, 0, 0, 0],
           [0, 0, 0, 0, 0],
           [0, 0, 0, 0, 0],
           [0, 0, 0, 1, 1],
           [0, 0, 0, 1, 1]])
    """

    plant: Any
    box: ParameterBox
    ratio: Any
    k1: np.ndarray
    k2: np.ndarray
    stable: np.ndarray
    boundary: tuple[BoundaryPiece, ...]
    worst_parameters: tuple[dict[str, float], ...]
    failing_point: np.ndarray
    failing_delay: np.ndarray
    samples: dict[str, np.ndarray]
    evaluations: int

    @property
    def stable_fraction(self) -> float:
        """Fraction of grid points that are robustly stable."""
        return float(np.mean(self.stable))

    @property
    def empty(self) -> bool:
        """True when no grid point is robustly stable."""
        return not bool(np.any(self.stable))

    def describe(self) -> str:
        """One line: the ratio and the box."""
        parts = []
        for name, unit in BOX_PARAMETERS.items():
            v = getattr(self.box, name)
            if v is None or (name == "delay" and v == 0.0):
                continue
            text = f"{v[0]:g}-{v[1]:g}" if isinstance(v, tuple) else f"{v:g}"
            parts.append(f"{name.replace('_', ' ')} {text} {unit}")
        a = self.ratio if not callable(self.ratio) else "a(V)"
        return f"a = {a}, " + ", ".join(parts)

    def plot(
        self, ax: Axes | None = None, *, nominal: bool = True, title: bool | str = True
    ) -> ct.ControlPlot:
        r"""Draw the robust region over the chart of the box's centre.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; a new figure if None.
        nominal : bool, optional
            Whether to draw the stable set of the nominal plant (every
            interval at its mid-point) underneath, light grey.
        title : bool or str, optional
            True: :meth:`describe`; a string: that title; False: none.

        Returns
        -------
        control.ControlPlot
            ``.lines[0, 0]`` holds the drawn artists.

        Examples
        --------
        >>> import matplotlib; matplotlib.use("Agg")
        >>> import matplotlib.pyplot as plt, numpy as np, fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> reg = fws.robust_region(veh, ratio=0.0, box={"speed": (10.0, 30.0)},
        ...                         k1=np.linspace(-0.1, 0.3, 21),
        ...                         k2=np.linspace(-0.2, 1.0, 21))
        >>> cplt = reg.plot()
        >>> cplt.axes[0, 0].get_xlabel()
        '$k_1$ [rad/m]'
        >>> plt.close(cplt.figure)
        """
        import control as ct
        import matplotlib.pyplot as plt
        from matplotlib.patches import Patch

        from .charts import stability_chart

        if ax is None:
            _, ax = plt.subplots(figsize=(6.0, 5.0), layout="constrained")
        artists: list[Any] = []
        handles: list[Any] = []
        X, Y = np.meshgrid(self.k1, self.k2)
        if nominal:
            fam = _Family(self.plant, self.box, None)
            mid = fam.nominal()
            tau = mid.pop("delay", self.box.delay_range[0])
            p0 = fam.plant(mid)
            ratio = resolve_ratio(p0, self.ratio)
            ch = stability_chart(p0, ratio=ratio, k1=self.k1, k2=self.k2, delay=tau)
            if not ch.empty:
                artists.append(
                    ax.contourf(X, Y, ch.stable, levels=[0.5, 1.5], colors=["0.8"])
                )
            handles.append(Patch(facecolor="0.8", label="stable at the box centre"))
        if not self.empty:
            artists.append(
                ax.contourf(
                    X, Y, self.stable, levels=[0.5, 1.5], colors=["C0"], alpha=0.6
                )
            )
        handles.append(Patch(facecolor="C0", alpha=0.6, label="robustly stable (grid)"))
        styles = {"complex": ("C3", "-"), "real": ("k", "--"), "envelope": ("C2", "-")}
        names = {
            "complex": r"boundary: roots at $\pm j\omega$",
            "real": r"boundary: root at $s = 0$",
            "envelope": "boundary: envelope over the delay",
        }
        shown = set()
        for piece in self.boundary:
            color, ls = styles[piece.kind]
            (ln,) = ax.plot(piece.k1, piece.k2, ls, color=color, lw=1.4)
            artists.append(ln)
            if piece.kind not in shown:
                ln.set_label(names[piece.kind])
                handles.append(ln)
                shown.add(piece.kind)
        ax.set_xlim(self.k1.min(), self.k1.max())
        ax.set_ylim(self.k2.min(), self.k2.max())
        ax.set_xlabel(r"$k_1$ [rad/m]")
        ax.set_ylabel(r"$k_2$ [-]")
        if title:
            ax.set_title(self.describe() if title is True else title, fontsize=9)
        leg = ax.legend(handles=handles, fontsize=7, loc="best")
        lines = np.empty((1, 1), dtype=object)
        lines[0, 0] = artists
        return ct.ControlPlot(lines, np.array([[ax]]), ax.figure, legend=leg)


def _axis(name: str, values) -> np.ndarray:
    from .charts import DEFAULT_GAIN_AXIS

    if values is None:
        return DEFAULT_GAIN_AXIS.copy()
    arr = np.asarray(check_finite(name, values), dtype=float)
    if arr.ndim != 1 or arr.size < 2:
        raise ValueError(
            f"{name} must be a 1-D array of at least 2 finite gains, got {values!r}"
        )
    if not np.all(np.diff(arr) > 0):
        raise ValueError(f"{name} must be strictly increasing, got {values!r}")
    return arr


def _check_count(name: str, value: Any, low: int, high: int) -> int:
    ok = (
        isinstance(value, (int, np.integer))
        and not isinstance(value, (bool, np.bool_))
        and low <= value <= high
    )
    if not ok:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    return int(value)


def _check_ratio(ratio: Any) -> Any:
    if callable(ratio):
        return ratio
    return check_magnitude("ratio", check_scalar("ratio", ratio), MAX_RATIO)


def robust_stable(
    plant: Any,
    gains: SteeringGains,
    *,
    box: ParameterBox | dict[str, Any],
    samples: int = 9,
    depth: int = 6,
    model: str | None = None,
) -> bool | np.ndarray:
    r"""Whether gains are stable at every parameter point of a box.

    The delay interval is exact (crossing delays in closed form); the other
    interval parameters are sampled on a grid with every vertex, refined
    adaptively (see :mod:`fws_control.robust`).

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant; the box overrides its speed, curvature, lag and (dynamic
        model) cornering stiffnesses and mass. A Vehicle needs the speed in
        the box. A state space admits only a delay interval.
    gains : SteeringGains
        Gains (arrays broadcast) with a scalar ratio (or a ratio schedule
        ``ratio(vehicle, speed=...)``).
    box : ParameterBox or dict
        The parameter box, e.g. ``{"speed": (10, 30), "delay": (0, 0.24)}``.
    samples : int, optional
        Base samples per interval parameter (vertices included), 2 to 101.
    depth : int, optional
        Most bisection rounds of the adaptive refinement, 0 to 12.
    model : str, optional
        With a Vehicle only: ``"kinematic"`` (default), ``"paper"`` or
        ``"dynamic"``.

    Returns
    -------
    bool or ndarray of bool
        True where the loop is stable for every parameter point.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> box = {"speed": (10.0, 30.0), "delay": (0.0, 0.24), "steering_lag": 0.27}
    >>> fws.robust_stable(veh, fws.SteeringGains(0.002, 0.2, ratio=0.0), box=box)
    True
    >>> fws.robust_stable(veh, fws.SteeringGains(0.02, 0.2, ratio=0.0), box=box)
    False
    """
    g = check_gains(gains)
    if np.ndim(g.ratio):
        raise ValueError(f"gains.ratio must be a scalar here, got {g.ratio!r}")
    b = _as_box(box)
    fam = _Family(plant, b, model)
    sweep = _Sweep(
        fam,
        _check_ratio(g.ratio),
        _check_count("samples", samples, 2, 101),
        _check_count("depth", depth, 0, 12),
    )
    k1, k2 = np.broadcast_arrays(
        np.asarray(g.k1, dtype=float), np.asarray(g.k2, dtype=float)
    )
    ok = sweep.run(k1.ravel(), k2.ravel())[0].reshape(k1.shape)
    return bool(ok) if ok.ndim == 0 else ok


def robust_region(
    plant: Any,
    *,
    ratio: Any,
    box: ParameterBox | dict[str, Any],
    k1: RealArrayLike | None = None,
    k2: RealArrayLike | None = None,
    samples: int = 9,
    depth: int = 6,
    model: str | None = None,
) -> RobustRegion:
    r"""The gains stable at every parameter point of a box, with its boundary.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant; the box overrides its speed, curvature, lag and (dynamic
        model) cornering stiffnesses and mass. A Vehicle needs the speed in
        the box. A state space admits only a delay interval.
    ratio : float or callable
        Rear-to-front steering ratio :math:`a` [-], or a schedule
        ``ratio(vehicle, speed=...)``.
    box : ParameterBox or dict
        The parameter box: ``{"speed": (10, 30), "delay": (0, 0.24),
        "steering_lag": 0.27, "curvature": 0.0}`` (a pair is an interval,
        a number a fixed value).
    k1, k2 : array_like, optional
        Strictly increasing grid axes [rad/m], [-]; default 401 points on
        ``[-1, 1]``.
    samples : int, optional
        Base samples per interval parameter other than the delay (vertices
        included), 2 to 101.
    depth : int, optional
        Most bisection rounds of the adaptive refinement, 0 to 12.
    model : str, optional
        With a Vehicle only: ``"kinematic"`` (default), ``"paper"`` or
        ``"dynamic"``.

    Returns
    -------
    RobustRegion
        ``stable`` of shape ``(len(k2), len(k1))`` and the computed
        ``boundary``.

    Raises
    ------
    ValueError
        For an invalid box entry, grid, ratio, `samples` or `depth`.
    TypeError
        For an unknown plant, or a Vehicle without a speed in the box.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> box = {"speed": (10.0, 30.0), "delay": (0.0, 0.24), "steering_lag": 0.27}
    >>> reg = fws.robust_region(veh, ratio=0.0, box=box,
    ...                         k1=np.linspace(0.0, 0.01, 41),
    ...                         k2=np.linspace(0.0, 0.5, 41))
    >>> bool(reg.stable[20, 10]), bool(reg.stable[20, 35])
    (True, False)
    """
    b = _as_box(box)
    fam = _Family(plant, b, model)
    sweep = _Sweep(
        fam,
        _check_ratio(ratio),
        _check_count("samples", samples, 2, 101),
        _check_count("depth", depth, 0, 12),
    )
    k1a = _axis("k1", k1)
    k2a = _axis("k2", k2)
    K1, K2 = np.meshgrid(k1a, k2a)
    ok, fail_point, fail_delay, points, all_points, grid = sweep.run(
        K1.ravel(), K2.ravel()
    )
    # the boundary test runs on the final samples

    def verdict(x, y):
        good = np.ones(x.size, dtype=bool)
        for key in all_points:
            idx = np.flatnonzero(good)
            if idx.size == 0:
                break
            res, _ = _delay_verdict(
                sweep.poly(key), x[idx], y[idx], sweep.tlo, sweep.thi
            )
            good[idx[~res]] = False
        return good

    # candidate curves: the parameter points that removed grid points (a
    # curve of a point that removes none does not reach the region)
    boundary = _boundary(sweep, points, k1a, k2a, ok.reshape(K1.shape), verdict)
    shape = K1.shape
    return RobustRegion(
        plant=fam.template,
        box=b,
        ratio=sweep.ratio,
        k1=k1a,
        k2=k2a,
        stable=ok.reshape(shape),
        boundary=boundary,
        worst_parameters=tuple(dict(p) for p in points),
        failing_point=fail_point.reshape(shape),
        failing_delay=fail_delay.reshape(shape),
        samples={n: np.array(v) for n, v in grid.items()},
        evaluations=sweep.evaluations,
    )


@summary_repr
@dataclass(frozen=True, eq=False)
class RobustDesign:
    r"""Gains that maximise the worst-case decay over a parameter box.

    Returned by :func:`robust_gains`; do not build it directly.

    Attributes
    ----------
    gains : SteeringGains
        The design.
    abscissa : float
        Worst-case spectral abscissa over the box [1/s]: the real part of
        the rightmost root at the worst parameter point (the decay rate is
        ``-abscissa``).
    worst : dict of str to float
        The worst-case parameter point, the delay included.
    region : RobustRegion
        The robust region the search started from.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> des = fws.robust_gains(veh, ratio=0.0, box={"speed": (10.0, 30.0)},
    ...                        k1=np.linspace(0.0, 0.2, 5),
    ...                        k2=np.linspace(0.0, 1.0, 5), starts=1)
    >>> des.abscissa < 0
    True
    """

    gains: SteeringGains
    abscissa: float
    worst: dict[str, float]
    region: RobustRegion


def _abscissa(family: _Family, ratio, k1: float, k2: float, point: dict) -> float:
    """Real part of the rightmost root at one parameter point (delay included)."""
    from .delay import rightmost_roots

    values = dict(point)
    tau = float(values.pop("delay", 0.0))
    # the discretisation takes no delay below 1e-6 s; that close to zero the
    # delay-free roots are the answer to far better than the search needs
    tau = 0.0 if tau < 1e-6 else tau
    plant = family.plant(values)
    a = resolve_ratio(plant, ratio)
    g = SteeringGains(k1, k2, float(a))
    # 10 starting nodes: the discretisation doubles them until the rightmost
    # root agrees between two of them, so a small start costs no accuracy
    return float(rightmost_roots(plant, g, delay=tau, n=1, nodes=10)[0].real)


def robust_gains(
    plant: Any,
    *,
    ratio: Any,
    box: ParameterBox | dict[str, Any],
    k1: RealArrayLike | None = None,
    k2: RealArrayLike | None = None,
    samples: int = 3,
    starts: int = 2,
    model: str | None = None,
) -> RobustDesign:
    r"""Gains that maximise the worst-case decay rate over a parameter box.

    The worst-case spectral abscissa
    :math:`lpha^*(k) = \max_{p \in B} lpha(k; p)` (rightmost root by
    :func:`~fws_control.rightmost_roots`, or the eigenvalues without delay)
    is minimised over the gains. The inner maximum runs over the vertices
    of the box and ``samples`` points per interval (delay included), and is
    then polished at the optimum by a bounded search in each parameter from
    the worst sample; the outer minimum starts from the `starts` grid points
    of :func:`robust_region` with the smallest worst-case abscissa and is
    refined by Nelder-Mead. The returned worst case is the polished one.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        As in :func:`robust_region`.
    ratio : float or callable
        Rear-to-front steering ratio :math:`a` [-] or a schedule.
    box : ParameterBox or dict
        The parameter box.
    k1, k2 : array_like, optional
        Grid axes of the robust region the search starts from [rad/m], [-].
    samples : int, optional
        Samples per interval parameter of the inner maximum, 2 to 9.
    starts : int, optional
        Starting points of the outer search, 1 to 50.
    model : str, optional
        With a Vehicle only, as in :func:`robust_region`.

    Returns
    -------
    RobustDesign

    Raises
    ------
    ValueError
        If no grid point is robustly stable (widen the grid), or for invalid
        arguments as in :func:`robust_region`.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> des = fws.robust_gains(veh, ratio=0.0, box={"speed": (10.0, 30.0)},
    ...                        k1=np.linspace(0.0, 0.2, 5),
    ...                        k2=np.linspace(0.0, 1.0, 5), starts=1)
    >>> des.worst["speed"]
    10.0
    """
    from scipy.optimize import minimize, minimize_scalar

    n_samples = _check_count("samples", samples, 2, 9)
    n_starts = _check_count("starts", starts, 1, 50)
    region = robust_region(plant, ratio=ratio, box=box, k1=k1, k2=k2, model=model)
    if region.empty:
        raise ValueError(
            "no gain point of the grid k1, k2 is robustly stable over the box; "
            "widen or move the grid"
        )
    fam = _Family(plant, region.box, model)
    ranges = dict(region.box.intervals)
    names = list(ranges)
    lists = [np.linspace(*ranges[n], n_samples) for n in names]
    fixed_delay = {} if "delay" in ranges else {"delay": region.box.delay_range[0]}
    points = [
        {**dict(zip(names, vals, strict=True)), **fixed_delay}
        for vals in _product([list(v) for v in lists])
    ]

    def worst(x) -> tuple[float, dict]:
        vals = [_abscissa(fam, region.ratio, x[0], x[1], p) for p in points]
        j = int(np.argmax(vals))
        return vals[j], points[j]

    sweep = _Sweep(fam, region.ratio, 9, 6)  # keeps its plants between calls

    def objective(x) -> float:
        if not sweep.run(np.array([x[0]]), np.array([x[1]]))[0][0]:
            return 1e3  # outside the robust region
        return worst(x)[0]

    iy, ix = np.nonzero(region.stable)
    pick = np.linspace(0, ix.size - 1, min(ix.size, 4 * n_starts)).astype(int)
    cand = [(region.k1[ix[i]], region.k2[iy[i]]) for i in pick]
    scored = sorted(cand, key=lambda x: worst(x)[0])[:n_starts]
    span = np.array([np.ptp(region.k1), np.ptp(region.k2)])
    best: Any = None
    for x0 in scored:
        res = minimize(
            objective,
            np.array(x0),
            method="Nelder-Mead",
            options={
                "initial_simplex": np.array(x0)
                + np.array([[0, 0], [0.05, 0], [0, 0.05]]) * span,
                "xatol": 1e-6 * float(np.min(span)),
                "fatol": 1e-6,
                "maxiter": 80,
            },
        )
        if best is None or res.fun < best.fun:
            best = res
    x = best.x
    value, point = worst(x)
    # polish the worst case: each interval parameter in turn, bounded
    for n in names:
        lo, hi = ranges[n]

        def neg(v, n=n, base=point):
            return -_abscissa(fam, region.ratio, x[0], x[1], {**base, n: v})

        r = minimize_scalar(
            neg, bounds=(lo, hi), method="bounded", options={"xatol": 1e-6 * (hi - lo)}
        )
        if -r.fun > value:
            value, point = -float(r.fun), {**point, n: float(r.x)}
    return RobustDesign(
        gains=SteeringGains(float(x[0]), float(x[1]), _plain(region.ratio)),
        abscissa=float(value),
        worst={k: float(v) for k, v in point.items()},
        region=region,
    )


def _plain(ratio):
    return ratio if callable(ratio) else float(ratio)
