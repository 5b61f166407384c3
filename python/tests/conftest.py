"""Fixtures: each test that needs a skill manager gets its own, on its own port (see support.py)."""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from support import TOYBOT, Manager, start_manager


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
