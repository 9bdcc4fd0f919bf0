"""The flight HUD drawn over the video, like QGroundControl's fly view.

Not a widget: :func:`paint_hud` draws into the camera view's painter so the HUD
sits exactly on the picture. A right roll turns the horizon line counter-clockwise
and nose up moves it down, as the pilot sees the world from the camera. The text
(:func:`text_rows`) stays readable: the roll scale stays below the heading tape, the
horizon line stops short of the side readouts, and a pitch rung that would cross any
text is not drawn. On a small video (1024×600: 156 px wide) the top row could not hold
the mode, the heading and the battery side by side, and they overlapped: there the
heading tape is left out, the heading goes under the battery, and the battery drops its
volts if it must (:func:`hud_labels` lays every text out; none overlaps another).
"""
from __future__ import annotations

import math

from typing import NamedTuple

from PyQt5.QtCore import QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QFont, QFontMetricsF, QPainter, QPen, QRegion

from driver.vehicle.state import BatteryAlarm, LinkStatus, VehicleState
from ..flight.phase import no_vehicle_words
from ..units import fmt as _num

__all__ = ["arming_text", "paint_hud", "text_rows", "hud_labels", "hud_font", "Label", "HUD_COLOUR", "STALE_COLOUR",
           "hud_colour", "stale_text"]

HUD_COLOUR = QColor(120, 255, 140)
SHADOW = QColor(0, 0, 0, 160)
WARN = QColor(255, 90, 70)
STALE_COLOUR = QColor(150, 156, 164)      # every live value, once the link is lost: the last heard, not now
ALARM = {BatteryAlarm.WARNING: QColor(255, 176, 32), BatteryAlarm.CRITICAL: WARN}
VISIBLE_PITCH_DEG = 30.0        # centre to top edge
MARGIN = 8


def _text(p: QPainter, rect: QRectF, flags, text: str, colour: QColor = HUD_COLOUR) -> None:
    flags = flags | Qt.TextDontClip
    p.setPen(SHADOW)
    p.drawText(rect.translated(1, 1), flags, text)
    p.setPen(colour)
    p.drawText(rect, flags, text)


class Label(NamedTuple):
    rect: QRectF
    flags: int
    text: str
    colour: QColor


def _text_size(rect: QRectF) -> int:
    return max(9, int(min(rect.width(), rect.height()) / 22))


def hud_font(base: QFont, rect: QRectF) -> QFont:
    font = QFont(base)
    font.setPixelSize(_text_size(rect))
    font.setBold(True)
    return font


def _compact(rect: QRectF, font: QFont) -> bool:
    """Too narrow for the mode, the heading tape and the battery side by side (the longest of each)."""
    fm = QFontMetricsF(font)
    need = fm.horizontalAdvance("GUIDED_NOGPS") + fm.horizontalAdvance("000°") * 2.2 + \
        fm.horizontalAdvance("BAT 100% 16.8 V") + 4 * MARGIN
    return need > rect.width()


def _top_band(rect: QRectF, size: int) -> QRectF:
    """The heading tape with its labels, and the mode and battery rows beside it."""
    return QRectF(rect.left(), rect.top(), rect.width(), 4 + size * 3.1)


def _side_rows(rect: QRectF, size: int) -> tuple[QRectF, QRectF]:
    """Speeds on the left, altitude and distance on the right: two rows each, about the centre."""
    line = size * 1.4
    w = rect.width() * 0.25
    top = rect.center().y() - line
    return (QRectF(rect.left() + MARGIN, top, w, 2 * line),
            QRectF(rect.right() - MARGIN - w, top, w, 2 * line))


def text_rows(rect: QRectF) -> list[QRectF]:
    """Where the HUD over ``rect`` writes text; horizon, ladder and roll scale keep out of them."""
    size = _text_size(rect)
    return [_top_band(rect, size), *_side_rows(rect, size)]


def stale_text(state: VehicleState) -> str:
    """"LINK LOST · values 12 s old" once the link is lost with a vehicle known, else ""."""
    if state.link.status not in (LinkStatus.LOST, LinkStatus.CLOSED) or not state.mode:
        return ""
    if state.link.replay_ended:
        return "REPLAY ENDED · its last moment"
    age = state.link.heartbeat_age
    return "LINK LOST · values " + (f"{age:.0f} s old" if age is not None else "stale")


def arming_text(state: VehicleState) -> str:
    """"ARMED" or "DISARMED" as the vehicle last said it; "ARMING UNKNOWN" while no vehicle is heard (nothing
    heard yet, or after leaving one, which may well still be flying)."""
    if state.link.status is LinkStatus.WAITING or not state.mode:
        return "ARMING UNKNOWN"
    return "ARMED" if state.armed else "DISARMED"


