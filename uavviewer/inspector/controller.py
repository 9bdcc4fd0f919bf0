"""Tools › MAVLink inspector: the menu entry and its window, fed by the window's adapter."""
from __future__ import annotations

from PyQt5.QtCore import QObject
from PyQt5.QtWidgets import QAction

from ..widgets.menus import menu_named

from .view import InspectorWindow

__all__ = ["InspectorController"]


class InspectorController(QObject):
    def __init__(self, window, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.window = window
        self.view: InspectorWindow | None = None
        self.action = QAction("&MAVLink inspector", window)
        self.action.setToolTip("Every message the vehicle sends, from every component: rate, values, plot")
        self.action.triggered.connect(self.show)
        menu_named(window, "menuTools", "&Tools").addAction(self.action)

    def show(self) -> InspectorWindow:
        if self.view is None:
            self.view = InspectorWindow(self.window.adapter.inspection, self.window)
        self.view.show()
        self.view.raise_()
        return self.view

    def close(self) -> None:
        if self.view is not None:
            self.view.close()
