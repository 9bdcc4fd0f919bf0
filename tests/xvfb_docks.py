"""Run under a real X server of a given size (tests/test_screen_steady.py starts it with xvfb-run): the window opens as
on that screen with a fresh profile (no vehicle), each of View › Messages, Plan, Map and Telemetry is hidden and shown
again, and every move of a flight control is printed as one JSON line. Qt's offscreen screen is 800×600: too short
for the layout a 1366×768 laptop gets, where Messages stood under the controls."""
from __future__ import annotations

import json
import os
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [ROOT]

from PyQt5.QtCore import QPoint, QRect, QSettings  # noqa: E402
from PyQt5.QtWidgets import QApplication  # noqa: E402

from uavviewer.connect.opener import Disconnected  # noqa: E402
from uavviewer.main_window import MainWindow, load_style  # noqa: E402


def main() -> int:
    app = QApplication(sys.argv[:1])
    app.setStyleSheet(load_style())
    folder = tempfile.mkdtemp()
    w = MainWindow(Disconnected(), qsettings=QSettings(os.path.join(folder, "viewer.ini"), QSettings.IniFormat),
                   tile_cache_dir=os.path.join(folder, "tiles"))
    w.show()

    def rects() -> dict[str, tuple]:
        for _ in range(20):
            app.processEvents()
        fc = w.flightControls
        named = {"main button": fc.main_button, "stop": fc.stop_button, "rtl": fc.rtl_button, "arm": fc.arm_button,
                 "mode": w.modeSelector, "left stick": w.leftStick, "right stick": w.rightStick,
                 "attitude": w.attitude, "video": w.camera_view}
        return {n: QRect(x.mapTo(w, QPoint(0, 0)), x.size()).getRect() for n, x in named.items()}

    before = rects()
    print(json.dumps({"window": [w.width(), w.height()]}), flush=True)
    docks = {"Messages": w.messagesDock, "Plan": w.plan.dock, "Map": w.mapDock, "Telemetry": w.telemetryDock}
    for name, dock in docks.items():
        action = dock.toggleViewAction()
        for turn in ("off", "on") if action.isChecked() else ("on", "off"):
            action.trigger()
            now = rects()
            moved = {n: [before[n], r] for n, r in now.items() if r != before[n]}
            print(json.dumps({"step": f"View › {name} {turn}", "moved": moved}), flush=True)
    w.quit_without_asking()
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    os._exit(code)              # what was measured is out; Qt's teardown at exit is not what is tested here
