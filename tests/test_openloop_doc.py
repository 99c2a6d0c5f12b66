"""docs/openloop.md: the tables are current, entries hold by other routes.

The tables come from ``docs/scripts/openloop.py``; here the script runs
again and the page must hold exactly its output. Entries are then
recomputed independently: the linear steady gains and the frequency
response from the textbook single-track model (python-control), the circle
from the force balance of the magic tyre written here. The statements of the
page's prose are checked against the tables.
"""

from __future__ import annotations

import importlib.util
import math
import pathlib

import control as ct
import numpy as np
import pytest

import fws_control as fws

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "openloop.md"
_spec = importlib.util.spec_from_file_location(
    "openloop_tables", ROOT / "docs" / "scripts" / "openloop.py"
)
D = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(D)
VEH = D.VEHICLE


def _block(name: str) -> str:
    start, end = D.markers(name)
    return PAGE.read_text().split(start)[1].split(end)[0].strip()


def _rows(name: str) -> list[list[str]]:
    return [
        [c.strip() for c in line.strip().strip("|").split("|")]
        for line in _block(name).splitlines()[2:]
    ]


@pytest.fixture(scope="module")
def fresh() -> dict[str, str]:
    return D.tables()


@pytest.mark.parametrize("name", D.TABLES)
def test_page_holds_the_script_output(fresh, name):
    assert _block(name) == fresh[name].strip(), (
        f"docs/openloop.md table {name!r} is stale: run docs/scripts/openloop.py"
    )


def _textbook(u: float, a: float) -> ct.StateSpace:
    m, iz = VEH.mass, VEH.yaw_inertia
    lr = VEH.rear_to_cg
    lf = VEH.wheelbase - lr
    cf, cr = VEH.cornering_front, VEH.cornering_rear
    A = np.array(
        [
            [-(cf + cr) / (m * u), -u - (lf * cf - lr * cr) / (m * u)],
            [-(lf * cf - lr * cr) / (iz * u), -(lf**2 * cf + lr**2 * cr) / (iz * u)],
        ]
    )
    B = np.array([[(cf + a * cr) / m], [(lf * cf - a * lr * cr) / iz]])
    C = np.array([[0.0, 1.0], [A[0, 0], A[0, 1] + u]])
    D_ = np.array([[0.0], [B[0, 0]]])
    return ct.ss(A, B, C, D_)


def _zero_sideslip(u: float) -> float:
    m, f = VEH.mass, VEH.wheelbase
    lf, lr = f - VEH.rear_to_cg, VEH.rear_to_cg
    return (-lr + m * lf * u**2 / (f * VEH.cornering_rear)) / (
        lf + m * lr * u**2 / (f * VEH.cornering_front)
    )


def test_step_table_by_other_routes():
    rows = _rows("step")
    u = D.SPEED
    for r in rows:
        schedule, a, model, output = r[0], float(r[1]), r[2], r[3]
        want_a = 0.0 if schedule == "front" else _zero_sideslip(u)
        assert a == pytest.approx(want_a, abs=5e-5)
        if model.startswith("linear"):
            gain = np.ravel(_textbook(u, want_a).dcgain())
            k = 0 if output == "r" else 1
            steady = float(r[4].split()[0])
            assert steady == pytest.approx(D.STEP_ANGLE * gain[k], abs=5e-5)
    # the neutral car's yaw rate: no peak anywhere
    assert all(r[7] == "none" for r in rows if r[3] == "r")


def test_step_prose():
    rows = {(r[0], r[2].split()[0], r[3]): r for r in _rows("step")}
    for schedule in ("front", "4WS a(V)"):
        for out in ("r", "a_y"):
            lin = rows[(schedule, "linear", out)]
            nl = rows[(schedule, "nonlinear", out)]
            # "by less than 0.1 %"
            s_lin, s_nl = float(lin[4].split()[0]), float(nl[4].split()[0])
            assert abs(s_nl / s_lin - 1.0) < 1e-3
            # "delays the responses by 0.02 s at most"
            delay = float(nl[5]) - float(lin[5])
            assert 0.0 < delay <= 0.02
    # "the response times of the yaw rate are the same as with front steering"
    assert rows[("front", "linear", "r")][5] == rows[("4WS a(V)", "linear", "r")][5]
    # "the same front angle gives a smaller yaw rate"
    assert float(rows[("4WS a(V)", "linear", "r")][4].split()[0]) < float(
        rows[("front", "linear", "r")][4].split()[0]
    )


