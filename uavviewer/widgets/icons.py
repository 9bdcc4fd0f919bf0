"""The app's SVG icons, with a greyed form for disabled buttons (Qt's own keeps a white SVG bright)."""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtGui import QColor, QIcon, QPainter, QPixmap

from .. import RESOURCES

__all__ = ["icon", "DISABLED_COLOUR"]

DISABLED_COLOUR = QColor("#56606b")      # the style sheet's disabled text colour
_SIZES = (16, 20, 24, 32, 40, 48)
_cache: dict[str, QIcon] = {}


def _greyed(pixmap: QPixmap) -> QPixmap:
    out = QPixmap(pixmap.size())
    out.setDevicePixelRatio(pixmap.devicePixelRatio())
    out.fill(Qt.transparent)
    p = QPainter(out)
    p.drawPixmap(0, 0, pixmap)
    p.setCompositionMode(QPainter.CompositionMode_SourceIn)       # the shape, in the disabled colour
    p.fillRect(out.rect(), DISABLED_COLOUR)
    p.end()
    return out


def icon(name: str) -> QIcon:
    """``resources/icons/<name>.svg``, its Disabled mode the same shape in the disabled text colour."""
    cached = _cache.get(name)
    if cached is not None:
        return cached
    source = QIcon(str(RESOURCES / "icons" / f"{name}.svg"))
    made = QIcon()
    for size in _SIZES:
        pixmap = source.pixmap(size, size)
        made.addPixmap(pixmap, QIcon.Normal)
        made.addPixmap(pixmap, QIcon.Active)
        made.addPixmap(_greyed(pixmap), QIcon.Disabled)
    _cache[name] = made
    return made
