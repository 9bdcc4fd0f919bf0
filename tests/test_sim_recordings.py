"""The simulated ArduCopter against a real one: the 4.7 SITL flight recording, replayed command by command.

The recording (tests/data/recordings/arducopter-4.7-sitl-flight.tlog) is parsed here,
never transcribed: each COMMAND_LONG the ground station (system 255) sent, the vehicle's
COMMAND_ACK result, the STATUSTEXT lines that followed within 50 ms, and the vehicle's
state (its last HEARTBEAT) when the command went out. The same commands then go to the
simulator in the same order and the same situations: before ready at the recording's
times scaled to a short ``ready_after`` (the sim's start-up is the recording's, scaled),
after ready at the recording's own times. The sim runs on a hand-driven clock, so each
command is handled at a known sim time however busy the machine is.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import ManualClock, SimConfig, SimVehicle
from driver.sim.replay import read_tlog
from test_sim import GroundStation, wait_until

from recordings import FLIGHT, MISSION  # noqa: E402

RECORDING = FLIGHT + ".tlog"
WINDOW = 0.05            # s: the STATUSTEXT lines that follow an ACK this closely are its reasons
READY_AFTER = 8.0        # sim s: the recording's 40.6 s start-up, compressed
SPEEDUP = 10.0



def normal(text: str) -> str:
    """A text with its numbers blanked: "SIM Hit ground at 0.499819 m/s" and the sim's 0.500000 compare equal."""
    return re.sub(r"\d+(\.\d+)?", "#", text)


@dataclass
class Exchange:
    """One thing the ground station sent and what the vehicle made of it."""
    t: float                      # recording s
    msg: object                   # what was sent (COMMAND_LONG or SET_MODE)
    version: int                  # its MAVLink framing
    result: int | None            # COMMAND_ACK result, None: no ACK at all
    ack_version: int | None
    texts: tuple[str, ...]        # STATUSTEXT within WINDOW after the ACK
    situation: tuple | None       # (custom_mode, armed, airborne, ready) from the last HEARTBEAT before
    mode_after: int | None = None  # SET_MODE: the mode the next HEARTBEAT shows

    @property
    def name(self) -> str:
        if self.msg.get_type() == "SET_MODE":
            return f"SET_MODE {self.msg.custom_mode}"
        entry = mavlink.enums["MAV_CMD"].get(self.msg.command)
        m = self.msg
        return f"{entry.name if entry else m.command} {m.param1:g},{m.param2:g},{m.param7:g}"


def version_of(msg) -> int:
    return 2 if msg.get_msgbuf()[0] == mavlink.PROTOCOL_MARKER_V2 else 1


