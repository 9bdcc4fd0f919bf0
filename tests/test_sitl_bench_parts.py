"""The parts of bench/real_sitl.py that need no SITL binary: the lossy frame relay (bench/lossy_relay.py) and the
SERIAL1 judge (bench/sitl_judge.py), each against the simulated vehicle on real sockets. The bench itself needs
ArduPilot's SITL, which CI cannot build."""
from __future__ import annotations

import os
import sys

from pymavlink.dialects.v10 import ardupilotmega as mavlink1
from pymavlink.dialects.v20 import ardupilotmega as mavlink

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.lossy_relay import Framer, LossyRelay, Way, free_udp_port  # noqa: E402
from bench.sitl_judge import Judge  # noqa: E402
from driver.mission.plan import MissionItem, Plan, PlanKind  # noqa: E402


def _frames() -> list[bytes]:
    v1 = mavlink1.MAVLink(None, srcSystem=1, srcComponent=1)
    v2 = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    signed = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    signed.signing.secret_key = bytes(range(32))
    signed.signing.sign_outgoing = True
    heartbeat = mavlink.MAVLink_heartbeat_message(2, 3, 81, 4, 3, 3)
    text = mavlink.MAVLink_statustext_message(6, b"ArduPilot Ready")
    old = mavlink1.MAVLink_statustext_message(6, b"ArduPilot Ready")
    return [mavlink1.MAVLink_heartbeat_message(2, 3, 81, 4, 3, 3).pack(v1), text.pack(v2), heartbeat.pack(signed),
            old.pack(v1), text.pack(signed)]


def test_framer_cuts_v1_v2_and_signed_frames_however_the_bytes_arrive():
    frames = _frames()
    assert frames[0][0] == 0xFE and frames[1][0] == 0xFD and frames[2][2] & 1     # v1, v2, signed v2
    stream = b"\x00\x11garbage" + b"".join(frames)
    whole = Framer()
    assert whole.feed(stream) == frames
    assert whole.skipped == 9
    trickle = Framer()
    got = [f for i in range(len(stream)) for f in trickle.feed(stream[i:i + 1])]
    assert got == frames


def test_a_way_drops_its_share_the_same_frames_for_the_same_seed_and_everything_in_a_blackout():
    a, b = Way(0.3, 7), Way(0.3, 7)
    kept = [a.keep(False) for _ in range(10000)]
    assert kept == [b.keep(False) for _ in range(10000)]
    assert 2700 < a.dropped < 3300 and a.passed + a.dropped == 10000
    assert not any(Way(0.0, 1).keep(True) for _ in range(100))
    assert all(Way(0.0, 1).keep(False) for _ in range(100))


def test_the_driver_reaches_the_vehicle_through_the_relay(sim, vehicle_factory):
    port = free_udp_port()
    relay = LossyRelay(sim.tcp_port, port, loss=0.0, seed=1)
    try:
        vehicle = vehicle_factory(f"udpin:127.0.0.1:{port}")
        assert vehicle.wait_for(lambda s: s.connected and s.mode, 10), vehicle.state().link
        assert vehicle.set_mode("LOITER").result(timeout=10).ok
        assert sim.truth().mode == "LOITER"
        assert relay.down.passed > 0 and relay.up.passed > 0
        assert relay.down.dropped == relay.up.dropped == 0
    finally:
        relay.close()


def test_the_judge_reads_what_the_vehicle_holds(sim_factory, vehicle_factory):
    sim = sim_factory(usb_port=0)                  # the driver on the USB-like port, the judge on the telemetry one
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.usb_port}")
    judge = Judge(sim.tcp_port)
    try:
        assert vehicle.wait_for(lambda s: s.connected and s.home is not None, 10)
        home = vehicle.state().home
        rally = Plan(PlanKind.RALLY, (MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, lat=home.lat + 1e-4,
                                                  lon=home.lon, alt=15),))
        assert vehicle.upload_plan(rally).result(timeout=20).result.ok
        held = judge.read_plan(mavlink.MAV_MISSION_TYPE_RALLY)
        assert [(i.command, i.x, i.z) for i in held] == [(mavlink.MAV_CMD_NAV_RALLY_POINT,
                                                          round((home.lat + 1e-4) * 1e7), 15)]
        assert judge.read_plan(mavlink.MAV_MISSION_TYPE_MISSION) == []
        assert judge.param("WPNAV_SPEED")[0] == sim.autopilot.params.get("WPNAV_SPEED")
        assert judge.param("NO_SUCH_PARAM") is None
        assert len(judge.all_params()) == len(sim.autopilot.params)
        assert judge.wait(lambda: judge.mode == sim.truth().mode and judge.armed is False, 10)
    finally:
        judge.close()


def test_the_bench_downloads_the_newest_log_and_compares_it_with_the_vehicles_file(sim_factory, tmp_path):
    """real_sitl.py's log row against the simulator in the SITL's place: its logs in the scratch folder's logs/,
    as the SITL keeps them; the newest downloaded through the relay and judged byte for byte."""
    import argparse
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "bench"))
    import real_sitl
    from driver.sim.dataflash import LogFolder, write_flight_log
    logs = LogFolder(str(tmp_path / "logs"))
    write_flight_log(logs, 40_000)
    newest = os.path.getsize(logs.path(write_flight_log(logs, 150_000, seed=1)))
    sim = sim_factory(usb_port=0, log_dir=logs.folder)
    relay = LossyRelay(sim.usb_port, free_udp_port(), loss=0.1, seed=1)
    judge = Judge(sim.tcp_port)
    bench = real_sitl.Bench(judge, relay, argparse.Namespace(keep=False), str(tmp_path))
    try:
        assert bench.vehicle.wait_for(lambda s: s.connected, 20)
        bench.op_log_download()
        row = bench.rows[-1]
        assert row.verdict == "right", row
        assert row.said.startswith(f"log 2: {newest:,} bytes in ")
        assert row.holds == f"logs/00000002.BIN: {newest:,} bytes now; its first {newest:,} are the download"
    finally:
        bench.vehicle.close()
        judge.close()
        relay.close()
