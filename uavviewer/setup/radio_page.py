"""Setup › Radio: the transmitter's channels live, as the vehicle receives them (RC_CHANNELS, RC_CHANNELS_RAW on
3.3), and the radio calibration: Start records each channel's lowest and highest while the pilot moves every
stick and switch to its ends; Finish (sticks let go, throttle low) shows what it will write to RCn_MIN/MAX/TRIM
and flags a channel that never moved; Write… hands the values to the Parameters review, the same checked path
as the Parameters page: nothing is written before the pilot presses Write there."""
from __future__ import annotations

from PyQt5.QtWidgets import QHBoxLayout, QLabel, QPlainTextEdit, QPushButton, QVBoxLayout, QWidget

from .bars import ChannelBars
from .radio_calibration import THROTTLE, RadioCalibration, parameters, throttle_channel

__all__ = ["RadioPage"]


class RadioPage(QWidget):
    title = "Radio"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        self._calibration: RadioCalibration | None = None
        self._values: dict[str, float] = {}
        self._channels = ()
        self._throttle = THROTTLE                    # RCMAP_THROTTLE as the vehicle reported it
        layout = QVBoxLayout(self)
        self.status = QLabel("Waiting for the vehicle's RC channels…")
        self.status.setObjectName("setupRadioStatus")
        self.status.setWordWrap(True)
        layout.addWidget(self.status)
        self.channels = ChannelBars("Channel", 8)
        layout.addWidget(self.channels)
        row = QHBoxLayout()
        self.start = QPushButton("Start calibration")
        self.start.setObjectName("setupRadioStart")
        self.start.clicked.connect(self.start_calibration)
        self.finish = QPushButton("Finish (sticks centred, throttle low)")
        self.finish.setObjectName("setupRadioFinish")
        self.finish.setEnabled(False)
        self.finish.clicked.connect(self.finish_calibration)
        self.write = QPushButton("Write…")
        self.write.setObjectName("setupRadioWrite")
        self.write.setEnabled(False)
        self.write.clicked.connect(self.write_calibration)
        for b in (self.start, self.finish, self.write):
            row.addWidget(b)
        layout.addLayout(row)
        self.plan = QPlainTextEdit()
        self.plan.setObjectName("setupRadioPlan")
        self.plan.setReadOnly(True)
        self.plan.setMaximumHeight(130)
        self.plan.setPlaceholderText("Start, move every stick and switch to both ends, let them go, then Finish: "
                                     "what will be written shows here.")
        layout.addWidget(self.plan)
        layout.addStretch(1)

    def start_calibration(self) -> None:
        self._calibration = RadioCalibration()
        self._values = {}
        self.plan.setPlainText("Recording: move every stick and switch to both ends…")
        self.finish.setEnabled(True)
        self.write.setEnabled(False)

    def finish_calibration(self) -> None:
        if self._calibration is None:
            return
        ranges = self._calibration.ranges(self._channels, self._throttle)
        self._calibration = None
        self.finish.setEnabled(False)
        self._values = parameters(ranges)
        self.plan.setPlainText("\n".join(r.words() for r in ranges) or "No channel received: nothing to write.")
        self.write.setEnabled(bool(self._values))

    def write_calibration(self) -> None:
        unknown = self._runner.propose(self._values)
        if unknown:
            self.status.setText(f"Not staged: the vehicle has not reported {', '.join(unknown)} yet (its parameters "
                                "are being read); press Write… again in a moment.")

    def show_state(self, s) -> None:
        rc = s.setup.rc
        self._channels = rc.values
        self._throttle = throttle_channel(s)
        self.channels.show_values(rc.values[:16])
        if self._calibration is not None:
            self._calibration.feed(rc.values)
        no_setup = self._runner.no_setup()
        self.start.setEnabled(not no_setup)
        if no_setup:
            self.status.setText(f"No RC channels on this connection: {no_setup}.")
        elif not rc.updated:
            self.status.setText("Waiting for the vehicle's RC channels…")
        elif not self.status.text().startswith("Not staged"):
            sent = len([v for v in rc.values if v])
            rssi = "unknown" if rc.rssi is None else f"{rc.rssi * 100 // 254} %"
            self.status.setText(f"{sent} channels received; signal strength {rssi}.")
