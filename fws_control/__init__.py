"""fws_control: path tracking of automated vehicles with four-wheel steering.

A control-systems toolbox built on python-control for the kinematic
single-track model with front and rear steering, ``delta_r = ratio*delta_f``:
nonlinear models as :class:`control.NonlinearIOSystem`, exact and paper
linearisations as :class:`control.StateSpace`, closed-form Routh-Hurwitz
stability and double-root pole placement.
"""

from . import symbolic
from .acceleration import lateral_acceleration, yaw_acceleration
from .charts import (
    ChartPanel,
    StabilityChart,
    paper_figure_panels,
    plot_paper_figure,
    stability_chart,
)
from .design import UncontrollableError, double_root_gains
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
from .models import (
    SingularStateError,
    feedforward_steering,
    global_frame_model,
    path_frame_model,
    yaw_rate,
)
from .stability import StabilityBoundary, is_stable, stability_boundaries
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
]
__version__ = "0.1.0"
