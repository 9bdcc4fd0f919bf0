"""One ArduCopter vehicle over one MAVLink link: the façade :class:`Vehicle` and the parts it is made of.

    from driver.vehicle import Vehicle, VehicleConfig
"""
from .vehicle import Vehicle, VehicleConfig

__all__ = ["Vehicle", "VehicleConfig"]
