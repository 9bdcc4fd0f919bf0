#!/usr/bin/env python3
"""Glass-to-glass video latency: a real H.264 sender on 127.0.0.1, the viewer's own capture and paint path.

    python bench/bench_video_latency.py [--seconds 20] [--transports rtp,mpegts,rtsp] [--no-low-latency]
                                        [--markdown] [--write-docs]

The sender is ``ffmpeg`` (Debian's; installed here with apt-get when missing, with ``rtsp-server-perl`` for
RTSP) encoding a 1280×720 30 fps test picture as a drone does (libx264 baseline, ``-tune zerolatency``, no
B-frames, a key frame every second). Each frame carries its number as a bar code (16 black or white blocks,
and below them the same bits inverted, which the reader checks). The bench notes the moment it hands each
frame to the encoder: the frame's "glass" time.

The viewer runs in its own process: the real ``CameraPanel`` and ``CameraController`` (960×540 video area,
no HUD), opening the stream by its URI exactly as ``--camera URI`` does. When the view has painted a frame,
that process renders the bar code's strip of the view again (``QWidget.grab``, the same paint code) and
reads the number off the pixels: latency is the time from the frame's glass time to the end of its paint.
It reports its own CPU (all threads, % of one core) over the measured seconds.

Transports: RTP H.264 described by an SDP file (the Solo and most FPV links), MPEG-TS over UDP, and RTSP
(ffmpeg publishes to Debian's ``rtsp-server-perl``, the viewer plays from it over RTSP/TCP).
Printed per transport: latency p50/p95/max, frames shown / sent, frames shown out of order, unreadable
bar codes, the latency trend (median of the last fifth minus the first fifth of the run: a growing delay
shows here), and the viewer's CPU. ``--no-low-latency`` opens the streams without the low-latency capture
options (the "before").
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

import numpy as np  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)

WIDTH, HEIGHT, FPS = 1280, 720, 30
BITS = 16
BLOCK_W, BLOCK_H = 64, 60
BAR_X, BAR_Y = (WIDTH - BITS * BLOCK_W) // 2, 300        # two rows: the number, then its inverse
VIEW_SIZE = (960, 540)
TOOLS = {"ffmpeg": "ffmpeg", "rtsp-server-perl": "rtsp-server-perl", "xvfb-run": "xvfb"}   # command -> Debian package


# -- the picture --------------------------------------------------------------------------------------------
def draw_bar_code(image: np.ndarray, number: int) -> None:
    """``number`` (16 bits) as white (1) and black (0) blocks, with the inverse row below."""
    for bit in range(BITS):
        on = (number >> (BITS - 1 - bit)) & 1
        x = BAR_X + bit * BLOCK_W
        image[BAR_Y:BAR_Y + BLOCK_H, x:x + BLOCK_W] = 255 if on else 0
        image[BAR_Y + BLOCK_H:BAR_Y + 2 * BLOCK_H, x:x + BLOCK_W] = 0 if on else 255


def read_bar_code(gray: np.ndarray) -> int | None:
    """The number in a grey picture of the bar code's strip (any scale), or None when the rows disagree."""
    h, w = gray.shape
    number = 0
    for bit in range(BITS):
        cx = int((bit + 0.5) * w / BITS)
        top = gray[int(0.2 * h):int(0.3 * h), max(0, cx - 3):cx + 4].mean()
        bottom = gray[int(0.7 * h):int(0.8 * h), max(0, cx - 3):cx + 4].mean()
        if (top > 128) == (bottom > 128):
            return None
        number = (number << 1) | int(top > 128)
    return number


