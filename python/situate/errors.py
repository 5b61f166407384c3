"""The errors a skill manager can answer with, as Python exceptions.

Every refused request comes back over the link as
``{"error": {"kind": ..., "message": ..., ...}}`` (``docs/protocol.md``,
"Error kinds"). This module is the one place that turns such a reply into an
exception: :func:`from_reply` picks the class by ``kind``, and the exception
carries the manager's message *exactly* (it already names the thing and
suggests what you probably meant), plus the whole error object as
``detail``.

Catch :class:`SituateError` for any of them, or a subclass for one kind::

    try:
        await robot.activate("wandr")
    except situate.UnknownSkill as e:
        print(e)  # unknown skill `wandr` — did you mean `wander`?

A refused request changes nothing on the robot, so it is always safe to fix
the request and send it again.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

__all__ = [
    "AmbiguousRobot",
    "BadCondition",
    "BadParam",
    "BadReply",
    "BadRequest",
    "Interrupted",
    "Invalid",
    "MissingProviders",
    "NoSession",
    "NotOwner",
    "NotRunning",
    "OtherRobots",
    "ProtocolMismatch",
    "SituateError",
    "Unavailable",
    "UnknownMonitor",
    "UnknownParam",
    "UnknownSignal",
    "UnknownSkill",
    "UnknownVerb",
    "from_reply",
]


class SituateError(Exception):
    """A request the skill manager refused, or a manager that could not be reached.

    Attributes:
        kind: The protocol's error kind (``"unknown_skill"``, ``"bad_param"``, ...),
            or a client-side kind (``"not_running"``, ``"ambiguous_robot"``, ``"bad_reply"``).
        message: The manager's message, word for word.
        detail: The whole error object of the reply (extra members such as
            ``column`` live here too); empty for client-side errors.
    """

    #: The protocol kind this class stands for (the base class: any).
    KIND: ClassVar[str] = ""

    def __init__(
        self, message: str, *, kind: str | None = None, detail: Mapping[str, Any] | None = None
    ) -> None:
        super().__init__(message)
        self.kind: str = kind if kind is not None else self.KIND
        self.message: str = message
        self.detail: dict[str, Any] = dict(detail or {})

    def __repr__(self) -> str:
        return f"{type(self).__name__}(kind={self.kind!r}, message={self.message!r})"


class BadRequest(SituateError):
    """The request was malformed: not JSON, a missing, wrongly typed or unknown argument."""

    KIND = "bad_request"


class UnknownVerb(SituateError):
    """The manager has no such request verb (a newer client talking to an older manager?)."""

    KIND = "unknown_verb"


class ProtocolMismatch(SituateError):
    """The manager does not speak the protocol version the request asked for."""

    KIND = "protocol"


class UnknownSkill(SituateError):
    """No skill of that name on this robot; the message suggests the closest name."""

    KIND = "unknown_skill"


class UnknownParam(SituateError):
    """The skill has no parameter of that name; the message suggests the closest name."""

    KIND = "unknown_param"


class BadParam(SituateError):
    """A parameter value of the wrong type or out of range; the message names both."""

    KIND = "bad_param"


class MissingProviders(SituateError):
    """Activating would leave inputs that no active skill provides.

    Attributes:
        signals: The signals nobody active would write.
        providers: Inactive skills that could provide them; activate them too, or
            pass ``with_providers=True``.
    """

    KIND = "missing_providers"

    @property
    def signals(self) -> list[str]:
        """The signals nobody active would write."""
        return [str(s) for s in self.detail.get("signals", [])]

    @property
    def providers(self) -> list[str]:
        """The inactive skills that could write them."""
        return [str(s) for s in self.detail.get("providers", [])]


class UnknownSignal(SituateError):
    """No signal of that name; the message suggests the closest name."""

    KIND = "unknown_signal"


class BadCondition(SituateError):
    """A monitor condition that does not parse or does not type-check.

    Attributes:
        column: The 1-based column of the problem in the condition.
        pointer: The condition with a caret under that column, ready to print.
        index: Which of a monitor's ``any`` conditions it is in (``None`` for a
            monitor on one condition); the message then starts ``any[2]: ``.
    """

    KIND = "bad_condition"

    @property
    def index(self) -> int | None:
        """Which of an ``any`` monitor's conditions is bad (``None``: the one condition)."""
        i = self.detail.get("index")
        return None if i is None else int(i)

    @property
    def column(self) -> int:
        """The column of the problem in the condition."""
        return int(self.detail.get("column", 0))

    @property
    def pointer(self) -> str:
        """The condition with a caret under the problem."""
        return str(self.detail.get("pointer", ""))


