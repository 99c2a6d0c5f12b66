"""Exhaustive fuzz counts: every (public callable, argument, bad value).

Runs the cases of ``tests/test_fuzz.py`` -- each public callable of
``fws_control`` with one argument at a time replaced by each bad value
(NaN, +-inf, 0, negative, huge, tiny, bool, complex, None, strings, foreign
objects, wrong shapes) -- and prints, per callable, "N calls tried, M handled
well" (handled well: a result that passes the callable's postconditions, or
a ValueError/TypeError naming the argument), then the total; then the
targeted categories of valid-looking bad input (``TARGETED`` there, each
probe once) and +-1e300 in every command-line option given in degrees,
per category and in total. Known failures (``KNOWN`` there) are counted
as not handled well and listed with ``-v``.

    python benchmarks/fuzz_counts.py            # summary and totals
    python benchmarks/fuzz_counts.py -v         # also every call not handled well
    python benchmarks/fuzz_counts.py simulate   # only the named callables
    python benchmarks/fuzz_counts.py --targeted # only the targeted categories
"""

from __future__ import annotations

import os
import sys
import time
import warnings

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests"))
sys.path.insert(0, HERE)

import matplotlib  # noqa: E402

matplotlib.use("Agg")

from test_fuzz import (  # noqa: E402
    BAD_VALUES,
    CASES,
    EXCLUDED,
    TARGETED,
    cli_angle_options,
    judge,
    judge_cli,
)
from timing import machine_line  # noqa: E402


def main(argv: list[str]) -> int:
    verbose = "-v" in argv
    names = [a for a in argv if not a.startswith("-")] or list(CASES)
    targeted_only = "--targeted" in argv
    print(machine_line())
    total_tried = total_well = 0
    t0 = time.perf_counter()
    for name in [] if targeted_only else names:
        case = CASES[name]
        tried = well = 0
        bad_lines = []
        for arg in case.names:
            for label, value in BAD_VALUES:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    good, why = judge(case, arg, value)
                tried += 1
                well += good
                if not good:
                    bad_lines.append(f"    {arg}={label}: {why[:200]}")
        total_tried += tried
        total_well += well
        print(f"{name}: {tried} calls tried, {well} handled well")
        if verbose:
            print("\n".join(bad_lines))
    if not targeted_only:
        pct = 100.0 * total_well / max(total_tried, 1)
        print(
            f"total: {total_tried} calls tried to {len(names)} callables, "
            f"{total_well} handled well ({pct:.1f} %); "
            f"{len(EXCLUDED)} public names excluded (see tests/test_fuzz.py); "
            f"{time.perf_counter() - t0:.1f} s"
        )
    if [a for a in argv if not a.startswith("-")]:
        return 0  # named callables only
    t0 = time.perf_counter()
    cat_tried = cat_well = 0
    groups = {
        name: [(p.case, p.arg, p.label, p) for p in probes]
        for name, probes in TARGETED.items()
    }
    groups["huge finite angles in CLI options"] = [
        (command, option, text, None)
        for command, option in cli_angle_options()
        for text in ("1e300", "-1e300")
    ]
    for category, probes in groups.items():
        tried = well = 0
        bad_lines = []
        for who, arg, label, p in probes:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                if p is None:
                    good, why = judge_cli(who, arg, label)
                else:
                    good, why = judge(
                        CASES[who], arg, p.value, base=p.base, post=p.post
                    )
            tried += 1
            well += good
            if not good:
                bad_lines.append(f"    {who}({arg}={label}): {why[:200]}")
        cat_tried += tried
        cat_well += well
        print(f"[{category}]: {tried} calls tried, {well} handled well")
        if verbose and bad_lines:
            print("\n".join(bad_lines))
    pct = 100.0 * cat_well / max(cat_tried, 1)
    print(
        f"targeted total: {cat_tried} calls tried in {len(groups)} categories, "
        f"{cat_well} handled well ({pct:.1f} %); "
        f"{time.perf_counter() - t0:.1f} s"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
