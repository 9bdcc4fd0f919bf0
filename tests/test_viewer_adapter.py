"""The window's door to the vehicle: a command is the drone's own method, and its answer goes back to the caller
that asked, on the UI thread, never inside the call, and never to a caller of a drone no longer flown."""
from __future__ import annotations

from PyQt5.QtCore import QThread
from PyQt5.QtWidgets import QApplication

from driver.vehicle import Vehicle, VehicleConfig
from driver.vehicle.state import CommandStatus
from uavviewer.drone_adapter import DroneAdapter


def test_an_answer_at_once_reaches_the_caller_after_the_call_returned(qtbot):
    """A refusal the driver gives at once (a go-to to nowhere) still comes back on a later turn of the event loop:
    the caller has stored what the call returned before its answer arrives."""
    vehicle = Vehicle(VehicleConfig())                   # never started: the driver itself answers
    adapter = DroneAdapter(vehicle)
    returned, answers, shown = [], [], []
    adapter.commandFinished.connect(shown.append)
    future = adapter.send(vehicle.go_to, float("nan"), 0.0, 10.0,
                          then=lambda result: answers.append((result, list(returned), QThread.currentThread())))
    returned.append(future)
    assert future is not None and future.done() and answers == []
    qtbot.waitUntil(lambda: bool(answers), timeout=2000)
    result, seen, thread = answers[0]
    assert result.status is CommandStatus.REJECTED and "not finite" in result.reason
    assert seen == [future] and thread is QApplication.instance().thread()
    assert shown == [result]                             # Messages has it too, once
    vehicle.close()


def test_an_answer_from_the_drone_flown_before_reaches_messages_only(qtbot):
    """The pilot picked another vehicle (a fleet, File › Connect) while a command to the first was on its way:
    its answer is still said in Messages, but what asked for it now shows the other vehicle and is not told."""
    first, second = Vehicle(VehicleConfig()), Vehicle(VehicleConfig())
    adapter = DroneAdapter(first)
    answers, shown = [], []
    adapter.commandFinished.connect(shown.append)
    adapter.send(adapter.drone.set_mode, "LOITER", then=answers.append)    # no link: it waits for the vehicle
    adapter.use(second)
    first.close()                                         # ... until its driver closes
    qtbot.waitUntil(lambda: bool(shown), timeout=5000)
    assert shown[0].status is CommandStatus.ABORTED and "closed" in shown[0].reason
    adapter.send(adapter.drone.go_to, float("nan"), 0.0, 10.0, then=answers.append)
    qtbot.waitUntil(lambda: bool(answers), timeout=2000)
    assert [r.command for r in answers] == ["go to"]      # the second vehicle's answer only
    second.close()
