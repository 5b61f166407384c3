"""A ROS 2 node in Python that speaks rmw_zenoh on a Zenoh session, with no ROS 2 installed.

It publishes and subscribes exactly as a ROS 2 program on `rmw_zenoh_cpp` (Jazzy, Kilted) does.
The physics robot (`situate.physics`) is such a node, and the tests' ROS 2 robots
(python/tests/ros2_base.py's kinematic `DiffDriveBase`) are built on it, so situate's ROS 2 side
is tried against "a robot" without ROS 2. `Ros2Peer` is one ROS 2 node; `Publisher` and
`Subscription` its entities. It needs the `physics` extra (``pip install 'situate[physics]'``:
`rosbags` and `xxhash`).

Messages are encoded and decoded with `rosbags`' ROS 2 Jazzy type store, and the type hashes in
keys and tokens are its RIHS01 hashes (`Typestore.hash_rihs01`).

What it does, and where that was checked: ros2/rmw_zenoh's sources, read at these commits of
rolling (2025): docs/design.md 99a6a2bd, rmw_zenoh_cpp/src/detail/liveliness_utils.cpp 3411fdec,
qos.cpp 5e10d47b, attachment_helpers.cpp 534747dc, rmw_publisher_data.cpp 3e19ec73; the tests in
test_ros2_peer.py check the results against values captured from real systems:

- **Data key** (`TopicInfo`, rmw_zenoh_cpp/src/detail/liveliness_utils.cpp; docs/design.md
  "Topic and Service name mapping"): ``<domain>/<fully qualified name, one leading and one
  trailing slash stripped>/<pkg>::msg::dds_::<Name>_/RIHS01_<hex>``.
- **Payload**: CDR, little endian, behind the encapsulation header ``00 01 00 00``.
- **Attachment** (rmw_zenoh_cpp/src/detail/attachment_helpers.cpp, since rmw_zenoh 0.2.4 on Jazzy
  and 0.6.0 on Rolling, PR #601/#605; docs/design.md "Publishers"): zenoh-ext serialization of
  the sequence number (i64, from 1, one more per put: rmw_publisher_data.cpp), the source
  timestamp (i64, ns since the Unix epoch) and the GID (``std::array<uint8_t, 16>``: its length
  16 as a varint, then the bytes): 33 bytes. Before 0.2.4 rmw_zenoh on Jazzy sent another layout
  (named fields), which this double does not speak.
- **GID** (`Entity::Entity`, liveliness_utils.cpp): XXH3-128 of the entity's whole liveliness
  token, ``low64`` then ``high64``, each copied with memcpy (little endian on every platform ROS 2
  runs on). That is `xxhash.xxh3_128_digest(token)` reversed.
- **Liveliness tokens** (`Entity::Entity`; docs/design.md "Graph Cache"):
  ``@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<NN|MP|MS|SS|SC>/<enclave>/<namespace>/<node>``
  and, for all but nodes, ``/<topic>/<dds type>/<type hash>/<qos>``; enclave, namespace and topic
  have every ``/`` written ``%`` (the root namespace ``/`` is ``%``, the fully qualified topic
  ``/chatter`` is ``%chatter``). A node's token has its node id twice. Ids count up from 0 in the
  session (context): a node takes one, then each of its entities the next.
- **QoS** (`qos_to_keyexpr`, liveliness_utils.cpp, with `QoS::best_available_qos` and the defaults
  of rmw_zenoh_cpp/src/detail/qos.cpp): ``<reliability>:<durability>:<history>,<depth>:<deadline
  s>,<ns>:<lifespan s>,<ns>:<liveliness>,<lease s>,<ns>``, each field the rmw enum value or
  number, empty when it equals rmw_zenoh's default: reliable, volatile (since rmw_zenoh PR #492,
  March 2025: before, transient local), keep last, depth **42**, infinite durations, automatic
  liveliness. So rclcpp's default QoS (depth 10) is ``::,10:,:,:,,``, the sensor-data QoS (best
  effort, depth 5) ``2::,5:,:,:,,``, tf2's broadcaster (depth 100) ``::,100:,:,:,,``, rosout
  (transient local, depth 1000, lifespan 10 s) ``:1:,1000:,:10,0:,,``.
- A publisher is declared before its token, a subscriber before its token, as rmw_zenoh does
  (rmw_publisher_data.cpp, rmw_subscription_data.cpp); congestion control is drop, or block for
  reliable keep-all; reliability best effort or reliable as the QoS says.

Not done: transient-local durability (rmw_zenoh uses zenoh-ext's advanced publisher and
subscriber with a cache for it), services, actions, type description services.
"""

