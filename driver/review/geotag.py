"""Geotag a survey's photos from the flight log: each JPEG gets the position and altitude the autopilot logged
when it took that photo, written into its EXIF GPS tags (File › Review, docs/review.md).

Where the photos' moments are in a log:

* a DataFlash .BIN: ``CAM`` records (AP_Camera::Write_Camera: the shutter, confirmed by the feedback pin when
  there is one), else ``TRIG`` (the trigger sent, when a feedback pin is set but none came back). Each has Lat,
  Lng, Alt (AMSL), RelAlt (above home) and, on ArduPilot 3.6 and later, GPSTime/GPSWeek; without those the GPS
  time comes from the nearest GPS record (GMS/GWk beside its TimeUS).
* a .tlog: ``CAMERA_FEEDBACK`` (time_usec is UTC from the autopilot's GPS; where it is not, the ground
  station's own receive time stands in).

The n-th photo goes to the n-th event, as Mission Planner's geotag does by default: the camera counts its
pictures in the same order the autopilot logged them. That match is then checked by time: a photo's EXIF
DateTimeOriginal (camera clock, minus ``clock_offset``: how far the camera's clock runs ahead of UTC) must be
within ``tolerance`` seconds of its event's GPS time, else it is left untagged and said why. Matching ``by="time"``
instead pairs each photo with the nearest event within the tolerance (when the camera missed triggers).

The EXIF is written with piexif into copies in an output folder (``<folder>/geotagged`` unless told): a pilot's
originals are never rewritten unless ``in_place`` is asked for, and then through a temporary file and a rename
so an interrupted run leaves each photo whole. Only the GPS tags change; the pixels are not re-encoded.
"""
from __future__ import annotations

import io
import logging
import os
import shutil
import statistics
import tempfile
from dataclasses import dataclass, field, replace
from datetime import datetime, timedelta, timezone
from typing import Callable

import numpy as np
import piexif

from .log import FlightLog, open_log

log = logging.getLogger(__name__)

__all__ = ["CameraEvent", "GeotagError", "GeotagReport", "Photo", "Tagged", "Untagged", "camera_events", "geotag",
           "gps_ifd", "gps_utc", "read_photos", "write_tags", "DEFAULT_TOLERANCE", "OUTPUT_FOLDER"]

GPS_EPOCH = datetime(1980, 1, 6, tzinfo=timezone.utc)
#: GPS time runs ahead of UTC by the leap seconds since 1980 (AP_GPS: GPS_LEAPSECONDS_MILLIS)
LEAP_SECONDS = 18
WEEK_MS = 604_800_000
DEFAULT_TOLERANCE = 2.0          # s: DateTimeOriginal has whole seconds, and a shutter lags its trigger
OUTPUT_FOLDER = "geotagged"
JPEG_ENDINGS = (".jpg", ".jpeg", ".jpe")
SOURCES = ("CAM", "TRIG")        # a .BIN's event records, in the order they are preferred
EPOCH_USEC_SINCE = 1e15          # a CAMERA_FEEDBACK time_usec above this is UTC (2001 on), below it boot time
_EXIF_TIME = "%Y:%m:%d %H:%M:%S"


class GeotagError(ValueError):
    """Geotagging cannot start (no camera events in the log, no such folder...); str() says why, for the pilot."""


@dataclass(frozen=True)
class CameraEvent:
    number: int               # 1, 2, ... in the log's order
    t: float                  # seconds from the log's start
    image: int                # the autopilot's image number (CAM Img, CAMERA_FEEDBACK img_idx)
    utc: datetime | None      # the photo's moment by the GPS, None where the log has no GPS time
    lat: float                # degrees
    lon: float
    alt: float                # m above mean sea level
    rel_alt: float            # m above home
    source: str               # "CAM", "TRIG" or "CAMERA_FEEDBACK"
    camera: int = 0           # the camera's instance (CAM I, CAMERA_FEEDBACK cam_idx)


