"""Sphinx configuration for the fws_control documentation.

Build (warnings are errors, the gallery is executed)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

Set ``FWS_DOCS_SKIP_GALLERY=1`` to skip executing the examples (faster
iteration on the text; the gallery pages then have no figures).
"""

from __future__ import annotations

import collections
import functools
import importlib
import inspect
import os
import re
import shutil
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(DOCS / "_ext"))

from sphinx_gallery.sorting import FunctionSortKey  # noqa: E402

import fws_control  # noqa: E402

# -- Project -----------------------------------------------------------------

project = "fws_control"
author = "fws_control developers"
copyright = "2026, fws_control developers"
release = fws_control.__version__
version = ".".join(release.split(".")[:2])

# -- General -----------------------------------------------------------------

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "sphinx.ext.mathjax",
    # MathJax 3 (JS and CHTML woff fonts) copied into _static/mathjax: the
    # pages render math without a network (docs/check_math_offline.py).
    "mathjax_offline",  # sphinx-mathjax-offline (docs/_ext: its parallel safety)
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    # runs the Python blocks of the pages below and shows their output
    "fws_exec",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
templates_path = ["_templates"]
exclude_patterns = [
    "_build",
    "_intersphinx",
    "Thumbs.db",
    ".DS_Store",
    "auto_examples/*.ipynb",
    "auto_examples/*.py",
    "auto_examples/*.zip",
    "auto_examples/*.json",
    "auto_examples/*.md5",
]
default_role = "py:obj"
pygments_style = "sphinx"
nitpicky = False

# The bundled copy, not a CDN (set here as well as by the extension, so that
# the page never points elsewhere).
mathjax_path = "mathjax/tex-chtml.js"

# -- MyST (Markdown pages; docs/errata.md uses $...$ math) -------------------

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# -- Executed pages (docs/_ext/fws_exec.py) ----------------------------------
# Their Python blocks run at build time, one namespace per page, with what
# each block prints and draws shown under it; a block that raises fails the
# build. Slow pages (minutes of simulation) are left to the test suite.

fws_exec_pages = ["index", "getting_started", "user_guide/*"]

# -- autodoc / autosummary / numpydoc ----------------------------------------

autosummary_generate = True
# autosummary never deletes pages of names that left the API: start afresh.
shutil.rmtree(DOCS / "api" / "generated", ignore_errors=True)
autosummary_imported_members = False
autodoc_default_options = {"member-order": "bysource"}
autodoc_typehints = "none"  # numpydoc's Parameters sections carry the types
autodoc_class_signature = "mixed"
add_module_names = False

numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = True
numpydoc_xref_aliases = {
    # this package
    "Vehicle": "fws_control.Vehicle",
    "SteeringGains": "fws_control.SteeringGains",
    "StabilityBoundary": "fws_control.StabilityBoundary",
    "StabilityChart": "fws_control.StabilityChart",
    "StabilityBoundaries": "fws_control.StabilityBoundaries",
    "BoundaryCurve": "fws_control.BoundaryCurve",
    "ChartPanel": "fws_control.paper.ChartPanel",
    "AffinePolynomial": "fws_control.AffinePolynomial",
    "LateralPlant": "fws_control.LateralPlant",
    "LoopMatrices": "fws_control.LoopMatrices",
    "SimulationResult": "fws_control.SimulationResult",
    "Projection": "fws_control.paths.Projection",
    "Path": "fws_control.paths.Path",
    "Straight": "fws_control.paths.Straight",
    "Arc": "fws_control.paths.Arc",
    "Clothoid": "fws_control.paths.Clothoid",
    "Spline": "fws_control.paths.Spline",
    "PathChain": "fws_control.paths.PathChain",
    # python-control
    "StateSpace": "control.StateSpace",
    "TransferFunction": "control.TransferFunction",
    "NonlinearIOSystem": "control.NonlinearIOSystem",
    "InterconnectedSystem": "control.InterconnectedSystem",
    "PoleZeroData": "control.PoleZeroData",
    # numpy / matplotlib
    "ndarray": "numpy.ndarray",
    "array_like": ":term:`numpy:array_like`",
    "array-like": ":term:`numpy:array_like`",
    "Figure": "matplotlib.figure.Figure",
    "Axes": "matplotlib.axes.Axes",
}
numpydoc_xref_ignore = {
    "optional",
    "default",
    "or",
    "of",
    "shape",
    "the",
    "and",
    "each",
    "one",
    "per",
    "run",
    "runs",
    "path",
    "object",
    "None",
    "True",
    "False",
}

# -- intersphinx (offline) ---------------------------------------------------
# The build machines reach package registries only, so the projects'
# objects.inv cannot be downloaded (a failed fetch is a warning, fatal with
# -W). docs/_intersphinx/ holds inventories generated from the installed
# packages by make_inventories.py; FWS_DOCS_ONLINE_INTERSPHINX=1 uses the
# projects' own inventories instead.

