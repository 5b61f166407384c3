"""The physics robot is a ROS 2 robot: situate's standard skills drive it through ROS 2 alone.

`situate.physics.node.PhysicsNode` (MuJoCo: mass, wheel motors, friction, the sonar's cone) in
the default building's lab, speaking rmw_zenoh on a Zenoh session connected to situate's link.
situate runs no simulator: its ``sonar.range`` and ``odom`` come from the node's ``/sonar`` and
``/odom`` (topics in), its ``drive`` goes out as ``/cmd_vel``, and its cycle follows the node's
``/clock`` (``use_sim_time``). The delivery's wander, avoid and runaway skills, unchanged, move
the base about the lab, and its walls hold it.
"""

from __future__ import annotations

import json
import math
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from support import REPO, STARTUP_S, situate, start_manager, zenoh_client

from situate.physics import Building, PhysicsWorld
from situate.physics.model import FLOOR_HEIGHT
from situate.physics.node import PhysicsNode
from situate.ros2 import Ros2Peer

ROBOT = """\
robot: physbot
cycle: {rate_hz: 10, clock: simulated}
skills:
  - {name: runaway, type: std.runaway}
  - {name: avoid, type: std.avoid}
  - {name: wander, type: std.wander, params: {seed: 5}}
ros2:
  use_sim_time: true
  rate_hz: 100
  topics:
    - {topic: /sonar, type: sensor_msgs/msg/LaserScan, signal: sonar.range, direction: in, ring: 24}
    - {topic: /odom, type: nav_msgs/msg/Odometry, signal: odom, direction: in}
    - {signal: drive, topic: /cmd_vel, type: geometry_msgs/msg/Twist}
"""


def wait_until(
    cond: Callable[[], bool],
    what: str,
    bound: float = 3 * STARTUP_S,
    detail: Callable[[], str] | None = None,
) -> None:
    deadline = time.monotonic() + bound
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: {detail() if detail else 'not in time'}")
        time.sleep(0.05)


def test_the_standard_skills_drive_the_physics_robot_through_ros_2(tmp_path: Path) -> None:
    robot_file = tmp_path / "physbot.yaml"
    robot_file.write_text(ROBOT)
    robot = start_manager(robot_file, "physbot")
    connect = robot.connect_args

    def stats() -> dict[str, float]:
        out = situate("stats", *connect, "--json")
        assert out.returncode == 0, out.stderr
        result: dict[str, float] = json.loads(out.stdout)
        return result

    def query(signal: str) -> object:
        out = situate("query", signal, *connect, "--json")
        assert out.returncode == 0, out.stderr
        value = json.loads(out.stdout)
        return value.get("value", value) if isinstance(value, dict) else value

    building = Building.load(REPO / "maps" / "default.yaml")
    world = PhysicsWorld(building, seed=2)
    start = world.pose()
    try:
        with zenoh_client(robot.endpoint) as s:
            peer = Ros2Peer(s, node="physics")
            node = PhysicsNode(world, peer, rate_hz=10)
            try:
                wait_until(
                    lambda: any("/MS/" in k and "/%clock/" in k for k in peer.graph()),
                    "situate's /clock subscription",
                )
                assert stats()["cycle"] == 0, "no cycle before the robot's clock runs"
                node.start(time_scale=2.0)
                # The skills' commands reach the base, and the base drives about the lab.
                wait_until(lambda: node.commands_received > 20, "commands reach the base")
                wait_until(
                    lambda: math.dist((world.pose().x, world.pose().y), (start.x, start.y)) > 1.0,
                    "the base drives a metre",
                )
                node.stop()
                assert not node.cmd_problems, node.cmd_problems

                # One cycle per tick of the robot's clock, none skipped, none doubled: the
                # first tick anchors the robot's time 0, even when the robot's clock thread
                # looks late and finds two ticks come (the flake hunt saw cycle 36 of 38 ticks
                # before the driver kept the first). The clock stopped: its last /clock is sent
                # again while waiting, as a paused simulator does (a keep-last /clock may be
                # dropped under load: the hunt saw cycle 37 of 39 ticks when the last one was).
                # The same time again runs no cycle, so a doubled cycle still shows.
                def caught_up() -> bool:
                    node.publish_clock()
                    return bool(stats()["cycle"] == node.ticks - 1)

                wait_until(
                    caught_up,
                    "a cycle per tick",
                    detail=lambda: f"cycle {stats()['cycle']}, ticks {node.ticks}",
                )
                # situate's odom is the base's wheel odometry (as of the last tick or the one
                # before: the device hands a message to the cycle within a millisecond).
                odom = query("odom")
                assert isinstance(odom, dict), odom
                o = world.odometry()
                assert math.dist((float(odom["x"]), float(odom["y"])), (o.x, o.y)) < 0.1, odom
                ring = query("sonar.range")
                assert isinstance(ring, list), ring
                assert len(ring) == 24
                # The lab's walls held the base, and it stayed on its wheels.
                p = world.pose()
                assert 0.0 < p.x < 8.5, p
                assert 0.0 < p.y < 6.0, p
                assert p.floor == -1
                assert world.tilt() < 0.1
            finally:
                node.close()
                peer.close()
    finally:
        err = robot.stop()
    assert "panicked" not in err, err