from __future__ import annotations

import itertools
import math
import struct
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np
import xxhash
import zenoh
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from zenoh.ext import Int64, z_serialize

ADMIN_SPACE = "@ros2_lv"
ATTACHMENT_LEN = 8 + 8 + 1 + 16
GID_LEN = 16

_STORE: Any = None
_STORE_LOCK = threading.Lock()


#: situate's own messages: the package `ros2/situate_msgs` of the repository, for a ROS 2 system
#: to build (python/tests/test_physics_ros2.py checks these are its files).
SITUATE_MSGS = {
    "situate_msgs/msg/Barcodes": """\
# The barcodes a reader sees now: situate's `barcodes` signal (docs/robot-signals.md), one entry
# per barcode within the reader's range and field of view, facing it and in line of sight,
# nearest first. The three arrays have one element per barcode.
std_msgs/Header header

# The barcodes' ids.
int64[] ids
# Where each is, rad, counter-clockwise from ahead (the base's x axis).
float64[] bearing
# How far each is from the base's centre, m.
float64[] distance
""",
    "situate_msgs/msg/People": """\
# The people walking in a simulated building now: situate's `truth.people` signal
# (docs/robot-signals.md), a simulator's ground truth for displays and tests (no skill reads it).
# The three arrays have one element per person.
std_msgs/Header header

# Where each person stands, m, in the building's frame (the map's).
float64[] x
float64[] y
# The floor each is on (the map's level).
int64[] floor
""",
    "situate_msgs/msg/Cars": """\
# The elevator's cars now: situate's `truth.cars` signal (docs/robot-signals.md), a simulator's
# ground truth for displays and tests (no skill reads it). The two arrays have one element per
# car, in the map's order.
std_msgs/Header header

# Where each car is, in floors (the map's level; fractional while it moves).
float64[] floor
# How far each car's door is open: 0 closed, 1 open.
float64[] door
""",
}


def store() -> Any:
    """Returns rosbags' ROS 2 Jazzy type store, with `SITUATE_MSGS` (made once)."""
    global _STORE
    with _STORE_LOCK:
        if _STORE is None:
            s = get_typestore(Stores.ROS2_JAZZY)
            for name, text in SITUATE_MSGS.items():
                s.register(get_types_from_msg(text, name))
            _STORE = s
        return _STORE


def type_hash(ros_type: str) -> str:
    """Returns the RIHS01 hash of a ROS 2 type (``pkg/msg/Name``), as rosbags computes it."""
    value: str = store().hash_rihs01(ros_type)
    return value


def msg(ros_type: str, **fields: Any) -> Any:
    """Returns a message of a ROS 2 type, made with rosbags' class for it."""
    return store().types[ros_type](**fields)


def time_msg(stamp_ns: int) -> Any:
    """Returns a `builtin_interfaces/msg/Time` of ns since the epoch (of ROS time)."""
    return msg("builtin_interfaces/msg/Time", sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)


def header(stamp_ns: int, frame: str) -> Any:
    """Returns a `std_msgs/msg/Header`."""
    return msg("std_msgs/msg/Header", stamp=time_msg(stamp_ns), frame_id=frame)


def _yaw(theta: float) -> Any:
    return msg(
        "geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2)
    )


def odometry_msg(
    stamp_ns: int,
    odom_frame: str,
    base_frame: str,
    x: float,
    y: float,
    theta: float,
    v: float,
    w: float,
) -> Any:
    """Returns a planar base's `nav_msgs/msg/Odometry`.

    Its pose is (x, y, yaw), its twist (v, w); the covariances are 0 (unknown).
    """
    vec = "geometry_msgs/msg/Vector3"
    return msg(
        "nav_msgs/msg/Odometry",
        header=header(stamp_ns, odom_frame),
        child_frame_id=base_frame,
        pose=msg(
            "geometry_msgs/msg/PoseWithCovariance",
            pose=msg(
                "geometry_msgs/msg/Pose",
                position=msg("geometry_msgs/msg/Point", x=x, y=y, z=0.0),
                orientation=_yaw(theta),
            ),
            covariance=np.zeros(36, dtype=np.float64),
        ),
        twist=msg(
            "geometry_msgs/msg/TwistWithCovariance",
            twist=msg(
                "geometry_msgs/msg/Twist",
                linear=msg(vec, x=v, y=0.0, z=0.0),
                angular=msg(vec, x=0.0, y=0.0, z=w),
            ),
            covariance=np.zeros(36, dtype=np.float64),
        ),
    )


