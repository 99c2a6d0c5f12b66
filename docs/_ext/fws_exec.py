"""Run the Python blocks of selected pages when Sphinx reads them.

A small Sphinx extension: for every page whose name matches a pattern of
the configuration value ``fws_exec_pages`` (``fnmatch`` patterns of
document names, e.g. ``"user_guide/*"``), each Python code block (a
```` ```python ```` fence, or a ``code-block`` in Python) is executed in
document order, in one namespace per page, and what it prints is inserted
under it as a literal block with the class ``fws-exec-output``. Every
matplotlib figure open at the end of a block is saved as a PNG image,
inserted under the output and closed, as a notebook shows it.

A block that raises fails the build: a warning (fatal with ``sphinx -W``)
names the page, the block's number and its line, with the traceback. A
:class:`FutureWarning` or :class:`DeprecationWarning` caused by the page's
own code (a deprecated call) fails the build the same way; other warnings
are shown in the output, as a notebook shows them. What the blocks write
to standard error (progress bars, the compiler's one-time notice) is left
out: it depends on the machine, not on the page.

A Python block that must not run (an illustration, or code for another
environment) carries the class ``no-exec``::

    ```{code-block} python
    :class: no-exec

    client = Client("tcp://scheduler:8786")
    ```

The directive ``fws-cli-run`` shows a command of ``fws-control`` with its
output, run in this process when the page is read (a command that fails
fails the build)::

    ```{fws-cli-run} gains --speed 5 --curvature 0.1 --ratio -1 --pole -1
    ```

Blocks run in a temporary working directory (files they write vanish),
with matplotlib's settings and numpy's print options restored after each
page. An executed page is read again when a module of ``fws_control``
changes, so its output follows the code.

Why not a Jupyter-based tool (myst-nb, jupyter-sphinx): they run each page
in a kernel, a separate process that imports the package again and pays
its start-up per page, and they add the Jupyter stack to the ``docs``
extra; the blocks here need nothing but the interpreter that builds the
docs, which has the package imported already.
"""

from __future__ import annotations

import contextlib
import fnmatch
import functools
import io
import linecache
import os
import shlex
import tempfile
import time
import traceback
import warnings
from pathlib import Path

from docutils import nodes
from sphinx.transforms import SphinxTransform
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

#: Class that keeps a Python block from running.
NO_EXEC_CLASS = "no-exec"
#: Class of the inserted output blocks (styled in ``_static/custom.css``).
OUTPUT_CLASS = "fws-exec-output"
#: Class of the inserted figures.
FIGURE_CLASS = "fws-exec-figure"
#: Resolution of the inserted figures.
FIGURE_DPI = 96

__all__ = ["BlockError", "CliRun", "ExecutePythonBlocks", "run_blocks", "setup"]


class BlockError(Exception):
    """A block raised; carries the block's number, line and traceback."""

    def __init__(self, index: int, line: int | None, text: str):
        super().__init__(text)
        self.index = index
        self.line = line
        self.text = text


def _is_python(node: nodes.literal_block) -> bool:
    return node.get("language") in ("python", "python3", "py") and (
        NO_EXEC_CLASS not in node["classes"]
    )


def _format_warning(message, category, filename, lineno, line=None):
    return f"{category.__name__}: {message}\n"


def _show_warning(stream, message, category, filename, lineno, file=None, line=None):
    # into the block's output, where a notebook shows it
    stream.write(_format_warning(message, category, filename, lineno))


def run_blocks(blocks, *, name: str, figure_dir: Path | None = None):
    """Execute `blocks` in one namespace; yield each block's output.

    Parameters
    ----------
    blocks : iterable of (str, int or None)
        The source of each block and its first line in the page.
    name : str
        The page's name, used in tracebacks (``<name block N>``).
    figure_dir : pathlib.Path or None
        Where the figures open at the end of a block are saved
        (``<name>-block<N>-<M>.png``, ``/`` in `name` replaced by ``-``, so
        that every page's figures have names of their own); None leaves
        them out.

    Yields
    ------
    text : str
        What the block printed, its warnings included.
    figures : list of pathlib.Path
        The PNG files of its figures.

    Raises
    ------
    BlockError
        When a block raises, or calls something deprecated.
    """
    import matplotlib
    import matplotlib.pyplot as plt
    import numpy as np

    namespace: dict = {"__name__": "__main__", "__builtins__": __builtins__}
    old_cwd = os.getcwd()
    with (
        tempfile.TemporaryDirectory(prefix="fws_exec_") as workdir,
        matplotlib.rc_context(),
        np.printoptions(),
    ):
        plt.close("all")
        os.chdir(workdir)
        try:
            for index, (source, line) in enumerate(blocks, start=1):
                filename = f"<{name} block {index}>"
                linecache.cache[filename] = (
                    len(source),
                    None,
                    source.splitlines(keepends=True),
                    filename,
                )
                out = io.StringIO()
                try:
                    with (
                        warnings.catch_warnings(),
                        contextlib.redirect_stdout(out),
                        contextlib.redirect_stderr(io.StringIO()),
                    ):
                        warnings.simplefilter("default")
                        for category in (FutureWarning, DeprecationWarning):
                            warnings.filterwarnings(
                                "error", category=category, module="__main__"
                            )
                        warnings.formatwarning = _format_warning
                        warnings.showwarning = functools.partial(_show_warning, out)
                        exec(compile(source, filename, "exec"), namespace)  # noqa: S102
                except BaseException as exc:
                    tb = traceback.format_exception(exc)
                    # drop this function's own frame from the traceback
                    text = "".join(tb[:1] + tb[2:])
                    plt.close("all")
                    raise BlockError(
                        index, _page_line(exc, filename, line), text
                    ) from exc
                figures = []
                for number in plt.get_fignums():
                    if figure_dir is not None:
                        figure_dir.mkdir(parents=True, exist_ok=True)
                        stem = name.replace("/", "-")
                        path = figure_dir / f"{stem}-block{index}-{number}.png"
                        plt.figure(number).savefig(path, dpi=FIGURE_DPI)
                        figures.append(path)
                plt.close("all")
                yield out.getvalue(), figures
        finally:
            os.chdir(old_cwd)
            plt.close("all")


