"""DataFlash logs over LOG_*: the simulator writes and serves real .BIN logs as ArduCopter 4.6.3 does
(tests/data/recordings/arducopter-4.6-sitl-logs.*), and the driver lists and downloads them complete and
byte-identical through loss, resuming from its partial file after a dropped link or an app restart."""
from __future__ import annotations

import io
import os

import pytest
from pymavlink.DFReader import DFReader_binary

from driver.console.console import Console
from driver.logs import ranges
from driver.logs.check import LogFileError, check_dataflash
from driver.sim.dataflash import LogFolder, write_flight_log
from driver.sim.faults import LinkFaults

from ice_fixtures import eventually
from test_mission_console import wait_text


def logs_sim(sim_factory, tmp_path, sizes, **config):
    """A simulated vehicle whose log folder already holds logs of these sizes (as if flown)."""
    folder = LogFolder(str(tmp_path / "vehicle-logs"))
    for i, size in enumerate(sizes):
        write_flight_log(folder, size, seed=i)
    return sim_factory(log_dir=folder.folder, **config), folder


def connect(vehicle_factory, sim, **config):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", **config)
    assert v.wait_for(lambda s: s.connected, 10)
    return v


def lossy(sim, share: float) -> None:
    sim.faults.uplink = LinkFaults(loss=share)
    sim.faults.downlink = LinkFaults(loss=share)


def same_bytes(path, folder: LogFolder, log_id: int) -> bool:
    with open(path, "rb") as a, open(folder.path(log_id), "rb") as b:
        return a.read() == b.read()


def test_the_sim_logs_while_armed_and_dfreader_reads_it(sim_factory, vehicle_factory, tmp_path):
    sim = sim_factory(log_dir=str(tmp_path / "logs"), auto_disarm_after=3.0, camera=True)
    v = connect(vehicle_factory, sim)
    assert v.set_mode("GUIDED").result(10).ok
    assert v.arm().result(10).ok
    assert v.wait_for(lambda s: s.armed, 10)
    assert v.take_photo().result(10).ok
    assert v.wait_for(lambda s: not s.armed, 30), "the sim did not disarm by itself"
    folder = LogFolder(str(tmp_path / "logs"))
    assert folder.numbers() == [1]
    reader = DFReader_binary(folder.path(1))
    kinds = set()
    while (m := reader.recv_msg()) is not None:
        kinds.add(m.get_type())
    assert {"FMT", "PARM", "MODE", "MSG", "ATT", "GPS", "BAT", "CTUN", "CAM"} <= kinds
    assert check_dataflash(folder.path(1)).messages > 100
    listed = v.logs.list().result(20)
    assert listed.ok and [(e.id, e.size) for e in listed.entries] == [(1, os.path.getsize(folder.path(1)))]


def test_the_list_is_complete_under_loss(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [3000 + 500 * i for i in range(6)])
    v = connect(vehicle_factory, sim)
    lossy(sim, 0.3)
    listed = v.logs.list().result(60)
    assert listed.ok, listed.reason
    assert [(e.id, e.size) for e in listed.entries] == [(n, s) for n, s, _ in folder.entries()]


def test_each_list_request_goes_twice_and_never_finds_the_vehicle_busy(sim_factory, vehicle_factory, tmp_path):
    """The list is asked twice a try (a lost request or entry costs no try at 30 % loss), each LOG_REQUEST_LIST
    behind a LOG_REQUEST_END: a second LIST on its own would find the first listing still running whenever there
    is more than one log, and the pilot would read the vehicle's "Log download in progress"."""
    sim, folder = logs_sim(sim_factory, tmp_path, [3000, 4000, 5000])
    v = connect(vehicle_factory, sim)
    listed = v.logs.list().result(20)
    assert listed.ok and [e.id for e in listed.entries] == [1, 2, 3]
    asked = [kind for _, kind, _ in list(sim.received_messages) if kind.startswith("LOG_REQUEST")]
    assert asked[:4] == ["LOG_REQUEST_END", "LOG_REQUEST_LIST"] * 2
    # (the vehicle says it on receipt, before the entries that end the list: on one TCP stream, read before them)
    assert not [m.text for m in v.state().messages if "in progress" in m.text]


