"""Vehicle › Setup: the bench pages (summary, sensors, radio, motors), after QGroundControl's Vehicle Setup."""
