"""DataFlash logs over LOG_* (issue 31): the simulator writes and serves real .BIN logs as ArduCopter 4.6.3 does
(tests/data/recordings/arducopter-4.6-sitl-logs.*), and the driver lists and downloads them complete and
byte-identical through loss, resuming from its partial file after a dropped link or an app restart."""
from __future__ import annotations

import io
import os

import pytest
from pymavlink.DFReader import DFReader_binary

from driver.console.console import Console
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
    assert check_dataflash(folder.path(1)) > 100
    listed = v.logs.list().result(20)
    assert listed.ok and [(e.id, e.size) for e in listed.entries] == [(1, os.path.getsize(folder.path(1)))]


def test_the_list_is_complete_under_loss(sim_factory, vehicle_factory, tmp_path):
    sim, folder = logs_sim(sim_factory, tmp_path, [3000 + 500 * i for i in range(6)])
    v = connect(vehicle_factory, sim)
    lossy(sim, 0.3)
    listed = v.logs.list().result(60)
    assert listed.ok, listed.reason
    assert [(e.id, e.size) for e in listed.entries] == [(n, s) for n, s, _ in folder.entries()]


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


def test_a_corrupt_or_truncated_bin_is_told(tmp_path):
    folder = LogFolder(str(tmp_path / "logs"))
    data = open(folder.path(write_flight_log(folder, 20_000)), "rb").read()
    cases = {"cut.BIN": (data[:-7], "truncated"), "bad.BIN": (data[:9000] + b"x" * 40 + data[9040:], "corrupt"),
             "empty.BIN": (b"", "empty"), "text.BIN": (b"hello, not a log\n" * 10, "not a DataFlash log")}
    for name, (raw, word) in cases.items():
        (tmp_path / name).write_bytes(raw)
        with pytest.raises(LogFileError, match=word):
            check_dataflash(str(tmp_path / name))


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