@pytest.mark.parametrize("via, loss", [("log_data", 0.0), ("log_data", 0.3), ("ftp", 0.0), ("ftp", 0.3)])
def test_download_is_byte_identical(sim_factory, vehicle_factory, tmp_path, via, loss):
    sim, folder = logs_sim(sim_factory, tmp_path, [20_000, 120_000], speedup=8.0)
    v = connect(vehicle_factory, sim)
    lossy(sim, loss)
    out = tmp_path / "got" / "two.BIN"
    outcome = v.logs.download(2, str(out), via=via).result(120)
    assert outcome.ok, outcome.reason
    assert outcome.size == os.path.getsize(folder.path(2)) and same_bytes(out, folder, 2)
    assert outcome.messages > 1000
    assert not os.path.exists(str(out) + ".part") and not os.path.exists(str(out) + ".part.json")


def test_a_dropped_link_resumes_and_commands_keep_flowing(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [600_000], radio_baud=1_000_000)
    v = connect(vehicle_factory, sim, loss_timeout=1.0)
    out = str(tmp_path / "one.BIN")
    future = v.logs.download(1, out)
    assert eventually(lambda: v.logs.progress and v.logs.progress.held > 50_000, 30)
    assert v.set_mode("LOITER").result(10).ok          # commands and their answers go on during a download
    sim.faults.link_down = True
    assert v.wait_for(lambda s: not s.connected, 10)
    held = v.logs.progress.held if v.logs.progress else 0
    sim.faults.link_down = False
    outcome = future.result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1)
    assert held > 0 and outcome.bytes_received < 1.5 * outcome.size    # resumed, never restarted


def test_a_new_vehicle_resumes_from_the_partial_file(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [600_000], radio_baud=1_000_000)
    first = connect(vehicle_factory, sim)
    out = str(tmp_path / "one.BIN")
    future = first.logs.download(1, out)
    assert eventually(lambda: first.logs.progress and first.logs.progress.held > 100_000, 30)
    first.close()                                       # the app quits mid-download
    assert not future.result(10).ok
    assert os.path.exists(out + ".part") and os.path.exists(out + ".part.json")
    second = connect(vehicle_factory, sim)
    outcome = second.logs.download(1, out).result(120)
    assert outcome.ok, outcome.reason
    assert outcome.resumed_from >= 100_000 and same_bytes(out, folder, 1)
    assert outcome.bytes_received <= outcome.size - outcome.resumed_from + 300 * 90   # (+ what was queued)


def test_armed_the_vehicle_says_disarm_for_log_download(sim_factory, vehicle_factory, tmp_path):
    sim, _ = logs_sim(sim_factory, tmp_path, [5_000], auto_disarm_after=60.0)
    v = connect(vehicle_factory, sim)
    assert v.set_mode("GUIDED").result(10).ok and v.arm().result(10).ok
    assert v.wait_for(lambda s: s.armed, 10)
    outcome = v.logs.list().result(20)
    assert not outcome.ok and "Disarm for log download" in outcome.reason
    assert eventually(lambda: any(m.text == "Disarm for log download" for m in v.state().messages), 10)


def test_an_unknown_log_id_and_an_empty_log(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [5_000])
    open(folder.path(2), "wb").close()                  # a log the vehicle began and never wrote to
    v = connect(vehicle_factory, sim)
    outcome = v.logs.download(7, str(tmp_path / "x.BIN")).result(20)
    assert not outcome.ok and outcome.reason == "no log 7 on the vehicle (logs 1 to 2)"
    assert not os.path.exists(tmp_path / "x.BIN.part")
    outcome = v.logs.download(2, str(tmp_path / "x.BIN")).result(20)
    assert not outcome.ok and outcome.reason == "log 2 is empty (0 bytes) on the vehicle"
    for wrong in (0, 70_000, "2"):
        outcome = v.logs.download(wrong, str(tmp_path / "x.BIN")).result(5)
        assert not outcome.ok and outcome.reason == f"no log {wrong}: log numbers go from 1 to 65535"


