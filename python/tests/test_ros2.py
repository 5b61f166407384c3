"""The ROS 2 bridge, checked with a CDR library it does not share: `rosbags`.

The toy robot with its bridge (`situate_ros2`'s `ros2_toybot` example, built with cargo) serves on
a free port; this test reads its liveliness tokens and messages over a real Zenoh session, checks
them against rmw_zenoh's documented format (docs/ros2.md), and decodes every payload with
`rosbags`' ROS 2 Jazzy type definitions, whose RIHS01 hashes must be the ones in the keys.
"""

from __future__ import annotations

import json
import os
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh
from rosbags.typesys import Stores, get_typestore
from support import REPO, STARTUP_S, free_port
from zenoh.ext import Int64, z_deserialize

TYPES = {
    "cmd_vel": "geometry_msgs/msg/Twist",
    "odom": "nav_msgs/msg/Odometry",
    "sonar": "sensor_msgs/msg/LaserScan",
}
QOS = "::,10:,:,:,,"


def dds_name(ros_type: str) -> str:
    package, _, name = ros_type.split("/")
    return f"{package}::msg::dds_::{name}_"


def build_example() -> Path:
    """Builds the example with cargo and returns its executable (cargo says where it is)."""
    out = subprocess.run(
        [
            "cargo",
            "build",
            "-q",
            "-p",
            "situate_ros2",
            "--example",
            "ros2_toybot",
            "--message-format=json",
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=1800,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    for line in out.stdout.splitlines():
        msg = json.loads(line)
        if (
            msg.get("reason") == "compiler-artifact"
            and msg.get("executable")
            and msg["target"]["name"] == "ros2_toybot"
        ):
            return Path(msg["executable"])
    pytest.fail(f"cargo named no ros2_toybot executable: {out.stdout[-2000:]}")


@pytest.fixture(scope="module")
def toybot() -> Iterator[str]:
    """The toy robot with its bridge, on a free port; yields its endpoint."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    env = dict(os.environ)
    env.setdefault("RUST_LOG", "warn,zenoh=error")
    proc = subprocess.Popen(
        [str(build_example()), "--listen", endpoint],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    assert proc.stdout is not None
    ready: list[str] = []
    reader = threading.Thread(
        target=lambda: ready.append(proc.stdout.readline() if proc.stdout else "")
    )
    reader.start()
    reader.join(STARTUP_S)
    assert ready, "the robot did not start"
    assert ready[0].startswith("ready "), f"the robot did not start: {ready}"
    yield endpoint
    assert proc.stdin is not None
    proc.stdin.close()
    try:
        assert proc.wait(STARTUP_S) == 0
    finally:
        if proc.poll() is None:
            proc.kill()


def session(endpoint: str) -> zenoh.Session:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


def tokens(s: zenoh.Session) -> list[str]:
    keys = []
    for reply in s.liveliness().get("@ros2_lv/0/**"):
        if reply.ok is not None:
            keys.append(str(reply.ok.key_expr))
    return sorted(keys)


def test_rosbags_decodes_what_the_bridge_publishes_on_rmw_zenoh_keys(toybot: str) -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    with session(toybot) as s:
        zid = None
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline:
            found = tokens(s)
            if len(found) == 4:
                break
            time.sleep(0.05)
        assert len(found) == 4, found
        node = [k for k in found if "/NN/" in k]
        assert len(node) == 1, found
        parts = node[0].split("/")
        zid = parts[2]
        assert node[0] == f"@ros2_lv/0/{zid}/0/0/NN/%/%/toybot"
        for i, (topic, ros_type) in enumerate(TYPES.items(), start=1):
            token = (
                f"@ros2_lv/0/{zid}/0/{i}/MP/%/%/toybot/%{topic}/{dds_name(ros_type)}/"
                f"{store.hash_rihs01(ros_type)}/{QOS}"
            )
            assert token in found, (token, found)

        keys = {f"0/{t}/{dds_name(ty)}/{store.hash_rihs01(ty)}": t for t, ty in TYPES.items()}
        got: dict[str, list[tuple[int, int, bytes, Any]]] = {t: [] for t in TYPES}
        lock = threading.Lock()

        def on_sample(sample: zenoh.Sample) -> None:
            key = str(sample.key_expr)
            topic = keys.get(key)
            assert topic is not None, key
            payload = sample.payload.to_bytes()
            msg = store.deserialize_cdr(payload, TYPES[topic])
            assert sample.attachment is not None
            # Zenoh's serialization: two i64, then the 16-byte GID (its length as a varint).
            assert len(sample.attachment.to_bytes()) == 8 + 8 + 1 + 16
            sequence, stamp, gid = z_deserialize(tuple[Int64, Int64, bytes], sample.attachment)
            with lock:
                got[topic].append((int(sequence), int(stamp), gid, msg))

        sub = s.declare_subscriber("0/**", on_sample)
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline:
            with lock:
                if all(len(v) >= 3 for v in got.values()):
                    break
            time.sleep(0.05)
        sub.undeclare()
        with lock:
            assert all(len(v) >= 3 for v in got.values()), {t: len(v) for t, v in got.items()}
            results = {t: list(v) for t, v in got.items()}

    now_ns = time.time_ns()
    gids = set()
    for topic, puts in results.items():
        seqs = [p[0] for p in puts]
        assert seqs == list(range(seqs[0], seqs[0] + len(seqs))), (topic, seqs)
        assert len({p[2] for p in puts}) == 1, topic
        assert len(puts[0][2]) == 16, topic
        assert all(abs(now_ns - p[1]) < 600 * 10**9 for p in puts), topic
        gids.add(puts[0][2])
    assert len(gids) == 3

    twist = results["cmd_vel"][-1][3]
    assert twist.linear.y == 0.0
    assert twist.angular.x == 0.0
    odom = results["odom"][-1][3]
    assert odom.header.frame_id == "odom"
    assert odom.child_frame_id == "base_link"
    q = odom.pose.pose.orientation
    assert abs(q.z**2 + q.w**2 - 1.0) < 1e-9
    assert len(odom.pose.covariance) == 36
    scan = results["sonar"][-1][3]
    assert scan.header.frame_id == "base_link"
    assert len(scan.ranges) == 24
    assert scan.range_max == pytest.approx(4.0)
    assert all(0.0 < r <= 2.0 for r in scan.ranges), list(scan.ranges)
    assert scan.header.stamp.sec > 1_600_000_000
