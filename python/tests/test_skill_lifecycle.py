"""A class skill's `activate(self)` and `deactivate(self)`, called by a real manager in process.

The manager calls `activate` once when a skill is switched on, before its first run after that,
and `deactivate` once when it is switched off (by the sequencer or by a fault), after its last
run. An exception in `activate` faults the skill; one in `deactivate` is one of its prints, and
the skill is off and not faulted. Each test writes a skill file and a robot file into its own
directory and steps a `situate.LocalRobot` on the simulated clock.
"""

from __future__ import annotations

import sys
import textwrap
import threading
import time
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from support import Write

import situate

#: A generous bound on anything waited for (a loaded machine included).
BOUND_S = 60.0


def robot_yaml(skills: str) -> str:
    return (
        "robot: lifecycle\ncycle: {rate_hz: 100, clock: simulated, executor: serial}\n"
        f"python: [skills.py]\nskills:\n{textwrap.indent(textwrap.dedent(skills), '  ')}"
    )


def module_of(path: Path) -> types.ModuleType:
    """The module the loader made of a skill file (its latest import)."""
    found = [m for m in list(sys.modules.values()) if getattr(m, "__file__", None) == str(path)]
    assert found, f"{path} was not imported"
    return found[-1]


def step_until(robot: situate.LocalRobot, what: str, done: Callable[[], bool]) -> None:
    """Steps the robot one cycle at a time until `done()` holds (bounded in wall time)."""
    deadline = time.monotonic() + BOUND_S
    while not done():
        assert time.monotonic() < deadline, f"never {what}"
        robot.step(1)


HOOKED = """
import threading

import situate

LOG: list[str] = []
THREADS: set[int] = set()


class Hooked:
    def __init__(self) -> None:
        self.switched_on = 0

    def note(self, what: str) -> None:
        LOG.append(what)
        THREADS.add(threading.get_ident())

    def activate(self) -> None:
        self.switched_on += 1
        self.note("activate")
        print(f"switched on ({self.switched_on})")

    def step(self, fail: bool = False) -> dict[str, int]:
        self.note("step")
        if fail:
            raise RuntimeError("step failed on purpose")
        return {"on": self.switched_on}

    def deactivate(self) -> None:
        self.note("deactivate")
        print("switched off")


# One class, two skill types (the loader takes the module's `@situate.skill` objects).
HOOKED = situate.skill(name="hooked", outputs={"on": "i64"})(Hooked)
HOOKED_ASYNC = situate.skill(name="hooked.async", kind="async", outputs={"on": "i64"})(Hooked)
"""


def phases(log: list[str]) -> list[str]:
    """The log with each run of repeated entries made one (`step, step` is `step`)."""
    return [w for i, w in enumerate(log) if i == 0 or log[i - 1] != w]


@pytest.mark.parametrize(
    ("kind", "clock"),
    # On the wall clock an async body runs on a thread of its own, told between its runs.
    [("sync", "simulated"), ("async", "simulated"), ("async", "wall")],
)
def test_activate_comes_before_the_runs_and_deactivate_after_them_each_switch(
    files: Write, kind: str, clock: str
) -> None:
    skills = files("skills.py", HOOKED)
    type_name = "hooked" if kind == "sync" else "hooked.async"
    path = files("robot.yaml", robot_yaml(f"- {{name: h, type: {type_name}}}"))
    robot = situate.LocalRobot(path, clock=clock)
    log: list[str] = module_of(skills).LOG
    if clock == "wall":
        # A threaded body's thread starts as the robot is built, and is told it is on there,
        # before its first run: that may come before the first cycle, and nothing else may.
        assert log in ([], ["activate"]), log
    else:
        assert log == [], "nothing is called before the first cycle"
    step_until(robot, "ran after the start", lambda: log.count("step") >= 3)
    assert phases(log) == ["activate", "step"]
    assert robot.deactivate("h") == ["h"]
    step_until(robot, "deactivated", lambda: "deactivate" in log)
    robot.step(3)
    assert phases(log) == ["activate", "step", "deactivate"], "no run after the deactivation"
    assert robot.activate("h") == ["h"]
    step_until(robot, "ran after the reactivation", lambda: log[-1] == "step")
    assert phases(log) == ["activate", "step", "deactivate", "activate", "step"]
    # The same object all along (its state kept across switches), and the hooks' prints are the
    # skill's own.
    step_until(robot, "wrote its output", lambda: robot.query("on").value == 2)
    info = robot.skill("h")
    assert (info.active, info.faulted) == (True, None)
    lines = [line for _, line in info.prints]
    assert lines == ["switched on (1)", "switched off", "switched on (2)"]
    threads = module_of(skills).THREADS
    assert len(threads) == 1, "every call on the thread that runs the body"
    if clock == "wall":
        assert threading.get_ident() not in threads, "an async body's thread is its own"


def test_switched_off_and_on_between_two_cycles_it_is_deactivated_then_activated(
    files: Write,
) -> None:
    skills = files("skills.py", HOOKED)
    robot = situate.LocalRobot(files("robot.yaml", robot_yaml("- {name: h, type: hooked}")))
    robot.step(1)
    robot.deactivate("h")
    robot.activate("h")
    robot.step(1)
    assert module_of(skills).LOG == ["activate", "step", "deactivate", "activate", "step"]


