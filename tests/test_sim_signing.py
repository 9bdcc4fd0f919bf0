"""MAVLink 2 signing on the simulated ArduCopter, spoken to over real sockets by plain pymavlink (mavutil and its
``setup_signing``, as MAVProxy does), replaying tests/data/recordings/arducopter-4.7-sitl-signing: SETUP_SIGNING on
the USB port (SERIAL0), then on the telemetry port unsigned commands ignored and signed ones obeyed.

An ignored command gets no answer at all, so its absence is proved by order, never by waiting: the vehicle
handles one link's frames in order, so when a later signed command's COMMAND_ACK is the only one heard, the
earlier command was dropped.
"""
from __future__ import annotations

import hashlib
import time

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import MODES, SimConfig, SimVehicle, passphrase_key
from driver.sim.__main__ import configure, main, parser
from driver.sim.signing import MAX_STREAMS, MINUTE, signing_timestamp
from test_sim import GroundStation, wait_until
from test_sim_recordings import read_tlog

from recordings import SIGNING

KEY = hashlib.sha256(b"uavviewer-test").digest()          # the recording's key
WRONG = hashlib.sha256(b"not-the-key").digest()
FAST = dict(tcp_port=0, usb_port=0, speedup=10.0, ready_after=0.5, seed=7)
SET_MODE = mavlink.MAV_CMD_DO_SET_MODE
HARMLESS = (mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)   # ACCEPTED at once on every profile
CAPABILITIES = (mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)      # ACCEPTED armed or not
ARM, FORCE = mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 21196
ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
REFUSED_ARMED = "ERROR: Won't setup signing when armed"


def now_stamp() -> int:
    """A signing timestamp for now, as pymavlink's setup_signing makes one (10 µs since 2015)."""
    return int((time.time() - 1420070400) * 100 * 1000)


def signature(msg) -> tuple[int, int] | None:
    """(link id, timestamp) of a signed frame, None for an unsigned one."""
    buf = msg.get_msgbuf()
    if buf[0] != mavlink.PROTOCOL_MARKER_V2 or not buf[2] & mavlink.MAVLINK_IFLAG_SIGNED:
        return None
    return buf[-13], int.from_bytes(buf[-12:-6], "little")


def signed_with(msg, key: bytes) -> bool:
    buf = bytes(msg.get_msgbuf())
    return signature(msg) is not None and hashlib.sha256(key + buf[:-6]).digest()[:6] == buf[-6:]


def ack_of(command: int):
    return lambda m: m.get_type() == "COMMAND_ACK" and m.command == command


class Station:
    """A plain pymavlink ground station (mavutil) on one of the sim's ports, read on the test's own thread.

    Once ``sign(key)`` is called it is strict like MAVProxy: an unsigned or badly signed frame from the vehicle
    is BAD_DATA to it, so every message it decodes passed pymavlink's own signature check.
    """

    def __init__(self, port: int) -> None:
        self.conn = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=255, source_component=190)
        self.heard: list = []
        assert self.until("HEARTBEAT") is not None, "no HEARTBEAT"
        assert self.conn.WIRE_PROTOCOL_VERSION == "2.0"      # mavutil switched on the vehicle's MAVLink 2

    def close(self) -> None:
        self.conn.close()

    def until(self, predicate, timeout: float = 5.0) -> list | None:
        """Read until a message satisfies ``predicate`` (a type name works): what was read, the match last;
        None if none came within ``timeout`` seconds."""
        if isinstance(predicate, str):
            kind = predicate
            predicate = lambda m: m.get_type() == kind  # noqa: E731
        read = []
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            msg = self.conn.recv_match(blocking=True, timeout=left)
            if msg is None:
                continue
            self.heard.append(msg)
            read.append(msg)
            if predicate(msg):
                return read
        return None

    def sign(self, key: bytes, timestamp: int | None = None, link_id: int = 0) -> None:
        self.conn.setup_signing(key, sign_outgoing=True, initial_timestamp=timestamp, link_id=link_id)

    def send(self, msg, signed: bool | None = None, mav1: bool = False) -> bytes:
        """Send ``msg`` (signed or not, else as the station signs now); the frame as it went out."""
        signing = self.conn.mav.signing
        before = signing.sign_outgoing
        if signed is not None:
            signing.sign_outgoing = signed
        try:
            self.conn.mav.send(msg, force_mavlink1=mav1)
        finally:
            signing.sign_outgoing = before
        return bytes(msg.get_msgbuf())

    def command(self, command: int, *params: float, signed: bool | None = None, mav1: bool = False) -> bytes:
        p = list(params) + [0.0] * (7 - len(params))
        return self.send(self.conn.mav.command_long_encode(1, 1, command, 0, *p), signed, mav1)

    def ask(self, command: int, *params: float, signed: bool | None = None, mav1: bool = False):
        """COMMAND_LONG, then its COMMAND_ACK (None if none came)."""
        self.command(command, *params, signed=signed, mav1=mav1)
        read = self.until(ack_of(command))
        return read[-1] if read else None

    def set_mode(self, name: str, signed: bool | None = None):
        return self.ask(SET_MODE, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES[name], signed=signed)

    def acks_until_sentinel(self, signed: bool | None = None) -> list[int]:
        """A harmless command, then the commands of every COMMAND_ACK heard up to its own: [HARMLESS] alone
        proves that what was sent before it got no answer."""
        self.command(*HARMLESS, signed=signed)
        read = self.until(ack_of(HARMLESS[0]))
        assert read is not None, "the sentinel command got no COMMAND_ACK"
        return [m.command for m in read if m.get_type() == "COMMAND_ACK"]


