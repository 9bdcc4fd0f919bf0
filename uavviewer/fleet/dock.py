"""The Fleet dock (docs/fleet.md): several vehicles in one window. The sticks, keys, buttons and instruments follow
the picked one; the map shows all of them, and a click on one there picks it too. Take off, land or stop every
vehicle after one confirmation (for a takeoff Cancel is the focused default, as for one vehicle).
"""
from __future__ import annotations

from PyQt5.QtCore import QObject, Qt
from PyQt5.QtWidgets import QDockWidget, QMessageBox, QWidget

from driver.vehicle.api import Drone

from ..widgets.ask import ask
from .controller import FleetController
from .panel import FleetPanel

__all__ = ["FleetDock", "all_vehicles_question"]


def all_vehicles_question(parent: QWidget, command: str, names: list[str], altitude: float) -> QMessageBox:
    """One confirmation for Take off / Land / Stop on every vehicle of the fleet (window-modal, not waited on).

    For a takeoff Cancel is the focused default, as for one vehicle; for Land and Stop the action is."""
    what = {"takeoff": (f"Take off all {len(names)} vehicles", f"Every vehicle takes off and climbs to "
                        f"{altitude:.1f} m above its home. The motors will start: keep clear of all of them."),
            "land": (f"Land all {len(names)} vehicles", "Every vehicle switches to LAND where it is."),
            "stop": (f"Stop all {len(names)} vehicles", "Every vehicle stops and holds its position.")}[command]
    box = QMessageBox(QMessageBox.Question, what[0], f"{what[0]}?\n\n{', '.join(names)}\n\n{what[1]}",
                      QMessageBox.Yes | QMessageBox.Cancel, parent)
    box.setObjectName("allVehiclesQuestion")
    go = box.button(QMessageBox.Yes)
    go.setText(what[0])
    if command == "takeoff":
        go.setFocusPolicy(Qt.NoFocus)
        go.setAutoDefault(False)
        box.setDefaultButton(QMessageBox.Cancel)
    else:
        box.setDefaultButton(QMessageBox.Yes)
    box.setEscapeButton(QMessageBox.Cancel)
    return box


class FleetDock(QObject):
    """``window``: the main window; ``window.fleet`` and ``window.fleet_panel`` are the fleet flown, if any."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = window
        self.box: QMessageBox | None = None         # the all-vehicles question while open
        window.fleet = window.fleet_panel = None

    def attach(self, fleet: FleetController) -> None:
        """A Fleet dock for ``fleet``, already flying its picked vehicle."""
        w = self.window
        w.fleet, self.box = fleet, None
        w.fleet_panel = panel = FleetPanel()
        dock = QDockWidget("Fleet", w)
        dock.setObjectName("fleetDock")
        dock.setWidget(panel)
        w.addDockWidget(Qt.LeftDockWidgetArea, dock)
        w.resizeDocks([dock], [400], Qt.Horizontal)          # every column in sight, the link age too
        w.menuView.addAction(dock.toggleViewAction())
        panel.vehiclePicked.connect(fleet.pick)
        panel.allRequested.connect(self.request_all)
        fleet.rowsChanged.connect(panel.set_rows)
        fleet.vehiclePicked.connect(self._fly_vehicle)
        fleet.said.connect(w.log_message)
        fleet.resultArrived.connect(w.readouts.show_result)
        fleet.vehiclesRead.connect(w.map.show_fleet)                 # the map shows all of them
        w.mapPanel.mapView.vehicleClicked.connect(fleet.pick)         # a click on one there picks it too
        w.map.use_vehicle(fleet.picked)
        w.setWindowTitle(f"UavViewerPy — {fleet.picked} · {fleet.fleet.description}")
        fleet.start()

    def leave(self) -> None:
        """Another connection replaces the fleet: its panel goes; the fleet itself is closed by the connections."""
        w = self.window
        fleet = w.fleet
        if fleet is None:
            return
        fleet.stop()
        w.mapPanel.mapView.vehicleClicked.disconnect(fleet.pick)
        w.map.show_fleet(())
        dock = w.fleet_panel.parentWidget()
        w.removeDockWidget(dock)
        dock.deleteLater()
        fleet.deleteLater()
        w.fleet = None

    def _fly_vehicle(self, name: str, drone: Drone) -> None:
        w = self.window
        w.sticks.centre()                       # the vehicle left behind gets zero velocity: it hovers
        if w.map.use_vehicle(name):             # ... and a Fly here on its way ends where it is, as Stop does
            w.adapter.send(w.adapter.drone.stop)          # (still the previous vehicle: adapter.use comes below)
        w.readouts.follow(drone.state())        # its log starts from now: older lines were another vehicle's
        w.adapter.use(drone)
        w.setWindowTitle(f"UavViewerPy — {name} · {w.fleet.fleet.description}")
        if w.default_cameras and w.camera.uris == w.default_cameras:   # not --camera nor Preferences'
            w.default_cameras = [w.fleet.camera_uri(name)]              # the picked vehicle's own
            w.camera.set_sources(w.default_cameras)

    def request_all(self, command: str) -> None:
        """Take off, land or stop every vehicle, after one confirmation."""
        w = self.window
        names = [r.name for r in w.fleet.rows]
        if not names or (self.box is not None and self.box.isVisible()):
            return
        if command != "takeoff":
            w.sticks.centre()
        self.box = ask(all_vehicles_question(w, command, names, w.takeoff_altitude),
                       lambda box: self._all_answered(box, command))

    def _all_answered(self, box: QMessageBox, command: str) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            w = self.window
            args = (w.takeoff_altitude,) if command == "takeoff" else ()
            w.fleet.command_all(command, *args, skip=w.fleet.picked)
            # the picked one through the window's own path (a Fly here ends, a takeoff is checked again);
            # its answer is shown once
            {"takeoff": lambda: w.flight.take_off_if_still_fits(*args), "land": w.flight.request_land,
             "stop": w.flight.request_stop}[command]()
        box.deleteLater()
        if self.box is box:
            self.box = None
