"""The reactive robot's route-leg follower, and the actions its rules and it return.

`rules` holds the rule list; the rules "to office" and "to lobby" act through
`RouteFollower.route_action`, which follows one leg of the map's route (docs/maps.md, route
steps) a step at a time. What it keeps is a `RouteState` in the robot's memory: the leg and
the step it is at (decision 0008 allows a route step counter), and where along the step it
is. It does not know what phase the robot is in: the rules decide when a leg applies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from courier.geometry import Pose, wrap
from courier.mission import HINT_DOOR_AHEAD_M, HINT_DOOR_ASIDE_M, WALL_AHEAD_M, Mission, door_hint
from courier.reactive.state import Memory, RouteState, Senses

#: The office route starts this far square in front of the goal floor's button, m.
BUTTON_STANDOFF_M = 1.0
#: Within this of a barcode, the robot has homed on it, m.
HOMED_M = 1.1
#: The call button is pushed from this near (its centre to the barcode), m.
PUSH_M = 0.5
#: Counted a junction abeam, the robot goes this much farther before turning into it, m.
JUNCTION_ON_M = 0.7
#: The first opening of a step is counted only this far past its blind distance, m. The
#: side sonars see a mouth about 0.6-0.8 m before its near edge.
FIRST_COUNT_M = 0.3
#: Following to a wall, the robot counts a wall across the way (`wall_across`) once it has
#: been there this long (s), with no gap longer than `WALL_GAP_S` (s).
WALL_STEADY_S = 3.0
WALL_GAP_S = 1.0
#: Turned into a junction, the robot drives this far into the side corridor, m.
INTO_MOUTH_M = 1.5
#: In front of a door, this far from it, before passing it, m.
DOOR_STANDOFF = 0.9
#: Following a step, having lost this much of the way made (m), facing more than
#: `WRONG_WAY_RAD` off the way (turned round by going round people, say), the robot turns back
#: to the way, until it faces within `BACK_ON_WAY_RAD` of it, rad. (Facing off the way alone
#: does not count: a step's heading, from odometry, may be a corridor's width off.)
LOST_WAY_M = 1.0
WRONG_WAY_RAD = math.pi / 2
BACK_ON_WAY_RAD = 0.3
#: A step's trail (`RouteState.trail`) notes where the robot is every this much new way, m.
TRAIL_STEP_M = 0.25
#: Homing on a route's barcode and losing it (seen too obliquely, near its wall), the robot
#: goes this far square in front of where it was seen (m), for at most this long (s).
LOST_CODE_M = 1.2
LOST_CODE_S = 60.0
#: Within this of where it squared up (m), and of the heading (rad), the robot is still there.
SQUARED_HERE_M, SQUARED_HERE_RAD = 0.3, 0.35


@dataclass
class Action:
    """A rule's action: skills on, their parameters, and a key that restarts it when new."""

    skills: tuple[str, ...]
    params: dict[tuple[str, str], Any] = field(default_factory=dict)
    key: Any = None


def goto(
    x: float,
    y: float,
    key: Any,
    *,
    speed: float = 0.3,
    reverse_within: float = 0.0,
    avoid: bool = False,
) -> Action:
    """Drives to (x, y) of the odometry frame (`std.home_position`), runaway on."""
    skills = ("runaway", "avoid", "home_position") if avoid else ("runaway", "home_position")
    params = {
        ("home_position", "x"): x,
        ("home_position", "y"): y,
        ("home_position", "speed"): speed,
        ("home_position", "reverse_within"): reverse_within,
    }
    return Action(skills, params, key=key)


#: A turn still off is issued again this often (one that ended short, say), s.
TURN_AGAIN_S = 8.0


