r"""Many closed-loop runs integrated together, locally or on a Dask cluster.

:func:`simulate_batch` stacks the path-frame states of all runs of a chunk
into one state vector and integrates them with a single
:func:`scipy.integrate.solve_ivp` call, using the same right-hand side as
:func:`simulate`. Gains, ratios, speeds and initial poses may differ per run
(numpy broadcasting). A run that meets a singular state leaves the stacked
state at that time (the integration restarts from there for the others) and
is marked in :attr:`BatchResult.status`; its samples after the stop are NaN.

Large sweeps are split into chunks of ``chunk_size`` runs. With a
``dask.distributed`` client (optional extra ``distributed``) the chunks are
submitted to the cluster; otherwise they run one after the other here. A
tqdm progress bar over the chunks is shown on interactive terminals.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .gains import SteeringGains
from .simulation import (
    SIGNALS,
    SimulationResult,
    _check_initial_state,
    _initial_path_state,
    _integrate,
    _outputs,
    _prepare_limits,
    _single_result,
    _stderr_is_tty,
    _time_grid,
    check_path,
    plot_responses,
)
from .validation import check_nonzero, check_type
from .vehicle import Vehicle

__all__ = ["BatchResult", "simulate_batch", "DEFAULT_CHUNK_SIZE"]

#: Runs per chunk (one solve_ivp call, one Dask task) unless told otherwise.
DEFAULT_CHUNK_SIZE = 256


@dataclass(frozen=True, eq=False)
class BatchResult:
    """Time responses of many runs on a common time grid.

    Every signal of :class:`SimulationResult` (``x, y, psi, s, e, theta,
    delta_f, delta_r, delta_f_rate, delta_r_rate, lateral_accel``) is an
    array of shape ``(runs, time)``; samples after a run stopped are NaN.

    Attributes
    ----------
    t : ndarray
        Output times [s], shape ``(time,)``.
    status : ndarray of str
        Per run: ``"ok"`` or why it stopped (see :class:`SimulationResult`).
    message : tuple of str
        Per run explanation ("" for ``"ok"``).
    t_stop : ndarray
        Per run end time [s]; NaN for runs that were not simulated.
    speed : ndarray
        Per run speed [m/s].
    k1, k2, ratio : ndarray
        Per run gains, shape ``(runs,)``; NaN gains mark a design that could
        not be built (status ``"uncontrollable"``). :attr:`gains` gives them
        as a :class:`SteeringGains`.
    initial_state : ndarray
        Per run ``(x_R, y_R, psi)``, shape ``(runs, 3)``.
    feedforward : bool
    vehicle : Vehicle
    path : path object

    Indexing (``result[i]``) or :attr:`runs` gives :class:`SimulationResult`
    objects holding each run's data up to its stop.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    psi: np.ndarray
    s: np.ndarray
    e: np.ndarray
    theta: np.ndarray
    delta_f: np.ndarray
    delta_r: np.ndarray
    delta_f_rate: np.ndarray
    delta_r_rate: np.ndarray
    lateral_accel: np.ndarray
    status: np.ndarray
    message: tuple[str, ...]
    t_stop: np.ndarray
    speed: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    ratio: np.ndarray
    initial_state: np.ndarray
    feedforward: bool = True
    vehicle: Vehicle | None = field(default=None, repr=False)
    path: Any = field(default=None, repr=False)

    def __len__(self) -> int:
        return int(self.status.shape[0])

    @property
    def gains(self) -> SteeringGains:
        """The per-run gains as one :class:`SteeringGains` (arrays).

        Raises
        ------
        ValueError
            If some runs have no gains (NaN, status ``"uncontrollable"``).
        """
        return SteeringGains(self.k1, self.k2, self.ratio)

    @property
    def ok(self) -> np.ndarray:
        """Boolean mask of the runs that reached the final time."""
        return self.status == "ok"

    def __getitem__(self, i: int) -> SimulationResult:
        n = len(self)
        if not isinstance(i, (int, np.integer)):
            raise TypeError(f"run index must be an integer, got {type(i).__name__}")
        if not -n <= i < n:
            raise IndexError(f"run index {i} out of range for {n} runs")
        i = int(i) % n
        return _single_result(
            self.t,
            {name: getattr(self, name)[i] for name in SIGNALS},
            self.status[i],
            self.message[i],
            self.t_stop[i],
            float(self.speed[i]),
            _gains_or_none(self.k1[i], self.k2[i], self.ratio[i]),
            self.feedforward,
            self.vehicle,
            self.path,
        )

    @property
    def runs(self) -> list[SimulationResult]:
        """Each run as a :class:`SimulationResult`."""
        return [self[i] for i in range(len(self))]

    def plot(self, labels: Sequence[str] | None = None, fig=None):
        """Overlay all runs (see :meth:`SimulationResult.plot`).

        Parameters
        ----------
        labels : sequence of str, optional
            Legend label per run; default ``"a=<ratio>"``.
        fig : matplotlib.figure.Figure, optional

        Returns
        -------
        matplotlib.figure.Figure
        """
        if labels is None:
            labels = [f"a={float(r):g}" for r in self.ratio]
        return plot_responses(self.runs, labels, fig=fig)

    def to_pandas(self):
        """Long-format :class:`pandas.DataFrame` with columns ``run, t, ...``.

        Only the samples up to each run's stop are included; the per-run
        status is in the column ``status``.

        Raises
        ------
        ImportError
            If pandas is not installed.
        """
        from .simulation import _import_pandas

        pd = _import_pandas()
        n, T = self.s.shape
        valid = np.isfinite(self.s)
        run = np.broadcast_to(np.arange(n)[:, None], (n, T))[valid]
        data = {"run": run, "t": np.broadcast_to(self.t, (n, T))[valid]}
        data.update({name: getattr(self, name)[valid] for name in SIGNALS})
        data["status"] = self.status[run]
        return pd.DataFrame(data)


