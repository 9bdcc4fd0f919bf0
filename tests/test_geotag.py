"""Geotagging photos from a flight log (issue 31, Review): real JPEGs made with OpenCV and dated with piexif, real
DataFlash logs with CAM records written by the simulator's log writer (and one flown on the simulator), the EXIF
read back with piexif. The n-th photo takes the n-th event, checked by time; what is left over is reported; the
originals are never rewritten unless asked."""
from __future__ import annotations

import os
import struct
from datetime import datetime, timedelta, timezone

import cv2
import numpy as np
import piexif
import pytest
from pymavlink import DFReader
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.review.geotag import GeotagError, geotag, gps_utc
from driver.review.writer import DataFlashWriter
from driver.sim.dataflash import LogFolder

LOGS = os.path.join(os.path.dirname(__file__), "data", "logs")
WEEK = 2300
HOME = (-35.3632621, 149.1652374, 584.0)      # ArduPilot's SITL home (CMAC)
CAMERA_AHEAD = 3600.0                          # the camera's clock set to UTC+1


def cam_rows(count: int, first_ms: int = 100_000, every_ms: int = 3_000):
    """(TimeUS, GPS ms into the week, lat, lon, alt AMSL m, above home m) of ``count`` photos along a line."""
    return [(1_000_000 + k * every_ms * 1000, first_ms + k * every_ms, HOME[0] + k * 1.234567e-4,
             HOME[1] - k * 2.345678e-4, HOME[2] + 30.0 + k * 0.37, 30.0 + k * 0.37) for k in range(count)]


def write_log(folder, rows, with_cam: bool = True, second=()) -> str:
    """A .BIN as the simulator writes one: PARM, GPS at 5 Hz over the flight, a CAM for each row (and for each row
    of ``second``, a second camera's, instance 1)."""
    logs = LogFolder(str(folder))
    number = logs.begin([("SYSID_THISMAV", 1.0)])
    end_us = (rows[-1][0] if rows else 10_000_000) + 2_000_000
    pending = sorted([(r, 0) for r in rows] + [(r, 1) for r in second]) if with_cam else []
    counts = [0, 0]
    gps_ms0 = (rows[0][1] if rows else 100_000) - (rows[0][0] if rows else 1_000_000) // 1000
    for us in range(0, end_us, 200_000):
        while pending and pending[0][0][0] <= us:
            (t_us, ms, lat, lon, alt, rel), camera = pending.pop(0)
            counts[camera] += 1
            logs.write("CAM", t_us, camera, counts[camera], ms, WEEK, round(lat * 1e7), round(lon * 1e7),
                       round(alt * 100), round(rel * 100), round(alt * 100), 0, 0, 9000)
        logs.write("GPS", us, 3, gps_ms0 + us // 1000, WEEK, 14, round(HOME[0] * 1e7), round(HOME[1] * 1e7),
                   round(HOME[2] * 100), 0.0, 0.0)
    logs.end()
    return logs.path(number)


def utc_of(row) -> datetime:
    return gps_utc(WEEK, row[1])


def make_photo(path, taken: datetime | None, shade: int = 0) -> None:
    """A real JPEG (OpenCV), with DateTimeOriginal and SubSecTimeOriginal as a camera writes them."""
    image = np.zeros((48, 64, 3), np.uint8)
    image[:, :, 0] = np.arange(64, dtype=np.uint8) * 4
    image[:, :, 1] = shade
    assert cv2.imwrite(str(path), image)
    if taken is not None:
        exif = {"0th": {piexif.ImageIFD.Make: b"UavViewerPy test"}, "Exif": {
            piexif.ExifIFD.DateTimeOriginal: taken.strftime("%Y:%m:%d %H:%M:%S").encode(),
            piexif.ExifIFD.SubSecTimeOriginal: f"{taken.microsecond // 10_000:02d}".encode()}}
        piexif.insert(piexif.dump(exif), str(path))


