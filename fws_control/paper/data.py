"""The paper's numbers, defined once: vehicle, speeds, curvatures, ratios.

Lim, Vörös, Lim, Orosz, *The effects of four-wheel steering on the
path-tracking control of automated vehicles*, section 4.3.
"""

from __future__ import annotations

import numpy as np

from ..vehicle import Vehicle

__all__ = [
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
]

#: The paper's vehicle: wheelbase f = 2.7 m, rear axle to CG d = 1.35 m.
PAPER_VEHICLE = Vehicle(wheelbase=2.7, rear_to_cg=1.35)

#: The two speeds of the paper's study [m/s].
PAPER_SPEEDS = (5.0, 20.0)

#: Curvature of the curved-road scenario at each speed [1/m].
PAPER_CURVED = {5.0: 0.1, 20.0: 0.01}

#: Curvatures [1/m] overlaid in each panel of Figs. 3 (V = 5) and 4 (V = 20).
#: The paper does not list them; these are this library's choice and include
#: the curvatures of the simulations (0.1 and 0.01 1/m).
PAPER_CURVATURES = {3: (0.0, 0.05, 0.1, 0.2), 4: (0.0, 0.01, 0.02, 0.05)}

#: Ratios of Fig. 5: a in [-1.5, 1.5] in steps of 0.05 (includes 0 and 1).
FIG5_RATIOS = np.round(np.linspace(-1.5, 1.5, 61), 12)

#: Default double roots of Fig. 5 per speed [1/s].
FIG5_POLES: dict[float, tuple[float, ...]] = {
    5.0: (-1.0, -2.0),
    20.0: (-1.0, -2.0, -3.0),
}

#: Ratios of Figs. 6-9.
FIG6_TO_9_RATIOS = (-1.0, -0.5, 0.0, 0.5, 1.0)

#: Ratios of the charts (Figs. 3-4) and of the gains table.
TABLE_RATIOS = (-1.5, -1.0, -0.5, 0.0, 0.5, 1.0, 1.5)

#: A production lateral controller's input delay on the steering command [s]:
#: Autoware's MPC lateral controller default ``input_delay``.
REALISTIC_DELAY = 0.24

#: Its first-order steering time constant [s] (``vehicle_model_steer_tau``).
REALISTIC_STEERING_LAG = 0.27

#: Where the two values come from.
ACTUATOR_SOURCE = (
    "Autoware Universe, control/autoware_mpc_lateral_controller/param/"
    "lateral_controller_defaults.param.yaml: input_delay: 0.24 (steering input "
    "delay time), vehicle_model_steer_tau: 0.27 (steering dynamics time "
    "constant, 1st-order approximation)"
)
