"""The standalone server's interactive console, in MAVProxy's spirit.

Commands return at once; each result is printed when the vehicle answers, and
the autopilot's messages, every command result (also those asked for over Ice)
and the noteworthy log records are printed as they arrive, each once, on a
fresh line above the prompt and what is being typed. Velocity typed here is
re-sent for a few seconds (the driver's deadman would otherwise stop it after
half a second) and then falls to zero, like ArduCopter's own guided timeout.
"""
from __future__ import annotations

import cmd
import inspect
import logging
import sys
import threading
import time
from concurrent.futures import Future

from ..vehicle.battery import time_left
from .plans import PlanCommands
from .words import number, result_line
from ..vehicle.state import BatteryAlarm, CommandResult, CommandStatus, SequencePhase, VehicleState
from ..vehicle.rules import COPTER_MODES, mode_refusal, mode_warning
from .payload import PayloadCommands
from .setup import SetupCommands
from .logs import LogCommands
from .shots import ShotCommands

ARM_USAGE = ("arm [throttle] [force] | arm check [all|none|MASK] | arm safetyon | arm safetyoff | arm list")
VELOCITY_HOLD = 3.0          # s a typed velocity lasts (ArduCopter's GUID_TIMEOUT)
VELOCITY_HOLD_MAX = 30.0
CMD_WAIT = 30.0              # s --cmd waits for the vehicle's first heartbeat before running anyway
TELEMETRY_WAIT = 5.0         # s more for the requested telemetry (battery, position) to start
#: Loggers whose INFO records the console shows although it runs at WARNING: what an Ice client
#: asked the vehicle to do (Extra takeoff/land/flatTrim...), camera switches and recordings.
NOTEWORTHY = ("driver.ice.servants", "driver.ice.camera", "driver.camera.uri")