_ONLINE = os.environ.get("FWS_DOCS_ONLINE_INTERSPHINX", "") not in ("", "0")


def _inventory(name: str):
    return None if _ONLINE else str(DOCS / "_intersphinx" / f"{name}.inv")


def _control_url() -> str:
    import control

    return f"https://python-control.readthedocs.io/en/{control.__version__}/"


intersphinx_mapping = {
    "python": ("https://docs.python.org/3/", _inventory("python")),
    "numpy": ("https://numpy.org/doc/stable/", _inventory("numpy")),
    "scipy": ("https://docs.scipy.org/doc/scipy/", _inventory("scipy")),
    "matplotlib": ("https://matplotlib.org/stable/", _inventory("matplotlib")),
    "control": (_control_url(), _inventory("control")),
}
intersphinx_timeout = 10

# -- sphinx-gallery ----------------------------------------------------------

_SKIP_GALLERY = os.environ.get("FWS_DOCS_SKIP_GALLERY", "") not in ("", "0")

#: Gallery order: the tour first, then analysis, then simulation. The sort
#: key must pickle (Sphinx caches the configuration), hence a dict lookup
#: rather than a function defined here; unlisted examples go last.
_EXAMPLE_RANK = collections.defaultdict(
    functools.partial(int, "99"),
    {
        name: rank
        for rank, name in enumerate(
            (
                "plot_quick_start.py",
                "plot_stability_chart.py",
                "plot_root_loci.py",
                "plot_any_plant.py",
                "plot_delay.py",
                "plot_design_delay.py",
                "plot_fws_vs_4ws.py",
                "plot_spline_course.py",
                "plot_ratio_sweep.py",
            )
        )
    },
)

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "plot_gallery": "False" if _SKIP_GALLERY else "True",
    "within_subsection_order": FunctionSortKey(
        _EXAMPLE_RANK.__getitem__, "fws_example_order"
    ),
    "doc_module": ("fws_control",),
    "backreferences_dir": "gen_modules/backreferences",
    "reference_url": {"fws_control": None},
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "remove_config_comments": True,
    "min_reported_time": 1,
    # The global sg_execution_times.rst would be written into docs/ itself.
    "write_computation_times": False,
    "show_memory": False,
    "download_all_examples": False,
    "only_warn_on_example_error": False,
    "abort_on_example_error": False,
}

# -- HTML --------------------------------------------------------------------

html_theme = "pydata_sphinx_theme"
html_title = f"fws_control {release}"
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_theme_options = {
    "navigation_with_keys": False,
    # Every top-level page up to Errata and Delay in the header (index.md's
    # order); Changes and Performance under "More".
    "header_links_before_dropdown": 8,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc", "sourcelink"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
}
html_sidebars = {"**": ["sidebar-nav-bs"], "index": []}
html_show_sourcelink = True

# -- API completeness check --------------------------------------------------


def _documented_names() -> set[str]:
    """Every ``fws_control...`` name listed in an autosummary of api.rst."""
    text = (DOCS / "api.rst").read_text(encoding="utf-8")
    names: set[str] = set()
    module = "fws_control"
    in_autosummary = False
    for line in text.splitlines():
        m = re.match(r"\.\. currentmodule:: (\S+)", line)
        if m:
            module = m.group(1)
            continue
        if line.startswith(".. autosummary::"):
            in_autosummary = True
            continue
        if in_autosummary:
            if line and not line[0].isspace():
                in_autosummary = False
                continue
            item = line.strip()
            if not item or item.startswith(":"):
                continue
            names.add(item if item.startswith("fws_control") else f"{module}.{item}")
    return names


def _resolve(name: str):
    module, _, attr = name.rpartition(".")
    try:
        return getattr(importlib.import_module(module), attr)
    except (ImportError, AttributeError):
        return None


def _is_constant(obj) -> bool:
    return isinstance(obj, (bool, int, float, str, tuple, dict, frozenset))


