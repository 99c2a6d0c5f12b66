r"""Closed-loop simulation of the 4WS path-tracking controller.

The subpackage is layered in one direction (each module imports only those
above it)::

    engine     the numerical engine: vectorised path-frame right-hand side,
       │       integration of many runs with per-run stops, output signals
       ▼
    result     SimulationResult: one type for one run or many (a run axis)
       │
       ▼
    runners    simulate (one run) and simulate_batch (many, chunks, Dask)

    reference  closed_loop_system, projection_system: the same loop as a
               python-control interconnection (uses the engine's argument
               checks only), the tests' reference for the engine

A run stops, and is marked in its result rather than raising, when the model
becomes singular (``status`` :data:`STATUS_SINGULAR_STEERING`,
:data:`STATUS_SINGULAR_CURVATURE`) or leaves an open path
(:data:`STATUS_END_OF_PATH`); the data up to that time are kept.
"""

from typing import TYPE_CHECKING

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


def __getattr__(name: str):
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
