"""The review's log reader (driver/review): a .BIN made here with FMT + records reads as pymavlink's DFReader
reads it; a .tlog from the recordings gives its types, modes, messages and parameters; bad input is a LogError."""
from __future__ import annotations

import os
import random
import tracemalloc

import numpy as np
import pytest
from pymavlink import DFReader

from driver.review import LogError, open_log
from driver.review.log import param_diff
from driver.review.writer import DataFlashWriter, sample_flight

RECORDINGS = os.path.join(os.path.dirname(__file__), "data", "recordings")


@pytest.fixture()
def bin_path(tmp_path):
    path = str(tmp_path / "flight.BIN")
    sample_flight(seconds=20, rate_hz=10).save(path)
    return path


def test_fields_read_as_dfreader_reads_them(bin_path):
    log = open_log(bin_path)
    reader = DFReader.DFReader_binary(bin_path)
    rolls, lats = [], []
    while (m := reader.recv_msg()) is not None:
        if m.get_type() == "ATT":
            rolls.append(m.Roll)
        elif m.get_type() == "GPS":
            lats.append(m.Lat)
    assert np.allclose(log.series("ATT", "Roll")[1], rolls)
    assert np.allclose(log.series("GPS", "Lat")[1], lats)
    assert "DesRoll" in log.tree()["ATT"] and "TimeUS" not in log.tree()["ATT"]
    t = log.series("ATT", "Roll")[0]
    assert np.all(np.diff(t) > 0) and t[0] >= 0


def test_modes_events_path_and_parameters(bin_path):
    log = open_log(bin_path)
    assert [m for _t, m in log.modes()] == ["GUIDED", "LOITER", "RTL"]
    kinds = {(e.kind, e.text) for e in log.events()}
    assert ("arming", "armed") in kinds and ("arming", "disarmed") in kinds
    assert ("failsafe", "battery failsafe triggered") in kinds
    assert ("message", "Battery 1 is low 10.40V used 2200 mAh") in kinds
    path = log.flight_path()
    assert path.mode[0] == "GUIDED" and path.mode[-1] == "RTL" and abs(path.lat[0] + 35.36) < 0.01
    assert log.params()["RTL_ALT"] == 1500.0
    assert param_diff(log.params(), {"RTL_ALT": 2000.0, "WPNAV_SPEED": 500.0, "NEW": 1.0}) == [
        ("BATT_LOW_VOLT", 10.5, None), ("NEW", None, 1.0), ("RTL_ALT", 1500.0, 2000.0)]


def test_each_gps_imu_and_battery_is_its_own_series(tmp_path):
    """Two GPS, two IMUs, two batteries interleave record by record: each instance is its own type in the tree
    (GPS[0], GPS[1], as pymavlink names them), and the path and the presets follow the first."""
    path = str(tmp_path / "dual.BIN")
    sample_flight(seconds=20, rate_hz=10, sensors=2).save(path)
    log = open_log(path)
    tree = log.tree()
    assert {"GPS[0]", "GPS[1]", "VIBE[0]", "VIBE[1]", "BAT[0]", "BAT[1]"} <= set(tree)
    assert not {"GPS", "VIBE", "BAT"} & set(tree) and "Lat" in tree["GPS[1]"]
    assert log.count("GPS[0]") == log.count("GPS[1]") == log.count("GPS") // 2
    (t0, lat0), (t1, lat1) = log.series("GPS[0]", "Lat"), log.series("GPS[1]", "Lat")
    assert np.allclose(lat1 - lat0, 1e-4, atol=2e-7) and np.array_equal(t0, t1)
    assert np.allclose(log.series("VIBE[1]", "VibeX")[1] - log.series("VIBE[0]", "VibeX")[1], 10.0)
    flown = log.flight_path()
    assert np.array_equal(flown.lat, lat0)              # one receiver, not a zig-zag between the two
    assert log.preset("Vibration") == [("VIBE[0]", "VibeX", 0), ("VIBE[0]", "VibeY", 0), ("VIBE[0]", "VibeZ", 0)]
    assert ("GPS[0]", "NSats", 0) in log.preset("GPS") and ("BAT[0]", "Volt", 0) in log.preset("Battery")
    sample_flight(seconds=5, rate_hz=10).save(str(tmp_path / "one.BIN"))
    single = open_log(str(tmp_path / "one.BIN")).tree()
    assert "GPS" in single and "GPS[0]" not in single           # one receiver: nothing to tell apart


