"""Renamed modules: the old paths import for one release, with a FutureWarning
that names the new module, and give the same objects.

Each old path is imported afresh (removed from ``sys.modules`` first), so the
warning of the import itself is seen whatever the order of the tests.
"""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

import fws_control
from fws_control.deprecation import REMOVED_IN

RENAMED = {
    "fws_control.models": "fws_control.kinematic_models",
    "fws_control.comparison": "fws_control.linear_vs_nonlinear",
    "fws_control.design": "fws_control.pole_placement",
}


@pytest.mark.parametrize(("old", "new"), sorted(RENAMED.items()))
def test_old_path_warns_and_gives_the_new_modules_objects(old, new, monkeypatch):
    current = importlib.import_module(new)
    monkeypatch.delitem(sys.modules, old, raising=False)
    expected = (
        f"the module {old} is deprecated and is removed in fws_control "
        f"{REMOVED_IN}; use {new}"
    )
    with pytest.warns(FutureWarning) as caught:
        # an import statement's own call (no importlib frame in between)
        shim = __import__(old, fromlist=["__all__"])
    assert [str(w.message) for w in caught] == [expected]
    # the warning names the importing line (this file), not the package
    assert caught[0].filename == __file__
    assert list(shim.__all__) == list(current.__all__)
    for name in current.__all__:
        assert getattr(shim, name) is getattr(current, name), name
    # a name outside __all__ too, and a missing one still raises
    private = next(n for n in vars(current) if n.startswith("_") and n[1] != "_")
    assert getattr(shim, private) is getattr(current, private)
    with pytest.raises(AttributeError):
        _ = shim.no_such_name


def test_the_package_imports_no_old_path():
    # every module of the package, imported with the old paths' warning as an
    # error: none of them imports a shim
    code = (
        "import importlib, pkgutil, warnings, fws_control\n"
        "warnings.simplefilter('error', FutureWarning)\n"
        f"old = {sorted(RENAMED)!r}\n"
        "for m in pkgutil.walk_packages(fws_control.__path__, 'fws_control.'):\n"
        "    if m.name not in old:\n"
        "        importlib.import_module(m.name)\n"
        "import sys\n"
        "print(sorted(n for n in old if n in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_lateral_controller_interface_has_its_own_module():
    from fws_control import baselines, lateral_controller

    assert fws_control.LateralController is lateral_controller.LateralController
    assert fws_control.saturate is lateral_controller.saturate
    assert lateral_controller.LateralController.__module__ == (
        "fws_control.lateral_controller"
    )
    # the concrete controllers implement it; the interface's names stay
    # importable from the baselines' module
    for name in baselines.__all__:
        obj = getattr(baselines, name)
        if isinstance(obj, type):
            assert issubclass(obj, lateral_controller.LateralController), name
    assert baselines.LateralController is lateral_controller.LateralController
    assert baselines.saturate is lateral_controller.saturate
    assert baselines.CONTROLLER_SIGNALS == ("s", "e", "theta", "curvature")
