"""The Shots panel: pick a smart shot, set it up, start it; the running shot's state and its buttons.

A widget only: its buttons say what the pilot wants (signals), :class:`~uavviewer.shots.controller.ShotsController`
asks the drone. What it shows is the vehicle's (``VehicleState.shot``): the phase, where the vehicle is on the
shot, how far the camera is off its look.
"""
from __future__ import annotations

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import (
    QComboBox, QDoubleSpinBox, QFormLayout, QHBoxLayout, QLabel, QLineEdit, QProgressBar, QPushButton, QTabWidget,
    QVBoxLayout, QWidget,
)

from driver.shots.model import ShotKind, ShotPhase, ShotState

__all__ = ["ShotsPanel", "CENTRES", "SOURCES"]

#: the orbit's centre: the spot under the camera or the vehicle's region of interest (a map click: right-click)
CENTRES = (("spot", "Spot under the camera"), ("roi", "The camera's point of interest"))
SOURCES = ("given", "nmea+udp://:10110", "gpsd://127.0.0.1:2947", "nmea+serial:///dev/ttyUSB0?baud=4800")


def _spin(low: float, high: float, value: float, suffix: str, step: float = 1.0) -> QDoubleSpinBox:
    box = QDoubleSpinBox()
    box.setRange(low, high)
    box.setDecimals(1)
    box.setSingleStep(step)
    box.setValue(value)
    box.setSuffix(suffix)
    return box


