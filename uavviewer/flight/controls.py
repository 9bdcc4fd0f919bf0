"""Take off / Land, Stop, RTL and Arm/Disarm buttons; they show the vehicle's state, not a guess.

In the air Disarm is the emergency motor stop: the drone falls. It is no longer a button beside Stop, the one a
pilot hits most under stress (one slip away, it only asked); the window places it in the mode's row, and in the air
it opens a menu whose one item, "Emergency motor stop…", asks first (as QGroundControl hides it behind a slider).
"""
from __future__ import annotations

from PyQt5.QtCore import QSize, Qt, pyqtSignal
from PyQt5.QtGui import QFontMetrics, QIcon
from PyQt5.QtWidgets import QAction, QGridLayout, QMenu, QProgressBar, QPushButton, QSizePolicy, QWidget

from ..widgets.icons import icon
from .phase import FlightPhase

__all__ = ["FlightControls"]

MENU_ARROW = 14                         # px the menu's arrow takes on Disarm in the air


def _icon(name: str) -> QIcon:
    return icon(name)


class FlightControls(QWidget):
    """Emits what the pilot asks for; ``set_vehicle`` makes the buttons match the vehicle."""

    takeoffRequested = pyqtSignal()
    landRequested = pyqtSignal()
    stopRequested = pyqtSignal()
    rtlRequested = pyqtSignal()
    armRequested = pyqtSignal()
    disarmRequested = pyqtSignal()          # in the air too: the window asks before an emergency motor stop
    cancelTakeoffRequested = pyqtSignal()   # a takeoff that has not left the ground: give the vehicle back

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._phase = FlightPhase.NO_VEHICLE
        self._armed = False
        self._cancellable = False
        self._shown: tuple | None = None        # the last set_vehicle arguments: nothing to redo when unchanged
        self.main_button = self._button("mainButton", "Take off", "takeoff")
        self.main_button.setMinimumHeight(44)
        self.progress = QProgressBar()
        self.progress.setObjectName("takeoffProgress")
        self.progress.setRange(0, 100)
        self.progress.setTextVisible(False)       # the phase line above says it in words
        self.progress.setFixedHeight(5)           # a thin bar along the main button's foot: nothing below moves
        self.progress.setAttribute(Qt.WA_TransparentForMouseEvents)   # a click there is the button's
        self.progress.setVisible(False)
        self.stop_button = self._button("stopButton", "Stop", "stop")
        self.rtl_button = self._button("rtlButton", "RTL", "rtl")
        self.arm_button = self._button("armButton", "Arm", "arm")       # laid out by the window, away from Stop
        self.arm_button.setSizePolicy(QSizePolicy.Fixed, QSizePolicy.Fixed)
        self.emergency_menu = QMenu(self.arm_button)                    # in the air: Disarm opens this, not a question
        self.emergency_menu.setObjectName("emergencyMenu")
        self.emergency_action = QAction(_icon("disarm"), "Emergency motor stop (the drone falls)…", self.emergency_menu)
        self.emergency_action.triggered.connect(self.disarmRequested)
        self.emergency_menu.addAction(self.emergency_action)
        for button, longest in ((self.stop_button, "Stop"), (self.rtl_button, "RTL"), (self.arm_button, "Disarm")):
            button.setMinimumWidth(self._width_for(button, longest))   # "Disarm" fits whatever the font
        self.arm_button.setMinimumWidth(self.arm_button.minimumWidth() + MENU_ARROW)
        self.stop_button.setToolTip("Hold position (Space)")
        self.rtl_button.setToolTip("Return to launch and land (R)")
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        grid.setSpacing(6)
        grid.addWidget(self.main_button, 0, 0, 1, 2)
        grid.addWidget(self.progress, 0, 0, 1, 2, Qt.AlignBottom)   # over the button: it never pushes the row
        grid.addWidget(self.stop_button, 1, 0)
        grid.addWidget(self.rtl_button, 1, 1)
        self.main_button.clicked.connect(self._main_clicked)
        self.stop_button.clicked.connect(self.stopRequested)
        self.rtl_button.clicked.connect(self.rtlRequested)
        self.arm_button.clicked.connect(self._arm_clicked)
        self.set_vehicle(FlightPhase.NO_VEHICLE, armed=False, connected=False)

    def _button(self, name: str, text: str, icon: str) -> QPushButton:
        b = QPushButton(_icon(icon), text)
        b.setObjectName(name)
        b.setIconSize(QSize(20, 20))
        b.setFocusPolicy(Qt.NoFocus)        # Space flies (Stop), it must never "click" a focused button
        b.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        b.setMinimumHeight(36)
        return b

    @staticmethod
    def _width_for(button: QPushButton, text: str) -> int:
        """Icon, spacing, the text in bold and the style sheet's padding and border (6 px 6 px, 1 px)."""
        button.ensurePolished()                 # the style sheet's font, not the default one
        font = button.font()
        font.setBold(True)
        return QFontMetrics(font).horizontalAdvance(text) + button.iconSize().width() + 6 + 2 * 6 + 2 + 4

    @property
    def phase(self) -> FlightPhase:
        return self._phase

    def set_vehicle(self, phase: FlightPhase, armed: bool, connected: bool,
                    progress: float | None = None, detail: str = "", waiting_for: tuple[str, ...] = (),
                    cancellable: bool = False) -> None:
        """``waiting_for``: what the vehicle still lacks before it can arm (the button says the takeoff will
        wait); ``cancellable``: a takeoff under way that has not left the ground (the button cancels it)."""
        self._phase, self._armed, self._cancellable = phase, armed, cancellable
        if (phase, armed, connected, progress, detail, waiting_for, cancellable) == self._shown:
            return
        self._shown = (phase, armed, connected, progress, detail, waiting_for, cancellable)
        b = self.main_button
        if phase is FlightPhase.ON_GROUND or phase is FlightPhase.NO_VEHICLE:
            wait = bool(waiting_for) and phase is FlightPhase.ON_GROUND
            b.setText("Take off when ready" if wait else "Take off")
            b.setIcon(_icon("takeoff"))
            b.setEnabled(connected and phase is FlightPhase.ON_GROUND)
            b.setProperty("action", "takeoff-wait" if wait else "takeoff")
            b.setToolTip(f"Waiting for {', '.join(waiting_for)}: the takeoff starts once the vehicle is ready"
                         if wait else "Take off (T)")
        elif phase is FlightPhase.TAKING_OFF and cancellable:
            b.setText("Cancel takeoff")
            b.setIcon(_icon("stop"))
            b.setEnabled(True)
            b.setProperty("action", "cancel")
            b.setToolTip("Nothing has left the ground: end the takeoff and leave the vehicle as it was")
        elif phase is FlightPhase.LANDING:
            b.setText("Landing…")
            b.setIcon(_icon("land"))
            b.setEnabled(False)
            b.setProperty("action", "landing")
        else:
            b.setText("Land")
            b.setIcon(_icon("land"))
            b.setEnabled(True)                  # Land is always available in the air
            b.setProperty("action", "land")
            b.setToolTip("Land where it is (L)")
        b.style().unpolish(b)
        b.style().polish(b)
        taking_off = phase is FlightPhase.TAKING_OFF and progress is not None
        self.progress.setVisible(taking_off)
        if taking_off:
            self.progress.setValue(int(round(100 * max(0.0, min(1.0, progress)))))
            self.progress.setToolTip(detail or f"taking off {self.progress.value()} %")
        self.stop_button.setEnabled(phase.airborne)
        self.rtl_button.setEnabled(phase.airborne or (connected and armed))
        a = self.arm_button
        a.setText("Disarm" if armed else "Arm")
        a.setIcon(_icon("disarm" if armed else "arm"))
        a.setEnabled(connected and (armed or not phase.airborne))     # in the air: the emergency motor stop
        emergency = armed and phase.airborne
        if a.property("action") != ("emergency" if emergency else ""):
            a.setProperty("action", "emergency" if emergency else "")
            a.setMenu(self.emergency_menu if emergency else None)     # in the air: a menu first, then a question
            a.setToolTip("Emergency motor stop, in this menu: the drone falls (asks first). To come down, use Land."
                         if emergency else "")
            a.style().unpolish(a)
            a.style().polish(a)

    def _main_clicked(self) -> None:
        if self._phase is FlightPhase.ON_GROUND:
            self.takeoffRequested.emit()
        elif self._phase is FlightPhase.TAKING_OFF and self._cancellable:
            self.cancelTakeoffRequested.emit()
        elif self._phase in (FlightPhase.TAKING_OFF, FlightPhase.FLYING):
            self.landRequested.emit()

    def _arm_clicked(self) -> None:
        (self.disarmRequested if self._armed else self.armRequested).emit()