def test_python_m_situate_physics_runs_the_robot_until_sigterm(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nrobot_radius: 0.25\n")
    out = subprocess.run(
        [sys.executable, "-m", "situate.physics", str(bad)],
        capture_output=True,
        text=True,
        timeout=STARTUP_S,
        check=False,
    )
    assert out.returncode == 3, out
    assert "bad.yaml" in out.stderr
    robot_file = tmp_path / "physbot.yaml"
    robot_file.write_text(ROBOT)
    robot = start_manager(robot_file, "physbot")
    try:
        with zenoh_client(robot.endpoint) as s:
            peer = Ros2Peer(s, node="watcher")
            node = subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "situate.physics",
                    str(REPO / "maps" / "default.yaml"),
                    "--connect",
                    robot.endpoint,
                    "--node",
                    "base",
                ],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
            )
            try:
                # Its node and its /clock publisher are in the ROS 2 graph, and situate's
                # cycle follows its clock.
                wait_until(
                    lambda: any(
                        "/MP/" in k and "/%clock/" in k and "/base/" in k for k in peer.graph()
                    ),
                    "the physics node's /clock publisher",
                )
                wait_until(
                    lambda: (
                        json.loads(situate("stats", *robot.connect_args, "--json").stdout)["cycle"]
                        > 5
                    ),
                    "the cycle follows the physics robot's clock",
                )
            finally:
                node.send_signal(signal.SIGTERM)
                stdout, stderr = node.communicate(timeout=STARTUP_S)
            peer.close()
        assert node.returncode == 0, stderr
        assert "physics robot in 'default'" in stdout
    finally:
        robot.stop()


LOCKSTEP = ROBOT.replace(
    "  use_sim_time: true\n", "  use_sim_time: true\n  lockstep: true\n"
).replace(
    "    - {topic: /odom,",
    "    - {topic: /barcodes, type: situate_msgs/msg/Barcodes, signal: barcodes, direction: in}\n"
    "    - {topic: /odom,",
)