@dataclass(frozen=True)
class Photo:
    name: str
    path: str
    taken: datetime | None    # DateTimeOriginal (+ SubSecTimeOriginal), on the camera's clock, naive


@dataclass(frozen=True)
class Tagged:
    photo: Photo
    event: CameraEvent
    written: str              # the file written
    time_error: float | None  # s, the photo's time (offset applied) less its event's; None: not checked


@dataclass(frozen=True)
class Untagged:
    name: str
    reason: str


@dataclass(frozen=True)
class GeotagReport:
    source: str                                  # the events used: "CAM", "TRIG" or "CAMERA_FEEDBACK"
    output: str                                  # the folder written to
    tagged: tuple[Tagged, ...]
    unmatched: tuple[Untagged, ...]              # JPEGs left untagged, and why
    events_without_photo: tuple[tuple[CameraEvent, str], ...]
    ignored: tuple[Untagged, ...] = ()           # files in the folder that are not photos
    #: s, the camera clock offset the photos suggest (the median of camera time less event time over the pairs by
    #: order) when it differs from the one used by more than the tolerance; else None
    suggested_offset: float | None = None
    cameras: tuple[int, ...] = (0,)              # the camera instances in the log; the report is of the first
                                                 # unless another was asked for (``camera``)
    camera: int = 0

    def lines(self) -> list[str]:
        """The report in words, one line a fact, for the dialog and the console."""
        out = [f"{len(self.tagged)} photos tagged from {self.source} events into {self.output}"]
        out += [f"untagged {u.name}: {u.reason}" for u in self.unmatched]
        out += [f"{e.source} {e.number} (image {e.image}, {e.t:.1f} s into the log) has no photo: {why}"
                for e, why in self.events_without_photo]
        out += [f"ignored {u.name}: {u.reason}" for u in self.ignored]
        if len(self.cameras) > 1:
            out.append(f"the log has cameras {', '.join(map(str, self.cameras))}: camera {self.camera}'s events "
                       "were used")
        unchecked = sum(t.time_error is None for t in self.tagged)
        if unchecked:
            out.append(f"{unchecked} photos matched by order only, not checked by time (no DateTimeOriginal in the "
                       "photo, or no GPS time in the log)")
        if self.suggested_offset is not None:
            out.append(f"the camera's clock reads {self.suggested_offset:+.1f} s from the log's GPS time "
                       "(median over the photos matched by order): set that as the camera clock offset")
        return out


# -- the log's events --------------------------------------------------------------------------------------------
def gps_utc(week: int, ms: float) -> datetime:
    """UTC of a GPS week and milliseconds into it (GPS time less the leap seconds)."""
    return GPS_EPOCH + timedelta(milliseconds=week * WEEK_MS + ms - LEAP_SECONDS * 1000)


def camera_events(flight: FlightLog, source: str = "auto") -> tuple[str, list[CameraEvent]]:
    """(the record type used, its events in the log's order, every camera's). ``source``: "auto" (CAM, else TRIG;
    a .tlog's CAMERA_FEEDBACK), "CAM" or "TRIG". Raises :class:`GeotagError` when the log has none."""
    if flight.kind == "tlog":
        events = _tlog_events(flight)
        if not events:
            raise GeotagError(f"{os.path.basename(flight.path)}: no CAMERA_FEEDBACK in this telemetry log: the "
                              "vehicle reported no photo (is a camera configured, CAM1_TYPE?)")
        return "CAMERA_FEEDBACK", events
    wanted = SOURCES if source == "auto" else (source,)
    for name in wanted:
        if flight.count(name):
            return name, _dataflash_events(flight, name)
    raise GeotagError(f"{os.path.basename(flight.path)}: no {' or '.join(wanted)} records in this log: the "
                      "autopilot logged no photo (is a camera configured, CAM1_TYPE, and LOG_BITMASK's camera "
                      "bit set?)")