def test_a_corrupt_or_truncated_bin_is_told(tmp_path):
    folder = LogFolder(str(tmp_path / "logs"))
    data = open(folder.path(write_flight_log(folder, 20_000)), "rb").read()
    cases = {"cut.BIN": (data[:9000] + data[9100:], "corrupt"),          # cut in the middle
             "bad.BIN": (data[:9000] + b"x" * 40 + data[9040:], "corrupt"),
             "tail.BIN": (data + b"hello, not a log", "truncated or corrupt"),   # garbage after the last record
             "unknown.BIN": (data + b"\xa3\x95\x10" + bytes(5), "truncated or corrupt"),   # a type never declared
             "zeros.BIN": (data + bytes(70_000), "truncated or corrupt"),   # more than any page or cluster pads
             "empty.BIN": (b"", "empty"), "text.BIN": (b"hello, not a log\n" * 10, "not a DataFlash log")}
    for name, (raw, word) in cases.items():
        (tmp_path / name).write_bytes(raw)
        with pytest.raises(LogFileError, match=word):
            check_dataflash(str(tmp_path / name))
    (tmp_path / "short.BIN").write_bytes(data[:-24])                      # a whole record less than announced
    with pytest.raises(LogFileError, match=f"{len(data) - 24} bytes, shorter than the {len(data)} bytes the "
                                           "vehicle announced"):
        check_dataflash(str(tmp_path / "short.BIN"), announced=len(data))


def test_a_log_may_end_with_an_unfinished_record_or_padding(tmp_path):
    """A power loss stops AP_Logger inside a record; AP_Logger_Block pads its last page with zeros and erased flash
    reads 0xFF: such a tail is told, the file left as it is, and DFReader's messages all counted."""
    folder = LogFolder(str(tmp_path / "logs"))
    data = open(folder.path(write_flight_log(folder, 20_000)), "rb").read()      # it ends with a whole BAT (24 B)
    whole = check_dataflash(folder.path(1))
    assert whole.ending == "" and whole.tail == 0
    msg = data[data.rindex(b"\xa3\x95\x42"):][:37]                             # a MSG record's first 37 of 75 bytes
    cases = {"power-loss.BIN": (data[:-7], whole.messages - 1, 17, "an unfinished BAT record"),
             "msg.BIN": (data + msg, whole.messages, 37, "an unfinished MSG record"),
             "head.BIN": (data + b"\xa3", whole.messages, 1, "an unfinished record"),
             "page.BIN": (data + bytes(249), whole.messages, 249, "padding (0x00)"),
             "erased.BIN": (data + b"\xff" * 2042, whole.messages, 2042, "padding (0xFF)")}
    for name, (raw, messages, tail, ending) in cases.items():
        path = tmp_path / name
        path.write_bytes(raw)
        checked = check_dataflash(str(path), announced=len(raw))
        assert (checked.messages, checked.tail, checked.ending) == (messages, tail, f"{tail} bytes of {ending}"), name
        assert path.read_bytes() == raw
    real = os.path.join(os.path.dirname(__file__), "data", "logs", "pymavlink-test.BIN")   # a real ArduCopter log
    assert check_dataflash(real).ending == "24 bytes of an unfinished AHR2 record"


def test_a_vehicle_log_ending_inside_a_record_downloads_as_it_is(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [30_000])
    with open(folder.path(1), "ab") as f:
        f.write(b"\xa3\x95\x42" + bytes(34))                 # a power loss 37 bytes into a MSG record (75)
    v = connect(vehicle_factory, sim)
    out = tmp_path / "cut.BIN"
    outcome = v.logs.download(1, str(out)).result(60)
    assert outcome.ok, outcome.reason
    assert outcome.ending == "37 bytes of an unfinished MSG record" and outcome.reason.endswith(
        "; it ends with 37 bytes of an unfinished MSG record")
    assert same_bytes(out, folder, 1)


