"""The demo's link layer (demo/courier/link.py) against a skill that faults.

A fault switches a skill off (the manager's guard against a body over its budget, which a busy
machine can cause in a healthy skill). A sequencer that waits for that skill's output must not
wait for good: it switches the skill on again, and fails the mission, saying why, when the skill
keeps faulting.
"""

from __future__ import annotations

import asyncio
import sys
import textwrap
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from support import Manager, run

import situate

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "demo"))  # the demo's package, `courier`, is there

from courier.link import EVENT_KINDS, Link, PhaseFailed  # noqa: E402

SKILLS = """
import situate

#: Faults so far.
FAULTS = [0]


@situate.skill(name="flaky", outputs={"n": "i64"})
class Flaky:
    \"\"\"Counts its runs; from the 2nd on, raises until it raised `faults` times.\"\"\"

    def __init__(self) -> None:
        self.n = 0

    def step(self, faults: int = situate.param(1, min=0)) -> dict[str, int]:
        self.n += 1
        if self.n >= 2 and FAULTS[0] < faults:
            FAULTS[0] += 1
            raise RuntimeError("a hiccup")
        return {"n": self.n}


@situate.skill(
    name="still",
    outputs={"odom": "{x: f64, y: f64, theta: f64}", "target": "f64", "range": "f32[24]"},
)
def still() -> dict[str, object]:
    \"\"\"What every wait of the sequencer reports (`link.CARRIED`).\"\"\"
    return {"odom": {"x": 0.0, "y": 0.0, "theta": 0.0}, "target": 0.0, "range": [4.0] * 24}
"""

ROBOT = """
robot: faultbot
cycle: {{rate_hz: 50, clock: wall, executor: serial}}
python: [{skills}]
skills:
  - name: flaky
    type: flaky
    active: {active}
    params: {{faults: {faults}}}
    remap: {{n: flaky.n}}
  - {{name: still, type: still, remap: {{range: sonar.range}}}}
"""


@pytest.fixture
def faultbot(tmp_path: Path, manager_for: Callable[[str, str], Manager]) -> Callable[..., Manager]:
    """A robot whose one skill faults ``faults`` times (on the wall clock: the cycle does not
    race ahead of the sequencer's answers, so the faults come within a few cycles); on from
    the start when ``active``, as a device is."""
    skills = tmp_path / "flaky.py"
    skills.write_text(textwrap.dedent(SKILLS))

    def start(faults: int, active: bool = False) -> Manager:
        text = ROBOT.format(skills=skills, faults=faults, active=str(active).lower())
        return manager_for(text, "faultbot")

    return start


async def waited(manager: Manager, kept_on: bool = False) -> tuple[int, Link]:
    """Switches `flaky` on (or, ``kept_on``, takes it as on from the start, never switched, as
    a device is) and waits (at most 60 s) until it counted to 20."""
    async with situate.connect(manager.robot, endpoint=manager.endpoint) as robot:
        seq = Link(robot, normal={}, quiet=True)
        async with robot.events(*EVENT_KINDS) as stream:
            seq.stream = stream
            await robot.stop()
            seq.t_stale = True
            if kept_on:
                # On all along without faults; it faults once from now on, seen on the stream.
                seq.kept_on = {"flaky"}
                await seq.set("flaky", "faults", 1)
            else:
                await seq.use("flaky")
            index = await seq.wait("flaky.n >= 20", within=60.0)
        return index, seq


def test_a_sequencer_switches_a_skill_that_faulted_on_again(
    faultbot: Callable[[int], Manager],
) -> None:
    index, seq = run(waited(faultbot(1)))
    # Without the switch back on, the wait ran to its time-out (index 1): n stopped at 4.
    assert index == 0
    assert [(skill, "RuntimeError: a hiccup" in cause) for _, skill, cause in seq.faults] == [
        ("flaky", True)
    ]


def test_a_skill_on_from_the_start_that_faulted_is_switched_on_again(
    faultbot: Callable[..., Manager],
) -> None:
    """A device or the sonar filter: never switched by the sequencer, on all along."""
    index, seq = run(waited(faultbot(0, True), kept_on=True))
    assert index == 0
    assert [skill for _, skill, _ in seq.faults] == ["flaky"]


def test_a_skill_that_keeps_faulting_fails_the_mission_naming_it(
    faultbot: Callable[[int], Manager],
) -> None:
    with pytest.raises(PhaseFailed, match=r"skill 'flaky' faulted 5 times within 60 s"):
        run(waited(faultbot(100)))


def test_what_a_wait_reports_is_read_without_a_request_of_its_own(
    faultbot: Callable[[int], Manager],
) -> None:
    """The pose, the target and the sonar ring come with the wait's event (`link.CARRIED`)."""
    _index, seq = run(waited(faultbot(0)))
    requests = seq.requests
    sonar = run(seq.sonar())
    odom = run(seq.odom())
    assert sonar == [4.0] * 24
    assert (odom.x, odom.y, odom.theta) == (0.0, 0.0, 0.0)
    # No query was sent (the link is closed by now: one would fail): each came with the event.
    assert seq.requests == requests
    sonar[0] = 1.0  # a reader's own copy
    assert run(seq.sonar()) == [4.0] * 24


STUCK = """
import time
import situate

SLEPT = []


@situate.skill(name="stuck", outputs={"y": "f64"})
def stuck() -> dict[str, float]:
    \"\"\"Gets stuck once (2 s, over its 100 ms budget), then runs at once.\"\"\"
    if not SLEPT:
        SLEPT.append(1)
        time.sleep(2.0)
    return {"y": 1.0}
"""


def test_a_step_cut_short_by_a_stuck_body_is_no_refusal_and_its_fault_is_reported(
    tmp_path: Path, manager_for: Callable[[str, str], Manager]
) -> None:
    skills = tmp_path / "stuck.py"
    skills.write_text(textwrap.dedent(STUCK))
    manager = manager_for(
        f"""
        robot: stuckbot
        cycle: {{rate_hz: 50, clock: simulated, executor: serial}}
        python: [{skills}]
        skills:
          - {{name: stuck, type: stuck, budget_ms: 100, active: false}}
        """,
        "stuckbot",
    )

    async def main() -> tuple[list[Any], bool, list[str]]:
        async with situate.connect(manager.robot, endpoint=manager.endpoint) as robot:
            seq = Link(robot, normal={}, quiet=True)
            async with robot.events(*EVENT_KINDS) as stream:
                seq.stream = stream
                await robot.stop()
                await robot.activate("stuck")
                seq.send("step", cycles=3)
                results = await seq.flush()  # the watchdog cuts the step short: no raise
                stale = seq.t_stale
                faulted: list[str] = []
                for _ in range(500):  # the event follows the reply (bounded: 5 s)
                    faulted += [f.skill for f in seq.take_faults()]
                    if faulted:
                        break
                    await asyncio.sleep(0.01)
                return results, stale, faulted

    results, stale, faulted = run(main())
    assert isinstance(results[0], situate.Interrupted), results
    assert "left behind" in str(results[0])
    assert stale  # the time is read anew: fewer cycles ran than were asked for
    assert faulted == ["stuck"]
