"""The standalone server's interactive console: its command sets (flight, plans, payload, parameters, setup).

It drives a :class:`~driver.vehicle.api.Drone`; nothing below it imports it."""
