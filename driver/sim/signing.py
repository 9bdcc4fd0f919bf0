"""MAVLink 2 message signing as ArduPilot does it, for the simulated vehicle's links.

Follows libraries/GCS_MAVLink/GCS_Signing.cpp (ArduPilot 4.x) and the C library's
mavlink_signature_check() (mavlink_helpers.h), checked against
tests/data/recordings/arducopter-4.7-sitl-signing.tlog:

* SETUP_SIGNING stores key and initial_timestamp and loads them on every link at
  once (handle_setup_signing -> load_signing_key per channel). Each link signs
  what it sends with link_id = its channel number and a timestamp of its own,
  starting one minute past the stored one (the recording: the first frame on
  SERIAL1 carried initial_timestamp + 6,000,001) and rising by one per frame.
  An all-zero key with timestamp 0 turns signing off.
* Once on, a frame that is unsigned, signed with another key, replayed or more
  than a minute behind the link's timestamp on a new stream is dropped before
  anything sees it (no COMMAND_ACK). accept_unsigned_callback lets such frames
  through on channel 0 (USB, "assumed to be secure") and RADIO_STATUS / RADIO on
  any link. The stream table (link id, system, component -> last timestamp) is
  shared by all links; a link's timestamp rises to any timestamp it accepted and,
  once the GPS has a fix, to GPS time (AP_RTC -> update_signing_timestamp).
* The C check verifies the signature before it records a stream's timestamp;
  pymavlink's check_signature() records first, so a forged frame with a future
  timestamp would lock the real stream out. :meth:`Signing.admit` verifies the
  HMAC first, then lets pymavlink do the stream bookkeeping.

Everything here runs on the sim's clock thread (checks, sending, SETUP_SIGNING),
except opening and closing a link's channel (the I/O thread), hence the lock.
"""
from __future__ import annotations

import hashlib
import logging
import threading
import time
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..link.signing import EPOCH_2015, key_from_passphrase as passphrase_key    # the driver's: one key derivation
from .profiles import speaks_mavlink2

__all__ = ["Signing", "SigningCounters", "Channel", "passphrase_key", "signing_timestamp", "EPOCH_2015", "MINUTE",
           "MAX_STREAMS", "ACCEPT_UNSIGNED"]

log = logging.getLogger(__name__)

MINUTE = 60 * 100 * 1000            # one minute in those units
MAX_STREAMS = 16                    # MAVLINK_MAX_SIGNING_STREAMS: a 17th stream is refused
ACCEPT_UNSIGNED = frozenset((mavlink.MAVLINK_MSG_ID_RADIO_STATUS, mavlink.MAVLINK_MSG_ID_RADIO))
KEY_BYTES = 32


def signing_timestamp(unix_seconds: float) -> int:
    """GPS time as update_signing_timestamp() turns it into a signing timestamp: whole seconds since 2015."""
    seconds = int(unix_seconds)
    if seconds > EPOCH_2015:
        seconds -= EPOCH_2015
    return seconds * 100 * 1000


@dataclass
class SigningCounters:
    """What the vehicle's signing did with incoming frames and SETUP_SIGNING, for tests and the log."""
    accepted_signed: int = 0        # good signature, fresh timestamp
    accepted_unsigned: int = 0      # unsigned or badly signed, let through on USB or as RADIO_STATUS / RADIO
    dropped_unsigned: int = 0       # unsigned (MAVLink 1 included) on a telemetry link
    dropped_bad_signature: int = 0  # signed with another key, or altered
    dropped_replay: int = 0         # timestamp not newer than its stream's, or a new stream over a minute behind
    dropped_streams: int = 0        # a new stream when MAX_STREAMS are known already
    setups: int = 0                 # SETUP_SIGNING applied (a zero key included)
    refused_armed: int = 0          # SETUP_SIGNING refused: "ERROR: Won't setup signing when armed"


class Channel:
    """One link's signing (ArduPilot: one GCS_MAVLINK's mavlink_signing_t): its link id and its own timestamp.

    ``state`` is pymavlink's signing record; the link's encoders share it, so what they pack is signed with
    this link id and timestamp, and the check below raises the same timestamp.
    """

    def __init__(self, number: int, usb: bool, streams: dict) -> None:
        self.number = number
        self.usb = usb
        self.closed = False
        self.state = mavlink.MAVLinkSigning()
        self.state.link_id = number
        self.state.stream_timestamps = streams          # shared by every link, as signing_streams is
        self._checker = mavlink.MAVLink(None)
        self._checker.signing = self.state

    @property
    def timestamp(self) -> int:
        """The timestamp this link signs its next frame with."""
        return self.state.timestamp

    def check_streams(self, buf: bytearray, system: int, component: int) -> bool:
        """pymavlink's check_signature(): new-stream age, replay, record, raise this link's timestamp."""
        return self._checker.check_signature(buf, system, component)


