"""Made-up sonar rings for the pure tests of what the courier reads in them."""

from __future__ import annotations

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.geometry import SONARS

#: What a sonar that heard no echo reads (its reach), m.
REACH_M = 4.0


def ring(around: dict[int, float], rest: float = REACH_M) -> list[float]:
    """A ring of readings: ``around`` (sonar offset from 0, negative clockwise), else ``rest``."""
    ranges = [rest] * SONARS
    for k, r in around.items():
        ranges[k % SONARS] = r
    return ranges
