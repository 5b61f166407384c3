"""Every request verb of docs/protocol.md, with its success and its error replies.

Each test starts its own toybot manager (`situate run examples/toybot.yaml`)
on a free port and drives it with `situate.connect`.
"""

from __future__ import annotations

import asyncio
import json
import math
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
import zenoh
from support import Manager, free_port, run

import situate
from situate import _link

# ----- hello / connect ---------------------------------------------------------------


def test_connect_finds_the_only_robot_and_says_hello(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect(endpoint=toybot.endpoint) as robot:
            assert robot.name == "toybot"
            assert robot.hello.protocol == 1
            assert robot.hello.robot == "toybot"
            assert robot.hello.version
        robot = await situate.connect("toybot", endpoint=toybot.endpoint)
        try:
            assert robot.name == "toybot"
        finally:
            await robot.close()

    run(main())


def test_connect_to_an_unknown_robot_names_the_robots_that_answered(toybot: Manager) -> None:
    async def main() -> None:
        # A short timeout: the others are asked at its end.
        with pytest.raises(situate.OtherRobots) as e:
            async with situate.connect("wallE", endpoint=toybot.endpoint, timeout=0.5):
                pass
        assert str(e.value) == (
            "robot `wallE` did not answer; robot `toybot` did (name it with robot=)"
        )
        assert (e.value.robot, e.value.answering) == ("wallE", ["toybot"])
        assert isinstance(e.value, situate.NotRunning)  # what callers caught before
        # A long one: asked after a second of nobody serving the name, not at its end.
        started = time.monotonic()
        with pytest.raises(situate.OtherRobots):
            async with situate.connect("wallE", endpoint=toybot.endpoint, timeout=120.0):
                pass
        assert time.monotonic() - started < 60.0, "the name was waited for to the timeout"

    run(main())


def test_connect_with_nothing_listening_says_no_manager_answered() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"

    async def main() -> None:
        with pytest.raises(situate.NotRunning, match="no skill manager answered") as e:
            async with situate.connect(endpoint=endpoint, timeout=1.0):
                pass
        assert endpoint in str(e.value)
        assert e.value.kind == "not_running"
        # Zenoh's own error names the source file it came from on the build machine: not shown.
        assert ".rs:" not in str(e.value), str(e.value)

    run(main())


def test_zenoh_errors_lose_the_build_machines_source_paths() -> None:
    raw = (
        "Unable to connect to any of [Single(tcp/127.0.0.1:9)]!  at "
        "/root/.cargo/git/checkouts/zenoh-9c599d5ef3e0480e/cc83980/zenoh/src/net/runtime/"
        "orchestrator.rs:447."
    )
    clean = "Unable to connect to any of [Single(tcp/127.0.0.1:9)]!"
    assert _link.zenoh_error(Exception(raw)) == clean


def test_a_robot_that_takes_requests_and_never_answers_is_a_sentence() -> None:
    # A stuck robot: its link takes every request and never answers. Zenoh then ends the query
    # with an error reply `Timeout`, which once surfaced as "`…/req/hello` failed: Timeout".
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    held: list[zenoh.Query] = []
    session = zenoh.open(_link.zenoh_config(listen=[endpoint], mode="peer"))
    try:
        queryable = session.declare_queryable("situate/stuck/req/**", held.append)

        async def main() -> None:
            with pytest.raises(situate.NotRunning) as e:
                async with situate.connect("stuck", endpoint=endpoint, timeout=0.5):
                    pass
            message = str(e.value)
            assert message.startswith(
                "no skill manager answered `situate/stuck/req/hello` within 0.5 s"
            )
            assert "is its cycle stuck" in message
            assert "Timeout" not in message

        run(main())
        assert held, "the request reached the stuck robot"
        queryable.undeclare()  # type: ignore[no-untyped-call]
    finally:
        held.clear()
        session.close()  # type: ignore[no-untyped-call]


def _nothing_takes_it(endpoint: str, error: BaseException, started: float) -> None:
    assert isinstance(error, situate.NotRunning), error
    assert time.monotonic() - started < 20.0, "ended at once, not at the time-out"
    message = str(error)
    assert "within 30 s" not in message, message
    assert "the request ended after" in message, message
    assert "nothing on the link" in message, message
    assert endpoint in message, message


def test_a_request_nothing_on_the_link_takes_says_it_ended_at_once() -> None:
    # Zenoh ends a query at once when nothing on the link takes its key (no robot of that
    # name now, or the connection to it just lost): the message once said "within 30 s" of a
    # request that had waited no time at all, in a delivery that failed under load.
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    session = zenoh.open(_link.zenoh_config(listen=[endpoint], mode="peer"))
    client = _link.open_session([endpoint])
    try:
        started = time.monotonic()
        with pytest.raises(situate.NotRunning) as e:
            _link.request(client, "nobody", "get_param", {}, timeout=30.0, endpoints=[endpoint])
        _nothing_takes_it(endpoint, e.value, started)
        # The same for a request sent without waiting (`send`: what `robot.send` uses).
        got: list[BaseException | None] = []
        done = threading.Event()

        def outcome(_result: object, error: BaseException | None) -> None:
            got.append(error)
            done.set()

        started = time.monotonic()
        _link.send(
            client, "nobody", "get_param", {}, timeout=30.0, endpoints=[endpoint], done=outcome
        )
        assert done.wait(60), "no outcome"
        assert got[0] is not None
        _nothing_takes_it(endpoint, got[0], started)
    finally:
        _link.close_session(client)
        session.close()  # type: ignore[no-untyped-call]


# ----- send: requests that travel together ----------------------------------------------


def test_requests_sent_together_are_answered_each_as_if_alone_and_in_order(
    toybot: Manager,
) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            sent = [
                robot.send("set_param", skill="wander", param="speed", value=0.3),
                robot.send("get_param", skill="wander", param="speed"),
                robot.send("activate", skills=["wandr"]),
                robot.send("set_param", skill="wander", param="speed", value=0.4),
                robot.send("get_param", skill="wander", param="speed"),
            ]
            results = await asyncio.gather(*sent, return_exceptions=True)
            assert results[1] == 0.3, results  # the set before it, not the one after
            assert results[4] == 0.4, results
            assert isinstance(results[2], situate.UnknownSkill), results
            assert "did you mean `wander`?" in str(results[2])
            # More than one query carries (64): all of them, in order.
            values = [0.1 + k / 1000 for k in range(70)]
            sets = [robot.send("set_param", skill="wander", param="speed", value=v) for v in values]
            await asyncio.gather(*sets)
            assert await robot.get_param("wander", "speed") == values[-1]

    run(main())


def test_a_manager_without_batch_gets_each_request_on_its_own() -> None:
    # A test double of a manager older than `batch` (it refuses the verb as unknown), on a
    # real Zenoh session; the requests sent together must still each get their answer.
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    asked: list[str] = []
    session = zenoh.open(_link.zenoh_config(listen=[endpoint], mode="peer"))

    def answer(query: zenoh.Query) -> None:
        verb = str(query.key_expr).rsplit("/", 1)[-1]
        asked.append(verb)
        if verb == "hello":
            body: object = {"ok": {"protocol": 1, "robot": "oldbot", "version": "0.0.1"}}
        elif verb == "get_param":
            args = json.loads(query.payload.to_string()) if query.payload else {}
            body = {"ok": f"{args['skill']}.{args['param']}"}
        else:
            body = {"error": {"kind": "unknown_verb", "message": f"unknown request `{verb}`"}}
        query.reply(query.key_expr, json.dumps(body))

    try:
        queryable = session.declare_queryable("situate/oldbot/req/*", answer)

        async def main() -> None:
            async with situate.connect("oldbot", endpoint=endpoint, timeout=5.0) as robot:
                for _round in range(2):
                    got = await asyncio.gather(
                        robot.send("get_param", skill="a", param="x"),
                        robot.send("get_param", skill="b", param="y"),
                    )
                    assert list(got) == ["a.x", "b.y"]

        run(main())
        # One batch refused, then every request alone, the second round too.
        assert asked.count("batch") == 1, asked
        assert asked.count("get_param") == 4, asked
        queryable.undeclare()  # type: ignore[no-untyped-call]
    finally:
        session.close()  # type: ignore[no-untyped-call]


# ----- activate / deactivate -----------------------------------------------------------


def test_activate_and_deactivate_report_what_changed(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            assert await robot.deactivate("wander") == ["wander"]
            assert await robot.deactivate("wander") == []
            assert "wander" not in (await robot.stats()).active
            assert await robot.activate("wander", "runaway") == ["wander"]
            assert (await robot.skill("wander")).active

    run(main())


def test_activating_an_unknown_skill_suggests_a_name(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            with pytest.raises(situate.UnknownSkill) as e:
                await robot.activate("wandr")
            assert e.value.kind == "unknown_skill"
            assert "`wandr`" in e.value.message
            assert "did you mean `wander`?" in e.value.message
            with pytest.raises(situate.UnknownSkill, match="did you mean `runaway`"):
                await robot.deactivate("runaway_")
            # A refused request changes nothing.
            assert set((await robot.stats()).active) == {"sonar", "wheels", "runaway", "wander"}

    run(main())


UNPROVIDED = """
    robot: lonely
    cycle: {rate_hz: 50}
    devices:
      - {name: sonar, type: toy.sonar, active: false}
      - {name: wheels, type: toy.wheels}
    skills:
      - {name: runaway, type: toy.runaway, active: false}
      - {name: wander, type: toy.wander}
"""


def test_activating_a_skill_without_providers_is_refused_with_them(
    manager_for: Callable[[str, str], Manager],
) -> None:
    m = manager_for(UNPROVIDED, "lonely")

    async def main() -> None:
        async with situate.connect("lonely", endpoint=m.endpoint) as robot:
            with pytest.raises(situate.MissingProviders) as e:
                await robot.activate("runaway")
            assert e.value.signals == ["sonar.range"]
            assert e.value.providers == ["sonar"]
            assert "sonar.range" in e.value.message
            assert not (await robot.skill("runaway")).active  # refused: nothing changed
            changed = await robot.activate("runaway", with_providers=True)
            assert sorted(changed) == ["runaway", "sonar"]
            assert (await robot.skill("sonar")).active

    run(main())


# ----- parameters ------------------------------------------------------------------------


def test_parameters_are_set_and_read_back(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            assert await robot.get_param("runaway", "safe_distance") == pytest.approx(0.6)
            await robot.set_param("runaway", "safe_distance", 0.3)
            assert await robot.get_param("runaway", "safe_distance") == pytest.approx(0.3)
            await robot.set_param("runaway", "safe_distance", 2)  # an integer is fine for f64
            assert await robot.get_param("runaway", "safe_distance") == pytest.approx(2.0)
            await robot.set_param("wander", "seed", 11)
            assert await robot.get_param("wander", "seed") == 11
            info = (await robot.skill("runaway")).param("safe_distance")
            assert (info.type, info.min, info.max, info.unit) == ("f64", 0.1, 3.0, "m")
            assert info.value == pytest.approx(2.0)
            assert info.default == pytest.approx(0.5)

    run(main())


def test_bad_parameter_values_name_the_expected_type_and_range(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            with pytest.raises(situate.BadParam) as wrong_type:
                await robot.set_param("runaway", "safe_distance", "far")
            assert "safe_distance" in wrong_type.value.message
            assert "far" in wrong_type.value.message
            with pytest.raises(situate.BadParam) as out_of_range:
                await robot.set_param("runaway", "safe_distance", 5.0)
            assert "0.1" in out_of_range.value.message
            assert "3" in out_of_range.value.message
            with pytest.raises(situate.BadParam):
                await robot.set_param("wander", "seed", 1.5)
            assert await robot.get_param("runaway", "safe_distance") == pytest.approx(0.6)

    run(main())


def test_unknown_parameters_and_skills_suggest_names(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            with pytest.raises(situate.UnknownParam, match="did you mean `safe_distance`"):
                await robot.set_param("runaway", "safe_distanc", 0.3)
            with pytest.raises(situate.UnknownParam, match="did you mean `speed`"):
                await robot.get_param("wander", "sped")
            with pytest.raises(situate.UnknownSkill, match="did you mean `runaway`"):
                await robot.get_param("runawy", "speed")

    run(main())


# ----- priority and verbosity ----------------------------------------------------------


def test_priority_and_verbosity_are_set(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            assert (await robot.skill("wander")).priority == 10
            await robot.set_priority("wander", 30)
            assert (await robot.skill("wander")).priority == 30
            await robot.set_verbose("runaway", True)
            assert (await robot.skill("runaway")).verbose
            await robot.set_verbose("runaway", False)
            assert not (await robot.skill("runaway")).verbose
            with pytest.raises(situate.UnknownSkill, match="did you mean `wander`"):
                await robot.set_priority("wandr", 1)
            with pytest.raises(situate.BadRequest, match="priority"):
                await robot.set_priority("wander", 2**40)
            with pytest.raises(situate.UnknownSkill):
                await robot.set_verbose("nobody", True)

    run(main())


# ----- queries -------------------------------------------------------------------------


def test_signals_are_queried_with_their_type_and_writer(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            # The toy devices read on their own threads (wall clock): step until both have
            # reported, a minute at most (on a loaded machine that can take many cycles).
            deadline = time.monotonic() + 60
            while True:
                await robot.step(1)
                sonar = await robot.query("sonar.range")
                if sonar.value is not None and (await robot.query("odom")).value is not None:
                    break
                assert time.monotonic() < deadline, "no sonar and odometry readings within a minute"
                await asyncio.sleep(0.005)
            assert (sonar.signal, sonar.type, sonar.writer) == ("sonar.range", "f32[24]", "sonar")
            assert len(sonar.value) == 24
            assert all(isinstance(r, float) and 0 < r <= 2.0 for r in sonar.value)
            odom = await robot.query("odom")
            assert odom.type == "{x: f64, y: f64, theta: f64}"
            assert set(odom.value) == {"x", "y", "theta"}
            assert all(math.isfinite(v) for v in odom.value.values())
            x = await robot.query("odom.x")
            assert x.type == "f64"
            assert isinstance(x.value, float)
            with pytest.raises(situate.UnknownSignal, match=r"did you mean `sonar\.range`"):
                await robot.query("sonar.rnge")

    run(main())


def test_several_signals_are_read_at_once_each_as_query_reads_it(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            deadline = time.monotonic() + 60
            while any(r.value is None for r in await robot.query_many("sonar.range", "odom")):
                assert time.monotonic() < deadline, "no sonar and odometry readings within a minute"
                await robot.step(1)
            names = ["odom", "sonar.range", "odom.x", "odom"]
            readings = await robot.query_many(*names)
            # In the order asked, a name asked twice read twice; each what `query` gives alone
            # (the cycle is stopped: nothing changes in between).
            assert [r.signal for r in readings] == names
            assert readings == [await robot.query(n) for n in names]
            assert readings[0] == readings[3]
            assert readings[1].type == "f32[24]"
            assert len(readings[1].value) == 24
            # An unknown name refuses the whole request, naming it; so do none and too many.
            with pytest.raises(situate.UnknownSignal, match=r"`sonar\.rnge` — did you mean"):
                await robot.query_many("odom", "sonar.rnge")
            with pytest.raises(situate.BadRequest, match="has 0 signal names, it takes 1 to 256"):
                await robot.query_many()
            many = ["odom"] * (situate.client.MAX_QUERY_SIGNALS + 1)
            with pytest.raises(situate.BadRequest, match="has 257 signal names, it takes 1 to 256"):
                await robot.query_many(*many)
            assert len(await robot.query_many(*many[1:])) == 256

    run(main())


def test_skills_describe_themselves(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            skills = await robot.skills()
            assert [s.name for s in skills] == ["sonar", "wheels", "runaway", "wander"]
            assert [s.kind for s in skills] == ["device", "device", "sync", "sync"]
            runaway = await robot.skill("runaway")
            assert runaway.type_name == "toy.runaway"
            assert runaway.doc.startswith("Turns away from the nearest obstacle")
            assert runaway.faulted is None
            assert runaway.active
            assert [(p.name, p.signal, p.type) for p in runaway.inputs] == [
                ("sonar_range", "sonar.range", "f32[]")
            ]
            assert [p.name for p in runaway.outputs] == ["drive"]
            assert runaway.timing.runs >= 0
            with pytest.raises(situate.UnknownSkill, match="did you mean `wheels`"):
                await robot.skill("wheel")

    run(main())


def test_winners_graph_and_stats(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.step(1)
            winners = {w.signal: w for w in await robot.winners()}
            assert set(winners) == {"drive.v", "drive.w"}
            assert set(winners["drive.v"].writers) == {"runaway", "wander"}
            graph = await robot.graph()
            assert [s.name for s in graph.skills] == ["sonar", "wheels", "runaway", "wander"]
            signals = {s.signal: s for s in graph.signals}
            assert signals["sonar.range"].writers == ["sonar"]
            assert signals["sonar.range"].readers == ["runaway"]
            stats = await robot.stats()
            assert stats.robot == "toybot"
            assert not stats.running
            assert stats.period_s == pytest.approx(0.05)
            assert stats.cycle >= 1

    run(main())


# ----- the cycle ---------------------------------------------------------------------------


def test_the_cycle_stops_steps_and_runs(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            assert (await robot.stats()).running
            await robot.stop()
            before = await robot.stats()
            assert not before.running
            await robot.step(5)
            after = await robot.stats()
            assert after.cycle == before.cycle + 5
            assert not after.running
            with pytest.raises(situate.BadRequest, match="cycles"):
                await robot.step(0)
            with pytest.raises(situate.BadRequest, match="1000000"):
                await robot.step(1_000_001)
            assert (await robot.stats()).cycle == after.cycle
            await robot.run()
            assert (await robot.stats()).running

    run(main())


# ----- monitors (registration; firing is in test_client_monitors.py) ------------------------


def test_monitors_are_added_listed_and_cancelled(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            await robot.stop()
            first = await robot.monitor("sonar.range[0] < 0.25", "edge")
            second = await robot.monitor("runaway.safe_distance > 1", "level")
            listed = {m.monitor: m for m in await robot.monitors()}
            assert listed[first].condition == "sonar.range[0] < 0.25"
            assert (listed[first].mode, listed[second].mode) == ("edge", "level")
            assert listed[second].fired == 0
            await robot.cancel_monitor(first)
            assert [m.monitor for m in await robot.monitors()] == [second]
            with pytest.raises(situate.UnknownMonitor):
                await robot.cancel_monitor(first)

    run(main())


def test_only_the_session_that_added_a_monitor_cancels_it(toybot: Manager) -> None:
    async def main() -> None:
        async with (
            situate.connect("toybot", endpoint=toybot.endpoint) as a,
            situate.connect("toybot", endpoint=toybot.endpoint) as b,
        ):
            assert a.session_id != b.session_id
            events = b.events("monitor_cancelled")
            mine = await a.monitor("sonar.range[0] < -1", "level")
            [listed] = await b.monitors()
            # Everyone sees whose it is (the public id, which cannot cancel anything)…
            assert (listed.monitor, listed.session, listed.client) == (
                mine,
                a.session_id,
                a.client_id,
            )
            # …but another connection cannot cancel it.
            with pytest.raises(situate.NotOwner, match=f"monitor {mine} belongs to session"):
                await b.cancel_monitor(mine)
            assert [m.monitor for m in await b.monitors()] == [mine]
            await a.cancel_monitor(mine)
            cancelled = await asyncio.wait_for(events.__anext__(), 60)
            assert isinstance(cancelled, situate.MonitorCancelled), cancelled
            assert cancelled == situate.MonitorCancelled(
                monitor=mine,
                condition="sonar.range[0] < -1",
                session=a.session_id,
                reason="owner",
                cycle=cancelled.cycle,
            )
            # A hand-made secret without its liveliness token is no session.
            with pytest.raises(situate.NoSession, match="situate/toybot/session/"):
                await b.request("monitor_add", condition="cycle > 0", session="f" * 32)

    run(main())


SEQUENCER_THAT_CRASHES = """
import asyncio, os, sys
import situate

async def main() -> None:
    robot = await situate.connect("toybot", endpoint=sys.argv[1])
    for _ in range(240):
        robot.send("monitor_add", condition="sonar.range[0] < -1", mode="level")
    await robot.send("monitor_list")
    print(robot.session_id, flush=True)
    os.kill(os.getpid(), 9)  # a crash: no close, no goodbye

asyncio.run(main())
"""


def test_a_crashed_sequencers_monitors_go_with_it(toybot: Manager, tmp_path: Path) -> None:
    script = tmp_path / "crash.py"
    script.write_text(SEQUENCER_THAT_CRASHES)

    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as watcher:
            # It once found the robot full on its 5th start.
            for start in range(6):
                done = subprocess.run(
                    [sys.executable, str(script), toybot.endpoint],
                    capture_output=True,
                    text=True,
                    timeout=120,
                )
                assert done.returncode == -9, done.stderr
                session = done.stdout.strip()
                deadline = time.monotonic() + 60
                while any(m.session == session for m in await watcher.monitors()):
                    assert time.monotonic() < deadline, f"start {start}: its monitors stayed"
                    await asyncio.sleep(0.05)
            assert await watcher.monitors() == []

    run(main())


def test_bad_conditions_point_at_the_problem(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            with pytest.raises(situate.BadCondition) as e:
                await robot.monitor("sonar.range[0] < ")
            assert e.value.column > 0
            assert "^" in e.value.pointer
            assert e.value.message.startswith(f"column {e.value.column}")
            with pytest.raises(situate.BadCondition, match=r"did you mean `sonar\.range`") as e:
                await robot.monitor("sonr.range[0] < 1")
            assert e.value.pointer == "sonr.range[0] < 1\n^"
            with pytest.raises(situate.BadRequest, match="did you mean `edge`"):
                await robot.monitor("sonar.range[0] < 1", "edg")
            assert await robot.monitors() == []

    run(main())


# ----- telemetry ----------------------------------------------------------------------------


def test_telemetry_carries_the_chosen_signals(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            async with robot.telemetry_stream() as samples:
                await robot.telemetry(["sonar.range", "odom.x"], rate_hz=50)
                async for sample in samples:
                    if sample.signals.get("sonar.range") is not None:
                        break
            assert len(sample.signals["sonar.range"]) == 24
            assert "odom.x" in sample.signals
            assert sample.cycle > 0
            assert "runaway" in sample.active
            # Out of range is the rate's problem (`bad_param`); 1e-300 once killed the sampler.
            for rate in (0, 1000, 1e-300, 1e-9):
                with pytest.raises(situate.BadParam, match="rate_hz"):
                    await robot.telemetry(["odom.x"], rate_hz=rate)

    run(main())


# ----- malformed requests -------------------------------------------------------------


def test_malformed_requests_are_refused_and_named(toybot: Manager) -> None:
    async def main() -> None:
        async with situate.connect("toybot", endpoint=toybot.endpoint) as robot:
            with pytest.raises(situate.UnknownVerb, match="did you mean `activate`"):
                await robot.request("activte", skills=["wander"])
            with pytest.raises(situate.BadRequest, match="unknown argument `extra`"):
                await robot.request("query", signal="odom.x", extra=1)
            with pytest.raises(situate.BadRequest, match="missing argument `signal`"):
                await robot.request("query")
            with pytest.raises(situate.BadRequest, match="list of strings"):
                await robot.request("activate", skills=3)
            with pytest.raises(situate.ProtocolMismatch, match="protocol 2"):
                await robot.request("stats", protocol=2)
            assert (await robot.request("stats", protocol=1))["robot"] == "toybot"

    run(main())


def test_a_payload_that_is_not_json_is_a_bad_request(toybot: Manager) -> None:
    session = _link.open_session([toybot.endpoint])
    try:
        replies = list(session.get("situate/toybot/req/stats", payload=b"{not json", timeout=10))
        assert len(replies) == 1
        assert replies[0].ok is not None
        body = json.loads(replies[0].ok.payload.to_bytes())
        assert body["error"]["kind"] == "bad_request"
        assert "not JSON" in body["error"]["message"]
    finally:
        _link.close_session(session)
