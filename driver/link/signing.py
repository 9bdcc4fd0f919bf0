"""MAVLink 2 message signing on the vehicle link (MAVLink's message-signing spec, done by pymavlink's codec).

Why: an unsigned link obeys whoever puts a frame on it. With a key set on both ends, ArduPilot drops every
unsigned or wrongly signed frame on its telemetry ports (it still takes unsigned ones on USB, SERIAL0, by
design), and we drop the vehicle's frames that do not verify, so nobody without the key can command the
drone or speak for it. Signing is authentication, not encryption: anyone on the link still reads it.

* The key is 32 bytes; MAVProxy derives it as SHA-256 of a passphrase, and so do we, so a MAVProxy user's
  passphrase works here and back.
* Timestamps count 10 µs since 2015-01-01 and must never go back for a stream (link id, system, component):
  ours follow the clock, and the highest one sent is kept on disk so a restart or a clock set back cannot
  reuse one.
* The link id is derived from the connection string, so the same link keeps the same stream in the
  vehicle's table (ArduPilot holds 16 streams until it reboots) across restarts.
* SETUP_SIGNING carries the key in clear: send it only over a link you trust (USB, a cable).
* MAVLink 1 frames cannot carry a signature: a MAVLink 1 link (the stock Solo) cannot be signed, and we
  say so instead of pretending.
"""
from __future__ import annotations

import enum
import hashlib
import logging
import os
import stat
import time
import zlib
from concurrent.futures import Future
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.results import CommandStatus

log = logging.getLogger(__name__)


class SigningStatus(enum.Enum):
    OFF = "off"                                    # no key, the vehicle does not sign either
    SIGNING = "signing"                            # we sign everything we send (see Signing.detail)
    REQUIRED = "vehicle requires signing"          # the vehicle signs and we have no key: it ignores us
    MISMATCH = "key mismatch"                      # the vehicle's signatures fail with our key
    UNAVAILABLE = "MAVLink 1: cannot sign"         # a MAVLink 1 link (stock Solo) has no signing at all
    SETTING_UP = "setting up"                      # SETUP_SIGNING sent, waiting for the vehicle to sign


@dataclass(frozen=True)
class Signing:
    """MAVLink 2 message signing on the vehicle link: state and what was accepted or dropped."""
    status: SigningStatus = SigningStatus.OFF
    detail: str = ""
    link_id: int | None = None           # the link id our signatures carry; None without a key
    allow_unsigned: bool = False         # the pilot lets unsigned frames from the vehicle in
    vehicle_signs: bool | None = None    # the autopilot's last heartbeat was signed; None before one
    signed_accepted: int = 0             # frames whose signature verified with our key
    bad_signature: int = 0               # signed frames dropped: wrong key, replayed or too old
    unsigned_rejected: int = 0           # unsigned frames dropped (MAVLink 1 frames among them)
    unsigned_accepted: int = 0           # unsigned frames let in (RADIO_STATUS, or allowed by the pilot)

    @property
    def counts(self) -> str:
        """What was verified and dropped, in a few words ("" while signing has counted nothing)."""
        parts = [f"{n} {what}" for n, what in ((self.signed_accepted, "verified"),
                                                (self.bad_signature, "bad signatures dropped"),
                                                (self.unsigned_rejected, "unsigned dropped"),
                                                (self.unsigned_accepted, "unsigned let in")) if n]
        return ", ".join(parts)

    @property
    def summary(self) -> str:
        """One line for the pilot: "signing (both ends sign; link id 7): 1200 verified, 3 unsigned dropped"."""
        notes = [n for n in (self.detail, f"link id {self.link_id}" if self.link_id is not None else "",
                             "unsigned frames from the vehicle allowed" if self.allow_unsigned else "") if n]
        text = self.status.value + (f" ({'; '.join(notes)})" if notes else "")
        return text + (f": {self.counts}" if self.counts else "")

__all__ = ["SigningConfig", "LinkSigning", "key_from_passphrase", "read_key_file", "write_key_file",
           "signing_time", "link_id_for", "verify_signature_first", "default_timestamp_path"]

EPOCH_2015 = 1420070400                     # the signing clock's zero, in Unix seconds
UNSIGNED_OK = frozenset({mavlink.MAVLINK_MSG_ID_RADIO, mavlink.MAVLINK_MSG_ID_RADIO_STATUS})   # radios cannot sign
SAVE_INTERVAL = 10.0                        # s between writes of the highest timestamp while signing
SETUP_RESEND = 2.0                          # s between SETUP_SIGNING attempts
SETUP_ATTEMPTS = 3
ARMED_REFUSAL = "won't setup signing when armed"     # ArduPilot's STATUSTEXT (GCS_Signing.cpp)


