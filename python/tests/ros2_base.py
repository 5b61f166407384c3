"""The ROS 2 robot to test against: a kinematic differential-drive base on a `Ros2Peer`.

`DiffDriveBase` takes `cmd_vel` and publishes `/odom`, `/tf`, `/scan` and (with simulated time)
`/clock` exactly as a ROS 2 driver on rmw_zenoh does: the wire format is `situate.ros2`'s
(checked in test_ros2_peer.py against rmw_zenoh and captures of real systems); this module is the
robot: its room, its kinematics and its ray-cast scan.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from situate.ros2 import (
    QOS_SENSOR_DATA,
    QOS_TF,
    Ros2Peer,
    Subscription,
    header,
    msg,
    odometry_msg,
    tf_msg,
    time_msg,
)


@dataclass(frozen=True)
class Pose:
    """A planar pose: x, y (m) and heading theta (rad, in (-pi, pi])."""

    x: float
    y: float
    theta: float


@dataclass(frozen=True)
class Box:
    """An axis-aligned rectangle, xmin < xmax, ymin < ymax (m)."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    def __post_init__(self) -> None:
        if not (self.xmin < self.xmax and self.ymin < self.ymax):
            raise ValueError(f"an empty box: {self}")


@dataclass(frozen=True)
class Room:
    """The robot's world: the walls of a rectangle, and optionally a box standing in it."""

    walls: Box = field(default_factory=lambda: Box(0.0, 0.0, 6.0, 4.0))
    obstacle: Box | None = None


@dataclass(frozen=True)
class Command:
    """The last velocity command: forward speed v (m/s), turn rate w (rad/s), and when it came
    (the robot's time, ns)."""

    v: float
    w: float
    at_ns: int


def _normalize(theta: float) -> float:
    t = math.remainder(theta, 2 * math.pi)
    return math.pi if t == -math.pi else t


def ray_cast(room: Room, x: float, y: float, angles: np.ndarray[Any, Any]) -> np.ndarray[Any, Any]:
    """Returns the distance from (x, y) along each world angle to the first wall or box face."""
    dx = np.cos(angles)
    dy = np.sin(angles)
    w = room.walls
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(dx > 0, (w.xmax - x) / dx, np.where(dx < 0, (w.xmin - x) / dx, np.inf))
        ty = np.where(dy > 0, (w.ymax - y) / dy, np.where(dy < 0, (w.ymin - y) / dy, np.inf))
        t = np.minimum(tx, ty)
        b = room.obstacle
        if b is not None:
            # Slab method: entering a box seen from outside.
            inside_x = (b.xmin <= x) & (x <= b.xmax)
            inside_y = (b.ymin <= y) & (y <= b.ymax)
            x1 = (b.xmin - x) / dx
            x2 = (b.xmax - x) / dx
            y1 = (b.ymin - y) / dy
            y2 = (b.ymax - y) / dy
            txmin = np.where(dx != 0, np.minimum(x1, x2), np.where(inside_x, -np.inf, np.inf))
            txmax = np.where(dx != 0, np.maximum(x1, x2), np.where(inside_x, np.inf, -np.inf))
            tymin = np.where(dy != 0, np.minimum(y1, y2), np.where(inside_y, -np.inf, np.inf))
            tymax = np.where(dy != 0, np.maximum(y1, y2), np.where(inside_y, np.inf, -np.inf))
            enter = np.maximum(txmin, tymin)
            leave = np.minimum(txmax, tymax)
            hit = (enter <= leave) & (enter >= 0)
            t = np.where(hit, np.minimum(t, enter), t)
    result: np.ndarray[Any, Any] = t
    return result


