"""The robot's geometry, as both designs read it: its odometry pose and its sonar ring.

Headings are radians, counter-clockwise; a difference of headings is wrapped into (-pi, pi]
(`wrap`). The sonar ring has `SONARS` sonars, sonar 0 straight ahead, counter-clockwise.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

#: The sonars of the robot's ring (sonar 0 ahead, counter-clockwise).
SONARS = 24


@dataclass
class Pose:
    """An odometry pose."""

    x: float
    y: float
    theta: float


def wrap(a: float) -> float:
    """``a`` wrapped into (-pi, pi]."""
    a = math.fmod(a, 2 * math.pi)
    if a > math.pi:
        a -= 2 * math.pi
    elif a <= -math.pi:
        a += 2 * math.pi
    return a


def bearing_of(i: int) -> float:
    """Bearing of sonar ``i`` in the robot frame (sonar 0 ahead, counter-clockwise)."""
    return wrap(i * 2 * math.pi / SONARS)


def sonar_toward(bearing: float) -> int:
    """The sonar whose axis is nearest ``bearing`` (rad, robot frame)."""
    return round(wrap(bearing) / (2 * math.pi / SONARS)) % SONARS


def live_sonar_ahead(dead_mask: int) -> int:
    """The sonar nearest ahead that is not dead (bit i of ``dead_mask``: sonar i is dead).

    `std.sonar_filter` fills a dead sonar in with the nearer of its neighbours' readings: in
    a car facing its door, those see the jambs, and the door never reads open. Sonar 0 if
    all are dead.
    """
    live = [k for k in range(SONARS) if not dead_mask >> k & 1]
    return min(live, key=lambda k: abs(bearing_of(k))) if live else 0


def mean_heading(headings: Iterable[float]) -> float:
    """The circular mean of ``headings`` (rad): right across the ±pi seam too."""
    hs = list(headings)
    return math.atan2(sum(math.sin(h) for h in hs), sum(math.cos(h) for h in hs))
