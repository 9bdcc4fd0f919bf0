"""Setup › Frame: the motor layouts of every frame ArduCopter sets up (uavviewer/setup/frames.json, written by
scripts/frames-table from AP_MotorsMatrix.cpp and AP_MotorsTri.cpp), checked as data and against values copied from
ArduPilot 4.6.3's source, and the page drawing the ones a pilot picks."""
from __future__ import annotations

from dataclasses import replace

import pytest
from PyQt5.QtGui import QColor

from driver.params.model import Parameter, ParameterTable, ParameterValues
from driver.vehicle.state import LinkHealth, LinkStatus, VehicleState
from uavviewer.setup.frame_page import CLASSES, TYPES, FramePage
from uavviewer.setup.frames import CCW, CW, layout, layouts

#: (FRAME_CLASS, FRAME_TYPE) ArduCopter sets up (AP_MotorsMatrix::setup_*_matrix's cases, AP_MotorsTri) that the
#: page must draw: every type of quad, hexa, octa, octaquad (X8), Y6, tri, dodecahexa and deca but the V/A-tail
REQUIRED = ([(1, t) for t in (0, 1, 2, 3, 6, 12, 13, 14, 18, 19)] + [(2, t) for t in (0, 1, 3, 13, 14)]
            + [(3, t) for t in (0, 1, 2, 3, 13, 14, 15)] + [(4, t) for t in (0, 1, 2, 3, 12, 14, 18)]
            + [(5, t) for t in (0, 1, 10, 11)] + [(7, t) for t in (0, 1, 6)] + [(12, 0), (12, 1)]
            + [(14, t) for t in (0, 1, 14)])


@pytest.mark.parametrize("frame", REQUIRED, ids=lambda f: f"{f[0]}-{f[1]}")
def test_every_matrix_frame_has_a_layout(frame):
    assert layout(*frame) is not None, frame


@pytest.mark.parametrize("key", sorted(layouts(), key=str), ids=lambda k: f"{k[0]}-{k[1]}")
def test_each_layout_is_whole(key):
    frame = layouts()[key]
    tests = sorted(m.test for m in frame.motors)
    assert tests == list(range(1, len(frame.motors) + 1)), "the test order is a permutation of 1..n"
    outputs = [m.output for m in frame.motors]
    assert len(set(outputs)) == len(outputs)
    assert all(-180 < m.angle <= 180 and 0 < m.radius < 2 for m in frame.motors)
    spins = [m.spin for m in frame.motors if not m.servo]
    if frame.frame_class == 7:                                  # the tricopter yaws with its servo
        assert spins == [None] * 3 and [m.output for m in frame.motors if m.servo] == [7]
    else:
        assert spins.count(CW) == spins.count(CCW) == len(spins) / 2, "a matrix frame's torques balance"


def test_spot_checks_copied_from_the_source():
    """Rows typed from libraries/AP_Motors/AP_MotorsMatrix.cpp and AP_MotorsTri.cpp at 92b0cd78 (4.6.3): (output,
    angle, spin, test)."""
    def rows(c, t):
        return {m.output: (m.angle, m.spin, m.test) for m in layout(c, t).motors}
    quad_x = rows(1, 1)                          # { 45, CCW, 1 }, { -135, CCW, 3 }, { -45, CW, 4 }, { 135, CW, 2 }
    assert quad_x == {1: (45, CCW, 1), 2: (-135, CCW, 3), 3: (-45, CW, 4), 4: (135, CW, 2)}
    assert rows(1, 0)[3] == (0, CW, 1)           # quad +: { 0, CW, 1 } is output 3
    assert rows(1, 3)[1] == (45, CW, 1)          # quad H: X with the spins reversed
    assert rows(2, 1)[5] == (30, CCW, 1)         # hexa X: { 30, CCW, 1 } is output 5
    octa_x = rows(3, 1)                          # { 22.5, CW, 1 }, { -157.5, CW, 5 }, ..., { 112.5, CW, 3 }
    assert octa_x[1] == (22.5, CW, 1) and octa_x[2] == (-157.5, CW, 5) and octa_x[8] == (112.5, CW, 3)
    x8 = rows(4, 1)                              # octaquad X: { 45, CCW, 1 } over { 45, CW, 2 } (output 6)
    assert x8[1] == (45, CCW, 1) and x8[6] == (45, CW, 2) and x8[5] == (-45, CCW, 8)
    y6b = layout(5, 10).motors                   # { -1, 0.5, CW, 1 }, { -1, 0.5, CCW, 2 }: one arm, both motors
    assert (y6b[0].angle, y6b[0].spin, y6b[1].spin) == (y6b[1].angle, CW, CCW) and y6b[0].angle == pytest.approx(63.4)
    tri = {m.output: (m.test, m.servo) for m in layout(7, 0).motors}
    assert tri == {1: (1, False), 4: (2, False), 7: (3, True), 2: (4, False)}   # _output_test_seq 1..4
    assert layout(5, 0).name == "Y6/default" and layout(7, 6).name == "TRI/PLUSREV"


