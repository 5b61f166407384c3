"""A robot file run in this process: for tests, scripts and notebooks.

:class:`LocalRobot` builds the skill manager of a robot file as ``situate run``
does (the toy skills and the file's ``python:`` skills) but runs no link and
no thread of its own: you step it, and ask it anything with the same methods
(and the same replies, errors and events) as :class:`situate.Robot`, only
synchronous::

    robot = situate.LocalRobot("examples/python/runaway/robot.yaml", clock="simulated")
    robot.step(100)
    print(robot.query("drive").value, robot.skill("runaway").prints)

:func:`run` loads, runs a number of cycles and returns what happened, with
per-cycle readings of the signals you name. The GIL is released while the
manager works, so Python skills run in its cycle (prints, faults and all).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from . import _native
from .errors import BadReply, from_reply
from .events import Event, parse_event
from .info import MonitorInfo, Reading, SkillInfo, Stats, Winner, monitor_target
from .values import decode_untyped, encode

__all__ = ["LocalRobot", "RunResult", "run"]


class LocalRobot:
    """A robot file's skill manager in this process (see the module docs)."""

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        clock: str | None = None,
        executor: str | None = None,
        resources: Mapping[str, Any] | None = None,
    ) -> None:
        """Loads and builds the robot file.

        Args:
            path: The robot file.
            clock: ``"simulated"`` (as fast as possible, every body in the cycle)
                or ``"wall"``; default: the file's.
            executor: ``"serial"`` or ``"parallel"``; default: the file's.
            resources: Objects the skills are made with, by name: a class
                skill's ``__init__`` is given those its arguments name (a camera,
                a model loaded once; docs/python.md, "Resources").

        Raises:
            ValueError: The file, one of its ``python:`` files or its wiring has
                errors (the message lists them with their positions), or a skill
                needs a resource that ``resources`` does not hold.
        """
        self._native = _native.LocalRobot(
            os.fspath(path), clock, executor, dict(resources) if resources else None
        )
        #: The robot's name.
        self.name: str = self._native.name

    def __repr__(self) -> str:
        return f"<situate.LocalRobot {self.name!r}>"

    # ----- the cycle -------------------------------------------------------------

    def step(self, cycles: int = 1) -> None:
        """Runs ``cycles`` cycles now (paced by the clock)."""
        self._native.step(cycles, [])

    def record(self, signals: Sequence[str], cycles: int) -> dict[str, list[Reading]]:
        """Runs ``cycles`` cycles and returns each signal's reading after each cycle.

        A reading's ``cycle`` says when the signal was last written (a skill
        that wrote nothing leaves the previous value in place).
        """
        rows = json.loads(self._native.step(cycles, list(signals)))
        if isinstance(rows, dict):
            raise from_reply(rows.get("error") or {})
        out: dict[str, list[Reading]] = {s: [] for s in signals}
        for row in rows:
            for s, reading in zip(signals, row):
                out[s].append(Reading.from_json(reading))
        return out

    # ----- requests --------------------------------------------------------------

    def request(self, verb: str, **args: Any) -> Any:
        """Any protocol verb with its arguments; returns the raw ``ok`` result.

        Raises the same :class:`~situate.SituateError` subclasses as
        :class:`situate.Robot` does.
        """
        payload = json.dumps({k: encode(v) for k, v in args.items()})
        reply = json.loads(self._native.request(verb, payload))
        if "error" in reply:
            raise from_reply(reply["error"])
        if "ok" not in reply:
            raise BadReply(f"a reply with neither `ok` nor `error`: {reply}", kind="bad_reply")
        return reply["ok"]

    def activate(self, *skills: str, with_providers: bool = False) -> list[str]:
        """Switches skills on from the next cycle; returns those whose state changed."""
        result = self.request("activate", skills=list(skills), with_providers=with_providers)
        return [str(s) for s in result["changed"]]

    def deactivate(self, *skills: str) -> list[str]:
        """Switches skills off from the next cycle; returns those whose state changed."""
        result = self.request("deactivate", skills=list(skills))
        return [str(s) for s in result["changed"]]

    def set_param(self, skill: str, param: str, value: Any) -> None:
        """Sets a parameter from the next cycle (:class:`~situate.BadParam` if refused)."""
        self.request("set_param", skill=skill, param=param, value=value)

    def get_param(self, skill: str, param: str) -> Any:
        """A parameter's current value."""
        return decode_untyped(self.request("get_param", skill=skill, param=param))

    def set_priority(self, skill: str, priority: int) -> None:
        """Sets a skill's priority."""
        self.request("set_priority", skill=skill, priority=priority)

    def set_verbose(self, skill: str, verbose: bool = True) -> None:
        """Makes a skill's prints arrive as :class:`~situate.Print` events (or stop)."""
        self.request("set_verbose", skill=skill, verbose=verbose)

    def phase(self, text: str, client: str | None = None) -> None:
        """Says which phase of its mission the program is in (see ``Robot.phase``)."""
        if client is None:
            self.request("phase", text=text)
        else:
            self.request("phase", text=text, client=client)

    def query(self, signal: str) -> Reading:
        """A signal's value at the end of the last cycle."""
        return Reading.from_json(self.request("query", signal=signal))

    def query_many(self, *signals: str) -> list[Reading]:
        """Several signals' values at the end of the last cycle, one per name, in order.

        As :meth:`situate.Robot.query_many`: 1 to 256 names; an unknown one refuses them all.
        """
        result = self.request("query_many", signals=list(signals))
        if not (isinstance(result, list) and len(result) == len(signals)):
            raise BadReply(
                f"`query_many`: not a list of {len(signals)} readings: {result!r}", kind="bad_reply"
            )
        return [Reading.from_json(r) for r in result]

    def skill(self, name: str) -> SkillInfo:
        """Everything about one skill: state, parameters, ports, timing, recent prints."""
        return SkillInfo.from_json(self.request("skill", skill=name))

    def skills(self) -> list[SkillInfo]:
        """Every skill of the robot."""
        return [SkillInfo.from_json(s) for s in self.request("skills")]

    def winners(self) -> list[Winner]:
        """Who won each contested signal in the last cycle."""
        return [Winner.from_json(w) for w in self.request("winners")]

    def stats(self) -> Stats:
        """Cycle statistics."""
        return Stats.from_json(self.request("stats"))

    def monitor(
        self, condition: str | None = None, mode: str = "once", *, any: Sequence[str] | None = None
    ) -> int:
        """Registers a monitor on ``condition`` or ``any`` of several (events: :meth:`events`).

        As :meth:`situate.Robot.monitor`: an ``any`` monitor's events say in
        ``held`` which of its conditions held.
        """
        args = monitor_target(condition, any)
        return int(self.request("monitor_add", mode=mode, **args)["monitor"])

    def cancel_monitor(self, monitor: int) -> None:
        """Cancels a monitor."""
        self.request("monitor_cancel", monitor=monitor)

    def monitors(self) -> list[MonitorInfo]:
        """The registered monitors."""
        return [MonitorInfo.from_json(m) for m in self.request("monitor_list")]

    def events(self, *kinds: str) -> list[Event]:
        """The events since the last call (all, or only these kinds: ``"skill_faulted"``, ...)."""
        out: list[Event] = []
        for text in self._native.events():
            data = json.loads(text)
            if not kinds or data.get("kind") in kinds:
                out.append(parse_event(data))
        return out


