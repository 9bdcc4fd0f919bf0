"""The console's ``log`` verbs, in MAVProxy's words (mixed into :class:`driver.console.Console`): each answers
when the vehicle has, so ``--cmd "log download latest FILE"`` works unattended; and ``geotag``, a downloaded
log's camera events written into a folder of photos (driver.review.geotag), which needs no vehicle."""
from __future__ import annotations

import os
import threading
import time
from concurrent.futures import Future

__all__ = ["LogCommands", "entry_line", "GEOTAG_USAGE"]

LOG_USAGE = "usage: log list | log download N|latest [FILE] | log download all [FOLDER] | log erase [yes] | " \
            "log cancel"
GEOTAG_USAGE = "usage: geotag LOG FOLDER [OUT] [offset=SECONDS] [tolerance=SECONDS] [by=order|time] " \
               "[altitude=msl|relative] [camera=N] [inplace]"


def entry_line(entry) -> str:
    """One log as MAVProxy's ``log list`` shows it: number, date, size."""
    when = time.strftime("%Y-%m-%d %H:%M:%S", time.gmtime(entry.time_utc)) if entry.time_utc else "no date"
    return f"Log {entry.id}  {when}  {entry.size} bytes"


def default_file(log_id: int) -> str:
    return f"log{log_id}.bin"                     # MAVProxy's name


class LogCommands:
    """``log``; needs the Console's ``vehicle`` and ``say``."""

    def do_log(self, arg: str) -> None:
        """log list | log download N|latest [FILE] | log download all [FOLDER] | log erase [yes] | log cancel
        The vehicle's DataFlash logs (.BIN), as MAVProxy's log module: download resumes from FILE.part after a
        dropped link or a restart and ends byte-identical (size and DFReader checked); erase needs 'yes'"""
        words = arg.split()
        logs = self.vehicle.logs
        if words == ["list"]:
            self._log_report(logs.list(), show=True)
        elif len(words) in (2, 3) and words[0] == "download" and words[1] == "all":
            folder = words[2] if len(words) == 3 else "."
            self._log_all(folder)
        elif len(words) in (2, 3) and words[0] == "download":
            which = words[1]
            if which == "latest":
                path = words[2] if len(words) == 3 else None
                self.say("downloading the newest log" + (f" to {path}" if path else ""))
                if path is None:
                    future = Future()
                    logs.list().add_done_callback(lambda f: self._log_latest(f, future))
                else:
                    future = logs.download_latest(path)
                self._log_report(future)
                return
            try:
                log_id = int(which)
            except ValueError:
                raise ValueError(f"log download N: N is a log's number, got {which!r}") from None
            path = words[2] if len(words) == 3 else default_file(log_id)
            self.say(f"downloading log {log_id} to {path}")
            self._log_report(logs.download(log_id, path))
        elif words == ["erase"]:
            self.say("this erases EVERY log on the vehicle; type 'log erase yes' to do it")
        elif words == ["erase", "yes"]:
            self._log_report(logs.erase(), show=True)
        elif words == ["cancel"]:
            logs.cancel()
        else:
            raise ValueError(LOG_USAGE)

    geotag_run: Future | None = None

    def do_geotag(self, arg: str) -> None:
        """geotag LOG FOLDER [OUT] [offset=SECONDS] [tolerance=SECONDS] [by=order|time] [altitude=msl|relative]
        [camera=N] [inplace]
        Write the position of each camera event of LOG (.BIN CAM/TRIG, .tlog CAMERA_FEEDBACK) into the EXIF of
        the photos in FOLDER, the n-th photo to the n-th event, checked by time; copies go to OUT (FOLDER/geotagged
        unless given), the originals are rewritten only with 'inplace'. offset: how far the camera's clock runs
        ahead of UTC. Photos left untagged and events without a photo are listed (on a thread: the console stays
        free; ``geotag_run`` is its future)"""
        from ..review.geotag import geotag
        words = arg.split()
        options = dict(w.split("=", 1) for w in words if "=" in w)
        places = [w for w in words if "=" not in w and w != "inplace"]
        unknown = set(options) - {"offset", "tolerance", "by", "altitude", "camera"}
        if len(places) not in (2, 3) or unknown:
            raise ValueError(GEOTAG_USAGE)
        try:
            numbers = {k: float(options[k]) for k in ("offset", "tolerance") if k in options}
            camera = int(options["camera"]) if "camera" in options else None
        except ValueError:
            raise ValueError(f"geotag: offset and tolerance are seconds, camera a number; {GEOTAG_USAGE}") from None
        kwargs = dict(clock_offset=numbers.get("offset", 0.0), in_place="inplace" in words,
                      by=options.get("by", "order"), altitude=options.get("altitude", "msl"), camera=camera)
        if "tolerance" in numbers:
            kwargs["tolerance"] = numbers["tolerance"]
        future: Future = Future()

        def run() -> None:
            try:
                report = geotag(places[0], places[1], places[2] if len(places) == 3 else None, **kwargs)
            except ValueError as e:                   # GeotagError, LogError: the words are for the pilot
                self.say(f"error: geotag: {e}")
                future.set_result(None)
                return
            except Exception as e:                    # noqa: BLE001 - the console stays up
                self.say(f"error: geotag: {e}")
                future.set_exception(e)
                return
            for line in report.lines():
                self.say(line)
            future.set_result(report)
        self.geotag_run = future
        threading.Thread(target=run, name="console-geotag", daemon=True).start()

    def _log_latest(self, listed: Future, future: Future) -> None:
        outcome = listed.result()
        if not outcome.ok or not outcome.entries:
            future.set_result(outcome if not outcome.ok else
                              type(outcome)(outcome.name, False, "no logs on the vehicle"))
            return
        newest = outcome.entries[-1].id
        self.vehicle.logs.download(newest, default_file(newest)).add_done_callback(
            lambda f: future.set_result(f.result()))

    def _log_all(self, folder: str) -> None:
        def listed(f: Future) -> None:
            outcome = f.result()
            if not outcome.ok:
                self.say(f"error: {outcome.reason}")
                return
            self.say(f"downloading {len(outcome.entries)} logs to {folder}")
            for entry in outcome.entries:
                self._log_report(self.vehicle.logs.download(entry.id, os.path.join(folder,
                                                                                   default_file(entry.id))))
        self.vehicle.logs.list().add_done_callback(listed)

    def _log_report(self, future: Future, show: bool = False) -> None:
        def done(f: Future) -> None:
            outcome = f.result()                  # a LogOutcome: vehicle.logs settles its futures, never raises
            if not outcome.ok:
                self.say(f"error: {outcome.name}: {outcome.reason}")
                return
            if show:
                for entry in outcome.entries:
                    self.say(entry_line(entry))
                self.say(f"{len(outcome.entries)} logs")
            if outcome.path:
                self.say(f"Finished downloading {outcome.path} ({outcome.size} bytes in {outcome.seconds:.1f} s, "
                         f"{outcome.rate / 1000:.1f} kB/s, {outcome.messages} messages read back"
                         + (f"; it ends with {outcome.ending})" if outcome.ending else ")"))
        future.add_done_callback(done)
