"""Remote skills: the skill's side of docs/protocol.md "Remote skills", against a fake manager.

A *fake manager* written here plays the manager's side by the protocol, so
each promise of the server (latest inputs only, errors, prints, types) can
be driven exactly: a Zenoh peer listening on a free port that publishes
`.../inputs` and subscribes to `.../outputs`. The server under test connects
to it as a client, as it would to `situate run`. test_remote_e2e.py runs a
remote skill in a real robot.
"""

from __future__ import annotations

import json
import math
import queue
import signal
import subprocess
import textwrap
import threading
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import pytest
import zenoh
from support import EVENT_S, free_port, program_env, situate_program

import situate
from situate import _link
from situate.remote import RemoteSkillServer

ROBOT = "fakebot"


class FakeManager:
    """Plays the manager's side of one remote skill: publishes inputs, collects outputs."""

    def __init__(self, skill: str) -> None:
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        self.session = zenoh.open(_link.zenoh_config(listen=[self.endpoint], mode="peer"))
        prefix = f"situate/{ROBOT}/remote/{skill}"
        self.outputs: queue.Queue[dict[str, Any]] = queue.Queue()
        self.subscriber = self.session.declare_subscriber(f"{prefix}/outputs", self._on_output)
        self.publisher = self.session.declare_publisher(f"{prefix}/inputs")
        self._matched = threading.Event()
        self.listener = self.publisher.declare_matching_listener(self._on_matching)
        self.hello = self.session.declare_queryable(f"situate/{ROBOT}/req/hello", self._on_hello)

    def _on_output(self, sample: zenoh.Sample) -> None:
        self.outputs.put(json.loads(sample.payload.to_bytes()))

    def _on_matching(self, status: zenoh.MatchingStatus) -> None:
        if status.matching:
            self._matched.set()

    def _on_hello(self, query: zenoh.Query) -> None:
        hello = {"ok": {"protocol": 1, "robot": ROBOT, "version": "fake"}}
        query.reply(f"situate/{ROBOT}/req/hello", json.dumps(hello))

    def wait_for_skill(self) -> None:
        """Waits until the skill's subscription has reached this peer (an event, not a sleep)."""
        # `matching_status` is a MatchingStatus (zenoh's stub says bool): read `.matching`.
        status = self.publisher.matching_status
        if not getattr(status, "matching", status) and not self._matched.wait(EVENT_S):
            pytest.fail("the remote skill never subscribed to its inputs")

    def send(self, cycle: int, inputs: Mapping[str, Any], params: Mapping[str, Any]) -> None:
        message = {"cycle": cycle, "time_s": cycle * 0.05, "inputs": inputs, "params": params}
        self.publisher.put(json.dumps(message))

    def output(self) -> dict[str, Any]:
        try:
            return self.outputs.get(timeout=EVENT_S)
        except queue.Empty:
            pytest.fail("no output from the remote skill")

    def close(self) -> None:
        _link.close_session(self.session)


@pytest.fixture
def fake_manager(request: pytest.FixtureRequest) -> Iterator[FakeManager]:
    manager = FakeManager(getattr(request, "param", "doubler"))
    yield manager
    manager.close()


@situate.remote_skill(inputs={"x": "f64"}, outputs={"y": "f64"}, params={"gain": 2.0})
def doubler(x: float, gain: float) -> dict[str, object]:
    """Doubles `x` (or multiplies it by `gain`)."""
    if x < 0:
        raise ValueError(f"x must not be negative, got {x}")
    print(f"computing {x} * {gain}")
    return {"y": x * gain}


class Served:
    """A server running in a thread, stopped at the end."""

    def __init__(self, skill: situate.RemoteSkill, endpoint: str, name: str = "doubler") -> None:
        self.server = RemoteSkillServer(skill, robot=ROBOT, name=name, endpoint=endpoint)
        self.errors: list[BaseException] = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()
        assert self.server.wait_ready(EVENT_S) or self.errors, "server never got ready"

    def _serve(self) -> None:
        try:
            self.server.serve()
        except BaseException as e:
            self.errors.append(e)
            raise

    def stop(self) -> None:
        self.server.stop()
        self.thread.join(EVENT_S)
        assert not self.thread.is_alive()


