"""Start-up: what ``import fws_control`` and the CLI import (issue 14, item 6).

Timing a start-up in a test would fail on a busy machine and pass a
regression on an idle one; what makes start-up slow is *which* modules get
imported (python-control alone costs about 1.3 s of CPU: it pulls in
matplotlib.pyplot, scipy.signal and scipy.stats; sympy 0.3 s). So these
tests run a fresh interpreter and check ``sys.modules``; the times
themselves are measured by ``benchmarks/bench_startup.py``.
"""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import fws_control as fws

ROOT = Path(__file__).resolve().parents[1]

#: Modules that cost most of a second or more to import.
HEAVY = ("control", "matplotlib", "sympy", "scipy.integrate", "scipy.signal")

#: What the numpy engine, splines and the projection's tree import (with
#: asyncio, for a Dask cluster); none is needed by a compiled run on an
#: analytic path (together about 0.5 s of CPU before a process's first result).
SOLVER_SIDE = (
    "scipy.integrate",
    "scipy.interpolate",
    "scipy.optimize",
    "scipy.spatial",
    "asyncio",
)


def _fresh(code: str) -> dict:
    """Run `code` in a new interpreter; it prints one JSON object last."""
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


_REPORT = (
    "def report():\n"
    f"    heavy = [m for m in {HEAVY!r} if m in sys.modules]\n"
    "    loaded = sorted(m for m in sys.modules if m.startswith('fws_control'))\n"
    "    return {'heavy': heavy, 'loaded': loaded}\n"
)

GAINS_ARGS = ["gains", "--speed", "20", "--curvature", "0.01", "--ratio", "0.5"]

# One fresh interpreter for every check below (each start costs about 2 s):
# the stages run in this order and each records sys.modules before the next
# one. Imports only add modules, so a module absent after a stage is absent
# when that stage runs alone in a new interpreter; the stages that must not
# import something heavy come first, the ones that import everything last.
_STAGES = (
    "import contextlib, io, json, sys\n" + _REPORT + "import fws_control as fws\n"
    "out = {'fresh': '_ORIGIN' not in vars(fws)}\n"
    "out['import'] = report()\n"
    # --help
    "import fws_control.cli as cli\n"
    "buf = io.StringIO()\n"
    "with contextlib.redirect_stdout(buf):\n"
    "    try:\n"
    "        cli.main(['--help'])\n"
    "    except SystemExit as exc:\n"
    "        assert exc.code == 0, exc.code\n"
    "assert 'reproduce' in buf.getvalue()\n"
    "out['help'] = report()\n"
    # the plant checks against python-control's classes
    "veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)\n"
    "p = fws.as_plant(veh, speed=5.0)\n"
    "assert fws.loop_matrices(p).order == 2\n"
    "for bad in (fws.as_plant, fws.loop_matrices):\n"
    "    try:\n"
    "        bad(object())\n"
    "    except TypeError as exc:\n"
    "        assert 'plant must be' in str(exc), exc\n"
    "    else:\n"
    "        raise AssertionError('no TypeError')\n"
    "out['plant'] = report()\n"
    # `gains`
    "buf = io.StringIO()\n"
    "with contextlib.redirect_stdout(buf):\n"
    f"    assert cli.main({GAINS_ARGS!r}) == 0\n"
    "out['gains_text'] = buf.getvalue()\n"
    "out['gains'] = report()\n"
    "out['matplotlib_after_gains'] = 'matplotlib' in sys.modules\n"
    # simulate and simulate_batch, both engines
    "from fws_control.paths import Arc\n"
    "g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0,\n"
    "                          pole=-1.0)\n"
    f"SOLVER_SIDE = {SOLVER_SIDE!r}\n"
    "for engine in ('auto', 'numpy'):\n"
    "    kw = dict(speed=5.0, initial_state=(0.0, -5.0, 0.0), duration=5.0,\n"
    "              dt=0.5, engine=engine)\n"
    "    r = fws.simulate(veh, Arc(curvature=0.1), g, **kw)\n"
    "    b = fws.simulate_batch(veh, Arc(curvature=0.1), g, **kw)\n"
    "    assert (b.e[0] == r.e).all()\n"
    "    out['e_' + engine] = r.e.tolist()\n"
    "    out['engine_' + engine] = r.engine\n"
    "    out['solvers_' + engine] = [m for m in SOLVER_SIDE if m in sys.modules]\n"
    "out['simulate'] = report()\n"
    # the backend the CLI selected (imports matplotlib)
    "import matplotlib\n"
    "out['backend'] = matplotlib.get_backend().lower()\n"
    # every public name but symbolic, then symbolic (imports everything)
    f"for n in {[n for n in fws.__all__ if n != 'symbolic']!r}:\n"
    "    getattr(fws, n)\n"
    "out['sympy_before'] = 'sympy' in sys.modules\n"
    "fws.symbolic.characteristic_polynomial\n"
    "out['sympy_after'] = 'sympy' in sys.modules\n"
    # the star import and dir()
    "ns = {}\n"
    "exec('from fws_control import *', ns)\n"
    "out['star'] = sorted(n for n in ns if n != '__builtins__')\n"
    "out['public'] = sorted(fws.__all__)\n"
    "out['dir'] = dir(fws)\n"
    "print(json.dumps(out))\n"
)


@pytest.fixture(scope="module")
def fresh():
    """What the fresh interpreter of _STAGES recorded at each stage."""
    return _fresh(_STAGES)


