"""Command-line interface ``fws-control`` (also ``python -m fws_control``).

Subcommands::

    fws-control gains     --speed 5 --curvature 0.1 --ratio -1 --pole -1
    fws-control chart     --speed 5 --curvature 0.1 --ratio -1 --out chart.png
    fws-control chart     --paper-figure 3 --out fig3.png
    fws-control rlocus    --speed 5 --curvature 0.1 --ratio -1 --out rl.png
    fws-control simulate  --path arc --curvature 0.1 --y0 -5 --out sim.png
    fws-control delay-margin --speed 20 --ratio 0.5 --pole -1 --steering-lag 0.27
    fws-control compare   --manoeuvre iso3888-1 --speed 20 --delay 0.24
    fws-control design    --speed 20 --delay 0.24 --steering-lag 0.27 --json
    fws-control reproduce --out figures

Angles are given and printed in degrees (also in the CSV of ``simulate``);
everything else is SI. Every subcommand but ``design`` defaults to the
curvature :data:`DEFAULT_CURVATURE` (0.1 1/m, the paper's Fig. 7 curve);
``design`` defaults to a straight road (its defaults are the 20 m/s case
with Autoware's delay and steering lag).

Exit status: 0 success; 1 an unexpected failure (one line on stderr; run
with ``--debug`` or ``FWS_CONTROL_DEBUG=1`` for the traceback); 2 invalid
input, a request beyond the work budget (:data:`BUDGETS`) or an output folder
in use (a one-line message on stderr, no traceback); 3 ``simulate`` ran, but
the run stopped early (e.g. at a singular steering angle, ``|delta_f| -> 90
deg``): the figure, the CSV and the printed status say when and why; 130
interrupted (Ctrl-C), 143 terminated (``SIGTERM``). Inputs far outside the
range of the kinematic model (e.g. a curvature above 1 1/m, ``|k2| > 20``)
are accepted with a one-line warning each on stderr.

Every file is written to a temporary file in its folder and renamed into
place (:func:`fws_control.files.atomic_write`): an interrupted command leaves
complete files only. ``reproduce`` holds a lock on its output folder; a
second ``reproduce`` into the same folder is refused at once (status 2).
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import math
import os
import re
import signal
import sys
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

if TYPE_CHECKING:
    from .manoeuvres import Manoeuvre

__all__ = [
    "main",
    "run",
    "build_parser",
    "BUDGETS",
    "COMPARE_MIN_SPEED",
    "COMPARE_MIN_STEERING_LAG",
    "DELAY_MARGIN_MIN_DELAY",
    "DEBUG_ENV",
    "DESIGN_TOLERANCE",
    "MAX_MESSAGE",
]

PROG = "fws-control"

#: Curvature [1/m] of every subcommand when --curvature is not given.
DEFAULT_CURVATURE = 0.1

#: Exit status of ``simulate`` when the run stopped before --duration.
EXIT_STOPPED = 3

#: Work budget of each size option: (subcommand, option) -> (largest value,
#: unit, what to do instead). A larger request is refused with exit status 2 before
#: any work starts; the limits keep every command within about a gigabyte of
#: memory and a minute on a laptop (measured: ``chart --points 2001`` 0.33 GB,
#: 2.4 s; ``rlocus --points 10000`` 2.3 s; ``simulate --duration 3600`` 0.4
#: GB, 4.8 s; ``reproduce --dpi 600``: the widest figure is 10200 x 3120
#: pixels).
BUDGETS: dict[tuple[str, str], tuple[int | float, str, str]] = {
    ("chart", "--points"): (
        2001,
        "points per axis",
        "for finer detail narrow --k1-range/--k2-range",
    ),
    ("rlocus", "--points"): (10000, "values", "for finer detail narrow --range"),
    ("simulate", "--duration"): (
        3600.0,
        "s",
        "for longer runs use fws_control.simulate with a coarser dt",
    ),
    ("reproduce", "--dpi"): (
        600,
        "dpi",
        "for larger images use fws_control.paper.make_figure and savefig",
    ),
    ("delay-margin", "--delay"): (
        60.0,
        "s",
        "the critical delay (without --delay) decides stability at any delay",
    ),
    ("compare", "--delay"): (
        10.0,
        "s",
        "longer than the whole manoeuvre",
    ),
}

#: ``compare --vehicle`` choices -> CommonRoad vehicle id
#: (:func:`fws_control.vehicles.from_commonroad` numbering).
COMPARE_VEHICLES = {"ford-escort": 1, "bmw-320i": 2, "vw-vanagon": 3}

#: Slowest speed [m/s] of ``compare``: the manoeuvre's duration and cost grow
#: as 1/speed (0.5 m/s already takes half a minute).
COMPARE_MIN_SPEED = 1.0

#: Smallest nonzero ``delay-margin --delay`` [s]: the rightmost-root search
#: grows as the delay shrinks (1e-4 s: 6 s, 1e-5 s: 31 s, 1e-6 s: minutes).
DELAY_MARGIN_MIN_DELAY = 1e-4

#: Fastest steering lag [s] of ``compare``: a faster first-order actuator
#: makes the closed loop stiff, and the explicit solver's cost grows as 1/lag
#: (0.01 s already doubles the run time; 0.001 s takes minutes).
COMPARE_MIN_STEERING_LAG = 0.01

#: Largest relative distance of a design's closed-loop poles (in its own
#: linearisation) from the requested double root before the CLI refuses the
#: gains: well-posed designs reach about 1e-5 (measured over V 1..40 m/s,
#: kappa 0..0.3, a -1.5..1.5, lambda0 -0.1..-10); a = 0.9999 on a straight
#: road misses by 2e-3, a = 1 - 2e-6 by 1.5.
DESIGN_TOLERANCE = 1e-3

#: Error messages longer than this (plus a margin of 60) are cut to about
#: this many characters on stderr, keeping their beginning and end.
MAX_MESSAGE = 200

#: Environment variable that, set to 1, lets errors end with a traceback.
DEBUG_ENV = "FWS_CONTROL_DEBUG"

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
        self.exit(2, f"{self.prog}: error: {_bounded(message)} (see --help)\n")

    def exit(self, status=0, message=None):  # noqa: D401 - argparse API
        if message:
            _say(message.rstrip("\n"))
        sys.exit(status)


# A negative number in any float spelling: -1, -1.5, -.5, -1e3, -1.5e-2,
# -1E+3, -inf, -nan. argparse (before Python 3.13.1) takes "-1e3" for an
# option because its negative-number pattern knows no exponent.
_NEGATIVE_NUMBER = re.compile(
    r"-(?:(?:\d[\d_]*(?:\.[\d_]*)?|\.\d[\d_]*)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan)",
    re.IGNORECASE,
)


def _protect_negative_numbers(argv: Sequence[str]) -> list[str]:
    """Let option values such as ``--pole -1e3`` through argparse.

    argparse treats a token as an option when it starts with ``-``, and as a
    value otherwise (no option of this program starts with a digit or a
    dot). A leading space keeps a negative number a value; ``float`` and
    ``int`` ignore it. Tokens after ``--`` are left alone.
    """
    out = []
    rest = False
    for tok in argv:
        if tok == "--":
            rest = True
        if not rest and _NEGATIVE_NUMBER.fullmatch(tok):
            tok = " " + tok
        out.append(tok)
    return out


def _finite(text: str) -> float:
    text = text.strip()
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {_short(text)}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be finite, got {text!r}")
    return v


def _model_type(flag: str):
    """The argparse type of a linearisation option such as ``--model``.

    A deprecated name (``exact``) is read as its current name
    (``kinematic``) with a one-line warning on stderr.
    """

    def model(text: str) -> str:
        from .deprecation import LEGACY_MODELS, REMOVED_IN

        if text in LEGACY_MODELS:
            new = LEGACY_MODELS[text]
            _say(
                f"{PROG}: warning: {flag} {text} is deprecated and is removed in "
                f"fws_control {REMOVED_IN}; use {flag} {new}"
            )
            return new
        return text

    model.__name__ = flag.lstrip("-").replace("-", "_")  # argparse's messages
    return model


def _angle_deg(text: str) -> float:
    """A finite angle in degrees whose magnitude names a direction."""
    from .validation import MAX_ANGLE

    v = _finite(text)
    limit = math.degrees(MAX_ANGLE)
    if abs(v) > limit:
        raise argparse.ArgumentTypeError(
            f"must have magnitude <= {limit:.4g} deg (angles are used modulo "
            f"360 deg, and a larger number names no direction), got {v:g}"
        )
    return v


def _positive_int(
    text: str, *, low: int = 2, high: int | None = None, unit: str = "", hint=""
) -> int:
    """An integer in ``low..high``; integral floats (``1e4``) are accepted."""
    text = text.strip()
    try:
        v = int(text)
    except ValueError:
        try:
            f = float(text)
        except ValueError:
            f = math.nan
        if not (math.isfinite(f) and f == int(f)):
            raise argparse.ArgumentTypeError(
                f"not an integer: {_short(text)}"
            ) from None
        v = int(f)
    if v < low:
        raise argparse.ArgumentTypeError(f"must be >= {low}, got {v}")
    if high is not None and v > high:
        raise argparse.ArgumentTypeError(
            f"{v} is beyond the budget of {high} {unit}; {hint}"
            if hint
            else f"must be <= {high}, got {v}"
        )
    return v


def _budget_int(command: str, option: str, low: int = 2):
    high, unit, hint = BUDGETS[(command, option)]

    def parse(text: str) -> int:
        return _positive_int(text, low=low, high=int(high), unit=unit, hint=hint)

    parse.__name__ = "integer"  # argparse names the type in some messages
    return parse


def _budget_float(
    command: str, option: str, *, positive: bool = True, smallest: float = 0.0
):
    """A number in ``(0, high]`` (``[0, high]`` if not ``positive``).

    With ``smallest``, a nonzero value must be at least ``smallest`` too.
    """
    high, unit, hint = BUDGETS[(command, option)]

    def parse(text: str) -> float:
        v = _finite(text)
        if positive and v <= 0:
            raise argparse.ArgumentTypeError(f"must be > 0, got {v:g}")
        if v < 0:
            raise argparse.ArgumentTypeError(f"must be >= 0, got {v:g}")
        if 0 < v < smallest:
            raise argparse.ArgumentTypeError(
                f"{v:g} is below the smallest {smallest:g} {unit} that the budget "
                f"allows (0 is allowed): the root search needs ever more work as "
                "the delay shrinks"
            )
        if v > high:
            raise argparse.ArgumentTypeError(
                f"{v:g} is beyond the budget of {high:g} {unit}; {hint}"
            )
        return v

    parse.__name__ = "number"
    return parse


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
        type=_model_type("--model"),
        choices=("kinematic", "paper"),
        default="kinematic",
        help="linearisation: the exact Jacobian of the kinematic model or the "
        "paper's eq. (33) (kinematic)",
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
    parser.add_argument(
        "--debug",
        action="store_true",
        help=f"show the traceback of an error (also {DEBUG_ENV}=1)",
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
    p.add_argument("--json", action="store_true", help="machine-readable output")
    _add_vehicle(p)
    p.set_defaults(func=_cmd_gains)

    p = sub.add_parser(
        "chart",
        help="stability chart in the (k1, k2) plane (figure)",
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
        "--points",
        type=_budget_int("chart", "--points"),
        default=501,
        help=f"grid points per axis, 2 to {BUDGETS[('chart', '--points')][0]} (501)",
    )
    p.add_argument(
        "--paper-figure",
        type=int,
        choices=(2, 3, 4),
        help="draw the paper's Fig. 2, 3 or 4 instead",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("chart.png"),
        help="figure file: .png, .svg or .pdf (chart.png)",
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_chart)

    p = sub.add_parser(
        "rlocus",
        help="root locus of the gain scaling or of a parameter (figure)",
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
    p.add_argument(
        "--points",
        type=_budget_int("rlocus", "--points"),
        default=400,
        help=f"values, 2 to {BUDGETS[('rlocus', '--points')][0]} (400)",
    )
    p.add_argument(
        "--redesign",
        action="store_true",
        help="re-design the lambda0 gains at every value (not k1/k2)",
    )
    p.add_argument(
        "--design-model",
        type=_model_type("--design-model"),
        choices=("kinematic", "paper"),
        help="model of the re-design (default --model); --model kinematic "
        "--design-model paper shows where the paper's gains put the true poles",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("rlocus.png"),
        help="figure file: .png, .svg or .pdf (rlocus.png)",
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_rlocus)

    p = sub.add_parser(
        "simulate",
        help="nonlinear closed-loop simulation (figure, optional CSV)",
        description="Simulate the nonlinear closed loop on a straight path or an "
        "arc from the initial pose (x0, y0, psi0) of the rear-axle centre, "
        "next to the linear closed loop from the same initial errors. Exit "
        f"status {EXIT_STOPPED} if the run stopped early (singular steering).",
    )
    _add_operating_point(p)
    _add_gains(p)
    p.add_argument(
        "--path",
        choices=("straight", "arc", *COURSES),
        default="arc",
        help="reference path; arc of --curvature starting at the origin "
        "heading +x; or a course: ISO 3888-1 lane change, ISO 3888-2 obstacle "
        "avoidance, 18 m slalom (nonlinear run only, gains designed on a "
        "straight road, run to the end of the course) (arc)",
    )
    p.add_argument("--x0", type=_finite, default=0.0, help="x_R(0) [m] (0)")
    p.add_argument(
        "--y0", type=_finite, default=None, help="y_R(0) [m] (-5; 0 on a course)"
    )
    p.add_argument("--psi0", type=_angle_deg, default=0.0, help="psi(0) [deg] (0)")
    p.add_argument(
        "--duration",
        type=_budget_float("simulate", "--duration"),
        default=None,
        help="[s], at most "
        f"{BUDGETS[('simulate', '--duration')][0]:g} s, sampled every 0.01 s (15; "
        "on a course: its length over --speed)",
    )
    p.add_argument(
        "--no-feedforward",
        action="store_true",
        help="feedback only (the paper's straight-road controller)",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("simulation.png"),
        help="figure file: .png, .svg or .pdf (simulation.png)",
    )
    p.add_argument(
        "--csv",
        type=Path,
        help="also write the time series as CSV: header row with units, angles "
        "in deg and rates in deg/s as printed, a status column (none)",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
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
        type=_budget_float(
            "delay-margin", "--delay", positive=False, smallest=DELAY_MARGIN_MIN_DELAY
        ),
        help="also report the rightmost roots at this delay [s]: 0, or "
        f"{DELAY_MARGIN_MIN_DELAY:g} to {BUDGETS[('delay-margin', '--delay')][0]:g}",
    )
    p.add_argument("--json", action="store_true", help="machine-readable output")
    _add_vehicle(p)
    p.set_defaults(func=_cmd_delay_margin)

    p = sub.add_parser(
        "compare",
        help="controllers side by side on a standard manoeuvre (table + figure)",
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
    p.add_argument(
        "--speed",
        type=_finite,
        default=20.0,
        help=f"V [m/s], at least {COMPARE_MIN_SPEED:g} (the run lasts course "
        "length / V) (20)",
    )
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
        "--delay",
        type=_budget_float("compare", "--delay", positive=False),
        default=0.0,
        help="input delay on the steering [s], 0 to "
        f"{BUDGETS[('compare', '--delay')][0]:g} (0)",
    )
    p.add_argument(
        "--steering-lag",
        type=_finite,
        help="steering actuator time constant [s], at least "
        f"{COMPARE_MIN_STEERING_LAG:g} (none: ideal steering)",
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
        "--model",
        choices=("kinematic", "dynamic"),
        default="kinematic",
        help="simulated model: kinematic, or the dynamic single-track model with "
        "tyres (needs --vehicle) (kinematic)",
    )
    p.add_argument(
        "--tyre",
        choices=("linear", "magic"),
        default="linear",
        help="tyre of --model dynamic: linear, or magic (saturates at the "
        "friction limit) (linear)",
    )
    p.add_argument(
        "--controllers",
        nargs="+",
        metavar="NAME",
        help="run only these controllers, by their labels in the table (quote "
        "each, e.g. 'pure pursuit' 'paper, a = 0') (all)",
    )
    p.add_argument(
        "--vehicle",
        choices=tuple(COMPARE_VEHICLES),
        help="a CommonRoad car (geometry, mass, tyres, friction; replaces "
        "--wheelbase and --rear-to-cg); the table then adds the friction use",
    )
    p.add_argument(
        "--out",
        type=Path,
        default=Path("compare.png"),
        help="figure file: .png, .svg or .pdf (compare.png)",
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser(
        "reproduce",
        help="write every figure of the paper (Figs. 2-9) and summary.md",
        description="Regenerate the paper's Figs. 2-9 (plus extras) as PNG, SVG "
        "or PDF files "
        "and summary.md (gains table, Fig. 5 peak accelerations) in --out. Each "
        "file is written under a temporary name and renamed when complete, so an "
        "interrupted run (Ctrl-C: exit status 130) leaves complete files only. "
        "The run locks the folder (file .fws-control.lock, released when the "
        "process ends, however it ends); a second run into a folder in use is "
        "refused at once with exit status 2.",
    )
    p.add_argument(
        "--out", type=Path, default=Path("figures"), help="directory (figures)"
    )
    p.add_argument(
        "--model",
        type=_model_type("--model"),
        choices=("kinematic", "paper"),
        default="kinematic",
        help="linearisation of the charts and designs (kinematic)",
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
    p.add_argument(
        "--dpi",
        type=_budget_int("reproduce", "--dpi", low=1),
        default=110,
        help=f"PNG resolution, 1 to {BUDGETS[('reproduce', '--dpi')][0]} (110)",
    )
    p.add_argument(
        "--format",
        choices=("png", "svg", "pdf"),
        default="png",
        help="file format of the figures (png)",
    )
    p.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (none either when stderr is not a terminal)",
    )
    p.set_defaults(func=_cmd_reproduce)
    _add_design_parser(sub)
    p = sub.add_parser(
        "compile",
        help="compile the compiled engine's kernels now (extra 'fast')",
        description="Compile the kernels of the compiled simulation engine into "
        "its cache (fws_control.simulation.precompile), as the first simulations "
        "after an install would (in a background process, while they run on the "
        "numpy engine): the paper's loop with DOP853 and with Radau, "
        "the kernels of a delay, the dynamic model, a controller's law or a "
        "varying speed, and the one-run drivers solve_run and radau_run. Prints "
        "the CPU time of each set; a set already cached takes about a second.",
    )
    p.add_argument(
        "--jobs", type=lambda t: _positive_int(t, low=1, high=64), default=2,
        help="worker processes that compile at once, 1 to 64 (2)",
    )  # fmt: skip
    p.set_defaults(func=_cmd_compile)
    return parser


def _cmd_compile(args) -> int:
    import time

    from .simulation.compilation import cache_dir
    from .simulation.precompile import precompile

    try:
        import numba  # noqa: F401
    except ImportError:
        # a request this installation cannot serve: exit status 2, one line
        raise ValueError(
            "the compiled engine needs numba: pip install 'fws-control[fast]'"
        ) from None
    print(f"compiling into {cache_dir() or 'no cache folder (none writable)'}")
    start = time.perf_counter()
    done = precompile(jobs=args.jobs)
    for item in done:
        print(f"  {item.name:<16} {item.cpu_seconds:7.1f} s CPU")
    total = sum(item.cpu_seconds for item in done)
    print(
        f"{total:.1f} s CPU in {time.perf_counter() - start:.1f} s "
        f"({args.jobs} worker{'s' if args.jobs > 1 else ''})"
    )
    return 0


def _add_design_parser(sub) -> None:
    p = sub.add_parser(
        "design",
        help="most-stable or robust gains for a delay and a steering lag",
        description="Gains for the delayed, lagged loop: 'most-stable' minimises "
        "the spectral abscissa at one speed (most_stable_gains, certified); "
        "'robust' maximises the worst-case decay over the speeds --speed LOW HIGH "
        "and the delays 0 to --delay (robust_gains). Prints a table (or JSON with "
        "--json) and, with --out, draws the chart of the design.",
    )
    p.add_argument(
        "--method", choices=("most-stable", "robust"), default="most-stable",
        help="most-stable (one speed) or robust (a speed interval) (most-stable)",
    )  # fmt: skip
    p.add_argument(
        "--speed", nargs="+", type=_finite, default=[20.0], metavar="V", dest="speeds",
        help="V [m/s]; robust: LOW HIGH (20)",
    )  # fmt: skip
    p.add_argument("--curvature", type=_finite, default=0.0, help="kappa [1/m] (0)")
    p.add_argument("--ratio", type=_finite, default=0.0, help="a (0)")
    p.add_argument(
        "--delay", type=_finite, default=0.24, help="input delay tau [s] (0.24)"
    )
    p.add_argument(
        "--steering-lag", type=_finite, default=0.27,
        help="first-order steering time constant [s], both axles (0.27)",
    )  # fmt: skip
    p.add_argument(
        "--grid", type=lambda t: _positive_int(t, low=4, high=40), default=10,
        help="start grid points per gain axis, 4 to 40 (10)",
    )  # fmt: skip
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument(
        "--out", type=Path, help="figure file of the chart: .png, .svg or .pdf (none)"
    )
    _add_vehicle(p)
    p.set_defaults(func=_cmd_design)


def _design_numbers(args) -> tuple[dict[str, Any], Callable[[], Any]]:
    """The design the arguments ask for, as a dict of plain numbers, and its plot."""
    import numpy as np

    from .plant import LateralPlant

    veh = _vehicle(args)
    if args.method == "most-stable":
        from .delay_design import most_stable_gains

        if len(args.speeds) != 1:
            raise ValueError(
                f"--speed takes one speed for most-stable, got {len(args.speeds)}"
            )
        plant = LateralPlant(
            veh, speed=args.speeds[0], curvature=args.curvature,
            steering_lag=args.steering_lag,
        )  # fmt: skip
        d = most_stable_gains(plant, delay=args.delay, ratio=args.ratio, grid=args.grid)
        out = {
            "method": "most-stable",
            "speed": args.speeds[0],
            "delay": d.delay,
            "k1": float(d.gains.k1),
            "k2": float(d.gains.k2),
            "ratio": float(d.gains.ratio),
            "abscissa": d.abscissa,
            "critical_delay": d.critical_delay,
            "certified": d.certified,
        }
        return out, d.plot
    from .robust import robust_gains

    if len(args.speeds) != 2 or not args.speeds[0] < args.speeds[1]:
        raise ValueError(
            f"--speed takes LOW HIGH (LOW < HIGH) for robust, got {args.speeds}"
        )
    box = {
        "speed": tuple(args.speeds),
        "delay": (0.0, args.delay),
        "steering_lag": args.steering_lag,
        "curvature": args.curvature,
    }
    # the start grid spans about twice the scaled most-stable gains of the
    # Autoware case (k1 V^2 = 0.62 m/s^2, k2 V = 2.2 m/s at 20 m/s) at the
    # slower speed, where the gains are largest (k1 ~ 1/V^2, k2 ~ 1/V)
    v = args.speeds[0]
    k1 = np.linspace(0.0, 1.5 / v**2, args.grid)
    k2 = np.linspace(0.0, 5.0 / v, args.grid)
    r = robust_gains(veh, ratio=args.ratio, box=box, k1=k1, k2=k2)
    out = {
        "method": "robust",
        "speed": list(args.speeds),
        "delay": [0.0, args.delay],
        "k1": float(r.gains.k1),
        "k2": float(r.gains.k2),
        "ratio": float(r.gains.ratio),
        "abscissa": r.abscissa,
        "worst": r.worst,
    }
    return out, r.region.plot


def _cmd_design(args) -> int:
    import json

    if args.out is not None:
        _check_out(args.out)
    out, plot = _design_numbers(args)
    if args.json:
        print(json.dumps(out))
    else:
        rows = [(k, v) for k, v in out.items() if k != "worst"]
        rows += [(f"worst {k}", v) for k, v in out.get("worst", {}).items()]
        for k, v in rows:
            text = f"{v:.6g}" if isinstance(v, float) else str(v)
            print(f"{k:>16}  {text}")
    if args.out is not None:
        import matplotlib.pyplot as plt

        fig = plot().figure
        _save_quiet(fig, args.out, args.json)
        plt.close(fig)
    return 0


def _save_quiet(fig, out: Path, quiet: bool) -> None:
    """Save the figure; with --json keep stdout to the JSON line."""
    if not quiet:
        _save(fig, out)
        return
    _write_figure(fig, out)


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
    from .gains import SteeringGains
    from .pole_placement import double_root_gains

    if (args.k1 is None) != (args.k2 is None):
        raise ValueError("give both --k1 and --k2, or neither (then --pole is used)")
    if args.k1 is not None:
        return SteeringGains(args.k1, args.k2, args.ratio)
    plant = _plant(args, veh)
    g = double_root_gains(plant, ratio=args.ratio, pole=args.pole)
    _check_design(plant, g, args.pole, args.model)
    return SteeringGains(float(g.k1), float(g.k2), args.ratio)


def _closed_loop_poles(plant, g, ratio: float):
    """Eigenvalues of A - b (k1 c_e + k2 c_theta), the closed_loop state matrix.

    Computed from the loop matrices, without building a control.StateSpace
    (python-control costs ~1 s of import that ``gains`` does not need).
    """
    import numpy as np

    from .plant import loop_matrices

    lm = loop_matrices(plant)
    k = float(g.k1) * lm.c_e + float(g.k2) * lm.c_theta
    with np.errstate(all="ignore"):
        a_cl = lm.A - np.outer(lm.input_vector(ratio), k)
    if not np.all(np.isfinite(a_cl)):
        return np.full(a_cl.shape[0], np.nan, dtype=complex)
    return np.linalg.eigvals(a_cl)


def _design_error(plant, g, pole: float) -> float:
    """Largest distance of the closed-loop poles from ``pole``, relative to it."""
    import numpy as np

    poles = np.asarray(_closed_loop_poles(plant, g, float(g.ratio)), dtype=complex)
    if not np.all(np.isfinite(poles)):
        return math.inf
    return float(np.max(np.abs(poles - pole)) / abs(pole))


def _check_design(plant, g, pole: float, model: str) -> None:
    """Refuse gains whose closed loop (in their own model) misses the double root.

    Near a = 1 on a straight road, for extreme magnitudes or a pole next to
    0 the design's linear system is so ill-conditioned that the gains place
    the poles somewhere else (even in the right half plane); printing or
    simulating them would be a silent wrong answer.
    """
    err = _design_error(plant, g, pole)
    if not err <= DESIGN_TOLERANCE:
        import numpy as np

        poles = np.sort_complex(_closed_loop_poles(plant, g, float(g.ratio)))
        where = ", ".join(
            f"{z.real:.4g}" if abs(z.imag) < 1e-9 else f"{z:.3g}" for z in poles
        )
        raise ValueError(
            f"no reliable {model}-model design for --pole {pole:g}: its poles are "
            f"{where} (off by {err:.2g} relative, limit {DESIGN_TOLERANCE:g}); "
            "ill-conditioned: a near 1 on a straight road, extreme values or a "
            "pole near 0"
        )


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


def _json_number(x: float) -> float | None:
    """`x`, or None where JSON has no number (NaN, infinity)."""
    return float(x) if math.isfinite(x) else None


def _roots_json(roots) -> list[list[float | None]]:
    """Complex roots sorted, as [re, im] pairs (JSON has no complex numbers)."""
    import numpy as np

    return [
        [_json_number(r.real), _json_number(r.imag)]
        for r in np.sort_complex(np.asarray(roots, dtype=complex))
    ]


def _gains_numbers(args) -> dict:
    """The gains command's designs as plain numbers (one entry per model)."""
    from .pole_placement import UncontrollableError, double_root_gains

    veh = _vehicle(args)
    # Design first so that bad input fails before anything is printed.
    plant = _plant(args, veh)
    _check_design(
        plant,
        double_root_gains(plant, ratio=args.ratio, pole=args.pole),
        args.pole,
        args.model,
    )
    out: dict = {
        "speed": args.speed,
        "curvature": args.curvature,
        "ratio": args.ratio,
        "pole": args.pole,
        "wheelbase": veh.wheelbase,
        "model": args.model,
        "designs": {},
    }
    order = [args.model] + [m for m in ("kinematic", "paper") if m != args.model]
    for model in order:
        try:
            g = double_root_gains(
                _plant(args, veh, model), ratio=args.ratio, pole=args.pole
            )
        except UncontrollableError as exc:
            if model == args.model:
                raise
            out["designs"][model] = {"error": f"no design ({exc})"}
            continue
        err = _design_error(_plant(args, veh, model), g, args.pole)
        if model != args.model and not err <= DESIGN_TOLERANCE:
            out["designs"][model] = {
                "error": "no reliable design (its poles miss lambda0 by "
                f"{err:.2g} relative)"
            }
            continue
        out["designs"][model] = {
            "k1": float(g.k1),
            "k2": float(g.k2),
            "k3": float(g.k3),
            "k4": float(g.k4),
            "poles": {
                lin: _roots_json(
                    _closed_loop_poles(_plant(args, veh, lin), g, args.ratio)
                )
                for lin in ("kinematic", "paper")
            },
        }
    return out


