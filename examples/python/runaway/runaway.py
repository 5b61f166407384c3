"""The paper's runaway skill in Python, run inside the manager's cycle.

When the nearest of the 24 sonars is closer than ``safe_distance``, it writes
``drive`` to back away from the obstacle and turn from it; otherwise nothing.
The arithmetic (:func:`runaway`) is the C, C++ and Rust versions' step for step
(all in f64), so the four agree bit for bit on the same inputs. Like them, the
skill counts the cycles it ran away from each switch on (``activate``) and says
the count when switched off (``deactivate``), in the same words.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

import numpy as np

import situate

SONARS = 24
TWO_PI = 2.0 * math.pi


def runaway(sonar_range: np.ndarray, safe_distance: float) -> dict[str, Any] | None:
    """The command away from the nearest obstacle closer than safe_distance, or None."""
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


@situate.skill(
    name="py.runaway",
    priority=50,
    outputs={"drive": "{v: f64, w: f64}"},
)
class Runaway:
    """Backs away from the nearest sonar obstacle closer than safe_distance."""

    def __init__(self) -> None:
        self.ran = 0  # cycles it ran away since it was last switched on

    def activate(self) -> None:
        """Switched on: counts afresh (the object lives across activations)."""
        self.ran = 0

    def step(
        self,
        sonar_range: Annotated[np.ndarray, situate.port("f32[24]", signal="sonar.range")],
        safe_distance: float = situate.param(
            0.5, min=0.1, max=3.0, unit="m", doc="Obstacles nearer than this repel."
        ),
    ) -> dict[str, Any] | None:
        """One cycle: the command away from what is too near (counted), or nothing."""
        command = runaway(sonar_range, safe_distance)
        if command is not None:
            self.ran += 1
        return command

    def deactivate(self) -> None:
        """Switched off: says how long it ran away while on."""
        print(f"switched off after running away {self.ran} cycles")
