"""The simulated vehicle's link as a faultable radio, both ways: loss, bursts, duplicates, latency, reordering,
outages and lost replies, seen from a ground station on a real socket.

Latency, bursts and outages are in real seconds; those tests run the sim on a hand-driven clock and read the
faults' counters, so they prove "held, then delivered" exactly rather than by a stopwatch.
"""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import Faults, LinkFaults, ManualClock, SimConfig, SimVehicle
from driver.sim.__main__ import configure, parser
from test_sim import FAST, GroundStation, connect, make_sim, wait_until  # noqa: F401  (fixtures)
from test_sim_recordings import Replay

HARMLESS = (mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)   # always ACCEPTED at once (a level
# calibration is not: ArduCopter 4.6 ACKs it after 1 s, the Solo's 3.3 refuses it)


@pytest.fixture
def clocked():
    """A sim on a ManualClock with one ground station connected: (sim, clock, gs, replay)."""
    made = []

    def make(**overrides):
        clock = ManualClock()
        sim = SimVehicle(SimConfig(**dict(FAST, **overrides)), clock=clock).start()
        gs = GroundStation(sim.tcp_port)
        made.append((sim, gs))
        assert wait_until(lambda: sim.clients == 1, 10)
        return sim, clock, gs, Replay(sim, clock, gs)

    yield make
    for sim, gs in made:
        gs.close()
        sim.stop()


def command(gs: GroundStation, cmd: int, *params: float):
    p = list(params) + [0.0] * (7 - len(params))
    gs.send(gs.encoder.command_long_encode(1, 1, cmd, 0, *p))


# -- settings ----------------------------------------------------------------------------------------------
def test_fault_settings_are_checked_when_set():
    faults = Faults()
    for name, value in (("loss", 1.5), ("burst_rate", -0.1), ("duplicate", float("nan")), ("reorder", 2)):
        with pytest.raises(ValueError):
            setattr(faults.uplink, name, value)
    for name, value in (("latency", -0.1), ("jitter", float("inf")), ("burst_seconds", float("nan"))):
        with pytest.raises(ValueError):
            setattr(faults.downlink, name, value)
    with pytest.raises(ValueError):
        LinkFaults(duplicate=2)
    with pytest.raises(ValueError):
        faults.drop_fraction = -0.1
    with pytest.raises(ValueError):
        faults.corrupt_fraction = 1.01
    with pytest.raises(ValueError):
        faults.lose_replies = 400                  # one id or a share? say {400} or 0.5
    with pytest.raises(ValueError):
        faults.uplink = {"loss": 0.1}
    with pytest.raises(ValueError):
        faults.outage(-1)
    with pytest.raises(TypeError):
        Faults(no_such_fault=True)
    faults.lose_replies = [400, 22]
    assert faults.lose_replies == {400, 22}
    faults.uplink.latency = 0.25
    assert faults.uplink.active and not faults.downlink.active
    # every older attribute still works, defaults off
    old = Faults(drop_fraction=0.2)
    assert (old.link_down, old.heartbeats, old.drop_fraction, old.corrupt_fraction, old.ignore_commands,
            old.refuse_arm, list(old.ignored)) == (False, True, 0.2, 0.0, set(), None, [])


