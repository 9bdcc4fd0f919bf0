"""The ground floor: values and helpers every layer of the driver shares (frames, safe files, command results).

It imports nothing else of the driver."""
