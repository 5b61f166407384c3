"""The sequenced design hears of faults: its phases run on a stream of the link's events that
carries `skill_faulted` as well as `monitor_fired`, so that `Link.on_fault` switches a skill the
manager faulted on again (test_demo_faults.py tests `on_fault` itself, on a stream it opens).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from typing import Any

import reactive_support  # (first: puts demo/ on the path)
from courier.link import EVENT_KINDS
from courier.sequenced.delivery import Delivery


class Robot:
    """Records the kinds of events the sequencer subscribes to; nothing else is asked of it."""

    def __init__(self) -> None:
        self.kinds: list[str] = []

    @contextlib.asynccontextmanager
    async def events(self, *kinds: str) -> AsyncIterator[list[Any]]:
        self.kinds.extend(kinds)
        yield []


def test_the_sequenced_phases_run_on_a_stream_that_carries_faults() -> None:
    robot = Robot()
    seq = Delivery(robot, reactive_support.mission(), quiet=True)  # type: ignore[arg-type]
    ran: list[tuple[str, str]] = []

    async def run_phases(first: str, last: str) -> None:
        assert seq.stream is not None, "the phases run with the stream open"
        ran.append((first, last))

    seq.run_phases = run_phases  # type: ignore[method-assign]
    asyncio.run(seq.run("lab", "office"))
    assert ran == [("lab", "office")]
    assert "skill_faulted" in robot.kinds, robot.kinds
    assert "monitor_fired" in robot.kinds, robot.kinds
    assert set(EVENT_KINDS) <= set(robot.kinds)
