"""Monitors firing (once, edge, level), `when`, and every event kind, over a real manager.

Counting tests are deterministic: the manager is stopped, monitors are
registered, then `step N` runs exactly N cycles before its reply. The
manager's own count (`monitor_list`'s `fired`) says how many events to wait
for; the wait is bounded by a generous timeout, never a sleep.
"""

from __future__ import annotations

import asyncio
import time

import pytest
from support import EVENT_S, TOYBOT, Manager, run, start_manager

import situate
from situate import Event, MonitorFired, Robot, Stream

ALWAYS = "runaway.safe_distance > 0"  # a parameter: true from the first cycle, no device involved


async def take(stream: Stream[Event], n: int) -> list[Event]:
    """The next ``n`` events of ``stream`` (bounded wait)."""

    async def gather() -> list[Event]:
        return [await stream.__anext__() for _ in range(n)]

    return await asyncio.wait_for(gather(), EVENT_S)


async def fired(robot: Robot, monitor: int) -> int:
    for m in await robot.monitors():
        if m.monitor == monitor:
            return m.fired
    return -1


def test_a_once_monitor_fires_once_and_is_gone(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            async with robot.events("monitor_fired") as stream:
                monitor = await robot.monitor(ALWAYS, "once")
                before = (await robot.stats()).cycle
                await robot.step(5)
                [event] = await take(stream, 1)
            assert isinstance(event, MonitorFired)
            assert (event.monitor, event.condition) == (monitor, ALWAYS)
            assert event.cycle == before + 1
            assert event.values == {"runaway.safe_distance": pytest.approx(0.6)}
            assert monitor not in [m.monitor for m in await robot.monitors()]

    run(main())


def test_an_edge_monitor_fires_each_time_its_condition_becomes_true(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            async with robot.events("monitor_fired") as stream:
                monitor = await robot.monitor("runaway.safe_distance > 1", "edge")
                await robot.step(2)  # false
                await robot.set_param("runaway", "safe_distance", 2.0)
                await robot.step(3)  # true: one edge
                await robot.set_param("runaway", "safe_distance", 0.5)
                await robot.step(2)  # false
                await robot.set_param("runaway", "safe_distance", 2.5)
                await robot.step(3)  # true again: a second edge
                assert await fired(robot, monitor) == 2
                events = await take(stream, 2)
            assert all(isinstance(e, MonitorFired) and e.monitor == monitor for e in events)
            values = [
                e.values["runaway.safe_distance"] for e in events if isinstance(e, MonitorFired)
            ]
            assert values == [pytest.approx(2.0), pytest.approx(2.5)]

    run(main())


def test_a_level_monitor_fires_every_cycle_its_condition_holds(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            async with robot.events("monitor_fired") as stream:
                monitor = await robot.monitor(ALWAYS, "level")
                start = (await robot.stats()).cycle
                await robot.step(4)
                assert await fired(robot, monitor) == 4
                events = await take(stream, 4)
            cycles = [e.cycle for e in events if isinstance(e, MonitorFired)]
            assert cycles == [start + 1, start + 2, start + 3, start + 4]
            await robot.cancel_monitor(monitor)

    run(main())


def test_when_returns_the_event_of_its_condition(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            # The toy sonar's drifting box keeps some sonar near: range 0 of 24 is under 100 m.
            event = await robot.when("sonar.range[0] < 100", timeout=EVENT_S)
            assert event.condition == "sonar.range[0] < 100"
            assert event.values["sonar.range"][0] < 100  # the values of the names it reads
            assert await robot.monitors() == []

    run(main())


def test_when_cancels_its_monitor_on_timeout_and_on_cancellation(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()  # nothing can fire
            with pytest.raises(asyncio.TimeoutError):
                await robot.when(ALWAYS, timeout=0.5)
            assert await robot.monitors() == []

            task = asyncio.ensure_future(robot.when(ALWAYS))
            while not await robot.monitors():  # poll until registered
                await asyncio.sleep(0.02)
            task.cancel()
            with pytest.raises(asyncio.CancelledError):
                await task
            assert await robot.monitors() == []

            # A condition that does not parse fails at once, with nothing left behind.
            with pytest.raises(situate.BadCondition):
                await robot.when("sonar.range[0] <")

    run(main())


def test_an_any_monitor_says_which_of_its_conditions_held(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            async with robot.events("monitor_fired") as stream:
                at = (await robot.stats()).cycle + 2
                conditions = [f"cycle == {at}", "runaway.safe_distance > 5", f"cycle >= {at}"]
                monitor = await robot.monitor(any=conditions, mode="level", report=["time"])
                [info] = [m for m in await robot.monitors() if m.monitor == monitor]
                assert info.any == tuple(conditions)
                assert info.condition == " || ".join(f"({c})" for c in conditions)
                await robot.step(3)  # false, then two cycles where it holds
                events = await take(stream, 2)
            fired = [e for e in events if isinstance(e, MonitorFired)]
            # Exactly the conditions true that cycle, several at once too.
            assert [(e.cycle, e.held) for e in fired] == [(at, (0, 2)), (at + 1, (2,))]
            # The values of every name any condition reads, and of `report`.
            assert set(fired[0].values) == {"cycle", "runaway.safe_distance", "time"}
            assert fired[0].values["cycle"] == at
            await robot.cancel_monitor(monitor)

            # A bad condition is named by its index; nothing is left behind.
            with pytest.raises(situate.BadCondition) as bad:
                await robot.monitor(any=["cycle > 0", "sonar.rang[0] < 1"])
            assert bad.value.index == 1
            assert str(bad.value).startswith("any[1]: column 1: "), str(bad.value)
            assert await robot.monitors() == []
            with pytest.raises(situate.BadRequest, match="has 65 conditions, it takes 1 to 64"):
                await robot.monitor(any=["cycle > 0"] * 65)
            with pytest.raises(ValueError, match="exactly one"):
                await robot.monitor("cycle > 0", any=["cycle > 1"])
            with pytest.raises(TypeError, match="not one string"):
                await robot.monitor(any="cycle > 0")

            # `first` is one monitor on any of its conditions.
            await robot.run()
            index, event = await robot.first("time < 0", ALWAYS, timeout=30)
            assert (index, event.held) == (1, (1,))
            assert event.condition == f"(time < 0) || ({ALWAYS})"
            assert await robot.monitors() == []

    run(main())


def test_activation_and_parameter_changes_are_events(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            async with robot.events("activation_applied", "param_changed") as stream:
                await robot.deactivate("wander")
                await robot.set_param("runaway", "safe_distance", 0.4)
                await robot.step(1)
                events = await take(stream, 2)
            applied = [e for e in events if isinstance(e, situate.ActivationApplied)]
            changed = [e for e in events if isinstance(e, situate.ParamChanged)]
            assert applied[0].deactivated == ["wander"]
            assert applied[0].activated == []
            assert (changed[0].skill, changed[0].param) == ("runaway", "safe_distance")
            assert changed[0].value == pytest.approx(0.4)

    run(main())


def test_a_sequencers_phase_is_an_event_from_the_next_cycle(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            async with robot.events("phase") as stream:
                before = (await robot.stats()).cycle
                await robot.phase("leaving the lab", client="deliver")
                await robot.phase("riding the car")
                events = await take(stream, 2)
            assert events == [
                situate.Phase(text="leaving the lab", client="deliver", cycle=before + 1),
                situate.Phase(text="riding the car", client=None, cycle=before + 1),
            ]
            with pytest.raises(situate.Invalid, match="one line without control characters"):
                await robot.phase("two\nlines")
            with pytest.raises(situate.Invalid, match="1 to 200 characters, got 201"):
                await robot.phase("x" * 201)

    run(main())


def test_drain_takes_what_has_arrived_without_waiting(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            stream = robot.events("activation_applied")
            assert stream.drain() == []  # nothing yet: returns at once
            await robot.deactivate("wander")
            await robot.step(1)
            got: list[Event] = []
            deadline = asyncio.get_running_loop().time() + EVENT_S
            while not got and asyncio.get_running_loop().time() < deadline:
                got = stream.drain()
                await asyncio.sleep(0.01)
            assert [type(e) for e in got] == [situate.ActivationApplied]
            assert stream.drain() == []  # taken: not handed out twice
            stream.close()
            assert stream.drain() == []
            assert [e async for e in stream] == []  # ended

    run(main())


def test_prints_of_a_verbose_skill_are_events(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            async with robot.events("print") as stream:
                await robot.set_verbose("runaway", True)
                # runaway prints every cycle an obstacle is near; the toy sonar's box always is.
                event = await stream.next(timeout=EVENT_S)
            assert isinstance(event, situate.Print)
            assert event.skill == "runaway"
            assert "running away" in event.line
            await robot.set_verbose("runaway", False)
            prints = (await robot.skill("runaway")).prints
            assert prints
            assert "running away" in prints[-1][1]

    run(main())


def test_stopping_and_running_the_cycle_are_events(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            async with robot.events() as stream:  # every kind
                await robot.stop()
                await robot.run()
                kinds: list[type] = []
                while len(kinds) < 2:
                    event = await stream.next(timeout=EVENT_S)
                    if isinstance(event, (situate.ManagerStarted, situate.ManagerStopped)):
                        kinds.append(type(event))
            assert kinds == [situate.ManagerStopped, situate.ManagerStarted]

    run(main())


# skill_faulted: no toy skill faults; test_remote_e2e.py makes a remote skill raise.


def test_streams_end_when_the_robot_is_closed(toybot: Manager) -> None:
    async def main() -> None:
        robot = await situate.connect("toybot", endpoint=toybot.endpoint)
        stream = robot.events()
        await robot.close()

        async def drain() -> int:
            return len([e async for e in stream])

        await asyncio.wait_for(drain(), EVENT_S)  # ends instead of waiting forever

    run(main())


def test_a_pausing_monitor_stops_the_cycle_where_its_condition_held(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            start = (await robot.stats()).cycle
            target = start + 40
            index, event = await robot.first(
                "time < 0", f"cycle >= {target}", pause=True, timeout=30
            )
            assert (index, event.cycle) == (1, target)
            stats = await robot.stats()
            # The cycle stopped right there, however long the event took to arrive.
            assert (stats.running, stats.cycle) == (False, target)
            # Both monitors are gone: the one that fired and the one cancelled.
            assert await robot.monitors() == []
            await robot.run()
            await robot.when(f"cycle > {target + 2}", timeout=30)

    run(main())


def test_a_monitor_reports_the_values_asked_for_as_of_its_cycle(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            start = (await robot.stats()).cycle
            target = start + 10
            event = await robot.when(
                f"cycle >= {target}",
                pause=True,
                report=["odom", "runaway.safe_distance"],
                timeout=30,
            )
            assert await robot.monitors() == []  # a `once` monitor is gone once fired
            # The whole record comes as its leaves, all as of the cycle it fired in,
            # which is where the cycle stopped: a query now reads the same values.
            odom = await robot.query("odom")
            assert {k: v for k, v in event.values.items() if k.startswith("odom.")} == {
                f"odom.{field}": value for field, value in odom.value.items()
            }
            assert event.values["runaway.safe_distance"] == 0.6
            with pytest.raises(situate.UnknownSignal, match="did you mean `odom`"):
                await robot.monitor("cycle > 0", report=["odm"])
            assert await robot.monitors() == []
            await robot.run()

    run(main())


def test_a_link_thread_that_panics_is_reported_and_restarted_seen_from_outside() -> None:
    # The program's own hook makes its link's request and telemetry threads panic once, as a bug
    # would, from their first turns on; a client finds them counted in `stats`, restarted, and the
    # robot answering on; the program's log names each.
    threads = ["situate-link-telemetry", "situate-link-req"]
    manager = start_manager(TOYBOT, "toybot", env={"SITUATE_TEST_PANIC": ",".join(threads)})
    try:

        async def main() -> situate.Stats:
            async with situate.connect("toybot", endpoint=manager.endpoint, timeout=30) as robot:
                # Telemetry asked for keeps its thread turning.
                await robot.telemetry(["sonar.range"])
                deadline = time.monotonic() + EVENT_S
                while (stats := await robot.stats()).worker_failures < len(threads):
                    assert time.monotonic() < deadline, stats
                    await asyncio.sleep(0.05)
                return stats

        stats = run(main())
    finally:
        stderr = manager.stop()
    assert stats.worker_failures == len(threads), stats
    assert stats.cycle > 0
    assert "SITUATE_TEST_PANIC" in stderr
    for thread in threads:
        assert f"thread={thread}" in stderr or thread in stderr, stderr
    assert "restarted" in stderr, stderr
