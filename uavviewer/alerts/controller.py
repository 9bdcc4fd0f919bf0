"""Alerts in the window: every snapshot through the model, each alert spoken, critical ones in the banner."""
from __future__ import annotations

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QAction

from driver.vehicle.state import VehicleState

from .banner import AlertBanner
from .model import Alert, AlertModel
from .speech import Speaker

__all__ = ["AlertController"]


class AlertController(QObject):
    alerted = pyqtSignal(object)             # every Alert raised (tests, the status bar)

    def __init__(self, banner: AlertBanner, mute_action: QAction, speaker: Speaker | None = None,
                 muted: bool = False, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.model = AlertModel()
        self.banner = banner
        self.speaker = speaker or Speaker(self)
        self.mute_action = mute_action
        mute_action.setCheckable(True)
        mute_action.setChecked(muted)
        mute_action.toggled.connect(self.speaker.set_muted)
        self.speaker.set_muted(muted)

    def show_state(self, s: VehicleState) -> None:
        for alert in self.model.update(s):
            self.raise_alert(alert)

    def raise_alert(self, alert: Alert) -> None:
        self.speaker.say(alert)
        if alert.critical:
            self.banner.show_alert(alert.text, alert.severity, alert.time)
        elif alert.clears:
            self.banner.clear_if("Link lost")
        self.alerted.emit(alert)

    def reset(self) -> None:
        """Another connection: its first snapshot is a baseline, not news; the banner was the old vehicle's."""
        self.model.reset()
        self.banner.dismiss()

    def close(self) -> None:
        self.speaker.close()