def _gains_or_none(k1, k2, ratio) -> SteeringGains | None:
    if np.isfinite(k1) and np.isfinite(k2) and np.isfinite(ratio):
        return SteeringGains(float(k1), float(k2), float(ratio))
    return None


def _normalise_gains(gains, name: str = "gains_list") -> SteeringGains:
    """One SteeringGains with 1-D arrays from a SteeringGains or a sequence.

    `name` is the caller's argument name, used in error messages.
    """
    if isinstance(gains, SteeringGains):
        k1, k2, a = np.broadcast_arrays(
            np.asarray(gains.k1, dtype=float),
            np.asarray(gains.k2, dtype=float),
            np.asarray(gains.ratio, dtype=float),
        )
        return SteeringGains(k1.ravel().copy(), k2.ravel().copy(), a.ravel().copy())
    try:
        items = list(gains)
    except TypeError:
        raise TypeError(
            f"{name} must be a SteeringGains or a sequence of SteeringGains, got "
            f"{type(gains).__name__}"
        ) from None
    if not items or not all(isinstance(g, SteeringGains) for g in items):
        raise TypeError(
            f"{name} must be a SteeringGains or a non-empty sequence of "
            f"SteeringGains, got {gains!r}"
        )
    parts = [_normalise_gains(g, name) for g in items]
    return SteeringGains(
        np.concatenate([p.k1 for p in parts]),
        np.concatenate([p.k2 for p in parts]),
        np.concatenate([p.ratio for p in parts]),
    )


def _run_chunk(vehicle, path, k1, k2, a, speed, feedforward, x0, t, tau, opts):
    """Simulate one chunk; module-level so that Dask can pickle it."""
    g = SteeringGains(k1, k2, a)
    z0 = _initial_path_state(path, x0)
    states, status, message, t_stop = _integrate(
        vehicle, path, g, speed, feedforward, z0, t, tau, **opts
    )
    sig = _outputs(vehicle, path, g, speed, feedforward, tau, states, x0[:, 2])
    return sig, status, message, t_stop


