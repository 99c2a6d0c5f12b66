"""Tests of fws_control.paths against independent references.

References: hand-derived geometry, finite differences (position -> heading ->
curvature -> curvature rate), Fresnel integrals and scipy quadrature for the
clothoid, dense polyline/quadrature arc length for the spline, and a
brute-force nearest point (dense sampling + bounded Brent refinement that
uses only ``path.position``) for projections.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar
from scipy.special import fresnel

from fws_control.paths import (
    AmbiguousProjectionError,
    Arc,
    Clothoid,
    Path,
    PathChain,
    Projection,
    Spline,
    Straight,
)

FAST = settings(max_examples=25, derandomize=True, deadline=None)

# An open, wiggly course and a closed, kidney-shaped one.
OPEN_WP = np.array(
    [[0.0, 0.0], [10.0, 3.0], [20.0, -2.0], [30.0, 5.0], [35.0, 15.0], [25.0, 25.0]]
)
CLOSED_WP = np.array(
    [
        [0.0, 0.0],
        [15.0, -3.0],
        [30.0, 2.0],
        [35.0, 15.0],
        [25.0, 25.0],
        [12.0, 18.0],
        [3.0, 22.0],
        [-6.0, 12.0],
        [0.0, 0.0],
    ]
)


def make_paths() -> dict[str, Path]:
    return {
        "clothoid": Clothoid(0.05, -0.2, 40.0, start=(1.0, 2.0), start_heading=0.3),
        "spline_open": Spline(OPEN_WP),
        "spline_closed": Spline(CLOSED_WP),
        "chain": PathChain(
            [
                Straight(length=20.0),
                Clothoid(0.0, 0.1, 10.0),
                Arc(0.1, length=20.0),
                Spline([[0.0, 0.0], [5.0, 2.0], [10.0, 0.0], [15.0, -3.0]]),
            ]
        ),
        "arc_segment": Arc(-0.1, length=25.0, start=(3.0, -1.0), start_heading=1.0),
    }


PATHS = make_paths()


def assert_close(actual, desired, atol=0.0, rtol=1e-12):
    """assert_allclose with a tight default rtol (numpy's 1e-7 hides errors)."""
    np.testing.assert_allclose(actual, desired, rtol=rtol, atol=atol)


def wrap(a):
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2 * np.pi)


def central(f, s, h):
    return (np.asarray(f(s + h)) - np.asarray(f(s - h))) / (2 * h)


_DENSE: dict[int, tuple] = {}


def reference_nearest(path: Path, px, py, n: int = 20001):
    """Brute force: dense samples, then bounded Brent around the best one."""
    if id(path) not in _DENSE:
        s = np.linspace(0.0, path.length, n)
        _DENSE[id(path)] = (path, s, *path.position(s))
    _, s, X, Y = _DENSE[id(path)]
    s_out, d_out = [], []
    for x, y in zip(np.ravel(px), np.ravel(py), strict=True):
        d = np.hypot(X - x, Y - y)
        j = int(np.argmin(d))
        lo, hi = s[max(j - 1, 0)], s[min(j + 1, n - 1)]

        # Offset from lo: the bounded method's tolerance is relative to |u|.
        def dist(u, x=x, y=y, lo=lo):
            qx, qy = path.position(lo + u)
            return math.hypot(float(qx) - x, float(qy) - y)

        res = minimize_scalar(
            dist, bounds=(0.0, hi - lo), method="bounded", options={"xatol": 1e-13}
        )
        if res.fun < d[j]:
            s_out.append(lo + res.x)
            d_out.append(res.fun)
        else:
            s_out.append(s[j])
            d_out.append(d[j])
    return np.array(s_out), np.array(d_out)


def check_projection_consistent(path: Path, px, py, p: Projection) -> None:
    """Foot point, heading and e must agree with evaluating the path at p.s."""
    fx, fy = path.position(p.s)
    assert_close(p.x, fx, atol=1e-9)
    assert_close(p.y, fy, atol=1e-9)
    assert_close(p.distance, np.hypot(px - fx, py - fy), atol=1e-9)
    psi = path.heading(p.s)
    assert_close(wrap(p.heading - psi), 0.0, atol=1e-12)
    e_ref = np.cos(psi) * (py - fy) - np.sin(psi) * (px - fx)
    assert_close(p.e, e_ref, atol=1e-9)


# --------------------------------------------------------------------------
# Straight


def test_straight_evaluation_hand_values():
    line = Straight(start=(1.0, 2.0), start_heading=math.pi / 2)
    x, y = line.position([3.0, -2.0])
    assert_close(x, [1.0, 1.0], atol=1e-15)
    assert_close(y, [5.0, 0.0], atol=1e-15)
    assert_close(line.heading([3.0, -2.0]), math.pi / 2)
    assert line.curvature(7.0) == 0.0 and line.curvature_rate(7.0) == 0.0
    assert line.length == math.inf and line.closed is False


def test_straight_projection_sign_convention():
    # Heading +y: the left side is -x.
    line = Straight(start=(1.0, 2.0), start_heading=math.pi / 2)
    p = line.project([0.0, 4.0], [5.0, 7.0])
    assert_close(p.s, [3.0, 5.0], atol=1e-14)
    assert_close(p.e, [1.0, -3.0], atol=1e-14)
    assert p.unique.all()
    # The x-axis: y is the lateral error, x the arc length.
    q = Straight().project(-7.5, -2.5)
    assert (float(q.s), float(q.e), float(q.distance)) == (-7.5, -2.5, 2.5)


