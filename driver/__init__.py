"""MAVLinkServer: the MAVLink driver for ArduCopter vehicles (3DR Solo, SITL, the built-in simulator).

    from driver import Vehicle, VehicleConfig
    drone = Vehicle(VehicleConfig(connection="tcp:127.0.0.1:5760")).start()
    drone.takeoff(3.0).result()

This package never imports Qt.
"""
from .vehicle.api import Drone, Limits
from .vehicle.state import CommandStatus, LandedState, LinkStatus, SequencePhase, Severity, VehicleState
from .vehicle.vehicle import Vehicle, VehicleConfig

__all__ = ["Drone", "Limits", "Vehicle", "VehicleConfig", "VehicleState", "CommandStatus", "LandedState",
           "LinkStatus", "SequencePhase", "Severity"]