def key_from_passphrase(passphrase: str) -> bytes:
    """The 32-byte key MAVProxy's ``signing setup PASSPHRASE`` derives."""
    return hashlib.sha256(passphrase.encode("utf-8")).digest()


def read_key_file(path: str) -> bytes:
    """A key file holds the key as 64 hex digits, or a passphrase on its first line.

    Like ssh with its private keys, a file other users can read is refused: the key is the whole secret.
    """
    try:
        st = os.stat(path)
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror or exc}") from exc
    if stat.S_IMODE(st.st_mode) & 0o077:
        raise ValueError(f"{path} can be read by other users: chmod 600 {path}")
    with open(path, encoding="utf-8") as f:
        text = f.read()
    compact = "".join(text.split())
    if len(compact) == 64:
        try:
            return bytes.fromhex(compact)
        except ValueError:
            pass
    first = text.splitlines()[0].strip() if text.strip() else ""
    if not first:
        raise ValueError(f"{path} is empty: it must hold a passphrase or 64 hex digits")
    return key_from_passphrase(first)


def write_key_file(path: str, key: bytes) -> None:
    """Save ``key`` as 64 hex digits, readable only by us (0600), never through a planted symlink."""
    from ..core.files import write_private
    write_private(path, key.hex().encode("ascii") + b"\n")


def signing_time(now: float | None = None) -> int:
    """Now on the signing clock: 10 µs units since 2015-01-01 (as pymavlink's setup_signing)."""
    return int((max(time.time() if now is None else now, EPOCH_2015) - EPOCH_2015) * 100_000)


def link_id_for(description: str) -> int:
    """A link id that stays the same for the same connection string."""
    return zlib.crc32(description.encode("utf-8")) & 0xFF


def default_timestamp_path() -> str:
    base = os.environ.get("XDG_STATE_HOME") or os.path.join(os.path.expanduser("~"), ".local", "state")
    return os.path.join(base, "uavviewer", "signing-timestamp")


def verify_signature_first(codec) -> None:
    """Make ``codec`` check a frame's signature before it records the frame's timestamp.

    pymavlink's check_signature stores the timestamp of a stream first, so one forged frame stamped in the
    future would make every genuine frame of that stream look replayed (the vehicle would fall silent).
    MAVLink's C library checks the signature first; so do we, then let pymavlink check the timestamp.
    """
    check = codec.check_signature

    def verified_then_checked(msgbuf, src_system, src_component):
        secret = codec.signing.secret_key
        if secret is None or hashlib.sha256(secret + bytes(msgbuf[:-6])).digest()[:6] != bytes(msgbuf[-6:]):
            return False
        return check(msgbuf, src_system, src_component)
    codec.check_signature = verified_then_checked


Settled = tuple  # (future, name, CommandStatus, reason): a finished exchange, for the vehicle to record and settle


def _signed(buf) -> bool:
    return len(buf) > 2 and buf[0] == mavlink.PROTOCOL_MARKER_V2 and bool(buf[2] & mavlink.MAVLINK_IFLAG_SIGNED)


class TimestampFile:
    """The highest timestamp sent, kept across restarts (the spec asks for it: clocks go back)."""

    def __init__(self, path: str | None):
        self.path = path
        self.saved = 0

    def load(self) -> int:
        if not self.path:
            return 0
        try:
            with open(self.path, encoding="ascii") as f:
                self.saved = max(0, int(f.read().strip() or 0))
        except (OSError, ValueError):
            self.saved = 0
        return self.saved

    def save(self, stamp: int) -> None:
        if not self.path or stamp <= self.saved:
            return
        from ..core.files import private_dir, write_private
        try:
            private_dir(os.path.dirname(self.path))
            write_private(self.path, f"{stamp}\n".encode("ascii"))
            self.saved = stamp
        except OSError as exc:
            log.warning("cannot keep the signing timestamp in %s: %s", self.path, exc)


@dataclass(frozen=True)
class SigningConfig:
    key: bytes | None = None                  # None: no signing until a key is given
    allow_unsigned: bool = False              # let unsigned frames from the vehicle in (it has no key yet)
    link_id: int | None = None                # None: from the connection string
    timestamp_path: str | None = ""           # "": the per-user default; None: not kept


@dataclass
class _Change:
    """A SETUP_SIGNING exchange in progress: setting a key, or removing it (key of zeros)."""
    key: bytes | None                         # None: removing
    name: str                                 # "signing setup" / "signing remove", as results call it
    future: Future
    old_key: bytes | None
    attempts: int = 0
    next_at: float = 0.0


