"""Argument checks shared by the public functions.

Every check raises :class:`ValueError` naming the argument, the offending
value and the valid range, as the design card asks.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = [
    "check_finite",
    "check_positive",
    "check_nonzero",
    "check_scalar",
    "check_type",
    "check_model",
    "check_angle_limit",
    "check_rate_limit",
    "check_delay",
    "check_optional_positive",
    "MODELS",
]

MODELS = ("exact", "paper", "dynamic")


def check_finite(name: str, value: Any) -> np.ndarray | float:
    """Return `value` as float (or float array) if every element is finite."""
    if isinstance(value, (str, bytes)) or value is None:
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(
            f"{name} must be a finite number or array, got {value!r}"
        ) from exc
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return float(arr) if arr.ndim == 0 else arr


def check_positive(name: str, value: Any) -> np.ndarray | float:
    """Return `value` as float (array) if every element is finite and > 0."""
    v = check_finite(name, value)
    if not np.all(np.asarray(v) > 0):
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return v


def check_nonzero(name: str, value: Any) -> np.ndarray | float:
    """Return `value` as float (array) if every element is finite and != 0."""
    v = check_finite(name, value)
    if np.any(np.asarray(v) == 0):
        raise ValueError(f"{name} must be finite and nonzero, got {value!r}")
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


def check_model(model: Any) -> str:
    """Return `model` if it names a known linearisation."""
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    return model


def _float_or_nan(value: Any) -> float:
    # a value that is no number fails the range test below with its name
    if isinstance(value, bool):
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
