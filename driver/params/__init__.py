"""Vehicle parameters: the table the vehicle reports (:mod:`.model`), and the parts that download it, set
values with confirmation, read ArduPilot's metadata and read and write .param files."""
