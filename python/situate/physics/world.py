"""The delivery robot in MuJoCo: a differential-drive base with mass and friction in the building.

`PhysicsWorld` builds a MuJoCo model from a `Building` (the map file the 2-D simulator reads) and
a `BaseSpec`, and runs it:

- **The building.** Every floor is a slab at ``level * FLOOR_HEIGHT``; every wall and shaft
  wall a thin box (`WALL_THICKNESS`, centred on its line; ends meeting at corners lengthened to
  close them) `WALL_HEIGHT` tall; an obstacle is solid, its outside exactly its polygon. The
  cars' shafts stand on every floor with their doors shut (a box over the door): cars that move
  and open are not built yet.
- **The base.** A cylinder chassis (the map's robot radius, `BaseSpec.mass`) on two driven
  wheels (hinge joints, `BaseSpec.wheel_radius`, `track` apart, rubber on the floor:
  `friction`) and two frictionless casters. Each wheel has a velocity-controlled motor whose
  torque is limited to `wheel_torque`: a command the wheels cannot follow (too quick a start,
  a turn against a wall) is not followed, and the wheels may slip.
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

try:
    import mujoco
except ImportError as e:  # pragma: no cover - depends on the installation
    raise ImportError(
        "the physics robot needs MuJoCo: pip install 'situate[physics]' (or pip install mujoco)"
    ) from e

#: Height between two floors, m.
FLOOR_HEIGHT = 4.0
#: Walls' height above their floor, m.
WALL_HEIGHT = 2.2
#: Walls' thickness, m: the map's barcodes are 2 cm off their wall's line, on its face.
WALL_THICKNESS = 0.04
#: The sonars' and the barcode reader's height above the floor, m.
SONAR_HEIGHT = 0.3
#: Sonars in the ring.
SONARS = 24
#: The barcode reader's range, m, and half field of view, rad (the 2-D simulator's).
BARCODE_RANGE = 5.0
BARCODE_FOV = math.radians(60)
#: Geom group of the robot's own geoms: the sonar's and the reader's rays do not see them.
ROBOT_GROUP = 3
#: Geom group of what is not there now (an open door's panel): no ray sees it.
GONE_GROUP = 5
#: A floor slab's thickness, m.
SLAB = 0.1
#: The height of the shafts' walls and the landing doors: up to the next floor's slab, m.
SHAFT_HEIGHT = FLOOR_HEIGHT - SLAB - 0.01
#: A car's mass, kg (its weight compensated: the counterweight).
CAR_MASS = 200.0
#: The car's position servo: stiffness N/m and damping N·s/m (critically damped).
CAR_KP = 1.0e6
CAR_KV = 2 * math.sqrt(CAR_KP * CAR_MASS)
#: The elevator logic's step, s (the 2-D simulator's step).
ELEVATOR_DT = 0.01
#: A person: a cylinder this wide (the 2-D simulator's `PERSON_RADIUS`) and tall, m.
PERSON_RADIUS = 0.25
PERSON_HEIGHT = 1.7
#: Most people per floor (the 2-D simulator's `--people` limit).
MAX_PEOPLE = 100
#: Where a person not in the building stands (none such: every person is on a floor).
_AWAY = (0.0, 0.0, -1000.0)
#: The arm's reach from the robot's centre, m, and how far off ahead a button may be, rad
#: (the 2-D `sim.arm`'s defaults).
ARM_REACH = 0.6
ARM_FOV = math.radians(25)


@dataclass(frozen=True)
class BaseSpec:
    """The base: its body, wheels and motors, and its controller's limits (SI units)."""

    #: The chassis' mass, kg (the wheels add 1 kg each).
    mass: float = 20.0
    wheel_radius: float = 0.08
    #: Distance between the wheels, m.
    track: float = 0.4
    #: Each wheel motor's torque limit, N·m.
    wheel_torque: float = 3.0
    #: Each wheel's velocity loop gain, N·m per rad/s.
    wheel_gain: float = 8.0
    #: Rubber on the floor: sliding friction coefficient.
    friction: float = 1.0
    #: The controller's limits, as the 2-D base's: m/s, rad/s, m/s², rad/s².
    max_v: float = 0.8
    max_w: float = 2.0
    acc_v: float = 1.0
    acc_w: float = 3.0


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


def _box(
    name: str, seg: Segment, z0: float, height: float, thickness: float, ext: tuple[float, float]
) -> str:
    """A wall box along a segment, lengthened by ``ext`` at its two ends."""
    x0, y0, x1, y1 = seg
    length = math.hypot(x1 - x0, y1 - y0)
    if length < 1e-9:
        return ""
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    x0, y0 = x0 - ux * ext[0], y0 - uy * ext[0]
    x1, y1 = x1 + ux * ext[1], y1 + uy * ext[1]
    half = (length + ext[0] + ext[1]) / 2
    angle = math.atan2(uy, ux)
    return (
        f'<geom name="{name}" type="box" size="{half:.6f} {thickness / 2:.6f} {height / 2:.6f}" '
        f'pos="{(x0 + x1) / 2:.6f} {(y0 + y1) / 2:.6f} {z0 + height / 2:.6f}" '
        f'euler="0 0 {angle:.6f}" class="wall"/>'
    )


