"""Room for the Plan list beside the map: without it the list showed 1 row at 1366×768 and none at 1280×720.

While Plan is shown, the tabs behind it and behind the map (Preflight, Shots, Plots, Messages: not in view anyway; the
latest autopilot message is in the status strip) step out, so no tab bar takes height, and the Plan dock gets the height its panel needs with its list showing
:data:`~uavviewer.plan.panel.ROWS_IN_VIEW` rows; the map has the rest of the column. Where the column is short
(1024×600) the map's title bar and status line step out too and the list keeps at least
:data:`~uavviewer.plan.panel.ROWS_AT_LEAST` rows, Upload above them in view. Never wider: the flight
controls beside it stay where they are. Plan closed: the tabs come back as they were.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QDockWidget, QWidget

__all__ = ["make_room_for_plan"]

_STEPPED_OUT = "_plan_stepped_out"       # the window's docks that stepped out for Plan


def make_room_for_plan(window, dock, on: bool) -> None:
    if on:
        keep = (dock, window.mapDock, window.telemetryDock)
        behind = [d for d in window.findChildren(QDockWidget)       # every feature's tab, whoever added it
                  if d not in keep and d.isVisible() and not d.isFloating()
                  and window.dockWidgetArea(d) == window.dockWidgetArea(dock)
                  and window.tabifiedDockWidgets(d)]                  # a tab, not a dock of its own
        for d in behind:
            d.hide()
        setattr(window, _STEPPED_OUT, behind)
        window.mapDock.setTitleBarWidget(QWidget())     # "Map" over the map: its height goes to the list,
        window.mapPanel.statusLabel.hide()              # and the map's status line's
        window.mapPanel.layout().activate()
        window.mapDock.raise_()
        dock.raise_()
        window.layout().activate()               # the docks' heights as they are now, without the tab bars
        scroll = dock.widget()                   # the panel in its scroll area
        panel = scroll.widget()                  # a PlanPanel: its lines above the list, wrapped at this width,
        width = scroll.width() - scroll.verticalScrollBar().sizeHint().width()   # and the list's own minimum
        above = panel.heightForWidth(width) if panel.hasHeightForWidth() else 0  # (the list asks for no more)
        need = max(panel.minimumSizeHint().height(), above + panel.tabs.minimumHeight()) \
            + getattr(panel, "wanted_rows_height", 0) + dock.height() - scroll.height()
        total = dock.height() + window.mapDock.height()
        window.resizeDocks([dock, window.mapDock], [need, max(1, total - need)], Qt.Vertical)
    else:
        for d in getattr(window, _STEPPED_OUT, []):
            d.show()
        setattr(window, _STEPPED_OUT, [])
        window.mapDock.setTitleBarWidget(None)
        window.mapPanel.statusLabel.show()
        window.mapDock.raise_()
        window.telemetryDock.raise_()