def situation(heartbeat, ready: bool) -> tuple | None:
    if heartbeat is None:
        return None
    armed = bool(heartbeat.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
    return heartbeat.custom_mode, armed, heartbeat.system_status == mavlink.MAV_STATE_ACTIVE, ready


def recorded_exchanges(frames) -> tuple[list[Exchange], float, list[str]]:
    """The exchanges, when the vehicle was ready ("... is using GPS"), and what it said after the last one."""
    ready_at = next(t for t, m in frames if m.get_type() == "STATUSTEXT" and "is using GPS" in m.text)
    out, heartbeat = [], None
    sent = [(i, t, m) for i, (t, m) in enumerate(frames)
            if m.get_srcSystem() == 255 and m.get_type() in ("COMMAND_LONG", "SET_MODE")]
    for n, (i, t, msg) in enumerate(sent):
        heartbeat = next((m for _, m in reversed(frames[:i]) if m.get_type() == "HEARTBEAT" and m.get_srcSystem() == 1),
                         None)
        end = sent[n + 1][0] if n + 1 < len(sent) else len(frames)
        ex = Exchange(t, msg, version_of(msg), None, None, (), situation(heartbeat, t >= ready_at))
        if msg.get_type() == "COMMAND_LONG":             # its ACK may come after the next command went out
            later = [(t2, m) for t2, m in frames[i + 1:] if m.get_srcSystem() == 1]
            k, ack = next((k, m) for k, (_, m) in enumerate(later)
                          if m.get_type() == "COMMAND_ACK" and m.command == msg.command)
            ack_t = later[k][0]
            ex.result, ex.ack_version = ack.result, version_of(ack)
            ex.texts = tuple(m.text for t2, m in later[k + 1:] if m.get_type() == "STATUSTEXT" and t2 - ack_t <= WINDOW)
        else:
            later = [(t2, m) for t2, m in frames[i + 1:end] if m.get_srcSystem() == 1]
            assert not any(m.get_type() == "COMMAND_ACK" for _, m in later)        # the recording's own claim
            ex.mode_after = next(m.custom_mode for _, m in later if m.get_type() == "HEARTBEAT")
        out.append(ex)
    last = sent[-1][0]
    epilogue = [m.text for _, m in frames[last:] if m.get_type() == "STATUSTEXT" and m.get_srcSystem() == 1]
    return out, ready_at, epilogue


class Replay:
    """Drives a sim on a ManualClock: to a sim time, one step at a time, one message at a time."""

    def __init__(self, sim: SimVehicle, clock: ManualClock, gs: GroundStation) -> None:
        self.sim, self.clock, self.gs = sim, clock, gs
        self.real_step = 1.0 / sim.config.rate_hz / sim.config.speedup
        self.marks = 0

    def advance_to(self, sim_time: float) -> None:
        while self.sim.truth().time < sim_time - 1e-9:
            need = (sim_time - self.sim.truth().time) / self.sim.config.speedup
            self.clock.advance(min(0.2, max(need, self.real_step)))
            assert self.clock.settle(), "the sim's clock thread stalled"

    def let_pass(self, real_seconds: float) -> None:
        """Real time passes, in slices the sim keeps up with (it drops a backlog over 0.25 s, as when busy)."""
        while real_seconds > 1e-12:
            part = min(0.2, real_seconds)
            self.clock.advance(part)
            assert self.clock.settle(), "the sim's clock thread stalled"
            real_seconds -= part

    def step(self) -> None:
        steps = self.sim.steps
        while self.sim.steps == steps:
            self.clock.advance(self.real_step)
            assert self.clock.settle(), "the sim's clock thread stalled"

    def deliver(self, msg, mav1: bool, flush: bool = True) -> int:
        """Send ``msg``, wait until it is in the vehicle's inbox, run one step: it is handled. Returns the mark
        from which the answer is on the ground station's list (what was said before has arrived first)."""
        if flush:
            self.marker()
        counters = self.sim.faults.counters.uplink
        before, mark = counters.delivered, self.gs.mark()
        self.gs.send(msg, mav1)
        assert wait_until(lambda: counters.delivered > before, 10), "the vehicle never got the frame"
        self.step()
        return mark

    def marker(self) -> int:
        """Everything the vehicle said so far has arrived once its answer to a TIMESYNC has (TCP keeps order)."""
        self.marks += 1
        token = 7_000_000 + self.marks
        mark = self.deliver(self.gs.encoder.timesync_encode(0, token), mav1=True, flush=False)
        reply = self.gs.wait(lambda m: m.get_type() == "TIMESYNC" and m.ts1 == token, 10, since=mark)
        assert reply is not None, "no TIMESYNC answer"
        return self.gs.mark()

    def last_heartbeat(self):
        beats = self.gs.messages("HEARTBEAT")
        return beats[-1] if beats else None


@pytest.fixture(scope="module")
def recording():
    return recorded_exchanges(read_tlog(RECORDING))


def test_the_recording_is_what_the_project_says(recording):
    """The facts the sim is held to are in the recording itself (else the replay below proves nothing)."""
    exchanges, ready_at, epilogue = recording
    assert 35.0 < ready_at < 45.0
    results = {(ex.name.split()[0], ex.result) for ex in exchanges}
    assert ("MAV_CMD_GET_HOME_POSITION", mavlink.MAV_RESULT_FAILED) in results
    assert ("MAV_CMD_WAYPOINT_USER_1", mavlink.MAV_RESULT_UNSUPPORTED) in results
    takeoffs = [ex for ex in exchanges if ex.msg.get_type() == "COMMAND_LONG" and ex.msg.command == 22]
    assert [ex.result for ex in takeoffs][-2:] == [mavlink.MAV_RESULT_ACCEPTED] * 2      # the retry, too
    assert any(ex.msg.get_type() == "SET_MODE" and ex.result is None for ex in exchanges)
    assert any(normal(t) == normal("SIM Hit ground at 0.5 m/s") for t in epilogue) and "Disarming motors" in epilogue


def test_the_sim_answers_every_recorded_command_as_the_real_vehicle_did(recording):
    exchanges, ready_at, epilogue = recording

    def sim_time(t: float) -> float:
        """Recording s → sim s: scaled while starting up, the recording's own pace once ready."""
        return t * READY_AFTER / ready_at if t < ready_at else READY_AFTER + (t - ready_at)

    clock = ManualClock()
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=SPEEDUP, ready_after=READY_AFTER, seed=11), clock=clock).start()
    gs = GroundStation(sim.tcp_port)
    try:
        assert wait_until(lambda: sim.clients == 1, 10)
        replay = Replay(sim, clock, gs)
        got, want = [], []
        for ex in exchanges:
            replay.advance_to(sim_time(ex.t))
            here = situation(replay.last_heartbeat(), sim.truth().ready)
            if ex.situation is not None and here is not None:
                assert here == ex.situation, \
                    f"{ex.name} at {ex.t:.2f} s: the sim was {here}, the vehicle {ex.situation}"
            mav1 = ex.version == 1                       # as the recorded ground station framed it
            if ex.msg.get_type() == "COMMAND_LONG":
                m = ex.msg
                msg = gs.encoder.command_long_encode(1, 1, m.command, m.confirmation, m.param1, m.param2, m.param3,
                                                     m.param4, m.param5, m.param6, m.param7)
            else:
                msg = gs.encoder.set_mode_encode(1, ex.msg.base_mode, ex.msg.custom_mode)
            mark = replay.deliver(msg, mav1)
            end = replay.marker()
            answer = [m for m, _ in gs.frames[mark:end]]
            acks = [m for m in answer if m.get_type() == "COMMAND_ACK"]
            if ex.msg.get_type() == "COMMAND_LONG":
                assert len(acks) == 1 and acks[0].command == ex.msg.command, (ex.name, acks)
                ack = acks[0]
                got.append((ex.name, ack.result))
                want.append((ex.name, ex.result))
                version = next(v for m, v in gs.frames[mark:end] if m is ack)
                assert version == ex.ack_version, f"{ex.name}: ACK in MAVLink {version}, recorded {ex.ack_version}"
                assert (ack.target_system, ack.target_component) == (255, 190)
                said = [normal(m.text) for m in answer[answer.index(ack) + 1:] if m.get_type() == "STATUSTEXT"]
                missing = [t for t in ex.texts if normal(t) not in said]
                assert not missing, f"{ex.name} at {ex.t:.2f} s: the vehicle said {ex.texts}, the sim {said}"
            else:
                assert not acks, f"{ex.name}: the real vehicle sends no COMMAND_ACK for SET_MODE"
                beat = gs.wait("HEARTBEAT", 10, since=mark)
                assert beat is not None and beat.custom_mode == ex.mode_after
        assert got == want                               # every result, in the recorded order
        # and what followed the last command (LAND): touchdown, "Disarming motors", disarmed
        mark = gs.mark()
        landed_by = sim.truth().time + 60.0
        while sim.truth().armed and sim.truth().time < landed_by:
            replay.advance_to(sim.truth().time + 1.0)
        assert not sim.truth().armed, sim.truth()
        end = replay.marker()
        said = [normal(m.text) for m, _ in gs.frames[mark:end] if m.get_type() == "STATUSTEXT"]
        assert said == [normal(t) for t in epilogue], (said, epilogue)
        assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
                       10, since=mark)
    finally:
        gs.close()
        sim.stop()


