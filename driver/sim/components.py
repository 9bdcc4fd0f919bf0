"""The other components of the simulated vehicle's system: a gimbal, a companion computer.

They share the autopilot's system id and link and say HEARTBEAT at 1 Hz, nothing
else. The Solo's gimbal (component 154) frames its HEARTBEAT in MAVLink 2 even
though the Solo's autopilot speaks only MAVLink 1: a ground station that switches
to MAVLink 2 on the first MAVLink 2 frame it hears, or that takes any HEARTBEAT of
the system for the autopilot's, goes wrong. Only component 1 decides mode, arming
and framing.
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .profiles import speaks_mavlink2

__all__ = ["Component", "components_of", "GIMBAL", "COMPANION"]

GIMBAL = mavlink.MAV_COMP_ID_GIMBAL                 # 154
COMPANION = mavlink.MAV_COMP_ID_ONBOARD_COMPUTER    # 191


class Component:
    """One non-autopilot component: a HEARTBEAT every ``interval`` sim seconds."""

    def __init__(self, config, component_id: int, mav_type: int, mavlink2: bool, interval: float = 1.0) -> None:
        self.component_id = component_id
        self.mav_type = mav_type
        self.mavlink2 = mavlink2
        self.interval = interval
        self.next_at = 0.0
        self.factory = mavlink.MAVLink(None, srcSystem=config.system_id, srcComponent=component_id)

    def step(self, t: float) -> list:
        """Messages due at sim time ``t``."""
        if t + 1e-9 < self.next_at:
            return []
        self.next_at = max(self.next_at + self.interval, t)
        return [self.factory.heartbeat_encode(self.mav_type, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                              mavlink.MAV_STATE_ACTIVE, 3)]


def components_of(config) -> list[Component]:
    out = []
    if getattr(config, "gimbal", False):
        out.append(Component(config, GIMBAL, mavlink.MAV_TYPE_GIMBAL, mavlink2=True))
    if getattr(config, "companion", False):
        out.append(Component(config, COMPANION, mavlink.MAV_TYPE_ONBOARD_CONTROLLER,
                             mavlink2=speaks_mavlink2(config)))
    return out
