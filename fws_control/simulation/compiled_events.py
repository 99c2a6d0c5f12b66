"""The compiled engine's event functions: the stops and the clips' switches.

Events 0-3 stop a run (the singular steering angle, the singular curvature,
the ends of an open path), events 4-7 switch a steering clip between free
and held; an event fires where its function falls to 0 or below
(:mod:`~fws_control.simulation.compiled` locates it on the dense output).
"""

from __future__ import annotations

import math

import numpy as np

from .compilation import jit
from .compiled_layout import (
    N_EVENTS,
    N_STOPS,
    NP,
    P_MODE,
    P_NOW,
    P_RELEASED,
    Q_CURV_MARGIN,
    Q_DELAY,
    Q_OPEN_LENGTH,
    Q_STEER_MARGIN,
    Q_SWITCH,
    Q_TAU,
    WITH_DELAY,
    WITH_PROFILE,
    clip_switch_margin,
    jit_inline,
)
from .compiled_loop import (
    clip_values,
    clipped_command,
    curvature_at,
    follow_speed,
    measured_state,
)
from .compiled_speed import (
    P_SPEED_TIME,
    Q_PROFILE,
)

# The names here are shared by the compiled_* modules; the public API of
# the compiled engine is simulation.compiled (which re-exports them).
__all__: list[str] = []


@jit_inline
def set_now(t, p, q):
    # the time of the state the events are next evaluated on (a delay's
    # applied angle depends on it; see P_NOW)
    if WITH_DELAY and q[Q_DELAY] > 0.0:
        p[P_NOW] = t
    if WITH_PROFILE and q[Q_PROFILE] != 0.0:
        p[P_SPEED_TIME] = t


@jit
def stop_event_values(y, p, q, breaks, coefs, g):
    """The stop events 0-3 of :func:`event_values` (into ``g[:4]``)."""
    s, e = y[0], y[1]
    if WITH_PROFILE and q[Q_PROFILE] != 0.0:
        follow_speed(p[P_SPEED_TIME], s, p, q, breaks, coefs)
    kappa = curvature_at(s, q, breaks, coefs)
    if q[Q_TAU] > 0.0:
        df = y[3]
    elif WITH_DELAY and q[Q_DELAY] > 0.0:
        # the applied angle: the law on the measurements of t - delay, for
        # the time the caller set in p[P_NOW]
        s_m, e_m, th_m = measured_state(p[P_NOW], y, p, q)
        kappa_m = curvature_at(s_m, q, breaks, coefs)
        df = clipped_command(s_m, e_m, th_m, kappa_m, p, q, breaks, coefs)[0]
    else:
        df = clipped_command(s, e, y[2], kappa, p, q, breaks, coefs)[0]
    g[0] = (0.5 * math.pi - q[Q_STEER_MARGIN]) - abs(df)
    g[1] = (1.0 - kappa * e) - q[Q_CURV_MARGIN]
    L = q[Q_OPEN_LENGTH]
    if L < np.inf:
        # the offset lets a run start exactly at s = 0 (or at the end)
        g[2] = (L - s) / L + 1e-9
        g[3] = s / L + 1e-9
    else:
        g[2] = np.inf
        g[3] = np.inf


@jit
def event_values(y, p, q, breaks, coefs, g):
    """Event functions: 0-3 stop a run, 4-7 switch a clip's mode (at <= 0).

    A clip released from its limit at the start of the step (``p[8 + j]``,
    with ``p`` of 12 entries) is at that limit there: it can only move away
    from it, so only the opposite limit switches it in that step. With
    ``|raw|`` against the limit, the released clip would start the step on
    the wrong side by the rounding of the located switch and be switched
    back at once, for ever, when the step crosses to the opposite limit.
    """
    stop_event_values(y, p, q, breaks, coefs, g)
    if q[Q_SWITCH] == 0.0:
        for j in range(N_STOPS, N_EVENTS):
            g[j] = np.inf
        return
    # clip j: free (mode 0) while |raw| < limit, held while mode * raw > limit
    v = np.empty(8)
    clip_values(y, p, q, breaks, coefs, v)
    released = p.size >= NP
    for j in range(4):
        side = p[P_RELEASED + j] if released else 0.0
        g[N_STOPS + j] = clip_switch_margin(v[j], v[4 + j], p[P_MODE + j], side)