def _public_names() -> dict[str, object]:
    """``{qualified name: object}`` for every public name of the package.

    Public: listed in ``fws_control.__all__`` or in the ``__all__`` of a
    module or subpackage (``fws_control.paper``, ``fws_control.simulation``
    and their modules) whose name has no leading underscore.
    """
    out = {}
    pkg = Path(fws_control.__file__).parent
    modnames = []
    for path in sorted(pkg.rglob("*.py")):
        parts = list(path.relative_to(pkg.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if any(part.startswith("_") for part in parts):
            continue
        modnames.append(".".join(parts))
    for modname in modnames:
        mod = importlib.import_module(modname)
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name)
            if not inspect.ismodule(obj):
                out[f"{modname}.{name}"] = obj
    return out


def _check_api_complete(app) -> None:
    """Warn (fatal with -W) for a public name that api.rst does not list.

    A function or class counts as documented under any of its public names
    (``fws_control.simulate`` or ``fws_control.simulation.simulate``); a
    constant under its own qualified name or under a re-export of the same
    object by the same name (``fws_control.paper.PAPER_SPEEDS`` for
    ``fws_control.paper.data.PAPER_SPEEDS``).
    """
    from sphinx.util import logging

    logger = logging.getLogger("fws_control.api")
    documented = _documented_names()
    documented_ids = set()
    documented_constants = set()
    for name in documented:
        obj = _resolve(name)
        if obj is None:
            logger.warning(
                "docs/api.rst lists %s, which does not exist",
                name,
                type="fws_control",
                subtype="api",
            )
        elif not _is_constant(obj):
            documented_ids.add(id(obj))
        else:
            documented_constants.add((name.rpartition(".")[2], id(obj)))
    for name, obj in sorted(_public_names().items()):
        if name in documented:
            continue
        if not _is_constant(obj) and id(obj) in documented_ids:
            continue
        if (name.rpartition(".")[2], id(obj)) in documented_constants:
            continue
        logger.warning(
            "public name %s is missing from docs/api.rst",
            name,
            type="fws_control",
            subtype="api",
        )


# -- Pages that quote an example's output ------------------------------------

#: Page -> (example, marker): the page quotes, between ``<!-- marker -->``
#: and ``<!-- end-marker -->``, the Markdown table the example prints. The
#: example runs here (sphinx-gallery records its output in the generated
#: page), not in pytest, so the quote is checked here: a difference is a
#: warning, fatal with -W.
QUOTED_OUTPUT = {"varying_speed": ("plot_varying_speed", "varying-speed-table")}


def table_rows(text: str) -> list[str]:
    """The rows of the Markdown tables in `text`, stripped (header included)."""
    rows = (line.strip() for line in text.splitlines())
    return [row for row in rows if row.startswith("| ")]


def _check_quoted_output(app, docname, source) -> None:
    """Warn where a page's quote differs from its example's recorded output."""
    if docname not in QUOTED_OUTPUT or _SKIP_GALLERY:
        return
    from sphinx.util import logging

    logger = logging.getLogger("fws_control.quoted")
    example, marker = QUOTED_OUTPUT[docname]
    generated = Path(app.srcdir) / "auto_examples" / f"{example}.rst"
    text = source[0]
    begin, end = f"<!-- {marker} -->", f"<!-- end-{marker} -->"
    if begin not in text or end not in text or not generated.exists():
        logger.warning(
            "%s: no quote between %s and %s, or no output of %s (%s)",
            docname, begin, end, example, generated,
            type="fws_control", subtype="quoted",
        )  # fmt: skip
        return
    quoted = table_rows(text.split(begin, 1)[1].split(end, 1)[0])
    printed = table_rows(generated.read_text(encoding="utf-8"))
    if quoted != printed:
        logger.warning(
            "%s: the table between %s and %s is not what examples/%s.py "
            "printed:\n%s",
            docname, begin, end, example, "\n".join(printed),
            type="fws_control", subtype="quoted",
        )  # fmt: skip


def _reread_quoting_pages(app, env, added, changed, removed) -> list[str]:
    """The quoting pages, read again in every build: their example may have
    printed something else since (an incremental build reads only the
    changed pages)."""
    return [docname for docname in QUOTED_OUTPUT if docname in env.found_docs]


# -- ``fws-cli-help`` directive: the CLI's --help text, always current -------


def _cli_help_directive():
    from docutils import nodes
    from sphinx.util.docutils import SphinxDirective

    class CliHelp(SphinxDirective):
        """Literal block with ``fws-control [COMMAND] --help``."""

        optional_arguments = 1

        def run(self):
            from fws_control.cli import build_parser

            parser = build_parser()
            if self.arguments:
                sub = None
                for action in parser._actions:
                    choices = getattr(action, "choices", None)
                    if isinstance(choices, dict) and self.arguments[0] in choices:
                        sub = choices[self.arguments[0]]
                if sub is None:
                    raise self.error(f"no fws-control command {self.arguments[0]!r}")
                parser = sub
            old = os.environ.get("COLUMNS")
            os.environ["COLUMNS"] = "72"
            try:
                text = parser.format_help()
            finally:
                if old is None:
                    del os.environ["COLUMNS"]
                else:
                    os.environ["COLUMNS"] = old
            return [nodes.literal_block(text, text, language="text")]

    return CliHelp


def _own_source_only(app, modname, attribute):
    """viewcode links an object to its module's source, following an
    imported name to the module that defines it; a type alias of
    fws_control.hints would lead to the standard library's typing (a page
    of typing's source, made only by parallel builds). Such an object keeps
    the module that documents it."""
    from sphinx.ext.viewcode import _get_full_modname

    full = _get_full_modname(modname, attribute)
    if full is not None and not full.startswith("fws_control"):
        return modname
    return None


def setup(app):
    app.connect("viewcode-follow-imported", _own_source_only)
    app.connect("builder-inited", _check_api_complete)
    app.connect("source-read", _check_quoted_output)
    app.connect("env-get-outdated", _reread_quoting_pages)
    app.add_directive("fws-cli-help", _cli_help_directive())
