"""A simulated ArduCopter (in the spirit of QGroundControl's MockLink) speaking real MAVLink.

    from driver.sim import SimVehicle, SimConfig
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=4.0, ready_after=1.0)).start()
    url = f"tcp:127.0.0.1:{sim.tcp_port}"
    ...
    sim.truth()      # ground truth for assertions
    sim.stop()
"""
from .autopilot import MODE_NAMES, MODES, Autopilot, SimTruth
from .faults import Faults
from .vehicle import SimConfig, SimVehicle

#: Simulated seconds until ready to arm in a demo (``python -m driver --sim``, ``main.py --sim``): a first
#: takeoff starts at once. SimConfig's own default (20 s) is a real vehicle's GPS and EKF start-up.
DEMO_READY_AFTER = 3.0

__all__ = ["SimVehicle", "SimConfig", "SimTruth", "Faults", "Autopilot", "MODES", "MODE_NAMES", "DEMO_READY_AFTER"]
