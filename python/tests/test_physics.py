"""The physics robot's world (situate.physics): the building from the map file, in MuJoCo.

Each test puts the robot somewhere in a small building drawn for it (or the default one) and
checks one claim of `situate/physics/world.py` against geometry worked out by hand: the sonar
reads a wall where it is, the reader sees a barcode only in line of sight, the base has mass
(it takes distance to stop, its motors' torque bounds how fast it speeds up), walls stop it,
and a run is the same, step for step, for the same seed and commands.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from support import REPO, situate

from situate.physics.building import Building
from situate.physics.world import BaseSpec, PhysicsWorld, SonarSpec

# A 10 m by 6 m room on floor 0 with a door in its north wall (x 4.4..5.6) marked by barcode 10
# at x 4.0; a box (x 6..7, y 1..2); barcode 11 on the east wall (x 10, y 3), facing west; a lobby
# and an office so that the map is a whole building.
ROOM = """\
name: room
robot_radius: 0.25
elevator:
  travel_s_per_floor: 2.0
  door_move_s: 1.5
  open_s: [15, 25]
  arrive_s: [5, 20]
  cars:
    - {id: 1, rect: [12, 8, 14, 10], door: south, door_width: 1.2, barcode: 201}
floors:
  - level: 0
    name: ground
    walls:
      - {polyline: [[4.4, 6], [0, 6], [0, 0], [10, 0], [10, 6], [5.6, 6]]}
      - [11, 7.5, 15, 7.5]
    obstacles:
      - {name: box, rect: [6, 1, 7, 2]}
    doors:
      - {name: room, at: [4.4, 6, 5.6, 6], barcode: {id: 10, at: [4.0, 5.98], facing_deg: -90}}
    barcodes:
      - {id: 11, at: [9.98, 3.0], facing_deg: 180}
    lobby: {button: [11.5, 7.48], facing_deg: -90, barcode: 100}
  - level: 1
    name: top
    walls:
      - [11, 7.5, 15, 7.5]
      - {polyline: [[11, 7.5], [11, 3], [15, 3], [15, 7.5]]}
    lobby: {button: [11.5, 7.48], facing_deg: -90, barcode: 101}
    office:
      polygon: [[11, 3], [15, 3], [15, 5], [11, 5]]
      barcode: {id: 40, at: [13, 5.02], facing_deg: 90}
mission:
  start: {floor: 0, x: 2.0, y: 3.0, theta_deg: 0}
  goal_floor: 1
  lab_door_barcode: 10
  call_button_barcode: 100
  office_barcode: 40
  car_barcode_first: 201
  message: hello
