r"""The public runners: :func:`simulate` (one run) and :func:`simulate_batch`.

Both resolve and validate the arguments
(:mod:`~fws_control.simulation.arguments`), let an engine integrate the
closed loop chunk by chunk (:mod:`~fws_control.simulation.chunks` on the
numpy engine, :mod:`~fws_control.simulation.engine`; on a Dask cluster
:mod:`~fws_control.simulation.cluster`) and return a
:class:`~fws_control.simulation.result.SimulationResult`; :func:`simulate`
is a batch of one run, squeezed.

:func:`simulate_batch` stacks the path-frame states of the runs of a chunk
into one state vector and integrates them with one solver. Gains, ratios,
speeds and initial poses may differ per run (numpy broadcasting). A run that
meets a singular state leaves the stacked state at that time (the
integration restarts from there for the others) and is marked in its status;
its samples after the stop are NaN. Large sweeps are split into chunks of
``chunk_size`` runs. With a ``dask.distributed`` client (optional extra
``distributed``) the chunks are submitted to the cluster; otherwise they run
one after the other here. A tqdm progress bar over the chunks is shown on
interactive terminals.

That is the numpy engine. By default (``engine="auto"``) the runners use
the compiled per-run engine of :mod:`~fws_control.simulation.compiled`
instead wherever numba is installed and it covers the case (the paper's
law on the kinematic model with DOP853 or Radau, with a delay DOP853; on
the dynamic model and a controller's compiled law DOP853, with or without
a delay): each run then has its own
steps, error norm and stop, and its exact peaks come from its own dense
output. Until the kernels a call needs are in the cache, a background
process compiles them and the calls run on the numpy engine
(:func:`~fws_control.simulation.precompile.ready_or_background`).
"""

from __future__ import annotations

import functools
import math
import sys
import warnings
from typing import Any

import numpy as np

from ..controllers import check_feedforward
from ..dynamics import require_dynamics
from ..exceptions import ClusterLostError
from ..gains import SteeringGains
from ..lateral_controller import LateralController
from ..metrics import HORIZON_METRICS
from ..paths import Path
from ..plant import LateralPlant
from ..speed_profile import SpeedProfile
from ..validation import (
    MAX_SPEED,
    check_bool,
    check_delay,
)
from ..vehicle import Vehicle
from .arguments import (
    check_chunk_size,
    check_out,
    check_profile_run,
    check_signals,
    prepare_runs,
    resolve_plant,
    speed_option,
    with_profile,
)
from .chunks import (
    chunk_controller,
    outputs_in_blocks,
    reduce_chunk,
    run_isolated,
    run_kept,
)
from .cluster import run_on_dask
from .dense import CompiledDense
from .loop import is_sampled, scheduled_gains
from .options import (
    LSODA_MAX_RUNS,
    SAFE_STEP,
    initial_path_state,
    path_key,
    run_gains,
)
from .outcomes import PEAK_SIGNALS, SIGNALS
from .peaks import exact_peaks_per_run
from .result import SimulationResult

__all__ = ["simulate", "simulate_batch", "DEFAULT_CHUNK_SIZE"]

#: Runs per chunk (one solver, one Dask task) unless told otherwise.
DEFAULT_CHUNK_SIZE = 256


def _stderr_is_tty() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


# Engines of simulate_batch (documented in its docstring).
_ENGINES = ("auto", "numpy", "compiled")

#: With an actuator of time constant T under ``method="auto"``, the compiled
#: engine's DOP853 steps at most this times T: half its stability bound of
#: about 6.4 T, where its error estimate bounds the error again. Measured on
#: the curve scenario at T = 0.05 s over 15 s against a fixed-step RK4
#: reference: 330 tolerances off at the bound, 5.7 with the cap (0.3 of the
#: bound: 4.3; 0.8: 386), at 0.24 ms of CPU per run (numpy LSODA in chunks
#: of 16: 17.3 ms).
_CAPPED_STEP = SAFE_STEP
#: Beyond this many capped steps "auto" on the compiled engine takes its
#: Radau (implicit, stepping by accuracy: 9-13 ms of CPU per run of the
#: curve scenario with all signals and exact peaks, whatever T and the
#: duration) instead of the capped DOP853 (about 4.3 us per step, 1.0-1.4
#: ms for the 15 s scenario at T = 0.27 and 0.05 s; 16.5 ms at 4,688 steps,
#: 43 ms at 9,375 and 396 ms at 93,750). Measured with `simulate`, best of
#: 3, output step 0.1 s: they cost the same near 2,300 steps.
_RADAU_FROM_STEPS = 2500


def _compiled_reason(
    path, gains, *, delay, method, model, feedforward, profile=None, schedule=None
):
    """Why ``engine="compiled"`` cannot run this case, or None if it can."""
    # imported here: numba's import is paid only by those who use it
    from .compiled import compiled_support
    from .compiled_speed import compiled_speed_reason

    if is_sampled(gains):
        # held commands between the samples (compiled_sampled); the delay
        # is in the switch times
        from .compiled import compiled_method
        from .compiled_sampled import HeldCommand

        if compiled_method(method) != "DOP853":
            return (
                f"a sampled controller is compiled with method='DOP853' only, "
                f"got {method!r}"
            )
        gains, delay = HeldCommand(0.0, 0.0), 0.0
    reason = compiled_support(path, gains, delay=delay, method=method, model=model)
    if reason is None and feedforward == "dynamic":
        reason = "feedforward='dynamic' is not compiled"
    if reason is None:
        reason = compiled_speed_reason(profile, schedule, method=method)
    return reason


def _check_compiled(
    path, gains, *, delay, method, model, feedforward, profile=None, schedule=None
) -> None:
    """Raise ValueError if ``engine="compiled"`` cannot run this case."""
    reason = _compiled_reason(
        path, gains, delay=delay, method=method, model=model, feedforward=feedforward,
        profile=profile, schedule=schedule,
    )  # fmt: skip
    if reason is not None:
        raise ValueError(
            f"engine='compiled' cannot run this simulation: {reason}; use "
            "engine='numpy'"
        )


def _choose_engine(
    path, gains, *, delay, method, model, feedforward, profile=None, schedule=None
):
    """The engine ``engine="auto"`` runs, and the compiled engine's table.

    Returns ``("compiled", table)`` where the compiled engine can run the
    case, else ``("numpy", None)``. `method` is already resolved (DOP853
    for a stiff run under ``method="auto"``, which the compiled engine then
    runs as capped DOP853 or Radau, see ``_RADAU_FROM_STEPS``; LSODA and
    BDF: numpy). A path whose curvature table misses its tolerance goes to
    numpy too. A varying speed (`profile`, `schedule`) goes to numpy where
    it is evaluated in Python (a function profile or schedule).
    """
    try:
        import numba  # noqa: F401  (the optional extra "fast")
    except ImportError:
        return "numpy", None
    if _compiled_reason(
        path, gains, delay=delay, method=method, model=model, feedforward=feedforward,
        profile=profile, schedule=schedule,
    ):  # fmt: skip
        return "numpy", None
    table = _path_table(path)
    return ("numpy", None) if table is None else ("compiled", table)


