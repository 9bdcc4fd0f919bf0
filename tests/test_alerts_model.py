"""The alert model turns snapshots into the alerts a pilot hears; the speech engine really makes sound."""
from __future__ import annotations

import array
import os
import shutil
import wave

import pytest

from driver.vehicle.state import (
    Battery, BatteryAlarm, Fence, LinkHealth, LinkStatus, Message, SequencePhase, SequenceProgress, Severity, VehicleState,
    replace,
)
from uavviewer.alerts.model import MAV_STATE_CRITICAL, AlertKind, AlertModel
from uavviewer.alerts.speech import Speaker, render_wav

LIVE = VehicleState(link=LinkHealth(status=LinkStatus.OK), mode="GUIDED", system_status=3)


def kinds(model: AlertModel, s: VehicleState) -> list[AlertKind]:
    return [a.kind for a in model.update(s)]


@pytest.fixture
def model() -> AlertModel:
    m = AlertModel()
    assert kinds(m, LIVE) == [AlertKind.CONNECTED]          # the first vehicle snapshot is only a baseline
    assert kinds(m, LIVE) == []
    return m


def test_nothing_before_a_vehicle_and_the_baseline_is_not_news():
    m = AlertModel()
    assert m.update(VehicleState()) == []                     # waiting: no vehicle yet
    armed = replace(LIVE, armed=True, mode="LOITER")
    alerts = m.update(armed)
    assert [a.kind for a in alerts] == [AlertKind.CONNECTED] and "armed" in alerts[0].text


def test_link_lost_and_recovered(model):
    lost = replace(LIVE, link=LinkHealth(status=LinkStatus.LOST))
    alert, = model.update(lost)
    assert alert.kind is AlertKind.LINK_LOST and alert.critical and alert.text == "Link lost"
    alert, = model.update(LIVE)
    assert alert.kind is AlertKind.LINK_RECOVERED and alert.clears and not alert.critical


def test_battery_warning_then_critical_once_each(model):
    def battery(alarm):                             # a pack that the default thresholds judge so
        volts, remaining = {BatteryAlarm.OK: (16.0, 80.0), BatteryAlarm.WARNING: (15.0, 18.0),
                            BatteryAlarm.CRITICAL: (14.0, 10.0)}[alarm]
        state = replace(LIVE, battery=Battery(voltage=volts, remaining=remaining, cells=4))
        assert state.battery.alarm is alarm
        return state
    assert kinds(model, battery(BatteryAlarm.OK)) == []
    alert, = model.update(battery(BatteryAlarm.WARNING))
    assert alert.kind is AlertKind.BATTERY_WARNING and "18 percent" in alert.text and alert.critical
    assert kinds(model, battery(BatteryAlarm.WARNING)) == []          # said once, not on every snapshot
    alert, = model.update(battery(BatteryAlarm.CRITICAL))
    assert alert.kind is AlertKind.BATTERY_CRITICAL and alert.severity is Severity.CRITICAL
    assert kinds(model, battery(BatteryAlarm.WARNING)) == []          # getting better is not news


def test_failsafe_and_critical_messages_but_not_info(model):
    failsafe = replace(LIVE, system_status=MAV_STATE_CRITICAL, mode="RTL", fence=Fence(enabled=True, breached=True))
    found = kinds(model, failsafe)
    assert AlertKind.FAILSAFE in found and AlertKind.FENCE in found and AlertKind.MODE in found
    messages = (Message(1, 0.0, Severity.INFO, "EKF3 IMU0 is using GPS"),
                Message(2, 0.0, Severity.CRITICAL, "Radio Failsafe"),
                Message(3, 0.0, Severity.WARNING, "Crash: Disarming"),
                Message(4, 0.0, Severity.WARNING, "Recording the flight log", source="driver"))
    alerts = model.update(replace(failsafe, messages=messages))
    assert [(a.kind, a.text) for a in alerts] == [(AlertKind.MESSAGE, "Radio Failsafe"),
                                                  (AlertKind.MESSAGE, "Crash: Disarming")]
    assert model.update(replace(failsafe, messages=messages)) == []   # each message once


def test_armed_disarmed_mode_and_takeoff_complete(model):
    armed = replace(LIVE, armed=True)
    assert kinds(model, armed) == [AlertKind.ARMED]
    climbing = replace(armed, takeoff=SequenceProgress(SequencePhase.CLIMBING, target_altitude=3.0))
    assert kinds(model, climbing) == []
    done = replace(armed, takeoff=SequenceProgress(SequencePhase.DONE, target_altitude=3.0), altitude=2.9)
    alert, = model.update(done)
    assert alert.kind is AlertKind.TAKEOFF_COMPLETE and "3 metres" in alert.text
    assert [a.text for a in model.update(replace(done, mode="ALT_HOLD"))] == ["Alt hold"]
    assert kinds(model, replace(done, mode="ALT_HOLD", armed=False)) == [AlertKind.DISARMED]


def test_reset_makes_the_next_vehicle_a_baseline(model):
    model.reset()
    assert kinds(model, replace(LIVE, armed=True, mode="LAND")) == [AlertKind.CONNECTED]


def test_speaker_never_waits_and_mute_silences(qtbot):
    speaker = Speaker()
    said = []
    speaker.spoken.connect(said.append)
    model = AlertModel()
    model.update(LIVE)
    alert, = model.update(replace(LIVE, link=LinkHealth(status=LinkStatus.LOST)))
    speaker.say(alert)                                   # returns at once: a speech thread runs the engine
    qtbot.waitUntil(lambda: said == ["Link lost"], timeout=3000)
    for _ in range(10):
        speaker.say(alert)
    assert len(speaker.waiting) <= 4                     # the queue never grows stale
    speaker.set_muted(True)
    assert speaker.waiting == ()
    qtbot.waitUntil(lambda: not speaker.busy, timeout=3000)   # what was being said is stopped
    count = len(said)
    speaker.say(alert)
    # muted: nothing more, and nothing that could still be said (the thread only speaks what waits)
    assert len(said) == count and speaker.waiting == () and not speaker.busy
    speaker.close()


def test_the_speech_engine_makes_audible_sound_headless(tmp_path):
    if shutil.which("espeak-ng") is None:                # scripts/bootstrap installs it wherever apt can
        if os.path.exists("/etc/debian_version"):
            pytest.fail("espeak-ng is missing: run scripts/bootstrap")
        pytest.skip("espeak-ng comes from the distribution's packages; this is not Debian")
    path = tmp_path / "alert.wav"
    assert render_wav("Battery critical. Land now", str(path))
    with wave.open(str(path)) as w:
        assert w.getsampwidth() == 2 and w.getnframes() > w.getframerate() // 2     # over half a second of it
        samples = array.array("h", w.readframes(w.getnframes()))
    loud = max(abs(v) for v in samples)
    rms = (sum(v * v for v in samples) / len(samples)) ** 0.5
    assert loud > 3000 and rms > 300                     # speech, not silence


def test_an_alert_carries_the_time_of_its_event(model):
    """A replay's banner shows the recording's clock, not the time it is watched."""
    said = Message(7, 1234.5, Severity.CRITICAL, "GPS Glitch")
    alert, = model.update(replace(LIVE, time=2000.0, messages=(said,)))
    assert alert.time == 1234.5
    alert, = model.update(replace(LIVE, time=2001.0, messages=(said,), link=LinkHealth(status=LinkStatus.LOST)))
    assert alert.kind is AlertKind.LINK_LOST and alert.time == 2001.0
