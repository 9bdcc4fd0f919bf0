"""The simulated vehicle's links: a TCP server like SITL's 5760, UDP pushed like the Solo's controller.

Every ground station ("peer") gets its own MAVLink sequence numbers (one series
per component of the vehicle), its own parser and its own signing channel
(signing.py): the optional USB port's peers are channel 0, every other link a
telemetry link numbered from 1. Everything the vehicle says goes to every peer,
except the few answers ArduPilot sends only on the link that asked. One I/O
thread reads all sockets; writes come from the vehicle's clock thread and never
block (a peer that stops reading loses frames, as over a saturated radio). Each
peer's link has a :class:`~driver.sim.pipe.Pipe` each way, applying the uplink
and downlink faults.
"""
from __future__ import annotations

import logging
import random
import selectors
import socket
import threading
from contextlib import ExitStack, contextmanager
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .faults import Faults
from .pipe import Pipe
from .profiles import speaks_mavlink2
from .signing import Channel, Signing

log = logging.getLogger(__name__)

__all__ = ["LinkServer", "parse_address"]

MAX_PENDING = 1 << 20          # bytes queued for a slow TCP peer before frames are dropped
CORK_BYTES = 16384             # bytes of answers held while a read's requests are handled, then written at once
V2_MARKER = mavlink.PROTOCOL_MARKER_V2


def parse_address(text: str) -> tuple[str, int]:
    """"HOST:PORT" → (host, port); port 0 to 65535 (0: any free port)."""
    host, sep, port = text.rpartition(":")
    if not sep or not host:
        raise ValueError(f"expected HOST:PORT, got {text!r}")
    if not port.isdigit() or int(port) > 65535:
        raise ValueError(f"{text!r}: the port must be a number from 0 to 65535")
    return host, int(port)


class Peer:
    """One ground station on one link."""

    def __init__(self, name: str, config, usb: bool = False) -> None:
        self.name = name
        self.usb = usb                        # on the USB port (SERIAL0): unsigned frames pass even with a key
        self.system_id = config.system_id
        self.channel: Channel | None = None   # set by the LinkServer; its signing state signs what is sent here
        self.encoder = mavlink.MAVLink(None, srcSystem=config.system_id, srcComponent=config.component_id)
        self.encoders = {config.component_id: self.encoder}
        self.parser = mavlink.MAVLink(None, srcSystem=config.system_id, srcComponent=config.component_id)
        self.parser.robust_parsing = True
        self.lock = threading.Lock()
        self.closed = False
        self.up: Pipe | None = None          # set by the LinkServer
        self.down: Pipe | None = None

    def attach(self, channel: Channel) -> None:
        """Sign with ``channel``'s state from now on: every component's encoder on this link shares it."""
        self.channel = channel
        for encoder in self.encoders.values():
            encoder.signing = channel.state

    def encoder_for(self, component: int):
        """This peer's encoder (own sequence numbers) for one component of the vehicle.

        The gimbal and the companion sign with the autopilot's key and this link's id and timestamp: on a
        real vehicle they are devices of their own, which would need the key set in them too.
        """
        encoder = self.encoders.get(component)
        if encoder is None:
            encoder = self.encoders[component] = mavlink.MAVLink(None, srcSystem=self.system_id,
                                                                 srcComponent=component)
            if self.channel is not None:
                encoder.signing = self.channel.state
        return encoder

    def write(self, data: bytes) -> None:
        raise NotImplementedError

    def cork(self) -> None:
        """Hold what is written until :meth:`uncork` (a byte stream only: a datagram is a frame)."""

    def uncork(self) -> None:
        """Write what :meth:`cork` held."""

    @contextmanager
    def held(self):
        """Corked for the block (see :meth:`cork`), whatever it raises."""
        self.cork()
        try:
            yield
        finally:
            self.uncork()


