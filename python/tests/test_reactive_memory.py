"""The reactive robot's memory (demo/reactive.py): beliefs it must drop, stalls it must notice.

Pure tests of `Reactive.remember` and the rules' actions on made-up senses: no link, no
simulator (the controller is built without a robot; nothing here sends anything). The
behaviour in the simulator is covered by `test_demo.py`'s reactive runs.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "demo"))  # the demo's modules import each other by name

from deliver import Mission  # noqa: E402
from link import SONARS, Pose  # noqa: E402
from reactive import (  # noqa: E402
    PANEL_LOST_S,
    PATROL_HALF_M,
    STUCK_S,
    Reactive,
    Senses,
)
from reactive_route import RouteState  # noqa: E402

ROUTE: dict[str, list[dict[str, Any]]] = {
    "button_to_office": [
        {"turn": "back"},
        {"follow": "hallway", "until": "wall", "turn": "left"},
        {"follow": "hallway", "until": "barcode", "barcode": 40},
        {"home": 40},
        {"pass": "door"},
    ]
}


def _robot() -> Reactive:
    mission = Mission(
        goal_floor=2,
        start_floor=0,
        lab_door_barcode=10,
        call_button_barcode=30,
        office_barcode=50,
        car_barcode_first=201,
        cars=2,
        message="hello",
        route=ROUTE,
        goal_button_barcode=32,
        lobbies={0: 30, 1: 31, 2: 32},
    )
    return Reactive(None, mission, [("office", 2)], quiet=True)  # type: ignore[arg-type]


def _senses(t: float, **kw: Any) -> Senses:
    s: dict[str, Any] = {
        "t": t,
        "pose": Pose(0.0, 0.0, 0.0),
        "sonar": [4.0] * SONARS,
        "barcodes": {},
        "floor": 0,
        "presses": 0,
        "said": 0,
        "junction": {},
        "door": {},
        "opened": {},
        "car": 0,
        "opening": {},
        "wall": {},
        "door_passed": False,
        "car_entered": False,
        "car_exited": False,
    }
    s.update(kw)
    return Senses(**s)


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


def test_a_stall_while_following_a_corridor_gets_the_robot_unstuck() -> None:
    # Wedged in a room's doorway while following the corridor, the robot stood for 1300 s.
    r = _robot()
    _following(r, step=1)
    r.remember(_senses(500.0))
    r.remember(_senses(500.0 + STUCK_S / 2, pose=Pose(0.3, 0.0, 0.0)))
    assert r.mem.unstick_to is None
    r.remember(_senses(500.0 + STUCK_S + 1, pose=Pose(0.4, 0.1, 0.0)))
    assert r.mem.unstick_to is not None
    assert r.stuck(_senses(500.0 + STUCK_S + 2, pose=Pose(0.4, 0.1, 0.0)))


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
    assert action.params[("home_position", "reverse_within")] >= 2 * PATROL_HALF_M


def test_a_door_placed_anew_far_from_where_it_was_found_is_not_taken() -> None:
    # Stopped in the office's doorway (a door closing, someone in the way), the robot looked
    # again and took the corridor behind it for the door: it went through, said its message
    # there, and ended its mission out of the office.
    r = _robot()
    opening = {"seen": True, "width": 1.2, "normal": 0.0, "x": 1.5, "y": 0.0}
    first = r.pass_door_action(_senses(10.0, opening=opening))
    assert r.mem.door_goal is not None
    assert r.mem.door_first == r.mem.door_goal
    assert first.skills == ("runaway", "home_position")
    # Stopped short: the door is placed anew from where the robot stands.
    r.mem.door_goal, r.mem.door_stage = None, ""
    # The same door, seen from a little aside: taken.
    r.pass_door_action(_senses(20.0, opening={**opening, "y": 0.3}))
    assert r.mem.door_goal is not None
    r.mem.door_goal, r.mem.door_stage = None, ""
    # An opening off to the left, facing another way (the corridor): not the door.
    behind = {"seen": True, "width": 1.5, "normal": math.pi / 2, "x": 0.0, "y": 1.8}
    action = r.pass_door_action(_senses(30.0, opening=behind))
    assert r.mem.door_goal is None
    assert action.key == "wait for opening"


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
    for k in (-1, 0, 1):
        walled[k % SONARS] = 0.6
    assert r.step_until_met(step, rs, _senses(3.0, pose=Pose(0.8, 0, 0), sonar=walled))
