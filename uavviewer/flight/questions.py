"""The flight buttons' confirmations: takeoff, arm, a mode that needs an RC transmitter, the emergency motor stop.

All are window-modal and opened without waiting (:func:`uavviewer.widgets.ask.ask`); Cancel is the focused
default, so Space (Stop) or Enter never starts or stops the motors: a click does, or for takeoff and arming their
own key (T, as Help › Keys says, and A). The emergency stop and a throttle mode in flight take a click.
"""
from __future__ import annotations

from PyQt5.QtWidgets import QMessageBox, QWidget

from ..widgets.ask import cautious_question

__all__ = ["takeoff_question", "arm_question", "mode_question", "emergency_stop_question"]


def takeoff_question(parent: QWidget, altitude: float, waiting_for: tuple[str, ...] = (),
                     wait_limit: float = 60.0) -> QMessageBox:
    """``waiting_for``: what the vehicle still lacks (GPS fix, EKF, pre-arm checks): the question says the takeoff
    waits for it, and how to cancel."""
    if not waiting_for:
        return cautious_question(parent, "Take off", f"Take off and climb to {altitude:.1f} m above home?\n\n"
                                 "The motors will start. Keep clear of the propellers.", "Take off",
                                 "takeoffQuestion", key="T")
    return cautious_question(
        parent, "Take off when ready",
        f"The vehicle is not ready yet: waiting for {', '.join(waiting_for)}.\n\n"
        f"Take off as soon as it is (up to {wait_limit:.0f} s), and climb to {altitude:.1f} m above home?\n\n"
        "Until then nothing starts; \"Cancel takeoff\" on the main button ends the wait and leaves the vehicle as "
        "it is. Then the motors will start: keep clear of the propellers.", "Take off when ready", "takeoffQuestion",
        key="T")


def arm_question(parent: QWidget, mode: str, consequence: str) -> QMessageBox:
    """Before Arm: the motors start; say what happens next in this mode (the driver's words)."""
    return cautious_question(parent, "Arm the motors", f"Arm the motors in {mode or 'the current mode'}?\n\n"
                             f"{consequence}\n\nKeep clear of the propellers.", "Arm", "armQuestion",
                             QMessageBox.Warning, key="A")


def mode_question(parent: QWidget, mode: str, warning: str) -> QMessageBox:
    """Confirm a mode that needs an RC transmitter in flight, saying why (the driver's words)."""
    return cautious_question(parent, f"Switch to {mode}", warning, f"Switch to {mode}", "modeQuestion",
                             QMessageBox.Warning)


def emergency_stop_question(parent: QWidget) -> QMessageBox:
    """Disarm in the air stops the motors: the drone falls. Asked every time; only a click on "Stop the motors"
    does it."""
    return cautious_question(parent, "Emergency motor stop", "Stop the motors now? The drone will fall.\n\n"
                             "Only for an emergency. To come down safely, use Land.", "Stop the motors",
                             "emergencyStopQuestion", QMessageBox.Critical)
