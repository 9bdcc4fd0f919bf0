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


def played(path: str, step: float = 0.05, **config):
    """Each message of the recording ``path`` read by a driver on a manual clock, one at a time at its recorded
    time, the driver's ticker stepped every ``step`` s between them: yields (seconds into the recording, the
    driver, its state after that message). A replay over a transport is paced in real seconds and a loaded
    machine skipped states a test was waiting to see; here each state is seen, whatever the load."""
    from pymavlink import mavutil

    from driver.sim.clock import ManualClock
    from driver.vehicle import Vehicle, VehicleConfig

    clock = ManualClock()
    options = dict(connection="udpin:127.0.0.1:0", tlog_path=None, param_cache=None)
    options.update(config)
    vehicle = Vehicle(VehicleConfig(**options), clock=clock.now)
    log = mavutil.mavlink_connection(path, robust_parsing=True)
    try:
        start = stepped = None
        while (msg := log.recv_msg()) is not None:
            if msg.get_type() == "BAD_DATA":
                continue
            at = msg._timestamp                       # pymavlink's time of a .tlog record
            if start is None:
                start = stepped = at
            while stepped + step <= at:
                stepped += step
                clock.advance(max(0.0, 1000.0 + stepped - start - clock.now()))
                vehicle.step()
            clock.advance(max(0.0, 1000.0 + at - start - clock.now()))
            vehicle.ingest(msg.get_msgbuf(), publish=True)
            yield at - start, vehicle, vehicle.state()
    finally:
        log.close()
        vehicle.close()
