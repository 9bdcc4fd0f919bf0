"""The one version of UavViewerPy and its MAVLinkServer (pyproject.toml reads it from here)."""
__version__ = "0.6.0"
