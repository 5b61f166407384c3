"""The physics robot as a ROS 2 robot: `PhysicsWorld` behind a ROS 2 node over rmw_zenoh.

What a Gazebo robot offers a ROS 2 stack, on the topics a ROS 2 robot driver uses:

- subscribes to ``cmd_vel`` (`geometry_msgs/msg/Twist`, or `TwistStamped` with
  ``stamped=True``): the base's command; one older than `cmd_timeout` s of simulated time
  stops the base (``diff_drive_controller``'s ``cmd_vel_timeout``, default 0.5 s);
- publishes, every tick of its clock (``rate_hz``), ``/clock`` (`rosgraph_msgs/msg/Clock`),
  ``odom`` (`nav_msgs/msg/Odometry`: the wheel odometry, odom → base_link), ``/tf``
  (`tf2_msgs/msg/TFMessage`: the same transform) and ``sonar`` (`sensor_msgs/msg/LaserScan`:
  the 24 sonars, ``angle_min`` 0, ``angle_increment`` 15°, ranges from the robot's centre; what
  situate's ROS 2 bridge reads with ``ring: 24``), stamped with simulated time.

Tick k runs the physics for one period with the command in force, then publishes what the robot
senses at simulated time ``k / rate_hz``. `run` paces the ticks at `time_scale` times real time
(falling behind, it goes on from now and never skips a tick); `tick` runs one at once.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np

from situate.physics.world import SONARS, PhysicsWorld
from situate.ros2 import QOS_SENSOR_DATA, QOS_TF, Ros2Peer, msg


class PhysicsNode:
    """A `PhysicsWorld` on a `Ros2Peer`; see the module's documentation."""

    def __init__(
        self,
        world: PhysicsWorld,
        peer: Ros2Peer,
        *,
        rate_hz: float = 10.0,
        stamped: bool = False,
        cmd_timeout: float | None = 0.5,
        cmd_topic: str = "cmd_vel",
        odom_topic: str = "odom",
        sonar_topic: str = "sonar",
        odom_frame: str = "odom",
        base_frame: str = "base_link",
    ) -> None:
        if not 0 < rate_hz <= 1000:
            raise ValueError(f"rate_hz {rate_hz}: expected in (0, 1000]")
        self.world = world
        self.peer = peer
        self.rate_hz = rate_hz
        self.stamped = stamped
        self.cmd_timeout = cmd_timeout
        self.odom_frame = odom_frame
        self.base_frame = base_frame
        self._lock = threading.Lock()
        self._ticks = 0
        self._command: tuple[float, float, float] | None = None  # v, w, simulated time it came
        self._commands = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._clock = peer.publisher("/clock", "rosgraph_msgs/msg/Clock")
        self._odom = peer.publisher(odom_topic, "nav_msgs/msg/Odometry")
        self._tf = peer.publisher("/tf", "tf2_msgs/msg/TFMessage", QOS_TF)
        self._sonar = peer.publisher(sonar_topic, "sensor_msgs/msg/LaserScan", QOS_SENSOR_DATA)
        cmd_type = "geometry_msgs/msg/TwistStamped" if stamped else "geometry_msgs/msg/Twist"
        self._cmd = peer.subscribe(cmd_topic, cmd_type, self._on_cmd)

    # -- state --

    @property
    def ticks(self) -> int:
        """Ticks run so far."""
        with self._lock:
            return self._ticks

    @property
    def commands_received(self) -> int:
        """Commands that came."""
        with self._lock:
            return self._commands

    @property
    def cmd_problems(self) -> list[str]:
        """What was wrong with the commands that came (see `Subscription.problems`)."""
        return self._cmd.problems

    @property
    def running(self) -> bool:
        """Whether the clock's thread runs."""
        return self._thread is not None and self._thread.is_alive()

    def _on_cmd(self, message: Any) -> None:
        twist = message.twist if self.stamped else message
        v, w = float(twist.linear.x), float(twist.angular.z)
        if not (math.isfinite(v) and math.isfinite(w)):
            return  # a driver ignores a command it cannot follow
        with self._lock:
            self._commands += 1
            self._command = (v, w, self._ticks / self.rate_hz)

    # -- ticks --

    def tick(self) -> None:
        """One tick: the physics for one period, then what the robot senses, published."""
        with self._lock:
            now = self._ticks / self.rate_hz
            cmd = self._command
        v, w = 0.0, 0.0
        if cmd is not None and (self.cmd_timeout is None or now - cmd[2] <= self.cmd_timeout):
            v, w = cmd[0], cmd[1]
        self.world.command(v, w)
        self.world.advance(1.0 / self.rate_hz)
        with self._lock:
            self._ticks += 1
            tick = self._ticks
        self._publish(round(tick * 1e9 / self.rate_hz))

    def _publish(self, stamp_ns: int) -> None:
        stamp = msg("builtin_interfaces/msg/Time", sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)

        def header(frame: str) -> Any:
            return msg("std_msgs/msg/Header", stamp=stamp, frame_id=frame)

        o = self.world.odometry()
        vec = "geometry_msgs/msg/Vector3"
        rotation = msg(
            "geometry_msgs/msg/Quaternion",
            x=0.0,
            y=0.0,
            z=math.sin(o.theta / 2),
            w=math.cos(o.theta / 2),
        )
        ranges = self.world.sonar()
        spec = self.world.sonar_spec
        inc = 2 * math.pi / SONARS
        # The sensors first, then the clock: a ROS 2 node that acts on /clock has the readings
        # of that time already (rmw_zenoh delivers one session's puts in order).
        self._sonar.publish(
            msg(
                "sensor_msgs/msg/LaserScan",
                header=header(self.base_frame),
                angle_min=0.0,
                angle_max=(SONARS - 1) * inc,
                angle_increment=inc,
                time_increment=0.0,
                scan_time=1.0 / self.rate_hz,
                range_min=spec.min_range,
                range_max=spec.max_range,
                ranges=ranges.astype(np.float32),
                intensities=np.zeros(0, dtype=np.float32),
            )
        )
        self._odom.publish(
            msg(
                "nav_msgs/msg/Odometry",
                header=header(self.odom_frame),
                child_frame_id=self.base_frame,
                pose=msg(
                    "geometry_msgs/msg/PoseWithCovariance",
                    pose=msg(
                        "geometry_msgs/msg/Pose",
                        position=msg("geometry_msgs/msg/Point", x=o.x, y=o.y, z=0.0),
                        orientation=rotation,
                    ),
                    covariance=np.zeros(36, dtype=np.float64),
                ),
                twist=msg(
                    "geometry_msgs/msg/TwistWithCovariance",
                    twist=msg(
                        "geometry_msgs/msg/Twist",
                        linear=msg(vec, x=o.v, y=0.0, z=0.0),
                        angular=msg(vec, x=0.0, y=0.0, z=o.w),
                    ),
                    covariance=np.zeros(36, dtype=np.float64),
                ),
            )
        )
        self._tf.publish(
            msg(
                "tf2_msgs/msg/TFMessage",
                transforms=[
                    msg(
                        "geometry_msgs/msg/TransformStamped",
                        header=header(self.odom_frame),
                        child_frame_id=self.base_frame,
                        transform=msg(
                            "geometry_msgs/msg/Transform",
                            translation=msg(vec, x=o.x, y=o.y, z=0.0),
                            rotation=rotation,
                        ),
                    )
                ],
            )
        )
        self._clock.publish(msg("rosgraph_msgs/msg/Clock", clock=stamp))

    # -- the clock's thread --

    def start(self, time_scale: float = 1.0) -> None:
        """Runs the ticks on a thread, `time_scale` times as fast as real time."""
        if not time_scale > 0:
            raise ValueError(f"time_scale {time_scale}: expected > 0")
        if self.running:
            raise RuntimeError("the robot's clock already runs")
        self._stop.clear()
        self._thread = threading.Thread(
            target=self.run, args=(time_scale,), name="physics-clock", daemon=True
        )
        self._thread.start()

    def run(self, time_scale: float = 1.0) -> None:
        """Runs the ticks on this thread until `stop`, paced at `time_scale` times real time."""
        period = 1.0 / (self.rate_hz * time_scale)
        due = time.monotonic() + period
        while not self._stop.is_set():
            now = time.monotonic()
            if now < due:
                self._stop.wait(due - now)  # pacing the clock, not synchronising
                continue
            self.tick()
            due += period
            if time.monotonic() - due > 0.5:
                due = time.monotonic() + period

    def stop(self, timeout: float = 30.0) -> None:
        """Stops the clock's thread after the tick under way."""
        self._stop.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)
            if thread.is_alive():
                raise RuntimeError("the robot's clock did not stop")
        self._thread = None

    def close(self) -> None:
        """Stops the clock and closes the node's publishers and subscription (the peer stays)."""
        self.stop()
        for e in (self._cmd, self._clock, self._odom, self._tf, self._sonar):
            e.close()
