"""Steps DOP853 spends at the course's curvature corners, and without them.

The ISO 3888-1 course (:func:`fws_control.double_lane_change`, vehicle
width 1.8 m) is a chain of straights and clothoids: its curvature is
continuous, its slope jumps where a clothoid starts or ends unless the
next piece has the same sharpness (a corner of kappa(s)). The path-frame
equations read kappa at the rear axle's arc length s, and so does the
feedforward; Stanley's law also reads the path at the front axle's
projection. Where one of these crosses a corner, the closed loop's
right-hand side has a corner in time; DOP853's error estimate then
rejects step after step until the step is short enough to straddle it
(tens of microseconds at rtol 1e-10, atol 1e-12).

For the paper's law (double root -2, ratio 0, feedforward) and Stanley
(gain 2, ratio 0), at 20 m/s from 0.5 m beside the path, on the compiled
engine (:func:`fws_control.simulation.compiled.integrate_compiled`):

1. one run over the course, its accepted and rejected steps;
2. the same run cut at the times where s or the front axle's projection
   (Stanley only) crosses a corner, from a dense output grid of 400 001
   samples, linearly interpolated; each piece integrated alone from the
   previous piece's end state (the loop is autonomous: each piece starts
   at t = 0), and the sums of their steps and evaluations.

Printed: both runs' attempted steps (accepted and rejected) and
right-hand-side evaluations, their ratios, and each run's error at the
end in ``s, e, theta`` against the cut run at rtol 1e-13, atol 1e-15
(whose own error in ``s`` may reach about 1e-13 of the 200 m course).
Counts, not times: they do not depend on the machine.

Run: ``python benchmarks/bench_corners.py`` (a few seconds).
"""

from __future__ import annotations

import numpy as np
from timing import machine_line

import fws_control as fws
from fws_control.equations import front_axle_point
from fws_control.simulation.compiled import curvature_table, integrate_compiled

SPEED = 20.0
SAMPLES = 400_001
UNITS = ("m (s)", "m (e)", "rad (theta)")


def crossings(s: np.ndarray, t: np.ndarray, corners: np.ndarray) -> list[float]:
    """Times at which the arc length `s(t)` crosses one of `corners`."""
    ok = np.isfinite(s)
    s, t = s[ok], t[ok]
    out = []
    for c in corners:
        # one crossing per interval whose ends lie on either side (a sample
        # exactly at c counts once)
        for i in np.nonzero((s[:-1] < c) != (s[1:] < c))[0]:
            out.append(t[i] + (c - s[i]) * (t[i + 1] - t[i]) / (s[i + 1] - s[i]))
    return out


def main() -> None:
    print(machine_line())
    path = fws.double_lane_change(vehicle_width=1.8).path
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    breaks = np.asarray(curvature_table(path).breaks)
    # the breaks where the curvature's slope jumps (the others join two
    # straights, or two clothoids of the same sharpness)
    inner = breaks[1:-1]
    jump = path.curvature_rate(inner + 1e-6) - path.curvature_rate(inner - 1e-6)
    corners = inner[np.abs(jump) > 1e-9]
    g = fws.double_root_gains(veh, speed=SPEED, curvature=0.0, ratio=0.0, pole=-2.0)
    laws = {
        "paper law": fws.SteeringGains(float(g.k1), float(g.k2), 0.0),
        "Stanley": fws.Stanley(gain=2.0, ratio=0.0),
    }

    def run(law, x0, t_eval, rtol=1e-10, atol=1e-12):
        out = integrate_compiled(
            veh, path, law, speed=np.array([SPEED]), feedforward=True,
            path_state=np.array([x0]), t_eval=t_eval, time_constant=None,
            rtol=rtol, atol=atol,
        )  # fmt: skip
        return out[0][:, 0, :], out[4][0]

    def cut_run(law, x0, cuts, rtol=1e-10, atol=1e-12):
        """The end state and the statistics of the run cut at `cuts`."""
        total = np.zeros(3, dtype=np.int64)  # accepted, rejected, evaluations
        x, t0 = x0, 0.0
        for t1 in cuts:
            if t1 <= t0:  # (coincident cuts)
                continue
            piece, st = run(law, x, np.array([0.0, t1 - t0]), rtol, atol)
            total += st[:3]
            x, t0 = piece[:, -1], t1
        return x, total

    x0 = np.array([0.0, 0.5, 0.0])
    t = np.linspace(0.0, float(path.length) / SPEED, SAMPLES)
    print(
        f"ISO 3888-1 at {SPEED:g} m/s: {breaks.size} breaks of its curvature "
        f"table, {corners.size} of them corners of kappa(s) (at s = "
        + ", ".join(f"{c:.2f}" for c in corners)
        + " m)"
    )
    for name, law in laws.items():
        states, stats = run(law, x0, t)
        s, e, th = states
        end = float(t[np.isfinite(s)][-1])
        times = crossings(s, t, corners)
        if name == "Stanley":
            # the front axle, a wheelbase ahead of the rear axle R
            sr = np.nan_to_num(s)
            x, y = path.position(sr)
            fx, fy, _ = front_axle_point(
                x, y, path.heading(sr), np.nan_to_num(e), np.nan_to_num(th),
                veh.wheelbase,
            )  # fmt: skip
            sf = path.project(fx, fy, s_guess=sr + veh.wheelbase).s
            times += crossings(np.where(np.isfinite(s), sf, np.nan), t, corners)
        cuts = [*sorted(c for c in times if 0.0 < c < end), end]
        x, (accepted, rejected, evals) = cut_run(law, x0, cuts)
        ref = cut_run(law, x0, cuts, rtol=1e-13, atol=1e-15)[0]
        whole = states[:, np.searchsorted(t, end)]
        one = stats[0] + stats[1]
        print(
            f"  {name:10s} one run: {stats[0]:4d} accepted + {stats[1]:4d} "
            f"rejected = {one:4d} steps, {stats[2]:5d} evaluations; cut at "
            f"{len(cuts) - 1:2d} corner crossings: {accepted:4d} + {rejected:4d} "
            f"= {accepted + rejected:4d} steps, {evals:5d} evaluations "
            f"({one / (accepted + rejected):.2f}x fewer steps, "
            f"{stats[2] / evals:.2f}x fewer evaluations)"
        )
        for label, value in (("one run", whole), ("cut run", x)):
            err = np.abs(value - ref)
            print(
                f"    error at the end, {label}: "
                + ", ".join(f"{v:.1e} {u}" for v, u in zip(err, UNITS, strict=True))
            )
    print(machine_line())


if __name__ == "__main__":
    main()
