"""The command sender: COMMAND_LONG and mode changes, each with retries and its own reply (parameter writes:
driver.params.setter).

What a pilot must be able to trust, on a lossy link shared with other systems:

* a COMMAND_ACK settles only a command that was really sent (attempts > 0), from the autopilot, and
  addressed to us (target system *and* component; MAVLink 1 ACKs carry neither and are taken as ours);
* a reply answers its own request, never a later one with the same id: an ACK carries only the command's id,
  so while an earlier request with that id (replaced, or answered fewer times than it was sent) may still be
  answered, an ACK is not taken for the new one, which goes on being re-sent until an answer can only be its
  own (:meth:`CommandSender._ambiguous`: the earlier request's last send plus the answer window *as the link's
  round trip is known when the ACK arrives*, so a slow radio measured later still counts);
* a mode change is confirmed by the HEARTBEAT, never by the ACK alone: an ACK cannot say which of two
  DO_SET_MODEs it answers, so a late one for an earlier switch would otherwise confirm a lost packet; arming and
  disarming likewise, by the heartbeat's armed bit;
* firmware without MAV_CMD_DO_SET_MODE (the stock Solo) is remembered in the vehicle's firmware profile
  (:class:`driver.core.firmware.FirmwareProfile`, which learns every command an ACK calls UNSUPPORTED) after its
  first UNSUPPORTED: later mode changes go straight to SET_MODE, re-sent about every second until the heartbeat
  shows the mode, within the command's time;
* MAV_RESULT_IN_PROGRESS waits for the final answer and never re-sends (a re-sent long command restarts);
* a command with a guard (ground-only commands) is checked each time it is about to go out, and every one
  against the flight rules (:mod:`driver.vehicle.safety`) before each attempt.

:meth:`CommandSender.service` runs on the driver's ticker with the state lock held and only *returns*
the messages to send: the caller writes them after releasing the lock. Futures are settled by one
:class:`Notifier` thread, never under a lock and never on a thread per command.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.firmware import FirmwareProfile
from .state import CommandResult, CommandStatus, Severity, VehicleState

log = logging.getLogger(__name__)

__all__ = ["CommandSender", "CommandFuture", "Notifier", "command_name", "decided"]

MODE_RESEND = 1.0            # s between SET_MODE messages on firmware that answers none (one heartbeat)
ACKED_MODE_WAIT = 1.5        # s an accepted mode change waits for a heartbeat showing it before re-sending
STATUSTEXT_GRACE = 0.3       # s: the STATUSTEXT explaining a refusal may trail the ACK
SHOWN_FOR = 2.5              # s the heartbeat must go on showing what an unanswered arm or mode change asked (three
                             # heartbeats) before it counts as done: a state the vehicle passed through on its own (a
                             # motor test arms it for a second) is not the request's doing
PROGRESS_TIMEOUT = 30.0      # s an IN_PROGRESS command may stay silent before it counts as lost


class CommandFuture(Future):
    """A command's answer. The driver's own parts (the sequences, the mission watch) read it the moment it is
    decided, under the state lock (:func:`decided`); everyone else once the notifier has settled it, so no caller's
    callback ever runs under the lock. On a hand-driven clock the driver then behaves the same however slowly the
    notifier's threads run."""
    decision = None


def decided(future: Future):
    """``future``'s result if it is decided, else None: at once for a :class:`CommandFuture`."""
    decision = getattr(future, "decision", None)
    if decision is not None:
        return decision
    return future.result() if future.done() else None


def command_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name.replace("MAV_CMD_", "") if entry else f"command {command}"


class Notifier:
    """A few fixed threads settle every future, never under a lock: a done-callback that takes its time
    (a client chaining a blocking call) delays neither the link nor other commands' results, and no
    thread is started per command."""

    WORKERS = 4

    def __init__(self) -> None:
        self._pool = ThreadPoolExecutor(max_workers=self.WORKERS, thread_name_prefix="command-results")

    def settle(self, future: Future, result: CommandResult) -> None:
        try:
            self._pool.submit(self._set, future, result)
        except RuntimeError:                  # shut down: settle here, nothing else is waiting on the pool
            self._set(future, result)

    @staticmethod
    def _set(future: Future, result: CommandResult) -> None:
        if not future.done():
            future.set_result(result)         # concurrent.futures logs a failing callback itself

    def close(self) -> None:
        self._pool.shutdown(wait=False)


@dataclass
class _Echo:
    """Earlier requests with one id, replaced or given up before every send was answered."""
    sent: float = -1e18                       # the last of them went out then
    owed: int = 0                             # answers they may still get


