"""fws_control: path tracking of automated vehicles with four-wheel steering."""

from .vehicle import Vehicle

__all__ = ["Vehicle"]
__version__ = "0.1.0"