def test_straight_segment_clamps_to_its_ends():
    seg = Straight(length=20.0)
    p = seg.project([25.0, -4.0], [3.0, -3.0])
    assert_close(p.s, [20.0, 0.0])
    assert_close(p.e, [3.0, -3.0])
    assert_close(p.distance, [math.sqrt(34.0), 5.0])


# --------------------------------------------------------------------------
# Arc


@pytest.mark.parametrize("y0, e0", [(2.0, 2.0), (-5.0, -5.0), (-10.0, -10.0)])
def test_arc_convention_paper_initial_positions(y0, e0):
    p = Arc(curvature=0.1).project(0.0, y0, strict=True)
    assert float(p.s) == pytest.approx(0.0, abs=1e-12)
    assert float(p.e) == pytest.approx(e0, abs=1e-12)
    assert float(p.heading) == pytest.approx(0.0, abs=1e-12)
    assert float(p.curvature) == 0.1


def test_arc_evaluation_hand_values():
    arc = Arc(curvature=0.2)  # radius 5, centre (0, 5)
    quarter, half = math.pi / 2 / 0.2, math.pi / 0.2
    x, y = arc.position([quarter, half])
    assert_close(x, [5.0, 0.0], atol=1e-12)
    assert_close(y, [5.0, 10.0], atol=1e-12)
    assert_close(arc.heading([quarter, half]), [math.pi / 2, math.pi])
    assert arc.center == (0.0, 5.0) and arc.radius == 5.0
    right = Arc(curvature=-0.2)
    x, y = right.position(quarter)
    assert (float(x), float(y)) == pytest.approx((5.0, -5.0), abs=1e-12)
    assert float(right.heading(quarter)) == pytest.approx(-math.pi / 2)
    assert right.center == (0.0, -5.0)


def test_arc_negative_curvature_projection():
    arc = Arc(curvature=-0.1)  # centre (0, -10): the inside is on the right
    p = arc.project([0.0, 0.0, 10.0], [5.0, -5.0, -10.0])
    assert_close(p.s, [0.0, 0.0, 5.0 * math.pi], atol=1e-12)
    assert_close(p.e, [5.0, -5.0, 0.0], atol=1e-12)


def test_arc_is_closed_and_wraps():
    arc = Arc(curvature=0.1)
    L = 2.0 * math.pi * 10.0
    assert arc.closed and arc.length == pytest.approx(L, rel=1e-15)
    s = np.array([0.3, 7.0, 40.0])
    assert_close(arc.position(s + L), arc.position(s), atol=1e-12)
    assert_close(arc.position(s - 3 * L), arc.position(s), atol=1e-12)
    assert float(arc.heading(-1.0)) == pytest.approx(float(arc.heading(L - 1.0)))
    # Points just behind and just ahead of the start, 2 m outside the circle:
    # the direction from the centre to the foot point is k*s - pi/2.
    phi = np.array([-math.pi / 2 - 0.01, -math.pi / 2 + 0.01])
    px, py = 12.0 * np.cos(phi), 10.0 + 12.0 * np.sin(phi)
    p = arc.project(px, py)
    assert_close(p.s, [L - 0.1, 0.1], atol=1e-10)
    assert_close(p.e, [-2.0, -2.0], atol=1e-12)


def test_arc_centre_is_ambiguous_and_strict_raises():
    arc = Arc(curvature=0.1)
    p = arc.project(0.0, 10.0)
    assert not bool(p.unique)
    assert float(p.distance) == pytest.approx(10.0)
    assert abs(float(p.e)) == pytest.approx(10.0)
    with pytest.raises(AmbiguousProjectionError, match=r"\(0\.0, 10\.0\)"):
        arc.project(0.0, 10.0, strict=True)
    with pytest.raises(ValueError):  # it is a ValueError too
        arc.errors(0.0, 10.0, 0.0, strict=True)
    # 1 mm off the centre towards +x the nearest point is unique: (10, 10).
    q = arc.project(1e-3, 10.0, strict=True)
    assert float(q.s) == pytest.approx(5.0 * math.pi, abs=1e-9)
    assert float(q.e) == pytest.approx(10.0 - 1e-3, abs=1e-12)


def test_open_arc_segment_ends_and_tie():
    half = Arc(0.1, length=10.0 * math.pi)  # from (0, 0) to (0, 20), x >= 0
    p = half.project([-5.0, -5.0, 12.0], [10.0, 9.0, 10.0])
    assert p.unique.tolist() == [False, True, True]
    # (-5, 9) lies behind the start: nearest is the end (0, 0).
    assert float(p.s[1]) == 0.0
    assert float(p.distance[1]) == pytest.approx(math.sqrt(106.0))
    assert float(p.e[1]) == pytest.approx(9.0)
    # (12, 10) projects radially onto (10, 10), a quarter of the way round.
    assert float(p.s[2]) == pytest.approx(5.0 * math.pi)
    assert float(p.e[2]) == pytest.approx(-2.0)
    with pytest.raises(AmbiguousProjectionError):
        half.project(-5.0, 10.0, strict=True)


# --------------------------------------------------------------------------
# Clothoid


