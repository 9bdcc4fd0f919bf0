"""Hostile inputs against a protected link: how many of each kind were tried, and whether any changed anything.

    .venv/bin/python bench/hostile.py [--tries 50] [--speedup 4] [--markdown] [--write-docs]

The simulated ArduCopter holds a signing key (ArduPilot's rules, driver/sim/signing.py) and pushes its
telemetry over UDP to the embedded driver, which listens with ``udpin`` pinned to it and signs with the key.
The vehicle takes off to 3 m in GUIDED; then, while it hovers, each kind of hostile input is thrown at it
``--tries`` times from real sockets on this machine:

* unsigned commands to the vehicle's telemetry port (land, motors off, arm, a 5 m/s velocity);
* the same commands signed with another key;
* our own signed frames, captured from the flight log and replayed;
* datagrams to the ground station's port from another address, claiming to be the vehicle (a LAND heartbeat,
  a COMMAND_ACK, a STATUSTEXT, a position 1 km away);
* frames claiming to be the vehicle that got past the pin (a spoofed source address), signed with another key.

A kind *changed something* if the vehicle's truth (armed, mode, position within 0.5 m, altitude within 0.5 m)
or what the driver shows the pilot (mode, armed, system, messages, position) differs afterwards. Each input is
accounted for by the part that dropped it (the vehicle's signing counters, the driver's foreign-packet and
bad-signature counts), so "dropped" is counted, not assumed. Target: every input dropped, nothing changed.
"""
from __future__ import annotations

import argparse
import hashlib
import logging
import os
import socket
import sys
import tempfile
import time
from dataclasses import dataclass

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.link.signing import SigningConfig, signing_time  # noqa: E402
from driver.sim import MODES, SimConfig, SimVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402

KEY = hashlib.sha256(b"the pilot's key").digest()
OTHER = hashlib.sha256(b"an intruder's key").digest()
TIMEOUT = 30.0


@dataclass
class Row:
    kind: str
    tried: int
    dropped: int
    where: str                 # who counted the drop
    changed: list[str]


def _wait(condition, timeout: float = TIMEOUT) -> bool:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.02)
    return True


def _encoder(system: int, component: int, key: bytes | None = None, link_id: int = 0):
    codec = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
    if key is not None:
        codec.signing.secret_key, codec.signing.sign_outgoing = key, True
        codec.signing.link_id, codec.signing.timestamp = link_id, signing_time()
    return codec


def _commands(target: int = 1) -> list:
    """What an intruder would send a hovering copter: land, motors off, arm, fly away."""
    return [
        mavlink.MAVLink_command_long_message(target, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, MODES["LAND"], 0, 0, 0, 0, 0),
        mavlink.MAVLink_command_long_message(target, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 0, 21196, 0, 0, 0, 0, 0),
        mavlink.MAVLink_command_long_message(target, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 21196, 0, 0, 0, 0, 0),
        mavlink.MAVLink_set_position_target_local_ned_message(0, target, 1, mavlink.MAV_FRAME_BODY_OFFSET_NED, 1479,
                                                              0, 0, 0, 5, 0, 0, 0, 0, 0, 0, 0),
    ]


def _vehicle_lies() -> list:
    """What a stranger claiming to be the vehicle would tell the pilot."""
    return [
        mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                          mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES["LAND"], 3, 3),
        mavlink.MAVLink_command_ack_message(mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_RESULT_ACCEPTED),
        mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_CRITICAL, b"hostile: land now"),
        mavlink.MAVLink_global_position_int_message(0, 0, 0, 0, 0, 0, 0, 0, 0),
    ]


def _pack(codec, msg) -> bytes:
    data = bytes(msg.pack(codec))
    codec.seq = (codec.seq + 1) % 256
    return data


