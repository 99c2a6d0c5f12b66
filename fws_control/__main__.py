"""``python -m fws_control``: the ``fws-control`` command line."""

from .cli import run

__all__: list[str] = []

if __name__ == "__main__":
    run()
