"""The jderobot::Camera servant over real Ice sockets, and the viewer's Ice camera source."""
from __future__ import annotations

import math
import os
import time

import cv2
import numpy as np
import pytest

Ice = pytest.importorskip("Ice", reason="zeroc-ice is not installed")

from camera_media import COLOURS, UdpSender, free_udp_port, wait, write_clip, write_ts  # noqa: E402
import driver.ice.camera_source  # noqa: F401  (registers ice: cameras)
from driver.camera import open_source  # noqa: E402
from driver.camera.sim import SimulatedCamera  # noqa: E402
from driver.ice import load_slice  # noqa: E402
from driver.ice.camera import CameraI  # noqa: E402
from driver.ice.servants import ArDroneExtraI, ServerSettings  # noqa: E402
from driver.vehicle.state import Attitude, LocalPosition, VehicleState  # noqa: E402

jderobot, _ = load_slice()

STILL = VehicleState(attitude=Attitude(roll=math.radians(12), pitch=math.radians(-4), yaw=0.7),
                     local=LocalPosition(3.0, -2.0, -6.0))


class StillVehicle:
    """A vehicle hovering motionless: the simulated camera's picture is then known exactly."""

    def state(self) -> VehicleState:
        return STILL


@pytest.fixture
def serve():
    """Serve servants on an ephemeral 127.0.0.1 port; returns their proxies' strings."""
    init = Ice.InitializationData()
    init.properties = Ice.createProperties()
    init.properties.setProperty("Ice.MessageSizeMax", "65536")
    com = Ice.initialize(init)
    adapter = com.createObjectAdapterWithEndpoints("CameraTest", "tcp -h 127.0.0.1 -p 0")
    adapter.activate()
    cameras = []

    def add(servant, identity):
        if isinstance(servant, CameraI):
            cameras.append(servant)
        return com.proxyToString(adapter.add(servant, Ice.stringToIdentity(identity)))

    add.communicator = com
    yield add
    com.destroy()
    for c in cameras:
        c.close()


def camera_proxy(serve, proxy):
    return jderobot.CameraPrx.checkedCast(serve.communicator.stringToProxy(proxy))


def test_round_trip_preserves_pixels_exactly(serve):
    servant = CameraI({"Uri": "sim", "Name": "sim"}, StillVehicle())
    proxy = serve(servant, "Camera")
    expected = SimulatedCamera(640, 480).render(STILL)
    src = open_source("ice:" + proxy)
    try:
        frame = wait(src.latest, what="an image over Ice")
    finally:
        src.close(wait=3)
    assert frame.image.shape == (480, 640, 3)
    assert np.array_equal(frame.image, expected)

    cam = camera_proxy(serve, proxy)
    data = cam.getImageData("RGB8")
    assert (data.description.width, data.description.height, data.description.format) == (640, 480, "RGB8")
    assert data.description.size == len(data.pixelData) == 640 * 480 * 3
    assert abs(data.timeStamp.seconds + data.timeStamp.useconds / 1e6 - time.time()) < 5
    gray = cam.getImageData("GRAY8")
    assert np.array_equal(np.frombuffer(gray.pixelData, np.uint8).reshape(480, 640),
                          cv2.cvtColor(expected, cv2.COLOR_RGB2GRAY))
    desc = cam.getCameraDescription()
    assert desc.name == "sim" and "simulated" in desc.shortDescription and desc.u0 == 320.0
    d = cam.getImageDescription()
    assert (d.width, d.height, d.size, d.format) == (640, 480, 640 * 480 * 3, "RGB8")


class CountingCamera(CameraI):
    """Counts the getImageData calls that reach the server."""

    calls = 0

    def getImageData(self, format, current=None):
        self.calls += 1
        return super().getImageData(format, current)


def test_ice_source_asks_about_once_per_new_frame(serve):
    """Each ask that gets the same image again sends the whole image again: the client paces its asks
    to the camera's frame rate (30 frames/s here) rather than asking as fast as it can."""
    servant = CountingCamera({"Uri": "sim"}, StillVehicle())
    src = open_source("ice:" + serve(servant, "Camera"))
    try:
        wait(lambda: src.status().frames >= 10, what="video over Ice")
        calls, frames = servant.calls, src.status().frames
        wait(lambda: src.status().frames >= frames + 30, what="30 more frames")
        calls, frames = servant.calls - calls, src.status().frames - frames
    finally:
        src.close(wait=3)
    assert calls < 2 * frames, f"{calls} asks for {frames} new frames"


