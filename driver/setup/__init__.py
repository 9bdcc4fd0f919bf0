"""Vehicle setup on the bench: calibrations, the motor test, the radio and the outputs (driver.setup).

:mod:`.model` holds the immutable snapshots (in :class:`~driver.state.VehicleState`.setup), :mod:`.control`
the procedures (``vehicle.setup``), :mod:`.console` MAVProxy's words for them.
"""
