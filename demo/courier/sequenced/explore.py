"""Exploring a building without a route: the delivery when the map gives no `route` hints.

With `situate map generate --no-route` (or a hand-drawn map without `route`), the robot is told
only the barcodes it must find (the office's, and each floor's call button) and the floors.
It explores the corridors by the left-hand rule: it follows the corridor, turns into every
side corridor on its left, and where a wall ends the way it turns left if it can, else right,
else back. In corridors that form a tree (every building of docs/maps.md) that walks each
corridor once each way and comes back to where it began: no barcode in reach is missed. As it
goes it notes every barcode it reads and where (`places`, the topological map: which barcode
lies where along which corridor), and the side corridors it turned into: one taken before is
passed (in a tree only a misread opening, a door beside a junction read with it as one, leads
back into one).

On the start floor it explores from the lab door until the call button is in view, then goes
into the lobby. On the goal floor it starts from the lobby's entry, which it finds from the
call button: every floor's lobby is alike (docs/maps.md, "Lobby"), so the entry lies where it
lay from the start floor's button. From there it explores until the office's barcode is in
view; homing on it and passing its door are the route interpreter's (`run_route`).
"""

from __future__ import annotations

import math
from typing import Any

import situate
from courier.geometry import SONARS, Pose, bearing_of, wrap
from courier.link import PhaseFailed
from courier.mission import Mission
from courier.sequenced.lobby import Lobby
from courier.sequenced.routes import FOLLOW_SLICE_S, farther_than, way_made_expr

#: A side is open (a corridor goes that way) when a sonar within 20° of square to it reads
#: farther than this, m: a corridor's wall is at most 1.5 m off its middle, and a side
#: corridor's dead end at least 2 m beyond the crossing's middle (docs/maps.md).
SIDE_OPEN_M = 2.4
#: Exploring begins facing a wall nearer than this (out of a door): the way ends there, m.
START_WALL_M = 1.6
#: Into a side corridor: at least this far along it before a wall ahead ends it, m.
NEW_LEG_M = 1.0
#: Into a side corridor: a side corridor on the left counts only this far along it, m.
OUT_OF_CROSSING_M = 2.0
#: A mouth stood in this near one taken before, facing the same way, is that one, m.
SAME_MOUTH_M = 1.5
#: The call button in view, the robot goes on into the lobby at most this far, m.
INTO_LOBBY_M = 3.0
#: Exploring gives up after this much time on the robot's clock (unless the barcode it looks for
#: came into view: the call button on the start floor, the office's on the goal floor), s.
EXPLORE_BUDGET_S = 900.0
#: A barcode read within this of ahead is homed on from where it was read, rad.
AHEAD_RAD = math.radians(30)
#: A barcode read less than this to the side of the way is on the wall ahead, m.
FACE_AHEAD_M = 0.5
#: Facing a barcode read in passing from this far off its wall, m.
FACE_NOTED_M = 1.2
#: A slice with less than this way made along the corridor is no progress, m.
PROGRESS_M = 0.5


def side_open(ranges: list[float], sign: float) -> bool:
    """Whether a way goes off to the left (``sign`` 1) or right (-1).

    A sonar within 20° of square to that side reads beyond `SIDE_OPEN_M`.
    """
    return any(
        ranges[i] > SIDE_OPEN_M
        for i in range(SONARS)
        if abs(sign * bearing_of(i) - math.pi / 2) <= math.radians(20)
    )