def _dataflash_events(flight: FlightLog, name: str) -> list[CameraEvent]:
    t, lat = flight.series(name, "Lat")
    lon = flight.series(name, "Lng")[1]
    alt = flight.series(name, "Alt")[1]
    rel = flight.series(name, "RelAlt")[1] if flight.has(name, "RelAlt") else np.full(len(t), np.nan)
    image = flight.series(name, "Img")[1] if flight.has(name, "Img") else np.arange(1, len(t) + 1)
    camera = flight.series(name, "I")[1] if flight.has(name, "I") else np.zeros(len(t))
    if flight.has(name, "GPSTime") and flight.has(name, "GPSWeek"):
        ms, week = flight.series(name, "GPSTime")[1], flight.series(name, "GPSWeek")[1]
        utc = [gps_utc(int(w), float(m)) if w > 0 else None for w, m in zip(week, ms)]
        if any(u is None for u in utc):                 # logged before the GPS had its time: ask the GPS records
            from_gps = _utc_from_gps_records(flight, t)
            utc = [u if u is not None else g for u, g in zip(utc, from_gps)]
    else:
        utc = _utc_from_gps_records(flight, t)
    order = np.argsort(t, kind="stable")
    return [CameraEvent(n + 1, float(t[i]), int(image[i]), utc[i], float(lat[i]), float(lon[i]), float(alt[i]),
                        float(rel[i]), name, int(camera[i])) for n, i in enumerate(order.tolist())]


def _utc_from_gps_records(flight: FlightLog, t: np.ndarray) -> list[datetime | None]:
    """UTC at each log time ``t`` from the GPS record nearest it (its GMS/GWk at its TimeUS, plus the
    difference), only from records with the time known (a week above 0)."""
    if not (flight.has("GPS", "GMS") and flight.has("GPS", "GWk")):
        return [None] * len(t)
    gt, ms = flight.series("GPS", "GMS")
    week = flight.series("GPS", "GWk")[1]
    known = week > 0
    gt, ms, week = gt[known], ms[known], week[known]
    if len(gt) == 0:
        return [None] * len(t)
    i = np.clip(np.searchsorted(gt, t), 0, len(gt) - 1)
    before = np.clip(i - 1, 0, len(gt) - 1)
    i = np.where(np.abs(gt[before] - t) < np.abs(gt[i] - t), before, i)
    return [gps_utc(int(week[k]), float(ms[k]) + (float(a) - float(gt[k])) * 1000.0)
            for k, a in zip(i.tolist(), t.tolist())]


def _tlog_events(flight: FlightLog) -> list[CameraEvent]:
    if not flight.count("CAMERA_FEEDBACK"):
        return []
    t, lat = flight.series("CAMERA_FEEDBACK", "lat")
    cols = {f: flight.series("CAMERA_FEEDBACK", f)[1] for f in ("lng", "alt_msl", "alt_rel", "img_idx",
                                                                   "time_usec", "cam_idx")}
    start = flight.start_unix
    out = []
    for n, i in enumerate(np.argsort(t, kind="stable").tolist()):
        usec = float(cols["time_usec"][i])
        if usec >= EPOCH_USEC_SINCE:
            utc = datetime.fromtimestamp(usec / 1e6, timezone.utc)
        else:                                   # boot time: the ground station's clock when it came in
            utc = datetime.fromtimestamp(start + float(t[i]), timezone.utc) if start else None
        out.append(CameraEvent(n + 1, float(t[i]), int(cols["img_idx"][i]), utc, float(lat[i]) / 1e7,
                               float(cols["lng"][i]) / 1e7, float(cols["alt_msl"][i]), float(cols["alt_rel"][i]),
                               "CAMERA_FEEDBACK", int(cols["cam_idx"][i])))
    return out


