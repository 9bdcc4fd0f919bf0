"""A log download's files are written off the vehicle's state lock (driver/logs/partfile.py): a disk that stalls
holds up neither the link nor the download, and the map never names bytes the .part does not hold.

The driver runs on a clock the test moves (``Vehicle.step``, ``Vehicle.ingest``), against the simulated ArduCopter
in this process; each of the driver's passes runs on a thread of its own, so a pass that waits on the disk is told
instead of hanging the test.
"""
from __future__ import annotations

import json
import os
import threading

import pytest

from driver.logs import ranges
from driver.sim import Autopilot, ManualClock, SimConfig
from driver.sim.dataflash import LogFolder, write_flight_log
from driver.vehicle import Vehicle, VehicleConfig

STEP = 0.01                    # s of the vehicle's time a pass


class Bench:
    """The driver and the simulated vehicle, each stepped ``STEP`` at a time on one manual clock."""

    def __init__(self, tmp_path, size: int, **config) -> None:
        self.folder = LogFolder(str(tmp_path / "vehicle-logs"))
        write_flight_log(self.folder, size)
        self.clock = ManualClock(start=1000.0)
        self.vehicle = Vehicle(VehicleConfig(connection="udpin:127.0.0.1:0", tlog_path=None, param_cache=None),
                               clock=self.clock.now)
        self.emitted: list = []
        self.ap = Autopilot(SimConfig(log_dir=self.folder.folder, ready_after=0.0, seed=1, **config),
                            emit=self.emitted.append)

    def tick(self) -> None:
        """One pass each way; the driver's (its tick, then what the vehicle said) on a thread that must finish."""
        self.clock.advance(STEP)
        frames = [self._frame(m) for m in self.emitted]
        self.emitted.clear()
        sent: list = []

        def driver() -> None:
            sent.extend(self.vehicle.step())
            for frame in frames:
                self.vehicle.ingest(frame)
            sent.append(None)
        thread = threading.Thread(target=driver, daemon=True)
        thread.start()
        thread.join(10)
        assert sent and sent[-1] is None, "the driver's pass waited on the disk"
        for m in sent[:-1]:
            self.ap.handle(m)
        self.ap.step(STEP)

    def _frame(self, m) -> bytes:
        """``m`` as the vehicle sends it: packed, its sequence number counted on (as MAVLink.send does)."""
        data = m.pack(self.ap.factory)
        self.ap.factory.seq = (self.ap.factory.seq + 1) % 256
        return data

    def until(self, done, ticks: int = 20_000) -> None:
        for _ in range(ticks):
            if done():
                return
            self.tick()
        raise AssertionError("not done in the vehicle's time given")


@pytest.fixture
def bench(tmp_path):
    made = []

    def make(size: int, **config) -> Bench:
        made.append(Bench(tmp_path, size, **config))
        return made[-1]
    yield make
    for b in made:
        b.vehicle.close()


def test_a_stalled_disk_holds_up_neither_the_link_nor_the_download(bench, tmp_path, monkeypatch):
    b = bench(300_000, radio_baud=1_000_000)             # ~100 kB a second: many flushes of the .part
    out = str(tmp_path / "got.BIN")
    stalled, release = threading.Event(), threading.Event()
    real_fsync = os.fsync

    def slow_fsync(fd: int) -> None:                      # the .part's first fsync with bytes in it: the disk stalls
        if os.readlink(f"/proc/self/fd/{fd}") == out + ".part" and os.fstat(fd).st_size and not release.is_set():
            stalled.set()
            release.wait(60)
        real_fsync(fd)
    monkeypatch.setattr(ranges.os, "fsync", slow_fsync)
    try:
        future = b.vehicle.logs.download(1, out)
        b.until(stalled.is_set)
        held = b.vehicle.logs.progress.held
        for _ in range(50):                               # half a second of the vehicle's, the disk stalled
            b.tick()
        assert b.vehicle.logs.progress.held > held + 20_000    # the download went on
        assert b.vehicle.state().connected
    finally:
        release.set()
    b.until(future.done)
    outcome = future.result()
    assert outcome.ok, outcome.reason
    with open(out, "rb") as got, open(b.folder.path(1), "rb") as own:
        assert got.read() == own.read()


def test_the_map_names_only_bytes_the_part_holds_whenever_it_is_read(bench, tmp_path, monkeypatch):
    """Every map the worker saves during a download is read back the moment it replaces the last one: each range
    it names holds the vehicle's bytes in the .part already."""
    b = bench(200_000, radio_baud=1_000_000)
    out = str(tmp_path / "got.BIN")
    with open(b.folder.path(1), "rb") as f:
        own = f.read()
    wrong, maps = [], []
    real_replace = os.replace

    def replace(a, c) -> None:
        real_replace(a, c)
        if c == out + ".part.json":
            with open(c) as f:
                spans = json.load(f)["ranges"]      # as written (load_part_map would clip it to the .part)
            maps.append(sum(end - start for start, end in spans))
            with open(out + ".part", "rb") as f:
                for start, end in spans:
                    f.seek(start)
                    if f.read(end - start) != own[start:end]:
                        wrong.append((start, end))
    monkeypatch.setattr(ranges.os, "replace", replace)
    future = b.vehicle.logs.download(1, out)
    b.until(future.done)
    assert future.result().ok, future.result().reason
    assert len(maps) > 5 and maps == sorted(maps) and not wrong, (maps, wrong)


def test_a_cancelled_download_is_told_once_its_last_bytes_are_on_disk(bench, tmp_path, monkeypatch):
    """Whoever is told "cancelled" may read the .part's map at once (the window shows what was kept, Resume opens
    it): the outcome waits for the last bytes and the map that names them, and the cancel itself never waits on
    the disk."""
    b = bench(300_000, radio_baud=1_000_000)
    out = str(tmp_path / "got.BIN")
    future = b.vehicle.logs.download(1, out)
    b.until(lambda: b.vehicle.logs.progress and b.vehicle.logs.progress.held > 50_000)
    stalled, release = threading.Event(), threading.Event()
    real_fsync = os.fsync

    def slow_fsync(fd: int) -> None:
        if os.readlink(f"/proc/self/fd/{fd}") == out + ".part" and not release.is_set():
            stalled.set()
            release.wait(60)
        real_fsync(fd)
    monkeypatch.setattr(ranges.os, "fsync", slow_fsync)
    try:
        held = b.vehicle.logs.progress.held
        cancel = threading.Thread(target=b.vehicle.logs.cancel, daemon=True)
        cancel.start()
        cancel.join(10)
        assert not cancel.is_alive(), "the cancel waited on the disk"
        b.until(stalled.is_set)
        for _ in range(20):
            b.tick()
        assert not future.done(), "told before its last bytes were on disk"
    finally:
        release.set()
    b.until(future.done)
    outcome = future.result()
    assert not outcome.ok and outcome.reason == "cancelled"
    with open(out + ".part.json") as f:
        spans = json.load(f)["ranges"]
    assert sum(end - start for start, end in spans) >= held          # (the last tick's bytes too)
    with open(out + ".part", "rb") as got, open(b.folder.path(1), "rb") as own:
        part, vehicle = got.read(), own.read()
    assert all(part[start:end] == vehicle[start:end] for start, end in spans)
