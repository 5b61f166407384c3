"""What a skill manager answers to queries, as typed dataclasses.

Each class mirrors one result of ``docs/protocol.md`` ("Requests") and has a
``from_json`` that reads the wire form. Values inside are decoded by their
types (see :mod:`situate.values`). Members a newer manager adds are ignored.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from .values import decode, decode_untyped

__all__ = [
    "Graph",
    "GraphSignal",
    "GraphSkill",
    "Hello",
    "MonitorInfo",
    "ParamInfo",
    "PortInfo",
    "Reading",
    "SkillInfo",
    "Stats",
    "Timing",
    "Winner",
]


def _strings(j: Any) -> list[str]:
    return [str(x) for x in j] if isinstance(j, list) else []


def _opt_str(j: Any) -> str | None:
    return None if j is None else str(j)


def _decode(j: Any, ty: str) -> Any:
    try:
        return decode(j, ty)
    except ValueError:  # a type this version cannot parse: keep what came, decoded loosely
        return decode_untyped(j)


@dataclass(frozen=True)
class Hello:
    """Who answered: the protocol version, the robot's name and the manager's version."""

    protocol: int
    robot: str
    version: str

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> Hello:
        """Reads a ``hello`` result."""
        return cls(protocol=int(j["protocol"]), robot=str(j["robot"]), version=str(j["version"]))


@dataclass(frozen=True)
class Reading:
    """A signal's latest value, as of the end of the last cycle.

    ``value`` is ``None`` until the signal is first written; ``cycle`` is the
    cycle it was last written in and ``writer`` the skill that wrote it (the
    winner, for a contested resource).
    """

    signal: str
    type: str
    value: Any
    cycle: int
    writer: str | None

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> Reading:
        """Reads a signal reading, decoding ``value`` by ``type``."""
        ty = str(j["type"])
        return cls(
            signal=str(j["signal"]),
            type=ty,
            value=_decode(j.get("value"), ty),
            cycle=int(j.get("cycle", 0)),
            writer=_opt_str(j.get("writer")),
        )


@dataclass(frozen=True)
class ParamInfo:
    """One parameter of a skill: its value, default, range, unit and documentation."""

    name: str
    type: str
    value: Any
    default: Any
    min: float | None
    max: float | None
    unit: str | None
    doc: str

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> ParamInfo:
        """Reads one member of a skill info's ``params``."""
        return cls(
            name=str(j["name"]),
            type=str(j.get("type", "")),
            value=decode_untyped(j.get("value")),
            default=decode_untyped(j.get("default")),
            min=None if j.get("min") is None else float(j["min"]),
            max=None if j.get("max") is None else float(j["max"]),
            unit=_opt_str(j.get("unit")) or None,
            doc=str(j.get("doc") or ""),
        )


@dataclass(frozen=True)
class PortInfo:
    """An input or output of a skill: the signal it is wired to, its type and latest value."""

    name: str
    signal: str
    type: str
    optional: bool
    value: Any

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> PortInfo:
        """Reads one port, decoding its value by its type."""
        ty = str(j.get("type", ""))
        return cls(
            name=str(j["name"]),
            signal=str(j.get("signal", j["name"])),
            type=ty,
            optional=bool(j.get("optional", False)),
            value=_decode(j.get("value"), ty),
        )


@dataclass(frozen=True)
class Timing:
    """How often a skill's body ran and how long it took, in nanoseconds.

    `runs` and `total_ns` count every run; `last_ns` and `max_ns` are of the
    runs timed exactly, a sample of them (see docs/protocol.md, "skill info").
    """

    runs: int
    last_ns: int
    max_ns: int
    total_ns: int

    @property
    def mean_ns(self) -> float:
        """The mean run time (0 before the first run)."""
        return self.total_ns / self.runs if self.runs else 0.0

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> Timing:
        """Reads a skill info's ``timing``."""
        return cls(
            runs=int(j.get("runs", 0)),
            last_ns=int(j.get("last_ns", 0)),
            max_ns=int(j.get("max_ns", 0)),
            total_ns=int(j.get("total_ns", 0)),
        )