def fresnel_clothoid(k0, k1, L, s):
    """Position of a clothoid from the origin, via scipy's Fresnel integrals."""
    c = (k1 - k0) / L
    a = math.sqrt(abs(c) / math.pi)
    t0, t1 = a * (k0 / c), a * (s + k0 / c)
    S1, C1 = fresnel(t1)
    S0, C0 = fresnel(t0)
    z = (C1 - C0 + 1j * math.copysign(1.0, c) * (S1 - S0)) / a
    z = z * np.exp(-1j * k0 * k0 / (2.0 * c))
    return z.real, z.imag


@pytest.mark.parametrize(
    "k0, k1, L",
    [(0.0, 0.1, 10.0), (0.05, -0.2, 40.0), (-0.3, 0.25, 25.0), (0.0, 1.0, 30.0)],
)
def test_clothoid_position_matches_fresnel(k0, k1, L):
    s = np.linspace(0.0, L, 23)
    x, y = Clothoid(k0, k1, L).position(s)
    xr, yr = fresnel_clothoid(k0, k1, L, s)
    assert_close(x, xr, atol=1e-10)
    assert_close(y, yr, atol=1e-10)


def test_clothoid_position_matches_quadrature_of_heading():
    c = Clothoid(0.05, -0.2, 40.0, start=(1.0, 2.0), start_heading=0.3)
    for s in (0.0, 3.3, 17.0, 40.0):
        xr = 1.0 + quad(lambda u: math.cos(float(c.heading(u))), 0, s, epsabs=1e-13)[0]
        yr = 2.0 + quad(lambda u: math.sin(float(c.heading(u))), 0, s, epsabs=1e-13)[0]
        x, y = c.position(s)
        assert (float(x), float(y)) == pytest.approx((xr, yr), abs=1e-10)


def test_clothoid_hand_values():
    c = Clothoid(0.05, -0.2, 40.0, start_heading=0.3)
    assert float(c.curvature(0.0)) == 0.05
    assert float(c.curvature(40.0)) == pytest.approx(-0.2)
    assert_close(c.curvature_rate([0.0, 13.0]), -0.25 / 40.0)
    # heading = psi0 + k0 s + (k1 - k0) s^2 / (2 L)
    s = 20.0
    assert float(c.heading(s)) == pytest.approx(0.3 + 0.05 * s - 0.25 * s * s / 80.0)


@pytest.mark.parametrize("name", ["clothoid", "spline_open", "spline_closed", "chain"])
def test_derivatives_consistent_by_finite_differences(name):
    path = PATHS[name]
    L = path.length
    s = np.linspace(0.02 * L, 0.98 * L, 41)
    if isinstance(path, Spline):
        # Away from the knots, where the curvature rate jumps.
        knots = path.waypoint_s
        s = s[np.min(np.abs(s[:, None] - knots[None, :]), axis=1) > 1e-3]
    if isinstance(path, PathChain):
        s = s[np.min(np.abs(s[:, None] - path.offsets[None, :]), axis=1) > 1e-3]
    h = 1e-5
    dx = central(lambda u: path.position(u)[0], s, h)
    dy = central(lambda u: path.position(u)[1], s, h)
    assert_close(np.hypot(dx, dy), 1.0, atol=1e-8)
    psi = path.heading(s)
    assert_close(wrap(np.arctan2(dy, dx) - psi), 0.0, atol=1e-8)
    dpsi = (wrap(path.heading(s + h) - path.heading(s - h))) / (2 * h)
    assert_close(dpsi, path.curvature(s), atol=1e-7)
    dk = central(path.curvature, s, h)
    assert_close(dk, path.curvature_rate(s), atol=1e-6)


def test_constant_curvature_clothoid_is_an_arc():
    c = Clothoid(0.1, 0.1, 15.0)
    s = np.linspace(0.0, 15.0, 7)
    x, y = c.position(s)
    assert_close(x, 10.0 * np.sin(0.1 * s), atol=1e-12)
    assert_close(y, 10.0 * (1.0 - np.cos(0.1 * s)), atol=1e-12)
    assert not bool(c.project(0.0, 10.0).unique)  # the arc's centre


# --------------------------------------------------------------------------
# Spline


def polyline_length(path, a, b, n):
    s = np.linspace(a, b, n + 1)
    x, y = path.position(s)
    return float(np.sum(np.hypot(np.diff(x), np.diff(y))))


@pytest.mark.parametrize("name", ["spline_open", "spline_closed"])
def test_spline_s_is_arc_length(name):
    sp = PATHS[name]
    L = sp.length
    for a, b in [(0.0, L), (0.13 * L, 0.57 * L), (0.6 * L, 0.61 * L)]:
        # Richardson on the O(h^2) polyline length.
        l1, l2 = polyline_length(sp, a, b, 4000), polyline_length(sp, a, b, 8000)
        assert (4 * l2 - l1) / 3 == pytest.approx(b - a, rel=1e-8)


def test_spline_length_matches_quadrature_of_chord_spline():
    # The documented construction: natural cubic spline on chord length.
    t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(OPEN_WP, axis=0).T))])
    cs = CubicSpline(t, OPEN_WP, bc_type="natural", axis=0)
    L = sum(
        quad(lambda u: float(np.hypot(*cs(u, 1))), t[i], t[i + 1], epsabs=1e-13)[0]
        for i in range(len(t) - 1)
    )
    assert PATHS["spline_open"].length == pytest.approx(L, rel=1e-12)


