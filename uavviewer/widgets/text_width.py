"""Widths reserved for a control's longest text, so that a text changing with the state moves nothing."""
from __future__ import annotations

__all__ = ["width_for"]


def width_for(widget, text: str) -> int:
    """How wide ``widget`` (a label or a button) is with ``text`` in it, in the style it is drawn with."""
    widget.ensurePolished()
    shown, reserved = widget.text(), widget.minimumWidth()
    widget.setMinimumWidth(0)                  # a label's size hint grows to its minimum: measure the text alone
    widget.setText(text)
    width = widget.sizeHint().width()
    widget.setText(shown)
    widget.setMinimumWidth(reserved)
    return width
