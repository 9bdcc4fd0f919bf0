"""Setup › Sensors: gyro, barometer, level, the six-position accelerometer calibration (a drawing of each asked
position and Next), the compass (progress per compass, fitness, Accept / Cancel) and the compass from a known
yaw. What the vehicle says (its STATUSTEXT) is shown as it comes, and its verdict is the result; a firmware that
lacks a calibration says so (driver.core.firmware) instead of failing."""
from __future__ import annotations

from PyQt5.QtWidgets import (
    QDoubleSpinBox, QGridLayout, QGroupBox, QHBoxLayout, QLabel, QPlainTextEdit, QProgressBar, QPushButton,
    QVBoxLayout, QWidget,
)

from driver.core.firmware import unavailable
from driver.setup.model import AccelStep

from .accel_pose import AccelPose

__all__ = ["SensorsPage"]


def _button(text: str, name: str) -> QPushButton:
    b = QPushButton(text)
    b.setObjectName(name)
    return b


class SensorsPage(QWidget):
    title = "Sensors"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        self._accel = None                      # the running AccelCalibration
        self._confirming: int | None = None     # the position Next was pressed for
        self._texts_from = 0.0                  # the vehicle's words shown from this time on
        layout = QVBoxLayout(self)
        self.notes = QLabel("")
        self.notes.setWordWrap(True)
        layout.addWidget(self.notes)
        row = QHBoxLayout()
        self.gyro = _button("Gyro", "setupGyro")
        self.baro = _button("Barometer", "setupBaro")
        self.level = _button("Level", "setupLevel")
        self.simple = _button("Simple accel", "setupSimpleAccel")
        for b, name, call in ((self.gyro, "gyro", lambda setup: setup.calibrate_gyro()),
                              (self.baro, "baro", lambda setup: setup.calibrate_baro()),
                              (self.level, "level", lambda setup: setup.calibrate_level()),
                              (self.simple, "accel_simple", lambda setup: setup.calibrate_accel_simple())):
            b.clicked.connect(lambda _c=False, n=name, c=call: self._run(n, c))
            row.addWidget(b)
        layout.addLayout(row)
        columns = QHBoxLayout()
        accel = QGroupBox("Accelerometer: six positions")
        a = QVBoxLayout(accel)
        self.accel_start = _button("Start", "setupAccelStart")
        self.accel_start.clicked.connect(self.start_accel)
        self.pose = AccelPose()
        self.asked = QLabel("Press Start: the vehicle asks for six positions in turn.")
        self.asked.setWordWrap(True)
        self.next = _button("Next: it is in position", "setupAccelNext")
        self.next.setEnabled(False)
        self.next.clicked.connect(self.confirm_position)
        for widget in (self.accel_start, self.pose, self.asked, self.next):
            a.addWidget(widget)
        columns.addWidget(accel)
        compass = QGroupBox("Compass")
        c = QVBoxLayout(compass)
        buttons = QHBoxLayout()
        self.compass_start = _button("Start", "setupCompassStart")
        self.compass_accept = _button("Accept", "setupCompassAccept")
        self.compass_cancel = _button("Cancel", "setupCompassCancel")
        self.compass_start.clicked.connect(lambda: self._run("compass", lambda s: s.compass_calibration().finished))
        self.compass_accept.clicked.connect(lambda: self._run("accept_compass", lambda s: s.accept_compass()))
        self.compass_cancel.clicked.connect(lambda: self._run("cancel_compass", lambda s: s.cancel_compass()))
        for b in (self.compass_start, self.compass_accept, self.compass_cancel):
            buttons.addWidget(b)
        c.addLayout(buttons)
        self.compass_grid = QGridLayout()
        c.addLayout(self.compass_grid)
        self.compass_bars: dict[int, tuple[QProgressBar, QLabel]] = {}
        yaw = QHBoxLayout()
        self.yaw = QDoubleSpinBox()
        self.yaw.setRange(0.0, 360.0)
        self.yaw.setSuffix(" °")
        self.fixed_yaw = _button("Compass from this yaw", "setupFixedYaw")
        self.fixed_yaw.clicked.connect(lambda: self._run("fixed_yaw", lambda s: s.fixed_mag_yaw(self.yaw.value())))
        yaw.addWidget(self.yaw)
        yaw.addWidget(self.fixed_yaw)
        c.addLayout(yaw)
        c.addStretch(1)
        columns.addWidget(compass)
        layout.addLayout(columns, 1)
        self.result = QLabel("")
        self.result.setObjectName("setupSensorsResult")
        self.result.setWordWrap(True)
        layout.addWidget(self.result)
        layout.addWidget(QLabel("The vehicle says:"))
        self.said = QPlainTextEdit()
        self.said.setReadOnly(True)
        self.said.setMaximumHeight(80)
        layout.addWidget(self.said)

    # -- actions --------------------------------------------------------------------------------------
    def _run(self, name: str, call) -> None:
        self.result.setText(f"{name.replace('_', ' ')}: running…")
        self._texts_from = self._runner.now()
        self._runner.run(name, call, self._done)

    def _done(self, result) -> None:
        self.result.setText(str(result))          # the vehicle's verdict, in its own words

    def start_accel(self) -> None:
        self._texts_from = self._runner.now()
        self.result.setText("accel calibration: starting…")

        def start(setup):
            self._confirming = None
            self._accel = setup.accel_calibration()
            return self._accel.verdict
        self._runner.run("accel", start, self._done)

    def confirm_position(self) -> None:
        if self._accel is not None:
            self._confirming = self._accel.position
            self.next.setEnabled(False)             # until the vehicle asks for the next one
            self._runner.run("accel position", lambda _s: self._accel.confirm_position(), self._position_done)

    def _position_done(self, result) -> None:
        if not result.ok:                           # not confirmed (lost, refused): Next again for the same one
            self._confirming = None
            self._done(result)

    # -- the vehicle's state ------------------------------------------------------------------------
    def show_state(self, s) -> None:
        no_setup = self._runner.no_setup()
        notes = [why for why in (unavailable(a, s.firmware) for a in ("level", "accel_simple", "accel", "fixed_yaw"))
                 if why]
        if s.armed:
            notes.insert(0, "Armed: the vehicle refuses calibrations until it is disarmed.")
        if no_setup:
            notes = [f"No calibration on this connection: {no_setup}."]
        self.notes.setText("\n".join(notes))
        for button in (self.gyro, self.baro, self.compass_start):
            button.setEnabled(not no_setup)
        self.level.setEnabled(not no_setup and not unavailable("level", s.firmware))
        self.simple.setEnabled(not no_setup and not unavailable("accel_simple", s.firmware))
        self.fixed_yaw.setEnabled(not no_setup and not unavailable("fixed_yaw", s.firmware))
        self.accel_start.setEnabled(not no_setup and not unavailable("accel", s.firmware))
        accel = s.setup.accel
        self.pose.set_position(accel.position if accel.step is AccelStep.WAITING else None)
        waiting = accel.step is AccelStep.WAITING
        if waiting:
            if self.result.text().startswith("accel calibration: starting"):
                self.result.setText("accel calibration: running…")
            self.asked.setText(f"Position {accel.position} of 6: put the vehicle {accel.position_name}, "
                               "hold it still, then press Next.")
        elif accel.step is AccelStep.SUCCESS:
            self.asked.setText("All six positions done: calibration successful.")
        elif accel.step is AccelStep.FAILED:
            self.asked.setText("The accelerometer calibration failed (see what the vehicle says).")
        self.next.setEnabled(waiting and self._accel is not None and self._confirming != accel.position)
        self._show_compass(s.setup.compass)
        said = [m.text for m in s.messages if m.source == "vehicle" and m.time >= self._texts_from]
        text = "\n".join(said[-20:])
        if text != self.said.toPlainText():
            self.said.setPlainText(text)
            self.said.verticalScrollBar().setValue(self.said.verticalScrollBar().maximum())

    def _show_compass(self, state) -> None:
        ids = sorted({p.compass for p in state.progress} | {r.compass for r in state.reports})
        for compass in ids:
            if compass not in self.compass_bars:
                bar, words = QProgressBar(), QLabel("")
                row = len(self.compass_bars)
                self.compass_grid.addWidget(QLabel(f"Compass {compass + 1}"), row, 0)
                self.compass_grid.addWidget(bar, row, 1)
                self.compass_grid.addWidget(words, row, 2)
                self.compass_bars[compass] = (bar, words)
            bar, words = self.compass_bars[compass]
            bar.setValue(state.percent(compass) or 0)
            report = next((r for r in state.reports if r.compass == compass), None)
            words.setText("" if report is None else f"fitness {report.fitness:.1f}"
                          + ("" if report.ok else f" FAILED (status {report.status})"))
        # ArduPilot's accept stops every calibrator and fails when one still runs: only once each has reported
        self.compass_accept.setEnabled(state.running and bool(state.reports) and not state.progress)
        self.compass_cancel.setEnabled(state.running)
