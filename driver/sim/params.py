"""The simulated ArduCopter's parameters: ArduCopter 4.6.3's real table, and the PARAM_* protocol as it answers.

:class:`SimParams` holds every parameter the recording lists (``data/arducopter-4.6.3.params``, written by
``scripts/params-table`` from tests/data/recordings/arducopter-4.6-sitl-params.tlog): 1,392 names in the vehicle's
own index order, each with its MAV_PARAM_TYPE and the value 4.6.3 SITL reported. The sim's own values
(:data:`~driver.sim.common.DEFAULT_PARAMS`, the parameters its behaviour reads) are laid over it; a name
the recording does not list (CHUTE_ALT_MIN: ArduPilot hides a group's parameters while its enable is 0) is
kept, readable and settable by name, but never listed, so the count stays the recording's.

Everything in the sim reads its parameters through ``params.get(NAME)`` (or ``params[NAME]``).

:class:`ParamProtocol` (mixed into the Autopilot) answers as the recording shows (GCS_Param.cpp):

* PARAM_REQUEST_LIST: the version banner, then every parameter, streamed per link as ArduPilot's
  ``queued_param_send`` does: at most what the link's bandwidth allows (``SimConfig.radio_baud``; without it
  the recorded TCP rate, 2,300 a second);
* PARAM_REQUEST_READ by index answers with that index, by name with param_index 65535; an unknown name or
  an index past the end gets no answer at all. Reads wait in a queue of :data:`READ_QUEUE` (one more is
  dropped) and their answers share the list's bandwidth, first (ArduPilot's async parameter replies);
* PARAM_SET is obeyed whatever the type it is sent as (REAL32 for an int8 is fine) and answered with the
  parameter's true type and param_index 65535; nothing is range-checked (RTL_ALT = 1e9 is stored); integers
  are rounded and held in their type's range as AP_Param::set_float does; NaN, infinity and unknown names get
  silence.
"""
from __future__ import annotations

import math
import os

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["SimParams", "ParamProtocol", "TABLE_FILE", "RECORDED_RATE"]

TABLE_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "arducopter-4.6.3.params")
RECORDED_RATE = 2300.0          # PARAM_VALUE a second over TCP in the recording (1,392 in 0.60 s)
READ_BY_NAME_INDEX = 65535      # param_index of a reply to a read by name or a set (the recording)
READ_QUEUE = 20                 # PARAM_REQUEST_READs waiting for an answer (GCS_MAVLINK's param_requests)
PARAM_VALUE_BYTES = 25 + 12       # a PARAM_VALUE in a MAVLink 2 frame, unsigned: payload + header and CRC
FTP_FRAME_BYTES = 254 + 12        # a full FILE_TRANSFER_PROTOCOL frame

_RANGES = {
    mavlink.MAV_PARAM_TYPE_INT8: (-128, 127), mavlink.MAV_PARAM_TYPE_UINT8: (0, 255),
    mavlink.MAV_PARAM_TYPE_INT16: (-32768, 32767), mavlink.MAV_PARAM_TYPE_UINT16: (0, 65535),
    mavlink.MAV_PARAM_TYPE_INT32: (-2 ** 31, 2 ** 31 - 1), mavlink.MAV_PARAM_TYPE_UINT32: (0, 2 ** 32 - 1),
}


def read_table(path: str = TABLE_FILE) -> list[tuple[str, int, float]]:
    """(name, MAV_PARAM_TYPE, value) in index order."""
    out = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            name, ptype, value = line.split()
            out.append((name, int(ptype), float(value)))
    return out


_RECORDED: list[tuple[str, int, float]] | None = None


def _recorded() -> list[tuple[str, int, float]]:
    global _RECORDED
    if _RECORDED is None:
        _RECORDED = read_table()
    return _RECORDED


def stored(ptype: int, value: float) -> float | int:
    """``value`` as the vehicle stores it in ``ptype`` (AP_Param::set_float: integers rounded by adding 0.01
    away from zero, then held in the type's range)."""
    low_high = _RANGES.get(ptype)
    if low_high is None:
        return float(value)
    v = math.trunc(value + (0.01 if value >= 0 else -0.01))
    return int(min(max(v, low_high[0]), low_high[1]))


