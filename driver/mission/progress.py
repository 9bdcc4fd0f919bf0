"""The mission as the vehicle reports it, folded into :class:`~driver.mission.plan.MissionProgress` (pure).

MISSION_CURRENT carries the current item, the count without the home slot and, on 4.x, mission_state
(3 active, 2 stopped as in BRAKE, 5 complete); MISSION_ITEM_REACHED marks an item done; "Mission: 3 WP" names
the item started. ArduCopter 3.3 (the Solo) sends MISSION_CURRENT with the seq only: the state is then left
UNKNOWN rather than guessed, and the count comes from the last transfer.
"""
from __future__ import annotations

import re
from dataclasses import replace

from .plan import MissionProgress, MissionRunState, Plan, PlanKind, TransferDirection

__all__ = ["fold_mission_current", "fold_item_reached", "fold_text", "fold_transfer_end", "fold_restart",
           "fold_arming"]

_STARTED = re.compile(r"^Mission: (\d+) (\S+)")


def fold_mission_current(p: MissionProgress, m) -> MissionProgress:
    state = getattr(m, "mission_state", 0)
    total = getattr(m, "total", None)
    if state == 0:                       # MAVLink 1 / 3.3: no extension fields
        return replace(p, current=int(m.seq))
    try:
        run = MissionRunState(state)
    except ValueError:
        run = MissionRunState.UNKNOWN
    name = p.current_name if p.current == m.seq else ""
    if p.flown and run is MissionRunState.ACTIVE:    # rewound after the landing that ended it, and disarmed:
        run = MissionRunState.COMPLETE               # it flew to the end, it is not flying
    return replace(p, current=int(m.seq), count=int(total) if total is not None else p.count, state=run,
                   current_name=name, flown=p.flown or run is MissionRunState.COMPLETE)


def fold_item_reached(p: MissionProgress, m) -> MissionProgress:
    return replace(p, last_reached=int(m.seq))


def fold_text(p: MissionProgress, text: str) -> MissionProgress | None:
    """The item a "Mission: N NAME" line says started; None for any other text."""
    found = _STARTED.match(text)
    if not found:
        return None
    return replace(p, current=int(found.group(1)), current_name=found.group(2))


def fold_transfer_end(p: MissionProgress, kind: PlanKind, direction: TransferDirection, ok: bool,
                      plan: Plan | None) -> MissionProgress:
    """What is known to be on the vehicle after a transfer: the plan read back, nothing after a clear, and
    after an upload that failed or is not verified not even the old plan (the vehicle may hold part of the new
    one, or the new one)."""
    others = tuple(x for x in p.on_vehicle if x.kind is not kind)
    if ok and plan is not None:
        known = others + (plan,)
        count = len(plan) if kind is PlanKind.MISSION else p.count
        return replace(p, on_vehicle=known, count=count)
    if direction is TransferDirection.UPLOAD:
        return replace(p, on_vehicle=others)
    return p


def fold_restart(p: MissionProgress) -> MissionProgress:
    """The vehicle started again: what it holds and where it was in its mission are not known until it says
    (a plan held before may have been wiped or replaced meanwhile); transfers under way stay as they are."""
    return MissionProgress(transfers=p.transfers)


#: What ArduCopter names the last item of a mission that ends on the ground ("Mission: 5 Land").
_LANDING_ITEMS = ("Land", "RTL")


def fold_arming(p: MissionProgress, armed: bool, mode: str, last_in_air: tuple[int | None, str]) -> MissionProgress:
    """The vehicle armed or disarmed; ``last_in_air``: (item, name) of the last item current while it flew.
    Disarmed in AUTO after its mission's last item, a landing, the mission was flown to its end: ArduCopter then
    resets it (AP_Mission::reset, from the disarm) and restarts it at item 1 disarmed, saying "Mission: 1 Takeoff"
    and MISSION_CURRENT active (4.6.3 SITL); the pilot is told it is complete. Armed again, it may fly again."""
    if armed:
        return replace(p, flown=False) if p.flown else p
    item, name = last_in_air
    last = item is not None and p.count is not None and item == p.count
    if mode == "AUTO" and p.state is not MissionRunState.NOT_STARTED and (last or name in _LANDING_ITEMS):
        return replace(p, flown=True, state=MissionRunState.COMPLETE)
    return p
