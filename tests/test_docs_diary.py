"""The docs, docstrings and comments describe the software, not its history.

Reference text says what the library does and how it was measured; the
history of how it got there belongs in git and in the changelog. This test
reads

* every page of the documentation (``docs/*.md``, ``docs/**/*.md``,
  ``docs/*.rst``) and ``README.md``, except the changelog page
  ``docs/changes.md`` (its entries are history by design, and dated
  versions belong there);
* the docstrings (:mod:`ast`) and comments (:mod:`tokenize`) of every module
  of the package,

and fails on the patterns of a work log: the words "session", "reviewer",
"review's", "yesterday", "A/A" (runs), "before/after the fix", "last
session", "this session"; ISO dates and written-out dates such as
"22 Nov 2026"; "commit" followed by a hash; and hexadecimal words of 7-40
characters with both letters and digits (what commit hashes look like),
unless they are numbers in context (after ``0x``, inside a number).

It also holds ``docs/performance.md`` to a reference page's length.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PACKAGE = ROOT / "fws_control"

MONTHS = "Jan|Feb|Mar|Apr|May|Jun|Jul|Aug|Sep|Oct|Nov|Dec"
PATTERNS = {
    "session": re.compile(r"\bsessions?\b", re.I),
    "reviewer": re.compile(r"\breviewers?\b|\breview's\b", re.I),
    "yesterday": re.compile(r"\byesterday\b", re.I),
    "A/A run": re.compile(r"\bA/A\b"),
    "before/after the fix": re.compile(r"\b(before|after) the fix\b", re.I),
    "ISO date": re.compile(r"(?<![\d.])20\d\d-[01]\d-[0-3]\d(?!\d)"),
    "written date": re.compile(
        rf"\b[0-3]?\d (?:{MONTHS})[a-z]* 20\d\d\b"
        rf"|\b(?:{MONTHS})[a-z]* [0-3]?\d, 20\d\d\b"
    ),
    "commit": re.compile(r"\bcommit [0-9a-f]{7,40}\b", re.I),
    # a hash-looking word: 7-40 hex characters with a letter and a digit,
    # not part of a number or an identifier (0x..., 1e300, abc_1234567)
    "hex word": re.compile(
        r"(?<![\w.+-])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}(?![\w.])"
    ),
}


def _pages() -> list[Path]:
    pages = set(DOCS.glob("*.md")) | set(DOCS.glob("**/*.md"))
    pages |= set(DOCS.glob("*.rst"))
    pages = {p for p in pages if "_build" not in p.parts and p.name != "changes.md"}
    return sorted(pages) + [ROOT / "README.md"]


def _docstrings_and_comments(path: Path) -> list[tuple[int, str]]:
    """(line, text) of each docstring and comment of a module."""
    source = path.read_text(encoding="utf-8")
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(
            node,
            ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef,
        ):
            body = node.body
            if (
                body
                and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)
            ):
                out.append((body[0].lineno, body[0].value.value))
    # attribute docstrings (#: comments) are comments, found below
    for tok in tokenize.generate_tokens(io.StringIO(source).readline):
        if tok.type == tokenize.COMMENT:
            out.append((tok.start[0], tok.string))
    return out


def _hits(text: str) -> list[str]:
    found = []
    for name, pattern in PATTERNS.items():
        for m in pattern.finditer(text):
            found.append(f"{name}: {m.group(0)!r}")
    return found


def test_patterns_find_what_they_are_for():
    # each pattern catches its diary phrase and leaves the neighbouring
    # technical text alone (so the tests below can fail, and only on diary)
    diary = [
        "measured this session",
        "after the review's fixes",
        "a reviewer found",
        "an A/A run",
        "before the fix it took",
        "on 2026-11-26 the run",
        "branch fuzzfix, 22 Nov 2026, 07:05",
        "at commit be7c435",
        "against bc34e9f",
        "yesterday",
    ]
    for text in diary:
        assert _hits(text), text
    technical = [
        "the last time |e| leaves 2 %",
        "k1 = 0.9259259259259258",
        "1e-300 and 1e300",
        "0x7fffffff",
        "4.17871859155190428",
        "period=62.83185307179586",
        "a decade of 1234567 runs",
        "accepted steps (abcdefa is a word of letters only)",
    ]
    for text in technical:
        assert not _hits(text), (text, _hits(text))


@pytest.mark.parametrize("page", _pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_page_has_no_diary_wording(page):
    bad = []
    for lineno, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1):
        bad += [f"{page.name}:{lineno}: {hit}" for hit in _hits(line)]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize(
    "module",
    sorted(PACKAGE.rglob("*.py")),
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_docstrings_and_comments_have_no_diary_wording(module):
    bad = []
    for lineno, text in _docstrings_and_comments(module):
        bad += [f"{module.name}:{lineno}: {hit}" for hit in _hits(text)]
    assert not bad, "\n".join(bad)


def test_performance_page_is_a_reference_page():
    lines = (DOCS / "performance.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) < 300, len(lines)
