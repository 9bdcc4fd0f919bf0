"""What the autopilot says about itself: its firmware and its board (``VehicleState.autopilot``).

ArduPilot tells its board in two places:

* AUTOPILOT_VERSION (GCS_MAVLINK::send_autopilot_version): ``board_version`` is the APJ board id << 16 on a
  ChibiOS build (0 on SITL), ``vendor_id``/``product_id`` its USB ids (0 on SITL), ``flight_custom_version`` the
  git hash, ``uid2`` the board's serial (on SITL the host's machine id, as ASCII). ArduCopter 3.3 (the Solo,
  3drobotics/ardupilot-solo GCS_Common.cpp) sends every field 0 but the hashes.
* the banner (GCS_MAVLINK::send_banner), STATUSTEXT lines sent on PARAM_REQUEST_LIST, on opening
  @PARAM/param.pck and on MAV_CMD_DO_SEND_BANNER: ``fw_string`` ("ArduCopter V4.6.3 (92b0cd78)"), then on a
  ChibiOS board "ChibiOS: <hash>", then the system id: ``"<board> XXXXXXXX XXXXXXXX XXXXXXXX"`` (AP_HAL_ChibiOS
  Util::get_system_id: CHIBIOS_SHORT_BOARD_NAME and the 96-bit serial, "CubeOrange 003F0026 ..."); on SITL the
  host's machine id alone (AP_HAL_SITL: "7d1219c7c4c5404aaa1f6d2a48adfda4", the recordings), with no board name;
  then IOMCU, RCOut and IMU lines where they apply, and last "Frame: QUAD/X" (GCS_MAVLINK_Copter::send_banner).
  ArduCopter 3.3 sends "APM:Copter V3.3 (hash)", "PX4: <hash> NuttX: <hash>" and "Frame: QUAD" on
  PARAM_REQUEST_LIST, and the system id ("PX4v2 XXXXXXXX ...", AP_HAL_PX4) only on DO_SEND_BANNER.

The board is what the id line names, never a guess; :meth:`Autopilot.board_words` says it, or exactly why not.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, replace

__all__ = ["Autopilot", "heard_text", "heard_version"]

_FIRMWARE = re.compile(r"^(?:Ardu\w+|APM:\w+) \S+(?: \([0-9a-f]+\))?$")         # fw_string
_OS = re.compile(r"^(?:ChibiOS|PX4|NuttX): ")
_BOARD_ID = re.compile(r"^(\S+)((?: [0-9A-F]{8}){3})$")                         # ChibiOS / PX4 get_system_id
_MACHINE_ID = re.compile(r"^[0-9a-f]{32}$")                                      # SITL get_system_id
_FRAME = re.compile(r"^Frame: \S+")


@dataclass(frozen=True)
class Autopilot:
    """What the autopilot reported about itself (AUTOPILOT_VERSION and its banner), nothing inferred."""
    firmware_line: str = ""          # the banner's first line, "ArduCopter V4.6.3 (92b0cd78)"
    board: str = ""                  # the id line's board name, "CubeOrange"; "" until an id line names one
    board_line: str = ""             # the id line as sent ("CubeOrange 003F0026 3439510B 30363934", SITL's machine id)
    simulated: bool = False          # the id line is a bare machine id: ArduPilot's SITL
    os_line: str = ""                # "ChibiOS: 6a85082c", "PX4: ... NuttX: ..."
    frame_line: str = ""             # "Frame: QUAD/X"
    banner: bool = False             # a whole banner (its Frame: line) has been heard
    git_hash: str = ""               # AUTOPILOT_VERSION.flight_custom_version
    board_version: int | None = None   # AUTOPILOT_VERSION.board_version (APJ board id << 16); None: not received
    usb_ids: tuple[int, int] = (0, 0)  # AUTOPILOT_VERSION vendor_id, product_id
    asked: str = ""                  # DO_SEND_BANNER's answer when the vehicle would not send its banner

    @property
    def board_id(self) -> int | None:
        """The APJ board id AUTOPILOT_VERSION carries (140 for a CubeOrange), None when it carries none."""
        return (self.board_version >> 16) or None if self.board_version else None

    def board_words(self) -> str:
        """The board, or precisely why it is not known."""
        if self.board:
            return self.board
        if self.simulated:
            return ("SITL, ArduPilot's simulator on a computer (its id line is the computer's machine id "
                    f"{self.board_line[:8]}…, no board name)")
        if self.asked:
            return f"not reported: the vehicle would not send its banner ({self.asked})"
        if self.board_id:
            return (f"APJ board id {self.board_id} (AUTOPILOT_VERSION; the banner's id line naming it not heard "
                    "yet)")
        if self.banner:
            return "not reported: the vehicle's banner had no id line naming its board"
        return "not reported yet (its banner, asked for with MAV_CMD_DO_SEND_BANNER, has not come)"


def heard_text(a: Autopilot, text: str) -> Autopilot | None:
    """``a`` with the banner line ``text`` taken in; None when ``text`` is no banner line."""
    if _FIRMWARE.match(text):
        return replace(a, firmware_line=text)
    if _OS.match(text):
        return replace(a, os_line=text)
    board = _BOARD_ID.match(text)
    if board:
        return replace(a, board=board.group(1), board_line=text, simulated=False, asked="")
    if _MACHINE_ID.match(text) and a.firmware_line:
        return replace(a, board="", board_line=text, simulated=True, asked="")
    if _FRAME.match(text):
        return replace(a, frame_line=text, banner=True)
    return None


def heard_version(a: Autopilot, m) -> Autopilot:
    """``a`` with AUTOPILOT_VERSION ``m`` taken in."""
    custom = bytes(m.flight_custom_version).split(b"\0")[0].decode("ascii", "replace")
    return replace(a, git_hash=custom, board_version=int(m.board_version),
                   usb_ids=(int(m.vendor_id), int(m.product_id)))
