"""The truth about a real ArduCopter, read on a loss-free second link (SITL's SERIAL1) with plain pymavlink:
never the project's code. bench/real_sitl.py judges every answer of the driver against it.

A reader thread drains the link all the time (so what is "latest" is never stale and the vehicle never finds the
port full) and hands replies to whoever waits for them. Streams come from SET_MESSAGE_INTERVAL, which changes no
parameter (REQUEST_DATA_STREAM would rewrite the SR1_* parameters the bench compares). The judge sends no
heartbeat: the vehicle routes broadcast messages between its links, and the driver should see no second ground
station.
"""
from __future__ import annotations

import queue
import threading
import time
from dataclasses import dataclass

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink    # mission_type needs MAVLink 2, whatever mavutil's

PREARM_CHECK = 0x10000000                      # MAV_SYS_STATUS_PREARM_CHECK
#: message id -> interval in microseconds
STREAMS = {
    mavlink.MAVLINK_MSG_ID_SYS_STATUS: 500_000,
    mavlink.MAVLINK_MSG_ID_GPS_RAW_INT: 1_000_000,
    mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 250_000,
    mavlink.MAVLINK_MSG_ID_MISSION_CURRENT: 250_000,
    mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 500_000,
    mavlink.MAVLINK_MSG_ID_HOME_POSITION: 1_000_000,
}
STREAM_CHECK = 2.0                             # s between checks that every stream flows (asked again if not)


@dataclass(frozen=True)
class HeldItem:
    """A plan item as the vehicle holds it (MISSION_ITEM_INT)."""
    command: int
    frame: int
    param1: float
    x: int                                     # latitude e7
    y: int                                     # longitude e7
    z: float


