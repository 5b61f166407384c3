"""The reactive robot built without a link, and made-up senses, for the pure controller tests.

`test_reactive_memory.py` and `test_reactive_car.py` test `Reactive.remember` and the rules'
actions on these: no link, no simulator (nothing here sends anything).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "demo"))  # the demo's package, `courier`, is there

from courier.geometry import SONARS, Pose  # noqa: E402
from courier.mission import Mission  # noqa: E402
from courier.reactive.rules import Reactive  # noqa: E402
from courier.reactive.state import Senses  # noqa: E402

ROUTE: dict[str, list[dict[str, Any]]] = {
    "button_to_office": [
        {"turn": "back"},
        {"follow": "hallway", "until": "wall", "turn": "left"},
        {"follow": "hallway", "until": "barcode", "barcode": 40},
        {"home": 40},
        {"pass": "door"},
    ]
}


def mission() -> Mission:
    """A made-up mission: the office on floor 2, the lab and the route on floor 0."""
    return Mission(
        goal_floor=2,
        start_floor=0,
        lab_door_barcode=10,
        call_button_barcode=30,
        office_barcode=50,
        car_barcode_first=201,
        cars=2,
        message="hello",
        route=ROUTE,
        goal_button_barcode=32,
        lobbies={0: 30, 1: 31, 2: 32},
    )


def robot() -> Reactive:
    """The reactive controller for `mission`, without a robot."""
    return Reactive(None, mission(), [("office", 2)], quiet=True)  # type: ignore[arg-type]


def senses(t: float, **kw: Any) -> Senses:
    """One cycle's senses at simulated time ``t``: nothing in view but what ``kw`` gives."""
    s: dict[str, Any] = {
        "t": t,
        "pose": Pose(0.0, 0.0, 0.0),
        "sonar": [4.0] * SONARS,
        "barcodes": {},
        "floor": 0,
        "presses": 0,
        "said": 0,
        "junction": {},
        "door": {},
        "opened": {},
        "car": 0,
        "opening": {},
        "wall": {},
        "door_passed": False,
        "car_entered": False,
        "car_exited": False,
    }
    s.update(kw)
    return Senses(**s)
