"""The route interpreter: route hints of a map (docs/maps.md, "Route steps") followed by a robot.

`RouteSequencer` adds to `Sequencer` (the behaviours every mission shares, over the link of
`courier.link.Link`) what following a route takes: following a hallway until a junction, a door, a
barcode, a wall or a distance (`follow`), with the fall-backs each needs when people, clutter
or odometry get in the way (a junction looked for on the way back and probed for, a wall
found round a corner, way made measured along the route's heading); turning at a junction
into the side corridor's mouth; and `run_route`, which runs a leg's steps in order.
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable, Mapping, Sequence
from typing import Any

from courier.geometry import SONARS, Pose, bearing_of, wrap
from courier.link import PhaseFailed
from courier.mission import (
    WALL_AHEAD_M,
    distance_from_door,
    door_hint,
    travelled_heading,
)
from courier.sequenced.behaviours import DOOR_STANDOFF, Sequencer

#: Following for a distance: the time in which some way must be made, s.
FOLLOW_SLICE_S = 20.0
#: A wall ahead this near (sonar, from the centre) where no way is made is the corridor's end, if
#: it stays there (`way_stays_shut`): a box by a side wall near the end keeps the robot some 1.3 m
#: off it, m.
DEAD_END_M = 1.6
#: Following until a barcode: the time budget, s (a corridor 25 m long, followed to its end and
#: back towards the barcode's face, round people: docs/maps.md, "Clutter").
BARCODE_BUDGET_S = 360.0
#: Someone standing in the way has walked on after this long (docs/maps.md, people), s.
PEOPLE_PAUSE_S = 6.0
#: Following to a wall: turned off the way by more than this (rad) and this far to its side
#: (m), the robot has gone round a corner into a side corridor.
SIDE_EXIT_RAD = math.radians(60)
SIDE_EXIT_M = 1.0
#: Following to a wall: how often the robot notes where it follows the way (s), facing
#: within this of it (rad): the way's line runs through there, not through where it began.
LINE_CHECK_S = 4.0
ON_LINE_RAD = math.radians(10)
#: Walls on both sides nearer together than this: a corridor (they are 1.8 to 2.6 m wide), m.
CORRIDOR_MAX_M = 3.0
#: Following to a wall: the time budget, renewed while way is made, up to the longest, s.
WALL_BUDGET_S = 180.0
WALL_LONGEST_S = 600.0
#: Turned into a junction, the robot moves in line with the side corridor's mouth when
#: farther than this off its middle, m.
MOUTH_OFF_M = 0.35
#: Where only one side's wall is seen, the robot keeps at least this far from it, m.
SIDE_CLEAR_M = 0.8
#: A junction a route's `distance` leads to lies within this of where looking began, m.
PROBE_LOOK_M = 6.0
#: Where it is probed for, along the corridor from there, m.
PROBE_AT_M = (2.4, 2.9, 1.9, 3.4)
#: The way into it is open when the front sonars read beyond this, m.
PROBE_OPEN_M = 2.2
#: Looks (half a second apart) a probe takes, each sonar's farthest reading counting.
PROBE_LOOKS = 6
#: Turned into a junction and facing a wall: where the mouth is probed for, along the
#: corridor from there (the detector's centre is off by some metre at worst), m.
MOUTH_PROBE_AT_M = (0.0, -1.0, 1.0, -1.8, 1.8)
#: ... facing a wall: the front sonar reads nearer than this in every one of a few looks, m.
MOUTH_BLOCKED_M = 1.6
#: A junction found on the way back this far before where looking began is still the one, m.
JUNCTION_DRIFT_M = 1.0


def farther_than(o: Pose, metres: float) -> str:
    """The condition: the robot is more than ``metres`` (straight line) from pose ``o``."""
    dx, dy = f"(odom.x - {o.x!r})", f"(odom.y - {o.y!r})"
    return f"{dx} * {dx} + {dy} * {dy} > {metres * metres!r}"


def way_made_expr(start: Pose, heading: float) -> str:
    """The way made from ``start`` along ``heading``, in the monitor language.

    What `Pose.along` of ``start`` says of the robot's odometry (negative: behind), m.
    """
    c, s = math.cos(heading), math.sin(heading)
    return f"(odom.x - {start.x!r}) * {c!r} + (odom.y - {start.y!r}) * {s!r}"


def heading_off(along: float, rad: float) -> str:
    """The condition: the odometry heading is more than ``rad`` (< pi) off ``along``.

    ``odom.theta`` is wrapped into (-pi, pi]; the allowed range around ``along`` may wrap too.
    """
    lo, hi = wrap(along) - rad, wrap(along) + rad
    if hi > math.pi:
        return f"odom.theta < {lo!r} && odom.theta > {hi - 2 * math.pi!r}"
    if lo < -math.pi:
        return f"odom.theta > {hi!r} && odom.theta < {lo + 2 * math.pi!r}"
    return f"(odom.theta < {lo!r} || odom.theta > {hi!r})"


def off_the_way(start: Pose, line: Pose, along: float) -> str:
    """The condition: following ``along``, the robot has gone round a corner off the way.

    Turned more than `SIDE_EXIT_RAD` off ``along`` and more than `SIDE_EXIT_M` to a side of
    both the line along it through ``start`` (where the step began) and the one through
    ``line`` (where the robot last followed the way): the first drifts aside with the
    heading's error over a long corridor (3° off, 1 m in 19 m), the second with where the
    robot stood in the corridor then.
    """
    c, s = math.cos(along), math.sin(along)
    aside = [
        f"abs((odom.y - {p.y!r}) * {c!r} - (odom.x - {p.x!r}) * {s!r}) > {SIDE_EXIT_M!r}"
        for p in (start, line)
    ]
    return " && ".join([heading_off(along, SIDE_EXIT_RAD), *aside])


def side_walls(ranges: Sequence[float], spread_deg: float = 60.0) -> tuple[float, float]:
    """The nearest wall on the left and on the right, across the robot's heading, m.

    Each side's is the nearest perpendicular distance the sonars within ``spread_deg`` of
    square to that side see (from 30° to 150° by default: a doorway's jambs are on the
    wall's line; clutter counts, it narrows the way).
    """
    lo, hi = math.radians(90 - spread_deg), math.radians(90 + spread_deg)

    def wall(sign: float) -> float:
        return min(
            ranges[i] * abs(math.sin(bearing_of(i)))
            for i in range(SONARS)
            if lo <= sign * bearing_of(i) <= hi
        )

    return wall(1.0), wall(-1.0)


class RouteSequencer(Sequencer):
    """A `Sequencer` that follows a map's route hints (`run_route`)."""

    #: Where the leg's first `distance` runs from (odometry frame): the middle of the door
    #: it began out of, until its first `follow` step; None otherwise.
    leg_origin: tuple[float, float] | None = None

    async def follow(self, step: Mapping[str, Any]) -> bool:
        """A route step ``follow: hallway, until: …`` (docs/maps.md, "Route steps").

        ``until: junction`` or ``door`` waits for the ``count``-th opening (default 1) on
        ``side`` (either when not given) since the step began, each counted once, as it passes;
        ``until: barcode`` until that barcode is in view; ``until: wall`` until a wall stops the
        robot; ``until: distance`` after ``distance`` m. With ``distance`` and another ``until``,
        the first ``distance`` m are followed without looking.
        """
        until = str(step.get("until"))
        side = step.get("side")
        count = int(step.get("count", 1))
        await self.restore("follow_hallway", "speed")
        if step.get("distance") is not None:
            metres = float(step["distance"])
            if self.leg_origin is not None:
                metres = await self.distance_left(metres, self.leg_origin)
            if not await self.follow_for(metres):
                return False
            if until == "distance":
                return True
        if until == "barcode":
            code = int(step["barcode"])
            await self.set("track_barcode", "id", code)
            return await self.follow_until(
                f"target.seen && target.id == {code}", BARCODE_BUDGET_S, barcode=code
            )
        if until == "wall":
            return await self.follow_to_wall()
        detector, signal = (
            ("detect_intersection", "junction") if until == "junction" else ("detect_door", "door")
        )
        await self.use("runaway", "avoid", "follow_hallway", detector, restart=[detector])
        sides = [side] if side in ("left", "right") else ["left", "right"]
        seen = " || ".join(f"{signal}.{s}" for s in sides)
        # A junction expected just ahead (`distance` brought the robot to about 1.5 m before
        # it: docs/maps.md) that the detector misses is probed for where it should be.
        if until == "junction" and step.get("distance") is not None and count == 1:
            look_from = await self.odom()
            # Unseen by PROBE_LOOK_M on, or the way ahead blocked for good (a dead end just
            # past it): look for it on the way back, then probe for it.
            beyond = farther_than(look_from, PROBE_LOOK_M)
            if await self.wait(seen, beyond, within=120) != 0:
                if len(sides) != 1:
                    return False
                if await self.junction_on_the_way_back(look_from, sides[0]):
                    return True
                return await self.probe_junction(look_from, sides[0])
        else:
            for k in range(1, count + 1):
                if await self.wait(seen, within=180):
                    return False
                if k < count:
                    await self.say(f"      {until} {k} of {count} passed")
                    # On past this one: the next is another only once this one is behind
                    # (its flag off) and the robot a metre on (a flag flickering counts once).
                    away = farther_than(await self.odom(), 1.0)
                    if await self.wait(f"!({seen}) && {away}", within=60):
                        return False
        if until == "junction":
            o = await self.odom()
            await self.junction_centre(
                o.theta if self.corridor_heading is None else self.corridor_heading
            )
        return True

    async def distance_left(self, metres: float, origin: tuple[float, float]) -> float:
        """Of a step's ``metres`` measured from the door's middle ``origin``, what is left.

        See `distance_from_door`: along the route's heading, from where the robot stands.
        """
        o = await self.odom()
        heading = o.theta if self.corridor_heading is None else self.corridor_heading
        left = distance_from_door(metres, origin, o, heading)
        if self.debug and left != metres:
            await self.say(f"      {metres - left:+.2f} m along the way from the door's middle")
        return left

    async def junction_centre(self, along: float) -> None:
        """Into the middle of the junction the detector saw, going ``along``, before turning.

        `junction.centre` says where it is along the way (the detector may have waited until
        the robot was well past its near edge).
        """
        self.prefetch("junction", "odom")
        junction: dict[str, Any] = await self.value("junction") or {}
        centre = float(junction.get("centre", 0.6))
        # Never more than 0.6 m on (a corridor that opens into a hall has no far edge), and
        # never back: past the centre the robot is still well inside the junction.
        forward = max(-1.5, min(0.6, centre)) if math.isfinite(centre) else 0.6
        o = await self.odom()
        if self.debug:
            await self.say(f"      junction {junction}: {forward:+.2f} m on")
        # Best effort: someone standing there may keep the robot from the very middle,
        # and the turn and the next corridor's following work from near it too.
        if abs(forward) > 0.1:
            await self.goto(*o.ahead(forward, along), within=10)

    async def junction_on_the_way_back(self, look_from: Pose, side: str) -> bool:
        """The junction on ``side`` the detector missed going on, looked for coming back.

        Someone standing in its mouth, or clutter by it, hid it on the way; the robot turns
        round and follows the corridor back to 2.5 m past ``look_from`` (where `distance`
        brought it, before the junction; odometry drifts) with the detector watching the
        other side. Seen no more than `JUNCTION_DRIFT_M` before ``look_from``, the robot
        stands in the junction's middle (the route's next turn is from the heading it
        planned, whichever way the robot faces).
        """
        along = look_from.theta if self.corridor_heading is None else self.corridor_heading
        back = wrap(along + math.pi)
        other = "right" if side == "left" else "left"
        await self.say(f"      no junction seen on the {side}: looking for it on the way back")
        if not await self.turn((await self.odom()).turn_to(back)):
            return False
        o = await self.odom()
        todo = look_from.along(o.x, o.y, along) + 2.5
        if todo > 0.5:
            await self.use(
                "runaway",
                "avoid",
                "follow_hallway",
                "detect_intersection",
                restart=["detect_intersection"],
            )
            passed = f"{way_made_expr(o, back)} > {todo!r}"
            if await self.wait(f"junction.{other}", passed, within=30 + 10 * todo) == 0:
                # Where its middle lies along the way from ``look_from``: the junction the
                # route means lies ahead of it, give or take odometry's drift; one well
                # before it is one the robot was meant to pass.
                self.prefetch("junction", "odom")
                junction: dict[str, Any] = await self.value("junction") or {}
                centre = float(junction.get("centre", 0.0))
                here = await self.odom()
                at = look_from.along(here.x, here.y, along)
                if math.isfinite(centre):
                    at -= centre
                if self.debug:
                    await self.say(f"      a junction {at:+.1f} m along the way from the look")
                if at > -JUNCTION_DRIFT_M:
                    await self.junction_centre(back)
                    return True
        await self.turn((await self.odom()).turn_to(along))
        return False

    async def follow_to_wall(self) -> bool:
        """Follows the hallway up to the wall it ends in (`until: wall`).

        Up to the wall ahead: about the middle of the corridor it ends in (corridors are 1.8
        to 2.6 m wide), before avoidance would start turning away from it. A wall across the
        way: a line fitted to at least 5 of the 7 sonars within 45° of ahead, square to the
        way, that stays put (`wall_stays`). Neither a jamb caught by the front sonar's cone
        nor clutter or someone in the corridor (a person fills two or three sonars' view, and
        a narrow corridor's side walls lie along the way) is taken for it.

        Where the corridor ends in a T, following may take the robot round the corner before
        the wall is near enough (people in the crossing, a narrow crossing corridor). Turned
        off the way by more than ``SIDE_EXIT_RAD`` and ``SIDE_EXIT_M`` to its side, between
        walls as near as a corridor's (else it is in a room, a lobby, whose way out was only
        roughly planned: the way is where it now goes), it goes back onto the way's line,
        faces the way and looks for the wall there; none near, it follows on (it was a
        crossing on the way). The time budget is renewed while way is
        made along the route's heading (a busy lobby), up to ``WALL_LONGEST_S``.
        """
        start = await self.odom()
        along = start.theta if self.corridor_heading is None else self.corridor_heading

        ahead = await self.wall_ahead_condition()

        async def watch_ahead() -> None:
            await self.set("fit_wall", "bearing_deg", 0.0)
            await self.set("fit_wall", "half_angle_deg", 45.0)

        await watch_ahead()
        await self.use("runaway", "avoid", "follow_hallway", "fit_wall", restart=["fit_wall"])
        began = await self.now()
        deadline = began + WALL_BUDGET_S
        best = 0.0
        # A point of the way's line: where the robot last followed it, facing along it. The
        # line drawn from ``start`` alone drifts aside with the heading's error (3° off, 1 m
        # in 19 m): a robot going round clutter then seems to have left the way, and going
        # back onto it takes it through a door. Off the way means off both lines.
        line = start
        progress_t = began
        try:
            while self.t < deadline:
                within = min(LINE_CHECK_S, deadline - self.t)
                held = await self.wait(ahead, off_the_way(start, line, along), within=within)
                if held == 0:
                    off = (await self.odom()).turn_to(along)
                    if abs(off) < math.radians(30):
                        # Square to the way, not to where avoidance turned the robot (round
                        # clutter, a box on each wall then lines up across its view).
                        if abs(off) > math.radians(8):
                            await self.turn(off)
                        if await self.wall_stays():
                            return True
                        await self.use("runaway", "avoid", "follow_hallway", "fit_wall")
                        continue
                    # Facing a side wall (turned there by avoidance, round clutter): not the end.
                    if await self.wait(f"!({ahead})", within=deadline - self.t):
                        return False
                    continue
                if held == 1:
                    # Square to each side only: corners ahead and behind are no walls of it.
                    left, right = side_walls(await self.sonar(), 30.0)
                    if self.debug:
                        await self.say(f"      off the way: walls {left:.2f} and {right:.2f}")
                    if left + right > CORRIDOR_MAX_M:
                        # Not in a corridor (a lobby, a hall): the way bends with the room
                        # (the heading planned out of it is only roughly the corridor's).
                        start = line = await self.odom()
                        along, best = start.theta, 0.0
                        continue
                    if await self.wall_from_the_way(line, along):
                        return True
                    await watch_ahead()
                    await self.use("runaway", "avoid", "follow_hallway", "fit_wall")
                o = await self.odom()
                if held == 2 and abs(o.turn_to(along)) < ON_LINE_RAD:
                    line = o
                made = start.along(o.x, o.y, along)
                if made > best + 0.5:
                    best = made
                    progress_t = self.t
                    renewed = max(deadline, self.t + WALL_BUDGET_S / 2)
                    deadline = min(renewed, began + WALL_LONGEST_S)
                elif held == 2 and self.t - progress_t >= FOLLOW_SLICE_S:
                    # No way made in a whole slice (turned into a doorway beside the way):
                    # facing the way again from the corridor's middle, on.
                    progress_t = self.t
                    await self.say(
                        f"    no way made in {FOLLOW_SLICE_S:.0f} s: to the corridor's middle"
                    )
                    await self.turn(o.turn_to(along))
                    await self.recentre(along)
                    await watch_ahead()
                    await self.use(
                        "runaway",
                        "avoid",
                        "follow_hallway",
                        "fit_wall",
                        restart=["follow_hallway", "fit_wall"],
                    )
            return False
        finally:
            await self.restore("fit_wall", "bearing_deg")
            await self.restore("fit_wall", "half_angle_deg")

    async def wall_ahead_condition(self) -> str:
        """The condition: a wall across the way ahead, near (`std.fit_wall` looking ahead).

        A line fitted to at least 5 of the 7 sonars within 45° of ahead, square to the way,
        with the front sonar (or the live one nearest it) on it: not a jamb in the front
        sonar's cone, nor clutter or someone in the corridor.
        """
        return (
            f"wall.seen && wall.inliers >= 5 && abs(wall.normal) < {math.radians(25):.3f}"
            f" && wall.distance < {WALL_AHEAD_M} && {await self.front_on_wall()}"
        )

    async def wall_from_the_way(self, start: Pose, along: float) -> bool:
        """Gone round a corner off the way that began at ``start``: whether the way ends here.

        Back onto the way's line (abreast of where the robot is), facing the way: a wall
        square to it within a corridor's width and a half (the far wall of the crossing
        corridor) is driven up to and must stay put (`wall_stays`).
        """
        o = await self.odom()
        made = start.along(o.x, o.y, along)
        await self.say("    turned into a side corridor: back onto the way, looking for its end")
        await self.goto(*start.ahead(made, along), within=30)
        await self.turn((await self.odom()).turn_to(along))
        wall = await self.wall_towards(along)
        if self.debug:
            await self.say(f"      wall towards the way: {wall}")
        if wall is None or abs(wrap(wall[0] - along)) > math.radians(25) or wall[1] > 3.5:
            return False
        go = wall[1] - (WALL_AHEAD_M - 0.3)
        if go > 0.1:
            o = await self.odom()
            await self.goto(*o.ahead(go, along), within=20)
        await self.set("fit_wall", "bearing_deg", 0.0)
        await self.set("fit_wall", "half_angle_deg", 45.0)
        return await self.wall_stays()

    async def follow_until(
        self, condition: str, within: float, *, barcode: int | None = None
    ) -> bool:
        """Follows the hallway (barcode tracking on) until ``condition`` holds.

        Making less than 0.5 m of way along the route's heading in ``FOLLOW_SLICE_S``
        (pushed into a doorway by someone coming the other way, with a jamb beside it), the
        robot faces the way, moves to the corridor's middle (`recentre`) and goes on.
        Following until ``barcode`` is in view, it first looks round for it: a box beside a
        barcode on its wall hides its face from a robot coming from that side (docs/maps.md,
        "Clutter"), which passes it unread; at the corridor's end (a wall ahead) it follows
        the corridor back, towards the barcode's face.
        """
        o = await self.odom()
        heading = o.theta if self.corridor_heading is None else self.corridor_heading
        deadline = await self.now() + within
        await self.use("runaway", "avoid", "follow_hallway", "track_barcode")
        best = 0.0
        while self.t < deadline:
            slice_s = min(FOLLOW_SLICE_S, deadline - self.t)
            if await self.wait(condition, within=slice_s) == 0:
                return True
            here = await self.odom()
            made = o.along(here.x, here.y, heading)
            if made > best + 0.5:
                best = made
                continue
            if barcode is not None:
                if await self.look_round(barcode):
                    return True
                await self.turn((await self.odom()).turn_to(heading))
                if (await self.sonar())[0] < DEAD_END_M and await self.way_stays_shut():
                    await self.say(
                        f"    the corridor ends, barcode {barcode} unseen: back along it"
                    )
                    heading = wrap(heading + math.pi)
                    self.corridor_heading = heading
                    await self.turn(math.pi)
                    await self.use(
                        "runaway",
                        "avoid",
                        "follow_hallway",
                        "track_barcode",
                        restart=["follow_hallway"],
                    )
                    o = await self.odom()
                    best = 0.0
                    continue
                here = await self.odom()
            await self.say(f"    no way made in {FOLLOW_SLICE_S:.0f} s: to the corridor's middle")
            await self.turn(here.turn_to(heading))
            await self.recentre(heading)
            await self.use("runaway", "avoid", "follow_hallway", "track_barcode")
            best = made
        return False

    async def way_stays_shut(self) -> bool:
        """Whether the way ahead, shut within `DEAD_END_M`, stays shut while the robot stands.

        Someone standing in the corridor (docs/maps.md: people pause at most 2.5 s, and wait
        at most 3 s for the robot) walks on within `PEOPLE_PAUSE_S`; the corridor's end does
        not.
        """
        await self.use("runaway", "track_barcode")
        opened = f"sonar.range[0] > {DEAD_END_M + 0.3!r}"
        return await self.wait(opened, within=PEOPLE_PAUSE_S) != 0

    async def probe_junction(
        self,
        look_from: Pose,
        side: str,
        *,
        at: Sequence[float] = PROBE_AT_M,
        axis: float | None = None,
    ) -> bool:
        """The junction on ``side`` the detector missed, probed where a route says it is.

        It lies 1.5 m or more ahead of ``look_from`` (docs/maps.md, route hints with
        `distance`), 1.8 to 2.6 m wide: at points along the corridor the robot turns to that side
        and takes the first where the way is open (the three front sonars read beyond
        `PROBE_OPEN_M` at least once in `PROBE_LOOKS` looks: people there move on), standing
        in it facing the corridor's way, as the detector would have left it. ``at`` gives
        the points (m along the corridor from ``look_from``, behind it if negative) and
        ``axis`` the corridor's way (default: the route's heading).
        """
        if axis is None:
            axis = look_from.theta if self.corridor_heading is None else self.corridor_heading
        turn = math.pi / 2 if side == "left" else -math.pi / 2
        await self.say(f"      no junction seen: probing for it on the {side}")
        made = way_made_expr(look_from, axis)
        for along in at:
            here = await self.odom()
            if look_from.along(here.x, here.y, axis) < along - 0.3:
                # On to it by following the corridor: it keeps to the middle and goes round
                # people, where a point drawn by odometry after a long way may be off the
                # middle, near a wall the robot cannot come close to.
                await self.turn(here.turn_to(axis))
                await self.use("runaway", "avoid", "follow_hallway", restart=["follow_hallway"])
                if await self.wait(f"{made} > {along!r}", within=30) != 0:
                    continue
            elif not await self.goto(*look_from.ahead(along, axis), within=30):
                continue
            if not await self.turn((await self.odom()).turn_to(axis + turn)):
                continue
            # The farthest each sonar reads over a few seconds: people walking in the side
            # corridor move on, its walls do not.
            ranges = await self.sonar()
            for _look in range(PROBE_LOOKS - 1):
                self.send("step", cycles=5)
                ranges = [max(a, b) for a, b in zip(ranges, await self.sonar())]
            if self.debug:
                await self.say(
                    f"        at {along} m: ahead {[round(r, 2) for r in ranges[-2:] + ranges[:3]]}"
                )
            # The sonars at ±15° see the side corridor's walls from about 2 m on, and one of
            # them its corner when the robot stands near an edge (odometry is off by some
            # tenths after a long corridor): one of them open, the other not blocked at once.
            pair = sorted((ranges[1], ranges[-1]))
            if ranges[0] > PROBE_OPEN_M and pair[1] > PROBE_OPEN_M - 0.6 and pair[0] > 0.7:
                await self.turn((await self.odom()).turn_to(axis))
                return True
        return False

    async def follow_for(self, metres: float) -> bool:
        """Follows the hallway for ``metres`` along the way (odometry).

        The way is the route's heading, not any straight line from here: pushed out of a
        corridor's mouth into the crossing corridor (going round someone), the robot would go
        on along the wrong one, pressing towards its way. Making less than 0.5 m of way in
        ``FOLLOW_SLICE_S``, it goes back to where the step began, faces the way, moves to the
        corridor's middle (`recentre`) and starts again (twice at most), each time with the
        whole time budget. Done, the way it travelled squares the route's heading
        (`travelled_heading`).
        """
        start = await self.odom()
        heading = start.theta if self.corridor_heading is None else self.corridor_heading
        made_expr = way_made_expr(start, heading)
        # 0.3 m/s, with time to wait for people in the way and to go round them.
        deadline = self.t + 60 + 10 * metres
        await self.use("runaway", "avoid", "follow_hallway", restart=["follow_hallway"])
        best, restarts = 0.0, 0
        while self.t < deadline:
            within = min(FOLLOW_SLICE_S, deadline - self.t)
            if await self.wait(f"{made_expr} > {metres!r}", within=within) == 0:
                here = await self.odom()
                travel = travelled_heading(start, here, heading)
                if travel is not None:
                    if self.debug:
                        off = math.degrees(wrap(travel - heading))
                        await self.say(f"      the corridor runs {off:+.0f}° off the way planned")
                    self.corridor_heading = travel
                return True
            o = await self.odom()
            made = start.along(o.x, o.y, heading)
            if made > best + 0.5:
                best = made
                continue
            if restarts == 2:
                return False
            restarts += 1
            await self.say(f"    {made:.1f} of {metres:.1f} m made, no more: from the start again")
            if self.debug:
                self.prefetch("drive", "odom", "sonar.range")
                drive = await self.value("drive")
                ranges = [round(r, 2) for r in await self.sonar()]
                await self.say(f"      drive {drive} pose {o} sonar {ranges}")
            await self.goto(start.x, start.y, within=40)
            await self.turn((await self.odom()).turn_to(heading))
            await self.recentre(heading)
            await self.use("runaway", "avoid", "follow_hallway", restart=["follow_hallway"])
            best = 0.0
            # A whole budget again: the time spent waiting for people who kept the way
            # (a busy corridor to a lobby) is no sign the way is wrong.
            deadline = await self.now() + 60 + 10 * metres
        return False

    async def wall_ahead_stays(self) -> bool:
        """Whether the front sonar reads nearer than `MOUTH_BLOCKED_M` in each of a few looks.

        Someone standing in the way moves on within them (docs/maps.md, people); a wall
        does not.
        """
        await self.use("runaway")
        for _look in range(PROBE_LOOKS):
            self.send("step", cycles=5)
            if (await self.sonar())[0] >= MOUTH_BLOCKED_M:
                return False
        return True

    async def into_mouth(self, heading: float, turned: float) -> None:
        """Turned towards a side corridor at a junction: in line with its mouth, facing it.

        The junction's centre is an estimate (someone in the mouth, clutter by it): turned
        a few tenths off it, the robot faces the corner with the mouth beside it, and a
        corner is what neither following nor avoidance gets round. The mouth is an opening
        in the near wall's line ahead (`std.locate_door`, as wide as a side corridor may
        be; at least 1 m of it seen); off its middle by more than `MOUTH_OFF_M`, the robot
        moves sideways to it.
        """
        await self.set("locate_door", "max_width", 3.0)
        try:
            fix = await self.clue("locate_door", "opening")
        finally:
            await self.restore("locate_door", "max_width")
        if self.debug:
            await self.say(f"      mouth {fix}")
        if fix is None and await self.wall_ahead_stays():
            # No mouth, a wall ahead: the junction's centre was far off (a crossing's stub
            # just before it seen with it, clutter by it). Probed for, from here.
            await self.say("    a wall where the side corridor should be: probing for its mouth")
            axis = wrap(heading - turned)
            here = await self.odom()
            side = "left" if turned > 0 else "right"
            at = Pose(here.x, here.y, axis)
            if await self.probe_junction(at, side, at=MOUTH_PROBE_AT_M, axis=axis):
                await self.turn((await self.odom()).turn_to(heading))
            return
        if fix is None or float(fix["width"]) < 1.0 or float(fix["wall"]) > 2.0:
            return
        lateral = float(fix["y"])
        if abs(lateral) < MOUTH_OFF_M or abs(float(fix["normal"])) > math.radians(25):
            return
        await self.say(f"    {abs(lateral):.1f} m off the side corridor's mouth: in line with it")
        await self.shift_sideways(lateral, heading)

    async def recentre(self, heading: float) -> None:
        """Facing ``heading`` along a corridor: sideways to its middle, then facing it again.

        A robot that stopped just out of a door (something ahead) stands with a jamb at its
        side, where avoidance turns it away as often as following turns it back: it makes
        no way. With walls on both sides within a corridor's width (`side_walls`), it moves
        to midway between them, else to at least `SIDE_CLEAR_M` from the one it sees.
        """
        left, right = side_walls(await self.sonar())
        if self.debug:
            await self.say(f"      walls: left {left:.2f}, right {right:.2f}")
        if max(left, right) < 2.6:
            shift = (left - right) / 2  # positive: to the left
        elif min(left, right) < SIDE_CLEAR_M:
            shift = (SIDE_CLEAR_M - min(left, right)) * (1.0 if left > right else -1.0)
        else:
            return
        if abs(shift) < 0.15:
            return
        await self.shift_sideways(shift, heading)

    async def shift_sideways(self, metres: float, heading: float) -> None:
        """Moves ``metres`` across ``heading`` (positive: to its left), then faces it."""
        o = await self.odom()
        x = o.x - metres * math.sin(heading)
        y = o.y + metres * math.cos(heading)
        await self.set("runaway", "safe_distance", 0.12)
        try:
            await self.goto(x, y, within=15)
            await self.turn((await self.odom()).turn_to(heading))
        finally:
            await self.restore("runaway", "safe_distance")

    async def run_route(
        self,
        leg: str,
        steps: Sequence[Mapping[str, Any]],
        *,
        stop_before_home: int | None = None,
        on_home: Callable[[int], Awaitable[None]] | None = None,
        heading: float | None = None,
    ) -> None:
        """Interprets the route hints ``steps`` of ``leg`` (docs/maps.md, "Route steps").

        Stops before a ``home`` on ``stop_before_home``; ``on_home`` is told each barcode homed on.
        ``heading`` is the way the leg begins facing, in the odometry frame (default: the robot's);
        given, the leg begins out through the door just passed, and its first ``distance`` runs
        from that door's middle (`distance_from_door`).
        """
        pending_home: int | None = None
        self.followed_heading = None
        # Out through a door (``heading`` given): its middle is where the first distance runs
        # from.
        self.leg_origin = self.passed_door if heading is not None else None
        # The way the leg begins facing: ``heading`` (odometry) when the caller knows it (out
        # through the door just passed, however the robot ended up turned), else the robot's.
        self.corridor_heading = (await self.odom()).theta if heading is None else heading
        for n, step in enumerate(steps):
            if step.get("home") is not None and int(step["home"]) == stop_before_home:
                return
            text = ", ".join(f"{k} {v}" for k, v in step.items())
            await self.say(f"    route {leg}, step {n + 1}: {text}")
            ok = True
            if step.get("follow"):
                ok = await self.follow(step)
                self.leg_origin = None
                # The way the leg went last (into a lobby: the way in, from its entry).
                self.followed_heading = self.corridor_heading
            if ok and step.get("home") is not None:
                pending_home = int(step["home"])
                if on_home is not None:
                    await on_home(pending_home)
                ok = False
                for _attempt in range(3):
                    await self.set("track_barcode", "id", pending_home)
                    await self.use("runaway", "avoid", "track_barcode")
                    self.send("step", cycles=3)
                    if not (await self.value("target"))["seen"] and not await self.search(
                        pending_home, 60
                    ):
                        continue
                    if any(s.get("pass") for s in steps[n + 1 :]):
                        ok = await self.line_up(pending_home, DOOR_STANDOFF)
                    else:
                        ok = await self.home_on(
                            pending_home, self.normal[("home", "stop_distance")]
                        )
                    if ok:
                        self.corridor_heading = (await self.odom()).theta
                        break
                    await self.say(f"    could not home on barcode {pending_home}: again")
            if ok and step.get("pass"):
                hint = door_hint(steps, n)
                for _attempt in range(3):
                    ok = await self.pass_door(pending_home, hint) and await self.beyond_wall()
                    if ok or pending_home is None:
                        break
                    await self.say(f"    lining up with barcode {pending_home} again")
                    await self.look_round(pending_home)
                    await self.line_up(pending_home, DOOR_STANDOFF)
                pending_home = None
            elif ok and step.get("turn"):
                if any(s.get("pass") for s in steps[n + 1 : n + 2]) and pending_home is not None:
                    await self.say("      (the door finder of the next step faces the door)")
                    continue
                angle = {"left": math.pi / 2, "right": -math.pi / 2, "back": math.pi}[
                    str(step["turn"])
                ]
                # From the heading the route planned (the last turn's, or the robot's where the
                # leg began or after homing), not from wherever following a corridor and
                # stepping into a junction left it facing: errors do not add up turn by turn.
                here = await self.odom()
                planned = here.theta if self.corridor_heading is None else self.corridor_heading
                goal = planned + angle
                ok = await self.turn(here.turn_to(goal))
                self.corridor_heading = goal
                if ok and step.get("until") == "junction" and angle != math.pi:
                    await self.into_mouth(goal, angle)
            if not ok:
                raise PhaseFailed(f"route {leg}, step {n + 1} ({text}) failed")