def _cmd_gains(args) -> int:
    import json

    out = _gains_numbers(args)
    if args.json:
        print(json.dumps(out))
        return 0
    print(
        f"V = {args.speed:g} m/s, kappa = {args.curvature:g} 1/m, a = {args.ratio:g}, "
        f"lambda0 = {args.pole:g} 1/s, f = {out['wheelbase']:g} m"
    )
    for model, d in out["designs"].items():
        if "error" in d:
            print(f"{model} model: {d['error']}")
            continue
        tag = "" if model == args.model else " (for comparison)"
        print(f"{model} model{tag}:")
        print(f"  k1 = {d['k1']:.6f} rad/m   k2 = {d['k2']:.6f}")
        print(f"  k3 = {d['k3']:.6f} rad/m   k4 = {d['k4']:.6f}")
        for lin, poles in d["poles"].items():
            nan = float("nan")
            roots = [complex(nan if x is None else x, y or 0.0) for x, y in poles]
            print(f"  closed-loop poles, {lin} linearisation: {_fmt_poles(roots)}")
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
        (k1_lo, k1_hi), (k2_lo, k2_hi) = args.k1_range, args.k2_range
        k1 = np.linspace(k1_lo, k1_hi, args.points)
        k2 = np.linspace(k2_lo, k2_hi, args.points)
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


