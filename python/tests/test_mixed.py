"""The runaway skill in Rust, C, C++ and Python, side by side in one cycle, agree exactly."""

from __future__ import annotations

import asyncio

from support import REPO, build_library, run, start_manager

import situate

MIXED = REPO / "examples" / "mixed" / "robot.yaml"


async def fired(stream: situate.Stream[situate.Event], monitor: int) -> None:
    async for event in stream:
        if isinstance(event, situate.MonitorFired) and event.monitor == monitor:
            return
    raise AssertionError("the link closed before the monitor fired")


def test_four_languages_agree_bit_for_bit_over_a_thousand_cycles() -> None:
    for lang in ("c", "cpp"):
        build_library(lang)
    manager = start_manager(MIXED, "mixed")
    try:

        async def main() -> tuple[int, int, int]:
            async with situate.connect("mixed", endpoint=manager.endpoint) as robot:

                async def counts() -> list[int]:
                    names = ("cycles", "commands", "mismatches")
                    return [int((await robot.query(f"agree.{n}")).value) for n in names]

                # The cycle runs as fast as it can: stop it, then count 1,000 more cycles
                # from there, pausing exactly at the last one.
                await robot.stop()
                start = await counts()
                async with robot.events("monitor_fired") as stream:
                    condition = f"agree.cycles >= {start[0] + 1000}"
                    monitor = await robot.monitor(condition, "once", pause=True)
                    await robot.run()
                    await asyncio.wait_for(fired(stream, monitor), 120)
                end = await counts()
                faulted = [s.name for s in await robot.skills() if s.faulted]
                assert faulted == []
                return end[0] - start[0], end[1] - start[1], end[2]

        cycles, commands, mismatches = run(main())
    finally:
        manager.stop()
    assert cycles == 1000
    # No disagreement in any cycle since the start.
    assert mismatches == 0
    # Both branches were exercised: commands in some cycles, silence in others.
    assert 0 < commands < cycles
