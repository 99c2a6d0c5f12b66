"""The layout of fws_control.simulation: small modules, short functions, no
private name shared between modules, imports in one direction.

Each module of the subpackage holds one stage of the closed loop (outcomes,
options, the loop's right-hand side, dense output, the engine driver,
signals, peaks, results, the runners and where their chunks run). These
tests keep it so: a module over :data:`MAX_MODULE_LINES` lines or a
function over :data:`MAX_FUNCTION_LINES` lines fails here, as does a
module that imports an underscore name from another module of the package
or an import cycle between the modules.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import fws_control

PACKAGE = Path(fws_control.__file__).resolve().parent
SIMULATION = PACKAGE / "simulation"

MAX_MODULE_LINES = 1500
MAX_FUNCTION_LINES = 300

#: Modules over the limits, with their present number of lines and their
#: longest function (name, lines): they may shrink, not grow (none now).
KNOWN_EXCEPTIONS: dict[str, tuple[int, tuple[str, int]]] = {}

MODULES = sorted(SIMULATION.glob("*.py"))


def _lines(path: Path) -> int:
    # counted as `wc -l` does: newline characters
    return path.read_bytes().count(b"\n")


def _functions(tree: ast.AST):
    """``(qualified name, lines)`` of every function and method, nested too."""

    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                name = prefix + child.name
                first = min([child.lineno, *(d.lineno for d in child.decorator_list)])
                yield name, child.end_lineno - first + 1
                yield from walk(child, name + ".")
            elif isinstance(child, ast.ClassDef):
                yield from walk(child, prefix + child.name + ".")
            else:
                yield from walk(child, prefix)

    return list(walk(tree, ""))


def _tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def test_the_modules_are_found():
    names = {p.name for p in MODULES}
    # the stages of the loop, each in a module of its own
    assert {
        "outcomes.py",
        "options.py",
        "loop.py",
        "dense.py",
        "engine.py",
        "signals.py",
        "peaks.py",
        "result.py",
        "arguments.py",
        "chunks.py",
        "cluster.py",
        "runners.py",
        "compiled.py",
        "compiled_layout.py",
        "compiled_loop.py",
        "compiled_events.py",
        "compiled_dop853.py",
        "compiled_radau.py",
        "compiled_drivers.py",
        "compiled_signals.py",
        "compiled_peaks.py",
        "compiled_variants.py",
    } <= names
    assert set(KNOWN_EXCEPTIONS) <= names


def test_function_lines_are_counted_from_def_to_last_line():
    # the counter itself, on a source whose sizes are known by construction
    source = (
        "@decorator\n"  # 1
        "def f(x):\n"  # 2
        "    def g():\n"  # 3
        "        return 1\n"  # 4
        "    return g\n"  # 5
        "class C:\n"  # 6
        "    def m(self):\n"  # 7
        "        pass\n"  # 8
    )
    assert dict(_functions(ast.parse(source))) == {"f": 5, "f.g": 2, "C.m": 2}


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_module_size(path):
    lines = _lines(path)
    limit = KNOWN_EXCEPTIONS.get(path.name, (MAX_MODULE_LINES,))[0]
    assert lines <= limit, (
        f"simulation/{path.name} has {lines} lines, more than {limit}: split it "
        "by concept (one stage of the loop per module)"
    )


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_function_size(path):
    functions = _functions(_tree(path))
    known = KNOWN_EXCEPTIONS.get(path.name)
    limit = MAX_FUNCTION_LINES if known is None else known[1][1]
    long = {name: n for name, n in functions if n > limit}
    assert not long, f"simulation/{path.name}: functions over {limit} lines: {long}"
    if known is not None:
        # the exception's longest function is where it was said to be
        assert max(functions, key=lambda f: f[1]) == known[1]


def _package_module(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path):
    """``(module, names)`` of every import of the package's own modules in
    `path`, relative imports resolved; local (lazy) imports included."""
    here = _package_module(path)
    package = here if path.name == "__init__.py" else here.rpartition(".")[0]
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if module == "fws_control" or module.startswith("fws_control."):
                yield module, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("fws_control."):
                    yield a.name, []


@pytest.mark.parametrize("path", MODULES, ids=lambda p: p.name)
def test_no_private_name_from_a_peer_module(path):
    here = _package_module(path)
    private = [
        f"{module}.{name}"
        for module, names in _imports(path)
        for name in names
        if name.startswith("_") and module != here
    ]
    assert not private, (
        f"simulation/{path.name} imports private names of other modules: "
        f"{private}; make them public in their module or move them here"
    )


def test_no_import_cycle_between_the_modules():
    modules = {_package_module(p) for p in MODULES}
    graph = {}
    for path in MODULES:
        here = _package_module(path)
        targets = set()
        for module, names in _imports(path):
            # `from . import reference` names a module, not an attribute
            targets |= {module} | {f"{module}.{name}" for name in names}
        graph[here] = (targets & modules) - {here}
    # the package's face (__init__) is left out: it imports every module
    graph.pop("fws_control.simulation", None)
    state = {}

    def visit(node, trail):
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == "open":
                cycle = trail[trail.index(nxt) :] + [nxt]
                raise AssertionError(f"import cycle: {' -> '.join(cycle)}")
            if nxt not in state:
                visit(nxt, trail + [nxt])
        state[node] = "done"

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    # the layering: the runners send chunks, a chunk drives the engine, and
    # the names of the outcomes depend on nothing
    sim = "fws_control.simulation."
    assert sim + "chunks" in graph[sim + "runners"]
    assert sim + "engine" in graph[sim + "chunks"]
    assert not graph[sim + "outcomes"]
