"""The fleet in the window: two vehicles of a real lab (IceGrid registry, IceStorm) flown from one window."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import QPointF, QRectF, QSizeF, Qt
from PyQt5.QtWidgets import QMessageBox

from uavviewer import app as main
from driver.core import frames
from driver.ice.fleet import IceFleet
from driver.vehicle.state import GlobalPosition, LinkStatus, LocalPosition, Severity, VehicleState
from uavviewer.fleet.controller import FleetController, row_for, switch_message
from uavviewer.map.geometry import MapFrame
from uavviewer.map.controller import fleet_marks, placed
from uavviewer.map.map_view import OTHER, STALE, VEHICLE, MapView, VehicleMark

from fleet_fixtures import fleet, lab  # noqa: F401  (fixtures)
from ice_fixtures import eventually
from test_viewer_flight import body_velocity, click_takeoff, press, release, speed, wait_flying
from test_viewer_map import right_click_fly_here
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(150)


@pytest.fixture
def ice_fleet(lab):
    made = []

    def make() -> IceFleet:
        f = IceFleet(lab.address, refresh=0.3).start()
        made.append(f)
        return f
    yield make
    for f in made:
        f.close()


def test_command_line_takes_a_registry():
    args = main.build_parser().parse_args(["--registry", "10.1.1.5:4061", "--vehicle", "solo-2"])
    assert args.registry == "10.1.1.5:4061" and args.vehicle == "solo-2"
    with pytest.raises(SystemExit):
        main.build_parser().parse_args(["--registry", "10.1.1.5:4061", "--sim"])
    with pytest.raises(SystemExit):
        main.build_parser().parse_args(["--registry", "10.1.1.5:port"])


def test_rows_say_what_each_vehicle_does_and_when_it_is_stale():
    assert row_for("solo-1", None, False, True).link == "waiting"
    fresh = VehicleState()
    row = row_for("solo-1", fresh, True, True)
    assert row.picked and row.stale and row.link == "waiting"          # no heartbeat yet
    text, severity = switch_message("solo-1", fresh, "solo-2")
    assert text == "The sticks, keys and buttons now fly solo-2" and severity is Severity.NOTICE


def test_marks_place_each_vehicle_in_the_picked_vehicles_frame():
    """Other vehicles by their own latitude/longitude, else their own home's plus their metres from it; the picked
    one, a vehicle without a state and one that cannot be placed are left off (no Qt, no network)."""
    frame = MapFrame(66.0, 179.9999)                                      # next to the antimeridian, far north
    lat, lon = frames.offset_latlon(66.0, 179.9999, 30.0, 40.0)           # 30 m north, 40 m east: across it
    lon = (lon + 180.0) % 360.0 - 180.0
    assert lon < -179.99                                                  # as the vehicle reports it
    far = VehicleState(position=GlobalPosition(lat, lon, 0.0), heading_deg=200.0)
    home2 = frames.offset_latlon(66.0, 179.9999, 0.0, -10.0)
    local_only = VehicleState(home=GlobalPosition(*home2, 0.0), local=LocalPosition(north=5.0, east=2.0))
    lost = VehicleState(local=LocalPosition(north=5.0))                   # metres from a home we do not know
    seen = ((row_for("a", far, False, True), far), (row_for("b", local_only, False, False), local_only),
            (row_for("c", lost, False, True), lost), (row_for("d", None, False, True), None),
            (row_for("e", far, True, True), far))
    marks = fleet_marks(frame, seen)
    assert [m.name for m in marks] == ["a", "b"]
    assert (marks[0].east, marks[0].north, marks[0].heading) == pytest.approx((40.0, 30.0, 200.0), abs=0.05)
    assert (marks[1].east, marks[1].north) == pytest.approx((-8.0, 5.0), abs=0.05) and marks[1].stale
    assert fleet_marks(None, seen) == () and placed(None, lost) == (0.0, 5.0)    # its own metres: the picked one only


def test_names_on_the_map_never_cover_each_other_or_an_arrow(qtbot):
    """Three vehicles 10 m apart in a row: zoomed out, the picked one's name is there and another's that has no room
    is left out; zoomed in, every name is there; never two boxes over each other or over an arrow."""
    view = MapView()
    qtbot.addWidget(view)
    view.resize(400, 300)
    view.set_vehicle((0.0, 0.0, 0.0))
    view.set_fleet("solo-1", False, (VehicleMark("solo-2", 10.0, 0.0, 0.0), VehicleMark("solo-3", 20.0, 0.0, 0.0, True)))
    for mpp, shown in ((0.5, ["▶ solo-1", "solo-3"]), (0.1, ["▶ solo-1", "solo-2", "solo-3"])):
        view.zoom_to(mpp)
        arrows = [QRectF(view.to_screen(e, 0.0) - QPointF(9, 9), QSizeF(18, 18)) for e in (0.0, 10.0, 20.0)]
        boxes = view.name_boxes()
        assert [text for _, text, _ in boxes] == shown and [stale for _, _, stale in boxes][-1]
        assert not any(a.intersects(b) for i, (a, _, _) in enumerate(boxes) for b, _, _ in boxes[i + 1:])
        assert not any(box.intersects(arrow) for box, _, _ in boxes for arrow in arrows)


def on_the_map(w, name: str, drone) -> bool:
    """Whether the map draws vehicle ``name`` (not the picked one) where its own state says: its latitude/longitude
    in ground metres from the picked vehicle's home (however far apart the two homes), turned to its heading."""
    view, home, s = w.mapPanel.mapView, w.adapter.state.home, drone.state()
    mark = next((m for m in view.others if m.name == name), None)
    if mark is None or home is None or (view.frame.lat, view.frame.lon) != (home.lat, home.lon):
        return False
    north, east = frames.offset_ned(home.lat, home.lon, s.position.lat, s.position.lon)
    return (math.hypot(mark.east - east, mark.north - north) < 0.1
            and abs((mark.heading - s.heading_deg + 180) % 360 - 180) < 1.0)


