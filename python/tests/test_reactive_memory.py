"""The reactive robot's memory (demo/courier/reactive): beliefs it must drop, stalls it must notice.

Pure tests of `Reactive.remember` and the rules' actions on made-up senses: no link, no
simulator (the controller is built without a robot; nothing here sends anything). The
behaviour in the simulator is covered by `test_demo.py`'s reactive runs.
"""

from __future__ import annotations

import math
from typing import Any

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.geometry import SONARS, Pose, wrap
from courier.mission import HINT_DOOR_ASIDE_M
from courier.reactive.car import PANEL_LOST_S, PATROL_MAX_M
from courier.reactive.door import DOOR_PUSHES
from courier.reactive.route import DOOR_STANDOFF
from courier.reactive.rules import SIGHTING_SHORT_M, STUCK_S, Reactive
from courier.reactive.state import RouteState
from reactive_support import robot as _robot
from reactive_support import senses as _senses


def test_a_car_whose_panel_never_shows_is_no_car() -> None:
    # Taken for a car (walls all round where a car was called: a corner with people round
    # the robot, say), the robot looked for the car's panel for good. Now the belief goes.
    r = _robot()
    r.mem.out_of_lab, r.mem.in_car, r.mem.called_on = True, True, 0
    r.mem.panel_seen_at = 100.0
    r.remember(_senses(100.0 + PANEL_LOST_S - 1))
    assert r.mem.in_car, "a turn or two to find the panel"
    r.remember(_senses(100.0 + PANEL_LOST_S + 1))
    assert not r.mem.in_car
    assert r.mem.called_on is None, "else walls all round would make it a car again at once"


def test_a_car_whose_panel_shows_stays_a_car() -> None:
    r = _robot()
    r.mem.out_of_lab, r.mem.in_car = True, True
    r.mem.panel_seen_at = 0.0
    for t in range(0, int(3 * PANEL_LOST_S), 5):
        r.remember(_senses(float(t), car=1 if t % 20 == 0 else 0))
    assert r.mem.in_car
    # Riding (the floor pushed), the robot faces the door, not the panel: no check then.
    r.mem.pressed_floor = 2
    r.remember(_senses(10 * PANEL_LOST_S))
    assert r.mem.in_car


def _following(r: Reactive, step: int) -> None:
    r.rule_name = "to office"
    r.mem.out_of_lab = True
    r.mem.route = RouteState("button_to_office", step=step, stage="follow", start=Pose(0, 0, 0))
    r.mem.route.trail = [(0.0, 0.0, 0.0)]


def test_a_stall_while_following_a_corridor_gets_the_robot_unstuck() -> None:
    # Wedged in a room's doorway while following the corridor, the robot stood for 1300 s.
    r = _robot()
    _following(r, step=1)
    assert r.mem.route is not None
    r.mem.route.progress_at = 500.0
    r.remember(_senses(500.0))
    r.remember(_senses(500.0 + STUCK_S / 2, pose=Pose(0.3, 0.0, 0.0)))
    assert r.mem.unstick_to is None
    r.remember(_senses(500.0 + STUCK_S + 1, pose=Pose(0.4, 0.1, 0.0)))
    assert r.mem.unstick_to is not None
    assert r.stuck(_senses(500.0 + STUCK_S + 2, pose=Pose(0.4, 0.1, 0.0)))


def test_following_into_a_room_and_round_it_goes_back_along_the_way() -> None:
    # Pushed round people into a room's doorway, the hallway follower took the robot round
    # the room for the rest of the half hour: it moved all the time, but made no way.
    r = _robot()
    _following(r, step=1)
    rs = r.mem.route
    assert rs is not None
    rs.heading, rs.progress_at = 0.0, 100.0
    r.mem.route = rs
    t = 100.0
    for k in range(21):  # 5 m along the corridor
        rs.start = Pose(0, 0, 0)
        r.route_action(_senses(t, pose=Pose(0.25 * k, 0.0, 0.0)))
        r.remember(_senses(t, pose=Pose(0.25 * k, 0.0, 0.0)))
        t += 1.0
    assert rs.trail[-1][0] == 5.0
    # Round the room beside the corridor: more than a metre every minute, no new way.
    room = [Pose(4.5, -1.5, -1.6), Pose(3.5, -3.0, 3.1), Pose(4.5, -2.0, 1.6)]
    for k in range(int(STUCK_S) + 2):
        r.remember(_senses(t + k, pose=room[k % 3]))
    assert r.mem.unstick_to == (4.0, 0.0)  # where it had made a metre less way
    action = r.get_unstuck(_senses(t + STUCK_S + 3, pose=room[0]))
    assert "avoid" in action.skills


