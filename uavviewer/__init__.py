"""UavViewerPy: a ground station to fly a MAVLink drone from a laptop.

The window sees the vehicle only through :class:`driver.api.Drone`, so the
embedded driver and a remote (Ice) client are interchangeable.
"""
from pathlib import Path

RESOURCES = Path(__file__).resolve().parent.parent / "resources"

__all__ = ["RESOURCES"]
