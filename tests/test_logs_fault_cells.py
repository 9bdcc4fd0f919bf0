"""The fault matrix's log rows (bench/log_cells.py): a cell is right only when the driver's word matches the
simulator's own log, byte for byte, or a resumable .part that holds the vehicle's bytes."""
from __future__ import annotations

import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench import log_cells  # noqa: E402
from bench.faults import FAULTS  # noqa: E402
from driver.logs.control import LogOutcome  # noqa: E402


def test_a_download_through_loss_is_judged_byte_identical(tmp_path):
    folder = log_cells.make_log(str(tmp_path / "vehicle"))
    cell = log_cells.check("solo", "loss30", "log_data", 4.0, FAULTS["loss30"][1], folder)
    assert cell.completed and not cell.wrong, (cell.error, cell.told, cell.wrong)
    assert cell.size == os.path.getsize(os.path.join(folder, "00000001.BIN"))
    head, lines = log_cells.rows([cell])
    assert dict(zip(head, lines[0]))["byte-identical"] == "yes"
    assert log_cells.paths("solo") == ("log_data",) and log_cells.paths("copter-4") == ("log_data", "ftp")


def test_the_judge_calls_a_wrong_file_or_part_wrong(tmp_path):
    own = bytes(range(256)) * 40
    out = str(tmp_path / "got.BIN")

    def judged(outcome) -> log_cells.LogCell:
        cell = log_cells.LogCell("copter-4", "clean", "log_data")
        log_cells.judge(cell, outcome, out, own)
        return cell

    saved = LogOutcome("log download 1", True, "log 1 saved")
    open(out, "wb").write(own)
    assert judged(saved).identical and not judged(saved).wrong
    open(out, "wb").write(own[:-1] + b"x")
    assert judged(saved).wrong == [f"told saved, but the file is {len(own)} bytes and not the vehicle's "
                                   f"{len(own)} bytes"]
    os.remove(out)
    stopped = LogOutcome("log download 1", False, "no data from the vehicle for 20 s: 4000 bytes of at least "
                                                  f"{len(own)} bytes kept in {out}.part, download again to resume")
    assert judged(stopped).wrong == [f"told '{stopped.reason}' but no resumable .part is left"]
    part = bytearray(own[:5000])
    open(out + ".part", "wb").write(part)
    with open(out + ".part.json", "w") as f:
        json.dump({"id": 1, "time_utc": 0, "size": None, "ranges": [[0, 4000]]}, f)
    cell = judged(stopped)
    assert not cell.wrong and cell.kept == 4000 and not cell.completed
    part[100] ^= 0xFF
    open(out + ".part", "wb").write(part)
    assert judged(stopped).wrong == ["the .part's bytes 0..4000 are not the vehicle's"]
