"""The embedded driver's mission part: transfers, the mission state, and flying the mission (start, pause,
resume, go to an item), wired into :class:`driver.vehicle.vehicle.Vehicle`, which only forwards to it.

Every command is confirmed by what the vehicle reports, as for every command of the driver: a start by the
heartbeat showing AUTO *and* MISSION_CURRENT saying the mission runs; a pause by the heartbeat (BRAKE); a
resume by MISSION_CURRENT running again; a jump by MISSION_CURRENT showing the item. The start itself is a
sequence of its own (driver.vehicle.sequences.mission_start).
"""
from __future__ import annotations

import collections
import logging
from concurrent.futures import Future
from dataclasses import dataclass, replace
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.ports import Ports
from ..core.results import chain
from .commands import decided
from .state import CommandResult, CommandStatus, LandedState, Severity, VehicleState
from ..mission.limits import UNCHECKED, held_mission_problems, plan_problems, unchecked
from ..mission.plan import MissionRunState, Plan, PlanKind, TransferOutcome
from ..mission.progress import fold_arming, fold_item_reached, fold_mission_current, fold_text, fold_transfer_end
from ..mission.transfer import PlanTransfers
from ..params.manager import param_name

__all__ = ["MissionControl", "MISSION_MESSAGES"]

#: What the mission part hears: the mission protocol's messages and the Solo's RALLY_POINT
MISSION_MESSAGES = ("MISSION_CURRENT", "MISSION_ITEM_REACHED", "MISSION_REQUEST", "MISSION_REQUEST_INT",
                    "MISSION_COUNT", "MISSION_ITEM", "MISSION_ITEM_INT", "MISSION_ACK", "RALLY_POINT")

log = logging.getLogger(__name__)

CONFIRM_TIME = 5.0           # s the vehicle's report may take to show a mission command done (MISSION_CURRENT
                             # streams at the stream rate; a slow link needs a few)


@dataclass(eq=False)
class _Watch:
    """A command whose reply is not the end: the vehicle's report must show ``done`` too."""
    name: str
    future: Future
    inner: Future
    done: Callable[[VehicleState], bool]
    what: str
    deadline: float | None = None


