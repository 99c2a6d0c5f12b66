r"""fws_control: path tracking of automated vehicles with four-wheel steering.

A control-systems toolbox built on python-control. The data flow runs one
way, one module per concept; a module knows only the modules above it::

    Vehicle ──► kinematic_models (ct.NonlinearIOSystem: global, path frame)
       │            │ exact Jacobian / paper eq. (33)
       │            ▼
       │        LateralPlant (operating point) ──► ct.StateSpace ◄── or any plant
       │            │                     (inputs delta_f, delta_r; outputs e, theta)
       │            ▼
       │        plant-first analysis (linear, stability, pole_placement, charts,
       │            rootlocus):
       │            u = [1, a]^T (-k1 e - k2 theta) is rank one, so the
       │            characteristic polynomial is affine in (k1, k2) for any order
       │
       └──► paths (Straight, Arc, Clothoid, Spline, chains: projection → s, e, θ, κ)
                controllers (the paper's law as static nlsys)
                simulation/ (engine, runners, one result type, python-control reference)
                metrics, linear_vs_nonlinear, turning
                paper/ (the paper's scenarios and figures, reproduce) ──► cli

Modules: :mod:`~fws_control.vehicle`, :mod:`~fws_control.exceptions`,
:mod:`~fws_control.validation`, :mod:`~fws_control.kinematic_models`,
:mod:`~fws_control.acceleration`, :mod:`~fws_control.gains`,
:mod:`~fws_control.plant`, :mod:`~fws_control.linear`,
:mod:`~fws_control.stability`, :mod:`~fws_control.pole_placement`,
:mod:`~fws_control.charts`, :mod:`~fws_control.rootlocus`,
:mod:`~fws_control.turning`, :mod:`~fws_control.paths`,
:mod:`~fws_control.controllers`, :mod:`~fws_control.simulation`,
:mod:`~fws_control.metrics`, :mod:`~fws_control.linear_vs_nonlinear`,
:mod:`~fws_control.openloop` (ISO 7401 and ISO 4138 open-loop tests),
:mod:`~fws_control.symbolic` (sympy derivations, the tests' reference) and
:mod:`~fws_control.paper` (imported only by the CLI).

``import fws_control`` itself imports no submodule: each name of ``__all__``
is loaded from its module at first use (PEP 562), so that a script or a
command-line call pays only for what it uses (python-control alone costs
about a second and a half of CPU to import).
"""

import importlib
import importlib.util
from typing import TYPE_CHECKING, Any

