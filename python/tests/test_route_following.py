"""How the sequencer follows a route's corridor steps (demo/courier/sequenced/routes.py).

Pure tests: no link, no simulator. Following to a wall, the robot took itself for gone round a
corner into a side corridor by measuring how far aside it was from a line drawn from where the
step began, along the route's heading: 3° off, that line was 1 m aside after 19 m, and a robot
going round a box there was off the way; going back onto that line took it through a door,
into a room whose wall it stopped at (generated building 30069). A leg's first `distance` ran
from where the robot stood out of the lab door, 1.6 m along the corridor from the door's
middle (where the map measures it from): it ended inside the junction it led to, which the
detector, started there, never saw (generated building 30054). Out of a door aslant, the
route's heading was 25° off the corridor's: the turn into the junction the route led to,
made from it, faced the corner and the next corridor was followed aslant (62080, a dev set).
"""

from __future__ import annotations

import math

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.geometry import Pose, wrap
from courier.mission import ORIGIN_MAX_M, distance_from_door, travelled_heading
from courier.sequenced.routes import off_the_way


def holds(condition: str, x: float, y: float, theta: float) -> bool:
    """``condition`` (the monitor language's &&, ||, abs) for the odometry pose (x, y, theta)."""
    text = condition.replace("&&", " and ").replace("||", " or ")
    text = text.replace("odom.x", repr(x)).replace("odom.y", repr(y))
    return bool(eval(text.replace("odom.theta", repr(theta)), {"abs": abs}))


def test_round_clutter_after_a_long_corridor_is_still_on_the_way() -> None:
    along = math.pi  # west; the corridor really runs 3° off that
    start = Pose(30.0, 14.0, along)
    drift = math.radians(3)
    # 22 m on, in the corridor's middle, turned 65° off round a box on its wall.
    here = (30.0 - 22 * math.cos(drift), 14.0 + 22 * math.sin(drift))
    line = Pose(here[0] + 4.0, here[1] - 0.2, along)  # where it followed the way 4 m back
    theta = wrap(along + math.radians(65))
    assert holds(off_the_way(start, start, along), *here, theta)  # the start's line alone
    assert not holds(off_the_way(start, line, along), *here, theta)


def test_into_a_side_corridor_is_off_the_way() -> None:
    along = math.pi
    start = Pose(30.0, 14.0, along)
    line = Pose(11.0, 14.0, along)
    # Round the corner at the corridor's end, 1.5 m into the side corridor, facing down it.
    assert holds(off_the_way(start, line, along), 7.0, 12.5, -math.pi / 2)
    # Turned as much but in the corridor (going round someone): not off it.
    assert not holds(off_the_way(start, line, along), 8.0, 13.8, -math.pi / 2)
    # As far aside facing the way (sidestepping): not off it.
    assert not holds(off_the_way(start, line, along), 7.0, 12.5, along)


def test_a_first_distance_runs_from_the_doors_middle() -> None:
    west = math.pi
    door = (30.04, 5.83)  # in the lab's wall; the corridor runs west along it
    # Out through the door 1.6 m west of its middle: the junction is that much nearer.
    left = distance_from_door(22.16, door, Pose(28.47, 7.09, 2.8), west)
    assert math.isclose(left, 22.16 - 1.57, abs_tol=1e-9)
    # Short of the middle (out aslant the other way): farther.
    assert math.isclose(distance_from_door(10.0, door, Pose(31.24, 6.9, 0.0), west), 11.2)


def test_near_the_doors_middle_or_far_from_it_the_step_is_as_written() -> None:
    west = math.pi
    door = (30.0, 5.83)
    # Half a metre along: the 1.5 m left before the junction is room enough.
    assert distance_from_door(22.16, door, Pose(29.5, 6.9, west), west) == 22.16
    # Farther than a door's middle can be misplaced by: not that door's.
    far = Pose(30.0 - ORIGIN_MAX_M - 1.0, 6.9, west)
    assert distance_from_door(22.16, door, far, west) == 22.16
    # Never down to nothing.
    assert distance_from_door(1.0, door, Pose(28.0, 6.9, west), west) == 0.1


def test_the_way_travelled_squares_a_plan_far_off() -> None:
    planned = math.radians(-154)  # the corridor runs west, 180°
    start, here = Pose(17.35, 8.51, planned), Pose(9.22, 8.30, math.pi)
    travel = travelled_heading(start, here, planned)
    assert travel is not None
    assert abs(wrap(travel - math.pi)) < math.radians(2)


def test_a_plan_near_enough_a_short_way_or_another_way_is_kept() -> None:
    west = math.pi
    # Started half a metre off the middle, back in it 6 m on: some 5° off the plan.
    assert travelled_heading(Pose(20.0, 8.5, west), Pose(14.0, 9.0, west), west) is None
    # Pushed about by people for a metre or two: too short to tell.
    assert travelled_heading(Pose(20.0, 8.5, west), Pose(17.0, 9.6, west), west) is None
    # Round a corner into the crossing corridor: no corridor of the plan's.
    assert travelled_heading(Pose(20.0, 8.5, west), Pose(15.0, 14.0, west), west) is None
