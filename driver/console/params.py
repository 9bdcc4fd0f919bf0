"""The console's ``param`` verbs, as MAVProxy's: fetch, show, help, set, load, save, diff.

They work on any :class:`~driver.vehicle.api.Drone` (the embedded driver or an Ice client): the table read is
``state().parameters``, every write goes through ``set_parameter`` and is confirmed by the vehicle.

``show``, ``save``, ``diff`` and ``load`` act on the vehicle's whole list: when it is not all known (right after
connecting, as with ``--cmd "param save FILE"``) they read it first, print how far that is, and act when it is
complete; a file of 0 parameters, or a diff against a few, would say something false about the vehicle.
"""
from __future__ import annotations

import fnmatch
import threading
from concurrent.futures import Future, wait
from typing import Callable

from ..params.model import ParameterTable

from ..params.files import ParamFormat, compare, read_param_file, write_param_file
from ..params.metadata import ParamMeta
from ..params.values import format_value

__all__ = ["ParamVerbs", "USAGE"]

PROGRESS_EVERY = 1.0     # s between progress lines while the list is read
COMPLETE_WAIT = 5.0      # s for the state to show the complete table once the read ended (an Ice client's lags)

USAGE = ("param fetch | param show [PATTERN] | param help NAME | param set NAME VALUE [force] | "
         "param load FILE [PATTERN] [force] | param save FILE [PATTERN] [missionplanner] | param diff FILE [PATTERN]")


