"""The link faults and vehicle profiles both matrices run (bench/fault_matrix.py flies through them,
bench/transfer_matrix.py moves plans and parameters through them): one list, so the two tables agree.

Each fault sets the simulator's link faults (``SimVehicle.faults``); "outage" is applied by the flight itself,
in the middle of the forward leg.
"""
from __future__ import annotations


def _loss(share):
    def apply(f):
        f.uplink.loss = f.downlink.loss = share
    return apply


def _replies(f):
    f.lose_replies = 0.5


def _duplicates(f):
    f.uplink.duplicate = f.downlink.duplicate = 0.2


def _latency(f):
    f.uplink.latency = f.downlink.latency = 0.2
    f.uplink.jitter = f.downlink.jitter = 0.02


def _bursts(f):
    f.uplink.burst_rate = f.downlink.burst_rate = 0.02
    f.uplink.burst_seconds = f.downlink.burst_seconds = 0.15


#: name -> (what it is, how to set it); "outage" is applied in the middle of the forward flight.
FAULTS = {
    "clean": ("no fault", lambda f: None),
    "loss10": ("10 % loss each way", _loss(0.10)),
    "loss30": ("30 % loss each way", _loss(0.30)),
    "replies": ("half the COMMAND_ACKs lost after the vehicle acted", _replies),
    "duplicates": ("20 % of frames duplicated each way", _duplicates),
    "latency": ("200 ms latency each way (±20 ms jitter)", _latency),
    "bursts": ("150 ms loss bursts, 2 % of frames start one", _bursts),
    "outage": ("a 1 s outage both ways mid-flight", lambda f: None),
}
PROFILES = ("copter-4", "solo")

#: profile -> {row: (the words of the driver's refusal that say the firmware lacks it, the table's label)}: such a
#: refusal is right (bench/verdicts.py). ArduCopter 3.3 fences only with FENCE_RADIUS and FENCE_ALT_MAX.
LACKS = {"solo": {"fence": ("no polygon fence", "refused: no fence on 3.3")}}
