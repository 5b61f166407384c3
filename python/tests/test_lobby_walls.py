"""Which sonar readings the lobby patrol takes for an end wall (demo/courier/mission.py).

Pure tests on made-up sonar rings: no link, no simulator. Someone standing in the lobby read
as a short wall square to a sonar's axis (`seen_wall_ends_at` took them), was kept as an end
wall of the lobby, bounded it short of the real one (a car's door opening there was then
beyond the lobby) and read as a door opening in it when they walked off: a car's door that
was not there, gone to time and again.
"""

from __future__ import annotations

import math

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.mission import seen_wall_ends_at, wall_wider_than_people_at
from sonar_rings import REACH_M, ring


def wall(distance: float, *, open_left: bool = False) -> list[float]:
    """A wall square to sonar 0's axis ``distance`` m off (its left half open: a car's door).

    Each sonar reads the nearest echo of its 15° cone: along its ray nearest the axis.
    """
    around = {}
    for k in range(-5, 6):
        r = distance / math.cos(math.radians(max(0.0, 15 * abs(k) - 7.5)))
        around[k] = REACH_M if r > REACH_M or (open_left and k > 0) else r
    return ring(around)


def test_a_wall_square_ahead_is_a_wall() -> None:
    for d in (0.7, 1.5, 2.5, 3.5):
        assert wall_wider_than_people_at(wall(d), 0), d
        assert seen_wall_ends_at(wall(d), 0), d


def test_a_wall_with_a_car_door_open_beside_the_axis_is_a_wall() -> None:
    assert wall_wider_than_people_at(wall(1.2, open_left=True), 0)


def test_someone_standing_ahead_is_no_wall() -> None:
    # As read across a lobby (generated building 60054): someone some 1.5 m off filled sonar
    # 12's view and the edges of its neighbours'; the sonars 30° off read the walls beyond.
    ranges = ring({-2: 2.02, -1: 1.65, 0: 1.49, 1: 1.65, 2: 4.0})
    assert seen_wall_ends_at(ranges, 0)  # what took them for a wall
    assert not wall_wider_than_people_at(ranges, 0)
    # Someone 0.7 m ahead, where the patrol stops short of a wall.
    ranges = ring({-2: 1.85, -1: 0.75, 0: 0.74, 1: 0.77, 2: 2.64})
    assert not wall_wider_than_people_at(ranges, 0)
    # The wall itself there, with a missed echo beside the axis.
    assert wall_wider_than_people_at(ring({-2: 0.77, -1: 0.68, 0: 0.7, 1: 4.0, 2: 0.76}), 0)


def test_a_wall_at_a_slant_is_a_wall() -> None:
    # As read where the patrol stopped short of a lobby's wall, facing it some 30° off square
    # (generated building 30030, no one about): nearer on one side, past its end on the other.
    assert wall_wider_than_people_at(ring({-2: 3.28, -1: 1.22, 0: 0.75, 1: 0.61, 2: 0.55}), 0)


def test_nothing_in_reach_is_no_wall() -> None:
    assert not wall_wider_than_people_at(ring({}), 0)
    assert not wall_wider_than_people_at(wall(3.8), 0)


def test_any_sonar_of_the_ring() -> None:
    ranges = wall(2.0)
    shifted = ranges[-12:] + ranges[:-12]  # the same wall behind (sonar 12)
    assert wall_wider_than_people_at(shifted, 12)
    assert not wall_wider_than_people_at(shifted, 0)
