"""What a pilot reaches for besides the sticks, wired into the window: connecting (File › Connect, Recent,
Disconnect, Replay a flight), spoken alerts and the critical banner, the preflight dock, the Fly menu's guided
actions, and the home arrow.

Each feature is its own part (``connect/``, ``alerts/``, ``preflight/``, ``flight/guided.py``, their widgets); this only
builds them into the window's layout and menus and connects them to its adapter. The window keeps what is its own:
switching the drone it flies (:meth:`MainWindow.use_connection`). Widgets and actions are also set on the window
under the names tests and the other parts use (``window.connections``, ``window.alerts``, ...).
"""
from __future__ import annotations

import os

from PyQt5.QtCore import QObject, Qt
from PyQt5.QtWidgets import QAction, QDockWidget, QFileDialog, QMenu, QMessageBox

from driver.vehicle.state import Severity

from ..alerts.controller import AlertController
from ..connect.choice import Choice, Kind
from ..connect.controller import ConnectionController
from ..connect.dialog import ConnectDialog
from ..connect.leaving import leaving_words
from ..widgets.ask import ask
from ..flight.phase import flight_phase
from ..flight.guided import GuidedController
from ..replay.logs_folder import LogsFolder
from ..preflight.model import overall, preflight
from ..refresh import TEXT_HZ
from ..alerts.banner import AlertBanner
from ..widgets.home_arrow import HomeArrow
from ..preflight.panel import PreflightPanel

__all__ = ["PilotTools"]


