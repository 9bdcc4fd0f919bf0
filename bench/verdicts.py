"""The fault matrix's gate: one verdict a cell, and an exit code that means it (bench/fault_matrix.py and
bench/transfer_matrix.py end with :func:`report`).

Every cell is one of three:

* **right**: done as asked (the flight landed; every plan is on the vehicle as told and read back; every parameter
  read and every set of one the vehicle has confirmed; the log byte-identical), where a row the driver refused,
  with the firmware's own reason, for what that firmware lacks counts as done: the Solo's ArduCopter 3.3 has no
  polygon fence, so its fence rows are "refused: no fence on 3.3";
* **wrong**: the driver said something the vehicle's truth contradicts when it said it (a wrong report), or the
  vehicle holds part of a plan while the driver claims one (a corrupted plan). Wrong outranks the rest of the cell;
* **unfinished**: nothing wrong was said, but the cell was not done: timed out, refused by the vehicle or by the
  driver for a reason that is not the firmware's, a crash inside the cell, a log left resumable, a parameter
  not read.

The bench exits 0 only when every cell is right, else 1, and names each cell that is not, with why.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Verdict", "RIGHT", "WRONG", "UNFINISHED", "flight", "transfers", "parameters", "log", "report"]

RIGHT, WRONG, UNFINISHED = "right", "wrong", "unfinished"
ACCEPTED, REJECTED = "accepted", "rejected"          # CommandStatus values, as the cells keep them


@dataclass(frozen=True)
class Verdict:
    cell: str                   # which: "flight solo/loss30", "transfers copter-4/clean", ...
    verdict: str                # RIGHT, WRONG or UNFINISHED
    why: str = ""               # what was wrong, or what was not done
    refused: int = 0            # rows the driver refused for what the firmware lacks (right)


def _judged(cell: str, wrong: list, done: bool, why: str, refused: int = 0) -> Verdict:
    if wrong:
        return Verdict(cell, WRONG, "; ".join(wrong), refused)
    if not done:
        return Verdict(cell, UNFINISHED, why, refused)
    return Verdict(cell, RIGHT, "", refused)


def flight(c) -> Verdict:
    """A flight cell (fault_matrix.Cell): takeoff, forward, stop, land, disarmed."""
    return _judged(f"flight {c.profile}/{c.fault}", c.wrong, c.completed, c.error or "not completed")


def transfers(c, rows, lacks: dict[str, str]) -> Verdict:
    """A transfer cell (transfer_matrix.TransferCell). ``lacks``: for a row whose name begins with a key, the words
    the driver's refusal must give for the firmware to lack it ("fence" -> "no polygon fence")."""
    refused, undone = 0, []
    for row in rows:
        status, reason = c.results.get(row, (None, ""))
        lacked = next((words for prefix, words in lacks.items() if row.startswith(prefix)), None)
        if status == ACCEPTED:
            continue
        if status == REJECTED and lacked is not None and lacked in reason:
            refused += 1
        else:
            undone.append(f"{row}: {status or 'not run'}" + (f" ({reason})" if reason else ""))
    wrong = list(c.wrong) + ([f"{c.corrupted} corrupted plans"] if c.corrupted else [])
    return _judged(f"transfers {c.profile}/{c.fault}", wrong, not undone and not c.error,
                   c.error or "; ".join(undone), refused)


def parameters(c) -> Verdict:
    """A parameter cell (param_cells.ParamCell): the whole table read, every set of a known name confirmed."""
    done = c.completed and c.sets_confirmed
    why = c.error or ("not every parameter read" if not c.completed else f"sets told {', '.join(c.told[1:])}")
    return _judged(f"parameters over {c.method} {c.profile}/{c.fault}", c.wrong, done, why)


def log(c) -> Verdict:
    """A log cell (log_cells.LogCell): byte-identical, or it is not finished (a resumable .part is right to tell,
    but the cell is not done)."""
    why = c.error or f"not finished ({c.told}), {c.kept:,} bytes kept resumable"
    return _judged(f"log over {c.path} {c.profile}/{c.fault}", c.wrong, c.completed, why)


def report(verdicts: list[Verdict]) -> int:
    """Print the gate's lines (stdout, after the tables): the count of each verdict, then every cell that is not
    right. Returns the exit code: 0 only when every cell is right."""
    count = {v: sum(1 for x in verdicts if x.verdict == v) for v in (RIGHT, WRONG, UNFINISHED)}
    refused = sum(v.refused for v in verdicts if v.verdict == RIGHT)
    code = 0 if verdicts and count[RIGHT] == len(verdicts) else 1
    print(f"\nVerdict: {len(verdicts)} cells: {count[RIGHT]} right ({refused} rows of them refused for what the "
          f"firmware lacks), {count[WRONG]} wrong, {count[UNFINISHED]} unfinished; exit {code}")
    for v in verdicts:
        if v.verdict != RIGHT:
            print(f"{v.verdict.upper()} {v.cell}: {v.why}")
    return code
