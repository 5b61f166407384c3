"""The situate link to the robot, as a mission's sequencer and the reactive robot use it.

The mechanics under both of the experiment's designs (`sequenced.behaviours.Sequencer`, the
sequenced robot's behaviours, and `reactive.rules.Reactive`, the rule list), in `Link`:

- the link, used so that a run on the simulated clock replays exactly: the robot's program acts
  only at the cycle a monitor fired (monitors registered with ``pause``), requests that change
  something are sent without waiting and collected by the next one that needs an answer
  (`Link.send`, `flush`), and every wait has a time-out on the robot's clock (`wait`);
- skills that fault switched on again (`on_fault`), up to a limit;
- switching skills (`use`: the active set), parameters (`set`, `restore`), reading values
  (`value`, `odom`, `sonar`; several at one moment in one request: `snapshot`); progress lines
  (`say`, `phase`).

What both read the robot with, its odometry pose and its sonar ring, is `geometry`'s.
"""

from __future__ import annotations

import asyncio
import contextlib
import copy
import json
import math
import os
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import situate
from courier.geometry import Pose
from situate.events import MonitorFired, SkillFaulted

#: A skill that faults (a body over its budget on a loaded machine, say) is switched on again,
#: unless it faulted this many times within FAULT_WINDOW_S (simulated): then the mission fails.
FAULTS_IN_WINDOW = 5
FAULT_WINDOW_S = 60.0
#: The events a link's stream carries (`Link.stream`).
EVENT_KINDS = ("monitor_fired", "skill_faulted")

#: Values read after most waits: each wait's monitor asks for them (``report``), so their
#: values as of the cycle it fired in come with its event instead of a query each. A record
#: (``odom``) comes as its leaves, a leaf (``sonar.range``: read after 4 waits in 5) whole.
CARRIED = ("odom", "target", "sonar.range")


class Snapshot:
    """Signals read in one ``query_many`` request: all at the end of the same cycle.

    `Link.snapshot` sends it; its reply comes with the next `Link.flush`, then `values` reads it.
    """

    def __init__(self, signals: Sequence[str], reply: asyncio.Future[Any]) -> None:
        self.signals = tuple(signals)
        self.reply = reply

    async def values(self) -> dict[str, Any]:
        """Each signal's value (None if never written), as `Link.value` would read it."""
        readings = await self.reply
        if not (isinstance(readings, list) and len(readings) == len(self.signals)):
            raise situate.BadReply(f"`query_many`: not {len(self.signals)} readings: {readings!r}")
        return {
            s: situate.Reading.from_json(r).value
            for s, r in zip(self.signals, readings, strict=True)
        }


class PhaseFailed(Exception):
    """A phase could not be completed (after its retries)."""


class OutOfTime(Exception):
    """The mission's time limit passed."""


class Link:
    """Drives a robot over the link: waits, skill switching, parameters, values, progress lines.

    ``normal`` holds the value of every parameter the robot's program changes in some phase, as
    it is elsewhere (`restore`). In ``all-active`` mode (the experiment's baseline) `use`
    changes nothing: every skill stays on and priorities alone decide. ``seed`` is the run's
    seed, for every random choice of the program (the wander paths), so a run is a function
    of it.
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
        #: Skills on from the start that the sequencer never switches (devices, the sonar
        #: filter): a fault switches them on again too (`on_fault`).
        self.kept_on: set[str] = set()
        #: The simulated time at the last pause (a monitor fired); `step` makes it stale.
        self.t = 0.0
        self.t_stale = False
        #: The cycle's period on the simulated clock (stepping N cycles adds N of them).
        self.period_s: float | None = None
        self.phase_no = 0
        self.phase_text = ""
        self.stream: situate.Stream[Any] | None = None
        self.params: dict[tuple[str, str], Any] = {}
        #: Replies to requests sent but not yet awaited (see `send`).
        self.pending: list[asyncio.Future[Any]] = []
        #: Queries sent since the cycle last ran, by signal: their answers stand until it runs.
        self.readings: dict[str, asyncio.Future[Any]] = {}
        #: Round trips to the robot so far (each `flush`; DELIVER_DEBUG prints them at the end),
        #: and the requests they carried.
        self.round_trips = 0
        self.requests = 0
        #: Values the last wait's event reported (`CARRIED`), until the cycle runs again.
        self.carried: dict[str, Any] = {}
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
        self.requests += 1

    def prefetch(self, *signals: str) -> None:
        """Sends a query for each of ``signals`` not asked for since the cycle last ran.

        Queries only read, so asking for what the next steps will read, all at once, saves
        round trips without changing anything on the robot.
        """
        for signal in signals:
            if signal not in self.readings and signal not in self.carried:
                self.readings[signal] = self.r.send("query", signal=signal)
                self.pending.append(self.readings[signal])
                self.requests += 1

    def snapshot(self, *signals: str) -> Snapshot:
        """Sends one ``query_many`` for ``signals``: all read at the end of the same cycle.

        One request however many signals (`prefetch` sends a ``query`` each); its reply comes
        with the next `flush`. A signal unknown to the robot refuses them all.
        """
        reply = self.r.send("query_many", signals=list(signals))
        self.pending.append(reply)
        self.requests += 1
        return Snapshot(signals, reply)

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
            self.requests += 1
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
        for name in CARRIED:
            if name in fired.values:  # a leaf
                if fired.values[name] is not None:  # else never written
                    self.carried[name] = fired.values[name]
                continue
            prefix = f"{name}."
            values = {
                k.removeprefix(prefix): v for k, v in fired.values.items() if k.startswith(prefix)
            }
            if values and all(v is not None for v in values.values()):  # else never written
                self.carried[name] = values
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
        if event.skill not in self.active and event.skill not in self.kept_on:
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

    async def keep_on_the_rest(self, switched: Iterable[str]) -> None:
        """Notes the skills on now that the design never switches, as `kept_on`.

        They are those not among ``switched`` (the devices, the sonar filter: on from the
        start), switched on again after a fault like the ones the design switched on.
        """
        self.kept_on = {s.name for s in await self.r.skills() if s.active} - set(switched)

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
        # Off and on again before the next cycle, a skill is told both (its `deactivate`, then
        # its `activate`, where it starts afresh): no cycle is needed between them.
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
            return copy.copy(self.carried[signal])  # a reader may change its own copy
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
        """The progress line of phase ``number`` of the narrative, also told to the robot.

        The robot's GUI shows it on its mission lane, recordings keep it; it is sent with the
        next requests, no round trip of its own.
        """
        self.phase_no = number
        self.phase_text = text
        self.send("phase", text=f"phase {number}: {text}"[:200], client="deliver")
        await self.say(f"phase {number}: {text}")
