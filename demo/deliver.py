"""The message delivery of the paper's section 6, as a sequencer over the situate link.

The robot wakes up in its lab, wanders about avoiding obstacles until it sees the barcode
beside the lab door, homes on it, finds the opening with its sonars and passes the door; it
follows the hallways to the elevator lobby (the mission's `route` hints, read by a small
interpreter), pushes the call button, patrols the lobby until a car's door opens, reads which
car it is, enters, pushes the goal floor, waits for it, leaves, follows the corridor to the
office's barcode and says its message inside the office.

The sequencer acts only at the cycle a monitor fired (monitors registered with ``pause``), so a
run on the simulated clock replays exactly, however fast or slow the link. Every wait has a
time-out on the robot's clock, and failed phases are retried a bounded number of times.
Changes (parameters, activations, steps) are sent without waiting for their replies; the
manager handles requests in the order they are sent, and the next request that needs an answer
(a query, a wait) collects them all: one round trip instead of one per change.

``--mode all-active`` is the experiment's baseline: every skill is switched on at the start and
never off; the sequencer sets the same parameters and waits on the same monitors, and the
skills' priorities alone decide who drives.

Run it through ``situate demo`` (which starts the simulated robot and passes the arguments).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import math
import os
import re
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from signal import SIGHUP, SIGINT, SIGTERM, Signals
from typing import Any

import situate
from situate.events import MonitorFired

#: The phases, in mission order (``--from``/``--to`` pick a stretch of them).
PHASES = ("lab", "corridor", "lobby", "ride", "office")

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
    ("track_barcode", "hold"): 15,
}

SONARS = 24
ROBOT_RADIUS = 0.25
#: How far in front of a door the robot lines up before passing it, m.
DOOR_STANDOFF = 0.9
#: Openings wider than this are not a door; a door is taken to be DOOR_WIDTH wide, m.
MAX_DOOR_WIDTH = 1.6
DOOR_WIDTH = 1.1
#: Time to get out of the lab before giving up, s.
LAB_BUDGET_S = 900.0
#: Wandering between two looks round, s.
SEARCH_LEG_S = 20.0
#: Homing that gets no closer for this long steps aside, s.
HOME_PROGRESS_S = 8.0

#: Records the sequencer reads after most waits: each wait's monitor asks for them (``report``),
#: so their values as of the cycle it fired in come with its event instead of a query each.
CARRIED = ("odom", "target")


class PhaseFailed(Exception):
    """A phase could not be completed (after its retries)."""


class OutOfTime(Exception):
    """The mission's time limit passed."""


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
        )


@dataclass
class Pose:
    """An odometry pose."""

    x: float
    y: float
    theta: float


def wrap(a: float) -> float:
    """``a`` wrapped into (-pi, pi]."""
    a = math.fmod(a, 2 * math.pi)
    if a > math.pi:
        a -= 2 * math.pi
    elif a <= -math.pi:
        a += 2 * math.pi
    return a


