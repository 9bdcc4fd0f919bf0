"""``python -m uavviewer``: the window, as ``uavviewer`` or ``python main.py``."""
import sys

from uavviewer.app import main

if __name__ == "__main__":
    sys.argv[0] = "python -m uavviewer"          # what --help and errors call the command
    sys.exit(main())