def hud_colour(state: VehicleState) -> QColor:
    """Green while live; grey once the link is lost (the values are the last heard)."""
    return STALE_COLOUR if stale_text(state) else HUD_COLOUR


def paint_hud(p: QPainter, rect: QRectF, state: VehicleState) -> None:
    """Horizon and roll, heading, altitude, speed, mode and battery over ``rect``."""
    p.save()
    p.setRenderHint(QPainter.Antialiasing)
    p.setClipRect(rect)
    font = hud_font(p.font(), rect)
    size = font.pixelSize()
    p.setFont(font)
    compact = _compact(rect, font)
    _horizon(p, rect, state, size)
    if not compact:
        _heading(p, rect, state, size)
    for label in hud_labels(rect, state, font):
        _text(p, label.rect, label.flags, label.text, label.colour)
    stale = stale_text(state)
    if stale:                                   # along the bottom, clear of the scales, on a dark band
        line = size * 1.4
        band = QRectF(rect.left(), rect.bottom() - line - MARGIN, rect.width(), line + MARGIN)
        p.fillRect(band, SHADOW)
        _text(p, band, Qt.AlignHCenter | Qt.AlignVCenter, stale, WARN)
    p.restore()


def _horizon(p: QPainter, rect: QRectF, state: VehicleState, size: int) -> None:
    colour = hud_colour(state)
    a = state.attitude
    roll = a.roll if math.isfinite(a.roll) else 0.0
    pitch = a.pitch if math.isfinite(a.pitch) else 0.0
    c = rect.center()
    px_per_deg = (rect.height() / 2) / VISIBLE_PITCH_DEG
    texts = text_rows(rect)
    p.save()
    clear = QRegion(rect.toAlignedRect())
    for t in texts:
        clear -= QRegion(t.toAlignedRect())
    p.setClipRegion(clear, Qt.IntersectClip)                # a steep horizon passes behind the heading tape
    base = p.transform()
    p.translate(c)
    p.rotate(-math.degrees(roll))
    p.translate(0, math.degrees(pitch) * px_per_deg)
    # the side readouts start a quarter of the width from the centre: the line, turned any way, ends before
    half = rect.width() * 0.22
    p.setPen(QPen(colour, 2))
    p.drawLine(QPointF(-half, 0), QPointF(-half * 0.3, 0))
    p.drawLine(QPointF(half * 0.3, 0), QPointF(half, 0))
    p.setPen(QPen(colour, 1))
    w = rect.width() * 0.1
    to_rect = p.transform() * base.inverted()[0]            # rung coordinates to those of ``rect``
    for deg in (-20, -10, 10, 20):                          # pitch ladder
        y = -deg * px_per_deg
        label = QRectF(w + 4, y - size * 0.7, size * 3, size * 1.4)
        # with 2 px for antialiased edges
        extent = to_rect.mapRect(QRectF(-w, y, 2 * w + 4 + label.width(), 0).united(label).adjusted(-2, -2, 2, 2))
        if any(extent.intersects(t) for t in texts):
            continue
        p.drawLine(QPointF(-w, y), QPointF(w, y))
        p.drawText(label, Qt.AlignLeft | Qt.AlignVCenter, f"{deg}")
    p.restore()
    # the fixed aircraft symbol and the roll scale
    p.setPen(QPen(QColor(255, 196, 0), 3))
    w = rect.width() * 0.06
    p.drawLine(QPointF(c.x() - 2 * w, c.y()), QPointF(c.x() - w, c.y()))
    p.drawLine(QPointF(c.x() - w, c.y()), QPointF(c.x() - w * 0.5, c.y() + w * 0.4))
    p.drawLine(QPointF(c.x() + 2 * w, c.y()), QPointF(c.x() + w, c.y()))
    p.drawLine(QPointF(c.x() + w, c.y()), QPointF(c.x() + w * 0.5, c.y() + w * 0.4))
    # below the heading tape, with room for the pointer's overshoot
    radius = max(0.0, min(min(rect.width(), rect.height()) * 0.38, c.y() - _top_band(rect, size).bottom() - 4))
    p.setPen(QPen(colour, 1.5))
    for tick in (-45, -30, -20, -10, 0, 10, 20, 30, 45):
        t = math.radians(tick)
        inner = radius - (10 if tick % 30 == 0 else 6)
        p.drawLine(QPointF(c.x() + inner * math.sin(t), c.y() - inner * math.cos(t)),
                   QPointF(c.x() + radius * math.sin(t), c.y() - radius * math.cos(t)))
    t = -roll                                               # pointer follows the sky
    p.setPen(QPen(QColor(255, 196, 0), 2))
    p.drawLine(QPointF(c.x() + (radius - 14) * math.sin(t), c.y() - (radius - 14) * math.cos(t)),
               QPointF(c.x() + (radius + 2) * math.sin(t), c.y() - (radius + 2) * math.cos(t)))


