"""The fault matrix's gate (bench/verdicts.py): exit 0 only when every cell is right, and the cells that are not
named. The Solo's honest refusals of a fence its firmware lacks are right; a wrong report is never hidden by them;
a cell that did not get done is not right either, whatever else went well.

The cells are the benches' own (fault_matrix.Cell, transfer_matrix.TransferCell, param_cells.ParamCell,
log_cells.LogCell) as their runs fill them; the refusal's words are the driver's own.
"""
from __future__ import annotations

import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "bench"))

import fault_matrix  # noqa: E402  (bench/: the scripts import each other by name)
import log_cells  # noqa: E402
import param_cells  # noqa: E402
import transfer_matrix  # noqa: E402
import verdicts  # noqa: E402
from driver.mission.plan import PlanKind  # noqa: E402
from driver.mission.transfer import PlanTransfers  # noqa: E402


def solo_fence_refusal() -> str:
    """What the driver answers a fence transfer on the Solo (ArduCopter 3.3, MAVLink 1)."""
    transfers = PlanTransfers(None, (255, 190), lambda: (1, 1), None, None, lambda: None, lambda: False)
    return transfers.unsupported(PlanKind.FENCE)


def transfer_cell(profile: str, fault: str = "clean", **rows) -> transfer_matrix.TransferCell:
    """A transfer cell whose rows were all accepted, but for ``rows`` (name with _ for spaces: (status, reason))."""
    cell = transfer_matrix.TransferCell(profile, fault)
    for row in transfer_matrix.ROWS:
        cell.results[row] = rows.get(row.replace(" ", "_"), ("accepted", "50 items, accepted and read back"))
    return cell


def solo_cell(fault: str = "clean") -> transfer_matrix.TransferCell:
    refusal = ("rejected", solo_fence_refusal())
    return transfer_cell("solo", fault, fence_up=refusal, fence_down=refusal)


def flight(profile: str = "copter-4", fault: str = "clean", **kw) -> fault_matrix.Cell:
    return fault_matrix.Cell(profile, fault, **dict(dict(completed=True), **kw))


def params(told=("accepted",) * 6 + ("timed out",), **kw) -> param_cells.ParamCell:
    return param_cells.ParamCell("copter-4", "loss30", "ftp", **dict(dict(downloaded=1392, expected=1392,
                                                                          told=list(told)), **kw))


def log(**kw) -> log_cells.LogCell:
    return log_cells.LogCell("solo", "bursts", "log_data", **dict(dict(told="saved", identical=True), **kw))


def gate(capsys, cells) -> tuple[int, list[str]]:
    code = verdicts.report(cells)
    return code, capsys.readouterr().out.strip().splitlines()


def test_every_cell_right_with_the_solos_fence_refusals_exits_0(capsys):
    assert "no polygon fence" in solo_fence_refusal()
    solo = [transfer_matrix.verdict(solo_cell(fault)) for fault in ("clean", "loss30")]
    assert [(v.verdict, v.refused) for v in solo] == [(verdicts.RIGHT, 2)] * 2
    code, lines = gate(capsys, [verdicts.flight(flight())] + solo + [verdicts.parameters(params()),
                                                                      verdicts.log(log())])
    assert code == 0
    assert lines == ["Verdict: 5 cells: 5 right (4 rows of them refused for what the firmware lacks), 0 wrong, "
                     "0 unfinished; exit 0"]


def test_a_wrong_report_is_never_hidden_and_the_cell_is_named(capsys):
    wrong = solo_cell("loss30")
    wrong.wrong.append("mission up: told timed out (no answer) but the vehicle holds the plan")
    code, lines = gate(capsys, [transfer_matrix.verdict(solo_cell()), transfer_matrix.verdict(wrong),
                                verdicts.flight(flight(fault="loss30", completed=False, error="did not land",
                                                       wrong=["takeoff: refused but the vehicle is at 2.9 m"]))])
    assert code == 1
    assert lines[0].endswith("1 right (2 rows of them refused for what the firmware lacks), 2 wrong, "
                             "0 unfinished; exit 1")
    assert lines[1:] == ["WRONG transfers solo/loss30: mission up: told timed out (no answer) but the vehicle "
                         "holds the plan",
                         "WRONG flight copter-4/loss30: takeoff: refused but the vehicle is at 2.9 m"]


@pytest.mark.parametrize("cell, named", [
    (lambda: verdicts.flight(flight("solo", "loss30", completed=False, error="takeoff command: refused")),
     "UNFINISHED flight solo/loss30: takeoff command: refused"),
    (lambda: transfer_matrix.verdict(transfer_cell("copter-4", "loss30", mission_down=(
        "timed out", "no answer to MISSION_REQUEST_LIST after 20 attempts in 30 s"))),
     "UNFINISHED transfers copter-4/loss30: mission down: timed out (no answer to MISSION_REQUEST_LIST after "
     "20 attempts in 30 s)"),
    # the firmware's words, but a vehicle that has the fence: the driver should have sent it
    (lambda: transfer_matrix.verdict(transfer_cell("copter-4", fence_up=("rejected", solo_fence_refusal()))),
     "UNFINISHED transfers copter-4/clean: fence up: rejected"),
    # the Solo, but not refused for what it lacks
    (lambda: transfer_matrix.verdict(transfer_cell("solo", fence_up=("rejected", "a fence upload is running"),
                                                   fence_down=("rejected", solo_fence_refusal()))),
     "UNFINISHED transfers solo/clean: fence up: rejected (a fence upload is running)"),
    (lambda: verdicts.parameters(params(told=("accepted", "accepted", "timed out", "accepted", "accepted",
                                              "accepted", "timed out"))),
     "UNFINISHED parameters over ftp copter-4/loss30: sets told accepted, timed out, accepted"),
    (lambda: verdicts.log(log(told="not finished: 120,000 of 300,074 bytes; resume to finish", identical=False,
                              kept=120_000)),
     "UNFINISHED log over log_data solo/bursts: not finished (not finished: 120,000 of 300,074 bytes; resume to "
     "finish), 120,000 bytes kept resumable"),
])
def test_a_cell_not_done_is_unfinished_and_exits_1(capsys, cell, named):
    code, lines = gate(capsys, [verdicts.flight(flight()), cell()])
    assert code == 1
    assert lines[0].endswith("1 right (0 rows of them refused for what the firmware lacks), 0 wrong, "
                             "1 unfinished; exit 1"), lines
    assert lines[1].startswith(named), lines
