r"""fws_control: path tracking of automated vehicles with four-wheel steering.

A control-systems toolbox built on python-control. The data flow runs one
way, one module per concept; a module knows only the modules above it::

    Vehicle ──► models (ct.NonlinearIOSystem: global and path frame)
       │            │ exact Jacobian / paper eq. (33)
       │            ▼
       │        LateralPlant (operating point) ──► ct.StateSpace ◄── or any plant
       │            │                     (inputs delta_f, delta_r; outputs e, theta)
       │            ▼
       │        plant-first analysis (linear, stability, design, charts, rootlocus):
       │            u = [1, a]^T (-k1 e - k2 theta) is rank one, so the
       │            characteristic polynomial is affine in (k1, k2) for any order
       │
       └──► paths (Straight, Arc, Clothoid, Spline, chains: projection → s, e, θ, κ)
                controllers (the paper's law as static nlsys)
                simulation/ (engine, runners, one result type, python-control reference)
                metrics, comparison (linear vs nonlinear), turning
                paper/ (the paper's scenarios and figures, reproduce) ──► cli

Modules: :mod:`~fws_control.vehicle`, :mod:`~fws_control.exceptions`,
:mod:`~fws_control.validation`, :mod:`~fws_control.models`,
:mod:`~fws_control.acceleration`, :mod:`~fws_control.gains`,
:mod:`~fws_control.plant`, :mod:`~fws_control.linear`,
:mod:`~fws_control.stability`, :mod:`~fws_control.design`,
:mod:`~fws_control.charts`, :mod:`~fws_control.rootlocus`,
:mod:`~fws_control.turning`, :mod:`~fws_control.paths`,
:mod:`~fws_control.controllers`, :mod:`~fws_control.simulation`,
:mod:`~fws_control.metrics`, :mod:`~fws_control.comparison`,
:mod:`~fws_control.symbolic` (sympy derivations, the tests' reference) and
:mod:`~fws_control.paper` (imported only by the CLI).

``import fws_control`` itself imports no submodule: each name of ``__all__``
is loaded from its module at first use (PEP 562), so that a script or a
command-line call pays only for what it uses (python-control alone costs
about a second and a half of CPU to import).
"""

