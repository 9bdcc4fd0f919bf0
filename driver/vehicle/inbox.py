"""What the vehicle says, handed to the parts that asked for it, as MAVSDK's ``MavlinkMessageHandler``: a part
registers a handler per message type and is never handed the reader.

Handlers run on the reader thread with the state lock held, in the order they were registered, after the
reader's own handling of that message (the link, the state's fields). The vehicle registers its parts' handlers
when it builds them.
"""
from __future__ import annotations

from typing import Callable

__all__ = ["Inbox"]


class Inbox:
    """Message type → the parts' handlers. ``any_component``: the payload's messages come from the gimbal and the
    camera as well as the autopilot; every other handler hears the autopilot only."""

    def __init__(self) -> None:
        self.handlers: dict[str, list[Callable]] = {}
        self.from_any: dict[str, list[Callable]] = {}
        self.text_handlers: list[Callable[[str], None]] = []

    def on(self, mtypes, handler: Callable, *, any_component: bool = False) -> None:
        """``handler(msg)`` for every message of ``mtypes`` (a name, or several)."""
        table = self.from_any if any_component else self.handlers
        for mtype in (mtypes,) if isinstance(mtypes, str) else mtypes:
            table.setdefault(mtype, []).append(handler)

    def on_text(self, handler: Callable[[str], None]) -> None:
        """``handler(text)`` for every STATUSTEXT of the autopilot, decoded and stripped."""
        self.text_handlers.append(handler)