_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*(?:\s*\()?")


def holds(condition: str, values: Mapping[str, Any], time_s: float, cycle: int) -> bool:
    """Evaluates a monitor condition (the subset this sequencer writes) on reported values.

    ``values`` are those of a ``monitor_fired`` event: each signal leaf or parameter the
    condition reads, whole (arrays are indexed here). The operators are the condition
    language's (``&& || ! == != < <= > >=``, arithmetic, ``abs``, ``min``, ``max``); a name
    without a value makes the condition false, as on the robot.
    """
    env: dict[str, Any] = {}

    def name(m: re.Match[str]) -> str:
        word = m.group(0)
        if word.endswith("("):
            return word  # abs( min( max(
        if word in ("true", "false"):
            return "True" if word == "true" else "False"
        if word in ("time", "cycle"):
            env[f"_n{len(env)}"] = time_s if word == "time" else cycle
        else:
            v = values.get(word)
            if v is None:
                raise LookupError(word)
            env[f"_n{len(env)}"] = [float(x) for x in v] if isinstance(v, list) else v
        return f"_n{len(env) - 1}"

    try:
        expr = _NAME.sub(name, condition)
    except LookupError:
        return False
    expr = expr.replace("&&", " and ").replace("||", " or ")
    expr = re.sub(r"!(?!=)", " not ", expr)
    funcs = {"abs": abs, "min": min, "max": max}
    try:
        return bool(eval(expr, {"__builtins__": {}, **funcs}, env))
    except (LookupError, TypeError, ValueError):
        return False


def bearing_of(i: int) -> float:
    """Bearing of sonar ``i`` in the robot frame (sonar 0 ahead, counter-clockwise)."""
    return wrap(i * 2 * math.pi / SONARS)


@dataclass
class DoorFix:
    """Where a door in the wall ahead is, in the robot frame."""

    normal: float  # direction from the robot to the wall (perpendicular), rad
    wall: float  # perpendicular distance to the wall, m
    centre: tuple[float, float]  # the opening's centre on the wall line
    width: float


def wall_ahead(ranges: Sequence[float], max_range: float = 3.9) -> tuple[float, float, int] | None:
    """The wall in front: ``(normal, distance, inliers)`` in the robot frame, from one scan.

    The wall is the line through most echoes of the front half of the ring (a small RANSAC
    over pairs of echoes), the nearest of equally supported ones.
    """
    front = [i for i in range(SONARS) if abs(bearing_of(i)) <= math.radians(80) + 1e-9]
    pts = {
        i: (ranges[i] * math.cos(bearing_of(i)), ranges[i] * math.sin(bearing_of(i)))
        for i in front
        if ranges[i] < max_range
    }
    best: tuple[int, float, float, float] | None = None  # inliers, -distance, nx, ny
    keys = sorted(pts)
    for a_i, a in enumerate(keys):
        for b in keys[a_i + 1 :]:
            (x1, y1), (x2, y2) = pts[a], pts[b]
            dx, dy = x2 - x1, y2 - y1
            n = math.hypot(dx, dy)
            if n < 0.3:
                continue
            nx, ny = dy / n, -dx / n
            d = x1 * nx + y1 * ny
            if d < 0:
                nx, ny, d = -nx, -ny, -d
            if not 0.3 < d < 3.0:
                continue
            inliers = sum(1 for p in pts.values() if abs(p[0] * nx + p[1] * ny - d) < 0.1)
            cand = (inliers, -d, nx, ny)
            if best is None or cand[:2] > best[:2]:
                best = cand
    if best is None or best[0] < 4:
        return None
    inliers, neg_d, nx, ny = best
    return math.atan2(ny, nx), -neg_d, inliers


def locate_door(ranges: Sequence[float], max_range: float = 3.9) -> DoorFix | None:
    """Finds the wall ahead and the opening in it from one sonar scan.

    The wall is the line through most echoes of the front half of the ring (a small RANSAC
    over pairs of echoes); the sonars that read well beyond it see through the opening, whose
    jambs lie between them and their neighbours that hit the wall.
    """
    front = [i for i in range(SONARS) if abs(bearing_of(i)) <= math.radians(80) + 1e-9]
    wall = wall_ahead(ranges, max_range)
    if wall is None:
        return None
    normal, d, _ = wall
    nx, ny = math.cos(normal), math.sin(normal)
    tx, ty = -ny, nx  # along the wall, to the left of the normal
    # Each front sonar, in bearing order: where its axis meets the wall line, and whether it
    # sees through (reads well beyond the line).
    order = sorted(front, key=bearing_of)
    hits: list[tuple[float, bool]] = []
    for i in order:
        c = math.cos(bearing_of(i)) * nx + math.sin(bearing_of(i)) * ny
        if c < 0.2:
            continue
        along_line = d / c
        s = along_line * (math.cos(bearing_of(i)) * tx + math.sin(bearing_of(i)) * ty)
        hits.append((s, ranges[i] > along_line + 0.5))
    hits.sort()
    # Runs of sonars seeing through: the opening is the run nearest the normal's foot.
    runs: list[tuple[float, float]] = []
    k = 0
    while k < len(hits):
        if not hits[k][1]:
            k += 1
            continue
        j = k
        while j + 1 < len(hits) and hits[j + 1][1]:
            j += 1
        lo = (hits[k - 1][0] + hits[k][0]) / 2 if k > 0 else hits[k][0] - 0.15
        hi = (hits[j][0] + hits[j + 1][0]) / 2 if j + 1 < len(hits) else hits[j][0] + 0.15
        runs.append((lo, hi))
        k = j + 1
    if not runs:
        return None
    lo, hi = min(runs, key=lambda r: abs((r[0] + r[1]) / 2))
    if hi - lo > MAX_DOOR_WIDTH:
        # Wider than a door: trust the edge nearer the barcode ahead, a usual door width in.
        lo, hi = (lo, lo + DOOR_WIDTH) if abs(lo) < abs(hi) else (hi - DOOR_WIDTH, hi)
    mid = (lo + hi) / 2
    centre = (nx * d + tx * mid, ny * d + ty * mid)
    return DoorFix(normal=math.atan2(ny, nx), wall=d, centre=centre, width=hi - lo)


class Sequencer:
    """Drives the mission over the link; one method per phase of the narrative."""

    def __init__(
        self, robot: situate.Robot, mission: Mission, mode: str, limit_s: float, quiet: bool
    ) -> None:
        self.r = robot
        self.m = mission
        self.sequenced = mode == "sequenced"
        self.limit_s = limit_s
        self.quiet = quiet
        self.debug = bool(os.environ.get("DELIVER_DEBUG"))
        self.active: set[str] = set()
        self.t = 0.0
        self.phase_no = 0
        self.phase_text = ""
        self.car = 0
        self.button_pose: Pose | None = None
        self.stream: situate.Stream[Any] | None = None
        self.params: dict[tuple[str, str], Any] = {}
        #: Replies to requests sent but not yet awaited (see `send`).
        self.pending: list[asyncio.Future[Any]] = []
        #: Queries sent since the cycle last ran, by signal: their answers stand until it runs.
        self.readings: dict[str, asyncio.Future[Any]] = {}
        #: Records the last wait's event reported (`CARRIED`), until the cycle runs again.
        self.carried: dict[str, dict[str, Any]] = {}

    # ----- the link: waiting, switching skills, parameters ------------------------------

    def send(self, verb: str, **args: Any) -> None:
        """Sends a request now; its reply is awaited with the next one that needs an answer.

        The manager handles requests in the order they are sent, so a query (or a wait) sent
        after changes costs one round trip for them all (see `flush`).
        """
        if verb in ("run", "step"):
            self.readings.clear()  # the cycle runs: every signal may change
            self.carried.clear()
        self.pending.append(self.r.send(verb, **args))

    def prefetch(self, *signals: str) -> None:
        """Sends a query for each of ``signals`` not asked for since the cycle last ran.

        Queries only read, so asking for what the next steps will read, all at once, saves
        round trips without changing anything on the robot.
        """
        for signal in signals:
            if signal not in self.readings and signal not in self.carried:
                self.readings[signal] = self.r.send("query", signal=signal)
                self.pending.append(self.readings[signal])

    async def flush(self) -> list[Any]:
        """Awaits the replies to every pending request; raises the first refusal."""
        pending, self.pending = self.pending, []
        results = await asyncio.gather(*pending, return_exceptions=True)
        for r in results:
            if isinstance(r, BaseException):
                raise r
        return results

    async def wait(self, *conditions: str, within: float | None = None) -> int:
        """Runs the cycle until one of ``conditions`` holds; returns its index.

        With ``within`` (simulated seconds), returns ``len(conditions)`` when that time passed
        first. The cycle is paused at the cycle the condition held.
        """
        deadline = min(self.t + within, self.limit_s) if within is not None else self.limit_s
        while True:
            # With DELIVER_DEBUG, a look at the truth every 5 s.
            until = min(deadline, self.t + 5) if self.debug else deadline
            conds = [*conditions, f"time > {until:.3f}"]
            index = await self._first(conds)
            if index < len(conditions) or self.t > deadline:
                break
            cars = await self.value("truth.cars")
            await self.say(f"      ... cars {cars} door {await self.value('door')}")
        if index == len(conditions) and self.t > self.limit_s:
            raise OutOfTime(f"the mission's {self.limit_s:.0f} s are up")
        return index

    async def _first(self, conds: list[str]) -> int:
        """Runs until one of ``conds`` holds (pausing there); returns the first that does.

        One pausing monitor watches them all, ``(c0) || (c1) || …``, registered and the cycle
        run in one round trip with the pending changes (the link's round trips are most of a
        headless run's wall time). Which of them held is worked out from the values the
        monitor reports for that cycle.
        """
        stream = self.stream
        assert stream is not None
        whole = " || ".join(f"({c})" for c in conds)
        self.send("monitor_add", condition=whole, mode="once", pause=True, report=list(CARRIED))
        self.send("run")
        monitor = int((await self.flush())[-2]["monitor"])
        fired: MonitorFired | None = None
        async for event in stream:
            if isinstance(event, MonitorFired) and event.monitor == monitor:
                fired = event
                break
        if fired is None:
            raise situate.NotRunning("the link closed while waiting")
        self.t = fired.time_s
        for record in CARRIED:
            prefix = f"{record}."
            values = {
                k.removeprefix(prefix): v for k, v in fired.values.items() if k.startswith(prefix)
            }
            if values and all(v is not None for v in values.values()):  # else never written
                self.carried[record] = values
        for k, c in enumerate(conds):
            if holds(c, fired.values, fired.time_s, fired.cycle):
                return k
        raise RuntimeError(f"none of {conds} holds for {fired.values} at {fired.time_s}")

    async def use(self, *skills: str, restart: Sequence[str] = ()) -> None:
        """Makes ``skills`` the active set (sequenced mode); ``restart`` ones start afresh.

        In all-active mode every skill is already on and stays on: nothing changes.
        """
        if not self.sequenced:
            return
        want = set(skills)
        again = [s for s in restart if s in self.active and s in want]
        off = sorted((self.active - want) | set(again))
        if off:
            self.send("deactivate", skills=off)
            self.active -= set(off)
        if again:
            # A skill notices a re-activation as a gap of more than one cycle.
            self.send("step", cycles=1)
        on = sorted(want - self.active)
        if on:
            self.send("activate", skills=on, with_providers=False)
            self.active |= set(on)

    async def set(self, skill: str, param: str, value: Any) -> None:
        """Sets a skill parameter (no request when it has that value already)."""
        if self.params.get((skill, param)) == value:
            return
        self.send("set_param", skill=skill, param=param, value=value)
        self.params[(skill, param)] = value

    async def restore(self, skill: str, param: str) -> None:
        """Sets a parameter back to its value outside special phases (``NORMAL``)."""
        await self.set(skill, param, NORMAL[(skill, param)])

    async def value(self, signal: str) -> Any:
        """The value of ``signal`` at the end of the last cycle (None if never written)."""
        if signal in self.carried:
            return dict(self.carried[signal])
        self.prefetch(signal)
        reading = self.readings[signal]
        await self.flush()
        return situate.Reading.from_json(await reading).value

    async def odom(self) -> Pose:
        """The odometry pose."""
        o = await self.value("odom")
        return Pose(float(o["x"]), float(o["y"]), float(o["theta"]))

    async def sonar(self) -> list[float]:
        """The sonar ranges, m."""
        return [float(v) for v in await self.value("sonar.range")]

    async def say(self, text: str) -> None:
        """One progress line, stamped with the simulated time."""
        if self.quiet:
            return
        extra = ""
        if self.debug:
            with contextlib.suppress(situate.SituateError):
                p = await self.value("truth.pose")
                if p is not None:
                    extra = f"   (truth: floor {p['floor']} x {p['x']:.2f} y {p['y']:.2f})"
        print(f"[{self.t:7.1f} s] {text}{extra}", flush=True)

    async def phase(self, number: int, text: str) -> None:
        """The progress line of phase ``number`` of the narrative."""
        self.phase_no = number
        self.phase_text = text
        await self.say(f"phase {number}: {text}")

    # ----- behaviours the phases share -------------------------------------------------

    async def turn(self, angle: float, *, keep: Sequence[str] = ()) -> bool:
        """Turns in place by ``angle`` (rad, left positive); False on time-out."""
        start = await self.odom()
        goal = start.theta + angle
        await self.set("turn", "angle", angle)
        await self.use("turn", *keep, restart=["turn"])
        near = " || ".join(
            f"abs(odom.theta - {goal + k * 2 * math.pi:.4f}) < 0.06" for k in (-1, 0, 1)
        )
        done = await self.wait(f"({near}) && abs(odom.w) < 0.1", within=5 + abs(angle) / 0.4)
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
                await self.turn(wrap(math.atan2(py - o.y, px - o.x) - o.theta), keep=["runaway"])
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
            i = round(wrap(b) / (2 * math.pi / SONARS)) % SONARS
            return min(ranges[(i + k) % SONARS] for k in (-1, 0, 1))

        left, right = free(bearing + math.pi / 2), free(bearing - math.pi / 2)
        side = bearing + (math.pi / 2 if left >= right else -math.pi / 2)
        await self.set("runaway", "safe_distance", 0.15)
        try:
            await self.turn(wrap(side), keep=["runaway", *keep])
            go = max(0.0, min(1.0, max(left, right) - 0.7))
            o = await self.odom()
            if go > 0.1:
                await self.goto(
                    o.x + go * math.cos(o.theta), o.y + go * math.sin(o.theta), within=10
                )
        finally:
            await self.restore("runaway", "safe_distance")

    async def goto(self, x: float, y: float, *, within: float = 40) -> bool:
        """Drives to (x, y) of the odometry frame."""
        await self.set("home_position", "x", x)
        await self.set("home_position", "y", y)
        await self.use("runaway", "home_position", restart=["home_position"])
        got = await self.wait(
            f"abs(odom.x - {x:.3f}) < 0.12 && abs(odom.y - {y:.3f}) < 0.12 && abs(odom.v) < 0.03",
            within=within,
        )
        return got == 0

    async def to_frame(self, x: float, y: float) -> tuple[float, float]:
        """A point of the robot frame in the odometry frame."""
        o = await self.odom()
        c, s = math.cos(o.theta), math.sin(o.theta)
        return o.x + c * x - s * y, o.y + s * x + c * y

    async def line_up(self, barcode: int, standoff: float) -> bool:
        """From in view of ``barcode`` on a wall: to ``standoff`` m straight in front of it.

        Homes to about a metre, fits the wall with the sonars, drives to the point on the
        barcode's normal and turns to face the wall.
        """
        await self.set("runaway", "safe_distance", 0.15)
        try:
            if not await self.home_on(barcode, 1.2, avoid=False, runaway=True, slack=0.2, aim=0.2):
                return False
        finally:
            await self.restore("runaway", "safe_distance")
        await self.use()
        self.send("step", cycles=2)
        self.prefetch("sonar.range", "target", "odom")
        wall = wall_ahead(await self.sonar())
        t = await self.value("target")
        if wall is None or not t["seen"]:
            return False
        normal = wall[0]
        bx = float(t["distance"]) * math.cos(float(t["bearing"]))
        by = float(t["distance"]) * math.sin(float(t["bearing"]))
        gx, gy = await self.to_frame(
            bx - standoff * math.cos(normal), by - standoff * math.sin(normal)
        )
        heading = (await self.odom()).theta + normal
        if not await self.goto(gx, gy, within=20):
            return False
        return await self.turn(wrap(heading - (await self.odom()).theta))

    async def pass_door(self, barcode: int | None, hint: str | None) -> bool:
        """Lines up with the door in the wall ahead (beside the barcode homed on) and passes it.

        The opening is found with the sonars (:func:`locate_door`); ``hint`` (``left`` or
        ``right``, from the route) is used only when the sonars cannot tell.
        """
        await self.use()
        self.send("step", cycles=2)
        self.prefetch("sonar.range", "odom")
        fix = locate_door(await self.sonar())
        pose = await self.odom()
        if fix is None or fix.width < 0.3:
            if hint is None:
                await self.say("    no door opening in sight")
                return False
            await self.say(f"    the sonars find no opening: trying the route's hint ({hint})")
            side = 1.0 if hint == "left" else -1.0
            normal = 0.0
            centre = (1.0, side * 0.75)
        else:
            normal, centre = fix.normal, fix.centre
            side = 1.0 if math.sin(math.atan2(centre[1], centre[0]) - normal) > 0 else -1.0
            await self.say(
                f"    door {fix.width:.1f} m wide, {'left' if side > 0 else 'right'} of "
                + (f"barcode {barcode}" if barcode is not None else "ahead")
            )
        # The point DOOR_STANDOFF in front of the opening's centre, in the odometry frame.
        ax = centre[0] - DOOR_STANDOFF * math.cos(normal)
        ay = centre[1] - DOOR_STANDOFF * math.sin(normal)
        c, s = math.cos(pose.theta), math.sin(pose.theta)
        gx, gy = pose.x + c * ax - s * ay, pose.y + s * ax + c * ay
        heading = pose.theta + normal
        await self.set("runaway", "safe_distance", 0.12)
        try:
            if not await self.goto(gx, gy):
                return False
            here = await self.odom()
            if not await self.turn(wrap(heading - here.theta)):
                return False
            start = await self.odom()
            await self.set("pass_door", "distance", DOOR_STANDOFF + 1.1)
            await self.use("runaway", "pass_door", restart=["pass_door"])
            if await self.wait("door_passed", within=30):
                return False
            # Through? Well beyond the wall line along the heading, not stopped at the wall.
            end = await self.odom()
            went = (end.x - start.x) * math.cos(start.theta) + (end.y - start.y) * math.sin(
                start.theta
            )
            if went < DOOR_STANDOFF + 0.3:
                await self.say("    stopped short of the door: backing off")
                await self.use()
                return False
            return True
        finally:
            await self.restore("runaway", "safe_distance")

    # ----- the phases --------------------------------------------------------------------

    async def search(self, barcode: int, budget: float, *, seed: int) -> bool:
        """Wanders (avoiding obstacles), looking round now and then, until ``barcode`` is seen.

        Every ``SEARCH_LEG_S`` of wandering the robot turns round once in place (the reader
        looks ahead only); when it has hardly moved meanwhile, it first drives out of the
        corner it is stuck in, towards the freest direction.
        """
        await self.set("track_barcode", "id", barcode)
        await self.set("wander", "seed", seed)
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
                await self.goto(
                    o.x + go * math.cos(o.theta), o.y + go * math.sin(o.theta), within=10
                )
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
            await self.goto(o.x + d * math.cos(o.theta), o.y + d * math.sin(o.theta), within=10)
            await self.turn(wrap(o.theta - side - (await self.odom()).theta), keep=["runaway"])
        finally:
            await self.set("runaway", "safe_distance", 0.1)  # still in the car

    async def enclosed(self) -> bool:
        """Whether walls are near all round (inside a car: all but the door's sonars)."""
        ranges = await self.sonar()
        return sum(1 for r in ranges if r < 1.9) >= SONARS - 6

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

    async def leave_lab(self) -> None:
        """Phases 1 to 3: out of the lab."""
        m = self.m
        end = self.t + LAB_BUDGET_S
        for attempt in range(12):
            if self.t > end:
                break
            await self.phase(
                1,
                "wandering about the lab, avoiding obstacles, looking for the lab door's "
                f"barcode {m.lab_door_barcode}",
            )
            if not await self.search(m.lab_door_barcode, 300, seed=1 + attempt):
                await self.say("    not found")
                continue
            await self.phase(2, f"homing on the lab door's barcode {m.lab_door_barcode}")
            if not await self.home_on(m.lab_door_barcode, NORMAL[("home", "stop_distance")]):
                await self.say("    the barcode was lost (or the way blocked): looking again")
                continue
            await self.phase(3, "looking for the door opening and passing the lab door")
            if await self.pass_door(m.lab_door_barcode, None):
                return
            await self.say("    could not pass the door: looking again")
            await self.escape(5)
        raise PhaseFailed("could not leave the lab")

    async def follow(self, step: dict[str, Any]) -> bool:
        """A route step ``follow: hallway, until: …``."""
        until = str(step.get("until"))
        side = step.get("side")
        await self.set("follow_hallway", "speed", NORMAL[("follow_hallway", "speed")])
        if until == "barcode":
            code = int(step["barcode"])
            await self.set("track_barcode", "id", code)
            await self.use("runaway", "avoid", "follow_hallway", "track_barcode")
            cond = f"target.seen && target.id == {code}"
        elif until in ("junction", "door"):
            detector, signal = (
                ("detect_intersection", "junction")
                if until == "junction"
                else ("detect_door", "door")
            )
            await self.use("runaway", "avoid", "follow_hallway", detector, restart=[detector])
            sides = [side] if side in ("left", "right") else ["left", "right"]
            cond = " || ".join(f"{signal}.{s}" for s in sides)
        else:  # wall
            await self.use("runaway", "avoid", "follow_hallway")
            cond = "sonar.range[0] < 0.8 && abs(odom.v) < 0.03"
        if await self.wait(cond, within=180):
            return False
        if until == "junction":
            # On into the junction's middle before turning: the opening was seen beside.
            o = await self.odom()
            if not await self.goto(o.x + 0.6 * math.cos(o.theta), o.y + 0.6 * math.sin(o.theta)):
                return False
        return True

    async def run_route(self, leg: str, *, stop_before_home: int | None = None) -> None:
        """Interprets the route hints of ``leg`` (up to a ``home`` on ``stop_before_home``)."""
        steps = self.m.route.get(leg, [])
        pending_home: int | None = None
        for n, step in enumerate(steps):
            if step.get("home") is not None and int(step["home"]) == stop_before_home:
                return
            text = ", ".join(f"{k} {v}" for k, v in step.items())
            await self.say(f"    route {leg}, step {n + 1}: {text}")
            ok = True
            if step.get("follow"):
                ok = await self.follow(step)
            if ok and step.get("home") is not None:
                pending_home = int(step["home"])
                if leg == "car_to_office":
                    await self.phase(12, f"homing on barcode {pending_home}, passing the door")
                ok = False
                for attempt in range(3):
                    await self.set("track_barcode", "id", pending_home)
                    await self.use("runaway", "avoid", "track_barcode")
                    self.send("step", cycles=3)
                    if not (await self.value("target"))["seen"] and not await self.search(
                        pending_home, 60, seed=attempt + 1
                    ):
                        continue
                    if any(s.get("pass") for s in steps[n + 1 :]):
                        ok = await self.line_up(pending_home, DOOR_STANDOFF)
                    else:
                        ok = await self.home_on(pending_home, NORMAL[("home", "stop_distance")])
                    if ok:
                        break
                    await self.say(f"    could not home on barcode {pending_home}: again")
            if ok and step.get("pass"):
                hint = next(
                    (str(s.get("turn")) for s in reversed(steps[:n]) if s.get("turn")), None
                )
                for _attempt in range(3):
                    ok = await self.pass_door(pending_home, hint)
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
                ok = await self.turn(angle)
            if not ok:
                raise PhaseFailed(f"route {leg}, step {n + 1} ({text}) failed")

    async def to_lobby(self) -> None:
        """Phase 4: the route hints from the lab door to the elevator lobby."""
        await self.phase(4, "following the hallways to the elevator lobby")
        await self.run_route("lab_to_lobby", stop_before_home=self.m.call_button_barcode)

    async def call_and_board(self) -> None:
        """Phases 5 to 7: call a car, wait for it, identify it, enter it (calling again)."""
        m = self.m
        for attempt in range(6):
            await self.phase(5, f"homing on the call button (barcode {m.call_button_barcode})")
            if self.button_pose is not None:
                # Called before: back to where the button was pushed, by odometry.
                b = self.button_pose
                back = (b.x - 0.9 * math.cos(b.theta), b.y - 0.9 * math.sin(b.theta))
                await self.set("runaway", "safe_distance", 0.15)
                if await self.goto(*back, within=60):
                    await self.turn(wrap(b.theta - (await self.odom()).theta), keep=["runaway"])
                await self.restore("runaway", "safe_distance")
            await self.set("track_barcode", "id", m.call_button_barcode)
            await self.use("runaway", "avoid", "track_barcode")
            self.send("step", cycles=3)
            if not (await self.value("target"))["seen"] and not await self.search(
                m.call_button_barcode, 120, seed=attempt + 1
            ):
                raise PhaseFailed("the call button is nowhere in sight")
            homed = await self.line_up(m.call_button_barcode, 1.0) and await self.home_on(
                m.call_button_barcode, 0.45, avoid=False, slack=0.12, aim=0.3
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
                self.button_pose = await self.odom()
            else:
                await self.restore("runaway", "safe_distance")
                continue
            if await self.wait_for_car():
                return
            await self.say("    no car to board: calling again")
        raise PhaseFailed("could not board a car")

    async def wait_for_car(self) -> bool:
        """Patrols the lobby along the cars until a car's door opens, identifies it, enters."""
        m = self.m
        await self.phase(6, "waiting for a car: patrolling the lobby, watching for an open door")
        self.car = 0
        # Crowded lobby: let the robot come nearer to things.
        await self.set("runaway", "safe_distance", 0.15)
        await self.set("follow_hallway", "speed", 0.6)
        if not await self.turn(-math.pi / 2, keep=["runaway"]):
            return False
        side = "left"  # the cars' wall, seen from the patrol heading
        deadline = self.t + 60
        while self.t < deadline:
            await self.use("runaway", "follow_hallway", "detect_door", restart=["detect_door"])
            got = await self.wait(
                f"door.{side}",
                "sonar.range[0] < 0.75 && abs(odom.v) < 0.03",
                within=deadline - self.t,
            )
            if got == 2:
                break
            if got == 1:
                await self.say("    end of the lobby: turning back")
                if not await self.turn(math.pi, keep=["runaway"]):
                    return False
                side = "right" if side == "left" else "left"
                continue
            self.prefetch("door", "odom")  # the turn reads the odometry
            bearing = float((await self.value("door"))["bearing"])
            await self.phase(6, "a car's door opened: facing it, reading which car it is")
            if not await self.turn(bearing, keep=["runaway"]):
                continue
            await self.set("identify_car", "first_id", m.car_barcode_first)
            await self.set("identify_car", "cars", m.cars)
            await self.set("runaway", "safe_distance", 0.1)
            await self.set("enter_car", "distance", 4.0)
            await self.use(
                "runaway", "enter_car", "identify_car", restart=["enter_car", "identify_car"]
            )
            if await self.wait("car > 0", "car_entered", within=20) == 0:
                self.car = int(await self.value("car"))
                await self.phase(7, f"car {self.car} arrived: entering it")
                await self.wait("car_entered", within=20)
            # Inside? Walls all round but for the door (the sonars), and the car's own
            # barcode on the panel, near once the robot looks round.
            self.car = int(await self.value("car")) or self.car
            if self.car > 0 and await self.enclosed():
                code = m.car_barcode_first + self.car - 1
                if await self.look_round(code):
                    await self.say(f"    inside car {self.car}")
                    return True
            if self.debug:
                await self.say(f"      car {self.car} target {await self.value('target')}")
            await self.say("    the car left before the robot got in")
            break
        await self.restore("runaway", "safe_distance")
        await self.restore("follow_hallway", "speed")
        return False

    async def ride(self) -> None:
        """Phases 8 to 10: push the goal floor, ride, leave the car."""
        m = self.m
        code = m.car_barcode_first + self.car - 1 if self.car else -1
        # Square to the back wall (the panel's), midway between the side walls: the door is
        # then straight behind, and the way out clear once turned round.
        await self.use("runaway")
        self.send("step", cycles=2)
        self.prefetch("sonar.range", "odom")  # a turn reads the odometry
        wall = wall_ahead(await self.sonar())
        if wall is not None and abs(wall[0]) > 0.03:
            await self.turn(wall[0], keep=["runaway"])
        await self.centre_between_walls()
        for _attempt in range(3):
            await self.phase(8, f"pushing the button for floor {m.goal_floor}")
            if self.car == 0:
                await self.set("identify_car", "first_id", m.car_barcode_first)
                await self.set("identify_car", "cars", m.cars)
                await self.use("identify_car")
                self.send("step", cycles=3)
                self.car = int(await self.value("car"))
                code = m.car_barcode_first + self.car - 1 if self.car else -1
            presses = int(await self.value("arm.presses") or 0)
            await self.set("track_barcode", "id", code)
            await self.set("push_button", "button", m.goal_floor)
            await self.set("home", "stop_distance", 0.45)
            await self.use(
                "runaway", "track_barcode", "home", "push_button", restart=["push_button"]
            )
            if await self.wait(f"arm.presses > {presses}", within=15) == 0:
                break
        else:
            raise PhaseFailed(f"could not push the button for floor {m.goal_floor}")
        await self.restore("home", "stop_distance")
        await self.phase(9, f"riding to floor {m.goal_floor}; turning to face the door")
        await self.use("runaway")
        if await self.wait(f"floor != {m.start_floor}", within=30):
            raise PhaseFailed("the car does not move")
        # Face the door squarely: the back wall (the panel's) straight behind.
        wall = wall_ahead(await self.sonar())
        about = wrap(math.pi + (wall[0] if wall is not None else 0.0))
        if not await self.turn(about, keep=["runaway"]):
            raise PhaseFailed("could not turn round in the car")
        if await self.wait(f"floor == {m.goal_floor} && sonar.range[0] > 2.2", within=90):
            raise PhaseFailed(f"the car never opened on floor {m.goal_floor}")
        await self.phase(10, f"floor {m.goal_floor}: leaving the car")
        await self.set("leave_car", "distance", 3.0)
        for _attempt in range(4):
            start = await self.odom()
            await self.use("runaway", "leave_car", restart=["leave_car"])
            if await self.wait("car_exited", within=30):
                raise PhaseFailed("could not leave the car")
            here = await self.odom()
            if math.hypot(here.x - start.x, here.y - start.y) > 1.5 or not await self.enclosed():
                break
            if self.debug:
                await self.say(f"      stopped: sonar ahead {(await self.sonar())[:3]}")
            await self.say("    stopped in the doorway: on out")
        else:
            raise PhaseFailed("could not leave the car")
        await self.restore("runaway", "safe_distance")
        await self.restore("follow_hallway", "speed")

    async def to_office(self) -> None:
        """Phases 11 to 13: the route hints from the car to the office, then deliver."""
        await self.phase(
            11, f"following the corridor to the office's barcode {self.m.office_barcode}"
        )
        await self.run_route("car_to_office")
        await self.phase(13, "delivering the message")
        count = int(await self.value("speaker.count") or 0)
        await self.set("say", "message", self.m.message)
        await self.use("say", restart=["say"])
        if await self.wait(f"speaker.count > {count}", within=5):
            raise PhaseFailed("the speaker said nothing")
        await self.say(f'    said: "{self.m.message}"')

    # ----- the whole mission ----------------------------------------------------------------

    async def setup(self) -> None:
        """Sets every parameter the sequencer changes, and the skills' starting state."""
        for (skill, param), value in NORMAL.items():
            await self.set(skill, param, value)
        if self.sequenced:
            self.send("deactivate", skills=list(SKILLS))
        else:
            self.send("activate", skills=list(SKILLS), with_providers=False)
            self.active = set(SKILLS)
        # A few cycles, so that every device's signal has a value.
        for _ in range(10):
            self.prefetch("odom", "sonar.range")
            if await self.value("odom") is not None and await self.value("sonar.range"):
                break
            self.send("step", cycles=1)

    async def run(self, first: str, last: str) -> None:
        """Runs the phases from ``first`` to ``last`` (names of ``PHASES``)."""
        async with self.r.events("monitor_fired") as stream:
            self.stream = stream
            try:
                await self.run_phases(first, last)
            finally:
                self.stream = None

    async def run_phases(self, first: str, last: str) -> None:
        """The phases from ``first`` to ``last``."""
        await self.setup()
        steps = {
            "lab": self.leave_lab,
            "corridor": self.to_lobby,
            "lobby": self.call_and_board,
            "ride": self.ride,
            "office": self.to_office,
        }
        for name in PHASES[PHASES.index(first) : PHASES.index(last) + 1]:
            await steps[name]()
        await self.use()
        await self.flush()
        await self.say("mission complete")


async def main(argv: Sequence[str] | None = None) -> int:
    """Parses the arguments `situate demo` passes, runs the mission; the exit status."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--connect", default=os.environ.get("SITUATE_CONNECT", "tcp/127.0.0.1:7447"))
    p.add_argument("--robot", default=None)
    p.add_argument("--mode", choices=["sequenced", "all-active"], default="sequenced")
    p.add_argument("--limit-s", type=float, default=1800.0, help="give up after this (simulated)")
    p.add_argument("--mission", required=True, help="the map's mission section, as JSON")
    p.add_argument(
        "--from",
        dest="first",
        choices=PHASES,
        default=os.environ.get("DELIVER_FROM") or PHASES[0],
        help="start at this phase (the scenario maps start the robot there; env DELIVER_FROM)",
    )
    p.add_argument(
        "--to",
        dest="last",
        choices=PHASES,
        default=os.environ.get("DELIVER_TO") or PHASES[-1],
        help="stop after this phase (env DELIVER_TO)",
    )
    p.add_argument("--quiet", action="store_true")
    a = p.parse_args(argv)
    mission = Mission.from_json(a.mission)
    async with situate.connect(a.robot, endpoint=a.connect, timeout=30) as robot:
        seq = Sequencer(robot, mission, a.mode, a.limit_s, a.quiet)
        try:
            await seq.run(a.first, a.last)
        except (PhaseFailed, OutOfTime) as e:
            await seq.say(f"mission failed: {e}")
            with contextlib.suppress(situate.SituateError):
                await robot.stop()
            return 1
        except (asyncio.CancelledError, KeyboardInterrupt):
            # Interrupted (`run`): one line, whatever --quiet says, and the cycle stopped.
            where = f" in phase {seq.phase_no} ({seq.phase_text})" if seq.phase_no else ""
            name = Signals(INTERRUPTED.get("signal", SIGINT)).name
            print(f"[{seq.t:7.1f} s] interrupted ({name}){where}, message not delivered")
            INTERRUPTED["said"] = 1
            with contextlib.suppress(situate.SituateError, asyncio.TimeoutError):
                await asyncio.wait_for(robot.stop(), 2)
            raise
        with contextlib.suppress(situate.SituateError):
            await robot.stop()
    return 0


#: How the run was interrupted: ``signal`` (its number) and whether the outcome was ``said``.
INTERRUPTED: dict[str, int] = {}


async def _main_stopping_on_signals(argv: Sequence[str] | None) -> int:
    """:func:`main`, cancelled by SIGTERM or SIGHUP as by Ctrl-C (``asyncio.run``'s own)."""
    task = asyncio.current_task()
    assert task is not None

    def stop(sig: int) -> None:
        if "signal" in INTERRUPTED:  # a second one: at once
            sys.stdout.flush()
            os._exit(128 + sig)
        INTERRUPTED["signal"] = sig
        task.cancel()

    loop = asyncio.get_running_loop()
    for sig in (SIGTERM, SIGHUP):
        with contextlib.suppress(NotImplementedError, AttributeError):  # not on Windows
            loop.add_signal_handler(sig, stop, sig)
    return await main(argv)


def run(argv: Sequence[str] | None = None) -> int:
    """Runs :func:`main`; the exit status.

    Ctrl-C, SIGTERM and SIGHUP end the mission with one line (the time and the phase) and
    status 128 + the signal's number (130 for Ctrl-C), without a traceback; a second signal
    ends the program at once.
    """
    try:
        return asyncio.run(_main_stopping_on_signals(argv))
    except (KeyboardInterrupt, asyncio.CancelledError):
        sig = INTERRUPTED.get("signal", SIGINT)
        if not INTERRUPTED.get("said"):
            print(f"interrupted ({Signals(sig).name}) before the mission started")
        return 128 + sig


if __name__ == "__main__":
    status = run()
    # The link is closed and the output written: leave without the interpreter's teardown
    # (collecting every object, stopping Zenoh's threads: some 30 ms of a headless run).
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