class UnknownMonitor(SituateError):
    """No monitor with that id (never registered, cancelled, or a ``once`` that fired)."""

    KIND = "unknown_monitor"


class NotOwner(SituateError):
    """A monitor another session holds: only the session that added a monitor cancels it."""

    KIND = "not_owner"


class NoSession(SituateError):
    """A ``session`` whose liveliness token the manager cannot find, or that has ended.

    A :class:`~situate.Robot` holds its session for as long as it is open; this comes
    only to clients that manage sessions themselves (docs/protocol.md, "Sessions").
    """

    KIND = "no_session"


class Invalid(SituateError):
    """A well-formed request the manager cannot carry out in its current state."""

    KIND = "invalid"


class Interrupted(SituateError):
    """A request cut short because a skill's body got stuck and was left behind.

    A ``step`` that ended early, or a request that arrived while the cycle restarted. The
    ``skill_faulted`` event names the skill; the cycle goes on, and the request may be sent again.
    """

    KIND = "interrupted"


class Unavailable(SituateError):
    """The manager is shutting down or too busy to answer; try again later."""

    KIND = "unavailable"


class NotRunning(SituateError):
    """No skill manager answered: nothing listens at the endpoint, or no robot of that name."""

    KIND = "not_running"


class OtherRobots(NotRunning):
    """The robot named did not answer, and others did: most likely a misspelt name.

    Attributes:
        robot: The name asked for.
        answering: The robots that did answer, by name.
    """

    KIND = "other_robots"

    def __init__(self, robot: str, answering: Sequence[str]) -> None:
        names = ", ".join(f"`{name}`" for name in answering)
        did = f"robot {names} did" if len(answering) == 1 else f"robots {names} did"
        super().__init__(f"robot `{robot}` did not answer; {did} (name it with robot=)")
        self.robot: str = robot
        self.answering: list[str] = list(answering)


class AmbiguousRobot(SituateError):
    """Several robots answered and none was named: pass ``robot=``."""

    KIND = "ambiguous_robot"


class BadReply(SituateError):
    """A reply that is not the protocol's JSON (not a situate manager?)."""

    KIND = "bad_reply"


_BY_KIND: dict[str, type[SituateError]] = {
    cls.KIND: cls
    for cls in (
        BadRequest,
        UnknownVerb,
        ProtocolMismatch,
        UnknownSkill,
        UnknownParam,
        BadParam,
        MissingProviders,
        UnknownSignal,
        BadCondition,
        UnknownMonitor,
        NotOwner,
        NoSession,
        Invalid,
        Interrupted,
        Unavailable,
    )
}


def from_reply(error: Mapping[str, Any]) -> SituateError:
    """The exception for a reply's ``error`` object (an unknown kind: :class:`SituateError`).

    >>> e = from_reply({"kind": "unknown_skill", "message": "unknown skill `x`"})
    >>> type(e).__name__, e.kind, str(e)
    ('UnknownSkill', 'unknown_skill', 'unknown skill `x`')
    """
    kind = str(error.get("kind", "unknown"))
    message = str(error.get("message", ""))
    cls = _BY_KIND.get(kind, SituateError)
    return cls(message, kind=kind, detail=error)