def simulate_batch(
    vehicle: Vehicle,
    path,
    gains_list,
    speed,
    initial_state,
    duration: float,
    *,
    feedforward: bool = True,
    dt: float = 0.01,
    t_eval=None,
    actuator_time_constant: float | None = None,
    method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-12,
    chunk_size: int | None = None,
    client=None,
    progress: bool | None = None,
) -> BatchResult:
    r"""Simulate many closed loops at once on stacked numpy state.

    Parameters
    ----------
    vehicle : Vehicle
        Geometry and optional limits (shared by all runs).
    path : path object
        Reference path (shared by all runs).
    gains_list : SteeringGains or sequence of SteeringGains
        Per-run gains: a sequence, or one :class:`SteeringGains` whose
        fields are arrays (e.g. from :func:`double_root_gains` over an array
        of ratios).
    speed : float or array_like
        Speed [m/s], scalar or one per run; nonzero.
    initial_state : array_like
        ``(x_R, y_R, psi)`` for all runs, or shape ``(runs, 3)``.
    duration : float
        Final time [s].
    feedforward, dt, t_eval, actuator_time_constant, method, rtol, atol
        As in :func:`simulate`.
    chunk_size : int, optional
        Runs per chunk (one solve_ivp call; one Dask task); default
        :data:`DEFAULT_CHUNK_SIZE`. Smaller chunks decouple the step sizes of
        runs with very different dynamics.
    client : dask.distributed.Client, optional
        Submit the chunks to this Dask cluster (needs the extra
        ``distributed``). The vehicle, path and arguments are pickled to the
        workers.
    progress : bool, optional
        Show a tqdm progress bar over the chunks. ``None`` (default): only if
        standard error is a terminal.

    Returns
    -------
    BatchResult
        Signals of shape ``(runs, time)`` on the common output grid. The
        number of runs is the broadcast of the numbers of gains, speeds and
        initial states.

    Raises
    ------
    ValueError
        If the per-run arguments do not broadcast, or as in :func:`simulate`.

    Examples
    --------
    Peak lateral acceleration over a sweep of the ratio ``a``:

    >>> import numpy as np, fws_control as fws
    >>> from fws_control.paths import Straight
    >>> veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    >>> ratios = np.array([-1.0, -0.5, 0.0, 0.5])
    >>> g = fws.double_root_gains(veh, 20.0, 0.0, ratio=ratios, pole=-1.0)
    >>> res = fws.simulate_batch(veh, Straight(), g, speed=20.0,
    ...                          initial_state=(0.0, 2.0, 0.0), duration=10.0,
    ...                          feedforward=False)
    >>> res.e.shape, res.status.tolist()
    ((4, 1001), ['ok', 'ok', 'ok', 'ok'])
    >>> bool(np.all(np.abs(res.e[:, -1]) < 1e-2))
    True
    """
    check_type("vehicle", vehicle, Vehicle)
    check_path(path)
    g = _normalise_gains(gains_list)
    speed_arr = np.atleast_1d(np.asarray(check_nonzero("speed", speed), dtype=float))
    x0 = _check_initial_state(initial_state)
    if speed_arr.ndim != 1:
        raise ValueError(f"speed must be a scalar or 1-D, got shape {speed_arr.shape}")
    sizes = {g.k1.size, speed_arr.size, x0.shape[0]} - {1}
    if len(sizes) > 1:
        raise ValueError(
            "gains_list, speed and initial_state must have one entry or the same "
            f"number of runs, got {g.k1.size}, {speed_arr.size} and {x0.shape[0]}"
        )
    n = sizes.pop() if sizes else 1
    k1, k2, a, V = (
        np.broadcast_to(v, (n,)).copy() for v in (g.k1, g.k2, g.ratio, speed_arr)
    )
    x0 = np.broadcast_to(x0, (n, 3)).copy()
    t = _time_grid(duration, dt, t_eval)
    tau = _prepare_limits(vehicle, actuator_time_constant)
    feedforward = bool(feedforward)
    if chunk_size is None:
        chunk_size = DEFAULT_CHUNK_SIZE
    if int(chunk_size) != chunk_size or chunk_size < 1:
        raise ValueError(f"chunk_size must be an integer >= 1, got {chunk_size!r}")
    chunk_size = int(chunk_size)
    bounds = [(i, min(i + chunk_size, n)) for i in range(0, n, chunk_size)]
    opts = {"method": method, "rtol": rtol, "atol": atol}
    if progress is None:
        progress = _stderr_is_tty()

    def args(lo, hi):
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
        )

    from tqdm.auto import tqdm

    bar = tqdm(
        total=len(bounds), desc="simulate_batch", unit="chunk", disable=not progress
    )
    chunks: list[Any] = [None] * len(bounds)
    try:
        if client is None:
            for j, (lo, hi) in enumerate(bounds):
                chunks[j] = _run_chunk(*args(lo, hi))
                bar.update(1)
        else:
            try:
                from dask.distributed import as_completed
            except ImportError as exc:  # pragma: no cover - optional extra
                raise ImportError(
                    "client= needs dask.distributed; install the extra "
                    "`pip install fws-control[distributed]`"
                ) from exc
            futures = {
                client.submit(_run_chunk, *args(lo, hi), pure=False): j
                for j, (lo, hi) in enumerate(bounds)
            }
            for fut in as_completed(list(futures)):
                chunks[futures[fut]] = fut.result()
                bar.update(1)
    finally:
        bar.close()

    sig = {name: np.concatenate([c[0][name] for c in chunks]) for name in SIGNALS}
    return BatchResult(
        t=t,
        **sig,
        status=np.concatenate([c[1] for c in chunks]).astype(str),
        message=tuple(str(m) for c in chunks for m in c[2]),
        t_stop=np.concatenate([c[3] for c in chunks]),
        speed=V,
        k1=k1,
        k2=k2,
        ratio=a,
        initial_state=x0,
        feedforward=feedforward,
        vehicle=vehicle,
        path=path,
    )


