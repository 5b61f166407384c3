"""The physics robot's command-line settings of the building's life, shared by its programs."""

from __future__ import annotations

import argparse
from typing import Any

from situate.physics.world import MAX_PEOPLE, SONARS


def add_world_args(p: argparse.ArgumentParser) -> None:
    """What real buildings have, as ``situate demo`` takes it: people, closures, dead sonars."""
    p.add_argument(
        "--people",
        type=int,
        default=0,
        metavar="N",
        help=f"people walking on every floor (this many per floor, 0 to {MAX_PEOPLE})",
    )
    p.add_argument(
        "--door-closures",
        action="store_true",
        help="the map's doors close now and then (one at a time, 20-60 s)",
    )
    p.add_argument(
        "--dead-sonar",
        type=int,
        action="append",
        default=[],
        metavar="I",
        help=f"a dead sonar (0-{SONARS - 1}): it always reads max_range (repeatable)",
    )


def world_settings(a: argparse.Namespace) -> dict[str, Any]:
    """`PhysicsWorld`'s keyword arguments from `add_world_args`'s arguments."""
    return {"people": a.people, "door_closures": a.door_closures, "dead_sonars": a.dead_sonar}
