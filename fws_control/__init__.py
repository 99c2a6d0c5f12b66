"""fws_control: path tracking of automated vehicles with four-wheel steering.

A control-systems toolbox built on python-control for the kinematic
single-track model with front and rear steering, ``delta_r = ratio*delta_f``:
nonlinear models as :class:`control.NonlinearIOSystem`, exact and paper
linearisations as :class:`control.StateSpace`, closed-form Routh-Hurwitz
stability and double-root pole placement, paths with robust projection,
closed-loop simulation (a python-control reference and a fast batch engine),
stability charts, root loci and the figures of the paper.
"""

from . import scenarios, symbolic
from .acceleration import lateral_acceleration, yaw_acceleration
from .batch import BatchResult, simulate_batch
from .charts import (
    ChartPanel,
    StabilityChart,
    paper_figure_panels,
    plot_paper_figure,
    stability_chart,
)
from .comparison import LinearNonlinearComparison, compare_linear_nonlinear
from .controllers import (
    feedback_controller,
    feedforward_feedback_controller,
    path_tracking_controller,
    steering_actuator,
    steering_command,
    steering_command_rate,
)
from .design import UncontrollableError, double_root_gains
from .figures import gains_table, make_figure, reproduce
from .gains import SteeringGains
from .linear import (
    AffineCoefficients,
    characteristic_coefficients,
    characteristic_polynomial,
    closed_loop,
    input_gain_factor,
    linearize,
    operating_point,
)
from .metrics import (
    TrackingMetrics,
    overshoot,
    peak_abs,
    rms,
    settling_time,
    steady_state,
    tracking_metrics,
)
from .models import (
    SingularStateError,
    feedforward_steering,
    global_frame_model,
    path_frame_model,
    yaw_rate,
)
from .paths import (
    AmbiguousProjectionError,
    Arc,
    Clothoid,
    Path,
    PathChain,
    Projection,
    Spline,
    Straight,
)
from .rootlocus import gain_locus, gain_loop, parameter_locus
from .simulation import (
    SimulationResult,
    closed_loop_system,
    projection_system,
    simulate,
)
from .stability import StabilityBoundary, is_stable, stability_boundaries
from .turning import (
    TurningGeometry,
    plot_turning_radius,
    steady_turn,
    turning_radius,
)
from .vehicle import Vehicle

__all__ = [
    "Vehicle",
    "SingularStateError",
    "global_frame_model",
    "path_frame_model",
    "yaw_rate",
    "feedforward_steering",
    "yaw_acceleration",
    "lateral_acceleration",
    "input_gain_factor",
    "operating_point",
    "linearize",
    "closed_loop",
    "AffineCoefficients",
    "characteristic_coefficients",
    "characteristic_polynomial",
    "SteeringGains",
    "UncontrollableError",
    "double_root_gains",
    "is_stable",
    "StabilityBoundary",
    "stability_boundaries",
    "symbolic",
    "StabilityChart",
    "stability_chart",
    "ChartPanel",
    "paper_figure_panels",
    "plot_paper_figure",
    "gain_loop",
    "gain_locus",
    "parameter_locus",
    "TurningGeometry",
    "steady_turn",
    "turning_radius",
    "plot_turning_radius",
    "LinearNonlinearComparison",
    "compare_linear_nonlinear",
    "make_figure",
    "gains_table",
    "reproduce",
]
__all__ += [
    "steering_command",
    "steering_command_rate",
    "path_tracking_controller",
    "feedback_controller",
    "feedforward_feedback_controller",
    "steering_actuator",
    "SimulationResult",
    "simulate",
    "closed_loop_system",
    "projection_system",
    "BatchResult",
    "simulate_batch",
    "peak_abs",
    "settling_time",
    "overshoot",
    "rms",
    "steady_state",
    "TrackingMetrics",
    "tracking_metrics",
    "scenarios",
]
__all__ += [
    "Path",
    "Straight",
    "Arc",
    "Clothoid",
    "Spline",
    "PathChain",
    "Projection",
    "AmbiguousProjectionError",
]
__version__ = "0.1.0"
