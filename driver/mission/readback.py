"""The read-back that ends every upload and every clear: the plan asked back from the vehicle and compared with
what was sent (:func:`driver.mission.wire.difference`), because only the vehicle's own copy says what it holds.
Mixed into :class:`~driver.mission.transfer.PlanTransfers`, whose transfer machinery (``_Transfer``, ``_end``)
it uses.

A read-back the vehicle does not answer is not the end of what is known. At 30 % loss each way a
MISSION_REQUEST_LIST and its MISSION_COUNT both arrive about half the time, so eight tries in a row come to
nothing about once in two hundred read-backs, and the vehicle is still there (its heartbeats arrive). So:

* the vehicle acknowledged the upload (MISSION_ACK ACCEPTED after the last item): that is its word that it holds
  the plan. After the usual tries the pilot is told so, "sent and acknowledged, not verified", ACCEPTED;
* its last answer was lost (ERROR to the last item sent again says only that it no longer receives: it completed,
  or gave up): nothing is known, so the list is asked for at least :data:`READ_PATIENCE` seconds before the
  pilot is told that it is not known (TIMED_OUT);
* either way the read-back then goes on, no longer holding up the pilot, for :data:`VERIFY_FOR` seconds, or until
  the pilot starts another transfer of that plan: what it finds is recorded as "verify <plan>" and becomes the plan
  known to be on the vehicle. Until then none is claimed.
"""
from __future__ import annotations

from concurrent.futures import Future

from ..core.results import CommandStatus
from .plan import Plan, TransferDirection, TransferOutcome
from .wire import difference

__all__ = ["ReadBack", "READ_PATIENCE", "VERIFY_FOR"]

READ_PATIENCE = 30.0         # s MISSION_REQUEST_LIST is asked for, at the least, before a read-back or a download
                             # that got no answer says so (at 1.5 s a try, 20 tries: 0.51^20 is one in 700,000)
VERIFY_FOR = 120.0           # s a read-back goes on after the pilot was told it got no answer


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

    def _unanswered(self, t, why: str, now: float) -> bool:
        """Read-back ``t`` got no answer (``why``) after its tries: tell the pilot what is known and go on asking,
        or end it once its verification has run out. True when it has ended."""
        upload = t.upload
        if t.verifying is not None:
            if now - t.verifying < VERIFY_FOR:
                return False
            self._end(t, CommandStatus.TIMED_OUT, f"still not verified: {why}")
            return True
        if upload.acked:
            status, reason = CommandStatus.ACCEPTED, f"sent and acknowledged, not verified: the read-back got no " \
                f"answer ({why}); reading back goes on"
        elif now - t.first_asked < READ_PATIENCE:
            return False
        else:
            said = f"the vehicle answered {upload.said}" if upload.said else "the vehicle's last answer was lost"
            if upload.direction is TransferDirection.CLEAR:
                sent, held = "clear sent", "still holds a plan"
            else:
                sent, held = f"all {len(upload.plan)} items sent", "holds the plan"
            status, reason = CommandStatus.TIMED_OUT, f"{sent}, {said}; not known whether it {held}: the read-back " \
                f"got no answer ({why}); reading back goes on"
        result = self._record(f"{upload.direction.value} {upload.kind.label}", status, reason)
        self._settle(t.future, result if upload.direction is TransferDirection.CLEAR else TransferOutcome(result))
        self.ended.append((upload.kind, upload.direction, status, None))
        t.future, t.verifying, t.detail = Future(), now, "not verified yet: reading back"
        self.changed = True
        return False
