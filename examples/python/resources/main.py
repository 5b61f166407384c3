"""Runs the toy robot with an emergency stop that this program owns.

The e-stop is a :class:`threading.Event` made here and handed to the robot as
the resource ``estop`` (``LocalRobot(..., resources={"estop": estop})``): the
skill ``guard`` (``guard.py``) takes it in its ``__init__`` and holds the robot
still while it is set. Here the program presses it itself, for the middle
third of the run; in yours, a button's handler, a watchdog or an operator's
console would, from any thread::

    .venv/bin/python examples/python/resources/main.py
"""

from __future__ import annotations

import math
import threading
from pathlib import Path

import situate

ROBOT = Path(__file__).resolve().parent / "robot.yaml"


def drive(robot: situate.LocalRobot, cycles: int) -> float:
    """Runs ``cycles`` cycles; how far the wheels went, metres (from their odometry)."""
    odom = [r.value for r in robot.record(["odom"], cycles)["odom"] if r.value is not None]
    return sum(math.dist((a["x"], a["y"]), (b["x"], b["y"])) for a, b in zip(odom, odom[1:]))


def main(cycles: int = 100) -> list[tuple[str, float]]:
    """Drives, presses the e-stop, releases it; prints and returns each phase's distance."""
    estop = threading.Event()
    robot = situate.LocalRobot(ROBOT, resources={"estop": estop})
    phases = [("released", drive(robot, cycles))]
    estop.set()
    phases.append(("pressed", drive(robot, cycles)))
    estop.clear()
    phases.append(("released", drive(robot, cycles)))
    for state, metres in phases:
        print(f"e-stop {state}: {metres:.2f} m in {cycles} cycles")
    for _, line in robot.skill("guard").prints:
        print(f"guard: {line}")
    return phases


if __name__ == "__main__":
    main()
