"""The delivery's first leg in real physics: the mission's sequencer takes the robot out of its lab.

The robot is `demo/physics.yaml` (the delivery robot's skills, its devices replaced by ROS 2
topics) run by `situate run --stopped`; the world is the physics robot (`situate.physics`:
MuJoCo, the default building) on a real Zenoh session, in lock-step with the robot's cycle; the
sequencer is the demo's own `demo/deliver.py`, unchanged, its phases 1 to 3 (`--to lab`): wander
until the lab door's barcode is seen, home on it, find the opening with the sonars, pass the
door. Nothing of the 2-D simulator runs.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from support import REPO, STARTUP_S, start_manager, zenoh_client

from situate.physics import Building, PhysicsWorld
from situate.physics.node import PhysicsNode
from situate.ros2 import Ros2Peer

#: The lab (x 0..8, y 0..6) and its door in the north wall, x 5.9..7.1 (maps/default.yaml).
LAB_NORTH_WALL_Y = 6.0


def test_the_sequencer_takes_the_physics_robot_out_of_its_lab(tmp_path: Path) -> None:
    building = Building.load(REPO / "maps" / "default.yaml")
    # Every seed from 1 to 10 leaves the lab (docs/physics.md); seed 5 (the world's sensor noise
    # and the sequencer's wandering) in 63 s of robot time.
    world = PhysicsWorld(building, seed=5)
    robot = start_manager(REPO / "demo" / "physics.yaml", "deliverybot", "--stopped")
    try:
        with zenoh_client(robot.endpoint) as session:
            peer = Ros2Peer(session, node="physics")
            node = PhysicsNode(world, peer, rate_hz=10, lockstep="/deliverybot/cycle")
            node.start(time_scale=float("inf"))
            try:
                out = subprocess.run(
                    [
                        sys.executable,
                        str(REPO / "demo" / "deliver.py"),
                        "--connect",
                        robot.endpoint,
                        "--robot",
                        "deliverybot",
                        "--mission",
                        json.dumps(building.mission),
                        "--to",
                        "lab",
                        "--seed",
                        "5",
                    ],
                    capture_output=True,
                    text=True,
                    timeout=20 * STARTUP_S,
                    check=False,
                )
            finally:
                node.close()
                peer.close()
    finally:
        err = robot.stop()
    assert out.returncode == 0, out.stdout + out.stderr
    assert "phase 3: looking for the door opening and passing the lab door" in out.stdout
    assert "mission complete" in out.stdout, out.stdout
    # Out of the lab, through its door, on its wheels: where the physics put it.
    p = world.pose()
    assert p.floor == -1
    assert p.y > LAB_NORTH_WALL_Y + building.robot_radius, (p, out.stdout)
    assert world.tilt() < 0.05
    assert node.ticks > 100
    assert "panicked" not in err, err
