"""What the driver flies in several steps, each an explicit state machine: takeoff, mission start, land, RTL and
Stop (docs/driver.md draws them)."""