def tf_msg(stamp_ns: int, parent: str, child: str, x: float, y: float, theta: float) -> Any:
    """Returns a `tf2_msgs/msg/TFMessage` of one planar transform `parent` → `child`."""
    return msg(
        "tf2_msgs/msg/TFMessage",
        transforms=[
            msg(
                "geometry_msgs/msg/TransformStamped",
                header=header(stamp_ns, parent),
                child_frame_id=child,
                transform=msg(
                    "geometry_msgs/msg/Transform",
                    translation=msg("geometry_msgs/msg/Vector3", x=x, y=y, z=0.0),
                    rotation=_yaw(theta),
                ),
            )
        ],
    )


# ----- names, keys, tokens ----------------------------------------------------------------------


def dds_name(ros_type: str) -> str:
    """Returns the DDS name of a ROS 2 type: ``pkg/msg/Name`` → ``pkg::msg::dds_::Name_``."""
    parts = ros_type.split("/")
    if len(parts) != 3 or parts[1] not in ("msg", "srv", "action") or not all(parts):
        raise ValueError(f"not a ROS 2 type name (pkg/msg/Name): {ros_type!r}")
    package, kind, name = parts
    return f"{package}::{kind}::dds_::{name}_"


def mangle(name: str) -> str:
    """Returns a name with every ``/`` written ``%``, as in a liveliness token."""
    return name.replace("/", "%")


def _strip_slashes(name: str) -> str:
    """rmw_zenoh's `strip_slashes`: one leading and one trailing slash off."""
    start = 1 if name.startswith("/") else 0
    end = len(name) - 1 if name.endswith("/") else len(name)
    return name[start:end]


def data_key(domain_id: int, topic: str, ros_type: str, hash_: str | None = None) -> str:
    """Returns the key expression of a topic's data: ``<domain>/<topic>/<dds type>/<hash>``.

    `topic` is fully qualified (``/robot1/cmd_vel``); `hash_` defaults to rosbags' RIHS01 hash.
    """
    if hash_ is None:
        hash_ = type_hash(ros_type)
    return f"{domain_id}/{_strip_slashes(topic)}/{dds_name(ros_type)}/{hash_}"


class Reliability(IntEnum):
    """rmw_qos_reliability_policy_e (rmw/types.h)."""

    RELIABLE = 1
    BEST_EFFORT = 2


class Durability(IntEnum):
    """rmw_qos_durability_policy_e (rmw/types.h)."""

    TRANSIENT_LOCAL = 1
    VOLATILE = 2


class History(IntEnum):
    """rmw_qos_history_policy_e (rmw/types.h)."""

    KEEP_LAST = 1
    KEEP_ALL = 2


class Liveliness(IntEnum):
    """rmw_qos_liveliness_policy_e (rmw/types.h)."""

    AUTOMATIC = 1
    MANUAL_BY_TOPIC = 3


#: RMW_DURATION_INFINITE: {9223372036 s, 854775807 ns}, rmw_zenoh's default for the durations.
DURATION_INFINITE = (9223372036, 854775807)
#: rmw_zenoh's defaults (qos.cpp): a field equal to one is left empty in a token.
_ZENOH_DEFAULT_DEPTH = 42