class PilotTools(QObject):
    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = w = window
        self.connect_dialog: ConnectDialog | None = None
        self.leave_box: QMessageBox | None = None      # "leave the vehicle flying?" while open
        self._alerts(w)
        self._preflight(w)
        w.home_arrow = HomeArrow(w.attitude)
        self._guided(w)
        self._connecting(w)
        w.plan.panel.editToggled.connect(w.mapPanel.hold_still)     # editing a plan: the map stays still
        channel = w.refresh.add(TEXT_HZ, self.show)
        w.adapter.stateChanged.connect(lambda _s: channel.mark())

    def _alerts(self, w) -> None:
        w.alert_banner = AlertBanner()                              # under the link banner, above the instruments
        w.alertSlot.addWidget(w.alert_banner)
        w.actionMute = QAction("&Mute spoken alerts", w)
        w.actionMute.setObjectName("actionMute")
        w.actionMute.setShortcut("Ctrl+M")
        settings = w._qsettings
        w.alerts = AlertController(w.alert_banner, w.actionMute, muted=settings.value("alerts/muted", False, type=bool),
                                   parent=w)
        w.actionMute.toggled.connect(lambda on: settings.setValue("alerts/muted", on))
        w.adapter.stateChanged.connect(w.alerts.show_state)
        w.adapter.droneChanged.connect(lambda _d: w.alerts.reset())   # another vehicle: its state is no news

    def _preflight(self, w) -> None:
        w.preflight_panel = PreflightPanel()
        w.preflightDock = QDockWidget("Preflight", w)
        w.preflightDock.setObjectName("preflightDock")
        w.preflightDock.setWidget(w.preflight_panel)
        w.addDockWidget(Qt.RightDockWidgetArea, w.preflightDock)
        self.tab_preflight()
        w.menuView.addAction(w.preflightDock.toggleViewAction())

    def tab_preflight(self) -> None:
        """Preflight as a tab beside Telemetry, not in the way (also for a dock layout saved before it existed)."""
        w = self.window
        w.tabifyDockWidget(w.telemetryDock, w.preflightDock)
        w.telemetryDock.raise_()

    def _guided(self, w) -> None:
        w.guided = GuidedController(w.adapter, w, w)
        view = w.mapPanel.mapView
        view.menu_parts.append(w.guided.add_map_items)
        view.overlays.append(w.guided.paint_circle)
        w.guided.view_changed.connect(view.update)
        for ended in (w.flightControls.stopRequested, w.flightControls.landRequested, w.flightControls.rtlRequested):
            ended.connect(w.guided.cancel)
        w.menuFly = QMenu("F&ly", w)
        w.menuFly.addActions([w.guided.change_altitude_action, w.guided.circle_action])
        w.menuBar().insertMenu(w.menuSettings.menuAction(), w.menuFly)

    def _connecting(self, w) -> None:
        w.connections = ConnectionController(w._qsettings, parent=w)
        w.connections.opened.connect(w._connected)
        w.connections.failed.connect(self._failed)
        w.connections.trouble.connect(self._trouble)
        w.connections.busyChanged.connect(self._opening)
        w.connections.opened.connect(lambda _opened: self.connect_dialog is not None and self.connect_dialog.accept())
        w.adapter.stateChanged.connect(w.connections.confirm)
        w.connections.answered.connect(w.remember_last_connection)
        w.actionConnect = QAction("&Connect…", w)
        w.actionConnect.setShortcut("Ctrl+K")
        w.actionConnect.triggered.connect(self.show_connect)
        w.actionDisconnect = QAction("&Disconnect", w)
        w.actionDisconnect.triggered.connect(lambda: self.leave_then(w.connections.disconnect, disconnecting=True))
        w.actionOpenLog = QAction("Re&play a flight (.tlog)…", w)     # beside Review a log: the verb says which
        w.actionOpenLog.setObjectName("actionReplayFlight")
        w.actionOpenLog.setToolTip("Play a recorded .tlog in this window as if it were live, with seek and speed; "
                                   "the vehicle flown now is left (asked first in the air)")
        w.actionOpenLog.setShortcut("Ctrl+O")
        w.actionOpenLog.triggered.connect(lambda: self.open_flight_log())
        w.menuRecent = QMenu("&Recent connections", w)
        w.menuRecent.setObjectName("menuRecent")
        w.connections.recentChanged.connect(self.show_recent)
        self.show_recent()
        first = w.menuFile.actions()[0] if w.menuFile.actions() else None      # above Quit
        w.logs = LogsFolder(w, w)                # File › Open logs folder; its path in Help › About
        w.menuFile.insertActions(first, [w.actionConnect, w.menuRecent.menuAction(), w.actionDisconnect,
                                         w.actionOpenLog, w.logs.action])
        w.menuFile.insertSeparator(first)
        w.menuFile.insertAction(first, w.actionMute)
        w.menuFile.insertSeparator(first)

    # -- following the vehicle --------------------------------------------------------------------------------
    def show(self) -> None:
        """The preflight lines, the home arrow and what guided actions allow (TEXT_HZ)."""
        w = self.window
        s = w.readouts.shown
        if s is None:
            return
        checks = preflight(s)
        w.preflight_panel.set_checks(checks, overall(checks))
        w.home_arrow.set_state(s)
        w.guided.update_actions(s)

    # -- connecting -------------------------------------------------------------------------------------------
    def _failed(self, why: str) -> None:
        """Said where the pilot asked (File › Connect, while open), in the status bar and in Messages."""
        self.window.log_message(f"Not connected: {why}", Severity.WARNING)
        self.window.statusbar.showMessage(f"Not connected: {why}", 8000)
        if self.connect_dialog is not None:
            self.connect_dialog.show_problem(f"Not connected: {why}")

    def _trouble(self, why: str) -> None:
        """The system's reason the new link does not open, the moment the driver meets it."""
        self.window.log_message(why, Severity.WARNING)
        self.window.statusbar.showMessage(why)
        if self.connect_dialog is not None:
            self.connect_dialog.show_problem(why)

    def _opening(self, busy: bool) -> None:
        """While a new link is tried beside the old one, the status bar (and File › Connect) say both, and how long
        it is given."""
        c = self.window.connections
        if busy and c._opening is not None:
            still = f"; still flying {c.current.drone.description}" if c.connected else ""
            text = f"Connecting to {c._opening.label}: waiting up to {c.answer_timeout:g} s for a heartbeat{still}"
            self.window.statusbar.showMessage(text)
        else:
            text = ""
            self.window.statusbar.clearMessage()
        if self.connect_dialog is not None:
            self.connect_dialog.set_busy(busy, text)

    def connect_to(self, choice: Choice) -> None:
        """The address is checked first: a typo is said at once, and never after the question about leaving the
        vehicle in the air."""
        problem = choice.problem()
        if problem:
            self._failed(problem)
            return
        self.leave_then(lambda: self.window.connections.connect_to(choice))

    def leave_then(self, act, disconnecting: bool = False) -> None:
        """Connect elsewhere or disconnect: ``act()`` at once on the ground, after the pilot's yes in the air."""
        w = self.window
        s = w.adapter.state
        if w.adapter.replay is not None or not flight_phase(s).airborne:
            act()
            return
        if self.leave_box is not None:
            self.leave_box.reject()
        box = QMessageBox(QMessageBox.Warning, "Leave the flying vehicle?", leaving_words(s, disconnecting),
                          QMessageBox.NoButton, w)
        box.setObjectName("leaveQuestion")
        leave = box.addButton("Leave it flying", QMessageBox.DestructiveRole)
        box.addButton(QMessageBox.Cancel)
        box.setDefaultButton(QMessageBox.Cancel)
        box.setEscapeButton(QMessageBox.Cancel)

        def answered(b: QMessageBox) -> None:
            if b.clickedButton() is leave:
                act()
            b.deleteLater()
            if self.leave_box is b:
                self.leave_box = None
        self.leave_box = ask(box, answered)

    def show_recent(self) -> None:
        """File › Recent connections: one click connects again."""
        menu, connections = self.window.menuRecent, self.window.connections
        menu.clear()
        for choice in connections.recent():
            action = menu.addAction(choice.label)
            action.triggered.connect(lambda _checked=False, c=choice: self.connect_to(c))
        menu.setEnabled(not menu.isEmpty())

    def show_connect(self) -> None:
        """File › Connect: not modal, so the vehicle flown now stays in reach until the new one answers."""
        w = self.window
        if self.connect_dialog is not None:
            self.connect_dialog.raise_()
            self.connect_dialog.activateWindow()
            return
        dialog = ConnectDialog(w.connections.recent(), w)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        dialog.chosenConnection.connect(self.connect_to)
        dialog.finished.connect(lambda _r: setattr(self, "connect_dialog", None))
        self.connect_dialog = dialog
        dialog.show()

    def open_flight_log(self, path: str | None = None) -> None:
        """File › Replay a flight: a .tlog played in this window (``path``: chosen already, else asked)."""
        settings = self.window._qsettings
        if not path:
            folder = str(settings.value("connect/log_folder", "") or "")
            path, _ = QFileDialog.getOpenFileName(self.window, "Replay a flight", folder,
                                                  "Flight logs (*.tlog);;All files (*)")
        if path:
            settings.setValue("connect/log_folder", os.path.dirname(path))
            self.connect_to(Choice(Kind.REPLAY, path))
