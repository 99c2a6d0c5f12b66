r"""The paper's designs under a realistic steering actuator.

The paper's controller acts at once on an ideal steering. A production
lateral controller sees an input delay and a steering lag: Autoware's MPC
lateral controller ships :data:`~fws_control.paper.data.REALISTIC_DELAY`
= 0.24 s and :data:`~fws_control.paper.data.REALISTIC_STEERING_LAG` =
0.27 s (:data:`~fws_control.paper.data.ACTUATOR_SOURCE`). This module
computes the delay margin (:func:`~fws_control.critical_delay`) of the
double-root designs the paper uses, with and without that lag, and draws the
responses of Fig. 9's scenario with delay and lag.

For the kinematic plant the delayed characteristic function of a
double-root design is
:math:`D(s) = s^2 + V^2\kappa^2 + e^{-s\tau}(-2\lambda_0 s + \lambda_0^2 -
V^2\kappa^2)`: it depends on :math:`\lambda_0` and :math:`V\kappa` only, not
on the ratio ``a`` or the model, so the margin is the same for every ``a``
(with equal lags on both axles the lag does not bring ``a`` back either).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import control as ct
import numpy as np

from ..charts import delay_margin_chart
from ..gains import SteeringGains
from ..hints import ModelName
from ..layout import grid_margins
from ..plant import LateralPlant
from ..vehicle import Vehicle
from .data import (
    PAPER_CURVED,
    PAPER_SPEEDS,
    PAPER_VEHICLE,
    REALISTIC_DELAY,
    REALISTIC_STEERING_LAG,
)

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["PAPER_POLES", "delay_margin_table", "plot_actuator"]

# Solver tolerances of the response panels (b), (c): see plot_actuator.
_PLOT_RTOL = 1e-8
_PLOT_ATOL = 1e-10

#: The double roots the paper uses (Fig. 5: -1, -2 at 5 m/s; -1, -2, -3 at
#: 20 m/s; Figs. 6-9: -1).
PAPER_POLES = (-1.0, -2.0, -3.0)


def delay_margin_table(
    *,
    vehicle: Vehicle | None = None,
    poles: Sequence[float] = PAPER_POLES,
    delay: float = REALISTIC_DELAY,
    steering_lag: float = REALISTIC_STEERING_LAG,
) -> str:
    r"""Markdown table: critical delay of the paper's designs, with and without lag.

    For each speed and curvature of the paper's scenarios and each double
    root :math:`\lambda_0`: the critical delay on the ideal steering, the
    critical delay with a first-order steering lag, and whether the design
    survives `delay` with that lag (its critical delay exceeds `delay`). The
    ratio does not matter (see the module docstring); ``a = 0`` is used.

    Parameters
    ----------
    vehicle : Vehicle, optional
        Default the paper's vehicle.
    poles : sequence of float, optional
        Double roots [1/s].
    delay : float, optional
        Loop delay to survive [s].
    steering_lag : float, optional
        Steering time constant [s] on both axles.

    Returns
    -------
    str

    Examples
    --------
    >>> from fws_control.paper.actuator import delay_margin_table
    >>> print(delay_margin_table(poles=[-1.0]).splitlines()[2])
    | 5 | 0 | -1 | 0.6474 | 0.4552 | yes |
    """
    vehicle = PAPER_VEHICLE if vehicle is None else vehicle
    head = (
        f"| V [m/s] | kappa [1/m] | lambda0 [1/s] | critical delay [s] | critical "
        f"delay with a {steering_lag:g} s lag [s] | survives {delay:g} s + lag |"
        "\n|---|---|---|---|---|---|"
    )
    rows = [head]
    for V in PAPER_SPEEDS:
        for kap in (0.0, PAPER_CURVED[V]):
            design = LateralPlant(vehicle, speed=V, curvature=kap)
            lagged = LateralPlant(
                vehicle, speed=V, curvature=kap, steering_lag=steering_lag
            )
            ideal = delay_margin_chart(design, ratio=0.0, pole=poles).delay[0]
            real = delay_margin_chart(
                lagged, ratio=0.0, pole=poles, design_plant=design
            ).delay[0]
            for lam, t0, t1 in zip(poles, ideal, real, strict=True):
                ok = "yes" if t1 > delay else "no"
                rows.append(
                    f"| {V:g} | {kap:g} | {lam:g} | {t0:.4f} | {t1:.4f} | {ok} |"
                )
    return "\n".join(rows)


def plot_actuator(
    *,
    model: ModelName = "kinematic",
    quick: bool = False,
    delay: float = REALISTIC_DELAY,
    steering_lag: float = REALISTIC_STEERING_LAG,
    ax: Sequence[Axes] | np.ndarray | None = None,
) -> ct.ControlPlot:
    r"""The paper's designs with an input delay and a steering lag (extra figure).

    (a) Critical delay of the double-root designs against :math:`\lambda_0`
    on a straight road (the same at 5 and 20 m/s and for every ``a``), with
    the ideal steering and with the lag; the horizontal line is `delay`.
    (b), (c) Lateral error in Fig. 9's scenario (curve 1/100 at 20 m/s, R(0)
    = (0, -10 m)) for :math:`\lambda_0 = -1` and -2, ``a = 0.5``: ideal
    steering (dashed) against delay and lag (solid).

    Parameters
    ----------
    model : {"kinematic", "paper"}, optional
        Linearisation of the designs.
    quick : bool, optional
        Shorter simulations and fewer poles (for tests).
    delay : float, optional
        Input delay [s] of the realistic loop.
    steering_lag : float, optional
        Steering time constant [s].
    ax : sequence of 3 matplotlib.axes.Axes, optional
        Axes of the panels; a new figure if None.

    Returns
    -------
    control.ControlPlot

    Examples
    --------
    >>> import matplotlib; matplotlib.use("Agg")
    >>> import matplotlib.pyplot as plt
    >>> from fws_control.paper.actuator import plot_actuator
    >>> cplt = plot_actuator(quick=True)
    >>> cplt.axes.shape
    (1, 3)
    >>> plt.close(cplt.figure)
    """
    import matplotlib.pyplot as plt

    from ..simulation import simulate_batch
    from .scenarios import paper_scenario, scenario_gains

    if ax is None:
        size = (16, 4.8)
        fig, axes = plt.subplots(
            1,
            3,
            figsize=size,
            gridspec_kw=grid_margins(size, ncols=3, left=0.65, top=0.95),
        )
    else:
        axes = list(np.asarray(ax, dtype=object).ravel())
        if len(axes) != 3:
            raise ValueError(f"ax must hold 3 axes, got {len(axes)}")
        fig = axes[0].figure
    poles = np.linspace(-4.0, -0.25, 16 if quick else 76)
    design = LateralPlant(PAPER_VEHICLE, speed=20.0, model=model)
    lagged = LateralPlant(
        PAPER_VEHICLE, speed=20.0, model=model, steering_lag=steering_lag
    )
    a0 = axes[0]
    ideal = delay_margin_chart(design, ratio=0.0, pole=poles).delay[0]
    real = delay_margin_chart(lagged, ratio=0.0, pole=poles, design_plant=design)
    a0.plot(poles, ideal, "-", color="C0", label="ideal steering")
    a0.plot(poles, real.delay[0], "-", color="C3", label=f"{steering_lag:g} s lag")
    a0.axhline(delay, color="k", ls="--", lw=1.0, label=f"delay {delay:g} s")
    a0.fill_between(poles, 0.0, real.delay[0], color="C3", alpha=0.1)
    a0.set_xlabel(r"double root $\lambda_0$ [1/s]")
    a0.set_ylabel("critical delay [s]")
    a0.set_ylim(0.0, 1.2 * float(np.max(ideal[poles <= -0.5])))
    a0.set_title(
        "(a) delay margin of the double-root designs\n(every a, straight road; "
        "stable below the curve)",
        fontsize=10,
    )
    a0.grid(alpha=0.3)
    a0.legend(fontsize=8)
    duration = 10.0 if quick else 30.0
    sc = paper_scenario("curve_20")
    lams = np.array([-1.0, -2.0])
    k1, k2, _ = scenario_gains(sc, 0.5, lams, model)  # a = 0.5: always a design
    gains = SteeringGains(k1, k2, np.full(lams.size, 0.5))
    # Both double roots in one batch per actuator; the runs differ only in
    # their gains. Tolerances: the panels show e on a +-15 m axis (about
    # 0.07 m per pixel), and rtol = 1e-8 puts the curves within 1e-6 m of
    # the default 1e-10 (tests/test_figures.py) at half the cost of the
    # delayed runs, the dearest of reproduce after Fig. 5.
    runs = {
        act: simulate_batch(
            LateralPlant(PAPER_VEHICLE, speed=sc.speed,
                         steering_lag=steering_lag if act else None),
            sc.path, gains,
            initial_state=sc.initial_state, duration=duration,
            delay=delay if act else 0.0,
            feedforward=sc.feedforward, dt=0.02, progress=False,
            rtol=_PLOT_RTOL, atol=_PLOT_ATOL,
        )
        for act in (False, True)
    }  # fmt: skip
    for i, (ax_i, lam, letter) in enumerate(
        ((axes[1], lams[0], "b"), (axes[2], lams[1], "c"))
    ):
        for act, style in ((False, "--"), (True, "-")):
            r = runs[act]
            label = (
                f"delay {delay:g} s + lag {steering_lag:g} s"
                if act
                else "ideal steering"
            )
            if r.status[i] != "ok":
                label += f" ({r.status[i]} at {np.asarray(r.t_stop)[i]:.3g} s)"
            ax_i.plot(r.t, r.e[i], style, color="C3" if act else "C0", label=label)
        ax_i.set_xlabel("time t [s]")
        ax_i.set_ylabel("lateral error e [m]")
        ax_i.set_ylim(-15.0, 15.0)
        ax_i.grid(alpha=0.3)
        ax_i.legend(fontsize=8, loc="upper right")
        ax_i.set_title(
            f"({letter}) curve 1/100 at 20 m/s, a = 0.5, "
            rf"$\lambda_0$ = {lam:g} 1/s" + "\n" + f"(critical delay with lag: "
            f"{_margin(lagged, design, lam):.3f} s)",
            fontsize=10,
        )
    fig.suptitle(
        "The paper's designs with an input delay and a steering lag "
        "(Autoware's MPC defaults)",
        fontsize=12,
    )
    lines = np.empty((1, 3), dtype=object)
    for i, a in enumerate(axes):
        lines[0, i] = list(a.get_lines())
    return ct.ControlPlot(lines, np.array([list(axes)], dtype=object), fig)


def _margin(plant, design, pole) -> float:
    d = delay_margin_chart(plant, ratio=0.0, pole=pole, design_plant=design)
    v = float(d.delay[0, 0])
    return v if math.isfinite(v) else math.inf