class Explorer(Lobby):
    """The lobby's phases and the route interpreter, and finding the way without route hints."""

    def __init__(self, robot: situate.Robot, mission: Mission, **kw: Any) -> None:
        super().__init__(robot, mission, **kw)
        #: Every barcode read while exploring, by floor and id: where it is (odometry frame).
        self.places: dict[tuple[int, int], tuple[float, float]] = {}
        #: The start floor's lobby entry, from its call button's barcode: how far out from the
        #: button's wall and how far to the left of it (facing the wall), and the way in,
        #: relative to the way the button faces.
        self.lobby_entry: tuple[float, float, float] | None = None

    async def note_barcodes(self) -> None:
        """Notes every barcode in view, and where (the topological map's places)."""
        self.prefetch("barcodes", "odom")
        seen: Any = await self.value("barcodes")
        o = await self.odom()
        if not isinstance(seen, dict):
            return
        ids, bearings, distances = (seen.get(k) or [] for k in ("ids", "bearing", "distance"))
        for code, bearing, distance in zip(ids, bearings, distances, strict=False):
            key = (self.here, int(code))
            if key not in self.places:
                self.places[key] = o.seen_at(float(bearing), float(distance))
                if self.debug:
                    await self.say(f"      barcode {code} read on floor {self.here}")

    async def explore(self, code: int, budget_s: float = EXPLORE_BUDGET_S) -> bool:
        """Explores the corridors by the left-hand rule until barcode ``code`` is in view.

        Begins along ``corridor_heading`` (default: the way the robot faces). True once the
        barcode is in view, False when the time is up.
        """
        await self.say(f"    exploring the corridors for barcode {code} (left-hand rule)")
        heading = self.corridor_heading
        if heading is None:
            heading = (await self.odom()).theta
        self.corridor_heading = heading
        deadline = self.t + budget_s
        await self.set("track_barcode", "id", code)
        seen = f"target.seen && target.id == {code}"
        ahead = await self.wall_ahead_condition()
        leg_start = await self.odom()
        afresh = True
        stalls = 0
        #: Walls ahead that did not stay put, on this leg.
        doubts = 0
        #: The side corridors turned into: where the robot stood in the mouth, and the way in.
        taken: list[tuple[float, float, float]] = []
        # Facing the way, and a wall already (out of a door, the corridor's far wall): the
        # way ends here.
        await self.turn((await self.odom()).turn_to(heading))
        at_wall = (await self.sonar())[0] < START_WALL_M
        while self.t < deadline:
            if at_wall:
                at_wall = False
                ranges = await self.sonar()
                if side_open(ranges, 1.0):
                    turn, what = math.pi / 2, "the way ends: left"
                elif side_open(ranges, -1.0):
                    turn, what = -math.pi / 2, "the way ends: right"
                else:
                    turn, what = math.pi, "a dead end: back"
                await self.say(f"    {what}")
                heading = wrap(heading + turn)
                if not await self.turn((await self.odom()).turn_to(heading)):
                    continue
                self.corridor_heading = heading
                leg_start, afresh, doubts = await self.odom(), True, 0
            await self.restore("follow_hallway", "speed")
            await self.set("fit_wall", "bearing_deg", 0.0)
            await self.set("fit_wall", "half_angle_deg", 45.0)
            await self.use(
                "runaway",
                "avoid",
                "follow_hallway",
                "detect_intersection",
                "fit_wall",
                "track_barcode",
                restart=["detect_intersection", "fit_wall"] if afresh else [],
            )
            afresh = False
            # A wall ahead counts only a little way into a new leg (the crossing corridor's
            # far wall is ahead of a robot just turned into a side corridor's mouth), a side
            # corridor only once the robot is out of the crossing (its other arm is beside
            # the robot entering the mouth; junctions are 1.5 m apart at least).
            into = farther_than(leg_start, NEW_LEG_M)
            out_of_crossing = farther_than(leg_start, OUT_OF_CROSSING_M)
            before = await self.odom()
            got = await self.wait(
                seen,
                f"junction.left && {out_of_crossing}",
                f"{ahead} && {into}",
                within=min(FOLLOW_SLICE_S, max(deadline - self.t, 0.1)),
            )
            await self.note_barcodes()
            if self.debug:
                o = await self.odom()
                await self.say(
                    f"      explore: event {got}, way {math.degrees(heading):.0f}°, odometry {o}"
                )
            if got == 0:
                return True
            if got == 1:
                await self.junction_centre(heading)
                await self.say("    a side corridor on the left: into it")
                heading = wrap(heading + math.pi / 2)
                if not await self.turn((await self.odom()).turn_to(heading)):
                    continue
                self.corridor_heading = heading
                await self.into_mouth(heading, math.pi / 2)
                here = await self.odom()
                if any(
                    math.hypot(here.x - x, here.y - y) < SAME_MOUTH_M
                    and abs(wrap(heading - h)) < math.pi / 4
                    for x, y, h in taken
                ):
                    # Taken before: in a tree of corridors only a door beside a junction
                    # (read with it as one wide opening) leads back into one. On the way.
                    await self.say("    that side corridor was explored already: on")
                    heading = wrap(heading - math.pi / 2)
                    await self.turn((await self.odom()).turn_to(heading))
                    self.corridor_heading = heading
                else:
                    taken.append((here.x, here.y, heading))
                leg_start, afresh = await self.odom(), True
                continue
            if got == 2:
                o = await self.odom()
                off = o.turn_to(heading)
                if abs(off) > math.radians(30):
                    # Facing a side wall (avoidance turned it round clutter): not the end.
                    await self.turn(off)
                    continue
                if abs(off) > math.radians(8):
                    await self.turn(off)
                # Someone standing in the way walks on; a wall with a door in it (the front
                # sonar reads through) never stays put, but it ends the way all the same.
                doubts += 1
                if doubts < 3 and not await self.wall_stays():
                    continue
                at_wall = True
                continue
            # No event in a whole slice: way made along the corridor, or stuck.
            o = await self.odom()
            if before.along(o.x, o.y, heading) > PROGRESS_M:
                stalls = 0
                continue
            stalls += 1
            await self.say(f"    no way made in {FOLLOW_SLICE_S:.0f} s: to the corridor's middle")
            await self.turn(o.turn_to(heading))
            await self.recentre(heading)
            if stalls >= 3:
                await self.unstick()
                await self.turn((await self.odom()).turn_to(heading))
                stalls = 0
        return False

    async def face_noted(self, code: int) -> None:
        """Across the corridor from barcode ``code`` where it was read, facing its wall.

        Read in passing, it may be seen aslant, or from behind a box beside it on its wall
        (docs/maps.md, "Clutter"), where homing straight at it loses it. A barcode beside a
        door is on a wall of the corridor: the side it was read on (or the wall ahead).
        """
        at = self.places.get((self.here, code))
        if at is None:
            return
        heading = self.corridor_heading
        o = await self.odom()
        if heading is None:
            heading = o.theta
        across = o.across(at[0], at[1], heading)
        facing = heading
        if abs(across) >= FACE_AHEAD_M:
            facing = wrap(heading + math.copysign(math.pi / 2, across))
        gx, gy = Pose(at[0], at[1], facing).ahead(-FACE_NOTED_M)
        await self.say(f"    to the corridor across from barcode {code}")
        await self.set("runaway", "safe_distance", 0.15)
        try:
            await self.goto(gx, gy, within=30, speed=0.4)
            await self.turn((await self.odom()).turn_to(facing))
        finally:
            await self.restore("runaway", "safe_distance")

    async def explore_to_lobby(self) -> None:
        """Phase 4 without a route: from the lab door to inside the lobby, its button in view."""
        m = self.m
        self.corridor_heading = self.passed_heading
        if not await self.explore(m.call_button_barcode):
            raise PhaseFailed(f"explored for {EXPLORE_BUDGET_S:.0f} s: no call button found")
        # The button is in view from the corridor into the lobby, or from inside: on into the
        # lobby until it opens on a side (the way in is behind then), never far.
        start = await self.odom()
        heading = start.theta if self.corridor_heading is None else self.corridor_heading
        await self.use(
            "runaway",
            "avoid",
            "follow_hallway",
            "detect_intersection",
            restart=["detect_intersection"],
        )
        made = f"{way_made_expr(start, heading)} > {INTO_LOBBY_M!r}"
        await self.wait("junction.left || junction.right", made, within=30)
        self.followed_heading = heading
        self.entry_heading = heading
        self.entered_at = await self.odom()
        # Where the entry lies from the button: the goal floor's lobby is alike.
        button = m.call_button_barcode
        if (await self.search(button, 60)) and await self.line_up(button, 1.0) and self.wall_fix:
            bx, by, normal = self.wall_fix
            wall = Pose(bx, by, normal)
            e = self.entered_at
            out, left = -wall.along(e.x, e.y), wall.across(e.x, e.y)
            self.lobby_entry = (out, left, wrap(heading - normal))
            if self.debug:
                await self.say(f"      lobby entry from the button: {self.lobby_entry}")

    async def explore_to_office(self) -> None:
        """Phases 11 and 12 without a route: out of the lobby, exploring for the office."""
        m = self.m
        button = m.goal_button_barcode
        if button is not None and self.lobby_entry is not None:
            await self.to_button(button)
            if self.wall_fix is not None:
                bx, by, normal = self.wall_fix
                wall = Pose(bx, by, normal)
                out, left, way_in = self.lobby_entry
                ex, ey = wall.ahead(-out)
                ex, ey = ex - left * math.sin(normal), ey + left * math.cos(normal)
                way_out = wrap(normal + way_in + math.pi)
                await self.say("    to the lobby's entry (where it lay on the start floor)")
                await self.set("runaway", "safe_distance", 0.15)
                await self.goto(ex, ey, within=40, speed=0.5)
                await self.restore("runaway", "safe_distance")
                await self.turn((await self.odom()).turn_to(way_out))
                self.corridor_heading = way_out
        await self.phase(11, f"exploring for the office's barcode {m.office_barcode}")
        if not await self.explore(m.office_barcode):
            raise PhaseFailed(f"explored for {EXPLORE_BUDGET_S:.0f} s: no office barcode found")

        # Read about straight ahead, it is homed on from here, as after a route's `until:
        # barcode`; else (read aslant, turning at a dead end) from across the corridor.
        target = await self.value("target")
        if not target["seen"] or abs(float(target["bearing"])) > AHEAD_RAD:
            await self.face_noted(m.office_barcode)

        async def homing(barcode: int) -> None:
            await self.phase(12, f"homing on barcode {barcode}, passing the door")

        steps: list[dict[str, Any]] = [{"home": m.office_barcode}, {"pass": "door"}]
        await self.run_route("explored", steps, on_home=homing)
