"""Setup › Motors: the motor test (one motor, or all in sequence), at a throttle % for some seconds; only
disarmed, on the ground, after the pilot ticked "propellers removed"; the outputs (SERVO_OUTPUT_RAW) live;
Stop ends the test at once."""
from __future__ import annotations

from PyQt5.QtWidgets import (
    QCheckBox, QDoubleSpinBox, QFormLayout, QHBoxLayout, QLabel, QPushButton, QSpinBox, QVBoxLayout, QWidget,
)

from .bars import ChannelBars
from .frames import layout

__all__ = ["MotorsPage", "motor_test_problem"]


def motor_test_problem(s, propellers_removed: bool, no_setup: str = "") -> str:
    """Why the test may not start now, in the pilot's words ("" when it may)."""
    if no_setup:
        return f"No motor test on this connection: {no_setup}."
    if not s.connected:
        return "No vehicle connected."
    if s.in_air:
        return "The vehicle is flying: the motor test is for the ground."
    if s.armed:
        return "The vehicle is armed: disarm it first."
    if not propellers_removed:
        return "Take the propellers off and tick \"Propellers removed\" first."
    return ""


def motors(s) -> int:
    """How many outputs the motor test steps through on the vehicle's frame (its layout, the tricopter's servo
    included), 4 while the frame is not read or has no layout."""
    c, t = s.parameters.get("FRAME_CLASS"), s.parameters.get("FRAME_TYPE")
    frame = layout(c.value, t.value) if c is not None and t is not None else None
    return len(frame.motors) if frame else 4


class MotorsPage(QWidget):
    title = "Motors"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        self._state = None
        layout = QVBoxLayout(self)
        warning = QLabel("The motors spin: take the propellers off before testing.")
        warning.setStyleSheet("font-weight: bold")
        layout.addWidget(warning)
        self.props_off = QCheckBox("Propellers removed")
        self.props_off.setObjectName("setupPropsOff")
        self.props_off.toggled.connect(lambda _on: self._show_reason())
        layout.addWidget(self.props_off)
        form = QFormLayout()
        self.motor = QSpinBox()
        self.motor.setRange(1, 12)
        self.all = QCheckBox("All motors in sequence (from this one)")
        self.throttle = QDoubleSpinBox()
        self.throttle.setRange(0.0, 100.0)
        self.throttle.setValue(10.0)
        self.throttle.setSuffix(" %")
        self.seconds = QDoubleSpinBox()
        self.seconds.setRange(0.1, 10.0)
        self.seconds.setValue(2.0)
        self.seconds.setSuffix(" s")
        form.addRow("Motor (test order: A = 1)", self.motor)
        form.addRow("", self.all)
        form.addRow("Throttle", self.throttle)
        form.addRow("Duration", self.seconds)
        layout.addLayout(form)
        row = QHBoxLayout()
        self.test = QPushButton("Spin")
        self.test.setObjectName("setupMotorSpin")
        self.test.clicked.connect(self.spin)
        self.stop = QPushButton("Stop")
        self.stop.setObjectName("setupMotorStop")
        self.stop.setEnabled(False)
        self.stop.clicked.connect(lambda: self._runner.run("stop motor test", lambda s: s.stop_motor_test(),
                                                           self._done))
        row.addWidget(self.test)
        row.addWidget(self.stop)
        layout.addLayout(row)
        self.reason = QLabel("")
        self.reason.setObjectName("setupMotorReason")
        self.reason.setWordWrap(True)
        layout.addWidget(self.reason)
        self.result = QLabel("")
        self.result.setWordWrap(True)
        layout.addWidget(self.result)
        layout.addWidget(QLabel("Outputs, as the vehicle reports them:"))
        self.outputs = ChannelBars("Output", 8)
        layout.addWidget(self.outputs)
        layout.addStretch(1)

    def _problem(self) -> str:
        if self._state is None:
            return "No vehicle."
        return motor_test_problem(self._state, self.props_off.isChecked(), self._runner.no_setup())

    def spin(self) -> None:
        problem = self._problem()
        if problem:
            self.reason.setText(problem)
            return
        motor = self.motor.value()
        count = max(1, motors(self._state) - motor + 1) if self.all.isChecked() else 1
        throttle, seconds = self.throttle.value(), self.seconds.value()
        self.result.setText(f"motor test {motor}: asked…")
        self._runner.run("motor test", lambda s: s.motor_test(motor, throttle_pct=throttle, seconds=seconds,
                                                              count=count, propellers_removed=True), self._done)

    def _done(self, result) -> None:
        self.result.setText(str(result))          # the vehicle's verdict, in its own words

    def _show_reason(self) -> None:
        problem = self._problem()
        self.test.setEnabled(not problem)
        self.reason.setText(problem)

    def show_state(self, s) -> None:
        self._state = s
        self.motor.setMaximum(motors(s))                 # the frame's motors, in test order
        self._show_reason()
        self.outputs.show_values(s.setup.outputs.values[:8])
        # a stop sent idle would start a test: only while one runs
        self.stop.setEnabled(s.connected and not self._runner.no_setup() and s.setup.motor_test_running)
