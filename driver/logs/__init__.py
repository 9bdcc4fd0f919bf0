"""The vehicle's DataFlash logs: list, download (resumable, byte-exact, through loss), erase."""
