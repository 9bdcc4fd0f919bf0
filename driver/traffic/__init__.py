"""ADS-B traffic (driver.traffic): contacts the autopilot forwards in ADSB_VEHICLE, their closest approach to us,
and the alert when one will pass too close. :mod:`.approach` is the pure geometry, :mod:`.model` the snapshots,
:mod:`.tracker` keeps the contacts (fading and dropping the stale ones)."""