@dataclass(frozen=True)
class SkillInfo:
    """Everything about one skill: the paper's *show data / input / output*.

    ``kind`` is ``"sync"``, ``"async"`` or ``"device"``; ``faulted`` holds the
    cause when the skill's body failed; ``prints`` the recent lines it printed
    as ``(cycle, line)`` pairs.
    """

    name: str
    type_name: str
    kind: str
    doc: str
    active: bool
    faulted: str | None
    verbose: bool
    priority: int
    params: list[ParamInfo]
    inputs: list[PortInfo]
    outputs: list[PortInfo]
    timing: Timing
    prints: list[tuple[int, str]]

    def param(self, name: str) -> ParamInfo:
        """The parameter called ``name`` (``KeyError`` if none)."""
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> SkillInfo:
        """Reads a skill info."""
        return cls(
            name=str(j["name"]),
            type_name=str(j.get("type_name", "")),
            kind=str(j.get("kind", "")),
            doc=str(j.get("doc") or ""),
            active=bool(j.get("active", False)),
            faulted=_opt_str(j.get("faulted")),
            verbose=bool(j.get("verbose", False)),
            priority=int(j.get("priority", 0)),
            params=[ParamInfo.from_json(p) for p in j.get("params") or []],
            inputs=[PortInfo.from_json(p) for p in j.get("inputs") or []],
            outputs=[PortInfo.from_json(p) for p in j.get("outputs") or []],
            timing=Timing.from_json(j.get("timing") or {}),
            prints=[(int(c), str(line)) for c, line in j.get("prints") or []],
        )


@dataclass(frozen=True)
class Winner:
    """Who won a contested signal (a *resource*) in the last cycle it was written."""

    signal: str
    writers: list[str]
    winner: str | None
    cycle: int
    #: How often the winner changed to another skill since the start.
    switches: int = 0
    #: Cycles in which some skill wrote it.
    held_cycles: int = 0

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> Winner:
        """Reads one member of a ``winners`` result."""
        return cls(
            signal=str(j["signal"]),
            writers=_strings(j.get("writers")),
            winner=_opt_str(j.get("winner")),
            cycle=int(j.get("cycle", 0)),
            switches=int(j.get("switches", 0)),
            held_cycles=int(j.get("held_cycles", 0)),
        )


@dataclass(frozen=True)
class GraphSkill:
    """A skill in the data-flow graph, with the signals it reads and writes."""

    name: str
    kind: str
    active: bool
    priority: int
    inputs: list[str]
    outputs: list[str]


@dataclass(frozen=True)
class GraphSignal:
    """A signal in the data-flow graph: its type, writers and readers."""

    signal: str
    type: str
    writers: list[str]
    readers: list[str]


@dataclass(frozen=True)
class Graph:
    """The robot's data-flow graph: skills and signals."""

    skills: list[GraphSkill]
    signals: list[GraphSignal]

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> Graph:
        """Reads a ``graph`` result."""
        return cls(
            skills=[
                GraphSkill(
                    name=str(s["name"]),
                    kind=str(s.get("kind", "")),
                    active=bool(s.get("active", False)),
                    priority=int(s.get("priority", 0)),
                    inputs=_strings(s.get("inputs")),
                    outputs=_strings(s.get("outputs")),
                )
                for s in j.get("skills") or []
            ],
            signals=[
                GraphSignal(
                    signal=str(s["signal"]),
                    type=str(s.get("type", "")),
                    writers=_strings(s.get("writers")),
                    readers=_strings(s.get("readers")),
                )
                for s in j.get("signals") or []
            ],
        )


