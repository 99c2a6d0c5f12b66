"""compare() on the dynamic model with friction: limits, lane, table object.

References: the friction limit mu g from the vehicle's data (CommonRoad's
BMW 320i, mu = 1.0489, g = 9.81); the lateral acceleration recomputed from
the run's own signals (finite differences of v_y plus u r); the lane
recomputed by sampling the wheel track's outline densely; the rows against a
direct :func:`fws_control.simulate` of the same controller on the same
plant with the documented start and duration.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import fws_control as fws
from fws_control.controller_comparison import COMPARISON_METRICS, FRICTION_METRICS

BMW = fws.vehicles.BMW_320I
MU_G = 1.0489 * 9.81  # CommonRoad's p_dy1 and g (hand value, m/s^2)
COURSE = fws.double_lane_change()


@pytest.fixture(scope="module")
def dynamic20():
    """The default set on the dynamic model with the saturating tyre, 20 m/s."""
    plant = fws.LateralPlant(BMW, speed=20.0, model="dynamic", tyre="magic")
    ctrls = fws.default_controllers(BMW, speed=20.0)
    return fws.compare(plant, COURSE, ctrls, progress=False), ctrls


def _outline_excursion(m, x, y, psi, wheelbase, n=400):
    """Largest distance [m] by which the sampled outline of the wheel track
    lies beyond a cone line inside a gate (negative: inside everywhere)."""
    half = m.vehicle_width / 2.0
    u = np.linspace(0.0, 1.0, n)
    lon = np.concatenate([u * wheelbase, np.full(n, wheelbase), u * wheelbase,
                          np.zeros(n)])  # fmt: skip
    lat = np.concatenate([np.full(n, -half), (2 * u - 1) * half, np.full(n, half),
                          (2 * u - 1) * half])  # fmt: skip
    worst = -math.inf
    for xi, yi, pi in zip(x, y, psi, strict=True):
        px = xi + math.cos(pi) * lon - math.sin(pi) * lat
        py = yi + math.sin(pi) * lon + math.cos(pi) * lat
        for g in m.gates:
            inside = (px >= g.x_start) & (px <= g.x_end)
            if inside.any():
                exc = np.maximum(py[inside] - g.y_left, g.y_right - py[inside])
                worst = max(worst, float(exc.max()))
    return worst


def test_dynamic_rows_stay_within_the_friction_limit(dynamic20):
    cmp, _ = dynamic20
    peak = cmp.table["peak a_lat [m/s^2]"]
    # a run stopped at singular steering (the front wheel at 90 deg) has no
    # finite exact peak (the table's "-"): it did not complete, and its
    # samples up to the stop are within the limit too
    stopped = ~np.isfinite(peak)
    assert not np.any(cmp.table["completed"][stopped])
    for i in np.flatnonzero(stopped):
        r = cmp.results[i]
        assert str(r.status) == "singular_steering", (cmp.labels[i], r.status)
        assert np.nanmax(np.abs(r.lateral_accel)) <= MU_G * 1.01
    assert np.all(peak[~stopped] <= MU_G * 1.01), peak
    np.testing.assert_allclose(cmp.table["peak a_lat / (mu g) [-]"], peak / MU_G,
                               rtol=1e-12)  # fmt: skip
    # "beyond friction": the finished rows no; a stopped row's undefined peak
    # counts as beyond (the table cannot vouch for it)
    np.testing.assert_array_equal(cmp.table["beyond friction"], stopped)
    for lab, r in zip(cmp.labels, cmp.results, strict=True):
        # independent: a_y = dv_y/dt + u r from the sampled states (the
        # saturating tyre caps each axle's force at mu F_z)
        ok = np.isfinite(r.v_y)
        t, vy, yaw = r.t[ok], r.v_y[ok], r.yaw_rate[ok]
        u = 20.0
        ay = np.gradient(vy, t) + u * yaw
        assert np.max(np.abs(ay[2:-2])) <= MU_G * 1.01, lab
        # the exact peak is at or above every sample
        assert peak[cmp.labels.index(lab)] >= np.nanmax(np.abs(r.lateral_accel)) - 1e-9


def test_dynamic_table_names_the_lane_leavers(dynamic20):
    cmp, _ = dynamic20
    assert "left lane" in cmp.columns
    for i, r in enumerate(cmp.results):
        ok = np.isfinite(r.x)
        exc = _outline_excursion(COURSE, r.x[ok], r.y[ok], r.psi[ok], BMW.wheelbase)
        if abs(exc) > 2e-3:  # beyond the outline's sampling error
            assert bool(cmp.table["left lane"][i]) == (exc > 0), (cmp.labels[i], exc)
    # on this course and speed the ranking reverses against the kinematic
    # table: pure pursuit (no feedforward) leaves the lane least
    i_pp = cmp.labels.index("pure pursuit")
    assert cmp.table["max e [m]"][i_pp] == min(cmp.table["max e [m]"])
    md = cmp.to_markdown()
    assert "| left lane |" in md.splitlines()[0]


@pytest.mark.parametrize("label", ["paper, a = 0", "pure pursuit"])
def test_rows_equal_a_direct_simulate(dynamic20, label):
    cmp, ctrls = dynamic20
    plant = fws.LateralPlant(BMW, speed=20.0, model="dynamic", tyre="magic")
    gates = COURSE.gates
    # the documented start (first gate's entry) and duration (1.1 x the
    # x-span over V, plus 0.5 s)
    duration = 1.1 * (gates[-1].x_end - gates[0].x_start) / 20.0 + 0.5
    # compare runs the paper's law as a state-feedback controller and the
    # baselines through simulate's default engine ("auto": the compiled
    # engine runs their compiled laws); the direct run takes the same
    direct = fws.simulate(plant, COURSE.path, ctrls[label],
                          initial_state=(gates[0].x_start, 0.0, 0.0),
                          duration=duration, dt=0.01)  # fmt: skip
    assert direct.engine == cmp.results[cmp.labels.index(label)].engine
    i = cmp.labels.index(label)
    r = cmp.results[i]
    assert cmp.duration == pytest.approx(duration, rel=1e-15)
    np.testing.assert_allclose(r.t, direct.t, rtol=0, atol=1e-12)
    for name in ("x", "y", "psi", "e", "delta_f", "lateral_accel"):
        np.testing.assert_allclose(getattr(r, name), getattr(direct, name),
                                   rtol=1e-7, atol=1e-9, err_msg=name)  # fmt: skip
    pk = direct.peaks
    assert cmp.table["max e [m]"][i] == pytest.approx(pk.e.value, rel=1e-7)
    assert cmp.table["peak a_lat [m/s^2]"][i] == pytest.approx(
        pk.lateral_accel.value, rel=1e-7
    )
    assert cmp.table["max delta_f [deg]"][i] == pytest.approx(
        math.degrees(pk.delta_f.value), rel=1e-7
    )
    cones = COURSE.cones_hit(direct.x, direct.y, direct.psi, wheelbase=BMW.wheelbase)
    assert int(cmp.table["cones hit"][i]) == cones


def test_kinematic_rows_beyond_the_friction_circle_are_flagged():
    # the kinematic model has no tyre: the feedforward laws follow the
    # course, whose peak curvature 0.0559 1/m at 20 m/s asks for V^2 kappa =
    # 22.4 m/s^2 at R, over twice mu g
    plant = fws.LateralPlant(BMW, speed=20.0)
    ctrls = fws.default_controllers(BMW, speed=20.0)
    cmp = fws.compare(
        plant, COURSE, {k: ctrls[k] for k in ("paper, a = 0", "pure pursuit")}
    )
    use = cmp.table["peak a_lat / (mu g) [-]"]
    for i, r in enumerate(cmp.results):
        sampled = np.nanmax(np.abs(r.lateral_accel)) / MU_G
        assert use[i] >= sampled - 1e-12
        assert bool(cmp.table["beyond friction"][i]) == (use[i] > 1.0)
    i = cmp.labels.index("paper, a = 0")
    assert use[i] > 0.95 * 20.0**2 * 0.0559 / MU_G > 2.0
    assert bool(cmp.table["beyond friction"][i])


@pytest.fixture(scope="module")
def small():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35, friction=0.8)
    plant = fws.LateralPlant(veh, speed=10.0)
    # (the paper's law: the cheapest runs; the columns do not depend on it)
    ctrls = {
        f"paper, a = {a:g}": fws.double_root_gains(plant, ratio=a, pole=-1.0)
        for a in (0.0, -0.3)
    }
    return fws.compare(plant, COURSE, ctrls, offset=0.2, progress=False)


def test_to_pandas_holds_the_table(small):
    df = small.to_pandas()
    assert list(df.index) == list(small.labels)
    assert df.index.name == "controller"
    assert tuple(df.columns) == small.columns == COMPARISON_METRICS
    for name in small.columns:
        np.testing.assert_array_equal(df[name].to_numpy(), small.table[name])
    assert df["completed"].dtype == bool and df["left lane"].dtype == bool
    assert df["cones hit"].dtype.kind == "i"
    # friction use recomputed with mu = 0.8
    np.testing.assert_allclose(
        df["peak a_lat / (mu g) [-]"], df["peak a_lat [m/s^2]"] / (0.8 * 9.81),
        rtol=1e-12,
    )  # fmt: skip


def test_no_friction_no_friction_columns():
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=10.0)
    g = fws.double_root_gains(plant, ratio=0.0, pole=-1.0)
    cmp = fws.compare(plant, COURSE, {"paper": g})
    assert not set(FRICTION_METRICS) & set(cmp.table)
    assert cmp.columns == tuple(n for n in COMPARISON_METRICS
                                if n not in FRICTION_METRICS)  # fmt: skip
    assert "mu g" not in cmp.to_markdown()
    assert list(cmp.to_pandas().columns) == list(cmp.columns)


def test_left_lane_against_a_sampled_outline():
    rng = np.random.default_rng(7)
    g = COURSE.gates[1]
    decided = 0
    for _ in range(300):
        n = 3
        x = rng.uniform(g.x_start - 4.0, g.x_end + 1.0, n)
        y = rng.uniform(g.y_right - 0.5, g.y_left + 0.5, n) - 1.0
        psi = rng.normal(0.0, 0.3, n)
        exc = _outline_excursion(COURSE, x, y, psi, 2.7)
        if abs(exc) < 2e-3:
            continue
        decided += 1
        assert COURSE.left_lane(x, y, psi, wheelbase=2.7) == (exc > 0), (x, y, psi)
    assert decided > 250
    # a course without gates has no lane
    circle = fws.constant_radius()
    assert circle.left_lane([0.0], [50.0], [0.0], wheelbase=2.7) is False


@pytest.mark.parametrize(
    "kw, arg",
    [({"wheelbase": -1.0}, "wheelbase"), ({"wheelbase": math.nan}, "wheelbase")],
)
def test_left_lane_bad_input(kw, arg):
    with pytest.raises(ValueError, match=arg):
        COURSE.left_lane([0.0], [0.0], [0.0], **kw)
    with pytest.raises(ValueError, match="same length"):
        COURSE.left_lane([0.0, 1.0], [0.0], [0.0], wheelbase=2.7)


def test_progress_bar_only_when_asked(capsys):
    veh = fws.Vehicle(wheelbase=2.7, rear_to_cg=1.35)
    plant = fws.LateralPlant(veh, speed=10.0)
    ctrls = {"paper": fws.double_root_gains(plant, ratio=0.0, pole=-1.0)}
    fws.compare(plant, COURSE, ctrls)  # captured stderr is not a terminal
    assert capsys.readouterr().err == ""
    fws.compare(plant, COURSE, ctrls, progress=True)
    assert "compare" in capsys.readouterr().err
    with pytest.raises((TypeError, ValueError), match="progress"):
        fws.compare(plant, COURSE, ctrls, progress="yes")


def test_plot_labels_units_and_friction_limit(small):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cplt = small.plot()
    axes = cplt.axes[0]
    assert axes[0].get_xlabel() == "x [m]" and axes[0].get_ylabel() == "y [m]"
    for a in axes[1:]:
        assert a.get_xlabel() == "time t [s]"
        assert "[" in a.get_ylabel() and "]" in a.get_ylabel()
    levels = sorted(
        ln.get_ydata()[0] for ln in axes[3].get_lines() if ln.get_linestyle() == ":"
    )
    assert levels == pytest.approx([-0.8 * 9.81, 0.8 * 9.81])
    plt.close(cplt.figure)


def _cli(argv, capsys):
    from fws_control.cli import main

    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    cap = capsys.readouterr()
    return code, cap.out, cap.err.strip().splitlines()


@pytest.mark.parametrize(
    "argv, name",
    [
        (["--model", "dynamic"], "--vehicle"),
        (["--tyre", "magic"], "--tyre"),
        (["--model", "dynamic", "--vehicle", "bmw"], "--vehicle"),
    ],
)
def test_cli_compare_model_options_refused(argv, name, tmp_path, capsys):
    code, out, err = _cli(["compare", *argv, "--out", tmp_path / "c.png"], capsys)
    assert code == 2 and len(err) == 1 and name in err[0], err
    assert not list(tmp_path.iterdir())


def test_cli_compare_dynamic_magic(tmp_path, capsys):
    png = tmp_path / "c.png"
    argv = ["compare", "--manoeuvre", "iso3888-2", "--speed", "15", "--out", png]
    argv += ["--model", "dynamic", "--tyre", "magic", "--vehicle", "bmw-320i"]
    # two controllers: every row of the full set is checked in-process above
    argv += ["--controllers", "paper, a = 0", "pure pursuit"]
    code, out, err = _cli(argv, capsys)
    assert code == 0, err
    assert any(
        "V = 15 m/s, dynamic model (magic tyre)" in ln for ln in out.splitlines()
    )
    lines = [ln for ln in out.splitlines() if ln.startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    j = head.index("peak a_lat / (mu g) [-]")
    k = head.index("peak a_lat [m/s^2]")
    rows = [[c.strip() for c in ln.strip("|").split("|")] for ln in lines[2:]]
    assert [r[0] for r in rows] == ["paper, a = 0", "pure pursuit"]
    for r in rows:
        assert float(r[j]) <= 1.01
        assert float(r[k]) == pytest.approx(float(r[j]) * MU_G, rel=5e-3)
    assert png.stat().st_size > 0