def test_the_command_line_sets_every_fault_and_checks_it(capsys):
    args = parser().parse_args(["--tcp", "127.0.0.1:0", "--profile", "solo", "--gimbal", "--companion",
                                "--uplink-loss", "0.1", "--downlink-loss", "0.2", "--latency", "0.2",
                                "--jitter", "0.05", "--duplicate", "0.05", "--reorder", "0.03", "--burst-rate",
                                "0.01", "--burst-seconds", "0.5", "--lose-replies", "NAV_TAKEOFF,400",
                                "--origin-offset", "1,2,-0.5", "--seed", "3"])
    sim = configure(args)
    up, down = sim.faults.uplink, sim.faults.downlink
    assert (up.loss, down.loss, up.latency, down.jitter, up.duplicate, down.reorder, up.burst_rate,
            down.burst_seconds) == (0.1, 0.2, 0.2, 0.05, 0.05, 0.03, 0.01, 0.5)
    assert sim.faults.lose_replies == {mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    assert sim.config.profile == "solo" and sim.config.gimbal and sim.config.companion
    assert sim.config.origin_offset == (1.0, 2.0, -0.5)
    assert configure(parser().parse_args(["--lose-replies"])).faults.lose_replies is True
    assert configure(parser().parse_args(["--lose-replies", "0.3"])).faults.lose_replies == 0.3
    for bad, reason in ((["--uplink-loss", "2"], "argument --uplink-loss: '2': a share from 0 to 1 is needed"),
                        (["--latency", "-1"], "argument --latency: '-1': zero or a positive number is needed"),
                        (["--profile", "px4"], "argument --profile: invalid choice: 'px4' (choose from "
                                               "'copter-4', 'solo')")):
        with pytest.raises(SystemExit):
            parser().parse_args(bad)
        assert capsys.readouterr().err.splitlines()[-1] == f"python -m driver.sim: error: {reason}"


# -- loss, duplicates, reordering -------------------------------------------------------------------------
def test_uplink_loss_drops_what_the_ground_station_sends(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert gs.wait("HEARTBEAT")
    counters = sim.faults.counters.uplink
    sim.faults.uplink.loss = 1.0
    lost, heard = counters.lost, len(sim.received_messages)
    command(gs, *HARMLESS)
    assert wait_until(lambda: counters.lost == lost + 1)
    assert len(sim.received_messages) == heard                  # lost before the autopilot: it never heard it
    # a share: with the seed, some commands get through and each of those is answered
    sim.faults.uplink.loss = 0.5
    frames, lost, delivered = counters.frames, counters.lost, counters.delivered
    mark = gs.mark()
    for _ in range(40):
        command(gs, *HARMLESS)
    assert wait_until(lambda: counters.frames == frames + 40)
    got = counters.delivered - delivered
    assert counters.lost - lost + got == 40 and 5 < got < 35, (got, counters)
    assert wait_until(lambda: len(gs.messages("COMMAND_ACK", mark)) == got)
    assert len(sim.received_messages) == heard + got


def test_downlink_loss_keeps_sequence_numbers_going(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    gs.request_streams(10)
    assert gs.wait("ATTITUDE")
    counters = sim.faults.counters.downlink
    sim.faults.downlink.loss = 0.3
    lost, mark = counters.lost, gs.mark()
    assert wait_until(lambda: counters.lost >= lost + 10 and len(gs.messages(since=mark)) >= 30)
    seqs = [m.get_seq() for m, _ in gs.frames[mark:] if m.get_srcComponent() == 1]
    assert any((b - a) % 256 > 1 for a, b in zip(seqs, seqs[1:]))       # the gaps show the loss


def test_downlink_duplicates_come_in_identical_pairs(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    gs.request_streams(10)
    assert gs.wait("ATTITUDE")
    sim.faults.downlink.duplicate = 1.0
    counters = sim.faults.counters.downlink
    duplicated = counters.duplicated
    mark = gs.mark()
    assert wait_until(lambda: counters.duplicated > duplicated + 20 and len(gs.messages(since=mark)) > 40)
    seqs = [m.get_seq() for m, _ in gs.frames[mark:]]
    first = next(i for i, (a, b) in enumerate(zip(seqs, seqs[1:])) if a == b)   # frames said before may still come
    runs = []
    for seq in seqs[first:]:
        if runs and runs[-1][0] == seq:
            runs[-1][1] += 1
        else:
            runs.append([seq, 1])
    assert len(runs) > 10 and all(count == 2 for _, count in runs[:-1]), runs   # each twice, same sequence number


def test_downlink_reordering_swaps_neighbours(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    gs.request_streams(10)
    assert gs.wait("ATTITUDE")
    sim.faults.downlink.reorder = 1.0
    counters = sim.faults.counters.downlink
    mark = gs.mark()
    assert wait_until(lambda: counters.reordered > 10 and len(gs.messages(since=mark)) > 20)
    seqs = [m.get_seq() for m, _ in gs.frames[mark:]]
    assert any((b - a) % 256 == 255 for a, b in zip(seqs, seqs[1:])), seqs      # one step back: a swap
    assert counters.lost == 0 and gs.bad == 0                                    # nothing lost or broken


# -- latency, bursts, outages on a hand-driven clock ----------------------------------------------------------
def test_downlink_latency_holds_every_frame_for_real_seconds_in_order(clocked):
    sim, clock, gs, replay = clocked(speedup=10.0)
    replay.advance_to(1.0)
    assert gs.wait("HEARTBEAT")
    replay.deliver(gs.encoder.request_data_stream_encode(1, 1, mavlink.MAV_DATA_STREAM_ALL, 10, 1), mav1=False)
    counters = sim.faults.counters.downlink
    sim.faults.downlink.latency = 0.5
    sim.faults.downlink.jitter = 0.2
    delivered, mark = counters.delivered, gs.mark()
    for _ in range(2):                          # 0.4 real s (4 sim s) said, none of it 0.5 s old
        replay.let_pass(0.2)
        assert counters.delivered == delivered and counters.delayed > 0
    replay.let_pass(0.8)                        # now what was said first is due (0.5 s ± 0.2 s)
    assert counters.delivered > delivered
    assert gs.wait("HEARTBEAT", since=mark) and gs.wait("ATTITUDE", since=mark)
    seqs = [m.get_seq() for m, _ in gs.frames[mark:] if m.get_srcComponent() == 1]
    assert all((b - a) % 256 == 1 for a, b in zip(seqs, seqs[1:]))      # jitter never reorders


def test_uplink_latency_delays_a_command_before_the_autopilot_hears_it(clocked):
    sim, clock, gs, replay = clocked()
    replay.advance_to(1.0)
    counters = sim.faults.counters.uplink
    sim.faults.uplink.latency = 0.5
    delayed, mark = counters.delayed, gs.mark()
    command(gs, *HARMLESS)
    assert wait_until(lambda: counters.delayed == delayed + 1)
    replay.let_pass(0.4)
    assert not any(kind == "COMMAND_LONG" for _, kind, _ in sim.received_messages)
    replay.let_pass(0.2)
    assert any(kind == "COMMAND_LONG" for _, kind, _ in sim.received_messages)
    assert gs.wait(lambda m: m.get_type() == "COMMAND_ACK", 10, since=mark)


def test_a_burst_loses_every_frame_until_it_ends(clocked):
    sim, clock, gs, replay = clocked()
    replay.advance_to(1.0)
    gs.request_streams(10)
    counters = sim.faults.counters.downlink
    sim.faults.downlink.burst_seconds = 0.3
    sim.faults.downlink.burst_rate = 1.0            # the next frame starts a burst ...
    replay.let_pass(0.1)
    assert counters.bursts == 1
    sim.faults.downlink.burst_rate = 0.0            # ... and no other one starts
    delivered, lost, mark = counters.delivered, counters.burst_lost, gs.mark()
    replay.let_pass(0.2)                            # still inside the 0.3 s
    assert counters.delivered == delivered and counters.burst_lost > lost
    replay.let_pass(0.2)                            # over
    assert counters.delivered > delivered and counters.bursts == 1
    assert gs.wait("HEARTBEAT", since=mark)


def test_an_outage_silences_both_ways_then_ends_by_itself(clocked):
    sim, clock, gs, replay = clocked()
    replay.advance_to(1.0)
    up, down = sim.faults.counters.uplink, sim.faults.counters.downlink
    sim.faults.outage(0.5)
    heard, sent_up, delivered = len(sim.received_messages), up.outage_lost, down.delivered
    command(gs, *HARMLESS)
    assert wait_until(lambda: up.outage_lost == sent_up + 1)
    replay.let_pass(0.3)
    assert down.delivered == delivered and down.outage_lost > 0
    assert len(sim.received_messages) == heard
    mark = gs.mark()
    replay.let_pass(0.3)                            # the outage is over, the same TCP connection carries on
    assert gs.wait("HEARTBEAT", since=mark)
    mark = replay.deliver(gs.encoder.command_long_encode(1, 1, HARMLESS[0], 0, HARMLESS[1], 0, 0, 0, 0, 0, 0), True)
    replay.marker()
    assert [m.result for m in gs.messages("COMMAND_ACK", mark)] == [mavlink.MAV_RESULT_ACCEPTED]


# -- lost replies ------------------------------------------------------------------------------------------
def test_a_lost_reply_means_the_vehicle_acted_but_said_nothing(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert wait_until(lambda: sim.truth().ready, 10)
    assert gs.set_mode("GUIDED").result == mavlink.MAV_RESULT_ACCEPTED
    sim.faults.lose_replies = {mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    mark = gs.mark()
    command(gs, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert wait_until(lambda: sim.truth().armed)                       # it armed ...
    later = gs.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)   # ... and the ACK after it came,
    assert later is not None                                            # so the ARM's ACK never will
    assert not [m for m in gs.messages("COMMAND_ACK", mark) if m.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM]
    assert list(sim.faults.replies_lost) == [mavlink.MAV_CMD_COMPONENT_ARM_DISARM]
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
                   since=mark)
    # all replies: a mode change happens, only the HEARTBEAT tells
    sim.faults.lose_replies = True
    mark = gs.mark()
    command(gs, mavlink.MAV_CMD_DO_SET_MODE, 1, 5)
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 5, since=mark)
    assert not gs.messages("COMMAND_ACK", mark) and sim.truth().mode == "LOITER"
    # a share: some answered, the rest acted on in silence
    sim.faults.lose_replies = 0.5
    lost, mark = len(sim.faults.replies_lost), gs.mark()
    for _ in range(20):
        command(gs, *HARMLESS)
    assert wait_until(lambda: len(gs.messages("COMMAND_ACK", mark)) + len(sim.faults.replies_lost) - lost == 20)
    assert 3 < len(gs.messages("COMMAND_ACK", mark)) < 17
