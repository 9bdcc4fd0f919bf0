"""What the Plan panel shows of the vehicle, worked out without Qt: the transfer's bar, how the plan here compares
with the vehicle's, which buttons may be pressed (and, when not, why), the mission's progress and the item it flies.

:func:`vehicle_view` is a pure function of the vehicle's snapshot and the plan being edited (:class:`PlanFacts`).
The plan controller applies its answer in one place, so what a button shows never depends on which widget was
updated first; tests read the answer directly.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

from driver.mission.plan import MissionRunState, Plan, PlanKind, TransferDirection
from driver.mission.wire import difference
from driver.vehicle.state import LinkStatus, VehicleState

from .progress import progress_text

__all__ = ["Button", "TransferBar", "PlanFacts", "VehicleView", "vehicle_view", "held_by_vehicle", "how_it_differs",
           "fence_off_words", "TITLES"]

TITLES = {PlanKind.MISSION: "Mission", PlanKind.FENCE: "Fence", PlanKind.RALLY: "Rally"}   # the tabs, in order
_DIRECTION = {TransferDirection.UPLOAD: "Uploading", TransferDirection.DOWNLOAD: "Downloading",
              TransferDirection.CLEAR: "Clearing"}


@dataclass(frozen=True)
class Button:
    """Whether a button may be pressed now, and when not, why (the pilot reads it in its tooltip)."""
    enabled: bool
    why_not: str = ""

    @classmethod
    def unless(cls, *reasons: str) -> "Button":
        """Enabled when every reason is "", else disabled for the first that is not."""
        why = next((r for r in reasons if r), "")
        return cls(not why, why)


@dataclass(frozen=True)
class TransferBar:
    text: str                    # "Uploading 3/8 · re-asking item 4", "upload mission: accepted", "No transfer yet"
    done: int
    total: int
    active: bool                 # under way: Cancel ends it


@dataclass(frozen=True)
class PlanFacts:
    """What the panel is drawn from besides the vehicle's snapshot: the plan being edited and what the window knows
    of the vehicle's plans."""
    shown: PlanKind                                  # the tab in front
    here: Mapping[PlanKind, Plan]                    # the plan being edited, each kind
    confirmed: Mapping[PlanKind, Plan]               # what each transfer last confirmed the vehicle holds
    synced: Mapping[PlanKind, tuple[Plan, Plan]]     # (here, there) the driver last found the same in meaning
    outcomes: Mapping[PlanKind, str]                 # each kind's last transfer, in words
    failed: frozenset[PlanKind] = frozenset()        # ... those the driver refused or that failed
    replaying: bool = False                          # a recording is only watched
    cruise: float = 5.0                              # m/s the time to the next item assumes when hovering


@dataclass(frozen=True)
class VehicleView:
    transfer: TransferBar
    tab_titles: tuple[str, ...]  # a dot on each tab whose plan is not the vehicle's
    comparison: str              # how the tab's plan compares with the vehicle's
    warning: bool                # ... shown in amber: it differs, the last transfer failed, or the fence is off
    upload: Button
    download: Button
    remove: Button
    cancel: Button
    start: Button
    pause: Button
    resume: Button
    skip: Button                 # Skip to item N (the list's and the map's menus)
    current: int | None          # the vehicle's item flown now, where the plan here is the vehicle's
    progress: str                # the mission's progress in words
    on_map: str                  # ... drawn on the map while a mission flies or is paused, else ""


def fence_off_words(s: VehicleState) -> str:
    """"The vehicle's fence is off (FENCE_ENABLE 0)" while the vehicle says so, else ""."""
    return "The vehicle's fence is off (FENCE_ENABLE 0)" if s.fence.enabled is False else ""


def held_by_vehicle(s: VehicleState, confirmed: Mapping[PlanKind, Plan], kind: PlanKind) -> Plan | None:
    """What the vehicle holds of ``kind``, as the driver last confirmed it (read back, downloaded or cleared)."""
    known = s.mission.vehicle_plan(kind)
    return known if known is not None else confirmed.get(kind)