import importlib
import importlib.util
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # static tools see the names; at run time __getattr__ loads them
    from . import dynamics, symbolic, vehicles
    from .acceleration import lateral_acceleration, yaw_acceleration
    from .baselines import (
        LateralController,
        LQRController,
        PurePursuit,
        RearWheelFeedback,
        Stanley,
        StateFeedback,
        as_controller,
        saturate,
    )
    from .charts import (
        DelayMarginChart,
        StabilityChart,
        delay_margin_chart,
        stability_chart,
    )
    from .comparison import LinearNonlinearComparison, compare_linear_nonlinear
    from .controller_comparison import (
        ControllerComparison,
        compare,
        default_controllers,
    )
    from .controllers import (
        feedback_controller,
        feedforward_feedback_controller,
        path_tracking_controller,
        steering_actuator,
        steering_command,
        steering_command_rate,
    )
    from .delay import (
        CriticalDelay,
        critical_delay,
        rightmost_roots,
        unstable_root_count,
    )
    from .delay_design import MostStableDesign, most_stable_gains
    from .design import double_root_gains
    from .dynamic_design import (
        KinematicDesignLimit,
        kinematic_design_limit,
        steady_state_offset,
        understeer_gradient,
        zero_sideslip_ratio,
    )
    from .exceptions import (
        AmbiguousProjectionError,
        SignalNotKeptError,
        SingularStateError,
        UncontrollableError,
    )
    from .gains import SteeringGains
    from .linear import (
        AffinePolynomial,
        characteristic_coefficients,
        characteristic_polynomial,
        closed_loop,
        linearize,
    )
    from .manoeuvres import (
        Gate,
        Manoeuvre,
        constant_radius,
        double_lane_change,
        obstacle_avoidance,
        slalom,
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
        feedforward_steering,
        global_frame_model,
        path_frame_model,
        yaw_rate,
    )
    from .paths import (
        Arc,
        Clothoid,
        Path,
        PathChain,
        Projection,
        Spline,
        Straight,
    )
    from .plant import LateralPlant, LoopMatrices, as_plant, loop_matrices
    from .rear_limits import (
        RearLimitBand,
        RearSaturation,
        rear_limit_band,
        rear_saturation,
    )
    from .robust import (
        BoundaryPiece,
        ParameterBox,
        RobustDesign,
        RobustRegion,
        robust_gains,
        robust_region,
        robust_stable,
    )
    from .rootlocus import gain_locus, gain_loop, parameter_locus
    from .schedule import GainSchedule, schedule_gains
    from .simulation import (
        SimulationResult,
        closed_loop_system,
        projection_system,
        simulate,
        simulate_batch,
    )
    from .stability import (
        BoundaryCurve,
        StabilityBoundaries,
        StabilityBoundary,
        StabilityVerdict,
        is_stable,
        stability_boundaries,
        stability_verdict,
    )
    from .tradeoff import ParetoFront, pareto_front
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
    "linearize",
    "closed_loop",
    "AffinePolynomial",
    "LateralPlant",
    "LoopMatrices",
    "as_plant",
    "loop_matrices",
    "StabilityBoundaries",
    "BoundaryCurve",
    "characteristic_coefficients",
    "characteristic_polynomial",
    "SteeringGains",
    "UncontrollableError",
    "CriticalDelay",
    "critical_delay",
    "rightmost_roots",
    "unstable_root_count",
    "MostStableDesign",
    "most_stable_gains",
    "double_root_gains",
    "is_stable",
    "stability_verdict",
    "StabilityVerdict",
    "StabilityBoundary",
    "stability_boundaries",
    "symbolic",
    "dynamics",
    "StabilityChart",
    "stability_chart",
    "LateralController",
    "StateFeedback",
    "LQRController",
    "PurePursuit",
    "Stanley",
    "RearWheelFeedback",
    "saturate",
    "as_controller",
    "ControllerComparison",
    "compare",
    "default_controllers",
    "Gate",
    "Manoeuvre",
    "double_lane_change",
    "obstacle_avoidance",
    "slalom",
    "constant_radius",
    "DelayMarginChart",
    "delay_margin_chart",
    "gain_loop",
    "gain_locus",
    "parameter_locus",
    "TurningGeometry",
    "steady_turn",
    "turning_radius",
    "plot_turning_radius",
    "LinearNonlinearComparison",
    "compare_linear_nonlinear",
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
    "simulate_batch",
    "peak_abs",
    "settling_time",
    "overshoot",
    "rms",
    "steady_state",
    "TrackingMetrics",
    "tracking_metrics",
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
    "SignalNotKeptError",
]
# the dynamic single-track model (issue 10)
__all__ += [
    "vehicles",
    "KinematicDesignLimit",
    "kinematic_design_limit",
    "steady_state_offset",
    "understeer_gradient",
    "zero_sideslip_ratio",
]
# robust stability over a parameter box
__all__ += [
    "ParameterBox",
    "BoundaryPiece",
    "RobustRegion",
    "RobustDesign",
    "robust_region",
    "robust_stable",
    "robust_gains",
]
# design for the real vehicle: trade-off, speed schedules, rear limits
__all__ += [
    "ParetoFront",
    "pareto_front",
    "GainSchedule",
    "schedule_gains",
    "RearLimitBand",
    "rear_limit_band",
    "RearSaturation",
    "rear_saturation",
]
__version__ = "0.2.0.dev0"