def painted(view, east: float, north: float):
    """The colour painted at a point of the map (view metres): the fill of the icon there."""
    return view.grab().toImage().pixelColor(view.to_screen(east, north).toPoint()).name()


def fleet_in_a_window(qtbot, fleet, lab, ice_fleet, window_factory, monkeypatch, **server_properties):
    """Two simulated vehicles registered as solo-1 and solo-2, flown from one window through the registry,
    solo-1 picked; (sims, vehicles, servers, the IceFleet, the window) once both rows are filled."""
    from driver.ice import camera_source as ice_source
    monkeypatch.setitem(ice_source.client_properties, "Ice.Default.Locator", lab.locator)
    sims, vehicles, servers = fleet(2, **server_properties)
    f = ice_fleet()
    assert f.wait_listed(10) and eventually(lambda: f.names() == ("solo-1", "solo-2"), 10)
    w = window_factory(f.drone("solo-1"), takeoff_altitude=3.0, default_cameras=[FleetController.camera_uri("solo-1")])
    controller = FleetController(f, "solo-1", parent=w)
    first_trail = w.map.trail
    w.fleet_dock.attach(controller)
    assert w.map.trail is first_trail                                      # the vehicle flown so far keeps its trail
    panel = w.fleet_panel
    qtbot.waitUntil(lambda: len(panel.row_texts()) == 2 and all("–" not in r for r in panel.row_texts()),
                    timeout=15000)
    return sims, vehicles, servers, f, w


def answer_all(qtbot, w, button, words: str) -> None:
    """A fleet button, and its one confirmation for all."""
    qtbot.mouseClick(button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.fleet_dock.box is not None and w.fleet_dock.box.isVisible(), timeout=3000)
    assert words in w.fleet_dock.box.text()
    qtbot.mouseClick(w.fleet_dock.box.button(QMessageBox.Yes), Qt.LeftButton)