@pytest.mark.parametrize(
    "name, wp", [("spline_open", OPEN_WP), ("spline_closed", CLOSED_WP)]
)
def test_spline_passes_through_waypoints(name, wp):
    sp = PATHS[name]
    x, y = sp.position(sp.waypoint_s)
    assert_close(np.column_stack([x, y]), wp, atol=1e-9)
    p = sp.project(wp[:, 0], wp[:, 1])
    assert_close(p.distance, 0.0, atol=1e-9)


@pytest.mark.parametrize("name", ["spline_open", "spline_closed"])
def test_spline_curvature_continuous_at_knots(name):
    sp = PATHS[name]
    knots = sp.waypoint_s[1:-1]
    eps = 1e-7
    k_minus, k_plus = sp.curvature(knots - eps), sp.curvature(knots + eps)
    r_minus, r_plus = sp.curvature_rate(knots - eps), sp.curvature_rate(knots + eps)
    # C2 spline: curvature continuous (jump at most |rate| * 2 eps) ...
    bound = 2 * eps * np.maximum(np.abs(r_minus), np.abs(r_plus)) + 1e-12
    assert np.all(np.abs(k_plus - k_minus) <= 1.5 * bound)
    # ... while the third derivative, hence the curvature rate, does jump:
    # these really are knots.
    assert np.max(np.abs(r_plus - r_minus)) > 1e-4
    assert_close(
        wrap(sp.heading(knots + eps) - sp.heading(knots - eps)),
        2 * eps * sp.curvature(knots),
        atol=1e-13,
    )


def test_closed_spline_through_circle_points():
    t = np.linspace(0.0, 2 * np.pi, 25)
    ring = Spline(np.column_stack([10 * np.cos(t), 10 * np.sin(t)]))
    assert ring.closed
    assert ring.length == pytest.approx(20 * math.pi, rel=1e-4)
    s = np.linspace(0.0, ring.length, 50)
    # Cubic interpolation of a circle: curvature error O(h^2), ~0.6 % here.
    assert_close(ring.curvature(s), 0.1, rtol=1e-2)
    # Periodic: the wrap point is as smooth as any other.
    L, eps = ring.length, 1e-7
    assert_close(ring.position(L), ring.position(0.0), atol=1e-12)
    assert float(ring.curvature(L - eps)) == pytest.approx(
        float(ring.curvature(eps)), abs=1e-6
    )
    assert float(wrap(ring.heading(L - eps) - ring.heading(eps))) == pytest.approx(
        0.0, abs=1e-6
    )
    assert_close(ring.position(s + 2 * L), ring.position(s), atol=1e-9)


def test_spline_closed_flag_overrides():
    sp = Spline(CLOSED_WP[:-1], closed=True)  # the first point is appended
    assert sp.closed
    assert_close(sp.length, PATHS["spline_closed"].length, rtol=1e-12)
    loop = Spline(CLOSED_WP, closed=False)  # ends coincide, but open: a corner
    assert not loop.closed
    assert abs(float(wrap(loop.heading(0.0) - loop.heading(loop.length)))) > 0.1
    with pytest.raises(ValueError, match="s must be in"):
        loop.position(loop.length + 1.0)


def test_closed_spline_projection_near_the_wrap():
    sp = PATHS["spline_closed"]
    L = sp.length
    s0 = np.array([L - 0.4, L - 0.05, 0.05, 0.4])
    x, y = sp.position(s0)
    psi = sp.heading(s0)
    off = np.array([0.5, -0.7, 1.0, -0.2])
    px, py = x - off * np.sin(psi), y + off * np.cos(psi)
    for guess in (None, s0 + 0.1):
        p = sp.project(px, py, s_guess=guess)
        assert_close(p.s, s0, atol=1e-9)
        assert_close(p.e, off, atol=1e-9)
        assert np.all((p.s >= 0) & (p.s < L))


def test_spline_medial_axis_is_ambiguous():
    # An ellipse-like course, symmetric about both axes: its centre is equally
    # near the top and the bottom.
    t = np.linspace(0.0, 2 * np.pi, 17)
    oval = Spline(np.column_stack([20 * np.cos(t), 8 * np.sin(t)]))
    p = oval.project(0.0, 0.0)
    assert not bool(p.unique)
    with pytest.raises(AmbiguousProjectionError, match="no unique nearest point"):
        oval.project(0.0, 0.0, strict=True)
    # Just off the axis of symmetry the nearer half wins (mirror argument).
    xs = np.linspace(-12.0, 12.0, 25)
    for delta in (1e-3, -1e-3):
        r = oval.project(xs, np.full_like(xs, delta), strict=True)
        assert np.all(np.sign(r.y) == np.sign(delta))
    q = oval.project(0.0, 0.5, strict=True)
    _, d_ref = reference_nearest(oval, np.array([0.0]), np.array([0.5]))
    assert float(q.distance) == pytest.approx(d_ref[0], abs=1e-9)
    assert float(q.y) > 0  # the top branch
    assert float(q.e) == pytest.approx(float(q.distance))  # inside, left of CCW


# --------------------------------------------------------------------------
# PathChain


