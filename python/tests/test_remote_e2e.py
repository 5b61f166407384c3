"""A Python remote skill in a real robot: a `remote:` entry served by `situate serve-skill`.

The manager publishes the skill's inputs each cycle and takes its latest
outputs in the next; these tests watch the result through the sequencer
client (`query`, events), so they exercise both sides of the protocol.
"""

from __future__ import annotations

import asyncio
import signal
import subprocess
import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from support import EVENT_S, Manager, program_env, run, situate_program

import situate

ROBOT_FILE = """
    robot: rbot
    cycle: {rate_hz: 50}
    devices:
      - {name: sonar, type: toy.sonar}
    skills:
      - name: nearest
        remote:
          doc: The nearest range, times gain.
          inputs: {ranges: "f32[]"}
          outputs: {y: f64}
          params: {gain: 2.0}
        remap: {ranges: sonar.range}
"""

SKILLS = '''
import situate

@situate.remote_skill(inputs={"ranges": "f32[]"}, outputs={"y": "f64"}, params={"gain": 2.0})
def nearest(ranges, gain):
    """The nearest range, times gain."""
    if gain > 5:
        raise RuntimeError("gain too high for this skill")
    print("nearest", min(ranges))
    return {"y": min(ranges) * gain}
'''


@pytest.fixture
def served(tmp_path: Path, manager_for: Callable[[str, str], Manager]) -> Iterator[Manager]:
    """A robot with a remote skill, and `situate serve-skill` serving it."""
    manager = manager_for(ROBOT_FILE, "rbot")
    (tmp_path / "rbot_skills.py").write_text(textwrap.dedent(SKILLS))
    server = subprocess.Popen(
        [
            situate_program(),
            *("serve-skill", "rbot_skills:nearest", "--robot", "rbot"),
            *("--connect", manager.endpoint),
        ],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=program_env(),
    )
    yield manager
    server.send_signal(signal.SIGINT)
    _, err = server.communicate(timeout=EVENT_S)
    assert server.returncode == 0, err


def test_the_manager_takes_the_remote_skills_outputs(served: Manager) -> None:
    async def main() -> None:
        async with situate.connect("rbot", endpoint=served.endpoint) as robot:
            info = await robot.skill("nearest")
            assert (info.kind, info.doc) == ("async", "The nearest range, times gain.")
            event = await robot.when("y > 0", timeout=EVENT_S)  # the first result arrived
            sonar, y = await robot.query("sonar.range"), await robot.query("y")
            assert y.writer == "nearest"
            assert 0 < y.value <= 2 * 2.0  # twice a range of the 2 m room
            assert event.values["y"] > 0
            assert sonar.value is not None

    run(main())


def test_prints_of_a_verbose_remote_skill_are_events(served: Manager) -> None:
    async def main() -> None:
        async with situate.connect("rbot", endpoint=served.endpoint) as robot:
            async with robot.events("print") as prints:
                await robot.set_verbose("nearest", True)
                event = await prints.next(timeout=EVENT_S)
            assert isinstance(event, situate.Print)
            assert event.skill == "nearest"
            assert event.line.startswith("nearest ")

    run(main())


def test_a_remote_skill_that_raises_is_faulted(served: Manager) -> None:
    async def main() -> None:
        async with situate.connect("rbot", endpoint=served.endpoint) as robot:
            await robot.when("y > 0", timeout=EVENT_S)  # running normally first
            async with robot.events("skill_faulted") as faults:
                await robot.set_param("nearest", "gain", 9.0)
                event = await asyncio.wait_for(faults.__anext__(), EVENT_S)
            assert isinstance(event, situate.SkillFaulted)
            assert event.skill == "nearest"
            assert "RuntimeError: gain too high for this skill" in event.cause
            info = await robot.skill("nearest")
            assert info.faulted is not None
            assert not info.active

    run(main())


HOSTED_ROBOT = """
    robot: hbot
    cycle: {rate_hz: 50}
    devices:
      - {name: sonar, type: toy.sonar}
    skills:
      - name: runaway
        remote:
          inputs: {sonar_range: "f32[24]"}
          outputs: {drive: "{v: f64, w: f64}"}
          params:
            safe_distance: {type: f64, default: 0.5, min: 0.1, max: 3.0}
        params: {safe_distance: 3.0}
        remap: {sonar_range: sonar.range}
"""


def test_a_skill_type_served_out_of_process_is_faulted_when_its_process_dies(
    manager_for: Callable[[str, str], Manager],
) -> None:
    """`serve-skill TYPE --python FILE`: an in-process Python type, hosted by the Rust host.

    The host holds a liveliness token; when it is killed (as a crash in a C
    skill would kill it) the manager faults the skill and runs on.
    """
    manager = manager_for(HOSTED_ROBOT, "hbot")
    example = Path(__file__).parents[2] / "examples/python/runaway/runaway.py"
    server = subprocess.Popen(
        [
            situate_program(),
            *("serve-skill", "py.runaway", "--python", str(example)),
            *("--name", "runaway", "--robot", "hbot", "--connect", manager.endpoint),
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=program_env(),
    )

    async def main() -> None:
        async with situate.connect("hbot", endpoint=manager.endpoint) as robot:
            # In the 2 m toy room every wall is nearer than 3 m: runaway drives.
            await robot.when("drive.w > -10", timeout=EVENT_S)
            drive = await robot.query("drive")
            assert drive.writer == "runaway"
            async with robot.events("skill_faulted") as faults:
                server.kill()
                event = await asyncio.wait_for(faults.__anext__(), EVENT_S)
            assert isinstance(event, situate.SkillFaulted)
            assert event.skill == "runaway"
            assert "is gone" in event.cause
            before = (await robot.stats()).cycle
            await robot.when(f"cycle > {before + 5}", timeout=EVENT_S)  # the cycle goes on

    try:
        run(main())
    finally:
        server.kill()
        server.communicate(timeout=EVENT_S)


@pytest.mark.parametrize(
    ("argv", "python"),
    [
        (["mybot.skills:doubler", "--robot", "r"], True),
        (["--robot", "r", "--name", "n", "pkg:fn"], True),
        (["c.runaway", "--library", "lib.so", "--robot", "r"], False),
        (["--python", "a:b.py", "py.runaway"], False),
        (["--help"], False),
    ],
)
def test_serve_skill_goes_to_python_only_for_a_module_function(
    argv: list[str], python: bool
) -> None:
    from situate._cli import _names_python_function

    assert _names_python_function(argv) is python