"""

QUIET = SonarSpec(noise=0.0, dropout=0.0)


@pytest.fixture(scope="module")
def room(tmp_path_factory: pytest.TempPathFactory) -> Building:
    path = tmp_path_factory.mktemp("room") / "room.yaml"
    path.write_text(ROOM)
    return Building.load(path)


def test_the_building_is_the_map_files(room: Building) -> None:
    assert room.start == (0, 2.0, 3.0, 0.0)
    ground = room.floor(0)
    assert {b.id for b in ground.barcodes} == {10, 11, 100}
    assert ground.doors == ((4.4, 6.0, 5.6, 6.0),)
    assert room.cars[0].barcode == 201
    assert room.mission["office_barcode"] == 40
    with pytest.raises(KeyError, match="no floor 7"):
        room.floor(7)


def test_a_bad_map_is_refused_with_its_file_and_line(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(ROOM.replace("robot_radius: 0.25", "robot_radius: -1"))
    with pytest.raises(ValueError, match=r"bad\.yaml:2"):
        Building.load(bad)


def test_situate_map_show_prints_the_building(tmp_path: Path) -> None:
    path = tmp_path / "room.yaml"
    path.write_text(ROOM)
    out = situate("map", "show", str(path))
    assert out.returncode == 0, out.stderr
    shown = json.loads(out.stdout)
    assert shown["name"] == "room"
    assert shown["elevator"]["cars"][0]["door_side"] == "south"
    assert shown["floors"][0]["barcodes"] == [{"id": 11, "x": 9.98, "y": 3.0, "facing": math.pi}]
    assert Building.from_json(out.stdout) == Building.load(path)
    missing = situate("map", "show", str(tmp_path / "none.yaml"))
    assert missing.returncode == 3, missing
    assert "none.yaml" in missing.stderr


def test_the_sonar_reads_the_walls_where_they_are(room: Building) -> None:
    # At (2, 3) facing east: the west wall's face is 2 - 0.02 behind, the south wall's 3 - 0.02
    # to the right, the north wall's 3 - 0.02 to the left; ahead, the east wall is past 4 m.
    w = PhysicsWorld(room, sonar=QUIET)
    r = w.sonar()
    assert r.dtype == np.float32
    assert r.shape == (24,)
    assert r[0] == pytest.approx(4.0)  # no echo within reach: max_range
    assert r[12] == pytest.approx(1.98, abs=1e-3)
    assert r[6] == pytest.approx(2.98, abs=1e-3)
    assert r[18] == pytest.approx(2.98, abs=1e-3)
    # A sonar reads the nearest return across its cone: sonar 1 (15°) to the north wall at
    # 2.98 m is beyond reach along its axis (11.5 m) but its cone's edge (22.5°) is not either.
    w.place(0, 5.0, 1.5, 0.0)  # the box is 1 m ahead, from y 1 to 2
    assert w.sonar()[0] == pytest.approx(1.0, abs=1e-3)


def test_the_sonar_noise_and_dropouts_follow_the_seed(room: Building) -> None:
    noisy = SonarSpec(noise=0.05, dropout=0.2)
    a = [PhysicsWorld(room, seed=3, sonar=noisy).sonar() for _ in range(2)]
    b = PhysicsWorld(room, seed=4, sonar=noisy).sonar()
    assert np.array_equal(a[0], a[1])
    assert not np.array_equal(a[0], b)
    assert (a[0] == 4.0).sum() > (PhysicsWorld(room, sonar=QUIET).sonar() == 4.0).sum()


def test_the_reader_sees_a_barcode_only_in_line_of_sight_and_from_its_front(
    room: Building,
) -> None:
    # From (6, 3) facing east, barcode 11 (9.98, 3) is 3.98 m ahead.
    w = PhysicsWorld(room, start=(0, 6.0, 3.0, 0.0))
    seen = w.barcodes()
    assert [s[0] for s in seen] == [11]
    assert seen[0][1] == pytest.approx(0.0, abs=1e-6)
    assert seen[0][2] == pytest.approx(3.98, abs=1e-6)
    # From (5.5, 1.6) the box (x 6..7, y 1..2) hides it: the line to (9.98, 3) enters the box
    # at x 6 (y 1.76). 0.45 m to the north, the line passes above the box: seen.
    w.place(0, 5.5, 2.05, 0.0)
    assert [s[0] for s in w.barcodes()] == [11]
    w.place(0, 5.5, 1.6, 0.0)
    assert 11 not in [s[0] for s in w.barcodes()]
    # Behind the robot or outside ±60°: not seen.
    w.place(0, 6.0, 3.0, math.pi)
    assert 11 not in [s[0] for s in w.barcodes()]
    # The door's barcode (4.0, 5.98) faces south: seen from inside the room, not from outside.
    w.place(0, 4.0, 4.0, math.pi / 2)
    assert [s[0] for s in w.barcodes()] == [10]
    w.place(0, 4.0, 7.0, -math.pi / 2)
    assert 10 not in [s[0] for s in w.barcodes()]


def test_the_base_has_mass_its_motors_have_limits_and_walls_stop_it(room: Building) -> None:
    w = PhysicsWorld(room, start=(0, 2.0, 3.0, 0.0))
    w.advance(0.2)  # settles on its wheels
    assert w.tilt() < 0.01
    start = w.pose()
    # The controller ramps at acc_v = 1 m/s²: 0.5 m/s is reached after about 0.5 s, not at once.
    w.command(0.5, 0.0)
    w.advance(0.25)
    v, _ = w.velocity()
    assert 0.15 < v < 0.35, v
    w.advance(2.0)
    v, _ = w.velocity()
    assert v == pytest.approx(0.5, abs=0.02)
    # Stopping takes distance: from 0.5 m/s at 1 m/s², about 0.125 m.
    before = w.pose()
    w.command(0.0, 0.0)
    w.advance(1.5)
    after = w.pose()
    assert 0.08 < after.x - before.x < 0.2, (before, after)
    assert w.velocity()[0] == pytest.approx(0.0, abs=0.01)
    # The wheel odometry agrees with the truth on a straight run (no slip at 1 m/s²).
    odom = w.odometry()
    assert odom.x == pytest.approx(after.x - start.x, abs=0.01)
    # Weak motors cannot follow the ramp: 0.2 N·m per wheel on 22 kg gives at most ~0.23 m/s².
    weak = PhysicsWorld(room, base=BaseSpec(wheel_torque=0.2), start=(0, 2.0, 3.0, 0.0))
    weak.advance(0.2)
    weak.command(0.5, 0.0)
    weak.advance(1.0)
    assert weak.velocity()[0] < 0.3
    # Driven at a wall, the base stops at it and stays upright: its rim at the wall's face.
    w.place(0, 8.0, 3.0, 0.0)
    w.command(0.8, 0.0)
    w.advance(6.0)
    p = w.pose()
    assert p.x == pytest.approx(10.0 - 0.02 - room.robot_radius, abs=0.03), p
    assert w.tilt() < 0.05


def test_a_turn_on_the_spot_is_measured_by_the_wheels(room: Building) -> None:
    w = PhysicsWorld(room, start=(0, 2.0, 3.0, 0.0))
    w.advance(0.2)
    w.command(0.0, 1.0)
    w.advance(1.5)
    w.command(0.0, 0.0)
    w.advance(1.0)
    p, o = w.pose(), w.odometry()
    assert p.theta > 1.0
    assert o.theta == pytest.approx(p.theta, abs=0.05)
    assert math.hypot(p.x - 2.0, p.y - 3.0) < 0.05


def test_a_run_is_the_same_step_for_step(room: Building) -> None:
    def run(seed: int) -> list[tuple[float, ...]]:
        w = PhysicsWorld(room, seed=seed, start=(0, 2.0, 3.0, 0.0))
        out = []
        for k in range(40):
            w.command(0.4 + 0.01 * (k % 5), 0.5 * math.sin(k / 5))
            w.advance(0.1)
            p = w.pose()
            out.append((p.x, p.y, p.theta, *w.sonar().tolist()))
        return out

    assert run(7) == run(7)


def test_the_default_building_builds_every_floor() -> None:
    b = Building.load(REPO / "maps" / "default.yaml")
    w = PhysicsWorld(b)
    assert w.pose().floor == b.start[0]
    levels = {f.level for f in b.floors}
    assert {w.model.geom(f"slab{level}").id for level in levels}
    # The robot starts in the lab with something within reach of its sonars.
    assert (w.sonar() < 4.0).any()
