"""The link's one round trip (driver.core.roundtrip) and the waits every part makes from it, on a clock the test
moves: a request answered once times the link; one unanswered for a whole timeout doubles the waits after it
until an answer times the link again (RFC 6298, Karn), so a link that slows down all at once is waited for.
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.roundtrip import RoundTrip
from driver.vehicle.commands import decided
from driver.vehicle.state import CommandStatus
from test_driver_clock import _AUTOPILOT, at, clock, heartbeat, kinds, vehicle  # noqa: F401 (fixtures)

GCS = (255, 190)


def ack(command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> bytes:
    frame = _AUTOPILOT.command_ack_encode(command, result, 0, 0, *GCS).pack(_AUTOPILOT)
    _AUTOPILOT.seq = (_AUTOPILOT.seq + 1) % 256
    return frame


def test_an_answer_times_the_link_and_a_whole_timeout_unanswered_doubles_the_waits():
    rt = RoundTrip(initial=1.0, floor=0.05)
    assert rt.timeout() == 2.0                          # nothing measured: twice the first guess
    rt.sample(0.1)
    assert abs(rt.timeout() - 0.3) < 1e-9               # srtt 0.1 and its variation 0.05: 0.1 + 4 x 0.05
    rt.expired(10.0)
    assert abs(rt.timeout() - 0.6) < 1e-9
    rt.expired(10.3)                                    # requests out together expire together: once a timeout
    assert abs(rt.timeout() - 0.6) < 1e-9
    rt.expired(10.6)
    assert abs(rt.timeout() - 1.2) < 1e-9
    rt.sample(0.1)                                      # answered once again: the link is timed, no more doubling
    assert rt.backoff == 1 and rt.timeout() < 0.3
    rt.sample(0.0)                                      # an answer in no time was on its way before: not a sample
    assert rt.samples == 2


def test_a_command_resent_at_the_links_pace_is_waited_for_when_the_link_slows(clock, vehicle):
    """Fast answers made the timeout 0.05 s; then the link takes 1.5 s. MISSION_START, re-sent at the link's pace
    (a sequence's step), is sent again less and less often, and is answered: not 'no answer after 3 attempts'."""
    vehicle.ingest(heartbeat(armed=True))
    quick = vehicle.command_long(mavlink.MAV_CMD_DO_SET_SERVO, (9, 1500))
    assert kinds(at(clock, vehicle, 0.0), "COMMAND_LONG")
    clock.advance(0.01)
    vehicle.ingest(ack(mavlink.MAV_CMD_DO_SET_SERVO))
    assert quick.result(timeout=5).ok
    rt = vehicle.ports.roundtrip
    assert rt.timeout() == rt.floor == 0.05
    future = vehicle.ports.commands.long(mavlink.MAV_CMD_MISSION_START, (0, 0), "MISSION_START",
                                         retry=rt.timeout())
    sent = []
    for step in range(20, 50):                          # 1.0 s to 2.45 s, a tick every 0.05 s
        t = round(step * 0.05, 2)
        sent += [t for m in kinds(at(clock, vehicle, t), "COMMAND_LONG")
                 if m.command == mavlink.MAV_CMD_MISSION_START]
    assert not future.done(), future.result()
    assert sent == [1.0, 1.05, 1.15, 1.35, 1.75], sent  # each wait twice the last: 0.05, 0.1, 0.2, 0.4 s
    clock.advance(1000.0 + 2.5 - clock.now())
    vehicle.ingest(ack(mavlink.MAV_CMD_MISSION_START))   # the first one's answer, 1.5 s after it went out
    at(clock, vehicle, 2.5)
    result = future.result(timeout=5)
    assert result.status is CommandStatus.ACCEPTED, str(result)


def test_a_quickly_retried_command_doubles_its_own_wait_and_waits_a_commands_whole_time(clock, vehicle):
    """MISSION_START re-sent every 0.25 s on a link timed at 0.05 s: each unanswered try waits twice as long as the
    last, by the command's own backoff and not only the link's (which stays below it), up to the command timeout;
    and it gives up no sooner than a command re-sent every command timeout would (3 s x 3 attempts): at the first
    try due after that."""
    vehicle.ingest(heartbeat(armed=True))
    quick = vehicle.command_long(mavlink.MAV_CMD_DO_SET_SERVO, (9, 1500))
    at(clock, vehicle, 0.0)
    clock.advance(0.01)
    vehicle.ingest(ack(mavlink.MAV_CMD_DO_SET_SERVO))
    assert quick.result(timeout=5).ok and vehicle.ports.roundtrip.timeout() == 0.05
    at(clock, vehicle, 0.95)
    future = vehicle.ports.commands.long(mavlink.MAV_CMD_MISSION_START, (0, 0), "MISSION_START", retry=0.25)
    sent = []
    for step in range(20, 215):                         # 1.0 s to 10.7 s, a tick every 0.05 s
        t = round(step * 0.05, 2)
        if step % 20 == 0:
            vehicle.ingest(heartbeat(armed=True))       # the link stays up: only this command goes unanswered
        sent += [t for m in kinds(at(clock, vehicle, t), "COMMAND_LONG")
                 if m.command == mavlink.MAV_CMD_MISSION_START]
        assert decided(future) is None, (t, decided(future))
    assert sent == [1.0, 1.25, 1.75, 2.75, 4.75, 7.75], sent   # 0.25, 0.5, 1, 2 s, then the command timeout
    last = [m for m in kinds(at(clock, vehicle, 10.75), "COMMAND_LONG")   # due again, 9.75 s after the first
            if m.command == mavlink.MAV_CMD_MISSION_START]
    assert last == []
    assert decided(future).status is CommandStatus.TIMED_OUT, str(decided(future))
