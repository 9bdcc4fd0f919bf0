"""Missions, fences and rally points: the plan model (:mod:`.plan`), and the parts that move plans to and from
the vehicle, check them against the flight limits and read and write plan files."""