#: Curvature tables by :func:`~fws_control.simulation.options.path_key`,
#: None where the path has none within its tolerance.
_TABLES: dict = {}
#: Paths whose tables are remembered (the oldest goes first).
_TABLES_SIZE = 16


def _auto_compiled_method(opts, *, stiff_auto, ctrl, tau, duration, profile) -> dict:
    """The compiled engine's options under ``method="auto"``: DOP853, with
    its steps held to half its stability bound for an actuator (see
    ``_CAPPED_STEP``), or Radau beyond ``_RADAU_FROM_STEPS`` such steps (the
    paper's kinematic loop only: with a delay, the dynamic model, a
    controller's law or a varying speed the compiled engine has DOP853
    only)."""
    if (
        stiff_auto
        and ctrl is None
        and duration > _RADAU_FROM_STEPS * _CAPPED_STEP * tau
        and not opts["delay"] > 0.0
        and opts["model"] == "kinematic"
        and profile is None
    ):
        return {"method": "Radau"}
    if tau is None:
        return {"method": "DOP853"}
    return {"method": "DOP853", "max_step": _CAPPED_STEP * tau}


def _kernels_ready(method, opts, law, profile) -> bool:
    """Whether a call of ``engine="auto"`` runs compiled now: its kernel set
    cached, or to compile here (see
    :func:`~fws_control.simulation.precompile.ready_or_background`)."""
    from .precompile import kernel_set, ready_or_background

    name = kernel_set(
        method=method, delay=opts["delay"], model=opts["model"], law=law,
        profile=profile,
    )  # fmt: skip
    return ready_or_background(name)


def _path_table(path):
    """The compiled engine's curvature table of `path`, or None if it has none.

    Remembered per path (paths are frozen; see ``path_key``): a table
    depends on the path only, and a loop of runs on one path builds it once.
    """
    key = path_key(path)
    if key is not None and key in _TABLES:
        return _TABLES[key]
    from .compiled import curvature_table

    try:
        table = curvature_table(path)
    except ValueError:
        table = None
    if key is not None:
        if len(_TABLES) >= _TABLES_SIZE:
            _TABLES.pop(next(iter(_TABLES)))
        _TABLES[key] = table
    return table


def _run_compiled(
    vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl, *, out=None
):
    """:func:`run_chunk` on the compiled engine (each run alone).

    Same arguments and results, the peaks those of each run's own dense
    output (:func:`~fws_control.simulation.compiled.compiled_peaks`);
    module-level so that Dask can pickle it. A run's solver, steps and stop
    are its own, so a failure needs no isolation. `out`: the chunk's rows of
    the batch's signals, written in place (then returned as the signals).
    """
    from .compiled import compiled_method, compiling

    # the first compilation in a process is announced once, with the time
    # of the three stages this call compiles (nothing when they are cached),
    # those of the kernels of every feature if the call uses one
    varying = getattr(opts.get("profile"), "is_constant", True) is False
    features = (
        ctrl is not None or bool(opts.get("delay")) or opts.get("model") == "dynamic"
        or varying
    )  # fmt: skip
    stages = (compiled_method(opts["method"]), "signals", "peaks")
    with compiling(*stages, features=features):
        return _run_compiled_stages(
            vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl, out
        )


def _run_compiled_stages(
    vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts, ctrl, out
):
    # _run_compiled's integration, signals and exact peaks
    from .compiled import (
        compiled_method,
        compiled_outputs,
        compiled_peaks,
        curvature_table,
        integrate_compiled,
    )

    # a controller's compiled law (compiled_laws), else the paper's law
    g = SteeringGains(k1, k2, a) if ctrl is None else ctrl
    profile = opts.get("profile")
    # once per call (simulate_batch builds it), for the integration, the
    # outputs and the peaks
    table = opts.get("curvature_table")
    if table is None:
        table = _path_table(path)
    if table is None:
        table = curvature_table(path)  # (raises: the path has no table)
    # each distinct initial pose projected once (a sweep often shares one);
    # distinct by bit pattern, so the numbers are those of every run's own
    if len(x0) == 1:
        path_state = initial_path_state(path, x0[:, :3])
    else:
        rows = np.ascontiguousarray(x0[:, :3]).view(np.dtype((np.void, 24))).ravel()
        _, first, inverse = np.unique(rows, return_index=True, return_inverse=True)
        path_state = initial_path_state(path, x0[first, :3])[inverse.ravel()]
    if is_sampled(ctrl):
        from .compiled_sampled import run_sampled

        return run_sampled(
            vehicle, path, ctrl, speed=speed, path_state=path_state,
            initial_heading=x0[:, 2], t_eval=t, time_constant=tau, table=table,
            rtol=opts["rtol"], atol=opts["atol"],
            max_step=opts.get("max_step", math.inf), delay=opts["delay"],
            model=opts["model"], tyre=opts["tyre"],
            body_state=x0[:, 3:] if opts["model"] == "dynamic" else None,
            out=out,
        )  # fmt: skip
    states, status, message, t_stop, _ = integrate_compiled(
        vehicle,
        table if ctrl is None else path,  # (a law may need the path's position)
        g,
        speed=speed,
        feedforward=feedforward,
        path_state=path_state,
        t_eval=t,
        time_constant=tau,
        rtol=opts["rtol"],
        atol=opts["atol"],
        max_step=opts.get("max_step", math.inf),
        method=compiled_method(opts["method"]),
        solution=(solution := []),
        delay=opts["delay"],
        model=opts["model"],
        tyre=opts["tyre"],
        body_state=x0[:, 3:] if opts["model"] == "dynamic" else None,
        profile=profile,
        schedule=opts.get("schedule"),
    )
    if ctrl is not None and profile is not None:
        # a controller at a varying speed: the numpy engine's signals and
        # peaks of the compiled solution
        from .compiled_laws import controller_outputs

        signals, peaks, peak_times = controller_outputs(
            vehicle, path, ctrl, speed=speed, feedforward=feedforward,
            time_constant=tau, states=states, initial_heading=x0[:, 2],
            solution=solution[0], t_eval=t, t_stop=t_stop, model=opts["model"],
            tyre=opts["tyre"],
        )  # fmt: skip
        if out is not None:
            out[...] = signals
            signals = out
        return signals, status, message, t_stop, peaks, peak_times
    if profile is not None:
        return _varying_speed_outputs(
            vehicle, path, g, speed, feedforward, x0, t, tau, opts, out, states,
            status, message, t_stop, solution[0],
        )  # fmt: skip
    signals = compiled_outputs(
        vehicle,
        path,
        g,
        speed=speed,
        feedforward=feedforward,
        time_constant=tau,
        states=states,
        initial_heading=x0[:, 2],
        table=table,
        out=out,
        solution=solution[0],
        t_eval=t,
        model=opts["model"],
        tyre=opts["tyre"],
    )
    peaks, peak_times = compiled_peaks(
        vehicle,
        table if ctrl is None else path,  # (a law may need the path's position)
        g,
        speed=speed,
        feedforward=feedforward,
        time_constant=tau,
        solution=solution[0],
        t_eval=t,
        signals=signals,
        t_stop=t_stop,
        model=opts["model"],
        tyre=opts["tyre"],
    )
    return signals, status, message, t_stop, peaks, peak_times