def test_the_sim_starts_up_as_the_real_vehicle_did():
    """At the recording's own pace (ready_after = its 40.6 s): the same start-up lines in the same order, a
    HEARTBEAT in BOOT state until "ArduPilot Ready", and no LOCAL_POSITION_NED until the EKF uses GPS."""
    frames = read_tlog(RECORDING)
    ready_at = next(t for t, m in frames if m.get_type() == "STATUSTEXT" and "is using GPS" in m.text)
    said = [(t, m) for t, m in frames if m.get_srcSystem() == 1 and t <= ready_at + 0.1]
    recorded = [m.text for _, m in said if m.get_type() == "STATUSTEXT" and not m.text.startswith(("Arm:", "PreArm:"))]
    initialised = next(t for t, m in said if m.get_type() == "STATUSTEXT" and m.text == "ArduPilot Ready")
    assert {m.system_status for t, m in said if m.get_type() == "HEARTBEAT" and t < initialised} == \
        {mavlink.MAV_STATE_BOOT}
    assert not any(m.get_type() == "LOCAL_POSITION_NED" for t, m in said if t < ready_at)

    clock = ManualClock()
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=SPEEDUP, ready_after=ready_at, seed=5), clock=clock).start()
    gs = GroundStation(sim.tcp_port)
    try:
        assert wait_until(lambda: sim.clients == 1, 10)
        replay = Replay(sim, clock, gs)
        replay.deliver(gs.encoder.request_data_stream_encode(1, 1, mavlink.MAV_DATA_STREAM_ALL, 4, 1), True)
        replay.advance_to(ready_at + 0.5)
        end = replay.marker()
        heard = [m for m, _ in gs.frames[:end]]
        texts = [m.text for m in heard if m.get_type() == "STATUSTEXT" and not m.text.startswith(("Arm:", "PreArm:"))]
        assert [normal(t) for t in texts] == [normal(t) for t in recorded]

        def line(text: str) -> int:
            return next(i for i, m in enumerate(heard) if m.get_type() == "STATUSTEXT" and m.text == text)

        boundary = line("ArduPilot Ready")
        assert {m.system_status for m in heard[:boundary] if m.get_type() == "HEARTBEAT"} <= {mavlink.MAV_STATE_BOOT}
        assert {m.system_status for m in heard[boundary:] if m.get_type() == "HEARTBEAT"} == {mavlink.MAV_STATE_STANDBY}
        using_gps = line("EKF3 IMU0 is using GPS")
        assert not any(m.get_type() == "LOCAL_POSITION_NED" for m in heard[:using_gps])
        assert any(m.get_type() == "LOCAL_POSITION_NED" for m in heard[using_gps:])
    finally:
        gs.close()
        sim.stop()


