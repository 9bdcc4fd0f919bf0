"""The simulated ArduCopter's log download over LOG_* messages, as ArduCopter 4.6.3 answers them
(tests/data/recordings/arducopter-4.6-sitl-logs.*, AP_Logger_MAVLinkLogTransfer.cpp), and its logging while armed.

Mixed into the Autopilot. What the recording shows, quirks included:

* LOG_REQUEST_LIST (start, end): ``end`` is clamped to the last log, then LOG_ENTRY counts from ``start`` up (the
  id wrapping past 65535) until it has sent ``end``, the first on receipt (handle_log_request_list calls
  handle_log_send_listing), the others one a call: ids that do not exist come with size 0 and time 0, about
  :data:`LIST_RATE` a second, so a list of ids past the last log floods for ~40 s unless LOG_REQUEST_END stops it.
  With no log at all: one LOG_ENTRY id 0, num_logs 0. While a listing or a transfer runs, a new LOG_REQUEST_LIST
  or LOG_REQUEST_DATA is dropped (AP_Logger_MAVLinkLogTransfer.cpp: "Log download in progress", except for a
  LOG_REQUEST_DATA on the link being served: silence, as the recording shows during a listing): a request never
  replaces the stream under way.
* LOG_REQUEST_DATA (id, ofs, count): LOG_DATA of 90 bytes in order until ``count`` is sent or a packet comes out
  short (the end of the log, whose size is taken at the request); an offset past the end: one LOG_DATA of count
  0; an unknown id: nothing. As handle_log_request_data does, the request is served AT ONCE, on receipt, up to
  the link's packets per call (:meth:`LogServer._log_sends`: handle_log_sending's num_sends) and the room in the
  port's transmit buffer (HAVE_PAYLOAD_SPACE); a request that ends within them ends the transfer there, so the
  next request of the same batch is served too (MAVProxy streams its gap requests so). What is left of a longer
  request goes on every step (update_send), and requests that come meanwhile are dropped. The Solo (3.3,
  3drobotics/ardupilot-solo GCS_Logs.cpp) drops nothing: a request for the log being sent moves the transfer to
  its offset and count (``_log_sending`` is only re-armed).
* The transmit buffer (:attr:`LogServer.log_room`, in LOG_DATA) refills with sim time at the link's rate, up to
  what one step carries (:data:`MAX_DATA_STEP` over TCP) or a radio port's buffer (:data:`RADIO_TX_BUFFER`).
* LOG_REQUEST_END stops either, but :data:`QUEUED_AFTER_END` LOG_DATA already queued still go out.
* Armed: every LOG_* request is ignored, the first with STATUSTEXT severity 3 "Disarm for log download".
* LOG_ERASE: no reply.

The sim logs only while armed (logs.py begins a log at arming, closes it at disarming): FMT, PARM, MODE, MSG,
ATT, GPS, BAT, CTUN at :data:`LOG_RATE`, CAM on each photo (dataflash.py writes the files).
"""
from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .dataflash import LogFolder

__all__ = ["LogServer", "LOG_DATA_SIZE", "LOG_DATA_RATE", "LIST_RATE", "SENDS_SITL", "SENDS_FLOW_CONTROL",
           "SENDS_RADIO"]

LOG_DATA_SIZE = 90               # bytes in one LOG_DATA
LOG_DATA_RATE = 61_000.0         # LOG_DATA a (sim) second over TCP: the recording's 6.6 MB in 1.2 s
LOG_DATA_FRAME = 12 + 97         # a LOG_DATA frame's bytes (MAVLink 2), for a radio's budget
MAX_DATA_STEP = 600              # LOG_DATA one sim step sends at most (the sim's own CPU: telemetry keeps flowing)
# LOG_DATA one handle_log_sending call sends at most (num_sends, AP_Logger_MAVLinkLogTransfer.cpp):
SENDS_SITL = 40                  # SITL ("assume USB speeds"): the TCP link of the copter-4 profile
SENDS_FLOW_CONTROL = 10          # a serial port with flow control: the Solo's telemetry UART to its companion
                                 # computer (sololink.conf: telemBaud=921600, telemFlow=True; 3.3 has the same 10)
