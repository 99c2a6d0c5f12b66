"""CPU cost of command-line calls: start-up and ``reproduce`` (issue 14).

Runs each command in a fresh interpreter (``python -m fws_control.cli ...``,
what the ``fws-control`` script does) and measures its CPU time, user +
system, from ``resource.getrusage(RUSAGE_CHILDREN)``: CPU time is far less
disturbed by other processes than wall time. Each figure is the best of
``--repeat`` runs (default 3); the machine load is printed before and after,
and every time is printed with its ratio to the target, and so is the
simulation engine ``reproduce`` gets (the compiled one needs numba, the
extra ``fast``; without it the numpy engine makes Fig. 5 and the responses,
about 1.8 s more).

``reproduce`` is timed twice: as installed with the extra ``fast`` (numba
importable, its kernels already compiled by an earlier run) and without
numba (the same command in an interpreter where ``import numba`` fails, as
on an install without the extra: the numpy engine makes the simulations).

The package's own modules run from byte code, as from ``pip install .``
(which compiles them): when this interpreter writes none
(``PYTHONDONTWRITEBYTECODE``), the benchmark compiles the checkout into a
temporary ``PYTHONPYCACHEPREFIX`` first, so that no timed run pays for
compiling the sources (about 0.3 s of ``reproduce``'s CPU otherwise).

Targets: ``--help`` 0.3 s, ``gains`` 0.5 s, ``reproduce`` 6 s of CPU. The
reference row ``python -c pass`` is the interpreter alone, and
``import control`` what python-control costs by itself.

With ``--baseline DIR`` (another checkout, e.g. ``main``) every command
also runs from DIR, alternating with this checkout so that both see the same
load (in flipping order: this, baseline, baseline, this, ...; each
``reproduce`` into its own folder), and the ratio this/baseline is printed.

With ``--breakdown`` it also runs ``reproduce``'s work stage by stage in
fresh interpreters and prints the best CPU time of each stage: the imports,
then per figure its making (data and artists, ``make_figure``) and its
``savefig`` (layout, drawing, PNG encoding, with ``reproduce``'s PNG options),
then the summary.

Run: ``python benchmarks/bench_startup.py [--repeat 3] [--no-reproduce]
[--baseline DIR] [--only-reproduce] [--breakdown]``; ``reproduce`` alone,
with and without numba: ``--only-reproduce``.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from timing import machine_line

ROOT = Path(__file__).resolve().parents[1]


def cpu_seconds(cmd: list[str], env: dict) -> float:
    """User + system CPU of one run of `cmd` (and its children) [s]."""
    # Run from the checkout under test: ``python -m`` puts the working
    # directory first on sys.path.
    cwd = env["PYTHONPATH"].split(os.pathsep)[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(
        cmd, check=True, stdout=subprocess.DEVNULL, env=env, cwd=cwd, timeout=600
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def engine_line(env: dict) -> str:
    """Which simulation engine ``reproduce`` gets in `env` (numba or not)."""
    # asked of the checkout under test, as the project decides it
    probe = (
        "from fws_control.simulation.compiled import available\n"
        "if available():\n"
        "    import numba; print(numba.__version__)"
    )
    cwd = env["PYTHONPATH"].split(os.pathsep)[0]
    run = subprocess.run(
        [sys.executable, "-c", probe],
        capture_output=True, text=True, env=env, cwd=cwd, check=True,
    )  # fmt: skip
    if run.stdout.strip():
        return (
            f"engine: compiled (numba {run.stdout.strip()}, extra 'fast'; after a "
            "fresh install the first runs use the numpy engine while its kernels "
            "compile, once, in a background process)"
        )
    return "engine: numpy (numba not installed: the compiled engine is off)"


def with_path(root: Path, pycache: Path | None = None) -> dict:
    """The environment with `root` first on PYTHONPATH.

    With `pycache`, byte code is written and read there (an installed
    package has its byte code; a checkout run with PYTHONDONTWRITEBYTECODE
    would compile every module in every run).
    """
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(root), *filter(None, [env.get("PYTHONPATH")])]
    )
    if pycache is not None:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(pycache)
        subprocess.run(
            [sys.executable, "-m", "compileall", "-q", str(root / "fws_control")],
            check=True, stdout=subprocess.DEVNULL, env=env, timeout=600,
        )  # fmt: skip
    return env


# ``fws-control`` (the console script calls fws_control.cli.run) in an
# interpreter where ``import numba`` raises ImportError, as without the extra.
_WITHOUT_NUMBA = (
    "import sys; sys.modules['numba'] = None; from fws_control.cli import run; run()"
)


def best_cpu(cmd: list[str], envs: list[dict], repeat: int) -> list[float]:
    """Best CPU time of `repeat` runs of `cmd` in each environment [s].

    The environments take turns, so that a change of load hits them alike,
    and the order of the turns flips every round (A B, B A, A B, ...), so
    that neither always runs first (after the other's output, in a
    warmer or a colder page cache). A ``{env}`` in `cmd` is replaced by the
    environment's index: ``reproduce`` writes into a folder of its own.
    """
    best = [float("inf")] * len(envs)
    order = list(range(len(envs)))
    for _ in range(repeat):
        for i in order:
            own = [part.replace("{env}", str(i)) for part in cmd]
            best[i] = min(best[i], cpu_seconds(own, envs[i]))
        order.reverse()
    return best


# One in-process run of reproduce's stages; prints "stage seconds" lines.
_STAGES = r"""
import io, sys, time
T = time.process_time
t = T()
import control, matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
from fws_control.paper.figures import FIGURES, make_figure, _summary_text
# reproduce's drawing and PNG options, taken from it so that they cannot drift
from fws_control.paper.figures import _DRAW_RC, _PNG_OPTIONS
print("imports", T() - t)
for name in FIGURES:
    t = T()
    fig = make_figure(name)
    print(name + ":make", T() - t)
    t = T()
    # as reproduce saves it (its default dpi 110)
    with plt.rc_context(_DRAW_RC):
        fig.savefig(io.BytesIO(), format="png", dpi=110, pil_kwargs=_PNG_OPTIONS)
    print(name + ":savefig", T() - t)
    plt.close(fig)
