"""API meta-tests: conventions that every public callable must follow.

In the spirit of python-control's ``kwargs_test.py`` and ``docstrings_test.py``
(the idea, not the code): instead of testing what a function computes, these
tests walk the public surface -- ``fws_control.__all__`` and the ``__all__`` of
the subpackages ``fws_control.simulation`` and ``fws_control.paper`` -- and
check the conventions of the 0.2 "plant-first" API:

1. the first parameter of a public function names its subject (plant, vehicle,
   path, ...);
2. scalar options are keyword-only (only data may be positional);
3. every parameter is documented in the numpydoc ``Parameters`` section and
   every public function and class has an ``Examples`` section;
4. unknown keyword arguments raise ``TypeError`` (no silent ``**kwargs``);
5. ``plot`` methods and ``plot_*`` functions accept ``ax`` and return a
   :class:`control.ControlPlot`;
6. there is no import cycle between the package's modules;
7. no module imports a private name or a private module of a peer module;
8. ``import fws_control`` does not import ``fws_control.paper``;
9. every module has an ``__all__`` whose names all exist.

Each test collects *all* violations of its rule and reports them together, so
one failing run lists everything that is left to fix. Exceptions to a rule
live in explicit dictionaries below, each with its reason; a new exception
must be argued there, not by weakening a check.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import subprocess
import sys
import warnings
from functools import cache
from pathlib import Path

import control as ct
import matplotlib
import numpy as np
import pytest
from conftest import PAPER_VEHICLE

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

import fws_control as fws  # noqa: E402

PACKAGE = "fws_control"
PACKAGE_DIR = Path(fws.__file__).resolve().parent

# Modules whose ``__all__`` is the public surface (the top level and the two
# subpackages of the spec). A subpackage that does not exist yet is skipped.
SURFACE_MODULES = (PACKAGE, f"{PACKAGE}.simulation", f"{PACKAGE}.paper")

# --------------------------------------------------------------------------
# Allow-lists and exceptions (each entry justified)
# --------------------------------------------------------------------------

# Check 1: the first parameter of a public function names what the function
# is about. Kept short on purpose:
FIRST_PARAMETER_NAMES = {
    "plant": "analysis utilities are plant-first (spec: 'A plant')",
    "vehicle": "models, controllers, kinematics and simulation of a Vehicle",
    "path": "systems built on a path alone (projection)",
    "gains": "functions of a SteeringGains only",
    "result": "post-processing of a SimulationResult (metrics)",
    "t": "time-signal metrics take (t, signal), like numpy.trapezoid(y, x)",
    "signal": "metrics of one signal without a time axis",
    "waypoints": "paths built from data points",
    "name": "look-ups by name (make_figure('fig2'))",
}

# Check 1: functions whose subject is none of the names above. Key: public
# label (without the subpackage prefix); value: (first parameter, reason).
# Check 2 lets that parameter be positional too, as the first one only.
FIRST_PARAMETER_EXCEPTIONS = {
    "paper_figure_panels": ("n", "the paper's figure number: panels of Fig. n"),
    "plot_paper_figure": ("n", "the paper's figure number: plot_paper_figure(3)"),
    "reproduce": ("out", "the output directory is what it fills: reproduce(out)"),
    "MPCRun": (
        "controller",
        "the state of one run of a controller: MPCRun(controller, vehicle, path)",
    ),
}

# Check 2: names that are *data* and may be positional (positional-or-keyword)
# anywhere. Everything else -- speed, curvature, ratio, model, pole, duration,
# initial_state, dt, k1/k2 of an analysis function, ax, ... -- is an option
# and must be keyword-only, so that a mis-ordered call fails.
POSITIONAL_DATA_NAMES = {
    # subjects (see FIRST_PARAMETER_NAMES)
    "plant",
    "vehicle",
    "path",
    "gains",
    "controller",
    "controllers",
    "result",
    # signals: time axis, a generic signal, steering angles and their rates,
    # path-frame errors and their rates, global pose, arc length
    "t",
    "signal",
    "delta_f",
    "delta_r",
    "delta_f_rate",
    "delta_r_rate",
    "e",
    "theta",
    "e_rate",
    "theta_rate",
    "x",
    "y",
    "psi",
    "s",
}

# Check 1 (excluded) and check 2 (all fields may be positional): constructors
# of plain frozen data records, whose fields are the data. Key: the public
# label of the class.
RECORD_CLASSES = {
    "Vehicle": "geometry record: Vehicle(wheelbase, rear_to_cg, ...)",
    "LateralPlant": "operating-point record (vehicle, speed, curvature, model)",
    "SteeringGains": "gain record: SteeringGains(k1, k2, ratio)",
    "AffinePolynomial": "result record (open_loop, n1, n2)",
    "AffineCoefficients": "result record of 0.1 (coefficients)",
    "StabilityBoundary": "result record: line alpha*k1 + beta*k2 + gamma = 0",
    "StabilityBoundaries": "result record (real_root, complex_root, lines)",
    "BoundaryCurve": "result record (omega, k1, k2 arrays)",
    "StabilityChart": "result record of stability_chart",
    "StabilityVerdict": "result record of stability_verdict (code, bound)",
    "DelayMarginChart": "result record of delay_margin_chart",
    "CriticalDelay": "result record of critical_delay (delay, frequency, ...)",
    "ParameterBox": "parameter record: one interval or value per parameter",
    "BoundaryPiece": "result record (kind, k1, k2, omega, parameters)",
    "RobustRegion": "result record of robust_region",
    "RobustDesign": "result record of robust_gains",
    "ParetoFront": "result record of pareto_front",
    "GainSchedule": "schedule record: speeds and the gains at each (the data)",
    "SpeedProfile": "speed record: a table (points, speeds) or a function of t or s",
    "RearLimitBand": "result record of rear_limit_band",
    "RearSaturation": "result record of rear_saturation",
    "ChartPanel": "result record (title, charts, labels)",
    "TurningGeometry": "result record of steady_turn / turning_radius",
    "LinearNonlinearComparison": "result record of compare_linear_nonlinear",
    "SimulationResult": "result record of simulate (signals are fields)",
    "BatchResult": "result record of 0.1 simulate_batch",
    "TrackingMetrics": "result record of tracking_metrics",
    "Projection": "result record of Path.project",
    "Straight": "path record: Straight(length, start, start_heading)",
    "Arc": "path record: Arc(curvature, length, ...)",
    "Clothoid": "path record: Clothoid(curvature_start, curvature_end, length)",
    "Spline": "path record: Spline(waypoints, closed)",
    "PathChain": "path record: PathChain(segments, closed)",
    "Path": "abstract base of the path records",
    "LoopMatrices": "record of the loop matrices (A, B_front, B_rear, c_e, ...)",
    "StateFeedback": "controller record: StateFeedback(K, feedforward), K = data",
    "Gate": "geometry record (x_start, x_end, y_right, y_left, name)",
    "Manoeuvre": "course record (name, path, gates, vehicle_width, start_x)",
    "ControllerComparison": "result record of compare",
    "MPCStep": "result record of MPCRun.step (measurement, prediction, plan)",
}

# Check 2: further parameters that are data for one particular callable.
# Key: public label; value: (names, reason).
POSITIONAL_EXCEPTIONS = {
    "SpeedProfile.from_time": (
        {"t", "v"},
        "alternate constructor from the data (t, v) (SpeedProfile.from_time(t, v))",
    ),
    "SpeedProfile.from_distance": (
        {"s", "v"},
        "alternate constructor from the data (s, v)",
    ),
    "SpeedProfile.constant": ({"v"}, "alternate constructor from the speed v"),
    "SpeedProfile.braking": (
        {"v0", "decel"},
        "alternate constructor from its data: initial speed and deceleration",
    ),
    "SpeedProfile.from_function": ({"function"}, "constructor from the function"),
    "SpeedProfile.derivative": ({"x"}, "evaluates the profile at x (the data)"),
    "SteeringGains.from_K": (
        {"K"},
        "alternate constructor from the data K (spec: SteeringGains.from_K(K))",
    ),
    "SteeringGains.steering": ({"e", "theta"}, "evaluates the law at errors"),
    "SimulationResult.signal": (
        {"name"},
        "result.signal('e') is result.e by name: the name is the data",
    ),
    "StabilityBoundary.satisfied": (
        {"k1", "k2"},
        "evaluates the boundary at gain points (the data, not options)",
    ),
    "StabilityBoundary.k2_at": ({"k1"}, "the line solved for k2 at given k1"),
    "StabilityBoundary.k1_at": ({"k2"}, "the line solved for k1 at given k2"),
    "StabilityBoundary.segment": (
        {"k1_range", "k2_range"},
        "the clipping window is the data of the method",
    ),
    "AffinePolynomial.coefficients": (
        {"k1", "k2"},
        "spec: .coefficients(k1, k2) evaluates at gain points",
    ),
    "AffinePolynomial.coefficient_bounds": (
        {"k1", "k2"},
        "evaluates the coefficients and their bounds at gain points",
    ),
    "AffinePolynomial.evaluate": (
        {"s", "k1", "k2"},
        "spec: .evaluate(s, k1, k2) evaluates p(s) at gain points",
    ),
    "AffineCoefficients.p1": ({"k1", "k2"}, "evaluates at gain points"),
    "AffineCoefficients.p0": ({"k1", "k2"}, "evaluates at gain points"),
    "StabilityBoundary.from_coefficients": (
        {"alpha", "beta", "gamma", "condition"},
        "alternate constructor of the record: its arguments are the fields",
    ),
    "Path.placed": (
        {"start", "start_heading"},
        "the new placement is the data (mirrors the record fields)",
    ),
    "RearLimitBand.allows": (
        {"ratio"},
        "evaluates the band at given ratios: the ratio is the data",
    ),
    "SpeedCertificate.P_at": (
        {"speed"},
        "evaluates the Lyapunov matrix at given speeds [m/s]: the speed is the data",
    ),
    "GainSchedule.at": (
        {"speed"},
        "evaluates the schedule at given speeds [m/s]: the speed is the data",
    ),
    "DelayMarginChart.tolerates": (
        {"delay"},
        "evaluates the chart at a given delay [s]: the delay is the data",
    ),
    "LoopMatrices.input_vector": (
        {"ratio"},
        "evaluates b = B_f + a*B_r at given ratios (broadcasts): the data",
    ),
    "StabilityChart.draw": (
        {"ax"},
        "overlay helper: the (required) Axes drawn into is its data",
    ),
    "Manoeuvre.draw_gates": (
        {"ax"},
        "overlay helper: the (required) Axes drawn into is its data",
    ),
    "LateralController.subset": ({"idx"}, "selects the runs idx: the data"),
    "PurePursuit.distance": ({"speed"}, "evaluates L_d at given speeds: the data"),
    "compare": (
        {"manoeuvre", "controllers"},
        "the course and the controllers are what is compared: the data",
    ),
}

# Check 2: a ``plot`` method may take ``ax`` as its first, positional
# parameter (spec: ``.plot(ax=None, ...)``); everywhere else ``ax`` is an
# option and keyword-only, as in python-control's plot functions.
PLOT_AX_POSITIONAL = "ax"

# Check 4: callables that may take **kwargs (the check fails for any other).
# Key: public label; value: reason. Each one is also called with a bogus
# keyword in test_kwargs_exceptions_reject_unknown (see _kwargs_calls).
KWARGS_EXCEPTIONS = {
    "StabilityChart.draw": (
        "forwards the styling keywords of StabilityChart.plot and checks the"
        " names itself"
    ),
    "simulate": (
        "accepts the deprecated Vehicle form (speed=, model=, tyre=,"
        " steering_lag=, actuator_time_constant=, gains=) until 0.4, with a"
        " FutureWarning; rejects any other name"
    ),
    "simulate_batch": "as simulate",
    "compare": (
        "accepts the deprecated Vehicle form (speed=, steering_lag=,"
        " actuator_time_constant=) until 0.4, with a FutureWarning"
    ),
    "steering_actuator": (
        "accepts the deprecated time_constant= until 0.4, with a FutureWarning"
    ),
    "closed_loop_system": (
        "accepts the deprecated actuator_time_constant= until 0.4, with a"
        " FutureWarning; rejects any other name"
    ),
    "reference_initial_state": "as closed_loop_system",
    "simulate_reference": "as closed_loop_system",
}

# Spec 0.2: exact positional parameters and required keyword-only parameters
# of the analysis functions (VK = the Vehicle convenience keywords).
VK = ("speed", "curvature", "model")
SPEC_SIGNATURES = {
    "linearize": (("plant",), VK),
    "closed_loop": (("plant", "gains"), VK),
    "affine_characteristic_polynomial": (("plant",), ("ratio", *VK)),
    "characteristic_polynomial_coefficients": (("plant", "gains"), VK),
    "is_stable": (("plant", "gains"), VK),
    "stability_boundaries": (("plant",), ("ratio", "omega", *VK)),
    "stability_chart": (("plant",), ("ratio", "k1", "k2", "pole", *VK)),
    "double_root_gains": (("plant",), ("ratio", "pole", *VK)),
    "gain_loop": (("plant", "gains"), VK),
    "gain_locus": (("plant", "gains"), ("scale", *VK)),
    "parameter_locus": (
        ("plant", "gains"),
        ("parameter", "values", "redesign_pole", "design_model", *VK),
    ),
    "compare_linear_nonlinear": (
        ("plant", "gains"),
        ("initial_state", "initial_errors", "duration", "feedforward", "dt", *VK),
    ),
    "simulate": (
        ("plant", "path", "controller"),
        (
            "initial_state",
            "duration",
            "delay",
            "feedforward",
            "dt",
            "t_eval",
            "method",
            "rtol",
            "atol",
        ),
    ),
    "simulate_batch": (
        ("plant", "path", "controllers"),
        ("initial_state", "duration", "delay", "chunk_size", "client", "progress"),
    ),
}
SPEC_TOP_LEVEL = (
    *SPEC_SIGNATURES,
    "Vehicle",
    "LateralPlant",
    "SteeringGains",
    "AffinePolynomial",
    "StabilityBoundary",
    "StabilityBoundaries",
    "BoundaryCurve",
    "StabilityChart",
    "SimulationResult",
    "UncontrollableError",
    "SingularStateError",
    "AmbiguousProjectionError",
)
SPEC_REMOVED = ("BatchResult",)
# Spec 0.2: attributes (fields, properties, methods) of the spec's classes,
# and those that are gone.
SPEC_ATTRIBUTES = {
    "LateralPlant": (
        "vehicle",
        "speed",
        "curvature",
        "model",
        "linearize",
        "input_gain_factor",
    ),
    "SteeringGains": ("k1", "k2", "ratio", "K", "K_paper", "from_K"),
    "AffinePolynomial": (
        "open_loop",
        "n1",
        "n2",
        "order",
        "coefficients",
        "evaluate",
    ),
    "StabilityBoundaries": ("real_root", "complex_root", "lines"),
    "BoundaryCurve": ("omega", "k1", "k2"),
    "StabilityChart": ("k1", "k2", "stable", "stable_fraction", "boundaries"),
    "SimulationResult": ("t", "x", "y", "psi", "e", "theta", "delta_f", "delta_r"),
}
SPEC_REMOVED_ATTRIBUTES = {"SteeringGains": ("matrix",)}
SPEC_PAPER = (
    "PAPER_VEHICLE",
    "PAPER_CURVATURES",
    "paper_figure_panels",
    "plot_paper_figure",
    "make_figure",
    "gains_table",
    "reproduce",
)


# --------------------------------------------------------------------------
# The public surface
# --------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Entry:
    """One public callable: label, object, kind and the owning class."""

    label: str
    obj: object
    kind: str  # "function", "class", "method", "classmethod", "staticmethod"
    owner: type | None = None


def _import_surface(name):
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name == name:  # the subpackage does not exist (yet)
            return None
        raise


def _is_ours(obj):
    return getattr(obj, "__module__", "").partition(".")[0] == PACKAGE


def _public_methods(cls):
    """Public methods defined in ``cls`` or its fws_control bases."""
    seen = set()
    for klass in cls.__mro__:
        if not _is_ours(klass):
            continue
        for name, raw in vars(klass).items():
            if name.startswith("_") or name in seen:
                continue
            seen.add(name)
            if isinstance(raw, classmethod):
                yield name, raw.__func__, "classmethod"
            elif isinstance(raw, staticmethod):
                yield name, raw.__func__, "staticmethod"
            elif inspect.isfunction(raw):
                yield name, raw, "method"


@cache
def public_api():
    """All public callables, each once (first public label wins)."""
    entries, seen = [], set()

    def add(label, obj, kind, owner=None):
        if id(obj) in seen:  # re-exported, or an inherited method: once
            return
        seen.add(id(obj))
        entries.append(Entry(label, obj, kind, owner))

    for modname in SURFACE_MODULES:
        mod = _import_surface(modname)
        if mod is None:
            continue
        prefix = "" if modname == PACKAGE else modname.split(".", 1)[1] + "."
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name, None)
            if inspect.isclass(obj):
                if issubclass(obj, BaseException):
                    continue  # exceptions: constructor is Exception's
                add(prefix + name, obj, "class")
                for mname, func, kind in _public_methods(obj):
                    add(f"{prefix}{name}.{mname}", func, kind, obj)
            elif inspect.isfunction(obj) or (callable(obj) and _is_ours(obj)):
                add(prefix + name, obj, "function")
    return tuple(entries)


def _label_key(entry):
    """Label without the subpackage prefix (for the exception tables)."""
    label = entry.label
    for prefix in ("simulation.", "paper."):
        if label.startswith(prefix):
            return label[len(prefix) :]
    return label


def _exception_keys(entry):
    """Keys under which an exception for ``entry`` may be listed.

    A method is also found under any base class that defines it (an override
    of ``Path.placed`` in ``Arc`` shares ``Path.placed``'s exception).
    """
    keys = [_label_key(entry)]
    if entry.owner is not None:
        name = entry.label.rsplit(".", 1)[1]
        keys += [f"{base.__name__}.{name}" for base in entry.owner.__mro__]
    return keys


def parameters(entry):
    """Signature parameters without ``self``/``cls``."""
    params = list(inspect.signature(entry.obj).parameters.values())
    if entry.kind in ("method", "classmethod") and params:
        params = params[1:]
    return params


def _where(entry):
    """``label (module:line)`` for the assertion messages."""
    obj = entry.obj
    try:
        src = inspect.getsourcefile(obj)
        line = inspect.getsourcelines(obj)[1]
        rel = Path(src).resolve().relative_to(PACKAGE_DIR.parent)
        return f"{entry.label} ({rel}:{line})"
    except (TypeError, OSError, ValueError):
        return entry.label


def _report(violations, what):
    return f"{len(violations)} {what}:\n  " + "\n  ".join(sorted(violations))


def test_public_api_found():
    labels = {e.label for e in public_api()}
    assert {"linearize", "Vehicle", "SteeringGains"} <= labels, sorted(labels)


# --------------------------------------------------------------------------
# Spec conformance of the names and the analysis signatures
# --------------------------------------------------------------------------


def test_spec_names_exported():
    missing = [n for n in SPEC_TOP_LEVEL if n not in fws.__all__]
    removed = [n for n in SPEC_REMOVED if n in fws.__all__ or hasattr(fws, n)]
    paper = _import_surface(f"{PACKAGE}.paper")
    if paper is None:
        missing.append("fws_control.paper (subpackage)")
    else:
        missing += [f"paper.{n}" for n in SPEC_PAPER if n not in paper.__all__]
    sim = _import_surface(f"{PACKAGE}.simulation")
    if not hasattr(sim, "__path__"):
        missing.append("fws_control.simulation is a module, spec: subpackage")
    problems = [f"missing: {n}" for n in missing]
    problems += [f"removed in 0.2 but still exported: {n}" for n in removed]
    assert not problems, _report(problems, "differences from the spec's names")


def _attribute_names(cls):
    fields = {f.name for f in dataclasses.fields(cls)}
    return fields | set(dir(cls)) if dataclasses.is_dataclass(cls) else set(dir(cls))


def test_spec_class_attributes():
    problems = []
    for cls_name, attrs in SPEC_ATTRIBUTES.items():
        cls = getattr(fws, cls_name, None)
        if not inspect.isclass(cls):
            problems.append(f"{cls_name}: not exported")
            continue
        names = _attribute_names(cls)
        problems += [f"{cls_name}.{a}: missing" for a in attrs if a not in names]
    for cls_name, attrs in SPEC_REMOVED_ATTRIBUTES.items():
        cls = getattr(fws, cls_name, None)
        if inspect.isclass(cls):
            names = _attribute_names(cls)
            problems += [
                f"{cls_name}.{a}: removed in 0.2 but present"
                for a in attrs
                if a in names
            ]
    assert not problems, _report(problems, "differences from the spec's classes")


def test_spec_analysis_signatures():
    problems = []
    for name, (positional, keywords) in SPEC_SIGNATURES.items():
        func = getattr(fws, name, None)
        if func is None:
            problems.append(f"{name}: not exported")
            continue
        params = inspect.signature(func).parameters
        pos = tuple(
            p.name
            for p in params.values()
            if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
        )
        if pos != positional:
            problems.append(f"{name}: positional {pos}, spec {positional}")
        for kw in keywords:
            if kw not in params:
                problems.append(f"{name}: no keyword {kw!r}")
            elif params[kw].kind is not inspect.Parameter.KEYWORD_ONLY:
                problems.append(f"{name}: {kw!r} is not keyword-only")
        for kw in VK if name not in ("simulate", "simulate_batch") else ():
            if kw in params and params[kw].default is not None:
                problems.append(
                    f"{name}: {kw}= defaults to {params[kw].default!r}, spec None"
                )
    assert not problems, _report(problems, "differences from the spec signatures")


# --------------------------------------------------------------------------
# 1. First parameter
# --------------------------------------------------------------------------


def _first_parameter_exception(entry):
    """The first parameter FIRST_PARAMETER_EXCEPTIONS allows ``entry``, or None."""
    return FIRST_PARAMETER_EXCEPTIONS.get(_label_key(entry), (None, ""))[0]


def test_first_parameter_names_the_subject():
    violations = []
    for entry in public_api():
        if entry.kind == "class" and _label_key(entry) in RECORD_CLASSES:
            continue  # first field is data, e.g. Vehicle(wheelbase)
        if entry.kind not in ("function", "class"):
            continue  # methods: the subject is self; see check 2
        params = parameters(entry)
        if not params:
            continue
        first = params[0]
        if first.kind in (first.VAR_POSITIONAL, first.VAR_KEYWORD):
            violations.append(f"{_where(entry)}: first parameter is {first}")
        elif first.kind is first.KEYWORD_ONLY:
            continue  # no positional parameter at all
        elif (
            first.name not in FIRST_PARAMETER_NAMES
            and first.name != _first_parameter_exception(entry)
        ):
            violations.append(
                f"{_where(entry)}: first parameter {first.name!r} not in "
                f"{sorted(FIRST_PARAMETER_NAMES)}"
            )
    assert not violations, _report(violations, "functions with a bad first parameter")


# --------------------------------------------------------------------------
# 2. Scalar options are keyword-only
# --------------------------------------------------------------------------


def test_options_are_keyword_only():
    violations = []
    for entry in public_api():
        key = _label_key(entry)
        if entry.kind == "class" and key in RECORD_CLASSES:
            continue
        allowed = set(POSITIONAL_DATA_NAMES)
        for k in _exception_keys(entry):
            allowed |= POSITIONAL_EXCEPTIONS.get(k, (set(), ""))[0]
        params = parameters(entry)
        if entry.kind in ("function", "class") and params:
            first, special = params[0].name, _first_parameter_exception(entry)
            if first in FIRST_PARAMETER_NAMES or first == special:
                allowed.add(first)
        if entry.kind == "method" and entry.label.endswith(".plot") and params:
            if params[0].name == PLOT_AX_POSITIONAL:
                allowed.add(PLOT_AX_POSITIONAL)
        for p in params:
            if p.kind is p.VAR_POSITIONAL:
                violations.append(f"{_where(entry)}: *{p.name} (positional catch-all)")
            elif (
                p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
                and p.name not in allowed
            ):
                violations.append(
                    f"{_where(entry)}: {p.name!r} is positional, must be keyword-only"
                )
    assert not violations, _report(violations, "positional options")


# --------------------------------------------------------------------------
# 3. numpydoc: every parameter documented, Examples present
# --------------------------------------------------------------------------


def _numpydoc(entry):
    npd = pytest.importorskip("numpydoc.docscrape")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if entry.kind == "class":
            return npd.ClassDoc(entry.obj)
        return npd.FunctionDoc(entry.obj)


def _documented_names(doc, sections=("Parameters", "Other Parameters")):
    names = set()
    for section in sections:
        for param in doc[section]:
            # numpydoc allows "a, b : float" (and "*args", "**kwargs")
            for name in param.name.split(","):
                names.add(name.strip().lstrip("*"))
    return names


def test_parameters_documented():
    violations = []
    for entry in public_api():
        try:
            doc = _numpydoc(entry)
        except Exception as exc:  # a docstring numpydoc cannot parse
            violations.append(f"{_where(entry)}: numpydoc error {exc!r}")
            continue
        documented = _documented_names(doc)
        if entry.kind == "class" and dataclasses.is_dataclass(entry.obj):
            # a dataclass's constructor parameters are its fields, which
            # numpydoc documents as Attributes
            documented |= _documented_names(doc, ("Attributes",))
        init = vars(entry.obj).get("__init__") if entry.kind == "class" else None
        if inspect.isfunction(init) and init.__doc__:
            # numpydoc also allows the constructor's parameters in __init__
            documented |= _documented_names(_numpydoc(Entry("", init, "method")))
        for p in parameters(entry):
            if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                continue
            if p.name not in documented:
                violations.append(f"{_where(entry)}: parameter {p.name!r} undocumented")
    assert not violations, _report(violations, "undocumented parameters")


def test_no_stale_parameter_docs():
    """The converse: a documented parameter must exist (catches renames)."""
    violations = []
    for entry in public_api():
        try:
            doc = _numpydoc(entry)
        except Exception:
            continue  # reported by test_parameters_documented
        names = {p.name for p in parameters(entry)}
        for name in _documented_names(doc) - names:
            if not name.isidentifier():
                violations.append(
                    f"{_where(entry)}: free text parsed as a parameter: {name!r}"
                )
            else:
                violations.append(
                    f"{_where(entry)}: documents {name!r}, not in the signature"
                )
    assert not violations, _report(violations, "stale parameter docs")


@pytest.mark.parametrize("kind", ["function", "class"])
def test_examples_section(kind):
    """Every public function (and class) docstring has an Examples section."""
    violations = []
    for entry in public_api():
        if entry.kind != kind:
            continue
        try:
            doc = _numpydoc(entry)
        except Exception as exc:
            violations.append(f"{_where(entry)}: numpydoc error {exc!r}")
            continue
        if not "".join(doc["Examples"]).strip():
            violations.append(f"{_where(entry)}: no Examples section")
    assert not violations, _report(violations, "missing Examples")


# --------------------------------------------------------------------------
# 4. Unknown keyword arguments are rejected
# --------------------------------------------------------------------------


def test_no_silent_kwargs():
    violations = []
    for entry in public_api():
        params = parameters(entry)
        var_kw = [p for p in params if p.kind is p.VAR_KEYWORD]
        if not var_kw:
            try:
                inspect.signature(entry.obj).bind_partial(bogus_kw=1)
            except TypeError:
                continue
            violations.append(f"{_where(entry)}: binds bogus_kw=1")
        elif not set(_exception_keys(entry)) & set(KWARGS_EXCEPTIONS):
            violations.append(
                f"{_where(entry)}: accepts **{var_kw[0].name} "
                "(list it in KWARGS_EXCEPTIONS with a reason, or remove it)"
            )
    assert not violations, _report(violations, "callables accepting **kwargs")


def _kwargs_calls():
    """KWARGS_EXCEPTIONS label -> call with ``bogus_kw=1``."""

    def draw():
        veh, plant, _ = _objects()
        chart = fws.stability_chart(plant, ratio=-1.0, k1=[0.0, 1.0], k2=[0.0, 1.0])
        _, ax = plt.subplots()
        chart.draw(ax, bogus_kw=1)

    def simulate(batch=False):
        veh, _, _ = _objects()
        run = fws.simulate_batch if batch else fws.simulate
        run(fws.LateralPlant(veh, speed=5.0), fws.Straight(),
            fws.SteeringGains(0.1, 0.5, ratio=0.0), initial_state=(0.0, 1.0, 0.0),
            duration=1.0, bogus_kw=1)  # fmt: skip

    def compare():
        veh, _, _ = _objects()
        fws.compare(fws.LateralPlant(veh, speed=5.0), fws.constant_radius(),
                    {"paper": fws.SteeringGains(0.05, 0.5, ratio=0.0)},
                    bogus_kw=1)  # fmt: skip

    def steering_actuator():
        veh, _, _ = _objects()
        fws.steering_actuator(veh, bogus_kw=1)

    def reference(name):
        veh, _, _ = _objects()
        g = fws.SteeringGains(0.1, 0.5, ratio=0.0)
        kw = dict(speed=5.0, bogus_kw=1)
        if name == "closed_loop_system":
            fws.closed_loop_system(veh, fws.Straight(), g, **kw)
        elif name == "reference_initial_state":
            fws.simulation.reference_initial_state(
                veh, fws.Straight(), g, initial_state=(0.0, 1.0, 0.0), **kw
            )
        else:
            fws.simulation.simulate_reference(
                veh, fws.Straight(), g, initial_state=(0.0, 1.0, 0.0),
                duration=1.0, **kw,
            )  # fmt: skip

    return {
        "closed_loop_system": lambda: reference("closed_loop_system"),
        "reference_initial_state": lambda: reference("reference_initial_state"),
        "simulate_reference": lambda: reference("simulate_reference"),
        "StabilityChart.draw": draw,
        "simulate": simulate,
        "simulate_batch": lambda: simulate(batch=True),
        "compare": compare,
        "steering_actuator": steering_actuator,
    }


@pytest.mark.parametrize("label", sorted(KWARGS_EXCEPTIONS))
def test_kwargs_exceptions_reject_unknown(label):
    """A function listed as taking **kwargs still rejects unknown names."""
    try:
        with pytest.raises(TypeError, match="bogus_kw"):
            _kwargs_calls()[label]()
    finally:
        plt.close("all")


def test_exception_tables_have_reasons():
    for table in (RECORD_CLASSES, KWARGS_EXCEPTIONS):
        assert all(isinstance(r, str) and r.strip() for r in table.values())
    assert all(r.strip() for _, r in POSITIONAL_EXCEPTIONS.values())
    assert all(r.strip() for _, r in FIRST_PARAMETER_EXCEPTIONS.values())


@cache
def _objects():
    """Small real objects to call the API on."""
    veh = PAPER_VEHICLE
    plant = fws.LateralPlant(veh, speed=5.0)
    gains = fws.SteeringGains(k1=0.2, k2=0.9, ratio=-1.0)
    return veh, plant, gains


def _analysis_calls():
    """Each spec function with valid arguments (the call is not executed)."""
    veh, plant, g = _objects()
    return {
        "linearize": ((plant,), {}),
        "closed_loop": ((plant, g), {}),
        "affine_characteristic_polynomial": ((plant,), {"ratio": -1.0}),
        "characteristic_polynomial_coefficients": ((plant, g), {}),
        "is_stable": ((plant, g), {}),
        "stability_boundaries": ((plant,), {"ratio": -1.0}),
        "stability_chart": ((plant,), {"ratio": -1.0}),
        "double_root_gains": ((plant,), {"ratio": -1.0, "pole": -1.0}),
        "gain_loop": ((plant, g), {}),
        "gain_locus": ((plant, g), {}),
        "parameter_locus": ((plant, g), {"parameter": "speed", "values": [1.0]}),
        "compare_linear_nonlinear": ((plant, g), {"duration": 1.0}),
        "simulate": (
            (fws.LateralPlant(veh, speed=5.0), fws.Straight(), g),
            {"initial_state": (0.0, 1.0, 0.0), "duration": 1.0},
        ),
        "simulate_batch": (
            (fws.LateralPlant(veh, speed=5.0), fws.Straight(), g),
            {"initial_state": (0.0, 1.0, 0.0), "duration": 1.0},
        ),
    }


@pytest.mark.parametrize("name", sorted(SPEC_SIGNATURES))
def test_analysis_call_rejects_unknown_keyword(name):
    func = getattr(fws, name, None)
    if func is None:
        pytest.fail(f"fws.{name} is not exported (spec 0.2)")
    args, kwargs = _analysis_calls()[name]
    # a real call: a decorator with **kwargs would hide the keyword from a
    # signature check but not from this
    with pytest.raises(TypeError, match="bogus_kw"):
        func(*args, **kwargs, bogus_kw=1)


# --------------------------------------------------------------------------
# 5. Plots: accept ax, return control.ControlPlot
# --------------------------------------------------------------------------


def _is_plot(entry):
    name = entry.label.rsplit(".", 1)[-1]
    return name == "plot" or name.startswith("plot_")


@cache
def _plot_factories():
    """Label -> zero-argument factory of ``f(**kwargs)`` calling the plot."""
    veh, plant, g = _objects()
    k = np.linspace(-1.0, 1.0, 21)

    def chart():
        c = fws.stability_chart(plant, ratio=-1.0, k1=k, k2=k)
        return c.plot

    def simulation():
        res = fws.simulate(
            fws.LateralPlant(veh, speed=5.0),
            fws.Straight(),
            g,
            initial_state=(0.0, 1.0, 0.0),
            duration=2.0,
        )
        return res.plot

    def comparison():
        return fws.compare_linear_nonlinear(plant, g, duration=2.0).plot

    def delay_chart():
        fast = fws.LateralPlant(veh, speed=20.0)
        return fws.delay_margin_chart(fast, ratio=[-1.0, 0.5], pole=[-1.0, -2.0]).plot

    def turning_radius():
        return lambda **kw: fws.plot_turning_radius(veh, **kw)

    def paper_figure():
        paper = importlib.import_module(f"{PACKAGE}.paper")
        return lambda **kw: paper.plot_paper_figure(2, npoints=21, **kw)

    def actuator_figure():
        paper = importlib.import_module(f"{PACKAGE}.paper")
        return lambda **kw: paper.plot_actuator(quick=True, **kw)

    def controller_comparison():
        m = fws.constant_radius(radius=20.0, turns=0.1)
        g = fws.SteeringGains(0.05, 0.5, ratio=0.0)
        return fws.compare(fws.LateralPlant(veh, speed=5.0), m, {"paper": g}).plot

    def design_limit():
        return fws.kinematic_design_limit(
            fws.vehicles.BMW_320I, ratio=0.0, pole=-1.0, speeds=[5.0, 20.0, 40.0]
        ).plot

    def robust():
        return fws.robust_region(
            veh, ratio=0.0, box={"speed": (10.0, 30.0)}, k1=k, k2=k
        ).plot

    def most_stable():
        lagged = fws.LateralPlant(veh, speed=20.0, steering_lag=0.27)
        return fws.most_stable_gains(lagged, delay=0.24, ratio=0.0, grid=4).plot

    def pareto():
        fast = fws.LateralPlant(veh, speed=20.0)
        return fws.pareto_front(fast, delay=0.24, points=2, grid=4).plot

    def schedule():
        return fws.GainSchedule(
            speeds=[10.0, 20.0], k1=[0.01, 0.004], k2=[0.3, 0.2], ratio=[0.0, 0.0]
        ).plot

    def speed_certificate():
        sch = fws.GainSchedule(
            speeds=[10.0, 20.0], k1=[0.027, 0.00675], k2=[0.54, 0.27], ratio=[0.0, 0.0]
        )
        return fws.speed_certificate(veh, sch, rate=0.5, cells=2).plot

    def rear_band():
        return fws.rear_limit_band(
            veh, front_angle=np.linspace(0.02, 0.6, 20), rear_limit=0.05
        ).plot

    def step_steer():
        return fws.step_steer(
            fws.vehicles.BMW_320I, speed=20.0, amplitude=0.01, duration=1.0
        ).plot

    def frequency_response():
        return fws.steering_frequency_response(
            fws.vehicles.BMW_320I, speed=20.0, omega=[1.0, 5.0, 20.0]
        ).plot

    def circle():
        return fws.steady_state_circle(
            fws.vehicles.BMW_320I, lateral_acceleration=[1.0, 5.0]
        ).plot

    return {
        "StepSteerResponse.plot": step_steer,
        "SteeringFrequencyResponse.plot": frequency_response,
        "SteadyStateCircle.plot": circle,
        "RearLimitBand.plot": rear_band,
        "ParetoFront.plot": pareto,
        "GainSchedule.plot": schedule,
        "SpeedCertificate.plot": speed_certificate,
        "RobustRegion.plot": robust,
        "MostStableDesign.plot": most_stable,
        "KinematicDesignLimit.plot": design_limit,
        "ControllerComparison.plot": controller_comparison,
        "StabilityChart.plot": chart,
        "DelayMarginChart.plot": delay_chart,
        "SimulationResult.plot": simulation,
        "LinearNonlinearComparison.plot": comparison,
        "plot_turning_radius": turning_radius,
        "paper.plot_paper_figure": paper_figure,
        "paper.plot_actuator": actuator_figure,
    }


def test_plot_signatures():
    violations = []
    factories = _plot_factories()
    for entry in public_api():
        if not _is_plot(entry):
            continue
        params = {p.name: p for p in parameters(entry)}
        if "ax" not in params:
            violations.append(f"{_where(entry)}: no 'ax' keyword")
        if entry.label not in factories:
            violations.append(f"{_where(entry)}: no factory in _plot_factories()")
    assert not violations, _report(violations, "plot signature problems")


def _plot_labels():
    return sorted(_plot_factories())


def _flat_axes(cplt):
    return [ax for ax in np.asarray(cplt.axes, dtype=object).ravel() if ax]


@pytest.mark.parametrize("label", _plot_labels())
def test_plot_returns_controlplot(label):
    entry = next((e for e in public_api() if e.label == label), None)
    # a factory for a name that is no longer public is stale: fail, do not skip
    assert entry is not None, f"{label} has a plot factory but is not public"
    plot = _plot_factories()[label]()
    try:
        cplt = plot()
        assert isinstance(cplt, ct.ControlPlot), (
            f"{label}() returned {type(cplt).__name__}, not control.ControlPlot"
        )
        axes = _flat_axes(cplt)
        assert axes, f"{label}(): ControlPlot without axes"
        # re-plot into the axes just made; ``ax`` may be one Axes or an array
        ax = axes[0] if len(axes) == 1 else cplt.axes
        cplt2 = plot(ax=ax)
        assert isinstance(cplt2, ct.ControlPlot), (
            f"{label}(ax=...) returned {type(cplt2).__name__}"
        )
        assert {id(a) for a in _flat_axes(cplt2)} <= {id(a) for a in axes}, (
            f"{label}(ax=...) drew outside the given axes"
        )
    finally:
        plt.close("all")


# --------------------------------------------------------------------------
# 6./7. Import graph (static, with ast)
# --------------------------------------------------------------------------


#: Old module paths kept for one release as shims that warn on import.
DEPRECATED_MODULES = {
    "fws_control.models",
    "fws_control.comparison",
    "fws_control.design",
}


def _module_name(path):
    rel = path.resolve().relative_to(PACKAGE_DIR.parent).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


@cache
def _modules():
    """Module name -> (path, is_package) for every fws_control/**/*.py."""
    out = {}
    for path in sorted(PACKAGE_DIR.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        out[_module_name(path)] = (path, path.name == "__init__.py")
    return out


def _is_type_checking(node):
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _walk_imports(tree):
    """Yield (import node, lazy) outside ``if TYPE_CHECKING:`` blocks."""

    def visit(nodes, lazy):
        for child in nodes:
            if isinstance(child, ast.If) and _is_type_checking(child):
                yield from visit(child.orelse, lazy)  # the else branch runs
                continue
            if isinstance(child, ast.Import | ast.ImportFrom):
                yield child, lazy
            inner = isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef)
            yield from visit(ast.iter_child_nodes(child), lazy or inner)

    yield from visit(tree.body, False)


@dataclasses.dataclass(frozen=True)
class Import:
    """One internal import: importer, target module, names, line, lazy."""

    importer: str
    target: str  # the module executed (a package or a module)
    names: tuple[str, ...]  # imported names (empty for ``import x``)
    line: int
    lazy: bool
    submodule: bool  # target was named as ``from pkg import target``


@cache
def internal_imports():
    """All imports of fws_control modules by fws_control modules."""
    modules = _modules()
    out = []
    for mod, (path, is_pkg) in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        here = mod.split(".") if is_pkg else mod.split(".")[:-1]
        for node, lazy in _walk_imports(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.split(".")[0] == PACKAGE:
                        out.append(
                            Import(mod, alias.name, (), node.lineno, lazy, False)
                        )
                continue
            if node.level:
                base = here[: len(here) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != PACKAGE:
                continue
            names = tuple(a.name for a in node.names)
            subs = [n for n in names if f"{target}.{n}" in modules]
            for n in subs:
                out.append(Import(mod, f"{target}.{n}", (), node.lineno, lazy, True))
            rest = tuple(n for n in names if n not in subs)
            if rest:
                out.append(Import(mod, target, rest, node.lineno, lazy, False))
            elif not _is_ancestor(target, mod):
                # ``from pkg import sub`` runs pkg/__init__ unless pkg is
                # already being imported (an ancestor of the importer)
                out.append(Import(mod, target, (), node.lineno, lazy, False))
    return tuple(out)


def _is_ancestor(pkg, mod):
    return mod.startswith(pkg + ".")


def _graph(include_lazy):
    """Module -> set of modules executed by its imports.

    Importing ``a.b.c`` from outside package ``a.b`` first runs
    ``a/b/__init__``, so that edge is added too; packages that are ancestors
    of the importer are already being imported and add no edge.
    """
    graph = {m: set() for m in _modules()}
    for imp in internal_imports():
        if imp.lazy and not include_lazy:
            continue
        parts = imp.target.split(".")
        for i in range(2, len(parts)):
            pkg = ".".join(parts[:i])
            if not _is_ancestor(pkg, imp.importer) and pkg != imp.importer:
                graph[imp.importer].add(pkg)
        if imp.target != imp.importer and imp.target in graph:
            graph[imp.importer].add(imp.target)
    return graph


def _cycles(graph):
    """Strongly connected components with a cycle (Tarjan), as paths."""
    index, low, stack, on, sccs = {}, {}, [], set(), []

    def strong(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph[v]:
                sccs.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            strong(v)

    paths = []
    for comp in sccs:  # one concrete cycle through the first member
        start, members = comp[0], set(comp)
        prev, queue = {start: None}, [start]
        found = None
        while queue and found is None:
            v = queue.pop(0)
            for w in sorted(graph[v] & members):
                if w == start:
                    found = v
                    break
                if w not in prev:
                    prev[w] = v
                    queue.append(w)
        path, v = [start], found
        while v is not None and v != start:
            path.append(v)
            v = prev[v]
        path = [start, *reversed(path[1:]), start]
        paths.append(f"{' -> '.join(path)}   (component: {', '.join(comp)})")
    return paths


def _edge_lines(cycle_text, include_lazy):
    """Where the edges of a cycle are (importer:line -> target)."""
    path = cycle_text.split("   ")[0].split(" -> ")
    out = []
    for a, b in zip(path, path[1:], strict=False):
        for imp in internal_imports():
            if imp.importer != a or (imp.lazy and not include_lazy):
                continue
            if imp.target == b or imp.target.startswith(b + "."):
                lazy = " (in a function)" if imp.lazy else ""
                out.append(f"      {a}:{imp.line} -> {imp.target}{lazy}")
                break
    return out


def test_internal_imports_resolve():
    """Every internal import names an existing module and existing names.

    Keeps the graph below complete, and catches function-level imports left
    behind by a move (they fail only when the function runs).
    """
    modules = _modules()
    violations = []
    for imp in internal_imports():
        where = f"{imp.importer}:{imp.line}"
        if imp.target not in modules:
            violations.append(f"{where}: no module {imp.target}")
            continue
        if not imp.names:
            continue
        try:
            module = importlib.import_module(imp.target)
        except Exception as exc:
            violations.append(f"{where}: importing {imp.target} fails: {exc!r}")
            continue
        for name in imp.names:
            if name != "*" and not hasattr(module, name):
                violations.append(f"{where}: {imp.target} has no {name!r}")
    assert not violations, _report(violations, "unresolved internal imports")


def test_no_import_cycle_at_import_time():
    """Module-level imports (what runs on ``import``) form a DAG."""
    cycles = _cycles(_graph(include_lazy=False))
    text = [c + "\n" + "\n".join(_edge_lines(c, False)) for c in cycles]
    assert not cycles, _report(text, "import cycles at import time")


def test_no_import_cycle_including_lazy_imports():
    """Function-level imports count too.

    A lazy import breaks an import-time cycle but not the dependency: the
    design's layering ("a module knows only the modules above it") is a DAG
    whether an import sits at the top or inside a function. Only
    ``if TYPE_CHECKING:`` imports (never executed) are left out.
    """
    cycles = _cycles(_graph(include_lazy=True))
    text = [c + "\n" + "\n".join(_edge_lines(c, True)) for c in cycles]
    assert not cycles, _report(text, "import cycles counting function-level imports")


def _private(name):
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def test_no_private_imports_from_peers():
    """No ``from .peer import _name``, no import of a private module.

    A private module (``_validation``) may be imported only by its own
    package's ``__init__`` (which re-exports from it; it is the module's
    parent, not a peer). Siblings inside the same subpackage are peers.
    """
    modules = _modules()
    violations = []
    for imp in internal_imports():
        where = f"{imp.importer}:{imp.line}"
        for name in imp.names:
            if _private(name):
                violations.append(
                    f"{where}: imports private name {name!r} from {imp.target}"
                )
        parts = imp.target.split(".")
        for i in range(1, len(parts)):
            if _private(parts[i]):
                owner = ".".join(parts[:i])
                private_mod = ".".join(parts[: i + 1])
                parent_init = imp.importer == owner and modules[owner][1]
                if not parent_init:
                    violations.append(f"{where}: imports private module {private_mod}")
                break
    assert not violations, _report(violations, "private imports")


# --------------------------------------------------------------------------
# 8. fws_control does not import fws_control.paper
# --------------------------------------------------------------------------


def test_package_does_not_import_paper():
    code = "import fws_control, sys; print('fws_control.paper' in sys.modules)"
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=PACKAGE_DIR.parent,
        timeout=60,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False", (
        "import fws_control imports fws_control.paper (only the CLI may)"
    )


# --------------------------------------------------------------------------
# 9. Every module has __all__ and its names exist
# --------------------------------------------------------------------------


def test_every_module_has_all():
    violations = []
    for mod in _modules():
        try:
            with warnings.catch_warnings():
                # a renamed module's old path warns on import (tested in
                # tests/test_renames.py); its __all__ is checked here
                if mod in DEPRECATED_MODULES:
                    warnings.simplefilter("ignore", FutureWarning)
                module = importlib.import_module(mod)
        except Exception as exc:
            violations.append(f"{mod}: cannot be imported: {exc!r}")
            continue
        names = getattr(module, "__all__", None)
        if names is None:
            violations.append(f"{mod}: no __all__")
            continue
        if isinstance(names, str) or not all(isinstance(n, str) for n in names):
            violations.append(f"{mod}: __all__ is not a sequence of str")
            continue
        for name in names:
            if not hasattr(module, name):
                violations.append(f"{mod}: __all__ lists {name!r}, not defined")
        dups = {n for n in names if list(names).count(n) > 1}
        if dups:
            violations.append(f"{mod}: __all__ repeats {sorted(dups)}")
    assert not violations, _report(violations, "__all__ problems")
