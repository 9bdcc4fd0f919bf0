"""How the viewer writes numbers: one rule for every instrument."""
from __future__ import annotations

import math


def fmt(value: float | None, digits: int = 1, unit: str = "") -> str:
    """``value`` rounded to ``digits``, "--" when unknown; never "-0.0"."""
    if value is None or not math.isfinite(value):
        return "--"
    rounded = round(value, digits) + 0.0      # + 0.0 turns -0.0 into 0.0
    text = f"{rounded:.{digits}f}"
    return f"{text} {unit}" if unit else text