from pathlib import Path
t = T()
_summary_text("kinematic", [Path(n + ".png") for n in FIGURES])
print("summary", T() - t)
"""


def breakdown(env: dict, repeat: int) -> None:
    """Best CPU time of each stage of ``reproduce`` over `repeat` runs."""
    best: dict[str, float] = {}
    cwd = env["PYTHONPATH"].split(os.pathsep)[0]
    for _ in range(repeat):
        out = subprocess.run(
            [sys.executable, "-c", _STAGES], check=True, capture_output=True,
            text=True, env=env, cwd=cwd, timeout=600,
        ).stdout  # fmt: skip
        for line in out.splitlines():
            stage, sec = line.rsplit(" ", 1)
            best[stage] = min(best.get(stage, float("inf")), float(sec))
    make = sum(v for k, v in best.items() if k.endswith(":make"))
    save = sum(v for k, v in best.items() if k.endswith(":savefig"))
    print(f"reproduce by stage, in-process CPU seconds, best of {repeat}:")
    print(f"  {'imports':34s} {best['imports']:7.3f} s")
    for name in [k.split(":")[0] for k in best if k.endswith(":make")]:
        print(
            f"  {name:34s} make {best[name + ':make']:6.3f} s   "
            f"savefig {best[name + ':savefig']:6.3f} s"
        )
    print(f"  {'all figures':34s} make {make:6.3f} s   savefig {save:6.3f} s")
    print(f"  {'summary':34s} {best['summary']:7.3f} s")
    total = best["imports"] + make + save + best["summary"]
    print(f"  {'sum of the best stages':34s} {total:7.3f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs per command (3)")
    ap.add_argument("--no-reproduce", action="store_true", help="skip reproduce")
    ap.add_argument("--only-reproduce", action="store_true", help="time reproduce only")
    ap.add_argument("--baseline", type=Path, help="another checkout to compare with")
    ap.add_argument(
        "--breakdown", action="store_true", help="CPU of reproduce stage by stage"
    )
    opts = ap.parse_args()
    if opts.repeat < 3:
        ap.error(f"--repeat must be >= 3 (best of at least 3), got {opts.repeat}")
    pycache = None
    if sys.flags.dont_write_bytecode or os.environ.get("PYTHONDONTWRITEBYTECODE"):
        pycache = Path(tempfile.mkdtemp(prefix="bench_startup_pycache_"))
    envs = [with_path(ROOT, pycache)]
    if opts.baseline is not None:
        envs.append(with_path(opts.baseline.resolve(), pycache))
    py = [sys.executable]
    cli = [*py, "-m", "fws_control.cli"]
    out = Path(tempfile.mkdtemp(prefix="bench_startup_"))
    rows = [
        ("python -c pass (interpreter)", [*py, "-c", "pass"], None),
        ("python -c 'import control'", [*py, "-c", "import control"], None),
        ("python -c 'import fws_control'", [*py, "-c", "import fws_control"], None),
        ("fws-control --help", [*cli, "--help"], 0.3),
        ("fws-control gains", [*cli, "gains"], 0.5),
    ]
    if opts.only_reproduce:
        rows = []
    if not opts.no_reproduce:
        args = ["reproduce", "--out", str(out / "{env}"), "--no-progress"]
        rows.append(("fws-control reproduce", [*cli, *args], 6.0))
        rows.append(
            ("reproduce without numba", [*py, "-c", _WITHOUT_NUMBA, *args], 6.0)
        )
    print(machine_line())
    print(engine_line(envs[0]))
    if pycache is not None:
        print(f"byte code: compiled once into {pycache} (as an installed package)")
    print(f"CPU seconds (user + sys), best of {opts.repeat} runs each:")
    for label, cmd, target in rows:
        t, *base = best_cpu(cmd, envs, opts.repeat)
        tail = "" if target is None else f"   target {target:g} s: {t / target:.2f}x"
        if base:
            tail += f"   baseline {base[0]:7.3f} s: this/baseline {t / base[0]:.2f}"
        print(f"  {label:34s} {t:7.3f} s{tail}")
    if opts.breakdown:
        breakdown(envs[0], opts.repeat)
    print(machine_line())


if __name__ == "__main__":
    main()
