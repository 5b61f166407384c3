"""The sequenced robot's shared behaviours, on top of the link (`courier.link.Link`).

A mission (such as `delivery`) is a short narrative of phases. `courier.link.Link` gives it the
means to drive the robot: waits on the robot's clock, switching skills, parameters, reading
values. `Sequencer` adds the behaviours built of the standard skills (`std.*`, see
crates/components/situate_skills) that any mission of the mobile robot needs: turning, homing on a
barcode, driving to a point of the odometry frame, lining up with a barcode on a wall,
passing the door ahead, searching for a barcode, getting unstuck. The interpreter of route
hints (docs/maps.md) is `routes`, over this.

Perception is the skills' job: the wall ahead is `std.fit_wall`'s `wall`, the door in it
`std.locate_door`'s `opening`; the sequencer activates them and reads their outputs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import situate
from courier.geometry import SONARS, Pose, bearing_of, live_sonar_ahead, sonar_toward, wrap
from courier.link import Link
from courier.mission import (
    CLUTTER_DEPTH_M,
    DOOR_BESIDE_BARCODE_M,
    DOOR_OFF_WALL_M,
    DOOR_WAIT_S,
    HINT_DOOR_AHEAD_M,
    HINT_DOOR_ASIDE_M,
    WALL_AHEAD_M,
)

ROBOT_RADIUS = 0.25
#: How far in front of a door the robot lines up before passing it, m.
DOOR_STANDOFF = 0.9
#: Openings wider than this are not a door; a door is taken to be DOOR_WIDTH wide, m.
MAX_DOOR_WIDTH = 1.6
DOOR_WIDTH = 1.1
#: A raw sonar reading under this is an echo (the device reads 4 m for none), m.
ECHO_M = 3.9
ALL_SONARS = (1 << SONARS) - 1
#: How long a wall across the way must stay put while the robot stands (people move on), s.
WALL_STAYS_S = 6.0
#: Through a door: this far beyond the wall's line, m.
BEYOND_WALL_M = 0.4
#: Wandering between two looks round, s.
SEARCH_LEG_S = 20.0
#: Homing that gets no closer for this long steps aside, s.
HOME_PROGRESS_S = 8.0


def not_its_door(
    fix: Mapping[str, Any] | None,
    at: tuple[float, float] | None,
    hint: str | None,
    barcode: int | None,
) -> str | None:
    """Why the opening ``fix`` (`std.locate_door`'s, robot frame) is not the barcode's door.

    None when it may be: no opening, or one in the barcode's wall (within `DOOR_OFF_WALL_M`
    of the barcode at ``at``, robot frame: ahead, left; None: unknown, taken straight ahead)
    within `DOOR_BESIDE_BARCODE_M` of it along that wall and, with the route's ``hint``, on
    that side of it (the robot squared up in front of the barcode, docs/maps.md). Otherwise
    where it is (``"1.2 m to the right of barcode 40"``).
    """
    if fix is None or not fix.get("seen", True):
        return None
    x, y, width = float(fix["x"]), float(fix["y"]), float(fix["width"])
    ref = 0.0 if at is None else at[1]
    side = "left" if y > ref else "right"
    gap = abs(y - ref) - width / 2
    of = f"of barcode {barcode}" if barcode is not None else "of the barcode"
    if at is not None and gap > DOOR_BESIDE_BARCODE_M:
        return f"{gap:.1f} m to the {side} {of}"
    if at is not None and "normal" in fix:
        # A barcode is stuck on the door's wall (docs/maps.md): an opening whose wall runs
        # well in front of or behind it is another way seen through the door (the far
        # wall's end across a corridor, a room beyond).
        n = float(fix["normal"])
        off = (x - at[0]) * math.cos(n) + (y - at[1]) * math.sin(n)
        if abs(off) > DOOR_OFF_WALL_M:
            where = "beyond" if off > 0 else "in front of"
            return f"in a wall {abs(off):.1f} m {where} the wall {of}"
    if hint in ("left", "right") and side != hint:
        return f"to the {side} {of} (the route's door is to the {hint})"
    return None


class Sequencer(Link):
    """A `Link` with the behaviours the phases of a mission share.

    It keeps what they leave behind for each other: the searches so far, the corridor's
    heading, the last barcode lined up with and the heading the last door was passed at.
    """

    def __init__(self, robot: situate.Robot, **kw: Any) -> None:
        super().__init__(robot, **kw)
        #: Searches so far: each wanders along a path of its own (seeded by ``seed`` and this).
        self.searches = 0
        #: The odometry heading a route planned the robot to be following (see `run_route`).
        self.corridor_heading: float | None = None
        #: The barcode last lined up with and its wall's normal (odometry frame): x, y, rad.
        self.wall_fix: tuple[float, float, float] | None = None
        #: The barcode last placed (its id and where, odometry frame), with or without a wall.
        self.barcode_place: tuple[int, float, float] | None = None
        #: The odometry heading the last door was passed at (out through it).
        self.passed_heading: float | None = None
        #: The middle of the last door passed (odometry frame, m), as it was found.
        self.passed_door: tuple[float, float] | None = None
        #: The heading the route planned for its last `follow` step (odometry frame).
        self.followed_heading: float | None = None
        #: Sonars that heard an echo in the run (bit k: sonar k), noted after each turn.
        self.echoed = 0

    # ----- behaviours the phases share -------------------------------------------------

    async def turn(self, angle: float, *, keep: Sequence[str] = ()) -> bool:
        """Turns in place by ``angle`` (rad, left positive); False on time-out."""
        start = await self.odom()
        goal = start.theta + angle
        await self.set("turn", "angle", angle)
        await self.use("turn", *keep, restart=["turn"])
        # Loosely: `start` may be a cycle older than the skill's own start (the robot still
        # turning from what it did before); the turn rate under 0.1 rad/s says it is done.
        near = " || ".join(
            f"abs(odom.theta - {goal + k * 2 * math.pi:.4f}) < 0.15" for k in (-1, 0, 1)
        )
        done = await self.wait(f"({near}) && abs(odom.w) < 0.1", within=5 + abs(angle) / 0.4)
        if self.echoed != ALL_SONARS:
            await self.note_echoes()
        return done == 0

    async def home_on(
        self,
        barcode: int,
        stop: float,
        *,
        within: float = 40,
        avoid: bool = True,
        runaway: bool | None = None,
        slack: float = 0.06,
        aim: float = 0.12,
    ) -> bool:
        """Homes on ``barcode`` until ``stop`` m from it (it must be in view).

        Done when within ``stop + slack`` m and ``aim`` rad of straight ahead, standing still.
        Without ``avoid``, only the barcode (and, if not near a wall, runaway) steers.
        """
        await self.set("track_barcode", "id", barcode)
        await self.set("home", "stop_distance", stop)
        keep = (["runaway"] if (avoid if runaway is None else runaway) else []) + (
            ["avoid"] if avoid else []
        )
        end = self.t + within
        detours = 0
        while True:
            await self.use(*keep, "track_barcode", "home")
            t = await self.value("target")
            closer = float(t["distance"]) - 0.25 if t and t["seen"] else 0.0
            got = await self.wait(
                f"target.seen && target.id == {barcode} && target.distance < {stop + slack:.3f}"
                f" && abs(target.bearing) < {aim} && abs(odom.v) < 0.03",
                f"!target.seen && time > {self.t + 1:.3f}",
                f"target.seen && target.distance < {closer:.3f}",
                within=min(HOME_PROGRESS_S, max(end - self.t, 0.1)),
            )
            if got == 2:
                continue  # getting closer
            if got == 3 and self.t < end and detours < 3:
                # No progress: something is in the way. Step aside, then home again.
                detours += 1
                await self.say("    something in the way: stepping aside")
                bearing = float(t["bearing"]) if t else 0.0
                px, py = await self.to_frame(
                    float(t["distance"]) * math.cos(bearing),
                    float(t["distance"]) * math.sin(bearing),
                )
                await self.sidestep(bearing, keep=["track_barcode"])
                # Face where the barcode was (odometry) before homing on.
                o = await self.odom()
                await self.turn(o.bearing_to(px, py), keep=["runaway"])
                continue
            break
        if got and self.debug:
            await self.say(f"      home: {got} {await self.value('target')}")
        return got == 0

    async def sidestep(self, bearing: float, *, keep: Sequence[str] = ()) -> None:
        """Moves about a metre to the freer side of ``bearing`` (rad, robot frame)."""
        self.prefetch("sonar.range", "odom")  # the turn reads the odometry
        ranges = await self.sonar()

        def free(b: float) -> float:
            i = sonar_toward(b)
            return min(ranges[(i + k) % SONARS] for k in (-1, 0, 1))

        left, right = free(bearing + math.pi / 2), free(bearing - math.pi / 2)
        side = bearing + (math.pi / 2 if left >= right else -math.pi / 2)
        await self.set("runaway", "safe_distance", 0.15)
        try:
            await self.turn(wrap(side), keep=["runaway", *keep])
            go = max(0.0, min(1.0, max(left, right) - 0.7))
            o = await self.odom()
            if go > 0.1:
                await self.goto(*o.ahead(go), within=10)
        finally:
            await self.restore("runaway", "safe_distance")

    async def goto(
        self,
        x: float,
        y: float,
        *,
        within: float = 40,
        speed: float = 0.3,
        reverse_within: float = 0.0,
    ) -> bool:
        """Drives to (x, y) of the odometry frame at up to ``speed`` m/s.

        A goal behind the robot and at most ``reverse_within`` m away is backed up to
        (`std.home_position`), without turning round twice.
        """
        await self.set("home_position", "speed", speed)
        await self.set("home_position", "reverse_within", reverse_within)
        await self.set("home_position", "x", x)
        await self.set("home_position", "y", y)
        await self.use("runaway", "home_position", restart=["home_position"])
        got = await self.wait(
            f"abs(odom.x - {x:.3f}) < 0.12 && abs(odom.y - {y:.3f}) < 0.12 && abs(odom.v) < 0.03",
            within=within,
        )
        return got == 0

    async def clue(
        self, skill: str, signal: str, *, keep: Sequence[str] = ()
    ) -> dict[str, Any] | None:
        """A perception skill's output as the robot stands: ``signal`` of ``skill`` if ``seen``.

        Only ``skill`` and ``keep`` are on (nothing drives: the base stops), for a few cycles.
        """
        await self.use(*keep, skill, restart=[skill])
        self.send("step", cycles=3)
        self.prefetch(signal, "odom")
        value = await self.value(signal)
        return dict(value) if value and value.get("seen") else None

    async def to_frame(self, x: float, y: float) -> tuple[float, float]:
        """A point of the robot frame in the odometry frame."""
        return (await self.odom()).from_robot(x, y)

    async def line_up(self, barcode: int, standoff: float) -> bool:
        """From in view of ``barcode`` on a wall: to ``standoff`` m straight in front of it.

        Homes to about 1.6 m (straight at it: no avoidance, which would slide the robot along
        the wall), fits the wall the barcode is on (`std.fit_wall` looking towards it: a side
        wall of a corridor as well as the wall ahead), drives to the point on the barcode's
        normal and turns to face the wall. Everything is placed in the odometry frame, each
        reading with the pose it was taken at.
        """
        await self.set("runaway", "safe_distance", 0.15)
        try:
            if not await self.home_on(barcode, 1.6, avoid=False, runaway=True, slack=0.3, aim=0.3):
                return False
        finally:
            await self.restore("runaway", "safe_distance")
        fix = await self.barcode_wall(barcode)
        if fix is None:
            return False
        px, py, normal = fix
        # The wall is checked where the robot ends up: facing it, the barcode must be in
        # view straight ahead (a barcode is read only from within 80° of the way it faces).
        # A line fitted through people or clutter across the way, taken for the wall, puts
        # the robot beside the barcode, where it is not read: then the next likeliest wall
        # (square to the first, on the side the barcode was read from) is tried.
        o = await self.odom()
        towards = math.atan2(py - o.y, px - o.x)
        others = [normal + k * math.pi / 2 for k in (1, -1)]
        others = [n for n in others if abs(wrap(n - towards)) < math.radians(80)]
        others.sort(key=lambda n: abs(wrap(n - towards)))
        # Runaway keeps only a little room: a box beside the barcode on its wall (docs/maps.md,
        # "Clutter": up to 0.5 m deep, 5 cm from it) comes within its usual 0.3 m of the
        # point in front of the barcode, which the robot then never reached.
        await self.set("runaway", "safe_distance", 0.15)
        try:
            for n in [normal, *others][:2]:
                gx, gy = px - standoff * math.cos(n), py - standoff * math.sin(n)
                if not await self.goto(gx, gy, within=30):
                    return False
                if not await self.turn((await self.odom()).turn_to(n)):
                    return False
                if await self.barcode_ahead(barcode, standoff):
                    self.wall_fix = (px, py, wrap(n))
                    return True
                await self.say(
                    f"    barcode {barcode} not straight ahead: lining up with another wall"
                )
        finally:
            await self.restore("runaway", "safe_distance")
        return False

    async def barcode_ahead(self, barcode: int, distance: float) -> bool:
        """Whether ``barcode`` is in view about straight ahead, about ``distance`` m away."""
        await self.set("track_barcode", "id", barcode)
        await self.use("track_barcode")
        self.send("step", cycles=3)
        t = await self.value("target")
        return bool(
            t["seen"]
            and int(t["id"]) == barcode
            and abs(float(t["bearing"])) < 0.35
            and abs(float(t["distance"]) - distance) < 0.45
        )

    async def barcode_wall(self, barcode: int) -> tuple[float, float, float] | None:
        """Where ``barcode`` (in view) is and the wall it is on, as the robot stands.

        The barcode's place and its wall's normal (towards the wall), in the odometry
        frame: the wall fitted through it (`std.fit_wall` looking towards it), or, failing
        that, the corridor's wall it lies on. None if it is out of view or no wall is found.
        """
        # Standing still (the base may still be turning when homing ends): the barcode's place.
        await self.use("track_barcode")
        await self.wait("abs(odom.v) < 0.02 && abs(odom.w) < 0.02", within=3)
        self.prefetch("target", "odom")
        t = await self.value("target")
        if not t["seen"]:
            return None
        o = await self.odom()
        bearing, distance = float(t["bearing"]), float(t["distance"])
        px, py = o.seen_at(bearing, distance)
        self.barcode_place = (barcode, px, py)
        # Looking towards the barcode first; a door beside it may hide most of that wall from
        # the sonars, so then wider. The wall must be the barcode's: it lies on its line.
        # In the lab, the skill also gives the barcode's wall (`barcode_wall`): seen aslant
        # with furniture on the wall beside the barcode (a bin), the scan's best line may run
        # through the jamb, the bin's corner and the lab beyond, and still pass near the
        # barcode; the line through the barcode's point is then its wall. In a corridor its
        # walls decide (below).
        normal: float | None = None  # in the odometry frame
        in_lab = self.corridor_heading is None
        if in_lab:
            await self.set("fit_wall", "through_distance", distance)
            await self.set("fit_wall", "through_bearing_deg", math.degrees(bearing))
        try:
            for look, half in ((bearing, 60.0), (bearing, 90.0), (0.0, 80.0)):
                await self.set("fit_wall", "bearing_deg", math.degrees(look))
                await self.set("fit_wall", "half_angle_deg", half)
                wall = await self.clue("fit_wall", "wall", keep=["track_barcode"])
                if wall is None:
                    continue
                w = await self.odom()
                n = w.theta + float(wall["normal"])
                own = await self.value("barcode_wall") if in_lab else None
                if own and own.get("seen"):
                    on = w.theta + float(own["normal"])
                    if abs(wrap(on - n)) > 1e-9:
                        await self.say(
                            f"    the wall fitted is {math.degrees(wrap(n - on)):+.0f}° off "
                            f"barcode {barcode}'s: that one"
                        )
                        n, wall = on, own
                along = w.along(px, py, n)
                # Along the corridor the route followed or across it (docs/maps.md): a line
                # fitted through a door's jamb, the room beyond and someone standing by is not.
                square = self.corridor_heading is None or any(
                    abs(wrap(n - self.corridor_heading - k * math.pi / 2)) < math.radians(25)
                    for k in range(4)
                )
                if abs(along - float(wall["distance"])) < 0.35 and square:
                    normal = n
                    break
        finally:
            await self.restore("fit_wall", "through_distance")
            await self.restore("fit_wall", "bearing_deg")
            await self.restore("fit_wall", "half_angle_deg")
        if self.corridor_heading is not None:
            axis = self.corridor_heading
            across = normal is not None and abs(wrap(normal - axis)) < math.radians(25)
            if normal is None or across:
                # No wall through the barcode, or one across the corridor: clutter on both
                # walls or a bin and someone standing by line up across the way too, and
                # barcodes beside doors are mostly on side walls. The corridor's own walls
                # decide (docs/maps.md: along the corridor or across its end).
                normal = await self.corridor_wall_at(barcode, px, py, axis, fitted=normal)
        if normal is None:
            await self.say(f"    no wall through barcode {barcode} in sight")
            return None
        return px, py, normal

    async def corridor_wall_at(
        self, barcode: int, px: float, py: float, axis: float, *, fitted: float | None
    ) -> float:
        """The normal (odometry frame) of the corridor's wall ``barcode`` at (px, py) is on.

        The corridor runs along ``axis``: the point is on a side wall when a wall along the
        corridor lies about as far to that side as the point does (or nearer by clutter's
        depth: the face of a box beside the barcode); on the end wall when a
        wall lies across the corridor about as far ahead as the point, and no side wall
        holds it. ``fitted`` is a wall across the way fitted through the point (kept, with
        its angle, when it is the end wall). Walls fitted, not single echoes: someone
        standing in the corridor is no wall. With neither, the sonars cannot tell (a door
        beside the barcode fills their view): the side it lies to.
        """
        self.prefetch("odom")
        w = await self.odom()
        lateral = w.across(px, py, axis)
        side = axis + math.copysign(math.pi / 2, lateral)
        ahead = w.along(px, py, axis)
        by = await self.wall_towards(side)
        on_side = by is not None and abs(wrap(by[0] - side)) < math.radians(20)
        # As far as the point, or nearer by a box's depth at most: clutter standing along
        # the barcode's wall (in front of it beside the barcode) is no wall of its own.
        nearer = 0.0 if by is None else abs(lateral) - by[1]
        on_side = on_side and -0.35 < nearer < CLUTTER_DEPTH_M + 0.1
        end = await self.wall_towards(axis)
        on_end = end is not None and abs(wrap(end[0] - axis)) < math.radians(20)
        on_end = on_end and end is not None and abs(end[1] - ahead) < 0.35
        if self.debug:
            await self.say(
                f"      end wall {end} ({ahead:.2f} on), side {by} ({lateral:.2f}), fitted {fitted}"
            )
        if on_side or not (on_end or fitted is not None):
            if fitted is None:
                await self.say(
                    f"    no wall through barcode {barcode} in sight: taking the corridor's"
                )
            return side
        return fitted if fitted is not None else axis

    async def wall_towards(self, direction: float) -> tuple[float, float] | None:
        """`std.fit_wall`'s wall within 50° of ``direction`` (odometry frame), as the robot stands.

        Its normal in the odometry frame and its distance; None if none.
        """
        o = await self.odom()
        await self.set("fit_wall", "bearing_deg", math.degrees(o.turn_to(direction)))
        await self.set("fit_wall", "half_angle_deg", 50.0)
        try:
            wall = await self.clue("fit_wall", "wall")
        finally:
            await self.restore("fit_wall", "bearing_deg")
            await self.restore("fit_wall", "half_angle_deg")
        if wall is None:
            return None
        return o.heading_of(float(wall["normal"])), float(wall["distance"])

    async def wall_stays(self) -> bool:
        """Whether the wall `std.fit_wall` sees ahead stays put while the robot stands.

        Two people side by side in a corridor can pass for a wall across it; people do not
        stand still for long (docs/maps.md: a pause of at most 2.5 s, at most 3 s waiting for
        the robot), walls do. Someone walking by hides part of a wall for a while, so it must
        be seen at one distance in most looks of ``WALL_STAYS_S``, not in every one; where
        people keep passing (a busy crossing), it looks again, three times at most. Seen in
        few looks, it was people, gone.
        """
        await self.use("runaway", "fit_wall")
        await self.wait("abs(odom.v) < 0.02 && abs(odom.w) < 0.05", within=3)
        front = await self.front_sonars()
        looks = round(WALL_STAYS_S / 0.5)
        for _window in range(3):
            seen: list[float] = []
            for _ in range(looks):
                self.send("step", cycles=5)
                self.prefetch("wall", "sonar.raw")
                wall = await self.value("wall")
                square = abs(float(wall["normal"])) < math.radians(25)
                near = float(wall["distance"]) < WALL_AHEAD_M + 0.1
                ranges = [float(r) for r in await self.value("sonar.raw")]
                d = float(wall["distance"])
                # Hit straight ahead too: not boxes on both walls with the way open between.
                on = all(ranges[k] < d * f + 0.25 for k, f in front)
                if wall["seen"] and int(wall["inliers"]) >= 5 and square and near and on:
                    seen.append(float(wall["distance"]))
            middle = sorted(seen)[len(seen) // 2] if seen else 0.0
            steady = sum(abs(d - middle) < 0.08 for d in seen)
            if self.debug:
                await self.say(
                    f"      wall looks: {steady} of {looks} steady, {len(seen)} seen"
                    f" (last {dict(wall)}, front {(await self.sonar())[:2]})"
                )
            if steady >= 0.6 * looks:
                return True
            if steady <= 0.2 * looks:
                return False
        return False

    async def beyond_wall(self) -> bool:
        """Whether the robot stands beyond the wall of the barcode last lined up with.

        A door passed on the route's hint alone (the sonars found no opening: someone in
        it, or it was closed) may have left the robot short of it, or beside it; the wall's
        line (`line_up`'s fix, odometry frame) says. True when there is no fix.
        """
        if self.wall_fix is None:
            return True
        wall = Pose(*self.wall_fix)  # a point of the wall and its normal
        o = await self.odom()
        beyond = wall.along(o.x, o.y)
        if beyond < BEYOND_WALL_M:
            await self.say(f"    not through the wall ({beyond:+.1f} m): again")
            return False
        return True

    async def opening(self) -> dict[str, Any] | None:
        """`std.locate_door`'s opening as the robot stands, in the wall `line_up` placed.

        Beside a door the scan's own best line may run through clutter or someone standing
        by (and the door found on it into a jamb); the barcode's wall, placed from where it
        was read, does not. Without such a wall in front, the skill fits one.
        """
        known: tuple[float, float] | None = None
        if self.wall_fix is not None:
            px, py, normal = self.wall_fix
            o = await self.odom()
            distance = o.along(px, py, normal)
            bearing = o.turn_to(normal)
            if 0.3 < distance < 3.0 and abs(bearing) < math.radians(80):
                known = (distance, math.degrees(bearing))
        if known is not None:
            await self.set("locate_door", "wall_distance", known[0])
            await self.set("locate_door", "wall_normal_deg", known[1])
        try:
            return await self.clue("locate_door", "opening")
        finally:
            if known is not None:
                await self.restore("locate_door", "wall_distance")
                await self.restore("locate_door", "wall_normal_deg")

    async def barcode_ahead_at(self, barcode: int | None) -> tuple[float, float] | None:
        """Where the barcode just lined up with is, robot frame: ahead and across (left), m.

        From `line_up`'s fix, or, without a wall through it, from where it was last placed
        (`barcode_wall`); None without a barcode or a place, or when the place is not in
        front of the robot (some earlier barcode's).
        """
        if barcode is None:
            return None
        if self.wall_fix is not None:
            px, py, _normal = self.wall_fix
        elif self.barcode_place is not None and self.barcode_place[0] == barcode:
            _id, px, py = self.barcode_place
        else:
            return None
        o = await self.odom()
        ahead, across = o.along(px, py), o.across(px, py)
        return (ahead, across) if 0.2 < ahead < 3.0 and abs(across) < 2.0 else None

    async def pass_door(self, barcode: int | None, hint: str | None) -> bool:
        """Lines up with the door in the wall ahead (beside the barcode homed on) and passes it.

        The opening is `std.locate_door`'s: beside the barcode and, with ``hint`` (``left``
        or ``right``, from the route: the side of the barcode the door is on), on that side.
        Without such an opening the hint places the door.
        """
        fix = await self.opening()
        at = await self.barcode_ahead_at(barcode)
        beside = None if at is None else at[1]
        why = not_its_door(fix, at, hint, barcode)
        if why is not None:
            # Its door closed (or someone in it), the scan finds another way along the
            # wall: a corridor's mouth, the next room's door.
            await self.say(f"    an opening {why}: not its door")
            fix = None
        if fix is None or float(fix["width"]) < 0.3:
            # A door closed for a while, or someone standing in it: wait for the opening.
            await self.say("    no opening in sight (a closed door, someone in it?): waiting")
            await self.use("locate_door", restart=["locate_door"])
            wanted = "opening.seen && opening.width > 0.6"
            if beside is not None:
                wanted += (
                    f" && abs(opening.y - {beside:.3f}) - opening.width / 2"
                    f" < {DOOR_BESIDE_BARCODE_M}"
                )
            if hint in ("left", "right"):
                wanted += f" && opening.y {'>' if hint == 'left' else '<'} {beside or 0.0:.3f}"
            if await self.wait(wanted, within=DOOR_WAIT_S) == 0:
                # Read again, as the door fix is taken (in the barcode's wall): the opening
                # that made the condition hold may be gone, or another one found.
                fix = await self.opening()
                why = not_its_door(fix, at, hint, barcode)
                if why is not None:
                    await self.say(f"    the opening seen again is {why}: not its door")
                    fix = None
        pose = await self.odom()
        if fix is None or float(fix["width"]) < 0.3:
            if hint is None:
                await self.say("    no door opening in sight")
                return False
            await self.say(f"    the sonars find no opening: trying the route's hint ({hint})")
            side = 1.0 if hint == "left" else -1.0
            normal = 0.0
            centre = (HINT_DOOR_AHEAD_M, side * HINT_DOOR_ASIDE_M)
        else:
            if self.debug:
                ranges = [round(r, 2) for r in await self.sonar()]
                await self.say(f"      opening {fix}, wall {self.wall_fix}, pose {pose} {ranges}")
            normal, centre = float(fix["normal"]), (float(fix["x"]), float(fix["y"]))
            side = 1.0 if math.sin(math.atan2(centre[1], centre[0]) - normal) > 0 else -1.0
            await self.say(
                f"    door {float(fix['width']):.1f} m wide, {'left' if side > 0 else 'right'} of "
                + (f"barcode {barcode}" if barcode is not None else "ahead")
            )
        # The point DOOR_STANDOFF in front of the opening's centre, in the odometry frame.
        ax = centre[0] - DOOR_STANDOFF * math.cos(normal)
        ay = centre[1] - DOOR_STANDOFF * math.sin(normal)
        gx, gy = pose.from_robot(ax, ay)
        heading = pose.theta + normal
        await self.set("runaway", "safe_distance", 0.12)
        try:
            if not await self.goto(gx, gy):
                return False
            here = await self.odom()
            if not await self.turn(here.turn_to(heading)):
                return False
            start = await self.odom()
            went = 0.0
            for push in range(3):
                if push > 0:
                    # Stopped by someone ahead in the doorway or just beyond (a room's
                    # people walk about): they move on; the robot waits, then goes on.
                    await self.say("    someone in the way through the door: waiting")
                    here = await self.odom()
                    if abs(here.turn_to(start.theta)) > 0.2:  # pushed aside meanwhile
                        await self.turn(here.turn_to(start.theta))
                    await self.use("runaway")
                    await self.wait(f"sonar.range[0] > {ROBOT_RADIUS + 0.9}", within=10)
                await self.set("pass_door", "distance", DOOR_STANDOFF + 1.1 - went)
                await self.use("runaway", "pass_door", restart=["pass_door"])
                if await self.wait("door_passed", within=30):
                    return False
                # Through? Well beyond the wall line along the heading, not stopped at it.
                end = await self.odom()
                went = start.along(end.x, end.y)
                # Stopped short, but in the doorway already (some way past the standoff):
                # it was someone beyond, not the jambs.
                if went >= DOOR_STANDOFF + 0.3 or went < DOOR_STANDOFF - 0.3:
                    break
            if went < DOOR_STANDOFF + 0.3:
                await self.say("    stopped short of the door: backing off")
                await self.use()
                return False
            self.passed_heading = start.theta
            self.passed_door = pose.from_robot(*centre)
            return True
        finally:
            await self.restore("runaway", "safe_distance")

    # ----- the phases --------------------------------------------------------------------

    async def search(self, barcode: int, budget: float) -> bool:
        """Wanders (avoiding obstacles), looking round now and then, until ``barcode`` is seen.

        Every ``SEARCH_LEG_S`` of wandering the robot turns round once in place (the reader
        looks ahead only); when it has hardly moved meanwhile, it first drives out of the
        corner it is stuck in, towards the freest direction.
        """
        await self.set("track_barcode", "id", barcode)
        # Each search its own path, all of them fixed by the run's seed.
        self.searches += 1
        await self.set("wander", "seed", (self.seed * 7919 + self.searches) % (1 << 31))
        seen = f"target.seen && target.id == {barcode}"
        end = self.t + budget
        look_first = True
        while self.t < end:
            if look_first:
                # Look round: a full turn in place.
                here = await self.odom()
                await self.set("turn", "angle", 2 * math.pi)
                await self.use("runaway", "turn", "track_barcode", restart=["turn"])
                near = f"abs(odom.theta - {here.theta + 2 * math.pi:.4f}) < 0.1"
                if await self.wait(seen, near, within=min(20.0, max(end - self.t, 0.1))) == 0:
                    return True
            look_first = True
            before = await self.odom()
            await self.use("runaway", "avoid", "wander", "track_barcode")
            if await self.wait(seen, within=min(SEARCH_LEG_S, max(end - self.t, 0.1))) == 0:
                return True
            after = await self.odom()
            if math.hypot(after.x - before.x, after.y - before.y) < 1.0:
                await self.unstick(keep=["track_barcode"])
                if (await self.value("target"))["seen"]:
                    return True
        return False

    async def unstick(self, *, keep: Sequence[str] = ()) -> None:
        """Turns towards the freest direction the sonars see and drives a little that way."""
        self.prefetch("sonar.range", "odom")  # the turn reads the odometry
        ranges = await self.sonar()
        free = [min(ranges[(i + k) % SONARS] for k in (-1, 0, 1)) for i in range(SONARS)]
        best = max(range(SONARS), key=lambda i: (free[i], -abs(bearing_of(i))))
        await self.set("runaway", "safe_distance", 0.12)
        try:
            await self.turn(bearing_of(best), keep=["runaway", *keep])
            o = await self.odom()
            go = max(0.0, min(1.2, free[best] - 0.8))
            if go > 0.1:
                await self.goto(*o.ahead(go), within=10)
        finally:
            await self.restore("runaway", "safe_distance")

    async def centre_between_walls(self) -> None:
        """Moves sideways to midway between the walls left and right (in a car: its door)."""
        ranges = await self.sonar()
        left, right = ranges[SONARS // 4], ranges[3 * SONARS // 4]
        offset = (left - right) / 2
        if abs(offset) < 0.06 or max(left, right) > 2.0:
            return
        await self.say(f"    {abs(offset):.2f} m to the {'left' if offset > 0 else 'right'}")
        side = math.pi / 2 if offset > 0 else -math.pi / 2
        await self.set("runaway", "safe_distance", 0.1)
        try:
            await self.turn(side, keep=["runaway"])
            o = await self.odom()
            d = abs(offset)
            await self.goto(*o.ahead(d), within=10)
            await self.turn((await self.odom()).turn_to(o.theta - side), keep=["runaway"])
        finally:
            await self.set("runaway", "safe_distance", 0.1)  # still in the car

    async def live_sonar_ahead(self) -> int:
        """The sonar nearest ahead that `std.sonar_filter` does not take to be dead."""
        health = await self.value("sonar.health")
        return live_sonar_ahead(int(health["mask"]) if health else 0)

    async def front_sonars(self) -> list[tuple[int, float]]:
        """The live sonars within 15° of ahead, each with its slack on a wall's distance.

        They must all read a wall fitted across the way (`std.fit_wall`'s ``wall``): at most
        ``wall.distance * f + 0.25`` (``f``: seen aslant, up to 25° off square).

        A wall across the way is hit straight ahead; boxes on both walls, staggered (1.2 m or
        more apart on the diagonal: docs/maps.md, "Clutter"), line up across the way for the
        sonars beside, with the way open between them. The readings are the device's
        (`sonar.raw`): the sonar filter takes a sonar looking down a long corridor past
        clutter for dead and fills it in from its neighbours, which see the clutter. A sonar
        that never heard an echo in the run (`note_echoes`) is dead (docs/maps.md: a dead
        sonar hears none) and left out.
        """
        await self.note_echoes()
        return [(k, f) for k, f in ((0, 1.15), (1, 1.4), (SONARS - 1, 1.4)) if self.echoed >> k & 1]

    async def front_on_wall(self) -> str:
        """`front_sonars` as a condition of the monitor language."""
        parts = [
            f"sonar.raw[{k}] < wall.distance * {f!r} + 0.25" for k, f in await self.front_sonars()
        ]
        return " && ".join(parts) if parts else "true"

    async def note_echoes(self) -> None:
        """Notes which sonars hear an echo now (`echoed`): those are alive."""
        raw = await self.value("sonar.raw")
        for k, r in enumerate(raw or []):
            if float(r) < ECHO_M:
                self.echoed |= 1 << k

    async def enclosed(self) -> bool:
        """Whether walls are near all round (inside a car: all but the door's sonars)."""
        ranges = await self.sonar()
        return sum(1 for r in ranges if r < 1.9) >= SONARS - 6

    async def face_barcode(self, barcode: int) -> bool:
        """Turns in place to face ``barcode`` if it is in view now; False if it is not."""
        await self.set("track_barcode", "id", barcode)
        await self.use("runaway", "track_barcode")
        self.send("step", cycles=2)
        self.prefetch("target", "odom")  # the turn reads the odometry
        target = await self.value("target")
        if not (target["seen"] and int(target["id"]) == barcode):
            return False
        return await self.turn(float(target["bearing"]), keep=["runaway"])

    async def look_round(self, barcode: int) -> bool:
        """Turns round in place until ``barcode`` is in view; False if it never is."""
        await self.set("track_barcode", "id", barcode)
        await self.use("runaway", "track_barcode")
        self.send("step", cycles=3)
        self.prefetch("target", "odom")
        if (await self.value("target"))["seen"]:
            return True
        here = await self.odom()
        await self.set("turn", "angle", 2 * math.pi)
        await self.use("runaway", "turn", "track_barcode", restart=["turn"])
        near = f"abs(odom.theta - {here.theta + 2 * math.pi:.4f}) < 0.1"
        return await self.wait(f"target.seen && target.id == {barcode}", near, within=15) == 0

    async def escape(self, seconds: float) -> None:
        """Gets away from where the robot is stuck, then wanders a while."""
        await self.unstick()
        await self.use("runaway", "avoid", "wander")
        await self.wait(within=seconds)