def test_the_instance_column_is_the_one_fmtu_marks(tmp_path):
    """ArduPilot's FMTU marks the instance field with the unit '#': a type this reader has never heard of splits
    by it, and FMTU wins over the known columns."""
    w = DataFlashWriter()
    w.define(140, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds")
    w.define(141, "NEWS", "QBBf", "TimeUS,Unit,Core,Val")
    w.define(142, "GPS", "QBBL", "TimeUS,I,Rcv,Lat")
    w.record("FMTU", 1, 141, "s-#-", "F---")
    w.record("FMTU", 2, 142, "s-#D", "F--G")
    for k in range(10):
        w.record("NEWS", 100 + k, 0, k % 3, float(k))
        w.record("GPS", 100 + k, 0, k % 2, -353632621 + k)
    path = str(tmp_path / "fmtu.BIN")
    w.save(path)
    log = open_log(path)
    assert {"NEWS[0]", "NEWS[1]", "NEWS[2]", "GPS[0]", "GPS[1]"} <= set(log.tree())
    assert log.series("NEWS[2]", "Val")[1].tolist() == [2.0, 5.0, 8.0]
    assert log.count("GPS[1]") == 5 and log.first_instance("GPS") == "GPS[0]"


def test_events_and_errors_say_what_ardupilot_4_6_means(tmp_path):
    """EV ids and ERR subsystems/codes as AP_Logger.h (4.6.3) numbers them; arming once, from ARM, though EV logs
    it too; a flight mode error names the mode refused."""
    w = DataFlashWriter()
    w.define(130, "EV", "QB", "TimeUS,Id")
    w.define(131, "ERR", "QBB", "TimeUS,Subsys,ECode")
    w.define(132, "ARM", "QBIBB", "TimeUS,ArmState,ArmChecks,Forced,Method")
    w.record("ARM", 1000, 1, 0, 0, 0)
    w.record("EV", 1000, 10)                              # AP_Arming writes both
    for k, i in enumerate((41, 62, 64, 15)):
        w.record("EV", 2000 + k, i)
    for k, (sub, code) in enumerate(((19, 1), (24, 1), (27, 1), (20, 1), (29, 0), (23, 1), (10, 5), (16, 2),
                                     (12, 1), (6, 1), (99, 7))):
        w.record("ERR", 3000 + k, sub, code)
    w.record("EV", 9000, 11)
    w.record("ARM", 9000, 0, 0, 0, 0)
    path = str(tmp_path / "events.BIN")
    w.save(path)
    events = [(e.kind, e.text) for e in open_log(path).events()]
    assert events == [
        ("arming", "armed"), ("event", "fence enabled"), ("event", "EKF yaw reset"),
        ("event", "ADS-B avoidance disabled"), ("event", "auto armed"),
        ("failsafe", "CPU failsafe triggered"), ("event", "EKF primary changed to core 1"),
        ("failsafe", "leak failsafe triggered"), ("failsafe", "ADS-B failsafe triggered"),
        ("failsafe", "vibration failsafe cleared"), ("failsafe", "terrain failsafe triggered"),
        ("error", "flight mode LOITER refused"), ("error", "EKF check: bad variance"), ("error", "crash check: crash"),
        ("failsafe", "battery failsafe triggered"), ("error", "subsystem 99: code 7"), ("arming", "disarmed")]


def test_csv_holds_the_chosen_fields(bin_path, tmp_path):
    log = open_log(bin_path)
    out = str(tmp_path / "f.csv")
    rows = log.export_csv(out, [("ATT", "Roll"), ("BAT", "Volt")])
    lines = open(out).read().splitlines()
    assert lines[0] == "time_s,ATT.Roll,BAT.Volt" and len(lines) == rows + 1
    assert float(lines[-1].split(",")[2]) == pytest.approx(log.series("BAT", "Volt")[1][-1], rel=1e-6)


def test_truncated_and_corrupt_bin_still_open(bin_path, tmp_path):
    data = open(bin_path, "rb").read()
    cut = str(tmp_path / "cut.BIN")
    open(cut, "wb").write(data[:len(data) // 2 + 7])          # a record cut in half at the end
    log = open_log(cut)
    assert 0 < log.count("ATT") < open_log(bin_path).count("ATT") and log.skipped_bytes > 0
    bad = bytearray(data)
    middle = len(bad) // 2
    bad[middle:middle + 300] = os.urandom(300)                # garbage inside
    path = str(tmp_path / "bad.BIN")
    open(path, "wb").write(bad)
    log = open_log(path)
    assert log.count("ATT") > 0.9 * open_log(bin_path).count("ATT") and log.skipped_bytes >= 200


def test_a_bin_is_indexed_in_less_memory_than_twice_its_size(tmp_path):
    """The index keeps numpy arrays, never a Python int per record nor a temporary the size of the file:
    a 75 MB log took 485 MB to open (about 5x), a 100 MB one 505 MB."""
    path = str(tmp_path / "long.BIN")
    sample_flight(seconds=240, rate_hz=50).save(path)
    size = os.path.getsize(path)
    tracemalloc.start()
    try:
        log = open_log(path)
        assert log.count("ATT") == 240 * 50
        _now, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 2 * size, f"{peak / 1e6:.1f} MB to open a {size / 1e6:.1f} MB log"


@pytest.mark.parametrize("content,words", [(b"", "empty"), (os.urandom(5000), "not a .BIN"),
                                           (b"\xa3\x95\x80" + bytes(40), "FMT")])
def test_bad_bin_is_a_clear_error(tmp_path, content, words):
    path = str(tmp_path / "x.BIN")
    open(path, "wb").write(content.replace(b"\xa3\x95", b"\xa3\x96") if words == "not a .BIN" else content)
    with pytest.raises(LogError, match=words):
        open_log(path)


def test_tlog_from_the_recordings():
    log = open_log(os.path.join(RECORDINGS, "arducopter-4.6-sitl-adsb.tlog"))
    assert "roll" in log.tree()["ATTITUDE"]
    assert any(e.text == "ArduPilot Ready" for e in log.events())
    assert log.modes()[0][1] == "STABILIZE"
    assert len(log.params()) > 0
    assert log.flight_path() is not None


def test_a_tlog_gives_the_messages_above_id_255():
    """MAVLink 2's ids above 255 (ESC_TELEMETRY_1_TO_4 is 11030, in the 4.7 recording) are read with MAVLink 2's
    codec, whatever dialect mavutil picked for the process: with the 1.0 one they were UNKNOWN and dropped; and
    its array fields are plotted element by element."""
    log = open_log(os.path.join(RECORDINGS, "arducopter-4.7-sitl-flight.tlog"))
    fields = log.tree()["ESC_TELEMETRY_1_TO_4"]
    assert {"rpm[0]", "rpm[3]", "voltage[0]"} <= set(fields), fields     # an array field: a column per element


@pytest.mark.parametrize("content,words", [(b"", "empty"), (b"\x00garbage" * 500, "no MAVLink")])
def test_bad_tlog_is_a_clear_error(tmp_path, content, words):
    path = str(tmp_path / "x.tlog")
    open(path, "wb").write(content)
    with pytest.raises(LogError, match=words):
        open_log(path)


def test_random_bytes_are_not_a_telemetry_log(tmp_path):
    """Random bytes parse as a message the dialect does not know (UNKNOWN_79, from the year 340,000): none is kept,
    so the file is said to be no telemetry log rather than opened."""
    path = str(tmp_path / "random.tlog")
    open(path, "wb").write(random.Random(0).randbytes(20000))
    with pytest.raises(LogError, match="not a telemetry log"):
        open_log(path)


def test_a_tlog_is_kept_in_compact_columns():
    """Each field in an array of its MAVLink type, not a Python number a field a message: a 63 MB .tlog took
    648 MB; the 0.4 MB flight here took 3.9 MB (9x its size) at the peak."""
    path = os.path.join(RECORDINGS, "arducopter-4.7-sitl-flight.tlog")
    open_log(path)                                            # pymavlink's dialect loaded, not counted
    tracemalloc.start()
    try:
        log = open_log(path)
        _now, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert log.count("ATTITUDE") > 500 and log.series("ATTITUDE", "roll")[1].dtype == np.float64
    assert peak < 4 * os.path.getsize(path), f"{peak / 1e6:.1f} MB"


def test_tlog_with_garbage_inside_keeps_its_messages(tmp_path):
    data = open(os.path.join(RECORDINGS, "arducopter-4.6-sitl-adsb.tlog"), "rb").read()
    path = str(tmp_path / "g.tlog")
    open(path, "wb").write(data[:len(data) // 2] + os.urandom(2000) + data[len(data) // 2:])
    assert open_log(path).count("ATTITUDE") > 0


@pytest.mark.parametrize("name", ["pymavlink-test.BIN", "ap-logger-alltypes.BIN"])
def test_real_ardupilot_logs_read_as_dfreader_reads_them(name):
    path = os.path.join(os.path.dirname(__file__), "data", "logs", name)
    log = open_log(path)
    reader = DFReader.DFReader_binary(path)
    messages: dict[str, list] = {}
    while (m := reader.recv_msg()) is not None:
        messages.setdefault(m.get_type(), []).append(m)
    tree = log.tree()
    assert set(tree) == set(messages) - {"FMT"}
    for mtype, fields in tree.items():
        assert log.count(mtype) == len(messages[mtype]), mtype
        for f in fields:
            theirs = [float(getattr(m, f)) for m in messages[mtype]]
            assert np.allclose(log.series(mtype, f)[1], theirs, equal_nan=True, rtol=1e-6), (mtype, f)
