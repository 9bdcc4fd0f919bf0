"""The numbers a pilot glances at: mode, battery, GPS, height, speeds, link health and its protection."""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QFrame, QGridLayout, QLabel, QSizePolicy, QWidget

from driver.vehicle.state import BatteryAlarm, LandedState, LinkStatus, SigningStatus, VehicleState
from ..flight.phase import no_vehicle_words
from ..connect.security import SIGNING_WARNINGS, foreign_text, foreign_tooltip, signed_frames
from ..units import fmt

__all__ = ["TelemetryPanel"]

NORMAL = "#e6ebf0"
GOOD = "#5fd068"
WARN = "#ffb020"
BAD = "#ff4d4d"
DIM = "#7d8792"

ROWS = [("mode", "Mode"), ("armed", "Armed"), ("landed", "Landed state"), ("battery", "Battery"),
        ("gps", "GPS"), ("altitude", "Altitude (home)"), ("ground_speed", "Ground speed"),
        ("climb", "Climb rate"), ("heading", "Heading"), ("home", "From home"),
        ("heartbeat", "Heartbeat"), ("packets", "Packets/s"), ("loss", "Link loss"), ("signing", "Signing"),
        ("signed", "Signed frames"), ("foreign", "Foreign packets")]

def _num(value: float | None, unit: str, digits: int = 1) -> str:
    return fmt(value, digits, unit)