# The package's public names, once: type checkers read these imports as
# re-exports (``name as name``); at run time __getattr__ below reads the same
# statements to list ``__all__`` and load each name on first use. (isort would
# split every ``as`` import onto its own statement.)
# isort: off
if TYPE_CHECKING:
    from . import dynamics as dynamics
    from . import symbolic as symbolic
    from . import vehicles as vehicles
    from .acceleration import (
        lateral_acceleration as lateral_acceleration,
        yaw_acceleration as yaw_acceleration,
    )
    from .baselines import (
        LQRController as LQRController,
        PurePursuit as PurePursuit,
        RearWheelFeedback as RearWheelFeedback,
        Stanley as Stanley,
        StateFeedback as StateFeedback,
        as_controller as as_controller,
    )
    from .charts import (
        DelayMarginChart as DelayMarginChart,
        StabilityChart as StabilityChart,
        delay_margin_chart as delay_margin_chart,
        stability_chart as stability_chart,
    )
    from .linear_vs_nonlinear import (
        LinearNonlinearComparison as LinearNonlinearComparison,
        compare_linear_nonlinear as compare_linear_nonlinear,
    )
    from .controller_comparison import (
        ControllerComparison as ControllerComparison,
        compare as compare,
        default_controllers as default_controllers,
    )
    from .controllers import (
        feedback_controller as feedback_controller,
        feedforward_feedback_controller as feedforward_feedback_controller,
        path_tracking_controller as path_tracking_controller,
        steering_actuator as steering_actuator,
        steering_command as steering_command,
        steering_command_rate as steering_command_rate,
    )
    from .delay import (
        CriticalDelay as CriticalDelay,
        critical_delay as critical_delay,
        rightmost_roots as rightmost_roots,
        unstable_root_count as unstable_root_count,
    )
    from .delay_design import (
        MostStableDesign as MostStableDesign,
        most_stable_gains as most_stable_gains,
    )
    from .pole_placement import double_root_gains as double_root_gains
    from .dynamic_design import (
        KinematicDesignLimit as KinematicDesignLimit,
        kinematic_design_limit as kinematic_design_limit,
        steady_state_offset as steady_state_offset,
        understeer_gradient as understeer_gradient,
        zero_sideslip_ratio as zero_sideslip_ratio,
    )
    from .exceptions import (
        AmbiguousProjectionError as AmbiguousProjectionError,
        ClusterLostError as ClusterLostError,
        SignalNotKeptError as SignalNotKeptError,
        SingularStateError as SingularStateError,
        UncontrollableError as UncontrollableError,
    )
    from .gains import SteeringGains as SteeringGains
    from .linear import (
        AffinePolynomial as AffinePolynomial,
        affine_characteristic_polynomial as affine_characteristic_polynomial,
        characteristic_polynomial_coefficients as characteristic_polynomial_coefficients,  # noqa: E501
        closed_loop as closed_loop,
        linearize as linearize,
    )
    from .manoeuvres import (
        Gate as Gate,
        Manoeuvre as Manoeuvre,
        constant_radius as constant_radius,
        double_lane_change as double_lane_change,
        obstacle_avoidance as obstacle_avoidance,
        slalom as slalom,
    )
    from .metrics import (
        TrackingMetrics as TrackingMetrics,
        overshoot as overshoot,
        peak_abs as peak_abs,
        rms as rms,
        settling_time as settling_time,
        steady_state as steady_state,
        tracking_metrics as tracking_metrics,
    )
    from .lateral_controller import (
        LateralController as LateralController,
        saturate as saturate,
    )
    from .kinematic_models import (
        feedforward_steering as feedforward_steering,
        global_frame_model as global_frame_model,
        path_frame_model as path_frame_model,
        yaw_rate as yaw_rate,
    )
    from .mpc import (
        MPCController as MPCController,
        MPCRun as MPCRun,
        MPCStep as MPCStep,
    )
    from .openloop import (
        SteadyStateCircle as SteadyStateCircle,
        SteeringFrequencyResponse as SteeringFrequencyResponse,
        StepResponseMetrics as StepResponseMetrics,
        StepSteerResponse as StepSteerResponse,
        steady_state_circle as steady_state_circle,
        steering_frequency_response as steering_frequency_response,
        steering_response_system as steering_response_system,
        step_steer as step_steer,
    )
    from .paths import (
        Arc as Arc,
        Clothoid as Clothoid,
        Path as Path,
        PathChain as PathChain,
        Projection as Projection,
        Spline as Spline,
        Straight as Straight,
    )
    from .plant import (
        LateralPlant as LateralPlant,
        LoopMatrices as LoopMatrices,
        as_plant as as_plant,
        loop_matrices as loop_matrices,
    )
    from .rear_limits import (
        RearLimitBand as RearLimitBand,
        RearSaturation as RearSaturation,
        rear_limit_band as rear_limit_band,
        rear_saturation as rear_saturation,
    )
    from .robust import (
        BoundaryPiece as BoundaryPiece,
        ParameterBox as ParameterBox,
        RobustDesign as RobustDesign,
        RobustRegion as RobustRegion,
        robust_gains as robust_gains,
        robust_region as robust_region,
        robust_stable as robust_stable,
    )
    from .rootlocus import (
        gain_locus as gain_locus,
        gain_loop as gain_loop,
        parameter_locus as parameter_locus,
    )
    from .schedule import (
        GainSchedule as GainSchedule,
        schedule_gains as schedule_gains,
    )
    from .speed_profile import SpeedProfile as SpeedProfile
    from .simulation import (
        SimulationResult as SimulationResult,
        closed_loop_system as closed_loop_system,
        projection_system as projection_system,
        simulate as simulate,
        simulate_batch as simulate_batch,
    )
    from .stability import (
        BoundaryCurve as BoundaryCurve,
        StabilityBoundaries as StabilityBoundaries,
        StabilityBoundary as StabilityBoundary,
        StabilityVerdict as StabilityVerdict,
        is_stable as is_stable,
        stability_boundaries as stability_boundaries,
        stability_verdict as stability_verdict,
    )
    from .tradeoff import (
        ParetoFront as ParetoFront,
        pareto_front as pareto_front,
    )
    from .turning import (
        TurningGeometry as TurningGeometry,
        plot_turning_radius as plot_turning_radius,
        steady_turn as steady_turn,
        turning_radius as turning_radius,
    )
    from .varying_speed import (
        SpeedCertificate as SpeedCertificate,
        speed_certificate as speed_certificate,
    )
    from .vehicle import Vehicle as Vehicle
# isort: on

__version__ = "0.2.0.dev0"


# Lazy loading (PEP 562): ``import fws_control`` runs no submodule, so that a
# command-line call or a script that needs a few names does not pay for
# python-control (which pulls in matplotlib, scipy.signal and scipy.stats),
# sympy or scipy.integrate. The ``if TYPE_CHECKING:`` imports above are the
# one list of public names: type checkers read them as re-exports (the
# ``name as name`` form), and at the first attribute access the same
# statements are read from this file's source (as SPEC 1's lazy_loader reads
# a stub) to give ``__all__`` and the submodule of each name. A name is then
# imported from its submodule and cached in the module's namespace.


def _read_exports() -> dict[str, str | None]:
    """Public name -> the submodule that defines it (None for a submodule)."""
    import ast  # only here: ast costs about as much as this package's import

    get_source = getattr(getattr(__spec__, "loader", None), "get_source", None)
    source = get_source(__name__) if get_source is not None else None
    if source is None:
        raise ImportError(
            f"{__name__} reads its public names from the source of "
            f"{__name__}/__init__.py, which this installation does not include"
        )
    block = next(
        node
        for node in ast.parse(source).body
        if isinstance(node, ast.If)
        and isinstance(node.test, ast.Name)
        and node.test.id == "TYPE_CHECKING"
    )
    exports: dict[str, str | None] = {}
    for node in block.body:
        assert isinstance(node, ast.ImportFrom) and node.level == 1, ast.dump(node)
        for alias in node.names:
            exports[alias.asname or alias.name] = node.module
    return exports


def _origin() -> dict[str, str]:
    """Public name -> its submodule; sets ``__all__`` on the first call."""
    origin = globals().get("_ORIGIN")
    if origin is None:
        exports = _read_exports()
        origin = {n: m for n, m in exports.items() if m is not None}
        globals().update(__all__=list(exports), _ORIGIN=origin)
    return origin


# Former names, accepted until fws_control 0.4 and not in __all__: the
# module that defines each (its function warns, naming the current name).
_RENAMED = {
    "characteristic_coefficients": "linear",
    "characteristic_polynomial": "linear",
}


def __getattr__(name: str) -> Any:
    if name in ("__all__", "_ORIGIN"):
        _origin()
        return globals()[name]
    module = _origin().get(name) or _RENAMED.get(name)
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
    _origin()
    return sorted(set(globals()) | set(globals()["__all__"]))
