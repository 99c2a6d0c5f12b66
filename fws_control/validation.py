"""Argument checks shared by the public functions.

Every check raises :class:`ValueError` naming the argument, the offending
value and the valid range, as the design card asks.
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np

from .deprecation import LEGACY_MODELS, warn_deprecated
from .hints import ModelName

__all__ = [
    "check_real",
    "check_finite",
    "check_bool",
    "check_positive",
    "check_nonzero",
    "check_scalar",
    "check_type",
    "check_model",
    "check_angle_limit",
    "check_rate_limit",
    "check_delay",
    "check_optional_positive",
    "check_magnitude",
    "MODELS",
    "MAX_SPEED",
    "MAX_CURVATURE",
    "MAX_RATIO",
    "MAX_ANGLE",
]

#: Linearisations of a plant: ``"kinematic"`` (the exact Jacobian of the
#: kinematic model, eqs. 18-19), ``"paper"`` (the paper's eq. 33) and
#: ``"dynamic"`` (the single-track model with tyres).
MODELS = ("kinematic", "paper", "dynamic")

#: Largest speed magnitude accepted by the plant models [m/s]. Far above any
#: vehicle; it keeps products such as V^2 kappa^2 and m V^2 kappa finite in
#: double precision (with ``abs(kappa) <= MAX_CURVATURE`` they stay below 1e30).
MAX_SPEED = 1.0e6

#: Largest curvature magnitude accepted by the plant models [1/m] (a radius
#: of 1 micrometre); see :data:`MAX_SPEED`.
MAX_CURVATURE = 1.0e6

#: Largest rear-to-front ratio magnitude accepted where the characteristic
#: coefficients are formed from it (stability lines, charts): ``abs(a)`` of a real
#: four-wheel steering is below 10; 1e300 overflowed the coefficients.
MAX_RATIO = 1.0e6

#: Largest magnitude of an angle given as a heading or an initial angle
#: [rad]. Angles are used through sine and cosine, i.e. modulo 2 pi: at
#: 1e6 rad neighbouring doubles are 1.2e-10 rad apart, at 1e300 rad 1e284
#: rad apart, so such a number names no direction at all.
MAX_ANGLE = 1.0e6


def _short(value: Any) -> str:
    # one line, bounded: an error message never prints a whole array
    text = repr(value)
    if len(text) > 80 or "\n" in text:
        shape = np.shape(value) if isinstance(value, np.ndarray) else None
        head = " ".join(text[:60].split())
        return f"{head}... (shape {shape})" if shape is not None else f"{head}..."
    return text


_NOT_REAL = (bool, np.bool_, complex, np.complexfloating)


def _mixed(value: Any, budget: int = 10_000) -> bool:
    """True if a (nested) list/tuple/object array holds a bool or complex.

    numpy would turn ``(True, 0.5)`` into ``[1.0, 0.5]`` without a word.
    """
    stack = [value]
    while stack and budget > 0:
        v = stack.pop()
        budget -= 1
        if isinstance(v, _NOT_REAL):
            return True
        if isinstance(v, (list, tuple)):
            stack.extend(v)
        elif isinstance(v, np.ndarray):
            if v.dtype.kind in "bc":
                return True
            if v.dtype.kind == "O":
                stack.extend(v.ravel().tolist())
    return False


def check_real(name: str, value: Any) -> np.ndarray:
    """Return `value` as a float array if it is real numbers (not yet finite).

    ``bool`` and complex values are refused with :class:`TypeError` naming
    `name`: ``True`` is not 1 m, and a complex number would silently lose its
    imaginary part. Strings, ``None`` and ragged or non-numeric sequences are
    refused with :class:`ValueError`.

    Examples
    --------
    >>> from fws_control.validation import check_real
    >>> check_real("x", [1, 2.5]).tolist()
    [1.0, 2.5]
    >>> check_real("x", True)
    Traceback (most recent call last):
        ...
    TypeError: x must be a real number, not a bool, got True
    """
    if type(value) is np.ndarray and value.dtype == np.float64:
        return value
    if isinstance(value, (str, bytes)) or value is None:
        raise ValueError(f"{name} must be a finite number, got {_short(value)}")
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be a real number, not a bool, got {value!r}")
    if isinstance(value, (complex, np.complexfloating)):
        raise TypeError(
            f"{name} must be a real number, not a complex one, got {value!r}"
        )
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be a finite number or array, got {_short(value)}"
        ) from exc
    if raw.dtype.kind == "b":
        raise TypeError(f"{name} must be real numbers, not bools, got {_short(value)}")
    if raw.dtype.kind == "c":
        raise TypeError(
            f"{name} must be real numbers, not complex ones, got {_short(value)}"
        )
    if (raw.dtype.kind == "O" or isinstance(value, (list, tuple))) and _mixed(value):
        raise TypeError(
            f"{name} must be real numbers (no bool or complex), got {_short(value)}"
        )
    try:
        return np.asarray(raw, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be a finite number or array, got {_short(value)}"
        ) from exc


def check_finite(name: str, value: Any) -> np.ndarray | float:
    """Return `value` as float (or float array) if every element is finite.

    Real numbers only (see :func:`check_real`): ``bool`` and complex values
    raise :class:`TypeError`.
    """
    # (the common case first: a Python float; other types, numpy scalars
    # and subclasses included, take check_real's path)
    if type(value) is float:
        if math.isfinite(value):
            return float(value)
        raise ValueError(f"{name} must be finite, got {_short(value)}")
    arr = check_real(name, value)
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} must be finite, got {_short(value)}")
    return float(arr) if arr.ndim == 0 else arr


def check_bool(name: str, value: Any) -> bool:
    """Return `value` if it is a ``bool`` (or numpy bool), else raise TypeError.

    A flag given as a string (``"False"``) or a number is a mistake that
    would otherwise be read by its truth value (``"False"`` is true).

    Examples
    --------
    >>> from fws_control.validation import check_bool
    >>> check_bool("feedforward", False)
    False
    >>> check_bool("feedforward", "False")
    Traceback (most recent call last):
        ...
    TypeError: feedforward must be True or False, got 'False' (str)
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise TypeError(
        f"{name} must be True or False, got {_short(value)} ({type(value).__name__})"
    )


