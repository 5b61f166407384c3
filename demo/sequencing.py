"""Sequencing a situated robot over the situate link: a reusable layer under a mission.

A mission (such as `deliver.py`) is a short narrative of phases; this module gives it the means:

- the link, used so that a run on the simulated clock replays exactly: the sequencer acts only
  at the cycle a monitor fired (monitors registered with ``pause``), requests that change
  something are sent without waiting and collected by the next one that needs an answer
  (`Sequencer.send`, `flush`), and every wait has a time-out on the robot's clock (`wait`);
- switching skills (`use`: the active set), parameters (`set`, `restore`), reading values;
- behaviours built of the standard skills (`std.*`, see crates/situate_skills) that any mission
  of the mobile robot needs: turning, homing on a barcode, driving to a point of the odometry
  frame, lining up with a barcode on a wall, passing the door ahead, searching for a barcode,
  getting unstuck. The interpreter of route hints (docs/maps.md) is `routes.py`, over this.

Perception is the skills' job: the wall ahead is `std.fit_wall`'s `wall`, the door in it
`std.locate_door`'s `opening`; the sequencer activates them and reads their outputs.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import situate
from situate.events import MonitorFired, SkillFaulted

SONARS = 24
ROBOT_RADIUS = 0.25
#: How far in front of a door the robot lines up before passing it, m.
DOOR_STANDOFF = 0.9
#: Openings wider than this are not a door; a door is taken to be DOOR_WIDTH wide, m.
MAX_DOOR_WIDTH = 1.6
DOOR_WIDTH = 1.1
#: `until: wall` ends with the wall ahead this near (from the robot's centre), m.
WALL_AHEAD_M = 1.2
#: How long to wait in front of a door that shows no opening (closed doors open again), s.
DOOR_WAIT_S = 75.0
#: A door's nearer jamb is at most this far from its barcode (docs/maps.md: 0.1 to 0.6 m), with
#: the slack of placing a jamb by sonar; an opening farther off is some other way, m.
DOOR_BESIDE_BARCODE_M = 1.0
#: How long a wall across the way must stay put while the robot stands (people move on), s.
WALL_STAYS_S = 6.0
#: Through a door: this far beyond the wall's line, m.
BEYOND_WALL_M = 0.4
#: Wandering between two looks round, s.
SEARCH_LEG_S = 20.0
#: Homing that gets no closer for this long steps aside, s.
HOME_PROGRESS_S = 8.0
#: A skill that faults (a body over its budget on a loaded machine, say) is switched on again,
#: unless it faulted this many times within FAULT_WINDOW_S (simulated): then the mission fails.
FAULTS_IN_WINDOW = 5
FAULT_WINDOW_S = 60.0
#: The events a sequencer's stream carries.
EVENT_KINDS = ("monitor_fired", "skill_faulted")

#: Records the sequencer reads after most waits: each wait's monitor asks for them (``report``),
#: so their values as of the cycle it fired in come with its event instead of a query each.
CARRIED = ("odom", "target")


class PhaseFailed(Exception):
    """A phase could not be completed (after its retries)."""


class OutOfTime(Exception):
    """The mission's time limit passed."""


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


def bearing_of(i: int) -> float:
    """Bearing of sonar ``i`` in the robot frame (sonar 0 ahead, counter-clockwise)."""
    return wrap(i * 2 * math.pi / SONARS)