# -- the photos --------------------------------------------------------------------------------------------------
def read_photos(folder: str) -> tuple[list[Photo], list[Untagged]]:
    """(the JPEGs with their DateTimeOriginal, the files that are not JPEGs) in the folder (not its subfolders).
    A .jpg whose content is not a JPEG is listed with the ignored files: it cannot take an event's place."""
    if not os.path.isdir(folder):
        raise GeotagError(f"{folder}: no such folder")
    photos, ignored = [], []
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            continue
        if not name.lower().endswith(JPEG_ENDINGS):
            ignored.append(Untagged(name, "not a JPEG"))
            continue
        try:
            with open(path, "rb") as f:
                head = f.read(2)
            if head != b"\xff\xd8":
                ignored.append(Untagged(name, "named .jpg but not a JPEG"))
                continue
            exif = piexif.load(path)
        except (OSError, ValueError, piexif.InvalidImageDataError) as e:
            ignored.append(Untagged(name, f"cannot be read ({e})"))
            continue
        photos.append(Photo(name, path, _taken(exif)))
    return photos, ignored


def _taken(exif: dict) -> datetime | None:
    raw = exif.get("Exif", {}).get(piexif.ExifIFD.DateTimeOriginal)
    if not raw:
        return None
    try:
        taken = datetime.strptime(raw.decode("ascii", "replace").strip("\0 "), _EXIF_TIME)
    except ValueError:
        return None
    sub = exif["Exif"].get(piexif.ExifIFD.SubSecTimeOriginal)
    digits = sub.decode("ascii", "replace").strip("\0 ") if sub else ""
    if digits.isdigit():
        taken += timedelta(seconds=int(digits) / 10 ** len(digits))
    return taken


# -- matching ----------------------------------------------------------------------------------------------------
@dataclass
class _Match:
    pairs: list[tuple[Photo, CameraEvent, float | None]] = field(default_factory=list)
    unmatched: list[Untagged] = field(default_factory=list)
    idle: list[tuple[CameraEvent, str]] = field(default_factory=list)


def _apart(photo: Photo, event: CameraEvent, clock_offset: float) -> float | None:
    """Seconds the photo's time (less the camera's offset) is after its event's; None if either has no time."""
    if photo.taken is None or event.utc is None:
        return None
    taken = photo.taken.replace(tzinfo=timezone.utc) - timedelta(seconds=clock_offset)
    return (taken - event.utc).total_seconds()


def _by_order(photos: list[Photo], events: list[CameraEvent], clock_offset: float, tolerance: float) -> _Match:
    m = _Match()
    for i, photo in enumerate(photos):
        if i >= len(events):
            m.unmatched.append(Untagged(photo.name, f"more photos than events ({len(photos)} photos, "
                                                    f"{len(events)} {events[0].source} events): none left for it"))
            continue
        event = events[i]
        apart = _apart(photo, event, clock_offset)
        if apart is not None and abs(apart) > tolerance:
            m.unmatched.append(Untagged(photo.name, f"time mismatch: taken {apart:+.1f} s from {event.source} "
                                                    f"{event.number}, its event by order (tolerance {tolerance:g} s)"))
            m.idle.append((event, f"its photo by order, {photo.name}, is {apart:+.1f} s away"))
            continue
        m.pairs.append((photo, event, apart))
    m.idle += [(e, f"fewer photos than events ({len(photos)} photos, {len(events)} events)")
               for e in events[len(photos):]]
    return m


def _by_time(photos: list[Photo], events: list[CameraEvent], clock_offset: float, tolerance: float) -> _Match:
    """One to one, the closest pairs first, each within the tolerance."""
    m = _Match()
    candidates = sorted(((abs(a), e.number, p.name), a, p, e) for p in photos for e in events
                        if (a := _apart(p, e, clock_offset)) is not None and abs(a) <= tolerance)
    used_photos, used_events = set(), set()
    for _key, apart, photo, event in candidates:
        if photo.name in used_photos or event.number in used_events:
            continue
        used_photos.add(photo.name)
        used_events.add(event.number)
        m.pairs.append((photo, event, apart))
    for photo in photos:
        if photo.name not in used_photos:
            m.unmatched.append(Untagged(photo.name, "no DateTimeOriginal: cannot be matched by time"
                                        if photo.taken is None else f"no event within {tolerance:g} s"))
    m.idle = [(e, f"no photo within {tolerance:g} s") for e in events if e.number not in used_events]
    m.pairs.sort(key=lambda p: p[1].number)
    return m