def test_the_body_is_called_with_inputs_and_params_and_its_outputs_published(
    fake_manager: FakeManager,
) -> None:
    served = Served(doubler, fake_manager.endpoint)
    try:
        fake_manager.wait_for_skill()
        fake_manager.send(7, {"x": 1.5}, {"gain": 3})
        reply = fake_manager.output()
        assert reply == {"cycle": 7, "outputs": {"y": 4.5}, "prints": ["computing 1.5 * 3.0"]}
    finally:
        served.stop()


def test_an_exception_is_reported_with_its_traceback(fake_manager: FakeManager) -> None:
    served = Served(doubler, fake_manager.endpoint)
    try:
        fake_manager.wait_for_skill()
        fake_manager.send(3, {"x": -1.0}, {"gain": 2.0})
        reply = fake_manager.output()
        assert reply["cycle"] == 3
        assert "outputs" not in reply
        assert "Traceback" in reply["error"]
        assert "ValueError: x must not be negative, got -1.0" in reply["error"]
        # The server goes on: the next inputs are computed.
        fake_manager.send(4, {"x": 1.0}, {})
        assert fake_manager.output()["outputs"] == {"y": 2.0}  # the default gain
        assert served.server.stats.errors == 1
    finally:
        served.stop()


def test_only_the_latest_inputs_are_computed(fake_manager: FakeManager) -> None:
    entered, gate = threading.Event(), threading.Event()

    @situate.remote_skill(inputs={"x": "f64"}, outputs={"y": "f64"})
    def slow(x: float) -> dict[str, object]:
        entered.set()
        gate.wait(EVENT_S)
        return {"y": x}

    served = Served(slow, fake_manager.endpoint, name="doubler")
    try:
        fake_manager.wait_for_skill()
        fake_manager.send(1, {"x": 1.0}, {})
        assert entered.wait(EVENT_S)  # busy with cycle 1
        for cycle in range(2, 11):
            fake_manager.send(cycle, {"x": float(cycle)}, {})
        while served.server.stats.received < 10:  # poll until all have arrived
            threading.Event().wait(0.01)
        gate.set()
        assert fake_manager.output()["cycle"] == 1
        assert fake_manager.output() == {"cycle": 10, "outputs": {"y": 10.0}}
        assert served.server.stats.cycles == [1, 10]
        assert served.server.stats.dropped == 8
    finally:
        gate.set()
        served.stop()


@pytest.mark.parametrize("fake_manager", ["scanner"], indirect=True)
def test_values_travel_by_their_declared_types(fake_manager: FakeManager) -> None:
    @situate.remote_skill(
        inputs={"ranges": "f32[3]", "pose": "{x: f64, y: f64}", "tag": "bytes", "hint": "f64"},
        outputs={"nearest": "f64", "raw": "bytes", "seen": "f64[]"},
        params={"limit": math.inf, "label": "nan"},
    )
    def scanner(
        ranges: list[float],
        pose: dict[str, float],
        tag: bytes,
        hint: float | None,
        limit: float,
        label: str,
    ) -> dict[str, object]:
        assert hint is None  # an optional input nobody wrote
        assert label == "nan"
        assert limit == math.inf
        assert pose == {"x": 1.0, "y": 2.0}
        return {"nearest": min(ranges), "raw": tag[::-1], "seen": [*ranges, math.nan]}

    served = Served(scanner, fake_manager.endpoint, name="scanner")
    try:
        fake_manager.wait_for_skill()
        fake_manager.send(
            1,
            {
                "ranges": [0.5, "inf", 2],
                "pose": {"x": 1, "y": 2},
                "tag": {"$bytes": "AP8H"},
                "hint": None,
            },
            {"limit": "inf", "label": "nan"},
        )
        reply = fake_manager.output()
        assert "error" not in reply, reply.get("error")
        assert reply["outputs"] == {
            "nearest": 0.5,
            "raw": {"$bytes": "B/8A"},
            "seen": [0.5, "inf", 2.0, "nan"],
        }
    finally:
        served.stop()