class LinkSigning:
    """Signing for one vehicle link: configures the driver's codecs, counts what is dropped, runs SETUP_SIGNING.

    Threads: the reader alone counts (:meth:`parser`'s checks, :meth:`rejected`, :meth:`heartbeat`,
    :meth:`statustext`); the ticker calls :meth:`service`; the writer calls :meth:`stamp` under the link's
    transmit lock; keys change under the vehicle's lock and reach the codecs through :attr:`generation`.
    """

    def __init__(self, config: SigningConfig | None, description: str):
        config = config or SigningConfig()
        self.key = config.key
        self.allow_unsigned = config.allow_unsigned
        self.link_id = link_id_for(description) if config.link_id is None else config.link_id
        path = default_timestamp_path() if config.timestamp_path == "" else config.timestamp_path
        self._timestamps = TimestampFile(path)
        self._floor = self._timestamps.load()         # the highest timestamp sent, this run or an earlier one
        self._generation = 0                          # bumped when the incoming check must change
        self._change: _Change | None = None
        self._next_save = 0.0
        self.vehicle_signs: bool | None = None
        self.signed_accepted = self.bad_signature = self.unsigned_rejected = self.unsigned_accepted = 0
        self._mavlink1_rejected = 0
        self._last_good = self._last_bad = 0.0
        self._flagged_bad = False

    # -- codecs ------------------------------------------------------------------------------------
    @property
    def generation(self) -> int:
        return self._generation

    def parser(self):
        """A new incoming codec, checking signatures as the current key says (reader thread)."""
        codec = mavlink.MAVLink(None)
        codec.robust_parsing = True
        key = self.key
        if key is not None:
            codec.signing.secret_key = key
            codec.signing.allow_unsigned_callback = self._unsigned
            codec.signing.timestamp = self._floor
            verify_signature_first(codec)
            check = codec.check_signature

            def counted(msgbuf, src_system, src_component):
                ok = check(msgbuf, src_system, src_component)
                self._flagged_bad = not ok
                if ok:
                    self.signed_accepted += 1
                    self._last_good = time.monotonic()
                return ok
            codec.check_signature = counted
        self._flagged_bad = False
        return codec

    def _unsigned(self, codec, msg_id: int) -> bool:
        """pymavlink asks this for unsigned frames and for signed ones that failed: only the first may pass."""
        if self._flagged_bad:
            self._flagged_bad = False
            return False
        if msg_id in UNSIGNED_OK or self.allow_unsigned or (self._change is not None):
            self.unsigned_accepted += 1
            return True
        return False

    def configure_sender(self, codec, key: bytes | None) -> None:
        """Sign (or stop signing) what ``codec`` packs (caller holds the transmit lock)."""
        sig = codec.signing
        sig.secret_key = key
        sig.sign_outgoing = key is not None
        sig.link_id = self.link_id
        sig.timestamp = max(sig.timestamp, self._floor + 1, signing_time())

    def stamp(self, codec) -> None:
        """Before packing: the timestamp follows the clock and never goes back (transmit lock held)."""
        sig = codec.signing
        if sig.sign_outgoing:
            now = signing_time()
            if now > sig.timestamp:
                sig.timestamp = now
            if sig.timestamp <= self._floor:      # above a SETUP_SIGNING frame packed on a codec of its own
                sig.timestamp = self._floor + 1

    # -- what the reader sees (vehicle lock held) -------------------------------------------------
    def rejected(self, msg) -> None:
        """A frame pymavlink dropped for its signature (BAD_DATA "Invalid signature")."""
        data = getattr(msg, "data", b"")
        if _signed(data):
            self.bad_signature += 1
            self._last_bad = time.monotonic()
        else:
            self.unsigned_rejected += 1
            if data and data[0] == mavlink.PROTOCOL_MARKER_V1:
                self._mavlink1_rejected += 1

    def heartbeat(self, msg) -> Settled | None:
        """The autopilot's heartbeat: does the vehicle sign? Settles a SETUP_SIGNING exchange when it shows."""
        signs = _signed(msg.get_msgbuf())
        self.vehicle_signs = signs
        change = self._change
        if change is None:
            return None
        if change.key is not None and signs:
            self._change = None
            return change.future, change.name, CommandStatus.ACCEPTED, "the vehicle now signs with the new key"
        if change.key is None and not signs:
            self._change = None
            self._use(None)
            return change.future, change.name, CommandStatus.ACCEPTED, "the vehicle no longer signs; signing is off"
        return None

    def statustext(self, text: str) -> Settled | None:
        change = self._change
        if change is not None and ARMED_REFUSAL in text.lower():
            self._change = None
            self._use(change.old_key)
            return change.future, change.name, CommandStatus.REFUSED, text
        return None

    # -- keys (vehicle lock held) ------------------------------------------------------------------
    def use_key(self, key: bytes | None, allow_unsigned: bool | None = None) -> None:
        """Sign with ``key`` from now on (None: stop), without telling the vehicle (MAVProxy's ``signing key``)."""
        if allow_unsigned is not None:
            self.allow_unsigned = allow_unsigned
        self._use(key)

    def _use(self, key: bytes | None) -> None:
        self.key = key
        self._generation += 1

    def begin(self, name: str, key: bytes | None, future: Future, now: float) -> Settled | None:
        """Start SETUP_SIGNING: set ``key`` on the vehicle (None: remove it). ``future`` settles when the
        vehicle's own heartbeats show the change (signed, or unsigned again), or when the attempts run out;
        an exchange still running is returned, replaced."""
        previous = self._change
        self._change = _Change(key, name, future, self.key if previous is None else previous.old_key, next_at=now)
        if key is not None:
            self._use(key)                            # verify the vehicle's frames with the new key at once
        if previous is not None:
            return previous.future, previous.name, CommandStatus.ABORTED, "replaced by a newer signing request"
        return None

    def service(self, now: float, target: tuple[int, int], codec_factory) -> tuple[list[bytes], Settled | None]:
        """Ticker: SETUP_SIGNING frames due now (packed, signed with the key the vehicle has now) and a
        finished exchange, if any; and the highest timestamp saved now and then."""
        frames: list[bytes] = []
        done = None
        change = self._change
        if change is not None and now >= change.next_at:
            if change.attempts >= SETUP_ATTEMPTS:
                self._change = None
                if change.key is not None:
                    self._use(change.old_key)
                done = (change.future, change.name, CommandStatus.TIMED_OUT, "the vehicle's heartbeats never showed the change "
                        "(SETUP_SIGNING lost, or this autopilot cannot sign)")
            else:
                change.attempts += 1
                change.next_at = now + SETUP_RESEND
                frames.append(self._setup_frame(change, target, codec_factory))
        if now >= self._next_save:
            self._next_save = now + SAVE_INTERVAL
            self.save()
        return frames, done

    def _setup_frame(self, change: _Change, target: tuple[int, int], codec_factory) -> bytes:
        codec = codec_factory()
        self.configure_sender(codec, change.old_key)   # a signing telemetry port takes it only signed with that
        secret = change.key or bytes(32)
        stamp = 0 if change.key is None else max(signing_time(), self._floor + 1)
        msg = mavlink.MAVLink_setup_signing_message(target[0], target[1], secret, stamp)
        buf = msg.pack(codec)
        self._floor = max(self._floor, codec.signing.timestamp)
        return bytes(buf)

    def note_sent(self, codec) -> None:
        """The highest timestamp that went out (transmit lock held)."""
        if codec.signing.sign_outgoing and codec.signing.timestamp > self._floor:
            self._floor = codec.signing.timestamp

    def save(self) -> None:
        """Keep the highest timestamp sent (nothing is written until something was signed)."""
        self._timestamps.save(self._floor)

    # -- state -----------------------------------------------------------------------------------------
    def snapshot(self, mavlink_version: int) -> Signing:
        key = self.key
        counts = dict(signed_accepted=self.signed_accepted, bad_signature=self.bad_signature,
                      unsigned_rejected=self.unsigned_rejected, unsigned_accepted=self.unsigned_accepted,
                      vehicle_signs=self.vehicle_signs, allow_unsigned=self.allow_unsigned)
        if self._change is not None:
            doing = "setting the key on" if self._change.key is not None else "removing the key from"
            return Signing(SigningStatus.SETTING_UP, f"{doing} the vehicle (SETUP_SIGNING)",
                           self.link_id, **counts)
        if key is None:
            if self.vehicle_signs:
                return Signing(SigningStatus.REQUIRED, "the vehicle signs; except on its USB port it ignores "
                               "unsigned commands: give its key", None, **counts)
            return Signing(SigningStatus.OFF, "", None, **counts)
        if self._mavlink1_rejected or (mavlink_version == 1 and self.vehicle_signs is False):
            return Signing(SigningStatus.UNAVAILABLE, "the vehicle speaks MAVLink 1, which has no signatures: "
                           "this link cannot be signed", self.link_id, **counts)
        if self._last_bad > self._last_good:
            return Signing(SigningStatus.MISMATCH, "the vehicle's frames do not verify with our key",
                           self.link_id, **counts)
        if self.unsigned_rejected and not self.signed_accepted and not self.allow_unsigned:
            return Signing(SigningStatus.MISMATCH, "the vehicle's frames are unsigned: it has no key yet (allow "
                           "unsigned frames, then set the key up on it)", self.link_id, **counts)
        if self.vehicle_signs is False:
            return Signing(SigningStatus.SIGNING, "we sign; the vehicle's frames are unsigned (it has no key?)",
                           self.link_id, **counts)
        detail = "both ends sign" if self.vehicle_signs else "we sign; waiting for the vehicle"
        return Signing(SigningStatus.SIGNING, detail, self.link_id, **counts)
