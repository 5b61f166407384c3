"""The ROS 2 bridge, checked with a CDR library it does not share: `rosbags`.

The toy robot with its bridge (`situate_ros2`'s `ros2_toybot` example, built with cargo) serves on
a free port; this test reads its liveliness tokens and messages over a real Zenoh session, checks
them against rmw_zenoh's documented format (docs/ros2.md), and decodes every payload with
`rosbags`' ROS 2 Jazzy type definitions, whose RIHS01 hashes must be the ones in the keys. It
calls the bridge's services as an rmw_zenoh client does: a Zenoh get on the service's key, the
request CDR-encoded by `rosbags`, with the client's attachment.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zenoh
from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from support import PORT_TRIES, REPO, STARTUP_S, free_port, zenoh_client
from zenoh.ext import Int64, z_deserialize, z_serialize

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
            # The whole workspace's features, as `cargo test --workspace` built them: its
            # build is reused (`-p` alone would unify fewer features and rebuild much of it).
            "--workspace",
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
    """The toy robot with its bridge, on a free port; yields its endpoint.

    A port `free_port` chose can be taken before the robot listens on it (another test picked
    it too): the robot then exits saying "Address already in use", and another port is tried,
    as `start_manager` does (`PORT_TRIES`).
    """
    env = dict(os.environ)
    env.setdefault("RUST_LOG", "warn,zenoh=error")
    for _ in range(PORT_TRIES):
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        # Its log in a file, never a pipe nobody reads while it runs.
        with tempfile.TemporaryFile(mode="w+") as log:
            proc = subprocess.Popen(
                [str(build_example()), "--listen", endpoint],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=log,
                text=True,
                env=env,
            )
            assert proc.stdout is not None
            ready: list[str] = []
            reader = threading.Thread(
                target=lambda p=proc, r=ready: r.append(p.stdout.readline() if p.stdout else "")
            )
            reader.start()
            reader.join(STARTUP_S)
            if ready and ready[0].startswith("ready "):
                break
            if proc.poll() is None:
                proc.kill()
            proc.wait(STARTUP_S)
            log.seek(0)
            err = log.read()
            if "Address already in use" in err:
                continue
            pytest.fail(f"the robot did not start: {ready}\n{err}")
    else:
        pytest.fail(f"the robot found no free port in {PORT_TRIES} tries")
    yield endpoint
    assert proc.stdin is not None
    proc.stdin.close()
    try:
        assert proc.wait(STARTUP_S) == 0
    finally:
        if proc.poll() is None:
            proc.kill()


def tokens(s: zenoh.Session) -> list[str]:
    keys = []
    for reply in s.liveliness().get("@ros2_lv/0/**"):
        if reply.ok is not None:
            keys.append(str(reply.ok.key_expr))
    return sorted(keys)


def test_rosbags_decodes_what_the_bridge_publishes_on_rmw_zenoh_keys(toybot: str) -> None:
    store = get_typestore(Stores.ROS2_JAZZY)
    with zenoh_client(toybot) as s:
        zid = None
        deadline = time.monotonic() + STARTUP_S
        while time.monotonic() < deadline:
            found = [k for k in tokens(s) if "/SS/" not in k]
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
        sub.undeclare()  # type: ignore[no-untyped-call]
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


# ----- services ---------------------------------------------------------------------------------

SERVICES = {
    "std_srvs/srv/SetBool": ("bool data\n", "bool success\nstring message\n"),
    "rcl_interfaces/srv/GetParameters": (
        "string[] names\n",
        "rcl_interfaces/msg/ParameterValue[] values\n",
    ),
    "rcl_interfaces/srv/SetParameters": (
        "rcl_interfaces/msg/Parameter[] parameters\n",
        "rcl_interfaces/msg/SetParametersResult[] results\n",
    ),
    "rcl_interfaces/srv/ListParameters": (
        "string[] prefixes\nuint64 depth\n",
        "rcl_interfaces/msg/ListParametersResult result\n",
    ),
    "rcl_interfaces/srv/DescribeParameters": (
        "string[] names\n",
        "rcl_interfaces/msg/ParameterDescriptor[] descriptors\n",
    ),
    "rcl_interfaces/srv/GetParameterTypes": ("string[] names\n", "uint8[] types\n"),
}


def _unmangle(x: Any) -> Any:
    """rosbags writes a type `pkg/srv/Name` as `pkg/srv/msg/Name`: back to the ROS 2 name."""
    if isinstance(x, str):
        return x.replace("/srv/msg/", "/srv/")
    if isinstance(x, (list, tuple)):
        return type(x)(_unmangle(y) for y in x)
    return x


def service_store() -> Any:
    """rosbags' ROS 2 Jazzy types, with each service's request, response and event messages and
    its type description (request_message, response_message, event_message), as rosidl makes
    them, so that `hash_rihs01(service)` is the service's RIHS01 hash."""
    store = get_typestore(Stores.ROS2_JAZZY)
    # service_msgs/msg/ServiceEventInfo's `char[16] client_gid`: ROS 2 reads `char` in a .msg as
    # uint8, rosbags as char; the hash needs ROS 2's reading.
    consts, fields = store.fielddefs["service_msgs/msg/ServiceEventInfo"]
    store.fielddefs["service_msgs/msg/ServiceEventInfo"] = (
        consts,
        [
            (n, (Nodetype.ARRAY, ((Nodetype.BASE, ("uint8", 0)), 16)) if n == "client_gid" else t)
            for n, t in fields
        ],
    )
    extra = dict(SERVICES)
    # Two services whose hashes were published (in rmw_zenoh key expressions of ROS 2 Jazzy
    # systems): they check the method.
    extra["std_srvs/srv/Trigger"] = ("", "bool success\nstring message\n")
    extra["example_interfaces/srv/SetBool"] = ("bool data\n", "bool success\nstring message\n")
    types: dict[str, Any] = {}
    for srv, (request, response) in extra.items():
        event = (
            f"service_msgs/msg/ServiceEventInfo info\n{srv}_Request[<=1] request\n"
            f"{srv}_Response[<=1] response\n"
        )
        whole = (
            f"{srv}_Request request_message\n{srv}_Response response_message\n"
            f"{srv}_Event event_message\n"
        )
        for name, text in [
            (f"{srv}_Request", request),
            (f"{srv}_Response", response),
            (f"{srv}_Event", event),
            (srv, whole),
        ]:
            for k, v in get_types_from_msg(text, name).items():
                types[_unmangle(k)] = _unmangle(v)
    store.register(types)
    return store