def _not_empty(name: str, v: Any) -> None:
    # np.all of nothing is True: an empty array would pass a range check and
    # fail later without the argument's name (empty data arrays are fine in
    # check_finite: a vectorised function may be called on zero samples)
    if np.size(v) == 0:
        raise ValueError(
            f"{name} must not be empty, got an array of shape {np.shape(v)}"
        )


def check_positive(name: str, value: Any) -> np.ndarray | float:
    """Return `value` as float (array) if every element is finite and > 0."""
    v = check_finite(name, value)
    _not_empty(name, v)
    if not np.all(np.asarray(v) > 0):
        raise ValueError(f"{name} must be > 0, got {_short(value)}")
    return v


def check_nonzero(name: str, value: Any) -> np.ndarray | float:
    """Return `value` as float (array) if every element is finite and != 0."""
    v = check_finite(name, value)
    _not_empty(name, v)
    if np.any(np.asarray(v) == 0):
        raise ValueError(f"{name} must be finite and nonzero, got {_short(value)}")
    return v


def check_scalar(name: str, value: Any) -> float:
    """Return `value` as a finite float; arrays are refused, naming `name`."""
    v = check_finite(name, value)
    if np.ndim(v) != 0:
        raise ValueError(
            f"{name} must be a scalar here, got an array of shape {np.shape(v)}"
        )
    return float(v)


