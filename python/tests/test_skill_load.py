"""Loading `python:` skill files: in process and through the `situate` program of the wheel.

Every load error names the file (and the line when Python gives one), both from
`situate.LocalRobot` and from `situate check`/`situate run`, which report it at
the robot file's `python:` entry.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from support import EVENT_S, Write, run, situate, start_manager

import situate as sit

REPO = Path(__file__).resolve().parents[2]


def robot(python: str) -> str:
    return (
        "robot: loadtest\ncycle: {rate_hz: 100, clock: simulated}\n"
        f"python: [{python}]\n"
        "skills:\n  - {name: s, type: ok.skill}\n"
    )


GOOD = """
import situate

@situate.skill(name="ok.skill", outputs={"y": "f64"})
def ok_skill() -> dict[str, float]:
    print("tick")
    return {"y": 1.5}
"""


@pytest.mark.parametrize(
    ("source", "expected"),
    [
        (None, "skills.py: no such Python file"),
        ("def broken(:\n    pass\n", "skills.py:1:12: syntax error"),
        ("import situate\nx = 1\n", "skills.py: declares no skill"),
        (
            "import situate\n\n\n@situate.skill(name='ok.skill')\ndef f(x: list) -> None:\n"
            "    pass\n",
            "skills.py:4: skill `ok.skill`: input `x`: cannot tell its signal type from the "
            "annotation `list`",
        ),
        (
            "import situate\nraise RuntimeError('no robot here')\n",
            "skills.py:2: RuntimeError while importing: no robot here",
        ),
        (
            "import situate\n@situate.skill(name='ok.skill', outputs={'y': 'f32[x]'})\n"
            "def f() -> None:\n    pass\n",
            "skills.py:2: skill `ok.skill`, output `y`: bad type `f32[x]`",
        ),
    ],
)
def test_load_errors_name_the_file_and_line(
    files: Write, source: str | None, expected: str
) -> None:
    if source is not None:
        files("skills.py", source)
    path = files("robot.yaml", robot("skills.py"))
    with pytest.raises(ValueError, match=r"skills\.py") as info:
        sit.LocalRobot(path)
    message = str(info.value)
    assert "robot.yaml:3:" in message  # the `python:` entry of the robot file
    assert expected in message
    # The program says the same, at the same place.
    result = situate("check", str(path))
    assert result.returncode == 3  # a bad file
    assert expected in result.stderr
    assert "robot.yaml:3:" in result.stderr


def test_an_import_error_shows_the_users_frames_first_without_the_loaders(files: Write) -> None:
    files("helper_mod.py", "def fail() -> None:\n    raise ValueError('boom')\n")
    files("skills.py", "import situate\nimport helper_mod\n\nhelper_mod.fail()\n")
    path = files("robot.yaml", robot("skills.py"))
    result = situate("check", str(path))
    assert result.returncode == 3
    err = result.stderr
    assert "skills.py:4: ValueError while importing: boom" in err
    frames = [line.strip() for line in err.splitlines() if line.strip().startswith('File "')]
    # The first frame is the user's file (then the module it called); no importlib, no loader.
    assert 'skills.py", line 4' in frames[0], err
    assert 'helper_mod.py", line 2' in frames[1], err
    assert not any("importlib" in f or "_loader.py" in f for f in frames), err


def test_check_and_run_accept_python_skills(files: Write) -> None:
    files("skills.py", GOOD)
    path = files("robot.yaml", robot("skills.py"))
    result = situate("check", str(path))
    assert result.returncode == 0, result.stderr
    assert "ok" in result.stdout
    result = situate("run", str(path), "--cycles", "20", "--no-link")
    assert result.returncode == 0, result.stderr
    line = next(x for x in result.stdout.splitlines() if x.startswith("s "))
    assert "ok.skill" not in line  # the summary lists instances by name
    assert line.split()[2] == "20", result.stdout  # runs
    assert "active" in line
    # The body's prints are the skill's own, not the program's output.
    assert "tick" not in result.stdout


def test_a_wrong_type_name_in_the_robot_file_suggests_the_python_one(files: Write) -> None:
    files("skills.py", GOOD)
    path = files("robot.yaml", robot("skills.py").replace("type: ok.skill", "type: ok.skil"))
    result = situate("check", str(path))
    assert result.returncode == 3
    assert "ok.skill" in result.stderr


def test_a_python_skill_over_the_link_prints_and_faults_as_events(files: Write) -> None:
    from situate.events import Print, SkillFaulted

    files(
        "skills.py",
        """
        import situate

        @situate.skill(name="ok.skill", outputs={"y": "f64"})
        def ok_skill(fail: bool = False) -> dict[str, float]:
            print("tick")
            if fail:
                raise ValueError("asked to fail")
            return {"y": 1.5}
        """,
    )
    path = files(
        "robot.yaml",
        robot("skills.py").replace("clock: simulated", "clock: wall"),
    )
    manager = start_manager(path, "loadtest")
    try:

        async def scenario() -> tuple[float, Print, SkillFaulted, str]:
            async with sit.connect("loadtest", endpoint=manager.endpoint) as r:
                reading = await r.query("y")
                async with r.events("print", "skill_faulted") as events:
                    await r.set_verbose("s")
                    printed = await events.next(timeout=EVENT_S)
                    await r.set_param("s", "fail", True)
                    while True:
                        event = await events.next(timeout=EVENT_S)
                        if isinstance(event, SkillFaulted):
                            break
                info = await r.skill("s")
                assert isinstance(printed, Print)
                return reading.value, printed, event, info.faulted or ""

        value, printed, fault, cause = run(scenario())
    finally:
        stderr = manager.stop()
    assert value == 1.5
    assert (printed.skill, printed.line) == ("s", "tick")
    assert fault.skill == "s"
    assert "ValueError: asked to fail" in fault.cause
    assert cause == fault.cause
    assert "skill `s` faulted" in stderr


def test_two_skills_of_one_name_in_a_file_are_refused(files: Write) -> None:
    files(
        "skills.py",
        GOOD + "\n\n@situate.skill(name='ok.skill')\ndef again() -> None:\n    pass\n",
    )
    path = files("robot.yaml", robot("skills.py"))
    with pytest.raises(ValueError, match=r"two skills are named `ok\.skill`"):
        sit.LocalRobot(path)


def test_a_file_that_brings_a_skill_type_again_is_refused_naming_both(files: Write) -> None:
    files("a.py", GOOD)
    files("b.py", GOOD)
    path = files("robot.yaml", robot("a.py, b.py"))
    expected = "skill type `ok.skill` is defined already by `a.py`"
    with pytest.raises(ValueError, match="defined already") as info:
        sit.LocalRobot(path)
    assert expected in str(info.value)
    result = situate("check", str(path))
    assert result.returncode == 3, result.stderr
    assert expected in result.stderr
    assert "robot.yaml:3:" in result.stderr
    # A built-in type's name is the program's.
    files("c.py", GOOD.replace('name="ok.skill"', 'name="std.wander"'))
    path = files("robot.yaml", robot("c.py"))
    result = situate("check", str(path))
    assert result.returncode == 3, result.stderr
    assert "skill type `std.wander` is defined already by the program" in result.stderr
    # The same file twice (two included robot files may list it): loaded once, no clash.
    path = files("robot.yaml", robot("a.py, ./a.py"))
    assert situate("check", str(path)).returncode == 0


def test_a_skill_class_takes_its_resources_by_name() -> None:
    class NeedsArgs:
        def __init__(self, port: str, baud: int = 9600, **_more: object) -> None:
            self.port = port

        def step(self) -> None:
            pass

    assert sit.skill(NeedsArgs).resources == (("port", True), ("baud", False))

    class PositionalOnly:
        def __init__(self, port: str, /) -> None:
            self.port = port

        def step(self) -> None:
            pass

    with pytest.raises(sit.SkillDeclarationError, match="`port` is positional-only"):
        sit.skill(PositionalOnly)


RESOURCES = """
import situate


