"""The reactive robot's rules for calling a car, getting in, riding and getting out.

`rules` holds the rule list; its rules from "leave car" to "push call" take their
conditions and actions from `CarRider`, mixed into the controller as `RouteFollower` is.
What the rules keep about cars (called on which floor and when, the car door seen opening,
in a car, the floor pushed) is in the controller's `Memory`; `CarRider.remember_car` updates
it from each cycle's senses.
"""

from __future__ import annotations

import math
from typing import Any

from courier.geometry import Pose, bearing_of, mean_heading, sonar_toward, wrap
from courier.mission import OPENED_ON_WALL_M, Mission, seen_wall_ends_at
from courier.reactive.route import PUSH_M, Action, goto, turn
from courier.reactive.state import Memory, Senses

#: Waiting for a car longer than this after calling, the robot calls again, s.
CALL_AGAIN_S = 45.0
#: A car door seen opening this recently is still worth going to, s.
OPENED_FRESH_S = 4.0
#: In front of a car's door that opened, this far from it, before entering, m.
FACE_DOOR_M = 0.85
#: Waiting for a car, the robot walks to and fro along the button's wall, this far off it (m),
#: at this speed (m/s): each way to this far short of the end wall (m), this far from the
#: button at most and at least (m), or this far while the end wall is not known (m). A leg
#: ends within `PATROL_THERE_M` of its end (m), or after `PATROL_LEG_S` (s).
PATROL_OFF_M = 1.0
PATROL_SPEED = 0.6
PATROL_END_M = 1.0
PATROL_MAX_M = 4.5
PATROL_MIN_M = 0.5
PATROL_HALF_M = 2.5
PATROL_THERE_M = 0.3
PATROL_LEG_S = 20.0
#: In a car and no panel seen for this long (s; a turn takes 8 s), the robot is not in one.
PANEL_LOST_S = 30.0
#: Facing a car's door, the opening in the wall ahead is this near straight ahead (m), seen
#: within this long (s).
CAR_DOOR_OFF_M = 0.6
CAR_DOOR_LOOK_S = 1.0
#: Going into a car that opened takes at most this long, s.
CAR_ENTER_S = 25.0
#: Pushing a call button, the robot faces its wall within this, rad; a wall fitted farther
#: off is the button's if the button's barcode is on its line (`CODE_ON_WALL_M`).
BUTTON_WALL_RAD = 0.5
#: A barcode this near a fitted wall's line is on that wall (the call button's, the lab
#: door's: `wall_through`), m.
CODE_ON_WALL_M = 0.15
#: The button's wall is fitted from within this of the button (m), and the last this long of
#: fits (s) are averaged.
BUTTON_WALL_SEEN_M = 1.6
BUTTON_WALL_S = 5.0
#: Leaving a car, the robot is out once this far past where its door was ahead (its radius
#: and a margin), m.
OUT_OF_CAR_M = 0.4
#: Waiting for a car, a sonar this near the way along the button's wall reads the wall at
#: that end of the lobby, rad (the sonars are 15 degrees apart).
END_WALL_AIM_RAD = math.radians(8)
#: An end wall is read from this far or more, m: someone nearer fills the neighbours' view
#: too, and reads as a wall (a person about 0.4 m across fills one sonar's from 1.5 m on).
END_WALL_FROM_M = 1.5


def wall_through(code: tuple[float, float], wall: dict[str, Any], within: float) -> float | None:
    """The wall fitted ahead (`std.fit_wall`), if a barcode seen is on it: its normal, rad.

    ``code`` is the barcode's reading (bearing, distance; robot frame). It is on the wall if
    it lies within ``within`` m of the wall's line; the normal is in the robot frame.
    """
    if not wall.get("seen"):
        return None
    fitted = float(wall.get("normal", 0.0))
    off = code[1] * math.cos(code[0] - fitted) - float(wall.get("distance", 0.0))
    return fitted if abs(fitted) < math.pi / 2 and abs(off) < within else None