def test_frequency_table_by_python_control():
    rows = _rows("frequency")
    u = D.SPEED
    for r in rows:
        a = 0.0 if r[0] == "front" else _zero_sideslip(u)
        w = 2.0 * math.pi * float(r[1])
        h = ct.frequency_response(_textbook(u, a), [w]).complex[:, 0, 0]
        assert float(r[2]) == pytest.approx(abs(h[0]), abs=5e-4)
        assert float(r[4]) == pytest.approx(abs(h[1]), abs=5e-3)
        for cell, hk in ((r[3], h[0]), (r[5], h[1])):
            diff = math.radians(float(cell)) - np.angle(hk)
            assert abs(math.remainder(diff, 2 * math.pi)) <= math.radians(0.05)


def test_frequency_prose():
    for schedule in ("front", "4WS a(V)"):
        kept = [float(r[6]) for r in _rows("frequency") if r[0] == schedule]
        # "keeps almost all of the gain" at low frequency, "loses gain" higher
        assert kept[0] > 0.99
        assert kept[-1] < 0.9


def _magic(alpha, c, peak):
    # F = D sin(1.3 atan(B alpha)), B = C/(1.3 D), written here
    b = c / (1.3 * peak)
    return peak * math.sin(1.3 * math.atan(b * alpha))


def test_circle_table_by_force_balance():
    """Each row: lateral forces balance m a_y and the yaw moment, on the circle."""
    m, f = VEH.mass, VEH.wheelbase
    lr = VEH.rear_to_cg
    lf = f - lr
    g = 9.81
    peak_f = VEH.friction * m * g * lr / f
    peak_r = VEH.friction * m * g * lf / f
    for r in _rows("circle"):
        ay, u = float(r[1]), float(r[2])
        df, dr = math.radians(float(r[3])), math.radians(float(r[4]))
        beta = math.radians(float(r[5]))
        a = 0.0 if r[0] == "front" else _zero_sideslip(u)
        assert dr == pytest.approx(a * df, abs=math.radians(1e-4) * 2)
        v_y = u * math.tan(beta)
        yaw = ay / u
        # the circle: speed of G = r R (4 decimals in the table)
        assert math.hypot(u, v_y) == pytest.approx(yaw * D.RADIUS, rel=1e-4)
        af = df - math.atan2(v_y + lf * yaw, u)
        ar = dr - math.atan2(v_y - lr * yaw, u)
        ff = _magic(af, VEH.cornering_front, peak_f) * math.cos(df)
        fr = _magic(ar, VEH.cornering_rear, peak_r) * math.cos(dr)
        # rounded table entries: a relative 1e-3 of the forces
        assert ff + fr == pytest.approx(m * ay, rel=3e-3)
        assert lf * ff - lr * fr == pytest.approx(0.0, abs=3e-3 * m * ay * lf)


def test_circle_prose():
    rows = _rows("circle")
    front = [r for r in rows if r[0] == "front"]
    fws4 = [r for r in rows if r[0] != "front"]
    ackermann = math.degrees(VEH.wheelbase / D.RADIUS)
    # "the front angle stays at the Ackermann angle until ... the limit"
    assert float(front[0][3]) == pytest.approx(ackermann, abs=0.01)
    # "where the gradient rises"
    grads = [float(r[6]) for r in front]
    assert grads[-1] > 10 * max(abs(x) for x in grads[:3])
    # "the gradient of delta_f is large" with a(V)
    assert min(float(r[6]) for r in fws4) > 100 * max(abs(x) for x in grads[:3])
    # "the sideslip of G stays near zero only while the tyres are linear"
    assert abs(float(fws4[0][5])) < 0.01 < abs(float(fws4[-1][5]))
    # slip_front > slip_rear near the limit (the prose's reason)
    c = fws.steady_state_circle(VEH, radius=D.RADIUS, lateral_acceleration=[10.0])
    assert c.slip_front[0] > c.slip_rear[0]