def _varying_speed_outputs(
    vehicle, path, g, speed, feedforward, x0, t, tau, opts, out, states, status,
    message, t_stop, solution,
):  # fmt: skip
    """Signals and exact peaks of compiled varying-speed runs.

    The numpy engine's :func:`compute_outputs` and :func:`exact_peaks` on
    the runs' compiled dense output (:class:`~.dense.CompiledDense`): the longitudinal
    signals and the scheduled command's rate are the numpy engine's.
    """
    kw = dict(
        feedforward=feedforward, time_constant=tau, model=opts["model"],
        tyre=opts["tyre"], profile=opts["profile"], schedule=opts.get("schedule"),
    )  # fmt: skip
    signals = outputs_in_blocks(
        vehicle, path, g, speed=speed, states=states, initial_heading=x0[:, 2],
        delay=0.0, times=t, **kw,
    )  # fmt: skip
    if out is not None:
        out[...] = signals
        signals = out
    # every run on its own steps, a block of runs at once
    dense = CompiledDense(
        solution.records, solution.offsets, solution.initial_state, float(t[0])
    )
    n = speed.size
    k1, k2, a = (np.broadcast_to(np.ravel(v), (n,)) for v in (g.k1, g.k2, g.ratio))
    peaks, peak_times = exact_peaks_per_run(
        vehicle, path, lambda lo, hi: SteeringGains(k1[lo:hi], k2[lo:hi], a[lo:hi]),
        speed=speed, solution=dense, t_eval=t, signals=signals, t_stop=t_stop,
        **kw,
    )  # fmt: skip
    return signals, status, message, t_stop, peaks, peak_times


class _NoBar:
    """The progress bar's interface when no bar is shown."""

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def _simulate_run(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains | LateralController,
    *,
    speed: Any,
    initial_state: Any,
    duration: float,
    feedforward: bool | str = True,
    dt: float = 0.01,
    t_eval: Any = None,
    actuator_time_constant: float | None = None,
    delay: float = 0.0,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    model: str = "kinematic",
    tyre: str = "linear",
    engine: str = "auto",
    profile: SpeedProfile | None = None,
    schedule: Any = None,
) -> SimulationResult:
    """:func:`simulate` on the resolved plant (its vehicle, speed, model,
    tyre and lag as separate arguments)."""
    if isinstance(gains, LateralController):
        n_gains = gains.runs() or 1
    elif isinstance(gains, SteeringGains):
        # (validated once, by prepare_runs; here only counted)
        n_gains = np.broadcast(gains.k1, gains.k2, gains.ratio).size
    else:
        n_gains = run_gains(gains, name="gains").k1.size
    if n_gains != 1:
        raise ValueError(
            f"controller must be scalar for simulate (got {n_gains} designs); use "
            "simulate_batch for several runs"
        )
    if np.size(speed) != 1:
        raise ValueError(
            f"speed must be a scalar for simulate, got {speed!r}; use "
            "simulate_batch for several runs"
        )
    if np.ndim(initial_state) != 1:
        raise ValueError(
            "initial_state must be (x_R, y_R, psi) for simulate, got shape "
            f"{np.shape(initial_state)}; use simulate_batch for several runs"
        )
    return _simulate_batch(
        vehicle,
        path,
        gains,
        speed=speed,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        dt=dt,
        t_eval=t_eval,
        actuator_time_constant=actuator_time_constant,
        delay=delay,
        method=method,
        rtol=rtol,
        atol=atol,
        model=model,
        tyre=tyre,
        engine=engine,
        chunk_size=1,
        progress=False,
        profile=profile,
        schedule=schedule,
        squeeze=True,
    )