class CarRider:
    """Calls a car, gets in, rides and gets out; mixed into the reactive controller.

    It uses the controller's memory, mission and rule in charge, and two of its helpers
    (declared below, defined by `rules.Reactive`).
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
            and (s.sonar[s.ahead()] > 2.2 or self.rule_name == "leave car")
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
        """Drives out of the car; stopped short, on out the way it went, once the way is clear.

        `std.leave_car` starts from inside the car, facing the door: started again in the
        doorway, it centres between the jambs and turns the robot along them.
        """
        m = self.mem
        if m.leave_from is None:
            m.leave_from = (s.pose.x, s.pose.y)
        if m.exit_stopped and m.door_heading is not None:
            go = m.car_door_ahead + 1.0
            h = m.door_heading
            gx, gy = m.leave_from[0] + go * math.cos(h), m.leave_from[1] + go * math.sin(h)
            return goto(gx, gy, ("out of car", m.leave_from))
        return Action(("runaway", "leave_car"), key=("leave car", m.leave_from))

    def ride(self, s: Senses) -> Action:
        """Turns round to face the car's door (the panel's wall behind), then waits.

        It faces the door with the live sonar nearest ahead (`Senses.ahead`), as the sequenced
        robot does: a dead sonar reads its neighbours' jambs, and the door never reads open.
        """
        m = self.mem
        if m.door_heading is None:
            normal = float(s.wall["normal"]) if s.wall.get("seen") else 0.0
            m.door_heading = wrap(s.pose.theta + normal + math.pi)
        look = s.ahead()
        off = s.pose.turn_to(m.door_heading - bearing_of(look))
        if not m.turned_in_car and abs(off) > 0.08:
            return turn(off, "turn in car", s.t, runaway=True)
        m.turned_in_car = True
        if s.sonar[look] < 2.2:  # the door shut ahead
            m.car_door_ahead = s.sonar[look]
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
            off = s.pose.turn_to(m.opened[1])
            if abs(off) > 0.08:
                return turn(off, ("face car", m.opened), s.t)
            o = s.opening
            door_ahead = o.get("seen") and abs(float(o.get("y", 0.0))) < CAR_DOOR_OFF_M
            if m.faced_at is None:
                m.faced_at = s.t
            if not door_ahead and s.t - m.faced_at < CAR_DOOR_LOOK_S:
                return Action(("runaway",), key=("look for car door", m.opened))
            if s.sonar[s.ahead()] < 1.6 or not door_ahead:
                # No open door ahead: it closed meanwhile, or it was no car's door (someone
                # who stood still and walked off reads as a way opening too, but into the
                # lobby, with no wall ahead for a door to be in).
                m.opened, m.enter_stage = None, ""
                return Action(("runaway",), key="no door ahead")
            m.enter_stage = "in"
        return Action(("runaway", "enter_car"), key=("enter car", m.opened))

    def wait_for_car(self, s: Senses) -> Action:
        """Walks to and fro along the button's wall, a metre off it, watching for a car.

        The door watcher sees a door open only roughly face-on: walking along the wall brings
        each car door on it, and those on the end walls, into view. Each leg goes to a metre
        short of the end wall ahead, once that is known (`find_end_walls`), else
        `PATROL_HALF_M` from the button; the next begins there, or after `PATROL_LEG_S`.
        """
        m = self.mem
        b = m.called_from
        if b is None:
            return Action(("runaway",), key="wait for car")
        x, y, reach = self.patrol_goal(b)
        if (
            math.hypot(s.pose.x - x, s.pose.y - y) < PATROL_THERE_M
            or s.t - m.patrol_since > PATROL_LEG_S
        ):
            m.patrol_leg, m.patrol_since = m.patrol_leg + 1, s.t
            x, y, reach = self.patrol_goal(b)
        # Back the way it came without turning round: turning starts the door watcher
        # afresh, and a car already on this floor opens while the robot would be turning.
        return goto(
            x,
            y,
            ("wait for car", m.patrol_leg, round(reach, 1)),
            speed=PATROL_SPEED,
            reverse_within=2 * PATROL_MAX_M + 0.5,
        )

    def patrol_goal(self, b: Pose) -> tuple[float, float, float]:
        """Where the patrol's leg ends (odometry), and how far along the wall from the call.

        ``b`` is where the robot called from, facing the button's wall.
        """
        side = 1 if self.mem.patrol_leg % 2 == 0 else -1
        way = wrap(b.theta + side * math.pi / 2)
        reach = PATROL_HALF_M
        end = self.mem.lobby_walls.get(side)
        if end is not None:
            to_end = b.along(end[0], end[1], way)
            reach = max(PATROL_MIN_M, min(PATROL_MAX_M, to_end - PATROL_END_M))
        n = (math.cos(b.theta), math.sin(b.theta))
        x = b.x - PATROL_OFF_M * n[0] + reach * math.cos(way)
        y = b.y - PATROL_OFF_M * n[1] + reach * math.sin(way)
        return x, y, reach

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
                p = s.pose
                if m.called_on != s.floor:
                    m.lobby_walls = {}
                m.called_at, m.called_from = s.t, Pose(p.x, p.y, self.button_wall(s))
                # Each call's patrol starts the other way (a car whose door opens only a few
                # seconds on one side is missed on every call if it always went the same way).
                m.patrol_leg, m.patrol_since = m.patrol_leg + 1, s.t
                m.called_on = s.floor
                b = m.called_from
                # The button's wall holds nothing but cars' doors (docs/maps.md, "Lobby").
                m.lobby_walls[0] = (*b.ahead(PUSH_M), b.theta)
            elif self.rule_name == "push floor":
                m.pressed_floor = self.stop_floor()
                m.turned_in_car, m.door_heading = False, None
        if not m.in_car:
            self.note_button_wall(s)
        if self.rule_name == "wait for car":
            self.find_end_walls(s)
        fresh = m.opened is not None and s.t - m.opened[0] < CAR_ENTER_S
        if s.opened.get("seen") and m.called_at is not None and not m.in_car and not fresh:
            bearing = s.pose.heading_of(float(s.opened.get("bearing", 0.0)))
            before = float(s.opened.get("before", 1.0))
            placed = self.place_car_door(s.pose, bearing, before)
            if placed is not None:
                door, normal = placed
                # FACE_DOOR_M in front of the door, square to its wall.
                m.car_goal = (
                    door[0] - FACE_DOOR_M * math.cos(normal),
                    door[1] - FACE_DOOR_M * math.sin(normal),
                )
                m.opened, m.enter_stage, m.faced_at = (s.t, normal), "goto", None
            if self.debug:
                walls = {k: tuple(round(v, 2) for v in w) for k, w in m.lobby_walls.items()}
                where = (
                    f"on no wall of the lobby known ({walls}): not a car's door"
                    if placed is None
                    else f"a car door at ({placed[0][0]:.2f}, {placed[0][1]:.2f}), "
                    f"facing {math.degrees(placed[1]):.0f} deg"
                )
                print(
                    f"[{s.t:7.1f} s]   a way opened at {math.degrees(bearing):.0f} deg, "
                    f"{before:.2f} m from ({s.pose.x:.2f}, {s.pose.y:.2f}): {where}"
                )
        if not m.in_car and m.out_of_lab and m.called_on == s.floor and s.enclosed(tight=True):
            # Walls all round, nearer than a car is wide, where a car was called: inside a car
            # (its door shut). Elsewhere it is a closet, or people round the robot.
            m.in_car, m.called_at, m.opened, m.pressed_floor = True, None, None, None
            m.panel_seen_at, m.leave_from, m.exit_stopped = s.t, None, False
        if s.car_entered and self.rule_name == "enter car" and m.enter_stage == "in":
            if s.enclosed():
                m.in_car, m.called_at, m.opened, m.pressed_floor = True, None, None, None
                m.panel_seen_at, m.leave_from, m.exit_stopped = s.t, None, False
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
        if self.rule_name == "leave car" and (s.car_exited or m.exit_stopped):
            # Out once past the door by the robot's radius and more: the skill stops short for
            # someone outside the door, and from the doorway the way along the lobby's wall is
            # blocked by the door's jamb (the robot went back into the car and was shut in).
            f = m.leave_from
            went = math.hypot(s.pose.x - f[0], s.pose.y - f[1]) if f is not None else math.inf
            if not s.enclosed() and went >= m.car_door_ahead + OUT_OF_CAR_M:
                m.in_car, m.lobby_seen_on, m.route, m.called_on = False, None, None, None
                m.leave_from, m.exit_stopped = None, False
            elif s.car_exited:  # stopped short: on out the way it went (`leave_car`)
                m.exit_stopped = True
        if m.called_at is not None and s.t - m.called_at >= CALL_AGAIN_S and not m.in_car:
            m.called_at = None

    def note_button_wall(self, s: Senses) -> None:
        """Notes the call button's wall (its normal's heading, odometry), when it is in sight.

        That is the wall fitted ahead, if the button's barcode is on it (within
        `CODE_ON_WALL_M`), seen from within `BUTTON_WALL_SEEN_M`. One fit may be a few
        degrees off: the robot calls with the last `BUTTON_WALL_S` of them.
        """
        m = self.mem
        m.button_walls = [w for w in m.button_walls if s.t - w[0] < BUTTON_WALL_S]
        b = s.barcodes.get(self.button(s.floor))
        if b is None or b[1] > BUTTON_WALL_SEEN_M:
            return
        fitted = wall_through(b, s.wall, CODE_ON_WALL_M)
        if fitted is not None:
            m.button_walls.append((s.t, s.pose.heading_of(fitted)))

    def button_wall(self, s: Senses) -> float:
        """The call button's wall, having pushed it: its normal's heading (odometry).

        The mean of its last fits (`note_button_wall`): the robot may have come to the button
        aslant, and pushed it from up to 25 degrees off. With no fit noted, the wall fitted
        ahead if within `BUTTON_WALL_RAD` of ahead (a fit farther off is another wall, a side
        wall near the corner), else straight ahead, the best guess.
        """
        seen = self.mem.button_walls
        if seen:
            return mean_heading(h for _, h in seen)
        fitted = float(s.wall.get("normal", 0.0)) if s.wall.get("seen") else 0.0
        return s.pose.heading_of(fitted if abs(fitted) < BUTTON_WALL_RAD else 0.0)

    def find_end_walls(self, s: Senses) -> None:
        """Notes the walls at the ends of the button's wall, as the sonars along it read them.

        Waiting for a car, the robot walks along the button's wall: the sonar nearest each way
        along it reads the wall at that end, square across its axis (`seen_wall_ends_at`: not
        someone standing there), from `END_WALL_FROM_M` to 3.6 m.
        """
        m, p = self.mem, s.pose
        b = m.called_from
        if b is None or m.called_on != s.floor:
            return
        for side in (1, -1):
            way = wrap(b.theta + side * math.pi / 2)
            i = sonar_toward(way - p.theta)
            off = wrap(p.theta + bearing_of(i) - way)
            near = s.sonar[i] < END_WALL_FROM_M  # someone near fills three sonars' view
            if abs(off) < END_WALL_AIM_RAD and not near and seen_wall_ends_at(s.sonar, i):
                r = s.sonar[i]
                m.lobby_walls[side] = (*p.ahead(r, way), way)

    def place_car_door(
        self, pose: Pose, bearing: float, before: float
    ) -> tuple[tuple[float, float], float] | None:
        """Where a car door seen opening is (odometry), and the heading into the car.

        ``bearing`` is the way that opened (odometry), ``before`` the sonar's reading there
        while it was shut. Cars open on the button's wall or on the walls at its ends
        (docs/maps.md); the robot faced the button's wall when it pushed the button, and
        notes the end walls as it walks along it (`find_end_walls`). The door is on the known
        wall its shut reading was on (within `OPENED_ON_WALL_M`, as the sequenced robot
        takes it), where the sonar's bearing meets the wall's line: seen aslant, the bearing
        is sure, the range is not. None: on none of them, though the walls on that side are
        known (someone who stood still and walked off; the lobby's entry). On a side whose end
        wall is not known yet, the best guess is a door on it at the shut reading.
        """
        c, sn = math.cos(bearing), math.sin(bearing)
        door = pose.ahead(before, bearing)
        b = self.mem.called_from
        if b is None:
            return door, bearing
        best: tuple[float, float, float] | None = None  # (off the wall, reach, heading)
        for wx, wy, wn in self.mem.lobby_walls.values():
            n = (math.cos(wn), math.sin(wn))
            towards = c * n[0] + sn * n[1]
            if towards <= 0.1:
                continue
            reach = pose.along(wx, wy, wn) / towards
            off = abs(reach - before) * towards
            if off < OPENED_ON_WALL_M and (best is None or off < best[0]):
                best = (off, reach, wn)
        if best is not None:
            return pose.ahead(best[1], bearing), best[2]
        side = 1 if pose.across(door[0], door[1], b.theta) > 0 else -1
        if side in self.mem.lobby_walls:
            return None
        return door, wrap(b.theta + side * math.pi / 2)
