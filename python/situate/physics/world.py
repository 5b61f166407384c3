"""The delivery robot in MuJoCo: a differential-drive base with mass and friction in the building.

`PhysicsWorld` builds the MuJoCo model of a `Building` (the map file the 2-D simulator reads) and
a `BaseSpec`, and runs it:

- **The model** (`situate.physics.model.mjcf`): the building and the base, generated from the
  `Building` and a `BaseSpec`; see that module.
- **Its controller**, as ROS 2's ``diff_drive_controller``: the latest command ``(v, w)`` is
  clamped to ``max_v``/``max_w`` and rate-limited to ``acc_v``/``acc_w``, then turned into the
  two wheels' speeds.
- **Odometry** from the wheel encoders (the joints' angles), integrated each physics step: what
  a real base reports, wrong where the wheels slip. In the frame of the start pose, as the 2-D
  simulator's ``odom``.
- **The sonar ring** (`SonarSpec`): sonar i looks at bearing ``i * 15°``; each casts `rays`
  rays across its cone from the robot's centre at `SONAR_HEIGHT` (`mj_multiRay`, the robot's own
  geoms left out) and reads the nearest return, plus Gaussian noise; a missed echo (probability
  `dropout`) or nothing within `max_range` reads ``max_range``; a dead sonar (`dead_sonars`)
  always does. As the 2-D simulator's ring.
- **People and door closures** (``people`` per floor, ``door_closures``): the 2-D simulator's
  own logic (`situate._native.Traffic`) walks the people and closes the map's doors; here a
  person is a kinematic (mocap) cylinder the robot's sonars see and bumps into, and a closed
  door a panel across its opening. Off by default, as in the 2-D simulator.
- **The arm and the speaker**: `press` pushes the button with a label (the lobby's call
  button, the panel of the car the robot is in) within reach, as the 2-D arm; `say` says a
  text, and the message is delivered when it is said in the office.
- **The barcode reader**: a barcode within `BARCODE_RANGE` and `BARCODE_FOV` either side of
  ahead, read from in front of its label (within 80° of the way it faces), and in line of sight
  (`mj_ray`: nothing nearer on the way). As the 2-D simulator's `barcodes`.

One physics step is `timestep` (2 ms); `advance` runs the steps of a span of time. With the same
building, seed and commands at the same times, a run is the same, step for step.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from situate.physics.building import Building, Segment, wrap
from situate.physics.model import (
    FLOOR_HEIGHT,
    ROBOT_GROUP,
    WALL_THICKNESS,
    BaseSpec,
    door_name,
    mjcf,
    panel_name,
)

try:
    import mujoco
except ImportError as e:  # pragma: no cover - depends on the installation
    raise ImportError(
        "the physics robot needs MuJoCo: pip install 'situate[physics]' (or pip install mujoco)"
    ) from e

#: The sonars' and the barcode reader's height above the floor, m.
SONAR_HEIGHT = 0.3
#: Sonars in the ring.
SONARS = 24
#: The barcode reader's range, m, and half field of view, rad (the 2-D simulator's).
BARCODE_RANGE = 5.0
BARCODE_FOV = math.radians(60)
#: Geom group of what is not there now (an open door's panel): no ray sees it.
GONE_GROUP = 5
#: The elevator logic's step, s (the 2-D simulator's step).
ELEVATOR_DT = 0.01
#: Most people per floor (the 2-D simulator's `--people` limit).
MAX_PEOPLE = 100
#: The arm's reach from the robot's centre, m, and how far off ahead a button may be, rad
#: (the 2-D `sim.arm`'s defaults).
ARM_REACH = 0.6
ARM_FOV = math.radians(25)


@dataclass(frozen=True)
class SonarSpec:
    """The sonar ring: as the 2-D simulator's `SonarSettings`."""

    min_range: float = 0.1
    max_range: float = 4.0
    #: The cone's full width, degrees.
    cone_deg: float = 15.0
    #: Rays across each cone (>= 1).
    rays: int = 5
    #: Gaussian noise, m (std dev).
    noise: float = 0.02
    #: Probability of a missed echo.
    dropout: float = 0.01


