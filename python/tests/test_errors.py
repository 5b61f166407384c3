"""One place maps the protocol's error kinds to exceptions."""

from __future__ import annotations

import pytest

import situate
from situate.errors import from_reply


@pytest.mark.parametrize(
    ("kind", "cls"),
    [
        ("bad_request", situate.BadRequest),
        ("unknown_verb", situate.UnknownVerb),
        ("protocol", situate.ProtocolMismatch),
        ("unknown_skill", situate.UnknownSkill),
        ("unknown_param", situate.UnknownParam),
        ("bad_param", situate.BadParam),
        ("missing_providers", situate.MissingProviders),
        ("unknown_signal", situate.UnknownSignal),
        ("bad_condition", situate.BadCondition),
        ("unknown_monitor", situate.UnknownMonitor),
        ("invalid", situate.Invalid),
        ("interrupted", situate.Interrupted),
        ("unavailable", situate.Unavailable),
    ],
)
def test_every_error_kind_has_its_exception(kind: str, cls: type[situate.SituateError]) -> None:
    e = from_reply({"kind": kind, "message": "the manager's words"})
    assert type(e) is cls
    assert isinstance(e, situate.SituateError)
    assert (e.kind, e.message, str(e)) == (kind, "the manager's words", "the manager's words")


def test_unknown_kinds_stay_situate_errors() -> None:
    e = from_reply({"kind": "from_the_future", "message": "m", "extra": 1})
    assert type(e) is situate.SituateError
    assert e.kind == "from_the_future"
    assert e.detail["extra"] == 1


def test_extra_members_are_exposed() -> None:
    e = from_reply(
        {"kind": "missing_providers", "message": "m", "signals": ["a"], "providers": ["p"]}
    )
    assert isinstance(e, situate.MissingProviders)
    assert (e.signals, e.providers) == (["a"], ["p"])
    b = from_reply({"kind": "bad_condition", "message": "m", "column": 3, "pointer": "a <\n  ^"})
    assert isinstance(b, situate.BadCondition)
    assert (b.column, b.pointer) == (3, "a <\n  ^")
