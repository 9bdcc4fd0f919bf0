"""MAVLinkServer: the MAVLink driver for ArduCopter vehicles (3DR Solo, SITL, the built-in simulator).

    from driver import Vehicle, VehicleConfig
    drone = Vehicle(VehicleConfig(connection="tcp:127.0.0.1:5760")).start()
    drone.takeoff(3.0).result()

This package never imports Qt.

The names below are imported when first used (PEP 562): ``python -m driver`` and ``python -m driver.sim`` then
parse their options, and answer a wrong one, before pymavlink's dialect and the whole vehicle are loaded.
"""
import importlib

_WHERE = {"Drone": ".vehicle.api", "Limits": ".vehicle.api", "Vehicle": ".vehicle.vehicle",
          "VehicleConfig": ".vehicle.vehicle", "VehicleState": ".vehicle.state", "CommandStatus": ".vehicle.state",
          "LandedState": ".vehicle.state", "LinkStatus": ".vehicle.state", "SequencePhase": ".vehicle.state",
          "Severity": ".vehicle.state"}

__all__ = list(_WHERE)


def __getattr__(name: str):
    if name not in _WHERE:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(_WHERE[name], __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list:
    return sorted(list(globals()) + __all__)