class Sequencer:
    """Drives a robot over the link: waits, skill switching, parameters, shared behaviours.

    ``normal`` holds the value of every parameter the sequencer changes in some phase, as it
    is elsewhere (`restore`). In ``all-active`` mode (the experiment's baseline) `use` changes
    nothing: every skill stays on and priorities alone decide. ``seed`` seeds every random
    choice of the behaviours (the wander paths), so a run is a function of its seed.
    """

    def __init__(
        self,
        robot: situate.Robot,
        *,
        normal: Mapping[tuple[str, str], Any],
        mode: str = "sequenced",
        limit_s: float = 1800.0,
        quiet: bool = False,
        seed: int = 1,
    ) -> None:
        self.r = robot
        self.normal = dict(normal)
        self.sequenced = mode == "sequenced"
        self.limit_s = limit_s
        self.quiet = quiet
        self.seed = seed
        self.debug = bool(os.environ.get("DELIVER_DEBUG"))
        #: DELIVER_TRACE=FILE: the true pose every 0.25 s, one JSON line each (for debugging).
        trace = os.environ.get("DELIVER_TRACE")
        self.trace = open(trace, "w") if trace else None  # noqa: SIM115 (open for the run)
        self.active: set[str] = set()
        #: The simulated time at the last pause (a monitor fired); `step` makes it stale.
        self.t = 0.0
        self.t_stale = False
        #: The cycle's period on the simulated clock (stepping N cycles adds N of them).
        self.period_s: float | None = None
        self.phase_no = 0
        self.phase_text = ""
        #: Searches so far: each wanders along a path of its own (seeded by ``seed`` and this).
        self.searches = 0
        #: The odometry heading a route planned the robot to be following (see `run_route`).
        self.corridor_heading: float | None = None
        #: The barcode last lined up with and its wall's normal (odometry frame): x, y, rad.
        self.wall_fix: tuple[float, float, float] | None = None
        #: The odometry heading the last door was passed at (out through it).
        self.passed_heading: float | None = None
        self.stream: situate.Stream[Any] | None = None
        self.params: dict[tuple[str, str], Any] = {}
        #: Replies to requests sent but not yet awaited (see `send`).
        self.pending: list[asyncio.Future[Any]] = []
        #: Queries sent since the cycle last ran, by signal: their answers stand until it runs.
        self.readings: dict[str, asyncio.Future[Any]] = {}
        #: Round trips to the robot so far (each `flush`; DELIVER_DEBUG prints them at the end).
        self.round_trips = 0
        #: Records the last wait's event reported (`CARRIED`), until the cycle runs again.
        self.carried: dict[str, dict[str, Any]] = {}
        #: Skills that faulted: (cycle, skill, cause), oldest first.
        self.faults: list[tuple[int, str, str]] = []

    # ----- the link: waiting, switching skills, parameters ------------------------------

    def send(self, verb: str, **args: Any) -> None:
        """Sends a request now; its reply is awaited with the next one that needs an answer.

        The manager handles requests in the order they are sent, so a query (or a wait) sent
        after changes costs one round trip for them all (see `flush`).
        """
        if verb in ("run", "step"):
            self.readings.clear()  # the cycle runs: every signal may change
            self.carried.clear()
        if verb == "step":
            # The time moves on by the cycles stepped: on the simulated clock exactly that
            # many periods (known after the first look at the robot's stats).
            if self.period_s is not None:
                self.t += int(args.get("cycles", 1)) * self.period_s
            else:
                self.t_stale = True
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
        """Awaits the replies to every pending request; raises the first refusal.

        A request cut short because a body got stuck (`situate.Interrupted`: a `step` that
        ended early) is no refusal: the cycle went on, and the fault comes as an event
        (`on_fault`). Its place in the list holds the exception; the time is read anew.
        """
        pending, self.pending = self.pending, []
        self.round_trips += 1
        results = await asyncio.gather(*pending, return_exceptions=True)
        for r in results:
            if isinstance(r, situate.Interrupted):
                self.t_stale = True
            elif isinstance(r, BaseException):
                raise r
        return results

    async def now(self) -> float:
        """The simulated time now (``t``, asked of the robot when cycles were stepped since)."""
        if self.t_stale:
            stats = self.r.send("stats")
            self.pending.append(stats)
            await self.flush()
            result = await stats
            self.t = float(result["time_s"])
            period = float(result.get("period_s") or 0.0)
            self.period_s = period if period > 0 else None
            self.t_stale = False
        return self.t

    async def wait(self, *conditions: str, within: float | None = None) -> int:
        """Runs the cycle until one of ``conditions`` holds; returns its index.

        With ``within`` (simulated seconds from now), returns ``len(conditions)`` when that
        time passed first. The cycle is paused at the cycle the condition held.
        """
        # From the time now: after stepping (a look at a wall for 6 s, say) a deadline
        # from the last pause's time could be over before the wait began.
        await self.now()
        deadline = min(self.t + within, self.limit_s) if within is not None else self.limit_s
        # The deadline exactly (repr: the shortest text that reads back as the same float).
        watched = [*conditions, f"time >= {deadline!r}"]
        if self.trace is not None:  # stops every 0.25 s to write where the robot truly is
            while (index := await self._first([*watched, f"time >= {self.t + 0.25!r}"])) == len(
                watched
            ):
                await self._trace()
        else:
            index = await self._first(watched)
        if index == len(conditions) and self.t >= self.limit_s:
            raise OutOfTime(f"the mission's {self.limit_s:.0f} s are up")
        return index

    async def _first(self, conds: list[str]) -> int:
        """Runs until one of ``conds`` holds (pausing there); returns the first that does.

        One pausing monitor watches them all (``any``), registered and the cycle run in one
        round trip with the pending changes (the link's round trips are most of a headless
        run's wall time); its event says which of them held in the cycle it fired (``held``).
        """
        stream = self.stream
        assert stream is not None
        self.send("monitor_add", any=list(conds), mode="once", pause=True, report=list(CARRIED))
        self.send("run")
        added = (await self.flush())[-2]
        if isinstance(added, BaseException):
            raise added
        monitor = int(added["monitor"])
        fired: MonitorFired | None = None
        async for event in stream:
            if isinstance(event, SkillFaulted):
                await self.on_fault(event)
            elif isinstance(event, MonitorFired) and event.monitor == monitor:
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
        if not fired.held:
            raise RuntimeError(f"monitor {monitor} fired with none of {conds} holding")
        return min(fired.held)

    async def on_fault(self, event: SkillFaulted) -> None:
        """A skill faulted: the manager switched it off. One in use is switched on again.

        A fault is the manager's guard against a body that overran its deadline or raised; on
        a busy machine a healthy body can overrun once. The skill is reactivated at once (a
        fresh body), so a wait that needs its output is not left waiting for good. A skill that
        keeps faulting (`FAULTS_IN_WINDOW` within `FAULT_WINDOW_S`) fails the mission instead.
        """
        self.faults.append((event.cycle, event.skill, event.cause))
        await self.say(f"    skill {event.skill!r} faulted: {event.cause}")
        if event.skill not in self.active:
            return
        # Counted in cycles: while a wait runs, `t` is the time it began.
        window = FAULT_WINDOW_S / (self.period_s or 0.1)
        recent = [f for f in self.faults if f[1] == event.skill and f[0] >= event.cycle - window]
        if len(recent) >= FAULTS_IN_WINDOW:
            raise PhaseFailed(
                f"skill {event.skill!r} faulted {len(recent)} times within"
                f" {FAULT_WINDOW_S:.0f} s: {event.cause}"
            )
        self.send("activate", skills=[event.skill], with_providers=False)
        await self.say(f"    skill {event.skill!r} switched on again")

    def take_faults(self) -> list[SkillFaulted]:
        """The faults that arrived on the stream since the last look (a polling loop's)."""
        stream = self.stream
        if stream is None:
            return []
        return [e for e in stream.drain() if isinstance(e, SkillFaulted)]

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
        """Sets a parameter back to its value outside special phases (``normal``)."""
        await self.set(skill, param, self.normal[(skill, param)])

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

    async def _trace(self) -> None:
        assert self.trace is not None
        with contextlib.suppress(situate.SituateError):
            self.prefetch("truth.pose", "truth.cars", "truth.people")
            p = await self.value("truth.pose")
            if p is not None:
                cars = await self.value("truth.cars")
                people = await self.value("truth.people")
                line = {"t": self.t, **p, "cars": cars, "people": people}
                self.trace.write(json.dumps(line) + "\n")
                self.trace.flush()

    async def say(self, text: str) -> None:
        """One progress line, stamped with the simulated time."""
        if self.quiet:
            return
        extra = ""
        if self.debug:
            with contextlib.suppress(situate.SituateError):
                p = await self.value("truth.pose")
                if p is not None:
                    extra = (
                        f"   (truth: floor {p['floor']} x {p['x']:.2f} y {p['y']:.2f}"
                        f" heading {math.degrees(p['theta']):.0f}°)"
                    )
        print(f"[{await self.now():7.1f} s] {text}{extra}", flush=True)

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
        # Loosely: `start` may be a cycle older than the skill's own start (the robot still
        # turning from what it did before); the turn rate under 0.1 rad/s says it is done.
        near = " || ".join(
            f"abs(odom.theta - {goal + k * 2 * math.pi:.4f}) < 0.15" for k in (-1, 0, 1)
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
        o = await self.odom()
        c, s = math.cos(o.theta), math.sin(o.theta)
        return o.x + c * x - s * y, o.y + s * x + c * y

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
        for n in [normal, *others][:2]:
            gx, gy = px - standoff * math.cos(n), py - standoff * math.sin(n)
            if not await self.goto(gx, gy, within=30):
                return False
            if not await self.turn(wrap(n - (await self.odom()).theta)):
                return False
            if await self.barcode_ahead(barcode, standoff):
                self.wall_fix = (px, py, wrap(n))
                return True
            await self.say(f"    barcode {barcode} not straight ahead: lining up with another wall")
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
        px = o.x + distance * math.cos(o.theta + bearing)
        py = o.y + distance * math.sin(o.theta + bearing)
        # Looking towards the barcode first; a door beside it may hide most of that wall from
        # the sonars, so then wider. The wall must be the barcode's: it lies on its line.
        normal: float | None = None  # in the odometry frame
        try:
            for look, half in ((bearing, 60.0), (bearing, 90.0), (0.0, 80.0)):
                await self.set("fit_wall", "bearing_deg", math.degrees(look))
                await self.set("fit_wall", "half_angle_deg", half)
                wall = await self.clue("fit_wall", "wall", keep=["track_barcode"])
                if wall is None:
                    continue
                w = await self.odom()
                n = w.theta + float(wall["normal"])
                along = (px - w.x) * math.cos(n) + (py - w.y) * math.sin(n)
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
        corridor lies about as far to that side as the point does; on the end wall when a
        wall lies across the corridor about as far ahead as the point, and no side wall
        holds it. ``fitted`` is a wall across the way fitted through the point (kept, with
        its angle, when it is the end wall). Walls fitted, not single echoes: someone
        standing in the corridor is no wall. With neither, the sonars cannot tell (a door
        beside the barcode fills their view): the side it lies to.
        """
        self.prefetch("odom")
        w = await self.odom()
        lateral = -(px - w.x) * math.sin(axis) + (py - w.y) * math.cos(axis)
        side = axis + math.copysign(math.pi / 2, lateral)
        ahead = (px - w.x) * math.cos(axis) + (py - w.y) * math.sin(axis)
        by = await self.wall_towards(side)
        on_side = by is not None and abs(wrap(by[0] - side)) < math.radians(20)
        on_side = on_side and by is not None and abs(by[1] - abs(lateral)) < 0.35
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
        await self.set("fit_wall", "bearing_deg", math.degrees(wrap(direction - o.theta)))
        await self.set("fit_wall", "half_angle_deg", 50.0)
        try:
            wall = await self.clue("fit_wall", "wall")
        finally:
            await self.restore("fit_wall", "bearing_deg")
            await self.restore("fit_wall", "half_angle_deg")
        if wall is None:
            return None
        return wrap(o.theta + float(wall["normal"])), float(wall["distance"])

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
        looks = round(WALL_STAYS_S / 0.5)
        for _window in range(3):
            seen: list[float] = []
            for _ in range(looks):
                self.send("step", cycles=5)
                wall = await self.value("wall")
                square = abs(float(wall["normal"])) < math.radians(25)
                near = float(wall["distance"]) < WALL_AHEAD_M + 0.1
                if wall["seen"] and int(wall["inliers"]) >= 5 and square and near:
                    seen.append(float(wall["distance"]))
            middle = sorted(seen)[len(seen) // 2] if seen else 0.0
            steady = sum(abs(d - middle) < 0.08 for d in seen)
            if self.debug:
                await self.say(f"      wall looks: {steady} of {looks} steady, {len(seen)} seen")
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
        px, py, normal = self.wall_fix
        o = await self.odom()
        beyond = (o.x - px) * math.cos(normal) + (o.y - py) * math.sin(normal)
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
            distance = (px - o.x) * math.cos(normal) + (py - o.y) * math.sin(normal)
            bearing = wrap(normal - o.theta)
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

    async def barcode_across(self, barcode: int | None) -> float | None:
        """Where the barcode just lined up with is across the robot's view (robot frame, m).

        Its lateral offset, left positive, from `line_up`'s fix; None without a barcode or a
        fix, or when the fix is not in front of the robot (some earlier barcode's).
        """
        if barcode is None or self.wall_fix is None:
            return None
        px, py, _normal = self.wall_fix
        o = await self.odom()
        dx, dy = px - o.x, py - o.y
        ahead = dx * math.cos(o.theta) + dy * math.sin(o.theta)
        across = -dx * math.sin(o.theta) + dy * math.cos(o.theta)
        return across if 0.2 < ahead < 3.0 and abs(across) < 2.0 else None

    async def pass_door(self, barcode: int | None, hint: str | None) -> bool:
        """Lines up with the door in the wall ahead (beside the barcode homed on) and passes it.

        The opening is `std.locate_door`'s; ``hint`` (``left`` or ``right``, from the route)
        is used only when it finds none.
        """
        fix = await self.opening()
        beside = await self.barcode_across(barcode)
        if fix is not None and beside is not None:
            gap = abs(float(fix["y"]) - beside) - float(fix["width"]) / 2
            if gap > DOOR_BESIDE_BARCODE_M:
                # Its door closed (or someone in it), the scan finds another way along the
                # wall: a corridor's mouth, the next room's door.
                await self.say(f"    an opening {gap:.1f} m from barcode {barcode}: not its door")
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
            if await self.wait(wanted, within=DOOR_WAIT_S) == 0:
                fix = await self.opening()
        pose = await self.odom()
        if fix is None or float(fix["width"]) < 0.3:
            if hint is None:
                await self.say("    no door opening in sight")
                return False
            await self.say(f"    the sonars find no opening: trying the route's hint ({hint})")
            side = 1.0 if hint == "left" else -1.0
            normal = 0.0
            centre = (1.0, side * 0.75)
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
            went = 0.0
            for push in range(3):
                if push > 0:
                    # Stopped by someone ahead in the doorway or just beyond (a room's
                    # people walk about): they move on; the robot waits, then goes on.
                    await self.say("    someone in the way through the door: waiting")
                    here = await self.odom()
                    if abs(wrap(start.theta - here.theta)) > 0.2:  # pushed aside meanwhile
                        await self.turn(wrap(start.theta - here.theta))
                    await self.use("runaway")
                    await self.wait(f"sonar.range[0] > {ROBOT_RADIUS + 0.9}", within=10)
                await self.set("pass_door", "distance", DOOR_STANDOFF + 1.1 - went)
                await self.use("runaway", "pass_door", restart=["pass_door"])
                if await self.wait("door_passed", within=30):
                    return False
                # Through? Well beyond the wall line along the heading, not stopped at it.
                end = await self.odom()
                went = (end.x - start.x) * math.cos(start.theta) + (end.y - start.y) * math.sin(
                    start.theta
                )
                # Stopped short, but in the doorway already (some way past the standoff):
                # it was someone beyond, not the jambs.
                if went >= DOOR_STANDOFF + 0.3 or went < DOOR_STANDOFF - 0.3:
                    break
            if went < DOOR_STANDOFF + 0.3:
                await self.say("    stopped short of the door: backing off")
                await self.use()
                return False
            self.passed_heading = start.theta
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

    async def live_sonar_ahead(self) -> int:
        """The sonar nearest ahead that `std.sonar_filter` does not take to be dead."""
        health = await self.value("sonar.health")
        mask = int(health["mask"]) if health else 0
        live = [k for k in range(SONARS) if not mask >> k & 1]
        return min(live, key=lambda k: abs(bearing_of(k))) if live else 0

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