def _page_line(exc: BaseException, filename: str, fence: int | None) -> int | None:
    """The page line of the block's innermost frame in the traceback of `exc`.

    `fence` is the line of the block's opening fence; the block's first line
    is the next one.
    """
    if fence is None:
        return None
    inner = None
    if isinstance(exc, SyntaxError) and exc.filename == filename:
        inner = exc.lineno
    for frame in traceback.extract_tb(exc.__traceback__):
        if frame.filename == filename:
            inner = frame.lineno
    return fence if inner is None else fence + inner


class ExecutePythonBlocks(SphinxTransform):
    """Execute the Python blocks of a page and insert their output."""

    # after the parser's own transforms, before DoctreeReadEvent (880), so
    # that the image collector of doctree-read sees the inserted figures
    default_priority = 700

    def apply(self, **kwargs) -> None:
        docname = self.env.docname
        if not any(fnmatch.fnmatch(docname, p) for p in self.config.fws_exec_pages):
            return
        targets = [
            node
            for node in self.document.findall(nodes.literal_block)
            if _is_python(node)
        ]
        if not targets:
            return
        for path in _package_sources():
            self.env.note_dependency(str(path))
        figure_dir = Path(self.env.doctreedir) / "fws_exec" / docname
        doc_dir = (Path(self.env.srcdir) / docname).parent
        started = time.perf_counter()
        results = run_blocks(
            ((node.astext(), node.line) for node in targets),
            name=docname,
            figure_dir=figure_dir,
        )
        try:
            for node, (text, figures) in zip(targets, results, strict=False):
                new = []
                if text:
                    out = nodes.literal_block(text, text, language="none")
                    out["classes"].append(OUTPUT_CLASS)
                    new.append(out)
                for fig in figures:
                    uri = os.path.relpath(fig, doc_dir).replace(os.sep, "/")
                    image = nodes.image(uri=uri, alt="figure drawn by the block above")
                    image["classes"].append(FIGURE_CLASS)
                    new.append(image)
                parent = node.parent
                index = parent.index(node)
                parent[index + 1 : index + 1] = new
        except BlockError as err:
            logger.warning(
                "Python block %d of %s (line %s) raised:\n%s",
                err.index,
                docname,
                err.line,
                err.text,
                location=(docname, err.line),
                type="fws_exec",
                subtype="error",
            )
            return
        logger.verbose(
            "fws_exec: %s: %d blocks in %.1f s",
            docname,
            len(targets),
            time.perf_counter() - started,
        )


class CliRun(SphinxDirective):
    """``fws-control ARGS`` run in this process, shown as a terminal transcript.

    The argument is the command line after ``fws-control``; the block shows
    ``$ fws-control ARGS`` and what the command printed on standard output.
    A command that exits with a status other than 0 fails the build.
    """

    required_arguments = 1
    final_argument_whitespace = True

    def run(self):
        from fws_control.cli import main

        args = shlex.split(self.arguments[0])
        out = io.StringIO()
        err = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main(args)
        if status != 0:
            raise self.error(
                f"fws-control {self.arguments[0]} exited with status {status}: "
                f"{err.getvalue().strip()}"
            )
        for path in _package_sources():
            self.env.note_dependency(str(path))
        text = f"$ fws-control {self.arguments[0]}\n{out.getvalue()}"
        node = nodes.literal_block(text, text, language="text")
        node["classes"].append(OUTPUT_CLASS)
        self.set_source_info(node)
        return [node]


def _package_sources() -> list[Path]:
    import fws_control

    return sorted(Path(fws_control.__file__).parent.rglob("*.py"))


def setup(app):
    app.add_config_value("fws_exec_pages", [], "env", types=[list, tuple])
    app.add_transform(ExecutePythonBlocks)
    app.add_directive("fws-cli-run", CliRun)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
