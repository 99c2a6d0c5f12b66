r"""Steady-state turning radius of the kinematic 4WS vehicle.

With constant steering angles the rigid body rotates about a fixed
instantaneous centre O, the intersection of the wheel normals at F and R (no
tyre slip). In the vehicle frame (R at the origin, x forward, F at
``(f, 0)``) the normal at R is ``t*(-sin(dr), cos(dr))`` and the normal at F
is ``(f, 0) + u*(-sin(df), cos(df))``; they meet at

.. math::
    t = \frac{f\cos\delta_f}{\sin(\delta_f-\delta_r)},\qquad
    O = t\,(-\sin\delta_r,\ \cos\delta_r),

which agrees with the yaw rate of eq. (10): :math:`|\dot\psi| = V/|t|`, the
speed of R divided by its distance to O. Hence

.. math::
    R_R = \frac{f\cos\delta_f}{|\sin(\delta_f-\delta_r)|},\qquad
    R_G = |O - (d, 0)| = \sqrt{t^2 + 2 d\,t\sin\delta_r + d^2}.

With ``delta_r = a*delta_f`` at the front steering limit
:math:`\delta_{f,\max}`, front-wheel steering (``a = 0``) gives
:math:`R_R = f/\tan\delta_{f,\max}`; ``a = -1`` gives
:math:`f/(2\sin\delta_{f,\max})`, smaller by the factor
:math:`2\cos\delta_{f,\max}` (for limits below 60 degrees). ``R_R`` is
smallest where :math:`(1-a)\delta_{f,\max} = \pi/2`, i.e. at
:math:`a = 1 - \pi/(2\delta_{f,\max})` (-2 for a 30-degree limit, -1.25 for
40 degrees); beyond that more counter-steer widens the turn again. Positive
``a`` widens it, and ``a -> 1`` turns it into a straight crab walk.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import control as ct
import numpy as np

from . import equations
from .hints import RatioLike, RealArrayLike
from .kinematic_models import check_steering
from .layout import grid_margins
from .reprs import summary_repr
from .validation import check_finite, check_scalar, check_type
from .vehicle import Vehicle

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "TurningGeometry",
    "steady_turn",
    "turning_radius",
    "plot_turning_radius",
]


@summary_repr
@dataclass(frozen=True, eq=False)
class TurningGeometry:
    r"""Steady turn at constant steering angles (fields broadcast).

    Attributes
    ----------
    delta_f, delta_r : ndarray
        Steering angles [rad].
    curvature : ndarray
        Signed curvature of R's path :math:`\dot\psi/V =
        \sin(\delta_f-\delta_r)/(f\cos\delta_f)` [1/m]; positive turns left.
    rear_axle : ndarray
        Turning radius of the rear-axle centre R [m] (``inf`` when straight).
    cg : ndarray
        Turning radius of the centre of gravity G [m] (``inf`` when
        straight).
    centre : ndarray
        Instantaneous centre O in the vehicle frame (R at the origin, x
        forward), shape ``(..., 2)`` [m]; ``inf`` when straight.

    Examples
    --------
    Counter-steering with ``a = -1`` puts the centre abeam of G
    (``rear_to_cg = 1.35`` m):

    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> t = fws.steady_turn(veh, np.radians(30), np.radians(-30))
    >>> round(float(t.curvature), 6), t.centre.round(4)
    (0.37037, array([1.35  , 2.3383]))
    """

    delta_f: np.ndarray
    delta_r: np.ndarray
    curvature: np.ndarray
    rear_axle: np.ndarray
    cg: np.ndarray
    centre: np.ndarray


def steady_turn(
    vehicle: Vehicle, delta_f: RealArrayLike, delta_r: RealArrayLike
) -> TurningGeometry:
    r"""Turning radii of R and G at constant steering angles.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry (``wheelbase`` :math:`f`, ``rear_to_cg`` :math:`d`).
    delta_f, delta_r : float or array_like
        Front and rear steering angles [rad], ``|delta_f| < pi/2``;
        broadcast.

    Returns
    -------
    TurningGeometry

    Raises
    ------
    SingularStateError
        If ``|delta_f| >= pi/2``.
    ValueError
        If ``vehicle.rear_to_cg`` is None (needed for the radius of G).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> t = fws.steady_turn(veh, np.radians(30), 0.0)
    >>> round(float(t.rear_axle), 4)      # f / tan(30 deg)
    4.6765
    >>> t = fws.steady_turn(veh, np.radians(30), np.radians(-30))
    >>> round(float(t.rear_axle), 4), round(float(t.cg), 4)  # f/(2 sin), f/(2 tan)
    (2.7, 2.3383)
    """
    check_type("vehicle", vehicle, Vehicle)
    df = np.asarray(check_finite("delta_f", delta_f), dtype=float)
    dr = np.asarray(check_finite("delta_r", delta_r), dtype=float)
    check_steering(df)
    df, dr = np.broadcast_arrays(df, dr)
    f = vehicle.wheelbase
    d = vehicle.cg_distance(needed_by="steady_turn (the radius of G)")
    # the path curvature of R: the yaw rate of eq. (10) per unit speed
    kappa = equations.yaw_rate(1.0, f, df, dr)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(kappa != 0.0, 1.0 / kappa, np.inf)
        rear = np.abs(t)
        # sqrt(t^2 + 2 d t sin(dr) + d^2) written with kappa = 1/t so that a
        # straight run (kappa = 0) gives inf instead of inf - inf.
        cg = np.where(
            kappa != 0.0,
            np.sqrt(1.0 + 2.0 * d * kappa * np.sin(dr) + (d * kappa) ** 2)
            / np.abs(kappa),
            np.inf,
        )
        centre = np.stack([-t * np.sin(dr), t * np.cos(dr)], axis=-1)
    centre = np.where(np.isfinite(centre), centre, np.inf)
    return TurningGeometry(df, dr, np.asarray(kappa), rear, cg, centre)


def turning_radius(
    vehicle: Vehicle,
    *,
    ratio: RatioLike,
    max_steer_front: RealArrayLike | None = None,
    max_steer_rear: RealArrayLike | None = None,
) -> TurningGeometry:
    r"""Smallest steady turning radius with ``delta_r = ratio*delta_f``.

    The front wheels are at their limit, :math:`\delta_f = \delta_{f,\max}`;
    the rear angle is :math:`a\,\delta_{f,\max}`, clipped to the rear limit
    when one is given. Because ``R_R`` is not monotonic in ``|delta_f|`` for
    every ``a`` (see the module notes), this is the radius *at the limit*,
    which is the tightest one for ``(1-a)*delta_f_max <= pi/2``.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry; its ``max_steer_front`` / ``max_steer_rear`` are used when
        the arguments are None.
    ratio : float or array_like
        Rear-to-front steering ratio :math:`a`.
    max_steer_front : float or array_like, optional
        Front steering limit [rad] in (0, pi/2). Broadcasts with `ratio`.
    max_steer_rear : float, optional
        Rear steering limit [rad] in (0, pi/2); None: no limit.

    Returns
    -------
    TurningGeometry
        ``rear_axle`` and ``cg`` radii [m], broadcast over `ratio` and
        `max_steer_front`.

    Raises
    ------
    ValueError
        If no front limit is given (neither argument nor vehicle) or a limit
        is outside (0, pi/2). Also if ``vehicle.rear_to_cg`` is None
        (needed for the radius of G).

    Examples
    --------
    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> r = fws.turning_radius(veh, ratio=[0.0, -0.5, -1.0],
    ...                        max_steer_front=np.radians(30))
    >>> r.rear_axle.round(3)
    array([4.677, 3.307, 2.7  ])
    """
    check_type("vehicle", vehicle, Vehicle)
    a = np.asarray(check_finite("ratio", ratio), dtype=float)
    lim_f = vehicle.max_steer_front if max_steer_front is None else max_steer_front
    if lim_f is None:
        raise ValueError(
            "max_steer_front must be given (argument or Vehicle.max_steer_front), "
            "in (0, pi/2) rad"
        )
    lim_f = np.asarray(check_finite("max_steer_front", lim_f), dtype=float)
    if np.any((lim_f <= 0) | (lim_f >= np.pi / 2)):
        raise ValueError(
            f"max_steer_front must be in (0, pi/2) rad, got {max_steer_front!r}"
        )
    lim_r = vehicle.max_steer_rear if max_steer_rear is None else max_steer_rear
    try:
        shape = np.broadcast_shapes(a.shape, lim_f.shape)
    except ValueError:
        raise ValueError(
            "ratio and max_steer_front must broadcast, got shapes "
            f"{a.shape} and {lim_f.shape}"
        ) from None
    df = np.broadcast_to(lim_f, shape)
    dr = a * df
    if lim_r is not None:
        lim_r = check_scalar("max_steer_rear", lim_r)
        if not 0 < lim_r < np.pi / 2:
            raise ValueError(
                f"max_steer_rear must be in (0, pi/2) rad, got {max_steer_rear!r}"
            )
        dr = np.clip(dr, -lim_r, lim_r)
    return steady_turn(vehicle, df, dr)


def _curve(name: str, value) -> np.ndarray:
    """A non-empty 1-D array of finite numbers (a scalar: one element)."""
    v = np.atleast_1d(np.asarray(check_finite(name, value), dtype=float))
    if v.ndim != 1 or v.size == 0:
        raise ValueError(
            f"{name} must be a non-empty 1-D array, got shape {np.shape(value)}"
        )
    return v


def plot_turning_radius(
    vehicle: Vehicle,
    *,
    ratios: RealArrayLike | None = None,
    limits: RealArrayLike | None = None,
    ax: Axes | None = None,
    max_steer_rear: RealArrayLike | None = None,
    ylim: float = 12.0,
) -> ct.ControlPlot:
    r"""Turning radius of R (solid) and G (dashed) against the ratio ``a``.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry.
    ratios : array_like, optional
        Values of ``a``; default 381 points on [-3, 0.8], which holds the
        minimum of every default limit. A minimum at an end of `ratios` is
        annotated "min beyond range" instead of marked.
    limits : sequence of float, optional
        Front steering limits [rad]; default 20, 30 and 40 degrees.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default a new figure.
    max_steer_rear : float, optional
        Rear steering limit [rad]; see :func:`turning_radius`.
    ylim : float, optional
        Upper y limit [m]; radii grow without bound as ``a -> 1``.

    Returns
    -------
    control.ControlPlot
        ``.axes[0, 0]`` the axes, ``.lines[0, 0]`` the curves.

    Examples
    --------
    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt, fws_control as fws
    >>> cplt = fws.plot_turning_radius(fws.Vehicle(2.7, 1.35))
    >>> cplt.axes[0, 0].get_xlabel()
    'ratio $a$ [-]'
    >>> plt.close(cplt.figure)
    """
    import matplotlib.pyplot as plt

    # checked here, before any figure is made, with this function's names
    check_type("vehicle", vehicle, Vehicle)
    a = np.linspace(-3.0, 0.8, 381) if ratios is None else _curve("ratios", ratios)
    if limits is None:
        lims = np.radians([20.0, 30.0, 40.0])
    else:
        lims = _curve("limits", limits)
        if np.any((lims <= 0.0) | (lims >= np.pi / 2)):
            raise ValueError(f"limits must be in (0, pi/2) rad, got {limits!r}")
    if max_steer_rear is not None:
        max_steer_rear = check_scalar("max_steer_rear", max_steer_rear)
    ylim = check_scalar("ylim", ylim)
    if ylim <= 0.0:
        raise ValueError(f"ylim must be finite and > 0 m, got {ylim!r}")
    if ax is None:
        size = (7, 4.8)
        _, ax = plt.subplots(
            figsize=size, gridspec_kw=grid_margins(size, left=0.6, top=0.45)
        )
    for i, lim in enumerate(np.atleast_1d(lims)):
        geo = turning_radius(
            vehicle, ratio=a, max_steer_front=lim, max_steer_rear=max_steer_rear
        )
        color = f"C{i}"
        deg = np.degrees(lim)
        ax.plot(
            a,
            geo.rear_axle,
            "-",
            color=color,
            label=rf"R, $\delta_{{f,\max}}$ = {deg:.0f}°",
        )
        ax.plot(
            a, geo.cg, "--", color=color, label=rf"G, $\delta_{{f,\max}}$ = {deg:.0f}°"
        )
        j = int(np.argmin(geo.rear_axle))
        if 0 < j < a.size - 1:
            ax.plot(a[j], geo.rear_axle[j], "v", color=color, ms=7)
        else:
            # The minimum lies beyond the plotted ratios: a marker on the
            # edge would pose as an interior minimum.
            ax.annotate(
                "min beyond range",
                (a[j], geo.rear_axle[j]),
                xytext=(6 if j == 0 else -6, 8),
                textcoords="offset points",
                ha="left" if j == 0 else "right",
                fontsize=7,
                color=color,
            )
    ax.axvline(0.0, color="0.6", lw=0.8)
    ax.plot([], [], "v", color="0.4", label="minimum of R")
    ax.set_ylim(0.0, ylim)
    ax.set_xlabel("ratio $a$ [-]")
    ax.set_ylabel("steady turning radius [m]")
    ax.set_title(
        f"Turning radius at the front steering limit (f = {vehicle.wheelbase:g} m, "
        f"d = {vehicle.rear_to_cg:g} m)",
        fontsize=10,
    )
    ax.grid(alpha=0.3)
    leg = ax.legend(fontsize=8, ncol=2, loc="upper left")
    lines = np.empty((1, 1), dtype=object)
    lines[0, 0] = list(ax.get_lines())
    return ct.ControlPlot(lines, np.array([[ax]]), ax.figure, legend=leg)
