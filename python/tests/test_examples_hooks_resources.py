"""The examples' lifecycle hooks and resources, run as their READMEs say.

- ``examples/python/resources``: ``main.py`` provides the robot's emergency stop (a
  ``threading.Event``) as the resource ``estop``; the class skill ``py.estop_guard`` takes it in
  its ``__init__`` and holds the robot still while it is set.
- ``examples/{rust,c,cpp,python}/runaway``: switched off, each of the four says in the same words
  how many cycles it ran away since it was last switched on (the count its ``activate`` resets),
  side by side in ``examples/mixed/robot.yaml``.
"""

from __future__ import annotations

import re
import subprocess
import sys
import threading
import time

import pytest
from support import REPO, build_library

import situate

RESOURCES = REPO / "examples" / "python" / "resources"
MIXED = REPO / "examples" / "mixed" / "robot.yaml"
RUNAWAYS = ("rust", "c", "cpp", "py")

#: A generous bound on anything waited for (a loaded machine included).
BOUND_S = 300.0


def test_the_resources_example_program_holds_its_robot_still_while_its_estop_is_pressed() -> None:
    done = subprocess.run(
        [sys.executable, str(RESOURCES / "main.py")],
        capture_output=True,
        text=True,
        timeout=BOUND_S,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    phase = re.compile(r"e-stop (\w+): (\d+\.\d\d) m in 100 cycles")
    phases = [phase.fullmatch(line) for line in lines[:3]]
    assert all(phases), done.stdout
    said = [(m.group(1), float(m.group(2))) for m in phases if m]
    assert [state for state, _ in said] == ["released", "pressed", "released"], done.stdout
    # wander drives at 0.2 m/s: about 1 m in 100 cycles of 50 ms; nothing while pressed.
    assert said[0][1] > 0.5, done.stdout
    assert said[2][1] > 0.5, done.stdout
    assert said[1][1] == 0.0, done.stdout
    assert lines[3:] == [
        "guard: emergency stop pressed: holding still",
        "guard: emergency stop released",
    ], done.stdout


def test_the_estop_guard_uses_the_very_object_the_program_provides() -> None:
    estop = threading.Event()
    robot = situate.LocalRobot(RESOURCES / "robot.yaml", resources={"estop": estop})
    robot.step(5)
    assert robot.query("drive").writer == "wander"
    estop.set()  # the program's own object: the skill sees it set at its next run
    robot.step(1)
    drive = robot.query("drive")
    assert (drive.writer, drive.value) == ("guard", {"v": 0.0, "w": 0.0})
    estop.clear()
    robot.step(1)
    assert robot.query("drive").writer == "wander"
    # Without it the robot is not built, and the error names the skill and the resource.
    with pytest.raises(ValueError, match=r"skill `guard`: could not create `py.estop_guard`"):
        situate.LocalRobot(RESOURCES / "robot.yaml")


def test_the_four_runaways_say_the_same_when_switched_off() -> None:
    for lang in ("c", "cpp"):
        build_library(lang)
    robot = situate.LocalRobot(MIXED, clock="simulated")
    signals = [f"drive_{name}" for name in RUNAWAYS]
    # Twice: run, switch off (each says how long it ran away since the switch on), switch on again
    # (counted afresh: the second count is not the sum of both).
    for round, cycles in ((1, 300), (2, 200)):
        start = robot.stats().cycle
        records = robot.record(signals, cycles)
        written = {name: records[f"drive_{name}"] for name in RUNAWAYS}
        ran = {
            name: len({r.cycle for r in rows if r.value is not None and r.cycle > start})
            for name, rows in written.items()
        }
        assert len(set(ran.values())) == 1, f"round {round}: they disagree: {ran}"
        count = ran["rust"]
        assert 10 < count < cycles - 10, f"round {round}: both branches should run: {ran}"
        assert sorted(robot.deactivate(*RUNAWAYS)) == sorted(RUNAWAYS)
        expected = f"switched off after running away {count} cycles"
        deadline = time.monotonic() + BOUND_S
        while True:
            robot.step(1)
            said = {name: [line for _, line in robot.skill(name).prints] for name in RUNAWAYS}
            if all(lines and lines[-1].startswith("switched off") for lines in said.values()):
                break
            assert time.monotonic() < deadline, f"round {round}: not all said so: {said}"
        last = {name: lines[-1] for name, lines in said.items()}
        assert last == dict.fromkeys(RUNAWAYS, expected), f"round {round}"
        assert sorted(robot.activate(*RUNAWAYS)) == sorted(RUNAWAYS)
