"""Write offline intersphinx inventories for the documentation build.

The docs link to python-control, NumPy, SciPy, Matplotlib and Python through
:mod:`sphinx.ext.intersphinx`. Intersphinx normally downloads each project's
``objects.inv`` at build time; the build machines have no network (only
package registries), and none of the installed packages ships its
``objects.inv``. A failed download is a Sphinx warning, which ``-W`` turns
into an error.

This script builds equivalent inventories from the *installed* packages by
introspection: each public name is written with the URL pattern its
project's documentation uses (e.g. ``generated/control.ss.html`` for
python-control, ``reference/generated/numpy.roots.html`` for NumPy). The
inventories hold only names, roles and URLs -- no text is copied -- and are
a subset of the real ones; a name missing here is simply not linked (the
build is not nitpicky). With network access, ``FWS_DOCS_ONLINE_INTERSPHINX=1``
makes ``conf.py`` use the projects' own inventories instead.

Run from the repository root after upgrading one of these packages::

    python docs/_intersphinx/make_inventories.py
"""

from __future__ import annotations

import builtins
import importlib
import inspect
import sys
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent

#: name -> (base URL, version string of the installed package)
PROJECTS = {
    "python": "https://docs.python.org/3/",
    "numpy": "https://numpy.org/doc/stable/",
    "scipy": "https://docs.scipy.org/doc/scipy/",
    "matplotlib": "https://matplotlib.org/stable/",
    "control": "https://python-control.readthedocs.io/en/{version}/",
}


def _public(obj) -> list[str]:
    names = getattr(obj, "__all__", None)
    if names is None:
        names = [n for n in dir(obj) if not n.startswith("_")]
    return sorted(set(names))


def _role(obj) -> str:
    if inspect.ismodule(obj):
        return "py:module"
    if inspect.isclass(obj):
        return "py:class"
    if callable(obj):
        return "py:function"
    return "py:data"


def _members(cls) -> list[tuple[str, str]]:
    """(name, role) for the public methods, properties and attributes."""
    out = []
    for name, value in inspect.getmembers(cls):
        if name.startswith("_"):
            continue
        if isinstance(inspect.getattr_static(cls, name, None), property):
            out.append((name, "py:property"))
        elif callable(value):
            out.append((name, "py:method"))
        else:
            out.append((name, "py:attribute"))
    return out


def _write(project: str, version: str, entries: set[tuple[str, str, str]]) -> Path:
    lines = []
    for name, role, uri in sorted(entries):
        # Labels carry -1 as priority and a title, as Sphinx writes them.
        prio, disp = ("-1", name) if role == "std:label" else ("1", "-")
        lines.append(f"{name} {role} {prio} {uri} {disp}")
    header = (
        "# Sphinx inventory version 2\n"
        f"# Project: {project}\n"
        f"# Version: {version}\n"
        "# The remainder of this file is compressed using zlib.\n"
    ).encode()
    body = zlib.compress(("\n".join(lines) + "\n").encode(), 9)
    path = HERE / f"{project}.inv"
    path.write_bytes(header + body)
    return path


def python_entries() -> set[tuple[str, str, str]]:
    out = set()
    stdtypes = {"list", "tuple", "dict", "str", "set", "frozenset", "range", "bytes"}
    for name in dir(builtins):
        obj = getattr(builtins, name)
        if name.startswith("_"):
            continue
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            out.add((name, "py:exception", f"library/exceptions.html#{name}"))
        elif inspect.isclass(obj):
            page = "stdtypes" if name in stdtypes else "functions"
            out.add((name, "py:class", f"library/{page}.html#{name}"))
        elif callable(obj):
            out.add((name, "py:function", f"library/functions.html#{name}"))
    for name in ("None", "True", "False", "Ellipsis", "NotImplemented"):
        out.add((name, "py:data", f"library/constants.html#{name}"))
    for modname in (
        "math",
        "cmath",
        "dataclasses",
        "functools",
        "typing",
        "collections.abc",
        "pathlib",
        "argparse",
        "os",
        "abc",
        "enum",
    ):
        mod = importlib.import_module(modname)
        page = f"library/{modname}.html"
        out.add((modname, "py:module", f"{page}#module-{modname}"))
        for name in _public(mod):
            obj = getattr(mod, name, None)
            if obj is None or inspect.ismodule(obj):
                continue
            full = f"{modname}.{name}"
            out.add((full, _role(obj), f"{page}#{full}"))
    out.add(("os.PathLike", "py:class", "library/os.html#os.PathLike"))
    # Targets of numpydoc's default type aliases (bool, sequence, ...).
    out.add(
        ("bltin-boolean-values", "std:label", "library/stdtypes.html#boolean-values")
    )
    for term in ("sequence", "iterable", "generator", "mapping", "hashable"):
        out.add((term, "std:term", f"glossary.html#term-{term}"))
    return out