def test_a_stream_ending_short_of_the_listed_size_is_no_log_and_resumes(sim_factory, vehicle_factory, tmp_path):
    """The vehicle's stream ends (a short LOG_DATA) on a record boundary before the size it listed, as ArduPilot's
    "report as EOF on error" does after a read error: DFReader would read that file to its end, the size check
    refuses it, and the next download goes on from the .part to the whole log."""
    sim, folder = logs_sim(sim_factory, tmp_path, [600_000], radio_baud=1_000_000)
    whole = open(folder.path(1), "rb").read()
    reader = DFReader_binary(folder.path(1))
    while reader.recv_msg() is not None and reader.offset < 300_000:
        pass
    cut = reader.offset                                 # a record boundary
    stamp = os.stat(folder.path(1))                     # LOG_ENTRY's time_utc is the file's mtime, as ArduPilot's
    v = connect(vehicle_factory, sim)
    out = str(tmp_path / "one.BIN")
    future = v.logs.download(1, out)
    assert eventually(lambda: v.logs.progress and 0 < v.logs.progress.held < cut - 100_000, 30)
    with open(folder.path(1), "r+b") as f:
        f.truncate(cut)                                 # what the vehicle can read of it now
    os.utime(folder.path(1), ns=(stamp.st_atime_ns, stamp.st_mtime_ns))
    outcome = future.result(60)
    assert not outcome.ok and outcome.reason.endswith(
        f"{cut} bytes, shorter than the {len(whole)} bytes the vehicle announced (truncated)"), outcome.reason
    assert not os.path.exists(out) and os.path.getsize(out + ".part") == cut
    with open(folder.path(1), "r+b") as f:
        f.write(whole)                                  # readable again
    os.utime(folder.path(1), ns=(stamp.st_atime_ns, stamp.st_mtime_ns))
    outcome = v.logs.download(1, out).result(60)
    assert outcome.ok, outcome.reason
    assert outcome.resumed_from == cut - 90 and same_bytes(out, folder, 1)   # (its last 90 bytes: asked again, to
    #                                                                          check it is still the same log)


def tmpfs_available() -> bool:
    """A tmpfs in a mount namespace of our own (unprivileged user namespaces): a real small disk, without root."""
    import shutil
    import subprocess
    return shutil.which("unshare") is not None and subprocess.run(
        ["unshare", "-Urm", "mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", "/mnt"],
        capture_output=True).returncode == 0


@pytest.mark.parametrize("disk", ["tmpfs", "fsize"])
def test_a_full_disk_keeps_the_partial_file_and_resumes_once_there_is_room(sim_factory, tmp_path, disk):
    """The disk fills up for real mid-download: a 512 kB tmpfs with 128 kB free (ENOSPC), or RLIMIT_FSIZE at
    128 kB (EFBIG), in a process of its own (tests/logs_full_disk.py). The download ends with the reason, the
    bytes the map names are the vehicle's, the driver goes on answering, and with room again the download resumes
    from the .part to a byte-identical file."""
    import json
    import subprocess
    import sys
    if disk == "tmpfs" and not tmpfs_available():
        pytest.skip("no unprivileged mount namespace here for a small tmpfs")
    sim, folder = logs_sim(sim_factory, tmp_path, [400_000], radio_baud=250_000)
    # ~6 kB a .part flush (one each 0.25 real s, at 4x): the room fills over some twenty of them; at 1 Mbaud a
    # ticker starved for a third of a second wrote its first .part past the room, and nothing was kept
    mount = tmp_path / "disk"
    mount.mkdir()
    room = 128 * 1024
    helper = [sys.executable, os.path.join(os.path.dirname(__file__), "logs_full_disk.py"), disk,
              str(sim.tcp_port), "1", str(mount), str(room), str(tmp_path / "got.BIN")]
    if disk == "tmpfs":
        helper = ["unshare", "-Urm", "sh", "-c", 'mount -t tmpfs -o size=512k tmpfs "$0" && exec "$@"',
                  str(mount)] + helper
    done = subprocess.run(helper, capture_output=True, text=True, timeout=110)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    first, second = report["first"], report["second"]
    out = f"{mount}/one.BIN"
    kept = sum(b - a for a, b in report["kept"])
    words = "no space left on the disk" if disk == "tmpfs" else "no room for a larger file"
    assert not first["ok"] and first["reason"].startswith(f"{words}: {out}.part") \
        and first["reason"].endswith(f"kept {kept} bytes in {out}.part, resumable"), first["reason"]
    assert 0 < kept <= room
    vehicle_bytes = open(folder.path(1), "rb").read()
    part = open(tmp_path / "got.BIN.part", "rb").read()
    assert all(part[a:b] == vehicle_bytes[a:b] for a, b in report["kept"])
    assert report["listed"], "the driver stopped answering after the full disk"
    assert second["ok"], second["reason"]
    assert second["resumed_from"] == kept - 90 and second["size"] == len(vehicle_bytes)   # (the last 90: re-read)
    assert open(tmp_path / "got.BIN", "rb").read() == vehicle_bytes
    assert report["left"] == ["one.BIN"]


