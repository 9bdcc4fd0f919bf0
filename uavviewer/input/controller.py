"""The pilot's hands: the two on-screen pads, the keyboard and the gamepad become one velocity demand.

The demand is the pads and keys combined, or the gamepad, whichever the pilot moved last
(:class:`~uavviewer.input.selector.InputSelector`), scaled by the maximum speeds the drone has in force, and zero
while the vehicle cannot fly by velocity. Keys fly only when aimed at the window; a menu, popup or dialog opening,
focus lost or the window minimised centres everything (the key's release would go elsewhere). Space, T, L and R
(and the gamepad's buttons) do what their button does, and only while it is enabled; they do it from any other
window of the program too (Setup, Parameters, a review...), unless a text field there has the focus: with Setup
focused in flight, R did nothing.
"""
from __future__ import annotations

import logging
import math

from PyQt5.QtCore import QEvent, QObject, Qt
from PyQt5.QtWidgets import (QAbstractSpinBox, QApplication, QComboBox, QDialog, QLineEdit, QPlainTextEdit,
                             QTextEdit, QWidget)

from driver.vehicle.api import Limits
from driver.vehicle.state import Severity, VehicleState

from ..camera.gimbal import KEY_STEP
from ..flight.phase import FlightPhase, stick_hint
from .gamepad_input import GamepadInput
from .keyboard import ACTION_KEYS, AXIS_KEYS, EVERYWHERE_KEYS, KeyboardSticks
from .selector import Input, InputSelector
from .sticks import Axes, MaxSpeeds, axes_from_pads, combine, pad_labels, pads_from_axes, velocity_from_axes

__all__ = ["PilotSticks"]

log = logging.getLogger(__name__)


