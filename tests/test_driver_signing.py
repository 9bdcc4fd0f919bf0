"""The driver's MAVLink 2 signing: keys as MAVProxy derives them, timestamps that never go back, the real
ArduCopter's signed frames verified (the recording), forged frames dropped and counted."""
from __future__ import annotations

import hashlib
import os
import struct

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.link.signing import (
    LinkSigning, SigningConfig, key_from_passphrase, read_key_file, signing_time, write_key_file,
)
from driver.vehicle.state import SigningStatus
from driver.vehicle import Vehicle, VehicleConfig
from recordings import SIGNING

RECORDED_KEY = hashlib.sha256(b"uavviewer-test").digest()     # the recording's README


def stamp_of(frame: bytes) -> int:
    low, high = struct.unpack("<IH", frame[-12:-6])
    return low + (high << 32)


def test_the_key_is_mavproxys_sha256_of_the_passphrase():
    assert key_from_passphrase("uavviewer-test") == RECORDED_KEY


def test_a_key_file_holds_hex_or_a_passphrase_and_must_be_private(tmp_path):
    hexfile = tmp_path / "hex.key"
    write_key_file(str(hexfile), RECORDED_KEY)
    assert os.stat(hexfile).st_mode & 0o777 == 0o600
    assert read_key_file(str(hexfile)) == RECORDED_KEY
    phrase = tmp_path / "phrase.key"
    phrase.write_text("uavviewer-test\n")
    os.chmod(phrase, 0o600)
    assert read_key_file(str(phrase)) == RECORDED_KEY
    os.chmod(phrase, 0o644)
    with pytest.raises(ValueError, match="other users"):
        read_key_file(str(phrase))
    link = tmp_path / "link.key"                      # a planted symlink at the name is replaced, not followed
    victim = tmp_path / "victim"
    victim.write_text("untouched")
    link.symlink_to(victim)
    write_key_file(str(link), RECORDED_KEY)
    assert victim.read_text() == "untouched" and not link.is_symlink()


def test_timestamps_never_go_back_across_restarts(tmp_path):
    """A clock set back (or a restart within the same 10 µs tick) must not reuse a timestamp the vehicle saw."""
    path = tmp_path / "signing-timestamp"
    future = signing_time() + 3600 * 100_000           # an earlier run with a clock an hour ahead
    path.write_text(f"{future}\n")
    signing = LinkSigning(SigningConfig(key=RECORDED_KEY, timestamp_path=str(path)), "tcp:127.0.0.1:5760")
    codec = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    signing.configure_sender(codec, RECORDED_KEY)
    stamps = []
    for _ in range(3):
        signing.stamp(codec)
        frame = bytes(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3).pack(codec))
        signing.note_sent(codec)
        assert frame[2] & mavlink.MAVLINK_IFLAG_SIGNED
        assert frame[-13] == signing.link_id
        stamps.append(stamp_of(frame))
    assert stamps[0] > future and stamps == sorted(set(stamps))
    signing.save()
    assert int(path.read_text()) >= stamps[-1]
    assert os.stat(path).st_mode & 0o777 == 0o600
    again = LinkSigning(SigningConfig(key=RECORDED_KEY, timestamp_path=str(path)), "tcp:127.0.0.1:5760")
    assert again.link_id == signing.link_id            # the same link keeps its stream in the vehicle's table
    codec2 = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    again.configure_sender(codec2, RECORDED_KEY)
    assert stamp_of(bytes(mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3).pack(codec2))) > stamps[-1]


# -- the real ArduCopter's signed frames -----------------------------------------------------------------------
@pytest.fixture
def signed_replay():
    made = []

    def make(key: bytes | None, allow_unsigned: bool = False) -> Vehicle:
        v = Vehicle(VehicleConfig(connection=SIGNING + ".tlog", replay_speed=64, tlog_path=None,
                                  signing=SigningConfig(key=key, allow_unsigned=allow_unsigned, timestamp_path=None)))
        made.append(v)
        return v.start()
    yield make
    for v in made:
        v.close()


def test_the_recorded_vehicles_signed_frames_verify_with_the_recorded_key(signed_replay):
    replay = signed_replay(RECORDED_KEY)
    s = replay.wait_for(lambda s: replay.replay.finished and s.mode == "LOITER" and s.home is not None, 20)
    assert s is not None, replay.state().signing
    sig = s.signing
    assert sig.signed_accepted > 100 and sig.bad_signature == 0
    assert sig.vehicle_signs and sig.status is SigningStatus.SIGNING and sig.detail == "both ends sign"
    assert sig.unsigned_rejected > 0                 # its frames from before SETUP_SIGNING: not let in unasked


def test_with_another_key_every_signed_frame_is_dropped(signed_replay):
    replay = signed_replay(key_from_passphrase("not the key"))
    s = replay.wait_for(lambda s: replay.replay.finished and s.signing.bad_signature > 100, 20)
    assert s is not None, replay.state().signing
    assert s.signing.signed_accepted == 0 and s.signing.status is SigningStatus.MISMATCH
    assert s.mode != "LOITER" and s.home is None     # nothing it said after signing reached the state


def test_without_a_key_the_pilot_is_told_the_vehicle_requires_signing(signed_replay):
    replay = signed_replay(None)
    s = replay.wait_for(lambda s: replay.replay.finished and s.mode == "LOITER", 20)
    assert s is not None
    assert s.signing.status is SigningStatus.REQUIRED and s.signing.vehicle_signs


def test_a_forged_frame_stamped_in_the_future_does_not_silence_the_vehicle():
    """pymavlink records a stream's timestamp before checking the signature; the driver checks it first, as
    MAVLink's C library does: else one forged frame would make every genuine frame look replayed."""
    vehicle = Vehicle(VehicleConfig(connection="udpin:127.0.0.1:0", tlog_path=None,    # nobody else on its port
                                    signing=SigningConfig(key=RECORDED_KEY, timestamp_path=None))).start()
    try:
        genuine = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        genuine.signing.secret_key, genuine.signing.sign_outgoing = RECORDED_KEY, True
        genuine.signing.link_id, genuine.signing.timestamp = 0, signing_time()
        forger = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        forger.signing.secret_key, forger.signing.sign_outgoing = b"\x01" * 32, True
        forger.signing.link_id, forger.signing.timestamp = 0, signing_time() + 10 ** 12

        def heartbeat(codec, mode):
            return bytes(mavlink.MAVLink_heartbeat_message(2, 3, 1, mode, 3, 3).pack(codec))
        vehicle.ingest(heartbeat(genuine, 0))
        vehicle.ingest(heartbeat(forger, 9))
        vehicle.ingest(heartbeat(genuine, 4))
        signing = vehicle._signing
        assert (signing.signed_accepted, signing.bad_signature) == (2, 1)
        assert vehicle.wait_for(lambda s: s.mode == "GUIDED", 5)
    finally:
        vehicle.close()


def test_nothing_is_kept_on_disk_for_a_link_that_never_signed(sim, vehicle_factory, tmp_path):
    path = tmp_path / "signing-timestamp"
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", signing=SigningConfig(timestamp_path=str(path)))
    assert vehicle.wait_for(lambda s: s.connected, 10)
    vehicle.close()
    assert not path.exists()
