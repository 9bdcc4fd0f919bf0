"""What an upload leaves the vehicle with that the plan here does not say, asked where the pilot pressed Upload:

* its fence is off (FENCE_ENABLE 0): the fence just uploaded keeps nothing inside, a breach does nothing. Turn it
  on? (FENCE_ENABLE 1 goes through the Parameters page's checked write, reviewed and confirmed by the vehicle);
* it keeps a fence (or rally points) from before that this plan has none of (an upload never removes them). Remove
  it from the vehicle?

Each question's default (Enter, Escape) changes nothing; what was said also goes to Messages.
"""
from __future__ import annotations

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QMessageBox, QWidget

from driver.mission.plan import Plan, PlanKind
from driver.vehicle.state import Severity, VehicleState

from ..widgets.ask import ask, cautious_question
from .vehicle_view import fence_off_words

__all__ = ["UploadNotices"]


class UploadNotices(QObject):
    fenceOnRequested = pyqtSignal()            # FENCE_ENABLE 1, through the Parameters page's checked write
    removeRequested = pyqtSignal(object)       # a PlanKind to take off the vehicle (the pilot said yes here)
    said = pyqtSignal(str, object)             # a line for Messages (text, Severity)

    def __init__(self, window: QWidget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._window = window
        self.box: QMessageBox | None = None    # the question open now (tests answer it)

    def fence_uploaded(self, s: VehicleState, plan: Plan) -> None:
        """A fence went up: say so if the vehicle's own fence is off, and offer to turn it on."""
        words = fence_off_words(s)
        if not plan.items or not words:
            return
        text = (f"{words}: the fence just uploaded keeps nothing inside, and a breach does nothing "
                "(FENCE_ACTION never runs).\n\nTurn the fence on? FENCE_ENABLE 1 is written through Parameters, "
                "where you review it first.")
        self.said.emit(f"{words}: the fence uploaded is not enforced", Severity.WARNING)
        self._ask("fenceOffQuestion", "Fence off on the vehicle", text, "Turn fence on…", self.fenceOnRequested.emit)

    def left_on_vehicle(self, kind: PlanKind, there: Plan) -> None:
        """The plan uploaded has no ``kind``, and the vehicle holds ``there`` from before."""
        if not there.items:
            return
        what = "fence" if kind is PlanKind.FENCE else "rally points"
        text = (f"This plan has no {kind.label}, but the vehicle keeps its {what} from before ({len(there)} items): "
                f"an upload never removes {'it' if kind is PlanKind.FENCE else 'them'}.\n\n"
                f"Remove the {kind.label} from the vehicle?")
        self.said.emit(f"The vehicle keeps its {what} from before ({len(there)} items): this plan has none",
                       Severity.WARNING)
        self._ask("keptPlanQuestion", f"The vehicle keeps its {what}", text, "Remove from vehicle",
                  lambda: self.removeRequested.emit(kind))

    def _ask(self, name: str, title: str, text: str, yes: str, then) -> None:
        if self.box is not None:
            self.box.reject()

        def answered(b: QMessageBox) -> None:
            if self.box is b:
                self.box = None
            b.deleteLater()
            if b.clickedButton() is b.button(QMessageBox.Yes):
                then()
        self.box = ask(cautious_question(self._window, title, text, yes, name, QMessageBox.Warning), answered)