def test_chain_hand_values():
    chain = PathChain([Straight(length=20.0), Arc(0.1, length=10.0 * math.pi)])
    assert chain.length == pytest.approx(20.0 + 10.0 * math.pi)
    assert_close(chain.offsets, [0.0, 20.0, 20.0 + 10.0 * math.pi])
    x, y = chain.position([10.0, 20.0 + 5.0 * math.pi, chain.length])
    assert_close(x, [10.0, 30.0, 20.0], atol=1e-12)
    assert_close(y, [0.0, 10.0, 20.0], atol=1e-12)
    assert float(chain.heading(chain.length)) == pytest.approx(math.pi)
    assert_close(chain.curvature([5.0, 25.0]), [0.0, 0.1])


def test_chain_continuity_at_joints():
    chain = PathChain(
        [
            Straight(length=20.0, start=(2.0, -1.0), start_heading=0.4),
            Clothoid(0.0, 0.1, 10.0),
            Arc(0.1, length=20.0),
            Clothoid(0.1, -0.05, 12.0),
            Spline([[0.0, 0.0], [5.0, 2.0], [10.0, 0.0], [15.0, -3.0]]),
        ]
    )
    segs = chain.segments
    for prev, nxt in zip(segs[:-1], segs[1:], strict=True):
        ex, ey = prev.position(prev.length)
        sx, sy = nxt.position(0.0)
        assert (float(sx), float(sy)) == pytest.approx((float(ex), float(ey)), abs=1e-9)
        gap = wrap(nxt.heading(0.0) - prev.heading(prev.length))
        assert float(gap) == pytest.approx(0.0, abs=1e-9)
    joints = chain.offsets[1:-1]
    eps = 1e-6
    xm, ym = chain.position(joints - eps)
    xp, yp = chain.position(joints + eps)
    assert_close(np.hypot(xp - xm, yp - ym), 2 * eps, rtol=1e-3)
    assert_close(
        wrap(chain.heading(joints + eps) - chain.heading(joints - eps)), 0.0, atol=1e-6
    )
    # The first segment keeps its placement.
    assert float(chain.heading(0.0)) == pytest.approx(0.4)
    # Within the clothoid: curvature linear from 0 to 0.1 over 10 m.
    assert float(chain.curvature(20.0 + 4.0)) == pytest.approx(0.04)


