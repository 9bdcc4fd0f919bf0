"""The radio calibration's arithmetic (no Qt): each channel's lowest and highest while the pilot moves every
stick and switch to its ends, and its centre when they are let go. A channel that never moved is not written:
its RCn_MIN/MAX would collapse onto one value and the vehicle would read it as full deflection."""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["RadioCalibration", "ChannelRange", "MIN_TRAVEL", "parameters", "throttle_channel"]

MIN_TRAVEL = 200                 # µs between lowest and highest before a channel counts as moved
THROTTLE = 3                     # ArduCopter's default RCMAP_THROTTLE


def throttle_channel(s) -> int:
    """The throttle's channel as the vehicle maps it (RCMAP_THROTTLE; 3, the default, until it is read): a
    transmitter in another order (throttle first) has its pitch or roll on 3."""
    p = s.parameters.get("RCMAP_THROTTLE")
    channel = int(p.value) if p is not None else THROTTLE
    return channel if 1 <= channel <= 16 else THROTTLE


@dataclass(frozen=True)
class ChannelRange:
    channel: int
    low: int
    high: int
    trim: int

    @property
    def moved(self) -> bool:
        return self.high - self.low >= MIN_TRAVEL

    def words(self) -> str:
        if not self.moved:
            return f"RC{self.channel}: never moved ({self.low}–{self.high} µs): not written"
        return f"RC{self.channel}_MIN {self.low}, RC{self.channel}_MAX {self.high}, RC{self.channel}_TRIM {self.trim}"


@dataclass
class RadioCalibration:
    low: dict[int, int] = field(default_factory=dict)
    high: dict[int, int] = field(default_factory=dict)

    def feed(self, values: tuple[int, ...]) -> None:
        """One RC_CHANNELS snapshot (0: not sent, ignored)."""
        for i, us in enumerate(values, start=1):
            if us:
                self.low[i] = min(self.low.get(i, us), us)
                self.high[i] = max(self.high.get(i, us), us)

    def ranges(self, centred: tuple[int, ...], throttle: int = THROTTLE) -> list[ChannelRange]:
        """Every channel seen, with ``centred`` (the channels as the pilot let the sticks go) as trims; the
        ``throttle`` channel's trim is its lowest (RCn_TRIM at the bottom, as ArduCopter wants it)."""
        out = []
        for ch in sorted(self.low):
            low, high = self.low[ch], self.high[ch]
            now = centred[ch - 1] if ch <= len(centred) and centred[ch - 1] else (low + high) // 2
            trim = low if ch == throttle else min(max(now, low), high)
            out.append(ChannelRange(ch, low, high, trim))
        return out


def parameters(ranges: list[ChannelRange]) -> dict[str, float]:
    """What the calibration writes: RCn_MIN/MAX/TRIM of the channels that moved, nothing of the others."""
    values: dict[str, float] = {}
    for r in ranges:
        if r.moved:
            values.update({f"RC{r.channel}_MIN": r.low, f"RC{r.channel}_MAX": r.high, f"RC{r.channel}_TRIM": r.trim})
    return values