class PilotSticks(QObject):
    """``window``: the main window (its pads, labels, adapter, map, flight controls, gimbal and settings)."""

    def __init__(self, window, settings) -> None:
        super().__init__(window)
        self.window = w = window
        self.keyboard = KeyboardSticks()
        self.gamepad = GamepadInput(settings, parent=window)
        self._inputs = InputSelector()
        self.speeds = MaxSpeeds()                   # full deflection: the limits the drone has in force
        self.live = False
        w.leftStick.moved.connect(lambda *_: self.fly())
        w.rightStick.moved.connect(lambda *_: self.fly())
        self.gamepad.changed.connect(self.fly)
        self.gamepad.actionPressed.connect(self.key_action)
        self.gamepad.message.connect(self._gamepad_message)
        QApplication.instance().installEventFilter(self)

    def close(self) -> None:
        QApplication.instance().removeEventFilter(self)
        self.gamepad.close()

    def apply(self, settings) -> None:
        """The Preferences' stick mode, speeds and gamepad; everything back to the centre."""
        left, right = pad_labels(settings.mode)
        self.window.leftStick.set_caption(left)
        self.window.rightStick.set_caption(right)
        self.set_limits(settings.speeds)
        self.gamepad.apply_settings(settings)
        self.centre()

    def set_limits(self, wish: MaxSpeeds) -> None:
        """The pilot's maximum speeds become the driver's clamps; the sticks scale by what is in force."""
        drone = self.window.adapter.drone
        try:
            limits = drone.set_limits(Limits(wish.horizontal, wish.vertical, math.radians(wish.yaw_deg_s)))
        except NotImplementedError:
            limits = drone.limits
        except Exception:                       # noqa: BLE001 - a remote drone may fail; keep its clamps
            log.exception("setting the speed limits failed")
            limits = drone.limits
        if (limits.horizontal, limits.vertical) != (wish.horizontal, wish.vertical) \
                or not math.isclose(limits.yaw_rate, math.radians(wish.yaw_deg_s), abs_tol=1e-4):
            self.window.log_message(f"Maximum speeds in force: {limits.horizontal:g} m/s, {limits.vertical:g} m/s, "
                                    f"{math.degrees(limits.yaw_rate):.0f}°/s", Severity.WARNING)
        self.speeds = MaxSpeeds(limits.horizontal, limits.vertical, math.degrees(limits.yaw_rate))

    def show_state(self, s: VehicleState) -> None:
        """The pads are live only while the vehicle can fly by velocity (never in a replay)."""
        replay = self.window.adapter.replay is not None
        live = s.can_fly_velocity and not replay
        hint = "Replay" if replay else stick_hint(s)
        for pad in (self.window.leftStick, self.window.rightStick):
            pad.set_hint(hint)
            if pad.isEnabled() != live:
                pad.setEnabled(live)        # disabling centres the pad
        if live != self.live:
            self.live = live
            self.keyboard.clear()           # a key held while inert needs a fresh press to fly
            self.gamepad.release()          # and the gamepad a return to the centre
            self.fly()

    def demand(self) -> Axes:
        """The pilot's demand: both pads and the keyboard combined, or the gamepad, whichever the pilot moved
        last (zero if sticks are inert)."""
        if not self.live:
            self._inputs.reset()
            return Axes()
        w = self.window
        pads = axes_from_pads(w.settings.mode, w.leftStick.position, w.rightStick.position, w.settings.shaping)
        return self._inputs.choose(combine(pads, self.keyboard.axes()), self.gamepad.axes())

    def fly(self) -> None:
        w = self.window
        axes = self.demand()
        shots = getattr(w, "shots", None)
        if shots is not None and shots.steer(axes):     # a smart shot runs: the sticks fly it, as on the Solo
            self._echo_on_pads()
            w.setpointLabel.setText("Setpoint: the shot" if axes.is_zero else "Sticks: steering the shot")
            return
        command = velocity_from_axes(axes, self.speeds)
        w.adapter.fly(command)
        self._echo_on_pads()
        w.inputLabel.setText(self._input_text())
        if not command.is_zero:
            w.map.cancel()                      # a stick overrides a go-to
        if command.is_zero:
            w.setpointLabel.setText("Setpoint: hover")
        else:
            w.setpointLabel.setText(            # short enough for the controls' column at 1024×600
                f"fwd {command.forward:+.1f} rt {command.right:+.1f} up {command.up:+.1f} m/s "
                f"yaw {math.degrees(command.yaw_rate):+.0f}°/s")

    def _echo_on_pads(self) -> None:
        """Held keys (or the gamepad, while it flies) move the on-screen knobs: the pilot sees what flies."""
        echo = Axes()
        if self.live:
            echo = self.gamepad.axes() if self._inputs.owner is Input.GAMEPAD else self.keyboard.axes()
        left, right = pads_from_axes(self.window.settings.mode, echo)
        self.window.leftStick.set_echo(*left)
        self.window.rightStick.set_echo(*right)

    def _input_text(self) -> str:
        """Which input flies now, else which are there (and why the gamepad waits)."""
        pad = self.gamepad.pad
        owner = self._inputs.owner
        if owner is Input.GAMEPAD and pad is not None:
            return f"Flying: gamepad {pad.name}"
        if owner is Input.SCREEN:
            w = self.window
            pads_held = w.leftStick.position != (0.0, 0.0) or w.rightStick.position != (0.0, 0.0)
            held = [name for name, on in (("sticks", pads_held), ("keyboard", self.keyboard.active)) if on]
            return "Flying: " + (" + ".join(held) or "sticks")
        text = "Input: sticks, keyboard"
        if pad is not None:
            status = self.gamepad.status
            text += f", gamepad {pad.name}" + (f" ({status})" if status else "")
        return text

    def centre(self, gamepad: bool = True) -> None:
        """Both pads and every key back to the centre, and (``gamepad``) the gamepad waits for its centre;
        the new demand goes out (zero, unless the gamepad flies on)."""
        self.keyboard.clear()
        self.window.leftStick.centre()
        self.window.rightStick.centre()
        if gamepad:
            self.gamepad.release()
        self.fly()

    def window_changed(self, event: QEvent) -> None:
        """Focus lost or minimised: nobody holds the sticks or keys any more; the gamepad flies on only if the
        pilot chose "fly in background"."""
        w = self.window
        if event.type() == QEvent.ActivationChange:
            self.gamepad.set_focus(w.isActiveWindow())
            if not w.isActiveWindow():
                self.centre(gamepad=False)
        elif event.type() == QEvent.WindowStateChange and w.isMinimized():
            self.centre(gamepad=False)

    def _gamepad_message(self, text: str, severity: Severity) -> None:
        self.window.log_message(text, severity)
        self.window.statusbar.showMessage(text, 8000)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802
        """Keys fly only when aimed at the window, but a release counts wherever it lands, and a menu,
        popup or dialog opening centres everything (the release would go to it)."""
        kind = event.type()
        if kind == QEvent.KeyRelease and not event.isAutoRepeat() and event.key() in AXIS_KEYS:
            if self.keyboard.release(event.key()):
                self.fly()
        elif kind == QEvent.Show and self._interrupts(watched):
            self.centre()
            return False
        if kind in (QEvent.KeyPress, QEvent.KeyRelease) and self.window.adapter.replay is None \
                and (self._owns(watched) or self._beside(watched, event)):
            if QApplication.activeModalWidget() is not None or QApplication.activePopupWidget() is not None:
                return False
            if not self._owns(watched):                              # another window: the buttons' keys only
                return kind == QEvent.KeyPress and not event.isAutoRepeat() and \
                    self._key_pressed(event.key(), event.modifiers())
            if event.isAutoRepeat():
                return event.key() in ACTION_KEYS or event.key() in AXIS_KEYS   # held: already acted
            if kind == QEvent.KeyPress:
                return self._key_pressed(event.key(), event.modifiers())
            return event.key() in ACTION_KEYS or event.key() in AXIS_KEYS
        return False

    def _interrupts(self, watched: QObject) -> bool:
        """A menu, popup list or dialog is opening: it will take the keys (tooltips do not)."""
        if not isinstance(watched, QWidget) or not watched.isWindow() or watched is self.window:
            return False
        return isinstance(watched, QDialog) or watched.windowType() in (Qt.Popup, Qt.Dialog)

    def _owns(self, watched: QObject) -> bool:
        return isinstance(watched, QWidget) and watched.window() is self.window

    def _beside(self, watched: QObject, event) -> bool:
        """A key for a flight button (Space, T, L, R), pressed in another window of the program that is not a
        question, and not into a field that takes text."""
        if not isinstance(watched, QWidget) or event.key() not in EVERYWHERE_KEYS:
            return False
        other = watched.window()
        if other is self.window or other.windowType() not in (Qt.Window, Qt.Dialog) \
                or other.windowModality() != Qt.NonModal:
            return False
        return not _typing(watched)                     # the key's receiver: the widget with the focus

    def _key_pressed(self, key: int, modifiers) -> bool:
        if modifiers & (Qt.ControlModifier | Qt.AltModifier | Qt.MetaModifier):
            return False
        if self.keyboard.press(key):
            self.fly()
            return True
        action = ACTION_KEYS.get(key)
        if action is None:
            return False
        self.key_action(action[0])
        return True

    def key_action(self, action: str) -> None:
        """Space, T and L (and the gamepad's buttons) do what their button does, and only while it is enabled."""
        fc = self.window.flightControls
        if action == "stop":
            fc.stop_button.click()              # click() does nothing on a disabled button
        elif action == "rtl":
            fc.rtl_button.click()
        elif action == "takeoff" and fc.phase is FlightPhase.ON_GROUND:
            fc.main_button.click()
        elif action == "land" and fc.phase in (FlightPhase.TAKING_OFF, FlightPhase.FLYING):
            fc.main_button.click()
        elif action in ("tilt_up", "tilt_down"):      # the vehicle's camera (uavviewer/camera/gimbal.py)
            self.window.gimbal.tilt_by(KEY_STEP if action == "tilt_up" else -KEY_STEP)


def _typing(focus: QWidget | None) -> bool:
    """A field that takes text has the focus (a search box, a value being edited): letters and Space are its."""
    if isinstance(focus, (QLineEdit, QTextEdit, QPlainTextEdit)):
        return not focus.isReadOnly()
    return isinstance(focus, QAbstractSpinBox) or isinstance(focus, QComboBox) and focus.isEditable()