def test_two_vehicles_flown_at_once_from_one_window(qtbot, fleet, lab, ice_fleet, window_factory, monkeypatch):
    sims, vehicles, servers, f, w = fleet_in_a_window(qtbot, fleet, lab, ice_fleet, window_factory, monkeypatch,
                                                      **{"MAVLinkServer.Camera.Uri": "sim"})
    panel = w.fleet_panel
    first, second = panel.row_texts()
    assert first[0] == "▶ solo-1" and second[0] == "solo-2"              # name, mode, armed, battery, link age
    assert first[2] == "disarmed" and first[3].endswith("%") and first[4].endswith(" s")
    assert "Flying: <b>solo-1</b>" == panel.flyingLabel.text()
    view = w.mapPanel.mapView
    view.zoom_to(0.1)                                                      # 10 m apart: 100 px on the map
    qtbot.waitUntil(lambda: on_the_map(w, "solo-2", f.drone("solo-2")), timeout=5000)
    assert [m.name for m in view.others] == ["solo-2"] and view.vehicle_name == "solo-1"   # picked: the big one
    assert (view.others[0].east, view.others[0].north) == pytest.approx((10.0, 0.0), abs=0.5)   # its home: 10 m east
    assert painted(view, *view.vehicle[:2]) == VEHICLE.name() and painted(view, 10.0, 0.0) == OTHER.name()

    click_takeoff(qtbot, w)                                                # solo-1 through the window's button
    wait_flying(qtbot, w, timeout=60000)
    press(w.rightStick, 0.0, 1.0)                                          # forward
    qtbot.waitUntil(lambda: body_velocity(sims[0])[0] > 0.8, timeout=15000)
    assert speed(sims[1]) < 0.1 and not sims[1].truth().armed
    solo1_trail = w.map.trail
    qtbot.waitUntil(lambda: len(solo1_trail) > 1, timeout=5000)           # it draws its trail as it flies

    qtbot.mouseClick(panel.table.viewport(), Qt.LeftButton, pos=panel.click_vehicle("solo-2"))   # switch in flight
    qtbot.waitUntil(lambda: w.adapter.drone is f.drone("solo-2"), timeout=3000)
    assert any("solo-1 left hovering" in t for t in w.messages.texts()), w.messages.texts()
    assert panel.flyingLabel.text() == "Flying: <b>solo-2</b>" and "solo-2" in w.windowTitle()
    assert w.camera.uris == ["ice:Camera@solo-2"]                         # its camera, through the registry
    qtbot.waitUntil(lambda: w.camera.stats()["frames"] > 0, timeout=15000)
    release(w.rightStick)
    qtbot.waitUntil(lambda: speed(sims[0]) < 0.2, timeout=20000)           # the one left behind hovers
    assert vehicles[0].state().setpoint.is_zero and sims[0].truth().altitude > 2.0
    # the highlight moved: the map is solo-2's (its home, its trail), solo-1 is drawn where it hovers
    assert view.vehicle_name == "solo-2" and w.map.trail is not solo1_trail
    qtbot.waitUntil(lambda: on_the_map(w, "solo-1", f.drone("solo-1")), timeout=5000)
    assert view.frame.lon > vehicles[0].state().home.lon                  # solo-2's home, east of solo-1's
    assert [m.name for m in view.others] == ["solo-1"] and not view.others[0].stale

    click_takeoff(qtbot, w)                                                # now the button takes off solo-2
    wait_flying(qtbot, w, timeout=60000)
    assert w.adapter.state.system_id == 2                                  # the instruments follow solo-2
    press(w.rightStick, 0.0, 1.0)
    qtbot.waitUntil(lambda: body_velocity(sims[1])[0] > 0.8, timeout=15000)
    assert speed(sims[0]) < 0.2 and sims[0].truth().altitude > 2.0         # solo-1 still hovering
    release(w.rightStick)

    qtbot.mouseClick(panel.landAllButton, Qt.LeftButton)                   # one confirmation for all
    qtbot.waitUntil(lambda: w.fleet_dock.box is not None and w.fleet_dock.box.isVisible(), timeout=3000)
    assert "solo-1, solo-2" in w.fleet_dock.box.text()
    qtbot.mouseClick(w.fleet_dock.box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: all(v.state().mode == "LAND" for v in vehicles), timeout=10000)
    qtbot.waitUntil(lambda: not any(s.truth().armed for s in sims), timeout=60000)
    qtbot.waitUntil(lambda: [r[2] for r in panel.row_texts()] == ["disarmed", "disarmed"], timeout=5000)
    assert any(t.startswith("solo-1: mode LAND") for t in w.messages.texts()), w.messages.texts()   # each answer


