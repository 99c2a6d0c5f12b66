"""Short text and HTML representations of the result and data classes.

Results hold arrays of thousands of values; the dataclass ``__repr__``
would print all of them. :func:`summary_repr` replaces it by one line that
gives scalars and short vectors, and the shape and dtype of other arrays,
plus a small HTML table for notebooks (``_repr_html_``).

Inputs a user writes (a vehicle, gains, a plant, a path, a manoeuvre) keep
the form of a constructor call, :func:`value_repr`: the fields that differ
from their defaults, floats to 12 significant digits (a computed gain
prints as ``0.018``, not ``0.018000000000000002``), arrays and long nested
values by their shape or type.
"""

from __future__ import annotations

import dataclasses
import html
from types import ModuleType
from typing import Any, TypeVar

import numpy as np

_T = TypeVar("_T")

__all__ = ["brief", "summary_repr", "html_table", "value_repr", "import_pandas"]

_MAX = 60  # longest text kept for one field


def brief(value: Any) -> str:
    """A short text for one field value.

    Examples
    --------
    >>> import numpy as np
    >>> from fws_control.reprs import brief
    >>> brief(np.zeros((201, 201), dtype=bool)), brief(np.array([1.0, 2.5]))
    ('<array (201, 201) bool>', '[1, 2.5]')
    >>> brief(0.1 + 0.2), brief("ok")
    ('0.3', "'ok'")
    """
    if isinstance(value, np.ndarray):
        if value.ndim == 0:  # a 0-d array reads as its scalar
            return brief(value.item())
        if value.ndim <= 1 and value.size <= 4 and value.dtype.kind in "biufcUS":
            if value.dtype.kind in "fc":
                return "[" + ", ".join(f"{v:.6g}" for v in value.tolist()) + "]"
            return repr(value.tolist())
        return f"<array {value.shape} {value.dtype}>"
    if isinstance(value, (bool, np.bool_)):
        return repr(bool(value))
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.6g}"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (str, type(None))):
        text = repr(value)
        return text if len(text) <= _MAX else text[: _MAX - 4] + "...'"
    if isinstance(value, (list, tuple)):
        if len(value) <= 4 and all(
            isinstance(v, (int, float, str, bool, np.number)) for v in value
        ):
            return "(" + ", ".join(brief(v) for v in value) + ")"
        return f"<{type(value).__name__} of {len(value)}>"
    if isinstance(value, dict):
        keys = ", ".join(repr(k) for k in list(value)[:4])
        more = ", ..." if len(value) > 4 else ""
        return f"<dict of {len(value)}: {keys}{more}>"
    text = repr(value)
    if len(text) <= _MAX and "\n" not in text and " object at 0x" not in text:
        return text
    name = getattr(value, "name", None)
    label = f" {name!r}" if isinstance(name, str) and name else ""
    return f"<{type(value).__name__}{label}>"


def html_table(title: str, rows: list[tuple[str, str]]) -> str:
    """A small HTML table: `title`, then one ``name | value`` row per item.

    Examples
    --------
    >>> from fws_control.reprs import html_table
    >>> html_table("Data", [("t", "<array (3,) float64>")]).count("<tr>")
    1
    """
    body = "".join(
        f"<tr><th style='text-align:left'>{html.escape(k)}</th>"
        f"<td style='text-align:left'><code>{html.escape(v)}</code></td></tr>"
        for k, v in rows
    )
    return (
        f"<table><caption style='text-align:left'><b>{html.escape(title)}</b>"
        f"</caption>{body}</table>"
    )


def _fields(obj) -> list[tuple[str, str]]:
    return [
        (f.name, brief(getattr(obj, f.name))) for f in dataclasses.fields(obj) if f.repr
    ]


