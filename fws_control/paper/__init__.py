"""The paper's own material: its vehicle, scenarios, figures and ``reproduce``.

Lim, Vörös, Lim, Orosz, *The effects of four-wheel steering on the
path-tracking control of automated vehicles*. Nothing in :mod:`fws_control`
imports this subpackage (only the CLI does); import it explicitly::

    import fws_control.paper as paper
    paper.reproduce("figures")

Modules: :mod:`~fws_control.paper.data` (the paper's numbers, defined once),
:mod:`~fws_control.paper.scenarios` (the simulation set-ups of sections 4.3
and 5 as data), :mod:`~fws_control.paper.charts` (Figs. 2-4) and
:mod:`~fws_control.paper.figures` (every figure, the gains table and
:func:`reproduce`).
"""

from . import scenarios
from .actuator import delay_margin_table, plot_actuator
from .charts import ChartPanel, paper_figure_panels, plot_paper_figure
from .data import (
    ACTUATOR_SOURCE,
    FIG5_POLES,
    FIG5_RATIOS,
    FIG6_TO_9_RATIOS,
    PAPER_CURVATURES,
    PAPER_CURVED,
    PAPER_SPEEDS,
    PAPER_VEHICLE,
    REALISTIC_DELAY,
    REALISTIC_STEERING_LAG,
    TABLE_RATIOS,
)
from .figures import FIGURES, gains_table, make_figure, reproduce

__all__ = [
    "scenarios",
    "ChartPanel",
    "paper_figure_panels",
    "plot_paper_figure",
    "FIGURES",
    "gains_table",
    "make_figure",
    "reproduce",
    "PAPER_VEHICLE",
    "PAPER_SPEEDS",
    "PAPER_CURVED",
    "PAPER_CURVATURES",
    "FIG5_RATIOS",
    "FIG5_POLES",
    "FIG6_TO_9_RATIOS",
    "TABLE_RATIOS",
    "REALISTIC_DELAY",
    "REALISTIC_STEERING_LAG",
    "ACTUATOR_SOURCE",
    "delay_margin_table",
    "plot_actuator",
]
