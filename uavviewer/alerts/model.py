"""What the pilot must hear, from the vehicle's snapshots: no Qt, no audio, only alerts.

:class:`AlertModel` compares each snapshot with the one before and says what changed that a pilot
would want spoken: the link lost and back, the battery at warning and at critical (``Battery.alarm``, the pilot's
own thresholds), a failsafe (the autopilot's heartbeat state CRITICAL/EMERGENCY; a fence breach, FENCE_STATUS) and
the autopilot's messages of severity WARNING or worse, arming and disarming, mode changes and a finished takeoff,
and a vehicle in the air with no GCS failsafe (FS_GCS_ENABLE 0: if this laptop's link goes, nothing brings it back
but its battery failsafe), also when it was already flying as the window connected.
The first snapshot with a vehicle only sets the baseline: connecting to a vehicle already armed in LOITER says "Connected", not "Armed".
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, replace

from driver.vehicle.rules import gcs_failsafe_setting
from driver.vehicle.state import BatteryAlarm, LinkStatus, SequencePhase, Severity, VehicleState

__all__ = ["Alert", "AlertKind", "AlertModel", "LIVE_ONLY", "MAV_STATE_CRITICAL", "MAV_STATE_EMERGENCY"]

MAV_STATE_CRITICAL = 5       # HEARTBEAT.system_status: ArduCopter's failsafe state
MAV_STATE_EMERGENCY = 6


class AlertKind(enum.Enum):
    LINK_LOST = "link lost"
    LINK_RECOVERED = "link recovered"
    BATTERY_WARNING = "battery warning"
    BATTERY_CRITICAL = "battery critical"
    FAILSAFE = "failsafe"
    FENCE = "fence breached"
    MESSAGE = "autopilot message"
    ARMED = "armed"
    DISARMED = "disarmed"
    MODE = "mode"
    TAKEOFF_COMPLETE = "takeoff complete"
    CONNECTED = "connected"
    NO_GCS_FAILSAFE = "no GCS failsafe in flight"
    TRAFFIC = "traffic"


#: Kinds about the link and the airspace now, or advice to act on the vehicle: never raised while a recording plays
#: (its traffic passed long ago, its link is not ours, and there is nothing to fix on it)
LIVE_ONLY = {AlertKind.LINK_LOST, AlertKind.LINK_RECOVERED, AlertKind.NO_GCS_FAILSAFE, AlertKind.TRAFFIC}
#: Kinds that also go to the banner in the pilot's eye line (the rest are spoken only)
CRITICAL_KINDS = {AlertKind.LINK_LOST, AlertKind.BATTERY_WARNING, AlertKind.BATTERY_CRITICAL, AlertKind.FAILSAFE,
                  AlertKind.FENCE, AlertKind.MESSAGE, AlertKind.NO_GCS_FAILSAFE, AlertKind.TRAFFIC}


@dataclass(frozen=True)
class Alert:
    kind: AlertKind
    text: str                         # what is spoken and shown
    severity: Severity                # how urgent: lower is worse (MAV_SEVERITY)
    time: float = 0.0                 # wall clock of the event (a replay's: the recording's), 0 when not known

    @property
    def critical(self) -> bool:
        """Shown in the banner, not only heard."""
        return self.kind in CRITICAL_KINDS

    @property
    def clears(self) -> bool:
        """It ends what a banner shows about the same thing (the link is back)."""
        return self.kind is AlertKind.LINK_RECOVERED


class AlertModel:
    """Feed it every snapshot (:meth:`update`); it returns the alerts that snapshot raises, most urgent first."""

    def __init__(self) -> None:
        self._previous: VehicleState | None = None
        self._last_message = -1
        self._battery = BatteryAlarm.UNKNOWN

    def reset(self) -> None:
        """Another vehicle or connection: start again from its first snapshot."""
        self.__init__()

    def update(self, s: VehicleState) -> list[Alert]:
        prev, self._previous = self._previous, s
        out: list[Alert] = []
        if prev is None or not _has_vehicle(prev):
            if _has_vehicle(s):                        # the baseline: what the vehicle is now is not news
                self._last_message = s.messages[-1].index if s.messages else -1
                self._battery = s.battery.alarm
                out.append(Alert(AlertKind.CONNECTED, f"Connected. {_mode_words(s.mode)}, "
                                 f"{'armed' if s.armed else 'disarmed'}", Severity.INFO))
                out += [] if s.link.replay else _no_gcs_failsafe(None, s)
            return out
        link_was, link = prev.link.status, s.link.status
        if link_was is LinkStatus.OK and link is LinkStatus.LOST:
            out.append(Alert(AlertKind.LINK_LOST, "Link lost", Severity.CRITICAL))
        elif link_was is LinkStatus.LOST and link is LinkStatus.OK:
            out.append(Alert(AlertKind.LINK_RECOVERED, "Link recovered", Severity.NOTICE))
        out += self._battery_alerts(s)
        if s.system_status in (MAV_STATE_CRITICAL, MAV_STATE_EMERGENCY) and \
                prev.system_status not in (MAV_STATE_CRITICAL, MAV_STATE_EMERGENCY) and s.connected:
            out.append(Alert(AlertKind.FAILSAFE, f"Failsafe. Mode {_mode_words(s.mode)}", Severity.CRITICAL))
        if s.fence.breached and not prev.fence.breached:
            out.append(Alert(AlertKind.FENCE, "Fence breached", Severity.CRITICAL))
        for m in s.messages_since(self._last_message):
            self._last_message = m.index
            if m.source == "vehicle" and m.severity <= Severity.WARNING:
                out.append(Alert(AlertKind.MESSAGE, m.text, m.severity, m.time))
        if s.connected and prev.connected:
            if s.armed != prev.armed:
                out.append(Alert(AlertKind.ARMED if s.armed else AlertKind.DISARMED,
                                 "Armed" if s.armed else "Disarmed", Severity.NOTICE))
            if s.mode and prev.mode and s.mode != prev.mode:
                out.append(Alert(AlertKind.MODE, _mode_words(s.mode), Severity.INFO))
        out += _no_gcs_failsafe(prev, s)
        out += _traffic(prev, s)
        if s.takeoff.phase is SequencePhase.DONE and prev.takeoff.phase is not SequencePhase.DONE:
            out.append(Alert(AlertKind.TAKEOFF_COMPLETE, f"Takeoff complete, {s.altitude:.0f} metres", Severity.INFO))
        if s.link.replay:
            out = [a for a in out if a.kind not in LIVE_ONLY]
        return sorted((a if a.time else replace(a, time=s.time) for a in out), key=lambda a: a.severity)

    def _battery_alerts(self, s: VehicleState) -> list[Alert]:
        alarm, was = s.battery.alarm, self._battery
        self._battery = alarm
        if alarm <= was or alarm < BatteryAlarm.WARNING:
            return []                                   # only a step for the worse is news
        b = s.battery
        left = f" {b.remaining:.0f} percent" if b.remaining is not None else ""
        if alarm is BatteryAlarm.CRITICAL:
            return [Alert(AlertKind.BATTERY_CRITICAL, f"Battery critical{left}. Land now", Severity.CRITICAL)]
        return [Alert(AlertKind.BATTERY_WARNING, f"Battery low{left}", Severity.WARNING)]


def _unprotected(s: VehicleState | None) -> bool:
    """In the air (or climbing out) with FS_GCS_ENABLE 0, as last heard (a lost link and its return are no news)."""
    return s is not None and s.gcs_failsafe == 0 and (s.flying or s.takeoff.active)


def _no_gcs_failsafe(prev: VehicleState | None, s: VehicleState) -> list[Alert]:
    """Once a flight starts without a GCS failsafe (or the window finds one so): in the banner, not only spoken."""
    if not _unprotected(s) or _unprotected(prev):
        return []
    return [Alert(AlertKind.NO_GCS_FAILSAFE, f"No GCS failsafe ({gcs_failsafe_setting(0)}): on link loss it flies on "
                  "until its battery failsafe", Severity.WARNING)]


def _traffic(prev: VehicleState, s: VehicleState) -> list[Alert]:
    """An aircraft whose closest approach (driver.traffic) newly comes within the alert limits: said once, in the
    one text the driver's Messages line has too (``Contact.threat``), so the banner never disagrees with it."""
    before = {c.icao for c in prev.traffic.alerts}
    return [Alert(AlertKind.TRAFFIC, c.said or c.threat, Severity.WARNING) for c in s.traffic.alerts
            if c.icao not in before]


def _has_vehicle(s: VehicleState) -> bool:
    return s.link.status is not LinkStatus.WAITING and bool(s.mode)


def _mode_words(mode: str) -> str:
    """How a mode is said: "Alt hold", "Smart RTL" ("RTL" spelled out by the engine)."""
    words = {"ALT_HOLD": "Alt hold", "POSHOLD": "Position hold", "SMART_RTL": "Smart RTL", "GUIDED_NOGPS":
             "Guided no GPS", "AVOID_ADSB": "Avoid ADSB", "FLOWHOLD": "Flow hold"}
    return words.get(mode, mode.capitalize() if mode not in ("RTL",) else mode) or "unknown mode"