class TcpPeer(Peer):
    def __init__(self, sock: socket.socket, address, config, usb: bool = False) -> None:
        super().__init__(f"{'usb' if usb else 'tcp'} {address[0]}:{address[1]}", config, usb)
        self.sock = sock
        self.pending = bytearray()
        self.corks = 0                        # corks held (a step, a read's answers): frames gather up to
                                              # CORK_BYTES, see uncork()

    def write(self, data: bytes) -> None:
        with self.lock:
            if self.closed:
                return
            if len(self.pending) + len(data) > MAX_PENDING:
                return
            self.pending += data
            if not self.corks or len(self.pending) >= CORK_BYTES:
                self._push()

    def cork(self) -> None:
        with self.lock:
            self.corks += 1

    def uncork(self) -> None:
        """Write what a step, or answering a read, gathered, once no cork is left. ArduPilot's SITL writes its
        serial port's buffer to the socket in one piece each loop; a write a frame costs both ends a system call
        and a wake-up per frame: a batch of log requests (a thousand one-packet answers) turns that into most of
        their cost, and a step's telemetry into a wake-up of the ground station's reader per message."""
        with self.lock:
            self.corks = max(0, self.corks - 1)
            if not self.corks and self.pending and not self.closed:
                self._push()

    def _push(self) -> None:
        try:
            del self.pending[:self.sock.send(self.pending)]
        except (BlockingIOError, InterruptedError):
            pass
        except OSError:
            self.closed = True


class UdpPeer(Peer):
    """A UDP socket: pushes to fixed addresses (if any) and to whoever spoke last."""

    def __init__(self, name: str, sock: socket.socket, config, push_to: tuple[str, int] | None) -> None:
        super().__init__(name, config)
        self.sock = sock
        self.push_to = push_to
        self.reply_to: tuple[str, int] | None = None

    def destinations(self) -> list[tuple[str, int]]:
        out = [self.push_to] if self.push_to else []
        if self.reply_to and self.reply_to != self.push_to:
            out.append(self.reply_to)
        return out

    def write(self, data: bytes) -> None:
        with self.lock:
            for address in self.destinations():
                try:
                    self.sock.sendto(data, address)
                except OSError:        # nobody listening (ICMP refused), buffer full: a lost datagram
                    pass


