"""The vehicle at the other end of the link, as the reader learns it: which system it is, which of its components
speaks for it, and the MAVLink version its autopilot frames in (we answer in kind)."""
from __future__ import annotations

__all__ = ["Peer"]


class Peer:
    """``system`` 0: the first autopilot heard becomes the vehicle; ``component`` 0: any component speaks for it;
    ``mavlink_version`` None: start in MAVLink 1 and follow the autopilot to 2. Written by the reader, read by
    anyone (each a single reference)."""

    def __init__(self, system: int, component: int, mavlink_version: int | None) -> None:
        self.system = system
        self.component = component
        self.configured_version = mavlink_version
        self.mavlink2 = mavlink_version == 2

    def target(self) -> tuple[int, int]:
        """The autopilot's (system, component), where our commands go."""
        return self.system or 1, self.component

    @property
    def version(self) -> int:
        return 2 if self.mavlink2 else 1

    def reopened(self) -> None:
        """A new connection: back to the configured framing until the autopilot is heard again."""
        self.mavlink2 = self.configured_version == 2

    def heard_frame(self, magic: int) -> bool:
        """A frame from the autopilot starting with ``magic``; True when it moved the link to MAVLink 2."""
        if not self.mavlink2 and magic == 0xFD and self.configured_version is None:
            self.mavlink2 = True
            return True
        return False
