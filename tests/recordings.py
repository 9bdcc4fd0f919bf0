"""The recordings of a real ArduCopter, kept inside the project (``tests/data/recordings``, a copy of the
workplace's ``shared/recordings``), so a fresh clone runs every test. ``UAV_RECORDINGS`` points elsewhere."""
from __future__ import annotations

import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RECORDINGS = os.environ.get("UAV_RECORDINGS") or os.path.join(ROOT, "tests", "data", "recordings")
FLIGHT = os.path.join(RECORDINGS, "arducopter-4.7-sitl-flight")
SIGNING = os.path.join(RECORDINGS, "arducopter-4.7-sitl-signing")
MISSION = os.path.join(RECORDINGS, "arducopter-4.6-sitl-mission")
GIMBAL = os.path.join(RECORDINGS, "arducopter-4.6-sitl-gimbal")
PARAMS = os.path.join(RECORDINGS, "arducopter-4.6-sitl-params")

FTP_PARAMS = os.path.join(RECORDINGS, "arducopter-4.6-sitl-ftp-params")
FTP_PARAMS_SERIAL1 = os.path.join(RECORDINGS, "arducopter-4.6-sitl-ftp-params-serial1")
LOGS = os.path.join(RECORDINGS, "arducopter-4.6-sitl-logs")
SETUP = os.path.join(RECORDINGS, "arducopter-4.6-sitl-setup")
CALIB = os.path.join(RECORDINGS, "arducopter-4.6-sitl-calib")
ADSB = os.path.join(RECORDINGS, "arducopter-4.6-sitl-adsb")