def test_unusable_results_are_reported_as_errors() -> None:
    @situate.remote_skill(outputs={"y": "f64"})
    def wrong_name() -> dict[str, object]:
        return {"z": 1.0}

    @situate.remote_skill(outputs={"y": "f64"})
    def not_a_dict() -> Any:
        return 3.0

    @situate.remote_skill(outputs={"y": "f64"})
    def writes_nothing() -> None:
        return None

    assert "unknown output 'z'" in wrong_name.compute({"cycle": 1})["error"]
    assert "returned a float" in not_a_dict.compute({"cycle": 1})["error"]
    assert writes_nothing.compute({"cycle": 2}) == {"cycle": 2, "outputs": {}}


def test_a_body_that_cannot_take_its_arguments_is_refused_at_declaration() -> None:
    with pytest.raises(TypeError, match="no argument named gain"):

        @situate.remote_skill(inputs={"x": "f64"}, params={"gain": 1.0})
        def forgetful(x: float) -> dict[str, object]:
            return {}

    @situate.remote_skill(inputs={"x": "f64"}, params={"gain": 1.0})
    def flexible(**kwargs: Any) -> dict[str, object]:
        return {}

    assert flexible.manifest == {"inputs": {"x": "f64"}, "outputs": {}, "params": {"gain": 1.0}}


def test_serving_with_no_manager_says_so() -> None:
    with pytest.raises(situate.NotRunning, match="no skill manager answered"):
        situate.serve_skill(doubler, robot=ROBOT, endpoint=f"tcp/127.0.0.1:{free_port()}")


def test_serve_skill_returns_when_its_stop_event_is_set(fake_manager: FakeManager) -> None:
    stop = threading.Event()
    thread = threading.Thread(
        target=situate.serve_skill,
        args=(doubler,),
        kwargs={"robot": ROBOT, "endpoint": fake_manager.endpoint, "stop": stop},
    )
    thread.start()
    fake_manager.wait_for_skill()
    fake_manager.send(1, {"x": 2.0}, {})
    assert fake_manager.output()["outputs"] == {"y": 4.0}
    stop.set()
    thread.join(EVENT_S)
    assert not thread.is_alive()


SKILL_MODULE = """
import situate

@situate.remote_skill(inputs={"x": "f64"}, outputs={"y": "f64"}, params={"gain": 2.0})
def doubler(x, gain):
    return {"y": x * gain}
"""


@pytest.mark.parametrize("named", [True, False])
def test_the_cli_serves_a_skill_until_interrupted(
    fake_manager: FakeManager, tmp_path: Path, named: bool
) -> None:
    (tmp_path / "myskills.py").write_text(textwrap.dedent(SKILL_MODULE))
    robot = ["--robot", ROBOT] if named else []  # unnamed: the only robot answering hello
    process = subprocess.Popen(
        [
            situate_program(),
            "serve-skill",
            "myskills:doubler",
            *robot,
            "--connect",
            fake_manager.endpoint,
        ],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=program_env(),
    )
    try:
        fake_manager.wait_for_skill()
        fake_manager.send(5, {"x": 21.0}, {"gain": 2.0})
        assert fake_manager.output() == {"cycle": 5, "outputs": {"y": 42.0}}
    finally:
        process.send_signal(signal.SIGINT)
        _, err = process.communicate(timeout=EVENT_S)
    assert process.returncode == 0, err
    assert "serving remote skill `doubler` of robot `fakebot`" in err


def test_the_cli_names_a_missing_skill(tmp_path: Path) -> None:
    result = subprocess.run(
        [situate_program(), "serve-skill", "nosuchmodule:thing", "--robot", ROBOT],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env=program_env(),
        timeout=60,
        check=False,
    )
    assert result.returncode == 1
    assert "nosuchmodule" in result.stderr
