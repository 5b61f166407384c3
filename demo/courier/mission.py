"""The mission, and what both designs of the robot's program share about the building.

The mission is the map's `mission:` section (`Mission`), and the task the stops where the
message is said (`Stop`, `parse_task`). Both designs drive the same skills of demo/robot.yaml
(`SKILLS`), from the same parameters (`NORMAL`), and read the building the same way where
they agree: how near a wall ahead ends a corridor, where a door is beside its barcode, how long
a closed door is waited for, where a leg's first distance runs from (`distance_from_door`),
where the route's hint puts a door (`door_hint`), which way that opened in a lobby is a car's
door, and which sonar reading is a wall rather than someone standing there
(`seen_wall_ends_at`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from courier.geometry import SONARS, Pose, wrap

#: Every skill of demo/robot.yaml.
SKILLS = (
    "runaway",
    "avoid",
    "wander",
    "follow_hallway",
    "turn",
    "home",
    "home_position",
    "track_barcode",
    "detect_door",
    "detect_intersection",
    "identify_car",
    "pass_door",
    "push_button",
    "enter_car",
    "leave_car",
    "say",
)

#: Skill parameters that the sequencer changes in some phase, with their value elsewhere.
NORMAL = {
    ("runaway", "safe_distance"): 0.3,
    ("avoid", "distance"): 0.6,
    ("avoid", "stop_distance"): 0.2,
    ("follow_hallway", "speed"): 0.4,
    ("home", "stop_distance"): 1.0,
    ("turn", "max_turn"): 1.2,
    ("detect_door", "confirm"): 2,
    ("watch_openings", "confirm"): 2,
    ("track_barcode", "hold"): 15,
    ("fit_wall", "bearing_deg"): 0.0,
    ("fit_wall", "half_angle_deg"): 80.0,
    ("fit_wall", "through_distance"): 0.0,
    ("locate_door", "wall_distance"): 0.0,
    ("locate_door", "wall_normal_deg"): 0.0,
    ("locate_door", "max_width"): 1.8,
}

#: `until: wall` ends with the wall ahead this near (from the robot's centre), m.
WALL_AHEAD_M = 1.2
#: How long a robot waits in front of a door that shows no opening (closed doors open again: one
#: closed now and then stays closed up to a minute), s.
DOOR_WAIT_S = 75.0
#: A door's nearer jamb is at most this far from its barcode (docs/maps.md: 0.1 to 0.6 m), with
#: the slack of placing a jamb by sonar; an opening farther off is some other way, m.
DOOR_BESIDE_BARCODE_M = 1.0
#: An opening whose wall line runs this far in front of or behind the door's barcode is not in
#: the barcode's wall (the barcode is 1 to 2 cm off it; placing a wall and a barcode by sonar
#: and barcode reader is good to a few tenths), m.
DOOR_OFF_WALL_M = 0.45
#: Clutter stands this deep at most in front of its wall (docs/maps.md, "Clutter": 0.5 m, 5 cm
#: from the wall), m.
CLUTTER_DEPTH_M = 0.55
#: No opening in sight after `DOOR_WAIT_S`, the door is taken to be where the route's hint
#: (its last turn: left or right) says: its centre this far ahead and to that side, m.
HINT_DOOR_AHEAD_M, HINT_DOOR_ASIDE_M = 1.0, 0.75
#: A way that opened in the lobby is a car's door only this near an end wall found, m.
OPENED_ON_WALL_M = 0.4
#: An end wall of the lobby is taken from the sonars only nearer than this (their reach is 4 m), m.
END_WALL_SEEN_M = 3.6
#: A sonar that heard no echo reads its reach, m; each reads the nearest echo in its cone, this
#: wide (the simulator's sonars), deg.
NO_ECHO_READ_M = 4.0
SONAR_CONE_DEG = 15.0


#: Inside a car, the robot's centre is at most this far from the car's panel (the middle of its
#: back wall; shafts are 1.8 to 2.4 m on each side: docs/maps.md, "Lobby"), m. Stopped short
#: outside the door (someone in the way), with walls and people near all round, the robot reads
#: the panel through the open door from farther.
PANEL_INSIDE_M = 2.4
#: In a car, facing its door: the sonar nearest ahead reads it open beyond this, m; the live ones
#: 15° either side of it (their cones reach the door's plane a little farther off, from 7.5°)
#: beyond this, m. Shut, the door is at most 2.4 m less the robot's radius away.
DOOR_OPEN_AHEAD_M = 2.2
DOOR_OPEN_BESIDE_M = 2.5

#: Lined up with a barcode, the wall ahead reads this near square, m.
SQUARE_AHEAD_SLACK_M = 0.25

#: A route leg's first `distance` is measured from the middle of the door the leg begins
#: out of when the robot stands more than the first and at most the second this far along
#: the corridor from it, m (nearer, the 1.5 m a junction step's distance leaves before the
#: junction is room enough; farther, the door's middle was misplaced).
ORIGIN_MIN_M = 0.75
ORIGIN_MAX_M = 3.0


def distance_from_door(
    metres: float, door: tuple[float, float], here: Pose, heading: float
) -> float:
    """Of a route step's ``metres`` from the ``door``'s middle along ``heading``, those left.

    A leg's first `distance` runs from the middle of the door the leg begins out of
    (docs/maps.md, route hints: a junction step's to 1.5 m before the junction). Out through
    it aslant or round someone, the robot may stand a metre or more along the corridor from
    there (``here``), and the junction is that much nearer (or farther) than the step says.
    Within `ORIGIN_MIN_M` of the door's middle, or farther than `ORIGIN_MAX_M`, ``metres``.
    At least 0.1 m.
    """
    on = Pose(door[0], door[1], heading).along(here.x, here.y)
    if not ORIGIN_MIN_M < abs(on) <= ORIGIN_MAX_M:
        return metres
    return max(0.1, metres - on)


#: Following a corridor for a distance, the way travelled squares the route's heading when
#: at least `TRAVEL_MIN_M` long and between `TRAVEL_MIN_RAD` and `TRAVEL_MAX_RAD` off it (a
#: step that began half a metre off the corridor's middle, 5 m long, is some 6° off it).
TRAVEL_MIN_M = 5.0
TRAVEL_MIN_RAD = math.radians(15)
TRAVEL_MAX_RAD = math.radians(35)


def travelled_heading(start: Pose, here: Pose, planned: float) -> float | None:
    """The corridor's heading as travelled from ``start`` to ``here``, if ``planned`` is off.

    Turns are made from the heading the route planned (docs/maps.md, route hints); planned
    from a way out of a door misjudged (passed aslant), it is off by as much, and so is every
    turn from it: into a side corridor's corner instead of its mouth, along the next corridor
    aslant. Following the hallway keeps the robot in the corridor's middle whatever the plan,
    so the straight line it travelled is the corridor's way. None when the line is too short
    to tell, or the plan is near enough (or so far off that the robot went some other way).
    """
    dx, dy = here.x - start.x, here.y - start.y
    if math.hypot(dx, dy) < TRAVEL_MIN_M:
        return None
    travel = math.atan2(dy, dx)
    off = abs(wrap(travel - planned))
    return travel if TRAVEL_MIN_RAD < off < TRAVEL_MAX_RAD else None


def door_hint(steps: Sequence[Mapping[str, Any]], n: int) -> str | None:
    """The route's hint for the door of step ``n``: the last turn before it (docs/maps.md)."""
    return next((str(s.get("turn")) for s in reversed(steps[:n]) if s.get("turn")), None)


def seen_wall_ends_at(ranges: Sequence[float], i: int) -> bool:
    """Whether sonar ``i`` reads a wall across its axis (not someone standing there).

    A wall square to the axis reads nearer than `END_WALL_SEEN_M` in sonar ``i`` and about
    that over the cosine of 15° in both neighbours (a person, some 0.4 m across, fills
    one sonar's view from 1.5 m on; the neighbours then read past them).
    """
    r = ranges[i]
    if r >= END_WALL_SEEN_M:
        return False
    expect = r / math.cos(math.radians(15))
    return all(abs(ranges[(i + k) % SONARS] - expect) < 0.3 for k in (-1, 1))


def inside_car_by_panel(panel_distance: float) -> bool:
    """Whether the robot is inside a car, its panel read ``panel_distance`` m off."""
    return panel_distance <= PANEL_INSIDE_M


def car_door_open_expr(look: int, dead_mask: int) -> str:
    """The monitor condition of a car's door open ahead, facing it from inside with sonar ``look``.

    Sonar ``look`` reads farther than `DOOR_OPEN_AHEAD_M`, or a live neighbour of it (bit i of
    ``dead_mask``: sonar i is dead) farther than `DOOR_OPEN_BESIDE_M`. A robot off the car's
    middle (its sideways centring misled by a dead sonar on a side, or the car wider than the
    door) looks past the door's middle: the sonar ahead reads a jamb while the door stands open,
    one beside it looks out through the opening.
    """
    parts = [f"sonar.range[{look}] > {DOOR_OPEN_AHEAD_M!r}"]
    for k in ((look - 1) % SONARS, (look + 1) % SONARS):
        if not dead_mask >> k & 1:
            parts.append(f"sonar.range[{k}] > {DOOR_OPEN_BESIDE_M!r}")
    return "(" + " || ".join(parts) + ")"


def square_wall_reading(r: float, k: int) -> float:
    """What sonar ``k`` places off a sonar reading a wall square to its axis ``r`` m off reads.

    Each sonar reads the nearest echo in its cone (`SONAR_CONE_DEG` wide): from that wall, the
    edge of its cone nearest the axis, so ``r`` over the cosine of that edge's bearing, up to
    the sonars' reach (`NO_ECHO_READ_M`).
    """
    nearest = math.radians(max(0.0, abs(k) * 360 / SONARS - SONAR_CONE_DEG / 2))
    return min(r / math.cos(nearest), NO_ECHO_READ_M)


def square_wall_ahead(ranges: Sequence[float], distance: float) -> bool:
    """Whether the robot faces a wall square, about ``distance`` m ahead (a lined-up barcode's).

    Sonar 0 reads within `SQUARE_AHEAD_SLACK_M` of ``distance``; none of the sonars 15° and
    30° off reads nearer than a wall square to the axis would (`square_wall_reading`) by more
    than that (a wall seen aslant reads nearer on one side: 22° off square, 1 m ahead, the
    sonar 30° off some 0.45 m nearer; a wall beside the barcode's, 1 m clear of it as the
    call button is of a lobby's corners (docs/maps.md, "Generated buildings"), is out of their
    cones), and one of those 15° off reads it (the other may look into a car's open door
    beside the button).
    """
    r = ranges[0]
    if abs(r - distance) > SQUARE_AHEAD_SLACK_M:
        return False
    off = {k: ranges[k % SONARS] - square_wall_reading(r, k) for k in (1, -1, 2, -2)}
    return min(off.values()) > -SQUARE_AHEAD_SLACK_M and (
        abs(off[1]) < SQUARE_AHEAD_SLACK_M or abs(off[-1]) < SQUARE_AHEAD_SLACK_M
    )


def wall_wider_than_people_at(ranges: Sequence[float], i: int) -> bool:
    """Whether sonar ``i`` reads a wall across its axis wider than people standing together.

    Nearer than `END_WALL_SEEN_M`, and on each side a sonar 15° off the axis and one 30° off
    (either side) read no farther than a wall square to the axis would (`square_wall_reading`),
    with a tenth to spare. A wall at a slant reads nearer on one side. Someone
    standing (or two side by side) 0.7 to 2.5 m off fills sonar ``i``'s cone and the edges of its
    neighbours', and reads as a short wall square to the axis (`seen_wall_ends_at` takes it); the
    sonars 30° off, both sides, read past them. A wall with a way open on one side of the axis (a
    car's door, a corridor's mouth) still reads on the other.
    """
    r = ranges[i]
    if r >= END_WALL_SEEN_M:
        return False

    def reads_wall(k: int) -> bool:
        return ranges[(i + k) % SONARS] <= 1.1 * square_wall_reading(r, k) + 0.03

    return all(reads_wall(-n) or reads_wall(n) for n in (1, 2))


@dataclass
class Mission:
    """The mission section of the map (`Map::mission_json`)."""

    goal_floor: int
    start_floor: int
    lab_door_barcode: int
    call_button_barcode: int
    office_barcode: int
    car_barcode_first: int
    cars: int
    message: str
    route: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    #: The goal floor's call button barcode (where the `button_to_office` route starts).
    goal_button_barcode: int | None = None
    #: Each floor's call button barcode, for the floors with a lobby.
    lobbies: dict[int, int] = field(default_factory=dict)

    @staticmethod
    def from_json(text: str) -> Mission:
        """Reads the JSON of `Map::mission_json`."""
        m = json.loads(text)
        return Mission(
            goal_floor=int(m["goal_floor"]),
            start_floor=int(m["start"]["floor"]),
            lab_door_barcode=int(m["lab_door_barcode"]),
            call_button_barcode=int(m["call_button_barcode"]),
            office_barcode=int(m["office_barcode"]),
            car_barcode_first=int(m["car_barcode_first"]),
            cars=int(m.get("cars", 4)),
            message=str(m.get("message") or "Hello!"),
            route={str(k): list(v) for k, v in (m.get("route") or {}).items()},
            goal_button_barcode=(
                int(m["goal_button_barcode"]) if m.get("goal_button_barcode") is not None else None
            ),
            lobbies={int(x["floor"]): int(x["barcode"]) for x in m.get("lobbies") or []},
        )


#: A stop of a task: ``("office", goal floor)`` or ``("lobby", floor)``.
Stop = tuple[str, int]


def parse_task(text: str, mission: Mission) -> list[Stop]:
    """The stops of ``--task`` (``office,lobby:3``: see ``situate_sim::task``), checked."""
    stops: list[Stop] = []
    for i, part in enumerate(p.strip() for p in text.split(",")):
        kind, _, floor = part.partition(":")
        if part == "office":
            stops.append(("office", mission.goal_floor))
        elif kind == "lobby" and floor.strip().lstrip("-").isdigit():
            stops.append(("lobby", int(floor)))
        else:
            raise ValueError(f"task {text!r}: stop {i + 1} {part!r}: expected office or lobby:N")
    for kind, level in stops:
        if kind == "lobby" and level not in mission.lobbies:
            raise ValueError(f"task {text!r}: floor {level} has no lobby")
    if ("office", mission.goal_floor) in stops[:-1]:
        raise ValueError(f"task {text!r}: the office must be the last stop (no route leads back)")
    return stops
