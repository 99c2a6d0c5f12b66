"""Deprecated module path; use :mod:`fws_control.kinematic_models`.

``import fws_control.models`` keeps working until fws_control 0.4 and warns
with a :class:`FutureWarning` that names the new module; every name of
:mod:`fws_control.kinematic_models` is reachable here.
"""

from typing import Any

from . import kinematic_models as _new
from .deprecation import warn_deprecated
from .kinematic_models import *  # noqa: F403

__all__ = list(_new.__all__)

warn_deprecated("the module fws_control.models", "fws_control.kinematic_models")


def __getattr__(name: str) -> Any:
    # the module's other names (not in __all__) as well
    return getattr(_new, name)
