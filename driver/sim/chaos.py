"""Pilot chaos: random sequences of what a pilot does, under random link faults, judged against the vehicle's truth.

A :class:`Flight` flies one sequence of :class:`Action` in a :class:`~driver.sim.lockstep.Lockstep` (the real driver,
the simulated ArduCopter, a faulty link, one hand-driven clock) and checks, after every tick:

* the flight rules (driver.vehicle.safety), on what the *autopilot* heard and what it was doing then: no mode that
  takes the throttle from a stick while it was armed or in the air, no disarm in the air (the pilot here has no
  emergency stop), no motor test, calibration or log download while armed or in the air;
* the driver never thinks the vehicle surely on the ground while it is in the air (``may_be_airborne``);
* every answer agrees with the vehicle's truth: what was said *accepted* happened between the request and the
  answer, what was said *refused* did not; a Stop said holding finds the vehicle holding (GUIDED or BRAKE) or on
  the ground disarmed.

The generator of sequences lives with its users (tests/test_chaos.py, bench/chaos.py: Hypothesis, which shrinks a
failing sequence to the smallest); this module only flies and judges, so it imports nothing beyond the driver.
"""
from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.frames import offset_latlon
from ..mission.plan import MissionItem, Plan, PlanKind
from ..vehicle.commands import decided
from ..vehicle.safety import MANUAL_THROTTLE_MODES
from ..vehicle.state import CommandStatus
from .faults import LinkFaults
from .lockstep import Lockstep

__all__ = ["Action", "Flight", "ACTIONS", "MODES", "FaultSet", "Violation", "wrong_answer"]

#: What a pilot may do, by name; each :class:`Action` carries one and how long the flight then goes on.
ACTIONS = ("arm", "takeoff", "sticks", "stop", "land", "rtl", "mission", "pause", "resume", "mode", "motor test",
           "calibrate", "log download", "link loss", "reconnect", "wait")
#: Modes a pilot may pick from the list (the throttle ones included: the driver must refuse them in the air).
MODES = ("STABILIZE", "ACRO", "ALT_HOLD", "AUTO", "GUIDED", "LOITER", "RTL", "LAND", "BRAKE", "POSHOLD", "SMART_RTL")
HOLD_MODES = ("GUIDED", "BRAKE")
GROUND_ONLY = {mavlink.MAV_CMD_DO_MOTOR_TEST: "motor test", mavlink.MAV_CMD_PREFLIGHT_CALIBRATION: "calibration",
               mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN: "reboot"}
SETTLE = 45.0                     # s the flight goes on after the last action, for the answers still awaited


@dataclass(frozen=True)
class Action:
    kind: str
    value: float = 0.0            # the action's own choice in 0..1 (which mode, how hard the sticks, how long a loss)
    wait: float = 1.0             # s the flight goes on before the next action

    def __str__(self) -> str:
        return f"{self.kind}({self.value!r}) then {self.wait!r} s"     # exact: a failure replays as it flew


@dataclass(frozen=True)
class FaultSet:
    loss: float = 0.0             # each way
    latency: float = 0.0          # each way, s
    duplicate: float = 0.0

    def link(self) -> LinkFaults:
        return LinkFaults(loss=self.loss, latency=self.latency, jitter=min(0.05, self.latency / 10),
                          duplicate=self.duplicate)


@dataclass(frozen=True)
class Violation:
    t: float
    rule: str
    detail: str

    def __str__(self) -> str:
        return f"{self.t:.2f} s {self.rule}: {self.detail}"


@dataclass
class _Asked:
    action: Action
    name: str
    future: object
    since: int                    # index in the truth history
    judged: bool = False