def shoot(folder, rows, ahead: float = CAMERA_AHEAD, names=None) -> list[str]:
    """A photo for each row, taken on a camera clock ``ahead`` of UTC."""
    folder.mkdir(exist_ok=True)
    names = names or [f"IMG_{k + 1:04d}.JPG" for k in range(len(rows))]
    for k, (name, row) in enumerate(zip(names, rows)):
        make_photo(folder / name, (utc_of(row) + timedelta(seconds=ahead)).replace(tzinfo=None), shade=k * 20)
    return names


def exif_position(path) -> tuple[float, float, float]:
    gps = piexif.load(str(path))["GPS"]

    def degrees(dms, ref):
        value = sum(n / d / 60 ** i for i, (n, d) in enumerate(dms))
        return -value if ref in (b"S", b"W") else value
    alt = gps[piexif.GPSIFD.GPSAltitude][0] / gps[piexif.GPSIFD.GPSAltitude][1]
    return (degrees(gps[piexif.GPSIFD.GPSLatitude], gps[piexif.GPSIFD.GPSLatitudeRef]),
            degrees(gps[piexif.GPSIFD.GPSLongitude], gps[piexif.GPSIFD.GPSLongitudeRef]),
            -alt if gps[piexif.GPSIFD.GPSAltitudeRef] == 1 else alt)


def assert_tagged(path, row, relative: bool = False) -> None:
    lat, lon, alt = exif_position(path)
    assert abs(lat - row[2]) < 1e-7 and abs(lon - row[3]) < 1e-7, (path, lat, lon, row)
    assert abs(alt - (row[5] if relative else row[4])) < 0.006, (path, alt, row)


def test_each_photo_gets_its_cam_events_position_altitude_and_time(tmp_path):
    rows = cam_rows(5)
    bin_path = write_log(tmp_path, rows)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    before = {n: (photos / n).read_bytes() for n in names}
    report = geotag(bin_path, str(photos), clock_offset=CAMERA_AHEAD)
    assert report.source == "CAM" and len(report.tagged) == 5, report.lines()
    assert not report.unmatched and not report.events_without_photo and not report.ignored
    out = photos / "geotagged"
    assert report.output == str(out)
    for name, row, tagged in zip(names, rows, report.tagged):
        assert tagged.photo.name == name and tagged.written == str(out / name)
        assert abs(tagged.time_error) < 0.02
        assert_tagged(out / name, row)
        gps = piexif.load(str(out / name))["GPS"]
        when = utc_of(row)
        assert gps[piexif.GPSIFD.GPSDateStamp] == when.strftime("%Y:%m:%d").encode()
        h, m, s = gps[piexif.GPSIFD.GPSTimeStamp]
        assert (h[0], m[0], s[0] / s[1]) == (when.hour, when.minute, when.second + when.microsecond / 1e6)
        exif = piexif.load(str(out / name))
        assert exif["0th"][piexif.ImageIFD.Make] == b"UavViewerPy test"       # the camera's own tags kept
        assert np.array_equal(cv2.imread(str(out / name)), cv2.imread(str(photos / name)))   # pixels untouched
        assert (photos / name).read_bytes() == before[name]                  # the original is not rewritten
        assert piexif.load(str(photos / name))["GPS"] == {}
    assert "5 photos tagged from CAM events" in report.lines()[0]


def test_relative_altitude_and_a_chosen_output_folder(tmp_path):
    rows = cam_rows(3)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    out = tmp_path / "out"
    report = geotag(write_log(tmp_path, rows), str(photos), str(out), clock_offset=CAMERA_AHEAD,
                    altitude="relative")
    assert len(report.tagged) == 3 and report.output == str(out)
    for name, row in zip(names, rows):
        assert_tagged(out / name, row, relative=True)


def test_more_photos_than_events(tmp_path):
    rows = cam_rows(7)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)                   # 7 photos, but the log has only the first 5 events
    report = geotag(write_log(tmp_path, rows[:5]), str(photos), clock_offset=CAMERA_AHEAD)
    assert [t.photo.name for t in report.tagged] == names[:5]
    assert [u.name for u in report.unmatched] == names[5:]
    assert all("more photos than events (7 photos, 5 CAM events)" in u.reason for u in report.unmatched)
    assert not report.events_without_photo
    assert not (photos / "geotagged" / names[5]).exists()