def _suggested_offset(photos: list[Photo], events: list[CameraEvent], clock_offset: float,
                      tolerance: float) -> float | None:
    """The camera clock offset the photos paired by order show (their median), if it is not the one used."""
    gaps = [a for p, e in zip(photos, events) if (a := _apart(p, e, 0.0)) is not None]
    seen = float(statistics.median(gaps)) if gaps else None
    return seen if seen is not None and abs(seen - clock_offset) > tolerance else None


# -- writing -----------------------------------------------------------------------------------------------------
def _dms(value: float) -> tuple[tuple[int, int], tuple[int, int], tuple[int, int]]:
    """Degrees as EXIF's degrees, minutes, seconds rationals, to a micro-arcsecond (3e-10 degrees)."""
    micro = round(abs(value) * 3600 * 1_000_000)
    degrees, rest = divmod(micro, 3600 * 1_000_000)
    minutes, seconds = divmod(rest, 60 * 1_000_000)
    return (degrees, 1), (minutes, 1), (seconds, 1_000_000)


def _has_position(event: CameraEvent) -> bool:
    """A real place: finite, on the globe, not the 0,0 an autopilot logs before its first fix."""
    return (np.isfinite([event.lat, event.lon, event.alt]).all() and abs(event.lat) <= 90 and abs(event.lon) <= 180
            and (event.lat, event.lon) != (0.0, 0.0))


def gps_ifd(event: CameraEvent, altitude: str = "msl") -> dict:
    """The EXIF GPS tags for one event; ``altitude`` "msl" (EXIF's meaning: above sea level) or "relative"
    (above home, for tools that want height above the take-off)."""
    alt = event.alt if altitude == "msl" else event.rel_alt
    if not np.isfinite(alt):
        alt = event.alt
    tags = {
        piexif.GPSIFD.GPSVersionID: (2, 3, 0, 0),
        piexif.GPSIFD.GPSLatitudeRef: b"N" if event.lat >= 0 else b"S",
        piexif.GPSIFD.GPSLatitude: _dms(event.lat),
        piexif.GPSIFD.GPSLongitudeRef: b"E" if event.lon >= 0 else b"W",
        piexif.GPSIFD.GPSLongitude: _dms(event.lon),
        piexif.GPSIFD.GPSAltitudeRef: 0 if alt >= 0 else 1,
        piexif.GPSIFD.GPSAltitude: (round(abs(alt) * 1000), 1000),
        piexif.GPSIFD.GPSMapDatum: b"WGS-84",
    }
    if event.utc is not None:
        u = event.utc
        tags[piexif.GPSIFD.GPSTimeStamp] = ((u.hour, 1), (u.minute, 1),
                                            (round((u.second + u.microsecond / 1e6) * 1000), 1000))
        tags[piexif.GPSIFD.GPSDateStamp] = u.strftime("%Y:%m:%d").encode()
    return tags