def summary_repr(cls: type[_T]) -> type[_T]:
    """Class decorator: one-line ``__repr__`` and ``_repr_html_`` of a dataclass.

    Examples
    --------
    >>> import numpy as np
    >>> from dataclasses import dataclass
    >>> from fws_control.reprs import summary_repr
    >>> @summary_repr
    ... @dataclass
    ... class Data:
    ...     t: np.ndarray
    ...     ok: bool
    >>> Data(np.linspace(0, 1, 1001), True)
    Data(t=<array (1001,) float64>, ok=True)
    >>> Data(np.zeros(3), False)._repr_html_().startswith("<table>")
    True
    """

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={v}" for k, v in _fields(self))
        return f"{type(self).__name__}({inner})"

    def _repr_html_(self) -> str:
        return html_table(type(self).__name__, _fields(self))

    setattr(cls, "__repr__", __repr__)  # noqa: B010 (a class, typed as type[_T])
    setattr(cls, "_repr_html_", _repr_html_)  # noqa: B010
    return cls


#: Significant digits of a float in :func:`value_repr`: round-off of a few
#: ulp in a computed value (``0.1 + 0.2``) disappears, any value a person
#: types survives.
_DIGITS = 12

#: Longest nested repr kept whole in :func:`value_repr`.
_NESTED = 100


def _value_text(value: Any) -> str:
    if isinstance(value, (bool, np.bool_)):
        return repr(bool(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(f"{float(value):.{_DIGITS}g}"))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, np.ndarray):
        if value.ndim <= 1 and value.size <= 4 and value.dtype.kind in "biuf":
            inner = ", ".join(_value_text(v) for v in value.tolist())
            return f"array([{inner}])"
        return f"<array {value.shape} {value.dtype}>"
    if (
        isinstance(value, tuple)
        and len(value) <= 4
        and all(isinstance(v, (int, float, np.number)) for v in value)
    ):
        inner = ", ".join(_value_text(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    text = repr(value)
    if len(text) <= _NESTED and "\n" not in text:
        return text
    return brief(value) if not isinstance(value, str) else text


def _is_default(field: dataclasses.Field, value: Any) -> bool:
    if field.default is not dataclasses.MISSING:
        default = field.default
    elif field.default_factory is not dataclasses.MISSING:
        default = field.default_factory()
    else:
        return False
    if isinstance(value, np.ndarray) or isinstance(default, np.ndarray):
        return False
    try:
        return bool(value == default) and type(value) is type(default)
    except (TypeError, ValueError):
        return False


def value_repr(cls: type[_T]) -> type[_T]:
    """Class decorator: a short constructor-call ``__repr__`` of a dataclass.

    Fields equal to their default are left out; floats print to 12
    significant digits; arrays with more than four values, and nested values
    whose repr is longer than 100 characters, print as their shape or type.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> from fws_control.reprs import value_repr
    >>> @value_repr
    ... @dataclass
    ... class Point:
    ...     x: float
    ...     y: float = 0.0
    ...     label: str | None = None
    >>> Point(0.1 + 0.2)
    Point(x=0.3)
    >>> Point(1.0, 2.0, "p")
    Point(x=1.0, y=2.0, label='p')
    """

    def __repr__(self) -> str:
        parts = [
            f"{f.name}={_value_text(getattr(self, f.name))}"
            for f in dataclasses.fields(self)
            if f.repr and not _is_default(f, getattr(self, f.name))
        ]
        return f"{type(self).__name__}({', '.join(parts)})"

    setattr(cls, "__repr__", __repr__)  # noqa: B010 (a class, typed as type[_T])
    return cls


def import_pandas() -> ModuleType:
    """The :mod:`pandas` module, or an ImportError naming the extra for it.

    The ``to_pandas()`` methods call it: pandas is optional (the extra
    ``fws-control[pandas]``).
    """
    try:
        import pandas as pd
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(
            "to_pandas() needs pandas; install it with `pip install pandas` "
            "(or the extra `fws-control[pandas]`)"
        ) from exc
    return pd
