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
    """An odometry pose: a place (x, y, m) and the heading there (theta, rad).

    Its methods are the projections both designs make from where the robot is (or from a
    place and heading noted before: where a leg began, a wall's point and normal). Each keeps
    the operations of the hand-written formula it replaced, in their order, so a run on the
    simulated clock gives the same floating-point results, to the last bit.
    """

    x: float
    y: float
    theta: float

    def turn_to(self, heading: float) -> float:
        """The turn in place to face ``heading``: ``wrap(heading - theta)``, rad, left positive."""
        return wrap(heading - self.theta)

    def heading_of(self, bearing: float) -> float:
        """The heading (odometry frame) of ``bearing`` in the robot frame, wrapped, rad."""
        return wrap(self.theta + bearing)

    def bearing_to(self, x: float, y: float) -> float:
        """The turn in place that faces the point (x, y), rad, left positive."""
        return wrap(math.atan2(y - self.y, x - self.x) - self.theta)

    def along(self, x: float, y: float, heading: float | None = None) -> float:
        """How far the point (x, y) lies ahead along ``heading`` (default: theta), m.

        Behind is negative: the way made from here along a corridor's heading, how far beyond
        a wall's line (a wall's point and its normal as the pose).
        """
        h = self.theta if heading is None else heading
        return (x - self.x) * math.cos(h) + (y - self.y) * math.sin(h)

    def across(self, x: float, y: float, heading: float | None = None) -> float:
        """How far the point (x, y) lies left of the line along ``heading`` (default: theta), m."""
        h = self.theta if heading is None else heading
        return -(x - self.x) * math.sin(h) + (y - self.y) * math.cos(h)

    def ahead(self, distance: float, heading: float | None = None) -> tuple[float, float]:
        """The point ``distance`` m on along ``heading`` (default: theta; negative: back)."""
        h = self.theta if heading is None else heading
        return self.x + distance * math.cos(h), self.y + distance * math.sin(h)

    def seen_at(self, bearing: float, distance: float) -> tuple[float, float]:
        """Where a reading at ``bearing`` (rad, robot frame) and ``distance`` (m) is."""
        a = self.theta + bearing
        return self.x + distance * math.cos(a), self.y + distance * math.sin(a)

    def from_robot(self, x: float, y: float) -> tuple[float, float]:
        """A point of the robot's frame here (x ahead, y to the left) in the pose's frame."""
        c, s = math.cos(self.theta), math.sin(self.theta)
        return self.x + c * x - s * y, self.y + s * x + c * y


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
