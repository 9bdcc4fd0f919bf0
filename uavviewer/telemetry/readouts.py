"""What the pilot reads: the link banner, messages and command results, the plots' data, the attitude indicator,
the telemetry numbers, the phase line and the status bar's link line.

Every snapshot is taken in at once (the banner, messages and the plots' samples must not miss one); the views
that only show it redraw through their refresh channels (uavviewer/refresh.py): at the rate the eye needs, and
not while minimised.
"""
from __future__ import annotations

import math
import time

from PyQt5.QtCore import QObject
from PyQt5.QtWidgets import QLabel

from driver.vehicle.state import CommandResult, LinkStatus, SequencePhase, VehicleState

from ..connect.security import signing_warning
from ..flight.phase import (
    NO_VEHICLE, FlightPhase, flight_phase, link_gone_text, no_link_flag, no_vehicle_words, readiness_text,
)
from ..refresh import INSTRUMENTS_HZ, PLOTS_HZ, TEXT_HZ

__all__ = ["Readouts", "phase_text"]


def phase_text(s: VehicleState, phase: FlightPhase) -> str:
    """The phase line under the instruments: what the vehicle is doing, or waiting for."""
    if phase is FlightPhase.NO_VEHICLE:
        return no_vehicle_words(s)
    if s.link.status in (LinkStatus.LOST, LinkStatus.CLOSED):
        return link_gone_text(s, {FlightPhase.ON_GROUND: "on the ground", FlightPhase.TAKING_OFF: "taking off",
                                  FlightPhase.FLYING: f"flying in {s.mode}", FlightPhase.LANDING: "landing"}[phase])
    if phase is FlightPhase.TAKING_OFF and s.takeoff.phase is SequencePhase.WAITING_READY:
        return (f"Take off to {s.takeoff.target_altitude:.1f} m when ready — "
                + (readiness_text(s) if s.connected and s.readiness.missing else "waiting for the vehicle"))
    if phase is FlightPhase.TAKING_OFF and s.takeoff.active:
        return f"Taking off to {s.takeoff.target_altitude:.1f} m — {s.takeoff.phase.value}"
    if phase is FlightPhase.ON_GROUND and s.readiness.reasons and not s.armed:
        text = readiness_text(s)                         # "Not ready to arm: ...": on the ground, said shorter
        return text[:1].upper() + text[1:]
    if phase is FlightPhase.ON_GROUND:
        return "On the ground · " + ("armed" if s.armed else readiness_text(s))
    return {FlightPhase.TAKING_OFF: "Taking off", FlightPhase.FLYING: f"Flying · {s.mode}",
            FlightPhase.LANDING: "Landing"}[phase]


class Readouts(QObject):
    """``window``: the main window (its banner, messages, plots, attitude indicator, telemetry, status bar)."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = w = window
        self.shown: VehicleState | None = None      # the snapshot the views show next
        self._t0 = time.monotonic()
        self._last_sample_time: float | None = None
        self._plot_gap = False
        self._last_message = self._last_result = -1
        self._shown_results: set[int] = set()
        self.instruments_channel = w.refresh.add(INSTRUMENTS_HZ, self.show_instruments)
        self.text_channel = w.refresh.add(TEXT_HZ, self.show_text)
        self.plots_channel = w.refresh.add(PLOTS_HZ, w.plots.redraw)
        w.link_status = QLabel()
        w.statusbar.addPermanentWidget(w.link_status)
        w.adapter.commandFinished.connect(self.show_result)

    def follow(self, s: VehicleState | None) -> None:
        """Another vehicle (or connection) from now on: its log starts from ``s`` (older lines were another
        vehicle's; None: from its first line), and the plots leave a gap."""
        self._last_message = s.messages[-1].index if s is not None and s.messages else -1
        self._last_result = s.results[-1].index if s is not None and s.results else -1
        self._shown_results.clear()
        self._plot_gap = True
        self.window.plots.gap(time.monotonic() - self._t0)

    def show_state(self, s: VehicleState) -> None:
        w = self.window
        link = s.link
        replay = w.adapter.replay
        finished = replay is not None and replay.finished
        w.linkBanner.set_link(link.status, link.address or w.adapter.description, link.heartbeat_age,
                              finished, "" if w.signing_unavailable else signing_warning(s.signing))
        for m in s.messages_since(self._last_message):
            w.messages.add_message(m.time, m.severity, m.text, m.source)
            self._last_message = m.index
        for r in s.results_since(self._last_result):
            self._last_result = r.index
            if r.index not in self._shown_results:
                self._shown_results.add(r.index)
                w.messages.add_result(r)
        have_vehicle = link.status is not LinkStatus.WAITING and bool(s.mode)
        if link.status is not LinkStatus.OK or (replay is not None and replay.paused):
            if not self._plot_gap:                  # no line drawn across the time nothing came in
                self._plot_gap = True
                w.plots.gap(time.monotonic() - self._t0)
                self.plots_channel.mark()
        elif have_vehicle and s.time != self._last_sample_time:
            self._plot_gap = False
            self._last_sample_time = s.time
            forward, right, _ = s.velocity.body(s.attitude.yaw)
            w.plots.append(time.monotonic() - self._t0, altitude=s.altitude, forward=forward,
                           right=right, climb=s.velocity.climb, roll=math.degrees(s.attitude.roll),
                           pitch=math.degrees(s.attitude.pitch), heading=s.heading_deg)
            self.plots_channel.mark()
        self.shown = s
        self.instruments_channel.mark()
        self.text_channel.mark()

    def show_result(self, result: CommandResult) -> None:
        """A command's answer in Messages, once; a refusal in the status bar too."""
        if result.index and result.index in self._shown_results:
            return
        if result.index:
            self._shown_results.add(result.index)
        self.window.messages.add_result(result)
        if not result.ok:
            self.window.statusbar.showMessage(str(result), 8000)

    def show_instruments(self) -> None:
        """The attitude indicator (INSTRUMENTS_HZ)."""
        s, attitude = self.shown, self.window.attitude
        if s is None:
            return
        if s.link.status in (LinkStatus.LOST, LinkStatus.CLOSED):
            if attitude.values["flag"] != no_link_flag(s):     # the last attitude is no longer the drone's
                attitude.clear(no_link_flag(s))
        elif s.link.status is LinkStatus.WAITING or not s.mode:
            if attitude.values["flag"] != NO_VEHICLE.upper():
                attitude.clear(NO_VEHICLE.upper())
        else:
            attitude.set_attitude(s.attitude.roll, s.attitude.pitch, s.heading_deg)
            attitude.set_readouts(s.altitude, s.velocity.ground_speed, s.velocity.climb)

    def show_text(self) -> None:
        """Numbers and status lines (TEXT_HZ): telemetry, the phase line, the status bar."""
        s, w = self.shown, self.window
        if s is None:
            return
        link = s.link
        w.telemetry.set_state(s)
        w.statusStrip.set_state(s, w.flight_timer.seconds)
        phase = phase_text(s, flight_phase(s))
        if phase != w.phaseLabel.text():
            w.phaseLabel.setText(phase)
            w.phaseLabel.setToolTip(phase)
        pps = f"{link.packets_per_s:.0f} pkt/s" if link.status is LinkStatus.OK else link.status.value
        pinned = f"  ·  vehicle at {link.pinned_to}" if link.pinned_to else ""
        w.link_status.setText(f"{w.adapter.description}{pinned}  ·  {pps}")
