"""The driver signing against the simulated ArduCopter's signing (ArduPilot's rules, driver/sim/signing.py):
SETUP_SIGNING, then our signed commands fly it while an intruder's unsigned ones on the same telemetry port
are dropped; a vehicle that signs with a key we lack or do not match; a MAVLink 1 link that cannot sign."""
from __future__ import annotations

import hashlib

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.link.signing import SigningConfig
from driver.sim import MODES
from driver.vehicle.state import CommandStatus, SigningStatus
from ice_fixtures import eventually

KEY = hashlib.sha256(b"uavviewer-test").digest()
OTHER = hashlib.sha256(b"someone else's key").digest()


@pytest.fixture
def signed(vehicle_factory, tmp_path):
    """A driver with signing configured (None: no key), its timestamp kept in the test's own folder."""
    def make(sim, key=None, allow_unsigned=False, port=None, **kw):
        return vehicle_factory(f"tcp:127.0.0.1:{port or sim.tcp_port}",
                               signing=SigningConfig(key=key, allow_unsigned=allow_unsigned,
                                                     timestamp_path=str(tmp_path / "signing-timestamp")), **kw)
    return make


class Intruder:
    """Another ground station on the vehicle's telemetry port, without the key (plain pymavlink)."""

    def __init__(self, port: int):
        self.conn = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=255, source_component=191)
        self.conn.WIRE_PROTOCOL_VERSION = "2.0"

    def command(self, command: int, *params) -> None:
        p = (list(params) + [0] * 7)[:7]
        self.conn.mav.command_long_send(1, 1, command, 0, *p)

    def close(self) -> None:
        self.conn.close()


def test_after_setup_only_signed_commands_fly_it(sim_factory, signed):
    sim = sim_factory()
    vehicle = signed(sim)
    assert vehicle.wait_for(lambda s: s.connected and s.link.mavlink_version == 2, 10)
    assert vehicle.state().signing.status is SigningStatus.OFF
    result = vehicle.setup_signing(KEY).result(timeout=15)
    assert result.status is CommandStatus.ACCEPTED, result
    assert sim.signing.key == KEY
    s = vehicle.wait_for(lambda s: s.signing.status is SigningStatus.SIGNING and s.signing.vehicle_signs
                         and s.signing.signed_accepted > 0, 10)
    assert s is not None, vehicle.state().signing
    assert any("in clear" in m.text for m in s.messages)      # the pilot was told the key went out readable
    intruder = Intruder(sim.tcp_port)
    try:
        before = sim.signing.counters.dropped_unsigned
        intruder.command(mavlink.MAV_CMD_DO_SET_MODE, 1, MODES["LAND"])
        intruder.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, 21196)
        assert eventually(lambda: sim.signing.counters.dropped_unsigned >= before + 2, 10), "not dropped"
        takeoff = vehicle.takeoff(2.0).result(timeout=60)     # ours, signed, flies
        assert takeoff.ok, takeoff
        before = sim.signing.counters.dropped_unsigned
        intruder.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 21196)    # motors off in the air: dropped
        intruder.command(mavlink.MAV_CMD_DO_SET_MODE, 1, MODES["LAND"])
        assert eventually(lambda: sim.signing.counters.dropped_unsigned >= before + 2, 10)
        truth = sim.truth()
        assert truth.armed and truth.mode == "GUIDED" and truth.altitude > 1.5
        assert vehicle.land().result(timeout=30).ok
    finally:
        intruder.close()


def test_removing_the_key_turns_signing_off_on_both_ends(sim_factory, signed):
    sim = sim_factory(signing_key=KEY)
    vehicle = signed(sim, key=KEY)
    assert vehicle.wait_for(lambda s: s.connected and s.signing.vehicle_signs, 10)
    result = vehicle.remove_signing().result(timeout=15)
    assert result.status is CommandStatus.ACCEPTED, result
    assert sim.signing.key is None
    s = vehicle.wait_for(lambda s: s.signing.status is SigningStatus.OFF, 5)
    assert s is not None and not s.signing.vehicle_signs
    assert vehicle.set_mode("LOITER").result(timeout=10).ok   # unsigned now, and obeyed


