"""docs/varying_speed.md quotes the table of examples/plot_varying_speed.py.

The example runs in the documentation build (sphinx-gallery), which records
its output; ``docs/conf.py`` compares the page's table with that output
(:data:`QUOTED_OUTPUT` there, a warning, fatal with ``-W``). Here: that
the page's table is complete (nine runs, each reaching its final time), and
that the comparison passes the page's own table and fails a changed one or
a missing output. The page's other number, the speed at which the
zero-sideslip ratio changes sign, is recomputed from the vehicle's data
with the closed form :math:`V_0 = \\sqrt{f C_r l_r/(m l_f)}` (the zero of the
numerator of :math:`a(V)`), and checked against the library's ratio on both
sides.
"""

from __future__ import annotations

import importlib.util
import logging
import math
import re
from pathlib import Path

import pytest

import fws_control as fws

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "varying_speed.md"


def _conf():
    """docs/conf.py as a module."""
    spec = importlib.util.spec_from_file_location(
        "fws_docs_conf", ROOT / "docs" / "conf.py"
    )
    conf = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(conf)
    return conf


def _quoted(text: str) -> str:
    return text.split("<!-- varying-speed-table -->")[1].split(
        "<!-- end-varying-speed-table -->"
    )[0]


def test_page_table_is_complete():
    rows = _conf().table_rows(_quoted(PAGE.read_text(encoding="utf-8")))
    assert rows[0].startswith("| scenario | controller |")
    assert len(rows) == 1 + 9  # header, three scenarios x three controllers
    # every run reached its final time (no status note in the table)
    assert all(re.fullmatch(r"\| .+ \| .+ \| [\d.]+ \| [\d.]+ \| (yes|no) \|", r)
               for r in rows[1:])  # fmt: skip


def test_build_compares_the_page_with_the_example_output(tmp_path):
    conf = _conf()
    conf._SKIP_GALLERY = False
    assert conf.QUOTED_OUTPUT["varying_speed"] == (
        "plot_varying_speed",
        "varying-speed-table",
    )
    page = PAGE.read_text(encoding="utf-8")
    rows = conf.table_rows(_quoted(page))

    class App:
        srcdir = str(tmp_path)

    def warnings(output):
        """The build's warnings for the page, with `output` recorded."""
        generated = tmp_path / "auto_examples" / "plot_varying_speed.rst"
        generated.parent.mkdir(exist_ok=True)
        generated.unlink(missing_ok=True)
        if output is not None:
            # as sphinx-gallery writes it: the code, then the output block
            code = '    print("|---|---|---|---|---|")\n'
            block = "".join(f"    {row}\n" for row in output)
            generated.write_text(
                f".. code-block:: Python\n\n{code}\n"
                f".. rst-class:: sphx-glr-script-out\n\n .. code-block:: none\n\n"
                f"{block}\n",
                encoding="utf-8",
            )
        # Sphinx's logger does not propagate to the root logger once a build
        # has run in this process (and its handlers may hold a closed
        # stream), so the records are caught on the check's own logger.
        records: list[logging.LogRecord] = []
        handler = logging.Handler(logging.WARNING)
        handler.emit = records.append  # type: ignore[method-assign]
        log = logging.getLogger("sphinx.fws_control.quoted")
        propagate = log.propagate
        log.addHandler(handler)
        log.propagate = False
        try:
            conf._check_quoted_output(App, "varying_speed", [page])
        finally:
            log.removeHandler(handler)
            log.propagate = propagate
        return [r.getMessage() for r in records]

    assert warnings(rows) == []
    changed = [rows[0], *rows[1:4], rows[4].replace("| 3.15 |", "| 3.16 |"), *rows[5:]]
    assert changed != rows
    (message,) = warnings(changed)
    assert "varying_speed" in message and "plot_varying_speed.py" in message
    assert len(warnings(rows[:-1])) == 1  # a row missing
    assert len(warnings(None)) == 1  # the example did not run


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