def test_description_gives_the_size_and_only_a_uri_others_can_watch(serve):
    sim = camera_proxy(serve, serve(CameraI({"Uri": "sim"}, StillVehicle()), "Sim"))
    wait(lambda: "640×480" in sim.getCameraDescription().shortDescription, what="the size once a frame exists")
    port = free_udp_port()
    listening = camera_proxy(serve, serve(CameraI({"Uri": f"udp://0.0.0.0:{port}", "TimeoutMs": "500"}), "Udp"))
    assert listening.getCameraDescription().streamingUri == ""    # our own receive port: nobody else can read it
    assert listening.startCameraStreaming() == ""
    rtsp = camera_proxy(serve, serve(CameraI({"Uri": "rtsp://127.0.0.1:1/cam", "TimeoutMs": "500"}), "Rtsp"))
    assert rtsp.getCameraDescription().streamingUri == "rtsp://127.0.0.1:1/cam"


def test_unknown_format_lists_supported_ones(serve):
    cam = camera_proxy(serve, serve(CameraI({"Uri": "sim"}, StillVehicle()), "Camera"))
    assert cam.getImageFormat() == ["RGB8", "GRAY8"]
    wait(lambda: cam.getImageDescription().width > 0, what="first frame")
    with pytest.raises(jderobot.DataNotExistException) as err:
        cam.getImageData("YUY2")
    assert "RGB8" in err.value.what and "YUY2" in err.value.what


class EncodeCountingCamera(CameraI):
    """Notes each image it encodes: (frame index, format)."""

    def __init__(self, *args):
        super().__init__(*args)
        self.encoded: list[tuple[int, str]] = []

    def _encode(self, frame, fmt):
        self.encoded.append((frame.index, fmt))
        return CameraI._encode(frame, fmt)


def test_encoded_once_per_frame_whatever_the_clients(serve):
    """However many clients ask, and however often, each frame is encoded once per format; a newer frame is
    encoded anew."""
    servant = EncodeCountingCamera({"Uri": "sim", "Width": "160", "Height": "120"}, StillVehicle())  # quick asks
    encoded = servant.encoded
    proxy = serve(servant, "Camera")
    clients = [camera_proxy(serve, proxy) for _ in range(3)]
    wait(servant.source.latest, what="first frame")

    def asked_within_one_frame():
        """Ask from here and from every client while the source shows one frame; (frame, the answers here)
        once that happened, None if a new frame came in between."""
        frame = servant.source.latest()
        first = servant.getImageData("RGB8")
        over_ice = [c.getImageData("RGB8") for c in clients]
        again = servant.getImageData("RGB8")
        if servant.source.latest() is not frame:
            return None
        return frame, first, again, over_ice

    frame, first, again, over_ice = wait(asked_within_one_frame, what="all asks within one frame")
    assert again is first                                        # the same encoded image, not a new one
    assert encoded.count((frame.index, "RGB8")) == 1
    assert all(d.pixelData == first.pixelData for d in over_ice)
    wait(lambda: servant.source.latest().index > frame.index + 1, what="a newer frame")
    newer = servant.getImageData("RGB8")
    assert newer is not first and any(index > frame.index for index, _ in encoded)
    assert len(encoded) == len(set(encoded))                     # never the same frame twice in one format


def test_no_image_yet_then_source_gone(serve, tmp_path):
    # a UDP stream nobody sends: open in progress, nothing decoded yet
    cam = camera_proxy(serve, serve(CameraI({"Uri": f"udp://127.0.0.1:{free_udp_port()}", "TimeoutMs": "800"}), "Waiting"))
    with pytest.raises(jderobot.DataNotExistException):
        cam.getImageData("RGB8")
    # a file that is not there: the source has failed, and says why
    missing = str(tmp_path / "gone.mp4")
    servant = CameraI({"Uri": missing})
    cam = camera_proxy(serve, serve(servant, "Gone"))
    wait(lambda: servant.source.status().state == "retrying", what="failure")
    with pytest.raises(jderobot.HardwareFailedException) as err:
        cam.getImageData("RGB8")
    assert "no such file" in err.value.what