class Console(PlanCommands, PayloadCommands, SetupCommands, LogCommands, ShotCommands, cmd.Cmd):
    """``reboot, arm, disarm, takeoff, land, mode, velocity, parachute, bat, alt, param, status, help``; ``wp``,
    ``fence``, ``rally`` (console_plans.py); ``gimbal``, ``roi``, ``camera`` (payload/console.py); ``shot``
    (shots.py)."""

    intro = "MAVLinkServer console. Type help for commands, exit to quit."

    def __init__(self, vehicle, stdout=None, stdin=None, name: str = ""):
        super().__init__(stdin=stdin, stdout=stdout or sys.stdout)
        if stdin is not None:
            self.use_rawinput = False
        self.vehicle = vehicle
        self.name = name
        self._velocity_gen = 0
        self._velocity_lock = threading.Lock()
        self._watching = threading.Event()
        self._printed = 0
        self._results_seen = 0
        self._results_printed: set[int] = set()        # indices already shown: each result once
        self._out_lock = threading.RLock()
        self._prompting = ""                           # the prompt input() shows now, "" between lines
        self._readline = None                          # the module, when async lines redraw the input line

    # -- output ---------------------------------------------------------------------------------
    @property
    def prompt(self) -> str:  # type: ignore[override]
        mode = self.vehicle.state().mode or "MAV"
        text = f"{self.name + ' ' if self.name else ''}{mode}> "
        self._prompting = text                         # read by cmdloop right before input()
        return text

    def precmd(self, line: str) -> str:
        self._prompting = ""
        return line

    def redraw_input(self, readline_module) -> None:
        """Let asynchronous lines redraw the prompt and the partial input (a terminal with readline)."""
        self._readline = readline_module

    def say(self, text: str) -> None:
        """Print one line; while input() waits, on a fresh line, then the prompt and the typed text again."""
        with self._out_lock:
            if self._prompting and self._readline is not None:
                typed = self._readline.get_line_buffer()
                self.stdout.write(f"\r\x1b[K{text}\n{self._prompting}{typed}")
            else:
                self.stdout.write(text + "\n")
            self.stdout.flush()

    def _claim(self, result: CommandResult) -> bool:
        """True the first time a result is to be shown (results from the driver carry an index)."""
        if not result.index:
            return True
        with self._out_lock:
            if result.index in self._results_printed:
                return False
            self._results_printed.add(result.index)
            return True

    def _report(self, future: Future) -> None:
        """Print the vehicle's answer when it comes."""
        def done(f: Future) -> None:
            try:
                result = f.result()
            except Exception as exc:
                self.say(f"error: {exc}")
                return
            if self._claim(result):
                self.say(result_line(result))
        future.add_done_callback(done)

    def watch_messages(self, interval: float = 0.2) -> None:
        """Print the autopilot's and the driver's messages, and every command result, as they arrive."""
        s = self.vehicle.state()
        self._printed = max((m.index for m in s.messages), default=0)
        self._results_seen = max((r.index for r in s.results), default=0)
        self._watching.set()

        def run() -> None:
            while self._watching.is_set():
                s = self.vehicle.state()
                for m in s.messages_since(self._printed):
                    self.say(f"[{m.severity.name}] {m.text}")
                    self._printed = m.index
                for r in s.results_since(self._results_seen):
                    if self._claim(r):
                        self.say(result_line(r))
                    self._results_seen = r.index
                time.sleep(interval)
        threading.Thread(target=run, name="console-messages", daemon=True).start()

    def stop_watching(self) -> None:
        self._watching.clear()

    def log_handler(self) -> logging.Handler:
        """A logging handler printing through :meth:`say`, without what the console shows already."""
        return _ConsoleLogHandler(self)

    # -- cmd.Cmd plumbing -----------------------------------------------------------------------
    def emptyline(self) -> bool:
        return self.setup_enter()                       # never repeat the last command (Enter: accelcal's)

    def default(self, line: str) -> bool:
        self.say(f"unknown command {line.split()[0]!r}; type help for the list")
        return False

    def onecmd(self, line: str) -> bool:
        try:
            return super().onecmd(line)
        except ValueError as exc:                       # bad arguments: say so, keep the console alive
            self.say(f"error: {exc}")
            return False

    def get_names(self) -> list[str]:
        """The commands help lists: Ctrl+D (EOF) is a key, not a command to type."""
        return [name for name in super().get_names() if name != "do_EOF"]

    def do_help(self, arg: str) -> None:
        """help [COMMAND]: the commands, or what one does"""
        doc = getattr(getattr(self, "do_" + arg.strip(), None), "__doc__", None) if arg.strip() else None
        if doc:
            self.say(inspect.cleandoc(doc))             # multi-line help without the source's indentation
        else:
            super().do_help(arg)

    def do_exit(self, arg: str) -> bool:
        """exit: leave the console (the server stops)"""
        self._cancel_velocity()
        return True

    do_quit = do_exit

    def do_EOF(self, arg: str) -> bool:
        self.say("")
        return self.do_exit(arg)

    # -- commands -------------------------------------------------------------------------------
    def do_reboot(self, arg: str) -> None:
        """reboot: restart the autopilot (refused by ArduCopter while armed)"""
        self._report(self.vehicle.reboot())

    def do_arm(self, arg: str) -> None:
        """arm [throttle] [force] | arm check [all|none|MASK] | arm safetyon | arm safetyoff | arm list"""
        words = arg.split()
        sub = words[0] if words else "throttle"
        if sub in ("throttle", "force"):
            force = "force" in words
            self._report(self.vehicle.arm(force))
        elif sub == "check":
            if len(words) == 1:
                self.say("arm check all | none | MASK  (sets ARMING_CHECK; all = 1, none = 0, "
                         "else the ArduPilot bit mask)")
                return
            value = {"all": 1, "none": 0}.get(words[1])
            if value is None:
                value = number(words[1], "MASK", integer=True)
            self._report(self.vehicle.set_parameter("ARMING_CHECK", float(value)))
        elif sub in ("safetyon", "safetyoff") or (sub == "safety" and len(words) == 2 and words[1] in ("on", "off")):
            on = sub == "safetyon" or (sub == "safety" and words[1] == "on")
            self._report(self.vehicle.set_safety(on))
        elif sub == "list":
            self.say(ARM_USAGE)
        else:
            raise ValueError(f"usage: {ARM_USAGE}")

    def do_disarm(self, arg: str) -> None:
        """disarm [force] | disarm force emergency: stop the motors. force skips the vehicle's checks, on the
        ground only; in the air the vehicle would fall, so only "disarm force emergency" does that"""
        words = arg.split()
        if words not in ([], ["force"], ["force", "emergency"]):
            raise ValueError("usage: disarm [force] | disarm force emergency")
        self._cancel_velocity()
        self._report(self.vehicle.disarm(bool(words), emergency=words == ["force", "emergency"]))

    def do_takeoff(self, arg: str) -> None:
        """takeoff [ALT]: the whole sequence (GUIDED, arm, take off, climb to ALT metres)"""
        words = arg.split()
        if len(words) > 1:
            raise ValueError("usage: takeoff [ALT]")
        altitude = number(words[0], "ALT") if words else None
        future = self.vehicle.takeoff(altitude)
        if not future.done():                 # the driver refuses at once (out of range, already flying): no "started"
            self.say("takeoff started" + (f" to {altitude:g} m" if altitude is not None else ""))
        self._report(future)

    def do_land(self, arg: str) -> None:
        """land: switch to LAND (also aborts a takeoff)"""
        self._cancel_velocity()
        self._report(self.vehicle.land())

    def do_stop(self, arg: str) -> None:
        """stop: hold position in GUIDED with zero velocity (the sticks fly again; BRAKE if GUIDED is refused)"""
        self._cancel_velocity()
        self._report(self.vehicle.stop())

    def do_rtl(self, arg: str) -> None:
        """rtl: return to launch and land"""
        self._cancel_velocity()
        self._report(self.vehicle.return_to_launch())

    def do_mode(self, arg: str) -> None:
        """mode [NAME [confirm]]: show the flight mode, or change it (GUIDED, LOITER, BRAKE, ...); modes that
        need an RC transmitter in flight (STABILIZE, ALT_HOLD, ...) ask for confirm"""
        words = arg.split()
        if not words:
            self.say(f"mode {self.vehicle.state().mode or '?'}; available: {' '.join(sorted(COPTER_MODES))}")
            return
        if len(words) > 2 or words[1:] not in ([], ["confirm"]):
            raise ValueError("usage: mode [NAME [confirm]]")
        name = words[0].upper()
        refusal = mode_refusal(name, self.vehicle.state().may_be_airborne)
        if refusal:
            self.say(refusal)
            return
        warning = mode_warning(name, self.vehicle.state().flying)
        if warning and len(words) == 1:
            self.say(f"{warning} Type 'mode {name} confirm' to switch anyway.")
            return
        self._report(self.vehicle.set_mode(name))

    def do_velocity(self, arg: str) -> None:
        """velocity X Y Z [SECONDS]: forward, right, UP in m/s relative to the heading, held 3 s (max 30)
        (not MAVProxy's velocity, which is LOCAL_NED: north, east, z down)"""
        words = arg.split()
        if len(words) not in (3, 4):
            raise ValueError("usage: velocity X Y Z [SECONDS]  (forward right up, m/s, relative to the heading)")
        x, y, z = (number(w, name) for w, name in zip(words, "XYZ"))
        hold = number(words[3], "SECONDS") if len(words) == 4 else VELOCITY_HOLD
        if not 0 < hold <= VELOCITY_HOLD_MAX:
            raise ValueError(f"SECONDS must be between 0 and {VELOCITY_HOLD_MAX:g}")
        why = velocity_hint(self.vehicle.state())
        if why:
            self._cancel_velocity()                     # a hold still running falls to zero
            self.say(f"velocity not sent: {why}")
            return
        if not self.vehicle.set_velocity(x, y, z, 0.0):
            self.say("velocity refused")
            return
        gen = self._cancel_velocity()
        if x == y == z == 0:
            self.say("velocity zero: holding")
            return
        self.say(f"velocity forward {x:g} right {y:g} up {z:g} m/s for {hold:g} s")
        threading.Thread(target=self._hold_velocity, args=(gen, (x, y, z), hold),
                         name="console-velocity", daemon=True).start()

    def _cancel_velocity(self) -> int:
        with self._velocity_lock:
            self._velocity_gen += 1
            return self._velocity_gen

    def _hold_velocity(self, gen: int, v: tuple[float, float, float], hold: float) -> None:
        end = time.monotonic() + hold
        pause = threading.Event()
        while time.monotonic() < end and self._velocity_gen == gen:
            self.vehicle.set_velocity(*v, 0.0)
            pause.wait(0.1)
        if self._velocity_gen == gen:
            self.vehicle.set_velocity(0.0, 0.0, 0.0, 0.0)

    def do_parachute(self, arg: str) -> None:
        """parachute enable|disable|release"""
        action = arg.strip()
        if action not in ("enable", "disable", "release"):
            raise ValueError("usage: parachute enable|disable|release")
        self._report(self.vehicle.parachute(action))

    def do_bat(self, arg: str) -> None:
        """bat: battery voltage, current and remaining charge"""
        self.say(battery_line(self.vehicle.state()))

    def do_alt(self, arg: str) -> None:
        """alt: altitude above home and above sea level"""
        s = self.vehicle.state()
        amsl = f", {s.position.alt:.1f} m above sea level" if s.position else ""
        self.say(f"altitude {s.altitude:.2f} m above home{amsl}, {vertical_speed(s.velocity.climb)}")

    def do_signing(self, arg: str) -> None:
        """signing setup PASSPHRASE | key PASSPHRASE | keyfile FILE | remove | disable | unsigned on|off | status
        MAVLink 2 signing, as MAVProxy's (key = SHA-256 of the passphrase). setup gives the vehicle the key
        (in clear: over USB or a cable) and signs with it; key and keyfile sign without telling the vehicle;
        remove tells the vehicle to stop; disable stops signing here only; unsigned on lets the vehicle's
        unsigned frames in"""
        from ..link.signing import key_from_passphrase, read_key_file
        sub, _, rest = arg.strip().partition(" ")
        rest = rest.strip()
        usage = "usage: signing setup PASSPHRASE | key PASSPHRASE | keyfile FILE | remove | disable | " \
                "unsigned on|off | status"
        if sub in ("setup", "key", "keyfile") and not rest:
            raise ValueError(usage)
        if sub == "setup":
            self._report(self.vehicle.setup_signing(key_from_passphrase(rest)))
        elif sub == "key":
            self.say(result_line(self.vehicle.use_signing_key(key_from_passphrase(rest))))
        elif sub == "keyfile":
            self.say(result_line(self.vehicle.use_signing_key(read_key_file(rest))))
        elif sub == "remove":
            self._report(self.vehicle.remove_signing())
        elif sub == "disable":
            self.say(result_line(self.vehicle.use_signing_key(None)))
        elif sub == "unsigned" and rest in ("on", "off"):
            self.say(result_line(self.vehicle.allow_unsigned(rest == "on")))
        elif sub in ("status", ""):
            self.say("signing " + self.vehicle.state().signing.summary)
        else:
            raise ValueError(usage)

    def do_param(self, arg: str) -> None:
        """param fetch | param show [PATTERN] | param help NAME | param set NAME VALUE [force] |
        param load FILE [PATTERN] [force] | param save FILE [PATTERN] [missionplanner] | param diff FILE [PATTERN]
        The vehicle's parameters, as MAVProxy's verbs (driver.console.params). A value outside ArduPilot's
        documented bounds is written only with force; every write is confirmed by the vehicle."""
        from .params import ParamVerbs
        ParamVerbs(self.vehicle, self.say, self._report)(arg)

    def do_status(self, arg: str) -> None:
        """status: link, mode, armed, position, battery, GPS, takeoff"""
        for line in status_lines(self.vehicle.state()):
            self.say(line)


