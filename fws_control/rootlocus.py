r"""Root loci of the structured 4WS loop on python-control objects.

With the rear angle tied to the front one, ``delta_r = a*delta_f``, the
linear plant has a single input ``u = delta_f``:

.. math::
    \dot x = \mathbf A x + \mathbf b u,\qquad
    \mathbf b = \mathbf B\begin{bmatrix}1\\ a\end{bmatrix},\qquad
    u = -g\,[k_1\ k_2]\,x,

so scaling the gain direction ``(k1, k2)`` by ``g`` is a classical SISO root
locus of the loop transfer function

.. math:: L(s) = [k_1\ k_2](s\mathbf I-\mathbf A)^{-1}\mathbf b

(:func:`gain_loop`), drawn by :func:`control.root_locus_map` /
:func:`control.root_locus_plot`. At ``g = 1`` its closed-loop poles are those
of :func:`closed_loop`.

:func:`parameter_locus` follows the closed-loop poles while a parameter of
the loop (``ratio``, ``speed``, ``curvature``, ``k1`` or ``k2``) varies. The
characteristic polynomial is quadratic, so the poles are the closed-form
roots of :math:`\lambda^2 + p_1\lambda + p_0`, vectorised over the values and
returned as :class:`control.PoleZeroData` so that ``.plot()`` draws them.
"""

from __future__ import annotations

import control as ct
import numpy as np

from ._validation import check_finite, check_model, check_nonzero
from .design import double_root_gains
from .gains import SteeringGains
from .linear import characteristic_coefficients
from .vehicle import Vehicle

__all__ = [
    "gain_loop",
    "gain_locus",
    "parameter_locus",
    "quadratic_roots",
    "refined_scale",
    "LOCUS_PARAMETERS",
]

#: Names accepted by :func:`parameter_locus`.
LOCUS_PARAMETERS = ("ratio", "speed", "curvature", "k1", "k2")


def _check_gains(gains) -> SteeringGains:
    if not isinstance(gains, SteeringGains):
        raise TypeError(f"gains must be a SteeringGains, got {type(gains).__name__}")
    if np.ndim(gains.k1) or np.ndim(gains.k2) or np.ndim(gains.ratio):
        raise ValueError("gains must hold scalar k1, k2 and ratio")
    return gains


def gain_loop(
    vehicle: Vehicle,
    speed: float,
    curvature: float,
    gains: SteeringGains,
    model: str = "exact",
) -> ct.TransferFunction:
    r"""Loop transfer function of the gain scaling, SISO.

    .. math::
        L(s) = [k_1\ k_2](s\mathbf I-\mathbf A)^{-1}\mathbf B[1,\ a]^T
             = \frac{(p_1 - \gamma_1)s + (p_0 - \gamma_0)}{s^2 + V^2\kappa^2}

    where :math:`p_1, p_0` are the closed-loop coefficients of
    :func:`characteristic_coefficients` and :math:`\gamma_1 = 0`,
    :math:`\gamma_0 = V^2\kappa^2` their gain-free parts. Closing
    ``u = -g y`` gives :math:`\mathbf A - g\,\mathbf B[1, a]^T[k_1\ k_2]`, the
    structured controller with gains ``g*k1, g*k2``; python-control's root
    locus computes the roots of :math:`1 + g L(s)`, so its locus at ``g = 1`` is
    the pole set of :func:`closed_loop` with `gains`.

    The transfer function is built from these closed-form coefficients rather
    than converted from a state space: python-control's zeros of a state space
    with ``D = 0`` include a spurious huge "zero" (the one at infinity) that
    wrecks the automatic plot limits of :func:`control.root_locus_plot`.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    speed, curvature : float
        Operating point [m/s], [1/m].
    gains : SteeringGains
        Gain direction ``(k1, k2)`` and the ratio ``a``; scalars.
    model : {"exact", "paper"}, optional
        Linearisation, see :func:`linearize`.

    Returns
    -------
    control.TransferFunction
        Input ``delta_f``; output ``k_x`` (the feedback signal
        ``k1*e + k2*theta``). ``control.ss(loop)`` gives a state-space form.

    Examples
    --------
    >>> import numpy as np, control as ct, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, 5.0, 0.1, ratio=-1.0, pole=-1.0)
    >>> loop = fws.gain_loop(veh, 5.0, 0.1, g)
    >>> loop.poles().real.round(12) + 0.0, loop.poles().imag
    (array([0., 0.]), array([ 0.5, -0.5]))
    >>> rl = ct.root_locus_map(loop, gains=[1.0])
    >>> np.allclose(rl.loci[0], [-1.0, -1.0], atol=1e-6)
    True
    """
    gains = _check_gains(gains)
    check_model(model)
    V = float(check_nonzero("speed", speed))
    kappa = float(check_finite("curvature", curvature))
    cc = characteristic_coefficients(vehicle, V, kappa, float(gains.ratio), model)
    k1, k2 = float(gains.k1), float(gains.k2)
    n1 = float(cc.alpha1 * k1 + cc.beta1 * k2)
    n0 = float(cc.alpha0 * k1 + cc.beta0 * k2)
    num = [n1, n0] if n1 != 0.0 else [n0]
    den = [1.0, float(cc.gamma1), float(cc.gamma0)]
    return ct.tf(
        num,
        den,
        inputs=["delta_f"],
        outputs=["k_x"],
        name="gain_loop",
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
    vehicle: Vehicle,
    speed: float,
    curvature: float,
    gains: SteeringGains,
    scale=None,
    model: str = "exact",
) -> ct.PoleZeroData:
    """Root locus of the gain scaling ``g`` (``k1, k2 -> g*k1, g*k2``).

    Thin wrapper around :func:`control.root_locus_map` of :func:`gain_loop`.

    Parameters
    ----------
    vehicle, speed, curvature, gains, model
        See :func:`gain_loop`.
    scale : array_like, optional
        Values of ``g``; default: python-control's automatic choice.

    Returns
    -------
    control.PoleZeroData
        ``.loci`` of shape ``(len(scale), 2)``, ``.gains`` the scales.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.SteeringGains(0.05, 0.6, ratio=-1.0)
    >>> fws.gain_locus(veh, 5.0, 0.0, g, scale=[0.0, 1.0, 2.0]).loci.shape
    (3, 2)
    """
    loop = gain_loop(vehicle, speed, curvature, gains, model)
    if scale is not None:
        scale = np.atleast_1d(check_finite("scale", scale))
    return ct.root_locus_map(loop, gains=scale)


