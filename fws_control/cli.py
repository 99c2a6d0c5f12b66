"""Command-line interface ``fws-control`` (also ``python -m fws_control``).

Subcommands::

    fws-control gains     --speed 5 --curvature 0.1 --ratio -1 --pole -1
    fws-control chart     --speed 5 --curvature 0.1 --ratio -1 --out chart.png
    fws-control chart     --paper-figure 3 --out fig3.png
    fws-control rlocus    --speed 5 --curvature 0.1 --ratio -1 --out rl.png
    fws-control simulate  --path arc --curvature 0.1 --y0 -5 --out sim.png
    fws-control delay-margin --speed 20 --ratio 0.5 --pole -1 --steering-lag 0.27
    fws-control compare   --manoeuvre iso3888-1 --speed 20 --delay 0.24
    fws-control reproduce --out figures

Angles are given and printed in degrees (also in the CSV of ``simulate``);
everything else is SI. Every subcommand defaults to the curvature
:data:`DEFAULT_CURVATURE` (0.1 1/m, the paper's Fig. 7 curve).

Exit status: 0 success; 2 invalid input (a one-line message on stderr, no
traceback); 3 ``simulate`` ran, but the run stopped early (e.g. at a singular
steering angle, ``|delta_f| -> 90 deg``): the figure, the CSV and the printed
status say when and why. Inputs far outside the range of the kinematic model
(e.g. a curvature above 1 1/m, ``|k2| > 20``) are accepted with a one-line
warning each on stderr.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path

__all__ = ["main", "build_parser"]

PROG = "fws-control"

#: Curvature [1/m] of every subcommand when --curvature is not given.
DEFAULT_CURVATURE = 0.1

#: Exit status of ``simulate`` when the run stopped before --duration.
EXIT_STOPPED = 3

#: (attribute, limit, what): a one-line warning when |value| exceeds limit.
_EXTREME = (
    ("curvature", 1.0, "1/m", "a turn radius below 1 m"),
    ("speed", 70.0, "m/s", "beyond road speeds"),
    ("ratio", 5.0, "", "rear steering far beyond any vehicle"),
    ("pole", 20.0, "1/s", "faster than steering actuators can follow"),
    ("k1", 10.0, "rad/m", "the steering saturates at centimetre errors"),
    ("k2", 20.0, "", "the steering saturates at tiny heading errors"),
    ("wheelbase", 10.0, "m", "not a road vehicle"),
)


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage block)."""

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return v


def _positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if v < 2:
        raise argparse.ArgumentTypeError(f"must be >= 2, got {v}")
    return v


