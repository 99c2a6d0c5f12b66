"""Rewrite the generated blocks of a docs page, atomically.

A generated block sits between ``<!-- NAME:start -->`` and
``<!-- NAME:end -->`` on its page; the scripts of this folder print their
tables and put them there with :func:`write_blocks`, so that the page and
the script cannot disagree (the tests re-run parts of each script and
compare with the page).
"""

from __future__ import annotations

import pathlib

from fws_control.files import atomic_write


def markers(name: str) -> tuple[str, str]:
    """The start and end markers of block `name`."""
    return f"<!-- {name}:start -->", f"<!-- {name}:end -->"


def replace_blocks(text: str, blocks: dict[str, str]) -> str:
    """`text` with each block ``name -> content`` put between its markers."""
    for name, content in blocks.items():
        start, end = markers(name)
        if start not in text or end not in text:
            raise ValueError(f"the page has no block {name!r} ({start} ... {end})")
        head, rest = text.split(start, 1)
        _, tail = rest.split(end, 1)
        text = f"{head}{start}\n{content}\n{end}{tail}"
    return text


def write_blocks(page: pathlib.Path, blocks: dict[str, str]) -> None:
    """Put each block of `blocks` into `page` (temporary file, then rename)."""
    new = replace_blocks(page.read_text(), blocks)
    with atomic_write(page, mode="w") as fh:
        fh.write(new)
