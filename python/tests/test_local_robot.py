"""Robots in the test's process: every skill type `situate run` knows, and the pytest fixture.

`situate.run` and `situate.LocalRobot` once refused the standard and simulator skills
(`unknown skill type sim.sonar — did you mean toy.sonar?`) on files `situate check` accepted.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from support import REPO, build_library

import situate

DEMO_ROBOT = REPO / "demo" / "robot.yaml"


def test_the_delivery_robot_runs_in_process_with_the_simulator_and_the_standard_skills() -> None:
    result = situate.run(DEMO_ROBOT, 30, record=["sonar.raw", "sonar.range"])
    assert result.stats.cycle == 30
    raw = [r.value for r in result.records["sonar.raw"] if r.value is not None]
    assert raw, "sim.sonar never wrote"
    assert all(len(ring) == 24 for ring in raw)
    # std.sonar_filter (active in the file) filled in sonar.range from the raw ring.
    assert any(r.writer == "sonar_filter" for r in result.records["sonar.range"])
    assert {s.type_name for s in result.skills.values()} >= {"sim.sonar", "sim.base", "std.wander"}
    assert all(s.faulted is None for s in result.skills.values())


def test_a_standard_skill_drives_the_simulated_base_in_process() -> None:
    robot = situate.LocalRobot(DEMO_ROBOT, clock="simulated")
    robot.step(5)
    before = robot.query("odom").value
    robot.activate("wander")
    robot.step(50)  # 5 s at the file's 10 Hz
    after = robot.query("odom").value
    assert after is not None
    assert before is not None
    moved = ((after["x"] - before["x"]) ** 2 + (after["y"] - before["y"]) ** 2) ** 0.5
    assert moved > 0.2, (before, after)


def test_several_signals_are_read_in_process_as_over_the_link() -> None:
    robot = situate.LocalRobot(DEMO_ROBOT, clock="simulated")
    robot.step(5)
    names = ["odom", "sonar.range", "odom.x", "odom"]
    readings = robot.query_many(*names)
    assert readings == [robot.query(n) for n in names]
    assert readings[0].value is not None
    with pytest.raises(situate.UnknownSignal, match=r"`sonar\.rnge` — did you mean"):
        robot.query_many("odom", "sonar.rnge")


def test_c_and_cpp_libraries_run_in_process_beside_rust_and_python() -> None:
    for lang in ("c", "cpp"):
        build_library(lang)
    result = situate.run(REPO / "examples" / "mixed" / "robot.yaml", 300, clock="simulated")
    assert {s.type_name.split(".")[0] for s in result.skills.values()} >= {"c", "cpp", "py"}
    agree = {n: result.robot.query(f"agree.{n}").value for n in ("cycles", "mismatches")}
    assert agree["cycles"] is not None, agree
    assert agree["cycles"] > 100, agree
    assert agree["mismatches"] == 0, agree


def test_a_file_with_an_unknown_type_still_names_the_line(tmp_path: Path) -> None:
    text = DEMO_ROBOT.read_text()
    text = text.replace("../maps/default.yaml", str(REPO / "maps" / "default.yaml"))
    path = tmp_path / "robot.yaml"
    path.write_text(text.replace("type: std.wander", "type: std.wandr"))
    with pytest.raises(ValueError, match=r"std\.wandr") as e:
        situate.LocalRobot(path)
    line = 1 + text.splitlines().index(
        next(line for line in text.splitlines() if "std.wander" in line)
    )
    assert f"{path}:{line}" in str(e.value)
    assert "std.wander" in str(e.value)  # the close name


FIXTURE_TESTS = """
from pathlib import Path

ROBOT = Path({robot!r})
FAULTY = Path({faulty!r})


def test_wander(situate_robot):
    robot = situate_robot(ROBOT)
    robot.activate("wander")
    robot.step(30)
    assert robot.query("odom").value["v"] > 0.0


def test_a_fault_fails_the_test(situate_robot):
    robot = situate_robot(FAULTY)
    robot.step(3)


def test_a_fault_allowed(situate_robot):
    robot = situate_robot(FAULTY, faults_allowed=True)
    robot.step(3)
    assert robot.skill("boom").faulted
"""

FAULTY_SKILLS = '''
import situate


@situate.skill(name="test.boom", outputs={"x": "f64"})
def boom() -> dict[str, float]:
    """Fails every run."""
    raise RuntimeError("boom on purpose")
'''


def test_the_pytest_fixture_is_there_wherever_the_package_is_installed(tmp_path: Path) -> None:
    (tmp_path / "skills.py").write_text(FAULTY_SKILLS)
    faulty = tmp_path / "faulty.yaml"
    faulty.write_text(
        "robot: faulty\ncycle: {rate_hz: 100, clock: simulated}\npython: [skills.py]\n"
        "skills:\n  - {name: boom, type: test.boom}\n"
    )
    tests = tmp_path / "test_user.py"
    tests.write_text(FIXTURE_TESTS.format(robot=str(DEMO_ROBOT), faulty=str(faulty)))
    # A pytest of its own, in a folder outside the repository's tests (no conftest there): the
    # fixture comes from the installed package's pytest11 entry point.
    out = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(tests)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    report = out.stdout + out.stderr
    assert "fixture 'situate_robot' not found" not in report
    assert "test_user.py::test_a_fault_fails_the_test" in report, report
    # The fault fails its test (at teardown); the other two pass.
    assert out.returncode == 1, report
    assert "ERROR at teardown of test_a_fault_fails_the_test" in report, report
    assert " failed" not in report, report
    assert "3 passed, 1 error" in report, report
    assert "faulty: skill `boom` faulted:" in report
    assert "boom on purpose" in report