# -- the mission recording (ArduCopter 4.6.3): every mission-protocol message and command, replayed ----------
MISSION_RECORDING = MISSION + ".tlog"
MISSION_SENT = ("MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST_LIST", "MISSION_REQUEST_INT",
                "MISSION_ACK", "MISSION_CLEAR_ALL", "MISSION_SET_CURRENT", "COMMAND_LONG", "REQUEST_DATA_STREAM")
MISSION_TEXTS = re.compile(r"^(Mission: |Reached command|Flight plan received|Mission upload timeout|got MISSION_ITEM"
                           r"|Fence Indexed OK|Only \d+ items|Arming motors|Disarming motors)")


def mission_events(messages) -> list[tuple]:
    """What the vehicle said of its missions: requests, counts, items, ACKs, progress and its mission texts."""
    out = []
    for m in messages:
        kind = m.get_type()
        if kind == "MISSION_REQUEST":
            out.append(("request", m.seq, m.mission_type))
        elif kind == "MISSION_ACK":
            out.append(("ack", m.type, m.mission_type))
        elif kind == "MISSION_COUNT":
            out.append(("count", m.count, m.mission_type))
        elif kind == "MISSION_ITEM_INT":
            out.append(("item", m.seq, m.frame, m.command, m.autocontinue, m.param1, m.param2, m.param3, m.param4,
                        m.x // 10, m.y // 10, round(m.z, 2), m.mission_type))
        elif kind == "MISSION_ITEM_REACHED":
            out.append(("reached", m.seq))
        elif kind == "COMMAND_ACK":
            out.append(("command", m.command, m.result))
        elif kind == "STATUSTEXT" and MISSION_TEXTS.match(m.text):
            out.append(("text", m.text))
    return out


def test_the_sim_answers_the_recorded_mission_session_as_the_real_vehicle_did():
    """The mission recording's ground station, message by message at its own times (upload with an item out of
    order and a DENIED download, the 8 s timeout, the re-asked item, the legacy float item, fence, rally, the
    flight with pause, resume and both jumps, clear): the sim's answers in order are the real vehicle's."""
    frames = read_tlog(MISSION_RECORDING)
    ready_at = next(t for t, m in frames if m.get_type() == "STATUSTEXT" and "is using GPS" in m.text)
    home = next(m for _, m in frames if m.get_type() == "HOME_POSITION")
    sent = [(t, m) for t, m in frames if m.get_srcSystem() == 255 and m.get_type() in MISSION_SENT]

    def prompt(t: float):
        """The vehicle's request the ground station answered at ``t`` (sent within 10 ms before), or None."""
        said = [m for t2, m in frames if m.get_srcSystem() == 1 and t - 0.010 <= t2 <= t
                and m.get_type() in ("MISSION_REQUEST", "MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_ACK")]
        return said[-1] if said else None

    recorded = mission_events(m for t, m in frames if m.get_srcSystem() == 1 and t >= sent[0][0])
    assert ("ack", mavlink.MAV_MISSION_INVALID_SEQUENCE, 0) in recorded and ("ack", 14, 0) in recorded
    assert ("ack", mavlink.MAV_MISSION_OPERATION_CANCELLED, 0) in recorded

    clock = ManualClock()
    config = SimConfig(tcp_port=0, speedup=SPEEDUP, ready_after=ready_at, seed=3,
                       home=(home.latitude / 1e7, home.longitude / 1e7, home.altitude / 1000.0, 353.0))
    sim = SimVehicle(config, clock=clock).start()
    gs = GroundStation(sim.tcp_port)
    try:
        assert wait_until(lambda: sim.clients == 1, 10)
        replay = Replay(sim, clock, gs)
        start = gs.mark()
        asked = start
        for t, m in sent:
            replay.advance_to(t)                       # the sim's clock is the recording's (ready_after = its)
            ask = prompt(t)
            if ask is not None:      # an answer goes out once the sim has asked as often as the vehicle had
                wanted = mission_events([ask])[0]
                times = mission_events(m2 for t2, m2 in frames if m2.get_srcSystem() == 1
                                       and sent[0][0] <= t2 <= t).count(wanted)
                while mission_events(m2 for m2, _ in gs.frames[start:]).count(wanted) < times:
                    assert sim.truth().time < t + 2.0, f"the sim never said {wanted} ({t:.3f} s)"
                    replay.step()
                    gs.wait(lambda m2: mission_events([m2]) == [wanted], 0.05, since=asked)
            data = m.get_msgbuf()
            msg = type(m)(*[getattr(m, f) for f in m.get_fieldnames()])
            asked = replay.deliver(msg, data[0] == mavlink.PROTOCOL_MARKER_V1)
        replay.advance_to(frames[-1][0])
        end = replay.marker()
        answered = mission_events(m for m, _ in gs.frames[start:end])

        def states(messages) -> tuple[list[tuple], set[int]]:
            """MISSION_CURRENT's (seq, mission_state, mission_mode) each time it changes, and the totals seen
            (a stream tick may fall inside an upload, whose items count as they arrive: not compared)."""
            out, totals = [], set()
            for m in messages:
                if m.get_type() == "MISSION_CURRENT":
                    totals.add(m.total)
                    value = (m.seq, m.mission_state, m.mission_mode)
                    if not out or out[-1] != value:
                        out.append(value)
            return out, totals
        sim_states, sim_totals = states(m for m, _ in gs.frames[start:end])
        recorded_states, recorded_totals = states(m for t, m in frames if m.get_srcSystem() == 1
                                                  and t >= sent[0][0])
        assert sim_states == recorded_states and recorded_totals <= sim_totals, (sim_states, recorded_states)
        first = max(0, next((i for i, (a, b) in enumerate(zip(answered, recorded)) if a != b),
                            min(len(answered), len(recorded))) - 6)
        assert answered == recorded, "sim / vehicle from the first difference:\n" + "\n".join(
            f"{a!s:75} {b!s}" for a, b in zip(answered[first:first + 12], recorded[first:first + 12]))
    finally:
        gs.close()
        sim.stop()
