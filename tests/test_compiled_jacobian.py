"""The compiled closed loop's analytic Jacobian against finite differences.

:func:`~fws_control.simulation.compiled.closed_loop_jac` (for an implicit
method's Newton iteration) is checked against central differences of the
right-hand side written here from the formulas (``reference_rhs`` of
``tests/test_compiled_engine.py``: eqs. 17-19 with the paper's law and the
first-order actuator), not of the compiled one.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fws_control as fws

numba = pytest.importorskip(
    "numba", reason="numba is not installed: the compiled engine (extra 'fast') "
    "is not tested"
)  # fmt: skip

from test_compiled_engine import reference_rhs  # noqa: E402

from fws_control.simulation.compiled import (  # noqa: E402
    closed_loop_jac,
    curvature_table,
    shared_parameters,
)
from fws_control.simulation.compiled_variants import variant  # noqa: E402

# The Jacobian as the engine compiles it for a call without a delay, the
# dynamic model, a controller's law or a varying speed (these tests use
# none; the Radau driver runs only such calls): the code that runs, and a
# third of the full kernel's compilation.
closed_loop_jac = variant(closed_loop_jac, ())


def _central_difference(f, y, h=1e-6):
    n = y.size
    J = np.empty((n, n))
    for j in range(n):
        d = np.zeros(n)
        d[j] = h * max(1.0, abs(y[j]))
        J[:, j] = (f(0.0, y + d) - f(0.0, y - d)) / (2 * d[j])
    return J


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    e=st.floats(-3, 3),
    th=st.floats(-1, 1),
    s=st.floats(1, 49),
    df=st.floats(-1.2, 1.2),
    dr=st.floats(-0.5, 0.5),
    k1=st.floats(0.0, 2.0),
    k2=st.floats(0.0, 3.0),
    a=st.floats(-2, 2),
    act=st.booleans(),
    limited=st.booleans(),
)
def test_jacobian_matches_finite_differences(e, th, s, df, dr, k1, k2, a, act,
                                             limited):  # fmt: skip
    lim = dict(max_steer_front=0.6, max_steer_rear=0.3, max_steer_rate_front=0.4,
               max_steer_rate_rear=0.2) if limited else {}  # fmt: skip
    veh = fws.Vehicle(2.7, 1.35, **lim)
    # a clothoid: curvature linear in s (0.02 -> -0.08 over 50 m), so the
    # feedforward and 1/(1 - kappa e) depend on s
    path = fws.Clothoid(0.02, -0.08, length=50.0)
    tau = 0.05 if act else None
    V = 7.0
    rhs, _, _ = reference_rhs(veh, lambda s: 0.02 - 0.1 * s / 50, k1, k2, a, V, tau=tau)
    y = np.array([s, e, th, df, dr][: 5 if act else 3])
    # (|kappa e| <= 0.24 here: far from the singularity 1 - kappa e = 0)
    tab = curvature_table(path)
    q = shared_parameters(veh, tab, feedforward=True, time_constant=tau)
    J = np.empty((y.size, y.size))
    closed_loop_jac(0.0, y, np.array([V, k1, k2, a, 0, 0, 0, 0.0]), q, tab.breaks,
                    tab.coefs, J)  # fmt: skip
    ref = _central_difference(rhs, y)
    if limited:
        # a clip's kink within the difference step: no derivative there
        ref2 = _central_difference(rhs, y, h=1e-7)
        if not np.allclose(ref, ref2, rtol=1e-5, atol=1e-5):
            return
    scale = np.max(np.abs(ref)) + 1.0
    np.testing.assert_allclose(J, ref, rtol=1e-6, atol=1e-6 * scale)


def test_jacobian_of_switched_modes_holds_the_clipped_channels():
    # With the clips as switched modes (q[13] = 1), a channel held at its
    # limit does not depend on the state: its row (rate mode) or its
    # command's columns (angle mode) vanish. Reference: the Jacobian without
    # modes, those entries set to 0 by hand.
    veh = fws.Vehicle(2.7, 1.35, max_steer_front=0.6, max_steer_rear=0.3,
                      max_steer_rate_front=0.4, max_steer_rate_rear=0.2)  # fmt: skip
    tab = curvature_table(fws.Clothoid(0.02, -0.08, length=50.0))
    q = shared_parameters(veh, tab, feedforward=True, time_constant=0.05,
                          switching=True)  # fmt: skip
    y = np.array([10.0, 0.01, 0.001, 0.0, 0.0])
    free = np.empty((5, 5))
    closed_loop_jac(0.0, y, np.array([7.0, 1.0, 2.0, -0.5, 0, 0, 0, 0.0]), q,
                    tab.breaks, tab.coefs, free)  # fmt: skip
    assert free[3, 1] == pytest.approx(-1.0 / 0.05) and free[4, 2] == pytest.approx(
        0.5 * 2.0 / 0.05
    )
    held = np.empty((5, 5))
    closed_loop_jac(0.0, y, np.array([7.0, 1.0, 2.0, -0.5, 1, 0, 0, -1.0]), q,
                    tab.breaks, tab.coefs, held)  # fmt: skip
    expect = free.copy()
    expect[3, :3] = 0.0  # front angle held: cf constant, rf = (mf - df)/T
    expect[4, :] = 0.0  # rear rate held: dr' = -r
    np.testing.assert_array_equal(held, expect)
