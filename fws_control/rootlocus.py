r"""Root loci of the structured 4WS loop on python-control objects.

With the rear angle tied to the front one, ``delta_r = a*delta_f``, the
plant has a single steering input ``u = delta_f``:

.. math::
    \dot x = \mathbf A x + \mathbf b u,\qquad
    \mathbf b = \mathbf B_f + a\mathbf B_r,\qquad
    u = -g\,(k_1 e + k_2\theta),

so scaling the gain direction ``(k1, k2)`` by ``g`` is a classical SISO root
locus of the loop transfer function

.. math:: L(s) = \frac{k_1 n_1(s) + k_2 n_2(s)}{\det(s\mathbf I-\mathbf A)}

(:func:`gain_loop`, from the affine characteristic polynomial), drawn by
:func:`control.root_locus_map` / :func:`control.root_locus_plot`. At ``g = 1``
its closed-loop poles are those of :func:`closed_loop`.

:func:`parameter_locus` follows the closed-loop poles while a parameter of
the loop varies: ``ratio``, ``k1`` or ``k2`` for any plant, ``speed`` or
``curvature`` for the kinematic :class:`LateralPlant`. For two states the
poles are the closed-form roots of :math:`\lambda^2 + p_1\lambda + p_0`; for
more, the eigenvalues of the companion matrices, matched from one value to the
next so that the branches are continuous. Both come back as
:class:`control.PoleZeroData`, so ``.plot()`` draws them.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import control as ct
import numpy as np
from scipy.optimize import linear_sum_assignment

from .gains import SteeringGains
from .hints import RealArrayLike
from .linear import affine_characteristic_polynomial, check_gains
from .plant import LateralPlant, as_plant
from .pole_placement import double_root_gains
from .validation import check_finite, check_model

__all__ = [
    "gain_loop",
    "gain_locus",
    "parameter_locus",
    "quadratic_roots",
    "polynomial_roots",
    "refined_scale",
    "LOCUS_PARAMETERS",
]

#: Names accepted by :func:`parameter_locus`; the first two need a
#: :class:`LateralPlant` (or a Vehicle with ``speed=``).
LOCUS_PARAMETERS = ("speed", "curvature", "ratio", "k1", "k2")


def gain_loop(
    plant: Any,
    gains: SteeringGains,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> ct.TransferFunction:
    r"""Loop transfer function of the gain scaling, SISO.

    .. math:: L(s) = \frac{k_1 n_1(s) + k_2 n_2(s)}{d(s)}
              = [k_1\ k_2]\,\mathbf C_s(s\mathbf I-\mathbf A)^{-1}\mathbf b

    with :math:`d, n_1, n_2` of :func:`affine_characteristic_polynomial`. Closing
    ``u = -g y`` gives the structured controller with gains ``g*k1, g*k2``;
    python-control's root locus computes the roots of :math:`1 + g L(s)`, so
    its locus at ``g = 1`` is the pole set of :func:`closed_loop`.

    The transfer function is built from these coefficients rather than
    converted from a state space: python-control's zeros of a state space
    with ``D = 0`` include a spurious huge "zero" (the one at infinity) that
    wrecks the automatic plot limits of :func:`control.root_locus_plot`.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), one operating point.
    gains : SteeringGains
        Gain direction ``(k1, k2)`` and the ratio ``a``; scalars.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    control.TransferFunction
        Input ``delta_f``; output ``k_x`` (the feedback signal
        ``k1*e + k2*theta``). ``control.ss(loop)`` gives a state-space form.

    Examples
    --------
    >>> import numpy as np, control as ct, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    >>> g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    >>> loop = fws.gain_loop(plant, g)
    >>> loop.poles().real.round(12) + 0.0, loop.poles().imag
    (array([0., 0.]), array([ 0.5, -0.5]))
    >>> rl = ct.root_locus_map(loop, gains=[1.0])
    >>> np.allclose(rl.loci[0], [-1.0, -1.0], atol=1e-6)
    True
    """
    g = check_gains(gains, scalar=True)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    _one_point(p)
    cp = affine_characteristic_polynomial(p, ratio=g.ratio)
    num = np.trim_zeros(g.k1 * cp.n1 + g.k2 * cp.n2, "f")
    if num.size == 0:
        num = np.zeros(1)
    return ct.tf(
        num,
        np.asarray(cp.open_loop, dtype=float),
        inputs=["delta_f"],
        outputs=["k_x"],
        name="gain_loop",
    )


def _one_point(p) -> None:
    if isinstance(p, LateralPlant) and p.shape != ():
        raise ValueError(
            f"plant must be one operating point here, got speed/curvature of shape "
            f"{p.shape}"
        )


def refined_scale(lo: float, hi: float, n: int, at: float = 1.0) -> np.ndarray:
    """Gain scales ``linspace(lo, hi, n)`` plus geometric refinement near `at`.

    A double-root design breaks away from the real axis at ``g = 1``, where
    the poles move like ``sqrt(g - 1)``; uniform sampling draws a kink there.

    Examples
    --------
    >>> from fws_control.rootlocus import refined_scale
    >>> g = refined_scale(0.0, 4.0, 5)
    >>> bool(g[0] == 0.0 and g[-1] == 4.0 and (abs(g - 1.0) < 1e-5).sum() >= 2)
    True
    """
    step = np.geomspace(1e-6, 0.2, 40)
    near = at + np.concatenate([-step, step])
    near = near[(near >= lo) & (near <= hi)]
    return np.unique(np.concatenate([np.linspace(lo, hi, n), near]))


def gain_locus(
    plant: Any,
    gains: SteeringGains,
    *,
    scale: RealArrayLike | None = None,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> ct.PoleZeroData:
    """Root locus of the gain scaling ``g`` (``k1, k2 -> g*k1, g*k2``).

    Thin wrapper around :func:`control.root_locus_map` of :func:`gain_loop`.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`).
    gains : SteeringGains
        Scalar gain direction and ratio.
    scale : array_like, optional
        Values of ``g``; default: python-control's automatic choice.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    control.PoleZeroData
        ``.loci`` of shape ``(len(scale), n)``, ``.gains`` the scales. Its
        ``.plot()`` draws on a new figure (or on `ax`) and marks the roots of
        the design itself, ``g = 1`` (``initial_gain=None``: no mark).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    >>> fws.gain_locus(veh, g, speed=5.0, scale=[0.0, 1.0, 2.0]).loci.shape
    (3, 2)
    """
    loop = gain_loop(plant, gains, speed=speed, curvature=curvature, model=model)
    if scale is not None:
        scale = np.atleast_1d(check_finite("scale", scale))
        if scale.ndim != 1 or scale.size == 0:
            raise ValueError(
                f"scale must be None or a non-empty 1-D array, got shape {scale.shape}"
            )
    rl = ct.root_locus_map(loop, gains=scale)
    return _GainLocusData(
        rl.poles, rl.zeros, gains=rl.gains, loci=rl.loci, dt=rl.dt,
        sysname=rl.sysname, sys=rl.sys, sort_loci=False,
    )  # fmt: skip


def quadratic_roots(p1: RealArrayLike, p0: RealArrayLike) -> np.ndarray:
    r"""Roots of :math:`\lambda^2 + p_1\lambda + p_0`, shape ``(..., 2)``.

    Column 0 is ``(-p1 + sqrt(p1^2 - 4 p0))/2`` with the principal complex
    square root, column 1 the other root. Both are continuous functions of
    ``(p1, p0)``: where the discriminant changes sign the two roots meet, and
    column 0 continues into the root with positive imaginary part. A
    monotonic parameter sweep therefore gives continuous branches without
    re-sorting.

    Examples
    --------
    >>> from fws_control.rootlocus import quadratic_roots
    >>> quadratic_roots([3.0, 2.0], [2.0, 2.0])
    array([[-1.+0.j, -2.+0.j],
           [-1.+1.j, -1.-1.j]])
    """
    p1 = np.asarray(p1, dtype=float)
    p0 = np.asarray(p0, dtype=float)
    # Adding +0j (not complex()) keeps the imaginary zero positive, so the
    # square root of a negative discriminant is +i*sqrt(|disc|).
    sq = np.sqrt(p1**2 - 4.0 * p0 + 0j)
    return np.stack([(-p1 + sq) / 2.0, (-p1 - sq) / 2.0], axis=-1)


def polynomial_roots(coefficients: RealArrayLike) -> np.ndarray:
    """Roots of a sequence of polynomials, matched into continuous branches.

    The roots of each polynomial (rows of `coefficients`, highest power
    first, nonzero leading coefficient) are the eigenvalues of its companion
    matrix, computed for all rows at once; consecutive rows are then matched
    by a minimum-distance assignment, so column ``j`` follows one branch
    through a smooth parameter sweep.

    Parameters
    ----------
    coefficients : array_like
        Shape ``(m, n + 1)``.

    Returns
    -------
    ndarray of complex
        Shape ``(m, n)``.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.rootlocus import polynomial_roots
    >>> r = polynomial_roots([np.poly([-1, -2, -3]), np.poly([-1.1, -2, -3])])
    >>> np.round(r.real, 6)
    array([[-3. , -2. , -1. ],
           [-3. , -2. , -1.1]])
    """
    c = np.atleast_2d(np.asarray(coefficients, dtype=float))
    m, n1 = c.shape
    n = n1 - 1
    comp = np.zeros((m, n, n))
    comp[:, 0, :] = -c[:, 1:] / c[:, :1]
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    roots = np.linalg.eigvals(comp)
    roots[0] = roots[0][np.lexsort((roots[0].imag, roots[0].real))]
    for i in range(1, m):
        cost = np.abs(roots[i - 1][:, None] - roots[i][None, :])
        _, cols = linear_sum_assignment(cost)
        roots[i] = roots[i][cols]
    return roots


class _LocusData(ct.PoleZeroData):
    """PoleZeroData whose ``plot()`` draws on a new figure unless given `ax`.

    python-control draws a pole-zero or root-locus plot onto the current
    figure when it has a single axes, to overlay loci; after a stability
    chart (also a single axes, in the gain plane) that would draw s-plane
    roots into the k1-k2 chart. Every ``.plot()`` of this package draws on a
    new figure unless `ax` is given; pass ``ax=`` to overlay.
    """

    def plot(self, *args, **kwargs):
        if kwargs.get("ax") is None:
            import matplotlib.pyplot as plt  # not at import: CLI start-up

            # an empty current figure: python-control creates the axes
            # (with its grid) there instead of reusing the previous plot's
            plt.figure()
        return super().plot(*args, **kwargs)


class _GainLocusData(_LocusData):
    """Gain locus whose ``plot()`` marks the design, the scale ``g = 1``.

    ``initial_gain=None`` leaves the mark out; another value marks the
    roots at that scale.
    """

    def plot(self, *args, **kwargs):
        kwargs.setdefault("initial_gain", 1.0)
        if kwargs["initial_gain"] is not None and self.sys is None:
            raise ValueError("this gain locus carries no system to mark gains on")
        return super().plot(*args, **kwargs)


class _ParameterLocusData(_LocusData):
    """PoleZeroData whose ``plot()`` frames the whole locus.

    python-control chooses root-locus limits for a gain locus (around the
    open-loop poles and zeros); a speed or curvature locus can run far
    outside them. Explicit `xlim`/`ylim` still win.
    """

    def plot(self, *args, **kwargs):
        loci = np.asarray(self.loci)
        finite = loci[np.isfinite(loci)]
        if finite.size:
            re, im = finite.real, finite.imag
            span = max(float(np.ptp(re)), float(np.ptp(im)), 0.1)
            pad = 0.08 * span
            kwargs.setdefault("xlim", (float(re.min()) - pad, float(re.max()) + pad))
            ymax = max(float(np.abs(im).max()), 0.05 * span) + pad
            kwargs.setdefault("ylim", (-ymax, ymax))
        return super().plot(*args, **kwargs)


def parameter_locus(
    plant: Any,
    gains: SteeringGains,
    *,
    parameter: str,
    values: RealArrayLike,
    redesign_pole: float | None = None,
    design_model: str | None = None,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> ct.PoleZeroData:
    r"""Closed-loop poles while one parameter of the loop varies.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`), one operating point.
    gains : SteeringGains
        Scalar ``k1, k2`` and ``ratio``. When `parameter` is ``"ratio"`` the
        gains ``k1, k2`` stay fixed while ``a`` varies (so ``k3 = a*k1`` and
        ``k4 = a*k2`` change with it); to follow a design instead, give
        `redesign_pole`.
    parameter : {"speed", "curvature", "ratio", "k1", "k2"}
        The parameter that takes `values`; ``"speed"`` and ``"curvature"``
        need a :class:`LateralPlant`.
    values : array_like
        1-D values of the parameter (SI units). A monotonic sweep gives
        continuous branches.
    redesign_pole : float, optional
        If given, the gains are recomputed at every value by
        :func:`double_root_gains` with this double root (2-state plants;
        not for ``"k1"``, ``"k2"``). With `design_model` different from the
        plant's model this shows where a design made in one model puts the
        poles of the other, e.g. the paper's gains in the exact
        linearisation.
    design_model : {"kinematic", "paper"}, optional
        Model used for the redesign (a :class:`LateralPlant` only); default
        the plant's. With a ``model="dynamic"`` plant, ``"kinematic"`` shows
        where the kinematic double-root design puts the dynamic poles.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    control.PoleZeroData
        ``.loci`` of shape ``(len(values), n)``; ``.gains`` holds `values`;
        ``.poles`` the poles at the first value (plotted as ``x``);
        ``.zeros`` is empty. ``.plot()`` draws the locus with axis limits
        that cover all of it (pass ``xlim``/``ylim`` to override).

    Raises
    ------
    ValueError
        For an unknown `parameter`, ``"speed"``/``"curvature"``/
        `design_model` with a state-space plant, non-finite or empty
        `values`, a zero speed among them, or `redesign_pole` with
        ``"k1"``/``"k2"``.
    UncontrollableError
        If a redesign hits an uncontrollable design.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    >>> pz = fws.parameter_locus(plant, g, parameter="speed",
    ...                          values=[2.5, 5.0, 10.0])
    >>> pz.loci.shape
    (3, 2)
    >>> np.allclose(pz.loci[1], [-1.0, -1.0], atol=1e-6)
    True
    """
    g = check_gains(gains, scalar=True)
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    _one_point(p)
    if not isinstance(parameter, str) or parameter not in LOCUS_PARAMETERS:
        raise ValueError(
            f"parameter must be one of {LOCUS_PARAMETERS}, got {parameter!r}"
        )
    lateral = isinstance(p, LateralPlant)
    if parameter in ("speed", "curvature") and not lateral:
        raise ValueError(
            f"parameter={parameter!r} needs a LateralPlant (or a Vehicle with "
            "speed=); a state-space plant has no operating point to vary: sweep "
            "'ratio', 'k1' or 'k2', or rebuild the plant per value"
        )
    if design_model is not None:
        if not lateral:
            raise ValueError("design_model= needs a LateralPlant")
        design_model = check_model(design_model, name="design_model")
    vals = np.atleast_1d(check_finite("values", values)).astype(float)
    if vals.ndim != 1 or vals.size == 0:
        raise ValueError(
            f"values must be a non-empty 1-D array, got shape {vals.shape}"
        )
    par = {"ratio": g.ratio, "k1": g.k1, "k2": g.k2}
    swept = p
    if parameter in ("speed", "curvature"):
        try:
            swept = replace(p, **{parameter: vals})
        except ValueError as exc:
            # the plant names its field (speed, curvature): say it came from values
            raise ValueError(f"values (the swept {parameter}): {exc}") from exc
    else:
        par[parameter] = vals
    if redesign_pole is not None:
        if parameter in ("k1", "k2"):
            raise ValueError(
                f"redesign_pole cannot be used with parameter={parameter!r}: the "
                "design fixes both k1 and k2"
            )
        target = swept
        if design_model is not None:
            # a kinematic design model has no tyres: drop a magic tyre
            tyre = swept.tyre if design_model == "dynamic" else "linear"
            target = replace(swept, model=design_model, tyre=tyre)
        d = double_root_gains(target, ratio=par["ratio"], pole=redesign_pole)
        par["k1"], par["k2"] = d.k1, d.k2
    cp = affine_characteristic_polynomial(swept, ratio=par["ratio"])
    coeffs = cp.coefficients(par["k1"], par["k2"])
    coeffs = np.broadcast_to(coeffs, vals.shape + coeffs.shape[-1:])
    if cp.order == 2:
        loci = quadratic_roots(coeffs[:, 1], coeffs[:, 2])
    else:
        loci = polynomial_roots(coeffs)
    label = f"{parameter} {vals[0]:g} to {vals[-1]:g}"
    return _ParameterLocusData(
        loci[0].copy(),
        np.array([], dtype=complex),
        gains=vals,
        loci=loci,
        dt=0,
        sysname=label,
        sort_loci=False,
    )
