"""MAVLink FTP, one engine for every file read from the vehicle (parameters, logs)."""