@situate.skill(name="counting", outputs={"total": "f64"})
class Counting:
    \"\"\"Counts its runs into the host's list, scaled by the host's gain.\"\"\"

    def __init__(self, runs: list[int], gain: float = 1.0) -> None:
        self.runs = runs
        self.gain = gain

    def step(self) -> dict[str, float]:
        self.runs.append(len(self.runs) + 1)
        return {"total": len(self.runs) * self.gain}
"""


def test_a_class_skill_is_made_with_the_resources_the_host_provides(files: Write) -> None:
    files("skills.py", RESOURCES)
    path = files(
        "robot.yaml",
        "robot: res\ncycle: {rate_hz: 10, clock: simulated}\npython: [skills.py]\n"
        "skills:\n  - {name: c, type: counting}\n",
    )
    runs: list[int] = []
    robot = sit.LocalRobot(path, resources={"runs": runs, "gain": 2.5, "unused": object()})
    robot.step(3)
    assert runs == [1, 2, 3]  # the very list the host gave
    assert robot.query("total").value == 7.5
    # An argument with a default takes it when the host provides none of that name.
    other: list[int] = []
    robot = sit.LocalRobot(path, resources={"runs": other})
    robot.step(2)
    assert robot.query("total").value == 2.0
    # One without a default is a build error naming the skill and the resource.
    with pytest.raises(ValueError, match="needs the resource `runs`") as e:
        sit.LocalRobot(path, resources={"gain": 1.0})
    assert (
        "skill `c`: could not create `counting`: `counting` needs the resource `runs` (an"
        " argument of its __init__), and the program provides none of that name (it provides"
        " `gain`)"
    ) in str(e.value)
    with pytest.raises(ValueError, match="it provides no resources"):
        sit.LocalRobot(path)


def test_a_lookup_error_of_the_class_itself_keeps_its_traceback(files: Write) -> None:
    """Only a resource not provided is told in a line; the class's own KeyError is its fault."""
    files("skills.py", RESOURCES.replace("self.runs = runs", 'self.runs = {"a": runs}["b"]'))
    path = files(
        "robot.yaml",
        "robot: res\ncycle: {rate_hz: 10, clock: simulated}\npython: [skills.py]\n"
        "skills:\n  - {name: c, type: counting}\n",
    )
    with pytest.raises(ValueError, match="creating python skill `counting`") as e:
        sit.LocalRobot(path, resources={"runs": []})
    assert "KeyError: 'b'" in str(e.value)
    assert "skills.py" in str(e.value)  # the traceback, down to the line


