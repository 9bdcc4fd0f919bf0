"""The console's smart shots (mixed into :class:`driver.console.console.Console`): ``shot orbit|cable|selfie|
follow|pano`` and the buttons a running shot has (pause, resume, reverse, speed, stop)."""
from __future__ import annotations

import threading
import time

from ..core.results import CommandStatus
from .words import number

__all__ = ["ShotCommands", "shot_line", "SHOT_USAGE"]

SHOT_USAGE = ("shot | shot orbit [LAT LON [ALT]] [radius M] [speed M_S] [roi] | "
              "shot cable record|clear|list|play [speed M_S] [at N]|save FILE|load FILE | "
              "shot selfie [distance M] [rise M] [speed M_S] [pilot LAT LON] | "
              "shot follow [given|nmea+udp://:PORT|nmea+tcp://HOST:PORT|nmea+serial:///DEV|gpsd://HOST] "
              "[engine auto|follow|guided] | shot target LAT LON [ALT] | "
              "shot pano [cylinder|sphere] [fov DEG] [lens DEG] [pitch DEG] | shot pause|resume|reverse|stop|speed M_S")
FIRST_FIX_WAIT = 5.0         # s a follow from a stream waits for its first fix


def shot_line(s) -> str:
    """"orbit flying: orbiting at 20.1 m, 3.0 m/s (camera 0.8° off)"; the cable's keyframes when none runs."""
    shot = s.shot
    text = shot.describe()
    if shot.aim_error is not None and shot.active:
        text += f" (camera {shot.aim_error:.1f}° off)"
    if shot.progress is not None and shot.active:
        text += f", {100 * shot.progress:.0f} % along"
    return text + f"; {len(shot.keyframes)} keyframes recorded"


def _options(words: list[str], names: dict[str, int]) -> dict[str, list[str]]:
    """``{"radius": ["20"], "roi": []}`` from ``radius 20 roi``: each option name followed by its count of values."""
    out, i = {}, 0
    while i < len(words):
        name = words[i]
        if name not in names:
            raise ValueError(f"unknown option {name!r}: usage: {SHOT_USAGE}")
        values = words[i + 1:i + 1 + names[name]]
        if len(values) != names[name]:
            raise ValueError(f"{name} takes {names[name]} value(s)")
        out[name] = values
        i += 1 + names[name]
    return out


class ShotCommands:
    """``self.vehicle`` is a :class:`~driver.vehicle.api.Drone`; its ``shots`` runs them."""

    def do_shot(self, arg: str) -> None:
        """shot orbit|cable|selfie|follow|pano ...: a smart shot (docs/shots.md); "shot" alone shows it"""
        words = arg.split()
        shots = self.vehicle.shots
        if not words:
            self.say(shot_line(self.vehicle.state()))
            return
        verb, rest = words[0], words[1:]
        if verb in ("pause", "resume", "reverse", "stop") and not rest:
            self._report(getattr(shots, verb)())
        elif verb == "speed" and len(rest) == 1:
            self._report(shots.set_cruise(number(rest[0], "M_S")))
        elif verb == "orbit":
            self._orbit(shots, rest)
        elif verb == "cable":
            self._cable(shots, rest)
        elif verb == "selfie":
            o = _options(rest, {"distance": 1, "rise": 1, "speed": 1, "pilot": 2})
            pilot = (number(o["pilot"][0], "LAT"), number(o["pilot"][1], "LON")) if "pilot" in o else None
            self._report(shots.selfie(number(o.get("distance", ["30"])[0], "distance"),
                                      number(o.get("rise", ["15"])[0], "rise"),
                                      number(o.get("speed", ["3"])[0], "speed"), pilot))
        elif verb == "follow":
            source = rest.pop(0) if rest and rest[0] != "engine" else "given"
            o = _options(rest, {"engine": 1})
            self._follow(shots, source, o.get("engine", ["auto"])[0])
        elif verb == "target" and len(rest) in (2, 3):
            alt = number(rest[2], "ALT") if len(rest) == 3 else None
            ok = shots.follow_position(number(rest[0], "LAT"), number(rest[1], "LON"), alt)
            self.say("target fix taken" if ok else "target fix refused: not a place on Earth")
        elif verb == "pano":
            shape = rest.pop(0) if rest and rest[0] in ("cylinder", "sphere") else "cylinder"
            o = _options(rest, {"fov": 1, "lens": 1, "pitch": 1})
            self._report(shots.pano(shape, number(o.get("fov", ["360"])[0], "fov"),
                                    number(o.get("lens", ["74"])[0], "lens"), number(o.get("pitch", ["0"])[0], "pitch")))
        else:
            raise ValueError(f"usage: {SHOT_USAGE}")

    def _orbit(self, shots, rest: list[str]) -> None:
        centre: list[float] = []
        while rest and rest[0] not in ("radius", "speed", "roi") and len(centre) < 3:
            centre.append(number(rest.pop(0), ("LAT", "LON", "ALT")[len(centre)]))
        if len(centre) == 1:
            raise ValueError("the centre is LAT LON [ALT]")
        o = _options(rest, {"radius": 1, "speed": 1, "roi": 0})
        lat, lon, alt = (centre + [0.0])[:3] if centre else (None, None, 0.0)
        radius = number(o["radius"][0], "radius") if "radius" in o else None
        self._report(shots.orbit(lat, lon, alt, radius, number(o.get("speed", ["0"])[0], "speed"), "roi" in o))

    def _cable(self, shots, rest: list[str]) -> None:
        verb = rest.pop(0) if rest else "list"
        if verb == "record" and not rest:
            self._report(shots.record_keyframe())
        elif verb == "clear" and not rest:
            self._report(shots.set_keyframes(()))
        elif verb == "list" and not rest:
            keys = shots.keyframes()
            self.say(f"{len(keys)} keyframes" + "".join(
                f"\n  {i + 1}: {k.lat:.7f}, {k.lon:.7f}, {k.alt:.1f} m, camera {k.pitch:.0f}° at {k.yaw:.0f}°"
                for i, k in enumerate(keys)))
        elif verb == "play":
            o = _options(rest, {"speed": 1, "at": 1})
            attach = int(number(o["at"][0], "N", integer=True)) - 1 if "at" in o else None
            self._report(shots.cable(number(o.get("speed", ["0"])[0], "speed"), attach))
        elif verb == "save" and len(rest) == 1:
            self.say(str(shots.save_cable(rest[0])))
        elif verb == "load" and len(rest) == 1:
            self._report(shots.load_cable(rest[0]))
        else:
            raise ValueError("usage: shot cable record|clear|list|play [speed M_S] [at N]|save FILE|load FILE")

    def _follow(self, shots, source: str, engine: str) -> None:
        """A stream's first fixes take a moment after it is opened: asked again for up to FIRST_FIX_WAIT s, off the
        console's own thread."""
        def run() -> None:
            deadline = time.monotonic() + FIRST_FIX_WAIT
            while True:
                result = shots.follow(source, engine).result(timeout=30)
                if result.status is not CommandStatus.REJECTED or "no fix" not in result.reason \
                        or source == "given" or time.monotonic() > deadline:
                    break
                time.sleep(0.5)
            if self._claim(result):
                self.say(str(result))
        threading.Thread(target=run, name="shot follow", daemon=True).start()
