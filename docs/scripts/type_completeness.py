"""Print pyright's type-completeness score of the public API; fail below 95 %.

Runs ``pyright --verifytypes fws_control --ignoreexternal --outputjson`` on
the package of this source tree and prints the score, the symbol counts and
the symbols whose type is not fully known, grouped by module. Exit status 1
if the score is below the floor (``--floor``, default 0.95), 2 if pyright
cannot run.

pyright is a Node.js program: the ``pyright`` package of the ``typing``
extra downloads it on its first run (then it works offline from its cache),
so this check is a script, not a test of the suite::

    python -m pip install -e ".[typing]"
    python docs/scripts/type_completeness.py
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: The lowest accepted share of public symbols with a fully known type.
FLOOR = 0.95


def _pyright() -> list[str]:
    exe = shutil.which("pyright")
    return [exe] if exe else [sys.executable, "-m", "pyright"]


def verify_types() -> dict:
    """pyright's ``--verifytypes`` report of this tree's fws_control (JSON)."""
    env = dict(os.environ)
    # this tree's package, not another install of it
    env["PYTHONPATH"] = os.pathsep.join(
        p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p
    )
    cmd = [*_pyright(), "--verifytypes", "fws_control", "--ignoreexternal"]
    proc = subprocess.run(
        [*cmd, "--outputjson"], cwd=ROOT, env=env, capture_output=True, text=True
    )
    try:
        return json.loads(proc.stdout)
    except json.JSONDecodeError:
        raise SystemExit(
            f"pyright did not run ({' '.join(cmd)}): exit status "
            f"{proc.returncode}\n{proc.stderr.strip() or proc.stdout.strip()}"
        ) from None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--floor", type=float, default=FLOOR)
    args = parser.parse_args(argv)
    try:
        report = verify_types()
    except SystemExit as exc:
        print(exc, file=sys.stderr)
        return 2
    tc = report["typeCompleteness"]
    score = float(tc["completenessScore"])
    unknown = collections.Counter()
    for sym in tc["symbols"]:
        if sym.get("isExported") and not sym.get("isTypeKnown", True):
            unknown[sym["name"].rsplit(".", 1)[0]] += 1
    print(f"pyright {report.get('version', '?')} --verifytypes fws_control")
    print(
        f"exported symbols: {tc['exportedSymbolCounts']['withKnownType']} known, "
        f"{tc['exportedSymbolCounts']['withAmbiguousType']} ambiguous, "
        f"{tc['exportedSymbolCounts']['withUnknownType']} unknown"
    )
    for where, count in unknown.most_common():
        print(f"  {count:4d}  {where}")
    print(f"type completeness score: {score:.1%} (floor {args.floor:.0%})")
    return 0 if score >= args.floor else 1


if __name__ == "__main__":
    sys.exit(main())
