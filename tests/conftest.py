"""Shared fixtures and the hypothesis profile (fixed seed: derandomized)."""

import os

import matplotlib
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, settings

import fws_control as fws
from fws_control import symbolic as S

matplotlib.use("Agg")

settings.register_profile(
    "fws",
    derandomize=True,
    deadline=None,
    max_examples=int(os.environ.get("FWS_HYPOTHESIS_EXAMPLES", "200")),
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
settings.load_profile("fws")

PAPER_VEHICLE = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)


@pytest.fixture
def veh():
    """The paper's vehicle: f = 2.7 m, d = 1.35 m."""
    return PAPER_VEHICLE


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)


_ARGS = [
    S.SYMBOLS[n]
    for n in ("speed", "wheelbase", "curvature", "ratio", "k1", "k2", "pole")
]


def lambdify(expr):
    """Numeric function of (V, f, kappa, a, k1, k2, lam0) from a sympy expr."""
    return sp.lambdify(_ARGS, expr, modules="numpy")
