"""The compiled engine's kernels specialised to the features a call uses.

The kernels of :mod:`~fws_control.simulation.compiled` serve every call:
an input delay, the dynamic model, a controller's compiled law and a
varying speed are branches of one right-hand side, which numba inlines
into every step, dense output and event function of a driver. Compiling
them all for a call that uses none (the paper's kinematic loop) cost most
of its first compilation.

:func:`kernels` returns the top kernels (the drivers, the signals and the
peaks) of a set of :data:`FEATURES`: copies of the kernels' functions whose
flags (:data:`~fws_control.simulation.compiled_layout.WITH_DELAY` and the
others) are False for the features left out, so that numba prunes those
branches before it compiles anything. Each variant is compiled the first
time a call needs it and kept in numba's on-disk cache under names of its
own (the qualified name with the variant's suffix); a call that uses every
feature runs the kernels themselves. The branches left out are those the
call's parameters switch off, so a variant computes bit for bit what the
full kernels compute for that call.

Each variant is a compilation of the whole engine of its own, so the
compiled engine (:mod:`~fws_control.simulation.compiled`) runs two: the
variant without any feature, for the paper's kinematic loop (measured with
``benchmarks/bench_first_use.py``: 56 instead of 144 s of CPU for its
first ``simulate`` on a busy machine), and the kernels of every feature,
shared by every call that uses one.
"""

from __future__ import annotations

import functools
import types
from collections.abc import Iterable
from typing import Any

import numpy as np

# the modules themselves (not through the package, which imports the
# runners and so this module)
import fws_control.simulation.compiled_dop853 as compiled_dop853
import fws_control.simulation.compiled_drivers as compiled_drivers
import fws_control.simulation.compiled_events as compiled_events
import fws_control.simulation.compiled_loop as compiled_loop
import fws_control.simulation.compiled_peaks as compiled_peaks
import fws_control.simulation.compiled_radau as compiled_radau
import fws_control.simulation.compiled_signals as compiled_signals

from .compilation import jit
from .compiled_laws import Q_LAW
from .compiled_layout import Q_DELAY, Q_DYNAMIC
from .compiled_speed import Q_PROFILE

__all__ = ["FEATURES", "features_of", "kernels", "variant"]

#: The features a variant may leave out, with the flag each one sets.
FEATURES = ("delay", "dynamic", "law", "profile")
_FLAGS = {
    "delay": "WITH_DELAY",
    "dynamic": "WITH_DYNAMIC",
    "law": "WITH_LAW",
    "profile": "WITH_PROFILE",
}

# the modules whose kernels are copied for a variant, in the order they
# import each other (the closed loop first)
_MODULES = (
    compiled_loop,
    compiled_events,
    compiled_dop853,
    compiled_radau,
    compiled_drivers,
    compiled_signals,
    compiled_peaks,
)

# the top kernels of the stages (compiled.STAGES), by their module names
_TOP = (
    "solve_batch",
    "solve_batch_radau",
    "signals_batch",
    "delayed_signals_batch",
    "peaks_batch",
)


def features_of(q: np.ndarray) -> frozenset[str]:
    """The features that the shared parameter vector `q` switches on.

    Parameters
    ----------
    q : ndarray
        A shared parameter vector of
        :func:`~fws_control.simulation.compiled.shared_parameters`.

    Returns
    -------
    frozenset of str
        Names of :data:`FEATURES`.

    Examples
    --------
    >>> import fws_control as fws
    >>> from fws_control.simulation.compiled import curvature_table, shared_parameters
    >>> from fws_control.simulation.compiled_variants import features_of
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> tab = curvature_table(fws.Straight())
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None)
    >>> sorted(features_of(q))
    []
    >>> q = shared_parameters(veh, tab, feedforward=False, time_constant=None,
    ...                       delay=0.1)
    >>> sorted(features_of(q))
    ['delay']
    """
    on = {
        "delay": q[Q_DELAY] > 0.0,
        "dynamic": q[Q_DYNAMIC] != 0.0,
        "law": q[Q_LAW] != 0.0,
        "profile": q[Q_PROFILE] != 0.0,
    }
    return frozenset(name for name, used in on.items() if used)


def _is_kernel(value: Any, module: types.ModuleType) -> bool:
    # a dispatcher of compilation.jit whose function the module defines
    py_func = getattr(value, "py_func", None)
    return (
        py_func is not None
        and hasattr(value, "targetoptions")
        and py_func.__module__ == module.__name__
    )


