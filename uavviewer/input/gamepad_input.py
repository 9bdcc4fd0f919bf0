"""The chosen gamepad as a pilot input, on the UI thread: its sticks as pilot axes, its buttons as actions.

Frames come from the process's :class:`~uavviewer.input.gamepad.GamepadReader` thread through a queued signal. The pad
flies nothing until its sticks have been seen centred: after it connects, after Stop or Land, after the window
lost focus (unless the pilot chose to fly in the background), after it stopped reporting, and while Preferences
maps it. Disconnecting, or a reader silent for :data:`STALL` seconds, is zero at once and a message. Stop and Land
act from any window state; Take off and RTL only when the pad may fly.
"""
from __future__ import annotations

from typing import Protocol

import logging
import time

from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from driver.vehicle.state import Severity

from .gamepad import GamepadFrame, GamepadReader, Pad, PadReading, shared_reader
from .gamepad_mapping import ALWAYS_MAPPED, GamepadMapping, default_mapping, mappings_from_json
from .sticks import Axes


class GamepadSettings(Protocol):
    """What the gamepad reads of the pilot's preferences (``uavviewer.settings.ViewerSettings`` has these): named
    here, so that input/ depends on no module above it (settings.py builds on input/sticks.py)."""
    gamepad: str                  # "auto", "off", or the GUID of the pad that flies
    gamepad_background: bool      # the pad keeps flying while the window is not active
    gamepad_mappings: str         # JSON: controller GUID -> its mapping


__all__ = ["GamepadInput", "GamepadSettings", "STALL"]

log = logging.getLogger(__name__)

STALL = 0.4           # s without a frame while a pad is open: the reader has stalled (it beats every 0.1 s)


class _FrameRelay(QObject):
    """Carries frames from the reader's thread to the UI thread. No parent: a frame emitted while the window
    is being deleted reaches a living object (as the drone adapter's relay)."""
    frame = pyqtSignal(object)


