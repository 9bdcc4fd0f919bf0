"""The link to the autopilot: transports (serial, UDP, TCP, a tlog replayed), MAVLink 2 signing, forwarding.

It knows bytes and frames, not the vehicle; it imports only :mod:`driver.core`."""
