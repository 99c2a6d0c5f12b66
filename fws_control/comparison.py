"""Deprecated module path; use :mod:`fws_control.linear_vs_nonlinear`.

``import fws_control.comparison`` keeps working until fws_control 0.4 and warns
with a :class:`FutureWarning` that names the new module; every name of
:mod:`fws_control.linear_vs_nonlinear` is reachable here.
"""

from typing import Any

from . import linear_vs_nonlinear as _new
from .deprecation import warn_deprecated
from .linear_vs_nonlinear import *  # noqa: F403

__all__ = list(_new.__all__)

warn_deprecated("the module fws_control.comparison", "fws_control.linear_vs_nonlinear")


def __getattr__(name: str) -> Any:
    # the module's other names (not in __all__) as well
    return getattr(_new, name)