def how_it_differs(mine: Plan, theirs: Plan | None, synced: tuple[Plan, Plan] | None) -> str:
    """Why the plan here differs from the vehicle's ("" when it is the same, or neither has one)."""
    if theirs is None:
        return f"the vehicle's {mine.kind.label} is not known yet (Download reads it)" if mine.items else ""
    if synced == (mine, theirs):
        return ""                           # sent and read back, or downloaded: the driver compared them
    why = difference(mine, theirs, integer=True)
    return f"{len(theirs)} items there, {len(mine)} here" if why.endswith(f"instead of {len(mine)}") else why


def vehicle_view(s: VehicleState, facts: PlanFacts) -> VehicleView:
    kind = facts.shown
    there = {k: held_by_vehicle(s, facts.confirmed, k) for k in TITLES}
    whys = {k: how_it_differs(facts.here[k], there[k], facts.synced.get(k)) for k in TITLES}
    transfer = _transfer_bar(s, kind, facts.outcomes)
    # the transfers: with a link to a vehicle (not a recording), one at a time
    no_link = ("No link to the vehicle" if s.link.status is not LinkStatus.OK else
               "A recording is only watched" if facts.replaying else "")
    busy = "A transfer is under way" if transfer.active else ""
    # the mission: from the vehicle's mode and MISSION_CURRENT
    m = s.mission
    count = m.count if m.count is not None else len(there[PlanKind.MISSION] or ())
    running = s.mode == "AUTO" and s.flying and m.state is not MissionRunState.COMPLETE
    held = (s.flying and s.mode != "AUTO" and bool(m.current) and count > 0
            and m.state is not MissionRunState.COMPLETE)
    limits = m.limit_problems               # the driver's limits on the held mission (or no home yet)
    none_held = "No mission on the vehicle" if count <= 0 else ""
    current = m.current if m.current and (running or held) and not whys[PlanKind.MISSION] else None
    progress = progress_text(s, there[PlanKind.MISSION], facts.cruise, held)
    return VehicleView(
        transfer=transfer,
        tab_titles=tuple(("● " if whys[k] else "") + title for k, title in TITLES.items()),
        comparison=_comparison(s, facts, kind, there[kind], whys[kind]),
        warning=bool(whys[kind]) or kind in facts.failed or bool(_fence_off(s, facts, kind, there[kind])),
        upload=Button.unless(no_link, busy),
        download=Button.unless(no_link, busy),
        remove=Button.unless(no_link, busy),
        cancel=Button.unless("" if transfer.active else "No transfer under way"),
        start=Button.unless(no_link, none_held, "The mission is flying" if running else "",
                            f"Not started: the mission's {'; '.join(limits)}" if limits else ""),
        pause=Button.unless(no_link, "" if running else "The mission is not flying"),
        resume=Button.unless(no_link, "" if held else "No mission paused"),
        skip=Button.unless(no_link, none_held),
        current=current,
        progress=progress,
        on_map=progress if running or held else "",
    )


def _transfer_bar(s: VehicleState, kind: PlanKind, outcomes: Mapping[PlanKind, str]) -> TransferBar:
    t = s.mission.transfer(kind)
    if t is not None and t.active:
        return TransferBar(f"{_DIRECTION[t.direction]} {t.done}/{t.total or '?'}"
                           + (f" · {t.detail}" if t.detail else ""), t.done, t.total, True)
    return TransferBar(outcomes.get(kind, "No transfer yet"), 1 if kind in outcomes else 0, 1, False)


def _fence_off(s: VehicleState, facts: PlanFacts, kind: PlanKind, theirs: Plan | None) -> str:
    """The vehicle's fence is off, said on the Fence tab where there is a fence (here or there)."""
    has_fence = kind is PlanKind.FENCE and (theirs or facts.here[PlanKind.FENCE].items)
    return fence_off_words(s) if has_fence else ""


def _comparison(s: VehicleState, facts: PlanFacts, kind: PlanKind, theirs: Plan | None, why: str) -> str:
    failed = f"{facts.outcomes[kind]}. " if kind in facts.failed and kind in facts.outcomes else ""
    if why:
        words = f"Differs from the vehicle's: {why}"
    elif theirs is not None:
        words = f"Same as the vehicle's {kind.label} ({len(theirs)} items)"
    else:
        words = f"No {kind.label} here; the vehicle's is not known yet"
    fence_off = _fence_off(s, facts, kind, theirs)
    return failed + words + (f". {fence_off}" if fence_off else "")