def turn(
    off: float, key: Any, t: float, *, runaway: bool = False, every: float = TURN_AGAIN_S
) -> Action:
    """Turns in place by ``off`` (rad), issued again every ``every`` s while still asked."""
    skills = ("runaway", "turn") if runaway else ("turn",)
    return Action(skills, {("turn", "angle"): off}, key=(key, t // every))


def squared_here(r: RouteState, s: Senses) -> bool:
    """Whether the robot stands where it squared up in front of a barcode, facing its wall."""
    if r.square_at is None or r.heading is None:
        return False
    near = math.hypot(s.pose.x - r.square_at[0], s.pose.y - r.square_at[1]) < SQUARED_HERE_M
    return near and abs(s.pose.turn_to(r.heading)) < SQUARED_HERE_RAD


def code_sighting(
    r: RouteState, s: Senses, barcode: tuple[float, float]
) -> tuple[float, float, float] | None:
    """Where a route's barcode seen now is, and its wall's normal (towards it; odometry).

    The barcode is on a wall of the corridor the route followed: its normal is square to
    the corridor's heading (`RouteState.along` once squared up before, else the route's
    heading), on the side it is seen from here. None without a heading.
    """
    heading = r.along if r.along is not None else r.heading
    if heading is None:
        return None
    at = s.pose.theta + barcode[0]
    n = wrap(heading + (math.pi / 2 if wrap(at - heading) > 0 else -math.pi / 2))
    return (*s.pose.seen_at(barcode[0], barcode[1]), n)


class RouteFollower:
    """Follows the current route leg (`Memory.route`); mixed into the reactive controller.

    It uses the controller's memory, mission and a few of its actions (declared below, defined
    by `rules.Reactive`).
    """

    mem: Memory
    m: Mission
    debug: bool

    def button(self, floor: int) -> int:
        """The call button's barcode on ``floor``."""
        raise NotImplementedError

    def office_leg(self) -> str:
        """The name of the route leg that ends in the office."""
        raise NotImplementedError

    def wander_about(self, s: Senses) -> Action:
        """Looks round and wanders (a barcode not in view)."""
        raise NotImplementedError

    def pass_door_action(self, s: Senses) -> Action:
        """Passes the door beside the barcode in front."""
        raise NotImplementedError

    def through_door(self, s: Senses) -> bool:
        """Whether the door being passed is passed."""
        raise NotImplementedError

    def route_action(self, s: Senses) -> Action:
        """The route leg's current step (docs/maps.md)."""
        r = self.mem.route
        assert r is not None
        steps = self.m.route.get(r.leg, [])
        if r.step >= len(steps):
            return Action(("runaway",), key=("route end", r.leg))
        step = steps[r.step]
        if r.stage == "approach":
            code = self.button(s.floor)
            b = s.barcodes.get(code)
            normal = float(s.wall.get("normal", 0.0))
            if b is not None and b[1] < PUSH_M + 0.15 and abs(b[0]) < 0.25:
                if s.wall.get("seen") and abs(normal) < 0.7:
                    r.square_before(s, b, s.pose.heading_of(normal), BUTTON_STANDOFF_M)
                    return Action(("runaway",), key=("squaring", r.leg))
                return Action(("runaway",), key=("fitting the wall", r.leg, s.t // 3))
            if b is None:
                return self.wander_about(s)
            return Action(
                ("track_barcode", "home"),
                {("track_barcode", "id"): code, ("home", "stop_distance"): PUSH_M},
                key=("approach", r.leg),
            )
        if r.stage == "square" and r.square_at is not None and r.heading is not None:
            gx, gy = r.square_at
            if math.hypot(s.pose.x - gx, s.pose.y - gy) > 0.12:
                return goto(gx, gy, ("square", r.leg, r.step), reverse_within=1.5)
            off = s.pose.turn_to(r.heading)
            if abs(off) > 0.06:
                return turn(off, ("square turn", r.leg, r.step), s.t)
            r.stage, r.squared = "start", r.step
            if step.get("home") is not None:
                return self.next_step(r, s)
        if r.start is None:
            r.start, r.count, r.stage = s.pose, 0, "follow"
            r.last_side, r.counted_at = False, None
            r.turning_back, r.best_went, r.wall_since = False, 0.0, None
            r.trail, r.progress_at = [(0.0, s.pose.x, s.pose.y)], s.t
            if r.heading is None:
                r.heading = s.pose.theta
        if step.get("home") is not None:
            code = int(step["home"])
            if s.sees(code, HOMED_M) and abs(s.barcodes[code][0]) < 0.25:
                door_next = any(x.get("pass") for x in steps[r.step + 1 :])
                b = s.barcodes[code]
                if door_next and r.squared != r.step and r.heading is not None:
                    # A door beside the barcode: square in front of it first, so that the
                    # door finder looks along its wall (`code_sighting` says which). Homing
                    # again after a "door again", the corridor's heading is the one kept.
                    r.along = r.heading if r.along is None else r.along
                    sighting = code_sighting(r, s, b)
                    assert sighting is not None
                    r.square_before(s, b, sighting[2], DOOR_STANDOFF)
                    return Action(("runaway",), key=("squaring", r.step))
                return self.next_step(r, s)
            if s.sees(code):
                r.code_at, r.code_lost_at = code_sighting(r, s, s.barcodes[code]), None
                return Action(
                    ("runaway", "track_barcode", "home"),
                    {("track_barcode", "id"): code, ("home", "stop_distance"): DOOR_STANDOFF},
                    key=("route home", code),
                )
            lost = self.in_front_of_lost(r, s, code)
            return lost if lost is not None else self.wander_about(s)
        if step.get("pass"):
            if self.through_door(s):
                if r.leg == self.office_leg():
                    self.mem.in_office = True
                r.along, r.hinted = None, False
                return self.next_step(r, s)
            if self.mem.door_given_up_at > max(s.t - 1.0, r.given_up):
                r.given_up = self.mem.door_given_up_at
                hint = door_hint(steps, r.step)
                if hint in ("left", "right") and not r.hinted and squared_here(r, s):
                    # No opening in sight from in front of the barcode (a wide door beside it
                    # is seen too obliquely from there): where the route's hint says, once, as
                    # the sequenced robot does. In front of it, the door is placed anew.
                    r.hinted = True
                    self.door_by_hint(r, s, 1.0 if hint == "left" else -1.0)
                    return Action(("runaway",), key=("door by hint", hint))
                # No door showed here: back to the barcode's step, to home and square again.
                homes = [n for n in range(r.step) if steps[n].get("home") is not None]
                if homes:
                    r.step, r.squared, r.start, r.stage = homes[-1], -1, None, "start"
                    # Homing again along the corridor, not the wall's normal squaring set.
                    r.heading = r.along if r.along is not None else r.heading
                    self.mem.door_dropped()
                    return Action(("runaway",), key=("door again", s.t))
            return self.pass_door_action(s)
        if r.stage == "follow" and step.get("follow"):
            went = self.way_made(r, s)
            if r.trail and went > r.trail[-1][0] + TRAIL_STEP_M:
                r.trail.append((went, s.pose.x, s.pose.y))
                r.progress_at = s.t
            if r.heading is not None:
                # Going back along the corridor (avoidance turned the robot round someone):
                # the hallway follower would take it back the way it came. Turn to the way.
                off = s.pose.turn_to(r.heading)
                went = self.way_made(r, s)
                r.best_went = max(r.best_went, went)
                if went < r.best_went - LOST_WAY_M and abs(off) > WRONG_WAY_RAD:
                    r.turning_back = True
                elif r.turning_back and abs(off) < BACK_ON_WAY_RAD:
                    r.turning_back, r.best_went = False, went
                if r.turning_back:
                    back = ("back to the way", r.leg, r.step)
                    return turn(off, back, s.t, runaway=True, every=10)
            if self.step_until_met(step, r, s):
                r.stage = "turn" if step.get("turn") else "done"
            else:
                # The step's detectors start afresh with it (as the sequenced robot's do).
                return Action(
                    ("runaway", "avoid", "follow_hallway", "detect_intersection", "detect_door"),
                    key=("follow", r.leg, r.step),
                )
        if step.get("turn") and r.stage in ("follow", "turn"):
            # A turn after the next step's door finder faces the door itself.
            after = steps[r.step + 1] if r.step + 1 < len(steps) else {}
            if after.get("pass"):
                return self.next_step(r, s)
            if r.turn_goal is None:
                angle = {"left": math.pi / 2, "right": -math.pi / 2, "back": math.pi}[
                    str(step["turn"])
                ]
                base = r.heading if r.heading is not None else s.pose.theta
                r.turn_goal = wrap(base + angle)
            off = s.pose.turn_to(r.turn_goal)
            if abs(off) > 0.05 and r.stage != "into":
                return turn(off, ("route turn", r.step), s.t)
            r.heading = r.turn_goal
            if step.get("until") in ("junction", "wall") and str(step["turn"]) != "back":
                # Into the side corridor's mouth, straight on, before following it: in the
                # crossing the hallway follower could take either corridor.
                if r.stage != "into":
                    r.stage, r.start = "into", s.pose
                assert r.start is not None
                gx, gy = r.start.ahead(INTO_MOUTH_M, r.heading)
                if math.hypot(s.pose.x - gx, s.pose.y - gy) > 0.15 and s.sonar[0] > 0.6:
                    return goto(gx, gy, ("into mouth", r.step))
        return self.next_step(r, s)

    def in_front_of_lost(self, r: RouteState, s: Senses, code: int) -> Action | None:
        """To `LOST_CODE_M` square in front of a barcode lost while homing, facing its wall.

        Homing brings the robot near the barcode's wall, where a barcode beside it is seen too
        obliquely to read (`code_sighting`). None once there and facing it (not in view from
        there, it is forgotten), after `LOST_CODE_S`, or with no sighting.
        """
        if r.code_at is None:
            return None
        if r.code_lost_at is None:
            r.code_lost_at = s.t
        bx, by, n = r.code_at
        if s.t - r.code_lost_at > LOST_CODE_S:
            r.code_at = None
            return None
        gx, gy = bx - LOST_CODE_M * math.cos(n), by - LOST_CODE_M * math.sin(n)
        if math.hypot(s.pose.x - gx, s.pose.y - gy) > 0.2:
            return goto(gx, gy, ("to lost barcode", code, round(gx, 1), round(gy, 1)), avoid=True)
        off = s.pose.turn_to(n)
        if abs(off) > 0.1:
            return turn(off, ("face lost barcode", code), s.t)
        r.code_at = None
        return None

    def door_by_hint(self, r: RouteState, s: Senses, side: float) -> None:
        """Places the door by the route's hint: ahead and to ``side`` (1 left, -1 right).

        The point `DOOR_STANDOFF` in front of its centre, facing the barcode's wall (the
        heading squared up to).
        """
        h = r.heading if r.heading is not None else s.pose.theta
        ax, ay = HINT_DOOR_AHEAD_M - DOOR_STANDOFF, side * HINT_DOOR_ASIDE_M
        goal = (*Pose(s.pose.x, s.pose.y, h).from_robot(ax, ay), h)  # here, facing h
        self.mem.door_placed(goal, by_hint=True)

    def step_until_met(self, step: dict[str, Any], r: RouteState, s: Senses) -> bool:
        """Whether a follow step's `until` holds (counting openings as they pass)."""
        went = self.way_made(r, s)
        until = step.get("until")
        first = float(step.get("distance", 0.0))
        if until == "distance":
            return went >= first
        if went < first:
            return False
        if until == "wall":
            # A wall stays put; people across the way walk on. The robot keeps moving (the
            # sequenced one stands and looks), so a wall seen with gaps shorter than
            # `WALL_GAP_S` counts as one.
            if not self.wall_across(r, s):
                if r.wall_since is not None and s.t - r.wall_seen > WALL_GAP_S:
                    r.wall_since = None
                return False
            r.wall_seen = s.t
            if r.wall_since is None:
                r.wall_since = s.t
            return s.t - r.wall_since >= WALL_STEADY_S
        if until == "barcode":
            return s.sees(int(step["barcode"]))
        if until in ("junction", "door"):
            seen = s.junction if until == "junction" else s.door
            side = step.get("side")
            sides = [str(side)] if side in ("left", "right") else ["left", "right"]
            # The detector's flag, or (junctions) the side sonars reading far into a mouth
            # abeam: the detector counts an opening only once well past its near edge.
            now = any(bool(seen.get(x)) for x in sides)
            if until == "junction":
                now = now or any(s.open_abeam(x) for x in sides)
            # Openings are counted from FIRST_COUNT_M past the blind distance (generated maps
            # put the junction's near edge 1.5 m past it), then 1 m apart at least.
            if r.counted_at is None:
                fresh = went - first > FIRST_COUNT_M
            else:
                fresh = went - r.counted_at > 1.0
            if now and not r.last_side and fresh:
                r.count += 1
                r.counted_at = went
                if self.debug:
                    print(f"[{s.t:7.1f} s]   {until} {side or ''} {r.count} at {went:.1f} m")
            r.last_side = now
            if r.count >= int(step.get("count", 1)) and r.counted_at is not None:
                # On into the junction's middle (about half a corridor) before turning; at a
                # corner (the corridor ends in a wall across) the wall comes first.
                return (
                    not step.get("turn")
                    or went - r.counted_at >= JUNCTION_ON_M
                    or self.wall_across(r, s)
                )
        return False

    def way_made(self, r: RouteState, s: Senses) -> float:
        """How far along the step's heading the robot got (round someone and back: none), m."""
        assert r.start is not None
        if r.heading is None:
            return math.hypot(s.pose.x - r.start.x, s.pose.y - r.start.y)
        return r.start.along(s.pose.x, s.pose.y, r.heading)

    def wall_across(self, r: RouteState, s: Senses) -> bool:
        """A wall across the way ahead (not clutter, nor a side wall avoidance turned to).

        The sonar pointing along the way (the step's heading, wherever the robot faces) and
        two either side of it read near. At a corridor's end the hallway follower turns the
        robot into one of the ways off it, and the wall across is then beside it. Along a
        corridor the sonars 15 and 30 degrees off the way see down it; someone standing in
        the way is too narrow to reach the sonars 30 degrees off it.
        """
        rel = s.pose.turn_to(r.heading) if r.heading is not None else 0.0
        n = len(s.sonar)
        i = round(rel / (2 * math.pi / n)) % n
        way = [s.sonar[(i + k) % n] for k in range(-2, 3)]
        return s.sonar[i] < WALL_AHEAD_M and max(way) < WALL_AHEAD_M + 0.4

    def next_step(self, r: RouteState, s: Senses) -> Action:
        """Moves on to the route's next step."""
        r.step += 1
        r.start, r.stage, r.turn_goal = None, "start", None
        return Action(("runaway",), key=("route step", r.leg, r.step))