def _suffix(features: frozenset[str]) -> str:
    # "v" and the initials of the features kept, in the order of FEATURES
    return "v" + "".join(name[0] for name in FEATURES if name in features)


@functools.cache
def _variant(features: frozenset[str]) -> tuple[dict[str, Any], dict[int, Any]]:
    # (the top kernels, the copy of every kernel by the id of the original)
    if features == frozenset(FEATURES):
        return _top({mod: vars(mod) for mod in _MODULES}), {}
    flags = {_FLAGS[name]: name in features for name in FEATURES}
    suffix = _suffix(features)
    # one globals dict per module, filled once every copy exists: numba
    # reads a function's globals when it compiles it, after this
    spaces = {mod: dict(vars(mod)) | flags for mod in _MODULES}
    copies: dict[int, Any] = {}
    for mod in _MODULES:
        for value in vars(mod).values():
            if id(value) in copies or not _is_kernel(value, mod):
                continue
            fn = value.py_func
            clone = types.FunctionType(
                fn.__code__, spaces[mod], fn.__name__, fn.__defaults__, fn.__closure__
            )
            clone.__qualname__ = f"{fn.__qualname__}__{suffix}"
            clone.__doc__ = fn.__doc__
            inline = value.targetoptions.get("inline", "never")
            copies[id(value)] = jit(clone, inline=inline)
    for space in spaces.values():
        for name, value in space.items():
            if id(value) in copies:
                space[name] = copies[id(value)]
    # (the closures of the drivers reach each other through their module's
    # globals, so the copies of solve_batch call the copies of run_impl)
    return _top(spaces), copies


def _top(spaces: dict[types.ModuleType, Any]) -> dict[str, Any]:
    # the top kernels in the modules' (or their copies') globals
    return {
        name: spaces[mod][name]
        for mod in (compiled_drivers, compiled_signals, compiled_peaks)
        for name in _TOP
        if name in spaces[mod]
    }


def kernels(features: Iterable[str]) -> types.SimpleNamespace:
    """The top kernels compiled for the call's `features` only.

    Parameters
    ----------
    features : iterable of str
        Names of :data:`FEATURES` the call uses (:func:`features_of`).

    Returns
    -------
    types.SimpleNamespace
        ``solve_batch``, ``solve_batch_radau``, ``signals_batch``,
        ``delayed_signals_batch`` and ``peaks_batch`` (numba dispatchers,
        compiled on their first call), the same objects for the same
        features.

    Raises
    ------
    ValueError
        For a name not in :data:`FEATURES`.

    Examples
    --------
    >>> from fws_control.simulation.compiled_variants import kernels
    >>> k = kernels([])
    >>> k.solve_batch.py_func.__qualname__.endswith("__v")
    True
    >>> kernels(["delay"]).solve_batch is kernels({"delay"}).solve_batch
    True
    """
    return types.SimpleNamespace(**_variant(_check_features(features))[0])


def variant(kernel: Any, features: Iterable[str]) -> Any:
    """The copy of any kernel of the engine compiled for `features` only.

    :func:`kernels` gives the top kernels; this gives any other one (a step,
    a dense output, the right-hand side) of the same variant, for calling
    it alone: the copy inlines the same copies as the variant's drivers.

    Parameters
    ----------
    kernel : numba dispatcher
        A kernel of the compiled engine's modules (e.g.
        :func:`~fws_control.simulation.compiled.dop853_step`).
    features : iterable of str
        Names of :data:`FEATURES` the call uses.

    Returns
    -------
    numba dispatcher
        The variant's copy (`kernel` itself for every feature).

    Raises
    ------
    ValueError
        For a name not in :data:`FEATURES`, or a `kernel` that is not one of
        the engine's.

    Examples
    --------
    >>> from fws_control.simulation.compiled import dop853_step
    >>> from fws_control.simulation.compiled_variants import variant
    >>> variant(dop853_step, []).py_func.__qualname__
    'dop853_step__v'
    """
    chosen = _check_features(features)
    if chosen == frozenset(FEATURES):
        return kernel
    try:
        return _variant(chosen)[1][id(kernel)]
    except KeyError:
        raise ValueError(
            f"kernel must be a kernel of the compiled engine's modules, got {kernel!r}"
        ) from None


def _check_features(features: Iterable[str]) -> frozenset[str]:
    chosen = frozenset(features)
    unknown = chosen - set(FEATURES)
    if unknown:
        raise ValueError(f"features must be in {FEATURES}, got {sorted(unknown)}")
    return chosen