#: The courses of ``simulate --path`` besides straight and arc: the
#: manoeuvres of :mod:`fws_control.manoeuvres` with their default geometry.
COURSES = ("lane-change", "obstacle", "slalom")


def _course(name: str) -> Manoeuvre:
    from .manoeuvres import double_lane_change, obstacle_avoidance, slalom

    courses: dict[str, Callable[[], Manoeuvre]] = {
        "lane-change": double_lane_change,
        "obstacle": obstacle_avoidance,
        "slalom": slalom,
    }
    return courses[name]()


def _simulate_course(args, veh, g):
    """The nonlinear run on a manoeuvre's course (no linear prediction there)."""
    from .plant import LateralPlant
    from .simulation import simulate

    course = _course(args.path)
    duration = (
        args.duration if args.duration is not None else course.path.length / args.speed
    )
    res = simulate(
        LateralPlant(veh, speed=args.speed, model=args.model),
        course.path,
        g,
        initial_state=(args.x0, args.y0, math.radians(args.psi0)),
        duration=duration,
        feedforward=not args.no_feedforward,
    )
    cplt = res.plot(title=f"{course.name}, V = {args.speed:g} m/s")
    course.draw_gates(cplt.axes.flat[2])
    hit = course.cones_hit(res.x, res.y, res.psi, wheelbase=veh.wheelbase)
    return res, cplt.figure, hit


