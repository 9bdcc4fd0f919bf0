"""The simulated vehicle's mission protocol where an upload meets another question, against ArduPilot's sources.

ArduCopter 4.6.3: libraries/GCS_MAVLink/MissionItemProtocol.cpp (handle_mission_request_list and
handle_mission_request_int DENIED while ``receiving``, handle_mission_request without that check,
handle_mission_clear_all through cancel_upload, update()'s 8 s upload timeout). The Solo's 3.3:
3drobotics/ardupilot-solo libraries/GCS_MAVLink/GCS_Common.cpp (handle_mission_request_list sets
``waypoint_receiving = false``; update() gives up wp_recv_time + waypoint_receive_timeout = 6 s after the last item,
without a word). The autopilot is driven directly, step by step: no socket, no real second.
"""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import SimConfig
from driver.sim.autopilot import Autopilot

MISSION = mavlink.MAV_MISSION_TYPE_MISSION


class Bench:
    """One autopilot, booted and ready, and what it says."""

    def __init__(self, profile: str) -> None:
        self.said: list = []
        self.integer = profile != "solo"                         # 3.3 knows only the float MISSION_ITEM
        self.ap = Autopilot(SimConfig(ready_after=0.0, profile=profile, mavlink2=self.integer, seed=1),
                            emit=self.said.append, emit_to=lambda msg, link: self.said.append(msg))
        while not self.ap.initialised:
            self.ap.step(0.02)
        self.stations = {}

    def send(self, msg, system: int = 255) -> list:
        """``msg`` from ground station ``system``; what the vehicle answered to it (mission messages and texts)."""
        enc = self.stations.setdefault(system, mavlink.MAVLink(None, srcSystem=system, srcComponent=190))
        msg.pack(enc)
        before = len(self.said)
        self.ap.sender = system
        self.ap.handle(msg)
        self.ap.sender = None
        return [m for m in self.said[before:] if m.get_type() in ("MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM",
                                                                   "MISSION_ITEM_INT", "STATUSTEXT")]

    def run(self, seconds: float) -> list:
        """``seconds`` of the vehicle's time; the mission messages it sent meanwhile."""
        before = len(self.said)
        for _ in range(round(seconds / 0.02)):
            self.ap.step(0.02)
        return [m for m in self.said[before:] if m.get_type().startswith("MISSION_")
                and m.get_type() != "MISSION_CURRENT"]

    def item(self, seq: int):
        """Waypoint ``seq`` as this vehicle takes it."""
        if self.integer:
            return mavlink.MAVLink_mission_item_int_message(1, 1, seq, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                                            mavlink.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0,
                                                            402839000 + seq, -37940000, 10, MISSION)
        return mavlink.MAVLink_mission_item_message(1, 1, seq, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                                    mavlink.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0,
                                                    40.2839 + seq * 1e-7, -3.794, 10, MISSION)


def acks(answers) -> list[int]:
    return [m.type for m in answers if m.get_type() == "MISSION_ACK"]


@pytest.fixture
def copter() -> Bench:
    return Bench("copter-4")


@pytest.fixture
def solo() -> Bench:
    return Bench("solo")


def test_a_float_request_is_answered_during_an_upload_the_int_one_denied(copter):
    copter.send(mavlink.MAVLink_mission_count_message(1, 1, 3, MISSION))
    copter.send(copter.item(0))
    copter.send(copter.item(1))                                  # an upload of 3 items is receiving
    assert acks(copter.send(mavlink.MAVLink_mission_request_list_message(1, 1, MISSION))) == \
        [mavlink.MAV_MISSION_DENIED]
    assert acks(copter.send(mavlink.MAVLink_mission_request_int_message(1, 1, 1, MISSION))) == \
        [mavlink.MAV_MISSION_DENIED]
    answer = copter.send(mavlink.MAVLink_mission_request_message(1, 1, 1, MISSION))
    assert [(m.get_type(), m.seq) for m in answer if m.get_type() == "MISSION_ITEM"] == [("MISSION_ITEM", 1)]
    assert "got MISSION_REQUEST; use MISSION_REQUEST_INT!" in [m.text for m in copter.said
                                                               if m.get_type() == "STATUSTEXT"]
    assert copter.ap.uploads                                      # still receiving: the last item completes it
    assert acks(copter.send(copter.item(2))) == [mavlink.MAV_MISSION_ACCEPTED]


def test_a_clear_from_the_uploading_station_ends_its_upload_from_another_is_denied(copter):
    copter.send(mavlink.MAVLink_mission_count_message(1, 1, 3, MISSION))
    copter.send(copter.item(0))
    assert acks(copter.send(mavlink.MAVLink_mission_clear_all_message(1, 1, MISSION), system=254)) == \
        [mavlink.MAV_MISSION_DENIED, mavlink.MAV_MISSION_ERROR]
    assert copter.ap.uploads
    assert acks(copter.send(mavlink.MAVLink_mission_clear_all_message(1, 1, MISSION))) == \
        [mavlink.MAV_MISSION_ACCEPTED]
    assert not copter.ap.uploads and copter.ap.plans[MISSION] == []
    assert acks(copter.send(copter.item(1))) == [mavlink.MAV_MISSION_ERROR]     # no longer receiving


def test_a_copter_4_upload_times_out_8_s_after_its_last_item_and_says_so(copter):
    copter.send(mavlink.MAVLink_mission_count_message(1, 1, 3, MISSION))
    copter.send(copter.item(0))
    assert acks(copter.run(7.9)) == []
    assert acks(copter.run(0.2)) == [mavlink.MAV_MISSION_OPERATION_CANCELLED]


def test_the_solos_upload_ends_on_a_request_list_with_the_count(solo):
    solo.send(mavlink.MAVLink_mission_count_message(1, 1, 3, MISSION))
    solo.send(solo.item(0))
    answer = solo.send(mavlink.MAVLink_mission_request_list_message(1, 1, MISSION))
    assert [(m.get_type(), m.count) for m in answer] == [("MISSION_COUNT", 1)]
    assert not solo.ap.uploads
    assert [m for m in solo.run(3.0) if m.get_type() == "MISSION_REQUEST"] == []     # asks nothing more
    assert acks(solo.send(solo.item(1))) == [mavlink.MAV_MISSION_ERROR]


def test_the_solos_upload_gives_up_silently_6_s_after_its_last_item(solo):
    solo.send(mavlink.MAVLink_mission_count_message(1, 1, 3, MISSION))
    solo.send(solo.item(0))
    assert [m.seq for m in solo.run(5.9) if m.get_type() == "MISSION_REQUEST"] == [1] * 5   # asked again each 1 s
    assert solo.ap.uploads
    assert solo.run(0.2) == [] and not solo.ap.uploads
