"""A log download onto a disk that fills up, then again once there is room (run as a subprocess by
test_logs_download.py, so the full disk is real and touches nobody else).

    python logs_full_disk.py MODE PORT LOG_ID DISK ROOM COPY_TO

MODE "tmpfs": DISK is a small tmpfs of this process's own mount namespace (``unshare -Urm``, no root): a filler
file leaves ROOM bytes free, and write() fails with ENOSPC; removing the filler gives the room back.
MODE "fsize": DISK is any folder; RLIMIT_FSIZE caps every file of this process at ROOM bytes (SIGXFSZ ignored, so
write() fails with EFBIG); raising the limit again gives the room back.

Prints one JSON object: both outcomes, the .part map kept after the first, whether the driver was still
answering, and copies the .part as the full disk left it to COPY_TO.part and the finished file to COPY_TO (outside
the tmpfs) for the test to compare.
"""
from __future__ import annotations

import json
import os
import resource
import shutil
import signal
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from driver.logs.ranges import load_part_map          # noqa: E402
from driver.vehicle.vehicle import Vehicle, VehicleConfig   # noqa: E402


def outcome_dict(o) -> dict:
    return {"ok": o.ok, "reason": o.reason, "size": o.size, "resumed_from": o.resumed_from}


def main() -> None:
    mode, port, log_id, disk, room, copy_to = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4], \
        int(sys.argv[5]), sys.argv[6]
    filler = os.path.join(disk, "filler")
    if mode == "fsize":
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]
        resource.setrlimit(resource.RLIMIT_FSIZE, (room, hard))
    else:
        free = os.statvfs(disk)
        with open(filler, "wb") as f:
            f.write(b"\0" * (free.f_bavail * free.f_frsize - room))
    out = os.path.join(disk, "one.BIN")
    v = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{port}", param_cache=None)).start()   # no other file
    try:
        if not v.wait_for(lambda s: s.connected, 20):
            raise SystemExit("no heartbeat from the simulated vehicle")
        first = v.logs.download(log_id, out).result(40)
        part = load_part_map(out)
        kept = part.ranges.spans if part else None
        listed = v.logs.list().result(30)              # the driver goes on answering
        if mode == "fsize":
            resource.setrlimit(resource.RLIMIT_FSIZE, (resource.RLIM_INFINITY, hard))
        else:
            os.remove(filler)
        if os.path.exists(out + ".part"):
            shutil.copyfile(out + ".part", copy_to + ".part")      # as the full disk left it
        second = v.logs.download(log_id, out).result(40)
        if second.ok:
            shutil.copyfile(out, copy_to)
        print(json.dumps({"first": outcome_dict(first), "kept": kept, "listed": listed.ok,
                          "second": outcome_dict(second), "left": sorted(os.listdir(disk))}))
    finally:
        v.close()


if __name__ == "__main__":
    main()
