"""What the window asks and says around a flight's commands (arming, ...), apart from the window that wires them."""
