"""The simulated camera looks where the vehicle's gimbal points: tilting moves the horizon in the picture."""
from __future__ import annotations

import numpy as np

from driver.camera.sim import SKY, SimulatedCamera
from driver.payload import Gimbal
from driver.vehicle.state import LocalPosition, VehicleState


def horizon_row(image: np.ndarray) -> int:
    """The first row (from the top) of the centre column that is not sky; the height if it is all sky."""
    column = image[:, image.shape[1] // 2].astype(int)
    ground = np.where(np.abs(column - np.array(SKY)).sum(axis=1) > 30)[0]
    return int(ground[0]) if len(ground) else image.shape[0]


def test_the_horizon_moves_with_the_gimbal_pitch():
    camera = SimulatedCamera(320, 240)
    hovering = VehicleState(local=LocalPosition(0, 0, -10), altitude=10)
    level = camera.render(hovering)
    rows = {}
    for pitch in (0.0, -20.0, -40.0):
        rows[pitch] = horizon_row(camera.render(VehicleState(local=LocalPosition(0, 0, -10), altitude=10,
                                                             gimbal=Gimbal(pitch_deg=pitch))))
    assert abs(rows[0.0] - 120) <= 2, rows                  # level: the horizon across the middle
    assert rows[0.0] > rows[-20.0] > rows[-40.0], rows      # tilting down lifts it to the top
    down = camera.render(VehicleState(local=LocalPosition(0, 0, -10), altitude=10, gimbal=Gimbal(pitch_deg=-90.0)))
    assert horizon_row(down) == 0                           # straight down: only ground
    assert not np.array_equal(level, down)
