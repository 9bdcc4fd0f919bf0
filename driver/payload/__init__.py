"""The vehicle's payload: its gimbal, where it looks, and its camera (docs/camera.md).

:mod:`driver.payload.model` holds the values the state carries; :mod:`driver.payload.control` (imported by the
driver, not here: it needs the state) points the gimbal, and :mod:`driver.payload.camera` triggers the camera.
"""
from .model import CameraKind, Gimbal, GimbalControl, VehicleCamera

__all__ = ["CameraKind", "Gimbal", "GimbalControl", "VehicleCamera"]
