"""Setup › Frame: FRAME_CLASS and FRAME_TYPE as the vehicle reports them, the motor order drawn (numbered motors,
test letters, spin directions). ArduCopter reads the frame at boot: after a change the page says a reboot is
needed and offers it (only disarmed). Changes go through the Parameters review."""
from __future__ import annotations

from PyQt5.QtWidgets import QComboBox, QFormLayout, QHBoxLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from .frame_drawing import FrameDrawing

__all__ = ["FramePage"]

CLASSES = {0: "Undefined", 1: "Quad", 2: "Hexa", 3: "Octa", 4: "OctaQuad", 5: "Y6", 6: "Heli", 7: "Tri",
           10: "Single", 11: "Coax", 12: "BiCopter", 13: "Heli dual", 14: "DodecaHexa", 15: "HeliQuad", 16: "Deca"}
TYPES = {0: "Plus", 1: "X", 2: "V", 3: "H", 4: "V-Tail", 5: "A-Tail", 10: "Y6B", 11: "Y6F", 12: "BetaFlight X",
         13: "DJI X", 14: "Clockwise X", 15: "I", 18: "BetaFlight X reversed"}


def _combo(items: dict[int, str]) -> QComboBox:
    box = QComboBox()
    for number, name in items.items():
        box.addItem(f"{name} ({number})", number)
    return box


class FramePage(QWidget):
    title = "Frame"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        self._booted: tuple | None = None         # the frame the vehicle had when first read: what it flies
        self._reported: tuple | None = None
        layout = QHBoxLayout(self)
        left = QVBoxLayout()
        form = QFormLayout()
        self.frame_class = _combo(CLASSES)
        self.frame_type = _combo(TYPES)
        form.addRow("Frame class", self.frame_class)
        form.addRow("Frame type", self.frame_type)
        left.addLayout(form)
        self.write = QPushButton("Write…")
        self.write.setObjectName("setupFrameWrite")
        self.write.clicked.connect(self.write_changes)
        left.addWidget(self.write)
        self.status = QLabel("")
        self.status.setObjectName("setupFrameStatus")
        self.status.setWordWrap(True)
        left.addWidget(self.status)
        self.reboot = QPushButton("Reboot the vehicle")
        self.reboot.setObjectName("setupFrameReboot")
        self.reboot.setVisible(False)
        self.reboot.clicked.connect(lambda: self._runner.reboot())
        left.addWidget(self.reboot)
        left.addWidget(QLabel("Outputs numbered, test order lettered (A = first),\n"
                              "green clockwise, blue counter-clockwise."))
        left.addStretch(1)
        layout.addLayout(left)
        self.drawing = FrameDrawing()
        layout.addWidget(self.drawing, 1)

    def write_changes(self) -> None:
        wanted = {"FRAME_CLASS": float(self.frame_class.currentData()),
                  "FRAME_TYPE": float(self.frame_type.currentData())}
        reported = dict(zip(("FRAME_CLASS", "FRAME_TYPE"), self._reported or ()))
        self.status.setText(self._runner.propose_changes(wanted, reported))

    def show_state(self, s) -> None:
        if not s.connected:
            self._booted = None                   # a reboot (or another link): what it reads next is what it flies
        c, t = s.parameters.get("FRAME_CLASS"), s.parameters.get("FRAME_TYPE")
        if c is None or t is None:
            self.drawing.set_frame(None, None)
            return
        reported = (int(c.value), int(t.value))
        if self._booted is None:
            self._booted = reported
        if reported != self._reported:
            self._reported = reported
            self.frame_class.setCurrentIndex(max(0, self.frame_class.findData(reported[0])))
            self.frame_type.setCurrentIndex(max(0, self.frame_type.findData(reported[1])))
            self.drawing.set_frame(*reported)
        reboot = reported != self._booted
        self.reboot.setVisible(reboot)
        self.reboot.setEnabled(reboot and not s.armed)
        if reboot:
            self.status.setText("The vehicle reads its frame at boot: reboot it for the new frame to fly"
                                + (" (disarm first)." if s.armed else "."))
