"""Where the recordings of a real ArduCopter are: ``shared/recordings`` beside the checkout (as in CI), or
``UAV_RECORDINGS``. Without them a developer's run skips those tests; CI fails them, so they never go quiet."""
from __future__ import annotations

import os

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RECORDINGS = os.environ.get("UAV_RECORDINGS") or os.path.normpath(os.path.join(ROOT, os.pardir, "shared",
                                                                                "recordings"))
FLIGHT = os.path.join(RECORDINGS, "arducopter-4.7-sitl-flight")
SIGNING = os.path.join(RECORDINGS, "arducopter-4.7-sitl-signing")


def need_recordings():
    """A module mark: skip without the recordings on a developer's machine, fail without them in CI."""
    present = os.path.isfile(FLIGHT + ".tlog") and os.path.isfile(SIGNING + ".tlog")
    if not present and os.environ.get("CI"):
        raise RuntimeError(f"CI: the recordings are not in {RECORDINGS}")
    return pytest.mark.skipif(not present, reason=f"the recordings are not in {RECORDINGS} (set UAV_RECORDINGS)")