class ShotsPanel(QWidget):
    orbitAsked = pyqtSignal(float, float, str)          # radius m (0: where the vehicle is), speed m/s, centre
    recordAsked = pyqtSignal()
    clearAsked = pyqtSignal()
    saveAsked = pyqtSignal()
    loadAsked = pyqtSignal()
    cableAsked = pyqtSignal(float)                      # cruise speed m/s (0: the sticks)
    selfieAsked = pyqtSignal(float, float, float)       # distance, rise, speed
    followAsked = pyqtSignal(str, str)                  # source, engine
    panoAsked = pyqtSignal(str, float, float, float)    # shape, fov, lens, pitch
    buttonAsked = pyqtSignal(str)                       # pause, resume, reverse, stop

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._shown: tuple | None = None
        self.status = QLabel("No shot")
        self.status.setWordWrap(True)
        self.status.setStyleSheet("font-weight: bold")
        self.detail = QLabel("")
        self.detail.setWordWrap(True)
        self.progress = QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(True)
        self.progress.hide()
        self.tabs = QTabWidget()
        self.tabs.addTab(self._orbit_page(), "Orbit")
        self.tabs.addTab(self._cable_page(), "Cable")
        self.tabs.addTab(self._selfie_page(), "Selfie")
        self.tabs.addTab(self._follow_page(), "Follow")
        self.tabs.addTab(self._pano_page(), "Pano")
        buttons = QHBoxLayout()
        self.running_buttons = {}
        for key, text, tip in (("pause", "Pause", "Stop moving along the shot; the sticks still move it"),
                               ("resume", "Resume", "Cruise on"), ("reverse", "Reverse", "Cruise the other way"),
                               ("stop", "End shot", "End the shot and hold where the vehicle is")):
            b = QPushButton(text)
            b.setToolTip(tip)
            b.clicked.connect(lambda _=False, k=key: self.buttonAsked.emit(k))
            buttons.addWidget(b)
            self.running_buttons[key] = b
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addWidget(self.status)
        layout.addWidget(self.detail)
        layout.addWidget(self.progress)
        layout.addLayout(buttons)
        layout.addWidget(self.tabs, 1)
        self.start_buttons: list[QPushButton] = [self.orbit_button, self.play_button, self.selfie_button,
                                                 self.follow_button, self.pano_button]

    # -- the pages ---------------------------------------------------------------------------------------
    def _page(self, rows, button: QPushButton, extra: QWidget | None = None) -> QWidget:
        page = QWidget()
        form = QFormLayout(page)
        for label, widget in rows:
            form.addRow(label, widget)
        if extra is not None:
            form.addRow(extra)
        form.addRow(button)
        return page

    def _orbit_page(self) -> QWidget:
        self.orbit_centre = QComboBox()
        for key, text in CENTRES:
            self.orbit_centre.addItem(text, key)
        self.orbit_radius = _spin(0.0, 200.0, 0.0, " m")
        self.orbit_radius.setSpecialValueText("where it is")
        self.orbit_speed = _spin(-8.0, 8.0, 3.0, " m/s", 0.5)
        self.orbit_speed.setToolTip("Positive: clockwise seen from above; 0: the sticks alone")
        self.orbit_button = QPushButton("Orbit")
        self.orbit_button.setToolTip("Circle the centre with the camera on it (or right-click the map: Orbit here)")
        self.orbit_button.clicked.connect(lambda: self.orbitAsked.emit(
            self.orbit_radius.value(), self.orbit_speed.value(), self.orbit_centre.currentData()))
        return self._page((("Centre", self.orbit_centre), ("Radius", self.orbit_radius),
                           ("Speed", self.orbit_speed)), self.orbit_button)

    def _cable_page(self) -> QWidget:
        self.keyframes_label = QLabel("0 keyframes")
        self.record_button = QPushButton("Record keyframe")
        self.record_button.setToolTip("Where the vehicle is and where its camera looks, as the cable's next keyframe")
        self.record_button.clicked.connect(self.recordAsked)
        row = QWidget()
        files = QHBoxLayout(row)
        files.setContentsMargins(0, 0, 0, 0)
        for text, signal in (("Clear", self.clearAsked), ("Save…", self.saveAsked), ("Load…", self.loadAsked)):
            b = QPushButton(text)
            b.clicked.connect(signal)
            files.addWidget(b)
        self.cable_speed = _spin(0.0, 8.0, 5.0, " m/s", 0.5)
        self.play_button = QPushButton("Play cable")
        self.play_button.clicked.connect(lambda: self.cableAsked.emit(self.cable_speed.value()))
        page = self._page((("Keyframes", self.keyframes_label), ("", self.record_button), ("", row),
                           ("Cruise", self.cable_speed)), self.play_button)
        return page

    def _selfie_page(self) -> QWidget:
        self.selfie_distance = _spin(1.0, 200.0, 30.0, " m")
        self.selfie_rise = _spin(0.0, 100.0, 15.0, " m")
        self.selfie_speed = _spin(0.5, 8.0, 3.0, " m/s", 0.5)
        self.selfie_button = QPushButton("Selfie")
        self.selfie_button.setToolTip("Out and up away from the pilot (home) and back, the camera on the pilot")
        self.selfie_button.clicked.connect(lambda: self.selfieAsked.emit(
            self.selfie_distance.value(), self.selfie_rise.value(), self.selfie_speed.value()))
        return self._page((("Out", self.selfie_distance), ("Up", self.selfie_rise), ("Speed", self.selfie_speed)),
                          self.selfie_button)

    def _follow_page(self) -> QWidget:
        self.follow_source = QComboBox()
        self.follow_source.setEditable(True)
        self.follow_source.addItems(SOURCES)
        self.follow_source.setCurrentText(SOURCES[1])
        self.follow_source.setToolTip("This computer's GPS: NMEA over UDP, TCP or a serial port, or gpsd; "
                                      "'given' for positions sent through the API")
        self.follow_engine = QComboBox()
        self.follow_engine.addItems(("auto", "follow", "guided"))
        self.follow_engine.setToolTip("follow: ArduCopter's FOLLOW mode (needs FOLL_ENABLE 1); guided: flown by the "
                                      "driver, the sticks swing round the target; auto: FOLLOW where it can")
        self.follow_button = QPushButton("Follow")
        self.follow_button.clicked.connect(lambda: self.followAsked.emit(
            self.follow_source.currentText().strip() or "given", self.follow_engine.currentText()))
        return self._page((("Target", self.follow_source), ("Engine", self.follow_engine)), self.follow_button)

    def _pano_page(self) -> QWidget:
        self.pano_shape = QComboBox()
        self.pano_shape.addItems(("cylinder", "sphere"))
        self.pano_fov = _spin(30.0, 360.0, 360.0, "°", 10.0)
        self.pano_lens = _spin(20.0, 180.0, 74.0, "°")
        self.pano_pitch = _spin(-90.0, 0.0, 0.0, "°", 5.0)
        self.pano_button = QPushButton("Pano")
        self.pano_button.clicked.connect(lambda: self.panoAsked.emit(
            self.pano_shape.currentText(), self.pano_fov.value(), self.pano_lens.value(), self.pano_pitch.value()))
        return self._page((("Shape", self.pano_shape), ("Across", self.pano_fov), ("Lens", self.pano_lens),
                           ("Pitch", self.pano_pitch)), self.pano_button)

    # -- state in ------------------------------------------------------------------------------------------
    def show_shot(self, shot: ShotState, can_start: bool) -> None:
        key = (shot, can_start)
        if key == self._shown:
            return
        self._shown = key
        self.status.setText(shot.describe().capitalize() if shot.kind is not ShotKind.NONE else "No shot")
        parts = []
        if shot.active and shot.aim_error is not None:
            parts.append(f"camera {shot.aim_error:.1f}° off its look")
        if shot.radius is not None and shot.kind is ShotKind.ORBIT and shot.active:
            parts.append(f"radius {shot.radius:.1f} m" + (f" of {shot.radius_wanted:.0f}" if shot.radius_wanted
                                                         else ""))
        if shot.target_distance is not None and shot.active:
            parts.append(f"target {shot.target_distance:.1f} m, fix {shot.target_age or 0:.1f} s old")
        self.detail.setText(" · ".join(parts))
        total = shot.photos_total
        if shot.progress is not None or total:
            value = shot.photos / total if total else shot.progress
            self.progress.setValue(int(round(1000 * max(0.0, min(1.0, value)))))
            self.progress.setFormat(f"{shot.photos} of {total} pictures" if total else f"{100 * value:.0f} % along")
            self.progress.show()
        else:
            self.progress.hide()
        self.keyframes_label.setText(f"{len(shot.keyframes)} keyframe{'s' if len(shot.keyframes) != 1 else ''}")
        for b in self.start_buttons:
            b.setEnabled(can_start and not shot.active)
        self.play_button.setEnabled(can_start and not shot.active and len(shot.keyframes) >= 2)
        self.record_button.setEnabled(can_start and not (shot.active and shot.kind is ShotKind.CABLE))
        cruising = shot.active and shot.phase in (ShotPhase.FLYING, ShotPhase.PAUSED, ShotPhase.ATTACHING)
        for key, b in self.running_buttons.items():
            b.setEnabled(shot.active if key == "stop" else cruising)
