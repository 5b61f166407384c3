"""ROS 2 topics in, end to end through `situate run`, with a CDR library situate does not share.

`examples/ros2/lidar_runaway.yaml` has no simulator: a ROS 2 lidar's `/scan` (here published from
Python as rmw_zenoh publishes: the key with the type's RIHS01 hash, the attachment with sequence
number, timestamp and GID, the payload CDR-encoded by `rosbags`) feeds the runaway toy, whose
`drive` goes back out as `/cmd_vel`, read and decoded by `rosbags` too. The hashes situate puts in
its keys and tokens are checked against `rosbags`' ROS 2 Jazzy definitions, every one of them; the
GID against XXH3-128 computed by the `xxhash` package (rmw_zenoh's `generate_gid`).
"""

from __future__ import annotations

import re
import threading
import time
from typing import Any

import numpy as np
import xxhash
import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from support import REPO, STARTUP_S, start_manager, zenoh_client
from zenoh.ext import Int64, z_serialize

STORE = get_typestore(Stores.ROS2_JAZZY)
# situate's own messages (ros2/situate_msgs), as a ROS 2 system that built the package has them.
for _msg in sorted((REPO / "ros2" / "situate_msgs" / "msg").glob("*.msg")):
    STORE.register(get_types_from_msg(_msg.read_text(), f"situate_msgs/msg/{_msg.stem}"))


def dds_name(ros_type: str) -> str:
    package, _, name = ros_type.split("/")
    return f"{package}::msg::dds_::{name}_"


def key(topic: str, ros_type: str) -> str:
    return f"0/{topic}/{dds_name(ros_type)}/{STORE.hash_rihs01(ros_type)}"


def gid(token: str) -> bytes:
    """rmw_zenoh's GID: XXH3-128 of the token, low 64 bits then high, each little endian."""
    return int(xxhash.xxh3_128_intdigest(token.encode())).to_bytes(16, "little")


def test_every_hash_situate_writes_is_the_one_ros_2_computes() -> None:
    msgs = (REPO / "crates/surfaces/situate_ros2/src/msgs.rs").read_text()
    names = dict(re.findall(r'MsgType::(\w+) => "(\w+/msg/\w+)"', msgs))
    hashes = dict(re.findall(r'MsgType::(\w+) => "(RIHS01_[0-9a-f]{64})"', msgs))
    assert len(names) >= 14, names
    assert names.keys() == hashes.keys(), (names, hashes)
    for variant, ros_type in names.items():
        assert hashes[variant] == STORE.hash_rihs01(ros_type), ros_type
    clock = (REPO / "crates/surfaces/situate_ros2/src/clock.rs").read_text()
    (clock_hash,) = re.findall(r'CLOCK_HASH: &str = "(RIHS01_[0-9a-f]{64})"', clock)
    assert clock_hash == STORE.hash_rihs01("rosgraph_msgs/msg/Clock")
    # The one hash rmw_zenoh's design document prints, from a real system.
    assert STORE.hash_rihs01("std_msgs/msg/String") == (
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
    )


def scan(ahead_m: float, behind_m: float = 3.0) -> bytes:
    """360 rays from -π (behind), 3 m all round but `ahead_m` straight ahead and `behind_m`
    straight behind; encoded by rosbags."""
    t = STORE.types
    ranges = np.full(360, 3.0, dtype=np.float32)
    ranges[175:186] = ahead_m
    ranges[:6] = behind_m
    ranges[-5:] = behind_m
    msg = t["sensor_msgs/msg/LaserScan"](
        header=t["std_msgs/msg/Header"](
            stamp=t["builtin_interfaces/msg/Time"](sec=1, nanosec=0), frame_id="laser"
        ),
        angle_min=-np.pi,
        angle_max=np.pi,
        angle_increment=2 * np.pi / 360,
        time_increment=0.0,
        scan_time=0.1,
        range_min=0.05,
        range_max=10.0,
        ranges=ranges,
        intensities=np.zeros(0, dtype=np.float32),
    )
    return bytes(STORE.serialize_cdr(msg, "sensor_msgs/msg/LaserScan"))


