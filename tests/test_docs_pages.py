"""The docs scripts' block rewriting (docs/scripts/pages.py)."""

from __future__ import annotations

import importlib.util
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location(
    "docs_pages", ROOT / "docs" / "scripts" / "pages.py"
)
pages = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(pages)


def test_block_replaced_between_its_markers_only(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        "intro\n<!-- t:start -->\nold\n<!-- t:end -->\nmiddle\n"
        "<!-- u:start -->\nkeep\n<!-- u:end -->\n"
    )
    pages.write_blocks(page, {"t": "| a |\n| 1 |"})
    assert page.read_text() == (
        "intro\n<!-- t:start -->\n| a |\n| 1 |\n<!-- t:end -->\nmiddle\n"
        "<!-- u:start -->\nkeep\n<!-- u:end -->\n"
    )
    # nothing left behind by the temporary file
    assert sorted(p.name for p in tmp_path.iterdir()) == ["page.md"]


def test_missing_block_is_named_and_page_untouched(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("no markers\n")
    with pytest.raises(ValueError, match="no block 'table'"):
        pages.write_blocks(page, {"table": "x"})
    assert page.read_text() == "no markers\n"


@pytest.mark.parametrize(
    "name", ["comparison.md", "dynamic_simulation.md", "openloop.md"]
)
def test_generated_pages_round_trip(name):
    """Each generated page is a fixed point of putting its own blocks back."""
    text = (ROOT / "docs" / name).read_text()
    names = re.findall(r"<!-- (\S+):start -->", text)
    assert names, name
    blocks = {}
    for n in names:
        start, end = pages.markers(n)
        blocks[n] = text.split(start, 1)[1].split(end, 1)[0].strip("\n")
    assert pages.replace_blocks(text, blocks) == text
