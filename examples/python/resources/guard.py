"""An emergency-stop guard: a class skill made with a resource of the program's.

The program that runs the robot owns the emergency stop (a
:class:`threading.Event`, set while it is pressed) and provides it as the
resource ``estop``; the skill's ``__init__`` takes it by that name. While it is
set, the guard writes a zero ``drive`` every cycle, and its priority beats every
other writer of ``drive``; otherwise it writes nothing.
"""

from __future__ import annotations

import threading
from typing import Any

import situate


@situate.skill(name="py.estop_guard", priority=100, outputs={"drive": "{v: f64, w: f64}"})
class EStopGuard:
    """Holds the robot still while the program's emergency stop is pressed."""

    def __init__(self, estop: threading.Event) -> None:
        self.estop = estop  # the program's own object, not a copy
        self.held = False

    def step(self) -> dict[str, Any] | None:
        """One cycle: a zero drive while the e-stop is pressed, else nothing."""
        if not self.estop.is_set():
            if self.held:
                print("emergency stop released")
                self.held = False
            return None
        if not self.held:
            print("emergency stop pressed: holding still")
            self.held = True
        return {"drive": {"v": 0.0, "w": 0.0}}
