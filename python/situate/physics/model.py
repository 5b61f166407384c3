"""The MuJoCo model (MJCF) of a building and the delivery robot's base: `mjcf`.

Generated as text from a `Building` (the map file the 2-D simulator reads) and a `BaseSpec`:

- **The building.** Every floor is a slab at ``level * FLOOR_HEIGHT`` with a hole for each
  shaft; every wall a thin box (`WALL_THICKNESS`, centred on its line; ends meeting at corners
  lengthened to close them) `WALL_HEIGHT` tall; an obstacle is solid, its outside exactly its
  polygon. Each car's shaft walls and landing doors stand on every floor `SHAFT_HEIGHT` tall, a
  panel in every door of the map; the cars are floor plates on vertical slide joints under a
  position servo; people are mocap cylinders. `PhysicsWorld` moves the cars, shortens the doors
  and places the people.
- **The base.** A cylinder chassis (the map's robot radius, `BaseSpec.mass`) on two driven
  wheels (hinge joints, `BaseSpec.wheel_radius`, `track` apart, rubber on the floor:
  `friction`) and two frictionless casters. Each wheel has a velocity-controlled motor whose
  torque is limited to `wheel_torque`: a command the wheels cannot follow (too quick a start,
  a turn against a wall) is not followed, and the wheels may slip.

Text rather than `MjSpec`: readable, printable for a bug report, and the same on MuJoCo 3.2 to
4.x (decision 0013).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from situate.physics.building import Building, Segment

#: Height between two floors, m.
FLOOR_HEIGHT = 4.0
#: Walls' height above their floor, m.
WALL_HEIGHT = 2.2
#: Walls' thickness, m: the map's barcodes are 2 cm off their wall's line, on its face.
WALL_THICKNESS = 0.04
#: Geom group of the robot's own geoms: the sonar's and the reader's rays do not see them.
ROBOT_GROUP = 3
#: A floor slab's thickness, m.
SLAB = 0.1
#: The height of the shafts' walls and the landing doors: up to the next floor's slab, m.
SHAFT_HEIGHT = FLOOR_HEIGHT - SLAB - 0.01
#: A car's mass, kg (its weight compensated: the counterweight).
CAR_MASS = 200.0
#: The car's position servo: stiffness N/m and damping N·s/m (critically damped).
CAR_KP = 1.0e6
CAR_KV = 2 * math.sqrt(CAR_KP * CAR_MASS)
#: A person: a cylinder this wide (the 2-D simulator's `PERSON_RADIUS`) and tall, m.
PERSON_RADIUS = 0.25
PERSON_HEIGHT = 1.7
#: Where a person not in the building stands (none such: every person is on a floor).
_AWAY = (0.0, 0.0, -1000.0)


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


def door_name(level: int, car: int) -> str:
    """The landing door of a car on a floor."""
    return f"{_tag(level)}_car{car}_door"


def panel_name(level: int, door: int) -> str:
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
            geoms.append(_box(panel_name(f.level, k), door, z, WALL_HEIGHT, WALL_THICKNESS, (0, 0)))
        for c in building.cars:
            geoms += _walls(f"{tag}_car{c.id}_", list(c.walls), z, SHAFT_HEIGHT)
            geoms.append(
                _box(door_name(f.level, c.id), c.door, z, SHAFT_HEIGHT, WALL_THICKNESS, (0, 0))
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