class LinkServer:
    """Sockets and peers; hands decoded messages to ``on_message(msg, version, peer)``.

    Signatures are not checked here but where the vehicle takes the message (SimVehicle's clock thread,
    with ``signing.admit``): a SETUP_SIGNING then governs the very next frame, as in ArduPilot's one loop.
    """

    def __init__(self, config, faults: Faults, on_message: Callable[[object, int, Peer], None],
                 signing: Signing | None = None) -> None:
        self.config = config
        self.faults = faults
        self.on_message = on_message
        self.signing = signing if signing is not None else Signing(config)
        self.rng = random.Random(None if config.seed is None else config.seed + 1)
        self.mavlink2 = speaks_mavlink2(config)
        self.peers_added = 0
        self.up_lock = threading.Lock()      # the uplink's counters are counted by the I/O and clock threads
        self.down_lock = threading.Lock()
        self.peers: list[Peer] = []
        self.peers_lock = threading.Lock()
        self.selector = selectors.DefaultSelector()
        self.listener: socket.socket | None = None
        self.usb_listener: socket.socket | None = None
        self.udp_out: UdpPeer | None = None
        self.udp_in: UdpPeer | None = None
        self.tcp_port = 0
        self.usb_port: int | None = None
        self.udp_port: int | None = None
        self.ignored_v2 = 0
        self.bad_frames = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- lifecycle ---------------------------------------------------------------------------------
    def start(self) -> None:
        cfg = self.config
        try:
            if cfg.tcp_port is not None and cfg.tcp_port >= 0:
                self.listener = self._listen(cfg.tcp_host, cfg.tcp_port, "accept")
                self.tcp_port = self.listener.getsockname()[1]
                log.info("serving MAVLink on tcp:%s:%d", cfg.tcp_host, self.tcp_port)
            usb_port = getattr(cfg, "usb_port", None)
            if usb_port is not None and usb_port >= 0:
                self.usb_listener = self._listen(cfg.tcp_host, usb_port, "accept-usb")
                self.usb_port = self.usb_listener.getsockname()[1]
                log.info("serving MAVLink as USB (SERIAL0: unsigned accepted) on tcp:%s:%d", cfg.tcp_host,
                         self.usb_port)
            if cfg.udp_out:
                target = parse_address(cfg.udp_out)
                sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
                sock.bind(("", 0))
                sock.setblocking(False)
                self.udp_out = UdpPeer(f"udp out {cfg.udp_out}", sock, cfg, target)
                self._add(self.udp_out)
                self.selector.register(sock, selectors.EVENT_READ, self.udp_out)
                log.info("pushing MAVLink to udp:%s:%d", *target)
            if cfg.udp_listen:
                host, port = parse_address(cfg.udp_listen)
                sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                sock.bind((host, port))
                sock.setblocking(False)
                self.udp_port = sock.getsockname()[1]
                self.udp_in = UdpPeer(f"udp in {host}:{self.udp_port}", sock, cfg, None)
                self._add(self.udp_in)
                self.selector.register(sock, selectors.EVENT_READ, self.udp_in)
                log.info("serving MAVLink on udp:%s:%d", host, self.udp_port)
        except OSError:
            self.stop()
            raise
        self._thread = threading.Thread(target=self._run, name="sim-link", daemon=True)
        self._thread.start()

    def _listen(self, host: str, port: int, kind: str) -> socket.socket:
        listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            listener.bind((host, port))
            listener.listen(8)
            listener.setblocking(False)
            self.selector.register(listener, selectors.EVENT_READ, kind)
        except OSError:
            listener.close()
            raise
        return listener

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=1.0)
        self._thread = None
        with self.peers_lock:
            peers, self.peers = self.peers, []
        for peer in peers:
            self._close(peer, quiet=True)
        for listener in (self.listener, self.usb_listener):
            if listener is not None:
                listener.close()
        self.listener = self.usb_listener = None
        try:
            self.selector.close()
        except (OSError, RuntimeError):
            pass

    def _add(self, peer: Peer) -> None:
        faults, seed = self.faults, self.config.seed
        with self.peers_lock:
            index = self.peers_added = self.peers_added + 1
            base = None if seed is None else seed * 1000 + 10 * index
            peer.up = Pipe(faults, lambda: faults.uplink, faults.counters.uplink,
                           random.Random(None if base is None else base + 2), self.up_lock)
            peer.down = Pipe(faults, lambda: faults.downlink, faults.counters.downlink,
                             random.Random(None if base is None else base + 3), self.down_lock)
            peer.attach(self.signing.open_channel(peer.usb))
            self.peers.append(peer)

    def _close(self, peer: Peer, quiet: bool = False) -> None:
        with peer.lock:
            peer.closed = True
        try:
            self.selector.unregister(peer.sock)
        except (KeyError, ValueError, OSError, RuntimeError):
            pass
        peer.sock.close()
        with self.peers_lock:
            if peer in self.peers:
                self.peers.remove(peer)
        if peer.channel is not None:
            self.signing.close_channel(peer.channel)
        if not quiet:
            log.info("client disconnected: %s", peer.name)

    @property
    def clients(self) -> int:
        with self.peers_lock:
            return sum(isinstance(p, TcpPeer) for p in self.peers)

    # -- sending ------------------------------------------------------------------------------------
    def broadcast(self, msg, component: int | None = None, mavlink2: bool | None = None,
                  to: Peer | None = None) -> None:
        """Encode ``msg`` for every peer (own sequence numbers, signed while signing is on) and send it, faults
        applied.

        ``component``: which part of the vehicle speaks (default the autopilot); ``mavlink2``: its framing
        (default the autopilot's: a MAVLink-1 autopilot's gimbal may still speak MAVLink 2); ``to``: only
        this peer (ArduPilot's GCS_MAVLINK::send_text answers on the asking link alone).
        """
        faults = self.faults
        mav1 = not (self.mavlink2 if mavlink2 is None else mavlink2)
        if mav1 and msg.get_msgId() > 255:
            return
        component = self.config.component_id if component is None else component
        now = faults.clock()
        if to is not None:
            peers = [to]
        else:
            with self.peers_lock:
                peers = list(self.peers)
        for peer in peers:
            if peer.closed:
                continue
            encoder = peer.encoder_for(component)
            data = bytearray(msg.pack(encoder, force_mavlink1=mav1))
            encoder.seq = (encoder.seq + 1) % 256
            if faults.corrupt_fraction > 0 and self.rng.random() < faults.corrupt_fraction:
                index = self.rng.randrange(1, len(data))
                data[index] ^= 1 << self.rng.randrange(8)
                faults.counters.downlink.corrupted += 1
            for frame in peer.down.send(bytes(data), now, faults.drop_fraction):
                peer.write(frame)

    @contextmanager
    def held(self):
        """Every peer corked for the block (see Peer.cork): a step's frames go out in one write a peer."""
        with self.peers_lock:
            peers = list(self.peers)
        with ExitStack() as stack:
            for peer in peers:
                stack.enter_context(peer.held())
            yield

    def pump(self) -> None:
        """Hand on what latency and reordering held back, now that its time has come (the clock thread)."""
        now = self.faults.clock()
        with self.peers_lock:
            peers = list(self.peers)
        for peer in peers:
            if peer.closed:
                continue
            if peer.down.pending:
                for frame in peer.down.due(now):
                    peer.write(frame)
            if peer.up.pending:
                for item in peer.up.due(now):
                    self._deliver(*item)

    def inject(self, raw: bytes) -> None:
        with self.peers_lock:
            peers = list(self.peers)
        for peer in peers:
            peer.write(bytes(raw))

    # -- receiving ----------------------------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                events = self.selector.select(timeout=0.05)
            except (OSError, ValueError, RuntimeError):
                if self._stop.is_set():
                    return
                continue
            for key, _mask in events:
                if key.data in ("accept", "accept-usb"):
                    self._accept(key.fileobj, usb=key.data == "accept-usb")
                else:
                    self._read(key.data)

    def _accept(self, listener: socket.socket, usb: bool = False) -> None:
        try:
            sock, address = listener.accept()
        except OSError:
            return
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        peer = TcpPeer(sock, address, self.config, usb)
        self._add(peer)
        self.selector.register(sock, selectors.EVENT_READ, peer)
        log.info("client connected: %s", peer.name)

    def _read(self, peer: Peer) -> None:
        if isinstance(peer, TcpPeer):
            try:
                data = peer.sock.recv(65536)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                data = b""
            if not data:
                self._close(peer)
                return
            with peer.lock:     # flush what a full socket buffer held back
                if peer.pending and not peer.closed:
                    try:
                        del peer.pending[:peer.sock.send(peer.pending)]
                    except OSError:
                        pass
        else:
            try:
                data, address = peer.sock.recvfrom(65536)
            except OSError:     # BlockingIOError, or ICMP port unreachable from an earlier push
                return
            if not self.faults.dead():
                peer.reply_to = address
        try:
            messages = peer.parser.parse_buffer(data) or []
        except Exception:   # robust parsing should not raise; garbage must never stop the link
            log.exception("parser failed on %d bytes from %s", len(data), peer.name)
            peer.parser.buf = bytearray()
            peer.parser.buf_index = 0
            return
        now = self.faults.clock()
        with peer.held():                   # the answers to one read go out together
            for msg in messages:
                kind = msg.get_type()
                if kind in ("BAD_DATA", "UNKNOWN") or kind.startswith("UNKNOWN"):
                    self.bad_frames += 1
                    continue
                version = 2 if msg.get_msgbuf()[0] == V2_MARKER else 1
                for item in peer.up.send((msg, version, peer), now):
                    self._deliver(*item)

    def _deliver(self, msg, version: int, peer: Peer) -> None:
        """What reached the vehicle through the uplink's faults."""
        if version == 2 and not self.mavlink2:
            self.ignored_v2 += 1        # a MAVLink 1 autopilot does not see these frames at all
            return
        self.on_message(msg, version, peer)