def check_type(name: str, value: Any, cls: type, what: str | None = None) -> Any:
    """Return `value` if it is an instance of `cls`, else raise TypeError.

    The class is passed in by the caller, so that this module imports no
    library class (it sits below every other module).
    """
    if not isinstance(value, cls):
        what = what or f"a fws_control.{cls.__name__}"
        raise TypeError(f"{name} must be {what}, got {type(value).__name__}")
    return value


def check_model(model: Any, *, name: str = "model") -> ModelName:
    """Return `model` if it names a known linearisation (:data:`MODELS`).

    The deprecated ``"exact"`` is returned as ``"kinematic"``, with a
    :class:`FutureWarning`. `name` is the argument's name in messages.
    """
    if isinstance(model, str) and model in LEGACY_MODELS:
        new = LEGACY_MODELS[model]
        warn_deprecated(f"{name}={model!r}", f"{name}={new!r}")
        return cast("ModelName", new)
    if not isinstance(model, str) or model not in MODELS:
        raise ValueError(f"{name} must be one of {MODELS}, got {_short(model)}")
    return cast("ModelName", model)


def _float_or_nan(value: Any) -> float:
    # a value that is no number fails the range test below with its name
    if isinstance(value, (bool, np.bool_, complex, np.complexfloating)):
        return math.nan
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def check_angle_limit(name: str, value: Any) -> float | None:
    """Steering-angle limit: None (no limit) or a number in (0, pi/2)."""
    if value is None:
        return None
    v = _float_or_nan(value)
    if not (math.isfinite(v) and 0.0 < v < math.pi / 2):
        raise ValueError(f"{name} must be None or in (0, pi/2) rad, got {value!r}")
    return v


def check_rate_limit(name: str, value: Any) -> float | None:
    """Steering-rate limit: None (no limit) or a finite number > 0."""
    if value is None:
        return None
    v = _float_or_nan(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(
            f"{name} must be None or a finite value > 0 rad/s, got {value!r}"
        )
    return v


def check_delay(delay: Any) -> float:
    """Return `delay` as a float if it is a finite number >= 0 [s].

    Examples
    --------
    >>> from fws_control.validation import check_delay
    >>> check_delay(0.24)
    0.24
    """
    if isinstance(delay, (bool, np.bool_)):
        raise TypeError(f"delay must be a number of seconds, got {delay!r}")
    d = check_finite("delay", delay)
    if np.ndim(d) != 0 or d < 0:
        raise ValueError(f"delay must be a finite scalar >= 0 s, got {delay!r}")
    return float(d)


def check_magnitude(
    name: str, value: Any, limit: float, unit: str = ""
) -> np.ndarray | float:
    """Return `value` as float (array) if every element is finite, ``abs(x) <= limit``.

    A range check that keeps later products (squares of speeds and
    curvatures) from overflowing to inf.

    Examples
    --------
    >>> from fws_control.validation import check_magnitude
    >>> check_magnitude("speed", 20, 1e6, "m/s")
    20.0
    >>> check_magnitude("speed", 1e300, 1e6, "m/s")
    Traceback (most recent call last):
        ...
    ValueError: speed must be finite with magnitude <= 1e+06 m/s, got 1e+300
    """
    v = check_finite(name, value)
    if np.any(np.abs(np.asarray(v)) > limit):
        unit = f" {unit}" if unit else ""
        raise ValueError(
            f"{name} must be finite with magnitude <= {limit:g}{unit}, "
            f"got {_short(value)}"
        )
    return v


def check_optional_positive(name: str, value: Any, unit: str = "") -> float | None:
    """Return None or `value` as a float if it is a finite real number > 0.

    Examples
    --------
    >>> from fws_control.validation import check_optional_positive
    >>> check_optional_positive("mass", 1500, "kg")
    1500.0
    """
    if value is None:
        return None
    v = _float_or_nan(value)
    if isinstance(value, complex) or not (math.isfinite(v) and v > 0.0):
        unit = f" {unit}" if unit else ""
        raise ValueError(
            f"{name} must be None or a finite number > 0{unit}, got {value!r}"
        )
    return v
