"""What the pilot's tools cost and whether switching connections ever stalls the window.

    .venv/bin/python bench/bench_pilot_tools.py [--switches 6] [--write-docs]

Runs the real window (offscreen) on the embedded driver and two simulated vehicles. A 10 ms timer measures how
late the UI thread answers while File › Connect switches back and forth between them (each switch opens the new
link on a worker thread and closes the old one off the UI thread): any lateness is input lag the pilot feels.
Prints, per switch, the time from Connect to the new vehicle's first heartbeat in the window, and the UI's worst
lateness over all switches. Then times, per snapshot, the alert model, the preflight lines and an alert spoken
(handing the text to espeak-ng: the UI thread only starts a process).
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PyQt5.QtCore import QSettings, QTimer  # noqa: E402
from PyQt5.QtWidgets import QApplication  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--switches", type=int, default=6)
    parser.add_argument("--mute", action="store_true", help="no spoken alerts (to see what speech costs)")
    tables.add_write_docs(parser)
    args = parser.parse_args()
    import tempfile

    from driver.sim import SimConfig, SimVehicle
    from driver.vehicle.state import LinkHealth, LinkStatus, VehicleState
    from driver.vehicle import Vehicle, VehicleConfig
    from uavviewer.alerts.model import Alert, AlertKind, AlertModel
    from uavviewer.alerts.speech import Speaker
    from uavviewer.connect.choice import Choice, Kind
    from uavviewer.main_window import MainWindow
    from uavviewer.preflight.model import overall, preflight
    from driver.vehicle.state import Severity

    app = QApplication(sys.argv[:1])
    sims = [SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0)).start() for _ in range(2)]
    folder = tempfile.mkdtemp()
    first = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sims[0].tcp_port}", tlog_path=None)).start()
    w = MainWindow(first, qsettings=QSettings(os.path.join(folder, "v.ini"), QSettings.IniFormat))
    w.connections.adopt(first)
    w.alerts.speaker.set_muted(args.mute)
    w.resize(1366, 768)
    w.show()

    late: list[float] = []
    last = [time.perf_counter()]

    def tick():
        now = time.perf_counter()
        late.append(max(0.0, now - last[0] - 0.010))
        last[0] = now
    timer = QTimer()
    timer.timeout.connect(tick)
    timer.start(10)

    def wait(predicate, seconds: float) -> bool:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            app.processEvents()
            if predicate():
                return True
            time.sleep(0.002)
        return False

    assert wait(lambda: w.adapter.state.connected, 15), "no first vehicle"
    late.clear()
    wait(lambda: False, 3.0)                            # the same window, connected, nothing switching
    print(f"UI lateness, connected, not switching: p99 {sorted(late)[int(len(late) * 0.99)] * 1000:.1f} ms, "
          f"max {max(late) * 1000:.1f} ms ({len(late)} ticks of 10 ms)")
    late.clear()
    spent = []
    use = w.use_connection

    def timed(drone):
        t0 = time.perf_counter()
        use(drone)
        spent.append(time.perf_counter() - t0)
    w.use_connection = timed
    times = []
    for i in range(args.switches):
        sim = sims[(i + 1) % 2]
        old = w.adapter.drone
        start = time.perf_counter()
        w.connections.connect_to(Choice(Kind.MAVLINK, f"tcp:127.0.0.1:{sim.tcp_port}"))
        assert wait(lambda: w.adapter.drone is not old and w.adapter.state.connected, 15), "no switch"
        times.append(time.perf_counter() - start)
        wait(lambda: False, 0.5)                        # the old link closes meanwhile, off the UI thread
    print(f"switch to a vehicle's first heartbeat: median {statistics.median(times) * 1000:.0f} ms, "
          f"max {max(times) * 1000:.0f} ms ({len(times)} switches, TCP on loopback, sim at 1x)")
    print(f"the window's switch on the UI thread (use_connection): median {statistics.median(spent) * 1000:.1f} ms, "
          f"max {max(spent) * 1000:.1f} ms")
    print(f"UI lateness while switching: p99 {sorted(late)[int(len(late) * 0.99)] * 1000:.1f} ms, "
          f"max {max(late) * 1000:.1f} ms ({len(late)} ticks of 10 ms)")

    s = w.adapter.state
    model = AlertModel()
    model.update(s)
    lost = VehicleState(link=LinkHealth(status=LinkStatus.LOST), mode=s.mode)
    n = 20000
    t0 = time.perf_counter()
    for i in range(n):
        model.update(lost if i % 2 else s)
    alerts_us = (time.perf_counter() - t0) / n * 1e6
    t0 = time.perf_counter()
    for _ in range(n):
        overall(preflight(s))
    preflight_us = (time.perf_counter() - t0) / n * 1e6
    speaker = Speaker()
    alert = Alert(AlertKind.LINK_LOST, "Link lost", Severity.CRITICAL)
    said = []
    for _ in range(20):
        t0 = time.perf_counter()
        speaker.say(alert)
        said.append(time.perf_counter() - t0)
        wait(lambda: not speaker.busy, 5)
    print(f"per snapshot: alert model {alerts_us:.1f} µs, preflight lines {preflight_us:.1f} µs; "
          f"an alert handed to {speaker.engine}: median {statistics.median(said) * 1000:.2f} ms on the UI thread")
    speaker.close()
    w.quit_without_asking()
    w.connections.close()
    for sim in sims:
        sim.stop()
    return 0


if __name__ == "__main__":
    with tables.publishing(tables.variant("pilot_tools", "--mute")):
        sys.exit(main())