class TelemetryPanel(QFrame):
    """A two-column list of labelled values; colours warn, the text says why."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("telemetryPanel")
        self.setSizePolicy(QSizePolicy.Preferred, QSizePolicy.Expanding)
        grid = QGridLayout(self)
        grid.setContentsMargins(10, 10, 10, 10)
        grid.setVerticalSpacing(6)
        # the dock's title says TELEMETRY; this line only speaks when the values are stale
        self.stale_label = QLabel("")
        self.stale_label.setObjectName("staleLabel")
        self.stale_label.setStyleSheet(f"color: {BAD}; font-weight: bold;")
        self.stale_label.setWordWrap(True)
        self.stale_label.setVisible(False)
        grid.addWidget(self.stale_label, 0, 0, 1, 2)
        self._values: dict[str, QLabel] = {}
        for row, (key, text) in enumerate(ROWS, start=1):
            name = QLabel(text)
            name.setObjectName("telemetryName")
            value = QLabel("--")
            value.setObjectName("telemetryValue")
            value.setAlignment(Qt.AlignRight | Qt.AlignVCenter)
            value.setTextInteractionFlags(Qt.TextSelectableByMouse)
            grid.addWidget(name, row, 0)
            grid.addWidget(value, row, 1)
            self._values[key] = value
        grid.setRowStretch(len(ROWS) + 1, 1)
        self._colors: dict[str, str] = {}
        self._stale = False
        self._security_unknown = ""

    # -- for tests and tooltips ----------------------------------------------------------------
    def text(self, key: str) -> str:
        return self._values[key].text()

    def color(self, key: str) -> str:
        return self._colors.get(key, NORMAL)

    def tooltip(self, key: str) -> str:
        return self._values[key].toolTip()

    def set_security_unknown(self, reason: str) -> None:
        """The link's protection cannot be seen from here (a remote drone): its rows say "--" and why."""
        self._security_unknown = reason

    def _put(self, key: str, text: str, color: str = NORMAL, tooltip: str | None = None) -> None:
        if self._stale:
            color = DIM
        label = self._values[key]
        if label.text() != text:
            label.setText(text)
        if tooltip is not None and label.toolTip() != tooltip:
            label.setToolTip(tooltip)
        if self._colors.get(key) != color:
            self._colors[key] = color
            label.setStyleSheet(f"color: {color};")

    # -- values in ------------------------------------------------------------------------------
    def set_state(self, s: VehicleState) -> None:
        """Before the first heartbeat nothing is known ("--"); with the link lost the last values are
        shown dimmed, as stale, and the link rows say so."""
        self._stale = s.link.status in (LinkStatus.LOST, LinkStatus.CLOSED)
        age = s.link.heartbeat_age
        stale_text = ("Link lost: the values below are the last heard" +
                      (f", {age:.0f} s old" if age is not None else "")) if self._stale and s.mode else ""
        if stale_text and s.link.replay_ended:
            stale_text = f"{s.link.ended_words}: the values below are the recording's last"
        if self.stale_label.text() != stale_text:
            self.stale_label.setText(stale_text)
            self.stale_label.setVisible(bool(stale_text))
        if s.link.status is LinkStatus.WAITING or not s.mode:
            for key in ("mode", "armed", "landed", "battery", "gps", "altitude", "ground_speed", "climb",
                        "heading", "home"):
                self._put(key, "--", DIM)
        else:
            self._vehicle_values(s)
        self._stale = False
        self._link_values(s)
        self._security_values(s)

    def _vehicle_values(self, s: VehicleState) -> None:
        self._put("mode", s.mode)
        self._put("armed", "ARMED" if s.armed else "disarmed", WARN if s.armed else NORMAL)
        landed = {LandedState.ON_GROUND: "on ground", LandedState.IN_AIR: "in air", LandedState.TAKEOFF: "taking off",
                  LandedState.LANDING: "landing"}.get(s.landed_state)
        if landed is None:                  # firmware without EXTENDED_SYS_STATE: its heartbeat, or unknown
            landed = {True: "in air", False: "on ground"}.get(s.in_air, "unknown") if s.link.status is \
                LinkStatus.OK else "--"
        self._put("landed", landed)
        self.set_battery(s.battery.voltage, s.battery.cells, s.battery.remaining,
                         s.battery.low, s.battery.remaining_estimated, s.battery.alarm)
        fix_color = GOOD if s.gps.fix_type >= 3 else (WARN if s.gps.fix_type == 2 else BAD)
        self._put("gps", f"{s.gps.fix_name}, {s.gps.satellites} sats", fix_color)
        self._put("altitude", _num(s.altitude, "m", 2))
        self._put("ground_speed", _num(s.velocity.ground_speed, "m/s", 2))
        self._put("climb", _num(s.velocity.climb, "m/s", 2))
        self._put("heading", f"{s.heading_deg:03.0f}°")
        self._put("home", _num(s.distance_from_home, "m"))

    def _link_values(self, s: VehicleState) -> None:
        age = s.link.heartbeat_age
        hb_color = DIM if age is None else (GOOD if s.link.status is LinkStatus.OK else BAD)
        self._put("heartbeat", "--" if age is None else f"{age:.1f} s ago", hb_color)
        if s.link.status is LinkStatus.CLOSED:       # disconnected, or a replay played to its end: none is live
            self._put("heartbeat", f"none ({s.link.ended_words.lower() or 'link closed'})" if s.mode else
                      f"none ({no_vehicle_words(s).lower()})", DIM)
        if s.link.status is LinkStatus.LOST:
            self._put("packets", "0", BAD)
            self._put("loss", "link lost", BAD)
            return
        self._put("packets", f"{s.link.packets_per_s:.0f}", NORMAL if s.link.status is LinkStatus.OK else DIM)
        if s.link.status is not LinkStatus.OK:
            self._put("loss", "--", DIM)
            return
        loss = s.link.loss_percent
        self._put("loss", f"{loss:.1f} %", GOOD if loss < 2 else (WARN if loss < 10 else BAD))

    def _security_values(self, s: VehicleState) -> None:
        """Signing and the pinned link: amber where the vehicle ignores us or we ignore it, or a stranger
        sent; the tooltips say it in full."""
        if self._security_unknown:
            for key in ("signing", "signed", "foreign"):
                self._put(key, "--", DIM, self._security_unknown)
            return
        sig = s.signing
        color = WARN if sig.status in SIGNING_WARNINGS else (GOOD if sig.status is SigningStatus.SIGNING
                                                              else NORMAL)
        self._put("signing", sig.status.value, color, sig.summary)
        counts = signed_frames(sig)
        self._put("signed", counts or "--", NORMAL if counts else DIM,
                  sig.counts or "Nothing verified or dropped yet")
        link = s.link
        self._put("foreign", foreign_text(link), WARN if link.foreign_packets else NORMAL, foreign_tooltip(link))

    def set_battery(self, voltage: float | None, cells: int, remaining: float | None,
                    low: bool = False, estimated: bool = False, alarm: BatteryAlarm | None = None) -> None:
        """Coloured by ``alarm`` (our own thresholds) when given, else by the vehicle's ``low``."""
        if voltage is None and remaining is None:
            self._put("battery", "--", DIM)
            return
        parts = []
        if voltage is not None:
            parts.append(f"{voltage:.2f} V")
        if remaining is not None:
            parts.append(f"{remaining:.0f} %" + ("*" if estimated else ""))
        if alarm is None or alarm is BatteryAlarm.UNKNOWN:
            color = BAD if low else GOOD
        else:
            color = {BatteryAlarm.OK: GOOD, BatteryAlarm.WARNING: WARN}.get(alarm, BAD)
        self._put("battery", "  ".join(parts), color)
