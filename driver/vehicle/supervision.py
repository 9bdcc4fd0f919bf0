"""Link supervision: is the vehicle there, how healthy is the link, and what must we ask it for.

Counts frames and sequence gaps per component, ages the autopilot's heartbeat, declares the link lost
and recovered, decides when a half-open TCP link must be reopened, and asks the vehicle for what a
ground station needs and does not get unasked: its streams (again when it forgets them, e.g. after a
reboot), its firmware version (AUTOPILOT_VERSION), its home position (REQUEST_MESSAGE, or MAV_CMD_GET_HOME_POSITION on firmware without it, again
after arming since arming sets home), FS_GCS_ENABLE (is there a GCS failsafe if we go away?), the fence's
parameters (FENCE_ENABLE, FENCE_TYPE, FENCE_RADIUS, FENCE_ALT_MAX: where the vehicle itself will not go) and what
a mission plan's times rest on (WPNAV_SPEED and the rest of PLAN_PARAMS: a plan is timed at the vehicle's own
speeds from the start, not at defaults until the whole table is read). Each is read by name (PARAM_REQUEST_READ)
into the parameter table, state().parameters.
Runs with the driver's state lock held and returns the MAVLink messages to send; sends nothing itself.
"""
from __future__ import annotations

import collections

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .commands import Capabilities
from .state import FENCE_PARAMS, LinkHealth, LinkStatus

__all__ = ["LinkSupervisor"]

HOME_RETRY = 2.0             # s between home requests while the vehicle has not sent it
PARAM_RETRY = 3.0            # s between reads of the parameters below while some are unanswered
PARAM_TRIES = 3
STREAM_SILENCE = 3.0         # s without one of STREAM_WATCH before the streams are asked for again
# a message of each stream the pilot's screen lives on (EXTRA1, EXTENDED_STATUS, POSITION): one REQUEST_DATA_STREAM
# lost on a lossy link leaves that stream off while the others flow (at 30 % loss each way real SITL never sent
# SYS_STATUS nor GPS_RAW_INT, and the driver never told it ready to arm)
STREAM_WATCH = ("ATTITUDE", "SYS_STATUS", "GLOBAL_POSITION_INT")
ADSB_RATE_HZ = 5.0           # ADSB_VEHICLE asked for: one aircraft of the list each time (see stream_requests)
REOPEN_AFTER = 5.0           # s past the loss timeout before a reconnectable link is reopened
PLAN_PARAMS = ("WPNAV_SPEED", "WPNAV_SPEED_UP", "WPNAV_SPEED_DN", "LAND_SPEED", "RTL_ALT", "BATT_CAPACITY")
WANTED_PARAMS = ("FS_GCS_ENABLE",) + FENCE_PARAMS + PLAN_PARAMS