def test_waiting_at_a_door_on_the_route_is_no_stall() -> None:
    # A door closed for a while: the robot waits in front of it on purpose.
    r = _robot()
    _following(r, step=4)  # the `pass` step
    r.remember(_senses(500.0))
    r.remember(_senses(500.0 + 2 * STUCK_S))
    assert r.mem.unstick_to is None


def test_waiting_for_a_car_walks_back_without_turning_round() -> None:
    # Turning in place starts the door watcher afresh, so a car's door that opens while the
    # robot turns round at the end of a leg is missed (a car already on the floor opens at
    # once). The way back is backed up.
    r = _robot()
    r.mem.called_from = Pose(0.0, 0.0, math.pi / 2)
    r.rule_since = 0.0
    action = r.wait_for_car(_senses(20.0))
    assert action.params[("home_position", "reverse_within")] >= 2 * PATROL_MAX_M


def _place(
    r: Reactive, t0: float, opening: dict[str, Any], cycles: int = 6, pose: Pose | None = None
) -> float:
    """Shows ``opening`` for ``cycles`` cycles (0.1 s apart) from ``t0``; returns the time after."""
    t = t0
    for _ in range(cycles):
        r.pass_door_action(_senses(t, opening=opening, pose=pose or Pose(0.0, 0.0, 0.0)))
        t = round(t + 0.1, 6)
    return t


DOOR_AHEAD = {"seen": True, "width": 1.2, "normal": 0.0, "x": 1.5, "y": 0.0}


def test_a_door_is_placed_only_from_an_opening_seen_steadily() -> None:
    # A sonar that lost its echo for one cycle (or a dead one the filter had not found yet)
    # shows an opening beside the barcode for a moment; the robot went there, into the wall.
    r = _robot()
    t = _place(r, 10.0, DOOR_AHEAD, cycles=3)
    assert r.mem.door_goal is None  # not seen long enough yet
    glitch = {**DOOR_AHEAD, "y": 1.7, "width": 0.7}
    r.pass_door_action(_senses(t, opening=glitch))
    assert r.mem.door_goal is None
    _place(r, round(t + 0.1, 6), DOOR_AHEAD)
    assert r.mem.door_goal is not None
    gx, gy, heading = r.mem.door_goal
    assert math.hypot(gx - 0.6, gy) < 0.01
    assert abs(heading) < 0.01


def test_a_door_placed_anew_from_the_doorway_far_from_where_it_was_is_not_taken() -> None:
    # Stopped in the office's doorway (a door closing, someone in the way), the robot looked
    # again and took the corridor behind it for the door: it went through, said its message
    # there, and ended its mission out of the office.
    r = _robot()
    _place(r, 10.0, DOOR_AHEAD)
    assert r.mem.door_goal is not None
    assert r.mem.door_first == r.mem.door_goal
    # Passing, it stopped in the doorway, and went on three times: the door is placed anew.
    r.mem.door_stage, r.mem.door_pushes = "pass", DOOR_PUSHES
    assert not r.through_door(_senses(20.0, pose=Pose(1.3, 0.0, 0.0), door_passed=True))
    assert r.mem.door_goal is None
    assert r.mem.door_after_pass
    # The same door, seen from a little aside: taken.
    _place(r, 30.0, {**DOOR_AHEAD, "y": 0.3})
    assert r.mem.door_goal is not None
    r.mem.door_stage, r.mem.door_pushes = "pass", DOOR_PUSHES
    assert not r.through_door(_senses(40.0, pose=Pose(1.3, 0.0, 0.0), door_passed=True))
    # An opening off to the left, facing another way (the corridor): not the door.
    behind = {"seen": True, "width": 1.5, "normal": math.pi / 2, "x": 0.0, "y": 1.8}
    t = _place(r, 50.0, behind, cycles=5)
    action = r.pass_door_action(_senses(t, opening=behind))
    assert r.mem.door_goal is None
    assert action.key == "wait for opening"


