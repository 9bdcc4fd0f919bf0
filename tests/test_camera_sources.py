"""Video sources without Qt: files, MPEG-TS over UDP, RTP/SDP, the Solo link, recording, the simulated camera."""
from __future__ import annotations

import math
import os
import re
import socket
import stat
import tempfile
import threading

import cv2
import numpy as np
import pytest

from camera_media import COLOURS, UdpSender, frames_and_rate, free_udp_port, wait, write_clip, write_ts
from driver.camera import VideoRecorder, open_source, save_snapshot
from driver.camera.record import MEASURE_FRAMES, MEASURE_S, measured_fps
from driver.camera.sim import SKY, SimulatedCamera
from driver.camera.solo import SoloSource, write_sdp
from driver.camera.source import Frame
from driver.vehicle.state import Attitude, LocalPosition, VehicleState


def nearest_colour(rgb) -> tuple[int, int, int]:
    return min(COLOURS, key=lambda c: sum((int(a) - b) ** 2 for a, b in zip(rgb, c)))


def close_to(rgb, colour, tol=40) -> bool:
    return all(abs(int(a) - b) <= tol for a, b in zip(rgb, colour))


class Collector:
    """Every frame a source delivers, as it is delivered (listener on the capture thread)."""

    def __init__(self, source):
        self.frames = []
        self._lock = threading.Lock()
        source.add_listener(self._add)

    def _add(self, frame):
        with self._lock:
            self.frames.append(frame)

    def colours(self):
        with self._lock:
            centre = [tuple(f.image[f.height // 2, f.width // 2]) for f in self.frames]
        out = []
        for rgb in centre:
            c = nearest_colour(rgb)
            if not out or out[-1] != c:
                out.append(c)
        return out


@pytest.fixture
def sources():
    opened = []

    def make(uri, **kw):
        s = open_source(uri, **kw)
        opened.append(s)
        return s

    yield make
    for s in opened:
        s.close(wait=3)


def test_file_delivers_every_colour_in_order_then_ends(tmp_path, sources):
    clip = write_clip(str(tmp_path / "colours.mp4"), repeat=3)
    src = sources(clip, start=False)
    got = Collector(src)
    src.start()
    wait(lambda: src.status().state == "ended", what="end of file")
    assert got.colours() == COLOURS
    f = got.frames[0]
    assert f.image.shape == (240, 320, 3) and f.image.dtype == np.uint8
    assert close_to(f.image[120, 160], (255, 0, 0)), "red must arrive as R,G,B"
    assert [f.index for f in got.frames] == list(range(1, len(COLOURS) * 3 + 1))
    assert "end of file" in src.status().reason


def test_looping_file_starts_again(tmp_path, sources):
    clip = write_clip(str(tmp_path / "short.mp4"), COLOURS[:2], repeat=2, fps=60)
    src = sources(clip + "?loop=1")
    wait(lambda: src.status().frames > 10, what="frames beyond the file's length")
    assert src.status().live


def test_missing_file_says_so_and_retries(tmp_path, sources):
    path = tmp_path / "later.mp4"
    src = sources(str(path))
    wait(lambda: src.status().state == "retrying", what="retrying")
    assert "no such file" in src.status().reason
    write_clip(str(path), repeat=2)
    wait(lambda: src.latest() is not None, what="the file once it exists")


def test_an_unknown_scheme_says_it_is_unsupported(sources):
    src = sources("bogus://camera")
    wait(lambda: src.status().state == "retrying", what="retrying")
    assert "unsupported camera source bogus://" in src.status().reason and "rtsp://" in src.status().reason


QUIET_RETRIES = """
import sys, time
from driver.camera import open_source
sources = [open_source(uri, timeout_ms=300) for uri in sys.argv[1:]]
deadline = time.monotonic() + 10
while time.monotonic() < deadline and not all(s.status().attempts >= 3 for s in sources):
    time.sleep(0.05)
for s in sources:
    print(s.status().reason)
"""


def test_missing_camera_says_no_such_device_and_retries_quietly():
    """A webcam that is not plugged in, or a stream nobody sends: the reason is on screen, and retrying
    does not fill the terminal with OpenCV's own warnings."""
    import os
    import subprocess
    import sys
    missing = next(n for n in range(90, 200) if not os.path.exists(f"/dev/video{n}"))
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env = {k: v for k, v in os.environ.items() if k != "OPENCV_LOG_LEVEL"}
    run = subprocess.run([sys.executable, "-c", QUIET_RETRIES, f"/dev/video{missing}",
                          f"udp://127.0.0.1:{free_udp_port()}"], cwd=root, env=env, capture_output=True,
                         text=True, timeout=30)
    device, stream = run.stdout.splitlines()
    assert device.startswith(f"no such device: /dev/video{missing}")
    assert stream.startswith("cannot open udp://")
    assert "WARN" not in run.stderr and "ERROR" not in run.stderr, run.stderr


def test_mpegts_over_udp(tmp_path, sources):
    """Read slower than the stream (nobody takes a frame for a while), the source hands over the newest one:
    each new frame replaced the last untaken (counted as dropped), none queued."""
    data = write_ts(str(tmp_path / "stream.ts"))
    port = free_udp_port()
    with UdpSender(data, port):
        src = sources(f"udp://127.0.0.1:{port}", timeout_ms=2000)
        wait(lambda: src.status().frames >= 10, what="UDP frames")
        before = src.status()
        frame = src.latest()
        after = src.status()
        src.close(wait=3)
        assert frame.image.shape == (240, 320, 3)
        assert any(close_to(frame.image[120, 160], c) for c in COLOURS)
    assert before.frames <= frame.index <= after.frames
    assert before.dropped >= before.frames - 1          # every frame but the newest was replaced untaken


def test_live_streams_open_with_the_low_latency_options_and_files_do_not(tmp_path):
    """Network streams, SDP and the Solo are opened for latency (FFmpeg's options, one decoder thread) by
    default; a file, paced at its own rate, keeps OpenCV's defaults; low_latency=False is the old opening."""
    from driver.camera.solo import RTP_FFMPEG_OPTIONS
    from driver.camera.source import LOW_LATENCY_OPTIONS
    clip = write_clip(str(tmp_path / "clip.mp4"))
    sdp = write_sdp(str(tmp_path / "stream.sdp"), free_udp_port(), "H264/90000", 96)
    for uri in ("udp://127.0.0.1:5600", "rtsp://127.0.0.1:8554/live", "rtp://127.0.0.1:5000", sdp, "solo"):
        src = open_source(uri, start=False)
        assert src.low_latency and LOW_LATENCY_OPTIONS in src.ffmpeg_options, uri
        assert "nobuffer" in src.ffmpeg_options and "low_delay" in src.ffmpeg_options
    for uri in (sdp, "solo"):                       # what RTP needs stays
        assert RTP_FFMPEG_OPTIONS in open_source(uri, start=False).ffmpeg_options
    assert open_source(sdp, start=False, low_latency=False).ffmpeg_options == RTP_FFMPEG_OPTIONS
    rtsp = open_source("rtsp://127.0.0.1:8554/live", start=False)   # TCP first (as OpenCV's default), then
    transports = []                                                  # FFmpeg's own choice (UDP first), in turn
    for rtsp._attempts in (1, 2, 3):
        transports.append("rtsp_transport;tcp" in rtsp._options_now())
    assert transports == [True, False, True]
    plain = open_source("udp://127.0.0.1:5600", start=False, low_latency=False)
    assert not plain.low_latency and plain.ffmpeg_options is None
    file = open_source(clip, start=False)
    assert not file.low_latency and file.ffmpeg_options is None


def test_stream_that_stops_reports_and_comes_back(tmp_path, sources):
    data = write_ts(str(tmp_path / "stream.ts"))
    port = free_udp_port()
    src = sources(f"udp://127.0.0.1:{port}", timeout_ms=700)
    with UdpSender(data, port):
        wait(lambda: src.status().live and src.latest() is not None, what="first video")
    wait(lambda: src.status().state == "retrying", what="the loss noticed")
    assert src.status().reason
    before = src.status().frames
    with UdpSender(data, port):
        wait(lambda: src.status().live and src.status().frames > before, what="video again")


def test_stream_that_goes_quiet_is_stalled_then_live_again(tmp_path, sources):
    """The sender stops with its socket open: the capture hangs in a read (30 s timeout here),
    yet the source says "stalled" as soon as no frame has come for the stall time."""
    data = write_ts(str(tmp_path / "stream.ts"))
    port = free_udp_port()
    src = sources(f"udp://127.0.0.1:{port}", timeout_ms=30000, stall_s=0.5)
    with UdpSender(data, port) as sender:
        wait(lambda: src.status().live and src.status().frames >= 5, what="video")
        sender.pause()
        stalled = wait(lambda: (s := src.status()).state == "stalled" and s, what="the stall noticed")
        assert stalled.reason.startswith("no frame for ") and not stalled.live
        assert stalled.attempts == 1                      # still the first connection: the read has not timed out
        sender.resume()
        wait(lambda: src.status().live and src.status().frames > stalled.frames + 1, what="video again")
        src.close(wait=3)                                 # while frames still come: the read returns


def test_rtp_described_by_sdp(tmp_path, sources):
    data = write_ts(str(tmp_path / "stream.ts"))
    port = free_udp_port()
    sdp = write_sdp(str(tmp_path / "stream.sdp"), port, "MP2T/90000", 33)
    with UdpSender(data, port, rtp=True):
        src = sources(sdp, timeout_ms=2000)
        wait(lambda: src.status().frames >= 10, what="RTP frames")
        src.close(wait=3)
        assert any(close_to(src.latest().image[120, 160], c) for c in COLOURS)


class FakeController:
    """The Solo controller's part: sends RTP video to UDP ``video_port`` while a TCP client holds 5502 open."""

    def __init__(self, data: bytes, video_port: int):
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.data, self.video_port = data, video_port
        self.clients = 0
        self.client: socket.socket | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self):
        self.server.settimeout(0.2)
        while not self._stop.is_set():
            try:
                client, _ = self.server.accept()
            except socket.timeout:
                continue
            self.clients += 1
            self.client = client
            with UdpSender(self.data, self.video_port, rtp=True):
                client.settimeout(0.2)
                while not self._stop.is_set() and self.client is client:
                    try:
                        if not client.recv(10):
                            break
                    except socket.timeout:
                        continue
                    except OSError:
                        break

    def drop_client(self):
        client, self.client = self.client, None
        client.close()

    def close(self):
        self._stop.set()
        self._thread.join(3)
        self.server.close()


def test_solo_holds_the_link_open_and_reconnects(tmp_path):
    data = write_ts(str(tmp_path / "solo.ts"))
    video_port = free_udp_port()
    controller = FakeController(data, video_port)
    src = SoloSource("127.0.0.1", controller.port, video_port, str(tmp_path / "solo.sdp"), "MP2T/90000", 33,
                     timeout_ms=1500).start()
    try:
        wait(lambda: src.status().frames >= 5, what="Solo video")
        assert "m=video %d RTP/AVP 33" % video_port in (tmp_path / "solo.sdp").read_text()
        assert controller.clients == 1
        controller.drop_client()
        wait(lambda: controller.clients == 2 and src.link.connected, what="the link reopened")
        before = src.status().frames
        wait(lambda: src.status().frames > before + 5, what="video after the reconnection")
    finally:
        src.close(wait=3)
        controller.close()


def test_solo_without_controller_explains(tmp_path):
    with socket.socket() as s:                # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    src = SoloSource("127.0.0.1", port, free_udp_port(), str(tmp_path / "solo.sdp"), timeout_ms=500).start()
    try:
        wait(lambda: src.status().state == "retrying", what="failure")
        assert "unreachable" in src.status().reason
    finally:
        src.close(wait=3)


def unreachable_port() -> int:
    with socket.socket() as s:                # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_solo_sdp_is_private_unpredictable_and_gone_on_close(tmp_path, monkeypatch):
    """The SDP file is in our private runtime directory under a random name, 0600, never at the old fixed
    name in /tmp; the video flows through it, and it is removed when the source closes."""
    run = tmp_path / "run"
    run.mkdir()
    os.chmod(run, 0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(run))
    data = write_ts(str(tmp_path / "solo.ts"))
    video_port = free_udp_port()
    fixed = os.path.join(tempfile.gettempdir(), f"uavviewer-solo-{video_port}.sdp")
    controller = FakeController(data, video_port)
    src = SoloSource("127.0.0.1", controller.port, video_port, encoding="MP2T/90000", payload=33,
                     timeout_ms=1500).start()
    try:
        wait(lambda: src.status().frames >= 5, what="Solo video")
        path = src.sdp_path
        assert os.path.dirname(path) == str(run / "uavviewer")
        assert re.fullmatch(rf"solo-{video_port}-[0-9a-f]{{16}}\.sdp", os.path.basename(path))
        assert stat.S_IMODE(os.lstat(path).st_mode) == 0o600 and stat.S_IMODE(os.lstat(run / "uavviewer").st_mode) == 0o700
        with open(path) as f:
            assert f"m=video {video_port} RTP/AVP 33" in f.read()
        assert not os.path.lexists(fixed)
    finally:
        src.close(wait=3)
        controller.close()
    assert src.closed
    assert not os.path.lexists(path) and os.listdir(run / "uavviewer") == []


def test_solo_sdp_at_a_given_path_replaces_a_planted_link_and_stays(tmp_path):
    victim = tmp_path / "victim"
    victim.write_text("precious")
    os.symlink(victim, tmp_path / "solo.sdp")
    port = free_udp_port()
    src = SoloSource("127.0.0.1", unreachable_port(), port, str(tmp_path / "solo.sdp"), timeout_ms=500).start()
    try:
        wait(lambda: src.status().state == "retrying", what="failure")          # after the SDP was written
    finally:
        src.close(wait=3)
    assert victim.read_text() == "precious"
    assert not os.path.islink(tmp_path / "solo.sdp")
    assert f"m=video {port} RTP/AVP 96" in (tmp_path / "solo.sdp").read_text()   # the caller's file: it stays


def test_snapshot_and_recording_are_readable(tmp_path, sources):
    clip = write_clip(str(tmp_path / "in.mp4"), repeat=5)
    src = sources(clip)
    frame = wait(src.latest, what="a frame")
    png = save_snapshot(frame, str(tmp_path / "media"))
    img = cv2.imread(png)
    assert img is not None and img.shape == frame.image.shape
    assert np.array_equal(cv2.cvtColor(img, cv2.COLOR_BGR2RGB), frame.image)   # PNG is lossless

    recorder = VideoRecorder.in_folder(str(tmp_path / "media"), "video", fps=30)
    src.close(wait=3)
    src = sources(clip, start=False)
    src.add_listener(recorder.push)
    src.start()
    wait(lambda: src.status().state == "ended", what="end of file")
    path = recorder.stop()
    assert path.endswith(".mp4") and recorder.frames_written == len(COLOURS) * 5
    cap = cv2.VideoCapture(path)
    colours = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        c = nearest_colour(bgr[120, 160][::-1])
        if not colours or colours[-1] != c:
            colours.append(c)
    cap.release()
    assert colours == COLOURS


def made_frames(rate: float, count: int, size=(320, 240)) -> list[Frame]:
    """``count`` frames of a camera filming at ``rate`` frames/s, decode times exactly 1/rate apart (no clock
    involved), cycling through COLOURS."""
    frames = []
    for i in range(count):
        image = np.empty((size[1], size[0], 3), np.uint8)
        image[:] = COLOURS[i % len(COLOURS)]
        frames.append(Frame(image, i + 1, 1000.0 + i / rate, 1.7e9 + i / rate))
    return frames


def file_colours(path: str) -> list[tuple[int, int, int]]:
    """The colour of each frame of a video file, in order."""
    cap = cv2.VideoCapture(path)
    colours = []
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        colours.append(nearest_colour(bgr[bgr.shape[0] // 2, bgr.shape[1] // 2][::-1]))
    cap.release()
    return colours


@pytest.mark.parametrize("rate, count, declared", [
    (10.0, 25, 10.0),          # more than the measuring second
    (12.5, 25, 12.5),          # not a whole rate: kept as it is
    (29.97, 40, 30.0),         # NTSC: the whole rate it stands for
    (10.0, 5, 10.0),           # stopped within the first second: measured from what there is
])
def test_recording_declares_the_rate_the_frames_were_decoded_at(tmp_path, rate, count, declared):
    """Nobody tells the recorder the rate: the file declares the one the frames' own decode times give, and holds
    every frame handed to it, in order. (The decode times are made here, so no clock and no load matter.)"""
    frames = made_frames(rate, count)
    recorder = VideoRecorder(str(tmp_path / "rec.mp4"), max_queue=count)     # room for all: nothing dropped
    for frame in frames:
        recorder.push(frame)
    path = recorder.stop()
    assert recorder.error == "" and recorder.frames_dropped == 0
    n, fps = frames_and_rate(path)
    assert fps == pytest.approx(declared, abs=1e-3)
    assert n == recorder.frames_written == count
    assert file_colours(path) == [COLOURS[i % len(COLOURS)] for i in range(count)]


def rate_of(delivered: list[Frame]) -> float:
    """The rate ``delivered`` came at by their own decode times, over the span the recorder measures (its first
    second of frames, or MEASURE_FRAMES of them, or all there are), in the recorder's rounding."""
    window = []
    for frame in delivered:
        window.append(frame)
        if len(window) >= MEASURE_FRAMES or frame.decoded - delivered[0].decoded >= MEASURE_S:
            break
    return measured_fps(window)


def test_recording_from_a_camera_holds_each_delivered_frame_at_its_rate(tmp_path, sources):
    """A file camera filmed at 10 frames/s, recorded whole: the file holds exactly the frames the camera delivered,
    and declares the rate they came at (counted from them, never from how long the test took)."""
    clip = write_clip(str(tmp_path / "ten.mp4"), COLOURS, repeat=2, fps=10)      # 12 frames, 1.2 s
    src = sources(clip, start=False)
    recorder = VideoRecorder(str(tmp_path / "rec.mp4"), max_queue=100)         # room for all: nothing dropped
    delivered: list[Frame] = []

    def record(frame):
        delivered.append(frame)
        recorder.push(frame)
    src.add_listener(record)
    src.start()
    wait(lambda: src.status().state == "ended", what="end of file")
    n, fps = frames_and_rate(recorder.stop())
    assert len(delivered) == len(COLOURS) * 2 and recorder.frames_dropped == 0
    assert n == recorder.frames_written == len(delivered)
    assert fps == pytest.approx(rate_of(delivered), abs=1e-3)
    assert file_colours(recorder.path) == [c for c in COLOURS for _ in range(2)]


def horizon_rows(image: np.ndarray, columns=(100, 540)) -> list[int]:
    """For each column, the first row from the top that is not sky."""
    rows = []
    for x in columns:
        not_sky = np.any(np.abs(image[:, x].astype(int) - SKY) > 12, axis=1)
        rows.append(int(np.argmax(not_sky)))
    return rows


def test_simulated_horizon_follows_roll_and_pitch():
    cam = SimulatedCamera(640, 480)
    level = cam.render(VehicleState(local=LocalPosition(0, 0, -5)))
    left, right = horizon_rows(level)
    assert abs(left - right) <= 1
    rolled = cam.render(VehicleState(attitude=Attitude(roll=math.radians(20)), local=LocalPosition(0, 0, -5)))
    left_r, right_r = horizon_rows(rolled)
    angle = math.degrees(math.atan2(left_r - right_r, 440))
    assert angle == pytest.approx(20, abs=2)          # right roll: the horizon rises on the right
    nose_down = cam.render(VehicleState(attitude=Attitude(pitch=math.radians(-10)), local=LocalPosition(0, 0, -5)))
    assert horizon_rows(nose_down)[0] < left - 20     # nose down: more ground, the horizon moves up


def test_simulated_ground_moves_when_flying():
    cam = SimulatedCamera(320, 240)
    a = cam.render(VehicleState(local=LocalPosition(0, 0, -5)))
    b = cam.render(VehicleState(local=LocalPosition(2.5, 0, -5)))
    c = cam.render(VehicleState(local=LocalPosition(0, 0, -5)))
    assert np.array_equal(a, c)
    assert np.count_nonzero(np.any(a != b, axis=2)) > 500


def test_sim_source_without_state_is_refused():
    with pytest.raises(ValueError):
        open_source("sim")