def battery_line(s: VehicleState) -> str:
    b = s.battery
    parts = [f"{b.voltage:.2f} V" if b.voltage is not None else "voltage unknown"]
    if b.cell_voltage is not None:
        parts.append(f"{b.cell_voltage:.2f} V/cell ({b.cells}S)")
    if b.current is not None:
        parts.append(f"{b.current:.1f} A")
    if b.remaining is not None:
        parts.append(f"{b.remaining:.0f} %" + (" (from cell voltage)" if b.remaining_estimated else ""))
    if b.consumed_mah is not None:
        parts.append(f"{b.consumed_mah:.0f} mAh used")
    left = time_left(b)
    if left is not None:
        parts.append(f"about {left / 60:.0f} min left" if left > 0 else "down to the reserve")
    alarm = {BatteryAlarm.WARNING: " WARNING", BatteryAlarm.CRITICAL: " CRITICAL: land now"}.get(b.alarm, "")
    t = b.thresholds
    why = (f" (ours: warning {t.warning_cell:g} V/cell or {t.warning_percent:g} %, critical {t.critical_cell:g} V/cell "
           f"or {t.critical_percent:g} %)") if alarm else ""
    return "battery " + ", ".join(parts) + (alarm + why if alarm else " LOW" if b.low else "")


def status_lines(s: VehicleState) -> list[str]:
    ln = s.link
    lines = [f"link {ln.status.value} {ln.address} ({ln.packets_per_s:.0f} pkt/s, {ln.loss_percent:.0f} % lost, "
             f"MAVLink {ln.mavlink_version})",
             f"mode {s.mode or '?'}, {'ARMED' if s.armed else 'disarmed'}, {s.landed_state.name.lower()}, "
             f"heading {s.heading_deg:.0f}°",
             f"altitude {s.altitude:.2f} m"]
    if s.local is not None:
        lines[-1] += f", {s.local.north:.1f} m north, {s.local.east:.1f} m east of home"
    lines.append(battery_line(s))
    lines.append(f"GPS {s.gps.fix_name}, {s.gps.satellites} satellites; "
                 f"{'ready to arm' if s.readiness.ready_to_arm else 'not ready to arm'}")
    lines.append("signing " + s.signing.summary)
    if ln.foreign_packets:
        lines.append(f"{ln.foreign_packets} packets from other addresses ignored (pinned to {ln.pinned_to})")
    if s.takeoff.active:
        lines.append(takeoff_line(s))
    return lines


