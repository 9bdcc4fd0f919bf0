"""The windows the flying window opens besides itself (Setup, Parameters, a review, the inspector, Preferences...):
each fits the screen it opens on, comes back where the pilot left it (inside this screen), and never covers the
flight controls while they may be needed.

A secondary window opened for the first time stands beside the flight area (the window's central column: the
banners, the instruments, the sticks, Take off/Land, Stop, RTL, Arm and the mode), as large as the room there
allows; its content scrolls if it needs more (``widgets/dialog_fit.py``). Moved or resized by the pilot, it opens
there the next time (``windows/<its name>/geometry``), clamped to the screen. While the vehicle is armed or in the
air, none stands over the flight area: one that would is moved and shrunk beside it, at its opening and the moment
the vehicle arms or takes off. Questions (window-modal) are only fitted: the flight controls wait on them anyway.
"""
from __future__ import annotations

from PyQt5 import sip
from PyQt5.QtCore import QEvent, QObject, QPoint, QRect, QSettings, Qt, QTimer
from PyQt5.QtWidgets import QApplication, QWidget

from driver.vehicle.state import VehicleState

from ..flight.phase import flight_phase
from ..widgets.dialog_fit import fit_window

__all__ = ["SecondaryWindows", "GEOMETRY_KEY"]

GEOMETRY_KEY = "windows/{}/geometry"


class SecondaryWindows(QObject):
    """``window``: the flying window (its central widget is the flight area); ``qsettings``: where places are kept."""

    def __init__(self, window, qsettings: QSettings | None) -> None:
        super().__init__(window)
        self.window = window
        self._qsettings = qsettings
        self.guarding = False                 # armed or airborne: the flight area stays in view
        window.adapter.stateChanged.connect(self.show_state)
        QApplication.instance().installEventFilter(self)

    def close(self) -> None:
        QApplication.instance().removeEventFilter(self)

    # -- which windows ---------------------------------------------------------------------------------
    def is_secondary(self, widget: QObject) -> bool:
        """A window of this program other than the flying one: not a menu, list popup, tooltip or splash."""
        return (isinstance(widget, QWidget) and widget.isWindow() and widget is not self.window
                and widget.windowType() in (Qt.Window, Qt.Dialog))

    def shown(self) -> list[QWidget]:
        return [w for w in QApplication.topLevelWidgets() if w.isVisible() and self.is_secondary(w)]

    def flight_area(self) -> QRect:
        """The central column, on the screen: what no secondary window may cover while it matters."""
        central = self.window.centralWidget()
        return QRect(central.mapToGlobal(QPoint(0, 0)), central.size())

    def area(self) -> QRect:
        """The available area of the flying window's screen (with the window itself, where a virtual screen is
        smaller than the window)."""
        screen = self.window.screen() or QApplication.primaryScreen()
        free = screen.availableGeometry()
        frame = self.window.frameGeometry()
        return free if free.contains(frame) or not self.window.isVisible() else free.united(frame)

    # -- placing ---------------------------------------------------------------------------------------
    def fit(self, widget: QWidget, first: bool = False) -> None:
        """Fit ``widget``; beside the flight area when the vehicle is armed or airborne, or on its first opening
        (never over the controls by default), unless it is a question that holds the window anyway."""
        modal = widget.windowModality() != Qt.NonModal or (getattr(widget, "isModal", bool)())
        keep = [self.flight_area()] if (self.guarding or first) and not modal and self.window.isVisible() else []
        fit_window(widget, keep, self.area())

    def show_state(self, s: VehicleState) -> None:
        """Armed or airborne (a replay is neither): windows over the flight area step aside, now and as they open."""
        guarding = self.window.adapter.replay is None and (s.armed or flight_phase(s).airborne)
        if guarding == self.guarding:
            return
        self.guarding = guarding
        if guarding:
            area = self.flight_area()
            for widget in self.shown():
                if widget.frameGeometry().intersects(area):
                    self.fit(widget)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt's name)
        kind = event.type()
        if kind == QEvent.Show and not event.spontaneous() and self.is_secondary(watched):
            first = not self._restore(watched)
            self.fit(watched, first)
            # and once shown: a message box sizes itself as it shows (its text wrapped), after this filter
            QTimer.singleShot(0, lambda: not sip.isdeleted(watched) and watched.isVisible() and self.fit(watched, first))
        elif kind == QEvent.Hide and not event.spontaneous() and self.is_secondary(watched):
            self._remember(watched)
        return False

    # -- where the pilot left it -------------------------------------------------------------------------
    def _key(self, widget: QWidget) -> str:
        return GEOMETRY_KEY.format(widget.objectName()) if widget.objectName() and self._qsettings is not None \
            else ""

    def _restore(self, widget: QWidget) -> bool:
        """Its place from last time, if it has one (fitted to this screen afterwards)."""
        key = self._key(widget)
        saved = self._qsettings.value(key) if key else None
        if not saved:
            return False
        if widget.property("placed"):         # this very window was shown before: Qt kept its place
            return True
        widget.setProperty("placed", True)
        return widget.restoreGeometry(saved)

    def _remember(self, widget: QWidget) -> None:
        key = self._key(widget)
        if key:
            self._qsettings.setValue(key, widget.saveGeometry())
            widget.setProperty("placed", True)
