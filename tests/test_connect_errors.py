"""File › Connect says why a link does not open, where the pilot asked and at once: a refused port or an unknown host
said "no heartbeat in 15 s" while the log held "Connection refused"; a pasted command was taken for a host and the
question about leaving the airborne vehicle came before the address was checked; File › Disconnect in flight spoke
of "the new connection". Real window, real driver, real simulated vehicle, real sockets.
"""
from __future__ import annotations

import socket

import pytest
from PyQt5.QtCore import Qt

from uavviewer.connect.choice import Choice, Kind
from uavviewer.connect.dialog import KINDS

from test_connect_window import connecting  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def dead_port() -> int:
    """A local TCP port nobody listens on (bound, then let go): connecting to it is refused."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def resolver_words(host: str) -> str:
    """What this system's resolver says of ``host``."""
    with pytest.raises(socket.gaierror) as error:
        socket.getaddrinfo(host, 5760)
    return error.value.strerror


def open_connect(qtbot, w, host: str, port: int):
    w.actionConnect.trigger()
    dialog = w.tools.connect_dialog
    qtbot.waitExposed(dialog)
    dialog.kind.setCurrentIndex(KINDS.index("TCP"))
    dialog.tcp_host.setText(host)
    dialog.tcp_port.setValue(port)
    return dialog


@pytest.mark.parametrize("host", ["127.0.0.1", "no-such-host.invalid"], ids=["refused port", "unknown host"])
def test_the_systems_reason_is_said_in_the_dialog_while_the_link_is_still_tried(qtbot, vehicle, connecting, host):
    w = connecting(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    w.connections.answer_timeout = 4.0                  # ANSWER_TIMEOUT (15 s), shortened for the test
    port = dead_port()
    reason = "Connection refused" if host == "127.0.0.1" else resolver_words(host)
    failures = []
    w.connections.failed.connect(failures.append)
    dialog = open_connect(qtbot, w, host, port)
    qtbot.mouseClick(dialog.connect_button, Qt.LeftButton)
    assert dialog.isVisible() and not dialog.connect_button.isEnabled()    # it stays, saying what it does
    assert "up to 4 s" in dialog.progress.text() and "up to 4 s" in w.statusbar.currentMessage()   # the limit, first
    qtbot.waitUntil(lambda: reason in dialog.problem.text(), timeout=10000)
    assert w.connections.busy and not failures          # said at once: the link is still being tried
    qtbot.waitUntil(lambda: bool(failures), timeout=10000)
    assert reason in failures[0] and "no heartbeat in 4 s" in failures[0]   # and in the final error
    assert reason in dialog.problem.text() and dialog.connect_button.isEnabled() and dialog.isVisible()
    assert w.adapter.drone is vehicle


def test_a_bad_address_is_said_before_any_question_and_disconnect_speaks_of_disconnecting(qtbot, flying,
                                                                                             connecting):
    w = connecting(flying)
    qtbot.waitUntil(lambda: w.adapter.state.flying and w.adapter.state.connected, timeout=10000)
    dialog = open_connect(qtbot, w, "no such host!! ;rm", 5760)
    qtbot.mouseClick(dialog.connect_button, Qt.LeftButton)
    assert "not a host name" in dialog.problem.text()
    assert w.tools.leave_box is None and not w.connections.busy and w.adapter.drone is flying
    dialog.reject()

    w.tools.connect_to(Choice(Kind.MAVLINK, "udpout:no such host!! ;rm:14550"))    # File › Recent, say
    assert "not a host name" in w.statusbar.currentMessage() and w.tools.leave_box is None
    assert not w.connections.busy and w.adapter.drone is flying

    w.actionDisconnect.trigger()                         # File › Disconnect, in the air
    qtbot.waitUntil(lambda: w.tools.leave_box is not None and w.tools.leave_box.isVisible(), timeout=3000)
    text = w.tools.leave_box.text()
    assert "new connection" not in text and "Disconnect lets go of it now" in text
    w.tools.leave_box.button(w.tools.leave_box.Cancel).click()
    assert w.adapter.drone is flying