@dataclass(eq=False)
class _Command:
    name: str
    key: object                               # the command id
    command: int
    params: list
    future: Future
    message_index: int
    mode: int | None = None                   # a mode change: the custom_mode the heartbeat must show
    armed: bool | None = None                 # arming (True) or disarming (False): the heartbeat's armed bit
    shows_mode: int | None = None             # a command that switches mode (MISSION_START: AUTO), shown the same way
    guard: Callable[[VehicleState], str | None] | None = None
    retry: float | None = None                # s between attempts (None: the configured command timeout), at least
                                              # the link's timeout; doubled after each unanswered try
    give_up_at: float | None = None           # a command re-sent that quickly is still given a command's whole time
    attempts: int = 0
    budget: int = 0                           # attempts it may make (more once a lost link is back)
    first_sent: float | None = None
    last_sent: float = 0.0
    answers: int = 0                          # ACKs taken as its own
    next_send: float = 0.0
    deadline: float | None = None
    acked: bool = False                       # mode change or arming: ACCEPTED, waiting for the heartbeat
    acked_at: float = 0.0
    shown_since: float | None = None          # unanswered: since when the heartbeat has shown what it asked
    early: bool = False                       # a sequence's step: the vehicle's ACCEPTED settles it already
    in_progress: bool = False
    legacy: bool = False                      # mode change by the SET_MODE message
    asked: int = 0                            # attempts sent as COMMAND_LONG (SET_MODE has no answer to owe)
    refused: str | None = None
    refuse_at: float = 0.0
    tags: set = field(default_factory=set)
    settled: bool = False

    def shown(self, armed: bool, custom_mode: int | None) -> bool:
        """The vehicle's report shows what this command asked (a mode, the armed bit); False for the others."""
        if self.mode is not None or self.shows_mode is not None:
            return custom_mode == (self.mode if self.mode is not None else self.shows_mode)
        return self.armed is not None and armed == self.armed


