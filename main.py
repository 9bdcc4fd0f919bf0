#!/usr/bin/env python3
"""UavViewerPy from a checkout: ``python main.py --sim`` (installed, the same window is ``uavviewer``).

The window's code is the package's own (:mod:`uavviewer.app`); this file only starts it.
"""
import sys

from uavviewer.app import main

if __name__ == "__main__":
    sys.exit(main())