def test_stalled_stream_is_a_hardware_failure_until_frames_resume(serve, tmp_path):
    """A stream gone quiet while the capture still waits in its read fails with the reason, not a frozen image."""
    data = write_ts(str(tmp_path / "s.ts"))
    port = free_udp_port()
    with UdpSender(data, port) as sender:
        servant = CameraI({"Uri": f"udp://127.0.0.1:{port}", "TimeoutMs": "30000", "StallMs": "500"})
        cam = camera_proxy(serve, serve(servant, "Camera"))
        wait(lambda: _try(lambda: cam.getImageData("RGB8")), what="image")
        sender.pause()
        err = wait(lambda: _failure(lambda: cam.getImageData("RGB8")), what="the stall reported")
        assert "no frame for " in err.what
        sender.resume()
        wait(lambda: _failure(lambda: cam.getImageData("RGB8")) is None, what="images again")
        servant.close()                                   # while frames still come: the read returns


def _failure(call):
    """The HardwareFailedException ``call`` raises, else None."""
    try:
        call()
    except jderobot.HardwareFailedException as e:
        return e
    return None


def test_file_served_frames_keep_their_colours(serve, tmp_path):
    clip = write_clip(str(tmp_path / "c.mp4"), COLOURS[:1], repeat=200)
    cam = camera_proxy(serve, serve(CameraI({"Uri": clip}), "Camera"))
    data = wait(lambda: _try(lambda: cam.getImageData("RGB8")), what="image")
    px = np.frombuffer(data.pixelData, np.uint8).reshape(240, 320, 3)[120, 160]
    assert abs(int(px[0]) - 255) < 30 and px[1] < 30 and px[2] < 30     # red stays red


def _try(call):
    try:
        return call()
    except jderobot.DataNotExistException:
        return None


def test_extra_records_on_the_server_and_toggles_camera(serve, tmp_path):
    clip = write_clip(str(tmp_path / "blue.mp4"), [(0, 0, 255)], repeat=10)
    servant = CameraI({"Uri": "sim", "Uri.2": clip + "?loop=1", "RecordDir": str(tmp_path / "rec")}, StillVehicle())
    cam = camera_proxy(serve, serve(servant, "Camera"))
    extra = jderobot.ArDroneExtraPrx.checkedCast(
        serve.communicator.stringToProxy(serve(ArDroneExtraI(None, ServerSettings(), servant), "Extra")))
    wait(lambda: cam.getImageDescription().width == 640, what="the simulated camera")
    extra.recordOnUsb(True)
    wait(lambda: servant._recorder is not None and servant._recorder.frames_written >= 10, what="frames recorded")
    recorder = servant._recorder
    extra.recordOnUsb(False)
    assert servant._recorder is None
    files = os.listdir(tmp_path / "rec")
    assert len(files) == 1 and files[0].endswith(".mp4")
    cap = cv2.VideoCapture(str(tmp_path / "rec" / files[0]))
    ok, first = cap.read()
    cap.release()
    assert ok and first.shape == (480, 640, 3) and recorder.frames_written >= 10

    extra.toggleCam()
    wait(lambda: cam.getImageDescription().width == 320, what="the second camera")
    data = wait(lambda: _try(lambda: cam.getImageData("RGB8")), what="image")
    px = np.frombuffer(data.pixelData, np.uint8).reshape(240, 320, 3)[120, 160]
    assert px[2] > 200 and px[0] < 40                                  # blue


def test_server_with_sim_serves_the_simulated_camera(tmp_path):
    """``python -m driver --sim``: with no camera option, Camera serves the simulated vehicle's camera."""
    import socket
    import subprocess
    import sys
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    server = subprocess.Popen([sys.executable, "-m", "driver", "--sim", "--daemon", "--no-log",
                               "--one-port", str(port)], cwd=root, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    src = open_source(f"ice:Camera:default -h 127.0.0.1 -p {port}")
    try:
        frame = wait(src.latest, timeout=30, what="the server's simulated camera")
        assert frame.image.shape == (480, 640, 3)
    finally:
        src.close(wait=3)
        server.terminate()
        server.wait(10)


def test_server_streams_open_for_latency_unless_configured_off():
    """A live stream on the server opens with the low-latency options; LowLatency=0 keeps OpenCV's defaults
    (several decoder threads) for a companion computer too slow to decode on one."""
    for config, expected in (({}, True), ({"LowLatency": "0"}, False), ({"LowLatency": "1"}, True)):
        servant = CameraI({"Uri": f"udp://127.0.0.1:{free_udp_port()}", "TimeoutMs": "500", **config})
        try:
            assert servant.source.low_latency is expected, config
        finally:
            servant.close()
