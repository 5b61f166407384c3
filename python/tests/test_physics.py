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
from situate.physics.model import BaseSpec
from situate.physics.world import PhysicsWorld, SonarSpec

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
    assert Building.from_json(out.stdout, source=str(path)) == Building.load(path)
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
    names = [w.model.geom(g).name for g in range(w.model.ngeom)]
    for f in b.floors:
        tag = f"f{f.level}".replace("-", "m")
        assert any(n.startswith(f"{tag}_slab_") for n in names), f.level
    # The robot starts in the lab with something within reach of its sonars.
    assert (w.sonar() < 4.0).any()


def _drive_to(w: PhysicsWorld, x: float, y: float, tol: float = 0.03, limit: float = 30.0) -> None:
    """Drives the base to a point (turning towards it, then ahead) and stops it there."""
    end = w.time + limit
    while w.time < end:
        p = w.pose()
        d = math.hypot(x - p.x, y - p.y)
        if d < tol:
            break
        turn = math.remainder(math.atan2(y - p.y, x - p.x) - p.theta, 2 * math.pi)
        w.command(min(0.3 * max(0.0, math.cos(turn)), d) if abs(turn) < 0.5 else 0.0, 2.0 * turn)
        w.advance(0.05)
    w.command(0.0, 0.0)
    w.advance(0.5)


def _face(w: PhysicsWorld, theta: float) -> None:
    for _ in range(200):
        turn = math.remainder(theta - w.pose().theta, 2 * math.pi)
        if abs(turn) < 0.02:
            break
        w.command(0.0, 2.0 * turn)
        w.advance(0.05)
    w.command(0.0, 0.0)
    w.advance(0.5)


def _car_opened(w: PhysicsWorld, within_s: float = 30.0) -> int:
    """Runs the world until a car's door is open (simulated time, at most `within_s`): which car."""
    for _ in range(round(within_s / 0.1)):
        w.advance(0.1)
        came = next((k for k, c in enumerate(w.cars()) if c.phase == "open"), None)
        if came is not None:
            return came
    raise AssertionError(f"no car opened within {within_s} s: {w.cars()}")


def test_a_car_comes_when_called_and_carries_the_robot_to_the_floor_chosen() -> None:
    b = Building.load(REPO / "maps" / "default.yaml")
    # Before the call button of the basement lobby (15, 17.98), facing it.
    w = PhysicsWorld(b, seed=1, start=(-1, 15.0, 17.45, math.pi / 2))
    assert not w.press(30, reach=0.3), "out of reach"
    assert w.press(30)
    assert w.arm == (2, 1)
    # A car comes, and its landing door opens: until then, the door is a wall.
    came = _car_opened(w)
    car = b.cars[came]
    assert w.cars()[came].position == -1
    assert w.cars()[came].door == 1
    assert abs(w.car_height(came) - -1 * 4.0) < 0.01
    cx = (car.x0 + car.x1) / 2
    # In, before the panel (2 cm off the back wall), facing it: floor 4.
    _drive_to(w, cx, 17.3)
    _drive_to(w, cx, car.y1 - 0.55)
    _face(w, math.pi / 2)
    assert car.contains(w.pose().x, w.pose().y)
    assert w.press(4)
    # The door shuts, the car rises with the robot on its floor plate, and opens on floor 4.
    rose = False
    for _ in range(600):
        w.advance(0.1)
        c = w.cars()[came]
        rose = rose or c.phase == "travel"
        if c.phase == "open" and c.position == 4:
            break
    assert rose
    assert w.cars()[came].phase == "open"
    p = w.pose()
    assert p.floor == 4, p
    assert car.contains(p.x, p.y), p
    assert w.tilt() < 0.05
    assert abs(w.car_height(came) - 16.0) < 0.01
    # The sonar behind the robot (180°) reads the open doorway and the lobby beyond it.
    assert w.sonar()[12] > 1.5
    # Out into the floor 4 lobby.
    _drive_to(w, cx, 17.0)
    assert w.pose().floor == 4
    assert w.pose().y < car.y0


def test_a_closed_landing_door_is_a_wall() -> None:
    b = Building.load(REPO / "maps" / "default.yaml")
    car = b.cars[0]
    cx = (car.x0 + car.x1) / 2
    # Before car 1's closed basement door, facing it: the sonar ahead reads the door.
    w = PhysicsWorld(b, seed=2, start=(-1, cx, car.y0 - 0.8, math.pi / 2))
    w.advance(0.2)
    assert abs(float(w.sonar()[0]) - 0.8) < 0.1
    w.command(0.3, 0.0)
    w.advance(5.0)
    assert w.pose().y < car.y0 - b.robot_radius + 0.02