def _tag(level: int) -> str:
    """A floor's part of a geom's name."""
    return f"f{level}".replace("-", "m")


def _door_name(level: int, car: int) -> str:
    """The landing door of a car on a floor."""
    return f"{_tag(level)}_car{car}_door"


def _panel_name(level: int, door: int) -> str:
    """The panel that closes door `door` (its index on the floor) of a floor."""
    return f"{_tag(level)}_door{door}"


def _walls(name: str, segs: list[Segment], z0: float, height: float = WALL_HEIGHT) -> list[str]:
    """Boxes for walls, centred on their lines.

    An end that meets another wall's end is lengthened by half the thickness: corners are closed.
    """
    ends: dict[tuple[int, int], int] = {}

    def key(x: float, y: float) -> tuple[int, int]:
        return (round(x * 1000), round(y * 1000))

    for x0, y0, x1, y1 in segs:
        for k in (key(x0, y0), key(x1, y1)):
            ends[k] = ends.get(k, 0) + 1
    half = WALL_THICKNESS / 2
    out = []
    for i, s in enumerate(segs):
        ext = (
            half if ends[key(s[0], s[1])] > 1 else 0.0,
            half if ends[key(s[2], s[3])] > 1 else 0.0,
        )
        geom = _box(f"{name}{i}", s, z0, height, WALL_THICKNESS, ext)
        if geom:
            out.append(geom)
    return out


def _solid(name: str, polygon: tuple[tuple[float, float], ...], z0: float) -> list[str]:
    """Boxes along a polygon's edges, each inside the polygon.

    So its outside is exactly the polygon, as an obstacle of the 2-D simulator (its outline).
    """
    n = len(polygon)
    area2 = sum(
        polygon[i][0] * polygon[(i + 1) % n][1] - polygon[(i + 1) % n][0] * polygon[i][1]
        for i in range(n)
    )
    inward = 1.0 if area2 > 0 else -1.0  # counter-clockwise: the inside is on the left
    half = WALL_THICKNESS / 2
    out = []
    for i in range(n):
        (ax, ay), (bx, by) = polygon[i], polygon[(i + 1) % n]
        length = math.hypot(bx - ax, by - ay)
        if length < 1e-9:
            continue
        nx, ny = -(by - ay) / length * inward * half, (bx - ax) / length * inward * half
        seg = (ax + nx, ay + ny, bx + nx, by + ny)
        out.append(_box(f"{name}_{i}", seg, z0, WALL_HEIGHT, WALL_THICKNESS, (0.0, 0.0)))
    return out


def _slab(
    name: str,
    bounds: tuple[float, float, float, float],
    holes: list[tuple[float, float, float, float]],
    z: float,
) -> list[str]:
    """A floor slab (top at `z`) over `bounds`, with a hole for each shaft in `holes`.

    Cut into a grid by the holes' edges; each row's cells outside every hole are merged.
    """
    x0, y0, x1, y1 = bounds
    xs = sorted({x0, x1, *(v for h in holes for v in (h[0], h[2]) if x0 < v < x1)})
    ys = sorted({y0, y1, *(v for h in holes for v in (h[1], h[3]) if y0 < v < y1)})

    def solid(cx: float, cy: float) -> bool:
        return not any(h[0] < cx < h[2] and h[1] < cy < h[3] for h in holes)

    out = []
    for j in range(len(ys) - 1):
        cy, hy = (ys[j] + ys[j + 1]) / 2, (ys[j + 1] - ys[j]) / 2
        i = 0
        while i < len(xs) - 1:
            if not solid((xs[i] + xs[i + 1]) / 2, cy):
                i += 1
                continue
            k = i
            while k + 1 < len(xs) - 1 and solid((xs[k + 1] + xs[k + 2]) / 2, cy):
                k += 1
            cx, hx = (xs[i] + xs[k + 1]) / 2, (xs[k + 1] - xs[i]) / 2
            out.append(
                f'<geom name="{name}_{j}_{i}" type="box" size="{hx:.6f} {hy:.6f} {SLAB / 2}" '
                f'pos="{cx:.6f} {cy:.6f} {z - SLAB / 2:.6f}" class="slab"/>'
            )
            i = k + 1
    return out