@dataclass(frozen=True)
class Qos:
    """A ROS 2 QoS profile, as rmw_zenoh writes it in a token (after `best_available_qos`).

    Durations are ``(seconds, nanoseconds)``; None is the default (infinite). A depth of 0 is
    rmw_zenoh's default depth, 42.
    """

    reliability: Reliability = Reliability.RELIABLE
    durability: Durability = Durability.VOLATILE
    history: History = History.KEEP_LAST
    depth: int = 10
    deadline: tuple[int, int] | None = None
    lifespan: tuple[int, int] | None = None
    liveliness: Liveliness = Liveliness.AUTOMATIC
    lease: tuple[int, int] | None = None

    def keyexpr(self) -> str:
        """Returns the QoS as rmw_zenoh's `qos_to_keyexpr` writes it."""

        def one(value: int, default: int) -> str:
            return "" if value == default else str(value)

        def duration(value: tuple[int, int] | None) -> str:
            s, ns = DURATION_INFINITE if value is None else value
            return f"{one(s, DURATION_INFINITE[0])},{one(ns, DURATION_INFINITE[1])}"

        depth = self.depth if self.depth != 0 else _ZENOH_DEFAULT_DEPTH
        return (
            f"{one(self.reliability, Reliability.RELIABLE)}:"
            f"{one(self.durability, Durability.VOLATILE)}:"
            f"{one(self.history, History.KEEP_LAST)},{one(depth, _ZENOH_DEFAULT_DEPTH)}:"
            f"{duration(self.deadline)}:{duration(self.lifespan)}:"
            f"{one(self.liveliness, Liveliness.AUTOMATIC)},{duration(self.lease)}"
        )


#: rclcpp's default (`rclcpp::QoS(10)`): reliable, volatile, keep last 10.
QOS_DEFAULT = Qos()
#: `rclcpp::SensorDataQoS()` / rmw_qos_profile_sensor_data: best effort, volatile, keep last 5.
QOS_SENSOR_DATA = Qos(reliability=Reliability.BEST_EFFORT, depth=5)
#: tf2_ros's `DynamicBroadcasterQoS` / `DynamicListenerQoS`: reliable, volatile, keep last 100.
QOS_TF = Qos(depth=100)
#: `rclcpp::ClockQoS()`, what a node's time source subscribes to /clock with: best effort, 1.
QOS_CLOCK = Qos(reliability=Reliability.BEST_EFFORT, depth=1)


def token(
    kind: str,
    *,
    domain_id: int,
    zid: str,
    node_id: int,
    entity_id: int,
    namespace: str,
    node: str,
    enclave: str = "/",
    topic: str | None = None,
    ros_type: str | None = None,
    hash_: str | None = None,
    qos: Qos | None = None,
) -> str:
    """Returns an rmw_zenoh liveliness token.

    `kind` is NN (a node), MP (publisher), MS (subscription), SS (service server) or SC (service
    client); `namespace` and `topic` are fully qualified (``/`` is the root namespace).
    """
    if kind not in ("NN", "MP", "MS", "SS", "SC"):
        raise ValueError(f"unknown entity kind {kind!r}")
    parts = [
        ADMIN_SPACE,
        str(domain_id),
        zid,
        str(node_id),
        str(entity_id),
        kind,
        mangle(enclave or "/"),
        mangle(namespace or "/"),
        mangle(node),
    ]
    if kind == "NN":
        if topic is not None or ros_type is not None:
            raise ValueError("a node's token has no topic")
        return "/".join(parts)
    if topic is None or ros_type is None:
        raise ValueError(f"a {kind} token needs a topic and a type")
    if hash_ is None:
        hash_ = type_hash(ros_type)
    parts += [mangle(topic), dds_name(ros_type), hash_, (qos or QOS_DEFAULT).keyexpr()]
    return "/".join(parts)


def gid(token_key: str) -> bytes:
    """Returns the GID rmw_zenoh gives the entity of a liveliness token (16 bytes).

    XXH3-128 of the token: its low 64 bits then its high 64 bits, each little endian.
    """
    value = xxhash.xxh3_128_intdigest(token_key.encode())
    return struct.pack("<QQ", value & 0xFFFF_FFFF_FFFF_FFFF, value >> 64)


def attachment(seq: int, ts_ns: int, gid_: bytes) -> bytes:
    """Returns rmw_zenoh's attachment of a put: zenoh-ext serialization of (i64, i64, bytes)."""
    if len(gid_) != GID_LEN:
        raise ValueError(f"a GID has 16 bytes, not {len(gid_)}")
    out = z_serialize((Int64(seq), Int64(ts_ns), bytes(gid_))).to_bytes()
    if len(out) != ATTACHMENT_LEN:  # zenoh-ext's format changed: fail loudly, never send it
        raise AssertionError(f"zenoh-ext serialized the attachment in {len(out)} bytes")
    return out


