"""The mission's progress in words, from what the vehicle reports (no Qt): "Item 4 of 16 · WP · 68 m, 14 s to it"."""
from __future__ import annotations

import math

from driver.core.frames import offset_ned
from driver.mission.plan import MissionItem, MissionRunState, Plan
from driver.vehicle.state import VehicleState

__all__ = ["progress_text"]


def progress_text(s: VehicleState, plan: Plan | None, cruise: float, held: bool = False) -> str:
    """``plan``: the mission the vehicle holds (its items name the current one); ``cruise``: the speed the time to
    the item assumes while the vehicle moves slower than 0.5 m/s; ``held``: paused in another mode. The pictures
    the vehicle confirmed (a survey's CAMERA_FEEDBACK) follow, once there are any: "· 24 photos"."""
    text = _progress(s, plan, cruise, held)
    photos = s.camera.photos
    flown = s.mission.state in (MissionRunState.ACTIVE, MissionRunState.PAUSED, MissionRunState.COMPLETE) or held
    return text + (f" · {photos} photo{'s' if photos != 1 else ''}" if photos and flown else "")


def _progress(s: VehicleState, plan: Plan | None, cruise: float, held: bool) -> str:
    m = s.mission
    if m.state is MissionRunState.UNKNOWN and m.count is None:
        return "Mission: the vehicle has not said yet"
    if m.state is MissionRunState.NO_MISSION or not m.count:
        return "No mission on the vehicle"
    if m.state is MissionRunState.COMPLETE:
        return f"Mission complete ({m.count} items)"
    if not m.current or not (s.flying or m.state is MissionRunState.ACTIVE):
        return f"Mission of {m.count} items on the vehicle, not flying"
    item = plan.items[m.current - 1] if plan is not None and 1 <= m.current <= len(plan.items) else None
    name = m.current_name or (item.name if item is not None else "")
    text = f"Item {m.current} of {m.count}" + (f" · {name}" if name else "")
    if held:
        text += f" · paused ({s.mode})"
    to = _to_item(s, item, cruise)
    if to is not None:
        text += f" · {to[0]:.0f} m, {to[1]:.0f} s to it"
    return text


def _to_item(s: VehicleState, item: MissionItem | None, cruise: float) -> tuple[float, float] | None:
    pos = s.position
    if item is None or pos is None or not (item.lat or item.lon) or not item.has_position:
        return None
    north, east = offset_ned(pos.lat, pos.lon, item.lat, item.lon)
    d = math.hypot(north, east)
    speed = s.velocity.ground_speed if s.velocity.ground_speed > 0.5 else cruise
    return d, d / max(speed, 0.1)