def test_fewer_photos_than_events(tmp_path):
    rows = cam_rows(5)
    photos = tmp_path / "photos"
    shoot(photos, rows[:3])
    report = geotag(write_log(tmp_path, rows), str(photos), clock_offset=CAMERA_AHEAD)
    assert len(report.tagged) == 3 and not report.unmatched
    assert [e.number for e, _why in report.events_without_photo] == [4, 5]
    assert all("fewer photos than events" in why for _e, why in report.events_without_photo)
    assert any("CAM 4 (image 4" in line and "has no photo" in line for line in report.lines())


def test_a_photo_whose_time_does_not_match_its_event_is_left_untagged(tmp_path):
    rows = cam_rows(4)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    late = (utc_of(rows[2]) + timedelta(seconds=CAMERA_AHEAD + 1.4)).replace(tzinfo=None)
    make_photo(photos / names[2], late)           # 1.4 s after its event: still within 2 s, but not within 1 s
    bin_path = write_log(tmp_path, rows)
    report = geotag(bin_path, str(photos), clock_offset=CAMERA_AHEAD, tolerance=1.0)
    assert [t.photo.name for t in report.tagged] == [names[0], names[1], names[3]]
    (untagged,) = report.unmatched
    assert untagged.name == names[2] and "time mismatch: taken +1.4 s from CAM 3" in untagged.reason
    assert [e.number for e, _why in report.events_without_photo] == [3]
    assert not (photos / "geotagged" / names[2]).exists()
    assert report.suggested_offset is None                   # the offset set is right: one photo is off
    assert len(geotag(bin_path, str(photos), clock_offset=CAMERA_AHEAD).tagged) == 4     # the default 2 s


def test_a_camera_clock_left_unset_is_caught_and_its_offset_suggested(tmp_path):
    rows = cam_rows(3)
    photos = tmp_path / "photos"
    shoot(photos, rows)
    report = geotag(write_log(tmp_path, rows), str(photos))          # no offset: the camera is an hour ahead
    assert not report.tagged and len(report.unmatched) == 3
    assert report.suggested_offset == pytest.approx(CAMERA_AHEAD, abs=0.02)
    assert any("+3600.0 s" in line and "camera clock offset" in line for line in report.lines())


def test_a_missed_trigger_matched_by_time(tmp_path):
    """The camera missed the third trigger: by order, photos 3 and 4 fall on the wrong events (and are caught by
    time); by time, each photo finds its own event and the third event is reported without a photo."""
    rows = cam_rows(5)
    photos = tmp_path / "photos"
    names = shoot(photos, rows[:2] + rows[3:])
    bin_path = write_log(tmp_path, rows)
    by_order = geotag(bin_path, str(photos), clock_offset=CAMERA_AHEAD)
    assert [t.photo.name for t in by_order.tagged] == names[:2]
    assert [u.name for u in by_order.unmatched] == names[2:]
    report = geotag(bin_path, str(photos), str(tmp_path / "by-time"), clock_offset=CAMERA_AHEAD, by="time")
    assert [(t.photo.name, t.event.number) for t in report.tagged] == list(zip(names, [1, 2, 4, 5]))
    assert [e.number for e, why in report.events_without_photo] == [3]
    for name, row in zip(names, rows[:2] + rows[3:]):
        assert_tagged(tmp_path / "by-time" / name, row)


