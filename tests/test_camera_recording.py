"""The gimbal recording (ArduCopter 4.6.3, a servo mount: tests/data/recordings/arducopter-4.6-sitl-gimbal)
replayed through the driver's telemetry path, checked against the ground station's own timeline."""
from __future__ import annotations

import re

from recordings import GIMBAL, played  # noqa: E402
from test_driver_recordings import not_finite


def recorded_attitudes() -> list[tuple[float, float, int]]:
    """(pitch, yaw, flags) of each GIMBAL_DEVICE_ATTITUDE_STATUS change the timeline lists."""
    with open(GIMBAL + ".events.txt", encoding="utf-8") as f:
        return [(float(p), float(y), int(fl)) for p, y, fl in re.findall(
            r"RECV GIMBAL_DEVICE_ATTITUDE_STATUS pitch (\S+) yaw (\S+) flags (\d+)", f.read())]


def test_gimbal_recording_through_the_telemetry_path():
    timeline = recorded_attitudes()
    assert timeline[0] == (-90.0, -0.0, 44) and timeline[-1] == (0.0, 0.0, 45)
    assert (-90.0, 180.0, 44) in timeline            # Euler angles' gimbal lock, straight down
    seen: list[tuple[float, float | None, bool]] = []
    final = None
    for _t, _vehicle, s in played(GIMBAL + ".tlog"):     # every snapshot the pilot could have seen
        g = s.gimbal
        assert g.known or g.pitch_deg is None                              # unknown until the vehicle says
        if g.known and (not seen or seen[-1] != (g.pitch_deg, g.yaw_deg, g.retracted)):
            seen.append((g.pitch_deg, g.yaw_deg, g.retracted))
        final = s
    pitches = [p for p, _, _ in seen]
    # every plateau of the timeline, in order: RC -90, DO_MOUNT_CONTROL -45, the manager's -90, the rate up,
    # level, back to RC's -90 after DO_SET_ROI_NONE, retracted at 0
    plateaus = [-90.0, -45.0, -90.0, 0.0, -90.0, 0.0]
    it = iter(pitches)
    assert all(any(abs(p - want) < 0.1 for p in it) for want in plateaus), pitches
    rising = [p for p in pitches if -89.0 < p < -30.0 and abs(p + 45.0) > 0.1]
    assert len(rising) >= 3 and rising == sorted(rising), rising     # the +20 deg/s rate, reported as it went
    assert -36.0 < rising[-1] < -30.0, rising     # the timeline lists -35.2 at 26.1 s; level came at 26.4 s
    # straight down there is no yaw: never the 180 deg the Euler reading gives. The recorded mount does report
    # +6.9 deg at times (vehicle frame): north, from a nose at 353 deg; what it says is shown, nothing else
    assert all(yaw is None or abs(yaw) < 7.5 for _, yaw, _ in seen), seen
    assert any(yaw is not None and abs(yaw - 6.9) < 0.1 for _, yaw, _ in seen), seen
    assert [r for _, _, r in seen].count(True) >= 1 and seen[-1] == (0.0, 0.0, True)
    assert final is not None
    assert final.gimbal.source == "GIMBAL_DEVICE_ATTITUDE_STATUS" and final.gimbal.component == 1
    assert list(not_finite(final)) == []                              # NaN angular velocities stayed out
    assert final.camera.photos == 0          # DO_DIGICAM_CONTROL was ACCEPTED, but no camera said a thing
