"""What the vehicle will do on each failsafe, in plain words, from its parameters (ArduCopter 4.x's values), the
combinations that leave it with none, and each failsafe that does nothing: the one model the Failsafes page and
the Summary both read. No Qt."""
from __future__ import annotations

import re
from dataclasses import dataclass

__all__ = ["Failsafes", "failsafes", "BATTERY_ACTIONS"]

BATTERY_ACTIONS = {0: "nothing (a warning only)", 1: "lands", 2: "returns home (RTL)",
                   3: "SmartRTL, else RTL", 4: "SmartRTL, else lands", 5: "stops the motors (terminate)",
                   6: "auto lands (DO_LAND_START), else RTL", 7: "Brake, else lands"}
_RADIO = {0: "nothing: it keeps flying without the transmitter", 1: "returns home (RTL)",
          2: "goes on with its mission in AUTO, else RTL", 3: "lands", 4: "SmartRTL, else RTL",
          5: "SmartRTL, else lands", 6: "auto lands (DO_LAND_START), else RTL", 7: "Brake, else lands"}
_GCS = {0: "nothing: it keeps flying without the ground station", 1: "returns home (RTL)",
        2: "goes on with its mission in AUTO, else RTL", 3: "SmartRTL, else RTL", 4: "SmartRTL, else lands",
        5: "lands", 6: "auto lands (DO_LAND_START), else RTL", 7: "Brake, else lands"}
_EKF = {0: "nothing (reported only)", 1: "lands", 2: "switches to AltHold", 3: "lands even in Stabilize"}
_FENCE = {0: "reports the breach only", 1: "returns home (RTL), else lands", 2: "lands",
          3: "SmartRTL, else RTL, else lands", 4: "Brake, else lands", 5: "SmartRTL, else lands"}


def _v(s, name: str) -> float | None:
    p = s.parameters.get(name)
    return None if p is None else p.value


@dataclass(frozen=True)
class Failsafes:
    """What the vehicle will do on each failsafe, as its parameters say: the Failsafes page shows it whole, the
    Summary its verdict (one model, so the two never disagree)."""
    lines: tuple[tuple[str, str, str], ...]  # (area, what the vehicle does, the parameter that decides it)
    warnings: tuple[str, ...]                # combinations that leave it with no failsafe
    missing: tuple[str, ...]                 # each failsafe that does nothing: "no battery failsafe action", ...
    unread: tuple[str, ...]                  # the parameters not read yet

    @property
    def summary(self) -> str:
        """What is not set, then what is, in one line: "no battery failsafe action; GCS failsafe off; fence off;
        radio lost: returns home (RTL)" (the Failsafes page names each parameter)."""
        set_ = [f"{area.lower()}: {re.sub(rf' [(]{name} .*$', '', words)}" for area, words, name in self.lines
                if name not in self.unread and not words.startswith(("nothing", "off"))]
        return "; ".join(list(self.missing) + set_)


def failsafes(s) -> Failsafes:
    """The failsafes of the vehicle state ``s``; unread parameters say so."""
    lines: list[tuple[str, str, str]] = []
    unread = [n for n in ("BATT_FS_LOW_ACT", "BATT_FS_CRT_ACT", "FS_THR_ENABLE", "FS_GCS_ENABLE", "FS_EKF_ACTION",
                          "FENCE_ENABLE") if _v(s, n) is None]

    def say(area: str, name: str, words: dict, extra: str = "") -> float | None:
        value = _v(s, name)
        lines.append((area, "not read yet" if value is None else
                      f"{words.get(int(value), f'action {value:g}')} ({name} {value:g}){extra}", name))
        return value
    low = _v(s, "BATT_LOW_VOLT")
    say("Battery low", "BATT_FS_LOW_ACT", BATTERY_ACTIONS, "" if low is None else f" below {low:g} V")
    crit = _v(s, "BATT_CRT_VOLT")
    say("Battery critical", "BATT_FS_CRT_ACT", BATTERY_ACTIONS, "" if crit is None else
        (" (no voltage set: BATT_CRT_VOLT 0)" if crit == 0 else f" below {crit:g} V"))
    radio = say("Radio lost", "FS_THR_ENABLE", _RADIO)
    gcs = say("Ground station lost", "FS_GCS_ENABLE", _GCS)
    say("EKF unhealthy", "FS_EKF_ACTION", _EKF)
    fence = _v(s, "FENCE_ENABLE")
    if fence is not None and fence == 0:
        lines.append(("Fence", "off (FENCE_ENABLE 0): nothing keeps it inside", "FENCE_ENABLE"))
    else:
        say("Fence breached", "FENCE_ACTION", _FENCE)
    warnings, missing = [], []
    battery = [_v(s, n) for n in ("BATT_FS_LOW_ACT", "BATT_FS_CRT_ACT")]
    if radio == 0 and gcs == 0:
        warnings.append("Neither the radio nor the ground-station failsafe is on: if both links are lost it keeps "
                        "flying as it was until its battery runs out.")
    if all(b == 0 for b in battery):
        warnings.append("No battery failsafe action: a low battery is only reported, the vehicle does not come back.")
        missing.append("no battery failsafe action")
    for value, words in ((radio, "radio failsafe off"), (gcs, "GCS failsafe off"), (fence, "fence off")):
        if value == 0:
            missing.append(words)
    return Failsafes(tuple(lines), tuple(warnings), tuple(missing), tuple(unread))
