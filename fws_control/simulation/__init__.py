r"""Closed-loop simulation of the 4WS path-tracking controller.

The subpackage holds one stage of the closed loop per module, and each
module imports only those listed above it::

    outcomes   the statuses a run ends with, the stop margin, the names of
               the signals and of the peak signals
    options    each option of a run checked once: solver, tolerances, model,
               initial state, gains, steering lag, output times and memory
    dense      the solver's dense output of every step: the delay's history
               and the continuous solution
    loop       ClosedLoop: the vectorised right-hand side of n runs (path
               frame, the law or a controller, actuator, dynamic body)
    signals    the output signals from the path-frame states
    peaks      the exact peaks of the continuous solution
    engine     the numpy engine's driver: many runs in one solver, a run
               leaving the stack where it stops (re-exports the names above)
    result     SimulationResult: one type for one run or many (a run axis)
    arguments  a call's plant, speed profile, gain schedule and runs,
               resolved and validated once
    chunks     one chunk of runs on the numpy engine (module-level for Dask)
    cluster    the chunks of a batch on a Dask cluster
    compiled   the compiled per-run engine (numba), with compilation: its
               cache and first use
    runners    simulate (one run) and simulate_batch (many, chunks, Dask),
               and the choice of the engine

    reference  closed_loop_system, projection_system: the same loop as a
               python-control interconnection (uses the option checks only),
               the tests' reference for the engine

A run stops, and is marked in its result rather than raising, when the model
becomes singular (``status`` :data:`STATUS_SINGULAR_STEERING`,
:data:`STATUS_SINGULAR_CURVATURE`) or leaves an open path
(:data:`STATUS_END_OF_PATH`); the data up to that time are kept.
"""

from typing import TYPE_CHECKING, Any

from .outcomes import (
    SIGNALS,
    STATUS_END_OF_PATH,
    STATUS_FAILED,
    STATUS_OK,
    STATUS_SINGULAR_CURVATURE,
    STATUS_SINGULAR_STEERING,
    STATUS_UNCONTROLLABLE,
    STATUSES,
)
from .result import SimulationResult
from .runners import DEFAULT_CHUNK_SIZE, simulate, simulate_batch

if TYPE_CHECKING:
    from .reference import (
        DEFAULT_PADE_ORDER,
        closed_loop_system,
        projection_system,
        reference_initial_state,
        simulate_reference,
    )

# The reference systems are python-control interconnections: importing them
# costs python-control's import (0.7 s of CPU), which the engine and the
# runners do not need, so they are loaded at first use (PEP 562).
_REFERENCE = frozenset(
    {
        "DEFAULT_PADE_ORDER",
        "closed_loop_system",
        "projection_system",
        "reference_initial_state",
        "simulate_reference",
    }
)


def __getattr__(name: str) -> Any:
    if name in _REFERENCE:
        from . import reference

        return getattr(reference, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | _REFERENCE)


__all__ = [
    "simulate",
    "simulate_batch",
    "SimulationResult",
    "closed_loop_system",
    "projection_system",
    "simulate_reference",
    "reference_initial_state",
    "DEFAULT_PADE_ORDER",
    "SIGNALS",
    "DEFAULT_CHUNK_SIZE",
    "STATUS_OK",
    "STATUS_SINGULAR_STEERING",
    "STATUS_SINGULAR_CURVATURE",
    "STATUS_END_OF_PATH",
    "STATUS_FAILED",
    "STATUS_UNCONTROLLABLE",
    "STATUSES",
]