@pytest.fixture
def make_sim(sim_factory):
    return lambda **overrides: sim_factory(**dict(FAST, **overrides))


@pytest.fixture
def station():
    made = []

    def make(port: int) -> Station:
        made.append(Station(port))
        return made[-1]

    yield make
    for s in made:
        s.close()


def setup_signing(usb: Station, key: bytes, timestamp: int, target: int = 1) -> None:
    """SETUP_SIGNING as the recording sent it: unsigned, on the USB port; returns once the vehicle signs."""
    usb.send(usb.conn.mav.setup_signing_encode(target, 1, list(key), timestamp))
    if any(key) or timestamp:
        assert usb.until(lambda m: signature(m) is not None) is not None, "the vehicle never started signing"


# -- the recorded scenario -------------------------------------------------------------------------------
def test_unsigned_commands_are_ignored_on_the_telemetry_port_once_the_key_is_set(make_sim, station):
    sim = make_sim()
    usb = station(sim.usb_port)
    assert sim.signing.key is None
    initial = now_stamp()
    setup_signing(usb, KEY, initial)
    assert sim.signing.key == KEY and sim.signing.counters.setups == 1
    tel = station(sim.tcp_port)                             # SERIAL1, the telemetry radio's port
    tel.command(SET_MODE, 1, MODES["GUIDED"])               # unsigned: dropped, no ACK ...
    tel.sign(KEY, initial + 10_000)                         # ... then signed like the recording's station
    ack = tel.set_mode("GUIDED")
    assert ack.result == ACCEPTED and sim.truth().mode == "GUIDED"
    assert [m.command for m in tel.heard if m.get_type() == "COMMAND_ACK"] == [SET_MODE]   # one ACK: the signed
    assert tel.set_mode("LOITER").result == ACCEPTED and sim.truth().mode == "LOITER"
    tel.command(SET_MODE, 1, MODES["GUIDED"], signed=False)    # "stopped signing": ignored again
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.truth().mode == "LOITER"
    c = sim.signing.counters
    assert (c.dropped_unsigned, c.accepted_signed, c.dropped_bad_signature, c.dropped_replay) == (2, 3, 0, 0)
    # dropped frames never reached the autopilot; pymavlink verified every frame the station decoded
    assert sum(kind == "COMMAND_LONG" for _, kind, _ in sim.received_messages) == 3
    signed_part = tel.heard[next(i for i, m in enumerate(tel.heard) if m.get_type() == "COMMAND_ACK"):]
    assert signed_part and not any(m.get_type() == "BAD_DATA" for m in signed_part)


def test_the_usb_port_obeys_unsigned_and_every_link_signs_with_its_own_id(make_sim, station):
    sim = make_sim(gimbal=True)
    usb = station(sim.usb_port)
    initial = now_stamp()
    setup_signing(usb, KEY, initial)
    assert usb.set_mode("GUIDED", signed=False).result == ACCEPTED           # SERIAL0: unsigned always accepted
    assert usb.ask(*HARMLESS, signed=False).result == ACCEPTED
    assert usb.ask(*CAPABILITIES, mav1=True).result == ACCEPTED              # MAVLink 1 too, on USB
    assert sim.signing.counters.accepted_unsigned == 3 and sim.signing.counters.dropped_unsigned == 0
    one, two = station(sim.tcp_port), station(sim.tcp_port)                 # two telemetry links
    assert two.until(lambda m: m.get_srcComponent() == 154) is not None
    for st, link in ((usb, 0), (one, 1), (two, 2)):
        st.until("HEARTBEAT")
        first = next(i for i, m in enumerate(st.heard) if signature(m) is not None)
        assert first > 0 if st is usb else first == 0      # links opened after SETUP_SIGNING: signed from the start
        after = st.heard[first:]
        assert all(signed_with(m, KEY) and signature(m)[0] == link for m in after), link   # once signing, always
        stamps = [signature(m)[1] for m in after]
        assert stamps == sorted(set(stamps))                                # each link's own rising series
        if st is not usb:
            assert stamps[0] == initial + MINUTE                            # from a minute past the key's time
    assert {m.get_srcComponent() for m in two.heard} == {1, 154}            # the gimbal signs too