def test_chain_curvature_is_each_segments_formula_at_every_point():
    """The chain's curvature (computed without the positions) against each
    segment's curvature written here from its parameters (0 on a straight,
    the arc's, linear along a clothoid), at the joints, inside the
    segments, for arrays and single points; the spline's is its frame's."""
    segs = [
        Straight(length=20.0, start=(2.0, -1.0), start_heading=0.4),
        Clothoid(0.0, 0.1, 10.0),
        Arc(0.1, length=20.0),
        Clothoid(0.1, -0.05, 12.0),
        Spline([[0.0, 0.0], [5.0, 2.0], [10.0, 0.0], [15.0, -3.0]]),
    ]
    chain = PathChain(segs)
    off = chain.offsets

    def formula(i, u):
        if i == 0:
            return 0.0
        if i == 2:
            return 0.1
        if i in (1, 3):
            k0, k1, length = ((0.0, 0.1, 10.0), (0.1, -0.05, 12.0))[i // 2]
            return k0 + (k1 - k0) * u / length
        # the spline's: a central difference of its heading
        seg = chain.segments[4]
        lo, hi = max(u - 1e-4, 0.0), min(u + 1e-4, seg.length)
        return float(wrap(seg.heading(hi) - seg.heading(lo))) / (hi - lo)

    rng = np.random.default_rng(11)
    s = np.concatenate([rng.uniform(0.0, chain.length, 300), off])
    k = chain.curvature(s)
    seg = np.minimum(np.searchsorted(off, s, side="right") - 1, len(segs) - 1)
    for j, (sj, i) in enumerate(zip(s, seg, strict=True)):
        u = min(sj - off[i], off[i + 1] - off[i])
        tol = 1e-5 if i == 4 else 1e-15  # (one-sided difference at its ends)
        assert abs(k[j] - formula(int(i), u)) <= tol, (sj, i)
        # one point at a time: the same number as in the array (the spline's
        # vectorised evaluation may round its last bit differently)
        assert float(chain.curvature(float(sj))) == pytest.approx(k[j], rel=1e-14)
    # and the same number as the full evaluation of the chain's frame
    np.testing.assert_array_equal(k, chain._frame(s)[3])
    assert chain.curvature(np.zeros((2, 3))).shape == (2, 3)


def test_racetrack_chain_is_closed_and_wraps():
    half = Arc(0.1, length=10.0 * math.pi)
    track = PathChain([Straight(length=50.0), half, Straight(length=50.0), half])
    L = 100.0 + 20.0 * math.pi
    assert track.closed and track.length == pytest.approx(L)
    assert_close(track.position(L + 3.0), track.position(3.0), atol=1e-9)
    # Behind the start, 2 m outside the last arc (centre (0, 10), radius 10).
    p = track.project([-1.0, 1.0], [-2.0, -2.0])
    s_ref = L - 10.0 * math.atan2(1.0, 12.0)
    assert_close(p.s, [s_ref, 1.0], atol=1e-9)
    assert_close(p.e, [10.0 - math.sqrt(145.0), -2.0], atol=1e-9)


def test_chain_closed_option():
    half = Arc(0.1, length=10.0 * math.pi)
    parts = [Straight(length=50.0), half, Straight(length=50.0), half]
    assert not PathChain(parts, closed=False).closed
    with pytest.raises(ValueError, match="closed=True"):
        PathChain(parts[:3], closed=True)


def test_chain_tie_between_segments_is_ambiguous():
    uturn = PathChain(
        [Straight(length=20.0), Arc(0.1, length=10.0 * math.pi), Straight(length=20.0)]
    )
    p = uturn.project([10.0, 10.0], [10.0, 9.0])
    assert p.unique.tolist() == [False, True]
    assert float(p.s[1]) == pytest.approx(10.0) and float(p.e[1]) == pytest.approx(9.0)
    # A point on a joint is not a tie between the two segments sharing it.
    q = uturn.project(20.0, -3.0, strict=True)
    assert float(q.s) == pytest.approx(20.0) and float(q.e) == pytest.approx(-3.0)


def test_guess_follows_the_branch_it_is_on():
    # Hairpin: straights at y = 0 and y = 20. (10, 14) is 14 m from the lower
    # and 6 m from the upper one.
    uturn = PathChain(
        [Straight(length=20.0), Arc(0.1, length=10.0 * math.pi), Straight(length=20.0)]
    )
    top_s = 20.0 + 10.0 * math.pi + 10.0
    glob = uturn.project(10.0, 14.0)
    assert (float(glob.s), float(glob.e)) == pytest.approx((top_s, 6.0))
    local = uturn.project(10.0, 14.0, s_guess=9.0)
    assert (float(local.s), float(local.e)) == pytest.approx((10.0, 14.0))
    # A guess farther than `window` from the local minimum is not trusted.
    far = uturn.project(10.0, 14.0, s_guess=0.0, window=5.0)
    assert float(far.s) == pytest.approx(top_s)


def test_guess_rejected_when_a_nearer_branch_is_within_window():
    # Tight hairpin (radius 2, straights at y = 0 and y = 4, 3 m long): from
    # the guess s = 2 Newton stays on the lower straight (e = 3.5), but the
    # upper one, 8.3 m further along the path, is within the window and only
    # 0.5 m away.
    hairpin = PathChain(
        [Straight(length=3.0), Arc(0.5, length=2.0 * math.pi), Straight(length=3.0)]
    )
    p = hairpin.project(2.0, 3.5, s_guess=2.0)
    assert float(p.s) == pytest.approx(3.0 + 2.0 * math.pi + 1.0)
    assert float(p.e) == pytest.approx(0.5)
    # With a window that does not reach the other branch, the guess's branch.
    q = hairpin.project(2.0, 3.5, s_guess=2.0, window=2.0)
    assert (float(q.s), float(q.e)) == pytest.approx((2.0, 3.5))


# --------------------------------------------------------------------------
# Projection against brute force


@FAST
@given(
    name=st.sampled_from(sorted(PATHS)),
    seed=st.integers(0, 2**32 - 1),
    spread=st.sampled_from([5.0, 60.0, 2000.0]),
)
def test_projection_matches_brute_force(name, seed, spread):
    path = PATHS[name]
    rng = np.random.default_rng(seed)
    px = 15.0 + rng.uniform(-spread, spread, 6)
    py = 8.0 + rng.uniform(-spread, spread, 6)
    p = path.project(px, py)
    _, d_ref = reference_nearest(path, px, py)
    assert_close(p.distance, d_ref, rtol=1e-10, atol=1e-9)
    check_projection_consistent(path, px, py, p)
    if not path.closed:
        interior = (p.s > 1e-6) & (p.s < path.length - 1e-6)
        assert_close(np.abs(p.e[interior]), p.distance[interior], atol=1e-8)


@FAST
@given(
    name=st.sampled_from(sorted(PATHS)),
    frac=st.floats(0.03, 0.97),
    offset=st.floats(-3.0, 3.0),
    noise=st.floats(-2.0, 2.0),
)
def test_points_built_from_a_known_foot(name, frac, offset, noise):
    # Within 3 m of these paths (radius of curvature >= 4.9 m) the normal
    # through s0 gives the nearest point.
    path = PATHS[name]
    s0 = frac * path.length
    x, y = path.position(s0)
    psi = float(path.heading(s0))
    px, py = float(x) - offset * math.sin(psi), float(y) + offset * math.cos(psi)
    _, d_ref = reference_nearest(path, np.array([px]), np.array([py]))
    assert d_ref[0] == pytest.approx(abs(offset), abs=1e-9)  # the premise
    for guess in (None, s0 + noise):
        p = path.project(px, py, s_guess=guess)
        assert float(p.s) == pytest.approx(s0, abs=1e-8)
        assert float(p.e) == pytest.approx(offset, abs=1e-9)


@pytest.mark.parametrize("name", sorted(PATHS))
def test_far_points(name):
    path = PATHS[name]
    px = np.array([1e4, -3e4, 0.0, 5e5])
    py = np.array([-3e4, 2e3, 1e5, 5e5])
    p = path.project(px, py)
    _, d_ref = reference_nearest(path, px, py)
    assert_close(p.distance, d_ref, rtol=1e-12)
    # A bad guess must not matter.
    q = path.project(px, py, s_guess=0.5 * path.length)
    assert_close(q.distance, d_ref, rtol=1e-12)


def test_bad_guess_falls_back_to_global():
    sp = PATHS["spline_closed"]
    L = sp.length
    s0 = 30.0
    x, y = sp.position(s0)
    psi = float(sp.heading(s0))
    px, py = float(x) - 1.0 * math.sin(psi), float(y) + 1.0 * math.cos(psi)
    for guess in (s0 + L / 2, s0 - 25.0, 0.0):
        p = sp.project(px, py, s_guess=guess)
        assert float(p.s) == pytest.approx(s0, abs=1e-8)
        assert float(p.e) == pytest.approx(1.0, abs=1e-9)


def test_projection_is_vectorised_over_shapes():
    path = PATHS["chain"]
    rng = np.random.default_rng(7)
    px, py = rng.uniform(-10, 40, (3, 4)), rng.uniform(-10, 30, (3, 4))
    p = path.project(px, py)
    for f in dataclasses.fields(Projection):
        assert np.shape(getattr(p, f.name)) == (3, 4)
    for i, j in [(0, 0), (1, 2), (2, 3)]:
        q = path.project(px[i, j], py[i, j])
        assert np.ndim(q.s) == 0
        assert float(q.s) == pytest.approx(float(p.s[i, j]), abs=1e-10)
        assert float(q.e) == pytest.approx(float(p.e[i, j]), abs=1e-10)
    # A scalar guess broadcasts to every point.
    g = path.project(px, py, s_guess=25.0)
    assert_close(g.distance, p.distance, atol=1e-9)


def test_errors_wraps_heading_error():
    arc = Arc(curvature=0.1)
    x, y = arc.position(5.0)  # heading 0.5
    psi = np.array([0.5 + 2 * math.pi + 0.1, 0.5 - math.pi, 0.5 + math.pi, 0.2])
    s, e, theta, k = arc.errors(float(x), float(y), psi)
    assert_close(s, 5.0)
    assert_close(e, 0.0, atol=1e-12)
    assert_close(theta, [0.1, math.pi, math.pi, -0.3], atol=1e-12)
    assert_close(k, 0.1)
    assert np.all((theta > -math.pi) & (theta <= math.pi))


# --------------------------------------------------------------------------
# placement and data


@pytest.mark.parametrize(
    "path",
    [
        Straight(length=5.0),
        Arc(-0.2, length=4.0),
        Clothoid(0.1, -0.3, 6.0),
        Spline(OPEN_WP),
        PathChain([Straight(length=3.0), Arc(0.2, length=2.0)]),
    ],
    ids=lambda p: type(p).__name__,
)
def test_placed_is_a_rigid_motion(path):
    moved = path.placed((3.0, -4.0), 2.0)
    assert type(moved) is type(path)
    x0, y0 = moved.position(0.0)
    assert (float(x0), float(y0)) == pytest.approx((3.0, -4.0), abs=1e-12)
    assert float(moved.heading(0.0)) == pytest.approx(2.0, abs=1e-12)
    assert moved.length == pytest.approx(path.length, rel=1e-12)
    s = np.linspace(0.0, path.length, 9)
    assert_close(moved.curvature(s), path.curvature(s), atol=1e-9)
    # Distances between points are preserved.
    xa, ya = path.position(s)
    xb, yb = moved.position(s)
    assert_close(
        np.hypot(xb - xb[0], yb - yb[0]), np.hypot(xa - xa[0], ya - ya[0]), atol=1e-9
    )


def test_paths_are_frozen():
    arc = Arc(0.1)
    with pytest.raises(dataclasses.FrozenInstanceError):
        arc.curvature = 0.2
    assert Arc(0.1) == arc and Spline(OPEN_WP) == Spline(OPEN_WP.tolist())


# --------------------------------------------------------------------------
# invalid input


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Arc(0.0), "curvature"),
        (lambda: Arc(math.nan), "curvature"),
        (lambda: Arc(0.1, length=63.0), r"length .*\(0, 62\.83"),
        (lambda: Arc(0.1, length=-1.0), "length"),
        (lambda: Straight(length=0.0), "length"),
        (lambda: Straight(start=(0.0, math.nan)), "start"),
        (lambda: Straight(start_heading=math.inf), "start_heading"),
        (lambda: Clothoid(0.0, 0.1, 0.0), "length"),
        (lambda: Clothoid(math.nan, 0.1, 1.0), "curvature_start"),
        (lambda: Clothoid(0.0, math.inf, 1.0), "curvature_end"),
        (lambda: Spline(np.zeros((4, 3))), r"shape \(N, 2\), got shape \(4, 3\)"),
        (lambda: Spline([[0, 0], [1, 1]]), "N >= 3"),
        (lambda: Spline([[0, 0], [1, math.nan], [2, 0]]), "finite.*row 1"),
        (lambda: Spline([[0, 0], [1, 1], [1, 1], [2, 0]]), r"waypoints\[1\]"),
        (lambda: Spline([[0, 0], [1, 1], [0, 0]]), "3 distinct"),
        (lambda: PathChain([]), "at least one"),
        (lambda: PathChain([Straight()]), r"segments\[0\].*finite"),
        (lambda: PathChain([Straight(length=1.0), Arc(0.1)]), r"segments\[1\]"),
        (lambda: PathChain([Straight(length=1.0), "arc"]), r"segments\[1\] must be"),
    ],
)
def test_invalid_construction(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_invalid_evaluation_and_projection_inputs():
    seg = Straight(length=20.0)
    with pytest.raises(ValueError, match=r"s must be in \[0, length=20\.0\].*21\.0"):
        seg.position(21.0)
    with pytest.raises(ValueError, match=r"s must be in .*-0\.5"):
        PATHS["clothoid"].curvature(-0.5)
    with pytest.raises(ValueError, match="s must be finite"):
        Arc(0.1).heading([0.0, math.nan])
    with pytest.raises(ValueError, match="x must be finite"):
        seg.project(math.inf, 0.0)
    with pytest.raises(ValueError, match="broadcastable"):
        seg.project([1.0, 2.0], [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="window"):
        seg.project(1.0, 1.0, window=0.0)
    with pytest.raises(ValueError, match="s_guess must be finite"):
        PATHS["spline_open"].project(1.0, 1.0, s_guess=math.nan)
    with pytest.raises(ValueError, match="s_guess must broadcast"):
        PATHS["spline_open"].project([1.0, 2.0], [1.0, 1.0], s_guess=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="psi must be finite"):
        seg.errors(1.0, 1.0, math.nan)


# -- cusps (issue 13 item 5) --------------------------------------------------


@pytest.mark.parametrize(
    "wp, index",
    [
        ([[0, 0], [0, 2], [0, 1]], 1),
        ([[0, 0], [10, 0], [5, 0]], 1),
        ([[0, 0], [10, 0], [20, 0], [15, 0]], 2),
    ],
)
def test_spline_refuses_waypoints_that_double_back(wp, index):
    # Reference: the chord-length natural spline written with scipy directly;
    # its tangent reverses (dot product of the unit tangents at two nearby
    # parameters < 0) between the samples, so the path has a cusp.
    w = np.asarray(wp, dtype=float)
    t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(w, axis=0).T))])
    cs = CubicSpline(t, w, axis=0, bc_type="natural")
    tt = np.linspace(0.0, t[-1], 20001)
    d = cs(tt, 1)
    u = d / np.hypot(d[:, 0], d[:, 1])[:, None]
    assert np.min(np.sum(u[:-1] * u[1:], axis=1)) < 0.0
    with pytest.raises(ValueError, match=rf"cusp .*near waypoint {index}\b"):
        Spline(wp)