def test_the_solo_downloads_by_log_data(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [30_000], profile="solo")
    v = connect(vehicle_factory, sim)
    out = str(tmp_path / "solo.BIN")
    outcome = v.logs.download(1, out).result(60)
    assert outcome.ok, outcome.reason and same_bytes(out, folder, 1)
    kinds = {kind for _, kind, _ in sim.received_messages}
    assert "LOG_REQUEST_DATA" in kinds and "FILE_TRANSFER_PROTOCOL" not in kinds
    assert v.wait_for(lambda s: s.firmware, 10)         # AUTOPILOT_VERSION: no FTP capability
    refused = v.logs.download(1, out, via="ftp").result(10)
    assert not refused.ok and "offers no MAVLink FTP" in refused.reason


def test_console_log_list_and_download_latest(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [4_000, 9_000])
    v = connect(vehicle_factory, sim)
    out = io.StringIO()
    console = Console(v, stdout=out)
    console.onecmd("log list")
    text = wait_text(out, "2 logs")
    assert "Log 1 " in text and "Log 2 " in text and f"{os.path.getsize(folder.path(2))} bytes" in text
    target = tmp_path / "latest.bin"
    console.onecmd(f"log download latest {target}")
    wait_text(out, f"Finished downloading {target}")
    assert same_bytes(target, folder, 2)
    console.onecmd("log erase")
    wait_text(out, "type 'log erase yes'")
    assert folder.numbers() == [1, 2]
    console.onecmd("log erase yes")
    wait_text(out, "0 logs")
    assert folder.numbers() == []


def test_cmd_log_download_latest_runs_unattended(sim_factory, tmp_path):
    """``python -m driver --cmd "log download latest FILE" --daemon``: no list asked first, nobody at the console."""
    import subprocess
    import sys
    from ice_fixtures import free_port
    sim, folder = logs_sim(sim_factory, tmp_path, [4_000, 9_000])
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    proc = subprocess.Popen([sys.executable, "-m", "driver", "--master", f"tcp:127.0.0.1:{sim.tcp_port}", "--no-log",
                             "--one-port", str(free_port()), "--cmd", "log download latest got.bin", "--daemon"],
                            cwd=tmp_path, env={**os.environ, "PYTHONPATH": root}, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    import threading
    threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True).start()
    try:
        assert eventually(lambda: any(f"Finished downloading {tmp_path / 'got.bin'}" in x for x in lines), 30), \
            "".join(lines)
    finally:
        proc.terminate()
        proc.wait(timeout=15)
    assert same_bytes(tmp_path / "got.bin", folder, 2)


def test_an_erase_the_vehicle_never_got_is_not_told_done(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [5_000, 6_000])
    v = connect(vehicle_factory, sim)                   # nothing listed yet this session
    sim.autopilot._on_log_erase = lambda msg: None      # every LOG_ERASE lost on the way
    outcome = v.logs.erase().result(60)
    assert not outcome.ok and "still there" in outcome.reason
    assert folder.numbers() == [1, 2]
    del sim.autopilot._on_log_erase
    outcome = v.logs.erase().result(60)
    assert outcome.ok, outcome.reason
    assert folder.numbers() == [] and outcome.entries == ()