def test_all_taken_off_stopped_and_picked_on_the_map_then_their_servers_stop(qtbot, fleet, lab, ice_fleet,
                                                                              window_factory, monkeypatch):
    """The rest of the fleet's flight, in a window of its own (one test took 11 s): take off and stop all, solo-2
    sent to a Fly here, solo-1 picked by its icon, then each vehicle's server stops and the map greys it."""
    sims, vehicles, servers, f, w = fleet_in_a_window(qtbot, fleet, lab, ice_fleet, window_factory, monkeypatch)
    panel, view = w.fleet_panel, w.mapPanel.mapView
    answer_all(qtbot, w, panel.takeoffAllButton, "Take off all 2 vehicles")
    qtbot.waitUntil(lambda: all(s.truth().altitude > 2.5 for s in sims), timeout=60000)
    wait_flying(qtbot, w, timeout=60000)                                   # the sticks fly solo-1
    solo1_trail = w.map.trail
    press(w.rightStick, 0.0, 1.0)                                          # solo-1 forward: its trail
    qtbot.waitUntil(lambda: body_velocity(sims[0])[0] > 0.8 and len(solo1_trail) > 1, timeout=15000)
    release(w.rightStick)
    qtbot.mouseClick(panel.table.viewport(), Qt.LeftButton, pos=panel.click_vehicle("solo-2"))   # solo-2 flown
    qtbot.waitUntil(lambda: w.adapter.drone is f.drone("solo-2") and view.vehicle_name == "solo-2", timeout=3000)
    answer_all(qtbot, w, panel.stopAllButton, "Stop all 2 vehicles")
    qtbot.waitUntil(lambda: any(t.startswith("solo-1: stop") for t in w.messages.texts()), timeout=10000)
    assert all(v.state().setpoint.is_zero and v.state().mode == "GUIDED" for v in vehicles)   # both hold

    # solo-2 on its way to a Fly here; a click on solo-1's icon on the map picks solo-1, as a click on its row does:
    # solo-1's trail comes back, solo-2's target leaves the map and solo-2 stops where it is (nobody flies it)
    view.zoom_to(0.5)
    qtbot.waitUntil(lambda: view.fly_here_enabled, timeout=10000)
    start = vehicles[1].state().local
    assert right_click_fly_here(qtbot, view, start.east, start.north + 25.0).startswith("Fly here at")
    qtbot.waitUntil(lambda: w.map.question is not None and w.map.question.isVisible())
    qtbot.mouseClick(w.map.question.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: view.target is not None, timeout=5000)
    qtbot.waitUntil(lambda: vehicles[1].state().local.north - start.north > 3.0, timeout=20000)
    stops = sum(r.command == "stop" for r in vehicles[1].state().results)
    mark = view.others[0]
    qtbot.mouseClick(view, Qt.LeftButton, pos=view.to_screen(mark.east, mark.north).toPoint())
    qtbot.waitUntil(lambda: w.adapter.drone is f.drone("solo-1"), timeout=3000)
    assert panel.flyingLabel.text() == "Flying: <b>solo-1</b>" and view.vehicle_name == "solo-1"
    assert any("solo-2 left hovering" in t for t in w.messages.texts()), w.messages.texts()
    assert w.map.trail is solo1_trail and len(solo1_trail) > 1 and view.target is None
    qtbot.waitUntil(lambda: sum(r.command == "stop" for r in vehicles[1].state().results) > stops, timeout=5000)
    qtbot.waitUntil(lambda: speed(sims[1]) < 0.3, timeout=20000)
    assert vehicles[1].state().local.north - start.north < 20.0              # held short of the target
    qtbot.waitUntil(lambda: on_the_map(w, "solo-2", f.drone("solo-2")), timeout=5000)

    servers[1].close()                                                     # a vehicle's server stops: stale
    qtbot.waitUntil(lambda: panel.row_texts()[1][4].endswith("not in the registry"), timeout=15000)
    assert panel.row_texts()[1][0] == "solo-2" and panel.table.item(1, 0).foreground().color().name() == "#7f8791"
    qtbot.waitUntil(lambda: view.others and view.others[0].stale, timeout=3000)     # greyed on the map too
    mark = view.others[0]
    view.set_follow(False)                                                 # a close look at it, nothing else over it
    view.centre = (mark.east, mark.north)
    view.zoom_to(0.1)
    assert mark.name == "solo-2" and painted(view, mark.east, mark.north) == STALE.name()
    view.set_follow(True)
    assert not view.vehicle_stale and painted(view, *view.vehicle[:2]) == VEHICLE.name()

    servers[0].close()                                                     # the picked one's server too: grey as well
    qtbot.waitUntil(lambda: view.vehicle_stale, timeout=15000)
    assert painted(view, *view.vehicle[:2]) == STALE.name() and view.vehicle_name == "solo-1"