def test_a_replayed_frame_and_a_stale_new_stream_are_ignored(make_sim, station):
    sim = make_sim()
    usb = station(sim.usb_port)
    initial = now_stamp()
    setup_signing(usb, KEY, initial)
    tel = station(sim.tcp_port)
    tel.sign(KEY, initial - 1, link_id=3)       # a new stream over a minute behind the link's initial + 1 min
    tel.command(SET_MODE, 1, MODES["LOITER"])
    tel.sign(KEY, initial + 10_000, link_id=3)  # 59.9 s behind, as the recording's station was: accepted
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.signing.counters.dropped_replay == 1 and sim.truth().mode == "STABILIZE"
    loiter = tel.command(SET_MODE, 1, MODES["LOITER"])
    assert tel.until(ack_of(SET_MODE))[-1].result == ACCEPTED and sim.truth().mode == "LOITER"
    assert tel.set_mode("GUIDED").result == ACCEPTED
    tel.conn.write(loiter)                      # the same signed frame again: its timestamp is used up
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.truth().mode == "GUIDED" and sim.signing.counters.dropped_replay == 2


def test_a_wrong_key_and_a_forged_future_timestamp_are_ignored(make_sim, station):
    sim = make_sim(signing_key=KEY)             # a key kept in storage from before power-on
    assert sim.signing.key == KEY
    tel = station(sim.tcp_port)
    assert all(signed_with(m, KEY) for m in tel.heard)
    tel.sign(KEY)
    assert tel.set_mode("GUIDED").result == ACCEPTED
    state = tel.conn.mav.signing
    state.secret_key = WRONG
    tel.command(SET_MODE, 1, MODES["LOITER"])   # another key: dropped
    stamp = state.timestamp
    state.timestamp = stamp + 1000 * MINUTE     # a forgery from the station's own stream, far in the future
    tel.command(SET_MODE, 1, MODES["LOITER"])
    state.secret_key, state.timestamp = KEY, stamp
    # C checks the signature before it records a stream's timestamp: the real stream is not locked out
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.truth().mode == "GUIDED"
    assert tel.set_mode("LOITER").result == ACCEPTED and sim.truth().mode == "LOITER"
    c = sim.signing.counters
    assert (c.dropped_bad_signature, c.dropped_replay, c.accepted_signed) == (2, 0, 3)


def test_setup_signing_is_refused_while_armed_on_the_asking_link_only(make_sim, station):
    sim = make_sim(auto_disarm_after=0)
    usb, tel = station(sim.usb_port), station(sim.tcp_port)
    assert usb.ask(ARM, 1, FORCE).result == ACCEPTED and sim.truth().armed
    usb.send(usb.conn.mav.setup_signing_encode(1, 1, list(KEY), now_stamp()))
    text = usb.until(lambda m: m.get_type() == "STATUSTEXT" and m.text == REFUSED_ARMED)
    assert text is not None and text[-1].severity == mavlink.MAV_SEVERITY_WARNING    # GCS_Signing.cpp
    assert sim.signing.key is None and sim.signing.counters.refused_armed == 1
    assert signature(text[-1]) is None
    tel.acks_until_sentinel()       # everything said to the other link up to an answer to its own command ...
    assert not any(m.get_type() == "STATUSTEXT" and m.text == REFUSED_ARMED for m in tel.heard)   # ... but that
    assert usb.ask(ARM, 0, FORCE).result == ACCEPTED and not sim.truth().armed
    setup_signing(usb, KEY, now_stamp())
    assert sim.signing.key == KEY and sim.signing.counters.setups == 1


