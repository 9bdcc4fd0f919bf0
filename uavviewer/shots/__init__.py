"""Smart shots in the window: the Shots panel, the shot on the map and over the video, the sticks routed to the
shot while it runs (docs/shots.md)."""