class Scene:
    """The protected setup, flying: a signing vehicle pushing UDP to a pinned, signing driver."""

    def __init__(self, speedup: float, folder: str):
        probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        probe.bind(("127.0.0.1", 0))
        self.port = probe.getsockname()[1]
        probe.close()
        self.tlog = os.path.join(folder, "hostile.tlog")
        self.vehicle = Vehicle(VehicleConfig(
            connection=f"udpin:127.0.0.1:{self.port}", tlog_path=self.tlog,
            signing=SigningConfig(key=KEY, timestamp_path=os.path.join(folder, "stamp")))).start()
        self.sim = SimVehicle(SimConfig(tcp_port=0, udp_out=f"127.0.0.1:{self.port}", signing_key=KEY,
                                        speedup=speedup, ready_after=1.0, seed=3)).start()

    def fly(self) -> None:
        result = self.vehicle.takeoff(3.0).result(timeout=120)
        if not result.ok:
            raise RuntimeError(f"takeoff: {result}")

    def close(self) -> None:
        self.vehicle.close()
        self.sim.stop()

    # -- what must not change ------------------------------------------------------------------------
    def picture(self) -> dict:
        t, s = self.sim.truth(), self.vehicle.state()
        return dict(armed=t.armed, mode=t.mode, north=t.north, east=t.east, altitude=t.altitude,
                    shown=(s.mode, s.armed, s.system_id), texts=tuple(m.text for m in s.messages if m.source == "vehicle"),
                    position=None if s.position is None else (round(s.position.lat, 4), round(s.position.lon, 4)))

    @staticmethod
    def changes(before: dict, after: dict) -> list[str]:
        out = [k for k in ("armed", "mode", "shown", "position") if before[k] != after[k]]
        out += [k for k in ("north", "east", "altitude") if abs(before[k] - after[k]) > 0.5]
        if any("hostile" in text for text in after["texts"]):
            out.append("pilot's messages")
        return out

    # -- the kinds -------------------------------------------------------------------------------------
    def _to_vehicle(self, frames: list[bytes], counter: str) -> int:
        """Send raw frames on the vehicle's telemetry port (TCP); how many its signing dropped as ``counter``."""
        counters = self.sim.signing.counters
        before = getattr(counters, counter)
        with socket.create_connection(("127.0.0.1", self.sim.tcp_port)) as sock:
            for frame in frames:
                sock.sendall(frame)
            _wait(lambda: getattr(counters, counter) - before >= len(frames), 10)
        return getattr(counters, counter) - before

    def unsigned_commands(self, tries: int) -> Row:
        codec = _encoder(255, 191)
        frames = [_pack(codec, msg) for _ in range(tries) for msg in _commands()][:tries]
        return Row("unsigned commands to the vehicle", tries, self._to_vehicle(frames, "dropped_unsigned"),
                   "vehicle (signing)", [])

    def wrong_key_commands(self, tries: int) -> Row:
        codec = _encoder(255, 191, OTHER, link_id=7)
        frames = [_pack(codec, msg) for _ in range(tries) for msg in _commands()][:tries]
        return Row("commands signed with another key", tries,
                   self._to_vehicle(frames, "dropped_bad_signature"), "vehicle (signing)", [])

    def replayed_frames(self, tries: int) -> Row:
        ours = []
        with open(self.tlog, "rb") as f:
            data = f.read()
        from driver.link.tlog import _records
        for _, frame in _records(data):
            if frame[0] == 0xFD and frame[2] & 1 and frame[5] == 255:     # our own signed frames
                ours.append(frame)
        frames = (ours[-tries:] if len(ours) >= tries else ours * (tries // max(1, len(ours)) + 1))[:tries]
        return Row("our signed frames replayed", tries, self._to_vehicle(frames, "dropped_replay"),
                   "vehicle (signing)", [])

    def spoofed_datagrams(self, tries: int) -> Row:
        codec = _encoder(1, 1)
        link = self.vehicle.state().link
        before = link.foreign_packets
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            lies = _vehicle_lies()
            for i in range(tries):
                sock.sendto(_pack(codec, lies[i % len(lies)]), ("127.0.0.1", self.port))
            _wait(lambda: self.vehicle.state().link.foreign_packets - before >= tries, 10)
        return Row("datagrams claiming to be the vehicle", tries,
                   self.vehicle.state().link.foreign_packets - before, "driver (pinned link)", [])

    def forged_past_the_pin(self, tries: int) -> Row:
        """A stranger who spoofed the vehicle's address: its frames reach the parser, signed with another key."""
        codec = _encoder(1, 1, OTHER)
        codec.signing.timestamp = signing_time() + 10 ** 12            # and stamped far in the future
        before = self.vehicle.state().signing.bad_signature
        lies = _vehicle_lies()
        for i in range(tries):
            self.vehicle.ingest(_pack(codec, lies[i % len(lies)]))
        _wait(lambda: self.vehicle.state().signing.bad_signature - before >= tries, 10)
        return Row("forged vehicle frames past the pin", tries,
                   self.vehicle.state().signing.bad_signature - before, "driver (signing)", [])


KINDS = ("unsigned_commands", "wrong_key_commands", "replayed_frames", "spoofed_datagrams", "forged_past_the_pin")


def run(tries: int = 50, speedup: float = 4.0) -> list[Row]:
    with tempfile.TemporaryDirectory() as folder:
        scene = Scene(speedup, folder)
        try:
            scene.fly()
            rows = []
            for kind in KINDS:
                before = scene.picture()
                row = getattr(scene, kind)(tries)
                heard = scene.vehicle.state().signing.signed_accepted     # let the vehicle's answers come in
                _wait(lambda: scene.vehicle.state().signing.signed_accepted > heard + 20, 10)
                row.changed = scene.changes(before, scene.picture())
                rows.append(row)
            still = scene.vehicle.land().result(timeout=60)
            if not still.ok:
                rows.append(Row("the pilot's own Land afterwards", 1, 0, str(still), ["refused"]))
            return rows
        finally:
            scene.close()


def main(argv=None) -> int:
    import tables          # here, not at the top: the tests import this file as bench.hostile, bench/ not on the path
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--tries", type=int, default=50)
    p.add_argument("--speedup", type=float, default=4.0)
    p.add_argument("--markdown", action="store_true")
    tables.add_write_docs(p)
    opts = p.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    rows = run(opts.tries, opts.speedup)
    if tables.markdown(opts.markdown):
        print("| hostile input | tried | dropped | counted by | changed |\n|---|---|---|---|---|")
        for r in rows:
            print(f"| {r.kind} | {r.tried} | {r.dropped} | {r.where} | {', '.join(r.changed) or 'nothing'} |")
    else:
        for r in rows:
            print(f"{r.kind:42} tried {r.tried:4}  dropped {r.dropped:4} ({r.where:20})  changed: "
                  f"{', '.join(r.changed) or 'nothing'}")
    bad = [r for r in rows if r.changed or r.dropped < r.tried]
    print(f"{sum(r.tried for r in rows)} hostile inputs, {sum(r.dropped for r in rows)} dropped, "
          f"{len(bad)} kinds changed something or got through")
    return 1 if bad else 0


if __name__ == "__main__":
    import tables
    with tables.publishing("hostile"):
        sys.exit(main())