class SimParams:
    """The vehicle's parameters: ``get(name)``, ``params[name]``, ``params[name] = value``, ``name in params``."""

    def __init__(self, overrides: dict[str, tuple[float, int]] | None = None) -> None:
        self._types: dict[str, int] = {}
        self._values: dict[str, float | int] = {}
        self.names: list[str] = []                       # the listed ones, in index order
        for name, ptype, value in _recorded():
            self.names.append(name)
            self._types[name] = ptype
            self._values[name] = stored(ptype, value)
        self._index = {name: i for i, name in enumerate(self.names)}
        for name, (value, ptype) in (overrides or {}).items():
            self._types.setdefault(name, ptype)          # the recording's type wins for a listed name
            self._values[name] = stored(self._types[name], value)

    # -- reading, as everything in the sim does --------------------------------------------------------
    def get(self, name: str, default=None):
        """The value of ``name`` (an int for integer types), ``default`` when the vehicle has no such one."""
        return self._values.get(name, default)

    def __getitem__(self, name: str):
        return self._values[name]

    def __setitem__(self, name: str, value) -> None:
        """Store ``value`` in the parameter's type; a new name becomes a hidden (unlisted) REAL32 one."""
        ptype = self._types.setdefault(name, mavlink.MAV_PARAM_TYPE_REAL32)
        self._values[name] = stored(ptype, float(value))

    def update(self, values: dict | None = None, **more) -> None:
        """Several values at once, each as a PARAM_SET would store it (tests shorten RTL with this)."""
        for name, value in {**(values or {}), **more}.items():
            self[name] = value

    def __contains__(self, name: object) -> bool:
        return name in self._values

    def __len__(self) -> int:
        return len(self.names)

    def type_of(self, name: str) -> int:
        return self._types[name]

    def index_of(self, name: str) -> int | None:
        """The listed index, None for a hidden parameter."""
        return self._index.get(name)

    def items(self):
        return ((name, self._values[name]) for name in self.names)


class _LinkParams:
    """One link's parameter traffic (ArduPilot keeps it per GCS_MAVLINK): reads waiting, the list's progress, and
    the bandwidth left over from the last step (a fraction of a frame)."""

    def __init__(self) -> None:
        self.reads: list[tuple[int, str]] = []
        self.next_index: int | None = None          # the list's next index; None: no list asked
        self.budget = 0.0


class ParamProtocol:
    """PARAM_REQUEST_LIST, PARAM_REQUEST_READ and PARAM_SET as ArduCopter answers them; state on the Autopilot
    (``params``, ``emit_to``, ``sender``, ``factory``, ``config``)."""

    def _param_value(self, name: str, index: int | None = None):
        params: SimParams = self.params
        return self.factory.param_value_encode(name.encode(), float(params[name]), params.type_of(name), len(params),
                                               READ_BY_NAME_INDEX if index is None else index)

    def _link_rate(self) -> float:
        """Bytes a second a link carries for parameters (ArduPilot budgets its parameter replies by the port's
        bandwidth: a byte is 10 bits on a serial radio; without one, the recording's TCP rate)."""
        baud = getattr(self.config, "radio_baud", None)
        return RECORDED_RATE * PARAM_VALUE_BYTES if not baud else min(RECORDED_RATE * PARAM_VALUE_BYTES, baud / 10.0)

    def _param_link(self) -> _LinkParams:
        return self.param_links.setdefault(self.sender, _LinkParams())

    def _on_param_request_list(self, msg) -> None:
        self._banner()
        self._param_link().next_index = 0

    def _on_param_request_read(self, msg) -> None:
        link = self._param_link()
        if len(link.reads) < READ_QUEUE:                 # a full queue drops the request, silently
            link.reads.append((msg.param_index, msg.param_id))

    def _on_param_set(self, msg) -> None:
        params: SimParams = self.params
        name = msg.param_id
        if name not in params or not math.isfinite(msg.param_value):
            return                                        # silence, as the recording shows
        params[name] = msg.param_value
        self.emit(self._param_value(name))                # every link hears a change (send_parameter_value)

    def params_step(self, dt: float) -> None:
        """Each link: the reads' answers first, then the FTP worker's packets (ftp.py: paced as ArduPilot's,
        within the link's bandwidth), then the list, as many as its bandwidth allows this step."""
        links = self.param_links
        self.ftp_tick(dt)
        if self.ftp_busy:
            links.setdefault(self.ftp_peer(), _LinkParams())
        if not links:
            return
        params: SimParams = self.params
        step = self._link_rate() * dt
        for peer, link in list(links.items()):
            link.budget = min(link.budget + step, max(FTP_FRAME_BYTES, step))
            while link.budget >= PARAM_VALUE_BYTES and link.reads:
                index, name = link.reads.pop(0)
                link.budget -= PARAM_VALUE_BYTES
                if 0 <= index < len(params):
                    self.emit_to(self._param_value(params.names[index], index), peer)
                elif index < 0 and name in params:
                    self.emit_to(self._param_value(name), peer)
            while self.ftp_busy and self.ftp_peer() is peer and link.budget >= FTP_FRAME_BYTES:
                sent = self.ftp_packet()
                if not sent:
                    break
                link.budget -= sent
            while link.budget >= PARAM_VALUE_BYTES and link.next_index is not None:
                self.emit_to(self._param_value(params.names[link.next_index], link.next_index), peer)
                link.budget -= PARAM_VALUE_BYTES
                link.next_index += 1
                if link.next_index >= len(params):
                    link.next_index = None
            if not link.reads and link.next_index is None and not (self.ftp_busy and self.ftp_peer() is peer):
                del links[peer]
