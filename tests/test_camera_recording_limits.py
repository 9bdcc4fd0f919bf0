"""Recordings and snapshots on real files: never through a planted link, never over a file, bounded in
size and place when a client asks the server to record (ArDroneExtra.recordOnUsb over Ice)."""
from __future__ import annotations

import logging
import os
import re
import stat

import cv2
import numpy as np
import pytest

from camera_media import frames_and_rate, wait
from driver.camera import VideoRecorder, save_snapshot
from driver.camera.record import MIN_CAP_BYTES, WORK_DIR_PREFIX, recordings_size
from driver.camera.source import Frame

MB = 1_000_000
RECORDING = re.compile(r"(?P<prefix>.+)-\d{8}-\d{6}-\d{3}(-\d+)?\.mp4")


def write_noise_clip(path: str, frames: int = 30, size=(640, 480), fps: float = 30.0) -> str:
    """Random pictures: they stay large once re-encoded, so a recording of them grows fast (~100 kB a frame)."""
    writer = cv2.VideoWriter(path, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
    assert writer.isOpened()
    rng = np.random.default_rng(7)
    for _ in range(frames):
        writer.write(rng.integers(0, 256, (size[1], size[0], 3), dtype=np.uint8))
    writer.release()
    return path


def made_frame(index: int, size=(320, 240), wall_time: float = 1.7e9) -> Frame:
    image = np.full((size[1], size[0], 3), (index * 40) % 256, np.uint8)
    return Frame(image, index, 1000.0 + index / 30, wall_time + index / 30)


def victim(tmp_path):
    path = tmp_path / "victim"
    path.write_bytes(b"precious\n")
    return path


def listing(folder) -> list[str]:
    return sorted(os.listdir(folder))


# -- files made safely ---------------------------------------------------------------------------------------

def test_recorder_refuses_a_planted_link_or_an_existing_file(tmp_path):
    target = victim(tmp_path)
    os.symlink(target, tmp_path / "rec.mp4")
    (tmp_path / "old.mp4").write_bytes(b"earlier flight")
    for name in ("rec.mp4", "old.mp4"):
        with pytest.raises(FileExistsError):
            VideoRecorder(str(tmp_path / name))
    assert target.read_bytes() == b"precious\n" and (tmp_path / "old.mp4").read_bytes() == b"earlier flight"
    assert listing(tmp_path) == ["old.mp4", "rec.mp4", "victim"]          # no work directory left behind


def test_recording_in_progress_is_encoded_where_only_we_can_enter(tmp_path):
    """The name is reserved (empty, new) at once; the encoder writes in a 0700 directory of ours; the finished
    file takes the reserved name and the work directory goes."""
    folder = tmp_path / "media"
    folder.mkdir()
    recorder = VideoRecorder(str(folder / "rec.mp4"), fps=30, max_queue=100)
    reserved = os.lstat(folder / "rec.mp4")
    assert stat.S_ISREG(reserved.st_mode) and reserved.st_size == 0
    for i in range(1, 11):
        recorder.push(made_frame(i))
    wait(lambda: recorder.frames_written >= 1, what="the encoder writing")
    work = [n for n in os.listdir(folder) if n.startswith(WORK_DIR_PREFIX)]
    assert len(work) == 1
    assert stat.S_IMODE(os.lstat(folder / work[0]).st_mode) == 0o700 and not os.path.islink(folder / work[0])
    assert os.listdir(folder / work[0]) == ["rec.mp4"]
    assert recorder.stop() == str(folder / "rec.mp4") and recorder.wait(10)
    assert listing(folder) == ["rec.mp4"]
    assert frames_and_rate(str(folder / "rec.mp4"))[0] == recorder.frames_written == 10
    assert stat.S_IMODE(os.lstat(folder / "rec.mp4").st_mode) == 0o644           # media, for sharing


def test_recording_without_frames_gives_its_name_back(tmp_path):
    recorder = VideoRecorder(str(tmp_path / "rec.mp4"))
    recorder.stop()
    assert recorder.wait(10) and listing(tmp_path) == []


def test_snapshot_takes_the_next_name_rather_than_a_planted_link(tmp_path):
    frame = made_frame(1)
    first = save_snapshot(frame, str(tmp_path))                    # the name this frame gets
    os.unlink(first)
    target = victim(tmp_path)
    os.symlink(target, first)
    path = save_snapshot(frame, str(tmp_path))
    assert path == first[:-len(".png")] + "-2.png"
    assert target.read_bytes() == b"precious\n" and os.path.islink(first)
    assert np.array_equal(cv2.cvtColor(cv2.imread(path), cv2.COLOR_BGR2RGB), frame.image)
    assert save_snapshot(frame, str(tmp_path)) == first[:-len(".png")] + "-3.png"    # and never over one


# -- recordOnUsb over Ice, bounded ---------------------------------------------------------------------------

Ice = pytest.importorskip("Ice", reason="zeroc-ice is not installed")

from driver.ice import load_slice  # noqa: E402
from driver.ice.camera import CameraI  # noqa: E402
from driver.ice.servants import ArDroneExtraI, ServerSettings  # noqa: E402

jderobot, _ = load_slice()


@pytest.fixture
def extra_for():
    """Serve a camera servant and its ArDroneExtra on 127.0.0.1; returns the Extra proxy for a servant."""
    com = Ice.initialize()
    adapter = com.createObjectAdapterWithEndpoints("RecordTest", "tcp -h 127.0.0.1 -p 0")
    adapter.activate()
    cameras = []

    def make(servant: CameraI):
        cameras.append(servant)
        proxy = adapter.add(ArDroneExtraI(None, ServerSettings(), servant), Ice.stringToIdentity(f"Extra{len(cameras)}"))
        return jderobot.ArDroneExtraPrx.checkedCast(proxy)

    yield make
    com.destroy()
    for c in cameras:
        c.close()


def test_record_on_usb_stops_at_its_cap_inside_the_record_dir(tmp_path, extra_for, caplog):
    """A client starts a recording of large frames and never stops it: the file stops growing before
    RecordMaxMB, is finished and playable, and sits in RecordDir under a name of ours, even with a camera Name
    that looks like a path."""
    clip = write_noise_clip(str(tmp_path / "noise.mp4"))
    rec = tmp_path / "rec"
    servant = CameraI({"Uri": clip + "?loop=1", "Name": "../../escape/cam", "RecordDir": str(rec),
                       "RecordMaxMB": "3"})
    extra = extra_for(servant)
    wait(servant.source.latest, what="the first frame")
    caplog.set_level(logging.WARNING)
    extra.recordOnUsb(True)
    recorder = servant._recorder
    assert recorder is not None and recorder.max_bytes == 3 * MB
    assert recorder.wait(30), "the recording never stopped by itself"
    assert recorder.full and recorder.error == "" and servant._recorder is None
    assert servant._cameras._listeners == []                             # it no longer takes frames
    delivered = servant.source.status().frames
    wait(lambda: servant.source.status().frames > delivered, what="the camera going on")

    assert listing(tmp_path) == ["noise.mp4", "rec"]                     # nothing written outside RecordDir
    names = listing(rec)
    assert len(names) == 1, names                                        # no work directory left
    path = rec / names[0]
    assert recorder.path == str(path) and os.path.dirname(os.path.realpath(path)) == os.path.realpath(rec)
    assert RECORDING.fullmatch(names[0]).group("prefix") == "escape-cam"
    assert 0 < os.path.getsize(path) <= 3 * MB
    frames, _ = frames_and_rate(str(path))
    assert frames == recorder.frames_written > 0                       # finished: every frame written plays
    assert any("size cap" in r.getMessage() for r in caplog.records if r.levelno == logging.WARNING)

    extra.recordOnUsb(False)                                             # already stopped: nothing to do
    assert listing(rec) == names


def test_record_dir_cap_shortens_then_refuses_recordings(tmp_path, extra_for, caplog):
    """Our recordings in RecordDir never hold more than RecordDirMaxMB: a recording gets only the room left, and
    once too little is left, recordOnUsb(true) is refused with a warning (nothing is deleted). Files not named
    as ours do not count."""
    clip = write_noise_clip(str(tmp_path / "noise.mp4"))
    rec = tmp_path / "rec"
    rec.mkdir()
    earlier = rec / "cam-20240101-120000-000.mp4"
    with open(earlier, "wb") as f:
        f.truncate(int(4.5 * MB))                                        # an earlier recording (sparse)
    with open(rec / "notes.bin", "wb") as f:
        f.truncate(50 * MB)                                              # not ours: not counted
    servant = CameraI({"Uri": clip + "?loop=1", "Name": "cam", "RecordDir": str(rec),
                       "RecordMaxMB": "100", "RecordDirMaxMB": "8"})
    extra = extra_for(servant)
    wait(servant.source.latest, what="the first frame")
    caplog.set_level(logging.WARNING)

    extra.recordOnUsb(True)
    recorder = servant._recorder
    assert recorder is not None and recorder.max_bytes == int(3.5 * MB)  # the room left, not RecordMaxMB
    assert recorder.wait(30) and recorder.full
    assert os.path.getsize(recorder.path) <= 3.5 * MB
    assert recordings_size(str(rec)) <= 8 * MB
    assert 8 * MB - recordings_size(str(rec)) < MIN_CAP_BYTES           # too little left for another

    before = listing(rec)
    caplog.clear()
    extra.recordOnUsb(True)
    assert servant._recorder is None and listing(rec) == before         # refused: no file, none deleted
    assert os.path.getsize(earlier) == int(4.5 * MB)
    assert any("refused" in r.getMessage() and "RecordDirMaxMB" in r.getMessage()
               for r in caplog.records if r.levelno == logging.WARNING)


def test_record_caps_below_a_usable_size_are_raised(tmp_path):
    servant = CameraI({"Uri": str(tmp_path / "none.mp4"), "RecordDir": str(tmp_path), "RecordMaxMB": "0.5",
                       "RecordDirMaxMB": "lots"})
    try:
        assert servant._record_max == MIN_CAP_BYTES and servant._record_dir_max == 20000 * MB
    finally:
        servant.close()

