"""Modes that need an RC transmitter: in flight the window greys out those the driver never commands there (their
throttle is the stick: STABILIZE, ACRO), and asks first for those that only drift without one (ALT_HOLD)."""
from __future__ import annotations

import pytest
from PyQt5.QtWidgets import QMessageBox

from PyQt5.QtCore import Qt

from driver.vehicle.rules import mode_refusal, mode_warning
from viewer_fixtures import pick_mode, viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def test_in_flight_stabilize_is_greyed_out_and_alt_hold_is_asked_first(qtbot, sim, flying, window_factory):
    w = window_factory(flying, takeoff_altitude=3.0)
    sel = w.modeSelector
    qtbot.waitUntil(lambda: sel.mode == "GUIDED", timeout=10000)
    sent: list[str] = []
    w.adapter.commandSent.connect(sent.append)

    for name in ("STABILIZE", "ACRO"):
        index = sel.findText(name)
        qtbot.waitUntil(lambda: not sel.model().item(index).isEnabled(), timeout=3000)
        assert sel.itemData(index, Qt.ToolTipRole) == mode_refusal(name, True) and "RC transmitter" in \
            sel.itemData(index, Qt.ToolTipRole)
    assert sel.model().item(sel.findText("LOITER")).isEnabled()
    assert sent == [] and sim.truth().mode == "GUIDED"

    pick_mode(qtbot, sel, "ALT_HOLD")
    qtbot.waitUntil(lambda: w.flight.mode_box is not None and w.flight.mode_box.isVisible(), timeout=3000)
    box = w.flight.mode_box
    assert box.text() == mode_warning("ALT_HOLD", True) and "RC transmitter" in box.text()
    assert box.defaultButton() is box.button(QMessageBox.Cancel)
    box.button(QMessageBox.Yes).click()
    assert sent == ["set_mode"]
    qtbot.waitUntil(lambda: sim.truth().mode == "ALT_HOLD", timeout=10000)


def test_in_flight_loiter_needs_no_question(qtbot, sim, flying, window_factory):
    w = window_factory(flying, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.modeSelector.mode == "GUIDED", timeout=10000)
    pick_mode(qtbot, w.modeSelector, "LOITER")
    assert w.flight.mode_box is None
    qtbot.waitUntil(lambda: sim.truth().mode == "LOITER", timeout=10000)


def test_on_the_ground_no_mode_needs_a_question():
    assert all(mode_warning(m, flying=False) is None for m in ("STABILIZE", "ACRO", "ALT_HOLD", "DRIFT", "SPORT"))
    assert all(mode_warning(m, flying=True) for m in ("STABILIZE", "ACRO", "ALT_HOLD", "DRIFT", "SPORT"))
    assert mode_warning("LOITER", flying=True) is None
    assert mode_refusal("STABILIZE", may_be_airborne=False) is None


def test_the_console_refuses_stabilize_and_asks_confirm_for_alt_hold_in_flight(flying, sim):
    import io
    from driver.console.console import Console
    out = io.StringIO()
    console = Console(flying, stdout=out)
    console.onecmd("mode STABILIZE")
    assert mode_refusal("STABILIZE", True) in out.getvalue()
    console.onecmd("mode ALT_HOLD")
    assert "mode ALT_HOLD confirm" in out.getvalue()
    assert flying.state().mode == "GUIDED" and sim.truth().mode == "GUIDED"
    console.onecmd("mode LOITER")
    assert flying.wait_for(lambda s: s.mode == "LOITER", 10)
