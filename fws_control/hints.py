"""Type aliases for the annotations of the public functions.

``numpy.typing.ArrayLike`` also admits ``str`` and ``bytes``; the aliases
here admit real numbers only, so that a type checker flags
``double_root_gains(plant, ratio="minus one", pole=-1.0)`` before it runs.
They are aliases for static tools: at run time every argument is still
checked (a ValueError or TypeError names it).

Examples
--------
>>> import numpy as np
>>> from fws_control.hints import RealArrayLike
>>> def half(x: RealArrayLike) -> np.ndarray:
...     return np.asarray(x, dtype=float) / 2
>>> half([1.0, 3.0])
array([0.5, 1.5])
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal, Protocol, TypeAlias, runtime_checkable

import numpy as np

__all__ = [
    "RealArrayLike",
    "RatioLike",
    "SupportsArray",
    "ModelName",
    "TyreName",
    "FeedforwardLike",
]


@runtime_checkable
class SupportsArray(Protocol):
    """An object numpy converts with ``__array__`` (e.g. a pandas Series)."""

    def __array__(self, *args: Any, **kwargs: Any) -> np.ndarray: ...


#: A real number or an array of them: float, int, numpy scalar, numpy array,
#: (nested) sequence of floats, or an object with ``__array__``. Not str.
RealArrayLike: TypeAlias = (
    float
    | np.number
    | np.ndarray
    | Sequence[float]
    | Sequence[Sequence[float]]
    | SupportsArray
)

#: A rear-to-front steering ratio: real numbers as :data:`RealArrayLike`, or
#: a schedule ``ratio(vehicle, speed=...)`` evaluated at the plant's speed.
RatioLike: TypeAlias = RealArrayLike | Callable[..., Any]

#: The plant model of a design or simulation (``model=``): the kinematic
#: model, the paper's linearisation of it, or the dynamic single-track model
#: (:data:`fws_control.validation.MODELS`).
ModelName: TypeAlias = Literal["kinematic", "paper", "dynamic"]

#: The tyre law of the dynamic model (``tyre=``).
TyreName: TypeAlias = Literal["linear", "magic"]

#: The feedforward of the paper's law (``feedforward=``): on, off, or the
#: kinematic or dynamic curvature feedforward by name.
FeedforwardLike: TypeAlias = bool | Literal["kinematic", "dynamic"]