class Signing:
    """The vehicle's signing key and every link's signing state.

    ``key`` is None while signing is off. ``config.signing_key`` is a key already in storage at power-on,
    saved (as ArduPilot saves it every 30 s) at the sim's start: the links start a minute past that.
    """

    def __init__(self, config, wall_clock=time.time) -> None:
        self._wall = wall_clock              # GPS time, as SYSTEM_TIME tells it
        self.counters = SigningCounters()
        self.streams: dict = {}
        self.key: bytes | None = None
        self.stored_timestamp = 0            # as saved in storage: the key's initial_timestamp
        self._base = 0                       # where a link opened now starts: stored + 1 min, raised by GPS time
        self._channels: list[Channel] = []
        self._lock = threading.Lock()
        key = getattr(config, "signing_key", None)
        if key is not None:
            key = bytes(key)
            if len(key) != KEY_BYTES:
                raise ValueError(f"signing_key must be {KEY_BYTES} bytes, got {len(key)}")
            if not speaks_mavlink2(config):   # a stock Solo (3.3) has no GCS_Signing and no MAVLink 2 at all
                raise ValueError("signing needs MAVLink 2: this vehicle speaks MAVLink 1 only")
            self._load(key, signing_timestamp(self._wall()))

    @property
    def enabled(self) -> bool:
        return self.key is not None

    # -- links ---------------------------------------------------------------------------------------
    def open_channel(self, usb: bool = False) -> Channel:
        """A link's channel: 0 for the USB port (SERIAL0), else the lowest number no open link uses."""
        with self._lock:
            if usb:
                number = 0
            else:
                used = {c.number for c in self._channels}
                number = next(n for n in range(1, 256) if n not in used)
            channel = Channel(number, usb, self.streams)
            self._apply(channel)
            self._channels.append(channel)
            return channel

    def close_channel(self, channel: Channel) -> None:
        with self._lock:
            channel.closed = True
            if channel in self._channels:
                self._channels.remove(channel)

    @property
    def channels(self) -> list[Channel]:
        with self._lock:
            return list(self._channels)

    # -- SETUP_SIGNING and time ------------------------------------------------------------------------
    def setup(self, key: bytes, initial_timestamp: int) -> None:
        """handle_setup_signing() once the armed check passed: store, then load on every link at once."""
        self.counters.setups += 1
        self._load(bytes(key), int(initial_timestamp))

    def _load(self, key: bytes, timestamp: int) -> None:
        """load_signing_key(): a link signs from stored + 1 minute; an all-zero key with timestamp 0 is off."""
        with self._lock:
            self.stored_timestamp = timestamp
            off = timestamp == 0 and not any(key)
            self.key = None if off else key
            self._base = timestamp + MINUTE
            for channel in self._channels:
                self._apply(channel)
        log.info("signing %s", "off" if off else "on")

    def _apply(self, channel: Channel) -> None:
        state = channel.state
        state.secret_key = self.key
        state.sign_outgoing = self.key is not None
        state.timestamp = self._base

    def update_timestamp(self, unix_seconds: float) -> None:
        """update_signing_timestamp(): GPS time raises every link's timestamp (never lowers it)."""
        if self.key is None:
            return
        stamp = signing_timestamp(unix_seconds)
        with self._lock:
            self._base = max(self._base, stamp)
            for channel in self._channels:
                if channel.state.timestamp < stamp:
                    channel.state.timestamp = stamp

    # -- incoming ------------------------------------------------------------------------------------
    def admit(self, msg, channel: Channel | None) -> bool:
        """Whether the parser of ``channel`` hands ``msg`` on (ArduPilot: MAVLINK_FRAMING_OK), counted."""
        key = self.key
        if key is None or channel is None:
            return True                      # signing off: signed or not, nothing is checked
        buf = msg.get_msgbuf()
        counters = self.counters
        exempt = channel.usb or msg.get_msgId() in ACCEPT_UNSIGNED      # accept_unsigned_callback
        signed = buf[0] == mavlink.PROTOCOL_MARKER_V2 and buf[2] & mavlink.MAVLINK_IFLAG_SIGNED
        if not signed:
            if exempt:
                counters.accepted_unsigned += 1
                return True
            counters.dropped_unsigned += 1
            return False
        failure = self._check(bytearray(buf), msg.get_srcSystem(), msg.get_srcComponent(), channel, key)
        if failure is None:
            counters.accepted_signed += 1
            return True
        if exempt:                           # the callback is asked for badly signed frames too
            counters.accepted_unsigned += 1
            return True
        setattr(counters, failure, getattr(counters, failure) + 1)
        return False

    def _check(self, buf: bytearray, system: int, component: int, channel: Channel, key: bytes) -> str | None:
        """mavlink_signature_check(): the signature first, then the stream's timestamp; the failure's counter."""
        if hashlib.sha256(key + bytes(buf[:-6])).digest()[:6] != bytes(buf[-6:]):
            return "dropped_bad_signature"
        stream = (buf[-13], system, component)
        if stream not in self.streams and len(self.streams) >= MAX_STREAMS:
            return "dropped_streams"
        if not channel.check_streams(buf, system, component):
            return "dropped_replay"
        return None