def test_the_part_is_on_disk_before_the_map_that_names_it(tmp_path, monkeypatch):
    path = str(tmp_path / "one.BIN")
    with open(path + ".part", "wb") as f:
        f.write(b"x" * 900)
    done = []
    real_fsync, real_replace = os.fsync, os.replace
    monkeypatch.setattr(ranges.os, "fsync", lambda fd: (done.append(os.readlink(f"/proc/self/fd/{fd}")),
                                                        real_fsync(fd))[1])
    monkeypatch.setattr(ranges.os, "replace", lambda a, b: (done.append(f"replace {a}"), real_replace(a, b))[1])
    ranges.save_part_map(path, ranges.PartMap(1, 0, ranges.Ranges([(0, 900)]), None))
    assert done == [path + ".part", path + ".part.json.tmp", f"replace {path}.part.json.tmp"]


def test_a_map_that_claims_more_than_the_part_holds_is_clipped(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [200_000])
    out = str(tmp_path / "one.BIN")
    entry = folder.entries()[0]
    with open(folder.path(1), "rb") as f, open(out + ".part", "wb") as part:
        part.write(f.read(50_000))                      # a power loss kept only half of what the map names
    ranges.save_part_map(out, ranges.PartMap(1, entry[2], ranges.Ranges([(0, 100_000)]), None))
    v = connect(vehicle_factory, sim)
    outcome = v.logs.download(1, out).result(120)
    assert outcome.ok, outcome.reason
    assert outcome.resumed_from == 50_000 - 90 and same_bytes(out, folder, 1)   # (its last 90 bytes: asked again)


@pytest.mark.parametrize("via", ["log_data", "ftp"])
def test_another_log_with_the_same_number_and_date_is_not_spliced_into_the_part(sim_factory, vehicle_factory,
                                                                               tmp_path, via):
    sim, folder = logs_sim(sim_factory, tmp_path, [300_000], radio_baud=1_000_000)
    stamp = int(os.path.getmtime(folder.path(1)))      # the date the vehicle lists: the file's (closed) mtime
    first = connect(vehicle_factory, sim)
    out = str(tmp_path / "one.BIN")
    future = first.logs.download(1, out)
    assert eventually(lambda: first.logs.progress and first.logs.progress.held > 50_000, 30)
    first.logs.cancel()
    assert not future.result(10).ok
    assert first.logs.erase().result(60).ok            # erased: the next log is number 1 again
    first.close()
    with open(out + ".part", "rb") as f:
        old_part = f.read()
    write_flight_log(folder, 400_000, seed=7)
    os.utime(folder.path(1), (stamp, stamp))            # a board without a clock: every log has the same date
    second = connect(vehicle_factory, sim)
    outcome = second.logs.download(1, out, via=via).result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1) and outcome.resumed_from == 0
    with open(out + ".part.old", "rb") as f:
        assert f.read() == old_part                     # kept aside, not mixed in


@pytest.mark.parametrize("via", ["log_data", "ftp"])
def test_a_part_resumes_though_the_logs_time_changed_and_the_stream_end_is_stale(sim_factory, vehicle_factory,
                                                                                 tmp_path, via):
    sim, folder = logs_sim(sim_factory, tmp_path, [300_000], radio_baud=1_000_000)
    first = connect(vehicle_factory, sim)
    out = str(tmp_path / "one.BIN")
    future = first.logs.download(1, out)
    assert eventually(lambda: first.logs.progress and first.logs.progress.held > 50_000, 30)
    first.close()
    assert not future.result(10).ok
    part = ranges.load_part_map(out)
    held = part.ranges.total()
    part.time_utc += 60                                 # listed while open: the vehicle's clock then, not the file's
    part.size = 100_000                                 # the end its stream told then: the log has grown since
    ranges.save_part_map(out, part)
    second = connect(vehicle_factory, sim)
    outcome = second.logs.download(1, out, via=via).result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1) and outcome.resumed_from >= held - 90


@pytest.mark.parametrize("via", ["ftp", "log_data"])
def test_a_log_id_is_a_place_in_the_list_not_the_files_number(sim_factory, vehicle_factory, tmp_path, via):
    sim, folder = logs_sim(sim_factory, tmp_path, [20_000, 30_000, 40_000])
    os.remove(folder.path(1))                           # deleted for space (AP_Logger_File::Prep_MinSpace)
    v = connect(vehicle_factory, sim)
    listed = v.logs.list().result(30)
    sizes = [os.path.getsize(folder.path(2)), os.path.getsize(folder.path(3))]
    assert [(e.id, e.size) for e in listed.entries] == [(1, sizes[0]), (2, sizes[1]), (3, 0)]
    out = str(tmp_path / "first.BIN")
    outcome = v.logs.download(1, out, via=via).result(60)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 2)                   # the oldest log there: file 2


