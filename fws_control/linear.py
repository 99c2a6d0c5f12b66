r"""Linearisation, the linear closed loop and its characteristic polynomial.

With the paper's structure the steering feedback is rank one,

.. math::
    \begin{bmatrix}\delta_f\\ \delta_r\end{bmatrix}
    = \begin{bmatrix}1\\ a\end{bmatrix}(-k_1 e - k_2\theta),

so for any plant :math:`(\mathbf A, \mathbf B, \mathbf C)` the
characteristic polynomial of the closed loop is *affine* in the gains
(matrix determinant lemma):

.. math::
    p(s) = \det(s\mathbf I - \mathbf A) + k_1 n_1(s) + k_2 n_2(s),\qquad
    n_i(s) = \mathbf c_i\,\operatorname{adj}(s\mathbf I - \mathbf A)\,\mathbf b,

with :math:`\mathbf b = \mathbf B_f + a\mathbf B_r` and
:math:`\mathbf c_1, \mathbf c_2` the rows measuring ``e`` and ``theta``
(:class:`AffinePolynomial`). This module holds the single numeric
implementation of it: closed form for the kinematic :class:`LateralPlant`
(eq. 34 with ``(c - a)`` for ``(1 - a)``); for a :class:`control.StateSpace`
of any order the Faddeev-LeVerrier recursion run in exact integer arithmetic
on the double-precision matrices (every double is an integer times a power
of two), each coefficient then rounded once to the nearest double. In
floating point that recursion loses the small coefficients of a plant whose
poles span several decades (its error grows like :math:`\|A\|^k`); exact,
it cannot. Every coefficient carries a bound on its error
(:meth:`AffinePolynomial.coefficient_bounds`), which the stability verdict
uses. Stability, the stability boundaries, the double-root design and the
root loci all start from it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .deprecation import warn_deprecated
from .gains import SteeringGains
from .hints import RatioLike, RealArrayLike
from .plant import LateralPlant, LoopMatrices, as_plant, loop_matrices, resolve_ratio
from .reprs import summary_repr
from .validation import check_finite, check_type

if TYPE_CHECKING:  # imported where a state space is built: ~1 s of start-up
    import control as ct
    from numpy.typing import ArrayLike

__all__ = [
    "linearize",
    "closed_loop",
    "AffinePolynomial",
    "affine_characteristic_polynomial",
    "characteristic_polynomial_coefficients",
    "check_gains",
    "horner",
]


def check_gains(gains: Any, *, scalar: bool = False) -> SteeringGains:
    """Return `gains` if it is a :class:`SteeringGains` (scalar if asked).

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.linear import check_gains
    >>> check_gains(fws.SteeringGains(0.1, 0.5, ratio=0.0), scalar=True).k1
    0.1
    """
    check_type("gains", gains, SteeringGains)
    if scalar and (np.ndim(gains.k1) or np.ndim(gains.k2) or np.ndim(gains.ratio)):
        raise ValueError(
            "gains must hold scalar k1, k2 and ratio here, got shapes "
            f"{np.shape(gains.k1)}, {np.shape(gains.k2)}, {np.shape(gains.ratio)}"
        )
    return gains


def linearize(
    plant: Any,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> ct.StateSpace:
    r"""Linearised lateral dynamics of a plant, as a named state space.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`); a state space is returned
        as it is.
    speed, curvature, model : optional
        With a :class:`Vehicle` only: speed :math:`V` [m/s] (nonzero),
        curvature :math:`\kappa_C` [1/m] (default 0) and ``"kinematic"``
        (default: Jacobian of eqs. 18-19) or ``"paper"`` (eq. 33).

    Returns
    -------
    control.StateSpace
        For the kinematic plant: states and outputs ``e, theta`` (deviations
        from the feedforward operating point), inputs ``delta_f, delta_r``.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> fws.linearize(veh, speed=5.0, curvature=0.1, model="paper").B.round(4)
    array([[ 0.    ,  5.    ],
           [ 1.8519, -1.8519]])
    >>> plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    >>> fws.linearize(plant).B.round(4)
    array([[ 0.    ,  5.    ],
           [ 1.9869, -1.8519]])
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    return p.linearize() if isinstance(p, LateralPlant) else p


def closed_loop(
    plant: Any,
    gains: SteeringGains,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> ct.StateSpace:
    r"""Linear closed loop with the structured feedback ``u = K_paper y + w``.

    .. math:: \dot x = (\mathbf A + \mathbf B_s\mathbf K_{paper}\mathbf C_s) x
              + \mathbf B_s w

    where :math:`\mathbf B_s` are the columns of ``delta_f, delta_r``,
    :math:`\mathbf C_s` the rows of ``e, theta`` and
    :math:`\mathbf K_{paper} = -` :attr:`SteeringGains.K`.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`).
    gains : SteeringGains
        Scalar gains.
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    control.StateSpace
        The plant's states; inputs ``delta_f_dist, delta_r_dist`` (steering
        disturbances added to the controller's output) followed by the
        plant's other inputs; outputs: the plant's outputs followed by
        ``delta_f, delta_r`` (the steering deviations ``K_paper y + w``).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=5.0, curvature=0.1)
    >>> g = fws.double_root_gains(plant, ratio=-1.0, pole=-1.0)
    >>> cl = fws.closed_loop(plant, g)
    >>> np.allclose(cl.poles(), [-1.0, -1.0], atol=1e-6)
    True
    >>> cl.input_labels, cl.output_labels
    (['delta_f_dist', 'delta_r_dist'], ['e', 'theta', 'delta_f', 'delta_r'])
    """
    g = check_gains(gains, scalar=True)
    sys = linearize(plant, speed=speed, curvature=curvature, model=model)
    lm = loop_matrices(sys)
    A, B, C, D = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C, sys.D))
    inputs = list(sys.input_labels)
    if lm.states == ("e", "theta") and inputs == ["u[0]", "u[1]"]:
        steer = [0, 1]  # unnamed 2-state plant, read as (delta_f, delta_r)
    else:
        steer = [inputs.index("delta_f"), inputs.index("delta_r")]
    others = [j for j in range(B.shape[1]) if j not in steer]
    K = -g.K  # paper's sign: u = K_paper [e, theta]
    Cs = np.stack([lm.c_e, lm.c_theta])
    # Feedthrough of the other inputs into the measured e, theta (the steering
    # inputs have none there: loop_matrices refuses that algebraic loop). It
    # reaches the steering through the controller too.
    outputs = list(sys.output_labels)
    Dso = np.zeros((2, len(others)))
    for row, name in enumerate(("e", "theta")):
        if name in outputs:
            Dso[row] = D[outputs.index(name), others]
    Bs, Ds = B[:, steer], D[:, steer]
    Bo, Do = B[:, others], D[:, others]
    A_cl = A + Bs @ K @ Cs
    B_cl = np.hstack([Bs, Bo + Bs @ K @ Dso])
    C_cl = np.vstack([C + Ds @ K @ Cs, K @ Cs])
    D_cl = np.vstack(
        [
            np.hstack([Ds, Do + Ds @ K @ Dso]),
            np.hstack([np.eye(2), K @ Dso]),
        ]
    )
    import control as ct

    return ct.ss(
        A_cl,
        B_cl,
        C_cl,
        D_cl,
        states=list(sys.state_labels),
        inputs=["delta_f_dist", "delta_r_dist", *(inputs[j] for j in others)],
        outputs=[*sys.output_labels, "delta_f", "delta_r"],
        name=f"closed_loop_{sys.name}",
    )


@summary_repr
@dataclass(frozen=True, eq=False)
class AffinePolynomial:
    r"""Closed-loop characteristic polynomial as an affine map of (k1, k2).

    .. math:: p(s) = d(s) + k_1 n_1(s) + k_2 n_2(s)

    with :math:`d(s) = \det(s\mathbf I - \mathbf A)` (monic, degree ``n``)
    and :math:`n_1, n_2` of degree below ``n``. Coefficient arrays have
    shape ``(..., n + 1)``, highest power first (``numpy.polyval`` order);
    the leading dimensions broadcast (operating points, ratios).

    Attributes
    ----------
    open_loop : ndarray
        Coefficients of :math:`d(s)`.
    n1, n2 : ndarray
        Coefficients of :math:`n_1(s)` and :math:`n_2(s)` (leading zero).
    open_loop_error, n1_error, n2_error : ndarray or None
        Bounds on the absolute errors of those coefficients against the
        exact polynomials of the plant's (double-precision) data; None: the
        coefficients are exact. :func:`affine_characteristic_polynomial` fills
        them: half a unit in the last place for a state space (exact, then
        rounded once), a few units for the closed form.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> cp = fws.affine_characteristic_polynomial(fws.LateralPlant(veh, speed=5.0),
    ...                                      ratio=0.0)
    >>> cp.order, cp.coefficients(0.2, 0.5).round(9)
    (2, array([1.        , 0.92592593, 1.85185185]))
    """

    open_loop: np.ndarray
    n1: np.ndarray
    n2: np.ndarray
    open_loop_error: np.ndarray | None = None
    n1_error: np.ndarray | None = None
    n2_error: np.ndarray | None = None

    @property
    def order(self) -> int:
        """Degree ``n`` of the polynomial (the number of states)."""
        return int(self.open_loop.shape[-1]) - 1

    def coefficients(self, k1: RealArrayLike, k2: RealArrayLike) -> np.ndarray:
        """Coefficients of :math:`p(s)` for gains that broadcast, ``(..., n+1)``.

        Parameters
        ----------
        k1 : float or array_like
            Lateral-error gain [rad/m], any finite value.
        k2 : float or array_like
            Heading-error gain [rad/rad], any finite value; broadcasts with
            `k1` and with the leading dimensions of the polynomial.

        Returns
        -------
        ndarray
            Coefficients of :math:`p(s)`, highest power first, shape
            ``(..., n + 1)``.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> cp = fws.affine_characteristic_polynomial(fws.LateralPlant(veh, speed=5.0),
        ...                                      ratio=0.0)
        >>> cp.coefficients([0.1, 0.2], 0.5).shape
        (2, 3)
        """
        k1 = np.asarray(k1, dtype=float)[..., np.newaxis]
        k2 = np.asarray(k2, dtype=float)[..., np.newaxis]
        return self.open_loop + k1 * self.n1 + k2 * self.n2

    def coefficient_bounds(
        self, k1: RealArrayLike, k2: RealArrayLike
    ) -> tuple[list[np.ndarray], list[np.ndarray]]:
        r"""Coefficients of :math:`p(s)` and bounds on their errors, by column.

        Returns the lists ``p`` and ``r`` (one array per power, highest
        first, broadcast over the gains) with
        :math:`|p_j - p^{exact}_j| \le r_j`, where :math:`p^{exact}` is the
        polynomial of the exact data (``open_loop + k1 n1 + k2 n2`` with the
        stored error bounds) and :math:`r_j` adds the rounding of the
        evaluation, :math:`4\epsilon(|d_j| + |k_1 n_{1,j}| + |k_2 n_{2,j}|)`
        (three roundings, with room).

        Parameters
        ----------
        k1 : float or array_like
            Lateral-error gain [rad/m], any finite value.
        k2 : float or array_like
            Heading-error gain [rad/rad], any finite value; broadcasts with
            `k1` and with the leading dimensions of the polynomial.

        Returns
        -------
        tuple of list of ndarray
            ``(p, r)``, each a list of ``n + 1`` arrays.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> cp = fws.affine_characteristic_polynomial(fws.LateralPlant(veh, speed=5.0),
        ...                                      ratio=0.0)
        >>> p, r = cp.coefficient_bounds(0.2, 0.5)
        >>> [float(v) for v in p], all(float(e) < 1e-14 for e in r)
        ([1.0, 0.9259259259259258, 1.851851851851852], True)
        """
        k1 = np.asarray(k1, dtype=float)
        k2 = np.asarray(k2, dtype=float)
        a1, a2 = np.abs(k1), np.abs(k2)
        eps = np.finfo(float).eps
        p, r = [], []
        for j in range(self.order + 1):
            d, n1, n2 = self.open_loop[..., j], self.n1[..., j], self.n2[..., j]
            t1, t2 = k1 * n1, k2 * n2
            # Each bound term has the shape of its own factors (a row of k1,
            # a column of k2 on a chart grid): the sums reach the full grid
            # shape only once, in the last addition.
            u = 4 * eps * np.abs(d)
            v = 4 * eps * np.abs(t1)
            w = 4 * eps * np.abs(t2)
            if self.open_loop_error is not None:
                u = u + self.open_loop_error[..., j]
            if self.n1_error is not None:
                v = v + a1 * self.n1_error[..., j]
            if self.n2_error is not None:
                w = w + a2 * self.n2_error[..., j]
            p.append((d + t1) + t2)
            r.append((u + v) + w)
        return p, r

    def evaluate(
        self, s: ArrayLike, k1: RealArrayLike = 0.0, k2: RealArrayLike = 0.0
    ) -> np.ndarray:
        """:math:`p(s)` at points `s` (broadcast with the gains), by Horner.

        Parameters
        ----------
        s : complex or array_like
            Points of the complex plane [1/s] (e.g. ``1j*omega`` with
            :math:`\\omega` in rad/s), any finite value.
        k1 : float or array_like, optional
            Lateral-error gain [rad/m], any finite value; default 0.
        k2 : float or array_like, optional
            Heading-error gain [rad/rad], any finite value; default 0 (with
            ``k1 = k2 = 0``, the open-loop :math:`d(s)`).

        Returns
        -------
        ndarray
            :math:`p(s)`, complex where `s` is; the shapes of `s` and of the
            gains broadcast.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> cp = fws.affine_characteristic_polynomial(fws.LateralPlant(veh, speed=5.0),
        ...                                      ratio=0.0)
        >>> v = complex(cp.evaluate(1j, 0.2, 0.5))
        >>> round(v.real, 9), round(v.imag, 9)
        (0.851851852, 0.925925926)
        """
        return horner(self.coefficients(k1, k2), s)

    def polynomials_at(self, s: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(d(s), n1(s), n2(s))`` at points `s` (broadcast).

        Parameters
        ----------
        s : complex or array_like
            Points of the complex plane [1/s], any finite value; broadcasts
            with the leading dimensions of the polynomial.

        Returns
        -------
        tuple of ndarray
            :math:`d(s)`, :math:`n_1(s)`, :math:`n_2(s)`, so that
            :math:`p(s) = d(s) + k_1 n_1(s) + k_2 n_2(s)`.

        Examples
        --------
        >>> import fws_control as fws
        >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
        >>> cp = fws.affine_characteristic_polynomial(fws.LateralPlant(veh, speed=5.0),
        ...                                      ratio=0.0)
        >>> [complex(v) for v in cp.polynomials_at(0.0)]
        [0j, (9.25925925925926+0j), 0j]
        """
        q, n1, n2 = (horner(c, s) for c in (self.open_loop, self.n1, self.n2))
        return q, n1, n2