def mjcf(building: Building, base: BaseSpec, timestep: float, people: int = 0) -> str:
    """The MuJoCo model (MJCF) of the building and the robot, the robot at the origin.

    With `people` kinematic people (mocap bodies, placed by `PhysicsWorld`) and a panel in
    every door of the map (shut here: `PhysicsWorld` opens them all but a closed one).
    """
    r = building.robot_radius
    wr = base.wheel_radius
    geoms: list[str] = []
    holes = [(c.x0, c.y0, c.x1, c.y1) for c in building.cars]
    for f in building.floors:
        z = f.level * FLOOR_HEIGHT
        tag = _tag(f.level)
        geoms += _slab(f"{tag}_slab", building.bounds(f.level), holes, z)
        geoms += _walls(f"{tag}_wall", list(f.walls), z)
        for k, polygon in enumerate(f.obstacles):
            geoms += _solid(f"{tag}_obstacle{k}", polygon, z)
        for k, door in enumerate(f.doors):
            geoms.append(
                _box(_panel_name(f.level, k), door, z, WALL_HEIGHT, WALL_THICKNESS, (0, 0))
            )
        for c in building.cars:
            geoms += _walls(f"{tag}_car{c.id}_", list(c.walls), z, SHAFT_HEIGHT)
            geoms.append(
                _box(_door_name(f.level, c.id), c.door, z, SHAFT_HEIGHT, WALL_THICKNESS, (0, 0))
            )
    lowest = min((f.level for f in building.floors), default=0) * FLOOR_HEIGHT
    cars = []
    servos = []
    for c in building.cars:
        hx, hy = (c.x1 - c.x0) / 2 - 0.005, (c.y1 - c.y0) / 2 - 0.005
        cx, cy = (c.x0 + c.x1) / 2, (c.y0 + c.y1) / 2
        cars.append(
            f'<body name="car{c.id}" pos="{cx:.6f} {cy:.6f} {lowest}" '
            f'gravcomp="1"><joint name="car{c.id}" type="slide" axis="0 0 1"/>'
            f'<geom name="car{c.id}_floor" type="box" size="{hx:.6f} {hy:.6f} {SLAB / 2}" '
            f'pos="0 0 {-SLAB / 2}" mass="{CAR_MASS}" class="car"/></body>'
        )
        servos.append(
            f'<position name="car{c.id}" joint="car{c.id}" kp="{CAR_KP}" kv="{CAR_KV:.3f}"/>'
        )
    bodies = [
        f'<body name="person{k}" mocap="true" pos="{_AWAY[0]} {_AWAY[1]} {_AWAY[2]}">'
        f'<geom name="person{k}" type="cylinder" size="{PERSON_RADIUS} {PERSON_HEIGHT / 2}" '
        f'pos="0 0 {PERSON_HEIGHT / 2}" rgba="0.85 0.45 0.2 1"/></body>'
        for k in range(people)
    ]
    chassis_h = 0.3
    caster = 0.03
    return f"""
<mujoco model="situate-{building.name}">
  <compiler angle="radian"/>
  <option timestep="{timestep}" integrator="implicitfast" cone="elliptic"/>
  <default>
    <default class="wall"><geom rgba="0.7 0.7 0.72 1" friction="0.6 0.005 0.0001"/></default>
    <default class="slab"><geom rgba="0.9 0.9 0.88 1" friction="1 0.005 0.0001"/></default>
    <default class="car">
      <geom rgba="0.8 0.75 0.6 1" friction="1 0.005 0.0001" contype="2" conaffinity="2"/>
    </default>
    <default class="robot"><geom contype="3" conaffinity="3" group="{ROBOT_GROUP}"/></default>
  </default>
  <worldbody>
    {"".join(geoms)}
    <body name="robot" pos="0 0 0" childclass="robot">
      <freejoint name="robot"/>
      <geom name="chassis" type="cylinder" size="{r} {chassis_h / 2}"
            pos="0 0 {wr + 0.02 + chassis_h / 2}" mass="{base.mass}"
            rgba="0.2 0.4 0.8 1" friction="0.3 0.005 0.0001"/>
      <geom name="caster_front" type="sphere" size="{caster}" pos="{r - 0.07} 0 {caster}"
            mass="0.2" condim="1" priority="1"/>
      <geom name="caster_back" type="sphere" size="{caster}" pos="{-(r - 0.07)} 0 {caster}"
            mass="0.2" condim="1" priority="1"/>
      <body name="wheel_left" pos="0 {base.track / 2} {wr}">
        <joint name="wheel_left" type="hinge" axis="0 1 0" damping="0.01"/>
        <geom type="cylinder" size="{wr} 0.006" euler="1.5707963 0 0" mass="1"
              friction="{base.friction} 0.005 0.0001" priority="1" condim="4"/>
      </body>
      <body name="wheel_right" pos="0 {-base.track / 2} {wr}">
        <joint name="wheel_right" type="hinge" axis="0 1 0" damping="0.01"/>
        <geom type="cylinder" size="{wr} 0.006" euler="1.5707963 0 0" mass="1"
              friction="{base.friction} 0.005 0.0001" priority="1" condim="4"/>
      </body>
    </body>
    {"".join(cars)}
    {"".join(bodies)}
  </worldbody>
  <actuator>
    <velocity name="left" joint="wheel_left" kv="{base.wheel_gain}"
              forcelimited="true" forcerange="{-base.wheel_torque} {base.wheel_torque}"/>
    <velocity name="right" joint="wheel_right" kv="{base.wheel_gain}"
              forcelimited="true" forcerange="{-base.wheel_torque} {base.wheel_torque}"/>
    {"".join(servos)}
  </actuator>
</mujoco>
"""


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
                (self.model.geom(_door_name(f.level, c.id)).id, f.level, c.door)
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
            (f.level, k): (self.model.geom(_panel_name(f.level, k)).id, door)
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