def test_files_that_are_not_jpegs_are_ignored_and_take_no_event(tmp_path):
    rows = cam_rows(3)
    photos = tmp_path / "photos"
    names = shoot(photos, rows, names=["a.jpg", "c.jpeg", "e.JPG"])
    (photos / "b.txt").write_text("flight notes")
    (photos / "d.jpg").write_bytes(b"not a picture at all")
    cv2.imwrite(str(photos / "f.png"), np.zeros((8, 8, 3), np.uint8))
    (photos / "sub").mkdir()
    report = geotag(write_log(tmp_path, rows), str(photos), clock_offset=CAMERA_AHEAD)
    assert [t.photo.name for t in report.tagged] == names and not report.unmatched
    assert {u.name: u.reason for u in report.ignored} == {
        "b.txt": "not a JPEG", "d.jpg": "named .jpg but not a JPEG", "f.png": "not a JPEG"}
    for name, row in zip(names, rows):
        assert_tagged(photos / "geotagged" / name, row)


def test_a_log_without_camera_events_is_a_clear_error(tmp_path):
    photos = tmp_path / "photos"
    shoot(photos, cam_rows(2))
    with pytest.raises(GeotagError, match="no CAM or TRIG records in this log"):
        geotag(write_log(tmp_path, cam_rows(2), with_cam=False), str(photos))
    with pytest.raises(GeotagError, match="no CAM or TRIG records"):         # a real ArduPilot log
        geotag(os.path.join(LOGS, "pymavlink-test.BIN"), str(photos))
    assert not (photos / "geotagged").exists()


def test_bad_folders_are_clear_errors(tmp_path):
    rows = cam_rows(2)
    bin_path = write_log(tmp_path, rows)
    with pytest.raises(GeotagError, match="no such folder"):
        geotag(bin_path, str(tmp_path / "nowhere"))
    (tmp_path / "empty").mkdir()
    with pytest.raises(GeotagError, match="no JPEG photos"):
        geotag(bin_path, str(tmp_path / "empty"))
    photos = tmp_path / "photos"
    shoot(photos, rows)
    with pytest.raises(GeotagError, match="the photos' own folder"):
        geotag(bin_path, str(photos), str(photos))


def test_in_place_rewrites_the_originals_only_when_asked(tmp_path):
    rows = cam_rows(2)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    report = geotag(write_log(tmp_path, rows), str(photos), clock_offset=CAMERA_AHEAD, in_place=True)
    assert report.output == str(photos) and not (photos / "geotagged").exists()
    for name, row in zip(names, rows):
        assert_tagged(photos / name, row)
    assert sorted(os.listdir(photos)) == names                        # no temporary file left behind