@dataclass
class Flight:
    """One sequence flown and judged; ``violations`` after :meth:`fly`."""
    seed: int
    faults: FaultSet = field(default_factory=FaultSet)
    violations: list = field(default_factory=list)
    answers: list = field(default_factory=list)           # (action, result) as told
    seconds: float = 0.0                                   # of the vehicle's time flown
    log_dir: str = ""

    def fly(self, actions: list[Action]) -> list[Violation]:
        # a log's worker may still be checking a whole download after the driver closed (it closes its files
        # itself): what it leaves behind is not the flight's fault
        self._dir = tempfile.TemporaryDirectory(prefix="chaos-logs-", ignore_cleanup_errors=True)
        self.ls = Lockstep(self.seed, ready_after=2.0, log_dir=self._dir.name)
        self.ls.autopilot.params["DISARM_DELAY"] = 10
        self._asked: list[_Asked] = []
        self._heard = 0
        self._truth: list = []
        self._airborne_since: float | None = None
        self._lifted = False
        self._armed_by_us = False                 # this driver's last ARM_DISARM was an arm
        self._last_frame = b""                    # the last frame the vehicle heard
        try:
            self._prepare()
            self.ls.faults.uplink, self.ls.faults.downlink = self.faults.link(), self.faults.link()
            for action in actions:
                self._do(action)
                self._run(action.wait, sticks=action if action.kind == "sticks" else None)
            self.ls.faults.end_outage()
            self._run(SETTLE, until=lambda: all(a.judged for a in self._asked if a.action.kind != "log download"))
            for asked in self._asked:
                if not asked.judged and asked.action.kind != "log download":   # a log may take minutes
                    self._violate("no answer", f"{asked.name}: nothing said {SETTLE:g} s after the last action")
        finally:
            self.seconds = self.ls.autopilot.t
            self.ls.close()
            self._dir.cleanup()
        return self.violations

    # -- before the chaos: a vehicle ready, a mission on it -------------------------------------------------
    def _prepare(self) -> None:
        ls = self.ls
        ls.run(4.0, self._record)
        v = ls.vehicle
        home = v.state().home
        if home is None:
            self._violate("setup", "no home after 4 s on a clean link")
            return
        items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=5)]
        for north, east in ((10, 0), (10, 10), (0, 10)):
            lat, lon = offset_latlon(home.lat, home.lon, north, east)
            items.append(MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=lat, lon=lon, alt=5))
        items.append(MissionItem(mavlink.MAV_CMD_NAV_LAND))
        upload = v.upload_plan(Plan(PlanKind.MISSION, tuple(items)))
        self._run(20.0, until=upload.done)
        if not upload.done() or not upload.result().result.ok:
            self._violate("setup", f"mission upload on a clean link: {upload.result().result if upload.done() else '-'}")

    # -- the pilot ------------------------------------------------------------------------------------------
    def _do(self, action: Action) -> None:
        v = self.ls.vehicle
        kind, x = action.kind, action.value
        call = {
            "arm": lambda: v.arm(),
            "takeoff": lambda: v.takeoff(2.0 + 4.0 * x),
            "stop": v.stop, "land": v.land, "rtl": v.return_to_launch,
            "mission": v.start_mission, "pause": v.pause_mission, "resume": v.resume_mission,
            "mode": lambda: v.set_mode(MODES[int(x * len(MODES)) % len(MODES)]),
            "motor test": lambda: v.setup.motor_test(1 + int(x * 4) % 4, throttle_pct=5, seconds=1,
                                                     propellers_removed=True),
            "calibrate": v.calibrate_level,
            "log download": lambda: v.logs.download_latest(os.path.join(self._dir.name, "download.bin")),
        }.get(kind)
        if kind == "link loss":
            self.ls.faults.outage(0.5 + 6.0 * x)
        elif kind == "reconnect":
            self.ls.reconnect()
            self._lifted = self._armed_by_us = False
        elif call is not None:
            name = kind if kind != "mode" else f"mode {MODES[int(x * len(MODES)) % len(MODES)]}"
            self._asked.append(_Asked(action, name, call(), len(self._truth)))

    def _run(self, seconds: float, until=None, sticks: Action | None = None) -> None:
        ticks = max(1, round(seconds / 0.02))
        for i in range(ticks):
            if sticks is not None and i % 5 == 0:
                x = sticks.value
                self.ls.vehicle.set_velocity(2 * x - 1, 1 - 2 * x, 0.5 - x, 0.3 * (x - 0.5))
            self.ls.tick()
            self._record()
            self._check()
            if until is not None and until():
                return

    # -- the truth and the rules ------------------------------------------------------------------------------
    def _record(self) -> None:
        ap = self.ls.autopilot
        self._truth.append((ap.t, ap.mode_name, ap.armed, ap.landed, -ap.d, ap.mission_run == "running"))

    def _violate(self, rule: str, detail: str) -> None:
        self.violations.append(Violation(self.ls.autopilot.t, rule, detail))

    def _check(self) -> None:
        ls = self.ls
        heard = ls.heard
        for h in heard[self._heard:]:
            self._check_heard(h)
        self._heard = len(heard)
        ap = ls.autopilot
        if not ap.landed and self._airborne_since is None:
            self._airborne_since = ap.t
        elif ap.landed:
            self._airborne_since = None
        known = self._airborne_since is not None and (ls.reported >= self._airborne_since or self._lifted)
        if known and not ls.vehicle.state().may_be_airborne:
            self._violate("airborne unseen", f"the vehicle is {-ap.d:.1f} m up in {ap.mode_name} and the driver heard "
                          "it so, or sent what lifted it, yet says it is surely on the ground")
        for asked in self._asked:
            if not asked.judged and decided(asked.future) is not None:   # as the driver decided it, this tick
                asked.judged = True
                self._judge(asked)

    def _check_heard(self, h) -> None:
        msg, kind = h.msg, h.msg.get_type()
        frame = bytes(msg.get_msgbuf())
        if frame == self._last_frame:           # the link's duplicate (same sequence number): not the driver's act,
            return                              # and a motor test it repeats finds the vehicle armed by itself
        self._last_frame = frame
        if kind == "COMMAND_LONG" and msg.command in (mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_MISSION_START) \
                and msg.get_srcComponent() == self.ls.vehicle.config.source_component:
            self._lifted = True                 # this driver sent what lifts the vehicle: it knows from then on
        airborne = not h.landed
        mine = msg.get_srcComponent() == self.ls.vehicle.config.source_component
        # what the driver that sent it could know: the vehicle as its newest heartbeat showed it, and what it sent
        knew_airborne = not h.known_landed or (mine and self._lifted)
        knew_armed = h.known_armed or (mine and self._armed_by_us)
        mode = None
        if kind == "SET_MODE" and msg.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            mode = msg.custom_mode
        elif kind == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_SET_MODE:
            mode = int(msg.param2)
        if mode is not None and mode in MANUAL_THROTTLE_MODES.values() and airborne and knew_airborne:
            self._violate("throttle mode", f"mode {mode} commanded while airborne in {h.mode}")
        if kind == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            if msg.param1 < 0.5 and airborne and knew_airborne:
                self._violate("disarm in the air", f"disarm heard {-self.ls.autopilot.d:.1f} m up in {h.mode}")
            if mine:
                self._armed_by_us = msg.param1 >= 0.5
        what = GROUND_ONLY.get(msg.command) if kind == "COMMAND_LONG" else None
        if kind in ("LOG_REQUEST_DATA", "LOG_ERASE"):
            what = "log download"
        if what and (h.armed or airborne) and (knew_armed or knew_airborne) and not (
                kind == "COMMAND_LONG" and msg.command == mavlink.MAV_CMD_DO_MOTOR_TEST and msg.param4 == 0):
            self._violate("ground only", f"{what} heard while {'armed' if h.armed else 'airborne'}")

    # -- the answers --------------------------------------------------------------------------------------------
    def _judge(self, asked: _Asked) -> None:
        result = decided(asked.future)
        result = getattr(result, "result", result)          # a transfer's outcome carries its result
        self.answers.append((asked.action, result))
        stale = self.faults.latency * 1.1 + 0.1        # how old the freshest report at the answer can be
        first, at = asked.since, self._truth[-1][0] if self._truth else 0.0     # the autopilot's time
        while first > 0 and self._truth[first - 1][0] >= at - stale:
            first -= 1
        wrong = wrong_answer(asked.action.kind, asked.name, result, self._truth[asked.since:],
                             self._truth[first:])
        if wrong:
            self._violate("wrong answer", f"{asked.name}: {result.status.value} ({result.reason}): {wrong}")

    @staticmethod
    def describe(actions: list[Action]) -> str:
        return "; ".join(str(a) for a in actions)


