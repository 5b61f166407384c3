"""The paper's runaway skill in Python, run inside the manager's cycle.

When the nearest of the 24 sonars is closer than ``safe_distance``, it writes
``drive`` to back away from the obstacle and turn from it; otherwise nothing.
The arithmetic is the C, C++ and Rust versions' step for step (all in f64), so
the four agree bit for bit on the same inputs.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

import numpy as np

import situate

SONARS = 24
TWO_PI = 2.0 * math.pi


@situate.skill(
    name="py.runaway",
    priority=50,
    outputs={"drive": "{v: f64, w: f64}"},
)
def runaway(
    sonar_range: Annotated[np.ndarray, situate.port("f32[24]", signal="sonar.range")],
    safe_distance: float = situate.param(
        0.5, min=0.1, max=3.0, unit="m", doc="Obstacles nearer than this repel."
    ),
) -> dict[str, Any] | None:
    """Backs away from the nearest sonar obstacle closer than safe_distance."""
    ranges = sonar_range.tolist()  # f32 -> f64, exactly
    r_min = ranges[0]
    k = 0
    for i in range(1, SONARS):
        if ranges[i] < r_min:  # ties: the lowest index wins
            r_min = ranges[i]
            k = i
    if r_min >= safe_distance:
        return None  # nothing near: write nothing
    a = k * TWO_PI / SONARS if k <= 12 else k * TWO_PI / SONARS - TWO_PI
    return {
        "drive": {
            "v": -0.3 * math.cos(a) * (1.0 - r_min / safe_distance),
            "w": -1.0 * math.sin(a),
        }
    }
