"""A strip across the top that says when there is no vehicle to fly, or when signing stands in the way."""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QLabel, QSizePolicy, QWidget

from driver.vehicle.state import LinkStatus
from .choice import waiting_words
from ..flight.phase import NO_VEHICLE, NOT_CONNECTED

__all__ = ["LinkBanner"]


class LinkBanner(QLabel):
    """Hidden while the link is healthy; amber while waiting or with a warning, red when lost."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("linkBanner")
        self.setAlignment(Qt.AlignCenter)
        self.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Fixed)   # a long text is cut, never widens the window
        self._status: LinkStatus | None = None
        self.setVisible(False)

    @property
    def status(self) -> LinkStatus | None:
        return self._status

    def set_link(self, status: LinkStatus, address: str, heartbeat_age: float | None,
                 replay_finished: bool = False, warning: str = "") -> None:
        """``replay_finished``: a recorded flight has played to its end; what is shown is its last moment.
        ``warning``: why the vehicle and the viewer may not hear each other (signing), shown with the rest."""
        if replay_finished:
            text, kind = "Replay ended — the instruments show the recording's last moment; Restart plays it again", \
                "waiting"
        elif status is LinkStatus.OK:
            text, kind = "", ""
        elif status is LinkStatus.WAITING:
            text, kind = f"{NO_VEHICLE} — {waiting_words(address)}…", "waiting"
        elif status is LinkStatus.LOST:
            since = "" if heartbeat_age is None else f" — {heartbeat_age:.0f} s since the last heartbeat"
            text, kind = f"Link lost{since}", "lost"
        else:                                   # only File › Disconnect closes the link the window shows
            text, kind = f"{NOT_CONNECTED} — File › Connect picks a vehicle", "lost"
        if warning and status is not LinkStatus.CLOSED and not replay_finished:
            text, kind = (f"{text} — {warning}", kind) if text else (warning, "warning")
        if (status, kind) != (self._status, self.property("kind")):
            self._status = status
            self.setProperty("kind", kind)
            self.style().unpolish(self)
            self.style().polish(self)
        if self.text() != text:
            self.setText(text)
            self.setToolTip(text)
        self.setVisible(bool(text))