class GamepadInput(QObject):
    changed = pyqtSignal()                   # the pad's demand or state changed: fly again, redraw the label
    actionPressed = pyqtSignal(str)          # "stop" | "land" | "takeoff" | "rtl" | "tilt_up" | "tilt_down"
    message = pyqtSignal(str, object)        # text for the pilot, Severity
    frameArrived = pyqtSignal(object)        # every GamepadFrame (Preferences' live bars)

    def __init__(self, settings: GamepadSettings, reader: GamepadReader | None = None,
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._reader = reader or shared_reader()
        self.pads: tuple[Pad, ...] = ()
        self.pad: Pad | None = None
        self.reading: PadReading | None = None
        self.frame = GamepadFrame(time.monotonic())     # the latest from the reader
        self.mapping: GamepadMapping | None = None
        self.error = ""
        self._choice = "auto"
        self.background = False
        self._saved: dict[str, dict] = {}
        self._focused = False                   # until the window says it is active
        self._centred = False
        self._capturing = False
        self._stalled = False
        self._last_frame = time.monotonic()
        self._watchdog = QTimer(self)
        self._watchdog.setInterval(100)
        self._watchdog.timeout.connect(self._check_stall)
        self.apply_settings(settings)
        relay = self._relay = _FrameRelay()
        relay.frame.connect(self._on_frame)
        self._listener = relay.frame.emit        # called on the reader's thread: queued to this one
        self._reader.subscribe(self._listener)

    def close(self) -> None:
        self._watchdog.stop()
        self._reader.unsubscribe(self._listener)

    # -- settings -------------------------------------------------------------------------------
    def apply_settings(self, settings: GamepadSettings) -> None:
        self._choice = settings.gamepad or "auto"
        self.background = settings.gamepad_background
        self._saved = mappings_from_json(settings.gamepad_mappings)
        if self.pad is not None and self._wanted(self.pad):
            self.mapping = self.mapping_for(self.pad)
            self._centred = False
            self._update_centred()
        else:
            self._switch(self._pick())
        self.changed.emit()

    def mapping_for(self, pad: Pad) -> GamepadMapping:
        saved = self._saved.get(pad.guid)
        return GamepadMapping.from_dict(saved, pad) if saved is not None else default_mapping(pad)

    def _wanted(self, pad: Pad) -> bool:
        return self._choice == "auto" or self._choice == pad.guid

    def _pick(self) -> Pad | None:
        return next((p for p in self.pads if self._wanted(p)), None) if self._choice != "off" else None

    # -- what flies -----------------------------------------------------------------------------
    @property
    def may_fly(self) -> bool:
        return self.pad is not None and (self._focused or self.background) and not self._capturing \
            and not self._stalled

    def axes(self) -> Axes:
        """The pad's demand; zero unless it may fly and has been seen centred since it last had to stop."""
        if not self.may_fly or not self._centred or self.reading is None or self.mapping is None:
            return Axes()
        return self.mapping.pilot_axes(self.reading)

    @property
    def status(self) -> str:
        """Why the pad is not flying, for the window ("" when it may)."""
        if self.pad is None:
            return ""
        if self._stalled:
            return "not reporting"
        if self._capturing:
            return "being mapped"
        if not (self._focused or self.background):
            return "window not active"
        if self.mapping is None or not self.mapping.flies:
            return "map it in Preferences"
        if not self._centred:
            return "centre its sticks"
        return ""

    def set_focus(self, focused: bool) -> None:
        """The window gained or lost focus: without "fly in background", the pad stops with the focus."""
        if focused == self._focused:
            return
        self._focused = focused
        if not focused and not self.background:
            self.release()
        self.changed.emit()

    def set_capturing(self, capturing: bool) -> None:
        """Preferences is mapping this pad: it neither flies nor acts until done (then centre to fly)."""
        self._capturing = capturing
        if capturing:
            self.release()
        self.changed.emit()

    def release(self) -> None:
        """Stop listening to the sticks until they are seen centred (Stop, Land, a menu, focus lost)."""
        self._centred = False
        self._update_centred()

    def _update_centred(self) -> None:
        if self._centred or not self.may_fly or self.reading is None or self.mapping is None:
            return
        self._centred = self.mapping.pilot_axes(self.reading).is_zero

    # -- frames ---------------------------------------------------------------------------------
    def _on_frame(self, frame: GamepadFrame) -> None:
        before = (self.pad, self.axes(), self.status)
        self.frame = frame
        self._last_frame = frame.time
        if frame.error:
            if frame.error != self.error:
                self.error = frame.error
                self.message.emit(f"Gamepads unavailable: {frame.error}", Severity.WARNING)
            return
        if self._stalled:
            self._stalled = False
            self.message.emit(f"Gamepad {self.pad.name if self.pad else ''} reporting again: centre its sticks "
                              "to fly", Severity.INFO)
        for pad in frame.removed:
            if self.pad is not None and pad.instance == self.pad.instance:
                self._switch(None)
                self.message.emit(f"Gamepad {pad.name} disconnected: hovering", Severity.WARNING)
        self.pads = frame.pads
        for pad in frame.added:
            note = "" if pad.controller or pad.guid in self._saved else \
                " (SDL does not know its layout: map its sticks in Preferences > Gamepad)"
            self.message.emit(f"Gamepad {pad.name} connected{note}", Severity.INFO)
        if self.pad is None or self.pad not in self.pads:
            self._switch(self._pick())
        self.reading = next((r for r in frame.readings if r.pad == self.pad), None)
        self._update_centred()
        if self.reading is not None and self.mapping is not None and not self._capturing:
            for button in self.reading.pressed:
                action = self.mapping.action_for(button)
                if action is not None and (action in ALWAYS_MAPPED or self.may_fly):
                    self.actionPressed.emit(action)
        self._watchdog.start() if self.pad is not None else self._watchdog.stop()
        self.frameArrived.emit(frame)
        if (self.pad, self.axes(), self.status) != before:
            self.changed.emit()

    def _switch(self, pad: Pad | None) -> None:
        if pad == self.pad:
            return
        self.pad = pad
        self.reading = None
        self._centred = False
        self.mapping = self.mapping_for(pad) if pad is not None else None
        if pad is not None:
            log.info("flying with gamepad %s (%s)", pad.name, pad.guid)

    def _check_stall(self) -> None:
        if self.pad is None or self._stalled or time.monotonic() - self._last_frame < STALL:
            return
        self._stalled = True
        self._centred = False
        self.message.emit(f"Gamepad {self.pad.name} stopped reporting: hovering", Severity.WARNING)
        self.changed.emit()
