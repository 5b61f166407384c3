"""The physics robot as a ROS 2 robot: `PhysicsWorld` behind a ROS 2 node over rmw_zenoh.

What a Gazebo robot offers a ROS 2 stack, on the topics a ROS 2 robot driver uses:

- subscribes to ``cmd_vel`` (`geometry_msgs/msg/Twist`, or `TwistStamped` with
  ``stamped=True``): the base's command; one older than `cmd_timeout` s of simulated time
  stops the base (``diff_drive_controller``'s ``cmd_vel_timeout``, default 0.5 s);
- publishes, every tick of its clock (``rate_hz``), ``sonar`` (`sensor_msgs/msg/LaserScan`:
  the 24 sonars, ``angle_min`` 0, ``angle_increment`` 15°, ranges from the robot's centre; what
  situate's ROS 2 bridge reads with ``ring: 24``), ``barcodes`` (`situate_msgs/msg/Barcodes`:
  what the reader sees), ``odom`` (`nav_msgs/msg/Odometry`: the wheel odometry, odom →
  base_link), ``/tf`` (`tf2_msgs/msg/TFMessage`: the same transform), ``ground_truth/odom``
  (`nav_msgs/msg/Odometry`: the robot's true pose in the building, map → base_link, as
  Gazebo's p3d plugin offers it: x, y, the yaw, z the floor's slab (``floor * FLOOR_HEIGHT``),
  the true forward speed and turn rate; for displays and tests, never for skills: situate's GUI
  draws the robot from it mapped onto ``truth.pose``), ``ground_truth/people``
  (`situate_msgs/msg/People`: where each person walking in the building is, and on which floor)
  and ``ground_truth/cars`` (`situate_msgs/msg/Cars`: each car's position in floors and its door's
  opening; ``truth.people`` and ``truth.cars`` for the GUI, as the 2-D simulator's) and, last,
  ``/clock``
  (`rosgraph_msgs/msg/Clock`), all stamped with simulated time;
- the arm and the speaker, as a robot driver's plain topics: subscribes to ``arm/press``
  (`std_msgs/msg/Int64`: push the button with that label, as the 2-D arm) and ``speaker/say``
  (`std_msgs/msg/String`), and publishes each tick their counters ``arm/attempts``,
  ``arm/presses`` and ``speaker/count`` (`std_msgs/msg/Int64`) and the altimeter's ``floor``
  (`std_msgs/msg/Int64`: the floor the robot is on, the nearest one while a car carries it).
  A push or an utterance takes effect at the start of the next tick.

Tick k runs the physics for one period with the command in force, then publishes what the robot
senses at simulated time ``k / rate_hz``. `run` paces the ticks at `time_scale` times real time
(falling behind, it goes on from now and never skips a tick); `tick` runs one at once.

**Lock-step** (``lockstep=`` the robot's ``~/cycle`` topic; situate's ``ros2: {use_sim_time:
true, lockstep: true}``): after each tick the node waits until the robot says, on that topic,
that it has run its cycles up to the tick's time (sending ``/clock`` again every `resend_s` s
of waiting, so a first message sent before the robot listened is not waited for forever); the
commands that came before that say-so are the ones the next tick obeys, and a tick with none is
a stop: "no command in a cycle = stop", as the 2-D base. The robot holds the clock while it is
stopped (a pausing monitor, a sequencer thinking), so the world waits too, and a run is the
same every time for a seed. Its topics are then reliable and keep-all (never dropped).
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np

from situate.physics.model import FLOOR_HEIGHT
from situate.physics.world import SONARS, PhysicsWorld
from situate.ros2 import (
    QOS_DEFAULT,
    QOS_SENSOR_DATA,
    QOS_TF,
    History,
    Qos,
    Ros2Peer,
    header,
    msg,
    odometry_msg,
    tf_msg,
    time_msg,
)

#: Lock-step: every topic reliable and keep-all, so that none is dropped and all arrive in order.
QOS_LOCKSTEP = Qos(history=History.KEEP_ALL, depth=1000)


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
        barcodes_topic: str = "barcodes",
        truth_topic: str = "ground_truth/odom",
        people_topic: str = "ground_truth/people",
        cars_topic: str = "ground_truth/cars",
        odom_frame: str = "odom",
        map_frame: str = "map",
        base_frame: str = "base_link",
        lockstep: str | None = None,
        resend_s: float = 1.0,
    ) -> None:
        if not 0 < rate_hz <= 1000:
            raise ValueError(f"rate_hz {rate_hz}: expected in (0, 1000]")
        self.world = world
        self.peer = peer
        self.rate_hz = rate_hz
        self.stamped = stamped
        self.cmd_timeout = cmd_timeout
        self.odom_frame = odom_frame
        self.map_frame = map_frame
        self.base_frame = base_frame
        self.lockstep = lockstep
        self.resend_s = resend_s
        self._lock = threading.Lock()
        self._said = threading.Condition(self._lock)
        self._ticks = 0
        self._command: tuple[float, float, float] | None = None  # v, w, simulated time it came
        self._commands = 0
        # Lock-step: the command since the robot's last say-so, the one the next tick obeys,
        # the latest time said done (ns) and how often /clock was sent again.
        self._pending: tuple[float, float] | None = None
        self._next: tuple[float, float] | None = None
        self._done_ns = -1
        self._resent = 0
        # Pushes and utterances that came, done at the start of the next tick.
        self._presses: list[int] = []
        self._says: list[str] = []
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        qos = QOS_LOCKSTEP if lockstep else None
        self._sonar = peer.publisher(
            sonar_topic, "sensor_msgs/msg/LaserScan", qos or QOS_SENSOR_DATA
        )
        self._barcodes = peer.publisher(
            barcodes_topic, "situate_msgs/msg/Barcodes", qos or QOS_SENSOR_DATA
        )
        self._odom = peer.publisher(odom_topic, "nav_msgs/msg/Odometry", *([qos] if qos else []))
        self._truth = peer.publisher(truth_topic, "nav_msgs/msg/Odometry", *([qos] if qos else []))
        self._people = peer.publisher(
            people_topic, "situate_msgs/msg/People", *([qos] if qos else [])
        )
        self._cars = peer.publisher(cars_topic, "situate_msgs/msg/Cars", *([qos] if qos else []))
        self._tf = peer.publisher("/tf", "tf2_msgs/msg/TFMessage", qos or QOS_TF)
        self._clock = peer.publisher("/clock", "rosgraph_msgs/msg/Clock", *([qos] if qos else []))
        self._counters = {
            name: peer.publisher(name, "std_msgs/msg/Int64", *([qos] if qos else []))
            for name in ("arm/attempts", "arm/presses", "speaker/count", "floor")
        }
        self._press_sub = peer.subscribe(
            "arm/press", "std_msgs/msg/Int64", self._on_press, qos or QOS_DEFAULT, ordered=True
        )
        self._say_sub = peer.subscribe(
            "speaker/say", "std_msgs/msg/String", self._on_say, qos or QOS_DEFAULT, ordered=True
        )
        cmd_type = "geometry_msgs/msg/TwistStamped" if stamped else "geometry_msgs/msg/Twist"
        # Lock-step: the commands and the say-so in the order the robot sent them (`ordered`).
        self._cmd = peer.subscribe(
            cmd_topic, cmd_type, self._on_cmd, qos or QOS_DEFAULT, ordered=bool(lockstep)
        )
        self._done = (
            peer.subscribe(
                lockstep, "rosgraph_msgs/msg/Clock", self._on_done, QOS_LOCKSTEP, ordered=True
            )
            if lockstep
            else None
        )

    # -- state --

    @property
    def ticks(self) -> int:
        """Ticks run so far."""
        with self._lock:
            return self._ticks

    def publish_clock(self) -> None:
        """Publishes ``/clock`` at the time now again, as a paused simulator keeps doing.

        ``/clock`` is a keep-last topic: its publisher drops a message under congestion (as
        rmw_zenoh's keep-last publishers do), and a later one supersedes it. Once the clock has
        stopped there is no later one; a robot that missed the last catches up when it is sent
        again (Gazebo keeps publishing ``/clock`` while paused). Runs no tick.
        """
        with self._lock:
            tick = self._ticks
        self._clock.publish(self._clock_msg(round(tick * 1e9 / self.rate_hz)))

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

    @property
    def resent(self) -> int:
        """How often ``/clock`` was sent again while waiting for the robot (lock-step)."""
        with self._lock:
            return self._resent

    def _on_cmd(self, message: Any) -> None:
        twist = message.twist if self.stamped else message
        v, w = float(twist.linear.x), float(twist.angular.z)
        if not (math.isfinite(v) and math.isfinite(w)):
            return  # a driver ignores a command it cannot follow
        with self._lock:
            self._commands += 1
            self._command = (v, w, self._ticks / self.rate_hz)
            self._pending = (v, w)

    def _on_press(self, message: Any) -> None:
        with self._lock:
            self._presses.append(int(message.data))

    def _on_say(self, message: Any) -> None:
        with self._lock:
            self._says.append(str(message.data))

    def _on_done(self, message: Any) -> None:
        ns = int(message.clock.sec) * 10**9 + int(message.clock.nanosec)
        with self._said:
            if ns > self._done_ns:
                self._done_ns = ns
                # The commands of the cycles just done: the next tick obeys the last of them.
                self._next, self._pending = self._pending, None
                self._said.notify_all()

    # -- ticks --

    def tick(self) -> None:
        """One tick: the physics for one period, then what the robot senses, published.

        In lock-step it returns once the robot has run its cycles up to the tick's time (or
        the node is stopped).
        """
        with self._lock:
            now = self._ticks / self.rate_hz
            cmd = self._command
            step = self._next
            presses, self._presses = self._presses, []
            says, self._says = self._says, []
        for label in presses:
            self.world.press(label)
        for text in says:
            self.world.say(text)
        v, w = 0.0, 0.0
        if self.lockstep:
            if step is not None:
                v, w = step
        elif cmd is not None and (self.cmd_timeout is None or now - cmd[2] <= self.cmd_timeout):
            v, w = cmd[0], cmd[1]
        self.world.command(v, w)
        self.world.advance(1.0 / self.rate_hz)
        with self._lock:
            self._ticks += 1
            tick = self._ticks
        stamp_ns = round(tick * 1e9 / self.rate_hz)
        self._publish(stamp_ns)
        if self.lockstep:
            self._wait_done(stamp_ns)

    def _wait_done(self, stamp_ns: int) -> None:
        with self._said:
            while self._done_ns < stamp_ns and not self._stop.is_set():
                if not self._said.wait(self.resend_s) and self._done_ns < stamp_ns:
                    # Not said within resend_s: the robot may not have heard the first clock.
                    self._resent += 1
                    self._said.release()
                    try:
                        self._clock.publish(self._clock_msg(stamp_ns))
                    finally:
                        self._said.acquire()

    def _clock_msg(self, stamp_ns: int) -> Any:
        return msg("rosgraph_msgs/msg/Clock", clock=time_msg(stamp_ns))

    def _publish(self, stamp_ns: int) -> None:
        o = self.world.odometry()
        ranges = self.world.sonar()
        spec = self.world.sonar_spec
        inc = 2 * math.pi / SONARS
        seen = self.world.barcodes()
        # The sensors first, then the clock: a ROS 2 node that acts on /clock has the readings
        # of that time already (one session's puts arrive in order).
        self._barcodes.publish(
            msg(
                "situate_msgs/msg/Barcodes",
                header=header(stamp_ns, self.base_frame),
                ids=np.array([s[0] for s in seen], dtype=np.int64),
                bearing=np.array([s[1] for s in seen], dtype=np.float64),
                distance=np.array([s[2] for s in seen], dtype=np.float64),
            )
        )
        self._sonar.publish(
            msg(
                "sensor_msgs/msg/LaserScan",
                header=header(stamp_ns, self.base_frame),
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
            odometry_msg(stamp_ns, self.odom_frame, self.base_frame, o.x, o.y, o.theta, o.v, o.w)
        )
        self._tf.publish(tf_msg(stamp_ns, self.odom_frame, self.base_frame, o.x, o.y, o.theta))
        pose = self.world.pose()
        v, w = self.world.velocity()
        truth = odometry_msg(
            stamp_ns, self.map_frame, self.base_frame, pose.x, pose.y, pose.theta, v, w
        )
        truth.pose.pose.position.z = pose.floor * FLOOR_HEIGHT
        self._truth.publish(truth)
        people = self.world.people()
        self._people.publish(
            msg(
                "situate_msgs/msg/People",
                header=header(stamp_ns, self.map_frame),
                x=np.array([p[1] for p in people], dtype=np.float64),
                y=np.array([p[2] for p in people], dtype=np.float64),
                floor=np.array([p[0] for p in people], dtype=np.int64),
            )
        )
        cars = self.world.cars()
        self._cars.publish(
            msg(
                "situate_msgs/msg/Cars",
                header=header(stamp_ns, self.map_frame),
                floor=np.array([c.position for c in cars], dtype=np.float64),
                door=np.array([c.door for c in cars], dtype=np.float64),
            )
        )
        attempts, presses = self.world.arm
        for name, value in (
            ("arm/attempts", attempts),
            ("arm/presses", presses),
            ("speaker/count", len(self.world.said)),
            ("floor", pose.floor),
        ):
            self._counters[name].publish(msg("std_msgs/msg/Int64", data=value))
        self._clock.publish(self._clock_msg(stamp_ns))

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
        """Stops the clock's thread after the tick under way (a lock-step wait ends)."""
        self._stop.set()
        with self._said:
            self._said.notify_all()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout)
            if thread.is_alive():
                raise RuntimeError("the robot's clock did not stop")
        self._thread = None

    def close(self) -> None:
        """Stops the clock and closes the node's publishers and subscription (the peer stays)."""
        self.stop()
        for e in (self._cmd, self._done, self._press_sub, self._say_sub):
            if e is not None:
                e.close()
        for p in (
            self._clock,
            self._odom,
            self._truth,
            self._people,
            self._cars,
            self._tf,
            self._sonar,
            self._barcodes,
        ):
            p.close()
        for p in self._counters.values():
            p.close()