def lockstep_run(tmp_path: Path, ticks: int) -> tuple[list[tuple[float, float, float]], object]:
    """The standard skills drive the physics robot in lock-step for `ticks` ticks; the poses."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    robot_file = tmp_path / "physbot.yaml"
    robot_file.write_text(LOCKSTEP)
    robot = start_manager(robot_file, "physbot")
    poses = []
    try:
        with zenoh_client(robot.endpoint) as s:
            peer = Ros2Peer(s, node="physics")
            world = PhysicsWorld(Building.load(REPO / "maps" / "default.yaml"), seed=2)
            world.place(-1, 5.0, 4.0, 1.2)  # in sight of the lab door's barcode (10)
            node = PhysicsNode(world, peer, rate_hz=10, lockstep="/physbot/cycle")
            try:
                for k in range(1, ticks + 1):
                    node.tick()
                    p = world.pose()
                    poses.append((p.x, p.y, p.theta))
                    # Each tick returns once the robot has run its cycles up to its time: the
                    # first tick anchors ROS time 0, so after tick k, k - 1 cycles.
                    if k in (1, 2, ticks):
                        out = situate("stats", *robot.connect_args, "--json")
                        assert json.loads(out.stdout)["cycle"] == k - 1, (k, out.stdout)
                out = situate("query", "barcodes", *robot.connect_args, "--json")
                barcodes = json.loads(out.stdout)
            finally:
                node.close()
                peer.close()
    finally:
        robot.stop()
    return poses, barcodes


def test_in_lockstep_a_run_through_ros_2_is_the_same_every_time(tmp_path: Path) -> None:
    first, barcodes = lockstep_run(tmp_path / "a", 120)
    second, _ = lockstep_run(tmp_path / "b", 120)
    assert first == second, "the same seed and skills give the same run, tick for tick"
    start, end = first[0], first[-1]
    assert math.dist(start[:2], end[:2]) > 0.3, "the base moved"
    # The reader's barcodes reached the robot's `barcodes` signal through ROS 2.
    value = barcodes.get("value", barcodes) if isinstance(barcodes, dict) else barcodes
    assert isinstance(value, dict), barcodes
    assert set(value) == {"ids", "bearing", "distance"}
    assert len(value["ids"]) == len(value["bearing"]) == len(value["distance"])


def test_situate_msgs_is_the_package_a_ros_2_system_builds() -> None:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from situate.ros2 import SITUATE_MSGS, type_hash

    package = REPO / "ros2" / "situate_msgs"
    for name, text in SITUATE_MSGS.items():
        assert (package / "msg" / f"{name.rsplit('/', 1)[1]}.msg").read_text() == text
        store = get_typestore(Stores.ROS2_JAZZY)
        store.register(get_types_from_msg(text, name))
        assert type_hash(name) == store.hash_rihs01(name)
    built = (package / "CMakeLists.txt").read_text()
    assert sorted(f"msg/{f.name}" for f in (package / "msg").iterdir()) == sorted(
        f"msg/{name.rsplit('/', 1)[1]}.msg" for name in SITUATE_MSGS
    )
    for name in SITUATE_MSGS:
        assert f"msg/{name.rsplit('/', 1)[1]}.msg" in built, name


def test_the_ground_truth_topics_are_the_robots_truth_signals() -> None:
    """``ground_truth/*`` are the world's truth, and demo/physics.yaml maps them.

    The node publishes the robot's true pose in the building each tick on ``ground_truth/odom``
    (map → base_link, z the floor's slab, the true speeds: Gazebo's p3d), the people walking on
    ``ground_truth/people`` and the cars on ``ground_truth/cars``; the demo's robot file makes
    them ``truth.pose`` (with its floor in ``floor``), ``truth.people`` and ``truth.cars``, the
    GUI's world view's signals, as the 2-D simulator writes them: they follow the world.
    """
    robot = start_manager(REPO / "demo" / "physics.yaml", "deliverybot")
    try:
        out = situate("activate", "runaway", "avoid", "wander", *robot.connect_args)
        assert out.returncode == 0, out.stderr

        def query(signal: str) -> Any:
            out = situate("query", signal, *robot.connect_args, "--json")
            assert out.returncode == 0, out.stderr
            return json.loads(out.stdout)

        with zenoh_client(robot.endpoint) as s, zenoh_client(robot.endpoint) as ws:
            watcher = Ros2Peer(ws, node="watcher")
            truths: dict[int, Any] = {}

            def on_truth(m: Any) -> None:
                truths[int(m.header.stamp.sec) * 10**9 + int(m.header.stamp.nanosec)] = m

            watch = watcher.subscribe(
                "/ground_truth/odom", "nav_msgs/msg/Odometry", on_truth, ordered=True
            )
            peer = Ros2Peer(s, node="physics")
            world = PhysicsWorld(Building.load(REPO / "maps" / "default.yaml"), seed=2, people=2)
            node = PhysicsNode(world, peer, rate_hz=10, lockstep="/deliverybot/cycle")
            try:
                # The watcher's subscription is known before the first tick is published.
                wait_until(
                    lambda: any(
                        "/MS/" in k and "/watcher/" in k and "ground_truth%odom" in k
                        for k in peer.graph()
                    ),
                    "the watcher's subscription to /ground_truth/odom",
                )
                poses = [world.pose()]
                people = [world.people()]
                cars = [world.cars()]
                assert poses[0].floor == -1, poses
                for k in range(1, 101):
                    node.tick()
                    p = world.pose()
                    poses.append(p)
                    people.append(world.people())
                    cars.append(world.cars())
                    if k % 25:
                        continue
                    # The message of tick k: the pose and speeds the world has now.
                    v, w = world.velocity()
                    stamp_ns = k * 10**8
                    wait_until(lambda: stamp_ns in truths, f"the ground truth of tick {k}")  # noqa: B023
                    m = truths[stamp_ns]
                    assert (m.header.frame_id, m.child_frame_id) == ("map", "base_link")
                    pos = m.pose.pose.position
                    assert (pos.x, pos.y, pos.z) == (p.x, p.y, p.floor * FLOOR_HEIGHT), (pos, p)
                    q = m.pose.pose.orientation
                    yaw = 2 * math.atan2(q.z, q.w)
                    assert abs(math.remainder(yaw - p.theta, 2 * math.pi)) < 1e-9, (q, p)
                    twist = m.twist.twist
                    assert (twist.linear.x, twist.angular.z) == (v, w)
                    # Lock-step: after tick k the robot has run k - 1 cycles, and cycle n's
                    # truth.pose is the pose tick n published.
                    pose = query("truth.pose")
                    assert pose["cycle"] == k - 1, pose
                    value, then = pose["value"], poses[k - 1]
                    assert set(value) == {"x", "y", "theta", "v", "w"}, pose
                    assert (value["x"], value["y"]) == (then.x, then.y), (pose, then)
                    assert abs(math.remainder(value["theta"] - then.theta, 2 * math.pi)) < 1e-9
                    assert query("floor")["value"] == then.floor == -1
                    walking = query("truth.people")
                    assert walking["cycle"] == k - 1, walking
                    assert walking["value"] == {
                        "x": [x for _, x, _ in people[k - 1]],
                        "y": [y for _, _, y in people[k - 1]],
                        "floor": [f for f, _, _ in people[k - 1]],
                    }, (walking, people[k - 1])
                    shown = query("truth.cars")["value"]
                    assert shown == {
                        "floor": [c.position for c in cars[k - 1]],
                        "door": [c.door for c in cars[k - 1]],
                    }, (shown, cars[k - 1])
                assert not watch.problems, watch.problems
            finally:
                node.close()
                peer.close()
                watcher.close()
        # The robot drove, and truth.pose followed it; people walked, on several floors.
        assert math.dist((poses[-1].x, poses[-1].y), (poses[0].x, poses[0].y)) > 0.3, poses
        assert people[-1] != people[0], people
        assert len({f for f, _, _ in people[0]}) > 1, people[0]
        assert len(cars[0]) == len(Building.load(REPO / "maps" / "default.yaml").cars) > 1
    finally:
        err = robot.stop()
    assert "panicked" not in err, err