class DiffDriveBase:
    """A kinematic differential-drive robot on a `Ros2Peer`, in a room with walls.

    It takes ``cmd_vel`` (`geometry_msgs/msg/Twist`, or `TwistStamped` with ``stamped=True``:
    ``linear.x`` and ``angular.z``), and every tick of its clock moves by the last command
    (exactly, along the arc) and publishes ``odom`` (`nav_msgs/msg/Odometry`, odom → base_link,
    with the twist it moved at), ``/tf`` (`tf2_msgs/msg/TFMessage`, odom → base_link) and ``scan``
    (`sensor_msgs/msg/LaserScan` over the full circle from -pi, ray cast against the walls and
    the box; +inf past range_max), and with ``sim_time=True`` ``/clock``
    (`rosgraph_msgs/msg/Clock`).

    Its clock: tick k is at robot time k / rate_hz. `start` runs the ticks on a thread, paced so
    that robot time advances `time_scale` times as fast as real time (if it falls more than half a
    second behind, it goes on from now, as a slow simulator does: never skips a tick); `step`
    runs ticks at once, without the thread. With sim_time the stamps are robot time (from
    `sim_start_ns`); without, the wall clock. A command older than `cmd_timeout` s of robot time
    stops the robot (diff_drive_controller's default is 0.5 s); None keeps the last command.
    A move that would take the robot's centre within `radius` of a wall or into the box is not
    made (it still turns), and counted in `bumps`. Given its commands and when they come (in
    ticks), what it does is deterministic.
    """

    def __init__(
        self,
        peer: Ros2Peer,
        *,
        rate_hz: float = 20.0,
        scan_rays: int = 360,
        room: Room | None = None,
        sim_time: bool = False,
        time_scale: float = 1.0,
        start: Pose | None = None,
        stamped: bool = False,
        cmd_timeout: float | None = 0.5,
        radius: float = 0.1,
        range_min: float = 0.05,
        range_max: float = 10.0,
        scan_every: int = 1,
        sim_start_ns: int = 0,
        cmd_topic: str = "cmd_vel",
        odom_topic: str = "odom",
        scan_topic: str = "scan",
        odom_frame: str = "odom",
        base_frame: str = "base_link",
        scan_frame: str = "base_link",
    ) -> None:
        if rate_hz <= 0 or time_scale <= 0 or scan_rays < 1 or scan_every < 1:
            raise ValueError("rate_hz and time_scale must be > 0, scan_rays and scan_every >= 1")
        self.peer = peer
        self.rate_hz = rate_hz
        self.time_scale = time_scale
        self.sim_time = sim_time
        self.room = room if room is not None else Room()
        self.scan_rays = scan_rays
        self.stamped = stamped
        self.cmd_timeout_ns = None if cmd_timeout is None else int(cmd_timeout * 1e9)
        self.radius = radius
        self.range_min = range_min
        self.range_max = range_max
        self.scan_every = scan_every
        self.sim_start_ns = sim_start_ns
        self.odom_frame = odom_frame
        self.base_frame = base_frame
        self.scan_frame = scan_frame
        self.cmd_type = "geometry_msgs/msg/TwistStamped" if stamped else "geometry_msgs/msg/Twist"
        self._angles = -math.pi + np.arange(scan_rays) * (2 * math.pi / scan_rays)
        self._lock = threading.Lock()
        self._pose = start if start is not None else Pose(1.0, 2.0, 0.0)
        if not self._free(self._pose.x, self._pose.y):
            raise ValueError(f"the robot cannot start at {self._pose}")
        self._ticks = 0
        self._commands = 0
        self._last: Command | None = None
        self._moving = (0.0, 0.0)
        self._bumps = 0
        self._published = 0
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._odom = peer.publisher(odom_topic, "nav_msgs/msg/Odometry")
        self._tf = peer.publisher("/tf", "tf2_msgs/msg/TFMessage", QOS_TF)
        self._scan = peer.publisher(scan_topic, "sensor_msgs/msg/LaserScan", QOS_SENSOR_DATA)
        self._clock = peer.publisher("/clock", "rosgraph_msgs/msg/Clock") if sim_time else None
        self._cmd = peer.subscribe(cmd_topic, self.cmd_type, self._on_cmd)

    # -- state --

    def pose(self) -> Pose:
        """Where the robot is now."""
        with self._lock:
            return self._pose

    @property
    def commands_received(self) -> int:
        """How many commands came."""
        with self._lock:
            return self._commands

    @property
    def last_command(self) -> Command | None:
        """The last command that came, if any."""
        with self._lock:
            return self._last

    @property
    def ticks(self) -> int:
        """How many ticks the robot has run."""
        with self._lock:
            return self._ticks

    def publish_clock(self) -> None:
        """Publishes ``/clock`` at the time now again (no tick), as a paused simulator does: a
        keep-last ``/clock`` dropped under congestion is superseded by the next one, and once the
        clock stopped there is no next one."""
        if self._clock is None:
            return
        with self._lock:
            stamp_ns = self._time_ns(self._ticks)
        self._clock.publish(msg("rosgraph_msgs/msg/Clock", clock=time_msg(stamp_ns)))

    @property
    def now_ns(self) -> int:
        """The robot's time now (ns since its start, plus `sim_start_ns`)."""
        with self._lock:
            return self._time_ns(self._ticks)

    @property
    def bumps(self) -> int:
        """How many moves a wall or the box stopped."""
        with self._lock:
            return self._bumps

    @property
    def messages_published(self) -> int:
        """How many messages the robot has published, on all its topics."""
        with self._lock:
            return self._published

    @property
    def cmd_subscription(self) -> Subscription:
        """The cmd_vel subscription (its problems, its publishers' GIDs)."""
        return self._cmd

    @property
    def running(self) -> bool:
        """Whether the robot's thread runs."""
        return self._thread is not None and self._thread.is_alive()

    def _time_ns(self, ticks: int) -> int:
        return self.sim_start_ns + round(ticks * 1e9 / self.rate_hz)

    def _free(self, x: float, y: float) -> bool:
        w, r = self.room.walls, self.radius
        if not (w.xmin + r <= x <= w.xmax - r and w.ymin + r <= y <= w.ymax - r):
            return False
        b = self.room.obstacle
        if b is None:
            return True
        nx = min(max(x, b.xmin), b.xmax)
        ny = min(max(y, b.ymin), b.ymax)
        return math.hypot(x - nx, y - ny) > r

    # -- commands --

    def _on_cmd(self, message: Any) -> None:
        twist = message.twist if self.stamped else message
        with self._lock:
            self._commands += 1
            self._last = Command(
                float(twist.linear.x), float(twist.angular.z), self._time_ns(self._ticks)
            )

    # -- ticks --

    def step(self, ticks: int = 1) -> None:
        """Runs ticks now, one after the other (not while the thread runs)."""
        if self.running:
            raise RuntimeError("step() while the robot runs on its thread")
        for _ in range(ticks):
            self._tick()

    def _tick(self) -> None:
        dt = 1.0 / self.rate_hz
        with self._lock:
            now = self._time_ns(self._ticks)
            cmd = self._last
            if cmd is None or (
                self.cmd_timeout_ns is not None and now - cmd.at_ns > self.cmd_timeout_ns
            ):
                v, w = 0.0, 0.0
            else:
                v, w = cmd.v, cmd.w
            p = self._pose
            if abs(w) < 1e-12:
                nx = p.x + v * dt * math.cos(p.theta)
                ny = p.y + v * dt * math.sin(p.theta)
            else:
                nx = p.x + v / w * (math.sin(p.theta + w * dt) - math.sin(p.theta))
                ny = p.y - v / w * (math.cos(p.theta + w * dt) - math.cos(p.theta))
            nt = _normalize(p.theta + w * dt)
            if (nx, ny) != (p.x, p.y) and not self._free(nx, ny):
                self._bumps += 1
                nx, ny, v = p.x, p.y, 0.0
            self._pose = Pose(nx, ny, nt)
            self._moving = (v, w)
            self._ticks += 1
            tick = self._ticks
            pose = self._pose
        stamp_ns = self._time_ns(tick) if self.sim_time else time.time_ns()
        self._publish(tick, stamp_ns, pose, v, w)

    def _publish(self, tick: int, stamp_ns: int, pose: Pose, v: float, w: float) -> None:
        n = 0
        if self._clock is not None:
            self._clock.publish(msg("rosgraph_msgs/msg/Clock", clock=time_msg(stamp_ns)))
            n += 1
        p = pose
        odom = odometry_msg(stamp_ns, self.odom_frame, self.base_frame, p.x, p.y, p.theta, v, w)
        self._odom.publish(odom)
        self._tf.publish(tf_msg(stamp_ns, self.odom_frame, self.base_frame, p.x, p.y, p.theta))
        n += 2
        if (tick - 1) % self.scan_every == 0:
            self._scan.publish(self.scan(pose, stamp_ns))
            n += 1
        with self._lock:
            self._published += n

    def scan(self, pose: Pose | None = None, stamp_ns: int = 0) -> Any:
        """Returns the LaserScan the robot sees at a pose (by default, where it is)."""
        if pose is None:
            pose = self.pose()
        r = ray_cast(self.room, pose.x, pose.y, self._angles + pose.theta)
        r = np.where(r > self.range_max, np.inf, r).astype(np.float32)
        inc = 2 * math.pi / self.scan_rays
        return msg(
            "sensor_msgs/msg/LaserScan",
            header=header(stamp_ns, self.scan_frame),
            angle_min=-math.pi,
            angle_max=-math.pi + (self.scan_rays - 1) * inc,
            angle_increment=inc,
            time_increment=0.0,
            scan_time=self.scan_every / self.rate_hz,
            range_min=self.range_min,
            range_max=self.range_max,
            ranges=r,
            intensities=np.zeros(0, dtype=np.float32),
        )

    # -- the thread --

    def start(self) -> None:
        """Starts the robot's clock on a thread."""
        if self.running:
            raise RuntimeError("the robot already runs")
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="diff-drive-base", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        period = 1.0 / (self.rate_hz * self.time_scale)
        due = time.monotonic() + period
        while not self._stop.is_set():
            now = time.monotonic()
            if now < due:
                self._stop.wait(due - now)  # pacing the clock, not synchronising
                continue
            self._tick()
            due += period
            if time.monotonic() - due > 0.5:
                due = time.monotonic() + period

    def stop(self, timeout: float = 30.0) -> None:
        """Stops the thread (after the tick under way) and waits for it."""
        self._stop.set()
        thread = self._thread
        if thread is not None:
            thread.join(timeout)
            if thread.is_alive():
                raise RuntimeError("the robot's thread did not stop")
        self._thread = None

    def close(self) -> None:
        """Stops the robot and closes its publishers and subscription (the peer stays)."""
        self.stop()
        for e in (self._cmd, self._odom, self._tf, self._scan, self._clock):
            if e is not None:
                e.close()
