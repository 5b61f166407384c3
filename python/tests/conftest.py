"""Fixtures: each test that needs a skill manager gets its own, on its own port (see support.py)."""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from support import TOYBOT, Manager, Write, start_manager

# The modules whose tests take seconds (whole deliveries, recordings: 15-40 s each in test_demo.py),
# in the order to start them; the other tests take well under one. pytest-xdist hands tests out as
# workers free up (`--maxschedchunk 1`, scripts/python.sh): started first, the long ones run side
# by side and the short ones fill the gaps at the end, instead of one worker finishing a long
# delivery alone.
SLOW_FIRST = (
    "test_newcomer.py",
    "test_demo.py",
    "test_recording.py",
    "test_physics_delivery.py",
    "test_ros2_robot.py",
    "test_cli.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Runs the slow modules' tests first (the sort is stable: each module keeps its order)."""

    def rank(item: pytest.Item) -> int:
        name = item.path.name
        return SLOW_FIRST.index(name) if name in SLOW_FIRST else len(SLOW_FIRST)

    items.sort(key=rank)


@pytest.fixture
def toybot() -> Iterator[Manager]:
    """The example robot (examples/toybot.yaml), running, on its own port."""
    manager = start_manager(TOYBOT, "toybot")
    yield manager
    manager.stop()


@pytest.fixture
def robot_file(tmp_path: Path) -> Callable[[str], Path]:
    """Writes a robot file into the test's directory and returns its path."""

    def write(text: str) -> Path:
        path = tmp_path / "robot.yaml"
        path.write_text(textwrap.dedent(text))
        return path

    return write


@pytest.fixture
def manager_for(robot_file: Callable[[str], Path]) -> Iterator[Callable[[str, str], Manager]]:
    """Starts a manager for a robot file given as text; stopped after the test."""
    started: list[Manager] = []

    def start(text: str, robot: str) -> Manager:
        m = start_manager(robot_file(text), robot)
        started.append(m)
        return m

    yield start
    for m in started:
        m.stop()


@pytest.fixture
def files(tmp_path: Path) -> Write:
    """Writes a file (dedented) into the test's directory and returns its path."""

    def write(name: str, text: str) -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return write