class LinkSupervisor:
    def __init__(self, config, transport, capabilities: Capabilities, target, clock):
        self._cfg = config
        self._transport = transport
        # what ages the heartbeat: the vehicle's clock, or the recording's when replaying one
        self._clock = transport.clock if transport.is_replay else clock
        self._caps = capabilities
        self._target = target                 # () -> (system, component)
        self.status = LinkStatus.WAITING
        self.lost_count = 0
        self.lost_at = 0.0
        self.last_heartbeat: float | None = None          # self._clock
        self.last_heard = dict.fromkeys(STREAM_WATCH, 0.0)   # the vehicle's clock, by message
        self.rx_count = 0
        self.rx_lost = 0
        self.bad_crc = 0
        self.duplicates = 0                   # frames received twice (dropped: an answer counts once)
        self.last_seq: dict[int, int] = {}
        self._window: collections.deque[tuple[float, int, int]] = collections.deque(maxlen=6)
        self._streams_at: float | None = None
        self._home_wanted_since: float | None = None
        self._home_asked_at = -1e9
        self._home_tries = 0
        self._param_tries = 0
        self._param_asked_at = -1e9
        self.params_known: set[str] = set()
        self.version_known = False
        self._version_tries = 0
        self._version_asked_at = -1e9
        self._seeks = 0                       # a replay's seeks seen: its clock jumps, no heartbeat was missed

    # -- frames (reader thread; the driver counts rx_count, rx_lost and last_seq inline, the hot path) ------
    def reset_sequences(self) -> None:
        self.last_seq.clear()

    def heartbeat(self, now: float) -> str | None:
        """The autopilot's heartbeat; returns "first", "recovered" or None (no change of status)."""
        self.last_heartbeat = self._clock()
        if self.status is LinkStatus.OK:
            return None
        recovered = self.status is LinkStatus.LOST
        self.status = LinkStatus.OK
        if not self._transport.is_replay:
            self._streams_at = None               # ask at once, before anyone sees the link up
            self._home_wanted_since = now
            self._param_tries = 0
            self._version_tries = 0 if not self.version_known else PARAM_TRIES
        return "recovered" if recovered else "first"

    def armed_changed(self, armed: bool, now: float) -> None:
        if armed:                                 # arming sets home: ask for the new one
            self._home_wanted_since, self._home_tries = now, 0

    def home_received(self) -> None:
        self._home_wanted_since = None

    # -- the ticker (lock held) -----------------------------------------------------------------------------
    def tick(self, now: float) -> tuple[list, str | None, bool]:
        """(messages to send, "lost" when the link was just lost or "finished" when a replay just ended, whether
        to reopen the link)."""
        out: list = []
        event = None
        reopen = False
        cfg = self._cfg
        clock = self._clock()
        if self._transport.is_replay and self._transport.seeks != self._seeks:
            self._seeks = self._transport.seeks   # the pilot moved in the recording: its heartbeats count from there
            if self.last_heartbeat is not None:
                self.last_heartbeat = clock
        if (self.status is LinkStatus.LOST and self._transport.reconnectable and self.last_heartbeat is not None
                and clock - self.last_heartbeat > cfg.loss_timeout + REOPEN_AFTER and now - self.lost_at > REOPEN_AFTER):
            self.lost_at = now
            reopen = True                         # a half-open TCP link never errors: reopen it
        if not self._window or now - self._window[-1][0] >= 1.0:
            self._window.append((now, self.rx_count, self.rx_lost))
        if self.status is LinkStatus.OK and self._transport.is_replay and self._transport.finished:
            self.status = LinkStatus.CLOSED       # the recording has ended: no heartbeat is live any more
            event = "finished"
        if self.last_heartbeat is not None and self.status is LinkStatus.OK:
            if clock - self.last_heartbeat > cfg.loss_timeout:
                self.status = LinkStatus.LOST
                self.lost_at = now
                self.lost_count += 1
                event = "lost"
            elif not self._transport.is_replay:
                out += self._requests(now)
        return out, event, reopen

    def _requests(self, now: float) -> list:
        out = []
        silent = any(now - heard > STREAM_SILENCE for heard in self.last_heard.values())
        if self._streams_at is None or (silent and now - self._streams_at > 5.0):
            out += self.stream_requests()
            self._streams_at = now
        if self._home_wanted_since is not None and now - self._home_asked_at >= HOME_RETRY:
            out += self._home_request()
            self._home_asked_at = now
        if not self.version_known and self._version_tries < PARAM_TRIES and now - self._version_asked_at >= PARAM_RETRY:
            system, component = self._target()           # AUTOPILOT_VERSION: understood since ArduCopter 3.2
            out.append(mavlink.MAVLink_command_long_message(
                system, component, mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 0, 1, 0, 0, 0, 0, 0, 0))
            self._version_tries += 1
            self._version_asked_at = now
        missing = [name for name in WANTED_PARAMS if name not in self.params_known]
        if missing and self._param_tries < PARAM_TRIES and now - self._param_asked_at >= PARAM_RETRY:
            system, component = self._target()
            out += [mavlink.MAVLink_param_request_read_message(system, component, name.encode(), -1)
                    for name in missing]
            self._param_tries += 1
            self._param_asked_at = now
        return out

    def param_received(self, name: str) -> None:
        """A PARAM_VALUE for ``name``: not asked for again."""
        self.params_known.add(name)

    def stream_requests(self) -> list:
        """REQUEST_DATA_STREAM as MAVProxy, plus per-message intervals where the firmware has them."""
        cfg = self._cfg
        system, component = self._target()
        rate = max(1, int(cfg.stream_rate))
        fast = max(rate, int(cfg.attitude_rate))
        out = [mavlink.MAVLink_request_data_stream_message(system, component, stream, hz, 1)
               for stream, hz in ((mavlink.MAV_DATA_STREAM_EXTENDED_STATUS, rate),
                                  (mavlink.MAV_DATA_STREAM_POSITION, rate),
                                  (mavlink.MAV_DATA_STREAM_EXTRA1, fast),
                                  (mavlink.MAV_DATA_STREAM_EXTRA2, fast),
                                  (mavlink.MAV_DATA_STREAM_EXTRA3, max(1, rate // 2)),
                                  (mavlink.MAV_DATA_STREAM_RAW_SENSORS, max(1, rate // 2)))]
        if self._caps.message_interval is not False:   # 4.7 sends EXTENDED_SYS_STATE only when asked so
            for msg_id, hz in ((mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, rate),
                               (mavlink.MAVLINK_MSG_ID_HOME_POSITION, 0.5),
                               # ADS-B traffic is in no data stream (SRn_ADSB, 0 by default): unasked, 4.6.3
                               # SITL sent none in 40 s; at 5 Hz, one aircraft of its list each time, every
                               # aircraft about once a second (AP_ADSB::send_adsb_vehicle), as the recording
                               (mavlink.MAVLINK_MSG_ID_ADSB_VEHICLE, ADSB_RATE_HZ)):
                out.append(mavlink.MAVLink_command_long_message(
                    system, component, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0, msg_id, 1e6 / hz, 0, 0, 0, 0, 0))
        return out

    def _home_request(self) -> list:
        system, component = self._target()
        self._home_tries += 1
        if self._caps.request_message is not False and self._home_tries % 2:
            return [mavlink.MAVLink_command_long_message(system, component, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
                                                         mavlink.MAVLINK_MSG_ID_HOME_POSITION, 0, 0, 0, 0, 0, 0)]
        return [mavlink.MAVLink_command_long_message(system, component, mavlink.MAV_CMD_GET_HOME_POSITION, 0,
                                                     0, 0, 0, 0, 0, 0, 0)]

    def health(self, mavlink_version: int, status: LinkStatus | None = None) -> LinkHealth:
        clock = self._clock()
        age = None if self.last_heartbeat is None else max(0.0, clock - self.last_heartbeat)
        rate = loss = 0.0
        if len(self._window) >= 2:
            (t0, c0, l0), (t1, c1, l1) = self._window[0], self._window[-1]
            if t1 > t0:
                rate = (c1 - c0) / (t1 - t0)
            if (c1 - c0) + (l1 - l0) > 0:
                loss = 100.0 * (l1 - l0) / ((c1 - c0) + (l1 - l0))
        pinned = self._transport.pinned
        status = status or self.status
        ended = status is LinkStatus.CLOSED and self._transport.is_replay and self._transport.finished
        return LinkHealth(status, self._transport.description, age, rate, loss, self.rx_count,
                          self.rx_lost, self.bad_crc, mavlink_version, self.lost_count, self._transport.foreign,
                          f"{pinned[0]}:{pinned[1]}" if pinned else "", ended, self._transport.is_replay)