class Picture:
    """A moving test picture (colour gradient, a box sweeping across) carrying the frame number (at 1280×720;
    another size shows the moving picture only)."""

    def __init__(self, width: int = WIDTH, height: int = HEIGHT) -> None:
        y, x = np.mgrid[0:height, 0:width]
        self.base = np.stack([(x * 255 // width), (y * 255 // height), ((x + y) * 255 // (width + height))],
                             axis=-1).astype(np.uint8)
        self.frame = np.empty_like(self.base)
        self.size = (width, height)

    def render(self, number: int) -> np.ndarray:
        f = self.frame
        f[:] = self.base
        w, h = self.size
        box = h // 5
        x = (number * 12) % (w - box)
        f[h - 2 * box:h - box, x:x + box] = (240, 240, 40)
        if self.size == (WIDTH, HEIGHT):
            draw_bar_code(f, number)
        return f


# -- the sender ---------------------------------------------------------------------------------------------
def ensure_tools(needed: list[str]) -> None:
    """Debian's ffmpeg (and rtsp-server-perl for RTSP), installed when missing."""
    missing = [TOOLS[t] for t in needed if shutil.which(t) is None]
    if not missing:
        return
    sudo = [] if os.geteuid() == 0 else ["sudo"]
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    print(f"installing {' '.join(missing)} (apt-get)", flush=True)
    subprocess.run(sudo + ["apt-get", "update", "-qq"], check=True, env=env)
    subprocess.run(sudo + ["apt-get", "install", "-y", "-qq", "--no-install-recommends", *missing], check=True,
                   env=env, stdout=subprocess.DEVNULL)


def free_port(kind=socket.SOCK_STREAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


ENCODE = ["-c:v", "libx264", "-preset", "ultrafast", "-tune", "zerolatency", "-profile:v", "baseline",
          "-pix_fmt", "yuv420p", "-g", str(FPS), "-bf", "0"]


class Sender:
    """ffmpeg reading raw frames on stdin at 30 fps, sending them over one transport on loopback."""

    def __init__(self, transport: str, tmp: str, size: tuple[int, int] = (WIDTH, HEIGHT)) -> None:
        self.transport = transport
        self.size = size
        self.sent: dict[int, float] = {}         # frame number -> glass time (time.monotonic())
        self._stop = threading.Event()
        self._server: subprocess.Popen | None = None
        if transport == "rtp":
            port = free_port(socket.SOCK_DGRAM)
            sdp = os.path.join(tmp, "stream.sdp")
            out = ["-f", "rtp", "-sdp_file", sdp, f"rtp://127.0.0.1:{port}"]
            self.uri = sdp
        elif transport == "mpegts":
            port = free_port(socket.SOCK_DGRAM)
            out = ["-f", "mpegts", "-flush_packets", "1", "-muxdelay", "0", f"udp://127.0.0.1:{port}?pkt_size=1316"]
            self.uri = f"udp://127.0.0.1:{port}"
        elif transport == "rtsp":
            source_port, client_port = free_port(), free_port()
            self._server = subprocess.Popen(
                ["rtsp-server-perl", "--clientport", str(client_port), "--serverport", str(source_port),
                 "--client_listen_address", "127.0.0.1", "--source_listen_address", "127.0.0.1",
                 "--rtp_start_port", str(free_port(socket.SOCK_DGRAM))],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wait_for_port(source_port)
            out = ["-f", "rtsp", f"rtsp://127.0.0.1:{source_port}/live"]
            self.uri = f"rtsp://127.0.0.1:{client_port}/live"
        else:
            raise ValueError(transport)
        self._ffmpeg = subprocess.Popen(
            ["ffmpeg", "-hide_banner", "-loglevel", "error", "-f", "rawvideo", "-pix_fmt", "rgb24",
             "-s", f"{size[0]}x{size[1]}", "-r", str(FPS), "-i", "-", *ENCODE, *out],
            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL)
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        if transport == "rtp":
            deadline = time.monotonic() + 10
            while not (os.path.exists(sdp) and os.path.getsize(sdp)) and time.monotonic() < deadline:
                time.sleep(0.05)

    def _run(self) -> None:
        picture = Picture(*self.size)
        start = time.monotonic()
        number = 0
        while not self._stop.is_set():
            due = start + number / FPS
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            image = picture.render(number & 0xFFFF)
            self.sent[number] = time.monotonic()         # glass: the moment the encoder gets the picture
            try:
                self._ffmpeg.stdin.write(image.data)
                self._ffmpeg.stdin.flush()
            except (BrokenPipeError, ValueError):
                return
            number += 1

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        try:
            self._ffmpeg.stdin.close()
        except OSError:
            pass
        for p in (self._ffmpeg, self._server):
            if p is not None and p.poll() is None:
                p.send_signal(signal.SIGINT)
                try:
                    p.wait(5)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()


def wait_for_port(port: int, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.05)
    raise RuntimeError(f"nothing listens on 127.0.0.1:{port}")


# -- the viewer (its own process) ------------------------------------------------------------------------------
def run_viewer(uri: str, warmup: float, seconds: float, low_latency: bool) -> int:
    """The real camera panel and controller showing ``uri``; prints what it painted as JSON on stdout."""
    import resource

    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PyQt5.QtCore import QRect, QTimer
    from PyQt5.QtGui import QImage
    from PyQt5.QtWidgets import QApplication

    from uavviewer.camera.controller import CameraController
    from uavviewer.camera.panel import CameraPanel

    app = QApplication(sys.argv[:1])
    panel = CameraPanel()
    panel.hud_button.setChecked(False)
    panel.resize(VIEW_SIZE[0], VIEW_SIZE[1] + 30)
    panel.show()
    painted: list[tuple[int, float, float]] = []           # (number, painted at, decoded at)
    unreadable = [0]
    measuring = [False]
    tmp = tempfile.mkdtemp()
    controller = CameraController(panel, [uri], folder=tmp, low_latency=low_latency)
    view = panel.view

    def on_painted(index: int, latency: float) -> None:
        now = time.monotonic()
        if not measuring[0]:
            return
        target = view.video_rect()
        scale = target.width() / WIDTH
        strip = QRect(int(target.x() + BAR_X * scale), int(target.y() + BAR_Y * scale),
                      int(BITS * BLOCK_W * scale), int(2 * BLOCK_H * scale))
        image = view.grab(strip).toImage().convertToFormat(QImage.Format_Grayscale8)
        ptr = image.constBits()
        ptr.setsize(image.bytesPerLine() * image.height())
        gray = np.frombuffer(ptr, np.uint8).reshape(image.height(), image.bytesPerLine())[:, :image.width()]
        number = read_bar_code(gray)
        if number is None:
            unreadable[0] += 1
        else:
            painted.append((number, now, now - latency))

    view.framePainted.connect(on_painted)
    cpu: dict = {}

    def begin() -> None:
        if controller.source.status().frames == 0:            # not yet receiving: wait for the first frame
            QTimer.singleShot(100, begin)
            return
        QTimer.singleShot(int(warmup * 1000), start_measuring)

    def start_measuring() -> None:
        measuring[0] = True
        r = resource.getrusage(resource.RUSAGE_SELF)
        cpu.update(cpu0=r.ru_utime + r.ru_stime, t0=time.monotonic(), frames0=controller.source.status().frames)
        QTimer.singleShot(int(seconds * 1000), finish)

    def finish() -> None:
        measuring[0] = False
        r = resource.getrusage(resource.RUSAGE_SELF)
        cpu.update(cpu1=r.ru_utime + r.ru_stime, t1=time.monotonic(), frames1=controller.source.status().frames)
        app.quit()

    QTimer.singleShot(0, begin)
    QTimer.singleShot(int((warmup + seconds + 60) * 1000), app.quit)      # never hang
    app.exec_()
    status = controller.source.status()
    controller.close(wait=2)
    result = {"painted": painted, "unreadable": unreadable[0], "status": status.state, "reason": status.reason}
    if "cpu1" in cpu:
        wall = cpu["t1"] - cpu["t0"]
        result.update(cpu_percent=100.0 * (cpu["cpu1"] - cpu["cpu0"]) / wall, t0=cpu["t0"], t1=cpu["t1"],
                      decoded=cpu["frames1"] - cpu["frames0"])
    print(json.dumps(result), flush=True)
    return 0


# -- putting it together ---------------------------------------------------------------------------------------
def measure(transport: str, seconds: float, warmup: float, low_latency: bool) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        sender = Sender(transport, tmp)
        try:
            viewer = subprocess.run(
                [sys.executable, os.path.abspath(__file__), "--viewer", sender.uri, "--seconds", str(seconds),
                 "--warmup", str(warmup)] + ([] if low_latency else ["--no-low-latency"]),
                capture_output=True, text=True, cwd=ROOT, timeout=warmup + seconds + 120)
        finally:
            sender.close()
    try:
        result = json.loads(viewer.stdout.strip().splitlines()[-1])
    except (IndexError, json.JSONDecodeError):
        raise RuntimeError(f"viewer failed: {viewer.stderr[-2000:]}") from None
    if "t0" not in result:
        raise RuntimeError(f"no video on {transport}: {result.get('status')} {result.get('reason')}")
    sent = {n & 0xFFFF: t for n, t in sender.sent.items() if result["t0"] <= t <= result["t1"]}
    first_send = {}
    for n, t in sorted(sender.sent.items()):
        first_send.setdefault(n & 0xFFFF, t)
    latencies, order, shown, decoded = [], [], set(), []
    for number, painted_at, decoded_at in result["painted"]:
        glass = first_send.get(number)
        if glass is None or glass > painted_at:
            continue
        latencies.append((painted_at - glass) * 1000.0)
        decoded.append((decoded_at - glass) * 1000.0)
        order.append(number)
        if number in sent:
            shown.add(number)
    to_decoded = float(np.median(decoded)) if decoded else float("nan")
    out_of_order = sum(1 for a, b in zip(order, order[1:]) if b < a)
    lat = np.asarray(latencies)
    fifth = max(1, lat.size // 5)
    return dict(transport=transport, n=lat.size, p50=float(np.median(lat)), p95=float(np.percentile(lat, 95)),
                max=float(lat.max()), shown=len(shown), sent=len(sent), out_of_order=out_of_order,
                unreadable=result["unreadable"], trend=float(np.median(lat[-fifth:]) - np.median(lat[:fifth])),
                cpu=result["cpu_percent"], seconds=result["t1"] - result["t0"], to_decoded=to_decoded)


NAMES = {"rtp": "RTP H.264 (SDP)", "mpegts": "MPEG-TS over UDP", "rtsp": "RTSP (RTP/UDP)"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=20.0, help="measured seconds per transport (default 20)")
    ap.add_argument("--warmup", type=float, default=3.0, help="seconds shown before measuring (default 3)")
    ap.add_argument("--transports", default="rtp,mpegts,rtsp")
    ap.add_argument("--no-low-latency", action="store_true", help="open without the low-latency capture options")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    ap.add_argument("--viewer", metavar="URI", help=argparse.SUPPRESS)
    tables.add_write_docs(ap)
    opts = ap.parse_args()
    if opts.viewer:
        return run_viewer(opts.viewer, opts.warmup, opts.seconds, not opts.no_low_latency)

    transports = [t.strip() for t in opts.transports.split(",") if t.strip()]
    ensure_tools(["ffmpeg"] + (["rtsp-server-perl"] if "rtsp" in transports else []))
    mode = "without the low-latency options" if opts.no_low_latency else "low-latency capture (default)"
    print(f"{WIDTH}x{HEIGHT} {FPS} fps H.264 baseline zerolatency from ffmpeg on 127.0.0.1, {mode}, "
          f"{opts.seconds:.0f} s each, view {VIEW_SIZE[0]}x{VIEW_SIZE[1]}", flush=True)
    rows = []
    for transport in transports:
        try:
            r = measure(transport, opts.seconds, opts.warmup, not opts.no_low_latency)
        except RuntimeError as exc:
            print(f"  {NAMES[transport]}: {exc}", flush=True)
            continue
        rows.append(r)
        print(f"  {NAMES[transport]:18} latency p50 {r['p50']:5.0f} ms  p95 {r['p95']:5.0f} ms  max {r['max']:5.0f} ms"
              f"  shown {r['shown']}/{r['sent']}  out of order {r['out_of_order']}  unreadable {r['unreadable']}"
              f"  trend {r['trend']:+.0f} ms  viewer CPU {r['cpu']:.0f} %  (glass to decoded p50 {r['to_decoded']:.0f} ms)",
              flush=True)
    if tables.markdown(opts.markdown) and rows:
        print("\n| transport | p50 ms | p95 ms | max ms | shown / sent | out of order | trend ms | viewer CPU |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {NAMES[r['transport']]} | {r['p50']:.0f} | {r['p95']:.0f} | {r['max']:.0f} | "
                  f"{r['shown']} / {r['sent']} | {r['out_of_order']} | {r['trend']:+.0f} | {r['cpu']:.0f} % |")
    return 0


if __name__ == "__main__":
    with tables.publishing(tables.variant("video_latency", "--no-low-latency", "--transports")):
        sys.exit(main())
