"""docs/varying_speed.md quotes the table of examples/plot_varying_speed.py.

The example is run as a script (as tests/test_examples.py runs the others)
and the table it prints must be the page's, row by row. The page's other
number, the speed at which the zero-sideslip ratio changes sign, is
recomputed from the vehicle's data with the closed form
:math:`V_0 = \\sqrt{f C_r l_r/(m l_f)}` (the zero of the numerator of
:math:`a(V)`), and checked against the library's ratio on both sides.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from test_examples import run_example

import fws_control as fws

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "varying_speed.md"


def _table(text: str) -> list[str]:
    return [
        line.strip()
        for line in text.splitlines()
        if line.startswith("| ") and not line.startswith("| scenario")
    ]


def test_page_table_is_the_example_output(tmp_path):
    out = run_example("plot_varying_speed.py", tmp_path)
    printed = _table(out)
    assert len(printed) == 9
    page = PAGE.read_text(encoding="utf-8")
    block = page.split("<!-- varying-speed-table -->")[1].split(
        "<!-- end-varying-speed-table -->"
    )[0]
    assert _table(block) == printed
    # every run reached its final time (no status note in the table)
    assert all(re.fullmatch(r"\| .+ \| .+ \| [\d.]+ \| [\d.]+ \| (yes|no) \|", r)
               for r in printed)  # fmt: skip


def test_phase_switch_speed():
    veh = fws.vehicles.BMW_320I
    f, l_r = veh.wheelbase, veh.rear_to_cg
    l_f = f - l_r
    v0 = math.sqrt(f * veh.cornering_rear * l_r / (veh.mass * l_f))
    page = " ".join(PAGE.read_text(encoding="utf-8").split())
    quoted = float(re.search(r"= ([\d.]+)\$? m/s for this vehicle", page).group(1))
    assert quoted == pytest.approx(round(v0, 1), abs=1e-12)
    assert fws.zero_sideslip_ratio(veh, speed=v0 * 0.999) < 0.0
    assert fws.zero_sideslip_ratio(veh, speed=v0 * 1.001) > 0.0
    # the parking-lot exit crosses it: 3 m/s -> 22 m/s
    assert 3.0 < v0 < 22.0
