"""The driver's timers on a clock the test moves (issue 30, 4: time-dependent logic reads an injectable clock).

The vehicle is not started: no thread, no socket, no real second waited. What the vehicle says is fed with
``ingest``; ``step`` runs one pass of the ticker at the clock's time and returns what it would send. So the
deadman, a command's retries and the heartbeat's loss are checked to the tenth of a second, on a loaded machine
as on an idle one.
"""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim.clock import ManualClock
from driver.vehicle import Vehicle, VehicleConfig
from driver.vehicle.state import CommandStatus, LinkStatus

GUIDED = 4                                 # ArduCopter's custom mode number


_AUTOPILOT = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)


def heartbeat(armed: bool = True, mode: int = GUIDED) -> bytes:
    """The autopilot's heartbeat (system 1, component 1), as ArduCopter sends it: each with its own sequence
    number (a frame repeating the last one's is a duplicate, and dropped)."""
    enc = _AUTOPILOT
    base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (mavlink.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
    frame = enc.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base, mode,
                                 mavlink.MAV_STATE_ACTIVE).pack(enc)
    enc.seq = (enc.seq + 1) % 256
    return frame


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock(start=1000.0)


@pytest.fixture
def vehicle(clock):
    """A driver on its own clock, not started: nothing runs unless the test steps it."""
    v = Vehicle(VehicleConfig(connection="udpin:127.0.0.1:0", tlog_path=None, param_cache=None), clock=clock.now)
    yield v
    v.close()


def at(clock: ManualClock, vehicle: Vehicle, t: float) -> list:
    """Move the clock to 1000 + ``t`` s and step the driver once: what it sends then."""
    clock.advance(1000.0 + t - clock.now())
    return vehicle.step()


def kinds(sent: list, kind: str) -> list:
    return [m for m in sent if m.get_type() == kind]


def test_the_deadman_zeroes_the_velocity_when_the_pilot_stops_asking(clock, vehicle):
    vehicle.ingest(heartbeat())
    assert vehicle.set_velocity(2.0, 0.0, 0.0, 0.0)
    assert [m.vx for m in kinds(at(clock, vehicle, 0.0), "SET_POSITION_TARGET_LOCAL_NED")] == [2.0]
    sent = at(clock, vehicle, 0.45)                      # within the deadman (0.5 s): still flying forward
    assert [m.vx for m in kinds(sent, "SET_POSITION_TARGET_LOCAL_NED")] == [2.0]
    assert vehicle.state().setpoint.forward == 2.0
    sent = at(clock, vehicle, 0.55)                      # no demand for 0.55 s: hover
    assert [m.vx for m in kinds(sent, "SET_POSITION_TARGET_LOCAL_NED")] == [0.0]
    assert vehicle.state().setpoint.is_zero


def test_a_fresh_demand_keeps_the_velocity_past_the_deadman(clock, vehicle):
    vehicle.ingest(heartbeat())
    for t in (0.0, 0.4, 0.8, 1.2):                       # the pilot holds the stick: a demand every 0.4 s
        at(clock, vehicle, t)
        assert vehicle.set_velocity(2.0, 0.0, 0.0, 0.0)
    sent = at(clock, vehicle, 1.6)
    assert [m.vx for m in kinds(sent, "SET_POSITION_TARGET_LOCAL_NED")] == [2.0]
    assert vehicle.state().setpoint.forward == 2.0


def test_an_unanswered_command_goes_again_every_command_timeout_then_times_out(clock, vehicle):
    vehicle.ingest(heartbeat(armed=False))
    future = vehicle.command_long(mavlink.MAV_CMD_DO_SET_SERVO, (9, 1500))
    sent_at = {}
    for tenth in range(0, 100):                          # 10 s of the driver's ticks, 0.1 s apart
        for m in kinds(at(clock, vehicle, tenth / 10), "COMMAND_LONG"):
            if m.command == mavlink.MAV_CMD_DO_SET_SERVO:      # (the driver's own requests go meanwhile)
                sent_at.setdefault(m.confirmation, tenth / 10)
    assert sent_at == {0: 0.0, 1: 3.0, 2: 6.0}           # command_timeout 3 s, 3 attempts, as QGroundControl
    result = future.result(timeout=10)                   # settled at 9 s (the notifier's thread hands it over)
    assert result.status is CommandStatus.TIMED_OUT and result.attempts == 3, str(result)


def test_the_link_is_lost_after_the_loss_timeout_without_a_heartbeat_and_back_with_one(clock, vehicle):
    vehicle.ingest(heartbeat())
    at(clock, vehicle, 0.0)
    assert vehicle.state().link.status is LinkStatus.OK
    at(clock, vehicle, 3.4)                              # loss_timeout 3.5 s
    assert vehicle.state().link.status is LinkStatus.OK
    at(clock, vehicle, 3.6)
    state = vehicle.state()
    assert state.link.status is LinkStatus.LOST
    assert any(m.text == "Link lost: no heartbeat for 3.6 s" for m in state.messages), state.messages
    clock.advance(10.0)
    vehicle.ingest(heartbeat())
    vehicle.step()
    assert vehicle.state().link.status is LinkStatus.OK


def test_a_landed_mission_is_complete_though_its_rewind_is_heard_before_the_disarm(clock, vehicle):
    """Through loss the heartbeat that shows ArduCopter's disarm at the end of a LAND-ending mission can come after
    the MISSION_CURRENT of the mission it rewound at that disarm (item 1): the flight still reached its last item,
    and the pilot is told the mission is complete (seen on real SITL at 30 % loss: "ACTIVE item 1")."""
    from driver.mission.plan import MissionRunState
    enc, auto = _AUTOPILOT, 3

    def send(msg) -> None:
        vehicle.ingest(msg.pack(enc))
        enc.seq = (enc.seq + 1) % 256

    def current(seq: int) -> None:
        send(enc.mission_current_encode(seq, 5, mavlink.MISSION_STATE_ACTIVE, 0))

    vehicle.ingest(heartbeat(armed=True, mode=auto))
    send(enc.extended_sys_state_encode(0, mavlink.MAV_LANDED_STATE_IN_AIR))
    for seq in (1, 2, 3, 4, 5):
        current(seq)
    send(enc.statustext_encode(mavlink.MAV_SEVERITY_INFO, b"Mission: 5 Land"))
    current(1)                                   # rewound at the disarm, whose heartbeat was lost
    send(enc.statustext_encode(mavlink.MAV_SEVERITY_INFO, b"Mission: 1 Takeoff"))
    vehicle.ingest(heartbeat(armed=False, mode=auto))
    send(enc.extended_sys_state_encode(0, mavlink.MAV_LANDED_STATE_ON_GROUND))
    current(1)
    at(clock, vehicle, 0.1)
    s = vehicle.state()
    assert s.mission.state is MissionRunState.COMPLETE and s.mission.flown, s.mission