def test_spline_hairpin_is_not_a_cusp():
    # a tight U-turn turns by pi over a finite length: accepted, and its
    # heading changes continuously (no jump of pi between close samples)
    sp = Spline([[0, 0], [5, 0], [5, 0.5], [0, 0.5]])
    s = np.linspace(0.0, sp.length, 4001)
    jump = np.abs(np.diff(np.unwrap(sp.heading(s))))
    assert jump.max() < 0.1


# -- projection first pass: KD-tree vs the dense method (issue 14 item 5) -----


PROJECTION_PATHS = {
    **{k: v for k, v in PATHS.items()},
    "straight": Straight(length=30.0, start=(1.0, -2.0), start_heading=0.4),
    "arc_full": Arc(0.1),
    "clothoid_turning": Clothoid(-0.3, 0.5, 60.0),
}


@pytest.mark.parametrize("name", sorted(PROJECTION_PATHS))
def test_kdtree_projection_equals_dense_method_and_brute_force(name, monkeypatch):
    import fws_control.paths as paths_module

    path = PROJECTION_PATHS[name]
    rng = np.random.default_rng(7)
    s0 = rng.uniform(0.0, min(path.length, 200.0), 60)
    x0, y0 = path.position(s0)
    px = x0 + rng.normal(0.0, 8.0, s0.size)
    py = y0 + rng.normal(0.0, 8.0, s0.size)
    monkeypatch.setattr(paths_module, "_FIRST_PASS", "kdtree")  # forced
    new = path.project(px, py)
    monkeypatch.setattr(paths_module, "_FIRST_PASS", "dense")
    old = path.project(px, py)  # same cached samples, no tree
    # the same candidates in the same order: bitwise the same answer
    for f in ("s", "e", "distance", "unique"):
        np.testing.assert_array_equal(getattr(new, f), getattr(old, f))
    _, d_ref = reference_nearest(path, px, py)
    assert_close(new.distance, d_ref, atol=1e-9, rtol=1e-9)


def test_clothoid_projection_memory_does_not_grow_with_turning_squared():
    # 1000 rad of turning used to need ~6 GB (samples x panels); now each
    # point costs one 16-node panel integral.
    import tracemalloc

    c = Clothoid(0.0, 2.0, length=1000.0)
    tracemalloc.start()
    p = c.project([3.0, 100.0, 600.0], [1.0, -50.0, 30.0])
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 50e6, peak
    # positions against scipy's Fresnel integrals at high turning, and the
    # projection against the brute-force reference
    s = np.linspace(0.0, 1000.0, 11)
    x, y = c.position(s)
    xr, yr = fresnel_clothoid(0.0, 2.0, 1000.0, s)
    assert_close(x, xr, atol=1e-9)
    assert_close(y, yr, atol=1e-9)
    _, d_ref = reference_nearest(c, [3.0, 100.0, 600.0], [1.0, -50.0, 30.0], n=400001)
    assert_close(p.distance, d_ref, atol=1e-8, rtol=1e-9)