class MissionControl:
    """Owned by one Vehicle; ``ports`` (driver.core.ports) are its way to the state, the link and the commands;
    ``pilot_mode`` changes the mode as the pilot does (ending what runs in the sequence slot)."""

    def __init__(self, config, ports: Ports, pilot_mode: Callable[[str], Future]) -> None:
        self.config = config
        self._state, self._outbox, self._commands = ports.state, ports.outbox, ports.commands
        self._settler, self._clock, self._replaying = ports.settler, ports.clock, ports.replaying
        self._firmware = ports.firmware
        self._pilot_mode = pilot_mode
        self.transfers = PlanTransfers(ports.outbox.encoder(), (config.source_system, config.source_component),
                                       ports.outbox.target, ports.state.record_locked, self._settle_later,
                                       lambda: ports.state.state.home, ports.firmware, ports.roundtrip)
        self._settling: list = []      # transfers ended, settled once the state shows what they did (_publish)
        self._last_in_air: tuple = (None, "")     # (item, name) furthest current while the vehicle flew
        self._armed = ports.state.state.armed     # as the last heartbeat showed it
        self._watches: list[_Watch] = []
        self._currents: collections.deque = collections.deque(maxlen=64)   # (time, item) as the vehicle says
        self._limits_of: tuple = (None, None, None)   # (home, mission held, fence) the limits were checked for

    # -- transfers (any thread) -------------------------------------------------------------------------
    def _refusal(self, kind: PlanKind) -> str:
        if self._replaying:
            return "replaying a recording: no vehicle to command"
        if not self._state.state.connected:
            return "no vehicle connected"
        return self.transfers.unsupported(kind)

    def upload(self, plan: Plan) -> Future:
        name = f"upload {plan.kind.label}"
        s = self._state.state
        problems = plan_problems(plan, s, self.config)
        problem = _joined(problems)
        if not problem and unchecked(plan, s.home):
            self._state.add_message(Severity.NOTICE, f"Mission uploaded before the vehicle's home is known: "
                                       f"{UNCHECKED}; they are checked when it is, and it is not started until then")
        return self._start(name, plan.kind, problem,
                           lambda now: self.transfers.upload(plan, now), outcome=True)

    def download(self, kind: PlanKind) -> Future:
        return self._start(f"download {kind.label}", kind, "", lambda now: self.transfers.download(kind, now),
                           outcome=True)

    def clear(self, kind: PlanKind) -> Future:
        return self._start(f"clear {kind.label}", kind, "", lambda now: self.transfers.clear(kind, now),
                           outcome=False)

    def _start(self, name: str, kind: PlanKind, problem: str, begin, outcome: bool) -> Future:
        problem = problem or self._refusal(kind)
        with self._state.lock:
            problem = problem or self.transfers.busy(kind)
            if problem:
                result = self._state.record_locked(name, CommandStatus.REJECTED, problem)
                done: Future = Future()
                done.set_result(TransferOutcome(result) if outcome else result)
                return done
            future = begin(self._clock())
            self._publish()
        self._outbox.wake()
        return future

    def cancel(self, kind: PlanKind) -> None:
        with self._state.lock:
            if self.transfers.cancel(kind):
                self._publish()

    # -- flying it (any thread) ------------------------------------------------------------------------------
    def start_problem(self, s: VehicleState) -> str:
        """Why the mission the vehicle holds is not to be started now ("" when it may be)."""
        limits = held_mission_problems(s, self.config)
        return ("no mission on the vehicle: upload one first" if s.mission.count == 0 else
                f"the mission is not started: {UNCHECKED}" if limits == (UNCHECKED,) else
                f"the mission is not started: {_joined(limits)}" if limits else "")

    def pause(self) -> Future:
        s = self._state.state
        if s.mode != "AUTO":
            return self._commands.answer("mission pause", CommandStatus.REJECTED,
                                         f"not flying a mission (mode {s.mode})")
        return self._pilot_mode("BRAKE")

    def resume(self) -> Future:
        s = self._state.state
        answer = self._commands.answer
        if s.mode == "AUTO" and s.mission.state is MissionRunState.ACTIVE and self._commands.settled(
                mavlink.MAV_CMD_DO_SET_MODE):               # (a mode change on its way may make it otherwise)
            return answer("mission resume", CommandStatus.ACCEPTED, "the mission is running")
        if not s.flying:
            return answer("mission resume", CommandStatus.REJECTED, "on the ground: start the mission instead")
        if not s.mission.count:
            return answer("mission resume", CommandStatus.REJECTED, "no mission on the vehicle")
        return self._watch("mission resume", self._pilot_mode("AUTO"), _running, "MISSION_CURRENT shows it running")

    def go_to_item(self, seq: int) -> Future:
        s = self._state.state
        name = f"mission item {seq}"
        if not isinstance(seq, int) or seq < 1 or (s.mission.count is not None and seq > s.mission.count):
            return self._commands.answer(name, CommandStatus.REJECTED,
                                         f"no item {seq} (the mission has {s.mission.count} items)")
        asked = self._clock()

        def shown(st: VehicleState) -> bool:              # seen since asked, even if flown past at once
            return any(at >= asked and current == seq for at, current in self._currents)
        if self._firmware.mission_current_by_message:
            return self._watch(name, self._set_current_message(seq, name), shown, f"MISSION_CURRENT shows {seq}")
        inner = self._commands.long(mavlink.MAV_CMD_DO_SET_MISSION_CURRENT, (seq,), name)

        def fallback(r: CommandResult) -> Future:
            if not r.ok and "UNSUPPORTED" in r.reason:
                return self._watch(name, self._set_current_message(seq, name), shown, f"MISSION_CURRENT shows {seq}")
            return self._watch(name, inner, shown, f"MISSION_CURRENT shows {seq}")
        return chain(inner, fallback, name)

    def _set_current_message(self, seq: int, name: str) -> Future:
        system, component = self._outbox.target()
        self._outbox.post(mavlink.MAVLink_mission_set_current_message(system, component, seq))
        done: Future = Future()
        done.set_result(CommandResult(name, CommandStatus.ACCEPTED, "MISSION_SET_CURRENT sent"))
        return done

    def _watch(self, name: str, inner: Future, done: Callable[[VehicleState], bool], what: str) -> Future:
        w = _Watch(name, Future(), inner, done, what)
        with self._state.lock:
            self._watches.append(w)
        self._outbox.wake()
        return w.future

    # -- the driver's threads (lock held) ----------------------------------------------------------------
    def on_message(self, m) -> None:
        """A MISSION_* or RALLY_POINT message from the autopilot (reader, lock held)."""
        mtype = m.get_type()
        store = self._state
        if mtype == "MISSION_CURRENT":
            self._currents.append((self._clock(), int(m.seq)))
            store.set(mission=fold_mission_current(store.view()["mission"], m))
            self._note_in_air()
            return
        if mtype == "MISSION_ITEM_REACHED":
            store.set(mission=fold_item_reached(store.view()["mission"], m))
            return
        for msg in self.transfers.on_message(m, self._clock()):
            self._outbox.post(msg)
        if self.transfers.changed:
            self._publish()

    def on_param_value(self, m) -> None:
        """A PARAM_VALUE (reader, lock held): RALLY_TOTAL confirms the Solo's rally transfers."""
        for msg in self.transfers.on_param(param_name(m), m.param_value, self._clock()):
            self._outbox.post(msg)
        if self.transfers.changed:
            self._publish()

    def on_text(self, text: str) -> None:
        self.transfers.on_text(text)
        if self.transfers.changed:
            self._publish()
        store = self._state
        folded = fold_text(store.view()["mission"], text)
        if folded is not None:
            self._currents.append((self._clock(), folded.current))
            store.set(mission=folded)
            self._note_in_air()

    def _note_in_air(self) -> None:
        view = self._state.view()
        if view["armed"] and view["landed_state"] is not LandedState.ON_GROUND and view["system_status"] != 3:
            p = view["mission"]
            item = self._last_in_air[0]
            if item is None or p.current is None or p.current >= item:
                # never back: through loss the heartbeat that shows the disarm can come after the MISSION_CURRENT
                # of the mission ArduCopter rewound at the disarm (item 1, while we still think it flies)
                self._last_in_air = (p.current, p.current_name if p.current != item or p.current_name
                                     else self._last_in_air[1])

    def on_heartbeat(self, m) -> None:
        """The autopilot's heartbeat, folded (reader, lock held): arming or disarming changes the mission's story."""
        view = self._state.view()
        if view["armed"] != self._armed:
            self._armed = view["armed"]
            self._on_arming(view["armed"], view["mode"])

    def _on_arming(self, armed: bool, mode: str) -> None:
        """The heartbeat shows the vehicle armed or disarmed."""
        store = self._state
        store.set(mission=fold_arming(store.view()["mission"], armed, mode, self._last_in_air))
        if armed:
            self._last_in_air = (None, "")

    def service(self, now: float, state: VehicleState) -> list:
        out = self.transfers.service(now)
        self._check_limits(state)
        if self.transfers.changed:
            self._publish()
        for w in list(self._watches):
            r = decided(w.inner)
            if r is None:
                continue
            if not r.ok:
                self._settle(w, r)
            elif w.done(state):
                self._settle(w, self._state.record_locked(w.name, CommandStatus.ACCEPTED, w.what))
            elif w.deadline is None:
                w.deadline = now + CONFIRM_TIME
            elif now > w.deadline:
                self._settle(w, self._state.record_locked(
                    w.name, CommandStatus.TIMED_OUT, f"{r.command} was accepted but {w.what} never happened"))
        return out

    def _check_limits(self, s: VehicleState) -> None:
        """The mission the vehicle holds against the limits whenever it, home or the fence changes; what changes
        the verdict is told to the pilot and kept in ``mission.limit_problems``."""
        key = (s.home, s.mission.vehicle_plan(PlanKind.MISSION), s.fence)
        if all(a is b for a, b in zip(key, self._limits_of)):
            return
        self._limits_of = key
        problems = held_mission_problems(s, self.config)
        store = self._state
        before = store.view()["mission"].limit_problems
        if problems == before:
            return
        store.set(mission=replace(store.view()["mission"], limit_problems=problems))
        if problems and problems != (UNCHECKED,):
            store.add_message_locked(Severity.WARNING, f"Mission on the vehicle beyond the limits, not to be "
                                     f"started: {_joined(problems)}")
        elif not problems and before == (UNCHECKED,):
            store.add_message_locked(Severity.INFO, "Mission checked now that the vehicle's home is known: every "
                                     "item within the limits")
        store.publish()

    def _settle(self, w: _Watch, result: CommandResult) -> None:
        self._watches.remove(w)
        self._settler.settle(w.future, result)

    def close(self) -> None:
        with self._state.lock:
            self.transfers.abort_all("driver closed")
            self._publish()
            for w in list(self._watches):
                self._settle(w, CommandResult(w.name, CommandStatus.ABORTED, "driver closed"))

    def _settle_later(self, future: Future, result) -> None:
        """A transfer's answer waits until the state it leaves is published: whoever hears "uploaded" and reads
        the state (a window, an Ice client) finds the plan there."""
        self._settling.append((future, result))

    def _publish(self) -> None:
        store = self._state
        t = self.transfers
        p = store.view()["mission"]
        for kind, direction, status, plan in t.ended:
            p = fold_transfer_end(p, kind, direction, status is CommandStatus.ACCEPTED, plan)
        t.ended.clear()
        t.changed = False
        store.set(mission=replace(p, transfers=t.progress()))
        store.publish()
        settling, self._settling = self._settling, []
        for future, result in settling:
            self._settler.settle(future, result)


def _joined(problems) -> str:
    return "; ".join(problems[:5]) + (f" (and {len(problems) - 5} more)" if len(problems) > 5 else "")


def _running(s: VehicleState) -> bool:
    return s.mode == "AUTO" and (s.mission.state is MissionRunState.ACTIVE or
                                 s.mission.state is MissionRunState.UNKNOWN)

