"""Global projection onto paths: KD-tree first pass against the dense one.

``Path.project`` without a guess searches the whole path: a first pass over
samples of the path picks the local minima of the sampled distance, Newton
steps refine them. The dense first pass (before 0.2) computes every
point-sample distance; the KD-tree pass (``scipy.spatial.cKDTree``) looks only
at the samples within ``dmin + h`` of each point. Both give the same answer
bit for bit (``tests/test_paths.py``); this prints their times (best of 5,
the tree built once per path and cached, as in use) and the ratio old/new.
The library uses the tree from 200 path samples on (``paths._FIRST_PASS =
"auto"``); here both passes are forced.

    python benchmarks/bench_projection.py
"""

from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from timing import best_of, machine_line  # noqa: E402

import fws_control.paths as paths_module  # noqa: E402
from fws_control.paths import Clothoid, PathChain, Spline, Straight  # noqa: E402


def cases():
    t = np.linspace(0.0, 2.0 * np.pi, 41)
    ring = np.column_stack([60 * np.cos(t) + 8 * np.cos(5 * t), 40 * np.sin(t)])
    wiggle = np.column_stack(
        [np.linspace(0, 400, 81), 6 * np.sin(np.linspace(0, 400, 81) / 15.0)]
    )
    return {
        "closed spline course (40 waypoints)": Spline(ring),
        "open spline (80 waypoints, 400 m)": Spline(wiggle),
        "clothoid, 4 rad of turning": Clothoid(-0.3, 0.5, 60.0),
        "clothoid, 100 rad of turning": Clothoid(0.0, 2.0, 100.0),
        "chain straight-clothoid-spline": PathChain(
            [Straight(length=20.0), Clothoid(0.0, 0.1, 10.0), Spline(wiggle[:20])]
        ),
    }


def main() -> None:
    print(machine_line())
    rng = np.random.default_rng(1)
    n = 2000
    print(f"{n} points per call, best of 5; first pass alone, then all of project()")
    print(
        f"{'path':36s} {'pass: dense':>11s} {'kd-tree':>8s} {'old/new':>7s}   "
        f"{'project: dense':>14s} {'kd-tree':>8s} {'old/new':>7s}  [ms]"
    )
    for label, path in cases().items():
        s0 = rng.uniform(0.0, path.length, n)
        x0, y0 = path.position(s0)
        px = x0 + rng.normal(0.0, 5.0, n)
        py = y0 + rng.normal(0.0, 5.0, n)
        full, first, results = {}, {}, {}
        for mode in ("dense", "kdtree"):
            paths_module._FIRST_PASS = mode
            results[mode] = path.project(px, py)  # warm the sample cache/tree
            full[mode] = best_of(lambda p=path, x=px, y=py: p.project(x, y), repeat=5)
            segs = path.segments if isinstance(path, PathChain) else (path,)
            tot = 0.0
            for seg in segs:
                if seg._closed_form:
                    continue
                S, X, Y = seg._search_cache["samples"]
                tree = seg._search_cache["tree"] if mode == "kdtree" else None
                tot += best_of(
                    lambda g=seg, S=S, X=X, Y=Y, t=tree, x=px, y=py: g._candidates(
                        x, y, S, X, Y, t
                    ),
                    repeat=5,
                )
            first[mode] = tot
        paths_module._FIRST_PASS = "auto"
        same = np.array_equal(results["dense"].s, results["kdtree"].s)
        print(
            f"{label:36s} {1e3 * first['dense']:11.2f} {1e3 * first['kdtree']:8.2f} "
            f"{first['dense'] / first['kdtree']:7.1f}   "
            f"{1e3 * full['dense']:14.2f} {1e3 * full['kdtree']:8.2f} "
            f"{full['dense'] / full['kdtree']:7.1f}" + ("" if same else "  DIFFER")
        )


if __name__ == "__main__":
    main()
