"""Deprecated module path; use :mod:`fws_control.pole_placement`.

``import fws_control.design`` keeps working until fws_control 0.4 and warns
with a :class:`FutureWarning` that names the new module; every name of
:mod:`fws_control.pole_placement` is reachable here.
"""

from typing import Any

from . import pole_placement as _new
from .deprecation import warn_deprecated
from .pole_placement import *  # noqa: F403

__all__ = list(_new.__all__)

warn_deprecated("the module fws_control.design", "fws_control.pole_placement")


def __getattr__(name: str) -> Any:
    # the module's other names (not in __all__) as well
    return getattr(_new, name)