def quadratic_roots(p1, p0) -> np.ndarray:
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


def parameter_locus(
    vehicle: Vehicle,
    name: str,
    values,
    speed: float,
    curvature: float,
    gains: SteeringGains,
    model: str = "exact",
    redesign_pole: float | None = None,
    design_model: str | None = None,
) -> ct.PoleZeroData:
    r"""Closed-loop poles while one parameter of the loop varies.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    name : {"ratio", "speed", "curvature", "k1", "k2"}
        The parameter that takes `values`; the others come from `speed`,
        `curvature` and `gains`.
    values : array_like
        1-D values of the parameter (SI units). A monotonic sweep gives
        continuous branches.
    speed, curvature : float
        Operating point [m/s], [1/m] (the one named by `name` is replaced).
    gains : SteeringGains
        ``k1, k2`` and ``ratio``. When `name` is ``"ratio"`` the gains
        ``k1, k2`` stay fixed while ``a`` varies (so ``k3 = a*k1`` and
        ``k4 = a*k2`` change with it); to follow a design instead, give
        `redesign_pole`.
    model : {"exact", "paper"}, optional
        Linearisation in which the poles are computed.
    redesign_pole : float, optional
        If given, the gains are recomputed at every value by
        :func:`double_root_gains` with this double root (not for ``"k1"``,
        ``"k2"``). With ``design_model != model`` this shows where a design
        made in one model puts the poles of the other, e.g. the paper's
        gains in the exact linearisation.
    design_model : {"exact", "paper"}, optional
        Model used for the redesign; default `model`.

    Returns
    -------
    control.PoleZeroData
        ``.loci`` of shape ``(len(values), 2)``; ``.gains`` holds `values`;
        ``.poles`` the poles at the first value (plotted as ``x``);
        ``.zeros`` is empty. ``.plot()`` draws the locus.

    Raises
    ------
    ValueError
        For an unknown `name` or `model`, non-finite or empty `values`, a
        zero speed among them, or `redesign_pole` with ``"k1"``/``"k2"``.
    UncontrollableError
        If a redesign hits ``a = 1`` on a straight path.

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(veh, 5.0, 0.0, ratio=-1.0, pole=-1.0)
    >>> pz = fws.parameter_locus(veh, "speed", [2.5, 5.0, 10.0], 5.0, 0.0, g)
    >>> pz.loci.shape
    (3, 2)
    >>> np.allclose(pz.loci[1], [-1.0, -1.0], atol=1e-6)
    True
    """
    check_model(model)
    design_model = model if design_model is None else check_model(design_model)
    if name not in LOCUS_PARAMETERS:
        raise ValueError(f"name must be one of {LOCUS_PARAMETERS}, got {name!r}")
    gains = _check_gains(gains)
    vals = np.atleast_1d(check_finite("values", values)).astype(float)
    if vals.ndim != 1 or vals.size == 0:
        raise ValueError(
            f"values must be a non-empty 1-D array, got shape {vals.shape}"
        )
    V = float(check_nonzero("speed", speed))
    kappa = float(check_finite("curvature", curvature))
    a = float(gains.ratio)
    k1, k2 = float(gains.k1), float(gains.k2)
    par = {"speed": V, "curvature": kappa, "ratio": a, "k1": k1, "k2": k2}
    par[name] = vals
    if name == "speed":
        check_nonzero("values (speed)", vals)
    if redesign_pole is not None:
        if name in ("k1", "k2"):
            raise ValueError(
                f"redesign_pole cannot be used with name={name!r}: the design "
                "fixes both k1 and k2"
            )
        g = double_root_gains(
            vehicle,
            par["speed"],
            par["curvature"],
            par["ratio"],
            redesign_pole,
            design_model,
        )
        par["k1"], par["k2"] = g.k1, g.k2
    cc = characteristic_coefficients(
        vehicle, par["speed"], par["curvature"], par["ratio"], model
    )
    p1 = cc.p1(par["k1"], par["k2"])
    p0 = cc.p0(par["k1"], par["k2"])
    p1, p0 = np.broadcast_arrays(p1, p0, vals)[:2]
    loci = quadratic_roots(p1, p0)
    label = f"{name} {vals[0]:g} to {vals[-1]:g}"
    return ct.PoleZeroData(
        loci[0].copy(),
        np.array([], dtype=complex),
        gains=vals,
        loci=loci,
        dt=0,
        sysname=label,
        sort_loci=False,
    )