def _simulate_batch(
    vehicle: Vehicle,
    path: Path,
    gains: SteeringGains | Any,
    *,
    speed: Any,
    initial_state: Any,
    duration: float,
    feedforward: bool | str = True,
    dt: float = 0.01,
    t_eval: Any = None,
    actuator_time_constant: float | None = None,
    delay: float = 0.0,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    model: str = "kinematic",
    tyre: str = "linear",
    engine: str = "auto",
    chunk_size: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    signals: Any = None,
    out: np.ndarray | None = None,
    profile: SpeedProfile | None = None,
    schedule: Any = None,
    squeeze: bool = False,
) -> SimulationResult:
    """:func:`simulate_batch` on the resolved plant (its vehicle, speed,
    model, tyre and lag as separate arguments). With a varying speed
    `profile`, `speed` is only its direction (+1 or -1) and the recorded
    speed of each run is the profile's at its start; with a `schedule` the
    recorded gains are the schedule's at that speed. ``squeeze=True``
    (:func:`simulate`, one run): the result is the run squeezed, its grid
    ending at its last sample (views of the batch's arrays)."""
    if not isinstance(engine, str) or engine not in _ENGINES:
        raise ValueError(f"engine must be one of {_ENGINES}, got {engine!r}")
    if profile is not None:
        check_profile_run(
            profile, model=model, delay=delay, feedforward=feedforward,
            gains=gains, engine=engine,
        )  # fmt: skip
    auto_method = isinstance(method, str) and method == "auto"
    opts: dict[str, Any] = {
        "method": method,
        "rtol": rtol,
        "atol": atol,
        "delay": _delay(delay),
        "model": model,
        "tyre": tyre,
    }
    kept = check_signals(signals)
    k1, k2, a, V, x0, t, tau, ctrl = prepare_runs(
        vehicle,
        path,
        gains,
        speed,
        initial_state,
        duration,
        dt,
        t_eval,
        actuator_time_constant,
        opts,
        # a given out holds the kept signals: only the chunk's working set
        # is counted (below)
        kept=0 if out is not None else len(kept),
    )
    n = k1.size
    if profile is not None:
        # the speed of each run at its start: the record of the run
        x_start = np.full(n, float(t[0]))
        if profile.of == "distance":
            x_start = initial_path_state(path, x0[:, :3])[:, 0]
        V = np.asarray(profile(x_start), dtype=float)
        if schedule is not None:
            g0 = scheduled_gains(schedule, V)
            k1, k2, a = (
                np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy()
                for v in (g0.k1, g0.k2, g0.ratio)
            )
        opts["profile"], opts["schedule"] = profile, schedule
        if engine == "auto" and schedule is not None:
            _say_if_schedule_not_compiled(schedule)
    if out is not None:
        check_out(out, (n, len(kept), t.size))
    # False, True (eq. 26) or "dynamic" (dynamics.dynamic_feedforward)
    feedforward = check_feedforward(feedforward, speed=V)
    if feedforward == "dynamic":
        require_dynamics(vehicle, tyre=opts["tyre"])
        if np.any(V <= 0.0):
            raise ValueError(
                f"speed must be > 0 for feedforward='dynamic', got {speed!r}"
            )
    else:
        feedforward = bool(feedforward)
    table = None
    # (one record of the gains for the engine's checks below)
    law = SteeringGains(k1, k2, a) if ctrl is None else ctrl
    chosen_for = None
    # With an actuator, "auto" on the compiled engine is DOP853 with its steps
    # held to half its stability bound (see _CAPPED_STEP), or Radau beyond
    # _RADAU_FROM_STEPS such steps, also where the numpy engine would take
    # LSODA or Radau: the compiled engine runs every stiff case.
    stiff_auto = auto_method and tau is not None
    auto_engine = engine == "auto"
    if engine == "auto":
        chosen_for = "DOP853" if stiff_auto else opts["method"]
        engine, table = _choose_engine(
            path,
            law,
            delay=opts["delay"],
            method=chosen_for,
            model=opts["model"],
            feedforward=feedforward,
            profile=profile,
            schedule=schedule,
        )
    auto_opts: dict[str, Any] = {}  # the compiled engine's under method="auto"
    if engine == "compiled" and auto_method:
        auto_opts = _auto_compiled_method(
            opts, stiff_auto=stiff_auto, ctrl=ctrl, tau=tau,
            duration=float(t[-1] - t[0]), profile=profile,
        )  # fmt: skip
    compiled_method = auto_opts.get("method", opts["method"])
    if (
        engine == "compiled"
        and auto_engine
        and not _kernels_ready(compiled_method, opts, law, profile)
    ):
        # (a background process compiles them; the numpy engine runs the
        # method prepare_runs resolved)
        engine, table = "numpy", None
    if engine == "compiled":
        opts.update(auto_opts)
        if chosen_for is None or opts["method"] != chosen_for:
            # (not yet checked for this method by _choose_engine)
            _check_compiled(
                path,
                law,
                delay=opts["delay"],
                method=opts["method"],
                model=opts["model"],
                feedforward=feedforward,
                profile=profile,
                schedule=schedule,
            )
        if table is None:
            table = _path_table(path)
        if table is None:
            from .compiled import curvature_table

            table = curvature_table(path)  # (raises: the path has no table)
        opts["curvature_table"] = table  # built once, for every chunk
    if chunk_size is None:
        chunk_size = DEFAULT_CHUNK_SIZE
        if engine == "numpy" and opts["method"] == "LSODA":
            # LSODA's Jacobian of the stacked runs is dense. Measured (CPU
            # per run, T = 0.05 s, curve scenario): 16 runs per chunk 17.6 ms
            # over 15 s and 28 ms over 150 s, 32 runs 12.7 and 39 ms, one
            # run 156 and 187 ms. The stacked runs share LSODA's steps and
            # error norm: a run 0.72 tolerances off alone was 0.74 and 2.0 off
            # in two mixed chunks (within its tolerance, not bitwise alone;
            # chunk_size=1 is).
            chunk_size = LSODA_MAX_RUNS
    chunk_size = check_chunk_size(
        chunk_size, runs=n, kept=kept, out=out, duration=duration, dt=dt,
        t_eval=t_eval, samples=t.size,
    )  # fmt: skip
    bounds = [(i, min(i + chunk_size, n)) for i in range(0, n, chunk_size)]
    if progress is None:
        progress = _stderr_is_tty()
    progress = check_bool("progress", progress)

    run = run_isolated if engine == "numpy" else _run_compiled
    # both engines give the exact peaks of the continuous solution (the
    # compiled one on each run's own dense output)
    exact = True
    reduce = kept != SIGNALS
    if reduce:
        rows = [SIGNALS.index(k) for k in kept]
        horizon = not {"e", "theta"} <= set(kept)
        run = functools.partial(run_kept, run, rows, horizon, exact)

    def args(lo: int, hi: int) -> tuple:
        return (
            vehicle,
            path,
            k1[lo:hi],
            k2[lo:hi],
            a[lo:hi],
            V[lo:hi],
            feedforward,
            x0[lo:hi],
            t,
            tau,
            opts,
            chunk_controller(ctrl, lo, hi),
        )

    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(bounds), desc="simulate_batch", unit="chunk")
    else:
        # no bar, no tqdm import (tqdm.auto pulls in asyncio: 0.05 s of CPU
        # in a fresh process, a tenth of a short CLI call)
        bar = _NoBar()
    # The chunks are written into the batch's arrays of the kept signals as
    # they arrive (a single chunk is kept as it is) and freed, so no second
    # copy of the signals builds up: the peak memory is the result and one
    # chunk's working set.
    single = len(bounds) == 1 and out is None
    data: Any  # the batch's array (or out=), None while a single chunk comes
    if out is not None:
        data = out
    else:
        data = None if single else np.empty((n, len(kept), t.size))
    status = np.empty(n, dtype=object)
    message = np.empty(n, dtype=object)
    t_stop = np.empty(n)
    peak = np.empty((n, len(PEAK_SIGNALS)))
    peak_time = np.empty((n, len(PEAK_SIGNALS)))
    samples = np.empty(n, dtype=np.int64) if reduce else None
    metrics = np.empty((n, len(HORIZON_METRICS))) if reduce and horizon else None

    def keep(j, chunk, written=False):
        nonlocal data
        lo, hi = bounds[j]
        if reduce and len(chunk) == 6:  # a lost Dask task: reduced here
            chunk = reduce_chunk(chunk, rows, horizon, exact, args(lo, hi))
        if single:
            data = chunk[0]
        elif not written:
            data[lo:hi] = chunk[0]
        parts = (status, message, t_stop, peak, peak_time, samples, metrics)
        for whole, part in zip(parts, chunk[1:], strict=False):
            if whole is not None:
                whole[lo:hi] = part

    cluster_lost = None
    try:
        if client is None:
            # The compiled engine writes all signals straight into the
            # batch's array: no chunk buffer to fill and copy (46 MB for 256
            # runs of the paper's scenario; about 10 us of CPU per run).
            direct = engine == "compiled" and not reduce and data is not None
            for j, (lo, hi) in enumerate(bounds):
                if direct:
                    # (a memmap's rows as a plain array view: the same memory)
                    part = np.asarray(data[lo:hi])
                    keep(j, _run_compiled(*args(lo, hi), out=part), True)
                else:
                    keep(j, run(*args(lo, hi)))
                bar.update(1)
        else:
            cluster_lost = run_on_dask(client, bounds, args, keep, t.size, bar, run)
    finally:
        bar.close()

    if squeeze:
        # the one run's grid ends at its last sample (views, no copy)
        if samples is None:
            samples = np.count_nonzero(
                np.isfinite(data[:, kept.index("s"), :]), axis=1
            ).astype(np.int64)
        count = int(samples[0])
        t, data = t[:count], data[:, :, :count]
    result = SimulationResult(
        t=t,
        signals=data,
        run_status=status.astype(str),
        run_message=tuple(str(m) for m in message),
        run_t_stop=t_stop,
        # without the samples, the sample peaks were computed per chunk
        run_peak=peak if exact or reduce else None,
        run_peak_time=peak_time if exact or reduce else None,
        run_speed=V,
        run_k1=k1,
        run_k2=k2,
        run_ratio=a,
        run_initial_state=x0[:, :3],
        feedforward=feedforward,
        squeeze=squeeze,
        vehicle=vehicle,
        path=path,
        method=opts["method"]
        if isinstance(opts["method"], str)
        else opts["method"].__name__,
        model=opts["model"],
        tyre=opts["tyre"],
        engine=engine,
        signal_names=kept,
        run_samples=samples,
        run_metrics=metrics,
        peaks_exact=exact,
        speed_profile=profile,
    )
    if cluster_lost is not None:
        raise ClusterLostError(cluster_lost, result=result)
    return result