def horner(coefficients: np.ndarray, s: ArrayLike) -> np.ndarray:
    """Evaluate polynomials (coefficients on the last axis) at `s`, broadcasting.

    Examples
    --------
    >>> from fws_control.linear import horner
    >>> complex(horner([1.0, 0.0, 1.0], 1j))
    0j
    """
    c = np.asarray(coefficients)
    s = np.asarray(s)
    out = np.zeros(
        np.broadcast_shapes(c.shape[:-1], s.shape), dtype=np.result_type(c, s)
    )
    for k in range(c.shape[-1]):
        out = out * s + c[..., k]
    return out


def _dyadic(x: np.ndarray) -> tuple[np.ndarray, int]:
    """Integers ``X`` (object array) and a shift ``t`` with ``x == X * 2**-t``.

    Every finite double is an integer times a power of two, so this is exact.
    """
    x = np.asarray(x, dtype=float)
    m, e = np.frexp(x)  # x = m 2^e, 0.5 <= |m| < 1: m 2^53 is an integer
    mant = (m * 2.0**53).astype(np.int64)
    e = e.astype(np.int64) - 53
    nz = mant != 0
    t = int(-e[nz].min()) if np.any(nz) else 0
    shift = np.where(nz, e + t, 0)
    out = mant.astype(object) << shift.astype(object)
    return out, t