def numpy_entries() -> set[tuple[str, str, str]]:
    import numpy as np
    import numpy.typing as npt

    gen = "reference/generated/"
    out = {("numpy", "py:module", "reference/index.html#module-numpy")}
    for name in _public(np):
        obj = getattr(np, name, None)
        if obj is None or inspect.ismodule(obj):
            continue
        full = f"numpy.{name}"
        role = _role(obj)
        out.add((full, role, f"{gen}{full}.html"))
        if isinstance(obj, np.ufunc):
            # NumPy lists ufuncs as data; a :func: reference needs a function.
            out.add((full, "py:data", f"{gen}{full}.html"))
    for name, role in _members(np.ndarray):
        full = f"numpy.ndarray.{name}"
        out.add((full, role, f"{gen}{full}.html"))
    for sub in ("linalg", "random", "polynomial"):
        mod = importlib.import_module(f"numpy.{sub}")
        out.add((f"numpy.{sub}", "py:module", f"reference/routines.{sub}.html"))
        for name in _public(mod):
            obj = getattr(mod, name, None)
            if obj is None or inspect.ismodule(obj):
                continue
            full = f"numpy.{sub}.{name}"
            out.add((full, _role(obj), f"{gen}{full}.html"))
    for name in _public(npt):
        full = f"numpy.typing.{name}"
        out.add((full, "py:data", f"reference/typing.html#{full}"))
        out.add((full, "py:class", f"reference/typing.html#{full}"))
    out.add(
        ("arrays.scalars", "std:label", "reference/arrays.scalars.html#arrays-scalars")
    )
    for term in ("array_like", "array-like", "ndarray", "scalar", "dtype", "ufunc"):
        out.add((term, "std:term", f"glossary.html#term-{term}"))
    return out


def scipy_entries() -> set[tuple[str, str, str]]:
    gen = "reference/generated/"
    out = {("scipy", "py:module", "reference/index.html#module-scipy")}
    for sub in ("integrate", "interpolate", "optimize", "linalg", "signal", "special"):
        modname = f"scipy.{sub}"
        mod = importlib.import_module(modname)
        out.add((modname, "py:module", f"reference/{sub}.html#module-{modname}"))
        for name in _public(mod):
            obj = getattr(mod, name, None)
            if obj is None or inspect.ismodule(obj):
                continue
            full = f"{modname}.{name}"
            out.add((full, _role(obj), f"{gen}{full}.html"))
            if inspect.isclass(obj) and sub in ("integrate", "interpolate"):
                for member, role in _members(obj):
                    out.add((f"{full}.{member}", role, f"{gen}{full}.{member}.html"))
    return out


def matplotlib_entries() -> set[tuple[str, str, str]]:
    import matplotlib.axes
    import matplotlib.figure
    import matplotlib.pyplot as plt

    gen = "api/_as_gen/"
    out = {
        ("matplotlib", "py:module", "api/matplotlib_configuration_api.html"),
        ("matplotlib.pyplot", "py:module", "api/pyplot_summary.html"),
        ("matplotlib.axes.Axes", "py:class", "api/axes_api.html#matplotlib.axes.Axes"),
        ("matplotlib.figure.Figure", "py:class", f"{gen}matplotlib.figure.Figure.html"),
    }
    for name in _public(plt):
        obj = getattr(plt, name, None)
        if inspect.isfunction(obj) and obj.__module__ == "matplotlib.pyplot":
            full = f"matplotlib.pyplot.{name}"
            out.add((full, "py:function", f"{gen}{full}.html"))
    for cls, prefix in (
        (matplotlib.axes.Axes, "matplotlib.axes.Axes"),
        (matplotlib.figure.Figure, "matplotlib.figure.Figure"),
    ):
        for name, role in _members(cls):
            full = f"{prefix}.{name}"
            out.add((full, role, f"{gen}{full}.html"))
    return out


def control_entries() -> set[tuple[str, str, str]]:
    import control as ct

    gen = "generated/"
    out = {("control", "py:module", "intro.html#module-control")}
    for name in _public(ct):
        obj = getattr(ct, name, None)
        if obj is None or inspect.ismodule(obj):
            continue
        full = f"control.{name}"
        out.add((full, _role(obj), f"{gen}{full}.html"))
        if inspect.isclass(obj):
            for member, role in _members(obj):
                out.add((f"{full}.{member}", role, f"{gen}{full}.html#{full}.{member}"))
    return out


def main() -> int:
    import control
    import matplotlib
    import numpy
    import scipy

    versions = {
        "python": f"{sys.version_info.major}.{sys.version_info.minor}",
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
        "control": control.__version__,
    }
    makers = {
        "python": python_entries,
        "numpy": numpy_entries,
        "scipy": scipy_entries,
        "matplotlib": matplotlib_entries,
        "control": control_entries,
    }
    for project, make in makers.items():
        entries = make()
        path = _write(project, versions[project], entries)
        print(f"{path.name}: {len(entries)} names ({project} {versions[project]})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
