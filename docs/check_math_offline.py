"""Check that the built documentation renders its math without a network.

Opens the theory page of ``docs/_build/html`` in headless Chromium (no
network needed: MathJax is bundled by the ``sphinx-mathjax-offline``
extension into ``_static/mathjax``), dumps the DOM after the scripts ran and
takes a screenshot. The check passes when

* the page loads MathJax from the build itself, not from a CDN;
* the DOM holds rendered MathJax output (``mjx-container`` elements), at
  least one per math element of the page;
* no raw TeX delimiters ``\\(`` ... ``\\)`` or ``\\[`` ... ``\\]`` are left
  in the visible text.

Usage::

    python docs/check_math_offline.py            # build first if needed
    python docs/check_math_offline.py --page errata.html --shot /tmp/e.png

Needs Chromium (Debian: ``apt-get install chromium``). Exit status 0 on
success, 1 if math did not render, 2 if Chromium or the build is missing.
"""

from __future__ import annotations

import argparse
import html
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
HTML = DOCS / "_build" / "html"

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--hide-scrollbars",
    # MathJax typesets asynchronously: give the page's scripts time.
    "--virtual-time-budget=15000",
]


def find_chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def build_docs() -> None:
    subprocess.run(
        [sys.executable, "-m", "sphinx", "-b", "html", str(DOCS), str(HTML)],
        check=True,
    )


def run_chromium(chromium: str, url: str, *args: str) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory() as profile:
        return subprocess.run(
            [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args, url],
            capture_output=True,
            text=True,
            timeout=180,
        )


def check_dom(dom: str, source: str) -> list[str]:
    """Problems found in the rendered DOM (empty if the math rendered)."""
    problems = []
    scripts = re.findall(r'<script[^>]+src="([^"]*mathjax[^"]*)"', source, re.I)
    if not scripts:
        problems.append("the page loads no MathJax script")
    remote = [s for s in scripts if re.match(r"(https?:)?//", s)]
    if remote:
        problems.append(f"MathJax is loaded from the network: {remote}")
    n_math = len(re.findall(r'class="[^"]*\bmath\b', source))
    n_rendered = len(re.findall(r"<mjx-container\b", dom))
    if n_rendered == 0:
        problems.append("no rendered math (no <mjx-container> in the DOM)")
    elif n_rendered < n_math:
        problems.append(f"{n_rendered} rendered of {n_math} math elements")
    # Visible text: drop scripts, styles and tags; raw TeX would remain.
    text = re.sub(r"<(script|style)\b.*?</\1>", " ", dom, flags=re.S | re.I)
    text = html.unescape(re.sub(r"<[^>]+>", " ", text))
    raw = re.findall(r"\\\(.{0,40}?\\\)|\\\[.{0,40}?\\\]", text, flags=re.S)
    if raw:
        problems.append(f"{len(raw)} raw TeX spans left, e.g. {raw[0]!r}")
    return problems


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--page", default="theory.html", help="page of the build")
    ap.add_argument(
        "--shot", type=Path, default=HTML / "_math_check.png", help="screenshot"
    )
    ap.add_argument("--build", action="store_true", help="rebuild the docs first")
    args = ap.parse_args(argv)
    chromium = find_chromium()
    if chromium is None:
        print("chromium not found (apt-get install chromium)", file=sys.stderr)
        return 2
    page = HTML / args.page
    if args.build or not page.exists():
        build_docs()
    if not page.exists():
        print(f"{page} not found after the build", file=sys.stderr)
        return 2
    url = page.as_uri()
    dom = run_chromium(chromium, url, "--dump-dom").stdout
    args.shot.parent.mkdir(parents=True, exist_ok=True)
    run_chromium(chromium, url, f"--screenshot={args.shot}", "--window-size=1280,1600")
    problems = check_dom(dom, page.read_text(encoding="utf-8"))
    n = len(re.findall(r"<mjx-container\b", dom))
    print(f"{args.page}: {n} rendered math elements; screenshot {args.shot}")
    for p in problems:
        print(f"FAIL: {p}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
