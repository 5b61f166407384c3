"""pytest fixtures for testing robots in the test's own process.

Installed with the package, pytest loads this module by itself (an entry point in the
``pytest11`` group), as ``launch_testing`` offers ROS 2 tests their launch description. The fixture
``situate_robot`` starts a robot file's skill manager in the test's process, with every skill type
``situate run`` gives it (the built-ins, the simulator's ``sim.*`` devices for a file with a
``simulator:`` section, the file's ``python:`` and ``libraries:`` files), on the simulated clock by
default: cycles run as fast as the machine goes, and a run is the same every time::

    def test_the_robot_wanders_off(situate_robot):
        robot = situate_robot("robot.yaml")
        robot.activate("wander")
        robot.step(100)
        assert robot.query("odom").value["x"] != 0.0

A test may start several robots; each is the fixture's until the test ends. At the end of the test
the fixture fails it when a skill of one of its robots faulted (``situate_robot(...,
faults_allowed=True)`` for a test that provokes faults).
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from typing import Protocol

import pytest

from .local import LocalRobot

__all__ = ["RobotFactory", "situate_robot"]


class RobotFactory(Protocol):
    """What the ``situate_robot`` fixture gives a test: a function that starts a robot file."""

    def __call__(
        self,
        path: str | os.PathLike[str],
        *,
        clock: str | None = "simulated",
        executor: str | None = None,
        faults_allowed: bool = False,
    ) -> LocalRobot:
        """Loads and builds the robot file in this process; see :class:`situate.LocalRobot`.

        Args:
            path: The robot file.
            clock: ``"simulated"`` (the default here), ``"wall"``, or None for the file's own.
            executor: ``"serial"`` or ``"parallel"``; default: the file's.
            faults_allowed: Do not fail the test when one of this robot's skills faulted.
        """
        ...


@pytest.fixture
def situate_robot() -> Iterator[RobotFactory]:
    """Starts robot files in the test's process; fails the test when one of their skills faulted."""
    started: list[tuple[LocalRobot, bool]] = []

    def start(
        path: str | os.PathLike[str],
        *,
        clock: str | None = "simulated",
        executor: str | None = None,
        faults_allowed: bool = False,
    ) -> LocalRobot:
        robot = LocalRobot(path, clock=clock, executor=executor)
        started.append((robot, faults_allowed))
        return robot

    yield start

    faulted = [
        f"{robot.name}: skill `{skill.name}` faulted: {skill.faulted}"
        for robot, allowed in started
        if not allowed
        for skill in robot.skills()
        if skill.faulted is not None
    ]
    started.clear()
    if faulted:
        pytest.fail("\n".join(faulted), pytrace=False)
