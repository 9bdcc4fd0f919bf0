"""Preferences > Gamepad: pick the controller, watch its sticks and buttons live, map them by moving them."""
from __future__ import annotations


from PyQt5 import sip, uic
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QCheckBox, QComboBox, QDoubleSpinBox, QLabel, QProgressBar, QPushButton, QWidget

from .. import RESOURCES
from .gamepad import GamepadFrame, Pad, PadReading
from .gamepad_input import GamepadInput, GamepadSettings
from .gamepad_mapping import (ACTIONS, PILOT_AXES, AxisCapture, ButtonCapture, GamepadMapping, mappings_from_json,
                              mappings_to_json)
from .sticks import StickMode
from ..telemetry.panel import GOOD, NORMAL, WARN


__all__ = ["GamepadPage"]

_LIGHT = "border: 1px solid #30363d; border-radius: 3px; padding: 1px 4px; background: {};"


def _bar(value: float) -> int:
    return int(round(100 * max(-1.0, min(1.0, value))))


class GamepadPage(QWidget):
    """Edits the choice, "fly in background" and each connected pad's mapping; :meth:`chosen` gives them.

    While a stick or button is being mapped the gamepad neither flies nor acts (:meth:`GamepadInput.set_capturing`).
    """

    def __init__(self, gamepad: GamepadInput, settings: GamepadSettings, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "gamepad_page.ui"), self)
        self._gamepad = gamepad
        self._saved = mappings_from_json(settings.gamepad_mappings)
        self._edited: dict[str, GamepadMapping] = {}
        self._pad: Pad | None = None
        self._reading: PadReading | None = None
        self._capture: tuple[str, AxisCapture | ButtonCapture] | None = None
        self._choice = settings.gamepad or "auto"
        self._filling = False
        self.flyInBackground.setChecked(settings.gamepad_background)
        for mode in (StickMode.MODE2, StickMode.MODE1):
            self.padMode.addItem(mode.title.replace("left:", "left stick:").replace("right:", "right stick:"),
                                 mode.value)
        self.padMode.addItem("Custom (mapped by hand)", "custom")
        self._rows: dict[str, tuple] = {}
        for row, (name, (title, _)) in enumerate(PILOT_AXES.items(), start=1):
            self._rows[name] = self._axis_row(row, name, title)
        self._button_rows: dict[str, tuple] = {}
        for row, (action, title) in enumerate(ACTIONS.items()):
            self._button_rows[action] = self._button_row(row, action, title)
        self._raw_bars: list[QProgressBar] = []
        self._raw_lights: dict[str, QLabel] = {}
        self.controllerChoice.currentIndexChanged.connect(self._choice_changed)
        self.padMode.activated.connect(self._mode_chosen)
        self.cancelCapture.clicked.connect(self.cancel_capture)
        gamepad.frameArrived.connect(self._on_frame)
        self._fill_choices()
        self._choice_changed()

    # -- building ---------------------------------------------------------------------------------
    def _axis_row(self, row: int, name: str, title: str) -> tuple:
        grid = self.axesGrid
        source = QComboBox()
        source.setObjectName(f"{name}Input")
        invert = QCheckBox()
        invert.setObjectName(f"{name}Invert")
        deadband, expo = QDoubleSpinBox(), QDoubleSpinBox()
        for box, top, step in ((deadband, 0.5, 0.01), (expo, 1.0, 0.1)):
            box.setDecimals(2)
            box.setRange(0.0, top)
            box.setSingleStep(step)
        deadband.setObjectName(f"{name}Deadband")
        expo.setObjectName(f"{name}Expo")
        live = QProgressBar()
        live.setObjectName(f"{name}Live")
        live.setRange(-100, 100)
        live.setFormat("%v %")
        live.setMaximumHeight(16)
        map_button = QPushButton("Move…")
        map_button.setObjectName(f"{name}Map")
        map_button.setToolTip(f"Move the stick you want for {title.lower()} {PILOT_AXES[name][1]}")
        for col, w in enumerate((QLabel(title), source, invert, deadband, expo, live, map_button)):
            grid.addWidget(w, row, col)
        source.activated.connect(lambda _i, n=name, s=source: self._edit_axis(n, input=s.currentData()))
        invert.clicked.connect(lambda on, n=name: self._edit_axis(n, invert=on))
        deadband.valueChanged.connect(lambda v, n=name: self._edit_axis(n, deadband=v))
        expo.valueChanged.connect(lambda v, n=name: self._edit_axis(n, expo=v))
        map_button.clicked.connect(lambda _c, n=name: self.capture_axis(n))
        return source, invert, deadband, expo, live, map_button

    def _button_row(self, row: int, action: str, title: str) -> tuple:
        name, light = QLabel(), QLabel()
        name.setObjectName(f"{action}Button")
        light.setFixedWidth(14)
        map_button = QPushButton("Press…")
        map_button.setObjectName(f"{action}Map")
        for col, w in enumerate((QLabel(title), name, light, map_button)):
            self.buttonsGrid.addWidget(w, row, col)
        map_button.clicked.connect(lambda _c, a=action: self.capture_button(a))
        return name, light, map_button

    def _fill_choices(self) -> None:
        self._filling = True
        box = self.controllerChoice
        box.clear()
        box.addItem("Automatic (the first connected)", "auto")
        for pad in self._gamepad.pads:
            if box.findData(pad.guid) < 0:
                box.addItem(pad.name, pad.guid)
        if self._choice not in ("auto", "off") and box.findData(self._choice) < 0:
            box.addItem(f"{self._choice} (not connected)", self._choice)
        box.addItem("None: no gamepad flies", "off")
        box.setCurrentIndex(max(0, box.findData(self._choice)))
        self._filling = False

    # -- the pad being edited ---------------------------------------------------------------------
    @property
    def pad(self) -> Pad | None:
        return self._pad

    def mapping(self) -> GamepadMapping | None:
        if self._pad is None:
            return None
        return self._edited.get(self._pad.guid) or self._gamepad.mapping_for(self._pad)

    def _choice_changed(self) -> None:
        if self._filling:
            return
        self._choice = self.controllerChoice.currentData() or "auto"
        pads = self._gamepad.pads
        if self._choice == "auto":
            pad = self._gamepad.pad or (pads[0] if pads else None)
        else:
            pad = next((p for p in pads if p.guid == self._choice), None)
        self._set_pad(pad)

    def _set_pad(self, pad: Pad | None) -> None:
        self.cancel_capture()
        self._pad = pad
        self._reading = next((r for r in self._gamepad.frame.readings if r.pad == pad), None)
        for bar in self._raw_bars:
            bar.deleteLater()
        for light in self._raw_lights.values():
            light.deleteLater()
        self._raw_bars, self._raw_lights = [], {}
        if pad is None:
            self.padInfo.setText("No controller connected." if not self._gamepad.error else
                                 f"Gamepads unavailable: {self._gamepad.error}")
        else:
            kind = "SDL knows its layout" if pad.controller else \
                "SDL does not know its layout: map its sticks with Move… (an RC transmitter: throttle in the middle)"
            self.padInfo.setText(f"{pad.name} — {kind}. Mapped for this controller only ({pad.guid}).")
            for i, axis in enumerate(pad.axes):
                bar = QProgressBar()
                bar.setRange(0 if axis.endswith("trigger") else -100, 100)     # a trigger rests at 0
                bar.setFormat(f"{axis} %v")
                bar.setMaximumHeight(14)
                self.rawAxes.addWidget(bar, i // 2, i % 2)
                self._raw_bars.append(bar)
            for i, button in enumerate(pad.buttons):
                light = QLabel(button)
                light.setAlignment(Qt.AlignCenter)
                light.setStyleSheet(_LIGHT.format("transparent"))
                self.rawButtons.addWidget(light, i // 6, i % 6)
                self._raw_lights[button] = light
        for w in (self.padMode, self.axesBox, self.buttonsBox):
            w.setEnabled(pad is not None)
        for *_, live, _map in self._rows.values():     # no controller: no bar that looks like a reading
            live.setVisible(pad is not None)
            live.setValue(0)
        self._show_mapping()

    def _show_mapping(self) -> None:
        mapping = self.mapping()
        pad = self._pad
        self._filling = True
        self.padMode.setCurrentIndex(max(0, self.padMode.findData(mapping.mode if mapping else "mode2")))
        self.padMode.setEnabled(pad is not None and pad.controller)
        for name, (source, invert, deadband, expo, _live, _map) in self._rows.items():
            a = mapping.axis(name) if mapping else None
            source.clear()
            source.addItem("—", "")
            for axis in (pad.axes if pad else ()):
                source.addItem(axis, axis)
            source.setCurrentIndex(max(0, source.findData(a.input if a else "")))
            invert.setChecked(bool(a and a.invert))
            deadband.setValue(a.deadband if a else 0.1)
            expo.setValue(a.expo if a else 0.0)
        for action, (label, _light, _map) in self._button_rows.items():
            label.setText((mapping.buttons.get(action) if mapping else "") or "—")
        self._filling = False

    def _store(self, mapping: GamepadMapping) -> None:
        self._edited[self._pad.guid] = mapping
        self._show_mapping()

    def _edit_axis(self, name: str, **changes) -> None:
        if self._filling or self._pad is None:
            return
        self._store(self.mapping().with_axis(name, **changes))

    def _mode_chosen(self) -> None:
        mode = self.padMode.currentData()
        if self._pad is not None and mode in (StickMode.MODE2.value, StickMode.MODE1.value):
            self._store(self.mapping().with_mode(StickMode(mode), self._pad))

    # -- mapping by moving ------------------------------------------------------------------------
    def capture_axis(self, name: str) -> None:
        """"Move the stick you want for climb": the next stick moved far is taken (the wrong way: inverted)."""
        if self._pad is None or self._reading is None:
            return
        title, way = PILOT_AXES[name]
        self._start_capture(name, AxisCapture(self._reading),
                            f"Move the stick you want for {title.lower()} {way}…")

    def capture_button(self, action: str) -> None:
        """"Press the button you want for Land": the next button pressed is taken."""
        if self._pad is None:
            return
        self._start_capture(action, ButtonCapture(self._pad), f"Press the button you want for {ACTIONS[action]}…")

    def _start_capture(self, what: str, capture, prompt: str) -> None:
        self._capture = (what, capture)
        self._gamepad.set_capturing(True)
        self._say(prompt + " The gamepad does not fly while you map it.", NORMAL)
        self.cancelCapture.setVisible(True)

    def cancel_capture(self) -> None:
        if self._capture is None:
            return
        self._capture = None
        if not sip.isdeleted(self._gamepad):            # the window may be going with its gamepad
            self._gamepad.set_capturing(False)
        self.cancelCapture.setVisible(False)
        self._say("", NORMAL)

    @property
    def capturing(self) -> str | None:
        """The pilot axis or action being mapped."""
        return self._capture[0] if self._capture else None

    def _captured(self, reading: PadReading) -> None:
        what, capture = self._capture
        got = capture.feed(reading)
        if got is None:
            return
        self.cancel_capture()
        mapping = self.mapping()
        if isinstance(capture, AxisCapture):
            axis, inverted = got
            self._store(mapping.with_axis(what, input=axis, invert=inverted))
            self._say(f"{PILOT_AXES[what][0]}: {axis}{' (inverted)' if inverted else ''}. Centre the stick to fly.",
                      GOOD)
            return
        changed = mapping.with_button(what, got)
        if changed is mapping:
            owner = ACTIONS[mapping.action_for(got)]
            self._say(f"{got} is {owner}'s button, which must always have one: give it another first.", WARN)
            return
        self._store(changed)
        self._say(f"{ACTIONS[what]}: {got}.", GOOD)

    def _say(self, text: str, color: str) -> None:
        self.captureLabel.setText(text)
        self.captureLabel.setStyleSheet(f"color: {color};")

    # -- live -------------------------------------------------------------------------------------
    def _on_frame(self, frame: GamepadFrame) -> None:
        if frame.added or frame.removed:
            self._fill_choices()
            if self._pad is None or self._pad not in frame.pads:
                self._choice_changed()
        self._reading = next((r for r in frame.readings if r.pad == self._pad), None)
        if self._reading is None:
            return
        if self._capture is not None:
            self._captured(self._reading)
        self._show_live(self._reading)

    def _show_live(self, reading: PadReading) -> None:
        mapping = self.mapping()
        for name, (*_, live, _map) in self._rows.items():
            live.setValue(_bar(mapping.axis(name).value(reading)))
        for bar, value in zip(self._raw_bars, reading.axes):
            bar.setValue(_bar(value))
        for button, light in self._raw_lights.items():
            held = button in reading.held
            if light.property("held") != held:
                light.setProperty("held", held)
                light.setStyleSheet(_LIGHT.format(GOOD if held else "transparent"))
        for action, (label, light, _map) in self._button_rows.items():
            held = bool(mapping.buttons.get(action)) and mapping.buttons[action] in reading.held
            light.setStyleSheet(_LIGHT.format(GOOD if held else "transparent"))

    # -- result -----------------------------------------------------------------------------------
    def chosen(self) -> dict:
        """The ViewerSettings fields this page sets."""
        mappings = dict(self._saved)                     # controllers not connected keep theirs
        mappings.update({guid: m.to_dict() for guid, m in self._edited.items()})
        return {"gamepad": self._choice, "gamepad_background": self.flyInBackground.isChecked(),
                "gamepad_mappings": mappings_to_json(mappings)}

    def hideEvent(self, event) -> None:  # noqa: N802
        self.cancel_capture()             # a mapping never outlives the page
        super().hideEvent(event)

