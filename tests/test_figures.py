"""Figures of the paper and the reproduce summary."""

import re

import matplotlib.pyplot as plt
import numpy as np
import pytest

import fws_control as fws
from fws_control.figures import FIGURES

PNG = b"\x89PNG\r\n\x1a\n"
F, LAM = 2.7, -1.0


def _eq41(V, a):
    """Paper eq. (41): straight-path gains (valid in both models)."""
    k1 = F * LAM**2 / (V**2 * (1 - a))
    k2 = -LAM * F / (V * (1 - a)) * (2 + LAM * a * F / (V * (1 - a)))
    return k1, k2


def _rows(table):
    out = []
    for line in table.splitlines()[2:]:
        out.append([c.strip() for c in line.strip("|").split("|")])
    return out


def test_gains_table_straight_rows_match_eq41():
    table = fws.gains_table(
        ratios=[-1.5, -0.5, 0.5, 1.0], cases=[(5.0, 0.0), (20.0, 0.0)]
    )
    rows = _rows(table)
    assert len(rows) == 8
    for row in rows:
        V, _, a = (float(x) for x in row[:3])
        if a == 1.0:
            assert "uncontrollable" in row[-1]
            continue
        k1, k2 = _eq41(V, a)
        for col in (3, 5):  # exact and paper agree on a straight path
            assert float(row[col]) == pytest.approx(k1, abs=1e-5)
            assert float(row[col + 1]) == pytest.approx(k2, abs=1e-5)
        assert row[-1] == "-1.000, -1.000"


def test_gains_table_curved_row_poles():
    (row,) = _rows(fws.gains_table(ratios=[0.0], cases=[(5.0, 0.1)]))
    # Paper eq. (44) for a = 0; then the exact characteristic polynomial
    # lambda^2 + (V c k2/f) lambda + V^2 (c k1/f + kappa^2), c = 1 + f^2 kappa^2.
    V, kap = 5.0, 0.1
    k1 = F * (LAM**2 / V**2 - kap**2)
    k2 = -2 * LAM * F / V
    assert float(row[5]) == pytest.approx(k1, abs=1e-5)
    assert float(row[6]) == pytest.approx(k2, abs=1e-5)
    c = 1 + F**2 * kap**2
    ref = np.sort(np.roots([1, V * c * k2 / F, V**2 * (c * k1 / F + kap**2)]).real)
    got = np.sort([float(x) for x in row[-1].split(",")])
    np.testing.assert_allclose(got, ref, atol=1e-3)


@pytest.mark.parametrize("name", sorted(FIGURES))
def test_every_figure_draws(name):
    fig = fws.make_figure(name, quick=True)
    assert len(fig.axes) >= 1
    for ax in fig.axes:
        if ax.has_data():
            assert ax.get_xlabel() and ax.get_ylabel()
    plt.close(fig)


def test_make_figure_bad_name():
    with pytest.raises(ValueError, match="name must be one of"):
        fws.make_figure("fig1")
    with pytest.raises(ValueError, match="model"):
        fws.make_figure("fig2", model="linear")


def test_reproduce_subset_writes_pngs_and_summary(tmp_path):
    res = fws.reproduce(
        tmp_path / "out",
        quick=True,
        progress=False,
        dpi=40,
        names=["fig2", "extra_turning_radius"],
    )
    assert [p.name for p in res.figures] == ["fig2.png", "extra_turning_radius.png"]
    for p in res.figures:
        assert p.read_bytes()[:8] == PNG
    text = res.summary.read_text()
    assert "fig2.png" in text and "Double-root gains" in text
    # The a = -1 straight row of the summary gives eq. (41) at 5 m/s.
    k1, k2 = _eq41(5.0, -1.0)
    assert re.search(rf"\| 5 \| 0 \| -1 \| {k1:.5f} \| {k2:.5f} \|", text)
    with pytest.raises(ValueError, match="names"):
        fws.reproduce(tmp_path / "x", names=["fig99"], progress=False)
