"""Plans and mission progress between driver.mission's model and the mavlinkserver.ice structs."""
from __future__ import annotations

from ..core.results import CommandResult, CommandStatus
from ..mission.plan import (MissionItem, MissionProgress, MissionRunState, Plan, PlanKind, TransferDirection,
                            TransferOutcome, TransferProgress)

__all__ = ["plan_to_ice", "plan_from_ice", "outcome_to_ice", "outcome_from_ice", "mission_to_ice",
           "mission_from_ice", "kind_of", "outcome_from_result", "result_from_outcome"]


def kind_of(value: int) -> PlanKind | None:
    try:
        return PlanKind(int(value))
    except ValueError:
        return None


def plan_to_ice(ms, plan: Plan):
    return ms.Plan(kind=int(plan.kind), items=[
        ms.PlanItem(command=i.command, frame=i.frame, param1=i.param1, param2=i.param2, param3=i.param3,
                    param4=i.param4, lat=i.lat, lon=i.lon, alt=i.alt, autocontinue=i.autocontinue)
        for i in plan.items])


def plan_from_ice(p) -> Plan:
    kind = kind_of(p.kind)
    if kind is None:
        raise ValueError(f"no plan kind {p.kind}")
    return Plan(kind, tuple(MissionItem(i.command, i.frame, i.param1, i.param2, i.param3, i.param4, i.lat, i.lon,
                                        i.alt, bool(i.autocontinue)) for i in p.items))


def outcome_from_result(ms, result: CommandResult):
    return ms.CommandOutcome(index=result.index, command=result.command, status=result.status.name,
                             reason=result.reason, attempts=result.attempts)


def result_from_outcome(outcome) -> CommandResult:
    try:
        status = CommandStatus[outcome.status]
    except KeyError:
        status = CommandStatus.REJECTED
    return CommandResult(command=outcome.command, status=status, reason=outcome.reason,
                         attempts=outcome.attempts, index=outcome.index)


def outcome_to_ice(ms, outcome: TransferOutcome):
    plan = outcome.plan
    return ms.TransferOutcome(outcome=outcome_from_result(ms, outcome.result), hasPlan=plan is not None,
                              plan=plan_to_ice(ms, plan) if plan is not None else ms.Plan(kind=0, items=[]))


def outcome_from_ice(o) -> TransferOutcome:
    return TransferOutcome(result_from_outcome(o.outcome), plan_from_ice(o.plan) if o.hasPlan else None)


def mission_to_ice(ms, p: MissionProgress):
    return ms.MissionStatus(
        hasCount=p.count is not None, count=p.count or 0, hasCurrent=p.current is not None, current=p.current or 0,
        state=int(p.state), hasLastReached=p.last_reached is not None, lastReached=p.last_reached or 0,
        currentName=p.current_name,
        transfers=[ms.TransferProgress(kind=int(t.kind), direction=t.direction.value, done=t.done, total=t.total,
                                       detail=t.detail) for t in p.transfers],
        onVehicle=[plan_to_ice(ms, plan) for plan in p.on_vehicle], flown=p.flown)


def mission_from_ice(m) -> MissionProgress:
    if m is None:                                     # a server from before missions
        return MissionProgress()
    try:
        state = MissionRunState(m.state)
    except ValueError:
        state = MissionRunState.UNKNOWN
    transfers = tuple(TransferProgress(PlanKind(t.kind), TransferDirection(t.direction), t.done, t.total, True,
                                       t.detail) for t in m.transfers if kind_of(t.kind) is not None)
    return MissionProgress(count=m.count if m.hasCount else None, current=m.current if m.hasCurrent else None,
                           state=state, last_reached=m.lastReached if m.hasLastReached else None,
                           current_name=m.currentName, transfers=transfers,
                           on_vehicle=tuple(plan_from_ice(p) for p in m.onVehicle if kind_of(p.kind) is not None),
                           flown=m.flown)
