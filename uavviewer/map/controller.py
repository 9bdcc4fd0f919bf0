"""What the Map dock shows and what "Fly here" does, from the vehicle's snapshots.

Positions go into view metres around home (:mod:`uavviewer.map.geometry`): the vehicle's latitude/longitude when it
has one, else its metres from home (a plain JdeRobot server gives only those). The trail keeps the last
ten minutes, fading with age; a replay shows the whole recorded track at once. "Fly here" asks first
(distance and altitude), then uses the driver's go-to, whose limits and refusals apply; Stop, Escape, Land,
RTL, a stick or another mode end it on the map as they do on the vehicle.

In a fleet (docs/fleet.md) the map also shows the other vehicles, each from its own snapshot and placed by its
own latitude/longitude in the picked vehicle's frame, so vehicles with different homes stand where they are;
each vehicle keeps its trail while another is picked, and a go-to target belongs to the vehicle it was sent to.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QMessageBox, QWidget

from driver.vehicle.rules import MAX_ALTITUDE, MIN_GOTO_ALTITUDE
from driver.vehicle.state import CommandResult, VehicleState

from .camera_overlay import CameraOverlay
from .traffic_overlay import TrafficOverlay
from ..widgets.ask import ask, cautious_question
from .geometry import MapFrame, tiles_covering, tile_zoom_for
from .tiles import MAX_AREA_TILES, TileSource
from .trail import Trail
from .map_panel import MapPanel
from .map_view import TRAIL_BANDS, VehicleMark

__all__ = ["MapController", "TileSettings", "fleet_marks", "placed"]

log = logging.getLogger(__name__)

ARRIVED = 1.0                # m from the go-to target: reached, the target leaves the map


def fly_here_question(parent: QWidget, text: str) -> QMessageBox:
    """Confirm a go-to, saying how far and how high; like the takeoff question, Cancel is the default."""
    return cautious_question(parent, "Fly here", text, "Fly there", "flyHereQuestion")


@dataclass(frozen=True)
class TileSettings:
    """The tile server and cache as Preferences give them ("" url: the offline grid only)."""
    url: str = ""
    attribution: str = ""
    cache_mb: int = 200
    cache_dir: str | None = None             # None: the per-user cache folder


def placed(frame: MapFrame | None, s: VehicleState, own: bool = True) -> tuple[float, float] | None:
    """A vehicle in view metres (east, north): from its latitude/longitude, else its home's plus its metres from
    home. ``own``: the frame is this vehicle's home, so metres from home alone will do (a plain JdeRobot server
    gives only those); another vehicle without a latitude cannot be placed."""
    pos = s.position
    if frame is not None and pos is not None and (pos.lat or pos.lon):
        return frame.to_view(pos.lat, pos.lon)
    if s.local is None:
        return None
    if frame is not None and s.home is not None:
        east, north = frame.to_view(s.home.lat, s.home.lon)
        return east + s.local.east, north + s.local.north
    return (s.local.east, s.local.north) if own else None


def fleet_marks(frame: MapFrame | None, seen) -> tuple[VehicleMark, ...]:
    """The fleet's vehicles but the picked one, where their own snapshots put them in ``frame``.

    ``seen``: (FleetRow, VehicleState or None) for each vehicle, as
    :class:`uavviewer.fleet.controller.FleetController` reads
    them; a vehicle without a state or a position is left off."""
    marks = []
    for row, s in seen:
        where = None if row.picked or s is None else placed(frame, s, own=False)
        if where is not None:
            marks.append(VehicleMark(row.name, where[0], where[1], s.heading_deg, row.stale))
    return tuple(marks)


class MapController(QObject):
    flyHereAsked = pyqtSignal(object)        # the confirmation box, open (tests answer it)

    def __init__(self, panel: MapPanel, adapter, window: QWidget, takeoff_altitude=lambda: 3.0,
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.panel = panel
        self.view = panel.mapView
        self.adapter = adapter
        self._window = window
        self._takeoff_altitude = takeoff_altitude
        self._frame: MapFrame | None = None
        self._home_local = (0.0, 0.0)
        self.trail = Trail()                       # the live trail; a replay's whole track replaces it
        self._replay_track = False
        self._clock = time.monotonic
        self.target: tuple[float, float, float] | None = None      # north, east, altitude of an active go-to
        self._sent: tuple[float, float, float] | None = None        # a go-to on its way to the vehicle
        self._question: QMessageBox | None = None
        self.tiles: TileSource | None = None
        self._tile_settings = TileSettings()
        self._area_text = ""                       # the last "Download area": its progress or outcome
        self._state: VehicleState | None = None
        self._pending_track: list | None = None     # the replay's track, read on its own thread
        self._name = ""                            # in a fleet: the picked vehicle's name
        self._trails: dict[str, Trail] = {}        # ... and the others' trails, kept while they are not picked
        self._seen: tuple = ()                     # the fleet's (row, state) pairs last read
        panel.layerRequested.connect(self._layer)
        panel.offlineRequested.connect(self._offline)
        panel.downloadRequested.connect(self.download_area)
        self.view.flyHereRequested.connect(self.ask_fly_here)
        self.camera = CameraOverlay(self.view, adapter, self)     # footprint, look direction, Look here (ROI)
        self.traffic = TrafficOverlay(self.view, self)            # ADS-B contacts and their alert
        self._show_status()
        replay = adapter.replay
        if replay is not None:
            replay.track().add_done_callback(self._track_read)     # on its thread; picked up on the next state

    # -- tiles ----------------------------------------------------------------------------------
    def set_tile_settings(self, settings: TileSettings) -> None:
        old, self._tile_settings = self._tile_settings, settings
        if self.tiles is not None and (settings.url != old.url or settings.cache_dir != old.cache_dir):
            self.view.set_tiles(None)
            self.tiles.close()
            self.tiles.deleteLater()
            self.tiles = None
        if self.tiles is not None:
            self.tiles.set_cache_mb(settings.cache_mb)
        self.panel.set_tiles_available(bool(settings.url), "" if settings.url else
                                       "Set a tile server in Settings › Preferences › Map")
        if self.panel.layerCombo.currentIndex() == 1:
            self._layer(True)

    def _layer(self, tiles: bool) -> None:
        if not tiles or not self._tile_settings.url:
            self.view.set_tiles(None)
        else:
            if self.tiles is None:
                s = self._tile_settings
                self.tiles = TileSource(s.url, s.cache_dir, s.cache_mb, self.panel.offlineCheck.isChecked(), self)
                self.tiles.tileFailed.connect(lambda *_: self._show_status())
                self.tiles.tileReady.connect(lambda *_: self._show_status())
                self.tiles.areaProgress.connect(self._area_progress)
            self.view.set_tiles(self.tiles, self._tile_settings.attribution or self._tile_settings.url)
        self.panel.set_tiles_available(bool(self._tile_settings.url))
        self._show_status()

    def _offline(self, offline: bool) -> None:
        if self.tiles is not None:
            self.tiles.set_offline(offline)
        self.panel.set_tiles_available(bool(self._tile_settings.url))
        self.view.update()
        self._show_status()

    def download_area(self) -> int:
        """This view's tiles at this zoom and the three closer ones, into the cache; refused when too many."""
        if self.tiles is None or self._frame is None:
            return 0
        v = self.view
        w, n = v.view_at(v.rect().topLeft())
        e, s = v.view_at(v.rect().bottomRight())
        z0 = tile_zoom_for(v.mpp, self._frame.lat)
        keys = []
        for z in range(z0, min(19, z0 + 3) + 1):
            more = tiles_covering(self._frame, w, n, e, s, z, limit=MAX_AREA_TILES)
            if not more:
                keys = []
                break
            keys += [k for k, _ in more]
        if not keys or len(keys) > MAX_AREA_TILES or not self.tiles.download_area(keys):
            self._area_text = f"Area too large for offline use (at most {MAX_AREA_TILES} tiles): zoom in"
            self._show_status()
            return 0
        self._area_progress(0, 0, len(keys))
        return len(keys)

    def _area_progress(self, done: int, failed: int, total: int) -> None:
        if done + failed >= total:
            self._area_text = f"Area kept for offline use: {done} tiles" + (f", {failed} failed" if failed else "")
        else:
            self._area_text = f"Downloading {done + failed}/{total} tiles…"
        self._show_status()

    def _show_status(self) -> None:
        if self.view.tiles is None:
            self.panel.set_status("Grid: metres from home, no network")
            return
        failures = self.tiles.failures
        why = sorted(set(failures.values()))
        text = ("Offline (cache only)" if self.tiles.offline else "Tiles") + f": {self.view.drawn_tiles} shown"
        if failures:
            text += f", {len(failures)} failed ({'; '.join(why[:2])})"
        self.panel.set_status(f"{self._area_text} · {text}" if self._area_text else text)

    # -- state in ------------------------------------------------------------------------------
    def show_state(self, s: VehicleState) -> None:
        self._state = s
        self._set_frame(s)
        if self.adapter.replay is not None:
            self.take_replay_track()
        where = self._where(s)
        if where is not None:
            self.view.set_vehicle((where[0], where[1], s.heading_deg))
            if not self._replay_track:
                self._add_trail(where, s)
        else:
            self.view.set_vehicle(None)
        self.view.home_visible = s.home is not None or s.local is not None
        self.view.fence_radius = s.fence.circle
        self.view.fence_breached = bool(s.fence.breached)
        self.view.fence_ceiling = s.fence.ceiling
        self._follow_target(s, where)
        self._fly_here_item(s)
        self.camera.show_state(s, where)
        self.traffic.show_state(s)

    def _set_frame(self, s: VehicleState) -> None:
        home = s.home
        if home is None or (self._frame is not None and (self._frame.lat, self._frame.lon) == (home.lat, home.lon)):
            return
        self._frame = MapFrame(home.lat, home.lon)       # home moved (arming sets it): the trail follows
        self.view.frame = self._frame
        self._redraw_trail()
        self._show_fleet()

    # -- the fleet ------------------------------------------------------------------------------
    def use_vehicle(self, name: str) -> bool:
        """The pilot picked ``name`` (before its first snapshot arrives): its own trail comes back, the previous
        one's is kept, and the previous one's go-to target and any open "Fly here" question go. Returns whether
        a go-to was active or on its way (the window stops it: nobody flies the vehicle left behind)."""
        if name == self._name or self._replay_track:
            return False
        if not self._name:                         # the vehicle the window flew from the start: this trail is its
            self._name = name
            return False
        going = self.target is not None or self._sent is not None
        self._trails[self._name] = self.trail
        self.trail = self._trails.pop(name, None) or Trail()
        self._name = name
        self.cancel()
        self._redraw_trail()
        return going

    def use_connection(self) -> None:
        """Another connection (File › Connect, Replay a flight): its own frame, trail and, for a replay, track."""
        self.cancel()
        self._frame = None
        self._state = None
        self.trail = Trail()
        self._name, self._trails = "", {}
        self._replay_track = False
        self._pending_track = None
        self._redraw_trail()
        replay = self.adapter.replay
        if replay is not None:
            replay.track().add_done_callback(self._track_read)

    def show_fleet(self, seen) -> None:
        """Every vehicle's (FleetRow, VehicleState or None), a few times a second: the others are drawn from
        their own snapshots, and their trails grow while they are not picked."""
        self._seen = seen
        now = self._clock()
        states = {row.name: s for row, s in seen}
        for mark in self._show_fleet():
            pos = states[mark.name].position
            latlon = (pos.lat, pos.lon) if pos is not None and (pos.lat or pos.lon) else None
            self._trails.setdefault(mark.name, Trail()).add(now, mark.east, mark.north, latlon)

    def _show_fleet(self) -> tuple[VehicleMark, ...]:
        picked = next((row for row, _ in self._seen if row.picked), None)
        marks = fleet_marks(self._frame, self._seen)
        self.view.set_fleet(picked.name if picked else self._name, bool(picked and picked.stale), marks)
        return marks

    def _where(self, s: VehicleState) -> tuple[float, float] | None:
        """The picked vehicle in view metres: from its latitude/longitude, else its metres from home."""
        return placed(self._frame, s)

    def _add_trail(self, where: tuple[float, float], s: VehicleState) -> None:
        latlon = (s.position.lat, s.position.lon) if s.position is not None and self._frame is not None else None
        if self.trail.add(self._clock(), where[0], where[1], latlon):
            self._redraw_trail()

    def _redraw_trail(self) -> None:
        frame = self._frame
        self.view.set_trail(self.trail.bands(TRAIL_BANDS, self._clock(), frame.to_view if frame else None))

    def _track_read(self, future) -> None:
        """The replay's whole track (on the reading thread: only a reference is handed over)."""
        try:
            self._pending_track = future.result()
        except Exception:                   # noqa: BLE001
            log.warning("no track in this recording", exc_info=True)
            self._pending_track = []

    def take_replay_track(self) -> bool:
        """Draw the replay's whole track once it has been read (called on the UI thread by the window)."""
        track = self._pending_track
        if track is None or self._replay_track:
            return False
        self._replay_track = True
        self.trail = Trail(seconds=None)
        for t, lat, lon in track:
            self.trail.add(t, 0.0, 0.0, (lat, lon), force=True)
        self._redraw_trail()
        return True

    # -- fly here -------------------------------------------------------------------------------
    def fly_altitude(self, s: VehicleState) -> float:
        """Where a "Fly here" flies: at the present altitude (whole metres) in flight, else the takeoff altitude;
        within the driver's go-to rules."""
        altitude = round(s.altitude) if s.flying else self._takeoff_altitude()
        return round(min(MAX_ALTITUDE, max(MIN_GOTO_ALTITUDE, altitude)), 1)

    def _fly_here_item(self, s: VehicleState) -> None:
        if self.adapter.replay is not None:
            self.view.fly_here_text = ""
            return
        blocker = ("no home position yet" if s.home is None and s.local is None else
                   "" if s.mode == "GUIDED" and s.flying and not s.takeoff.active else "needs GUIDED and flying")
        altitude = self.fly_altitude(s)
        self.view.fly_here_text = f"Fly here at {altitude:g} m" + (f" ({blocker})" if blocker else "")
        self.view.fly_here_enabled = not blocker

    def ask_fly_here(self, north: float, east: float) -> None:
        s = self._state
        if s is None:
            return
        if self._question is not None:
            self._question.reject()
        altitude = self.fly_altitude(s)
        here = self._where(s) or (0.0, 0.0)
        far = math.hypot(east - here[0], north - here[1])
        text = (f"Fly {far:.0f} m to {abs(north):.0f} m {'north' if north >= 0 else 'south'}, {abs(east):.0f} m "
                f"{'east' if east >= 0 else 'west'} of home, at {altitude:g} m above home?\n\n"
                "Stop or Escape halts it where it is.")
        self._question = ask(fly_here_question(self._window, text),
                             lambda box: self._answered(box, (north, east, altitude)))
        self.flyHereAsked.emit(self._question)

    @property
    def question(self) -> QMessageBox | None:
        return self._question

    def _answered(self, box: QMessageBox, target: tuple[float, float, float]) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self._sent = target
            self.adapter.send(self.adapter.drone.go_to, *target, then=lambda result: self._went(result, target))
        box.deleteLater()
        if self._question is box:
            self._question = None

    def _went(self, result: CommandResult, target: tuple[float, float, float]) -> None:
        """The vehicle's answer to Fly here: the target is drawn while it flies there (unless ended meanwhile:
        Stop, a stick, another Fly here)."""
        if self._sent == target:
            self.target, self._sent = (target if result.ok else None), None
            self._show_target()

    def cancel(self) -> None:
        """Stop, Escape, Land, RTL or a stick: the go-to is over (the driver holds or does what was asked)."""
        if self.target is None and self._sent is None and self._question is None:
            return                                # nothing to end (a stick moves many times a second)
        self.target = self._sent = None
        if self._question is not None:
            self._question.reject()
        self._show_target()

    def _follow_target(self, s: VehicleState, where) -> None:
        if self.target is None:
            return
        north, east, _ = self.target
        arrived = s.local is not None and math.hypot(s.local.north - north, s.local.east - east) < ARRIVED
        if arrived or s.mode != "GUIDED" or not s.flying or not s.setpoint.is_zero:
            self.target = None
            self._show_target()

    def _show_target(self) -> None:
        self.view.target = None if self.target is None else (self.target[1], self.target[0])
        self.view.update()
