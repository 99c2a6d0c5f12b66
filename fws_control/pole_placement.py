r"""Closed-form double-root pole placement, paper section 4.2.

For a second-order plant the closed-loop polynomial
:math:`s^2 + p_1 s + p_0` is affine in ``(k1, k2)``
(:func:`~fws_control.affine_characteristic_polynomial`), so matching
:math:`(s-\lambda_0)^2` — eqs. (39)-(40) — is a 2 x 2 *linear* system,
solved here by Cramer's rule. For the kinematic plant its determinant is

.. math:: \Delta = -\frac{V^3}{f^2}\left(a^2 f^2\kappa^2 + (c-a)^2\right),

which equals the determinant of the controllability matrix of
:math:`(\mathbf A, \mathbf B[1, a]^T)`. It vanishes only for ``a = c`` and
``a*kappa = 0``, i.e. ``a = 1`` on a straight path in both models; nothing is
special about ``a = 0`` (the paper's eqs. (43)-(46) are singular there only
because of how they are written).

A plant of higher order has ``n`` poles but the structured controller only
two gains, ``k1`` on ``e`` and ``k2`` on ``theta``: a double root does not
determine them and the other poles go where they must. Choose the gains from
:func:`stability_chart` (and :func:`parameter_locus`) instead; a full state
feedback from :func:`control.place` on ``(A, B[:, delta_f] + a B[:,
delta_r])`` is a different controller (it feeds back every state).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from .exceptions import UncontrollableError
from .gains import SteeringGains
from .hints import RatioLike, RealArrayLike
from .linear import affine_characteristic_polynomial
from .plant import LateralPlant, as_plant, loop_matrices, resolve_ratio
from .validation import check_finite

__all__ = ["double_root_gains"]


#: Below this distance from the uncontrollable design (dimensionless
#: a^2 f^2 kappa^2 + (c - a)^2 for the kinematic plant, the determinant
#: relative to |n1| |n2| otherwise) the gains, which grow like its inverse,
#: exceed ~1e12 and are refused.
_SINGULAR_DISTANCE = 1e-12

#: Largest accepted *predicted* relative error of the placed double root,
#: ``sqrt(eps * condition)`` (see :func:`_condition`). A double
#: root is defective: a relative perturbation ``delta`` of the terms of the
#: closed loop moves it by about ``sqrt(delta * condition) * |pole|``, not
#: ``delta * condition``. At round-off (``delta = eps = 2.2e-16``) a design
#: passes if that error is <= 1e-5, i.e. ``condition <= 1e-10 / eps ~ 4.5e5``.
#: Over 3000 random designs (speed 0.01-100 m/s both signs, curvature 0 or
#: 1e-4-1 1/m, ratio in [-3, 3] and near 1, pole -1e-6 to -100) the
#: eigenvalues of :func:`closed_loop`'s matrix were at most 1.2 times this
#: prediction off, so every returned design has its closed-loop poles within
#: ``POLE_RTOL = 1e-4`` (relative) of the requested double root, with a
#: margin of 10 for the constants of the estimate.
_PREDICTED_RTOL = 1e-5
_POLE_RTOL = 1e-4


def _achieved_error(lm, a, k1, k2, lam) -> np.ndarray:
    """max |eig(A - b k) - pole| / |pole| of the closed loop (inf on overflow)."""
    with np.errstate(all="ignore"):
        b = lm.input_vector(a)
        kc = np.asarray(k1)[..., None] * lm.c_e + np.asarray(k2)[..., None] * lm.c_theta
        A_cl = lm.A - b[..., :, None] * kc[..., None, :]
        finite = np.all(np.isfinite(A_cl), axis=(-2, -1))
        ev = np.linalg.eigvals(np.where(finite[..., None, None], A_cl, 0.0))
        lam = np.asarray(lam, dtype=float)
        err = np.max(np.abs(ev - lam[..., None]), axis=-1) / np.abs(lam)
    return np.where(finite & np.isfinite(err), err, np.inf)


def _condition(lm, a, k1, k2, lam) -> np.ndarray:
    r"""Relative condition number of the placed double root (2-state loop).

    With :math:`\hat{\mathbf A} = |\mathbf A| + (|\mathbf b_f| + |a||\mathbf
    b_r|)(|k_1||\mathbf c_e| + |k_2||\mathbf c_\theta|)` -- the magnitudes of
    every term that enters the closed-loop matrix, before they cancel -- a
    relative perturbation ``delta`` of each term changes the trace by at most
    ``delta * (A11 + A22)`` and the determinant by at most ``delta * (A11 A22
    + A12 A21)`` (hats implied). The double root :math:`(s-\lambda_0)^2`
    then moves by :math:`\sqrt{\delta\,C}\,|\lambda_0|` with

    .. math:: C = \frac{|\lambda_0|(\hat A_{11} + \hat A_{22})
              + \hat A_{11}\hat A_{22} + \hat A_{12}\hat A_{21}}{\lambda_0^2}.

    ``C`` is invariant under a diagonal scaling of the states (balancing).
    """
    with np.errstate(all="ignore"):
        bh = np.abs(lm.B_front) + np.abs(np.asarray(a))[..., None] * np.abs(lm.B_rear)
        ch = np.abs(np.asarray(k1))[..., None] * np.abs(lm.c_e) + np.abs(
            np.asarray(k2)
        )[..., None] * np.abs(lm.c_theta)
        Ah = np.abs(lm.A) + bh[..., :, None] * ch[..., None, :]
        lam = np.abs(np.asarray(lam, dtype=float))
        out = (
            lam * (Ah[..., 0, 0] + Ah[..., 1, 1])
            + Ah[..., 0, 0] * Ah[..., 1, 1]
            + Ah[..., 0, 1] * Ah[..., 1, 0]
        ) / lam**2
    return np.where(np.isfinite(out), out, np.inf)


def double_root_gains(
    plant: Any,
    *,
    ratio: RatioLike,
    pole: RealArrayLike,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
    uncontrollable: Literal["raise", "mask"] = "raise",
) -> SteeringGains:
    r"""Gains that put both closed-loop poles of a 2-state plant at :math:`\lambda_0`.

    Solves eqs. (39)-(40) (with ``(c-a)`` in place of ``(1-a)`` for the exact
    model) as a linear system in ``(k1, k2)``:

    .. math::
        -2\lambda_0 = \frac{V}{f}(f a k_1 + (c-a) k_2),\qquad
        \lambda_0^2 = \frac{V^2}{f}\left((c-a)k_1 + (1-a k_2)f\kappa^2\right).

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        A second-order plant (see :mod:`fws_control.plant`).
    ratio : float, array_like or callable
        Rear-to-front steering ratio :math:`a`, or a schedule
        ``ratio(vehicle, speed=...)`` evaluated at the plant's speed (e.g.
        :func:`~fws_control.zero_sideslip_ratio`).
    pole : float or array_like
        Double root :math:`\lambda_0` [1/s], finite and < 0.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.
    uncontrollable : {"raise", "mask"}, optional
        What a design that does not exist (the UncontrollableError cases
        below) does: ``"raise"`` (default) raises for the whole call;
        ``"mask"`` returns `k1` and `k2` as :class:`numpy.ma.MaskedArray`\ s
        of the broadcast shape, masked (NaN underneath) at those designs, so
        that a sweep over `ratio` keeps its other elements.

    Returns
    -------
    SteeringGains
        Broadcast over the array arguments (and the operating points of a
        :class:`LateralPlant`). With ``uncontrollable="mask"``,
        ``gains.k1.mask`` flags the designs that do not exist.

    Raises
    ------
    UncontrollableError
        If :math:`(\mathbf A, \mathbf B[1, a]^T)` is (nearly) uncontrollable,
        e.g. ``ratio = 1`` on a straight path: then ``delta_r = delta_f``,
        the yaw rate is identically zero and the characteristic polynomial is
        :math:`\lambda(\lambda + V k_1)`, so no double root
        :math:`\lambda_0 \ne 0` exists. Also when the double root cannot be
        placed to working precision: the terms of the closed loop cancel so
        that round-off alone would move the poles by more than ``1e-5 *
        |pole|`` (predicted as :math:`\sqrt{\epsilon C}` from the condition
        number :math:`C` of the double root, see the notes), e.g. ``ratio =
        1 - 2e-6`` on a straight path (gains ~1e11) or ``pole = -1e-12`` on a
        curve (where :math:`\lambda_0^2 \ll V^2\kappa^2` must be reached by
        cancelling the open loop's own coefficient). The message names
        `ratio`, `pole`, `curvature` and `speed` of the worst design.
    ValueError
        For a plant that does not have two states, a `pole` that is not
        finite and negative, or a non-finite `ratio`.

    Notes
    -----
    The decision is taken from the closed loop the gains give, not from the
    characteristic coefficients (which report the requested double root even
    when the large terms behind them cancel in round-off). A double root is
    defective: a relative perturbation :math:`\delta` of the terms of
    :math:`\mathbf A - \mathbf b\mathbf k` moves it by about
    :math:`\sqrt{\delta C}\,|\lambda_0|` (a square root, not
    :math:`\delta C`), where, with hats the magnitudes of all terms before
    they cancel, :math:`C = (|\lambda_0|(\hat A_{11} + \hat A_{22}) +
    \hat A_{11}\hat A_{22} + \hat A_{12}\hat A_{21})/\lambda_0^2`. Designs
    with :math:`\sqrt{\epsilon C} > 10^{-5}` are refused. Over 3000 random
    designs the eigenvalues of :func:`closed_loop`'s matrix were within 1.2
    times this prediction, so every returned design has its closed-loop
    poles within ``1e-4 * |pole|`` of the double root (tested with
    hypothesis over speed, curvature, ratio and pole).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    >>> round(g.k1, 6), round(g.k2, 6)
    (0.054, 0.6129)
    >>> fws.double_root_gains(plant, ratio=1.0, pole=-1.0)
    Traceback (most recent call last):
        ...
    fws_control.exceptions.UncontrollableError: ratio=1.0 with curvature=0.0 makes ...

    A sweep over the ratio that crosses ``a = 1`` on a straight path:

    >>> g = fws.double_root_gains(plant, ratio=[0.0, 1.0, 2.0], pole=-1.0,
    ...                           uncontrollable="mask")
    >>> g.k1.mask
    array([False,  True, False])
    >>> g.k1.round(4)
    masked_array(data=[0.108, --, -0.108],
                 mask=[False,  True, False],
           fill_value=1e+20)
    """
    if uncontrollable not in ("raise", "mask"):
        raise ValueError(
            f"uncontrollable must be 'raise' or 'mask', got {uncontrollable!r}"
        )
    mask = uncontrollable == "mask"
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    ratio = resolve_ratio(p, ratio)
    a = check_finite("ratio", ratio)
    lam = check_finite("pole", pole)
    if np.any(np.asarray(lam) >= 0):
        raise ValueError(f"pole must be finite and < 0, got {pole!r}")
    cp = affine_characteristic_polynomial(p, ratio=a)
    if cp.order != 2:
        raise ValueError(
            f"double_root_gains needs a 2-state plant, got one of order {cp.order}: "
            "two gains on e and theta cannot place a double root and fix the "
            "other poles. Choose (k1, k2) from stability_chart or parameter_locus; "
            "control.place on (A, B[:, delta_f] + a*B[:, delta_r]) gives a full "
            "state feedback, a different controller"
            + (
                "; for model='dynamic', design on the kinematic plant "
                "(replace(plant, model='kinematic')) and check the design here"
                if isinstance(p, LateralPlant) and p.model == "dynamic"
                else ""
            )
        )
    a1, b1, g1 = cp.n1[..., 1], cp.n2[..., 1], cp.open_loop[..., 1]
    a0, b0, g0 = cp.n1[..., 2], cp.n2[..., 2], cp.open_loop[..., 2]
    with np.errstate(all="ignore"):  # an overflow is refused below
        det = a1 * b0 - b1 * a0
    if isinstance(p, LateralPlant):
        # det = -(V^3/f^2) * distance, distance = a^2 f^2 kappa^2 + (c - a)^2:
        # dimensionless, zero exactly at the uncontrollable design.
        V = np.asarray(p.speed, dtype=float)
        # (V**3 underflows to 0 for speeds near 1e-300 m/s: a NaN distance,
        # whose design is refused below by the working-precision check)
        with np.errstate(all="ignore"):
            distance = -det * p.vehicle.wheelbase**2 / V**3
        kappa = p.curvature
    else:
        scale = np.hypot(a1, a0) * np.hypot(b1, b0)
        with np.errstate(divide="ignore", invalid="ignore"):
            distance = np.where(scale > 0, np.abs(det) / scale, 0.0)
        kappa = None
    singular = np.asarray(distance) <= _SINGULAR_DISTANCE
    if np.any(singular) and not mask:
        worst = float(np.min(distance))
        if worst == 0.0:
            why = (
                "makes (A, B[1, a]^T) uncontrollable"
                if kappa is None
                else "makes delta_r = delta_f: the yaw rate is identically zero, "
                "the heading is uncontrollable and D(lambda) = lambda*(lambda + "
                f"V*k1), so no double root pole={pole!r} != 0 exists"
            )
        else:
            why = (
                f"is nearly uncontrollable: relative distance {worst:.3g} <= "
                f"{_SINGULAR_DISTANCE:g}; the gains grow like its inverse and would "
                "be meaningless"
            )
            if kappa is not None:
                why += " (delta_r = delta_f on a straight path is uncontrollable)"
        where = f"ratio={ratio!r}" + (
            "" if kappa is None else f" with curvature={kappa!r}"
        )
        raise UncontrollableError(f"{where} {why}")
    with np.errstate(all="ignore"):  # overflow is caught by the condition below
        r1 = -2.0 * np.asarray(lam) - g1
        r0 = np.asarray(lam) ** 2 - g0
        k1 = (r1 * b0 - b1 * r0) / det
        k2 = (a1 * r0 - r1 * a0) / det
    k1, k2, a_b = np.broadcast_arrays(k1, k2, a)
    # Decide from the closed loop the gains give, not from the coefficients
    # (which report the requested double root even when the terms behind
    # them cancel in round-off): refuse a design whose double root is not
    # defined to working precision.
    lm = loop_matrices(p)
    cond = _condition(lm, a_b, k1, k2, lam)
    predicted = np.sqrt(np.finfo(float).eps * cond)
    # ... and check the achieved poles themselves (eigenvalues of the
    # closed-loop matrix), which also catches an overflow in the solve
    # (e.g. ratio = 1e300 makes det = inf and the gains 0).
    achieved = _achieved_error(lm, a_b, k1, k2, lam)
    bad = ~(predicted <= _PREDICTED_RTOL) | ~(achieved <= _POLE_RTOL)
    if mask:
        # the singular designs' gains are inf or NaN (det = 0), their
        # achieved error inf: `bad` holds them; `singular` is added in case
        # a division by a tiny det still lands near the pole
        bad = bad | np.broadcast_to(singular, np.shape(bad))
        k1, k2 = (
            np.ma.masked_array(np.where(bad, np.nan, k), mask=bad) for k in (k1, k2)
        )
        return SteeringGains(k1=k1, k2=k2, ratio=a_b)
    if np.any(bad):
        shape = np.shape(bad)
        i = np.unravel_index(int(np.argmax(bad)), shape)

        def at(v):
            return np.broadcast_to(np.asarray(v, dtype=float), shape)[i].item()

        where = f"ratio={at(a_b)!r}, pole={at(lam)!r}"
        hint = (
            "Choose a pole not far slower or faster than the plant (|pole| "
            "comparable to speed*curvature and speed/wheelbase)"
        )
        if isinstance(p, LateralPlant):
            where += f", curvature={at(p.curvature)!r}, speed={at(p.speed)!r}"
            if at(distance) < 1e-2:
                hint = (
                    f"The design is nearly uncontrollable (relative distance "
                    f"{at(distance):.3g} from delta_r = delta_f on a straight "
                    "path, ratio = 1): move the ratio away from it"
                )
        raise UncontrollableError(
            f"{where}: the double root cannot be placed to working precision: "
            f"the closed loop's terms (gains k1={at(k1):.3g}, k2={at(k2):.3g}) "
            f"cancel so that round-off alone moves the poles by about "
            f"{at(predicted):.2g}*|pole| (condition {at(cond):.3g}; accepted: "
            f"<= {_PREDICTED_RTOL:g}*|pole|); the poles of A - b*k miss it by "
            f"{at(achieved):.2g}*|pole| (accepted: <= {_POLE_RTOL:g}*|pole|). {hint}"
        )
    return SteeringGains(k1=k1, k2=k2, ratio=a_b)
