"""The docs extension that runs the pages' Python blocks (docs/_ext/fws_exec.py).

The build itself checks the pages' code; these tests check the mechanism:
one namespace per page, the printed output and the figures under their
block, a failing build that names the page and the block, and the
``fws-cli-run`` transcripts of the command line.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))

import fws_exec  # noqa: E402


def test_blocks_share_one_namespace_and_print_under_their_block():
    blocks = [("x = 6 * 7\nprint(x)", 3), ("print(x + 1, x // 5)", 9), ("y = 1", 12)]
    out = list(fws_exec.run_blocks(blocks, name="page"))
    assert [text for text, _ in out] == ["42\n", "43 8\n", ""]


def test_a_raising_block_names_its_page_number_and_line():
    blocks = [("a = 1", 5), ("b = 2\nc = a / (b - 2)", 11), ("print('never')", 20)]
    runner = fws_exec.run_blocks(blocks, name="guide/page")
    assert next(runner) == ("", [])
    with pytest.raises(fws_exec.BlockError) as info:
        next(runner)
    err = info.value
    # the page line of the failing statement: the block's second line
    assert (err.index, err.line) == (2, 13)
    assert "ZeroDivisionError" in err.text
    # the traceback points into the block, at its second line
    assert 'File "<guide/page block 2>", line 2' in err.text
    assert "c = a / (b - 2)" in err.text


def test_a_deprecated_call_fails_other_warnings_are_shown():
    shown = "import warnings\nwarnings.warn('look', RuntimeWarning)\nprint('after')"
    ((text, _),) = fws_exec.run_blocks([(shown, 1)], name="p")
    assert text == "RuntimeWarning: look\nafter\n"
    deprecated = "import warnings\nwarnings.warn('old API', FutureWarning)"
    with pytest.raises(fws_exec.BlockError, match="FutureWarning: old API"):
        list(fws_exec.run_blocks([(deprecated, 1)], name="p"))


def test_figures_are_saved_per_block_and_closed(tmp_path):
    import matplotlib.pyplot as plt

    blocks = [
        ("import matplotlib.pyplot as plt\nfig, ax = plt.subplots()", 1),
        ("print(len(plt.get_fignums()))", 5),
    ]
    (text1, figs1), (text2, figs2) = fws_exec.run_blocks(
        blocks, name="guide/p", figure_dir=tmp_path
    )
    assert [f.name for f in figs1] == ["guide-p-block1-1.png"]
    assert figs1[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the first block's figure was closed after it was saved
    assert (text2, figs2) == ("0\n", [])
    assert plt.get_fignums() == []


PAGE = """\
# Page

```python
x = 6 * 7
print(x)
```

```{code-block} python
:class: no-exec

raise SystemExit("an illustration never runs")
```

```python
print(x - 1)
```
"""


def _build(tmp_path, page: str, *, warning_is_error: bool):
    pytest.importorskip("sphinx", reason="Sphinx (the extra 'docs') builds the page")
    pytest.importorskip("myst_parser", reason="MyST (the extra 'docs') reads .md")
    from sphinx.cmd.build import build_main

    src = tmp_path / "src"
    src.mkdir()
    (src / "conf.py").write_text(
        f"import sys\nsys.path.insert(0, {str(ROOT / 'docs' / '_ext')!r})\n"
        "extensions = ['myst_parser', 'fws_exec']\n"
        "fws_exec_pages = ['*']\n"
    )
    (src / "index.md").write_text(page)
    args = ["-q", "-E", "-b", "text", str(src), str(tmp_path / "out")]
    status = build_main((["-W"] if warning_is_error else []) + args)
    return status, tmp_path / "out" / "index.txt"


def test_sphinx_build_shows_the_output(tmp_path):
    status, out = _build(tmp_path, PAGE, warning_is_error=True)
    assert status == 0
    text = out.read_text()
    # each output under its own block, in page order; the no-exec block kept
    assert text.index("print(x)") < text.index("42") < text.index("SystemExit")
    assert text.index("print(x - 1)") < text.index("41")


def test_sphinx_build_fails_on_a_raising_block(tmp_path, capsys):
    page = PAGE.replace("print(x - 1)", "print(undefined_name)")
    status, _ = _build(tmp_path, page, warning_is_error=True)
    assert status != 0
    err = capsys.readouterr().err
    # the page and the failing line (the fence is line 14)
    assert "index.md:15: WARNING: Python block 2 of index (line 15) raised" in err
    assert "NameError: name 'undefined_name' is not defined" in err


def test_cli_transcript_is_run_at_build_time(tmp_path):
    import control as ct
    import numpy as np

    page = (
        "# CLI\n\n```{fws-cli-run} gains --speed 5 --curvature 0.1 --ratio -1"
        " --pole -1\n```\n"
    )
    status, out = _build(tmp_path, page, warning_is_error=True)
    assert status == 0
    text = out.read_text()
    assert "$ fws-control gains --speed 5 --curvature 0.1 --ratio -1 --pole -1" in text
    # the double-root gains, from python-control's Ackermann formula on the
    # kinematic Jacobian written out here (V = 5, kappa = 0.1, f = 2.7, a = -1)
    V, kappa, f, a = 5.0, 0.1, 2.7, -1.0
    A = np.array([[0.0, V], [-V * kappa**2, 0.0]])
    B = np.array([[0.0, V], [(1 + f**2 * kappa**2) * V / f, -V / f]])
    k1, k2 = ct.acker(A, (B @ [1.0, a])[:, None], [-1.0, -1.0]).ravel()
    assert f"k1 = {k1:.6f} rad/m   k2 = {k2:.6f}" in text


def test_a_failing_cli_transcript_fails_the_build(tmp_path, capsys):
    # a = 1 on a straight road: no design exists, the command exits with 2
    page = "# CLI\n\n```{fws-cli-run} gains --curvature 0 --ratio 1\n```\n"
    status, _ = _build(tmp_path, page, warning_is_error=True)
    assert status != 0
    err = capsys.readouterr().err
    assert "index.md:3" in err
    assert "fws-control gains --curvature 0 --ratio 1 exited with status 2" in err
