"""``python -m fws_control``: the ``fws-control`` command line."""

import sys

from .cli import main

__all__: list[str] = []

if __name__ == "__main__":
    sys.exit(main())
