"""CPU cost of command-line calls: start-up and ``reproduce`` (issue 14).

Runs each command in a fresh interpreter (``python -m fws_control.cli ...``,
what the ``fws-control`` script does) and measures its CPU time, user +
system, from ``resource.getrusage(RUSAGE_CHILDREN)``: CPU time is far less
disturbed by other processes than wall time. Each figure is the best of
``--repeat`` runs (default 3); the machine load is printed before and after,
and every time is printed with its ratio to the target.

Targets: ``--help`` 0.3 s, ``gains`` 0.5 s, ``reproduce`` 6 s of CPU. The
reference row ``python -c pass`` is the interpreter alone, and
``import control`` what python-control costs by itself.

With ``--baseline DIR`` (another checkout, e.g. ``main``) every command
also runs from DIR, alternating with this checkout so that both see the same
load, and the ratio this/baseline is printed.

Run: ``python benchmarks/bench_startup.py [--repeat 3] [--no-reproduce]
[--baseline DIR]``
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


def with_path(root: Path) -> dict:
    """The environment with `root` first on PYTHONPATH."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(root), *filter(None, [env.get("PYTHONPATH")])]
    )
    return env


def best_cpu(cmd: list[str], envs: list[dict], repeat: int) -> list[float]:
    """Best CPU time of `repeat` runs of `cmd` in each environment [s].

    The environments take turns, so that a change of load hits them alike.
    """
    best = [float("inf")] * len(envs)
    for _ in range(repeat):
        for i, env in enumerate(envs):
            best[i] = min(best[i], cpu_seconds(cmd, env))
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs per command (3)")
    ap.add_argument("--no-reproduce", action="store_true", help="skip reproduce")
    ap.add_argument("--only-reproduce", action="store_true", help="time reproduce only")
    ap.add_argument("--baseline", type=Path, help="another checkout to compare with")
    opts = ap.parse_args()
    if opts.repeat < 3:
        ap.error(f"--repeat must be >= 3 (best of at least 3), got {opts.repeat}")
    envs = [with_path(ROOT)]
    if opts.baseline is not None:
        envs.append(with_path(opts.baseline.resolve()))
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
        rows.append(
            (
                "fws-control reproduce",
                [*cli, "reproduce", "--out", str(out), "--no-progress"],
                6.0,
            )
        )
    print(machine_line())
    print(f"CPU seconds (user + sys), best of {opts.repeat} runs each:")
    for label, cmd, target in rows:
        t, *base = best_cpu(cmd, envs, opts.repeat)
        tail = "" if target is None else f"   target {target:g} s: {t / target:.2f}x"
        if base:
            tail += f"   baseline {base[0]:7.3f} s: this/baseline {t / base[0]:.2f}"
        print(f"  {label:34s} {t:7.3f} s{tail}")
    print(machine_line())


if __name__ == "__main__":
    main()