@dataclass(frozen=True)
class Stats:
    """Cycle statistics: where the cycle is, whether it runs, how long cycles take."""

    robot: str
    cycle: int
    time_s: float
    running: bool
    period_s: float
    last_cycle_ns: int
    mean_cycle_ns: float
    max_cycle_ns: int
    overruns: int
    active: list[str]
    late_starts: int = 0
    """Cycles that started more than half a period late, and skipped periods."""
    rate_hz: float = 0.0
    """The achieved cycle rate over about the last 20 cycles (0 when stopped)."""
    worker_failures: int = 0
    """Worker threads of the manager or the link that panicked (``worker_failed`` events)."""
    request_hold_ns: int = 0
    """How long requests served between cycles ran past the time the next cycle was due, in all."""
    lost_ns: int = 0
    """Time lost to cycles that started so late that periods were skipped."""

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> Stats:
        """Reads a ``stats`` result."""
        return cls(
            robot=str(j.get("robot", "")),
            cycle=int(j.get("cycle", 0)),
            time_s=float(j.get("time_s", 0.0)),
            running=bool(j.get("running", False)),
            period_s=float(j.get("period_s", 0.0)),
            last_cycle_ns=int(j.get("last_cycle_ns", 0)),
            mean_cycle_ns=float(j.get("mean_cycle_ns", 0.0)),
            max_cycle_ns=int(j.get("max_cycle_ns", 0)),
            overruns=int(j.get("overruns", 0)),
            active=_strings(j.get("active")),
            late_starts=int(j.get("late_starts", 0)),
            rate_hz=float(j.get("rate_hz", 0.0)),
            worker_failures=int(j.get("worker_failures", 0)),
            request_hold_ns=int(j.get("request_hold_ns", 0)),
            lost_ns=int(j.get("lost_ns", 0)),
        )


@dataclass(frozen=True)
class MonitorInfo:
    """A registered monitor: its condition, mode, how often it fired, whether it holds now."""

    monitor: int
    condition: str
    mode: str
    fired: int
    holds: bool
    pause: bool = False
    #: Names whose values its events carry besides the condition's, as asked.
    report: tuple[str, ...] = ()
    #: The conditions of a monitor added with ``any=[...]``, as given (``condition``
    #: is then their disjunction); ``None`` for a monitor on one condition.
    any: tuple[str, ...] | None = None
    #: The name its client gave itself (a :class:`~situate.Robot` sends its ``client_id``), if any:
    #: a label, not an identity.
    client: str | None = None
    #: The public id of the session that holds it (only that session cancels it; compare
    #: with :attr:`situate.Robot.session_id`); ``None``: the program running the robot.
    session: str | None = None

    @classmethod
    def from_json(cls, j: dict[str, Any]) -> MonitorInfo:
        """Reads one member of a ``monitor_list`` result."""
        return cls(
            monitor=int(j["monitor"]),
            condition=str(j.get("condition", "")),
            mode=str(j.get("mode", "")),
            fired=int(j.get("fired", 0)),
            holds=bool(j.get("holds", False)),
            pause=bool(j.get("pause", False)),
            report=tuple(str(r) for r in j.get("report", [])),
            any=None if j.get("any") is None else tuple(str(c) for c in j["any"]),
            client=None if j.get("client") is None else str(j["client"]),
            session=None if j.get("session") is None else str(j["session"]),
        )


#: The most conditions a monitor on ``any`` of several takes.
MAX_ANY_CONDITIONS = 64


def monitor_target(condition: str | None, any: Sequence[str] | None) -> dict[str, Any]:
    """The ``monitor_add`` argument for one condition or ``any`` of several.

    Raises:
        ValueError: Both or neither are given, or ``any`` is empty.
        TypeError: ``any`` is one string rather than a list of them.
    """
    if (condition is None) == (any is None):
        raise ValueError("give a condition or any=[...] (several conditions), exactly one of them")
    if condition is not None:
        return {"condition": condition}
    if isinstance(any, str):
        raise TypeError(f"any= takes a list of conditions, not one string: write any=[{any!r}]")
    conditions = list(any or ())
    if not conditions:
        raise ValueError("any= needs at least one condition")
    return {"any": conditions}