def test_a_door_placed_wrong_at_first_is_placed_anew_in_front_of_it() -> None:
    # The first placement came from a dead sonar the filter had not found yet: off to one
    # side. Checked in front of it, the opening is elsewhere; that placement is taken (before
    # the fix it was held to the first one, and the robot waited at the wall for good).
    r = _robot()
    _place(r, 10.0, {**DOOR_AHEAD, "y": 0.5})
    assert r.mem.door_goal is not None
    # There and facing it: the check sees the opening 1.3 m to the right.
    r.mem.door_stage = "check"
    right = {**DOOR_AHEAD, "y": -1.3}
    _place(r, 20.0, right, cycles=7)
    assert r.mem.door_goal is not None
    gy = r.mem.door_goal[1]
    assert abs(gy - -1.3) < 0.01, r.mem.door_goal
    assert r.mem.door_first == r.mem.door_goal


def test_a_junction_at_a_corner_turns_at_the_wall() -> None:
    # The junction counted was the corridor's end turning off (an L): the robot could not
    # go on into its middle before turning, and stood at the wall for good.
    r = _robot()
    _following(r, step=1)
    r.mem.route = RouteState(
        "button_to_office", step=1, stage="follow", start=Pose(0, 0, 0), heading=0.0
    )
    step = {"follow": "hallway", "until": "junction", "side": "right", "count": 1, "turn": "right"}
    rs = r.mem.route
    # A corridor: walls 1 m either side, open ahead and behind.
    corridor = [
        4.0 if min(i, SONARS - i) <= 2 or abs(i - SONARS // 2) <= 2 else 1.0 for i in range(SONARS)
    ]
    right_open = list(corridor)
    for k in range(-2, 3):
        right_open[(3 * SONARS // 4 + k) % SONARS] = 3.5
    assert not r.step_until_met(step, rs, _senses(1.0, pose=Pose(0.1, 0, 0), sonar=corridor))
    assert r.step_until_met(step, rs, _senses(2.0, pose=Pose(0.6, 0, 0), sonar=right_open)) is False
    assert rs.count == 1
    # Not yet 0.7 m on, but the wall across is there: turn now.
    walled = list(right_open)
    for k, reading in ((-2, 0.69), (-1, 0.62), (0, 0.6), (1, 0.62), (2, 0.69)):
        walled[k % SONARS] = reading
    assert r.step_until_met(step, rs, _senses(3.0, pose=Pose(0.8, 0, 0), sonar=walled))


def test_a_call_button_seen_from_afar_and_lost_is_gone_back_to() -> None:
    # The robot saw the lobby's button 4 m off, then lost it (someone stepped in front): it
    # wandered off across the floor and never came back in the half hour left.
    r = _robot()
    r.mem.out_of_lab = True
    r.remember(_senses(10.0, barcodes={30: (0.0, 4.0)}))
    action = r.look_for_button(_senses(11.0, pose=Pose(0.5, 0.0, 0.0)))
    assert "home_position" in action.skills
    assert action.params[("home_position", "x")] == 4.0 - SIGHTING_SHORT_M
    # There, facing it, and still not in view: forgotten, and the search takes over.
    there = _senses(20.0, pose=Pose(4.0 - SIGHTING_SHORT_M, 0.0, 0.0))
    action = r.look_for_button(there)
    assert 0 not in r.mem.button_at
    assert "home_position" not in action.skills


def test_a_wall_across_the_way_counts_with_the_robot_turned_along_it() -> None:
    # At the end of a corridor (a T), the hallway follower turned the robot into one of the
    # ways off it. The wall across the way was then beside the robot, not ahead, and the
    # robot followed on, into a room's door, and round the room until the time was up.
    r = _robot()
    _following(r, step=1)
    rs = r.mem.route
    assert rs is not None
    rs.heading = -math.pi / 2  # the way: south
    # Facing east at the T: the wall across (south) is on the robot's right, 0.8 m off.
    at_t = [4.0] * SONARS
    for k, reading in ((-2, 0.93), (-1, 0.83), (0, 0.8), (1, 0.83), (2, 0.93)):
        at_t[(3 * SONARS // 4 + k) % SONARS] = reading
    assert r.wall_across(rs, _senses(1.0, pose=Pose(0.0, 0.0, 0.0), sonar=at_t))
    # Someone standing in the way, a metre off, is no wall: the sonars 30 degrees off miss them.
    person = [4.0] * SONARS
    for k in (-1, 0, 1):
        person[(3 * SONARS // 4 + k) % SONARS] = 1.0
    assert not r.wall_across(rs, _senses(1.5, pose=Pose(0.0, 0.0, 0.0), sonar=person))
    # In the corridor, facing east round someone: the sonars along the way see down it.
    corridor = [1.0 if i in (0, 1, SONARS - 1) else 4.0 for i in range(SONARS)]
    assert not r.wall_across(rs, _senses(2.0, pose=Pose(0.0, 0.0, 0.0), sonar=corridor))


def test_the_way_out_of_the_lab_starts_from_the_heading_through_its_door() -> None:
    # Centring between the jambs turned the robot 50 degrees at the end of the door, and the
    # route's first turn, taken from there, sent it along the corridor's wall into a dead end.
    r = _robot()
    r.rule_name = "pass lab door"
    r.mem.door_goal, r.mem.door_stage = (0.0, 0.0, math.pi / 2), "pass"
    r.remember(_senses(10.0, pose=Pose(-0.3, 1.9, math.pi / 2 + 0.9), door_passed=True))
    assert r.mem.out_of_lab
    assert r.mem.passed_heading == math.pi / 2


def test_stopped_in_a_doorway_the_robot_waits_for_the_way_to_clear_and_goes_on() -> None:
    # Someone beyond the lab's door stopped the robot in the doorway. It placed the door anew
    # from in there, where the door finder sees no wall to find it in, and turned to and fro
    # in the doorway until the time was up.
    r = _robot()
    r.mem.door_goal, r.mem.door_stage = (0.0, 0.0, 0.0), "pass"
    assert not r.through_door(_senses(10.0, pose=Pose(1.0, 0.0, 0.0), door_passed=True))
    assert r.mem.door_goal == (0.0, 0.0, 0.0)
    blocked = [0.6] + [4.0] * (SONARS - 1)
    wait = r.pass_door_action(_senses(11.0, pose=Pose(1.0, 0.0, 0.0), sonar=blocked))
    assert wait.skills == ("runaway",)
    clear = [4.0] * SONARS
    on = r.pass_door_action(_senses(15.0, pose=Pose(1.0, 0.0, 0.0), sonar=clear))
    assert on.skills == ("runaway", "pass_door")
    # Through at last: beyond the door's line.
    r.mem.door_stage = "pass"
    assert r.through_door(_senses(25.0, pose=Pose(2.0, 0.0, 0.0), door_passed=True))


def _lab_door_robot() -> Reactive:
    """In the lab facing +x; the lab door's barcode on the wall x = 1 (at y = 0.8), noted."""
    r = _robot()
    r.mem.lab_door_at = (1.0, 0.8)
    r.mem.lab_door_walls = [0.0] * 5
    return r


def test_the_lab_door_barcodes_wall_is_noted_only_through_the_barcode() -> None:
    r = _robot()
    on = {"seen": True, "normal": 0.2, "distance": 2.0}
    r.remember(_senses(1.0, pose=Pose(0.0, 0.0, 0.5), barcodes={10: (0.2, 2.0)}, wall=on))
    assert r.mem.lab_door_walls == [0.7]
    # A wall fitted through clutter in front of the barcode (0.5 m nearer): not its wall.
    off = {**on, "distance": 1.5}
    r.remember(_senses(1.1, pose=Pose(0.0, 0.0, 0.5), barcodes={10: (0.2, 2.0)}, wall=off))
    assert r.mem.lab_door_walls == [0.7]
    # Near the barcode, the few echoes round it are its door's jamb as much as its wall: a
    # line fitted through them, square to the way the robot homed in, put the door 37 degrees
    # off (24012).
    near = {"seen": True, "normal": 0.0, "distance": 1.1}
    r.remember(_senses(1.2, pose=Pose(0.0, 0.0, 0.5), barcodes={10: (0.0, 1.1)}, wall=near))
    assert r.mem.lab_door_walls == [0.7]


def test_an_opening_off_the_lab_door_barcode_is_not_its_door_the_robot_lines_up() -> None:
    # Homed on the barcode aslant, the robot stood in the doorway and took the corridor
    # beyond for the door: it "passed" it along the corridor and followed the route from
    # there, up and down the corridor for the rest of the run (24000, 24024).
    r = _lab_door_robot()
    corridor = {"seen": True, "width": 1.2, "normal": math.pi / 2, "x": 0.3, "y": 1.5}
    t = _place(r, 10.0, corridor)
    action = r.pass_door_action(_senses(t, opening=corridor))
    assert r.mem.door_goal is None
    assert r.mem.door_stage == "line up"
    # To 1 m square in front of the barcode, whatever the robot sees on the way.
    assert action.params[("home_position", "x")] == 0.0
    assert action.params[("home_position", "y")] == 0.8
    assert r.at_lab_door(_senses(t))  # the barcode out of view: still the rule's
    # There, facing the wall: lined up, the door beside the barcode is taken.
    r.pass_door_action(_senses(20.0, pose=Pose(0.0, 0.8, 0.0)))
    assert r.mem.door_stage == ""
    assert r.mem.door_lined_up
    door = {"seen": True, "width": 1.0, "normal": 0.0, "x": 1.0, "y": -0.6}
    _place(r, 30.0, door, cycles=7, pose=Pose(0.0, 0.8, 0.0))
    assert r.mem.door_goal is not None
    gx, gy, heading = r.mem.door_goal
    assert math.hypot(gx - 0.1, gy - 0.2) < 0.01
    assert abs(heading) < 0.01


def test_a_lab_door_placed_aslant_of_its_barcodes_wall_is_not_taken() -> None:
    # Beside the barcode, but 35 degrees off square to its wall: the jambs seen askew from
    # the doorway (24012). Taken only with the wall not known.
    aslant = {"seen": True, "width": 1.0, "normal": 0.6, "x": 1.0, "y": 0.2}
    r = _lab_door_robot()
    _place(r, 10.0, aslant, cycles=7)
    assert r.mem.door_goal is None
    assert r.mem.door_stage == "line up"
    r = _lab_door_robot()
    r.mem.lab_door_walls = []
    _place(r, 10.0, aslant, cycles=7)
    assert r.mem.door_goal is not None


def test_out_of_the_lab_a_door_is_not_held_to_the_lab_doors_barcode() -> None:
    # The office door is passed by the same action: held to the lab door's barcode, far
    # behind, every office door was "not its door", and no office task was done.
    r = _lab_door_robot()
    r.mem.out_of_lab = True
    aslant = {"seen": True, "width": 1.0, "normal": 0.6, "x": 3.0, "y": 2.0}
    _place(r, 10.0, aslant, cycles=7)
    assert r.mem.door_goal is not None


def test_a_door_not_in_sight_is_tried_by_the_hint_then_squared_up_to_again() -> None:
    # No door showed beside the office's barcode (a wide one, seen too obliquely from in front
    # of it): the robot stood there for the rest of the run (24003). And back to homing on the
    # barcode, the route's heading was the wall's normal (squaring set it), and the side of the
    # wall was read against it: the robot squared facing along the wall, not at it.
    r = _robot()
    _following(r, step=3)
    rs = r.mem.route
    assert rs is not None
    rs.heading = 0.0  # the corridor runs east; the office's barcode is on its north wall
    facing_it = _senses(10.0, pose=Pose(0.0, 0.0, math.pi / 2), barcodes={40: (0.0, 1.0)})
    r.route_action(facing_it)
    assert rs.stage == "square"
    assert rs.heading == math.pi / 2
    assert rs.square_at is not None
    assert abs(rs.square_at[1] - (1.0 - DOOR_STANDOFF)) < 1e-9
    # Squared: on to the door, which does not show. Given up on, it is placed where the
    # route's hint (its last turn: left) says, once, as the sequenced robot does.
    r.route_action(_senses(11.0, pose=Pose(0.0, 1.0 - DOOR_STANDOFF, math.pi / 2)))
    assert rs.step == 4
    r.mem.door_given_up_at = 40.0
    r.route_action(_senses(40.5, pose=Pose(0.0, 0.1, math.pi / 2)))
    assert r.mem.door_goal is not None
    assert r.mem.door_stage == "goto"
    gx, gy, gh = r.mem.door_goal
    assert abs(gx - -HINT_DOOR_ASIDE_M) < 1e-9
    assert abs(gy - (0.1 + 1.0 - DOOR_STANDOFF)) < 1e-9
    assert gh == math.pi / 2
    # Not tried from elsewhere (stopped in the doorway, say): only from where it squared up.
    other = _robot()
    _following(other, step=4)
    assert other.mem.route is not None
    other.mem.route.heading, other.mem.route.square_at = math.pi / 2, (0.0, 0.1)
    other.mem.door_given_up_at = 40.0
    other.route_action(_senses(40.5, pose=Pose(-0.6, 0.8, math.pi / 2 + 0.5)))
    assert other.mem.door_goal is None
    assert other.mem.route.step == 3
    # The same give-up is handled once only.
    r.route_action(_senses(40.7, pose=Pose(0.0, 0.1, math.pi / 2)))
    assert rs.step == 4
    # Given up on again: back to the barcode's step, with the corridor's heading.
    r.mem.door_given_up_at = 120.0
    r.route_action(_senses(120.5, pose=Pose(0.0, 0.1, math.pi / 2)))
    assert rs.step == 3
    assert rs.heading == 0.0
    # Homed on it again: squares facing the wall again.
    r.route_action(_senses(130.0, pose=Pose(0.0, 0.0, math.pi / 2), barcodes={40: (0.0, 1.0)}))
    assert rs.stage == "square"
    assert rs.heading == math.pi / 2


def test_a_route_barcode_lost_while_homing_is_looked_for_square_in_front_of_its_wall() -> None:
    # Homing on the office's barcode brought the robot near its wall, where it was seen too
    # obliquely to read; the robot wandered for the rest of the half hour (24016).
    r = _robot()
    r.mem.route = RouteState("button_to_office", step=3, heading=math.pi)  # the home step
    seen = (wrap(math.atan2(-1.0, -3.0) - math.pi), math.hypot(1.0, 3.0))
    r.route_action(_senses(1.0, pose=Pose(0.0, 0.0, math.pi), barcodes={40: seen}))
    lost = r.route_action(_senses(2.0, pose=Pose(-2.5, -0.6, -2.0)))
    assert lost.key[0] == "to lost barcode"
    # On the corridor's wall on the left (facing west): 1.2 m north of it, facing south.
    assert abs(lost.params[("home_position", "x")] - -3.0) < 1e-9
    assert abs(lost.params[("home_position", "y")] - 0.2) < 1e-9
    there = r.route_action(_senses(3.0, pose=Pose(-3.0, 0.2, -math.pi / 2)))
    assert r.mem.route.code_at is None  # not in view from in front of it: forgotten
    assert there.key[0] in ("look", "wander")
    # The side is the one it was seen from: lost from beyond the wall's line (stopped in the
    # door's mouth, say), the search still goes to the corridor's side.
    r.route_action(_senses(3.5, pose=Pose(0.0, 0.0, math.pi), barcodes={40: seen}))
    lost = r.route_action(_senses(3.6, pose=Pose(-3.5, -1.4, math.pi / 2)))
    assert abs(lost.params[("home_position", "y")] - 0.2) < 1e-9
    # Lost again after a "door again", the route's heading is the wall's normal: the search
    # still goes square in front of the wall, along the corridor's heading kept.
    r.mem.route.along, r.mem.route.heading = math.pi, -math.pi / 2
    r.route_action(_senses(4.0, pose=Pose(0.0, 0.0, math.pi), barcodes={40: seen}))
    lost = r.route_action(_senses(5.0, pose=Pose(-2.5, -0.6, -2.0)))
    assert abs(lost.params[("home_position", "x")] - -3.0) < 1e-9
    assert abs(lost.params[("home_position", "y")] - 0.2) < 1e-9
