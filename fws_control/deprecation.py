"""Deprecated calling forms: one warning, one way of naming the new form.

A renamed keyword or a replaced calling form keeps working for one release
and warns with a :class:`FutureWarning` (shown to users by default, unlike
:class:`DeprecationWarning`) that names the form to use instead and the
release that removes the old one, :data:`REMOVED_IN`. The warning points at
the user's line: the first caller outside the package, however deep in the
package the old form was met.

Examples
--------
>>> import warnings
>>> from fws_control.deprecation import legacy_keyword
>>> options = {"time_constant": 0.1}
>>> with warnings.catch_warnings(record=True) as caught:
...     warnings.simplefilter("always")
...     lag = legacy_keyword(options, "time_constant", "steering_lag", None)
>>> lag, options, caught[0].category.__name__
(0.1, {}, 'FutureWarning')
>>> print(caught[0].message)
time_constant= is deprecated and is removed in fws_control 0.4; use steering_lag=
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path
from types import FrameType
from typing import Any

__all__ = [
    "REMOVED_IN",
    "LEGACY_MODELS",
    "warn_deprecated",
    "legacy_keyword",
    "reject_unknown",
]

#: The release that removes the deprecated forms.
REMOVED_IN = "0.4"

#: Deprecated names of a plant's `model` -> their current name.
LEGACY_MODELS = {"exact": "kinematic"}

# the package's folder: frames inside it are skipped so that the warning
# names the user's line, whatever the depth of the call
_PACKAGE_DIR = str(Path(__file__).resolve().parent)
_PACKAGE = __name__.partition(".")[0]


def _in_package(frame) -> bool:
    # by module name too: a dataclass's generated __init__ has no file
    name = frame.f_globals.get("__name__", "")
    return (
        name == _PACKAGE
        or name.startswith(_PACKAGE + ".")
        or frame.f_code.co_filename.startswith(_PACKAGE_DIR)
    )


def _user_stacklevel() -> int:
    """The `stacklevel` for :func:`warnings.warn`, called in this module's
    caller, that names the first frame outside the package."""
    frame: FrameType | None = sys._getframe(1)  # the function that calls warnings.warn
    level = 1
    while frame is not None and _in_package(frame):
        frame = frame.f_back
        level += 1
    return level


def warn_deprecated(old: str, new: str) -> None:
    """Warn that the form `old` goes away in :data:`REMOVED_IN`; use `new`.

    Parameters
    ----------
    old : str
        The deprecated form, as the user wrote it (e.g. ``"model='exact'"``).
    new : str
        The form to use instead.

    Examples
    --------
    >>> import warnings
    >>> from fws_control.deprecation import warn_deprecated
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn_deprecated("model='exact'", "model='kinematic'")
    >>> print(caught[0].message)
    model='exact' is deprecated and is removed in fws_control 0.4; use model='kinematic'
    """
    warnings.warn(
        f"{old} is deprecated and is removed in fws_control {REMOVED_IN}; use {new}",
        FutureWarning,
        stacklevel=_user_stacklevel(),
    )


def legacy_keyword(kwargs: dict[str, Any], old: str, new: str, value: Any) -> Any:
    """The value of keyword `new`, taken from the deprecated `old` if given.

    Pops `old` from `kwargs` (the caller's ``**kwargs``) and warns naming
    `new`. `value` is what the caller received for `new`; ``None`` means
    not given.

    Parameters
    ----------
    kwargs : dict
        The caller's remaining keyword arguments (modified: `old` removed).
    old, new : str
        The deprecated and the current keyword.
    value : object
        The value passed as `new` (``None``: not given).

    Returns
    -------
    object
        `value`, or the value of `old` if `value` is None and `old` given.

    Raises
    ------
    TypeError
        If both `old` and `new` are given.

    Examples
    --------
    >>> from fws_control.deprecation import legacy_keyword
    >>> legacy_keyword({}, "time_constant", "steering_lag", 0.2)
    0.2
    >>> legacy_keyword({"time_constant": 0.1}, "time_constant", "steering_lag", 0.2)
    Traceback (most recent call last):
    ...
    TypeError: time_constant= and steering_lag= name the same option; ...
    """
    if old not in kwargs:
        return value
    if value is not None:
        raise TypeError(f"{old}= and {new}= name the same option; give only {new}=")
    warn_deprecated(f"{old}=", f"{new}=")
    return kwargs.pop(old)


def reject_unknown(function: str, kwargs: dict[str, Any]) -> None:
    """Raise :class:`TypeError` for keywords left in `kwargs`.

    Parameters
    ----------
    function : str
        Name of the function, for the message.
    kwargs : dict
        Keywords that no parameter and no deprecated keyword took.

    Raises
    ------
    TypeError
        If `kwargs` is not empty, naming its keys.

    Examples
    --------
    >>> from fws_control.deprecation import reject_unknown
    >>> reject_unknown("simulate", {"bogus": 1})
    Traceback (most recent call last):
    ...
    TypeError: simulate() got an unexpected keyword argument 'bogus'
    """
    if kwargs:
        names = ", ".join(repr(k) for k in kwargs)
        plural = "s" if len(kwargs) > 1 else ""
        raise TypeError(
            f"{function}() got an unexpected keyword argument{plural} {names}"
        )
