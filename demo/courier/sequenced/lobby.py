"""The elevator lobby: phases 5 to 7 of the delivery, calling a car and boarding it.

The robot pushes the call button, patrols the lobby along the walls that may hold cars
(all but the entry's: docs/maps.md, "Lobby"), watching for a car's door standing open
(`open_in_walls`, `std.watch_openings`), reads which car it is, and enters. `Lobby` holds the
mission's state too (the floors, the button's pose, the way into the lobby):
`delivery.Delivery` is a `Lobby` with the other phases.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import situate
from courier.geometry import SONARS, Pose, bearing_of, wrap
from courier.link import PhaseFailed
from courier.mission import (
    NORMAL,
    OPENED_ON_WALL_M,
    Mission,
    inside_car_by_panel,
    seen_wall_ends_at,
    square_wall_ahead,
    square_wall_reading,
    wall_wider_than_people_at,
)
from courier.sequenced.routes import RouteSequencer, way_made_expr

#: The robot pushes the call button from this far from it (its centre from the barcode), m.
BUTTON_STANDOFF_M = 0.45
#: From where the button was pushed, back this far to patrol the lobby: about the middle of a
#: car door on a wall next to the button's (docs/maps.md, "Lobby"), m.
PATROL_BACK_M = 0.85
#: In front of a car's door that opened, this far from its wall, before entering, m.
FACE_DOOR_M = 0.85
#: Abreast of a door that opened within this (along its wall), the robot only turns to it, m.
ABREAST_M = 0.35
#: Along a side wall of a lobby entered facing the button, the patrol stops this short of
#: where the route left the robot inside (the entry is beyond), m; it goes there only if that
#: is this much deeper than the patrol line along the button's wall, m.
SIDE_LEG_SHORT_M = 0.3
SIDE_LEG_MIN_M = 0.8
#: The patrol looks this often for a door standing open in a known wall of the lobby, s.
OPEN_POLL_S = 0.5
#: A known wall is watched this near (along a sonar's axis), m; an opening must read this much
#: farther than the wall (a car is at least 1.8 m deep), m; and lie this far inside the
#: lobby's other walls (not a corner's), m.
OPEN_SEEN_M = 3.4
#: A sonar reading this far heard no echo (its reach is 4 m), m.
NO_ECHO_M = 3.95
OPEN_BEYOND_M = 1.0
#: A car is at most this deep behind its door (shafts are 1.8 to 2.4 m on each side:
#: docs/maps.md, "Lobby"), m; a sonar that looks through an open car door hears its walls
#: unless they are within this of the sonars' reach (odometry and noise), m.
CAR_DEPTH_MAX_M = 2.4
CAR_ECHO_SLACK_M = 0.15
OPEN_INSIDE_M = 0.4
#: Beyond the depth a route left the robot inside a lobby entered facing the button, nothing
#: is a car's door (the entry's wall is 1 m on in generated buildings), m.
ENTRY_BEYOND_M = 0.5
#: A wall seen ahead is one known already if that near its line (of about its heading), m.
KNOWN_WALL_M = 0.5
#: Calls for a car made at least, and at most while the mission has time left for the rest.
CALLS_MIN = 6
CALLS_MAX = 20
#: Time the mission keeps for the ride, the way to the office and the message after boarding, s.
AFTER_BOARDING_S = 600.0


def dist(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """The distance between two places (x, y, …), m."""
    return math.hypot(a[0] - b[0], a[1] - b[1])


def open_in_walls(
    o: Pose,
    ranges: Sequence[float],
    walls: Sequence[tuple[float, float, float]],
    bounds: Sequence[tuple[float, float, float]],
) -> tuple[float, float, float] | None:
    """Where a sonar reads through one of the lobby's known ``walls``: a door open in it.

    Each wall is a point and its normal (towards it), odometry frame. A sonar whose axis meets
    a wall within 60° of square, nearer than `OPEN_SEEN_M`, at a point inside the lobby
    (short of every other wall and bound in ``bounds``), but that reads `OPEN_BEYOND_M`
    farther, sees through it: its whole cone passes an opening there (a car's door: it hears
    the car's walls beyond, or reads no echo only where they may be out of its reach). Returns
    the point and the wall's normal, the nearest such; None if there is none.
    """
    best: tuple[float, float, float] | None = None
    best_range = math.inf
    for i, r in enumerate(ranges):
        a = o.theta + bearing_of(i)
        ca, sa = math.cos(a), math.sin(a)
        for wx, wy, wn in walls:
            cn, sn = math.cos(wn), math.sin(wn)
            square = ca * cn + sa * sn
            if square < 0.5:
                continue
            expect = o.along(wx, wy, wn) / square
            # (Farther than the sonars' reach less the car's depth: no echo at all.)
            if not 0.3 < expect < OPEN_SEEN_M or r < min(expect + OPEN_BEYOND_M, NO_ECHO_M):
                continue
            # No echo at all where the car's own walls would echo: a missed echo (they come
            # often, one sonar at a time, and two of them a poll apart near one spot of a wall
            # passed close by looked like a door standing open), not an opening.
            if r >= NO_ECHO_M and expect + CAR_DEPTH_MAX_M / square < NO_ECHO_M - CAR_ECHO_SLACK_M:
                continue
            px, py = o.ahead(expect, a)
            inside = all(
                Pose(bx, by, bn).along(px, py) < -OPEN_INSIDE_M
                for bx, by, bn in bounds
                if abs(wrap(bn - wn)) > 0.5
            )
            if inside and expect < best_range:
                best, best_range = (px, py, wn), expect
    return best


def new_wall_ahead(
    o: Pose, ranges: Sequence[float], walls: Sequence[tuple[float, float, float]]
) -> tuple[float, float, float] | None:
    """The wall across sonar 0's axis (not someone standing there), unless already known.

    Sonar 0 reads it nearer than `OPEN_SEEN_M`, and on one side at least the sonars 15° and
    30° off read it too, square to the axis (`square_wall_reading`, within 0.3 m): the
    other side may see the wall the patrol walks along, nearer. Someone standing ahead fills
    sonar 0's cone and its neighbours' edges; the sonars 30° off read past them (or the wall
    beside, nearer). Returns a point on it and the normal towards it (the robot's heading),
    odometry frame, as ``walls`` holds them; None if there is no such wall or a known wall of
    about that heading lies within `KNOWN_WALL_M` of that point (along its normal).
    """
    r = ranges[0]
    if r >= OPEN_SEEN_M:
        return None

    def square_wall_on(side: int) -> bool:
        return all(abs(ranges[k * side % SONARS] - square_wall_reading(r, k)) < 0.3 for k in (1, 2))

    if not (square_wall_on(1) or square_wall_on(-1)):
        return None
    x, y = o.ahead(ranges[0])
    return None if wall_known(walls, (x, y, o.theta)) else (x, y, o.theta)


def wall_known(walls: Sequence[tuple[float, float, float]], w: tuple[float, float, float]) -> bool:
    """Whether a known wall of about ``w``'s heading has ``w``'s point within `KNOWN_WALL_M`."""
    return any(
        abs(wrap(wn - w[2])) < 0.5 and abs(Pose(wx, wy, wn).along(w[0], w[1])) < KNOWN_WALL_M
        for wx, wy, wn in walls
    )


class Lobby(RouteSequencer):
    """The lobby's phases of the delivery, and the mission's state they share with the rest."""

    def __init__(self, robot: situate.Robot, mission: Mission, **kw: Any) -> None:
        super().__init__(robot, normal=NORMAL, **kw)
        self.m = mission
        self.car = 0
        #: The floor the robot is on, and the floor the next ride goes to.
        self.here = mission.start_floor
        self.to = mission.goal_floor
        self.button_pose: Pose | None = None
        #: Patrols so far: each starts the other way along the button's wall from the last.
        self.patrols = 0
        #: The way the robot came into this floor's lobby (odometry frame), if a route led it,
        #: and where the route left it inside.
        self.entry_heading: float | None = None
        self.entered_at: Pose | None = None
        #: The way out of the car the robot came to this floor in (odometry): the lobby's
        #: walls are square to it (the shafts' sides are: docs/maps.md, "Lobby"). None on the
        #: start floor.
        self.lobby_axis: float | None = None

    @property
    def button_here(self) -> int:
        """The call button's barcode on the floor the robot is on."""
        return self.m.lobbies.get(self.here, self.m.call_button_barcode)

    async def call_and_board(self) -> None:
        """Phases 5 to 7: call a car, wait for it, identify it, enter it (calling again)."""
        button = self.button_here
        # Each call brings a car picked at random, which may open where the patrol is not:
        # calling again is worth it while the mission has time left for the rest of it.
        for attempt in range(CALLS_MAX):
            if attempt >= CALLS_MIN and self.t > self.limit_s - AFTER_BOARDING_S:
                break
            await self.phase(5, f"homing on the call button (barcode {button})")
            facing = False
            if self.button_pose is not None:
                # Called before: back to where the button was pushed, by odometry (in the
                # lobby, across open floor: at the patrol's speed).
                b = self.button_pose
                back = b.ahead(-0.9)
                await self.set("runaway", "safe_distance", 0.15)
                if await self.goto(*back, within=60, speed=0.6):
                    facing = await self.turn((await self.odom()).turn_to(b.theta), keep=["runaway"])
                await self.restore("runaway", "safe_distance")
            await self.set("track_barcode", "id", button)
            await self.use("runaway", "avoid", "track_barcode")
            self.send("step", cycles=3)
            target = await self.value("target")
            if not target["seen"] and not await self.search(button, 120):
                raise PhaseFailed("the call button is nowhere in sight")
            # Back in front of the button and facing it (the odometry drifts little in a
            # minute in the lobby), it is straight ahead: the last approach only. Else
            # line up with it first.
            straight = facing and target["seen"] and abs(float(target["bearing"])) < 0.2
            homed = (straight or await self.line_up(button, 1.0)) and await self.home_on(
                button, BUTTON_STANDOFF_M, avoid=False, slack=0.12, aim=0.3
            )
            if not homed:
                await self.say("    could not reach the button: backing off, trying again")
                await self.unstick()
                continue
            await self.phase(5, "pushing the call button")
            presses = int(await self.value("arm.presses") or 0)
            await self.set("push_button", "button", 0)
            await self.use("track_barcode", "home", "push_button", restart=["push_button"])
            pushed = await self.wait(f"arm.presses > {presses}", within=10)
            if not pushed:
                o = await self.odom()
                if straight and self.button_pose is not None:
                    # Homed on the barcode from in front of it, not lined up: the robot faces
                    # the barcode, a little aslant, not the wall. The button's pose gives the
                    # wall's normal (the patrol's headings, the button's wall watched): the
                    # last one's, which lining up found. Taken from the heading here, the
                    # slant grew call after call (each call comes back along the last one's
                    # heading): the patrol ran aslant into the wall across the lobby, took it
                    # for the lobby's end and never came to the cars beyond.
                    o = Pose(o.x, o.y, self.button_pose.theta)
                self.button_pose = o
            else:
                await self.restore("runaway", "safe_distance")
                continue
            if await self.wait_for_car():
                return
            await self.say("    no car to board: calling again")
        raise PhaseFailed("could not board a car")

    async def to_button(self, button: int) -> None:
        """Phase 11: about 1 m in front of this floor's call button, facing it."""
        await self.phase(11, f"finding this floor's call button (barcode {button})")
        # Someone passing between may hide the barcode while lining up: look again.
        for attempt in range(3):
            if not await self.look_round(button) and not await self.search(button, 120):
                raise PhaseFailed(f"the call button of floor {self.here} is nowhere in sight")
            if await self.line_up(button, 1.0):
                # The barcode ahead, but no wall square ahead: lined up with a wrong wall (a
                # line fitted through people, or another wall near the corner), the barcode
                # read up to 80° off its facing; the route's turns would then all be off.
                # The lobby's walls are square to the car's door the robot came out of.
                if (
                    attempt == 2
                    or self.lobby_axis is None
                    or square_wall_ahead(await self.sonar(), 1.0)
                ):
                    return
                # Still turning, or someone passing: once more, standing still.
                await self.wait("abs(odom.v) < 0.02 && abs(odom.w) < 0.02", within=1)
                if square_wall_ahead(await self.sonar(), 1.0):
                    return
                await self.say(f"    lined up with barcode {button} aslant: square to the lobby")
                if await self.square_up_on_axes(button, self.lobby_axis, 1.0):
                    return
                continue
            await self.say(f"    could not line up with barcode {button}: again")
        raise PhaseFailed(f"could not line up with barcode {button}")

    async def square_up_on_axes(self, barcode: int, axis: float, standoff: float) -> bool:
        """To ``standoff`` m in front of ``barcode`` (in view), square to a wall on the axes.

        The barcode's wall's normal is one of ``axis`` + k·90° (odometry) within 80° of the
        way to it: each of those, nearest first, until the barcode is straight ahead and a
        wall square ahead (`square_wall_ahead`). False if neither is.
        """
        self.prefetch("target", "odom")
        t = await self.value("target")
        if not (t["seen"] and int(t["id"]) == barcode):
            return False
        o = await self.odom()
        px, py = o.seen_at(float(t["bearing"]), float(t["distance"]))
        toward = math.atan2(py - o.y, px - o.x)
        normals = [wrap(axis + k * math.pi / 2) for k in range(4)]
        normals = [n for n in normals if abs(wrap(n - toward)) < math.radians(80)]
        normals.sort(key=lambda n: abs(wrap(n - toward)))
        if self.debug:
            await self.say(
                f"      barcode at ({px:.2f}, {py:.2f}), normals "
                f"{[round(math.degrees(n)) for n in normals]}, heading {math.degrees(o.theta):.0f}"
            )
        await self.set("runaway", "safe_distance", 0.15)
        try:
            for n in normals:
                # (A wrong wall's point may be out of reach: next to a wall across the way.)
                gx, gy = px - standoff * math.cos(n), py - standoff * math.sin(n)
                await self.goto(gx, gy, within=20)
                if not await self.turn((await self.odom()).turn_to(n)):
                    continue
                ahead, ranges = await self.barcode_ahead(barcode, standoff), await self.sonar()
                if self.debug:
                    looks = [round(ranges[k % SONARS], 2) for k in (-1, 0, 1)]
                    await self.say(f"      facing {math.degrees(n):.0f}: {ahead}, {looks}")
                if ahead and square_wall_ahead(ranges, standoff):
                    self.wall_fix = (px, py, n)
                    return True
        finally:
            await self.restore("runaway", "safe_distance")
        return False

    async def restore_lobby_patrol(self) -> None:
        """The parameters of the lobby patrol (a crowded lobby: nearer to things)."""
        await self.set("runaway", "safe_distance", 0.15)
        await self.set("follow_hallway", "speed", 0.8)
        # A missed echo reads the sonars' reach: two in a row on one sonar, about once in
        # 40 s of the ring's readings, looked like a door opening; three, hardly ever.
        await self.set("watch_openings", "confirm", 3)

    async def wait_for_car(self) -> bool:
        """Patrols the lobby along the cars until a car's door opens, identifies it, enters."""
        m = self.m
        await self.phase(6, "waiting for a car: patrolling the lobby, watching for an open door")
        self.car = 0
        await self.restore_lobby_patrol()
        b = self.button_pose
        if b is not None:
            # The patrol line: PATROL_OFF_M from the button's wall, along it. A car on an end
            # wall (next to the button's wall) is then straight ahead at each end, its panel in
            # view through its open door the whole way towards it; a car on the button's wall
            # passes beside, its door seen by the side sonars.
            # Backwards: turning round to drive there and round again to patrol took some
            # 8 s of a car's 15 to 35 s from the call to its door closing.
            await self.goto(
                *b.ahead(-PATROL_BACK_M),
                within=30,
                speed=0.5,
                reverse_within=1.5,
            )
            # Right first, then left after the next call, and so on: a car on one side whose
            # door stays open only a few seconds is missed while the robot patrols the other
            # side, on every call if the robot always went the same way first.
            first = -math.pi / 2 if self.patrols % 2 == 0 else math.pi / 2
            along = (await self.odom()).turn_to(b.theta + first)
        else:
            along = -math.pi / 2 if self.patrols % 2 == 0 else math.pi / 2
        # The lobby's walls that may hold cars: all but the entry's (docs/maps.md, "Lobby"),
        # anywhere along them. The patrol goes along each, leg by leg (a heading, what ends
        # the leg besides the wall ahead, whether the wall ahead may hold a car):
        # - entered along the button's wall (the entry in a wall beside it): not that wall
        #   both ways (one way leads out through the entry) but round the other three: along
        #   the button's wall away from the entry, along the wall across from the entry,
        #   along the wall across from the button to the entry's wall, and back the same way
        #   to the button;
        # - entered facing the button's wall (the entry across from it): along the button's
        #   wall, turning back at the side walls (the doors of cars at the corners in sight);
        #   every other call (from the second) also along each side wall towards the entry,
        #   as deep as the route came in (the entry is beyond), and back.
        legs: list[tuple[float, str | None, bool]] = []
        corner = False
        if b is not None and self.entry_heading is not None:
            t = self.entry_heading
            u = wrap(b.theta + math.pi)
            depth = way_made_expr(b, u)
            back = wrap(t + math.pi)
            if abs(math.cos(b.turn_to(t))) < 0.5:
                corner = True
                level = f"{way_made_expr(b, back)} > 0.0"
                legs = [
                    (t, None, True),
                    (u, None, True),
                    (back, None, False),
                    (t, None, True),
                    (wrap(u + math.pi), None, True),
                    (back, level, True),
                ]
                along = (await self.odom()).turn_to(t)
            elif self.entered_at is not None and self.patrols % 2 == 1:
                inside = b.along(self.entered_at.x, self.entered_at.y, u) - SIDE_LEG_SHORT_M
                if inside > PATROL_BACK_M + SIDE_LEG_MIN_M:
                    t1 = wrap(b.theta + first)
                    deep = f"{depth} > {inside!r}"
                    shallow = f"{depth} < {PATROL_BACK_M!r}"
                    legs = [
                        (t1, None, True),
                        (u, deep, False),
                        (wrap(u + math.pi), shallow, True),
                        (wrap(t1 + math.pi), None, True),
                        (u, deep, False),
                        (wrap(u + math.pi), shallow, True),
                    ]
        leg = 0
        self.patrols += 1
        if not await self.turn(along, keep=["runaway"]):
            return False
        await self.set("identify_car", "first_id", m.car_barcode_first)
        await self.set("identify_car", "cars", m.cars)
        # The lobby's end walls found so far (a point and the normal towards the wall,
        # odometry frame), where the patrol turned back. A way that opens on one of them is
        # a car's door (one that opened just after the robot turned back there); elsewhere
        # it is someone who stood still and walked off, or a doorway the patrol's own motion
        # revealed. A car's door on the patrol's own wall is left to the door detector,
        # which sees it beside the robot, face-on. The robot goes to stand in front of the
        # door, facing its wall (seen aslant from afar, the car's panel is not read).
        walls: list[tuple[float, float, float]] = []
        if b is not None:
            # The button's wall holds nothing but cars (docs/maps.md, "Lobby"): a way that
            # opens on it is a car's door, one the patrol may be walking away from.
            r = BUTTON_STANDOFF_M
            walls.append((*b.ahead(r), b.theta))
        # The end walls in sonar reach from where the patrol begins, ahead and behind: a car's
        # door on the one behind (a short lobby) is seen opening while the robot walks the
        # other way, not only after the robot came to it and turned back there.
        ranges = await self.sonar()
        o = await self.odom()
        # (Round three walls, the one behind is towards the entry.) Someone standing in the
        # lobby, taken for an end wall, would bound it short of the real one (a car opening
        # there is then beyond the lobby) and read as a way opening in it when they walk off.
        for i in (0,) if legs else (0, SONARS // 2):
            if seen_wall_ends_at(ranges, i) and wall_wider_than_people_at(ranges, i):
                toward = o.heading_of(bearing_of(i))
                r = ranges[i]
                walls.append((*o.ahead(r, toward), toward))
        if self.debug:
            looks = [round(ranges[k % SONARS], 2) for k in (-2, -1, 0, 1, 2, 10, 11, 12, 13, 14)]
            await self.say(f"      walls known: {len(walls)} (sonars {looks})")
        # What else bounds the lobby (the entry's wall, or how deep the route came in): a
        # way seen open beyond it is no car's door.
        bounds = list(walls)
        if b is not None and self.entered_at is not None and not corner:
            into = wrap(b.theta + math.pi)
            far = b.along(self.entered_at.x, self.entered_at.y, into) + ENTRY_BEYOND_M
            bounds.append((*b.ahead(far, into), into))
        deadline = self.t + 60
        afresh = ["detect_door", "watch_openings", "identify_car"]
        polled = False
        last_open: tuple[float, float, float] | None = None
        while self.t < deadline:
            # A door opening beside the robot (either wall: cars may be on any), or a car's
            # panel barcode in view ahead through its open door.
            # Any door that opens within the sonars' reach, face-on (behind the robot just
            # turned back at an end, or across the lobby), is seen at once too
            # (`std.watch_openings`), not only when the patrol passes it.
            if not polled:
                await self.use(
                    "runaway",
                    "follow_hallway",
                    "detect_door",
                    "watch_openings",
                    "identify_car",
                    restart=afresh,
                )
                afresh = ["detect_door", "watch_openings", "identify_car"]
            polled = False
            conditions = [
                "door.left || door.right",
                "car > 0",
                "sonar.range[0] < 0.75 && abs(odom.v) < 0.03",
                "opened.seen",
            ]
            if legs and legs[leg][1] is not None:
                conditions.append(str(legs[leg][1]))
            got = await self.wait(*conditions, within=min(OPEN_POLL_S, deadline - self.t))
            spot: tuple[float, float, float] | None = None
            if got == len(conditions):
                if self.t >= deadline:
                    break
                # A door already open (it opened while the robot turned, or where the watch
                # cannot see a reading jump): a sonar reads through a known wall of the
                # lobby. Twice in a row at one place (not a missed echo).
                polled = True
                self.prefetch("odom", "sonar.range")  # one round trip for both
                o, ranges = await self.odom(), await self.sonar()
                # The wall the patrol walks towards is known as soon as it is in sight, not
                # only once the robot stands at it: a car's door there may open (and close
                # again) while the robot is still on its way. (Not on a leg that ends short
                # of the wall ahead: that one is the entry's, or the button's.)
                ahead_wall = new_wall_ahead(o, ranges, walls)
                to_wall = not legs or (legs[leg][2] and legs[leg][1] is None)
                if ahead_wall is not None and to_wall:
                    walls.append(ahead_wall)
                    bounds.append(ahead_wall)
                seen = open_in_walls(o, ranges, walls, bounds)
                if seen is None or last_open is None or dist(seen, last_open) > 0.5:
                    last_open = seen
                    continue
                if self.debug:
                    await self.say(f"      open in a known wall at ({seen[0]:.2f}, {seen[1]:.2f})")
                spot, last_open, got = seen, None, 3
            if got in (2, 4):
                o = await self.odom()
                # The wall ahead, unless it is the entry's (the way out of the lobby): that
                # only bounds it.
                if got == 2:
                    # (Someone standing in the way is no wall: the patrol turns back there
                    # all the same.)
                    ahead = await self.sonar()
                    end = (*o.ahead(ahead[0]), o.theta)
                    if wall_wider_than_people_at(ahead, 0):
                        if not legs or legs[leg][2]:
                            walls.append(end)
                        bounds.append(end)
                    elif self.debug:
                        await self.say(f"      no wall ahead but someone: {ahead[-2:] + ahead[:3]}")
                if legs:
                    leg = (leg + 1) % len(legs)
                    await self.say("    end of the lobby's wall: along the next one")
                    turned = await self.turn(o.turn_to(legs[leg][0]), keep=["runaway"])
                else:
                    await self.say("    end of the lobby: turning back")
                    turned = await self.turn(math.pi, keep=["runaway"])
                if not turned:
                    return False
                continue
            if got == 1:
                code = m.car_barcode_first + int(await self.value("car")) - 1
                await self.set("track_barcode", "id", code)
                await self.use("runaway", "track_barcode")
                self.send("step", cycles=1)
                bearing = float((await self.value("target"))["bearing"])
            elif got == 3 and spot is not None:
                o = await self.odom()
                px, py, on = spot[0], spot[1], [spot[2]]
            elif got == 3:
                self.prefetch("opened", "odom")  # the turn reads the odometry
                opened = await self.value("opened")
                bearing = float(opened["bearing"])
                o = await self.odom()
                px, py = o.seen_at(bearing, float(opened["before"]))
                on = [
                    wn
                    for wx, wy, wn in walls
                    if abs(Pose(wx, wy, wn).along(px, py)) < OPENED_ON_WALL_M
                ]
                # A door opening ahead on the wall the patrol walks along is the door
                # detector's: it sees it beside the robot a moment later, face-on, and the
                # robot turns straight into it (going to stand in front of it takes longer
                # than some cars stay open). Beside or behind the robot, or on an end wall,
                # it is this.
                ahead_along = [
                    wn
                    for wn in on
                    if abs(math.cos(wn - o.theta)) < 0.5 and abs(bearing) < math.radians(60)
                ]
                if self.debug:
                    await self.say(
                        f"      opened {opened}, on a known wall: {bool(on)}"
                        f"{' (ahead, along it)' if ahead_along else ''}"
                    )
                if not on or ahead_along:
                    # The watch starts afresh; the door detector keeps the walls it tracks.
                    afresh = ["watch_openings"]
                    continue
            if got == 3:
                gx, gy = Pose(px, py, on[0]).ahead(-FACE_DOOR_M)  # in front of the door
                # Abreast of the door already (it opened beside the robot), the robot only
                # turns to face it: entering works from a little farther off the wall too.
                abreast = abs(o.across(gx, gy, on[0]))
                off_wall = o.along(px, py, on[0])
                if abreast > ABREAST_M or not 0.6 < off_wall < 1.6:
                    await self.set("runaway", "safe_distance", 0.12)
                    # Backwards if the door is just behind (the robot walked past it).
                    # (At the patrol's speed: some cars stay open only 8 s.)
                    await self.goto(gx, gy, within=10, speed=0.8, reverse_within=1.5)
                    await self.restore_lobby_patrol()
                bearing = (await self.odom()).turn_to(on[0])
            elif got == 0:
                self.prefetch("door", "odom")  # the turn reads the odometry
                bearing = float((await self.value("door"))["bearing"])
            await self.phase(6, "a car's door opened: facing it, reading which car it is")
            if not await self.turn(bearing, keep=["runaway", "identify_car"]):
                continue
            await self.set("runaway", "safe_distance", 0.1)
            await self.set("enter_car", "distance", 4.0)
            await self.set("enter_car", "speed", 0.5)
            await self.use("runaway", "enter_car", "identify_car", restart=["enter_car"])
            started = self.t
            got = await self.wait(
                "car > 0", "car_entered", f"car == 0 && time >= {started + 4!r}", within=20
            )
            if got == 2:
                # An opening that shows no car's panel: some other door, or a car that was
                # closing. On with the patrol.
                await self.say("    no car behind that opening: patrolling on")
                await self.restore_lobby_patrol()
                again = (await self.odom()).turn_to(legs[leg][0]) if legs else -bearing
                if await self.turn(again, keep=["runaway"]):
                    continue
                break
            if got == 0:
                self.car = int(await self.value("car"))
                await self.phase(7, f"car {self.car} arrived: entering it")
                await self.wait("car_entered", within=20)
            # Inside? Walls all round but for the door (the sonars), and the car's own
            # barcode on the panel, near once the robot looks round.
            self.car = int(await self.value("car")) or self.car
            if self.car == 0 and not await self.enclosed():
                # Stopped short of an opening with no panel read (come at it off its middle,
                # a jamb ahead): while the way ahead is open, to its middle and in again.
                for _again in range(2):
                    if not await self.centre_on_opening():
                        break
                    await self.use("runaway", "enter_car", "identify_car", restart=["enter_car"])
                    await self.wait("car_entered", within=15)
                    self.car = int(await self.value("car")) or self.car
                    if await self.enclosed():
                        if self.car == 0:
                            await self.use("identify_car")
                            self.send("step", cycles=3)
                            self.car = int(await self.value("car"))
                        break
            code = m.car_barcode_first + self.car - 1
            if self.car > 0 and not await self.enclosed():
                # Stopped short: aslant in the doorway, a jamb ahead. While the car's panel
                # is in view, its door is open: facing the panel, in again.
                for _again in range(2):
                    if not await self.face_barcode(code):
                        break
                    await self.use("runaway", "enter_car", restart=["enter_car"])
                    await self.wait("car_entered", within=15)
                    if await self.enclosed():
                        break
            for again in range(2):
                if not (self.car > 0 and await self.enclosed() and await self.look_round(code)):
                    break
                # Walls and people near all round, the panel in view through the open door:
                # stopped short outside (someone in the way) unless the panel is near.
                if inside_car_by_panel(float((await self.value("target"))["distance"])):
                    await self.say(f"    inside car {self.car}")
                    return True
                if self.debug:
                    await self.say("      the panel is too far: outside the car")
                if again or not await self.face_barcode(code):
                    break
                await self.use("runaway", "enter_car", restart=["enter_car"])
                await self.wait("car_entered", within=15)
            if self.debug:
                await self.say(f"      car {self.car} target {await self.value('target')}")
            await self.say("    the car left before the robot got in")
            break
        await self.restore("runaway", "safe_distance")
        await self.restore("follow_hallway", "speed")
        await self.restore("watch_openings", "confirm")
        return False

    async def centre_on_opening(self) -> bool:
        """Facing an opening in a wall just ahead: sideways to its middle. False if none.

        The sonars within 45° of ahead that read well past the nearest of them (the wall, the
        jambs) see through the opening; its middle is between the outermost of them, where
        they cross the wall's line.
        """
        # The device's readings of the sonars that ever heard an echo (`note_echoes`): the
        # sonar filter fills a dead one in from its neighbours, which see the jambs.
        await self.note_echoes()
        ranges = [float(r) for r in await self.value("sonar.raw")]
        ahead = [k % SONARS for k in range(-3, 4) if self.echoed >> (k % SONARS) & 1]
        if not ahead:
            return False
        wall = min(ranges[k] * math.cos(bearing_of(k)) for k in ahead)
        through = [
            wall * math.tan(bearing_of(k))
            for k in ahead
            if ranges[k] * math.cos(bearing_of(k)) > wall + OPEN_BEYOND_M
        ]
        if not through or wall > OPEN_SEEN_M:
            return False
        shift = (min(through) + max(through)) / 2
        if self.debug:
            await self.say(f"      an opening {wall:.2f} m ahead, {shift:+.2f} m to the left")
        if abs(shift) > 0.08:
            await self.shift_sideways(shift, (await self.odom()).theta)
        return True