def test_trig_records_and_an_older_cam_without_gps_time(tmp_path):
    """TRIG where the log has no CAM; a CAM without GPSTime/GPSWeek takes its time from the GPS records."""
    rows = cam_rows(3)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    for name, layout in (("TRIG", "QBHIHLLeeeccC"), ("CAM", "QLLeeccC")):
        w = DataFlashWriter()
        w.define(68, "GPS", "QBIHBLLeff", "TimeUS,Status,GMS,GWk,NSats,Lat,Lng,Alt,Spd,GCrs")
        columns = ("TimeUS,I,Img,GPSTime,GPSWeek,Lat,Lng,Alt,RelAlt,GPSAlt,R,P,Y" if layout.startswith("QB")
                   else "TimeUS,Lat,Lng,Alt,RelAlt,Roll,Pitch,Yaw")
        w.define(71, name, layout, columns)
        by_time = {r[0]: (k, r) for k, r in enumerate(rows)}
        for us in range(0, rows[-1][0] + 1_000_000, 200_000):
            w.record("GPS", us, 3, rows[0][1] - rows[0][0] // 1000 + us // 1000, WEEK, 14, 0, 0, 0, 0.0, 0.0)
            if us in by_time:
                k, (_t, ms, lat, lon, alt, rel) = by_time[us]
                position = (round(lat * 1e7), round(lon * 1e7), round(alt * 100), round(rel * 100))
                if layout.startswith("QB"):
                    w.record(name, us, 0, k + 1, ms, WEEK, *position, position[2], 0, 0, 0)
                else:
                    w.record(name, us, *position, 0, 0, 0)
        path = str(tmp_path / f"{name}-{len(layout)}.BIN")
        w.save(path)
        report = geotag(path, str(photos), str(tmp_path / name), clock_offset=CAMERA_AHEAD)
        assert report.source == name and len(report.tagged) == 3, report.lines()
        for name_, row, tagged in zip(names, rows, report.tagged):
            assert abs(tagged.time_error) < 0.02
            assert_tagged(tmp_path / name / name_, row)


def tlog_bytes(messages) -> bytes:
    """A .tlog: each MAVLink 2 packet after its receive time (big-endian Unix microseconds), as ground stations
    write them."""
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    out = b""
    for stamp, m in messages:
        out += struct.pack(">Q", int(stamp * 1e6)) + m.pack(mav)
    return out


def test_camera_feedback_in_a_tlog(tmp_path):
    rows = cam_rows(3)
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    messages = []
    for k, (_us, _ms, lat, lon, alt, rel) in enumerate(rows):
        utc = utc_of(rows[k]).timestamp()
        messages.append((utc - 5.0, mavlink.MAVLink_heartbeat_message(2, 3, 0, 4, 4, 3)))
        messages.append((utc + 0.3, mavlink.MAVLink_camera_feedback_message(
            int(round(utc * 1e6)), 1, 0, k + 1, round(lat * 1e7), round(lon * 1e7), alt, rel, 0, 0, 90, 4.0, 0,
            k + 1)))
    path = tmp_path / "flight.tlog"
    path.write_bytes(tlog_bytes(messages))
    report = geotag(str(path), str(photos), clock_offset=CAMERA_AHEAD)
    assert report.source == "CAMERA_FEEDBACK" and len(report.tagged) == 3, report.lines()
    for name, row in zip(names, rows):
        assert_tagged(photos / "geotagged" / name, row)
    # with a feedback pin ArduPilot stamps CAMERA_FEEDBACK with its boot time: the receive time stands in
    for _stamp, m in messages[1::2]:
        m.time_usec = 1_000_000 + m.img_idx
    path.write_bytes(tlog_bytes(messages))
    report = geotag(str(path), str(photos), str(tmp_path / "boot"), clock_offset=CAMERA_AHEAD)
    assert len(report.tagged) == 3 and all(-0.35 < t.time_error < -0.25 for t in report.tagged), report.lines()
    (tmp_path / "none.tlog").write_bytes(tlog_bytes(messages[:1]))
    with pytest.raises(GeotagError, match="no CAMERA_FEEDBACK"):
        geotag(str(tmp_path / "none.tlog"), str(photos))


@pytest.mark.timeout(120)
def test_photos_of_a_survey_flown_on_the_simulator(sim_factory, vehicle_factory, tmp_path):
    """The simulated ArduCopter flies a survey pass taking photos; its own log's CAM records, read by pymavlink's
    DFReader, are the truth each photo's EXIF must hold."""
    from test_sim_survey_photos import fly
    from test_mission_flight import quick_rtl
    sim = quick_rtl(sim_factory(speedup=8.0, camera="trigger"))
    drone = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    fly(drone)
    folder = sim.autopilot.log_folder
    bin_path = folder.path(folder.numbers()[-1])
    reader = DFReader.DFReader_binary(bin_path)
    cams = []
    while (m := reader.recv_match(type="CAM")) is not None:
        cams.append(m)
    assert len(cams) == sim.autopilot.images >= 6
    rows = [(0, m.GPSTime, m.Lat, m.Lng, m.Alt, m.RelAlt) for m in cams]
    assert all(m.GPSWeek == WEEK for m in cams)
    photos = tmp_path / "photos"
    names = shoot(photos, rows, ahead=-7200.0)     # a camera on UTC-2
    report = geotag(bin_path, str(photos), clock_offset=-7200.0)
    assert len(report.tagged) == len(cams) and not report.unmatched and not report.events_without_photo
    for name, row in zip(names, rows):
        assert_tagged(photos / "geotagged" / name, row)
    assert len({exif_position(photos / "geotagged" / n)[:2] for n in names}) == len(names)   # along the pass


def test_an_event_without_a_position_writes_nothing(tmp_path):
    """A CAM logged before the first fix (0, 0): its photo keeps its EXIF as it was, and says why."""
    rows = cam_rows(3)
    rows[1] = rows[1][:2] + (0.0, 0.0) + rows[1][4:]
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    report = geotag(write_log(tmp_path, rows), str(photos), clock_offset=CAMERA_AHEAD)
    assert [t.photo.name for t in report.tagged] == [names[0], names[2]]
    assert [u.name for u in report.unmatched] == [names[1]] and "CAM 2 has no position" in report.unmatched[0].reason
    assert [e.number for e, _why in report.events_without_photo] == [2]
    assert not (photos / "geotagged" / names[1]).exists()


def test_photos_without_a_date_are_matched_by_order_and_said_so(tmp_path):
    rows = cam_rows(2)
    photos = tmp_path / "photos"
    photos.mkdir()
    for k in range(2):
        make_photo(photos / f"P{k}.jpg", None)
    report = geotag(write_log(tmp_path, rows), str(photos))
    assert [(t.photo.name, t.time_error) for t in report.tagged] == [("P0.jpg", None), ("P1.jpg", None)]
    assert "2 photos matched by order only, not checked by time" in "\n".join(report.lines())
    for k, row in enumerate(rows):
        assert_tagged(photos / "geotagged" / f"P{k}.jpg", row)


def test_two_cameras_each_count_their_own_photos(tmp_path):
    rows = cam_rows(3)
    other = [(r[0] + 2_600_000, r[1] + 2600, r[2] + 1e-4, r[3] + 1e-4, r[4] + 1.0, r[5] + 1.0) for r in cam_rows(2)]
    bin_path = write_log(tmp_path, rows, second=other)
    photos = tmp_path / "photos"
    names = shoot(photos, other)
    report = geotag(bin_path, str(photos), clock_offset=CAMERA_AHEAD, camera=1)
    assert report.cameras == (0, 1) and report.camera == 1
    assert [(t.photo.name, t.event.number, t.event.image) for t in report.tagged] == [(names[0], 1, 1),
                                                                                      (names[1], 2, 2)]
    assert not report.events_without_photo
    for name, row in zip(names, other):
        assert_tagged(photos / "geotagged" / name, row)
    first = geotag(bin_path, str(photos), str(tmp_path / "first"), clock_offset=CAMERA_AHEAD)
    assert first.camera == 0 and "the log has cameras 0, 1: camera 0's events were used" in first.lines()
    assert [u.name for u in first.unmatched] == names                 # 2.6 s off camera 0's: time mismatches
    with pytest.raises(GeotagError, match="no camera 2"):
        geotag(bin_path, str(photos), camera=2)


def test_the_console_geotags_without_a_vehicle(tmp_path):
    import io
    from driver.console.console import Console
    rows = cam_rows(3)
    photos = tmp_path / "photos"
    names = shoot(photos, rows + cam_rows(4)[3:])
    bin_path = write_log(tmp_path, rows)
    out = io.StringIO()
    console = Console(None, stdout=out)
    assert not console.onecmd(f"geotag {bin_path} {photos} {tmp_path / 'out'} offset={CAMERA_AHEAD:g} by=order "
                              "camera=0")
    report = console.geotag_run.result(30)
    assert len(report.tagged) == 3
    text = out.getvalue()
    assert f"3 photos tagged from CAM events into {tmp_path / 'out'}" in text
    assert f"untagged {names[3]}: more photos than events (4 photos, 3 CAM events)" in text
    for name, row in zip(names, rows):
        assert_tagged(tmp_path / "out" / name, row)
    console.onecmd(f"geotag {bin_path}")
    assert "error: usage: geotag LOG FOLDER" in out.getvalue()
    console.onecmd(f"geotag {os.path.join(LOGS, 'pymavlink-test.BIN')} {photos}")
    assert console.geotag_run.result(30) is None
    assert "error: geotag: pymavlink-test.BIN: no CAM or TRIG records" in out.getvalue()