def test_a_parameter_refresh_during_a_log_read_by_ftp_leaves_both_whole(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [400_000], radio_baud=1_000_000)
    v = connect(vehicle_factory, sim)
    assert v.wait_for(lambda s: s.firmware, 10)         # AUTOPILOT_VERSION offers FTP
    out = str(tmp_path / "one.BIN")
    future = v.logs.download(1, out, via="ftp")
    assert eventually(lambda: v.logs.progress and v.logs.progress.held > 50_000, 30)
    params = v.fetch_parameters(refresh=True).result(60)
    outcome = future.result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1)
    assert params.ok, params
    # the log's session holds the vehicle's one open file: param.pck is refused (InvalidSession) and the list read;
    # it never takes the log's replies for its own (the base commit: "MAVLink FTP stalled at byte 358,500")
    assert "invalid session" in params.reason and "stalled" not in params.reason, params.reason
    table = v.state().parameters
    assert table.complete and table.get("SYSID_THISMAV").value == sim.autopilot.params["SYSID_THISMAV"]


def test_a_log_read_by_ftp_goes_to_the_part_not_to_memory(sim_factory, vehicle_factory, tmp_path):
    import tracemalloc
    size = 700_000                                      # twice the bound below: all of it held would fail
    sim, folder = logs_sim(sim_factory, tmp_path, [size], speedup=8.0)
    v = connect(vehicle_factory, sim)
    out = str(tmp_path / "one.BIN")
    tracemalloc.start()
    try:
        future = v.logs.download(1, out, via="ftp")
        assert eventually(lambda: v.logs.progress and v.logs.progress.held > 450_000, 60)
        engine = [tracemalloc.Filter(True, "*driver/ftp/*"), tracemalloc.Filter(True, "*driver/logs/*")]
        held = sum(s.size for s in tracemalloc.take_snapshot().filter_traces(engine).statistics("filename"))
    finally:
        tracemalloc.stop()
    outcome = future.result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1)
    assert held < 300_000, held                         # the log's bytes are written as they come, never all held


def test_gaps_are_filled_packet_by_packet_without_asking_held_bytes_again(sim_factory, vehicle_factory, tmp_path):
    """Through 30 % loss each way, after the first pass the missing packets are asked one request each, many in
    flight (each within what the vehicle sends in one call, so none is dropped for a transfer still running), and
    no byte already held is asked again: merged windows re-sent the held bytes between scattered gaps, over and
    over (several times the log)."""
    sim, folder = logs_sim(sim_factory, tmp_path, [400_000], speedup=4.0)
    v = connect(vehicle_factory, sim)
    lossy(sim, 0.3)
    out = tmp_path / "lossy.BIN"
    outcome = v.logs.download(1, str(out), via="log_data").result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1)
    assert outcome.bytes_rerequested <= 0.01 * outcome.size, outcome
    assert outcome.bytes_received < 1.2 * outcome.size, outcome       # hardly a packet twice


@pytest.mark.parametrize("link", [dict(radio_baud=400_000, speedup=4.0), dict(profile="solo", speedup=4.0)])
def test_through_loss_on_a_radio_and_on_the_solo(sim_factory, vehicle_factory, tmp_path, link):
    """A radio without flow control sends one LOG_DATA a call; the Solo ten, and its 3.3 moves a running transfer
    to a new request: at 30 % loss each way both end byte-identical without asking a held byte again."""
    sim, folder = logs_sim(sim_factory, tmp_path, [60_000], **link)
    v = connect(vehicle_factory, sim)
    lossy(sim, 0.3)
    out = tmp_path / "lossy.BIN"
    outcome = v.logs.download(1, str(out)).result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1)
    assert outcome.bytes_rerequested <= 0.01 * outcome.size, outcome


