"""Boarding a car and riding it: inside a car or not, its door open or not.

Pure tests: no link, no simulator. In generated-hard building 30168 the robot, stopped short of
a car by people in its way, took itself to be inside (walls and people near all round, the
panel in view through the door) and pushed a floor button it could not reach; in 30162, off its
car's middle, the sonar ahead read a jamb while the door stood open on the goal floor.
"""

from __future__ import annotations

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.mission import (
    DOOR_OPEN_AHEAD_M,
    DOOR_OPEN_BESIDE_M,
    car_door_open_expr,
    inside_car_by_panel,
)


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
