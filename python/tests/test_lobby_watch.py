"""How the lobby patrol watches its known walls for a car's door standing open (lobby.py).

Pure tests on made-up sonar rings: no link, no simulator. In plain generated building 30174
(no one about) the patrol went, call after call, to doors that were not there: a missed echo
(a sonar reads its reach) on a wall passed close by, and another a poll later near the same
spot, looked like a door standing open in it. A car behind an open door echoes from its own
walls, at most 2.4 m beyond the door (docs/maps.md, "Lobby"). The wall across the lobby, where
the car was, became known only once the patrol stood at it: the car's door opened and closed
while the robot walked there.
"""

from __future__ import annotations

import math

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.geometry import SONARS, Pose
from courier.sequenced.lobby import (
    new_wall_ahead,
    open_in_walls,
)
from sonar_rings import REACH_M, ring


def wall_ahead(distance: float, **instead: float) -> list[float]:
    """A wall square to sonar 0's axis ``distance`` m off, as each sonar's cone reads it.

    ``instead``: readings of some sonars (``s0``, ``s1``, ``s_1`` for -1, …) in its place.
    """
    around = {}
    for k in range(-4, 5):
        r = distance / math.cos(math.radians(max(0.0, 15 * abs(k) - 7.5)))
        around[k] = min(r, REACH_M)
    for name, r in instead.items():
        around[int(name[1:].replace("_", "-"))] = r
    return ring(around)


HERE = Pose(0.0, 0.0, 0.0)
#: A known wall of the lobby 1.2 m ahead (a point on it and its normal, towards it).
NEAR = [(1.2, 0.0, 0.0)]


def test_a_missed_echo_on_a_near_wall_is_no_open_door() -> None:
    # The car's back wall would be 3.6 m off at most: a sonar reading no echo missed it.
    assert open_in_walls(HERE, wall_ahead(1.2, s0=REACH_M), NEAR, NEAR) is None


def test_a_car_seen_through_its_door_is_an_open_door() -> None:
    seen = open_in_walls(HERE, wall_ahead(1.2, s0=3.2), NEAR, NEAR)
    assert seen is not None
    assert abs(seen[0] - 1.2) < 1e-9
    assert abs(seen[1]) < 1e-9
    assert seen[2] == 0.0


def test_no_echo_counts_where_the_car_may_be_out_of_reach() -> None:
    far = [(2.0, 0.0, 0.0)]
    assert open_in_walls(HERE, wall_ahead(2.0, s0=REACH_M), far, far) is not None


def test_a_closed_wall_is_no_open_door() -> None:
    assert open_in_walls(HERE, wall_ahead(1.2), NEAR, NEAR) is None


def along_a_wall_on_the_right(ahead: float, aside: float = 0.5) -> list[float]:
    """A wall ``ahead`` m off square to the way, and the wall the robot walks along on its
    right, ``aside`` m off: the right-hand sonars read that one first."""
    ranges = wall_ahead(ahead)
    for k in (1, 2, 3):
        # The ray of sonar -k nearest the side wall is 15k + 7.5 degrees off the axis.
        ranges[-k % SONARS] = min(ranges[-k % SONARS], aside / math.sin(math.radians(15 * k + 7.5)))
    return ranges


def test_the_wall_the_patrol_walks_towards_is_known_from_afar() -> None:
    assert new_wall_ahead(HERE, along_a_wall_on_the_right(2.5), []) == (2.5, 0.0, 0.0)
    # Not twice.
    assert new_wall_ahead(HERE, along_a_wall_on_the_right(2.5), [(2.6, 0.3, 0.05)]) is None


def test_someone_standing_ahead_is_no_wall_ahead() -> None:
    # Someone some 1.5 m off fills sonar 0's view and the edges of its neighbours'; the
    # sonars 30° off read past them (as in test_lobby_walls.py).
    ranges = ring({-2: 2.02, -1: 1.65, 0: 1.49, 1: 1.65, 2: 4.0})
    assert new_wall_ahead(HERE, ranges, []) is None


def test_someone_standing_ahead_beside_the_walls_way_is_no_wall_ahead() -> None:
    # As read in hard generated building 30014: walking along the button's wall (on the
    # right), someone 2.85 m ahead; the right-hand sonars read the wall beside, nearer.
    ranges = [3.15, 4.0, 4.0, 3.77, 3.57, 4.0, 4.0, 3.07, 3.25, 3.75, 3.96, 3.68]
    ranges += [3.67, 3.23, 1.53, 1.53, 1.32, 1.22, 1.27, 1.23, 1.31, 1.59, 2.05, 2.81]
    ranges[0] = 2.85
    assert new_wall_ahead(HERE, ranges, []) is None


def test_nothing_in_reach_is_no_wall_ahead() -> None:
    assert new_wall_ahead(HERE, ring({}), []) is None
