"""The reactive robot's car rules (demo/courier/reactive/car.py): lobby walls, calls, leaving.

Pure tests on made-up senses (`reactive_support`): no link, no simulator. Each case is one
that a run on a generated building went wrong on (decision 0008, sixth round).
"""

from __future__ import annotations

import math

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.geometry import SONARS, Pose
from courier.reactive.car import END_WALL_FROM_M, PATROL_END_M, PATROL_HALF_M
from courier.reactive.rules import BUTTON_LAST_M, Reactive
from reactive_support import robot, senses

# The button's wall is the line x = 0.5 (the robot called from the origin, facing +x); the
# lobby's end walls are y = 4 (to the left, key 1) and y = -3 (to the right, key -1).
BUTTON_WALL = (0.5, 0.0, 0.0)
LEFT_WALL = (0.0, 4.0, math.pi / 2)
RIGHT_WALL = (0.0, -3.0, -math.pi / 2)


def _waiting() -> Reactive:
    r = robot()
    r.mem.called_from = Pose(0.0, 0.0, 0.0)
    r.mem.called_on = 0
    r.mem.lobby_walls = {0: BUTTON_WALL, 1: LEFT_WALL, -1: RIGHT_WALL}
    return r


def test_a_way_that_opens_on_no_wall_of_the_lobby_is_no_car_door() -> None:
    # Someone who stood in the lobby's entry, across from the button, walked off: a way
    # opened there. The robot went to a "car door" there again and again (23006).
    r = _waiting()
    pose = Pose(-1.0, 0.0, 0.0)
    assert r.place_car_door(pose, math.pi, 2.5) is None
    # The robot stood beside a person who walked off along the lobby: no wall there either.
    assert r.place_car_door(pose, math.radians(60), 1.0) is None


def test_a_car_door_is_placed_on_the_known_wall_it_opened_in() -> None:
    r = _waiting()
    pose = Pose(-1.0, 0.0, 0.0)
    # On the left end wall, seen aslant: placed where the bearing meets the wall's line.
    bearing = math.atan2(4.0, 1.0)
    placed = r.place_car_door(pose, bearing, 4.0)
    assert placed is not None
    (x, y), heading = placed
    assert abs(y - 4.0) < 1e-9
    assert abs(x - 0.0) < 1e-9
    assert abs(heading - math.pi / 2) < 1e-9, "faces into the car: towards the end wall"
    # On the button's wall beside the button, the shut door read a little short (aslant).
    bearing = math.atan2(-2.0, 1.5)
    placed = r.place_car_door(pose, bearing, 2.2)
    assert placed is not None
    (x, y), heading = placed
    assert abs(x - 0.5) < 1e-9
    assert heading == 0.0


def test_a_door_near_a_corner_goes_on_the_wall_its_reading_fits_best() -> None:
    # Near the corner both walls' lines are near the bearing: the shut reading decides.
    r = _waiting()
    pose = Pose(-0.5, 2.0, 0.0)
    bearing = math.atan2(2.0, 0.8)  # to (0.3, 4.0): on the left end wall
    placed = r.place_car_door(pose, bearing, math.hypot(0.8, 2.0))
    assert placed is not None
    assert placed[1] == LEFT_WALL[2]


def test_without_the_end_wall_known_a_door_on_that_side_is_the_best_guess() -> None:
    r = _waiting()
    del r.mem.lobby_walls[1]
    placed = r.place_car_door(Pose(-1.0, 0.0, 0.0), math.atan2(4.0, 1.0), 4.12)
    assert placed is not None
    assert abs(placed[1] - math.pi / 2) < 1e-9, "a door on the end wall on its side"


def _wall_across(ahead: float) -> list[float]:
    """Sonar readings of a wall square across sonar 0's axis, ``ahead`` m away."""
    ranges = [4.0] * SONARS
    for k in (-2, -1, 0, 1, 2):
        ranges[k % SONARS] = ahead / math.cos(math.radians(15 * k))
    return ranges


