"""Boarding a car, riding it, and lining up with the goal floor's call button.

Pure tests on made-up sonar rings: no link, no simulator. In generated-hard building 30168 the
robot, stopped short of a car by people in its way, took itself to be inside (walls and people
near all round, the panel in view through the door) and pushed a floor button it could not
reach; in 30162, off its car's middle, the sonar ahead read a jamb while the door stood open on
the goal floor. On the goal floor (dev hard 60025, 60196) the robot lined up with the call
button's barcode read aslant (a wall fitted through people, or a wall near the corner) and
every turn of the route to the office was off by as much.
"""

from __future__ import annotations

import math

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.mission import (
    DOOR_OPEN_AHEAD_M,
    DOOR_OPEN_BESIDE_M,
    car_door_open_expr,
    inside_car_by_panel,
    square_wall_ahead,
)
from sonar_rings import ring


def test_a_panel_read_through_the_door_from_outside_is_not_inside() -> None:
    assert inside_car_by_panel(1.6)
    assert inside_car_by_panel(2.3)
    # 30168: stopped 1.3 m short of the door of a 1.94 m deep car.
    assert not inside_car_by_panel(3.39)


def test_the_door_reads_open_beside_the_sonar_ahead() -> None:
    expr = car_door_open_expr(0, 0)
    assert f"sonar.range[0] > {DOOR_OPEN_AHEAD_M!r}" in expr
    assert f"sonar.range[1] > {DOOR_OPEN_BESIDE_M!r}" in expr
    assert f"sonar.range[23] > {DOOR_OPEN_BESIDE_M!r}" in expr
    # A dead neighbour reads what the filter fills in: it is left out.
    dead = car_door_open_expr(1, 1 << 0)
    assert "sonar.range[0]" not in dead
    assert "sonar.range[2]" in dead


def wall_at(sonar: int, distance: float) -> dict[int, float]:
    """A wall square to sonar ``sonar``'s axis ``distance`` m off, as its sonars read it."""
    return {
        sonar + k: min(distance / math.cos(math.radians(max(0.0, 15 * abs(k) - 7.5))), 4.0)
        for k in range(-3, 4)
    }


#: Heading north (odometry), 0.76 m east of the button's wall (the button faces east: the
#: robot faced west, 180°, pushing it), the wall across from it 3 m to the right.
def test_lined_up_square_with_the_wall_ahead() -> None:
    assert square_wall_ahead(ring(wall_at(0, 1.0)), 1.0)
    # A car's door open beside the button: one side looks into the car.
    assert square_wall_ahead(ring({**wall_at(0, 1.0), -1: 3.2, -2: 3.4}), 1.0)


def test_lined_up_aslant_is_not_square() -> None:
    # 60025 (dev hard): the barcode 1 m straight ahead, its wall 60° off square: the sonars
    # on one side read it much nearer than a square wall.
    aslant = {0: 1.0, 1: 0.63, 2: 0.55, -1: 2.0, -2: 4.0}
    assert not square_wall_ahead(ring(aslant), 1.0)
    # No wall at the standoff at all (facing along the wall: the barcode beside).
    assert not square_wall_ahead(ring({0: 2.48, 1: 0.57, -1: 4.0}), 1.0)


def test_lined_up_a_little_aslant_is_not_square() -> None:
    # 60196 (dev hard): 0.46 m off a side wall, 22° off square: the sonar 15° off reads the
    # wall but 0.24 m nearer; the one 30° off, 0.46 m nearer.
    assert not square_wall_ahead(ring({-2: 3.11, -1: 1.87, 0: 0.93, 1: 0.7, 2: 0.55}), 1.0)