@dataclass(frozen=True)
class Odometry:
    """The base's odometry: pose in the frame of the start pose, and its speeds."""

    x: float
    y: float
    theta: float
    v: float
    w: float


@dataclass(frozen=True)
class Pose:
    """The robot's true pose in the building (for displays and tests, as ``truth.pose``)."""

    x: float
    y: float
    theta: float
    floor: int


@dataclass(frozen=True)
class Utterance:
    """Something the robot said: when, where and what."""

    time: float
    floor: int
    x: float
    y: float
    text: str


@dataclass(frozen=True)
class CarView:
    """One car as the world has it: floor position (fractional while it moves), door opening."""

    position: float
    door: float
    phase: str


class PhysicsWorld:
    """The building and the robot in MuJoCo; see the module's documentation."""

    def __init__(
        self,
        building: Building,
        *,
        seed: int = 1,
        base: BaseSpec | None = None,
        sonar: SonarSpec | None = None,
        timestep: float = 0.002,
        start: tuple[int, float, float, float] | None = None,
        people: int = 0,
        door_closures: bool = False,
        dead_sonars: Sequence[int] = (),
    ) -> None:
        if not 0 < timestep <= 0.01:
            raise ValueError(f"timestep {timestep} s: expected in (0, 0.01]")
        if not 0 <= people <= MAX_PEOPLE:
            raise ValueError(f"people {people}: expected 0 to {MAX_PEOPLE} per floor")
        bad = [k for k in dead_sonars if not 0 <= k < SONARS]
        if bad:
            raise ValueError(f"dead sonar {bad[0]}: sonars are 0 to {SONARS - 1}")
        # People and door closures: the 2-D simulator's logic, from the map file.
        self._traffic: Any = None
        if people or door_closures:
            if building.source is None:
                raise ValueError(
                    "people and door closures need a building read from its map file "
                    "(Building.load): their logic reads it"
                )
            from situate import _native

            self._traffic = _native.Traffic(building.source, seed, people, door_closures)
        walking = self._traffic.people() if self._traffic is not None else []
        self.building = building
        self.base = base or BaseSpec()
        self.sonar_spec = sonar or SonarSpec()
        if self.sonar_spec.rays < 1:
            raise ValueError("a sonar casts at least 1 ray")
        self.timestep = timestep
        self.model: Any = mujoco.MjModel.from_xml_string(
            mjcf(building, self.base, timestep, len(walking))
        )
        self.data: Any = mujoco.MjData(self.model)
        self._rng = np.random.Generator(np.random.PCG64(seed))
        self._robot = self.model.body("robot").id
        self._left = self.model.joint("wheel_left").qposadr[0]
        self._right = self.model.joint("wheel_right").qposadr[0]
        self._left_v = self.model.joint("wheel_left").dofadr[0]
        self._right_v = self.model.joint("wheel_right").dofadr[0]
        self._robot_nq = max(self._left, self._right) + 1
        self._robot_nv = max(self._left_v, self._right_v) + 1
        floor, x, y, theta = start if start is not None else building.start
        self.place(floor, x, y, theta)
        # Every sonar's rays, in the robot's frame: sonar i at i·15°, spread across its cone.
        s = self.sonar_spec
        cone = math.radians(s.cone_deg)
        offsets = (
            np.linspace(-cone / 2, cone / 2, s.rays) if s.rays > 1 else np.zeros(1, dtype=float)
        )
        self._ray_angles = (np.arange(SONARS)[:, None] * (2 * math.pi / SONARS) + offsets).ravel()
        self._geomgroup = np.array(
            [0 if g in (ROBOT_GROUP, GONE_GROUP) else 1 for g in range(6)], np.uint8
        )
        self._command = (0.0, 0.0)
        self._moving = (0.0, 0.0)
        # The elevator: its logic (the 2-D simulator's), each car's servo, each landing door.
        self._elevator: Any = None
        if building.cars:
            if building.source is None:
                raise ValueError(
                    "a building with an elevator must be read from its map file (Building.load): "
                    "the elevator's logic reads it"
                )
            from situate import _native

            self._elevator = _native.Elevator(building.source, seed)
        self._lowest = min((f.level for f in building.floors), default=0)
        self._elevator_every = max(1, round(ELEVATOR_DT / timestep))
        self._steps = 0
        self._cars: list[tuple[float, float, str, float, float]] = (
            self._elevator.cars() if self._elevator else []
        )
        self._doors = [
            [
                (self.model.geom(door_name(f.level, c.id)).id, f.level, c.door)
                for f in building.floors
            ]
            for c in building.cars
        ]
        self._car_servo = [self.model.actuator(f"car{c.id}").id for c in building.cars]
        # Per car, the floor its doors were last shown open at and how far: unchanged, no update.
        self._door_shown: list[tuple[int | None, float] | None] = [None] * len(building.cars)
        # Each car's servo target (m, from the lowest floor) at the last two logic steps: the
        # target moves between them step by step, so the car runs smoothly, never by jerks.
        self._car_from = [0.0] * len(building.cars)
        self._car_to = [0.0] * len(building.cars)
        self._update_elevator()
        self._car_from = list(self._car_to)
        # Every map door's panel, open (shortened to its jamb) but the one the logic closed.
        self._panels = {
            (f.level, k): (self.model.geom(panel_name(f.level, k)).id, door)
            for f in building.floors
            for k, door in enumerate(f.doors)
        }
        self._closed: tuple[int, int] | None = None
        for geom, door in self._panels.values():
            self._door(geom, door, closed=False)
        self._people: list[tuple[int, float, float]] = walking
        self._dead = np.zeros(SONARS, dtype=bool)
        self._dead[list(dead_sonars)] = True
        self._update_traffic()
        mujoco.mj_forward(self.model, self.data)
        self._presses = [0, 0]  # attempts, presses
        self._said: list[Utterance] = []
        self._delivered_at: float | None = None

    # ----- state -----

    def place(self, floor: int, x: float, y: float, theta: float) -> None:
        """Puts the robot at rest at a pose, and its odometry's origin there."""
        self.building.floor(floor)  # KeyError for a floor the building lacks
        d = self.data
        # The robot's joints come first (its free joint, its wheels), the cars' after.
        d.qpos[: self._robot_nq] = 0
        d.qvel[: self._robot_nv] = 0
        d.qpos[0:3] = (x, y, floor * FLOOR_HEIGHT + 0.001)
        d.qpos[3:7] = (math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2))
        mujoco.mj_forward(self.model, d)
        self._odom = [0.0, 0.0, 0.0, 0.0, 0.0]
        self._wheels = (float(d.qpos[self._left]), float(d.qpos[self._right]))
        self._floor = floor

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return float(self.data.time)

    def pose(self) -> Pose:
        """The robot's true pose."""
        d = self.data
        w, _, _, z = d.qpos[3:7]
        theta = 2 * math.atan2(float(z), float(w))
        level = round(float(d.qpos[2]) / FLOOR_HEIGHT)
        return Pose(float(d.qpos[0]), float(d.qpos[1]), wrap(theta), level)

    def velocity(self) -> tuple[float, float]:
        """The robot's true forward speed (m/s) and turn rate (rad/s)."""
        d = self.data
        theta = self.pose().theta
        v = float(d.qvel[0]) * math.cos(theta) + float(d.qvel[1]) * math.sin(theta)
        return v, float(d.qvel[5])

    def tilt(self) -> float:
        """How far the chassis leans from upright, rad (a base that tipped over is not upright)."""
        _w, x, y, _z = (float(q) for q in self.data.qpos[3:7])
        # The body's z axis in the world: its z component is the cosine of the tilt.
        cz = 1 - 2 * (x * x + y * y)
        return math.acos(max(-1.0, min(1.0, cz)))

    def cars(self) -> list[CarView]:
        """The cars as the elevator's logic has them (the physical car follows it), car 1 first."""
        return [CarView(pos, door, phase) for pos, door, phase, _, _ in self._cars]

    def car_height(self, k: int) -> float:
        """Car `k`'s (0-based) floor plate's height, m: where its servo has it."""
        return float(
            self.data.qpos[self.model.joint(f"car{self.building.cars[k].id}").qposadr[0]]
        ) + (self._lowest * FLOOR_HEIGHT)

    def people(self) -> list[tuple[int, float, float]]:
        """Each person's ``(floor, x, y)`` now, floor by floor."""
        return list(self._people)

    def place_person(self, k: int, floor: int, x: float, y: float, until: float) -> None:
        """Moves person `k` (tests, scenarios).

        It stands at ``(x, y)`` on `floor` until time `until` (s), then walks on.
        """
        if self._traffic is None or not self._traffic.place_person(k, floor, x, y, until):
            raise IndexError(f"no person {k}: {len(self._people)} people in the building")
        self._update_traffic()

    def closed_door(self) -> tuple[int, int] | None:
        """The map's door closed now: ``(floor, k)``, door `k` of the floor's `doors`."""
        return self._closed

    @property
    def arm(self) -> tuple[int, int]:
        """The arm's counters: pushes tried and pushes that hit a button."""
        return self._presses[0], self._presses[1]

    @property
    def said(self) -> list[Utterance]:
        """What the robot said so far."""
        return list(self._said)

    @property
    def delivered_at(self) -> float | None:
        """When the message was said in the office (simulated time, s), if it was."""
        return self._delivered_at

    def odometry(self) -> Odometry:
        """The wheel odometry, in the frame of the start pose."""
        x, y, t, v, w = self._odom
        return Odometry(x, y, t, v, w)

    # ----- commands and steps -----

    def command(self, v: float, w: float) -> None:
        """The base's velocity command (m/s, rad/s): kept until the next one."""
        if not (math.isfinite(v) and math.isfinite(w)):
            raise ValueError(f"a command must be finite: v={v}, w={w}")
        self._command = (v, w)

    def press(self, label: int, reach: float = ARM_REACH, fov: float = ARM_FOV) -> bool:
        """The arm pushes the button for `label`, as the 2-D arm: whether it hit one.

        A call button (any label) in the lobby of the robot's floor, or the floor panel (the
        label is the floor) of the car the robot is in, within `reach` (m, from the robot's
        centre) and `fov` (rad, either side of ahead), the robot on the side it faces.
        """
        self._presses[0] += 1
        p = self.pose()
        hit = self._elevator is not None and bool(
            self._elevator.press(label, p.floor, p.x, p.y, p.theta, reach, fov, self.time)
        )
        self._presses[1] += int(hit)
        return hit

    def say(self, text: str) -> None:
        """The robot says `text`: the delivery, when it is in the office."""
        p = self.pose()
        self._said.append(Utterance(self.time, p.floor, p.x, p.y, text))
        if self._delivered_at is None and self.building.in_office(p.floor, p.x, p.y):
            self._delivered_at = self.time

    def advance(self, seconds: float) -> None:
        """Runs the physics steps of `seconds` (rounded to whole steps)."""
        for _ in range(max(0, round(seconds / self.timestep))):
            self.step()

    def step(self) -> None:
        """One physics step: the elevator, the controller, the motors, the world, the odometry."""
        if self._elevator is not None and self._steps % self._elevator_every == 0:
            p = self.pose()
            self._elevator.step(self.time, ELEVATOR_DT, p.floor, p.x, p.y, p.theta)
            self._cars = self._elevator.cars()
            self._car_from = list(self._car_to)
            self._update_elevator()
        if self._traffic is not None and self._steps % self._elevator_every == 0:
            p = self.pose()
            self._traffic.step(self.time, ELEVATOR_DT, p.floor, p.x, p.y)
            self._update_traffic()
        if self._cars:
            frac = (self._steps % self._elevator_every + 1) / self._elevator_every
            for k, servo in enumerate(self._car_servo):
                start, end = self._car_from[k], self._car_to[k]
                self.data.ctrl[servo] = start + (end - start) * frac if start != end else end
        self._steps += 1
        b, dt = self.base, self.timestep
        v_cmd = min(max(self._command[0], -b.max_v), b.max_v)
        w_cmd = min(max(self._command[1], -b.max_w), b.max_w)
        v0, w0 = self._moving
        v = v0 + min(max(v_cmd - v0, -b.acc_v * dt), b.acc_v * dt)
        w = w0 + min(max(w_cmd - w0, -b.acc_w * dt), b.acc_w * dt)
        self._moving = (v, w)
        d = self.data
        d.ctrl[0] = (v - w * b.track / 2) / b.wheel_radius
        d.ctrl[1] = (v + w * b.track / 2) / b.wheel_radius
        mujoco.mj_step(self.model, d)
        self._integrate_odometry()

    def _update_elevator(self) -> None:
        """Each car's servo target where the logic has it (eased), each landing door shortened."""
        for k, (pos, door, phase, start, end) in enumerate(self._cars):
            if phase == "travel" and abs(end - start) > 1e-9:
                u = min(max((pos - start) / (end - start), 0.0), 1.0)
                pos = start + (end - start) * u * u * (3 - 2 * u)
            self._car_to[k] = (pos - self._lowest) * FLOOR_HEIGHT
            on = round(pos) if phase != "travel" else None
            if self._door_shown[k] == (on, door):
                continue  # its doors as they are (most steps: nothing moves)
            self._door_shown[k] = (on, door)
            for geom, level, seg in self._doors[k]:
                self._shut(geom, seg, 1.0 if level != on else 1.0 - door)

    def _shut(self, geom: int, seg: Segment, closed: float) -> None:
        """A door's panel across `closed` (0 … 1) of its opening `seg`, from its first end."""
        x0, y0, x1, y1 = seg
        length = math.hypot(x1 - x0, y1 - y0)
        if length < 1e-9:
            return
        half = max(closed * length / 2, 0.0005)
        ux, uy = (x1 - x0) / length, (y1 - y0) / length
        m = self.model
        m.geom_size[geom][0] = half
        m.geom_pos[geom][0] = x0 + ux * half
        m.geom_pos[geom][1] = y0 + uy * half

    def _door(self, geom: int, seg: Segment, closed: bool) -> None:
        """A map door's panel: across its opening when closed, else not there at all.

        An open door's panel touches nothing and no ray sees it (as no geom at all: a stub of it
        at the jamb would change the contacts of every run, people and closures or not).
        """
        m = self.model
        self._shut(geom, seg, 1.0)
        m.geom_contype[geom] = m.geom_conaffinity[geom] = 1 if closed else 0
        m.geom_group[geom] = 0 if closed else GONE_GROUP
        m.geom_rgba[geom][3] = 1.0 if closed else 0.0

    def _update_traffic(self) -> None:
        """The people where the logic has them; the closed door's panel shut, the others open."""
        if self._traffic is None:
            return
        self._people = self._traffic.people()
        for k, (level, x, y) in enumerate(self._people):
            self.data.mocap_pos[k] = (x, y, level * FLOOR_HEIGHT)
        closed = self._traffic.closed_door()
        if closed != self._closed:
            for door in (self._closed, closed):
                if door is not None and door in self._panels:
                    geom, seg = self._panels[door]
                    self._door(geom, seg, closed=door == closed)
            self._closed = closed

    def _integrate_odometry(self) -> None:
        b, dt = self.base, self.timestep
        left, right = float(self.data.qpos[self._left]), float(self.data.qpos[self._right])
        dl = (left - self._wheels[0]) * b.wheel_radius
        dr = (right - self._wheels[1]) * b.wheel_radius
        self._wheels = (left, right)
        ds = (dl + dr) / 2
        dth = (dr - dl) / b.track
        x, y, t, _, _ = self._odom
        mid = t + dth / 2
        x, y = x + ds * math.cos(mid), y + ds * math.sin(mid)
        self._odom = [x, y, wrap(t + dth), ds / dt, dth / dt]

    # ----- sensors -----

    def _eye(self) -> np.ndarray[Any, Any]:
        d = self.data
        return np.array([d.qpos[0], d.qpos[1], d.qpos[2] + SONAR_HEIGHT], dtype=np.float64)

    def sonar(self) -> np.ndarray[Any, Any]:
        """The 24 ranges now (from the robot's centre), with noise and missed echoes."""
        s = self.sonar_spec
        theta = self.pose().theta
        angles = self._ray_angles + theta
        n = len(angles)
        vec = np.zeros((n, 3), dtype=np.float64)
        vec[:, 0] = np.cos(angles)
        vec[:, 1] = np.sin(angles)
        dist = np.full(n, -1.0, dtype=np.float64)
        geomid = np.full(n, -1, dtype=np.int32)
        cutoff = s.max_range + 1.0
        mujoco.mj_multiRay(
            self.model,
            self.data,
            self._eye(),
            vec.ravel(),
            self._geomgroup,
            1,
            self._robot,
            geomid,
            dist,
            None,
            n,
            cutoff,
        )
        dist = np.where(dist < 0, np.inf, dist).reshape(SONARS, s.rays).min(axis=1)
        noisy = dist + self._rng.normal(0.0, s.noise, SONARS) if s.noise > 0 else dist
        missed = self._rng.random(SONARS) < s.dropout
        out = np.where(
            missed | self._dead | ~np.isfinite(noisy) | (noisy > s.max_range), s.max_range, noisy
        ).clip(s.min_range, s.max_range)
        return out.astype(np.float32)

    def barcodes(self) -> list[tuple[int, float, float]]:
        """Barcodes in range and view, facing the robot, not hidden.

        Each as ``(id, bearing, distance)``, nearest first.
        """
        p = self.pose()
        eye = self._eye()
        codes = list(self.building.floor(p.floor).barcodes)
        # A car's panel is there when the car stands at the robot's floor (as in 2-D).
        codes += [
            _car_code(c)
            for c, state in zip(self.building.cars, self._cars, strict=True)
            if round(state[0]) == p.floor
        ]
        seen = []
        for code in codes:
            dx, dy = code.x - p.x, code.y - p.y
            dist = math.hypot(dx, dy)
            if dist > BARCODE_RANGE or dist < 1e-9:
                continue
            bearing = wrap(math.atan2(dy, dx) - p.theta)
            if abs(bearing) > BARCODE_FOV:
                continue
            if code.facing is not None:
                # Readable only from in front of the label (within 80° of the way it faces).
                facing_dot = -(math.cos(code.facing) * dx + math.sin(code.facing) * dy) / dist
                if facing_dot < math.sin(math.radians(10)):
                    continue
            ray = np.array([dx / dist, dy / dist, 0.0])
            hit = mujoco.mj_ray(
                self.model, self.data, eye, ray, self._geomgroup, 1, self._robot, None
            )
            # The label is on its wall's face: only something nearer hides it.
            if 0 <= hit < dist - WALL_THICKNESS:
                continue
            seen.append((code.id, bearing, dist))
        seen.sort(key=lambda s: (s[2], s[0]))
        return seen


def _car_code(c: Any) -> Any:
    from situate.physics.building import Barcode

    x, y, facing = c.panel
    return Barcode(c.barcode, x, y, facing)
