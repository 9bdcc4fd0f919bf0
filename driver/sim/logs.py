"""The simulated ArduCopter's log download over LOG_* messages, as ArduCopter 4.6.3 answers them
(tests/data/recordings/arducopter-4.6-sitl-logs.*, AP_Logger_MAVLinkLogTransfer.cpp), and its logging while armed.

Mixed into the Autopilot. What the recording shows, quirks included:

* LOG_REQUEST_LIST (start, end): ``end`` is clamped to the last log, then LOG_ENTRY counts from ``start`` up (the
  id wrapping past 65535) until it has sent ``end``: ids that do not exist come with size 0 and time 0, about
  :data:`LIST_RATE` a second, so a list of ids past the last log floods for ~40 s unless LOG_REQUEST_END stops it.
  With no log at all: one LOG_ENTRY id 0, num_logs 0. While a listing or a transfer runs, a new LOG_REQUEST_LIST
  or LOG_REQUEST_DATA is dropped (AP_Logger_MAVLinkLogTransfer.cpp: "Log download in progress", except for a
  LOG_REQUEST_DATA on the link being served: silence, as the recording shows during a listing): a request never
  replaces the stream under way.
* LOG_REQUEST_DATA (id, ofs, count): LOG_DATA of 90 bytes in order until ``count`` is sent or a packet comes out
  short (the end of the log, whose size is taken at the request); an offset past the end: one LOG_DATA of count
  0; an unknown id: nothing.
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

__all__ = ["LogServer", "LOG_DATA_SIZE", "LOG_DATA_RATE", "LIST_RATE"]

LOG_DATA_SIZE = 90               # bytes in one LOG_DATA
LOG_DATA_RATE = 61_000.0         # LOG_DATA a (sim) second over TCP: the recording's 6.6 MB in 1.2 s
LOG_DATA_FRAME = 12 + 97         # a LOG_DATA frame's bytes (MAVLink 2), for a radio's budget
MAX_DATA_STEP = 600              # LOG_DATA one sim step sends at most (the sim's own CPU: telemetry keeps flowing)
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
    log_credit = 0.0
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

    def _log_busy(self) -> bool:
        """A listing or a transfer runs (ArduPilot's _log_sending_link): a new LIST or DATA is dropped, with
        "Log download in progress" unless it is a LOG_REQUEST_DATA on the link being served."""
        busy = self.log_listing or self.log_sending
        if busy is None or (busy is self.log_sending and busy[4] is not None):
            return False                                # what follows LOG_REQUEST_END is only the queue
        return True

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

    def _on_log_request_data(self, msg) -> None:
        if self._log_refused():
            return
        if self._log_busy():
            busy = self.log_listing or self.log_sending
            if busy[0] is not self.sender:
                self._text(mavlink.MAV_SEVERITY_INFO, BUSY_TEXT)
            return                                      # dropped (the recording: during a listing, silently)
        folder = self.log_folder
        if not 1 <= msg.id <= len(folder.entries()):
            self.log_sending = None
            return                                      # an unknown id: nothing at all
        number = folder.file_number(msg.id)             # the id is a place in the list (log_num_from_list_entry)
        if number == folder.current:
            folder.end()                                # a download closes the log being written
        size = folder.entries()[msg.id - 1][1]
        remaining = min(msg.count, max(0, size - msg.ofs))   # the size as it is now (get_log_info)
        self.log_sending = [self.sender, msg.id, msg.ofs, remaining, None, number]

    def _on_log_request_end(self, msg) -> None:
        if self._log_refused():
            return
        self.log_listing = None
        if self.log_sending is not None and self.log_sending[4] is None:
            self.log_sending[4] = QUEUED_AFTER_END      # what was queued already still goes out

    def _on_log_erase(self, msg) -> None:
        if self._log_refused():
            return                                      # (ArduPilot erases even during a transfer)
        self.log_listing = self.log_sending = None
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
        if self.log_sending is not None:
            rate = LOG_DATA_RATE
            baud = getattr(self.config, "radio_baud", None)
            if baud:
                rate = min(rate, baud / 10.0 / LOG_DATA_FRAME)
            self.log_credit = min(self.log_credit + rate * dt, rate * dt + 1, MAX_DATA_STEP)
            while self.log_sending is not None and self.log_credit >= 1:
                self.log_credit -= 1
                self._log_data()
        else:
            self.log_credit = 0.0

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

