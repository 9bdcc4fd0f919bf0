"""A simulated ArduCopter (in the spirit of QGroundControl's MockLink) speaking real MAVLink.

    from driver.sim import SimVehicle, SimConfig
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=4.0, ready_after=1.0)).start()
    url = f"tcp:127.0.0.1:{sim.tcp_port}"
    ...
    sim.faults.downlink.latency = 0.3     # a faultable link, both ways (faults.py)
    sim.truth()      # ground truth for assertions (NED from home)
    sim.stop()

``SimConfig.profile`` picks the firmware: "copter-4" (matched to a real ArduCopter 4.7
recording) or "solo" (a stock 3DR Solo); ``gimbal``/``companion`` add components.

MAVLink 2 signing works as in ArduPilot (signing.py): SETUP_SIGNING, or
``SimConfig.signing_key`` for a key already stored, turns it on for every link;
``sim.signing`` has the key (None: off) and the counters. Unlike SITL, whose TCP
5760 is SERIAL0 (USB), the sim's ``tcp_port`` and UDP links are telemetry links:
once signing is on they drop unsigned frames. ``SimConfig.usb_port`` adds a TCP
port that acts as SERIAL0, where unsigned frames are always accepted (a ground
station sets or clears the key there without knowing it). A MAVLink-1-only
vehicle ("solo") cannot sign at all.
"""
from .autopilot import MODE_NAMES, MODES, Autopilot, SimTruth
from .clock import ManualClock, RealClock
from .faults import Faults, LinkCounters, LinkFaults
from .gcs import OtherGroundStation
from .profiles import PROFILES
from .signing import Signing, SigningCounters, passphrase_key
from .vehicle import SimConfig, SimVehicle

#: Simulated seconds until ready to arm in a demo (``python -m driver --sim``, ``main.py --sim``): a first
#: takeoff starts at once. SimConfig's own default (20 s) is a real vehicle's GPS and EKF start-up.
DEMO_READY_AFTER = 3.0

__all__ = ["SimVehicle", "SimConfig", "SimTruth", "Faults", "LinkFaults", "LinkCounters", "Autopilot", "MODES",
           "MODE_NAMES", "DEMO_READY_AFTER", "PROFILES", "OtherGroundStation", "ManualClock", "RealClock", "Signing",
           "SigningCounters", "passphrase_key"]
