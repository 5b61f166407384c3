"""What a skill manager tells its sequencers without being asked: events and telemetry.

A manager publishes an event on ``situate/<robot>/events/<kind>`` each time
something a sequencer may care about happens (``docs/protocol.md``,
"Events"). Each kind is a frozen dataclass here, and :func:`parse_event`
turns a payload into one::

    async for event in robot.events():
        match event:
            case situate.MonitorFired(monitor=m, values=v): ...
            case situate.SkillFaulted(skill=s, cause=c): ...

An event kind this version does not know (a newer manager) arrives as
:class:`OtherEvent` rather than being dropped, and members a newer manager
adds to a known kind are ignored: the protocol grows by addition.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Union

from .values import decode_untyped

__all__ = [
    "ActivationApplied",
    "Event",
    "ManagerStarted",
    "ManagerStopped",
    "MonitorCancelled",
    "MonitorEvent",
    "MonitorFired",
    "OtherEvent",
    "ParamChanged",
    "Print",
    "PriorityChanged",
    "SkillFaulted",
    "Telemetry",
    "WorkerFailed",
    "parse_event",
    "parse_telemetry",
]


@dataclass(frozen=True)
class MonitorFired:
    """A monitor's condition held.

    A ``once`` monitor fires the first time, ``edge`` each time the
    condition becomes true, ``level`` every cycle it holds.

    ``values`` holds the value of each name the condition reads, at that
    cycle (every condition's, for a monitor on ``any`` of several), and of
    the names it was asked to ``report``.

    ``held`` holds the indexes, in order, of the conditions that held in
    that cycle: for a monitor added with ``any=[...]``, which of them
    happened (several may at once); for one on a single condition, ``(0,)``.
    An ``any`` monitor's ``condition`` is its conditions joined as
    ``(a) || (b)``.
    """

    monitor: int
    condition: str
    cycle: int
    time_s: float
    values: dict[str, Any] = field(default_factory=dict)
    held: tuple[int, ...] = (0,)


MonitorEvent = MonitorFired
"""What :meth:`situate.Robot.when` returns: the :class:`MonitorFired` event it waited for."""


@dataclass(frozen=True)
class MonitorCancelled:
    """A monitor was removed before it fired for good.

    ``reason`` says by whom: ``"owner"`` (its own session cancelled it),
    ``"forced"`` (someone else did, e.g. the GUI after asking its user: a
    sequencer waiting on it should know it will never fire) or
    ``"session_ended"`` (its session's client went away). ``session`` is the
    public id of the session that held it (``None``: the program running the
    robot); compare it with :attr:`situate.Robot.session_id`.
    """

    monitor: int
    condition: str
    session: str | None
    reason: str
    cycle: int


@dataclass(frozen=True)
class ActivationApplied:
    """An activation change took effect at the start of ``cycle``."""

    activated: list[str]
    deactivated: list[str]
    cycle: int


@dataclass(frozen=True)
class ParamChanged:
    """A parameter got a new value, in force from ``cycle``."""

    skill: str
    param: str
    value: Any
    cycle: int


@dataclass(frozen=True)
class PriorityChanged:
    """A skill's priority changed (``set_priority``), in force from ``cycle``."""

    skill: str
    priority: int
    cycle: int


@dataclass(frozen=True)
class SkillFaulted:
    """A skill's body failed (error, panic, wrongly typed output): it was deactivated."""

    skill: str
    cause: str
    cycle: int


@dataclass(frozen=True)
class Print:
    """A line a verbose skill printed (see :meth:`situate.Robot.set_verbose`)."""

    skill: str
    line: str
    cycle: int


@dataclass(frozen=True)
class ManagerStarted:
    """The cycle started running (``run``)."""

    cycle: int


@dataclass(frozen=True)
class ManagerStopped:
    """The cycle stopped (``stop``, a bounded run's end, or shutdown)."""

    cycle: int


@dataclass(frozen=True)
class WorkerFailed:
    """A worker thread of the manager or the link panicked.

    ``thread`` names it (``situate-link-req``, ...), ``cause`` is ``panicked: ...``, and
    ``action`` what was done: ``restarted``, or that the robot is stopped (a thread that
    kept panicking, or the cycle's own).
    """

    thread: str
    cause: str
    action: str


@dataclass(frozen=True)
class Phase:
    """A sequencer said which phase of its mission it is in (``Robot.phase``), from ``cycle`` on.

    ``client`` is the name the sequencer gave itself, or ``None``.
    """

    text: str
    client: str | None
    cycle: int


@dataclass(frozen=True)
class OtherEvent:
    """An event of a kind this version of the package does not know, kept whole."""

    kind: str
    data: dict[str, Any]


Event = Union[
    MonitorFired,
    MonitorCancelled,
    ActivationApplied,
    ParamChanged,
    PriorityChanged,
    SkillFaulted,
    Print,
    ManagerStarted,
    ManagerStopped,
    WorkerFailed,
    Phase,
    OtherEvent,
]
"""Any event a manager publishes."""


def _strings(j: Any) -> list[str]:
    return [str(x) for x in j] if isinstance(j, list) else []


def parse_event(data: dict[str, Any]) -> Event:
    """The event for one payload (already parsed from JSON).

    Malformed known kinds (a member missing) come back as :class:`OtherEvent`.
    """
    kind = str(data.get("kind", ""))
    try:
        if kind == "monitor_fired":
            values = data.get("values") or {}
            return MonitorFired(
                monitor=int(data["monitor"]),
                condition=str(data["condition"]),
                cycle=int(data["cycle"]),
                time_s=float(data["time_s"]),
                values={str(k): decode_untyped(v) for k, v in values.items()},
                # A manager older than `any` watches one condition per monitor.
                held=tuple(int(i) for i in data.get("held", [0])),
            )
        if kind == "monitor_cancelled":
            session = data.get("session")
            return MonitorCancelled(
                monitor=int(data["monitor"]),
                condition=str(data["condition"]),
                session=None if session is None else str(session),
                reason=str(data["reason"]),
                cycle=int(data["cycle"]),
            )
        if kind == "activation_applied":
            return ActivationApplied(
                activated=_strings(data.get("activated")),
                deactivated=_strings(data.get("deactivated")),
                cycle=int(data["cycle"]),
            )
        if kind == "param_changed":
            return ParamChanged(
                skill=str(data["skill"]),
                param=str(data["param"]),
                value=decode_untyped(data.get("value")),
                cycle=int(data["cycle"]),
            )
        if kind == "priority_changed":
            return PriorityChanged(
                skill=str(data["skill"]), priority=int(data["priority"]), cycle=int(data["cycle"])
            )
        if kind == "skill_faulted":
            return SkillFaulted(
                skill=str(data["skill"]), cause=str(data["cause"]), cycle=int(data["cycle"])
            )
        if kind == "print":
            return Print(skill=str(data["skill"]), line=str(data["line"]), cycle=int(data["cycle"]))
        if kind == "manager_started":
            return ManagerStarted(cycle=int(data["cycle"]))
        if kind == "manager_stopped":
            return ManagerStopped(cycle=int(data["cycle"]))
        if kind == "worker_failed":
            return WorkerFailed(
                thread=str(data["thread"]), cause=str(data["cause"]), action=str(data["action"])
            )
        if kind == "phase":
            client = data.get("client")
            return Phase(
                text=str(data["text"]),
                client=None if client is None else str(client),
                cycle=int(data["cycle"]),
            )
    except (KeyError, TypeError, ValueError, AttributeError):
        pass
    return OtherEvent(kind=kind, data=data)


@dataclass(frozen=True)
class Telemetry:
    """One telemetry sample: cycle statistics and the signals chosen with ``Robot.telemetry``.

    Signal values come without their types on the wire; they are decoded as
    in :func:`situate.values.decode_untyped`.
    """

    cycle: int
    time_s: float
    mean_cycle_ns: float
    last_cycle_ns: int
    max_cycle_ns: int
    overruns: int
    active: list[str]
    signals: dict[str, Any]
    late_starts: int = 0
    rate_hz: float = 0.0


def parse_telemetry(data: dict[str, Any]) -> Telemetry:
    """The :class:`Telemetry` of one payload (already parsed from JSON)."""
    signals = data.get("signals") or {}
    return Telemetry(
        cycle=int(data.get("cycle", 0)),
        time_s=float(data.get("time_s", 0.0)),
        mean_cycle_ns=float(data.get("mean_cycle_ns", 0.0)),
        last_cycle_ns=int(data.get("last_cycle_ns", 0)),
        max_cycle_ns=int(data.get("max_cycle_ns", 0)),
        overruns=int(data.get("overruns", 0)),
        active=_strings(data.get("active")),
        signals={str(k): decode_untyped(v) for k, v in signals.items()},
        late_starts=int(data.get("late_starts", 0)),
        rate_hz=float(data.get("rate_hz", 0.0)),
    )