class CommandSender:
    """Pending commands of one vehicle; all methods run with the driver's state lock held."""

    def __init__(self, store, config, notifier: Notifier, target: Callable[[], tuple[int, int]],
                 firmware: FirmwareProfile, rules=None, roundtrip=None):
        self._store = store
        self._cfg = config
        self._notifier = notifier
        self._target = target                 # () -> (system, component) of the autopilot
        self._rules = rules                   # the flight rules (driver.vehicle.safety): checked before each send
        self._roundtrip = roundtrip           # the link's round trip (driver.core.roundtrip), fed by clean answers
        self._firmware = firmware             # learns what the vehicle calls UNSUPPORTED
        self._pending: dict[object, _Command] = {}
        self._echoes: dict[object, _Echo] = {}     # command id -> earlier requests not all answered
        self._unshown: dict[object, tuple[bool, float]] = {}   # an arm or disarm accepted early: (armed wanted,
                                                               # until when) the heartbeat has not shown it yet
        self._custom_mode: int | None = None       # the mode the heartbeat shows now
        self._armed = False                        # the armed bit it shows
        self._heartbeat_at = -1e18                 # when it was heard

    # -- submitting (any thread, under the lock) ------------------------------------------------------
    def submit(self, name: str, command: int, params, now: float, *, guard=None, tag=None,
               retry: float | None = None, early: bool = False, shows_mode: int | None = None) -> Future:
        """A COMMAND_LONG: sent on the next service, re-sent unanswered, settled by its ACK; arming and disarming
        by the heartbeat's armed bit once the vehicle accepted (or shows it). ``early``: by the vehicle's
        ACCEPTED already (a sequence's step, whose next step the heartbeat confirms anyway)."""
        c = _Command(name, command, command, params, CommandFuture(), self._store.message_index, guard=guard,
                     retry=retry, early=early)
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            c.armed = params[0] >= 0.5
        c.shows_mode = shows_mode
        return self._add(c, now, tag)

    def settled_by_state(self, command: int, now: float, pending: bool = True) -> bool:
        """Whether the state now tells the truth about ``command`` (no request of that id could still change it;
        ``pending`` False: leaving out the one pending now, which is being judged)."""
        unshown = self._unshown.get(command)
        return ((not pending or command not in self._pending) and not self._echo_due(command, now)
                and (unshown is None or now >= unshown[1]))

    def submit_mode(self, name: str, number: int, now: float, *, tag=None, early: bool = False) -> Future:
        """A mode change, confirmed by the heartbeat; SET_MODE on firmware known to lack DO_SET_MODE."""
        c = _Command(name, mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_CMD_DO_SET_MODE,
                     [mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number, 0, 0, 0, 0, 0],
                     CommandFuture(), self._store.message_index, mode=number, early=early)
        c.legacy = self._firmware.mode_by_message
        return self._add(c, now, tag)

    def _add(self, c: _Command, now: float, tag) -> Future:
        if tag is not None:
            c.tags.add(tag)
        old = self._pending.pop(c.key, None)
        if old is not None:
            self._resolve(old, CommandStatus.ABORTED, f"superseded by {c.name}", remove=False, now=now)
        c.next_send = now
        c.budget = self._cfg.command_attempts
        self._pending[c.key] = c
        return c.future

    def _shows(self, c: _Command, now: float) -> bool:
        """A heartbeat the vehicle sent after it got ``c`` shows what ``c`` asked, and no earlier request of its id
        could still be what made it so. A link keeps its frames in order, so a heartbeat heard after ``c``'s own
        ACCEPTED was sent after ``c`` was done. Without that answer (lost), only heartbeats heard at least the
        quickest round trip after ``c`` went out can be, and they must go on showing it for SHOWN_FOR: an older one
        may show a state the vehicle only passed through, or that ``c`` was meant to change back."""
        if not c.attempts or not c.shown(self._armed, self._custom_mode):
            c.shown_since = None
            return False
        if self._echo_due(c.key, now, counting=False):
            return False
        if c.acked:
            return self._heartbeat_at >= c.acked_at
        quickest = (self._roundtrip.lowest or 0.0) if self._roundtrip is not None else 0.0
        if self._heartbeat_at < c.first_sent + quickest:
            return False
        if c.shown_since is None:
            c.shown_since = self._heartbeat_at
            if c.deadline is not None:                # the vehicle shows it: no time out while that is confirmed
                c.deadline = max(c.deadline, c.shown_since + SHOWN_FOR + self._cfg.heartbeat_interval)
        return self._heartbeat_at - c.shown_since >= SHOWN_FOR

    def _link_timeout(self) -> float:
        return self._roundtrip.timeout() if self._roundtrip is not None else 0.0

    def _answer_window(self) -> float:
        """How long after it went out a request may still be answered."""
        return max(self._cfg.command_timeout, self._link_timeout())

    def _echo_due(self, key, now: float, counting: bool = True) -> bool:
        """An answer to an earlier request with this id may still arrive: within the answer window of its last
        send, judged with the round trip known now; and, ``counting``, while the answers it is owed have not all
        come, within the longest of a command's whole time and the slowest round trip the link may have (the
        estimate's ceiling): a radio that slowed down after its round trip was learnt answers later than the
        window says, and an ACK counted as the earlier one's, in order, is never taken for the new one. The
        heartbeat's confirmation waits the window only: it needs no ACK, and SHOWN_FOR already asks the vehicle
        to go on showing it (a request the vehicle ignores owes its answers for ever)."""
        e = self._echoes.get(key)
        if e is None:
            return False
        longest = max(self._cfg.command_timeout * self._cfg.command_attempts,
                      self._roundtrip.ceiling if self._roundtrip is not None else 0.0)
        return now < e.sent + self._answer_window() or (counting and e.owed > 0 and now < e.sent + longest)

    def _remember_echo(self, c: _Command, now: float) -> None:
        """``c`` leaves: if it was sent more often than it was answered, ACKs with its id stay ambiguous until an
        answer to its last attempt can no longer arrive."""
        if c.attempts > c.answers:
            e = self._echoes.setdefault(c.key, _Echo())
            e.sent, e.owed = max(e.sent, c.last_sent), e.owed + max(0, c.asked - c.answers)

    # -- cancelling ----------------------------------------------------------------------------------------
    def cancel_tagged(self, tag, reason: str, now: float = 0.0) -> list[tuple[int, int]]:
        """Abort every command carrying ``tag``; returns (command, attempts) of those that had gone out."""
        sent = []
        for c in [c for c in self._pending.values() if tag in c.tags]:
            self._resolve(c, CommandStatus.ABORTED, reason, now=now)
            if c.attempts:
                sent.append((c.command, c.attempts))
        return sent

    def abort_all(self, reason: str) -> None:
        for c in list(self._pending.values()):
            self._resolve(c, CommandStatus.ABORTED, reason)

    def link_recovered(self, now: float) -> None:
        """Every command still pending when the link comes back gets its full retries again, from now (those it
        spent into the silence may all have been lost)."""
        for c in self._pending.values():
            if c.deadline is not None and not c.in_progress:
                c.deadline = max(c.deadline, now + self._cfg.command_timeout * self._cfg.command_attempts)
            c.budget = c.attempts + self._cfg.command_attempts
            if c.give_up_at is not None:
                c.give_up_at = max(c.give_up_at, now + self._cfg.command_timeout * self._cfg.command_attempts)
            c.next_send = min(c.next_send, now)

    # -- replies (reader thread, under the lock) ----------------------------------------------------------
    def on_ack(self, m, now: float) -> None:
        """A COMMAND_ACK from the autopilot (the caller checked its source)."""
        to_system, to_component = getattr(m, "target_system", 0), getattr(m, "target_component", 0)
        cfg = self._cfg
        if to_system not in (0, cfg.source_system) or to_component not in (0, cfg.source_component):
            return                                # another ground station's (or component's) answer
        told = self._firmware.heard_answer(m.command, m.result)
        if told:
            self._store.add_message_locked(Severity.NOTICE, told)
        c = self._pending.get(m.command)
        if c is None or c.attempts == 0:
            return                                # nothing of ours is waiting, or ours has not gone out yet
        if self._echo_due(c.key, now):
            self._echoes[c.key].owed -= 1         # counted as the earlier request's, the oldest first
            log.debug("%s: an answer that may be an earlier request's, not taken", c.name)
            return                                # it goes on being re-sent until an answer is surely its own
        c.answers += 1
        if c.attempts == 1 and c.answers == 1 and self._roundtrip is not None and c.first_sent is not None:
            self._roundtrip.sample(now - c.first_sent)      # Karn: one request, one answer
        result = m.result
        if result == mavlink.MAV_RESULT_IN_PROGRESS:
            c.in_progress = True
            c.deadline = now + PROGRESS_TIMEOUT
            return
        if c.mode is not None or c.armed is not None or c.shows_mode is not None:
            if result == mavlink.MAV_RESULT_ACCEPTED:
                if c.early:                       # its answer, and only its own: the vehicle did it
                    self._resolve(c, CommandStatus.ACCEPTED, "accepted (its heartbeat shows it next)", now=now)
                    if c.armed is not None:       # armed (or not) from now, though the state says so a beat later
                        self._unshown[c.key] = (c.armed, now + self._answer_window() + self._cfg.heartbeat_interval)
                    return
                c.acked, c.acked_at = True, now   # the heartbeat settles it
                c.next_send = now + ACKED_MODE_WAIT
            elif result == mavlink.MAV_RESULT_UNSUPPORTED and c.mode is not None:
                c.legacy, c.next_send = True, now  # old firmware: SET_MODE now, and from now on
            else:
                self._refuse(c, result, now)
            return
        if result == mavlink.MAV_RESULT_ACCEPTED:
            self._resolve(c, CommandStatus.ACCEPTED, now=now)
        else:
            self._refuse(c, result, now)

    def _refuse(self, c: _Command, result: int, now: float) -> None:
        entry = mavlink.enums["MAV_RESULT"].get(result)
        c.refused = entry.name if entry else f"result {result}"
        c.refuse_at = now + STATUSTEXT_GRACE

    def on_heartbeat(self, custom_mode: int, armed: bool, now: float) -> None:
        """The autopilot's heartbeat shows ``custom_mode`` and ``armed``: the truth for every mode change and
        every arming, once no earlier request could still be what made it so."""
        self._custom_mode, self._armed, self._heartbeat_at = custom_mode, armed, now
        for key, (wanted, _) in list(self._unshown.items()):
            if armed == wanted:
                del self._unshown[key]
        for c in list(self._pending.values()):
            if self._shows(c, now):
                self._resolve(c, CommandStatus.ACCEPTED, "" if c.acked or not c.legacy else "shown by the heartbeat",
                              now=now)

    # -- the ticker ---------------------------------------------------------------------------------------
    def service(self, now: float, state: VehicleState) -> list:
        """Re-send, time out and settle; returns the MAVLink messages to send (after the lock is released)."""
        out = []
        cfg = self._cfg
        system, component = self._target()
        for key in list(self._echoes):
            if not self._echo_due(key, now):
                del self._echoes[key]
        for c in list(self._pending.values()):
            if self._shows(c, now):
                self._resolve(c, CommandStatus.ACCEPTED, "", now=now)     # shown while an answer was ambiguous
                continue
            if c.refused is not None:                 # (a heartbeat showing a refused mode settles it above)
                if now >= c.refuse_at:
                    self._resolve(c, CommandStatus.REFUSED, self._vehicle_reason(c, c.refused), now=now)
                continue
            if c.deadline is not None and now >= c.deadline:
                self._time_out(c, state, now)
                continue
            if c.in_progress or now < c.next_send:
                continue
            problem = c.guard(state) if c.guard is not None else None
            if not problem and self._rules is not None:
                problem = (self._rules.mode_problem(c.mode, state) if c.mode is not None
                           else self._rules.command_problem(c.command, c.params, state, now))
            if problem:
                self._resolve(c, CommandStatus.REJECTED, problem, now=now)
                continue
            if c.attempts and c.answers == 0 and not c.acked and not c.legacy and self._roundtrip is not None:
                self._roundtrip.expired(now)      # unanswered for its whole wait: the link may have slowed
            if c.retry is None:
                retry = cfg.command_timeout
            else:           # at the link's pace, backing off with it when unanswered, never slower than a command
                retry = min(cfg.command_timeout, max(c.retry, self._link_timeout()))
            if c.mode is not None:
                if not c.legacy and c.attempts >= c.budget:
                    c.legacy = True               # no ACK at all: SET_MODE before giving up
                if c.legacy:
                    if c.deadline is None:        # SET_MODE has no reply: only the heartbeat, within this time
                        c.deadline = now + cfg.command_timeout * cfg.command_attempts
                    out.append(mavlink.MAVLink_set_mode_message(system, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
                                                                c.mode))
                    c.next_send = now + MODE_RESEND
                else:
                    out.append(mavlink.MAVLink_command_long_message(system, component, c.command,
                                                                    min(c.attempts, 255), *c.params))
                    c.next_send = now + (ACKED_MODE_WAIT if c.acked else retry)
            else:
                if c.attempts >= c.budget and (c.give_up_at is None or now >= c.give_up_at):
                    if c.shown_since is not None and now - c.shown_since < SHOWN_FOR + cfg.heartbeat_interval:
                        continue                          # the vehicle shows it: being confirmed, not lost
                    self._time_out(c, state, now)
                    continue
                out.append(mavlink.MAVLink_command_long_message(system, component, c.command,
                                                                min(c.attempts, 255), *c.params))
                c.next_send = now + (ACKED_MODE_WAIT if c.acked else retry)
                if c.retry is not None:                  # each unanswered try waits twice as long (RFC 6298's backoff)
                    c.retry = min(2 * c.retry, cfg.command_timeout)
            if c.first_sent is None:
                c.first_sent = now
                if c.retry is not None:
                    c.give_up_at = now + cfg.command_timeout * cfg.command_attempts
            c.last_sent = now
            c.attempts += 1
            c.asked += not (c.mode is not None and c.legacy)
        return out

    def _time_out(self, c: _Command, state: VehicleState, now: float) -> None:
        if c.in_progress:
            reason = f"the vehicle said IN_PROGRESS and then nothing for {PROGRESS_TIMEOUT:g} s"
        elif c.mode is not None:
            shown = state.mode or "no mode"
            said = "accepted it, but its" if c.acked else "did not confirm it, and its"
            reason = self._vehicle_reason(c, f"the vehicle {said} heartbeat still shows {shown} "
                                             f"after {c.attempts} attempts (the last ones by SET_MODE)")
        elif c.armed is not None and c.acked:
            shown = "armed" if state.armed else "disarmed"
            reason = self._vehicle_reason(c, f"the vehicle accepted it, but its heartbeat still shows {shown} "
                                             f"after {c.attempts} attempts")
        elif c.answers == 0 and c.key in self._echoes:
            reason = (f"no answer that could only be to this request after {c.attempts} attempts (an earlier "
                      "one with the same id was still being answered)")
        else:
            reason = f"no answer from the vehicle after {c.attempts} attempts"
        self._resolve(c, CommandStatus.TIMED_OUT, reason, now=now)

    def _vehicle_reason(self, c: _Command, fallback: str) -> str:
        """The vehicle's own words since the command: its warnings first (ArduCopter explains a refusal at
        NOTICE or worse), not the INFO lines that happened to arrive meanwhile."""
        said = [m for m in self._store.messages_since(c.message_index) if m.source == "vehicle"]
        texts = [m.text for m in said if m.severity <= Severity.NOTICE] or [m.text for m in said]
        return "; ".join(texts[-3:]) + f" ({fallback})" if texts else fallback

    def _resolve(self, c: _Command, status: CommandStatus, reason: str = "", remove: bool = True,
                 now: float | None = None) -> None:
        if remove and self._pending.get(c.key) is c:
            del self._pending[c.key]
        if now is not None:
            self._remember_echo(c, now)
        if not c.settled:
            c.settled = True
            result = self._store.record_locked(c.name, status, reason, c.attempts)
            c.future.decision = result                # the driver's own parts know it now; callers once settled
            self._notifier.settle(c.future, result)