def _delay(delay: Any) -> float:
    """`delay` checked: a float >= 0 as it is, anything else by check_delay."""
    if type(delay) is float and 0.0 <= delay < math.inf:
        return delay
    return check_delay(delay)


def _say_if_schedule_not_compiled(schedule) -> None:
    """Warn that a gain schedule given as a function runs on the numpy engine."""
    from ..schedule import GainSchedule

    if isinstance(schedule, GainSchedule):
        return
    warnings.warn(
        f"the gain schedule {schedule!r} is a Python function, evaluated at "
        "every step: this varying-speed run is not compiled and runs on the "
        "numpy engine (a GainSchedule table is compiled)",
        RuntimeWarning,
        stacklevel=5,
    )


def simulate(
    plant: LateralPlant,
    path: Path,
    controller: SteeringGains | LateralController | None = None,
    *,
    initial_state: Any,
    duration: float,
    delay: float = 0.0,
    feedforward: bool | str = True,
    dt: float = 0.01,
    t_eval: Any = None,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    engine: str = "auto",
    speed: SpeedProfile | None = None,
    **kwargs: Any,
) -> SimulationResult:
    r"""Simulate the closed loop (one run) with the fast path-frame engine.

    Integrates the corrected path-frame model (eqs. 17-19 with the curvature
    :math:`\kappa(s)` of the path at the projection point) closed with the
    controller of eqs. (24)-(29) in one right-hand side. The initial pose is
    projected onto the path once; the global pose is reconstructed from
    ``(s, e, theta)``.

    Parameters
    ----------
    plant : LateralPlant
        The simulated system, the same object the analysis takes: its
        vehicle (geometry and optional steering limits: angle limits clip
        the commands, rate limits insert the actuator of
        :func:`~fws_control.steering_actuator`), its `speed` :math:`V`
        [m/s] (one nonzero number; negative: reversing), its `model` and
        `tyre` and its `steering_lag`. ``model="kinematic"`` and
        ``model="paper"`` are two linearisations of one nonlinear kinematic
        model: both simulate that nonlinear model (eqs. 17-19). With
        ``model="dynamic"`` the single-track model of
        :mod:`fws_control.dynamics` is integrated (tyre slip; lateral velocity
        and yaw rate as states; `speed` is its constant longitudinal speed
        :math:`u > 0`), with the plant's `tyre` (linear, or the saturating
        simplified magic formula). The path errors are those of the
        rear-axle centre R in both models, so every controller applies
        unchanged; delay and lag combine with either model. The plant's
        `steering_lag` :math:`T` [s] is a first-order actuator
        :math:`T\dot\delta = \delta_{cmd} - \delta` on each axle, whose rate
        the vehicle's rate limits clip (its states start at the initial
        command); the simulation runs one time constant for both axles, so
        a (front, rear) pair must hold equal values. ``None``: an actuator
        only if the vehicle has a rate limit, with
        :data:`~fws_control.controllers.DEFAULT_ACTUATOR_TIME_CONSTANT`.
        The plant's `curvature` is its linearisation point and is not used
        here: the path gives the curvature along the run.
    path : Path
        Reference path (e.g. :class:`~fws_control.Straight`,
        :class:`~fws_control.Arc`).
    controller : SteeringGains, LateralController or GainSchedule
        Scalar ``k1, k2, ratio`` of the paper's law, or any controller of
        :mod:`fws_control.baselines` (e.g. :class:`~fws_control.PurePursuit`),
        which carries its own feedforward (`feedforward` applies to gains
        only), or a gain schedule (:class:`~fws_control.GainSchedule`, or
        any object whose ``at(speed)`` returns SteeringGains): its gains at
        the plant's speed. A sampled controller (one with a
        :attr:`~fws_control.LateralController.sample_time`, e.g.
        :class:`~fws_control.MPCController`) measures the state at the
        sample times ``k * sample_time`` and its command is held from
        ``k * sample_time + delay`` until the next one (zero-order hold; the
        output at a switch time shows the new command, whose rate is zero
        between switches), on either engine.
    initial_state : array_like
        ``(x_R, y_R, psi)`` of the rear-axle centre [m, m, rad].
    duration : float
        Final time [s], > 0.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        Include the curvature feedforward (default ``True``, the same as
        ``"kinematic"``: eq. 26); ``False`` is the feedback-only controller;
        ``"dynamic"`` the front and rear angles of
        :func:`~fws_control.dynamics.dynamic_feedforward` (for the plant's
        tyre model), which hold the dynamic model on a curve without offset.
    dt : float, optional
        Nominal spacing of the output times [s] (the solver chooses its own
        steps). The grid is ``linspace(0, duration, round(duration/dt) + 1)``,
        so the actual spacing is ``duration/round(duration/dt)`` (at least
        one interval): pass `t_eval` for exact times. It sets the output
        only, not the accuracy (`rtol`, `atol`); the signals of one call may
        not exceed
        :data:`~fws_control.simulation.options.MAX_OUTPUT_BYTES` (2 GiB).
    t_eval : array_like, optional
        Output times instead of `dt`; increasing, from 0 to at most
        `duration`.
    delay : float, optional
        Input delay :math:`\tau_d \ge 0` [s] on the steering command: the
        controller acts on the measurements of ``t - delay`` (perception and
        computation latency). Initial history: the state is held at its
        initial value before ``t = 0``, so the command is the one of the
        initial state until ``t = delay``. Integrated by the method of steps
        (see :func:`~fws_control.simulation.engine.integrate`). Default 0.
        The delay belongs to the loop, not to the plant, as in the analysis
        (:func:`~fws_control.critical_delay` of a plant and gains; the
        delayed charts take ``delay=``).
    method : str or scipy.integrate.OdeSolver, optional
        Integration method: ``"auto"`` (default), a name in ``"DOP853",
        "RK45", "RK23", "Radau", "BDF", "LSODA"`` or an OdeSolver class. The
        engine steps that solver itself, as :func:`scipy.integrate.solve_ivp`
        would, so that it can stop a run at a singular state. ``"auto"`` is
        DOP853, or Radau when a fast actuator makes the loop stiff, or LSODA
        for a run long enough that the actuator's stability bound would cost
        DOP853 more than 10 steps (rule and measurements in
        :func:`~fws_control.simulation.options.choose_method`); the result's
        ``method`` says which. An explicit method chosen for a stiff loop
        gives a :class:`RuntimeWarning`.
    rtol, atol : float, optional
        Relative and absolute tolerances of the solver: rtol in
        ``[100 eps, 0.1]`` (scipy's own floor to a 10 % error per step),
        atol in ``[1e-20, 0.1]`` [m, rad]; see
        :func:`~fws_control.simulation.options.check_tolerances`.
    engine : {"auto", "numpy", "compiled"}, optional
        ``"compiled"``: the numba ports of DOP853 and Radau of
        :mod:`fws_control.simulation.compiled` (extra ``fast``), each run
        with its own steps and stop, at compiled speed. It runs the paper's
        law (:class:`~fws_control.SteeringGains`) on the kinematic model
        (and on the dynamic model with DOP853), and a
        controller that declares a compiled law
        (:meth:`~fws_control.LateralController.compiled_law`: the
        baselines, with DOP853; their signals and peaks by the
        numpy engine's formulas on each run's dense output, see
        :mod:`~fws_control.simulation.compiled_laws`),
        with ``method="DOP853"``, ``"Radau"`` or ``"auto"``
        (which then means DOP853; with an actuator of time constant T, its
        steps held to 3.2 T, half its stability bound, where its error
        estimate bounds the error again, up to 2,500 such steps, and Radau
        beyond: 9-13 ms per run of the paper's curve scenario whatever T
        and the duration; with a delay DOP853 only, its steps at most the
        delay: the method of steps, its clips min/max as the numpy
        engine's) and `feedforward` True or
        False, on any path whose curvature it can tabulate; any other case
        raises :class:`ValueError` (no fallback). Its results agree with the
        numpy engine's to the solver tolerance (the same method; angle and
        rate limits are switched as events, and a run stops ``1e-3`` before
        a singularity: see that module), and its
        :attr:`~fws_control.SimulationResult.peaks` are the exact peaks of
        each run's own dense output
        (:func:`~fws_control.simulation.compiled.compiled_peaks`).
        ``"numpy"``: the engine described above, for every case.
        ``"auto"`` (default): the compiled engine where numba is installed
        and it runs the case (with ``method="auto"`` and an actuator: DOP853
        held to 3.2 T or Radau, as above; the numpy engine's own choice is
        :func:`~fws_control.simulation.options.choose_method`); the numpy
        engine otherwise, and while a background process compiles the
        kernels the case needs (``FWS_CONTROL_COMPILE=foreground``: the call
        compiles them and waits; see
        :func:`~fws_control.simulation.precompile.ready_or_background`). The
        result's ``engine`` says which ran, and is bitwise the result of
        asking for that engine explicitly.
    speed : SpeedProfile, optional
        A speed that varies along the run (:class:`~fws_control.SpeedProfile`:
        a table of the time or of the arc length, a braking manoeuvre, a
        function), instead of the plant's constant speed, which is then its
        linearisation point only. A table (of the time or the arc length)
        runs on the compiled engine (DOP853), with a gain schedule only a
        :class:`~fws_control.GainSchedule` whose grid holds the profile's
        speeds; a function profile or schedule runs on the numpy engine
        (``engine="auto"`` chooses it, with a RuntimeWarning for a schedule
        function; ``"compiled"`` raises). The
        dynamic model's longitudinal speed :math:`u` follows the profile,
        and a gain schedule passed as `controller` (a
        :class:`~fws_control.GainSchedule` or a function ``speed ->
        SteeringGains``) is read at the current speed at every step. The
        result's :attr:`~fws_control.SimulationResult.longitudinal_speed`,
        ``longitudinal_accel``, ``longitudinal_force`` and
        ``friction_usage`` report the longitudinal motion. Not with a
        delay, ``feedforward="dynamic"`` or a controller of
        :mod:`fws_control.baselines` (ValueError). A constant profile
        (:meth:`~fws_control.SpeedProfile.constant`) is the constant-speed
        run on the plant with that speed. See ``docs/varying_speed.md``.

    **kwargs
        Deprecated calling form, accepted until fws_control 0.4 with a
        :class:`FutureWarning`: a :class:`~fws_control.Vehicle` as `plant`
        with ``speed=``, ``model=`` ({"kinematic", "dynamic"}), ``tyre=``
        and ``steering_lag=`` (formerly ``actuator_time_constant=``), and
        ``gains=`` for `controller`. Any other keyword raises
        :class:`TypeError`.

    Returns
    -------
    SimulationResult
        One run, squeezed: ``res.e`` etc. have shape ``(time,)``,
        ``res.status`` is a str. If the run meets a singular state it stops
        there; ``status`` and ``message`` say why and the data end at the
        last output time before ``t_stop``.

    Raises
    ------
    TypeError
        If `plant` is not a :class:`~fws_control.LateralPlant` (a
        :class:`~fws_control.Vehicle` without ``speed=`` included), or for
        an unknown keyword.
    ValueError
        For non-scalar gains, plant speed or initial state (use
        :func:`simulate_batch`), a plant whose front and rear lags differ, a
        non-positive duration, an unknown method or feedforward, tolerances
        out of range, or an output larger than
        :data:`~fws_control.simulation.options.MAX_OUTPUT_BYTES`; for
        ``feedforward="dynamic"`` a vehicle without the dynamic data or a
        negative speed; for an unknown `engine`, or ``engine="compiled"``
        for a case it does not run (the message says why).
    AmbiguousProjectionError
        If the initial position has no unique closest point on the path.

    Examples
    --------
    >>> import fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> g = fws.double_root_gains(fws.LateralPlant(veh, speed=5.0, curvature=0.1),
    ...                           ratio=-1.0, pole=-1.0)
    >>> plant = fws.LateralPlant(veh, speed=5.0)
    >>> res = fws.simulate(plant, fws.Arc(curvature=0.1), g,
    ...                    initial_state=(0.0, -5.0, 0.0), duration=15.0)
    >>> res.status, round(float(res.e[0]), 6), round(float(res.e[-1]), 5)
    ('ok', -5.0, -3e-05)
    >>> len(res), res.e.shape
    (1, (1501,))
    """
    profile = speed_option(plant, speed, kwargs)
    vehicle, controller, plant_speed, model, tyre, lag = resolve_plant(
        "simulate", plant, controller, kwargs
    )
    profile, run_speed, controller, schedule = with_profile(
        profile, plant_speed, controller
    )
    if isinstance(plant, LateralPlant) and np.ndim(run_speed) != 0:
        raise ValueError(
            "plant.speed must be one speed (a scalar, nonzero, at most "
            f"{MAX_SPEED:g} m/s) for simulate, got an array of shape "
            f"{np.shape(run_speed)}: "
            f"{np.array2string(np.asarray(run_speed), threshold=6)}; "
            "use simulate_batch for several runs"
        )
    return _simulate_run(
        vehicle,
        path,
        controller,
        speed=run_speed,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        dt=dt,
        t_eval=t_eval,
        actuator_time_constant=lag,
        delay=delay,
        method=method,
        rtol=rtol,
        atol=atol,
        model=model,
        tyre=tyre,
        engine=engine,
        profile=profile,
        schedule=schedule,
    )


