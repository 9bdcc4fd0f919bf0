"""bench/hostile.py as a test: every kind of hostile input thrown at the protected link (signing vehicle, pinned
and signing driver) is dropped by the part that should drop it, and none changes the vehicle or what the pilot
sees. The bench prints the same table with more tries."""
from __future__ import annotations

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from bench.hostile import KINDS, run  # noqa: E402


def test_no_hostile_input_changes_the_vehicle_or_what_the_pilot_sees():
    rows = run(tries=8, speedup=8.0)
    assert len(rows) == len(KINDS), rows                   # a row more: the pilot's own Land failed afterwards
    for row in rows:
        assert row.dropped == row.tried, row
        assert row.changed == [], row