def test_a_burst_whose_end_is_lost_is_followed_by_the_next_burst_not_by_reads(sim_factory, vehicle_factory,
                                                                             tmp_path, monkeypatch):
    """Every burst's last packet (the one flagged burst_complete) is lost on the way, and 10 % of the others: the
    read bursts on from past the last packet heard, and the gaps are read one by one only once the bursts have
    reached the file's end (reading each burst's gaps before the next burst, a few in flight, took ten times the
    bursts at 30 % loss)."""
    from driver.ftp import reader
    sim, folder = logs_sim(sim_factory, tmp_path, [500_000], speedup=8.0)
    ap = sim.autopilot
    send = ap.emit_to

    def drop_burst_ends(msg, peer):
        if msg.get_type() == "FILE_TRANSFER_PROTOCOL":
            header = bytes(msg.payload)[:12]
            if header[5] == reader.OP_BURST and header[6]:           # req_opcode, burst_complete
                return
        send(msg, peer)
    monkeypatch.setattr(ap, "emit_to", drop_burst_ends)
    sim.faults.downlink = LinkFaults(loss=0.1)
    asked: list[int] = []
    service = reader.FtpRead.service

    def spy(self, now, target):
        out, why = service(self, now, target)
        asked.extend(bytes(m.payload)[3] for m in out)
        return out, why
    monkeypatch.setattr(reader.FtpRead, "service", spy)
    v = connect(vehicle_factory, sim)
    assert v.wait_for(lambda s: s.firmware, 10)
    out = str(tmp_path / "one.BIN")
    outcome = v.logs.download(1, out, via="ftp").result(120)
    assert outcome.ok, outcome.reason
    assert same_bytes(out, folder, 1)
    bursts = [i for i, op in enumerate(asked) if op == reader.OP_BURST]
    reads = [i for i, op in enumerate(asked) if op == reader.OP_READ]
    assert len(bursts) >= 5 and reads, asked
    assert not [i for i in reads if i < max(bursts)], "a burst's gaps were read before the next burst"


def test_heartbeats_lost_while_the_log_flows_do_not_pause_the_download(sim_factory, vehicle_factory, tmp_path):
    """At 30 % loss each way three heartbeats in a row go missing every half minute or so, and the link is told
    lost; while LOG_DATA still comes the vehicle is plainly there, so the gaps are asked for all the same instead
    of waiting for the next heartbeat (the download stalled until one came)."""
    sim, folder = logs_sim(sim_factory, tmp_path, [200_000], radio_baud=200_000, speedup=4.0)
    v = connect(vehicle_factory, sim, loss_timeout=1.0)
    lossy(sim, 0.3)
    sim.faults.heartbeats = False               # the stream takes ~3 s: the link is told lost during it
    out = tmp_path / "heartless.BIN"
    future = v.logs.download(1, str(out), via="log_data")
    assert v.wait_for(lambda s: not s.connected, 10)
    outcome = future.result(30)
    assert outcome.ok, outcome.reason
    assert not v.state().connected              # done with no heartbeat heard since
    assert same_bytes(out, folder, 1)
    sim.faults.heartbeats = True
    assert v.wait_for(lambda s: s.connected, 10)


def test_gap_requests_sent_many_a_write_are_recorded_a_frame_each(sim_factory, vehicle_factory, tmp_path):
    """A tick's gap requests go to a TCP link in a few writes of many frames; the .tlog still holds one record
    (a time stamp and a frame) per frame, so it replays and reviews as before."""
    sim, folder = logs_sim(sim_factory, tmp_path, [200_000], speedup=4.0)
    tlog = tmp_path / "flight.tlog"
    v = connect(vehicle_factory, sim, tlog_path=str(tlog))
    lossy(sim, 0.3)
    outcome = v.logs.download(1, str(tmp_path / "got.BIN"), via="log_data").result(60)
    assert outcome.ok, outcome.reason
    v.close()
    from pymavlink import mavutil
    log = mavutil.mavlink_connection(str(tlog))
    requests = bad = 0
    while (m := log.recv_msg()) is not None:
        if m.get_type() == "BAD_DATA":
            bad += 1
        elif m.get_type() == "LOG_REQUEST_DATA":
            requests += 1
    assert bad == 0
    assert requests > 100                       # the gaps of 30 % loss, asked one packet each
