"""sphinx-mathjax-offline, declared safe for parallel builds.

The extension (0.0.2) sets ``mathjax_path`` and copies its MathJax files
into ``_static`` when the build finishes; it keeps nothing per document.
Its ``setup`` returns no metadata, so Sphinx assumes it unsafe and, with
``-j``, reads the pages one after the other with a warning (an error under
``-W``). This shim loads it and declares what it is.
"""

from __future__ import annotations

import importlib
from typing import Any


def setup(app: Any) -> dict[str, bool]:
    # (the distribution's module name has hyphens: no import statement)
    importlib.import_module("sphinx-mathjax-offline").setup(app)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