def test_the_in_process_robot_names_a_c_library_it_cannot_load(files: Write) -> None:
    files("skills.py", GOOD)
    path = files(
        "robot.yaml", robot("skills.py").replace("python:", "libraries: [libx.so]\npython:")
    )
    with pytest.raises(ValueError, match=r"libx\.so") as e:
        sit.LocalRobot(path)
    assert f"{path}:" in str(e.value)


ARRAYS = """
import situate

@situate.skill(name="ok.skill", outputs={"ys": "f64[]"})
def ok_skill() -> dict[str, list[float]]:
    return {"ys": [1.0, 2.0]}
"""

IN_A_FRESH_INTERPRETER = """
import sys
import situate
robot = situate.LocalRobot(sys.argv[1])
# Loaded, not yet run: arrays cross as numpy arrays, so numpy is already there.
print("numpy" in sys.modules)
"""


def test_a_skill_with_array_ports_imports_numpy_at_load_not_in_its_first_timed_run(
    files: Write,
) -> None:
    # The import (100-200 ms) once ran inside the body's first timed call: with
    # `budget_ms: 100` the skill was faulted at cycle 1 in 3 runs of 3.
    files("skills.py", ARRAYS)
    path = files(
        "robot.yaml",
        robot("skills.py").replace("type: ok.skill}", "type: ok.skill, budget_ms: 100}"),
    )
    script = files("fresh.py", IN_A_FRESH_INTERPRETER)
    done = subprocess.run(
        [sys.executable, str(script), str(path)], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "True"
    result = situate("run", str(path), "--cycles", "5", "--no-link")
    assert result.returncode == 0, result.stderr
    assert "faulted" not in result.stdout + result.stderr