def test_service_hashes_are_computed_as_ros_2_computes_them() -> None:
    store = service_store()
    assert store.hash_rihs01("std_srvs/srv/Trigger") == (
        "RIHS01_eeff2cd6fa5ad9d27cdf4dec64818317839b62f212a91e6b5304b634b2062c5f"
    )
    assert store.hash_rihs01("example_interfaces/srv/SetBool") == (
        "RIHS01_a69782e5631b12e15c8e218410de1685bbf13e382718295adad14037a24afbe8"
    )


def srv_dds_name(ros_type: str) -> str:
    package, _, name = ros_type.split("/")
    return f"{package}::srv::dds_::{name}_"


class Client:
    """An rmw_zenoh service client: a get with the CDR request and the client's attachment."""

    def __init__(self, s: zenoh.Session, store: Any) -> None:
        self.s = s
        self.store = store
        self.gid = bytes(range(16))
        self.sequence = 0

    def key(self, service: str, srv: str) -> str:
        return f"0/{service}/{srv_dds_name(srv)}/{self.store.hash_rihs01(srv)}"

    def call(self, service: str, srv: str, **fields: Any) -> Any:
        request = self.store.types[f"{srv}_Request"](**fields)
        payload = bytes(self.store.serialize_cdr(request, f"{srv}_Request"))
        self.sequence += 1
        attachment = z_serialize((Int64(self.sequence), Int64(time.time_ns()), self.gid))
        replies = list(
            self.s.get(
                self.key(service, srv), payload=payload, attachment=attachment, timeout=STARTUP_S
            )
        )
        assert len(replies) == 1, replies
        reply = replies[0]
        assert reply.ok is not None, reply.err.payload.to_string() if reply.err else reply
        assert reply.ok.attachment is not None, "a reply without rmw_zenoh's attachment"
        sequence, _stamp, gid = z_deserialize(tuple[Int64, Int64, bytes], reply.ok.attachment)
        assert (int(sequence), gid) == (self.sequence, self.gid), "the reply names another request"
        return self.store.deserialize_cdr(reply.ok.payload.to_bytes(), f"{srv}_Response")


def param(store: Any, kind: int, **value: Any) -> Any:
    fields: dict[str, Any] = {
        "type": kind,
        "bool_value": False,
        "integer_value": 0,
        "double_value": 0.0,
        "string_value": "",
        # rosbags takes arrays of numbers as numpy arrays.
        "byte_array_value": np.array([], dtype=np.uint8),
        "bool_array_value": np.array([], dtype=np.bool_),
        "integer_array_value": np.array([], dtype=np.int64),
        "double_array_value": np.array([], dtype=np.float64),
        "string_array_value": [],
    }
    fields.update(value)
    return store.types["rcl_interfaces/msg/ParameterValue"](**fields)


