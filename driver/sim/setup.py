"""What a pilot does on the bench before a first flight, on the simulated ArduCopter: calibrations
(calibration.py), the motor test and the radio (motors.py) and ADS-B traffic (adsb.py), as one mixin of
:class:`~driver.sim.autopilot.Autopilot` (listed before Commands and Telemetry: its handlers and builders win)."""
from __future__ import annotations

from .adsb import AdsbTraffic
from .calibration import Calibration
from .motors import MotorTest

__all__ = ["Setup"]


class Setup(Calibration, MotorTest, AdsbTraffic):

    def _setup_init(self) -> None:
        self._calibration_init()
        self._motors_init()
        self._adsb_init()
        self._sender_ids = (255, 0)

    def _setup_step(self, dt: float) -> None:
        self._calibration_step()
        self._motors_step()
        self._adsb_step(dt)
