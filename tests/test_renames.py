"""Renamed modules and functions: the old names work for one release, with a
FutureWarning that names the new one, and give the same objects and values.

Each old path is imported afresh (removed from ``sys.modules`` first), so the
warning of the import itself is seen whatever the order of the tests.
"""

from __future__ import annotations

import importlib
import subprocess
import sys

import numpy as np
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


VEH = fws_control.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


@pytest.mark.parametrize("curvature", [0.0, 0.05])
@pytest.mark.parametrize("ratio", [-1.0, 0.0, 0.5])
def test_each_characteristic_name_says_what_it_returns(curvature, ratio):
    plant = fws_control.LateralPlant(VEH, speed=7.0, curvature=curvature)
    gains = fws_control.SteeringGains(0.3, 0.9, ratio)
    # the independent reference: det(sI - A_cl) of python-control's loop
    want = np.poly(fws_control.closed_loop(plant, gains).A)
    coefficients = fws_control.characteristic_polynomial_coefficients(plant, gains)
    assert isinstance(coefficients, np.ndarray)
    np.testing.assert_allclose(coefficients, want, rtol=1e-12, atol=1e-14)
    # the polynomial as an affine map of the gains, then its coefficients
    poly = fws_control.affine_characteristic_polynomial(plant, ratio=ratio)
    assert isinstance(poly, fws_control.AffinePolynomial)
    np.testing.assert_allclose(
        poly.coefficients(gains.k1, gains.k2), want, rtol=1e-12, atol=1e-14
    )


@pytest.mark.parametrize(
    ("old", "new", "args", "kwargs"),
    [
        (
            "characteristic_coefficients",
            "affine_characteristic_polynomial",
            (),
            {"ratio": -1.0},
        ),
        (
            "characteristic_polynomial",
            "characteristic_polynomial_coefficients",
            (fws_control.SteeringGains(0.3, 0.9, -1.0),),
            {},
        ),
    ],
)
def test_former_function_names_warn_and_give_the_same_values(old, new, args, kwargs):
    plant = fws_control.LateralPlant(VEH, speed=7.0, curvature=0.05)
    assert old not in fws_control.__all__ and new in fws_control.__all__
    former = getattr(fws_control, old)
    expected = (
        f"{old}() is deprecated and is removed in fws_control {REMOVED_IN}; use {new}()"
    )
    with pytest.warns(FutureWarning) as caught:
        got = former(plant, *args, **kwargs)
    assert [str(w.message) for w in caught] == [expected]
    assert caught[0].filename == __file__
    want = getattr(fws_control, new)(plant, *args, **kwargs)
    if isinstance(want, np.ndarray):
        np.testing.assert_array_equal(got, want)
    else:
        for field in ("open_loop", "n1", "n2"):
            np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
    # `from fws_control import <old name>` too
    ns = {}
    exec(f"from fws_control import {old} as f", ns)
    assert ns["f"] is former


def test_symbolic_characteristic_polynomial_is_the_polynomial():
    # its name stays: it returns the polynomial itself (a sympy Poly in s)
    import sympy as sp

    from fws_control import symbolic

    p = symbolic.characteristic_polynomial("kinematic")
    assert isinstance(p, sp.Poly) and p.degree() == 2 and p.LC() == 1
