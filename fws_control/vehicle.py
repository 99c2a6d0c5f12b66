"""Vehicle geometry, steering limits and (optionally) mass and tyre data."""

from __future__ import annotations

import math
from dataclasses import KW_ONLY, dataclass

import numpy as np

from .reprs import value_repr
from .validation import check_angle_limit, check_optional_positive, check_rate_limit

__all__ = ["Vehicle"]


def _number(name: str, value: object) -> float:
    # bool is an int subclass; a True wheelbase is a bug, not 1 m; a complex
    # number would silently lose its imaginary part in float()
    if isinstance(value, (bool, np.bool_, complex, np.complexfloating)):
        raise ValueError(f"{name} must be a real number in metres, got {value!r}")
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a number in metres, got {value!r}") from exc


# Optional fields of the dynamic single-track model and their units (for the
# error messages).
_DYNAMIC_FIELDS = {
    "mass": "kg",
    "yaw_inertia": "kg m^2",
    "cornering_front": "N/rad",
    "cornering_rear": "N/rad",
    "friction": "(dimensionless)",
}


@value_repr
@dataclass(frozen=True)
class Vehicle:
    r"""Geometry of a kinematic single-track (bicycle) vehicle with 4WS.

    Parameters
    ----------
    wheelbase : float
        Distance between the front and rear axle centres, paper symbol
        :math:`f` [m]. Must be finite and > 0.
    rear_to_cg : float or None, optional
        Distance from the rear axle centre R to the centre of gravity G,
        paper symbol :math:`d` [m]. Must satisfy ``0 <= rear_to_cg <=
        wheelbase``. ``None`` (default) leaves G unknown: the path-frame
        model of R, the gains, the stability analysis and its charts do not
        depend on it; what is measured at G (the lateral acceleration, the
        turning radius of G, the simulation's signals at G, the dynamic
        model) raises a ValueError naming ``rear_to_cg``.
    max_steer_front, max_steer_rear : float or None, optional
        Steering-angle limits [rad], in (0, pi/2). ``None`` (default) means
        unlimited; saturation is applied only where a limit is set.
    max_steer_rate_front, max_steer_rate_rear : float or None, optional
        Steering-rate limits [rad/s], > 0. ``None`` (default) means
        unlimited.
    mass : float or None, optional
        Vehicle mass :math:`m` [kg], finite and > 0. Needed only by the
        dynamic single-track model (:mod:`fws_control.dynamics`).
    yaw_inertia : float or None, optional
        Yaw moment of inertia about the centre of gravity :math:`I_z`
        [kg m^2], finite and > 0.
    cornering_front, cornering_rear : float or None, optional
        Cornering stiffness of the front and the rear axle :math:`C_f, C_r`
        [N/rad per axle, both tyres together], finite and > 0: the slope of
        the lateral tyre force over the slip angle at zero slip.
    friction : float or None, optional
        Peak tyre-road friction coefficient :math:`\mu` [-], finite and > 0;
        used only by the saturating tyre model.

    Raises
    ------
    ValueError
        If a field is not finite or out of its range; the message names the
        field.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> veh.wheelbase, veh.rear_to_cg
    (2.7, 1.35)
    >>> fws.Vehicle(wheelbase=2.7, rear_to_cg=3.0)
    Traceback (most recent call last):
        ...
    ValueError: rear_to_cg must be in [0, wheelbase=2.7] m, got 3.0

    The gains need only the wheelbase:

    >>> g = fws.double_root_gains(fws.Vehicle(wheelbase=2.7), speed=5.0,
    ...                           ratio=0.5, pole=-1.0)
    >>> round(g.k1, 6) == round(fws.double_root_gains(veh, speed=5.0,
    ...                                               ratio=0.5, pole=-1.0).k1, 6)
    True
    """

    wheelbase: float
    rear_to_cg: float | None = None
    _: KW_ONLY  # the limits are options, named at the call
    max_steer_front: float | None = None
    max_steer_rear: float | None = None
    max_steer_rate_front: float | None = None
    max_steer_rate_rear: float | None = None
    mass: float | None = None
    yaw_inertia: float | None = None
    cornering_front: float | None = None
    cornering_rear: float | None = None
    friction: float | None = None

    def __post_init__(self) -> None:
        f = _number("wheelbase", self.wheelbase)
        if not (math.isfinite(f) and f > 0.0):
            raise ValueError(
                f"wheelbase must be finite and > 0 m, got {self.wheelbase!r}"
            )
        # Store plain floats so that equality and hashing behave for ints too.
        object.__setattr__(self, "wheelbase", f)
        if self.rear_to_cg is not None:
            d = _number("rear_to_cg", self.rear_to_cg)
            if not (math.isfinite(d) and 0.0 <= d <= f):
                raise ValueError(
                    f"rear_to_cg must be in [0, wheelbase={f}] m, "
                    f"got {self.rear_to_cg!r}"
                )
            object.__setattr__(self, "rear_to_cg", d)
        for name in ("max_steer_front", "max_steer_rear"):
            object.__setattr__(self, name, check_angle_limit(name, getattr(self, name)))
        for name in ("max_steer_rate_front", "max_steer_rate_rear"):
            object.__setattr__(self, name, check_rate_limit(name, getattr(self, name)))
        for name, unit in _DYNAMIC_FIELDS.items():
            value = check_optional_positive(name, getattr(self, name), unit)
            object.__setattr__(self, name, value)

    @property
    def front_to_cg(self) -> float:
        """Distance from the centre of gravity to the front axle [m].

        Raises
        ------
        ValueError
            If ``rear_to_cg`` is None.
        """
        return self.wheelbase - self.cg_distance(needed_by="front_to_cg")

    def cg_distance(self, *, needed_by: str) -> float:
        """``rear_to_cg`` [m], or a ValueError saying what needs it.

        Parameters
        ----------
        needed_by : str
            What needs the centre of gravity, for the error message (a
            function, a signal or a quantity measured at G).

        Returns
        -------
        float
            The distance from the rear axle centre R to G.

        Raises
        ------
        ValueError
            If ``rear_to_cg`` is None.

        Examples
        --------
        >>> import fws_control as fws
        >>> fws.Vehicle(wheelbase=2.7, rear_to_cg=1.2).cg_distance(needed_by="a_y")
        1.2
        >>> fws.Vehicle(wheelbase=2.7).cg_distance(needed_by="the acceleration of G")
        Traceback (most recent call last):
            ...
        ValueError: rear_to_cg is None, but the acceleration of G needs the \
position of the centre of gravity G: give Vehicle(..., rear_to_cg=d) with 0 <= d \
<= wheelbase=2.7 m
        """
        if self.rear_to_cg is None:
            raise ValueError(
                f"rear_to_cg is None, but {needed_by} needs the position of the "
                "centre of gravity G: give Vehicle(..., rear_to_cg=d) with "
                f"0 <= d <= wheelbase={self.wheelbase:g} m"
            )
        return self.rear_to_cg

    @property
    def has_dynamics(self) -> bool:
        """True if rear_to_cg, mass, yaw inertia and both cornering
        stiffnesses are set.

        These five are what the dynamic single-track model needs.
        """
        return all(
            getattr(self, name) is not None
            for name in (
                "rear_to_cg",
                "mass",
                "yaw_inertia",
                "cornering_front",
                "cornering_rear",
            )
        )

    @property
    def has_limits(self) -> bool:
        """True if any steering angle or rate limit is set."""
        return any(
            v is not None
            for v in (
                self.max_steer_front,
                self.max_steer_rear,
                self.max_steer_rate_front,
                self.max_steer_rate_rear,
            )
        )