def test_the_page_names_every_frame():
    assert {CLASSES[c] for c in (3, 4, 5, 7, 12, 14)} == {"Octa", "OctaQuad (X8)", "Y6", "Tri", "DodecaHexa", "Deca"}
    assert {TYPES[t] for t in (2, 3, 10, 11, 15, 19)} == {"V", "H", "Y6B", "Y6F", "I", "Y4"}
    assert CLASSES[10] == "BiCopter" and CLASSES[11] == "Heli Dual"      # ArduCopter's FRAME_CLASS numbers


class _Runner:
    def propose_changes(self, wanted, reported):
        return ""


def _state(frame_class: int, frame_type: int) -> VehicleState:
    values = {n: Parameter(n, float(v)) for n, v in (("FRAME_CLASS", frame_class), ("FRAME_TYPE", frame_type))}
    return VehicleState(link=LinkHealth(status=LinkStatus.OK),
                        parameters=ParameterTable(values=ParameterValues(values), expected=2))


def _colours(widget) -> set[str]:
    image = widget.grab().toImage()
    return {QColor(image.pixel(x, y)).name() for x in range(0, image.width(), 2) for y in range(0, image.height(), 2)}


@pytest.mark.parametrize("frame, name", [((3, 1), "OCTA/X"), ((5, 10), "Y6/Y6B"), ((7, 0), "TRI")])
def test_the_frame_page_draws_a_chosen_frame(qtbot, frame, name):
    page = FramePage(_Runner())
    qtbot.addWidget(page)
    page.resize(700, 420)
    page.show()
    page.show_state(_state(1, 1))                                   # the vehicle: a quad X
    assert "QUAD/X" in page.drawn.text() and "the vehicle's frame" in page.drawn.text()
    page.frame_class.setCurrentIndex(page.frame_class.findData(frame[0]))
    page.frame_type.setCurrentIndex(page.frame_type.findData(frame[1]))
    assert page.drawing.missing() == "" and page.drawing.layout_.name == name
    assert name in page.drawn.text() and "not the vehicle's" in page.drawn.text()
    colours = _colours(page.drawing)
    if frame[0] == 7:
        assert "#6a1b9a" in colours                                  # the yaw servo drawn
    else:
        assert {"#2e7d32", "#1565c0"} <= colours                     # clockwise and counter-clockwise rotors
    page.show_state(_state(1, 1))                                   # a new snapshot keeps the pilot's choice
    assert page.drawing.layout_.name == name


def test_a_helicopter_says_why_it_is_not_drawn(qtbot):
    page = FramePage(_Runner())
    qtbot.addWidget(page)
    page.show_state(_state(6, 0))
    assert page.drawing.missing().startswith("No drawing for this frame: FRAME_CLASS 6 is a helicopter")


def test_the_cached_table_shown_while_the_list_is_read_is_not_taken_for_the_booted_frame(qtbot):
    """The parameter cache (the vehicle as last seen: a quad) shows while its own list is read (an octa): that is
    no frame change waiting for a reboot."""
    page = FramePage(_Runner())
    qtbot.addWidget(page)
    cached = _state(1, 1)
    page.show_state(replace(cached, parameters=replace(cached.parameters, downloading=True)))
    page.show_state(_state(3, 1))
    assert page.drawing.layout_.name == "OCTA/X" and page.reboot.isHidden()
    assert "reboot" not in page.status.text()
