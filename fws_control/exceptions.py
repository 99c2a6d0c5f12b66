"""Exceptions of fws_control, in one place.

Every exception about the input is a :class:`ValueError` subclass, so that
code that catches bad input in general keeps working, while callers that care
can tell a design that cannot exist from a singular state of the model or an
ambiguous projection. :class:`ClusterLostError` is a :class:`RuntimeError`:
the input was fine, the environment failed.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "UncontrollableError",
    "SingularStateError",
    "AmbiguousProjectionError",
    "SignalNotKeptError",
    "ClusterLostError",
]


class UncontrollableError(ValueError):
    """The requested closed-loop poles cannot be reached by any gains.

    Raised by :func:`~fws_control.double_root_gains` when the single-input
    pair :math:`(\\mathbf A, \\mathbf B[1, a]^T)` is uncontrollable (for the
    kinematic plant: ``ratio = c`` on a straight path, i.e. ``a = 1``) or so
    nearly so that the gains would be meaningless.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> try:
    ...     fws.double_root_gains(veh, speed=5.0, ratio=1.0, pole=-1.0)
    ... except fws.UncontrollableError:
    ...     print("uncontrollable")
    uncontrollable
    """


class SingularStateError(ValueError):
    """A state or input where the kinematic model is not defined.

    Raised for a front steering angle with ``|delta_f| >= pi/2`` (the yaw
    rate of eq. (10) has ``cos(delta_f)`` in the denominator) and, in the
    path frame, for ``1 - curvature * e <= 0`` (the vehicle is at or beyond
    the centre of curvature, where the projection onto the path is lost).

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> try:
    ...     fws.yaw_rate(veh, 2.0, 0.0, speed=5.0)
    ... except fws.SingularStateError:
    ...     print("singular")
    singular
    """


class AmbiguousProjectionError(ValueError):
    """The nearest point of a path to a given point is not unique.

    Raised by :meth:`Path.project` and :meth:`Path.errors` with
    ``strict=True``; the message names the first such point.

    Examples
    --------
    >>> from fws_control.paths import Arc
    >>> from fws_control.exceptions import AmbiguousProjectionError
    >>> try:
    ...     Arc(curvature=0.1).project(0.0, 10.0, strict=True)
    ... except AmbiguousProjectionError as exc:
    ...     print("ambiguous")
    ambiguous
    """


class SignalNotKeptError(ValueError, AttributeError):
    """A signal that the simulation did not keep was asked for.

    :func:`~fws_control.simulate_batch` with ``signals=`` keeps only the
    named time series (or none, ``signals="metrics"``); reading another one
    (``result.e``, ``result.signal("e")``, a plot that needs it) raises
    this error, naming the signal and the signals the result holds. It is
    a :class:`ValueError` like every exception of the package, and an
    :class:`AttributeError`, so that ``hasattr(result, "e")`` is False and
    ``getattr(result, "e", None)`` gives None for a signal not kept.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> res = fws.simulate_batch(fws.LateralPlant(veh, speed=5.0), fws.Straight(),
    ...                          fws.SteeringGains(0.1, 0.5, 0.0),
    ...                          initial_state=(0.0, 1.0, 0.0), duration=1.0,
    ...                          signals=("e",))
    >>> try:
    ...     res.theta
    ... except fws.SignalNotKeptError:
    ...     print("theta was not kept")
    theta was not kept
    >>> hasattr(res, "theta"), res.e.shape
    (False, (1, 101))
    """


class ClusterLostError(RuntimeError):
    """The Dask cluster of a batch lost all its workers; finished runs are kept.

    Raised by :func:`~fws_control.simulate_batch` (``client=``) once the
    cluster has had no worker for a bounded wait (60 s): without a nanny
    nothing restarts a killed worker, and the pending tasks would wait
    forever. The chunks that finished before are not lost: :attr:`result` is
    the batch's :class:`~fws_control.simulation.SimulationResult` with their
    runs, and the runs that were pending marked ``"failed"`` (NaN data, a
    message saying why). A :class:`RuntimeError`, not a ``ValueError``: the
    input was fine, the environment failed.

    Attributes
    ----------
    result : SimulationResult
        The whole batch: finished runs as computed, lost runs failed.

    Examples
    --------
    >>> import fws_control as fws
    >>> issubclass(fws.ClusterLostError, RuntimeError)
    True
    """

    # Any, not SimulationResult: the exceptions module imports nothing of the
    # package (the simulation imports it), even for type checkers
    def __init__(self, message: str, *, result: Any = None) -> None:
        super().__init__(message)
        self.result: Any = result