def takeoff_line(s: VehicleState) -> str:
    """The takeoff sequence's phase; while it waits, what the autopilot still lacks (from the live state)."""
    phase = s.takeoff.phase
    if phase is SequencePhase.WAITING_READY:
        missing = s.readiness.missing
        return f"takeoff: {phase.value}" + (f" (still missing: {', '.join(missing)})" if missing else "")
    return f"takeoff: {phase.value}" + (f" {s.takeoff.detail}" if s.takeoff.detail else "")


def velocity_hint(s: VehicleState) -> str:
    """Why a typed velocity would not fly the vehicle, or "": the viewer's stick hint, for the console."""
    why = s.velocity_blocker
    if why == "on the ground":
        return "take off to fly"
    if why == "not GUIDED":
        return f"velocity flies only in GUIDED (mode is {s.mode or '?'})"
    return why


def vertical_speed(climb: float) -> str:
    """"climbing 0.4 m/s", "descending 0.4 m/s"; a speed that rounds to zero is "climbing 0.0", never "-0.0"."""
    shown = round(climb, 1) + 0.0                       # + 0.0 turns -0.0 into 0.0
    return f"descending {-shown:.1f} m/s" if shown < 0 else f"climbing {shown:.1f} m/s"


class _ConsoleLogHandler(logging.Handler):
    """Log records as console lines. The driver's records of status messages and command results
    are left out: the console prints those itself (watch_messages), once."""

    def __init__(self, console: Console):
        super().__init__()
        self.console = console
        self.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))

    def filter(self, record: logging.LogRecord) -> bool:
        if record.name == "driver.vehicle" and record.args and isinstance(record.args, tuple):
            first = record.args[0]
            if isinstance(first, CommandResult):                   # "command %s"
                return False
            if record.msg == "%s: %s" and first in ("driver", "vehicle"):   # a status message
                return False
        return super().filter(record)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.console.say(self.format(record))
        except Exception:
            self.handleError(record)