def parse_attachment(data: bytes) -> tuple[int, int, bytes]:
    """Returns (sequence number, source timestamp in ns, GID) of an rmw_zenoh attachment.

    Raises:
        ValueError: when it is not exactly 33 bytes with the GID's length 16 at byte 16.
    """
    data = bytes(data)
    if len(data) != ATTACHMENT_LEN:
        raise ValueError(f"an rmw_zenoh attachment has {ATTACHMENT_LEN} bytes, not {len(data)}")
    if data[16] != GID_LEN:
        raise ValueError(f"the GID's length is {data[16]}, not 16")
    seq, ts = struct.unpack_from("<qq", data)
    return seq, ts, data[17:]


def resolve(name: str, namespace: str, node: str) -> str:
    """Returns the fully qualified name of a topic, as rcl expands it.

    A name starting with ``/`` is absolute, ``~`` is the node's private namespace, anything else is
    relative to the node's namespace.
    """
    ns = namespace if namespace.startswith("/") else "/" + namespace
    ns = ns.rstrip("/")
    if name.startswith("/"):
        full = name
    elif name == "~" or name.startswith("~/"):
        full = f"{ns}/{node}{name[1:]}"
    else:
        full = f"{ns}/{name}"
    if not name or "//" in full or full.endswith("/") or " " in full:
        raise ValueError(f"not a valid ROS 2 name: {name!r} (in {namespace!r})")
    return full


# ----- the peer ---------------------------------------------------------------------------------

_IDS: dict[str, Iterator[int]] = {}
_IDS_LOCK = threading.Lock()


def _next_id(zid: str) -> int:
    """The next entity id of a session: rmw_zenoh counts them per context, from 0."""
    with _IDS_LOCK:
        counter = _IDS.setdefault(zid, itertools.count())
        return next(counter)


@dataclass(frozen=True)
class Received:
    """One message a subscription took: the decoded message and the attachment's fields."""

    msg: Any
    seq: int
    ts_ns: int
    gid: bytes
    payload: bytes


