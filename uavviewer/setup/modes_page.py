"""Setup › Flight modes: the six modes of the transmitter's mode switch (FLTMODE1..6 on channel FLTMODE_CH),
the slot the switch selects now lit as the vehicle receives it, and simple / super simple per slot (the SIMPLE and
SUPER_SIMPLE bitmasks). Changes go through the Parameters review (the one checked write path)."""
from __future__ import annotations

from PyQt5.QtWidgets import QCheckBox, QComboBox, QGridLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from driver.vehicle.rules import COPTER_MODES

__all__ = ["ModesPage", "slot_of"]

_NAMES = {number: name for name, number in COPTER_MODES.items()}


SLOT_TOPS = (1231, 1361, 1491, 1621, 1750)    # µs: each slot's pulse is below its top (read_6pos_switch)
PWM_LIMITS = (800, 2200)                       # RC_MIN_LIMIT_PWM / RC_MAX_LIMIT_PWM: at or past them, no slot


def slot_of(pwm: int | None) -> int | None:
    """The switch position (1..6) ArduCopter reads from ``pwm`` (RC_Channel::read_6pos_switch), None if unknown
    or out of its limits (the vehicle keeps its mode then)."""
    if not pwm or not PWM_LIMITS[0] < pwm < PWM_LIMITS[1]:
        return None
    for slot, top in enumerate(SLOT_TOPS, start=1):
        if pwm < top:
            return slot
    return 6


def _param(s, name: str) -> float | None:
    p = s.parameters.get(name)
    return None if p is None else p.value


class ModesPage(QWidget):
    title = "Flight modes"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        self._shown: dict[str, float] = {}           # what the vehicle reported, as the widgets show it
        layout = QVBoxLayout(self)
        self.channel = QLabel("Mode switch: channel not read yet")
        self.channel.setObjectName("setupModeChannel")
        layout.addWidget(self.channel)
        grid = QGridLayout()
        grid.addWidget(QLabel("Slot"), 0, 0)
        grid.addWidget(QLabel("Mode"), 0, 1)
        grid.addWidget(QLabel("Simple"), 0, 2)
        grid.addWidget(QLabel("Super simple"), 0, 3)
        self.slots: list[QLabel] = []
        self.modes: list[QComboBox] = []
        self.simple: list[QCheckBox] = []
        self.super_simple: list[QCheckBox] = []
        for i in range(6):
            slot = QLabel(f"  {i + 1}  ")
            mode = QComboBox()
            for number, name in sorted(_NAMES.items()):
                mode.addItem(name, number)
            simple, super_simple = QCheckBox(), QCheckBox()
            for column, widget in enumerate((slot, mode, simple, super_simple)):
                grid.addWidget(widget, i + 1, column)
            self.slots.append(slot)
            self.modes.append(mode)
            self.simple.append(simple)
            self.super_simple.append(super_simple)
        layout.addLayout(grid)
        self.write = QPushButton("Write…")
        self.write.setObjectName("setupModesWrite")
        self.write.clicked.connect(self.write_changes)
        layout.addWidget(self.write)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        layout.addWidget(self.status)
        layout.addStretch(1)
        self.lit: int | None = None

    def wanted(self) -> dict[str, float]:
        values: dict[str, float] = {f"FLTMODE{i + 1}": float(m.currentData()) for i, m in enumerate(self.modes)}
        values["SIMPLE"] = float(sum(1 << i for i, b in enumerate(self.simple) if b.isChecked()))
        values["SUPER_SIMPLE"] = float(sum(1 << i for i, b in enumerate(self.super_simple) if b.isChecked()))
        return values

    def write_changes(self) -> None:
        self.status.setText(self._runner.propose_changes(self.wanted(), self._shown))

    def show_state(self, s) -> None:
        reported = {n: _param(s, n) for n in [f"FLTMODE{i}" for i in range(1, 7)] + ["SIMPLE", "SUPER_SIMPLE"]}
        reported = {n: v for n, v in reported.items() if v is not None}
        if reported != self._shown:                   # the vehicle's values, not over the pilot's edits otherwise
            self._shown = reported
            for i in range(6):
                mode = reported.get(f"FLTMODE{i + 1}")
                if mode is not None:
                    self.modes[i].setCurrentIndex(max(0, self.modes[i].findData(int(mode))))
                self.simple[i].setChecked(bool(int(reported.get("SIMPLE", 0)) >> i & 1))
                self.super_simple[i].setChecked(bool(int(reported.get("SUPER_SIMPLE", 0)) >> i & 1))
        channel = _param(s, "FLTMODE_CH")
        pwm = s.setup.rc.channel(int(channel)) if channel else None
        lit = slot_of(pwm)
        no_setup = self._runner.no_setup()
        self.channel.setText("Mode switch: channel not read yet" if channel is None else
                             f"Mode switch on channel {channel:g}: " + (f"{pwm} µs, slot {lit}" if pwm else
                                                                         "not received"))
        if no_setup:
            self.channel.setText(self.channel.text() + f" (the switch is not shown live: {no_setup})")
        if lit != self.lit:
            self.lit = lit
            for i, label in enumerate(self.slots):
                label.setStyleSheet("background: #2e7d32; color: white; font-weight: bold" if i + 1 == lit else "")