def wrong_answer(kind: str, name: str, result, window: list, known: list | None = None) -> str | None:
    """What is false in ``result`` (the answer to the pilot's ``kind`` action, ``name`` as told) given ``window``,
    the vehicle's truth from the request to the answer: (time, mode, armed, landed, altitude, mission running)
    tuples. None when it agrees with the vehicle. A log download is judged by the flight rules alone.
    ``known``: the truth over the last downlink latency before the answer (default: the answer's instant), what a
    report heard at the answer may show: a Stop's "holding" or "on the ground" is right if the vehicle was so in
    it (a ground station started after another one's arm, over a slow radio, cannot know of it sooner)."""
    if not hasattr(result, "status") or not window:
        return None
    modes = {t[1] for t in window}
    now = window[-1]
    if result.status is CommandStatus.ACCEPTED:
        if kind == "arm" and not any(t[2] for t in window):
            return "said armed, never armed"
        if kind == "takeoff" and max(t[4] for t in window) < 1.5:
            return f"said taken off, highest {max(t[4] for t in window):.1f} m"
        if kind == "mode" and name[5:] not in modes:
            return f"said {name[5:]}, the vehicle showed {sorted(modes)}"
        if kind in ("land", "rtl", "pause", "resume"):
            shown = {"land": "LAND", "rtl": "RTL", "pause": "BRAKE", "resume": "AUTO"}[kind]
            if shown not in modes:
                return f"said {shown}, modes {sorted(modes)}"
        if kind == "mission" and not any(t[1] == "AUTO" and t[5] for t in window):
            return "said the mission runs, never AUTO with the mission running"
        if kind == "stop" and not any(t[1] in HOLD_MODES or (t[3] and not t[2]) for t in (known or [now])):
            return (f"said {result.reason!r}, the vehicle in {now[1]}, {'armed' if now[2] else 'disarmed'}, "
                    f"{'landed' if now[3] else f'{now[4]:.1f} m up'}")
    elif result.status is CommandStatus.REFUSED:
        if kind == "arm" and all(t[2] for t in window[-5:]) and not window[0][2]:
            return "said refused, the vehicle armed"
        if kind == "mode" and now[1] == name[5:] and window[0][1] != now[1]:
            return f"said refused, the vehicle in {now[1]}"
    return None