def show_logs(console: Console, level: int = logging.WARNING) -> logging.Handler:
    """Route all logging through the console at ``level``, the :data:`NOTEWORTHY` loggers at INFO."""
    handler = console.log_handler()
    logging.basicConfig(level=level, handlers=[handler], force=True)
    for name in NOTEWORTHY:
        noteworthy = logging.getLogger(name)
        if noteworthy.level == logging.NOTSET or noteworthy.level > logging.INFO:
            noteworthy.setLevel(min(level, logging.INFO))
    return handler


def wait_for_vehicle(console: Console, timeout: float = CMD_WAIT) -> bool:
    """Before ``--cmd``: the vehicle's first heartbeat, then its telemetry; after ``timeout``, go on anyway."""
    if console.vehicle.wait_for(lambda s: s.connected, timeout) is None:
        console.say(f"warning: no heartbeat from the vehicle after {timeout:g} s; running the commands anyway")
        return False
    console.vehicle.wait_for(lambda s: s.battery.voltage is not None or s.local is not None, TELEMETRY_WAIT)
    return True


def run_commands(console: Console, text: str) -> None:
    """``--cmd "arm; takeoff 3"``: run each command as if typed."""
    for line in text.split(";"):
        if line.strip():
            console.say(f"> {line.strip()}")
            console.onecmd(line.strip())


__all__ = ["Console", "run_commands", "wait_for_vehicle", "show_logs", "status_lines", "battery_line",
           "velocity_hint", "result_line"]
