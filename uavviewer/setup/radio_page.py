"""Setup › Radio: the transmitter's channels live, as the vehicle receives them (RC_CHANNELS, RC_CHANNELS_RAW on
3.3). A calibration records each channel's lowest, highest and centre while the pilot moves the sticks."""
from __future__ import annotations

from PyQt5.QtWidgets import QLabel, QVBoxLayout, QWidget

from .bars import ChannelBars

__all__ = ["RadioPage"]


class RadioPage(QWidget):
    title = "Radio"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        layout = QVBoxLayout(self)
        self.status = QLabel("Waiting for the vehicle's RC channels…")
        self.status.setObjectName("setupRadioStatus")
        self.status.setWordWrap(True)
        layout.addWidget(self.status)
        self.channels = ChannelBars("Channel", 8)
        layout.addWidget(self.channels)
        layout.addStretch(1)

    def show_state(self, s) -> None:
        rc = s.setup.rc
        self.channels.show_values(rc.values[:16])
        if not rc.updated:
            self.status.setText("Waiting for the vehicle's RC channels…")
        else:
            sent = len([v for v in rc.values if v])
            rssi = "unknown" if rc.rssi is None else f"{rc.rssi * 100 // 254} %"
            self.status.setText(f"{sent} channels received; signal strength {rssi}.")