@dataclass
class RunResult:
    """What :func:`run` saw: the robot after the run, and what happened during it."""

    #: The robot, stopped after the last cycle (query it further, or step it again).
    robot: LocalRobot
    #: Cycle statistics at the end.
    stats: Stats
    #: Every skill at the end (state, fault cause, prints, timing).
    skills: dict[str, SkillInfo]
    #: Every event of the run, oldest first.
    events: list[Event] = field(default_factory=list)
    #: Per-cycle readings of the recorded signals.
    records: dict[str, list[Reading]] = field(default_factory=dict)


def run(
    path: str | os.PathLike[str],
    cycles: int,
    *,
    clock: str | None = None,
    executor: str | None = None,
    record: Sequence[str] = (),
    resources: Mapping[str, Any] | None = None,
) -> RunResult:
    """Runs a robot file for ``cycles`` cycles in this process and returns what happened.

    Args:
        path: The robot file.
        cycles: How many cycles to run.
        clock: ``"simulated"`` or ``"wall"`` (default: the file's).
        executor: ``"serial"`` or ``"parallel"`` (default: the file's).
        record: Signals to read after every cycle (``RunResult.records``).
        resources: Objects the skills are made with, by name (as :class:`LocalRobot`'s).
    """
    robot = LocalRobot(path, clock=clock, executor=executor, resources=resources)
    records = robot.record(record, cycles) if record else {}
    if not record:
        robot.step(cycles)
    return RunResult(
        robot=robot,
        stats=robot.stats(),
        skills={s.name: s for s in robot.skills()},
        events=robot.events(),
        records=records,
    )
