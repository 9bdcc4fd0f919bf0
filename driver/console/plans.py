"""The console's mission verbs, after MAVProxy's wp, fence and rally modules (mixed into
:class:`driver.console.console.Console`): each transfer answers when the vehicle has, its lines printed then."""
from __future__ import annotations

from concurrent.futures import Future

from ..mission.files import PlanFileError, load_plan_file, save_plan_file
from ..mission.plan import Plan, PlanKind
from .words import result_line

__all__ = ["PlanCommands", "plan_lines"]

WP_USAGE = "usage: wp load FILE | wp save FILE | wp list | wp clear | wp set N | wp start | wp pause | wp resume"


def plan_lines(plan: Plan) -> list[str]:
    """One line per item, numbered as the vehicle numbers them (a mission from 1)."""
    first = 1 if plan.kind is PlanKind.MISSION else 0
    if not plan.items:
        return [f"no {plan.kind.label} on the vehicle"]
    lines = [f"{plan.kind.label} on the vehicle, {len(plan)} items:"]
    for i, item in enumerate(plan.items, first):
        where = f" {item.lat:.7f} {item.lon:.7f} {item.alt:g} m" if item.has_position else ""
        params = " ".join(f"{p:g}" for p in item.params)
        lines.append(f"  {i:3d} {item.name:<22}{where}  [{params}] frame {item.frame}")
    return lines


class PlanCommands:
    """``wp``, ``fence`` and ``rally``; needs the Console's ``vehicle``, ``say`` and ``_report``."""

    def do_wp(self, arg: str) -> None:
        """wp load FILE | wp save FILE | wp list | wp clear | wp set N | wp start | wp pause | wp resume
        The mission, as MAVProxy's wp: FILE is a QGroundControl .plan or a QGC WPL 110 file (.waypoints, .txt);
        load checks every item against the limits, uploads it and reads it back; set N flies item N next"""
        sub, _, rest = arg.strip().partition(" ")
        rest = rest.strip()
        vehicle = self.vehicle
        if sub == "set" and rest:
            try:
                seq = int(rest)
            except ValueError:
                raise ValueError("wp set N: N is the item's number (1 = the first after home)") from None
            self._report(vehicle.set_mission_item(seq))
        elif sub in ("start", "pause", "resume") and not rest:
            call = {"start": vehicle.start_mission, "pause": vehicle.pause_mission,
                    "resume": vehicle.resume_mission}[sub]
            self._report(call())
        elif not self._plan_verb(PlanKind.MISSION, sub, rest):
            raise ValueError(WP_USAGE)

    def do_fence(self, arg: str) -> None:
        """fence load FILE | fence save FILE | fence list | fence clear
        The polygon and circle fence (MAVLink 2 mission_type FENCE); the vehicle enforces it once FENCE_ENABLE
        is set and FENCE_TYPE includes 4 (polygon)"""
        sub, _, rest = arg.strip().partition(" ")
        if not self._plan_verb(PlanKind.FENCE, sub, rest.strip()):
            raise ValueError("usage: fence load FILE | fence save FILE | fence list | fence clear")

    def do_rally(self, arg: str) -> None:
        """rally load FILE | rally save FILE | rally list | rally clear
        Rally points: where RTL may go instead of home"""
        sub, _, rest = arg.strip().partition(" ")
        if not self._plan_verb(PlanKind.RALLY, sub, rest.strip()):
            raise ValueError("usage: rally load FILE | rally save FILE | rally list | rally clear")

    def _plan_verb(self, kind: PlanKind, sub: str, rest: str) -> bool:
        vehicle = self.vehicle
        if sub == "load" and rest:
            try:
                plan = load_plan_file(rest).plan(kind)
            except (OSError, PlanFileError) as exc:
                raise ValueError(f"{rest}: {exc}") from None
            if plan is None:
                raise ValueError(f"{rest} holds no {kind.label}")
            self.say(f"uploading the {kind.label} from {rest} ({len(plan)} items)")
            self._report_transfer(vehicle.upload_plan(plan), kind)
        elif sub == "save" and rest:
            self._report_transfer(vehicle.download_plan(kind), kind, save_to=rest)
        elif sub == "list" and not rest:
            self._report_transfer(vehicle.download_plan(kind), kind, show=True)
        elif sub == "clear" and not rest:
            self._report(vehicle.clear_plan(kind))
        else:
            return False
        return True

    def _report_transfer(self, future: Future, kind: PlanKind, show: bool = False, save_to: str | None = None):
        """The transfer's result when it comes; then the items listed or the file written."""
        def done(f: Future) -> None:
            try:
                outcome = f.result()
            except Exception as exc:
                self.say(f"error: {exc}")
                return
            result = outcome.result
            if self._claim(result):
                self.say(result_line(result))
            if not result.ok or outcome.plan is None:
                return
            if show:
                for line in plan_lines(outcome.plan):
                    self.say(line)
            if save_to:
                home = self.vehicle.state().home
                try:
                    save_plan_file(save_to, (outcome.plan,), (home.lat, home.lon, home.alt) if home else None)
                except (OSError, PlanFileError) as exc:
                    self.say(f"error: {save_to}: {exc}")
                    return
                self.say(f"saved the {kind.label} ({len(outcome.plan)} items) to {save_to}")
        future.add_done_callback(done)