def test_a_zero_key_turns_signing_off_and_an_unsigned_key_cannot_take_over(make_sim, station):
    sim = make_sim(signing_key=KEY)
    tel = station(sim.tcp_port)
    tel.sign(KEY)
    # a key injected without the key, from the telemetry link: dropped like any unsigned frame
    tel.send(tel.conn.mav.setup_signing_encode(1, 1, list(WRONG), now_stamp()), signed=False)
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.signing.key == KEY and sim.signing.counters.setups == 0
    tel.send(tel.conn.mav.setup_signing_encode(1, 1, [0] * 32, 0))          # signed with the key: obeyed
    tel.conn.disable_signing()
    ack = tel.set_mode("GUIDED", signed=False)
    assert ack.result == ACCEPTED and signature(ack) is None                # unsigned both ways again
    assert sim.signing.key is None and sim.signing.counters.setups == 1


def test_radio_status_and_radio_pass_unsigned(make_sim, station):
    sim = make_sim(signing_key=KEY)
    tel = station(sim.tcp_port)
    tel.sign(KEY)
    mav = tel.conn.mav
    tel.send(mav.radio_status_encode(200, 180, 90, 40, 35, 0, 0), signed=False)
    tel.send(mav.radio_encode(200, 180, 90, 40, 35, 0, 0), signed=False)
    tel.send(mav.heartbeat_encode(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0), signed=False)
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    kinds = [kind for _, kind, _ in sim.received_messages]
    assert "RADIO_STATUS" in kinds and "RADIO" in kinds and "HEARTBEAT" not in kinds
    c = sim.signing.counters
    assert (c.accepted_unsigned, c.dropped_unsigned, c.accepted_signed) == (2, 1, 1)


def test_no_more_than_sixteen_streams(make_sim, station):
    sim = make_sim(signing_key=KEY)
    tel = station(sim.tcp_port)
    stamp = now_stamp()
    for link in range(100, 100 + MAX_STREAMS):
        tel.sign(KEY, stamp, link_id=link)
        tel.send(tel.conn.mav.heartbeat_encode(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0))
    tel.sign(KEY, stamp, link_id=200)           # the 17th stream: MAVLINK_MAX_SIGNING_STREAMS reached
    tel.command(SET_MODE, 1, MODES["LOITER"])
    tel.sign(KEY, stamp + 10, link_id=100)      # a known stream still works
    assert tel.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.signing.counters.dropped_streams == 1 and sim.truth().mode == "STABILIZE"


def test_gps_time_raises_the_signing_timestamp(make_sim, station):
    """update_signing_timestamp(): before a GPS fix a link signs from the key's time + 1 min; with one, from GPS
    time, so a station still at the key's old time is a stream over a minute behind."""
    for ready_after, gps in ((600.0, False), (0.5, True)):
        sim = make_sim(ready_after=ready_after)
        usb = station(sim.usb_port)
        if gps:
            assert wait_until(lambda: sim.truth().ready, 10)           # ready: GPS 3D fix and more
        before = signing_timestamp(time.time())
        setup_signing(usb, KEY, 1000)           # a key dated 2015
        tel = station(sim.tcp_port)
        first = signature(next(m for m in tel.heard if m.get_srcComponent() == 1))[1]
        if gps:
            assert first >= before
        else:
            assert first == 1000 + MINUTE
        tel.sign(KEY, 2000, link_id=1)
        tel.command(SET_MODE, 1, MODES["LOITER"])
        tel.sign(KEY, now_stamp(), link_id=2)
        assert tel.acks_until_sentinel() == ([HARMLESS[0]] if gps else [SET_MODE, HARMLESS[0]])
        assert sim.signing.counters.dropped_replay == (1 if gps else 0)


def test_setup_signing_targets_this_vehicle_only(make_sim, station):
    sim = make_sim()
    usb = station(sim.usb_port)
    usb.send(usb.conn.mav.setup_signing_encode(2, 1, list(KEY), now_stamp()))    # another system's key
    assert usb.acks_until_sentinel() == [HARMLESS[0]]
    assert sim.signing.key is None
    setup_signing(usb, KEY, now_stamp(), target=0)                              # broadcast: taken
    assert sim.signing.key == KEY


def test_a_mavlink1_vehicle_cannot_sign(make_sim):
    """A stock Solo (ArduCopter 3.3, MAVLink 1 headers only) has no GCS_Signing: SETUP_SIGNING is message 256,
    which no MAVLink 1 frame can carry, and its MAVLink 2 frame is not even parsed."""
    with pytest.raises(ValueError, match="MAVLink 2"):
        SimVehicle(SimConfig(profile="solo", signing_key=KEY))
    with pytest.raises(ValueError, match="32 bytes"):
        SimVehicle(SimConfig(signing_key=KEY[:16]))
    sim = make_sim(profile="solo")
    gs = GroundStation(sim.usb_port, mav1=True)
    try:
        gs.send(gs.encoder.setup_signing_encode(1, 1, list(KEY), now_stamp()), mav1=False)
        assert gs.command(*HARMLESS).result == ACCEPTED
        assert sim.server.ignored_v2 == 1 and sim.signing.key is None
        assert {version for _, version in gs.frames} == {1}
    finally:
        gs.close()