SENDS_RADIO = 1                  # a serial radio without flow control (``radio_baud`` on the copter-4 profile)
RADIO_TX_BUFFER = 1024           # bytes a radio port's transmit buffer holds (ChibiOS: HAL_UART_MIN_TX_SIZE 512,
                                 # doubled on boards with the memory)
LIST_RATE = 1_600.0              # LOG_ENTRY a second (the recording's flood)
QUEUED_AFTER_END = 243           # LOG_DATA that still arrive after LOG_REQUEST_END (the recording)
LOG_RATE = 10.0                  # Hz of ATT, CTUN, BAT (GPS at half of it)
DISARM_TEXT = "Disarm for log download"
BUSY_TEXT = "Log download in progress"


class LogServer:
    """State on the Autopilot: ``log_folder`` (dataflash.LogFolder), the listing and the transfer."""

    log_folder_: LogFolder | None = None
    log_listing: list | None = None       # [peer, next id, last id, num_logs]
    log_sending: list | None = None       # [peer, id, ofs, bytes left, packets left after END or None, file]
    log_told_armed = False
    log_room = 0.0                          # LOG_DATA the port's transmit buffer takes now
    log_room_t: float | None = None         # sim time it was last refilled at
    log_sizes: tuple | None = None          # (sim time, {log id: size}, file numbers) for the requests of one step
    log_list_credit = 0.0
    log_next_sample = 0.0
    log_mode = None
    log_gps_tick = 0

    @property
    def log_folder(self) -> LogFolder:
        if self.log_folder_ is None:
            self.log_folder_ = LogFolder(getattr(self.config, "log_dir", None))
        return self.log_folder_

    # -- requests ------------------------------------------------------------------------------------------
    def _log_refused(self) -> bool:
        """Armed: ignored, the first time with ArduPilot's text (AP_Logger::handle_mavlink_msg)."""
        if not self.armed:
            return False
        if not self.log_told_armed:
            self.log_told_armed = True
            self._text(mavlink.MAV_SEVERITY_ERROR, DISARM_TEXT)
        return True

    def _log_busy(self, data: bool = False) -> bool:
        """A listing or a transfer runs (ArduPilot's _log_sending_link): a new LIST or DATA is dropped, with
        "Log download in progress" unless it is a LOG_REQUEST_DATA on the link being served. The Solo (3.3) has
        no such check for LOG_REQUEST_DATA: it moves the transfer (``data``)."""
        busy = self.log_listing or self.log_sending
        if busy is None or (busy is self.log_sending and busy[4] is not None):
            return False                                # what follows LOG_REQUEST_END is only the queue
        if data and self._log_request_moves():
            self.log_listing = None                     # (3.3: "_log_listing = false")
            return False
        return True

    def _log_request_moves(self) -> bool:
        """3.3's handle_log_request_data sets the offset and count of the transfer under way."""
        return self.profile.name == "solo"

    def _log_sends(self) -> int:
        """num_sends: LOG_DATA one call of handle_log_sending sends at most, by the link."""
        if self.profile.name == "solo":
            return SENDS_FLOW_CONTROL
        return SENDS_RADIO if getattr(self.config, "radio_baud", None) else SENDS_SITL

    def _log_refill(self) -> None:
        """The transmit buffer empties onto the link as sim time passes: LOG_DATA_RATE over TCP, the baud on a
        radio; it holds what one step sends (TCP) or RADIO_TX_BUFFER (a radio)."""
        if self.log_room_t == self.t:
            return
        rate, dt = LOG_DATA_RATE, 1.0 / self.config.rate_hz
        baud = getattr(self.config, "radio_baud", None)
        if baud:
            rate = min(rate, baud / 10.0 / LOG_DATA_FRAME)
            cap = max(rate * dt + 1, RADIO_TX_BUFFER // LOG_DATA_FRAME)
        else:
            cap = min(rate * dt + 1, MAX_DATA_STEP)
        elapsed = dt if self.log_room_t is None else self.t - self.log_room_t
        self.log_room = min(self.log_room + rate * elapsed, cap)
        self.log_room_t = self.t

    def _log_send(self, budget: float) -> None:
        """Send LOG_DATA of the transfer while ``budget`` and the transmit buffer allow (handle_log_sending)."""
        self._log_refill()
        while self.log_sending is not None and budget >= 1 and self.log_room >= 1:
            self.log_room -= 1
            budget -= 1
            self._log_data()

    def _on_log_request_list(self, msg) -> None:
        if self._log_refused():
            return
        if self._log_busy():
            self._text(mavlink.MAV_SEVERITY_INFO, BUSY_TEXT)
            return
        entries = self.log_folder.entries()
        last = entries[-1][0] if entries else 0
        if not entries:
            self.log_listing = [self.sender, 0, 0, 0]
        else:
            self.log_listing = [self.sender, max(1, msg.start), min(msg.end, last), len(entries)]
        self._log_entry()                               # the first at once (handle_log_send_listing): a list of one
                                                        # log ends within its request

    def _on_log_request_data(self, msg) -> None:
        if self._log_refused():
            return
        if self._log_busy(data=True):
            busy = self.log_listing or self.log_sending
            if busy[0] is not self.sender:
                self._text(mavlink.MAV_SEVERITY_INFO, BUSY_TEXT)
            return                                      # dropped (the recording: during a listing, silently)
        folder = self.log_folder
        size = self._log_size(msg.id)
        if size is None:
            self.log_sending = None
            return                                      # an unknown id: nothing at all
        number = self._log_file_number(msg.id)          # the id is a place in the list (log_num_from_list_entry)
        if number == folder.current:
            folder.end()                                # a download closes the log being written
            self.log_sizes = None
            size = self._log_size(msg.id)
        remaining = min(msg.count, max(0, size - msg.ofs))   # the size as it is now (get_log_info)
        self.log_sending = [self.sender, msg.id, msg.ofs, remaining, None, number]
        self._log_send(self._log_sends())               # at once, within the same batch of requests

    def _log_size(self, list_id: int) -> int | None:
        """get_log_info's size of LOG_ENTRY id ``list_id`` (None: no such log), read from the folder once a sim
        step: disarmed, nothing is written between, and a batch of requests would otherwise list the folder for
        each one."""
        return self._log_listed()[1].get(list_id)

    def _log_listed(self) -> tuple:
        """(sim time, {list id: size}, the files' numbers), read once a sim step."""
        cached = self.log_sizes
        if cached is None or cached[0] != self.t:
            folder = self.log_folder
            numbers = folder.numbers()
            cached = self.log_sizes = (self.t, {e[0]: e[1] for e in folder.entries()}, numbers)
        return cached

    def _log_file_number(self, list_id: int) -> int:
        """LogFolder.file_number from the step's listing: a batch of requests would list the folder for each."""
        return self.log_folder.file_number(list_id, self._log_listed()[2])

    def _on_log_request_end(self, msg) -> None:
        if self._log_refused():
            return
        self.log_listing = None
        if self.log_sending is not None and self.log_sending[4] is None:
            self.log_sending[4] = QUEUED_AFTER_END      # what was queued already still goes out

    def _on_log_erase(self, msg) -> None:
        if self._log_refused():
            return                                      # (ArduPilot erases even during a transfer)
        self.log_listing = self.log_sending = self.log_sizes = None
        self.log_folder.erase()

    # -- each step -----------------------------------------------------------------------------------------
    def logs_step(self, dt: float) -> None:
        self._log_record()
        if self.log_listing is not None:
            self.log_list_credit = min(self.log_list_credit + LIST_RATE * dt, LIST_RATE * dt + 1)
            while self.log_listing is not None and self.log_list_credit >= 1:
                self.log_list_credit -= 1
                self._log_entry()
        else:
            self.log_list_credit = 0.0
        self._log_send(math.inf)                        # update_send: a long transfer goes on

    def _log_entry(self) -> None:
        peer, number, last, count = self.log_listing
        size = stamp = 0
        if number:
            for entry in self.log_folder.entries():
                if entry[0] == number:
                    size, stamp = entry[1], entry[2]
                    break
        self.emit_to(self.factory.log_entry_encode(number, count, last, stamp, size), peer)
        if number == last:
            self.log_listing = None
        else:
            self.log_listing[1] = (number + 1) & 0xFFFF

    def _log_data(self) -> None:
        sending = self.log_sending
        peer, log_id, ofs, remaining, after_end, number = sending
        n = min(LOG_DATA_SIZE, remaining)
        data = self.log_folder.read(number, ofs, n) or b"" if n else b""
        self.emit_to(self.factory.log_data_encode(log_id, ofs, len(data), data.ljust(LOG_DATA_SIZE, b"\0")), peer)
        sending[2], sending[3] = ofs + n, remaining - n
        if after_end is not None:
            sending[4] = after_end - 1
        if len(data) < LOG_DATA_SIZE or sending[3] <= 0 or (after_end is not None and after_end <= 1):
            self.log_sending = None

    # -- logging while armed -------------------------------------------------------------------------------
    def _log_record(self) -> None:
        folder = self.log_folder_ if not self.armed else self.log_folder
        if not self.armed:
            self.log_told_armed = False
            if folder is not None and folder.current is not None:
                folder.end()
            return
        if folder.current is None:
            folder.begin(self.params.items())
            self.log_mode = None
            self.log_next_sample = self.t
        us = int(self.boot_seconds * 1e6)
        if self.mode != self.log_mode:
            self.log_mode = self.mode
            folder.write("MODE", us, self.mode, self.mode, 1)
        if self.t + 1e-9 < self.log_next_sample:
            return
        self.log_next_sample += 1.0 / LOG_RATE
        deg = math.degrees
        folder.write("ATT", us, deg(self.roll), deg(self.roll), deg(self.pitch), deg(self.pitch),
                     deg(self.yaw) % 360.0, deg(self.yaw) % 360.0)
        folder.write("CTUN", us, 0.5, self._throttle() / 100.0, -self.d, -self.d, -self.d, -self.vd)
        folder.write("BAT", us, 0, self.voltage, self.current, self.consumed_mah)
        self.log_gps_tick += 1
        if self.log_gps_tick % 2 == 0:
            lat, lon = self._lat_lon()
            folder.write("GPS", us, 3, *self._gps_time(), 14, int(round(lat * 1e7)),
                         int(round(lon * 1e7)), int(round((self.home_alt - self.d) * 100)),
                         math.hypot(self.vn, self.ve), deg(math.atan2(self.ve, self.vn)) % 360.0)

    def log_text(self, text: str) -> None:
        """A STATUSTEXT is logged as MSG while a log is open."""
        if self.log_folder_ is not None and self.log_folder_.current is not None:
            self.log_folder_.write("MSG", int(self.boot_seconds * 1e6), text)

    def _gps_time(self) -> tuple[int, int]:
        """The simulated GPS's time, (ms into the week, week): the sim's seconds into week 2300 (GPS GMS/GWk, CAM
        GPSTime/GPSWeek, in that order in both)."""
        return int(self.t * 1000) % 604_800_000, 2300

    def log_camera(self) -> None:
        """A photo: CAM (AP_Camera::Write_Camera)."""
        if self.log_folder_ is None or self.log_folder_.current is None:
            return
        lat, lon = self._lat_lon()
        alt_cm = int(round((self.home_alt - self.d) * 100))
        self.log_folder_.write("CAM", int(self.boot_seconds * 1e6), 0, self.images & 0xFFFF, *self._gps_time(),
                               int(round(lat * 1e7)), int(round(lon * 1e7)), alt_cm, int(round(-self.d * 100)),
                               alt_cm, int(round(math.degrees(self.roll) * 100)),
                               int(round(math.degrees(self.pitch) * 100)),
                               int(round(math.degrees(self.yaw) % 360.0 * 100)))

