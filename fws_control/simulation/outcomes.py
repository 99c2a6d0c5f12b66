r"""What a run of the closed loop ends with and what it records.

The statuses a run ends with (:data:`STATUSES`), the margin before a
singular state at which it stops (:data:`STOP_MARGIN`), the names of the
time series of a result (:data:`SIGNALS`) and of the signals whose exact
peaks are located (:data:`PEAK_SIGNALS`). Both engines, the result and the
runners use these names; the module imports nothing of the package.

Examples
--------
>>> from fws_control.simulation.outcomes import STATUSES, SIGNALS
>>> STATUSES[0], SIGNALS[:3]
('ok', ('x', 'y', 'psi'))
"""

from __future__ import annotations

__all__ = [
    "STATUS_OK",
    "STATUS_SINGULAR_STEERING",
    "STATUS_SINGULAR_CURVATURE",
    "STATUS_END_OF_PATH",
    "STATUS_FAILED",
    "STATUS_UNCONTROLLABLE",
    "STATUSES",
    "STOP_MARGIN",
    "SIGNALS",
    "PEAK_SIGNALS",
]

#: The run reached the final time.
STATUS_OK = "ok"
#: The front steering angle reached :math:`|\delta_f| = \pi/2 - 10^{-3}`
#: (:data:`STOP_MARGIN` before the singular yaw rate).
STATUS_SINGULAR_STEERING = "singular_steering"
#: :math:`1 - \kappa e` reached :math:`10^{-3}` (:data:`STOP_MARGIN`): the
#: vehicle is at the centre of curvature.
STATUS_SINGULAR_CURVATURE = "singular_curvature"
#: The projection left an open path of finite length.
STATUS_END_OF_PATH = "end_of_path"
#: The ODE solver failed (its message is kept).
STATUS_FAILED = "failed"
#: No gains exist for the requested design (used by the paper's scenarios
#: for ``ratio = 1`` on a straight road); the run was not simulated.
STATUS_UNCONTROLLABLE = "uncontrollable"

#: Every status a run can have, :data:`STATUS_OK` first.
STATUSES = (
    STATUS_OK,
    STATUS_SINGULAR_STEERING,
    STATUS_SINGULAR_CURVATURE,
    STATUS_END_OF_PATH,
    STATUS_FAILED,
    STATUS_UNCONTROLLABLE,
)

#: Distance before a singular state at which a run stops:
#: ``|delta_f| = pi/2 - STOP_MARGIN`` [rad] and ``1 - kappa*e = STOP_MARGIN``.
#: At the singular state itself the solution has a square-root singularity
#: (``d delta_f/dt ~ 1/cos delta_f``) and the step size collapses before any
#: step reaches it: 4455 steps and 5.8 s for a delayed run at 20 m/s that
#: the margin stops after 0.17 s (tests/test_delay_simulation.py). Both
#: engines use it (the compiled one as its default ``steer_margin``,
#: ``curvature_margin``).
STOP_MARGIN = 1e-3

#: Names of the time series of a result, in order.
SIGNALS = (
    "x",
    "y",
    "psi",
    "s",
    "e",
    "theta",
    "delta_f",
    "delta_r",
    "delta_f_rate",
    "delta_r_rate",
    "lateral_accel",
    "v_y",
    "yaw_rate",
    "slip_front",
    "slip_rear",
)

#: Signals whose peak ``max |signal|``
#: :func:`~fws_control.simulation.peaks.exact_peaks` locates.
PEAK_SIGNALS = (
    "e",
    "delta_f",
    "delta_r",
    "delta_f_rate",
    "delta_r_rate",
    "lateral_accel",
)