class ParamVerbs:
    """``param ...`` typed at the console; ``say`` prints a line, ``report`` prints a future's result when it
    comes."""

    def __init__(self, drone, say: Callable[[str], None], report: Callable[[Future], None]) -> None:
        self.drone = drone
        self.say = say
        self.report = report

    def __call__(self, arg: str) -> None:
        words = arg.split()
        if not words:
            raise ValueError(f"usage: {USAGE}")
        verb, rest = words[0], words[1:]
        handler = getattr(self, "_" + verb, None)
        if handler is None:
            raise ValueError(f"usage: {USAGE}")
        handler(rest)

    # -- the verbs ----------------------------------------------------------------------------------------
    def _fetch(self, rest: list[str]) -> None:
        self.report(self.drone.fetch_parameters(refresh=True))

    def _show(self, rest: list[str]) -> None:
        pattern = (rest[0] if rest else "*").upper()
        self._with_all("param show", lambda table: self._show_table(table, pattern))

    def _show_table(self, table: ParameterTable, pattern: str) -> None:
        meta = self.drone.parameter_metadata
        names = [n for n in sorted(table.values) if fnmatch.fnmatchcase(n, pattern)]
        for name in names:
            p = table.values[name]
            info = meta.get(name) if meta is not None else None
            self.say(f"{name:<16} {format_value(p.type, p.value)}{_meaning(info, p.value)}")
        if not names:
            self.say(f"no parameter matches {pattern}")

    def _help(self, rest: list[str]) -> None:
        if len(rest) != 1:
            raise ValueError("usage: param help NAME")
        name = rest[0].upper()
        meta = self.drone.parameter_metadata
        info = meta.get(name) if meta is not None else None
        if info is None:
            self.say(f"{name}: no metadata" + ("" if meta is not None else " (none loaded)"))
            return
        self.say(f"{name}: {info.display_name}")
        self.say(f"  {info.description}")
        if info.min is not None:
            self.say(f"  range {info.min:g} to {info.max:g} {info.units}".rstrip())
        elif info.units:
            self.say(f"  units {info.units}")
        for code, text in info.values.items():
            self.say(f"  {code:g}: {text}")
        for bit, text in info.bitmask.items():
            self.say(f"  bit {bit}: {text}")
        if info.reboot_required:
            self.say("  takes effect after a reboot")

    def _set(self, rest: list[str]) -> None:
        force = rest[-1:] == ["force"]
        if force:
            rest = rest[:-1]
        if len(rest) != 2:
            raise ValueError("usage: param set NAME VALUE [force]")
        name, value = rest[0].upper(), _value(rest[1])
        self.report(self.drone.set_parameter(name, value, allow_out_of_bounds=force))
        meta = self.drone.parameter_metadata
        info = meta.get(name) if meta is not None else None
        if info is not None and info.reboot_required:
            self.say(f"{name} takes effect after a reboot")

    def _load(self, rest: list[str]) -> None:
        force = rest[-1:] == ["force"]
        if force:
            rest = rest[:-1]
        if not 1 <= len(rest) <= 2:
            raise ValueError("usage: param load FILE [PATTERN] [force]")
        f = self._read(rest[0])
        self._with_all("param load", lambda table: self._load_table(table, f, rest, force))

    def _load_table(self, table: ParameterTable, f, rest: list[str], force: bool) -> None:
        changes = compare(f.values, table, rest[1] if len(rest) > 1 else "*")
        unknown = [d.name for d in changes if d.vehicle_value is None]
        if unknown:
            self.say(f"not on the vehicle, left out: {', '.join(unknown)}")
        writes = [d for d in changes if d.vehicle_value is not None]
        self.say(f"{len(writes)} of {len(f.values)} parameters differ from the vehicle: writing them")
        for d in writes:
            self.report(self.drone.set_parameter(d.name, d.file_value, allow_out_of_bounds=force))

    def _save(self, rest: list[str]) -> None:
        fmt = ParamFormat.MISSION_PLANNER if rest[-1:] == ["missionplanner"] else ParamFormat.MAVPROXY
        if rest[-1:] == ["missionplanner"]:
            rest = rest[:-1]
        if not 1 <= len(rest) <= 2:
            raise ValueError("usage: param save FILE [PATTERN] [missionplanner]")
        self._with_all("param save", lambda table: self._save_table(table, rest, fmt))

    def _save_table(self, table: ParameterTable, rest: list[str], fmt: ParamFormat) -> None:
        try:
            count = write_param_file(rest[0], table, fmt, rest[1] if len(rest) > 1 else "*")
        except OSError as e:
            raise ValueError(f"cannot write {rest[0]}: {e.strerror or e}") from None
        self.say(f"saved {count} parameters to {rest[0]} ({fmt.value})")

    def _diff(self, rest: list[str]) -> None:
        if not 1 <= len(rest) <= 2:
            raise ValueError("usage: param diff FILE [PATTERN]")
        f = self._read(rest[0])
        self._with_all("param diff", lambda table: self._diff_table(table, f, rest))

    def _diff_table(self, table: ParameterTable, f, rest: list[str]) -> None:
        changes = compare(f.values, table, rest[1] if len(rest) > 1 else "*")
        self.say(f"{'PARAMETER':<16} {'FILE':>12} {'VEHICLE':>12}")
        for d in changes:
            mine = format_value(d.type, d.file_value) if d.file_value is not None else "-"
            theirs = format_value(d.type, d.vehicle_value) if d.vehicle_value is not None else "-"
            self.say(f"{d.name:<16} {mine:>12} {theirs:>12}")
        self.say(f"{len(changes)} differences")

    # -- the whole list first ----------------------------------------------------------------------------
    def _with_all(self, verb: str, act: Callable[[ParameterTable], None]) -> None:
        """``act`` on the vehicle's complete list: at once when it is known, else once it has been read."""
        table = self.drone.state().parameters
        if table.complete and not table.downloading:
            act(table)
            return
        self.say(f"{verb}: reading the vehicle's parameters first ({_known(table)})")
        future = self.drone.fetch_parameters()
        self._progress(future)

        def done(f: Future) -> None:
            try:
                result = f.result()
            except Exception as exc:  # noqa: BLE001 - said at the console, which stays alive
                self.say(f"{verb}: error: {exc}")
                return
            s = self.drone.wait_for(lambda s: s.parameters.complete, COMPLETE_WAIT) if result.ok else None
            if s is None:
                self.say(f"{verb}: not done, the vehicle's parameters were not all read ({result})")
                return
            try:
                act(s.parameters)
            except ValueError as exc:
                self.say(f"error: {exc}")
        future.add_done_callback(done)

    def _progress(self, future: Future) -> None:
        """A line whenever the count read has moved, at most every :data:`PROGRESS_EVERY`, until the end."""
        def run() -> None:
            last = ""
            while not wait([future], PROGRESS_EVERY).done:
                line = f"parameters: {_known(self.drone.state().parameters)}"
                if line != last:
                    self.say(line)
                    last = line
        threading.Thread(target=run, name="param-progress", daemon=True).start()

    def _read(self, path: str):
        try:
            f = read_param_file(path)
        except OSError as e:
            raise ValueError(f"cannot read {path}: {e.strerror or e}") from None
        for problem in f.problems:
            self.say(f"{path} {problem}")
        return f


def _known(table: ParameterTable) -> str:
    if table.expected:
        return f"{table.received} of {table.expected}"
    return table.detail or f"{table.received} known"


def _value(text: str) -> float:
    try:
        return float(int(text, 16)) if text.lower().startswith("0x") else float(text)
    except ValueError:
        raise ValueError(f"VALUE must be a number, not {text!r}") from None


def _meaning(info: ParamMeta | None, value: float) -> str:
    if info is None:
        return ""
    text = info.value_text(value)
    unit = f" {info.units}" if info.units else ""
    return f"{unit}  ({text})" if text else unit
