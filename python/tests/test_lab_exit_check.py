"""Out of the lab, or still in it: the check after passing the lab door.

A line fitted through the lab door's jamb and furniture beside its barcode can hold an
"opening" into the lab itself; the robot then "passes" it and stays in the lab. A wall ahead
far off the way it passed raises the doubt, and the lab door's barcode settles it: it faces
into the lab (docs/maps.md), so from the corridor its wall hides it. The sequencer's logic is
driven without a link or a simulator: a made-up robot whose turns are exact.
"""

from __future__ import annotations

import asyncio
import math
from typing import Any

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.geometry import Pose
from courier.sequenced.delivery import SQUARE_OUT_MAX_RAD, Delivery
from unlinked import Unlinked


class JustThrough(Unlinked, Delivery):
    """A `Delivery` with no link, just through a door (heading 0), the lab's barcode behind.

    `std.fit_wall` sees a wall ``off`` rad off the way passed, 1.5 m ahead; the barcode
    reader reads barcode 10 when facing back (behind) if ``in_view``.
    """

    def __init__(self, off: float, in_view: bool) -> None:
        self.unlink()
        self.pose = Pose(0.0, 0.0, 0.0)
        self.passed_heading: float | None = 0.0
        self.barcode_place = (10, -1.5, 0.1)
        self.off, self.in_view = off, in_view
        self.looked_from: list[float] = []

    async def odom(self) -> Pose:
        return self.pose

    async def sonar(self) -> list[float]:
        return [4.0] * 24

    async def turn(self, angle: float, *, keep: Any = ()) -> bool:
        p = self.pose
        self.pose = Pose(p.x, p.y, p.theta + angle)
        return True

    async def clue(self, skill: str, signal: str, *, keep: Any = ()) -> dict[str, Any] | None:
        assert (skill, signal) == ("fit_wall", "wall")
        normal = self.off - self.pose.theta
        return {"seen": True, "normal": normal, "distance": 1.5, "inliers": 5}

    async def value(self, signal: str) -> Any:
        assert signal == "target"
        self.looked_from.append(self.pose.theta)
        back = abs(math.remainder(self.pose.theta - math.pi, 2 * math.pi)) < 0.2
        seen = self.in_view and back
        return {"seen": seen, "id": 10 if seen else 0, "bearing": 0.0, "distance": 1.5}


def test_a_wall_far_off_and_the_lab_barcode_behind_in_view_is_still_the_lab() -> None:
    robot = JustThrough(SQUARE_OUT_MAX_RAD + 0.2, in_view=True)
    assert not asyncio.run(robot.square_the_way_out(10))
    # It looked where the barcode was read (behind), then faced the way it was going again.
    assert len(robot.looked_from) == 1
    assert abs(math.remainder(robot.looked_from[0] - math.pi, 2 * math.pi)) < 0.2
    assert abs(math.remainder(robot.pose.theta, 2 * math.pi)) < 1e-9


def test_a_wall_far_off_with_the_barcode_hidden_is_the_corridor() -> None:
    robot = JustThrough(SQUARE_OUT_MAX_RAD + 0.2, in_view=False)
    assert asyncio.run(robot.square_the_way_out(10))
    assert len(robot.looked_from) == 1


def test_a_wall_square_ahead_costs_no_look_back() -> None:
    robot = JustThrough(SQUARE_OUT_MAX_RAD / 2, in_view=True)
    assert asyncio.run(robot.square_the_way_out(10))
    assert robot.looked_from == []
    assert robot.passed_heading is not None
    assert abs(robot.passed_heading - SQUARE_OUT_MAX_RAD / 2) < 1e-9
