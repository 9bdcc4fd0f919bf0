"""Setup › Power: the battery monitor, capacity, cells and the battery failsafe as the vehicle reports them, and
the voltage and current calibration: the pilot types what a meter reads, BATT_VOLT_MULT (BATT_AMP_PERVLT) is
scaled by meter / reported and proposed through the Parameters review."""
from __future__ import annotations

import math

from PyQt5.QtWidgets import QDoubleSpinBox, QFormLayout, QGroupBox, QLabel, QPushButton, QVBoxLayout, QWidget

from .failsafe_words import BATTERY_ACTIONS

__all__ = ["PowerPage", "corrected"]

_MONITORS = {0: "none", 3: "analog voltage", 4: "analog voltage and current", 5: "Solo", 7: "SMBus", 9: "ESC"}


def corrected(multiplier: float | None, reported: float | None, measured: float) -> float | None:
    """The multiplier that makes ``reported`` read ``measured``; None when it cannot be known (no reading)."""
    if multiplier is None or not reported or not measured or reported <= 0 or measured <= 0:
        return None
    value = multiplier * measured / reported
    return round(value, 4) if math.isfinite(value) else None


class PowerPage(QWidget):
    title = "Power"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        self._state = None
        layout = QVBoxLayout(self)
        self.info = QLabel("Battery: parameters not read yet")
        self.info.setObjectName("setupPowerInfo")
        self.info.setWordWrap(True)
        layout.addWidget(self.info)
        box = QGroupBox("Calibrate with a meter")
        form = QFormLayout(box)
        self.measured_volts = QDoubleSpinBox()
        self.measured_volts.setRange(0.0, 100.0)
        self.measured_volts.setDecimals(2)
        self.measured_volts.setSuffix(" V")
        self.volts = QPushButton("Correct BATT_VOLT_MULT…")
        self.volts.setObjectName("setupVoltCalibrate")
        self.volts.clicked.connect(lambda: self._calibrate("BATT_VOLT_MULT", self.measured_volts.value(), "voltage"))
        self.measured_amps = QDoubleSpinBox()
        self.measured_amps.setRange(0.0, 500.0)
        self.measured_amps.setDecimals(2)
        self.measured_amps.setSuffix(" A")
        self.amps = QPushButton("Correct BATT_AMP_PERVLT…")
        self.amps.clicked.connect(lambda: self._calibrate("BATT_AMP_PERVLT", self.measured_amps.value(), "current"))
        form.addRow("The meter reads", self.measured_volts)
        form.addRow("", self.volts)
        form.addRow("The meter reads", self.measured_amps)
        form.addRow("", self.amps)
        layout.addWidget(box)
        self.status = QLabel("")
        self.status.setObjectName("setupPowerStatus")
        self.status.setWordWrap(True)
        layout.addWidget(self.status)
        layout.addStretch(1)

    def _calibrate(self, name: str, measured: float, what: str) -> None:
        s = self._state
        param = s.parameters.get(name) if s else None
        reported = getattr(s.battery, what, None) if s else None
        value = corrected(param.value if param else None, reported, measured)
        if value is None:
            self.status.setText(f"Not proposed: the vehicle reports no {what} or no {name} yet, or the meter "
                                "reading is 0.")
            return
        self.status.setText(f"{name} {param.value:g} → {value:g} (the vehicle reads {reported:.2f}, the meter "
                            f"{measured:.2f}): " + self._runner.propose_changes({name: value}, {name: param.value}))

    def show_state(self, s) -> None:
        self._state = s

        def v(name):
            p = s.parameters.get(name)
            return None if p is None else p.value
        monitor = v("BATT_MONITOR")
        if monitor is None:
            return
        b = s.battery
        reading = ("no reading" if b.voltage is None else f"{b.voltage:.2f} V" +
                   ("" if b.current is None else f", {b.current:.1f} A"))
        self.info.setText(
            f"Monitor: {_MONITORS.get(int(monitor), f'type {monitor:g}')} (BATT_MONITOR {monitor:g}); "
            f"capacity {v('BATT_CAPACITY') or 0:g} mAh; cells: {b.cells or 'not known'}; now {reading}.\n"
            f"Low below {v('BATT_LOW_VOLT') or 0:g} V: {BATTERY_ACTIONS.get(int(v('BATT_FS_LOW_ACT') or 0))}; "
            f"critical below {v('BATT_CRT_VOLT') or 0:g} V: {BATTERY_ACTIONS.get(int(v('BATT_FS_CRT_ACT') or 0))}.")
