"""The read-back that ends every upload and every clear: the plan asked back from the vehicle and compared with
what was sent (:func:`driver.mission.wire.difference`), because only the vehicle's own copy says what it holds.
Mixed into :class:`~driver.mission.transfer.PlanTransfers`, whose transfer machinery (``_Transfer``, ``_end``)
it uses.
"""
from __future__ import annotations

from ..core.results import CommandStatus
from .plan import Plan, TransferDirection
from .wire import difference

__all__ = ["ReadBack"]


class ReadBack:
    """The verdict of a read-back: what the upload or clear it checks comes to."""

    def _checked(self, t, plan: Plan) -> None:
        """``plan``, read back by ``t``, against what its upload sent (or its clear emptied)."""
        upload = t.upload
        why = difference(upload.plan, plan, self.integer)
        said = f"{upload.said}; " if upload.said else ""
        if upload.direction is TransferDirection.CLEAR:
            if why:
                self._end(t, CommandStatus.REFUSED, f"{said}the vehicle still holds {len(plan)} items", plan)
            else:
                self._end(t, CommandStatus.ACCEPTED, f"cleared (read back empty; the vehicle had answered "
                          f"{upload.said})", plan)
        elif why:
            self._end(t, CommandStatus.REFUSED, f"{said}the plan read back differs: {why}", plan)
        elif upload.said:
            self._end(t, CommandStatus.ACCEPTED, f"{len(plan)} items read back as sent (the vehicle answered "
                      f"{upload.said} to an item sent again after it had the plan)", plan)
        elif upload.acked:
            self._end(t, CommandStatus.ACCEPTED, f"{len(plan)} items, accepted and read back", plan)
        else:
            self._end(t, CommandStatus.ACCEPTED, f"{len(plan)} items read back as sent (the vehicle's final "
                      "MISSION_ACK was lost)", plan)
