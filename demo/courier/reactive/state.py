"""What the reactive robot senses in a cycle (`Senses`), and the little it keeps (`Memory`).

The rule list (`rules`), its route follower (`route`) and its car rules (`car`) read both; a
route leg's progress is part of the memory (`RouteState`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from courier.geometry import SONARS, Pose, live_sonar_ahead

#: Side sonars reading farther than this see a corridor's mouth abeam, m.
MOUTH_M = 2.6
#: Unsticking: towards the freest way, at most this far, for at most this long (m, s).
UNSTICK_M = 2.0
UNSTICK_S = 15.0


@dataclass
class Senses:
    """What the robot senses in one cycle (the skills' outputs and the devices')."""

    t: float
    pose: Pose
    sonar: list[float]
    barcodes: dict[int, tuple[float, float]]  # id: (bearing, distance)
    floor: int
    presses: int
    said: int
    junction: dict[str, Any]
    door: dict[str, Any]
    opened: dict[str, Any]
    car: int
    opening: dict[str, Any]
    wall: dict[str, Any]
    door_passed: bool
    car_entered: bool
    car_exited: bool
    #: The sonars `std.sonar_filter` takes to be dead (bit i: sonar i).
    dead: int = 0

    def ahead(self) -> int:
        """The sonar to read what is straight ahead with: the live one nearest ahead."""
        return live_sonar_ahead(self.dead)

    def enclosed(self, *, tight: bool = False) -> bool:
        """Walls near all round (inside a car: all but the door's sonars; ``tight``: all)."""
        return sum(1 for r in self.sonar if r < 1.9) >= SONARS - (1 if tight else 6)

    def open_abeam(self, side: str) -> bool:
        """Whether two neighbouring sonars abeam on ``side``, or ahead of it, read far: a mouth.

        The sonars from 30 degrees ahead of abeam to abeam (not those behind it: they see an
        opening already passed, an alcove say, after the step's blind distance).
        """
        mid = SONARS // 4 if side == "left" else 3 * SONARS // 4
        ahead = range(-2, 1) if side == "left" else range(0, 3)
        far = [self.sonar[(mid + k) % SONARS] > MOUTH_M for k in ahead]
        return any(a and b for a, b in zip(far, far[1:], strict=False))

    def sees(self, barcode: int, within: float = 5.0) -> bool:
        """Whether ``barcode`` is in view within ``within`` m."""
        return barcode in self.barcodes and self.barcodes[barcode][1] <= within


@dataclass
class Memory:
    """The little state the reactive robot keeps (all else is sensed anew every cycle)."""

    made: int = 0
    said_at_start: int = 0
    out_of_lab: bool = False
    in_car: bool = False
    #: In a car, when its panel was last seen (or the car entered), simulated time.
    panel_seen_at: float = 0.0
    pressed_floor: int | None = None
    #: The simulated time the call button was pushed on this floor (None: not called).
    called_at: float | None = None
    presses_seen: int = 0
    #: The floor whose call button was seen since arriving on it (the lobby is reached).
    lobby_seen_on: int | None = None
    in_office: bool = False
    #: The last car door seen opening: (time, bearing in the odometry frame).
    opened: tuple[float, float] | None = None
    #: The point in front of that door (odometry), and how far the robot has got with it.
    car_goal: tuple[float, float] | None = None
    enter_stage: str = ""
    #: When the robot faced the car's door it went to (None: not yet), simulated time.
    faced_at: float | None = None
    #: Route legs done, and the step the current one is at.
    legs_done: set[str] = field(default_factory=set)
    route: RouteState | None = None
    #: A door being passed: the point in front of it and the heading through (odometry).
    door_goal: tuple[float, float, float] | None = None
    door_stage: str = ""
    door_fixes: int = 0
    #: Where that door was last placed from in front of it (the point in front of it and the
    #: heading through); after stopping short in it, a new placement must be near this one.
    door_first: tuple[float, float, float] | None = None
    door_after_pass: bool = False
    #: Stopped in the doorway: how often it went on since the door was placed, and when it
    #: stopped last (simulated time).
    door_pushes: int = 0
    door_blocked_at: float = 0.0
    #: The door's placements of the last cycles: (time, the point in front, the heading through).
    door_seen: list[tuple[float, tuple[float, float, float]]] = field(default_factory=list)
    door_waiting_since: float | None = None
    door_given_up_at: float = -1e9
    passed_heading: float | None = None
    turned_in_car: bool = False
    #: In a car, the heading out through its door (odometry).
    door_heading: float | None = None
    #: Riding, facing the car's door: how far ahead it is (its reading while shut), m; where
    #: the robot began to leave the car (odometry), and whether `std.leave_car` stopped short.
    car_door_ahead: float = 1.2
    leave_from: tuple[float, float] | None = None
    exit_stopped: bool = False
    #: Per floor, where the call button was last seen from near (odometry).
    button_seen_from: dict[int, Pose] = field(default_factory=dict)
    #: Per floor, where the call button was last seen, and from where (odometry).
    button_at: dict[int, tuple[tuple[float, float], tuple[float, float]]] = field(
        default_factory=dict
    )
    #: Where the call button was pushed from (odometry), to wait for a car a step back.
    called_from: Pose | None = None
    #: The floor a car was called on (until the robot leaves a car): only there can it be in one.
    called_on: int | None = None
    #: The lobby's walls a car's door may be in, found on the floor called on: the button's
    #: (key 0) and the walls at its ends (1: to the left facing the button's wall, -1: to the
    #: right); each a point on it and the heading towards it (odometry).
    lobby_walls: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    #: The patrol waiting for a car: its leg (even: to the left facing the button's wall), and
    #: since when (simulated time).
    patrol_leg: int = 0
    patrol_since: float = 0.0
    #: The call button's wall as fitted in the last few seconds: (time, its normal's heading).
    button_walls: list[tuple[float, float]] = field(default_factory=list)
    #: Where the robot was when it last got 1 m away from the place before, and when
    #: (odometry, simulated time); unsticking: where to, and since when.
    moved_from: tuple[float, float, float] | None = None
    unstick_to: tuple[float, float] | None = None
    unstick_since: float = 0.0
    #: How long unsticking may take, s; back along a route leg (avoiding what is in the way).
    unstick_for: float = UNSTICK_S
    unstick_back: bool = False
    #: Where the lab door's barcode was last seen (odometry), and from where.
    lab_door_at: tuple[float, float] | None = None
    lab_door_from: tuple[float, float] = (0.0, 0.0)
    #: The lab door barcode's wall as fitted: its normal's headings (odometry), the last few.
    lab_door_walls: list[float] = field(default_factory=list)
    #: Whether the robot lined up in front of the lab door's barcode since it last gave up.
    door_lined_up: bool = False

    # ----- the door being passed: each change of it that is more than a step ----------------
    # (`rules.Reactive` steps the stage itself, from goto to face, check and pass, notes when
    # it began waiting for an opening, `door_waiting_since`, and its sightings, `door_seen`.)

    def door_placed(self, goal: tuple[float, float, float], *, by_hint: bool = False) -> None:
        """The door is at ``goal`` (the point in front of it, the heading through): to it.

        Placed from the opening seen, it is one more fix; after stopping short in the doorway
        the first placement stays, which a new one must be near (`door_first`). Placed by the
        route's hint, it starts afresh.
        """
        if by_hint:
            self.door_fixes, self.door_first = 0, goal
        else:
            self.door_fixes += 1
            if not self.door_after_pass:
                self.door_first = goal
        self.door_goal, self.door_stage = goal, "goto"
        self.door_pushes, self.door_after_pass, self.door_waiting_since = 0, False, None

    def door_place_anew(self) -> None:
        """In front of the door, its opening not straight ahead: placed anew from here."""
        self.door_goal = None

    def door_through(self) -> None:
        """Through the door, beyond its line: the next door starts afresh."""
        self.door_goal, self.door_stage, self.door_fixes, self.door_first = None, "", 0, None
        self.door_after_pass = False

    def door_blocked(self, t: float) -> None:
        """Stopped in the doorway at time ``t`` (someone beyond): wait, then on through it."""
        self.door_pushes += 1
        self.door_stage, self.door_blocked_at = "blocked", t

    def door_stopped_short(self) -> None:
        """Stopped short of the doorway: placed anew from here, near where it was first."""
        self.door_goal, self.door_stage, self.door_after_pass = None, "", True

    def door_dropped(self) -> None:
        """The route goes back to the door's barcode, to home and square up again."""
        self.door_goal, self.door_stage = None, ""
        self.door_first, self.door_after_pass = None, False

    def door_given_up(self, t: float) -> None:
        """No door showed in time, at time ``t``: left alone a while, then looked for anew."""
        self.door_given_up_at, self.door_waiting_since, self.door_first = t, None, None
        self.door_lined_up = False
        self.door_after_pass = False

    def door_lining_up(self) -> None:
        """An opening off the lab door's barcode: lining up square in front of the barcode."""
        self.door_stage, self.door_waiting_since = "line up", None

    def door_line_up_done(self) -> None:
        """Lined up in front of the lab door's barcode: not again until the door is given up."""
        self.door_stage, self.door_lined_up = "", True


@dataclass
class RouteState:
    """Where the robot is on a route leg (docs/maps.md, route steps)."""

    leg: str
    step: int = 0
    stage: str = "start"
    start: Pose | None = None
    count: int = 0
    last_side: bool = False
    heading: float | None = None
    turn_goal: float | None = None
    #: Before the leg: the point square in front of where it starts (odometry).
    square_at: tuple[float, float] | None = None
    #: The step squared up at last (-1: none).
    squared: int = -1
    #: How far along the step the last opening was counted, m.
    counted_at: float | None = None
    #: Turning back to the way (it faced the wrong way along the corridor).
    turning_back: bool = False
    #: The most way made on this step so far, m.
    best_went: float = 0.0
    #: Where the robot was each time it had made `TRAIL_STEP_M` more way on this step than ever
    #: before (way made, x, y; odometry), and when it last did: unsticking goes back along it.
    trail: list[tuple[float, float, float]] = field(default_factory=list)
    progress_at: float = 0.0
    #: Since when a wall has been across the way (None: none now), and when it last was.
    wall_since: float | None = None
    wall_seen: float = 0.0
    #: Squared before a door: the corridor's heading before squaring (`heading` is then the
    #: wall's normal); a "door again" homes and squares along it again. None: not squared.
    along: float | None = None
    #: The door's last give-up handled (`Memory.door_given_up_at`), and whether the route's
    #: hint was tried for this door.
    given_up: float = -1e9
    hinted: bool = False
    #: Homing on a barcode: where it was last seen and its wall's normal, towards the wall
    #: (odometry; None: not seen), and since when it is out of view (None: in view).
    code_at: tuple[float, float, float] | None = None
    code_lost_at: float | None = None

    def square_before(
        self, s: Senses, barcode: tuple[float, float], heading: float, standoff: float
    ) -> None:
        """Squares up next: facing `heading`, `standoff` in front of a barcode.

        `barcode` is where it is seen: (bearing, distance).
        """
        cx, cy = s.pose.seen_at(barcode[0], barcode[1])
        self.heading, self.stage = heading, "square"
        self.square_at = (cx - standoff * math.cos(heading), cy - standoff * math.sin(heading))
