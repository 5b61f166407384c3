"""Event and telemetry payloads become dataclasses (docs/protocol.md, "Events"), no network."""

from __future__ import annotations

import math

import situate
from situate.events import parse_event, parse_telemetry


def test_every_event_kind_parses_to_its_dataclass() -> None:
    assert parse_event(
        {
            "kind": "monitor_fired",
            "monitor": 3,
            "condition": "sonar.range[0] < 0.25",
            "cycle": 12,
            "time_s": 0.6,
            "values": {"sonar.range[0]": 0.2, "far": "inf", "never": None},
        }
    ) == situate.MonitorFired(
        3, "sonar.range[0] < 0.25", 12, 0.6, {"sonar.range[0]": 0.2, "far": math.inf, "never": None}
    )
    assert parse_event(
        {"kind": "activation_applied", "activated": ["a"], "deactivated": [], "cycle": 2}
    ) == situate.ActivationApplied(["a"], [], 2)
    assert parse_event(
        {"kind": "param_changed", "skill": "s", "param": "p", "value": "-inf", "cycle": 4}
    ) == situate.ParamChanged("s", "p", -math.inf, 4)
    assert parse_event(
        {"kind": "priority_changed", "skill": "s", "priority": -3, "cycle": 5}
    ) == situate.PriorityChanged("s", -3, 5)
    assert parse_event(
        {"kind": "skill_faulted", "skill": "s", "cause": "panicked: boom", "cycle": 9}
    ) == situate.SkillFaulted("s", "panicked: boom", 9)
    assert parse_event({"kind": "print", "skill": "s", "line": "hi", "cycle": 1}) == situate.Print(
        "s", "hi", 1
    )
    assert parse_event({"kind": "manager_started", "cycle": 0}) == situate.ManagerStarted(0)
    assert parse_event({"kind": "manager_stopped", "cycle": 7}) == situate.ManagerStopped(7)


def test_a_monitor_event_says_which_conditions_held() -> None:
    base = {"kind": "monitor_fired", "monitor": 1, "condition": "(a) || (b) || (c)"}
    event = parse_event({**base, "cycle": 4, "time_s": 0.2, "values": {}, "held": [0, 2]})
    assert isinstance(event, situate.MonitorFired)
    assert event.held == (0, 2)
    # A manager older than `any` sends no `held`: its monitors watch one condition.
    old = parse_event({**base, "cycle": 4, "time_s": 0.2, "values": {}})
    assert isinstance(old, situate.MonitorFired)
    assert old.held == (0,)


def test_new_kinds_and_members_do_not_break_a_client() -> None:
    future = {"kind": "battery_low", "percent": 9}
    assert parse_event(future) == situate.OtherEvent("battery_low", future)
    assert parse_event({"kind": "manager_started", "cycle": 1, "new": True}) == (
        situate.ManagerStarted(1)
    )
    broken = {"kind": "print", "skill": "s"}
    assert parse_event(broken) == situate.OtherEvent("print", broken)


def test_telemetry_parses_with_its_signals() -> None:
    t = parse_telemetry(
        {
            "cycle": 5,
            "time_s": 0.25,
            "mean_cycle_ns": 1000.5,
            "last_cycle_ns": 900,
            "max_cycle_ns": 2000,
            "overruns": 0,
            "active": ["sonar"],
            "signals": {"sonar.range": [1.0, "inf"], "odom.x": None},
        }
    )
    assert t.cycle == 5
    assert t.active == ["sonar"]
    assert t.signals == {"sonar.range": [1.0, math.inf], "odom.x": None}