def simulate_batch(
    plant: LateralPlant,
    path: Path,
    controllers: SteeringGains | Any = None,
    *,
    initial_state: Any,
    duration: float,
    delay: float = 0.0,
    feedforward: bool | str = True,
    dt: float = 0.01,
    t_eval: Any = None,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    engine: str = "auto",
    speed: SpeedProfile | None = None,
    chunk_size: int | None = None,
    client: Any = None,
    progress: bool | None = None,
    signals: Any = None,
    out: np.ndarray | None = None,
    **kwargs: Any,
) -> SimulationResult:
    r"""Simulate many closed loops at once on stacked numpy state.

    Parameters
    ----------
    plant : LateralPlant
        The simulated system (shared by all runs), as in :func:`simulate`;
        its `speed` may be an array, one speed per run (1-D), broadcast
        against the gains and the initial states. Its `curvature` is not
        used (the path gives the curvature).
    path : Path
        Reference path (shared by all runs).
    controllers : SteeringGains, sequence of SteeringGains or LateralController
        Per-run gains: one :class:`~fws_control.SteeringGains` whose fields
        are arrays (e.g. from :func:`~fws_control.double_root_gains` over an
        array of ratios; flattened), or a sequence of them; or a controller
        of :mod:`fws_control.baselines` (its array parameters, if any, hold
        one value per run). A controller's runs record NaN gains. A gain
        schedule (:class:`~fws_control.GainSchedule`) gives each run its
        gains at that run's speed. A sampled controller (e.g.
        :class:`~fws_control.MPCController`) is held between its samples as
        in :func:`simulate`, each run with its own controller state.
    initial_state : array_like
        ``(x_R, y_R, psi)`` for all runs, or shape ``(runs, 3)``; with
        a ``model="dynamic"`` plant also ``(x_R, y_R, psi, v_y, r)`` or ``(runs,
        5)``, as in :func:`simulate`.
    duration : float
        Final time [s], > 0.
    feedforward : bool or {"kinematic", "dynamic"}, optional
        Curvature feedforward (default ``True``), as in :func:`simulate`.
    dt : float, optional
        Nominal output spacing [s], as in :func:`simulate`.
    t_eval : array_like, optional
        Output times instead of `dt`, as in :func:`simulate`.
    delay : float, optional
        Input delay [s] on the steering command, as in :func:`simulate` (a
        property of the loop, not of the plant).
    method : str or scipy.integrate.OdeSolver, optional
        Integration method, as in :func:`simulate`.
    rtol, atol : float, optional
        Solver tolerances, as in :func:`simulate`.
    engine : {"auto", "numpy", "compiled"}, optional
        Integration engine, as in :func:`simulate` (default ``"auto"``: the
        compiled engine where numba is installed and it runs the case --
        the paper's law, kinematic model, DOP853, Radau or ``"auto"``
        (with a delay, on the dynamic model or with a controller's
        compiled law, DOP853 or ``"auto"``) -- else the numpy engine, and
        the numpy engine while the kernels compile in the background). With
        ``"compiled"`` each run has its own steps, error norm and stop, so a
        run's result does not depend on the other runs (nor on
        `chunk_size`).
    speed : SpeedProfile, optional
        A speed that varies along the run, shared by all runs, as in
        :func:`simulate` (the plant's `speed` then must be one number: its
        linearisation point). Each run's recorded ``speed`` is the
        profile's at its start. A table runs on the compiled engine under
        ``"auto"`` (see :func:`simulate`).
    chunk_size : int, optional
        Runs per chunk (one solver; one Dask task); default
        :data:`DEFAULT_CHUNK_SIZE`, or
        :data:`~fws_control.simulation.options.LSODA_MAX_RUNS` (16) when the
        numpy engine integrates with LSODA (``method="LSODA"``, or what
        ``method="auto"`` picks for a stiff actuator over a long run).
        Smaller chunks decouple the step sizes of runs with very different
        dynamics.
    client : dask.distributed.Client, optional
        Submit the chunks to this Dask cluster (needs the extra
        ``distributed``). The vehicle, path and arguments are pickled to the
        workers. Chunks that the cluster loses (a task cancelled, the
        scheduler gone) are marked ``"failed"`` with NaN data and a
        :class:`RuntimeWarning`; the finished chunks are kept. A cluster
        left with no worker for 60 s raises
        :class:`~fws_control.ClusterLostError`, whose ``result`` holds the
        finished chunks (the pending runs marked ``"failed"``).
    progress : bool, optional
        Show a tqdm progress bar over the chunks. ``None`` (default): only if
        standard error is a terminal.
    signals : None, sequence of str or "metrics", optional
        The time series to keep, for sweeps too large to hold them all.
        ``None`` (default): all of
        :data:`~fws_control.simulation.SIGNALS`. A sequence of their names:
        only those (held in the order of ``SIGNALS``; the result's
        ``signal_names`` says which). ``"metrics"``: none. Each chunk
        computes its signals, writes the kept ones into the preallocated
        result and is freed, so the peak memory is the returned data and one
        chunk's working set, and the budget
        :data:`~fws_control.simulation.options.MAX_OUTPUT_BYTES` counts the
        kept signals only (and one chunk's full signals). Whatever is kept,
        the result holds per run the status, ``t_stop``, the peaks
        (:attr:`~fws_control.SimulationResult.peaks`, computed before the
        signals are dropped: exact on either engine) and, when ``e`` or
        ``theta`` is dropped, the horizon metrics of
        :func:`~fws_control.tracking_metrics` (settling time, overshoot, RMS
        and steady-state errors, with its default settings), so
        ``tracking_metrics(result)`` works on every result.
        Reading a signal not kept (``result.theta``,
        :meth:`~fws_control.SimulationResult.signal`, ``plot``) raises
        :class:`~fws_control.SignalNotKeptError`.
    out : ndarray, optional
        Where to write the kept signals: a writeable, C-contiguous float64
        array (or :class:`numpy.memmap`) of shape ``(runs, len(kept),
        time)``, with ``time`` the number of output times; the result's
        ``signals`` is a view of it (the same memory). Each chunk is written
        into it as it finishes. One array reused across sweeps of the same
        size spares the kernel's providing fresh memory for every result
        at its first touch (measured on the paper's scenario: from next to
        nothing to about 150 us of CPU per run in best-of-5 timings, and up
        to 450 us of system time in single batches, next to the compiled
        engine's own 300 us: ``docs/performance.md``); a
        memory map of a ``.npy`` file
        (:func:`numpy.lib.format.open_memmap`) streams a sweep larger than
        memory to disk. The output budget
        :data:`~fws_control.simulation.options.MAX_OUTPUT_BYTES` then counts
        one chunk's working set only. If the call raises, `out` may hold
        some runs' signals. Not with ``signals="metrics"``. A result whose
        `out` is written again (by another sweep) shows the new signals
        next to its own per-run values: copy the signals of a result you
        keep (``result.signals.copy()``).

    **kwargs
        Deprecated calling form, accepted until fws_control 0.4 with a
        :class:`FutureWarning`: a :class:`~fws_control.Vehicle` as `plant`
        with ``speed=``, ``model=`` ({"kinematic", "dynamic"}), ``tyre=``
        and ``steering_lag=`` (formerly ``actuator_time_constant=``), and
        ``gains=`` for `controllers`. Any other keyword raises
        :class:`TypeError`.

    Returns
    -------
    SimulationResult
        Not squeezed, whatever the number of runs: signals of shape ``(runs,
        time)`` on the common output grid, NaN after a run's stop; per-run
        ``status``, ``t_stop``, ``speed``, ``k1``, ``k2``, ``ratio``. The
        number of runs is the broadcast of the numbers of gains, speeds and
        initial states.

    Raises
    ------
    ValueError
        If the per-run arguments do not broadcast, for an invalid
        `chunk_size`, for `signals` naming an unknown or repeated signal,
        empty or another str than ``"metrics"``, for an `out` of another
        shape or dtype, not C-contiguous or read-only (or given with
        ``signals="metrics"``), or as in :func:`simulate`.
    TypeError
        If `plant` is not a :class:`~fws_control.LateralPlant`, for an
        unknown keyword, if `controllers` is not a SteeringGains or a
        sequence of them, `signals` is not None, a str or a sequence of
        str, or `out` is not a numpy array.
    ClusterLostError
        If the Dask cluster of `client` has had no worker for 60 s (its
        ``result`` keeps the finished chunks).

    Examples
    --------
    Peak lateral acceleration over a sweep of the ratio ``a``:

    >>> import numpy as np, fws_control as fws
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> ratios = np.array([-1.0, -0.5, 0.0, 0.5])
    >>> plant = fws.LateralPlant(veh, speed=20.0)
    >>> g = fws.double_root_gains(plant, ratio=ratios, pole=-1.0)
    >>> res = fws.simulate_batch(plant, fws.Straight(), g,
    ...                          initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                          feedforward=False)
    >>> res.e.shape, res.status.tolist()
    ((4, 1001), ['ok', 'ok', 'ok', 'ok'])
    >>> bool(np.all(np.abs(res.e[:, -1]) < 1e-2))
    True
    >>> fws.tracking_metrics(res).peak_lateral_accel.round(2).tolist()
    [2.0, 1.91, 1.73, 1.19]

    A large sweep keeps only what it needs: here the lateral error, or only
    the metrics (the same values, computed before the signals are dropped):

    >>> few = fws.simulate_batch(plant, fws.Straight(), g,
    ...                          initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                          feedforward=False, signals=("e",))
    >>> few.signal_names, few.signals.shape, bool(np.all(few.e == res.e))
    (('e',), (4, 1, 1001), True)
    >>> none = fws.simulate_batch(plant, fws.Straight(), g,
    ...                           initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                           feedforward=False, signals="metrics")
    >>> m = fws.tracking_metrics(none)
    >>> m.peak_lateral_accel.round(2).tolist(), m.settling_time.round(2).tolist()
    ([2.0, 1.91, 1.73, 1.19], [5.9, 5.88, 5.83, 5.69])
    >>> bool(np.all(m.settling_time == fws.tracking_metrics(res).settling_time))
    True

    A sweep streamed to a ``.npy`` file as its chunks finish (a memory map
    as `out`; written under a temporary name and renamed when complete, so
    that an interrupted sweep leaves no file that looks finished):

    >>> import os, tempfile
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     part = os.path.join(folder, "sweep.npy.part")
    ...     disk = np.lib.format.open_memmap(part, mode="w+", shape=(4, 1, 1001))
    ...     _ = fws.simulate_batch(plant, fws.Straight(), g,
    ...                            initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                            feedforward=False, signals=("e",), out=disk)
    ...     disk.flush()
    ...     del disk
    ...     os.replace(part, os.path.join(folder, "sweep.npy"))
    ...     saved = np.load(os.path.join(folder, "sweep.npy"))
    >>> saved.shape, bool(np.all(saved[:, 0] == res.e))
    ((4, 1, 1001), True)
    """
    profile = speed_option(plant, speed, kwargs)
    vehicle, controllers, speed, model, tyre, lag = resolve_plant(
        "simulate_batch", plant, controllers, kwargs
    )
    profile, speed, controllers, schedule = with_profile(profile, speed, controllers)
    return _simulate_batch(
        vehicle,
        path,
        controllers,
        speed=speed,
        initial_state=initial_state,
        duration=duration,
        feedforward=feedforward,
        dt=dt,
        t_eval=t_eval,
        actuator_time_constant=lag,
        delay=delay,
        method=method,
        rtol=rtol,
        atol=atol,
        model=model,
        tyre=tyre,
        engine=engine,
        chunk_size=chunk_size,
        client=client,
        progress=progress,
        signals=signals,
        out=out,
        profile=profile,
        schedule=schedule,
    )
