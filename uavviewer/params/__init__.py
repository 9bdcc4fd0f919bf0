"""The Parameters page (docs/parameters.md): every parameter of the vehicle, searched and grouped by
prefix, edited within the metadata's bounds, reviewed and written in one go, compared with a .param file.

The page sees the vehicle through the window's :class:`~uavviewer.drone_adapter.DroneAdapter` only: the table
comes from ``VehicleState.parameters`` and writes go out as ``Drone.set_parameter`` calls, never waited on.
"""
from .controller import ParamsController

__all__ = ["ParamsController"]
