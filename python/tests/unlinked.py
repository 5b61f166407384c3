"""A sequencer driven with no link, for tests of its logic alone.

`Unlinked` answers the link's requests in place: the parameters set are kept (`params`, from
the mission's `NORMAL`), and so is what the robot says (`said`); switching skills, stepping and
prefetching do nothing. A test's made-up robot puts it before the sequencer's class, calls
`unlink` instead of the link's set-up, and answers the reads it needs (`odom`, `value`, `clue`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import reactive_support  # noqa: F401  (first: puts demo/ on the path)
from courier.mission import NORMAL


class Unlinked:
    """The link's requests answered in place (see the module)."""

    params: dict[tuple[str, str], Any]
    normal: dict[tuple[str, str], Any]
    said: list[str]

    def unlink(self) -> None:
        """What the sequencer's logic reads of the link's set-up, with nothing connected."""
        self.params = dict(NORMAL)
        self.normal = dict(NORMAL)
        self.debug = False
        self.t = 0.0
        self.said = []

    async def set(self, skill: str, param: str, value: Any) -> None:
        self.params[(skill, param)] = value

    async def use(self, *skills: str, restart: Sequence[str] = ()) -> None:
        return None

    def send(self, verb: str, **args: Any) -> None:
        return None

    def prefetch(self, *signals: str) -> None:
        return None

    async def say(self, text: str) -> None:
        self.said.append(text)