class Publisher:
    """An rmw_zenoh publisher: a Zenoh publisher on the topic's key, and its MP token."""

    def __init__(self, peer: Ros2Peer, topic: str, ros_type: str, qos: Qos) -> None:
        if qos.durability != Durability.VOLATILE:
            raise NotImplementedError("transient-local publishers are not in this double")
        self.topic = resolve(topic, peer.namespace, peer.node)
        self.ros_type = ros_type
        self.qos = qos
        self.entity_id = _next_id(peer.zid)
        self.key = data_key(peer.domain_id, self.topic, ros_type)
        self.token = peer.entity_token("MP", self.entity_id, self.topic, ros_type, qos)
        self.gid = gid(self.token)
        self._lock = threading.Lock()
        self._seq = 1
        reliable = qos.reliability == Reliability.RELIABLE
        block = reliable and qos.history == History.KEEP_ALL
        self._pub = peer.session.declare_publisher(
            self.key,
            congestion_control=(
                zenoh.CongestionControl.BLOCK if block else zenoh.CongestionControl.DROP
            ),
            reliability=zenoh.Reliability.RELIABLE if reliable else zenoh.Reliability.BEST_EFFORT,
        )
        self._token = peer.session.liveliness().declare_token(self.token)
        self._closed = False

    @property
    def sequence(self) -> int:
        """The sequence number the next message gets."""
        with self._lock:
            return self._seq

    def publish(self, message: Any, *, ts_ns: int | None = None) -> int:
        """Publishes a message (a rosbags message of the publisher's type); returns its number."""
        payload = bytes(store().serialize_cdr(message, self.ros_type))
        return self.publish_raw(payload, ts_ns=ts_ns)

    def publish_raw(self, payload: bytes, *, ts_ns: int | None = None) -> int:
        """Publishes CDR bytes as they are, with the attachment; returns the sequence number."""
        with self._lock:
            if self._closed:
                raise RuntimeError(f"the publisher of {self.topic} is closed")
            seq = self._seq
            self._seq += 1
            stamp = time.time_ns() if ts_ns is None else ts_ns
            self._pub.put(payload, attachment=attachment(seq, stamp, self.gid))
        return seq

    def close(self) -> None:
        """Withdraws the token, then undeclares the publisher (as rmw_zenoh's shutdown)."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._token.undeclare()  # type: ignore[no-untyped-call]
        self._pub.undeclare()  # type: ignore[no-untyped-call]


class Subscription:
    """An rmw_zenoh subscription: a Zenoh subscriber on the topic's key, and its MS token.

    Every sample is checked as rmw_zenoh reads it (the 33-byte attachment, a sequence number that
    increases per publisher GID, a payload that decodes); a problem is recorded in `problems`,
    never raised on Zenoh's thread. The callback gets each decoded message; if it raises, that
    is recorded too.
    """

    def __init__(
        self,
        peer: Ros2Peer,
        topic: str,
        ros_type: str,
        callback: Callable[[Any], None] | None,
        qos: Qos,
        keep: int,
        ordered: bool = False,
    ) -> None:
        if qos.durability != Durability.VOLATILE:
            raise NotImplementedError("transient-local subscriptions are not in this double")
        self.topic = resolve(topic, peer.namespace, peer.node)
        self.ros_type = ros_type
        self.qos = qos
        self.entity_id = _next_id(peer.zid)
        self.key = data_key(peer.domain_id, self.topic, ros_type)
        self.token = peer.entity_token("MS", self.entity_id, self.topic, ros_type, qos)
        self.gid = gid(self.token)
        self._callback = callback
        self._keep = keep
        self._lock = threading.Lock()
        self._cond = threading.Condition(self._lock)
        self._received: list[Received] = []
        self._count = 0
        self._problems: list[str] = []
        self._last_seq: dict[bytes, int] = {}
        # `ordered`: the callback runs on Zenoh's thread as each sample arrives, so the ordered
        # subscriptions of a session see one publisher session's puts in the order they were
        # made; by default zenoh-python runs each subscription's callbacks on a thread of its own.
        handler: Any = (
            zenoh.handlers.Callback(self._on_sample, indirect=False) if ordered else self._on_sample
        )
        self._sub = peer.session.declare_subscriber(self.key, handler)
        self._token = peer.session.liveliness().declare_token(self.token)
        self._closed = False

    def _problem(self, text: str) -> None:
        with self._cond:
            self._problems.append(text)
            self._cond.notify_all()

    def _on_sample(self, sample: zenoh.Sample) -> None:
        try:
            self._take(sample)
        except Exception as e:  # never raise on Zenoh's thread
            self._problem(f"unexpected {type(e).__name__}: {e}")

    def _take(self, sample: zenoh.Sample) -> None:
        key = str(sample.key_expr)
        if key != self.key:
            self._problem(f"a sample on {key}, not {self.key}")
            return
        if sample.kind != zenoh.SampleKind.PUT:
            self._problem(f"a {sample.kind} sample")
            return
        if sample.attachment is None:
            self._problem("a sample without an attachment")
            return
        try:
            seq, ts, gid_ = parse_attachment(sample.attachment.to_bytes())
        except ValueError as e:
            self._problem(f"bad attachment: {e}")
            return
        payload = sample.payload.to_bytes()
        try:
            message = store().deserialize_cdr(payload, self.ros_type)
        except Exception as e:
            self._problem(f"payload of seq {seq} from {gid_.hex()} not a {self.ros_type}: {e}")
            return
        with self._cond:
            last = self._last_seq.get(gid_)
            if seq < 1 or (last is not None and seq <= last):
                self._problems.append(f"seq {seq} from {gid_.hex()} after {last}")
            self._last_seq[gid_] = seq if last is None else max(seq, last)
            self._count += 1
            self._received.append(Received(message, seq, ts, gid_, payload))
            if len(self._received) > self._keep:
                del self._received[: len(self._received) - self._keep]
            self._cond.notify_all()
        if self._callback is not None:
            try:
                self._callback(message)
            except Exception as e:
                self._problem(f"the callback raised {type(e).__name__}: {e}")

    @property
    def count(self) -> int:
        """How many good messages came."""
        with self._lock:
            return self._count

    @property
    def problems(self) -> list[str]:
        """What was wrong with the samples that came, in order."""
        with self._lock:
            return list(self._problems)

    def received(self) -> list[Received]:
        """The last messages that came (at most `keep`), oldest first."""
        with self._lock:
            return list(self._received)

    def gids(self) -> set[bytes]:
        """The GIDs of the publishers heard from."""
        with self._lock:
            return set(self._last_seq)

    def wait_for(self, count: int, timeout: float) -> bool:
        """Waits until `count` good messages came in all; returns whether they did in time."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._count < count:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
            return True

    def close(self) -> None:
        """Withdraws the token, then undeclares the subscriber."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._token.undeclare()  # type: ignore[no-untyped-call]
        self._sub.undeclare()  # type: ignore[no-untyped-call]


class Ros2Peer:
    """One ROS 2 node on rmw_zenoh, on a Zenoh session (the caller's: it stays open on close).

    Declares the node's NN token at once; `publisher` and `subscribe` add MP and MS entities.
    It also watches the ROS 2 graph of its domain (every ``@ros2_lv/<domain>/**`` token alive)
    for `graph`.
    """

    def __init__(
        self,
        session: zenoh.Session,
        *,
        domain_id: int = 0,
        namespace: str = "",
        node: str,
        enclave: str = "/",
    ) -> None:
        if not node or "/" in node or "~" in node:
            raise ValueError(f"not a node name: {node!r}")
        if not 0 <= domain_id <= 232:
            raise ValueError(f"ROS_DOMAIN_ID {domain_id} is not in 0..232")
        self.session = session
        self.domain_id = domain_id
        ns = "/" + namespace.strip("/") if namespace.strip("/") else "/"
        self.namespace = ns
        self.node = node
        self.enclave = enclave
        self.zid = str(session.zid())
        self.node_id = _next_id(self.zid)
        self.node_token = token(
            "NN",
            domain_id=domain_id,
            zid=self.zid,
            node_id=self.node_id,
            entity_id=self.node_id,
            namespace=ns,
            node=node,
            enclave=enclave,
        )
        self._lock = threading.Lock()
        self._graph: set[str] = set()
        self._entities: list[Publisher | Subscription] = []
        self._graph_sub = session.liveliness().declare_subscriber(
            f"{ADMIN_SPACE}/{domain_id}/**", self._on_token, history=True
        )
        self._node_token = session.liveliness().declare_token(self.node_token)
        self._closed = False

    def _on_token(self, sample: zenoh.Sample) -> None:
        key = str(sample.key_expr)
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._graph.add(key)
            else:
                self._graph.discard(key)

    def graph(self) -> set[str]:
        """The liveliness tokens of the domain alive now, as this peer saw them come and go."""
        with self._lock:
            return set(self._graph)

    def entity_token(self, kind: str, entity_id: int, topic: str, ros_type: str, qos: Qos) -> str:
        """Returns the token of an entity of this node (`topic` fully qualified)."""
        return token(
            kind,
            domain_id=self.domain_id,
            zid=self.zid,
            node_id=self.node_id,
            entity_id=entity_id,
            namespace=self.namespace,
            node=self.node,
            enclave=self.enclave,
            topic=topic,
            ros_type=ros_type,
            qos=qos,
        )

    def publisher(self, topic: str, ros_type: str, qos: Qos = QOS_DEFAULT) -> Publisher:
        """Creates a publisher (a Zenoh publisher, then its MP token)."""
        with self._lock:
            if self._closed:
                raise RuntimeError("the peer is closed")
        pub = Publisher(self, topic, ros_type, qos)
        with self._lock:
            self._entities.append(pub)
        return pub

    def subscribe(
        self,
        topic: str,
        ros_type: str,
        callback: Callable[[Any], None] | None = None,
        qos: Qos = QOS_DEFAULT,
        *,
        keep: int = 1000,
        ordered: bool = False,
    ) -> Subscription:
        """Creates a subscription (a Zenoh subscriber, then its MS token).

        `callback` gets each decoded message; the last `keep` are kept. By default each
        subscription's callbacks run on a thread of its own; with `ordered`, on Zenoh's thread
        as the samples arrive, so that the ordered subscriptions see one remote session's puts
        in the order they were made (the callback must be quick: it holds up the session).
        """
        with self._lock:
            if self._closed:
                raise RuntimeError("the peer is closed")
        sub = Subscription(self, topic, ros_type, callback, qos, keep, ordered)
        with self._lock:
            self._entities.append(sub)
        return sub

    def tokens(self) -> list[str]:
        """The tokens this peer holds: its node's, then its entities' in order of creation."""
        with self._lock:
            return [self.node_token, *(e.token for e in self._entities)]

    def close(self) -> None:
        """Undeclares every entity and token of the node (the session stays open)."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            entities = list(self._entities)
        for e in reversed(entities):
            e.close()
        self._node_token.undeclare()  # type: ignore[no-untyped-call]
        self._graph_sub.undeclare()  # type: ignore[no-untyped-call]

    def __enter__(self) -> Ros2Peer:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()