def test_a_turn_in_a_moving_car_is_measured_by_the_wheels() -> None:
    b = Building.load(REPO / "maps" / "default.yaml")
    w = PhysicsWorld(b, seed=1, start=(-1, 15.0, 17.45, math.pi / 2))
    assert w.press(30)
    came = _car_opened(w)
    car = b.cars[came]
    w.place(-1, (car.x0 + car.x1) / 2, car.y1 - 0.55, math.pi / 2)
    w.advance(0.5)
    assert w.press(4)
    for _ in range(200):
        if w.cars()[came].phase == "travel":
            break
        w.advance(0.05)
    w.advance(0.3)
    # Half a turn on the spot while the car speeds up: the wheels' count of it is the body's
    # (a servo target that moved by the logic's 10 ms steps shook the plate: 0.3 rad apart).
    odom0, true0 = w.odometry().theta, w.pose().theta
    for _ in range(60):
        w.command(0.0, 1.2)
        w.advance(0.05)
    w.command(0.0, 0.0)
    w.advance(1.0)
    assert w.cars()[came].phase == "travel"
    measured = math.remainder(w.odometry().theta - odom0, 2 * math.pi)
    turned = math.remainder(w.pose().theta - true0, 2 * math.pi)
    assert abs(turned) > 2.0, turned
    assert abs(measured - turned) < 0.1, (measured, turned)


def test_a_person_is_a_body_the_sonar_sees_and_the_robot_cannot_pass(room: Building) -> None:
    # People are the 2-D simulator's (situate._native.Traffic), kinematic bodies here.
    w = PhysicsWorld(room, seed=4, sonar=QUIET, people=1)
    assert w.people(), "no person placed"
    w.advance(0.2)
    clear = float(w.sonar()[0])
    w.place_person(0, 0, 3.5, 3.0, until=1e9)  # 1.5 m ahead of the robot, standing there
    assert w.people()[0] == (0, 3.5, 3.0)
    w.advance(0.2)
    assert clear > 3.0, clear
    assert abs(float(w.sonar()[0]) - (1.5 - 0.25)) < 0.03, w.sonar()[0]
    w.command(0.3, 0.0)
    w.advance(8.0)
    # The robot's rim stops at the person's (a little give: contact is soft in MuJoCo).
    assert 2.6 < w.pose().x < 3.5 - 0.25 - room.robot_radius + 0.02, w.pose()
    with pytest.raises(IndexError, match="no person 9"):
        w.place_person(9, 0, 1.0, 1.0, until=0.0)


def test_a_closed_door_is_a_panel_until_it_opens_again(room: Building) -> None:
    w = PhysicsWorld(room, seed=3, sonar=QUIET, door_closures=True)
    assert w.closed_door() is None
    for _ in range(100):  # a closure comes 60-180 s after the last
        if w.closed_door() is not None:
            break
        w.advance(5.0)
    assert w.closed_door() == (0, 0), "the room's door never closed"
    # Below the closed door, facing it: the sonar ahead reads the panel 1 m away.
    w.place(0, 5.0, 5.0, math.pi / 2)
    w.advance(0.2)
    assert abs(float(w.sonar()[0]) - 1.0) < 0.05, w.sonar()[0]
    for _ in range(100):  # it stays closed 20-60 s
        if w.closed_door() is None:
            break
        w.advance(1.0)
    assert w.closed_door() is None, "the door never opened again"
    w.advance(0.2)
    assert float(w.sonar()[0]) > 2.0, w.sonar()[0]


def test_a_dead_sonar_reads_max_range(room: Building) -> None:
    w = PhysicsWorld(room, seed=4, sonar=QUIET, dead_sonars=[12])
    w.advance(0.2)
    # Sonar 12 looks west at the wall 2 m away: dead, it reads max_range; the others read.
    assert float(w.sonar()[12]) == QUIET.max_range
    assert abs(float(w.sonar()[6]) - 3.0) < 0.03, w.sonar()[6]  # north wall, 3 m
    with pytest.raises(ValueError, match="dead sonar 24"):
        PhysicsWorld(room, dead_sonars=[24])
