"""The LOG_* messages as ArduCopter 4.6.3 takes them (AP_Logger_MAVLinkLogTransfer.cpp, and the recording
tests/data/recordings/arducopter-4.6-sitl-logs.*), and the few numbers the protocol itself fixes."""
from __future__ import annotations

from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["CHUNK", "ALL_IDS", "OPEN_END", "DISARM_TEXT", "LogRequests"]

CHUNK = 90                      # bytes in one LOG_DATA (its data field)
ALL_IDS = (0, 0xFFFF)           # the whole list; ids past the last log flood LOG_ENTRY for ~40 s (the recording)
OPEN_END = 0xFFFFFFFF           # a LOG_REQUEST_DATA count that runs to the log's end, wherever it is by then
DISARM_TEXT = "Disarm for log download"     # armed, the vehicle says it to the first LOG_* request only


class LogRequests:
    """LOG_* requests for the autopilot the vehicle talks to now (``target``: its system and component)."""

    def __init__(self, target: Callable[[], tuple[int, int]]) -> None:
        self._target = target

    def list(self, first: int, last: int):
        return mavlink.MAVLink_log_request_list_message(*self._target(), first, last)

    def data(self, log_id: int, offset: int, count: int):
        return mavlink.MAVLink_log_request_data_message(*self._target(), log_id, offset, count)

    def end(self):
        """LOG_REQUEST_END: stops a listing or a transfer (what the vehicle queued still comes)."""
        return mavlink.MAVLink_log_request_end_message(*self._target())

    def erase(self):
        """LOG_ERASE: every log, no reply."""
        return mavlink.MAVLink_log_erase_message(*self._target())