def _add_vehicle(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("vehicle")
    g.add_argument("--wheelbase", type=_finite, default=2.7, help="f [m] (2.7)")
    g.add_argument(
        "--rear-to-cg", type=_finite, default=1.35, help="d, rear axle to CG [m] (1.35)"
    )


def _add_operating_point(p, curvature_default: float = DEFAULT_CURVATURE) -> None:
    p.add_argument("--speed", type=_finite, default=5.0, help="V [m/s] (5)")
    p.add_argument(
        "--curvature",
        type=_finite,
        default=curvature_default,
        help=f"path curvature kappa [1/m] ({curvature_default:g})",
    )
    p.add_argument(
        "--ratio", type=_finite, default=-1.0, help="a, delta_r = a*delta_f (-1)"
    )
    p.add_argument(
        "--model",
        choices=("exact", "paper"),
        default="exact",
        help="linearisation: exact Jacobian or the paper's eq. (33) (exact)",
    )


def _add_gains(p) -> None:
    p.add_argument(
        "--pole",
        type=_finite,
        default=-1.0,
        help="double root lambda0 [1/s] for the gains (-1); ignored with --k1/--k2",
    )
    p.add_argument("--k1", type=_finite, help="lateral-error gain [rad/m]")
    p.add_argument("--k2", type=_finite, help="heading-error gain [-]")


def build_parser() -> argparse.ArgumentParser:
    """The argparse parser of ``fws-control``."""
    parser = _Parser(
        prog=PROG,
        description="Path tracking with four-wheel steering: gains, stability "
        "charts, root loci, simulations and the paper's figures.",
    )
    from . import __version__

    parser.add_argument(
        "--version", action="version", version=f"%(prog)s {__version__}"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True

    p = sub.add_parser(
        "gains",
        help="double-root gains k1..k4 and closed-loop poles",
        description="Gains that put both closed-loop poles at --pole, in the exact "
        "model and in the paper's, with the poles each design gives in the "
        "exact linearisation.",
    )
    _add_operating_point(p)
    p.add_argument("--pole", type=_finite, default=-1.0, help="lambda0 [1/s] (-1)")
    _add_vehicle(p)
    p.set_defaults(func=_cmd_gains)

    p = sub.add_parser(
        "chart",
        help="stability chart in the (k1, k2) plane (PNG)",
        description="Routh-Hurwitz stable region, its boundaries and the "
        "lambda0 design point; or one of the paper's Figs. 2-4.",
    )
    _add_operating_point(p)
    p.add_argument("--pole", type=_finite, default=-1.0, help="lambda0 to mark (-1)")
    p.add_argument(
        "--k1-range",
        nargs=2,
        type=_finite,
        default=(-1.0, 1.0),
        metavar=("MIN", "MAX"),
        help="k1 axis [rad/m] (-1 1)",
    )
    p.add_argument(
        "--k2-range",
        nargs=2,
        type=_finite,
        default=(-1.0, 1.0),
        metavar=("MIN", "MAX"),
        help="k2 axis [-] (-1 1)",
    )
    p.add_argument(
        "--points", type=_positive_int, default=501, help="grid points per axis (501)"
    )
    p.add_argument(
        "--paper-figure",
        type=int,
        choices=(2, 3, 4),
        help="draw the paper's Fig. 2, 3 or 4 instead",
    )
    p.add_argument(
        "--out", type=Path, default=Path("chart.png"), help="PNG file (chart.png)"
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_chart)

    p = sub.add_parser(
        "rlocus",
        help="root locus of the gain scaling or of a parameter (PNG)",
        description="Root locus of the gain scaling g*(k1, k2) "
        "(control.root_locus_plot of the SISO loop), or with --param the "
        "closed-loop poles while ratio, speed, curvature, k1 or k2 varies.",
    )
    _add_operating_point(p)
    _add_gains(p)
    p.add_argument(
        "--param",
        choices=("gain", "ratio", "speed", "curvature", "k1", "k2"),
        default="gain",
        help="what varies (gain)",
    )
    p.add_argument(
        "--range",
        nargs=2,
        type=_finite,
        metavar=("MIN", "MAX"),
        help="range of the parameter (default: a sensible one)",
    )
    p.add_argument("--points", type=_positive_int, default=400, help="values (400)")
    p.add_argument(
        "--redesign",
        action="store_true",
        help="re-design the lambda0 gains at every value (not k1/k2)",
    )
    p.add_argument(
        "--design-model",
        choices=("exact", "paper"),
        help="model of the re-design (default --model); --model exact "
        "--design-model paper shows where the paper's gains put the true poles",
    )
    p.add_argument(
        "--out", type=Path, default=Path("rlocus.png"), help="PNG file (rlocus.png)"
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_rlocus)

    p = sub.add_parser(
        "simulate",
        help="nonlinear closed-loop simulation (PNG, optional CSV)",
        description="Simulate the nonlinear closed loop on a straight path or an "
        "arc from the initial pose (x0, y0, psi0) of the rear-axle centre, "
        "next to the linear closed loop from the same initial errors. Exit "
        f"status {EXIT_STOPPED} if the run stopped early (singular steering).",
    )
    _add_operating_point(p)
    _add_gains(p)
    p.add_argument(
        "--path",
        choices=("straight", "arc"),
        default="arc",
        help="reference path; arc of --curvature starting at the origin "
        "heading +x (arc)",
    )
    p.add_argument("--x0", type=_finite, default=0.0, help="x_R(0) [m] (0)")
    p.add_argument("--y0", type=_finite, default=-5.0, help="y_R(0) [m] (-5)")
    p.add_argument("--psi0", type=_finite, default=0.0, help="psi(0) [deg] (0)")
    p.add_argument("--duration", type=_finite, default=15.0, help="[s] (15)")
    p.add_argument(
        "--no-feedforward",
        action="store_true",
        help="feedback only (the paper's straight-road controller)",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("simulation.png"),
        help="PNG file (simulation.png)",
    )
    p.add_argument(
        "--csv",
        type=Path,
        help="also write the time series as CSV: header row with units, angles "
        "in deg and rates in deg/s as printed, a status column (none)",
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser(
        "delay-margin",
        help="critical input delay of a design (with an optional steering lag)",
        description="The smallest delay on the steering command at which a "
        "closed-loop root reaches the imaginary axis (the delay margin), with "
        "the crossing frequency. The double-root gains are designed on the "
        "kinematic model without lag; --steering-lag puts a first-order "
        "actuator in the plant they are evaluated on. With --delay, also the "
        "rightmost roots at that delay.",
    )
    _add_operating_point(p)
    _add_gains(p)
    p.add_argument(
        "--steering-lag",
        nargs="+",
        type=_finite,
        metavar="T",
        help="first-order steering time constant [s]: one for both axles or "
        "front and rear (none)",
    )
    p.add_argument(
        "--delay",
        type=_finite,
        help="also report the rightmost roots at this delay [s]",
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_delay_margin)

    p = sub.add_parser(
        "compare",
        help="controllers side by side on a standard manoeuvre (table + PNG)",
        description="Run the paper's double-root law (front steering and a rear "
        "ratio), rear-wheel feedback, pure pursuit, Stanley and LQR (paper "
        "structure and independent rear) on the same vehicle, course, speed, "
        "delay and steering lag, from the first gate to past the last; print a "
        "table of peak lateral acceleration, RMS and max lateral error, steering "
        "angles and rates (exact peaks), cones hit and completion, and write a "
        "figure.",
    )
    p.add_argument(
        "--manoeuvre",
        choices=("iso3888-1", "iso3888-2", "slalom", "circle"),
        default="iso3888-1",
        help="course (default: iso3888-1)",
    )
    p.add_argument("--speed", type=_finite, default=20.0, help="V [m/s] (20)")
    p.add_argument(
        "--ratio",
        type=_finite,
        default=-0.3,
        help="rear ratio of the 4WS designs (-0.3)",
    )
    p.add_argument(
        "--pole", type=_finite, default=-1.0, help="double root of the paper's law (-1)"
    )
    p.add_argument(
        "--delay", type=_finite, default=0.0, help="input delay on the steering [s] (0)"
    )
    p.add_argument(
        "--steering-lag",
        type=_finite,
        help="steering actuator time constant [s] (none)",
    )
    p.add_argument(
        "--offset",
        type=_finite,
        default=0.0,
        help="lateral offset of R from the centre line at the first gate [m] (0)",
    )
    p.add_argument(
        "--vehicle-width", type=_finite, default=1.8, help="b for the gates [m] (1.8)"
    )
    p.add_argument(
        "--out", type=Path, default=Path("compare.png"), help="PNG file (compare.png)"
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser(
        "reproduce",
        help="write every figure of the paper (Figs. 2-9) and summary.md",
        description="Regenerate the paper's Figs. 2-9 (plus extras) as PNG files "
        "and summary.md (gains table, Fig. 5 peak accelerations) in --out.",
    )
    p.add_argument(
        "--out", type=Path, default=Path("figures"), help="directory (figures)"
    )
    p.add_argument(
        "--model",
        choices=("exact", "paper"),
        default="exact",
        help="linearisation of the charts and designs (exact)",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="coarser grids and sweeps (seconds; for tests)",
    )
    p.add_argument(
        "--only",
        nargs="+",
        metavar="NAME",
        help="write only these figures (e.g. fig2 fig5)",
    )
    p.add_argument("--dpi", type=int, default=110, help="PNG resolution (110)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_reproduce)
    return parser


def _vehicle(args):
    from .vehicle import Vehicle

    return Vehicle(wheelbase=args.wheelbase, rear_to_cg=args.rear_to_cg)


def _plant(args, veh, model=None):
    from .plant import LateralPlant

    return LateralPlant(
        veh,
        speed=args.speed,
        curvature=args.curvature,
        model=args.model if model is None else model,
    )


def _gains(args, veh):
    from .design import double_root_gains
    from .gains import SteeringGains

    if (args.k1 is None) != (args.k2 is None):
        raise ValueError("give both --k1 and --k2, or neither (then --pole is used)")
    if args.k1 is not None:
        return SteeringGains(args.k1, args.k2, args.ratio)
    g = double_root_gains(_plant(args, veh), ratio=args.ratio, pole=args.pole)
    return SteeringGains(float(g.k1), float(g.k2), args.ratio)


def _fmt_poles(p) -> str:
    import numpy as np

    out = []
    for z in np.sort_complex(np.asarray(p, dtype=complex)):
        out.append(
            f"{z.real:.6f}" if abs(z.imag) < 1e-6 else f"{z.real:.6f}{z.imag:+.6f}j"
        )
    return ", ".join(out)


def _fmt_coeffs(c) -> str:
    """Polynomial coefficients for display, without float noise."""
    import numpy as np

    vals = [float(f"{v:.10g}") + 0.0 for v in np.asarray(c, dtype=float)]
    return (
        "["
        + ", ".join(f"{v:g}" if abs(v) >= 1e-4 or v == 0 else f"{v:.6g}" for v in vals)
        + "]"
    )


def _cmd_gains(args) -> int:
    import numpy as np

    from .design import UncontrollableError, double_root_gains
    from .plant import loop_matrices

    veh = _vehicle(args)
    # Design first so that bad input fails before anything is printed.
    double_root_gains(_plant(args, veh), ratio=args.ratio, pole=args.pole)
    print(
        f"V = {args.speed:g} m/s, kappa = {args.curvature:g} 1/m, a = {args.ratio:g}, "
        f"lambda0 = {args.pole:g} 1/s, f = {veh.wheelbase:g} m"
    )
    order = [args.model] + [m for m in ("exact", "paper") if m != args.model]
    for model in order:
        try:
            g = double_root_gains(
                _plant(args, veh, model), ratio=args.ratio, pole=args.pole
            )
        except UncontrollableError as exc:
            if model == args.model:
                raise
            print(f"{model} model: no design ({exc})")
            continue
        tag = "" if model == args.model else " (for comparison)"
        print(f"{model} model{tag}:")
        print(f"  k1 = {float(g.k1):.6f} rad/m   k2 = {float(g.k2):.6f}")
        print(f"  k3 = {float(g.k3):.6f} rad/m   k4 = {float(g.k4):.6f}")
        for lin in ("exact", "paper"):
            # Eigenvalues of A - b (k1 c_e + k2 c_theta), the closed_loop state
            # matrix, without building a control.StateSpace (~1 s of import).
            lm = loop_matrices(_plant(args, veh, lin))
            k = float(g.k1) * lm.c_e + float(g.k2) * lm.c_theta
            poles = np.linalg.eigvals(lm.A - np.outer(lm.input_vector(args.ratio), k))
            print(f"  closed-loop poles, {lin} linearisation: {_fmt_poles(poles)}")
    return 0


def _cmd_chart(args) -> int:
    import matplotlib.pyplot as plt
    import numpy as np

    from .charts import stability_chart
    from .paper.charts import plot_paper_figure

    _check_out(args.out)
    if args.paper_figure is not None:
        fig = plot_paper_figure(args.paper_figure, model=args.model).figure
    else:
        k1 = np.linspace(*args.k1_range, args.points)
        k2 = np.linspace(*args.k2_range, args.points)
        ch = stability_chart(
            _plant(args, _vehicle(args)),
            ratio=args.ratio,
            k1=k1,
            k2=k2,
            pole=args.pole,
        )
        fig = ch.plot().figure
        if ch.design is not None:
            print(f"k1 = {float(ch.design.k1):.6f}, k2 = {float(ch.design.k2):.6f}")
        for note in ch.notes():
            print(note.replace("$\\lambda_0$", "lambda0"))
        print(f"stable fraction of the grid: {ch.stable_fraction:.3f}")
    _save(fig, args.out)
    plt.close(fig)
    return 0


_PARAM_RANGE = {
    "ratio": (-1.5, 0.99),
    "speed": (1.0, 30.0),
    "curvature": (0.0, 0.3),
    "k1": (-0.5, 1.0),
    "k2": (-1.0, 2.0),
}


def _fixed_params(args) -> str:
    """The operating point without the parameter that varies."""
    parts = {
        "ratio": f"a = {args.ratio:g}",
        "speed": f"V = {args.speed:g} m/s",
        "curvature": f"kappa = {args.curvature:g} 1/m",
    }
    parts.pop(args.param, None)
    return ", ".join(parts.values())


def _cmd_rlocus(args) -> int:
    import control as ct
    import matplotlib.pyplot as plt
    import numpy as np

    from .rootlocus import gain_loop, parameter_locus, refined_scale

    _check_out(args.out)
    veh = _vehicle(args)
    g = _gains(args, veh)
    if args.param == "gain":
        if args.redesign:
            raise ValueError("--redesign needs --param ratio, speed or curvature")
        loop = gain_loop(_plant(args, veh), g)
        lo, hi = (0.0, 5.0) if args.range is None else args.range
        if lo < 0 or hi <= lo:
            raise ValueError(
                f"--range for the gain scale must be 0 <= MIN < MAX, got {lo:g} {hi:g}"
            )
        scale = refined_scale(lo, hi, args.points)
        cplt = ct.root_locus_plot(loop, gains=scale, grid=False, initial_gain=1.0)
        fig = cplt.figure
        ax = cplt.axes[0, 0]
        ax.set_title(
            f"gain locus of g*(k1, k2), k1 = {float(g.k1):.4f}, k2 = {float(g.k2):.4f}"
            f"\na = {args.ratio:g}, V = {args.speed:g} m/s, kappa = {args.curvature:g}"
            f" 1/m, {args.model} model; square: g = 1",
            fontsize=10,
        )
        fig.suptitle("")
        print(f"L(s) = {_fmt_coeffs(loop.num[0][0])} / {_fmt_coeffs(loop.den[0][0])}")
    else:
        lo, hi = _PARAM_RANGE[args.param] if args.range is None else args.range
        if hi <= lo:
            raise ValueError(f"--range must have MIN < MAX, got {lo:g} {hi:g}")
        values = np.linspace(lo, hi, args.points)
        pz = parameter_locus(
            _plant(args, veh),
            g,
            parameter=args.param,
            values=values,
            redesign_pole=args.pole if args.redesign else None,
            design_model=args.design_model,
        )
        fig, ax = plt.subplots(figsize=(7, 5.5), layout="constrained")
        for j, branch in enumerate(pz.loci.T):
            ax.plot(
                branch.real,
                branch.imag,
                color="C0",
                label="closed-loop poles" if j == 0 else None,
            )
        ax.plot(
            pz.loci[0].real,
            pz.loci[0].imag,
            "x",
            color="C0",
            ms=8,
            label=f"{args.param} = {lo:g}",
        )
        ax.plot(
            pz.loci[-1].real,
            pz.loci[-1].imag,
            ">",
            color="C0",
            ms=8,
            label=f"{args.param} = {hi:g}",
        )
        ax.axvline(0.0, color="0.5", lw=0.8)
        ax.axhline(0.0, color="0.8", lw=0.6)
        ymax = max(float(np.abs(pz.loci.imag).max()), 0.1) * 1.2
        ax.set_ylim(-ymax, ymax)
        ax.grid(alpha=0.3)
        ax.set_xlabel("Re [1/s]")
        ax.set_ylabel("Im [1/s]")
        if args.redesign:
            dm = args.model if args.design_model is None else args.design_model
            what = f"gains re-designed in the {dm} model"
        else:
            what = "fixed gains"
        ax.set_title(
            f"closed-loop poles, {args.param} from {lo:g} to {hi:g} ({what})\n"
            f"{_fixed_params(args)}, poles of the {args.model} model",
            fontsize=10,
        )
        ax.legend(fontsize=8)
    _save(fig, args.out)
    plt.close(fig)
    return 0


def _cmd_simulate(args) -> int:
    import matplotlib.pyplot as plt

    from .comparison import compare_linear_nonlinear

    veh = _vehicle(args)
    if args.path == "straight" and args.curvature != 0.0 and args.k1 is None:
        # The design of a straight path is made at zero curvature.
        args.curvature = 0.0
    g = _gains(args, veh)
    cmp = compare_linear_nonlinear(
        veh,
        g,
        speed=args.speed,
        curvature=args.curvature if args.path == "arc" else 0.0,
        initial_state=(args.x0, args.y0, math.radians(args.psi0)),
        duration=args.duration,
        feedforward=not args.no_feedforward,
        model=args.model,
    )
    res = cmp.nonlinear
    fig = cmp.plot().figure
    stopped = str(res.status) != "ok"
    if stopped:
        why = str(res.status).replace("_", " ")
        detail = f" ({res.message})" if res.message else ""
        fig.text(
            0.5,
            0.005,
            f"run stopped at t = {float(res.t_stop):.3g} s: {why}{detail}; "
            "curves end there",
            ha="center",
            va="bottom",
            color="C3",
            fontsize=10,
            bbox={"fc": "white", "ec": "C3"},
        )
    _save(fig, args.out)
    plt.close(fig)
    print(f"k1 = {float(g.k1):.6f}, k2 = {float(g.k2):.6f}, a = {float(g.ratio):g}")
    print(f"status: {res.status}{(' - ' + res.message) if res.message else ''}")
    import numpy as np

    acc = np.abs(np.asarray(res.lateral_accel, dtype=float))
    peak = (
        f"{np.nanmax(acc):.4f} m/s^2"
        if np.isfinite(acc).any()
        else "n/a (no valid sample)"
    )
    print(f"peak |lateral acceleration| = {peak}")
    print(
        f"final e = {res.e[-1]:.4g} m, final theta = "
        f"{math.degrees(res.theta[-1]):.4g} deg"
    )
    if args.csv is not None:
        _write_csv(res, args.csv)
        print(f"wrote {args.csv}")
    if stopped:
        print(
            f"{PROG} simulate: run stopped at t = {float(res.t_stop):.3g} s "
            f"({res.status}); exit status {EXIT_STOPPED}",
            file=sys.stderr,
        )
        return EXIT_STOPPED
    return 0


#: Unit of each CSV column; angles in degrees as the CLI prints them.
_CSV_UNITS = {
    "t": "s",
    "x": "m",
    "y": "m",
    "psi": "deg",
    "s": "m",
    "e": "m",
    "theta": "deg",
    "delta_f": "deg",
    "delta_r": "deg",
    "delta_f_rate": "deg/s",
    "delta_r_rate": "deg/s",
    "lateral_accel": "m/s^2",
    "v_y": "m/s",
    "yaw_rate": "deg/s",
    "slip_front": "deg",
    "slip_rear": "deg",
}


def _write_csv(res, path: Path) -> None:
    """One row per sample; header ``name [unit]``; last column the status.

    The status column reads ``ok`` while the run is valid and the run's
    status (e.g. ``singular_steering``) from the stop on; samples after the
    stop are empty.
    """
    import csv

    import numpy as np

    from .simulation import SIGNALS

    names = ("t", *SIGNALS)
    cols = []
    for n in names:
        v = np.asarray(getattr(res, n), dtype=float)
        cols.append(np.degrees(v) if _CSV_UNITS[n].startswith("deg") else v)
    t = cols[0]
    status = np.full(t.shape, "ok", dtype=object)
    if str(res.status) != "ok":
        status[t >= float(res.t_stop) - 1e-12] = str(res.status)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow([f"{n} [{_CSV_UNITS[n]}]" for n in names] + ["status"])
        for i in range(t.size):
            w.writerow(
                ["" if not np.isfinite(c[i]) else f"{c[i]:.10g}" for c in cols]
                + [status[i]]
            )


def _cmd_compare(args) -> int:
    import matplotlib.pyplot as plt

    from .controller_comparison import compare, default_controllers
    from .manoeuvres import (
        constant_radius,
        double_lane_change,
        obstacle_avoidance,
        slalom,
    )

    _check_out(args.out)
    if args.speed <= 0:
        raise ValueError(f"--speed must be > 0 m/s, got {args.speed:g}")
    course = {
        "iso3888-1": lambda: double_lane_change(vehicle_width=args.vehicle_width),
        "iso3888-2": lambda: obstacle_avoidance(vehicle_width=args.vehicle_width),
        "slalom": lambda: slalom(vehicle_width=args.vehicle_width),
        "circle": lambda: constant_radius(),
    }[args.manoeuvre]()
    veh = _vehicle(args)
    ctrls = default_controllers(veh, speed=args.speed, ratio=args.ratio, pole=args.pole)
    cmp = compare(
        veh,
        course,
        ctrls,
        speed=args.speed,
        offset=args.offset,
        delay=args.delay,
        actuator_time_constant=args.steering_lag,
    )
    cplt = cmp.plot()
    _save(cplt.figure, args.out)
    plt.close(cplt.figure)
    lag = "none" if args.steering_lag is None else f"{args.steering_lag:g} s"
    print(
        f"{course.name}, V = {args.speed:g} m/s, delay {args.delay:g} s, steering "
        f"lag {lag}, initial offset {args.offset:g} m"
    )
    print(cmp.to_markdown())
    return 0


def _cmd_delay_margin(args) -> int:
    from .delay import critical_delay, rightmost_roots
    from .plant import LateralPlant

    veh = _vehicle(args)
    g = _gains(args, veh)
    lag = args.steering_lag
    if lag is not None and len(lag) not in (1, 2):
        raise ValueError(
            f"--steering-lag takes one or two time constants, got {len(lag)}"
        )
    plant = LateralPlant(
        veh,
        speed=args.speed,
        curvature=args.curvature,
        model=args.model,
        steering_lag=None if lag is None else (lag[0] if len(lag) == 1 else lag),
    )
    cd = critical_delay(plant, g)
    design = "given gains" if args.k1 is not None else f"lambda0 = {args.pole:g} design"
    print(
        f"V = {args.speed:g} m/s, kappa = {args.curvature:g} 1/m, a = {args.ratio:g}, "
        f"k1 = {float(g.k1):.6f} rad/m, k2 = {float(g.k2):.6f} ({design}, "
        f"{args.model} model)"
    )
    if plant.steering_lag is None:
        print("steering lag: none")
    else:
        tf_, tr = plant.steering_lag
        print(f"steering lag: {tf_:g} s front, {tr:g} s rear")
    if not cd.stable_without_delay:
        print("critical delay: 0 s (the loop is unstable without delay)")
    elif math.isinf(cd.delay):
        print("critical delay: inf (no delay destabilises the loop)")
    else:
        print(
            f"critical delay: {cd.delay:.6g} s (crossing at {cd.frequency:.6g} rad/s "
            f"= {cd.frequency / (2 * math.pi):.4g} Hz)"
        )
    if args.delay is not None:
        roots = rightmost_roots(plant, g, delay=args.delay, n=2)
        verdict = "stable" if roots[0].real < 0 else "unstable"
        print(
            f"at delay {args.delay:g} s: {verdict}; rightmost roots {_fmt_poles(roots)}"
        )
    return 0


def _cmd_reproduce(args) -> int:
    from .paper.figures import reproduce

    res = reproduce(
        args.out,
        model=args.model,
        quick=args.quick,
        progress=not args.no_progress,
        dpi=args.dpi,
        names=args.only,
    )
    for p in res.figures:
        print(p)
    print(res.summary)
    return 0


def _check_out(out: Path) -> None:
    if Path(out).suffix.lower() != ".png":
        raise ValueError(f"--out must be a .png file, got {str(out)!r}")


def _save(fig, out: Path) -> None:
    out = Path(out)
    _check_out(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


def _warn_extreme(args) -> None:
    """One line on stderr per input far outside the model's useful range."""
    for name, limit, unit, why in _EXTREME:
        v = getattr(args, name, None)
        if v is not None and abs(v) > limit:
            u = f" {unit}" if unit else ""
            print(
                f"{PROG} {args.command}: warning: --{name.replace('_', '-')} "
                f"{v:g}{u} is outside |{name}| <= {limit:g}{u} ({why}); "
                "results may be meaningless",
                file=sys.stderr,
            )


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``fws-control``; returns the exit status.

    Errors in the input (ValueError, including UncontrollableError and
    SingularStateError, TypeError, OSError) end with one line on stderr and
    status 2; ``simulate`` returns 3 (:data:`EXIT_STOPPED`) when the run
    stopped early. Extreme but valid inputs print one warning line each.
    """
    import logging

    # Agg for every figure, without importing matplotlib here (0.2 s that
    # --help and gains do not need): through the environment until it is
    # imported.
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg")
    else:
        os.environ["MPLBACKEND"] = "Agg"
    # Equal-aspect root-locus axes make matplotlib log "Ignoring fixed x
    # limits ..." at every save; it is noise for a command-line user.
    logging.getLogger("matplotlib").setLevel(logging.ERROR)
    parser = build_parser()
    args = parser.parse_args(argv)
    _warn_extreme(args)
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:
        # Output piped into e.g. `head`, which closed early: not an error.
        # Point stdout at devnull so the interpreter's final flush is silent.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except (ValueError, TypeError, OSError, ArithmeticError) as exc:
        msg = " ".join(str(exc).split())
        print(f"{PROG} {args.command}: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