class Judge:
    """SERIAL1 of a SITL on 127.0.0.1:``port``."""

    def __init__(self, port: int, connect_timeout: float = 30.0):
        # SERIAL1 listens only once SERIAL0 is connected: pymavlink retries a second apart
        self.conn = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", source_system=254, source_component=191,
                                               retries=int(connect_timeout))
        self.conn.mav = mavlink.MAVLink(self.conn, srcSystem=254, srcComponent=191)   # MAVLink 2 whatever the
        self.conn.mav.robust_parsing = True                                            # process chose before
        self._latest: dict = {}
        self._lock = threading.Lock()
        self._send_lock = threading.Lock()
        self._waiters: list = []
        self.texts: list[tuple[float, int, str]] = []      # (monotonic time, severity, text)
        self.reached: list[int] = []                        # MISSION_ITEM_REACHED seqs
        self.changes: list[tuple[float, str, bool]] = []    # (monotonic time, mode, armed) as each changed
        self.prearm_changes: list[tuple[float, bool]] = []  # (monotonic time, pre-arm bit) as it changed
        self._closing = threading.Event()
        self._thread = threading.Thread(target=self._read, name="judge", daemon=True)
        self._thread.start()
        self.ask_streams()

    # -- the link ------------------------------------------------------------------------------------
    def _read(self) -> None:
        next_check = time.monotonic() + STREAM_CHECK
        while not self._closing.is_set():
            if time.monotonic() >= next_check:
                next_check = time.monotonic() + STREAM_CHECK
                self._keep_streams()
            try:
                m = self.conn.recv_match(blocking=True, timeout=0.2)
            except (OSError, ValueError):
                if self._closing.is_set():
                    return
                time.sleep(0.1)
                continue
            if m is None or m.get_type() == "BAD_DATA":
                continue
            if m.get_srcSystem() != 1:
                continue                       # another ground station routed to us
            mtype = m.get_type()
            with self._lock:
                if m.get_srcComponent() == 1 or mtype != "HEARTBEAT":
                    self._latest[mtype] = (time.monotonic(), m)
                if mtype == "HEARTBEAT" and m.get_srcComponent() == 1:
                    now = (mavutil.mode_string_v10(m), bool(m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED))
                    if not self.changes or self.changes[-1][1:] != now:
                        self.changes.append((time.monotonic(), *now))
                if mtype == "SYS_STATUS" and m.get_srcComponent() == 1:
                    bit = bool(m.onboard_control_sensors_health & PREARM_CHECK)
                    if not self.prearm_changes or self.prearm_changes[-1][1] != bit:
                        self.prearm_changes.append((time.monotonic(), bit))
                if mtype == "STATUSTEXT":
                    self.texts.append((time.monotonic(), m.severity, m.text))
                elif mtype == "MISSION_ITEM_REACHED":
                    self.reached.append(m.seq)
                for match, q in self._waiters:
                    if match(m):
                        q.put(m)

    def send(self, msg) -> None:
        with self._send_lock:                  # the reader thread asks for streams too
            self.conn.mav.send(msg)

    def _keep_streams(self) -> None:
        """Ask again for every stream that is not flowing. A request that reaches SERIAL1 before the vehicle has
        set up that port's intervals is overwritten by them (GCS_MAVLINK::update_send runs
        initialise_message_intervals_from_streamrates once, and SR1_* are 0): the judge then saw no SYS_STATUS at
        all and called a ready vehicle's pre-arm check failing."""
        now = time.monotonic()
        with self._lock:
            newest = {t: e[0] for t, e in self._latest.items()}
        stale = {i: interval for i, interval in STREAMS.items()
                 if now - newest.get(mavlink.mavlink_map[i].msgname, -1e9) > 3 * interval / 1e6 + 1.0}
        if stale:
            self.ask_streams(stale)

    def ask_streams(self, streams: dict | None = None) -> None:
        for msg_id, interval in (streams or STREAMS).items():
            self.send(mavlink.MAVLink_command_long_message(1, 1, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                                                           msg_id, interval, 0, 0, 0, 0, 0))

    def close(self) -> None:
        self._closing.set()
        self._thread.join(1.0)
        try:
            self.conn.close()
        except OSError:
            pass

    def latest(self, mtype: str, max_age: float = 5.0):
        with self._lock:
            entry = self._latest.get(mtype)
        return entry[1] if entry and time.monotonic() - entry[0] <= max_age else None

    def wait(self, predicate, timeout: float) -> bool:
        """Poll ``predicate()`` until it holds or ``timeout`` passes."""
        deadline = time.monotonic() + timeout
        while True:
            if predicate():
                return True
            if time.monotonic() > deadline:
                return False
            time.sleep(0.05)

    def _ask(self, msg, match, timeout: float, tries: int):
        """Send ``msg`` until a reply matching ``match`` comes (None after ``tries``)."""
        q: queue.Queue = queue.Queue()
        entry = (match, q)
        with self._lock:
            self._waiters.append(entry)
        try:
            for _ in range(tries):
                self.send(msg)
                try:
                    return q.get(timeout=timeout)
                except queue.Empty:
                    continue
            return None
        finally:
            with self._lock:
                self._waiters.remove(entry)

    def command(self, command: int, *params: float, timeout: float = 1.0, tries: int = 3):
        """COMMAND_LONG to the vehicle until its COMMAND_ACK comes (None after ``tries``)."""
        params = (list(params) + [0.0] * 7)[:7]
        return self._ask(mavlink.MAVLink_command_long_message(1, 1, command, 0, *params),
                         lambda m: m.get_type() == "COMMAND_ACK" and m.command == command, timeout, tries)

    # -- the vehicle's state ---------------------------------------------------------------------------
    @property
    def mode(self) -> str:
        hb = self.latest("HEARTBEAT")
        return mavutil.mode_string_v10(hb) if hb else "?"

    @property
    def armed(self) -> bool | None:
        hb = self.latest("HEARTBEAT")
        return bool(hb.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED) if hb else None

    @property
    def prearm_ok(self) -> bool:
        s = self.latest("SYS_STATUS", 2.0)
        return bool(s and s.onboard_control_sensors_health & PREARM_CHECK)

    @property
    def home(self):
        return self.latest("HOME_POSITION", 1e9)

    @property
    def mission_current(self):
        """(seq, mission_state) of MISSION_CURRENT, or None."""
        m = self.latest("MISSION_CURRENT", 2.0)
        return (m.seq, getattr(m, "mission_state", 0)) if m else None

    @property
    def altitude(self) -> float | None:
        p = self.latest("GLOBAL_POSITION_INT", 2.0)
        return p.relative_alt / 1000.0 if p else None

    def ages(self) -> str:
        """How old the newest of each streamed message is, in words (a judge whose streams stopped sees nothing)."""
        now = time.monotonic()
        with self._lock:
            got = {t: now - e[0] for t, e in self._latest.items()}
        return ", ".join(f"{mavlink.mavlink_map[i].msgname} {got[mavlink.mavlink_map[i].msgname]:.1f} s"
                         if mavlink.mavlink_map[i].msgname in got else f"{mavlink.mavlink_map[i].msgname} never"
                         for i in STREAMS)

    def story(self, since: float) -> str:
        """What the vehicle did since ``since``: its mode and arming changes and its texts, with the seconds."""
        with self._lock:
            events = [(t, f"{mode} {'armed' if armed else 'disarmed'}") for t, mode, armed in self.changes if t >= since]
            events += [(t, repr(text)) for t, _, text in self.texts if t >= since]
            events += [(t, f"pre-arm bit {'set' if bit else 'clear'}") for t, bit in self.prearm_changes if t >= since]
        return "; ".join(f"{t - since:.1f} s {what}" for t, what in sorted(events))

    # -- plans ----------------------------------------------------------------------------------------------
    def read_plan(self, kind: int, timeout: float = 20.0) -> list[HeldItem] | None:
        """The plan of ``kind`` (MAV_MISSION_TYPE) the vehicle holds, the mission without its home slot; None when
        it cannot be read (an upload on the other link holds the protocol: DENIED, retried until ``timeout``)."""
        deadline = time.monotonic() + timeout
        count = None
        while count is None and time.monotonic() < deadline:
            reply = self._ask(mavlink.MAVLink_mission_request_list_message(1, 1, kind),
                              lambda m: m.get_type() in ("MISSION_COUNT", "MISSION_ACK")
                              and getattr(m, "mission_type", 0) == kind, 1.5, 1)
            if reply is not None and reply.get_type() == "MISSION_COUNT":
                count = reply.count
            else:
                time.sleep(0.5)
        if count is None:
            return None
        items = []
        for seq in range(count):
            item = self._ask(mavlink.MAVLink_mission_request_int_message(1, 1, seq, kind),
                             lambda m, seq=seq: m.get_type() == "MISSION_ITEM_INT" and m.seq == seq
                             and getattr(m, "mission_type", 0) == kind, 1.0, 5)
            if item is None:
                return None
            items.append(HeldItem(item.command, item.frame, item.param1, item.x, item.y, item.z))
        self.send(mavlink.MAVLink_mission_ack_message(1, 1, mavlink.MAV_MISSION_ACCEPTED, kind))
        return items[1:] if kind == mavlink.MAV_MISSION_TYPE_MISSION else items

    # -- parameters -------------------------------------------------------------------------------------------
    def param(self, name: str) -> tuple[float, int] | None:
        """(value, MAV_PARAM_TYPE) of ``name``; None when the vehicle does not answer (it has no such parameter)."""
        reply = self._ask(mavlink.MAVLink_param_request_read_message(1, 1, name.encode(), -1),
                          lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == name, 1.0, 3)
        return (reply.param_value, reply.param_type) if reply else None

    def all_params(self, timeout: float = 30.0) -> dict[str, tuple[float, int]]:
        """Every parameter: PARAM_REQUEST_LIST, then the missing indexes one by one."""
        q: queue.Queue = queue.Queue()
        entry = (lambda m: m.get_type() == "PARAM_VALUE", q)
        by_index: dict[int, tuple[str, float, int]] = {}
        count = None
        with self._lock:
            self._waiters.append(entry)
        try:
            self.send(mavlink.MAVLink_param_request_list_message(1, 1))
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline and (count is None or len(by_index) < count):
                try:
                    m = q.get(timeout=1.0)
                except queue.Empty:
                    for i in [i for i in range(count or 0) if i not in by_index][:20]:
                        self.send(mavlink.MAVLink_param_request_read_message(1, 1, b"", i))
                    if count is None:
                        self.send(mavlink.MAVLink_param_request_list_message(1, 1))
                    continue
                count = m.param_count
                if 0 <= m.param_index < 65535:
                    by_index[m.param_index] = (m.param_id, m.param_value, m.param_type)
        finally:
            with self._lock:
                self._waiters.remove(entry)
        return {name: (value, ptype) for name, value, ptype in by_index.values()}

    # -- logs -----------------------------------------------------------------------------------------------
    def logs(self, timeout: float = 5.0) -> list:
        """LOG_ENTRY of every log (ids 0..0xffff only: a list beyond the last log floods), disarmed only."""
        q: queue.Queue = queue.Queue()
        entry = (lambda m: m.get_type() == "LOG_ENTRY", q)
        with self._lock:
            self._waiters.append(entry)
        entries = {}
        try:
            self.send(mavlink.MAVLink_log_request_list_message(1, 1, 0, 0xFFFF))
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline:
                try:
                    m = q.get(timeout=0.5)
                except queue.Empty:
                    if entries:
                        break
                    continue
                if m.size:
                    entries[m.id] = m
                if m.num_logs and len(entries) >= m.num_logs:
                    break
        finally:
            with self._lock:
                self._waiters.remove(entry)
        return [entries[i] for i in sorted(entries)]