def test_the_command_line_sets_the_key_and_the_usb_port(capsys):
    sim = configure(parser().parse_args(["--tcp", "127.0.0.1:0", "--usb-port", "0",
                                         "--signing-passphrase", "uavviewer-test"]))
    assert sim.signing.key == KEY == passphrase_key("uavviewer-test")     # as MAVProxy derives it
    assert sim.config.usb_port == 0 and sim.usb_port is None              # bound once started
    sim.start()
    try:
        assert sim.usb_port and sim.usb_port != sim.tcp_port
    finally:
        sim.stop()
    assert configure(parser().parse_args([])).signing.key is None
    with pytest.raises(SystemExit):
        main(["--profile", "solo", "--signing-passphrase", "x"])
    assert capsys.readouterr().err.splitlines()[-1] == \
        "python -m driver.sim: error: --signing-passphrase needs MAVLink 2: not with --profile solo or --mav1"
    with pytest.raises(SystemExit):
        parser().parse_args(["--usb-port", "70000"])
    assert "--usb-port: '70000'" in capsys.readouterr().err


# -- against the recording -------------------------------------------------------------------------------
def test_signing_as_recorded(make_sim, station):
    """The real 4.7's signing, read from the tlog, and the sim's in the same scenario: not one unsigned vehicle
    frame once the first signed one came; link id 0 on SERIAL0, 1 on SERIAL1; a link opened after SETUP_SIGNING
    starts a minute past the key's timestamp; the station's stream 59.9 s behind that is accepted."""
    frames = [msg for _, msg in read_tlog(SIGNING + ".tlog")]
    setup = next(m for m in frames if m.get_type() == "SETUP_SIGNING")
    initial, key = setup.initial_timestamp, bytes(setup.secret_key)
    assert key == KEY
    vehicle = [m for m in frames if m.get_srcSystem() == 1]
    flags = [signature(m) is not None for m in vehicle]
    assert flags == sorted(flags) and 0 < flags.count(False) and flags.index(True) > 0    # unsigned, then signed
    assert frames.index(vehicle[flags.index(True)]) > frames.index(setup)
    assert all(signed_with(m, KEY) for m in vehicle if signature(m))
    links = [signature(m)[0] for m in vehicle if signature(m)]
    assert links == sorted(links) and set(links) == {0, 1}                # SERIAL0, then SERIAL1
    recorded_first = next(signature(m)[1] for m in vehicle if signature(m) and signature(m)[0] == 1)
    assert 0 <= recorded_first - (initial + MINUTE) < 10                   # one frame lost before it, at most a few
    station_stream = next(signature(m)[1] for m in frames if m.get_srcSystem() == 255 and signature(m))
    behind = initial + MINUTE - station_stream                             # 59.9 s: a new stream not over 1 min
    assert 0 < behind < MINUTE
    recorded_acks = [m.result for m in frames if m.get_type() == "COMMAND_ACK"]

    sim = make_sim(ready_after=600.0)          # no GPS fix: its time would raise the links' timestamps
    usb = station(sim.usb_port)
    setup_signing(usb, key, initial)
    tel = station(sim.tcp_port)
    tel.command(SET_MODE, 1, MODES["GUIDED"])
    tel.sign(key, initial + MINUTE - behind)
    sim_acks = [tel.set_mode("GUIDED").result, tel.set_mode("LOITER").result]
    tel.command(SET_MODE, 1, MODES["GUIDED"], signed=False)
    tel.acks_until_sentinel()
    assert sim_acks == recorded_acks == [ACCEPTED, ACCEPTED]             # the unsigned ones: no ACK in either
    assert [m.command for m in tel.heard if m.get_type() == "COMMAND_ACK"] == [SET_MODE, SET_MODE, HARMLESS[0]]
    assert sim.truth().mode == "LOITER"
    flags = [signature(m) is not None for m in usb.heard]
    assert flags == sorted(flags) and flags.count(False) > 0
    assert {signature(m)[0] for m in usb.heard if signature(m)} == {0}
    assert all(signature(m) and signature(m)[0] == 1 and signed_with(m, key) for m in tel.heard)
    assert signature(tel.heard[0])[1] == initial + MINUTE
