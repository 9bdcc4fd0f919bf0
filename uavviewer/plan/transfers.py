"""The plans between the window and the vehicle: Upload, Download and Remove from vehicle, and what the window
knows the vehicle holds, as the driver confirmed it (read back after an upload, downloaded, cleared).

Each answer goes back to the transfer that asked for it. A vehicle that started again is read again, into what it
holds only, never into the plan being edited; another vehicle flown starts with nothing known of its plans.
"""
from __future__ import annotations

from typing import Callable

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QMessageBox, QWidget

from driver.mission.plan import Plan, PlanKind, TransferOutcome
from driver.vehicle.state import CommandResult, LinkStatus, VehicleState

from ..widgets.ask import ask, warning_question
from .model import PlanDocument
from .notices import UploadNotices
from .vehicle_view import PlanFacts, held_by_vehicle, how_it_differs

__all__ = ["PlanTransfers"]


class PlanTransfers(QObject):
    changed = pyqtSignal()                  # what is known of the vehicle's plans, or a transfer's words, changed

    def __init__(self, adapter, doc: PlanDocument, editor, notices: UploadNotices, window: QWidget,
                 shown: Callable[[], PlanKind], parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.adapter = adapter
        self.doc = doc
        self.editor = editor                            # a download goes into the list through it (undoable)
        self.notices = notices
        self._window = window
        self._shown = shown                             # the tab in front
        self.remove_question: QMessageBox | None = None     # "Remove the mission from the vehicle?"
        self.on_vehicle: dict[PlanKind, Plan] = {}      # what each transfer last confirmed the vehicle holds
        self._sending: dict[PlanKind, Plan] = {}        # each kind's upload under way
        self._synced: dict[PlanKind, tuple[Plan, Plan]] = {}   # (here, there) the driver last found the same
        self._outcome: dict[PlanKind, str] = {}         # each kind's last transfer, in words
        self._failed: dict[PlanKind, bool] = {}         # ... and whether the driver refused or failed it
        self._restarts: int | None = None               # the vehicle's restarts seen (VehicleState.boot)
        self._reread: set[PlanKind] = set()             # read again after a restart: into what it holds only
        self._reread_due = False                        # ... asked once the link is up
        self._left_behind: set[PlanKind] = set()        # none here: read to see whether the vehicle keeps one
        self._here: tuple[tuple, dict[PlanKind, Plan]] | None = None    # the plan here, built for this version
        self._state = VehicleState()
        adapter.droneChanged.connect(self._vehicle_changed)     # a fleet's pick, File › Connect

    def facts(self, replaying: bool, cruise: float) -> PlanFacts:
        """What the panel shows of the vehicle is worked out from (besides its snapshot)."""
        return PlanFacts(shown=self._shown(), here=self.plans_here(), confirmed=dict(self.on_vehicle),
                         synced=dict(self._synced), outcomes=dict(self._outcome),
                         failed=frozenset(k for k, failed in self._failed.items() if failed),
                         replaying=replaying, cruise=cruise)

    def plans_here(self) -> dict[PlanKind, Plan]:
        """The plan being edited, each kind, built again only after an edit (a survey's items are worked out)."""
        version = (tuple(self.doc.entries), tuple(self.doc.fence), tuple(self.doc.fence_extra), tuple(self.doc.rally))
        if self._here is None or self._here[0] != version:
            self._here = (version, {k: self.doc.plan(k) for k in PlanKind})
        return self._here[1]

    def how_it_differs(self, kind: PlanKind) -> str:
        """Why the plan here differs from the vehicle's ("" when it is the same, or neither has one)."""
        return how_it_differs(self.plans_here()[kind], self.vehicle_plan(kind), self._synced.get(kind))

    def vehicle_plan(self, kind: PlanKind) -> Plan | None:
        """What the vehicle holds, as the driver last confirmed it (read back, downloaded or cleared)."""
        return held_by_vehicle(self._state, self.on_vehicle, kind)

    def _vehicle_changed(self, _drone) -> None:
        """Another vehicle is flown: nothing is known of its plans yet."""
        for known in (self.on_vehicle, self._sending, self._synced, self._outcome, self._failed, self._reread):
            known.clear()
        self._restarts, self._reread_due = None, False

    def follow(self, s: VehicleState) -> None:
        """A vehicle that started again may hold other plans than before (wiped, or changed by another ground
        station meanwhile): what was known of them goes, and each is read again, into what the vehicle holds,
        never into the plan being edited here. A recording is only watched: its restarts are not read."""
        self._state = s
        restarts = s.boot.restarts
        if self._restarts is None or restarts < self._restarts or self.adapter.replay is not None:
            self._restarts = restarts
            return
        if restarts > self._restarts:
            self._restarts = restarts
            for known in (self.on_vehicle, self._sending, self._synced):
                known.clear()
            self._reread, self._reread_due = set(PlanKind), True
        if self._reread_due and s.link.status is LinkStatus.OK:
            self._reread_due = False
            for kind in self._reread:
                self._outcome[kind] = f"The vehicle restarted: reading its {kind.label} again…"
                self._download(kind)

    # -- transfers ----------------------------------------------------------------------------------
    def transfer(self, action: str, confirmed: PlanKind | None = None) -> None:
        """Upload every plan that differs from the vehicle's (the tab shown's at least), Download the tab's, or
        Remove it from the vehicle (asked first; ``confirmed``: the kind the pilot said yes to); the driver's answers
        come back by themselves."""
        kind = confirmed if confirmed is not None else self._shown()
        if action == "upload":
            for k in self.to_upload():
                self._outcome[k] = f"Uploading the {k.label}…"
                self._sending[k] = plan = self.doc.plan(k)
                self.adapter.send(self.adapter.drone.upload_plan, plan,
                                  then=lambda answer, k=k: self._transfer_finished(k, answer, downloaded=False))
            self._say_what_stays()
        elif action == "clear" and confirmed is None:
            self._ask_removal(kind)
            return
        elif action == "download":
            self._reread.discard(kind)          # the pilot's own download: into the list, as always
            self._outcome[kind] = f"Downloading the {kind.label}…"
            self._download(kind)
        else:
            self._outcome[kind] = f"Clearing the {kind.label}…"
            self.adapter.send(self.adapter.drone.clear_plan, kind, then=lambda result: self._cleared(kind, result))
        self.changed.emit()

    def _say_what_stays(self) -> None:
        """A fence or rally points the vehicle keeps from before while this plan has none: said now, or once read
        (into what the vehicle holds only) when nothing is known of them."""
        for kind in (PlanKind.FENCE, PlanKind.RALLY):
            if self.doc.plan(kind).items or kind in self.to_upload():
                continue
            theirs = self.vehicle_plan(kind)
            if theirs is not None:
                self.notices.left_on_vehicle(kind, theirs)
            elif kind not in self._reread:
                self._left_behind.add(kind)
                self._reread.add(kind)
                self._download(kind)

    def to_upload(self) -> list[PlanKind]:
        """The tab shown, and every other plan here that is not the vehicle's (one the vehicle holds but that is
        empty here is left there: removing is Remove from vehicle's, asked first)."""
        shown = self._shown()
        return [k for k in PlanKind if k is shown or (self.how_it_differs(k) and self.doc.plan(k).items)]

    def _ask_removal(self, kind: PlanKind) -> None:
        """Remove from vehicle asks first: it cannot be undone here (the list stays, Upload puts it back)."""
        theirs = self.vehicle_plan(kind)
        held = f"It holds {len(theirs)} items." if theirs is not None else "What it holds has not been read."
        box, (remove,) = warning_question(self._window, "removeQuestion", f"Remove the {kind.label} from the vehicle",
                                          f"Remove the {kind.label} from the vehicle? {held}\n\n"
                                          "The list here stays as it is.",
                                          ("Remove from vehicle", QMessageBox.DestructiveRole))

        def answered(b: QMessageBox) -> None:
            b.deleteLater()
            if b.clickedButton() is remove:
                self.transfer("clear", confirmed=kind)
        self.remove_question = ask(box, answered)

    def _download(self, kind: PlanKind) -> None:
        """Read the vehicle's plan of ``kind``: into the list here, or, when it is being read again (after a
        restart, to see what an upload leaves there), into what the vehicle holds only."""
        self.adapter.send(self.adapter.drone.download_plan, kind,
                          then=lambda answer: self._transfer_finished(kind, answer, downloaded=True))

    def _transfer_finished(self, kind: PlanKind, answer, downloaded: bool) -> None:
        """An upload's or a download's end: the driver's verdict and the plan the vehicle holds (read back, or
        read); ``answer`` is a bare CommandResult when the call itself failed."""
        outcome = answer if isinstance(answer, TransferOutcome) else TransferOutcome(answer)
        result: CommandResult = outcome.result
        if result.ok and outcome.plan is not None:
            self.on_vehicle[kind] = outcome.plan
            if downloaded and kind in self._reread:
                self._reread.discard(kind)      # what the vehicle holds now; the plan here stays as it is
                if kind in self._left_behind:
                    self.notices.left_on_vehicle(kind, outcome.plan)
            elif downloaded:
                self.editor.load(outcome.plan)
                self._synced[kind] = (self.doc.plan(kind), outcome.plan)
            elif kind in self._sending:         # the driver read it back and found it the same in meaning
                self._synced[kind] = (self._sending.pop(kind), outcome.plan)
                if kind is PlanKind.FENCE:
                    self.notices.fence_uploaded(self._state, outcome.plan)
        self._left_behind.discard(kind)
        self._outcome[kind] = str(result)
        self._failed[kind] = not result.ok
        self.changed.emit()

    def _cleared(self, kind: PlanKind, result: CommandResult) -> None:
        """A removal's answer: once accepted, the vehicle holds nothing of that kind any more."""
        if result.ok:
            self.on_vehicle[kind] = Plan(kind, ())
        self._outcome[kind] = str(result)
        self._failed[kind] = not result.ok
        self.changed.emit()
