"""Undo and redo for Plan mode: every edit of the :class:`~uavviewer.plan.model.PlanDocument` is one step on a
QUndoStack (Ctrl+Z, Ctrl+Shift+Z), and the stack's clean state says whether there is work not saved to a file.

A step holds the whole document before and after (its lists hold immutable items and surveys, so a snapshot is a
few tuples, however large the plan): an edit never has to know how to undo itself, and a drag's many moves of
one item merge into one step.
"""
from __future__ import annotations

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QUndoCommand, QUndoStack

__all__ = ["PlanHistory"]


def _snapshot(doc) -> tuple:
    return tuple(doc.entries), tuple(doc.fence), tuple(doc.fence_extra), tuple(doc.rally)


class _Step(QUndoCommand):
    def __init__(self, history: "PlanHistory", before: tuple, after: tuple, text: str, merge) -> None:
        super().__init__(text)
        self._history, self.before, self.after, self.merge = history, before, after, merge
        self._done = True                       # pushed after the edit was made: the first redo does nothing

    def id(self) -> int:                        # noqa: A003 (Qt's name)
        return 1 if self.merge is not None else -1

    def mergeWith(self, other: QUndoCommand) -> bool:    # noqa: N802 (Qt's name)
        if not isinstance(other, _Step) or other.merge != self.merge:
            return False
        self.after = other.after
        return True

    def redo(self) -> None:
        if self._done:
            self._done = False
            return
        self._history.restore(self.after)

    def undo(self) -> None:
        self._history.restore(self.before)


class PlanHistory(QObject):
    """The document's edits, undoable; ``restored`` after an undo or redo changed the document."""
    restored = pyqtSignal()

    def __init__(self, doc, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.stack = QUndoStack(self)
        self._recorded = _snapshot(doc)

    def record(self, text: str, merge=None) -> None:
        """The document changed (or not): a step from the last state to this one. Steps with the same ``merge``
        key in a row become one (a drag)."""
        now = _snapshot(self.doc)
        if now != self._recorded:
            before, self._recorded = self._recorded, now
            self.stack.push(_Step(self, before, now, text, merge))

    def restore(self, snapshot: tuple) -> None:
        d = self.doc
        d.entries, d.fence, d.fence_extra, d.rally = (list(part) for part in snapshot)
        self._recorded = snapshot
        self.restored.emit()

    @property
    def modified(self) -> bool:
        """Edits since the plan was last saved, opened or started anew."""
        return not self.stack.isClean()

    def mark_saved(self) -> None:
        self.stack.setClean()
