"""The reactive robot's rules for calling a car, getting in, riding and getting out.

`demo/reactive.py` holds the rule list; its rules from "leave car" to "push call" take their
conditions and actions from `CarRider`, mixed into the controller as `RouteFollower` is.
What the rules keep about cars (called on which floor and when, the car door seen opening,
in a car, the floor pushed) is in the controller's `Memory`; `CarRider.remember_car` updates
it from each cycle's senses.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from link import Pose, wrap
from reactive_route import PUSH_M, Action, goto, turn

if TYPE_CHECKING:
    from deliver import Mission
    from reactive import Memory, Senses

#: Waiting for a car longer than this after calling, the robot calls again, s.
CALL_AGAIN_S = 45.0
#: A car door seen opening this recently is still worth going to, s.
OPENED_FRESH_S = 4.0
#: In front of a car's door that opened, this far from it, before entering, m.
FACE_DOOR_M = 0.85
#: Waiting for a car, the robot walks this far each way along the button's wall, m, this far
#: off it, m, turning back after this long, s.
PATROL_HALF_M = 2.5
PATROL_OFF_M = 1.0
PATROL_LEG_S = 14.0
#: In a car and no panel seen for this long (s; a turn takes 8 s), the robot is not in one.
PANEL_LOST_S = 30.0
#: Facing a car's door, the opening in the wall ahead is this near straight ahead (m), seen
#: within this long (s).
CAR_DOOR_OFF_M = 0.6
CAR_DOOR_LOOK_S = 1.0
#: Going into a car that opened takes at most this long, s.
CAR_ENTER_S = 25.0
#: Pushing a call button, the robot faces its wall within this, rad.
BUTTON_WALL_RAD = 0.5


class CarRider:
    """Calls a car, gets in, rides and gets out; mixed into the reactive controller.

    It uses the controller's memory, mission and rule in charge, and two of its helpers
    (declared below, defined by `reactive.Reactive`).
    """

    mem: Memory
    m: Mission
    debug: bool
    rule_name: str
    rule_since: float

    def stop_floor(self) -> int:
        """The floor of the next stop."""
        raise NotImplementedError

    def button(self, floor: int) -> int:
        """The call button's barcode on ``floor``."""
        raise NotImplementedError

    # ----- conditions ------------------------------------------------------------------------

    def car_arrived(self, s: Senses) -> bool:
        """In the car, on the stop's floor, the door open ahead."""
        return (
            self.mem.in_car
            and self.mem.pressed_floor == self.stop_floor()
            and self.mem.turned_in_car
            and s.floor == self.stop_floor()
            # The door open ahead; once going out, on out (the doors do not close on it).
            and (s.sonar[0] > 2.2 or self.rule_name == "leave car")
        )

    def riding(self, s: Senses) -> bool:
        """In the car, the stop's floor pushed."""
        return self.mem.in_car and self.mem.pressed_floor == self.stop_floor()

    def in_car_to_press(self, s: Senses) -> bool:
        """In a car (the floor not pushed yet)."""
        return self.mem.in_car

    def car_opened(self, s: Senses) -> bool:
        """Called, and a car's door seen opening just now."""
        m = self.mem
        if m.in_car or s.floor == self.stop_floor() or m.opened is None:
            return False
        # Just seen opening; or going in already (committed until in, or until it took too long).
        entering = self.rule_name == "enter car" and s.t - m.opened[0] < CAR_ENTER_S
        return entering or s.t - m.opened[0] < OPENED_FRESH_S

    def waiting_for_car(self, s: Senses) -> bool:
        """Called on this floor, not long ago."""
        m = self.mem
        return (
            not m.in_car
            and s.floor != self.stop_floor()
            and m.called_at is not None
            and s.t - m.called_at < CALL_AGAIN_S
        )

    def at_call_button(self, s: Senses) -> bool:
        """In the lobby, near enough to this floor's call button to push it."""
        return (
            not self.mem.in_car
            and s.floor != self.stop_floor()
            and self.lobby_reached(s)
            # Once pushing, until a bit farther: the reading jitters.
            and s.sees(
                self.button(s.floor), PUSH_M + (0.3 if self.rule_name == "push call" else 0.08)
            )
        )

    def lobby_reached(self, s: Senses) -> bool:
        """This floor's call button was seen since the robot came to this floor."""
        return self.mem.lobby_seen_on == s.floor

    # ----- actions ---------------------------------------------------------------------------

    def leave_car(self, s: Senses) -> Action:
        """Drives out of the car."""
        return Action(("runaway", "leave_car"), key=("leave car", self.mem.exits_tried))

    def ride(self, s: Senses) -> Action:
        """Turns round to face the car's door (the panel's wall behind), then waits."""
        m = self.mem
        if m.door_heading is None:
            normal = float(s.wall["normal"]) if s.wall.get("seen") else 0.0
            m.door_heading = wrap(s.pose.theta + normal + math.pi)
        off = wrap(m.door_heading - s.pose.theta)
        if not m.turned_in_car and abs(off) > 0.08:
            return turn(off, "turn in car", s.t, runaway=True)
        m.turned_in_car = True
        return Action(("runaway",), key="ride")

    def push_floor(self, s: Senses) -> Action:
        """Homes on the car's panel and pushes the stop's floor."""
        if not s.car:
            # The panel (its barcode says which car) not in view: look round for it.
            return turn(2 * math.pi, "look for panel", s.t, every=10)
        code = self.m.car_barcode_first + s.car - 1
        return Action(
            ("runaway", "track_barcode", "home", "push_button"),
            {
                ("track_barcode", "id"): code,
                ("home", "stop_distance"): 0.45,
                ("push_button", "button"): self.stop_floor(),
            },
            key=("push floor", code),
        )

    def enter_car(self, s: Senses) -> Action:
        """Faces the car door seen opening, then drives in."""
        m = self.mem
        assert m.opened is not None
        assert m.car_goal is not None
        gx, gy = m.car_goal
        if m.enter_stage == "goto":
            if math.hypot(s.pose.x - gx, s.pose.y - gy) > 0.15:
                return goto(gx, gy, ("to car", m.opened), speed=0.6)
            m.enter_stage = "face"
        if m.enter_stage == "face":
            off = wrap(m.opened[1] - s.pose.theta)
            if abs(off) > 0.08:
                return turn(off, ("face car", m.opened), s.t)
            o = s.opening
            door_ahead = o.get("seen") and abs(float(o.get("y", 0.0))) < CAR_DOOR_OFF_M
            if m.faced_at is None:
                m.faced_at = s.t
            if not door_ahead and s.t - m.faced_at < CAR_DOOR_LOOK_S:
                return Action(("runaway",), key=("look for car door", m.opened))
            if s.sonar[0] < 1.6 or not door_ahead:
                # No open door ahead: it closed meanwhile, or it was no car's door (someone
                # who stood still and walked off reads as a way opening too, but into the
                # lobby, with no wall ahead for a door to be in).
                m.opened, m.enter_stage = None, ""
                return Action(("runaway",), key="no door ahead")
            m.enter_stage = "in"
        return Action(("runaway", "enter_car"), key=("enter car", m.opened))

    def wait_for_car(self, s: Senses) -> Action:
        """Walks to and fro along the button's wall, a metre off it, watching for a car."""
        # The door watcher sees a door open only roughly face-on: walking along the wall
        # brings each car door on it, and those on the end walls, into view.
        b = self.mem.called_from
        if b is None:
            return Action(("runaway",), key="wait for car")
        leg = int((s.t - self.rule_since) // PATROL_LEG_S)
        along = PATROL_HALF_M * (1 if leg % 2 == 0 else -1)
        n = (math.cos(b.theta), math.sin(b.theta))
        x = b.x - PATROL_OFF_M * n[0] - along * n[1]
        y = b.y - PATROL_OFF_M * n[1] + along * n[0]
        # Back the way it came without turning round: turning starts the door watcher
        # afresh, and a car already on this floor opens while the robot would be turning.
        return goto(x, y, ("wait for car", leg), reverse_within=2 * PATROL_HALF_M + 0.5)

    def push_call(self, s: Senses) -> Action:
        """Homes the last bit to the call button and pushes it."""
        code = self.button(s.floor)
        return Action(
            ("track_barcode", "home", "push_button"),
            {
                ("track_barcode", "id"): code,
                ("home", "stop_distance"): PUSH_M - 0.05,
                ("push_button", "button"): 0,
            },
            key=("push call", code),
        )

    # ----- memory updates from what was sensed -------------------------------------------------

    def remember_car(self, s: Senses) -> None:
        """Updates what the robot keeps about cars from this cycle's senses."""
        m = self.mem
        if s.presses > m.presses_seen:
            m.presses_seen = s.presses
            if self.rule_name == "push call":
                # The button's wall: its normal from the wall ahead, if fitted. The robot
                # homed on the button, so it about faces that wall: a fit farther off is
                # another wall (a side wall near the corner), and the heading is the best guess.
                fitted = float(s.wall["normal"]) if s.wall.get("seen") else 0.0
                normal = fitted if abs(fitted) < BUTTON_WALL_RAD else 0.0
                p = s.pose
                m.called_at, m.called_from = s.t, Pose(p.x, p.y, wrap(p.theta + normal))
                m.called_on = s.floor
            elif self.rule_name == "push floor":
                m.pressed_floor = self.stop_floor()
                m.turned_in_car, m.door_heading = False, None
        fresh = m.opened is not None and s.t - m.opened[0] < CAR_ENTER_S
        if s.opened.get("seen") and m.called_at is not None and not m.in_car and not fresh:
            bearing = wrap(s.pose.theta + float(s.opened.get("bearing", 0.0)))
            before = float(s.opened.get("before", 1.0))
            door, normal = self.place_car_door(s.pose, bearing, before)
            # FACE_DOOR_M in front of the door, square to its wall.
            m.car_goal = (
                door[0] - FACE_DOOR_M * math.cos(normal),
                door[1] - FACE_DOOR_M * math.sin(normal),
            )
            m.opened, m.enter_stage, m.faced_at = (s.t, normal), "goto", None
        if not m.in_car and m.out_of_lab and m.called_on == s.floor and s.enclosed(tight=True):
            # Walls all round, nearer than a car is wide, where a car was called: inside a car
            # (its door shut). Elsewhere it is a closet, or people round the robot.
            m.in_car, m.called_at, m.opened, m.pressed_floor = True, None, None, None
            m.panel_seen_at = s.t
        if s.car_entered and self.rule_name == "enter car" and m.enter_stage == "in":
            if s.enclosed():
                m.in_car, m.called_at, m.opened, m.pressed_floor = True, None, None, None
                m.panel_seen_at = s.t
            else:  # stopped short (the door closed, someone in the way): wait for the next
                m.opened, m.enter_stage = None, ""
        if m.in_car and m.pressed_floor is None:
            # In a car, the panel is in view within a turn or two. Not seen for long: this is
            # no car (a corner, people round the robot) or not the robot's any more.
            if s.car:
                m.panel_seen_at = s.t
            elif s.t - m.panel_seen_at > PANEL_LOST_S:
                if self.debug:
                    print(f"[{s.t:7.1f} s]   no car's panel in {PANEL_LOST_S:.0f} s: not in a car")
                m.in_car, m.called_on = False, None
        if s.car_exited and self.rule_name == "leave car":
            if s.enclosed():  # stopped in the doorway (someone outside): out again
                m.exits_tried += 1
            else:
                m.in_car, m.lobby_seen_on, m.route, m.called_on = False, None, None, None
        if m.called_at is not None and s.t - m.called_at >= CALL_AGAIN_S and not m.in_car:
            m.called_at = None

    def place_car_door(
        self, pose: Pose, bearing: float, before: float
    ) -> tuple[tuple[float, float], float]:
        """Where a car door seen opening is (odometry), and the heading into the car.

        Cars open on the button's wall or on the walls at its ends (docs/maps.md). The robot
        faced the button's wall when it pushed the button. A door on that wall is where the
        sonar's bearing meets the wall's line: seen aslant, the bearing is sure, the range
        (``before``, the reading while it was shut) is not.
        """
        c, sn = math.cos(bearing), math.sin(bearing)
        door = (pose.x + before * c, pose.y + before * sn)
        b = self.mem.called_from
        if b is None:
            return door, bearing
        n = (math.cos(b.theta), math.sin(b.theta))
        button = (b.x + PUSH_M * n[0], b.y + PUSH_M * n[1])
        towards = c * n[0] + sn * n[1]
        if towards > 0.1:
            reach = ((button[0] - pose.x) * n[0] + (button[1] - pose.y) * n[1]) / towards
            if abs(reach - before) < 1.0:
                return (pose.x + reach * c, pose.y + reach * sn), b.theta
        side = (door[0] - pose.x) * -n[1] + (door[1] - pose.y) * n[0]
        return door, wrap(b.theta + (math.pi / 2 if side > 0 else -math.pi / 2))
