"""UavViewerPy: a ground station to fly a MAVLink drone from a laptop.

The window sees the vehicle only through :class:`driver.api.Drone`, so the
embedded driver and a remote (Ice) client are interchangeable.
"""
from pathlib import Path

from driver.version import __version__

_PACKAGE = Path(__file__).resolve().parent
#: .ui files, style sheet and icons: package data when installed (uavviewer/resources, see pyproject.toml), in a
#: checkout resources/ beside the package
RESOURCES = _PACKAGE / "resources" if (_PACKAGE / "resources").is_dir() else _PACKAGE.parent / "resources"

__all__ = ["RESOURCES", "__version__"]
