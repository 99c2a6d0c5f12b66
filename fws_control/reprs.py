"""Short text and HTML representations of the result and data classes.

Results hold arrays of thousands of values; the dataclass ``__repr__``
would print all of them. :func:`summary_repr` replaces it by one line that
gives scalars and short vectors, and the shape and dtype of other arrays,
plus a small HTML table for notebooks (``_repr_html_``).
"""

from __future__ import annotations

import dataclasses
import html
from typing import Any

import numpy as np

__all__ = ["brief", "summary_repr", "html_table"]

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


def summary_repr(cls):
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

    cls.__repr__ = __repr__
    cls._repr_html_ = _repr_html_
    return cls