def _heading(p: QPainter, rect: QRectF, state: VehicleState, size: int) -> None:
    colour = hud_colour(state)
    heading = state.heading_deg if math.isfinite(state.heading_deg) else 0.0
    span = 90.0
    top = rect.top() + 4
    width = rect.width() * 0.5
    left = rect.center().x() - width / 2
    p.setPen(QPen(colour, 1))
    names = {0: "N", 90: "E", 180: "S", 270: "W"}
    start = int(math.floor((heading - span / 2) / 10.0)) * 10
    for deg in range(start, int(heading + span / 2) + 10, 10):
        x = left + (deg - heading + span / 2) / span * width
        if not left <= x <= left + width:
            continue
        d = deg % 360
        p.drawLine(QPointF(x, top + size * 1.3), QPointF(x, top + size * (1.8 if d % 30 == 0 else 1.55)))
        if d % 30 == 0:
            _text(p, QRectF(x - 20, top + size * 1.8, 40, size * 1.3), Qt.AlignCenter, names.get(d, str(d)), colour)
    # the heading itself: one of hud_labels


def hud_labels(rect: QRectF, state: VehicleState, font: QFont) -> list[Label]:
    """Every text of the HUD over ``rect`` in ``font`` (:func:`hud_font`), where it is written: speeds and the
    camera's tilt left, altitude and home right, mode and arming top left, battery top right, and the heading at
    the top (under the battery on a small video, where the tape is left out)."""
    colour = hud_colour(state)
    stale = stale_text(state)
    size = font.pixelSize()
    fm = QFontMetricsF(font)
    compact = _compact(rect, font)
    line = size * 1.4
    left, right = (QRectF(r.left(), r.top(), r.width(), line) for r in _side_rows(rect, size))
    L, R = Qt.AlignLeft | Qt.AlignVCenter, Qt.AlignRight | Qt.AlignVCenter
    dist = state.distance_from_home
    labels = [Label(left, L, f"GS {_num(state.velocity.ground_speed)} m/s", colour),
              Label(left.translated(0, line), L, f"VS {_num(state.velocity.climb)} m/s", colour),
              Label(right, R, f"ALT {_num(state.altitude)} m", colour),
              Label(right.translated(0, line), R, f"HOME {_num(dist, 0)} m", colour),
              # the vehicle's camera tilt, as it reports it
              Label(left.translated(0, 2 * line), L, f"CAM {_num(state.gimbal.pitch_deg, 0)}°", colour)]
    # mode and arming top-left, battery top-right
    half = rect.width() / 2 - MARGIN
    top = QRectF(rect.left() + MARGIN, rect.top() + 4, half if compact else rect.width() * 0.3, line)
    armed = arming_text(state)
    labels.append(Label(top, L, state.mode or no_vehicle_words(state),
                        colour if stale else (HUD_COLOUR if state.connected else WARN)))
    labels.append(Label(top.translated(0, line), L, armed,
                        colour if stale else (WARN if state.armed or armed == "ARMING UNKNOWN" else HUD_COLOUR)))
    b = state.battery
    parts = []
    if b.remaining is not None:
        parts.append(f"{b.remaining:.0f}%")
    if b.voltage is not None:
        parts.append(f"{b.voltage:.1f} V")
    battery = "BAT " + (" ".join(parts) or "--")
    width = half if compact else rect.width() * 0.3
    beside = rect.width() - 3 * MARGIN - fm.horizontalAdvance(labels[-2].text)     # what the mode leaves
    if compact and fm.horizontalAdvance(battery) > beside:
        battery = "BAT " + (parts[0] if parts else "--")                           # the percentage only
    width = max(width, fm.horizontalAdvance(battery)) if compact else width
    top_right = QRectF(rect.right() - MARGIN - width, rect.top() + 4, width, line)
    alarm = ALARM.get(b.alarm, WARN if b.low and b.alarm is BatteryAlarm.UNKNOWN else HUD_COLOUR)
    labels.append(Label(top_right, R, battery, colour if stale else alarm))
    heading = state.heading_deg if math.isfinite(state.heading_deg) else 0.0
    if compact:
        if armed != "ARMING UNKNOWN":             # no vehicle heard: no heading to give, and the words need the row
            labels.append(Label(top_right.translated(0, line), R, f"HDG {heading:03.0f}°", colour))
    else:
        labels.append(Label(QRectF(rect.center().x() - 40, rect.top() + 4, 80, size * 1.3), Qt.AlignCenter,
                            f"{heading:03.0f}°", colour))
    return labels