def test_a_fault_in_step_deactivates_the_skill(files: Write) -> None:
    skills = files("skills.py", HOOKED)
    robot = situate.LocalRobot(files("robot.yaml", robot_yaml("- {name: h, type: hooked}")))
    robot.step(2)
    robot.set_param("h", "fail", True)
    step_until(robot, "faulted", lambda: robot.skill("h").faulted is not None)
    step_until(robot, "deactivated", lambda: "deactivate" in module_of(skills).LOG)
    robot.step(2)
    assert phases(module_of(skills).LOG) == ["activate", "step", "deactivate"]
    faulted = robot.skill("h").faulted
    assert faulted is not None
    assert "RuntimeError: step failed on purpose" in faulted


FAILING = """
import situate

LOG: list[str] = []


@situate.skill(name="failing", outputs={"y": "f64"})
class Failing:
    def activate(self) -> None:
        LOG.append("activate")
        if FAIL == "activate":
            raise RuntimeError("no power to switch on")

    def step(self) -> dict[str, float]:
        LOG.append("step")
        return {"y": 1.0}

    def deactivate(self) -> None:
        LOG.append("deactivate")
        print("parking")
        if FAIL == "deactivate":
            raise ValueError("stuck while switching off")


FAIL = ""
"""


def test_an_exception_in_activate_faults_the_skill_naming_it(files: Write) -> None:
    skills = files("skills.py", FAILING)
    robot = situate.LocalRobot(
        files("robot.yaml", robot_yaml("- {name: f, type: failing, active: false}"))
    )
    module: Any = module_of(skills)  # its FAIL is set below
    module.FAIL = "activate"
    robot.step(1)
    assert module.LOG == [], "a skill that starts off is not activated"
    assert robot.activate("f") == ["f"]
    step_until(robot, "faulted", lambda: robot.skill("f").faulted is not None)
    info = robot.skill("f")
    assert not info.active
    cause = info.faulted
    assert cause is not None
    faults = robot.events("skill_faulted")
    assert [(e.skill, e.cause) for e in faults] == [("f", cause)]  # type: ignore[union-attr]
    assert "`activate` failed" in cause
    assert "python skill `failing`" in cause
    assert "RuntimeError: no power to switch on" in cause
    assert "in activate" in cause  # the traceback
    robot.step(3)
    assert module.LOG == ["activate"], "no run, and no deactivation of a skill never on"
    assert robot.query("y").value is None
    # Fixed, the skill is switched on again by the sequencer.
    module.FAIL = ""
    assert robot.activate("f") == ["f"]
    step_until(robot, "ran", lambda: module.LOG[-1] == "step")
    assert module.LOG[:3] == ["activate", "activate", "step"]
    assert robot.skill("f").faulted is None


def test_an_exception_in_deactivate_leaves_the_skill_off_and_not_faulted(files: Write) -> None:
    skills = files("skills.py", FAILING)
    robot = situate.LocalRobot(files("robot.yaml", robot_yaml("- {name: f, type: failing}")))
    module: Any = module_of(skills)  # its FAIL is set below
    module.FAIL = "deactivate"
    robot.step(2)
    assert robot.deactivate("f") == ["f"]
    step_until(robot, "deactivated", lambda: "deactivate" in module.LOG)
    robot.step(2)
    assert phases(module.LOG) == ["activate", "step", "deactivate"]
    info = robot.skill("f")
    assert (info.active, info.faulted) == (False, None)
    assert robot.events("skill_faulted") == []
    lines = [line for _, line in info.prints]
    assert lines[0] == "parking", "what it printed before the exception is kept"
    said = "\n".join(lines[1:])
    assert "`deactivate` failed" in said
    assert "ValueError: stuck while switching off" in said
    # It can be switched on again as if nothing happened.
    assert robot.activate("f") == ["f"]
    step_until(robot, "ran again", lambda: module.LOG[-1] == "step")
    assert robot.skill("f").active


# ----- declarations ------------------------------------------------------------------


def _declare(body: dict[str, Any]) -> situate.Skill:
    def step(self: Any) -> None:
        return None

    return situate.skill(name="k")(type("K", (), {"step": step, **body}))


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ({"activate": 3}, "`activate` must be a method taking only self, not a int"),
        ({"deactivate": property(lambda self: None)}, "`deactivate` must be a method"),
        ({"activate": lambda self, cx: None}, "`activate` is called with no arguments besides "),
        ({"deactivate": lambda self, *, now: None}, "but it needs `now`"),
        ({"activate": lambda: None}, "`activate` takes no `self`"),
        ({"activate": staticmethod(lambda when: None)}, "but it needs `when`"),
    ],
)
def test_hooks_that_cannot_be_called_with_only_self_are_refused(
    body: dict[str, Any], message: str
) -> None:
    with pytest.raises(situate.SkillDeclarationError, match="skill `k`: ") as info:
        _declare(body)
    assert message in str(info.value)


def test_an_async_def_hook_is_refused() -> None:
    async def activate(self: Any) -> None:
        return None

    with pytest.raises(situate.SkillDeclarationError, match="`activate` is an async def"):
        _declare({"activate": activate})


def test_hooks_callable_with_only_self_are_accepted() -> None:
    def with_default(self: Any, why: str = "") -> None:
        return None

    def any_args(*args: Any, **kwargs: Any) -> None:
        return None

    _declare({"activate": with_default, "deactivate": any_args})
    _declare({"activate": staticmethod(lambda: None), "deactivate": classmethod(lambda cls: None)})
    _declare({"activate": None})  # None: no hook