# Lazy loading (PEP 562): ``import fws_control`` runs no submodule, so that a
# command-line call or a script that needs a few names does not pay for
# python-control (which pulls in matplotlib, scipy.signal and scipy.stats),
# sympy or scipy.integrate. A name of __all__ is imported from its submodule
# at first access and then cached in the module's namespace.
#: Submodule -> the public names the package re-exports from it.
_EXPORTS = {
    "acceleration": (
        "lateral_acceleration",
        "yaw_acceleration",
    ),
    "baselines": (
        "LateralController",
        "LQRController",
        "PurePursuit",
        "RearWheelFeedback",
        "Stanley",
        "StateFeedback",
        "as_controller",
        "saturate",
    ),
    "charts": (
        "DelayMarginChart",
        "StabilityChart",
        "delay_margin_chart",
        "stability_chart",
    ),
    "comparison": (
        "LinearNonlinearComparison",
        "compare_linear_nonlinear",
    ),
    "controller_comparison": (
        "ControllerComparison",
        "compare",
        "default_controllers",
    ),
    "controllers": (
        "feedback_controller",
        "feedforward_feedback_controller",
        "path_tracking_controller",
        "steering_actuator",
        "steering_command",
        "steering_command_rate",
    ),
    "delay": (
        "CriticalDelay",
        "critical_delay",
        "rightmost_roots",
        "unstable_root_count",
    ),
    "delay_design": (
        "MostStableDesign",
        "most_stable_gains",
    ),
    "design": ("double_root_gains",),
    "dynamic_design": (
        "KinematicDesignLimit",
        "kinematic_design_limit",
        "steady_state_offset",
        "understeer_gradient",
        "zero_sideslip_ratio",
    ),
    "exceptions": (
        "AmbiguousProjectionError",
        "SignalNotKeptError",
        "SingularStateError",
        "UncontrollableError",
    ),
    "gains": ("SteeringGains",),
    "linear": (
        "AffinePolynomial",
        "characteristic_coefficients",
        "characteristic_polynomial",
        "closed_loop",
        "linearize",
    ),
    "manoeuvres": (
        "Gate",
        "Manoeuvre",
        "constant_radius",
        "double_lane_change",
        "obstacle_avoidance",
        "slalom",
    ),
    "metrics": (
        "TrackingMetrics",
        "overshoot",
        "peak_abs",
        "rms",
        "settling_time",
        "steady_state",
        "tracking_metrics",
    ),
    "models": (
        "feedforward_steering",
        "global_frame_model",
        "path_frame_model",
        "yaw_rate",
    ),
    "paths": (
        "Arc",
        "Clothoid",
        "Path",
        "PathChain",
        "Projection",
        "Spline",
        "Straight",
    ),
    "plant": (
        "LateralPlant",
        "LoopMatrices",
        "as_plant",
        "loop_matrices",
    ),
    "rear_limits": (
        "RearLimitBand",
        "RearSaturation",
        "rear_limit_band",
        "rear_saturation",
    ),
    "robust": (
        "BoundaryPiece",
        "ParameterBox",
        "RobustDesign",
        "RobustRegion",
        "robust_gains",
        "robust_region",
        "robust_stable",
    ),
    "schedule": (
        "GainSchedule",
        "schedule_gains",
    ),
    "tradeoff": (
        "ParetoFront",
        "pareto_front",
    ),
    "rootlocus": (
        "gain_locus",
        "gain_loop",
        "parameter_locus",
    ),
    "simulation": (
        "SimulationResult",
        "closed_loop_system",
        "projection_system",
        "simulate",
        "simulate_batch",
    ),
    "stability": (
        "BoundaryCurve",
        "StabilityBoundaries",
        "StabilityBoundary",
        "StabilityVerdict",
        "is_stable",
        "stability_boundaries",
        "stability_verdict",
    ),
    "turning": (
        "TurningGeometry",
        "plot_turning_radius",
        "steady_turn",
        "turning_radius",
    ),
    "vehicle": ("Vehicle",),
}
_ORIGIN = {name: module for module, names in _EXPORTS.items() for name in names}


def __getattr__(name: str):
    module = _ORIGIN.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f".{module}", __name__), name)
        globals()[name] = value
        return value
    if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}"):
        # A submodule or subpackage (``fws_control.symbolic``), imported on
        # first access like the names above.
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