def _rounded(value: int, shift: int) -> float:
    """``value * 2**-shift`` rounded once to the nearest double."""
    if value == 0:
        return 0.0
    try:
        # int true division and int -> float conversion round correctly
        return value / (1 << shift) if shift > 0 else float(value << -shift)
    except OverflowError:
        raise ValueError(
            "plant has a characteristic-polynomial coefficient beyond the double "
            f"range (about 2**{value.bit_length() - shift}); rescale its states "
            "or time unit"
        ) from None


def _exact_affine(
    A: np.ndarray, b_front: np.ndarray, b_rear: np.ndarray, c_e, c_theta
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """Exact ``d`` and the numerators of one plant, each rounded once.

    Faddeev-LeVerrier in integer arithmetic on the scaled matrix
    ``2**t A``: its characteristic polynomial has integer coefficients, so
    the division by ``k`` in the recursion is exact, and so are the
    adjugate terms ``M_k`` and the numerators ``c M_k b``. Returns ``d``
    and ``(e_f, e_r, theta_f, theta_r)`` (``n`` + 1 coefficients each).
    """
    n = A.shape[-1]
    Ai, t = _dyadic(A)
    eye = np.eye(n, dtype=np.int64).astype(object)
    Mk = np.zeros((n, n), dtype=object)
    d = [1]
    Ms = []
    for k in range(1, n + 1):
        Mk = Ai.dot(Mk) + d[-1] * eye
        Ms.append(Mk)
        q, r = divmod(-int(np.trace(Ai.dot(Mk))), k)
        if r:  # pragma: no cover - an integer matrix has an integer polynomial
            raise ArithmeticError("Faddeev-LeVerrier lost exactness")
        d.append(q)
    d_out = np.array([_rounded(dk, k * t) for k, dk in enumerate(d)])
    nums = []
    for c in (c_e, c_theta):
        ci, tc = _dyadic(c)
        for b in (b_front, b_rear):
            bi, tb = _dyadic(b)
            vals = [0.0] + [
                _rounded(int(ci.dot(Mk).dot(bi)), k * t + tc + tb)
                for k, Mk in enumerate(Ms)
            ]
            nums.append(np.array(vals))
    return d_out, tuple(nums)  # (c_e, c_theta) x (front, rear)


#: One rounding unit of double precision (half the machine epsilon).
_UNIT = 0.5 * np.finfo(float).eps


def _lateral_coefficients(plant: LateralPlant, ratio) -> AffinePolynomial:
    V = np.asarray(plant.speed, dtype=float)
    kappa = np.asarray(plant.curvature, dtype=float)
    c = np.asarray(plant.input_gain_factor, dtype=float)
    a = np.asarray(ratio, dtype=float)
    f = plant.vehicle.wheelbase
    V, kappa, c, a = np.broadcast_arrays(V, kappa, c, a)
    zero = np.zeros_like(V)
    one = np.ones_like(V)
    # eq. (34) with (c - a) for (1 - a): p1 = V a k1 + V (c - a)/f k2,
    # p0 = V^2/f ((c - a) k1 + (1 - a k2) f kappa^2)
    v2k2 = V**2 * kappa**2
    # Error bounds against the exact formulas of the double-precision inputs:
    # at most four roundings per term (c = 1 + f^2 kappa^2 two, c - a one, the
    # products the rest), taken on the magnitudes before (c - a) cancels. On a
    # straight path c = 1 exactly, so c - a is one correctly rounded
    # subtraction of exact operands: its error is relative to |c - a| itself,
    # and a structural zero (a = 1, the heading uncontrollable) stays an
    # exact zero that decides "not stable" instead of "undecided".
    ca = np.where(kappa == 0.0, np.abs(c - a), np.abs(c) + np.abs(a)) / abs(f)
    return AffinePolynomial(
        open_loop=np.stack([one, zero, v2k2], -1),
        n1=np.stack([zero, V * a, V**2 * (c - a) / f], -1),
        n2=np.stack([zero, V * (c - a) / f, -(V**2) * a * kappa**2 + 0.0], -1),
        open_loop_error=np.stack([zero, zero, 3 * _UNIT * v2k2], -1),
        n1_error=np.stack([zero, _UNIT * np.abs(V * a), 8 * _UNIT * V**2 * ca], -1),
        n2_error=np.stack(
            [zero, 8 * _UNIT * np.abs(V) * ca, 4 * _UNIT * np.abs(a) * v2k2], -1
        ),
    )


def _statespace_coefficients(lm: LoopMatrices, ratio) -> AffinePolynomial:
    A = np.asarray(lm.A, dtype=float)
    vecs = [
        np.broadcast_to(np.asarray(v, dtype=float), A.shape[:-1])
        for v in (lm.B_front, lm.B_rear, lm.c_e, lm.c_theta)
    ]
    lead = A.shape[:-2]
    n = A.shape[-1]
    d = np.empty(lead + (n + 1,))
    parts = np.empty((4,) + lead + (n + 1,))
    for idx in np.ndindex(lead):
        d[idx], polys = _exact_affine(A[idx], *(v[idx] for v in vecs))
        for j, poly in enumerate(polys):
            parts[(j,) + idx] = poly
    ef, er, tf_, tr = parts
    # n_i(s) = c_i adj(sI - A) (B_f + a B_r): four exact polynomials, then a
    # broadcast over the ratio (two roundings, bounded below).
    a = np.asarray(ratio, dtype=float)[..., np.newaxis]
    n1 = ef + a * er
    n2 = tf_ + a * tr
    open_loop = np.broadcast_to(d, np.broadcast_shapes(d.shape, n1.shape))
    n1 = np.broadcast_to(n1, open_loop.shape)
    n2 = np.broadcast_to(n2, open_loop.shape)
    # each of ef, er, tf, tr is the exact value rounded once; a*er and the sum
    # add a rounding each
    err1 = np.broadcast_to(3 * _UNIT * (np.abs(ef) + np.abs(a * er)), n1.shape)
    err2 = np.broadcast_to(3 * _UNIT * (np.abs(tf_) + np.abs(a * tr)), n2.shape)
    return AffinePolynomial(
        open_loop=open_loop,
        n1=n1,
        n2=n2,
        open_loop_error=_UNIT * np.abs(open_loop),
        n1_error=err1,
        n2_error=err2,
    )


def affine_characteristic_polynomial(
    plant: Any,
    *,
    ratio: RatioLike,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> AffinePolynomial:
    r"""The closed-loop characteristic polynomial as an affine map of the gains.

    For the kinematic :class:`LateralPlant` (eq. 34, with ``(c - a)`` in
    place of ``(1 - a)`` for the exact model):

    .. math::
        p(s) = s^2 + \frac{V}{f}\left(f a k_1 + (c-a)k_2\right)s
             + \frac{V^2}{f}\left((c-a)k_1 + (1-a k_2) f\kappa^2\right);

    for a :class:`control.StateSpace` of order ``n``:
    :math:`p(s) = \det(s\mathbf I-\mathbf A) + k_1 n_1(s) + k_2 n_2(s)`.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`).
    ratio : float, array_like or callable
        Rear-to-front steering ratio :math:`a`; broadcasts with the
        operating points of a :class:`LateralPlant`. A callable is a
        schedule ``ratio(vehicle, speed=...)`` evaluated at the plant's speed
        (:func:`~fws_control.plant.resolve_ratio`).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    AffinePolynomial

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> cp = fws.affine_characteristic_polynomial(veh, speed=5.0, ratio=0.0)
    >>> cp.n1.round(6), cp.n2.round(6)
    (array([0.      , 0.      , 9.259259]), array([0.      , 1.851852, 0.      ]))
    """
    p = as_plant(plant, speed=speed, curvature=curvature, model=model)
    ratio = check_finite("ratio", resolve_ratio(p, ratio))
    if isinstance(p, LateralPlant) and p.model != "dynamic" and p.steering_lag is None:
        return _lateral_coefficients(p, ratio)
    return _statespace_coefficients(loop_matrices(p), ratio)


def characteristic_polynomial_coefficients(
    plant: Any,
    gains: SteeringGains,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> np.ndarray:
    r"""Coefficients of the closed-loop characteristic polynomial.

    Parameters
    ----------
    plant : LateralPlant, control.StateSpace or Vehicle
        The plant (see :mod:`fws_control.plant`).
    gains : SteeringGains
        Gains; arrays broadcast (with the plant's operating points).
    speed, curvature, model : optional
        With a :class:`Vehicle` only, as in :func:`linearize`.

    Returns
    -------
    ndarray
        Shape ``(..., n + 1)``, monic, highest power first: a scalar design
        gives an array usable with :func:`numpy.roots`.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> plant = fws.LateralPlant(veh, speed=20.0, curvature=0.01)
    >>> g = fws.double_root_gains(plant, ratio=0.5, pole=-2.0)
    >>> fws.characteristic_polynomial_coefficients(plant, g).round(9)
    array([1., 4., 4.])
    """
    g = check_gains(gains)
    cp = affine_characteristic_polynomial(
        plant, ratio=g.ratio, speed=speed, curvature=curvature, model=model
    )
    return cp.coefficients(g.k1, g.k2)


def characteristic_coefficients(
    plant: Any,
    *,
    ratio: RatioLike,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> AffinePolynomial:
    """Deprecated name of :func:`affine_characteristic_polynomial`.

    It returns the polynomial as an affine map of the gains (an
    :class:`AffinePolynomial`), not coefficients; the name is accepted until
    fws_control 0.4 with a :class:`FutureWarning`.

    Examples
    --------
    >>> import warnings
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     cp = fws.characteristic_coefficients(veh, speed=5.0, ratio=0.0)
    >>> print(caught[0].message)
    characteristic_coefficients() is deprecated and is removed in fws_control 0.4; use affine_characteristic_polynomial()
    """  # noqa: E501
    warn_deprecated(
        "characteristic_coefficients()", "affine_characteristic_polynomial()"
    )
    return affine_characteristic_polynomial(
        plant, ratio=ratio, speed=speed, curvature=curvature, model=model
    )


def characteristic_polynomial(
    plant: Any,
    gains: SteeringGains,
    *,
    speed: Any = None,
    curvature: Any = None,
    model: Any = None,
) -> np.ndarray:
    """Deprecated name of :func:`characteristic_polynomial_coefficients`.

    It returns the coefficients of the polynomial (an array); the name is
    accepted until fws_control 0.4 with a :class:`FutureWarning`.

    Examples
    --------
    >>> import warnings
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     p = fws.characteristic_polynomial(fws.LateralPlant(veh, speed=5.0),
    ...                                       fws.SteeringGains(0.1, 0.5, 0.0))
    >>> print(caught[0].message)
    characteristic_polynomial() is deprecated and is removed in fws_control 0.4; use characteristic_polynomial_coefficients()
    """  # noqa: E501
    warn_deprecated(
        "characteristic_polynomial()", "characteristic_polynomial_coefficients()"
    )
    return characteristic_polynomial_coefficients(
        plant, gains, speed=speed, curvature=curvature, model=model
    )
