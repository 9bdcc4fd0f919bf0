"""Setup › Frame: FRAME_CLASS and FRAME_TYPE as the vehicle reports them, the motor order drawn (numbered motors,
test letters, spin directions) for every frame ArduCopter sets up (frames.py); a frame picked in the lists is drawn
at once, before anything is written, and the page says so. ArduCopter reads the frame at boot: after a change the page says a reboot is
needed and offers it (only disarmed). Changes go through the Parameters review."""
from __future__ import annotations

from PyQt5.QtWidgets import QComboBox, QFormLayout, QHBoxLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from .frame_drawing import FrameDrawing

__all__ = ["FramePage"]

# ArduCopter's own names (Parameters.cpp: FRAME_CLASS and FRAME_TYPE @Values; 6 PLUSREV from AP_Motors_Class.h,
# which @Values leaves out, though AP_MotorsMatrix and AP_MotorsTri set it up)
CLASSES = {0: "Undefined", 1: "Quad", 2: "Hexa", 3: "Octa", 4: "OctaQuad (X8)", 5: "Y6", 6: "Heli", 7: "Tri",
           8: "SingleCopter", 9: "CoaxCopter", 10: "BiCopter", 11: "Heli Dual", 12: "DodecaHexa", 13: "HeliQuad",
           14: "Deca", 15: "Scripting Matrix", 16: "6DoF Scripting", 17: "Dynamic Scripting Matrix"}
TYPES = {0: "Plus", 1: "X", 2: "V", 3: "H", 4: "V-Tail", 5: "A-Tail", 6: "Plus reversed", 10: "Y6B", 11: "Y6F",
         12: "BetaFlight X", 13: "DJI X", 14: "Clockwise X", 15: "I", 18: "BetaFlight X reversed", 19: "Y4"}


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
        self.frame_class.currentIndexChanged.connect(lambda _i: self._draw_chosen())
        self.frame_type.currentIndexChanged.connect(lambda _i: self._draw_chosen())
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
        self.drawn = QLabel("")
        self.drawn.setObjectName("setupFrameDrawn")
        self.drawn.setWordWrap(True)
        left.addWidget(self.drawn)
        left.addWidget(QLabel("Outputs numbered, test order lettered (A = first),\n"
                              "green clockwise, blue counter-clockwise;\n"
                              "a coaxial arm's two motors side by side;\n"
                              "the tricopter's yaw servo in purple."))
        left.addStretch(1)
        layout.addLayout(left)
        self.drawing = FrameDrawing()
        layout.addWidget(self.drawing, 1)

    def chosen(self) -> tuple[int, int]:
        return int(self.frame_class.currentData()), int(self.frame_type.currentData())

    def _draw_chosen(self) -> None:
        """The lists' frame drawn; said to be the vehicle's only when it is what the vehicle reported."""
        chosen = self.chosen()
        self.drawing.set_frame(*chosen)
        name = self.drawing.layout_.name if self.drawing.layout_ else self.drawing.missing()
        self.drawn.setText(f"Drawn: the vehicle's frame, {name}." if chosen == self._reported else
                           f"Drawn: {name}, as chosen here — not the vehicle's until written and rebooted.")

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
            return                                # not read yet: "Frame not read yet", or what the pilot picked
        reported = (int(c.value), int(t.value))
        if self._booted is None and not s.parameters.downloading:
            self._booted = reported               # the vehicle's own list, not the cache shown while it is read
        if reported != self._reported:
            self._reported = reported
            self.frame_class.setCurrentIndex(max(0, self.frame_class.findData(reported[0])))
            self.frame_type.setCurrentIndex(max(0, self.frame_type.findData(reported[1])))
            self._draw_chosen()
        reboot = self._booted is not None and reported != self._booted
        self.reboot.setVisible(reboot)
        self.reboot.setEnabled(reboot and not s.armed)
        if reboot:
            self.status.setText("The vehicle reads its frame at boot: reboot it for the new frame to fly"
                                + (" (disarm first)." if s.armed else "."))