def test_import_package_imports_no_submodule(fresh):
    assert fresh["import"]["heavy"] == []
    assert fresh["import"]["loaded"] == ["fws_control"]


def test_help_imports_only_the_parser(fresh):
    assert fresh["help"]["heavy"] == []
    # No analysis module either: each subcommand imports its own.
    assert not {"fws_control.plant", "fws_control.simulation"} & set(
        fresh["help"]["loaded"]
    )


def test_gains_without_python_control_gives_its_poles(fresh):
    """``gains`` runs on numpy alone; its poles are python-control's."""
    assert fresh["gains"]["heavy"] == []
    printed = fresh["gains_text"]
    # Reference: python-control's state space of the closed loop, in this
    # process, for the exact-model design in both linearisations.
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    exact = fws.LateralPlant(veh, speed=20.0, curvature=0.01)
    g = fws.double_root_gains(exact, ratio=0.5, pole=-1.0)
    for lin in ("kinematic", "paper"):
        plant = fws.LateralPlant(veh, speed=20.0, curvature=0.01, model=lin)
        ref = np.sort_complex(fws.closed_loop(plant, g).poles())
        line = next(
            ln for ln in printed.splitlines() if f"poles, {lin} linearisation" in ln
        )
        vals = [complex(v.strip()) for v in line.split(":", 1)[1].split(",")]
        np.testing.assert_allclose(np.sort_complex(vals), ref, atol=2e-6)


def test_cli_selects_agg_without_importing_matplotlib(fresh):
    assert fresh["matplotlib_after_gains"] is False
    assert fresh["backend"] == "agg"


def test_plant_checks_without_python_control(fresh):
    """isinstance checks against python-control classes import nothing."""
    assert fresh["plant"]["heavy"] == []


def test_sympy_only_with_symbolic(fresh):
    assert [fresh["sympy_before"], fresh["sympy_after"]] == [False, True]


def test_lazy_names_resolve_to_their_modules():
    for name in fws.__all__:
        obj = getattr(fws, name)
        if name not in fws._ORIGIN:  # a submodule, e.g. fws_control.symbolic
            assert obj.__name__ == f"fws_control.{name}"
            continue
        module = sys.modules[f"fws_control.{fws._ORIGIN[name]}"]
        assert getattr(module, name) is obj, name
    assert set(fws.__all__) <= set(dir(fws))
    import fws_control.plant as plant_module
    from fws_control import LateralPlant, simulate

    assert fws.plant is plant_module
    assert LateralPlant is plant_module.LateralPlant
    assert simulate is fws.simulation.runners.simulate
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        fws.not_a_name  # noqa: B018


def test_public_names_are_the_type_checking_imports():
    """``__all__`` is read from the ``if TYPE_CHECKING:`` imports, each in
    the ``name as name`` form that marks a re-export for type checkers."""
    tree = ast.parse((ROOT / "fws_control" / "__init__.py").read_text("utf-8"))
    block = next(
        node
        for node in tree.body
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING"
    )
    static = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom) and node.level == 1
        for alias in node.names:
            assert alias.asname == alias.name, ast.unparse(node)
            static[alias.name] = node.module or alias.name
    assert list(static) == fws.__all__
    assert len(set(fws.__all__)) == len(fws.__all__)
    submodules = {n for n, m in static.items() if m == n}
    assert {"symbolic", "dynamics", "vehicles"} == submodules
    assert {n: m for n, m in static.items() if n not in submodules} == fws._ORIGIN
    # No other module-level name is public: the package's own namespace
    # holds only dunders, private helpers and the lazy loader's hooks.
    assigned = {
        t.id
        for node in tree.body
        if isinstance(node, (ast.Assign, ast.AnnAssign))
        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
        if isinstance(t, ast.Name)
    }
    assert {n for n in assigned if not n.startswith("_")} == set()


def test_star_import_and_dir_list_every_public_name(fresh):
    # the import itself read nothing: the table is built on first use
    assert fresh["fresh"]
    star, public, listed = fresh["star"], fresh["public"], fresh["dir"]
    assert star == public == sorted(fws.__all__)
    assert set(public) <= set(listed)
    assert listed == sorted(listed)


def test_compiled_run_imports_no_solver_side_module(fresh):
    """A compiled run imports none of SOLVER_SIDE; the numpy engine's run,
    after it, imports scipy.integrate (the check sees what it should)."""
    if fresh["engine_auto"] != "compiled":
        pytest.skip("numba is not installed: the default run is the numpy engine's")
    assert fresh["solvers_auto"] == []
    assert "scipy.integrate" in fresh["solvers_numpy"]


@pytest.mark.parametrize("engine", ["auto", "numpy"])
def test_simulation_without_python_control(fresh, engine):
    """simulate and simulate_batch import neither python-control nor
    matplotlib; the run's lateral error is python-control's reference
    interconnection's (simulate_reference, in this process) to 1e-7 m."""
    heavy = fresh["simulate"]["heavy"]
    assert "control" not in heavy and "matplotlib" not in heavy, heavy
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    g = fws.double_root_gains(veh, speed=5.0, curvature=0.1, ratio=-1.0, pole=-1.0)
    ref = fws.simulation.simulate_reference(
        veh, fws.Arc(curvature=0.1), g, speed=5.0, initial_state=(0.0, -5.0, 0.0),
        duration=5.0, dt=0.5,
    )  # fmt: skip
    # outputs: x, y, psi, s, e, ...
    np.testing.assert_allclose(fresh["e_" + engine], ref.outputs[4], atol=1e-7)