def _expand_batch(
    result: BatchResult | None,
    positions: np.ndarray,
    n_total: int,
    fill_status: str,
    fill_message: str,
    k1: np.ndarray,
    k2: np.ndarray,
    ratio: np.ndarray,
    speed: np.ndarray,
    initial_state: np.ndarray,
    t: np.ndarray,
    feedforward: bool,
    vehicle: Vehicle,
    path,
) -> BatchResult:
    """Place `result`'s runs at `positions` of a batch of `n_total` runs.

    The other runs get all-NaN signals and `fill_status`; used for designs
    that could not be simulated (e.g. uncontrollable), so that they stay in
    the data instead of being dropped.
    """
    T = t.size
    sig = {name: np.full((n_total, T), np.nan) for name in SIGNALS}
    status = np.full(n_total, fill_status, dtype=object)
    message = [fill_message] * n_total
    t_stop = np.full(n_total, np.nan)
    if result is not None:
        for name in SIGNALS:
            sig[name][positions] = getattr(result, name)
        status[positions] = result.status
        for p, m in zip(positions, result.message, strict=True):
            message[p] = m
        t_stop[positions] = result.t_stop
    return BatchResult(
        t=t,
        **sig,
        status=status.astype(str),
        message=tuple(message),
        t_stop=t_stop,
        speed=speed,
        k1=k1,
        k2=k2,
        ratio=ratio,
        initial_state=initial_state,
        feedforward=feedforward,
        vehicle=vehicle,
        path=path,
    )