def test_end_walls_are_noted_walking_along_the_button_wall() -> None:
    r = robot()
    r.mem.called_from, r.mem.called_on = Pose(0.0, 0.0, 0.0), 0
    r.rule_name = "wait for car"
    # Walking to the left (+y), sonar 0 reads the end wall 2.5 m ahead.
    r.remember(senses(10.0, pose=Pose(-1.0, 1.0, math.pi / 2), sonar=_wall_across(2.5)))
    wall = r.mem.lobby_walls[1]
    assert abs(wall[1] - 3.5) < 1e-9
    assert abs(wall[2] - math.pi / 2) < 1e-9
    assert -1 not in r.mem.lobby_walls


def test_someone_standing_near_is_no_end_wall() -> None:
    # A person a metre away fills three sonars' view and read as a wall (22001): the end
    # wall was put 3 m short of where it is, and real car doors were taken for no car's.
    r = robot()
    r.mem.called_from, r.mem.called_on = Pose(0.0, 0.0, 0.0), 0
    r.rule_name = "wait for car"
    near = END_WALL_FROM_M - 0.5
    r.remember(senses(10.0, pose=Pose(-1.0, 1.0, math.pi / 2), sonar=_wall_across(near)))
    assert 1 not in r.mem.lobby_walls


def test_the_button_wall_is_the_mean_of_its_last_fits_not_the_heading() -> None:
    # Come to the button aslant, the robot pushes it 40 degrees off square; the button's
    # wall was taken as square to its heading, and every car door placed wrong (23017).
    r = robot()
    wall_heading = math.radians(180)
    t = 0.0
    for k in range(10):  # homing: the wall ahead, the barcode 1.2 m away, on it
        t = 0.1 * k
        heading = wall_heading - math.radians(40)
        fit = wall_heading - heading + math.radians(3 if k % 2 else -3)
        r.remember(
            senses(
                t,
                pose=Pose(1.0, 0.0, heading),
                barcodes={30: (wall_heading - heading, 1.2)},
                wall={"seen": True, "normal": fit, "distance": 1.2 * math.cos(math.radians(3))},
            )
        )
    r.rule_name = "push call"
    r.remember(senses(t + 0.1, pose=Pose(1.0, 0.0, heading), presses=1))
    assert r.mem.called_from is not None
    assert abs(math.remainder(r.mem.called_from.theta - wall_heading, math.tau)) < 0.01


def test_a_fit_the_button_is_not_on_is_another_wall() -> None:
    r = robot()
    r.remember(
        senses(
            0.0,
            barcodes={30: (0.0, 1.0)},
            wall={"seen": True, "normal": 1.2, "distance": 0.6},  # a side wall
        )
    )
    assert r.mem.button_walls == []


def test_homing_to_push_drops_runaway_for_the_last_metre() -> None:
    # Runaway keeps the robot 0.3 m off the wall it must come within 0.2 m of: come aslant,
    # it held the robot short of the button for a minute at a time (23017, 23016).
    r = robot()
    far = r.home_on_button(senses(0.0, barcodes={30: (0.3, BUTTON_LAST_M + 0.5)}))
    near = r.home_on_button(senses(0.1, barcodes={30: (0.3, BUTTON_LAST_M - 0.3)}))
    assert "runaway" in far.skills
    assert "runaway" not in near.skills
    assert "home" in near.skills
    # On the goal floor the robot stops a metre short: runaway stays on.
    r.stops = [("lobby", 0)]
    assert "runaway" in r.home_on_button(senses(0.2, barcodes={30: (0.3, 0.8)})).skills


def _riding_out(r: Reactive) -> None:
    r.mem.out_of_lab, r.mem.in_car, r.mem.called_on = True, True, 0
    r.mem.pressed_floor, r.mem.turned_in_car = 0, True
    r.mem.door_heading = math.pi
    r.mem.car_door_ahead = 1.0
    r.stops = [("lobby", 0)]
    r.rule_name = "leave car"


