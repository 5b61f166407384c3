"""``python -m situate.physics MAP``: the physics robot as a ROS 2 robot, until interrupted."""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from collections.abc import Sequence

import zenoh

from situate.physics.building import Building
from situate.physics.cli import add_world_args, world_settings
from situate.physics.node import PhysicsNode
from situate.physics.world import PhysicsWorld
from situate.ros2 import Ros2Peer


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the physics robot in a map's building until SIGINT or SIGTERM; the exit status."""
    p = argparse.ArgumentParser(prog="python -m situate.physics", description=__doc__)
    p.add_argument("map", help="the building's map file (docs/maps.md)")
    p.add_argument(
        "--connect",
        action="append",
        help="a Zenoh endpoint to connect to (situate's link, or a router; default "
        "tcp/127.0.0.1:7447, where rmw_zenoh looks for its router)",
    )
    p.add_argument(
        "--seed", type=int, default=1, help="seeds the sensors' noise, the cars and the people"
    )
    add_world_args(p)
    p.add_argument("--rate-hz", type=float, default=10.0, help="ticks of the clock per second")
    p.add_argument(
        "--time-scale", type=float, default=1.0, help="simulated seconds per real second"
    )
    p.add_argument("--node", default="physics", help="the ROS 2 node's name")
    p.add_argument("--namespace", default="", help="the ROS 2 node's namespace")
    p.add_argument("--domain-id", type=int, default=0, help="ROS_DOMAIN_ID")
    p.add_argument("--stamped", action="store_true", help="cmd_vel is TwistStamped")
    p.add_argument(
        "--lockstep",
        metavar="TOPIC",
        help="lock-step with the robot whose ~/cycle topic this is (e.g. /deliverybot/cycle): "
        "each tick waits for its cycles (docs/physics.md)",
    )
    a = p.parse_args(argv)
    try:
        building = Building.load(a.map)
        world = PhysicsWorld(building, seed=a.seed, **world_settings(a))
    except ValueError as e:
        print(f"python -m situate.physics: {e}", file=sys.stderr)
        return 3
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    endpoints = a.connect or ["tcp/127.0.0.1:7447"]
    config.insert_json5("connect/endpoints", json.dumps(endpoints))
    config.insert_json5("scouting/multicast/enabled", "false")
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: done.set())
    with zenoh.open(config) as session:
        peer = Ros2Peer(session, domain_id=a.domain_id, namespace=a.namespace, node=a.node)
        node = PhysicsNode(
            world,
            peer,
            rate_hz=a.rate_hz,
            stamped=a.stamped,
            lockstep=a.lockstep,
        )
        node.start(a.time_scale)
        print(
            f"physics robot in {building.name!r}: node {peer.namespace.rstrip('/')}/{a.node}, "
            f"{a.rate_hz:g} Hz at {a.time_scale:g}x real time, connected to "
            f"{', '.join(endpoints)}",
            flush=True,
        )
        done.wait()
        node.close()
        peer.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
