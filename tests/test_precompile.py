"""fws_control.simulation.precompile and ``fws-control compile``.

Reference: numba's own cache counters (``dispatcher.stats``: a cache miss
is a compilation, a hit a load from the cache). After :func:`precompile`,
a fresh process that runs each kernel set's call must compile nothing.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from fws_control.simulation.precompile import KERNEL_SETS, CompiledSet, precompile

pytest.importorskip("numba", reason="the extra 'fast' (numba)")

# every top kernel of both variants (the specialised and the full kernels):
# their compilations and cache loads in this process, as numba counts them
_COUNT = """
from fws_control.simulation import precompile, compiled_variants as v
from fws_control.simulation.compiled import radau_run, solve_run
for name in precompile.KERNEL_SETS:
    precompile._run_set(name)
kernels = [v.variant(solve_run, []), v.variant(radau_run, [])]
for features in ((), v.FEATURES):
    kernels += vars(v.kernels(features)).values()
misses = sum(sum(k.stats.cache_misses.values()) for k in kernels)
hits = sum(sum(k.stats.cache_hits.values()) for k in kernels)
print(misses, hits)
"""


def test_after_precompile_a_fresh_process_compiles_nothing():
    done = precompile(jobs=2)
    assert [d.name for d in done] == list(KERNEL_SETS)
    assert all(isinstance(d, CompiledSet) and d.cpu_seconds > 0.0 for d in done)
    out = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(_COUNT)],
        capture_output=True, text=True, timeout=900, check=True,
    )  # fmt: skip
    misses, hits = (int(v) for v in out.stdout.split())
    assert misses == 0, out.stderr[-2000:]
    # the sets load five top kernels and the two one-run drivers from the
    # cache at least
    assert hits >= 7


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"sets": ("paper-rk45",)}, "sets must hold names of"),
        ({"jobs": 0}, "jobs must be an integer >= 1, got 0"),
        ({"jobs": True}, "jobs must be an integer >= 1, got True"),
        ({"jobs": 1.5}, "jobs must be an integer >= 1, got 1.5"),
    ],
)
def test_bad_input_names_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        precompile(**kwargs)


def test_command_reports_each_set():
    out = subprocess.run(
        [sys.executable, "-m", "fws_control", "compile", "--jobs", "1"],
        capture_output=True, text=True, timeout=900, check=True,
    )  # fmt: skip
    lines = out.stdout.splitlines()
    assert lines[0].startswith("compiling into ")
    assert [line.split()[0] for line in lines[1:-1]] == list(KERNEL_SETS)
    assert lines[-1].endswith("(1 worker)")
    bad = subprocess.run(
        [sys.executable, "-m", "fws_control", "compile", "--jobs", "0"],
        capture_output=True, text=True, timeout=900, check=False,
    )  # fmt: skip
    assert bad.returncode == 2 and "--jobs" in bad.stderr


def test_results_follow_the_sets_asked_for_whatever_the_start_order():
    # the sets start longest first; the results come in the order asked for
    asked = ("paper-radau", "paper-dop853", "paper-radau")
    assert [d.name for d in precompile(asked, jobs=2)] == list(asked)