def test_a_car_left_only_to_the_doorway_is_not_left() -> None:
    # Someone outside the door: std.leave_car stopped in the doorway, and the robot took
    # itself for out, went for the button, was pushed back in by the jamb and shut in the
    # car for the rest of the run (23012).
    r = robot()
    _riding_out(r)
    start = Pose(0.0, 0.0, math.pi)
    assert r.leave_car(senses(0.0, pose=start)).skills == ("runaway", "leave_car")
    doorway = Pose(-1.1, 0.0, math.pi)
    r.remember(senses(5.0, pose=doorway, car_exited=True))
    assert r.mem.in_car, "the robot's back is still in the doorway"
    action = r.leave_car(senses(5.1, pose=doorway))
    assert action.skills[-1] == "home_position", "on out the way it went"
    assert action.params[("home_position", "x")] < -1.0 - 0.5, "past the door by its radius"
    out = Pose(-1.5, 0.0, math.pi)
    r.remember(senses(9.0, pose=out))
    assert not r.mem.in_car
    assert r.mem.leave_from is None
    assert not r.mem.exit_stopped


def test_a_car_left_all_the_way_is_left_at_once() -> None:
    r = robot()
    _riding_out(r)
    r.leave_car(senses(0.0, pose=Pose(0.0, 0.0, math.pi)))
    r.remember(senses(6.0, pose=Pose(-3.0, 0.0, math.pi), car_exited=True))
    assert not r.mem.in_car


def test_the_patrol_goes_to_a_metre_short_of_each_end_wall() -> None:
    r = _waiting()
    r.rule_name = "wait for car"
    left = r.wait_for_car(senses(0.0, pose=Pose(-1.0, 0.0, 0.0)))
    assert abs(left.params[("home_position", "y")] - (4.0 - PATROL_END_M)) < 1e-9
    # There: the next leg goes the other way, to a metre short of the right end wall.
    right = r.wait_for_car(senses(5.0, pose=Pose(-1.0, 4.0 - PATROL_END_M, 0.0)))
    assert abs(right.params[("home_position", "y")] - (-3.0 + PATROL_END_M)) < 1e-9
    # End walls not known yet: `PATROL_HALF_M` from the button.
    r.mem.lobby_walls = {}
    r.mem.patrol_leg = 0
    first = r.wait_for_car(senses(6.0, pose=Pose(-1.0, 0.0, 0.0)))
    assert abs(first.params[("home_position", "y")] - PATROL_HALF_M) < 1e-9


def test_riding_with_the_front_sonar_dead_the_door_is_watched_with_a_live_one() -> None:
    # Sonar 0 dead (the hard set's seed 24000): the sonar filter fills it in with the nearer
    # of its neighbours, which see the car's jambs. The door never read open on the goal
    # floor, and the robot rode the car for the rest of the run.
    r = robot()
    m = r.mem
    m.in_car, m.pressed_floor, m.door_heading = True, r.stop_floor(), 0.0
    action = r.ride(senses(1.0, dead=1))
    assert action.params[("turn", "angle")] == -2 * math.pi / SONARS
    assert not m.turned_in_car
    turned = Pose(0.0, 0.0, -2 * math.pi / SONARS)  # sonar 1 (15 degrees left) ahead
    r.ride(senses(2.0, pose=turned, dead=1))
    assert m.turned_in_car
    jambs = [1.5] * SONARS
    jambs[1] = 4.0  # through the open door
    assert r.car_arrived(senses(3.0, pose=turned, sonar=jambs, dead=1, floor=r.stop_floor()))
    filled = [1.5] * SONARS
    filled[0] = 4.0
    assert not r.car_arrived(senses(3.0, pose=turned, sonar=filled, dead=1, floor=r.stop_floor()))