def test_a_vehicle_that_signs_ignores_us_without_the_key_and_the_pilot_is_told(sim_factory, signed):
    sim = sim_factory(signing_key=KEY)
    vehicle = signed(sim, key=None, command_attempts=1)
    s = vehicle.wait_for(lambda s: s.connected and s.signing.status is SigningStatus.REQUIRED, 10)
    assert s is not None, vehicle.state().signing
    assert "give its key" in s.signing.summary
    result = vehicle.set_mode("LOITER").result(timeout=10)
    assert result.status is CommandStatus.TIMED_OUT, result   # dropped without a word, as ArduPilot does
    assert sim.signing.counters.dropped_unsigned > 0 and sim.truth().mode != "LOITER"


def test_the_usb_port_obeys_unsigned_commands_as_arducopter_does(sim_factory, signed):
    sim = sim_factory(signing_key=KEY, usb_port=0)
    vehicle = signed(sim, key=None, port=sim.usb_port)
    assert vehicle.wait_for(lambda s: s.connected and s.signing.vehicle_signs, 10)
    assert vehicle.set_mode("LOITER").result(timeout=10).ok


def test_another_key_is_a_mismatch_and_nothing_the_vehicle_says_is_believed(sim_factory, signed):
    sim = sim_factory(signing_key=KEY)
    vehicle = signed(sim, key=OTHER)
    s = vehicle.wait_for(lambda s: s.signing.status is SigningStatus.MISMATCH and s.signing.bad_signature > 10, 10)
    assert s is not None, vehicle.state().signing
    assert not s.connected and s.mode == "" and s.signing.signed_accepted == 0


@pytest.mark.parametrize("allow", [False, True], ids=["unsigned refused", "unsigned allowed"])
def test_a_mavlink1_link_cannot_sign_and_says_so(sim_factory, signed, allow):
    sim = sim_factory(profile="solo")
    vehicle = signed(sim, key=KEY, allow_unsigned=allow)
    s = vehicle.wait_for(lambda s: s.signing.status is SigningStatus.UNAVAILABLE, 10)
    assert s is not None, vehicle.state().signing
    assert "MAVLink 1" in s.signing.summary
    if allow:                                                  # flown unsigned, knowingly
        assert vehicle.wait_for(lambda s: s.connected, 10)
        result = vehicle.setup_signing(KEY).result(timeout=5)
        assert result.status is CommandStatus.REJECTED and "MAVLink 1" in result.reason
    else:
        assert not s.connected and s.signing.unsigned_rejected > 0


def test_a_restarted_driver_keeps_commanding_a_signing_vehicle(sim_factory, signed, vehicle_factory):
    """The same link keeps its link id and the kept timestamp moves on: the vehicle's stream table takes it."""
    sim = sim_factory(signing_key=KEY)
    first = signed(sim, key=KEY)
    assert first.wait_for(lambda s: s.connected and s.signing.vehicle_signs, 10)
    assert first.set_mode("LOITER").result(timeout=10).ok
    link_id = first.state().signing.link_id
    first.close()
    second = signed(sim, key=KEY)
    assert second.wait_for(lambda s: s.connected and s.mode == "LOITER", 10)
    assert second.state().signing.link_id == link_id
    assert second.set_mode("GUIDED").result(timeout=10).ok
    assert sim.signing.counters.dropped_replay == 0


def test_a_key_the_vehicle_does_not_have_yet_is_said_and_allowing_unsigned_lets_it_be_set_up(sim_factory, signed):
    sim = sim_factory()
    vehicle = signed(sim, key=KEY)
    s = vehicle.wait_for(lambda s: s.signing.status is SigningStatus.MISMATCH, 10)
    assert s is not None and "it has no key yet" in s.signing.detail and not s.connected
    vehicle.allow_unsigned(True)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    assert vehicle.setup_signing(KEY).result(timeout=15).ok
    vehicle.allow_unsigned(False)
    assert vehicle.wait_for(lambda s: s.signing.status is SigningStatus.SIGNING and s.signing.vehicle_signs, 10)