def test_activation_and_parameters_are_ros_2_services(toybot: str) -> None:
    import asyncio

    import situate

    store = service_store()
    with zenoh_client(toybot) as s:
        deadline = time.monotonic() + STARTUP_S
        found: list[str] = []
        while time.monotonic() < deadline:
            found = [k for k in tokens(s) if "/SS/" in k]
            if len(found) == 4 + 5:
                break
            time.sleep(0.05)
        zid = found[0].split("/")[2] if found else "?"
        expected = {
            # Every skill, devices too: a dskill has its activation switch as well.
            "toybot/sonar/set_active": "std_srvs/srv/SetBool",
            "toybot/wheels/set_active": "std_srvs/srv/SetBool",
            "toybot/runaway/set_active": "std_srvs/srv/SetBool",
            "toybot/wander/set_active": "std_srvs/srv/SetBool",
            "toybot/get_parameters": "rcl_interfaces/srv/GetParameters",
            "toybot/set_parameters": "rcl_interfaces/srv/SetParameters",
            "toybot/list_parameters": "rcl_interfaces/srv/ListParameters",
            "toybot/describe_parameters": "rcl_interfaces/srv/DescribeParameters",
            "toybot/get_parameter_types": "rcl_interfaces/srv/GetParameterTypes",
        }
        for service, srv in expected.items():
            mangled = "%" + service.replace("/", "%")
            token_tail = (
                f"/SS/%/%/toybot/{mangled}/{srv_dds_name(srv)}/{store.hash_rihs01(srv)}/{QOS}"
            )
            assert any(
                k.startswith(f"@ros2_lv/0/{zid}/0/") and k.endswith(token_tail) for k in found
            ), (token_tail, found)
        assert len(found) == len(expected), found

        c = Client(s, store)
        listed = c.call(
            "toybot/list_parameters", "rcl_interfaces/srv/ListParameters", prefixes=[], depth=0
        )
        names = sorted(listed.result.names)

        async def link_params() -> list[str]:
            async with situate.connect("toybot", endpoint=toybot) as robot:
                skills = await robot.skills()
                return sorted(f"{k.name}.{p.name}" for k in skills for p in k.params)

        # The same parameters the link lists, devices' too.
        assert names == asyncio.run(link_params()), names
        assert {"runaway.safe_distance", "wander.speed", "wander.seed"} <= set(names), names
        assert {"runaway", "wander", "sonar"} <= set(listed.result.prefixes)

        types = c.call(
            "toybot/get_parameter_types",
            "rcl_interfaces/srv/GetParameterTypes",
            names=["wander.speed", "wander.seed", "nope"],
        )
        assert list(types.types) == [3, 2, 0]  # double, integer, not set

        described = c.call(
            "toybot/describe_parameters",
            "rcl_interfaces/srv/DescribeParameters",
            names=["runaway.safe_distance"],
        )
        d = described.descriptors[0]
        assert (d.name, d.type) == ("runaway.safe_distance", 3)
        assert "run away" in d.description, d
        assert d.additional_constraints == "unit: m", d
        r = d.floating_point_range[0]
        assert (r.from_value, r.to_value) == (0.1, 3.0)

        set_ok = c.call(
            "toybot/set_parameters",
            "rcl_interfaces/srv/SetParameters",
            parameters=[
                store.types["rcl_interfaces/msg/Parameter"](
                    name="wander.speed", value=param(store, 3, double_value=0.35)
                ),
                # An integer for a double is taken, as `ros2 param set … 1` sends one.
                store.types["rcl_interfaces/msg/Parameter"](
                    name="runaway.speed", value=param(store, 2, integer_value=1)
                ),
                store.types["rcl_interfaces/msg/Parameter"](
                    name="wander.seed", value=param(store, 4, string_value="x")
                ),
                store.types["rcl_interfaces/msg/Parameter"](
                    name="runaway.safe_distance", value=param(store, 3, double_value=99.0)
                ),
                store.types["rcl_interfaces/msg/Parameter"](
                    name="nope.x", value=param(store, 3, double_value=1.0)
                ),
            ],
        )
        results = [(x.successful, x.reason) for x in set_ok.results]
        assert results[0] == (True, ""), results
        assert results[1] == (True, ""), results
        assert results[2][0] is False, results
        assert "wander.seed" in results[2][1], results
        assert results[3][0] is False, results
        assert "99" in results[3][1], results
        assert results[4][0] is False, results
        assert "nope.x" in results[4][1], results

        got = c.call(
            "toybot/get_parameters",
            "rcl_interfaces/srv/GetParameters",
            names=["wander.speed", "runaway.speed", "wander.seed", "nope"],
        )
        values = [(v.type, v.double_value, v.integer_value) for v in got.values]
        assert values == [(3, 0.35, 0), (3, 1.0, 0), (2, 0.0, 1), (0, 0.0, 0)], values

        off = c.call("toybot/wander/set_active", "std_srvs/srv/SetBool", data=False)
        assert off.success, off.message

        async def wander_active() -> bool:
            async with situate.connect("toybot", endpoint=toybot) as robot:
                return (await robot.skill("wander")).active

        assert asyncio.run(wander_active()) is False
        on = c.call("toybot/wander/set_active", "std_srvs/srv/SetBool", data=True)
        assert on.success, on.message
        assert asyncio.run(wander_active()) is True

        # A request that is no SetBool request: refused in the response (a ROS 2 client shows
        # its message), naming the type, nothing changed.
        replies = list(
            s.get(
                c.key("toybot/wander/set_active", "std_srvs/srv/SetBool"),
                payload=b"\x00\x01",
                timeout=STARTUP_S,
            )
        )
        assert len(replies) == 1, replies
        assert replies[0].ok is not None, replies
        refused = store.deserialize_cdr(
            replies[0].ok.payload.to_bytes(), "std_srvs/srv/SetBool_Response"
        )
        assert refused.success is False, refused
        assert "std_srvs/srv/SetBool" in refused.message, refused
        assert asyncio.run(wander_active()) is True
