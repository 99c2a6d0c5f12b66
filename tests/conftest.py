"""Shared fixtures, hand-written references and the hypothesis profile.

The hypothesis profile has a fixed seed (derandomized). The helpers below are
written out in the tests from the paper's equations, independent of the
library code they check.
"""

import gc
import os
import tracemalloc

# One BLAS thread. The tests' matrices are small (at most a few hundred
# rows): OpenBLAS threads gain nothing there and, on a busy 2-core machine,
# their busy-waiting made e.g. the delayed root-count test 7x slower (1.4 s
# with one thread, 9.3 s with the default). Set before numpy is imported
# (subprocesses inherit it); an explicit setting in the environment wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

# The tests compile what they need in their own process: engine="auto"
# with a kernel set not in the cache would otherwise run on the numpy engine
# while a background process compiles it (a local run without
# `fws-control compile`). test_background_compile.py sets the default.
os.environ.setdefault("FWS_CONTROL_COMPILE", "foreground")

import matplotlib  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import sympy as sp  # noqa: E402
from hypothesis import HealthCheck, settings  # noqa: E402

import fws_control as fws  # noqa: E402
from fws_control import symbolic as S  # noqa: E402

matplotlib.use("Agg")

settings.register_profile(
    "fws",
    derandomize=True,
    deadline=None,
    max_examples=int(os.environ.get("FWS_HYPOTHESIS_EXAMPLES", "200")),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
settings.load_profile("fws")

#: The paper's vehicle, written out here: f = 2.7 m, d = 1.35 m.
PAPER_VEHICLE = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


@pytest.fixture
def veh():
    """The paper's vehicle: f = 2.7 m, d = 1.35 m."""
    return PAPER_VEHICLE


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


_ARGS = [
    S.SYMBOLS[n]
    for n in ("speed", "wheelbase", "curvature", "ratio", "k1", "k2", "pole")
]


def lambdify(expr):
    """Numeric function of (V, f, kappa, a, k1, k2, lam0) from a sympy expr."""
    return sp.lambdify(_ARGS, expr, modules="numpy")


def gain_factor(wheelbase, curvature, model):
    """Factor c of the front-steering entry c V / f of B, written out.

    c = 1 + f^2 kappa^2 for the exact Jacobian of eqs. (18)-(19) (the
    derivative of V tan(delta_f)/f at delta_f = atan(kappa f)); c = 1 in the
    paper's eq. (33). Broadcasts over `curvature`.
    """
    kappa = np.asarray(curvature, dtype=float)
    if model == "paper":
        return np.ones_like(kappa)
    return 1.0 + (wheelbase * kappa) ** 2


# Fuzz counts (tests/test_fuzz.py): calls tried and handled well per callable,
# printed in the terminal summary. Kept on the config rather than in a
# fixture's closure so that, under pytest-xdist, each worker can send its
# counts to the controller, which prints the total.
_FUZZ_COUNTS = pytest.StashKey[dict]()


def _fuzz_counts_of(config) -> dict:
    return config.stash.setdefault(_FUZZ_COUNTS, {})


@pytest.fixture(scope="session")
def fuzz_counts(request):
    """``{callable name: Counter(tried=..., well=...)}`` of the fuzz suite."""
    return _fuzz_counts_of(request.config)


def pytest_sessionfinish(session):
    # on an xdist worker: hand the counts to the controller
    if hasattr(session.config, "workeroutput"):
        counts = _fuzz_counts_of(session.config)
        session.config.workeroutput["fws_fuzz_counts"] = {
            name: dict(c) for name, c in counts.items()
        }


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    # on the xdist controller: add up what each worker counted
    from collections import Counter

    total = _fuzz_counts_of(node.config)
    for name, c in getattr(node, "workeroutput", {}).get("fws_fuzz_counts", {}).items():
        total.setdefault(name, Counter()).update(c)


def pytest_terminal_summary(terminalreporter, config):
    counts = _fuzz_counts_of(config)
    if hasattr(config, "workeroutput") or not counts:
        return
    tried = sum(c["tried"] for c in counts.values())
    well = sum(c["well"] for c in counts.values())
    terminalreporter.write_line(
        f"fuzz: {tried} calls tried, {well} handled well ({len(counts)} callables)"
    )
    for name, c in sorted(counts.items()):
        if c["well"] < c["tried"]:
            terminalreporter.write_line(
                f"  {name}: {c['tried']} tried, {c['well']} handled well"
            )


# --------------------------------------------------------------------------
# The compiled engine compiled once, before the xdist workers start

# Under pytest-xdist every worker is a fresh process: with an empty numba
# cache (a fresh clone) each worker compiled the whole engine itself, the
# same kernels twice over, tens of seconds of CPU each. The controller
# compiles every kernel set first (fws_control.simulation.precompile, as
# `fws-control compile` does; two worker processes at once), into numba's
# cache; the workers then load the kernels from it (fws_control's cache
# folder is per-checkout, see fws_control.simulation.compilation). Cached
# already (CI runs `fws-control compile` before pytest), this takes a few
# seconds. Off with FWS_TEST_PRECOMPILE=0; a failure here fails no test
# (the tests then compile what they need, as before).


def _precompile_wanted(config) -> bool:
    if os.environ.get("FWS_TEST_PRECOMPILE", "1").strip() in ("0", ""):
        return False
    if hasattr(config, "workerinput"):  # an xdist worker: the controller did it
        return False
    workers = getattr(config.option, "numprocesses", None)
    if not workers or getattr(config.option, "dist", "no") == "no":
        return False  # one process: it compiles what its tests need
    import importlib.util

    return importlib.util.find_spec("numba") is not None


def pytest_sessionstart(session):
    # runs before xdist's own pytest_sessionstart (trylast) starts the workers
    config = session.config
    if not _precompile_wanted(config):
        return
    import time

    from fws_control.simulation.precompile import precompile

    start = time.perf_counter()
    try:
        precompile(jobs=2)
        what = "done"
    except Exception as exc:  # the tests compile what they need instead
        what = f"failed: {type(exc).__name__}: {exc}"
    reporter = config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        took = time.perf_counter() - start
        reporter.write_line(
            f"fws_control: compiled engine compiled before the workers start "
            f"({took:.0f} s, {what})"
        )


# --------------------------------------------------------------------------
# Dask and memory helpers shared by the batch tests


def dask_distributed():
    """``dask.distributed``, or skip the test saying why (extra ``distributed``)."""
    try:
        from dask import distributed
    except ImportError:  # pragma: no cover - depends on the environment
        print("dask.distributed is not installed: Dask tests skipped")
        pytest.skip("the extra 'distributed' (dask.distributed) is not installed")
    return distributed


@pytest.fixture(scope="module")
def dask_client():
    """A client of an in-process Dask cluster: one worker, one thread."""
    distributed = dask_distributed()
    with (
        distributed.LocalCluster(
            processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        yield client


class LosingClient:
    """A client whose tasks after the first are lost (cancelled) by the cluster."""

    def __init__(self, client):
        self.client = client
        self.count = 0

    def submit(self, *args, **kwargs):
        fut = self.client.submit(*args, **kwargs)
        self.count += 1
        if self.count > 1:
            fut.cancel()
        return fut


def traced_peak(fn):
    """``(fn(), peak bytes traced by tracemalloc while it ran)``.

    With Python's cyclic garbage collector paused: a memory bound must hold
    by reference counting alone, not depend on when the collector happens
    to run (it did: a chunk's solver cycles kept its dense output alive).
    """
    enabled = gc.isenabled()
    gc.collect()
    gc.disable()
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        out = fn()
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
        if enabled:
            gc.enable()
    return out, peak


#: A batch of the paper's curve scenario (Arc 1/10, 5 m/s, R(0) = (0, -5 m),
#: 12 s at dt 0.05, two chunks): five double-root designs (ratios over
#: [-1.5, 0.6], pole -1) and one that diverges (k2 < 0, front steering only),
#: which stops at a singular state with a NaN tail.
_SWEEP = fws.double_root_gains(
    PAPER_VEHICLE, speed=5.0, curvature=0.1, ratio=np.linspace(-1.5, 0.6, 5), pole=-1.0
)
CURVE_GAINS_WITH_STOP = fws.SteeringGains(
    np.append(_SWEEP.k1, 0.3), np.append(_SWEEP.k2, -2.0), np.append(_SWEEP.ratio, 0.0)
)
#: The curve batch's speed [m/s]: the plant's (fws.LateralPlant(vehicle,
#: speed=CURVE_SPEED)); CURVE_BATCH_KW holds the other options.
CURVE_SPEED = 5.0
CURVE_BATCH_KW = {
    "initial_state": (0.0, -5.0, 0.0),
    "duration": 12.0,
    "dt": 0.05,
    "chunk_size": 4,  # two chunks
    "progress": False,
}


# CPU seconds per test (this process and the subprocesses it waited for),
# appended as "nodeid<TAB>seconds" lines to the file FWS_TEST_CPU_LOG names:
# unlike wall-clock durations, CPU time does not grow with the machine's
# load, so the suite's cost can be profiled on a busy machine
# (docs/developer.md, "Keeping the suite fast").
_CPU_LOG = os.environ.get("FWS_TEST_CPU_LOG")

if _CPU_LOG:
    import resource
    import time

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(item, nextitem):
        def cpu():
            children = resource.getrusage(resource.RUSAGE_CHILDREN)
            return time.process_time() + children.ru_utime + children.ru_stime

        start = cpu()
        yield
        with open(_CPU_LOG, "a", encoding="utf-8") as fh:
            fh.write(f"{item.nodeid}\t{cpu() - start:.3f}\n")
