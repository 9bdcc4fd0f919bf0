"""The replay's seek bar: a click goes to the time under the pointer and a drag follows it.

A plain QSlider moves one page step towards a click on its groove (a tenth of the range at Qt's default, about
17 s of a 3-minute flight), which is not where the pilot clicked.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QSlider, QStyle, QStyleOptionSlider

__all__ = ["SeekSlider"]


class SeekSlider(QSlider):
    def __init__(self, parent=None) -> None:
        super().__init__(Qt.Horizontal, parent)

    def value_at(self, x: float) -> int:
        """The value whose handle would be centred at ``x`` (widget pixels), by the style's own geometry."""
        opt = QStyleOptionSlider()
        self.initStyleOption(opt)
        style = self.style()
        groove = style.subControlRect(QStyle.CC_Slider, opt, QStyle.SC_SliderGroove, self)
        handle = style.subControlRect(QStyle.CC_Slider, opt, QStyle.SC_SliderHandle, self)
        span = max(1, groove.width() - handle.width())
        return QStyle.sliderValueFromPosition(self.minimum(), self.maximum(),
                                              int(round(x - groove.x() - handle.width() / 2)), span,
                                              opt.upsideDown)

    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        """The handle jumps under the pointer first; Qt's own press then grabs it there, so a drag follows and
        the release (sliderReleased) seeks."""
        if event.button() == Qt.LeftButton:
            self.setSliderPosition(self.value_at(event.pos().x()))
        super().mousePressEvent(event)
