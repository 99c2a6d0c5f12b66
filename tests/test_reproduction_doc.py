"""docs/reproduction.md quotes simulation results: keep its table in step.

The Figs. 6-9 table of the page is recomputed with the code the page names
and compared cell by cell at the printed precision, so an edit of the
engine, the metrics or the design that changes a quoted number fails here
instead of leaving the page stale. The physics behind the numbers is tested
elsewhere (engine against the python-control reference, metrics against
closed forms).
"""

import math
import re
from pathlib import Path

import numpy as np
import pytest

import fws_control as fws
from fws_control.paper import PAPER_VEHICLE
from fws_control.paper.scenarios import (
    feedback_only_steady_state,
    fig6_to_9_responses,
)

PAGE = Path(__file__).resolve().parents[1] / "docs" / "reproduction.md"


def _table_rows():
    text = PAGE.read_text(encoding="utf-8")
    start = text.index('### Figs. 6–9, λ0 = −1, `model="exact"`')
    rows = {}
    lines = text[start:].splitlines()[1:]
    table = [ln for ln in lines[: lines.index("", 2)] if ln.startswith("|")]
    for line in table[2:]:  # skip the header and the separator
        cells = [c.strip() for c in line.strip("|").split("|")]
        fig = int(cells[0].split()[0])
        rows[fig, float(cells[1])] = cells
    return rows


def _matches(printed: str, value: float) -> bool:
    """True if `value` rounds to the printed decimal string."""
    decimals = len(printed.split(".")[1]) if "." in printed else 0
    return math.isclose(round(value, decimals), float(printed), abs_tol=1e-12)


@pytest.fixture(scope="module")
def responses():
    return fig6_to_9_responses(model="exact", dt=0.005)


def test_figs_6_to_9_table_matches_simulation(responses):
    rows = _table_rows()
    assert len(rows) == 20
    checked = 0
    for fig, resp in responses.items():
        m = fws.tracking_metrics(resp.result)
        for i, a in enumerate(resp.ratios):
            cells = rows[fig, float(a)]
            status = str(m.status[i])
            assert cells[4].startswith(status), (fig, a, cells[4], status)
            if status != "ok":
                continue
            k1 = float(resp.result.k1[i])
            k2 = float(resp.result.k2[i])
            quoted = {
                2: k1,
                3: k2,
                5: m.peak_lateral_accel[i],
                6: m.settling_time[i],
                7: m.rms_error[i],
                9: np.degrees(m.peak_delta_f[i]),
            }
            for col, value in quoted.items():
                assert _matches(cells[col], float(value)), (
                    fig,
                    a,
                    col,
                    cells[col],
                    value,
                )
                checked += 1
    assert checked >= 90


def test_quoted_steady_state_errors_of_feedback_only():
    """The 5-1 row quotes e_ss for curve_5; recompute them analytically."""
    text = PAGE.read_text(encoding="utf-8")
    quoted = re.search(r"`curve_5`: \$e_\{ss\}\$ = ([^m]+) m", text)[1]
    values = [float(v.replace("−", "-")) for v in quoted.split(",")]
    for a, e_q in zip((-1.0, -0.5, 0.0, 0.5), values, strict=True):
        plant = fws.LateralPlant(PAPER_VEHICLE, speed=5.0, curvature=0.1)
        g = fws.double_root_gains(plant, ratio=a, pole=-1.0)
        ss = feedback_only_steady_state(PAPER_VEHICLE, g, curvature=0.1)
        assert _matches(f"{e_q:.2f}", float(ss.e))