def write_tags(photo: Photo, event: CameraEvent, destination: str, altitude: str = "msl") -> None:
    """The photo with its GPS tags set from ``event``, written whole to ``destination`` (through a temporary
    file and a rename: never half a file), the source's times kept."""
    with open(photo.path, "rb") as f:
        data = f.read()
    exif = piexif.load(data)
    exif["GPS"] = gps_ifd(event, altitude)
    out = io.BytesIO()
    piexif.insert(piexif.dump(exif), data, out)
    folder = os.path.dirname(os.path.abspath(destination))
    fd, temporary = tempfile.mkstemp(prefix=".geotag-", suffix=".jpg", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(out.getvalue())
        shutil.copystat(photo.path, temporary)
        os.replace(temporary, destination)
    except BaseException:
        if os.path.exists(temporary):
            os.remove(temporary)
        raise


def geotag(log_or_path: FlightLog | str, folder: str, output: str | None = None, *, clock_offset: float = 0.0,
           tolerance: float = DEFAULT_TOLERANCE, in_place: bool = False, by: str = "order", source: str = "auto",
           altitude: str = "msl", camera: int | None = None,
           progress: Callable[[int, int], None] | None = None) -> GeotagReport:
    """Tag the JPEGs in ``folder`` from the log's camera events and say what was done (see the module's words).

    ``clock_offset``: seconds the camera's clock is ahead of UTC (a camera set to UTC+2 local time: 7200).
    ``output``: where the tagged copies go (default ``<folder>/geotagged``); ``in_place``: rewrite the originals.
    ``camera``: whose events, where the log has several cameras (CAM I); the lowest instance unless told.
    ``progress(done, total)`` is called after each photo written. Raises :class:`GeotagError` (or
    ``LogError`` for a log that cannot be read) before anything is written."""
    if by not in ("order", "time"):
        raise GeotagError(f"match by 'order' or 'time', not {by!r}")
    if altitude not in ("msl", "relative"):
        raise GeotagError(f"altitude 'msl' or 'relative', not {altitude!r}")
    if not (np.isfinite(clock_offset) and np.isfinite(tolerance) and tolerance >= 0):
        raise GeotagError("the camera clock offset and the tolerance must be numbers (the tolerance 0 or more)")
    photos, ignored = read_photos(folder)
    target = os.path.abspath(folder if in_place else (output or os.path.join(folder, OUTPUT_FOLDER)))
    if not in_place and os.path.realpath(target) == os.path.realpath(folder):
        raise GeotagError("the output folder is the photos' own folder: choose another, or ask to rewrite the "
                          "originals in place")
    flight = open_log(log_or_path) if isinstance(log_or_path, str) else log_or_path
    try:
        kind, events = camera_events(flight, source)
    finally:
        if isinstance(log_or_path, str):
            flight.close()
    cameras = tuple(sorted({e.camera for e in events}))
    chosen = cameras[0] if camera is None else camera
    if chosen not in cameras:
        raise GeotagError(f"the log has no camera {chosen} (its {kind} events are of camera "
                          f"{', '.join(map(str, cameras))})")
    if len(cameras) > 1:                      # each camera counts its own photos
        events = [replace(e, number=n) for n, e in enumerate((e for e in events if e.camera == chosen), 1)]
    if not photos:
        raise GeotagError(f"{folder}: no JPEG photos in this folder")
    if all(p.taken is not None for p in photos):
        photos.sort(key=lambda p: (p.taken, p.name))      # the camera's order; its file names may wrap at 9999
    match = (_by_order if by == "order" else _by_time)(photos, events, clock_offset, tolerance)
    os.makedirs(target, exist_ok=True)
    tagged, unmatched = [], list(match.unmatched)
    for done, (photo, event, apart) in enumerate(match.pairs, 1):
        destination = os.path.join(target, photo.name)
        if not _has_position(event):
            unmatched.append(Untagged(photo.name, f"{event.source} {event.number} has no position (no GPS fix "
                                                  "when it was logged): nothing written"))
            match.idle.append((event, f"no position to give its photo, {photo.name}"))
        else:
            try:
                write_tags(photo, event, destination, altitude)
            except (OSError, ValueError, piexif.InvalidImageDataError) as e:
                log.warning("geotag %s: %s", photo.name, e)
                unmatched.append(Untagged(photo.name, f"its EXIF could not be written ({e})"))
                match.idle.append((event, f"its photo, {photo.name}, could not be written"))
            else:
                tagged.append(Tagged(photo, event, destination, apart))
        if progress is not None:
            progress(done, len(match.pairs))
    report = GeotagReport(kind, target, tuple(tagged), tuple(unmatched),
                          tuple(sorted(match.idle, key=lambda x: x[0].number)), tuple(ignored),
                          _suggested_offset(photos, events, clock_offset, tolerance), cameras, chosen)
    log.info("geotag %s: %d tagged, %d untagged, %d events without a photo", folder, len(tagged),
             len(unmatched), len(report.events_without_photo))
    return report

