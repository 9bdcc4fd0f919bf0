"""A window's menu by object name, made before Settings when the window has none yet: features add their entries
to menus they share (Vehicle, Tools) without knowing which feature made it first."""
from __future__ import annotations

from PyQt5.QtWidgets import QMainWindow, QMenu

__all__ = ["menu_named"]


def menu_named(window: QMainWindow, name: str, title: str) -> QMenu:
    menu = window.findChild(QMenu, name)
    if menu is None:
        menu = QMenu(title, window.menuBar())
        menu.setObjectName(name)
        settings = window.findChild(QMenu, "menuSettings")
        window.menuBar().insertMenu(settings.menuAction() if settings is not None else None, menu)
    return menu