def _cmd_simulate(args) -> int:
    import json

    import matplotlib.pyplot as plt
    import numpy as np

    from .linear_vs_nonlinear import compare_linear_nonlinear

    veh = _vehicle(args)
    course = args.path in COURSES
    if args.path != "arc" and args.curvature != 0.0 and args.k1 is None:
        # The design of a straight path or a course is made at zero curvature.
        args.curvature = 0.0
    if args.y0 is None:
        args.y0 = 0.0 if course else -5.0
    g = _gains(args, veh)
    cones = None
    if course:
        res, fig, cones = _simulate_course(args, veh, g)
    else:
        cmp = compare_linear_nonlinear(
            veh,
            g,
            speed=args.speed,
            curvature=args.curvature if args.path == "arc" else 0.0,
            initial_state=(args.x0, args.y0, math.radians(args.psi0)),
            duration=15.0 if args.duration is None else args.duration,
            feedforward=not args.no_feedforward,
            model=args.model,
        )
        res = cmp.nonlinear
        fig = cmp.plot().figure
    # a course ends where its path ends: the run's normal end there
    stopped = str(res.status) != "ok" and not (
        course and str(res.status) == "end_of_path"
    )
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
    _write_figure(fig, args.out)
    plt.close(fig)
    acc = np.abs(np.asarray(res.lateral_accel, dtype=float))
    peak = float(np.nanmax(acc)) if np.isfinite(acc).any() else None
    e = np.asarray(res.e, dtype=float)
    out = {
        "path": args.path,
        "speed": args.speed,
        "k1": float(g.k1),
        "k2": float(g.k2),
        "ratio": float(g.ratio),
        "status": str(res.status),
        "message": res.message or None,
        "t_stop": float(res.t_stop),
        "peak_lateral_accel": peak,
        "max_abs_e": _json_number(float(np.nanmax(np.abs(e)))),
        "final_e": _json_number(float(e[-1])),
        "final_theta_deg": _json_number(math.degrees(float(res.theta[-1]))),
        "cones_hit": cones,
        "out": str(args.out),
        "csv": None if args.csv is None else str(args.csv),
    }
    if args.csv is not None:
        _write_csv(
            res,
            args.csv,
            gains=g,
            speed=args.speed,
            curvature=args.curvature if args.path == "arc" else 0.0,
        )
    if args.json:
        print(json.dumps(out))
    else:
        print(f"wrote {args.out}")
        print(f"k1 = {out['k1']:.6f}, k2 = {out['k2']:.6f}, a = {out['ratio']:g}")
        print(f"status: {res.status}{(' - ' + res.message) if res.message else ''}")
        text = f"{peak:.4f} m/s^2" if peak is not None else "n/a (no valid sample)"
        print(f"peak |lateral acceleration| = {text}")
        if course:
            print(f"max |e| = {out['max_abs_e']:.4g} m, cones hit = {cones}")
        print(
            f"final e = {res.e[-1]:.4g} m, final theta = "
            f"{math.degrees(res.theta[-1]):.4g} deg"
        )
        if args.csv is not None:
            print(f"wrote {args.csv}")
    if stopped:
        _say(
            f"{PROG} simulate: run stopped at t = {float(res.t_stop):.3g} s "
            f"({res.status}); exit status {EXIT_STOPPED}"
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


def _write_csv(res, path: Path, *, gains, speed: float, curvature: float) -> None:
    """One row per sample; header ``name [unit]``; last column the status.

    After the signals come the run's own data, the same on every row, so
    that the file alone says what was run and how it ended: ``k1 [rad/m]``,
    ``k2 [-]``, ``ratio [-]``, ``speed [m/s]``, ``curvature [1/m]``,
    ``run_status`` (the run's final status), ``message`` (why it stopped,
    empty for ``ok``) and ``t_stop [s]`` (when it stopped; the last time if
    it ran to the end). The status column reads
    ``ok`` while the run is valid and the run's status (e.g.
    ``singular_steering``) from the stop on; samples after the stop are
    empty.
    """
    import csv

    import numpy as np

    from .files import atomic_write
    from .simulation import SIGNALS

    names = ("t", *SIGNALS)
    cols = []
    for n in names:
        v = np.asarray(getattr(res, n), dtype=float)
        cols.append(np.degrees(v) if _CSV_UNITS[n].startswith("deg") else v)
    t = cols[0]
    status = np.full(t.shape, "ok", dtype=object)
    run_status = str(res.status)
    if run_status != "ok":
        status[t >= float(res.t_stop) - 1e-12] = run_status
    run = {
        "k1 [rad/m]": float(gains.k1),
        "k2 [-]": float(gains.k2),
        "ratio [-]": float(gains.ratio),
        "speed [m/s]": float(speed),
        "curvature [1/m]": float(curvature),
    }
    constant = [f"{v:.10g}" for v in run.values()] + [
        run_status,
        " ".join(str(res.message or "").split()),
        f"{float(res.t_stop):.10g}",
    ]
    with atomic_write(path, mode="w") as fh:
        w = csv.writer(fh)
        w.writerow(
            [f"{n} [{_CSV_UNITS[n]}]" for n in names]
            + list(run)
            + ["run_status", "message", "t_stop [s]", "status"]
        )
        for i in range(t.size):
            w.writerow(
                ["" if not np.isfinite(c[i]) else f"{c[i]:.10g}" for c in cols]
                + constant
                + [status[i]]
            )


def _cmd_compare(args) -> int:
    from .manoeuvres import (
        constant_radius,
        double_lane_change,
        obstacle_avoidance,
        slalom,
    )
    from .plant import LateralPlant

    _check_out(args.out)
    if args.speed < COMPARE_MIN_SPEED:
        raise ValueError(
            f"--speed must be >= {COMPARE_MIN_SPEED:g} m/s, got {args.speed:g} (the "
            "manoeuvre lasts its length / speed; slower runs are beyond the budget: "
            "call fws_control.controller_comparison.compare from Python for them)"
        )
    lag = args.steering_lag
    if lag is not None and 0 < lag < COMPARE_MIN_STEERING_LAG:
        raise ValueError(
            f"--steering-lag must be >= {COMPARE_MIN_STEERING_LAG:g} s, got {lag:g} "
            "(a faster actuator makes the simulation stiff and slow, beyond the "
            "budget; for ideal steering leave --steering-lag out)"
        )
    course = {
        "iso3888-1": lambda: double_lane_change(vehicle_width=args.vehicle_width),
        "iso3888-2": lambda: obstacle_avoidance(vehicle_width=args.vehicle_width),
        "slalom": lambda: slalom(vehicle_width=args.vehicle_width),
        "circle": lambda: constant_radius(),
    }[args.manoeuvre]()
    if args.vehicle is None:
        if args.model == "dynamic":
            raise ValueError(
                "--model dynamic needs a vehicle with mass, yaw inertia and "
                "tyres: add --vehicle (one of "
                f"{', '.join(COMPARE_VEHICLES)})"
            )
        veh = _vehicle(args)
    else:
        from .vehicles import COMMONROAD_VEHICLES

        veh = COMMONROAD_VEHICLES[COMPARE_VEHICLES[args.vehicle]]
    if args.tyre != "linear" and args.model != "dynamic":
        raise ValueError(
            f"--tyre {args.tyre} applies only to --model dynamic (the kinematic "
            "model has no tyres)"
        )
    # imported once the arguments are checked: pyplot's import is not paid
    # for a mistyped option
    import matplotlib.pyplot as plt

    from .controller_comparison import compare, default_controllers

    ctrls = default_controllers(
        veh, speed=args.speed, ratio=args.ratio, pole=args.pole, delay=args.delay
    )
    if args.controllers:
        unknown = [c for c in args.controllers if c not in ctrls]
        if unknown:
            raise ValueError(
                f"--controllers must name controllers of {sorted(ctrls)}, got {unknown}"
            )
        ctrls = {name: ctrls[name] for name in args.controllers}
    plant = LateralPlant(
        veh,
        speed=args.speed,
        steering_lag=args.steering_lag,
        model=args.model,
        tyre=args.tyre,
    )
    cmp = compare(plant, course, ctrls, offset=args.offset, delay=args.delay)
    fig = cmp.draw()  # (plot()'s panels without python-control's import)
    _save(fig, args.out)
    plt.close(fig)
    lag = "none" if args.steering_lag is None else f"{args.steering_lag:g} s"
    model = f"{args.model} model"
    if args.model == "dynamic":
        model += f" ({args.tyre} tyre)"
    print(
        f"{course.name}, V = {args.speed:g} m/s, {model}, delay "
        f"{args.delay:g} s, steering lag {lag}, initial offset {args.offset:g} m"
    )
    print(cmp.to_markdown())
    return 0


def _delay_margin_numbers(args) -> dict:
    """The delay-margin command's results as plain numbers."""
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
    out = {
        "speed": args.speed,
        "curvature": args.curvature,
        "ratio": args.ratio,
        "k1": float(g.k1),
        "k2": float(g.k2),
        "design": "given gains" if args.k1 is not None else f"lambda0 = {args.pole:g}",
        "model": args.model,
        # LateralPlant holds the lag as a (front, rear) pair
        "steering_lag": None
        if plant.steering_lag is None
        else list(cast("tuple[float, float]", plant.steering_lag)),
        "stable_without_delay": bool(cd.stable_without_delay),
        # JSON has no infinity: null where no delay destabilises the loop
        "critical_delay": _json_number(float(cd.delay)),
        "frequency": _json_number(float(cd.frequency)),
    }
    if args.delay is not None:
        roots = rightmost_roots(plant, g, delay=args.delay, n=2)
        out["delay"] = args.delay
        out["stable_at_delay"] = bool(roots[0].real < 0)
        out["rightmost_roots"] = _roots_json(roots)
    return out


def _cmd_delay_margin(args) -> int:
    import json

    out = _delay_margin_numbers(args)
    if args.json:
        print(json.dumps(out))
        return 0
    print(
        f"V = {args.speed:g} m/s, kappa = {args.curvature:g} 1/m, a = {args.ratio:g}, "
        f"k1 = {out['k1']:.6f} rad/m, k2 = {out['k2']:.6f} ({out['design']}"
        f"{'' if args.k1 is not None else ' design'}, {args.model} model)"
    )
    if out["steering_lag"] is None:
        print("steering lag: none")
    else:
        tf_, tr = out["steering_lag"]
        print(f"steering lag: {tf_:g} s front, {tr:g} s rear")
    if not out["stable_without_delay"]:
        print("critical delay: 0 s (the loop is unstable without delay)")
    elif out["critical_delay"] is None:
        print("critical delay: inf (no delay destabilises the loop)")
    else:
        w = out["frequency"]
        print(
            f"critical delay: {out['critical_delay']:.6g} s (crossing at {w:.6g} "
            f"rad/s = {w / (2 * math.pi):.4g} Hz)"
        )
    if args.delay is not None:
        verdict = "stable" if out["stable_at_delay"] else "unstable"
        roots = [complex(x, y) for x, y in out["rightmost_roots"]]
        print(
            f"at delay {args.delay:g} s: {verdict}; rightmost roots {_fmt_poles(roots)}"
        )
    return 0


def _stderr_is_terminal() -> bool:
    try:
        return sys.stderr is not None and sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced or closed stream
        return False


def _cmd_reproduce(args) -> int:
    from .paper.figures import reproduce

    res = reproduce(
        args.out,
        model=args.model,
        quick=args.quick,
        # a progress bar is for a terminal: in a log file it is noise
        progress=not args.no_progress and _stderr_is_terminal(),
        dpi=args.dpi,
        names=args.only,
        format=args.format,
    )
    for p in res.figures:
        print(p)
    print(res.summary)
    return 0


#: The figure formats of --out, by file suffix: raster for screens and
#: slides, vector for papers (matplotlib writes all three without extras).
FIGURE_FORMATS = ("png", "svg", "pdf")


def _check_out(out: Path) -> str:
    """The figure format of `out` (its suffix), or ValueError."""
    suffix = Path(out).suffix.lower().lstrip(".")
    if suffix not in FIGURE_FORMATS:
        allowed = ", ".join(f".{f}" for f in FIGURE_FORMATS)
        raise ValueError(f"--out must be a {allowed} file, got {str(out)!r}")
    return suffix


def _write_figure(fig, out: Path) -> None:
    """Write `fig` atomically in the format of `out`'s suffix."""
    from .files import atomic_write

    fmt = _check_out(out)
    with atomic_write(Path(out)) as fh:
        fig.savefig(fh, format=fmt, dpi=110)


def _save(fig, out: Path) -> None:
    _write_figure(fig, out)
    print(f"wrote {out}")


def _warn_extreme(args) -> None:
    """One line on stderr per input far outside the model's useful range."""
    for name, limit, unit, why in _EXTREME:
        v = getattr(args, name, None)
        if v is not None and abs(v) > limit:
            u = f" {unit}" if unit else ""
            _say(
                f"{PROG} {args.command}: warning: --{name.replace('_', '-')} "
                f"{v:g}{u} is outside |{name}| <= {limit:g}{u} ({why}); "
                "results may be meaningless"
            )


def _short(value, limit: int = 60) -> str:
    """``repr`` of a value cut to ``limit`` characters."""
    import reprlib

    r = reprlib.Repr()
    r.maxstring = r.maxother = limit
    return r.repr(value)


def _bounded(message: object, limit: int = MAX_MESSAGE) -> str:
    """One line of at most about ``limit`` characters.

    A message that quotes a whole array would fill the terminal; keep its
    beginning (what is wrong) and its end (the valid range, what to do).
    """
    msg = " ".join(str(message).split())
    if len(msg) <= limit + 60:  # cutting a few characters would hide, not save
        return msg
    tail = limit // 4
    head = limit - tail
    return f"{msg[:head]} ... [{len(msg) - limit} characters] ... {msg[-tail:]}"


def _say(line: str) -> None:
    """Print one line on stderr; a closed or broken stderr is not an error."""
    stream = sys.stderr
    if stream is None:
        return
    try:
        stream.write(line + "\n")
        stream.flush()
    except (OSError, ValueError):
        pass


def _ensure_std_streams() -> None:
    """Give closed standard descriptors (``2>&-``) a /dev/null.

    Otherwise the next file opened (a PNG, the lock) would get descriptor 2
    and whatever writes to stderr, from Python or from C, would write into
    it.
    """
    for fd, name, mode in ((0, "stdin", "r"), (1, "stdout", "w"), (2, "stderr", "w")):
        try:
            os.fstat(fd)
        except OSError:
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:  # pragma: no cover - only if a lower fd is closed too
                os.dup2(null, fd)
                os.close(null)
        if getattr(sys, name) is None:
            setattr(sys, name, open(fd, mode, closefd=False))


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that clean-up code runs."""


@contextlib.contextmanager
def _signals_raise():
    """Turn SIGTERM and Ctrl-C into exceptions that cannot be lost.

    A signal handler's exception is raised in whatever Python code runs
    when the signal arrives. If that is a weak-reference callback or a
    ``__del__`` method (matplotlib runs many while a figure is drawn and
    closed), Python prints "Exception ignored" and carries on, and the
    signal would be lost: ``reproduce`` then finished with status 0. So the
    handler also records the signal; a swallowed exception is not printed
    but the signal delivered again from another thread a millisecond later
    (:func:`_thread.interrupt_main`), so that the handler runs again in the
    interrupted code; and leaving the block normally with a signal recorded
    raises it (:class:`_Terminated` for SIGTERM, ``KeyboardInterrupt`` for
    SIGINT). SIGINT is taken over only from Python's default handler, so
    an ignored SIGINT stays ignored.
    """
    import _thread
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return

    received: list[int] = []
    in_hook = [False]
    # A delivery still pending when the command ends must not reach the
    # caller's code (Python's own SIGINT handler is back by then): the
    # timer delivers only while the command runs, checked under a lock.
    active = [True]
    lock = threading.Lock()

    def exception_for(signum):
        return _Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()

    def deliver(signum):
        with lock:
            if active[0]:
                _thread.interrupt_main(signum)

    def deliver_later(signum):
        # from another thread, 1 ms later: by then the hook has returned and
        # the handler runs in the code the swallowing callback interrupted
        timer = threading.Timer(0.001, deliver, args=(signum,))
        timer.daemon = True
        timer.start()

    def handler(signum, frame):
        received.append(signum)
        if in_hook[0]:  # raising here would be swallowed once more
            deliver_later(signum)
            return
        raise exception_for(signum)

    old_hook = sys.unraisablehook

    def unraisable(info):
        if received and isinstance(info.exc_value, (_Terminated, KeyboardInterrupt)):
            # The handler ran inside a callback, which swallowed its
            # exception: deliver the signal again. No traceback printed.
            in_hook[0] = True
            try:
                deliver_later(received[-1])
            finally:
                in_hook[0] = False
            return
        old_hook(info)

    old = {signal.SIGTERM: signal.signal(signal.SIGTERM, handler)}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        old[signal.SIGINT] = signal.signal(signal.SIGINT, handler)
    sys.unraisablehook = unraisable
    try:
        yield
        if received:
            raise exception_for(received[0])
    finally:
        with lock:
            active[0] = False
        sys.unraisablehook = old_hook
        for signum, previous in old.items():
            signal.signal(signum, previous)


def _print_warnings(command: str, caught) -> None:
    """One line per distinct warning of a command that succeeded."""
    seen = set()
    for w in caught:
        key = (w.category, str(w.message))
        if key in seen:
            continue
        seen.add(key)
        _say(f"{PROG} {command}: warning: {_bounded(w.message)}")


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``fws-control``; returns the exit status.

    Errors in the input (ValueError, including UncontrollableError and
    SingularStateError, TypeError, OSError) end with one line on stderr and
    status 2, as do requests beyond the budgets of :data:`BUDGETS`, a
    ``MemoryError`` and an output folder in use; any other error ends with
    one line and status 1 (``--debug`` or ``FWS_CONTROL_DEBUG=1`` shows the
    traceback instead). ``simulate`` returns 3 (:data:`EXIT_STOPPED`) when
    the run stopped early; Ctrl-C returns 130 and ``SIGTERM`` 143, each with
    one line, leaving complete files only. Extreme but valid inputs print
    one warning line each; numerical warnings raised while a command works
    are printed one line each after it succeeds and dropped when it fails
    (its error line says what went wrong).

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        The exit status.

    Examples
    --------
    >>> from fws_control.cli import main
    >>> main(["gains", "--speed", "5", "--curvature", "0", "--ratio", "-1",
    ...       "--pole", "-1e0"])  # doctest: +ELLIPSIS
    V = 5 m/s, kappa = 0 1/m, a = -1, lambda0 = -1 1/s, f = 2.7 m
    kinematic model:
    ...
    0
    """
    _ensure_std_streams()
    argv = sys.argv[1:] if argv is None else [str(a) for a in argv]
    debug = os.environ.get(DEBUG_ENV, "") not in ("", "0")
    where = PROG
    try:
        # SIGTERM and Ctrl-C end in one line from here on, even while the
        # libraries are still being imported.
        with _signals_raise():
            import logging

            # Agg for every figure, without importing matplotlib here (0.2 s
            # that --help and gains do not need): through the environment
            # until it is imported.
            if "matplotlib" in sys.modules:
                sys.modules["matplotlib"].use("Agg")
            else:
                os.environ["MPLBACKEND"] = "Agg"
            # Equal-aspect root-locus axes make matplotlib log "Ignoring
            # fixed x limits ..." at every save; noise for a command line.
            logging.getLogger("matplotlib").setLevel(logging.ERROR)
            args = build_parser().parse_args(_protect_negative_numbers(argv))
            debug = debug or args.debug
            where = f"{PROG} {args.command}"
            _warn_extreme(args)
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("default")
                status = int(args.func(args) or 0)
        _print_warnings(args.command, caught)
        return status
    except BrokenPipeError:
        # Output piped into e.g. `head`, which closed early: not an error.
        # Point stdout at devnull so the interpreter's final flush is silent.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        _say(f"{where}: interrupted; files already written are complete")
        return 130
    except _Terminated:
        _say(f"{where}: terminated; files already written are complete")
        return 143
    except MemoryError:
        if debug:
            raise
        _say(
            f"{where}: error: out of memory; ask for less (--points, --duration, "
            "--dpi, --range) and see --help for the budgets"
        )
        return 2
    except (ValueError, TypeError, OSError, ArithmeticError) as exc:
        if debug:
            raise
        _say(f"{where}: error: {_bounded(exc)}")
        return 2
    except Exception as exc:
        if debug:
            raise
        _say(
            f"{where}: internal error: {type(exc).__name__}: "
            f"{_bounded(exc, MAX_MESSAGE - 60)} (--debug shows the traceback)"
        )
        return 1


def run() -> None:
    """The ``fws-control`` console script: :func:`main`, then exit with its status.

    Before the interpreter exits, everything still alive is frozen
    (:func:`gc.freeze`), so that the interpreter's last garbage collection
    does not traverse the hundreds of thousands of objects of python-control,
    scipy and matplotlib only to free memory the operating system reclaims
    at exit anyway: 0.6-0.7 s of CPU after ``reproduce`` (the whole
    process 7.46 s with that last collection, 6.63 s without, measured with
    ``benchmarks/bench_startup.py --baseline``).
    Modules are still torn down and ``atexit`` handlers still run; every
    file is closed by then (the commands write through context managers).
    Library code and tests call :func:`main`, which leaves the collector
    alone.

    Examples
    --------
    >>> import subprocess, sys
    >>> subprocess.run([sys.executable, "-c", "from fws_control.cli import run; "
    ...                 "import sys; sys.argv = ['fws-control', '--version']; run()"],
    ...                capture_output=True, text=True).returncode
    0
    """
    status = main()
    gc.freeze()
    sys.exit(status)


if __name__ == "__main__":  # pragma: no cover
    run()