def test_a_ros_2_lidar_drives_the_runaway_and_its_command_comes_back_as_cmd_vel() -> None:
    robot = start_manager(REPO / "examples/ros2/lidar_runaway.yaml", "lidar_runaway")
    try:
        with zenoh_client(robot.endpoint) as s:
            # situate's subscription is discovered as rmw_zenoh's are: an MS token.
            deadline = time.monotonic() + STARTUP_S
            subs: list[str] = []
            while time.monotonic() < deadline and not subs:
                subs = [
                    str(r.ok.key_expr)
                    for r in s.liveliness().get("@ros2_lv/0/**")
                    if r.ok is not None and "/MS/" in str(r.ok.key_expr)
                ]
                time.sleep(0.05)
            assert len(subs) == 1, subs
            laser = "sensor_msgs/msg/LaserScan"
            assert subs[0].endswith(
                f"/MS/%/%/lidar_runaway/%scan/{dds_name(laser)}/{STORE.hash_rihs01(laser)}/"
                "::,10:,:,:,,"
            ), subs

            twists: list[Any] = []
            lock = threading.Lock()

            def on_cmd(sample: zenoh.Sample) -> None:
                msg = STORE.deserialize_cdr(sample.payload.to_bytes(), "geometry_msgs/msg/Twist")
                with lock:
                    twists.append(msg)

            cmd = s.declare_subscriber(key("cmd_vel", "geometry_msgs/msg/Twist"), on_cmd)
            token = "@ros2_lv/0/peer/0/1/MP/%/%/lidar/%scan"
            publisher = s.declare_publisher(key("scan", laser))
            payload = scan(0.3)
            sequence = 0
            backing_off = False
            deadline = time.monotonic() + STARTUP_S
            while time.monotonic() < deadline and not backing_off:
                sequence += 1
                attachment = z_serialize((Int64(sequence), Int64(time.time_ns()), gid(token)))
                publisher.put(payload, attachment=attachment)
                time.sleep(0.05)
                with lock:
                    backing_off = any(t.linear.x < 0 for t in twists)
            # An obstacle 0.3 m ahead: the runaway backs off and turns (toy.runaway).
            assert backing_off, twists[-5:]
            with lock:
                last = next(t for t in reversed(twists) if t.linear.x < 0)
            assert last.linear.x == -0.3, last
            assert abs(last.angular.z) == 1.0, last

            # A message of another type on /scan: ignored, and reported once, naming the
            # publisher by the GID rmw_zenoh derives from its token (XXH3-128, as computed here
            # by `xxhash`). Then an obstacle behind: the runaway drives forward. One subscription
            # reads both in order, so once it drives forward the report has been made.
            wrong = s.declare_publisher(key("scan", "std_msgs/msg/Float64"))
            float64 = STORE.types["std_msgs/msg/Float64"](data=1.0)
            wrong.put(
                bytes(STORE.serialize_cdr(float64, "std_msgs/msg/Float64")),
                attachment=z_serialize((Int64(1), Int64(0), gid(token))),
            )
            behind = scan(3.0, behind_m=0.3)
            forward = False
            deadline = time.monotonic() + STARTUP_S
            while time.monotonic() < deadline and not forward:
                sequence += 1
                attachment = z_serialize((Int64(sequence), Int64(time.time_ns()), gid(token)))
                publisher.put(behind, attachment=attachment)
                time.sleep(0.05)
                with lock:
                    forward = any(t.linear.x > 0 for t in twists)
            cmd.undeclare()  # type: ignore[no-untyped-call]
            assert forward, twists[-5:]
    finally:
        err = robot.stop()
    assert "panicked" not in err, err
    reports = [line for line in err.splitlines() if "std_msgs/msg/Float64" in line]
    assert len(reports) == 1, err
    assert "expected sensor_msgs/msg/LaserScan" in reports[0], reports
    assert gid(token).hex() in reports[0], (gid(token).hex(), reports)
