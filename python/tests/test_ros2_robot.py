"""A ROS 2 robot is a situate robot: the toy skills drive a ROS 2 base through topics alone.

The robot on the other side is `ros2_base.DiffDriveBase`, a kinematic differential-drive base in
a 6 m by 4 m room speaking rmw_zenoh exactly (checked in test_ros2_peer.py against rmw_zenoh and
captures of real ROS 2 systems): it takes `/cmd_vel` and publishes `/scan`, `/odom`, `/tf` and
`/clock`. situate runs no simulator: its `sonar.range` and `odom` come from `/scan` and `/odom`
(topics in), its `drive` goes out as `/cmd_vel`, and with `use_sim_time` its cycle follows the
base's `/clock`: one cycle per tick of the base, exactly.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from pathlib import Path

from ros2_base import DiffDriveBase, Pose
from support import STARTUP_S, situate, start_manager, zenoh_client

from situate.ros2 import Ros2Peer

ROBOT = """\
robot: rosbot
cycle: {rate_hz: 20, clock: simulated}
skills:
  - {name: runaway, type: toy.runaway, params: {safe_distance: 0.6}}
  - {name: wander, type: toy.wander, params: {speed: 0.3, seed: 3}}
ros2:
  use_sim_time: true
  topics:
    - {topic: /scan, type: sensor_msgs/msg/LaserScan, signal: sonar.range, direction: in, ring: 24}
    - {topic: /odom, type: nav_msgs/msg/Odometry, signal: odom, direction: in}
    - {signal: drive, topic: /cmd_vel, type: geometry_msgs/msg/Twist}
"""


def wait_until(cond: Callable[[], bool], what: str) -> None:
    deadline = time.monotonic() + 3 * STARTUP_S
    while not cond():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


def test_the_toy_skills_drive_a_ros_2_base_on_its_own_clock(tmp_path: Path) -> None:
    robot_file = tmp_path / "rosbot.yaml"
    robot_file.write_text(ROBOT)
    robot = start_manager(robot_file, "rosbot")
    connect = robot.connect_args

    def stats() -> dict[str, float]:
        out = situate("stats", *connect, "--json")
        assert out.returncode == 0, out.stderr
        result: dict[str, float] = json.loads(out.stdout)
        return result

    def query(signal: str) -> object:
        out = situate("query", signal, *connect, "--json")
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout)

    try:
        with zenoh_client(robot.endpoint) as s:
            peer = Ros2Peer(s, node="base")
            base = DiffDriveBase(peer, rate_hz=20, sim_time=True, start=Pose(3.0, 2.0, 0.0))
            try:
                # situate's /clock subscription is known here (its MS token) before the base's
                # first tick, so that tick's clock (ROS time 50 ms) is situate's time 0.
                wait_until(
                    lambda: any("/MS/" in k and "/%clock/" in k for k in peer.graph()),
                    "situate's /clock subscription",
                )
                # The robot waits for ROS time: no cycle before the base's clock runs.
                assert stats()["cycle"] == 0
                base.start()
                # The wander skill's commands reach the base, and the base moves.
                wait_until(lambda: base.commands_received > 20, "commands reach the base")
                start = base.pose()
                wait_until(
                    lambda: math.dist((base.pose().x, base.pose().y), (start.x, start.y)) > 0.5,
                    "the base moves half a metre",
                )
                # situate's odom is the base's /odom.
                odom = query("odom")
                assert isinstance(odom, dict), odom
                value = odom.get("value", odom)
                assert isinstance(value, dict), odom
                assert 0.1 < float(value["x"]) < 5.9, odom
                base.stop()

                # The clock stopped. Tick k said ROS time k·50 ms, tick 1 was time 0: after k
                # ticks the robot has run k - 1 cycles, none skipped, none doubled; and so after
                # ten more ticks made by hand. The last /clock is sent again while waiting, as a
                # paused simulator does (a keep-last /clock may be dropped under load, and no
                # later one supersedes it); the same time again runs no cycle.
                def caught_up() -> bool:
                    base.publish_clock()
                    return bool(stats()["cycle"] >= base.ticks - 1)

                wait_until(caught_up, "a cycle per tick")
                assert stats()["cycle"] == base.ticks - 1, "one cycle per tick: none doubled"
                base.step(10)
                wait_until(caught_up, "ten ticks, ten cycles")
                assert stats()["cycle"] == base.ticks - 1, "one cycle per tick: none doubled"
                assert abs(stats()["time_s"] - (base.ticks - 1) * 0.05) < 1e-6
            finally:
                base.close()
                peer.close()
    finally:
        err = robot.stop()
    assert "panicked" not in err, err
