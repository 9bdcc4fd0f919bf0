"""One line a pilot reads at a glance, always in view above the instruments: battery (against our own
thresholds), time left, flight time, the link, and the latest autopilot message. Stale values go grey and say
their age when the link is lost."""
from __future__ import annotations

import time

from PyQt5.QtCore import QSize, Qt
from PyQt5.QtGui import QPainter
from PyQt5.QtWidgets import QFrame, QHBoxLayout, QLabel, QSizePolicy, QVBoxLayout, QWidget

from driver.vehicle.battery import time_left
from driver.vehicle.state import BatteryAlarm, LinkStatus, Message, Severity, VehicleState
from ..flight.phase import NO_VEHICLE, flight_phase, no_vehicle_words
from ..flight.timer import clock_text
from ..widgets.messages_view import severity_color
from .panel import BAD, DIM, GOOD, NORMAL, WARN

__all__ = ["StatusStrip", "ALARM_COLOURS", "battery_text", "NO_VEHICLE"]


ALARM_COLOURS = {BatteryAlarm.UNKNOWN: DIM, BatteryAlarm.OK: GOOD, BatteryAlarm.WARNING: WARN,
                 BatteryAlarm.CRITICAL: BAD}


def battery_text(s: VehicleState) -> str:
    """"14.80 V (3.70/cell) 45 % · 1234 mAh · 6 min left", what is known of it."""
    b = s.battery
    parts = []
    if b.voltage is not None:
        parts.append(f"{b.voltage:.2f} V" + (f" ({b.cell_voltage:.2f}/cell)" if b.cell_voltage is not None else ""))
    if b.remaining is not None:
        parts.append(f"{b.remaining:.0f} %" + ("*" if b.remaining_estimated else ""))
    text = " ".join(parts) or "--"
    if b.consumed_mah is not None:
        text += f" · {b.consumed_mah:.0f} mAh"
    left = time_left(b) if flight_phase(s).airborne else None    # on the ground nothing is being used up
    if left is not None:
        text += (f" · {left / 60:.0f} min left" if left >= 60 else f" · {left:.0f} s left" if left > 0
                 else " · down to the reserve")
    if b.alarm is BatteryAlarm.CRITICAL:
        text = "CRITICAL " + text
    elif b.alarm is BatteryAlarm.WARNING:
        text = "LOW " + text
    return text


class ElidedLabel(QLabel):
    """One line that ends in "…" when the window is too narrow for it; the whole text is its tooltip."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setTextFormat(Qt.PlainText)
        self.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Fixed)
        self.setMinimumHeight(self.fontMetrics().height())

    def minimumSizeHint(self) -> QSize:  # noqa: N802
        return QSize(0, self.fontMetrics().height())

    def paintEvent(self, _event) -> None:  # noqa: N802
        p = QPainter(self)
        shown = self.fontMetrics().elidedText(self.text(), Qt.ElideRight, self.width())
        p.setPen(self.palette().color(self.foregroundRole()))
        p.drawText(self.rect(), int(Qt.AlignLeft | Qt.AlignVCenter), shown)


class StatusStrip(QFrame):
    """Battery · flight time · link · latest message; ``set_state`` each text refresh."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("statusStrip")
        self.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Fixed)
        lines = QVBoxLayout(self)
        lines.setContentsMargins(8, 2, 8, 2)
        lines.setSpacing(1)
        first, second = QHBoxLayout(), QHBoxLayout()
        first.setSpacing(14)
        second.setSpacing(14)
        lines.addLayout(first)
        lines.addLayout(second)
        self.battery = self._label("stripBattery", "Battery against our own thresholds (Settings › Preferences › "
                                   "Flying), whatever the vehicle's battery failsafe says")
        self.flight_time = self._label("stripFlightTime", "Flight time: time armed")
        self.link = self._label("stripLink", "The link to the vehicle: heartbeat age and packets a second")
        self.message = ElidedLabel()            # a line of its own: never squeezed out on a narrow window
        self.message.setObjectName("stripMessage")
        first.addWidget(self.battery)
        first.addStretch(1)
        first.addWidget(self.link)
        second.addWidget(self.flight_time)
        second.addWidget(self.message, 1)
        self.colours: dict[str, str] = {}
        self._last_message: Message | None = None

    def _label(self, name: str, tip: str) -> QLabel:
        label = QLabel("--")
        label.setObjectName(name)
        label.setToolTip(tip)
        label.setTextFormat(Qt.PlainText)
        font = label.font()
        font.setBold(True)                      # set here, not by style sheet: the size hint knows it at once
        label.setFont(font)
        return label

    def _put(self, label: QLabel, text: str, colour: str) -> None:
        if label.text() != text:
            label.setText(text)
        if self.colours.get(label.objectName()) != colour:
            self.colours[label.objectName()] = colour
            label.setStyleSheet(f"color: {colour}; font-weight: bold;")
            label.updateGeometry()

    def colour(self, label: QLabel) -> str:
        return self.colours.get(label.objectName(), NORMAL)

    def set_state(self, s: VehicleState, flight_seconds: float, now: float | None = None) -> None:
        now = time.time() if now is None else now
        known = bool(s.mode) and s.link.status is not LinkStatus.WAITING
        lost = s.link.status in (LinkStatus.LOST, LinkStatus.CLOSED)
        age = s.link.heartbeat_age
        stale = f" ({age:.0f} s old)" if lost and age is not None else (" (stale)" if lost else "")
        if not known:
            self._put(self.battery, "Battery --", DIM)
        else:
            self._put(self.battery, "Battery " + battery_text(s) + stale,
                      DIM if lost else ALARM_COLOURS[s.battery.alarm])
        self._put(self.flight_time, f"Flight {clock_text(flight_seconds)}", DIM if lost or not s.armed else NORMAL)
        if s.link.replay and not s.link.replay_ended:      # a recording: nothing here is live
            self._put(self.link, "Replay · recorded, not live", NORMAL)
        elif s.link.status is LinkStatus.OK:
            self._put(self.link, f"Link OK · {s.link.packets_per_s:.0f} pkt/s", GOOD)
        elif lost and not s.mode:
            self._put(self.link, no_vehicle_words(s), DIM)
        elif s.link.replay_ended:
            self._put(self.link, s.link.ended_words, DIM)
        elif lost:
            self._put(self.link, "LINK LOST" + (f" · {age:.0f} s" if age is not None else ""), BAD)
        else:
            self._put(self.link, NO_VEHICLE, DIM)
        vehicle_lines = [m for m in s.messages if m.source == "vehicle"]
        latest = vehicle_lines[-1] if vehicle_lines else None
        if latest is None:
            self._put(self.message, "No message from the autopilot yet", DIM)
            return
        ago = max(0.0, now - latest.time)
        when = time.strftime("%H:%M:%S", time.localtime(latest.time))
        self._put(self.message, f"{when} {latest.text}", severity_color(latest.severity)   # as in Messages
                  if latest.severity <= Severity.WARNING else DIM if ago > 60 else NORMAL)
        self.message.setToolTip(f"{latest.text}\n\nThe autopilot's latest message, {ago:.0f} s ago "
                                "(all of them in Messages)")
