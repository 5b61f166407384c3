"""The delivery demo (demo/deliver.py: demo/courier) on the simulated robot, via `situate demo`.

Runs the `situate` program ($SITUATE_BIN, else the package's console script next to this
interpreter: the release build `scripts/python.sh` installs): a headless sample of seeds of the
whole delivery, and per-phase scenarios whose maps (maps/scenarios/) start the robot at that phase,
the sequencer told where to start and stop with DELIVER_FROM / DELIVER_TO. No timing
assertions: outcomes are read from the simulator's ground truth (`--json`).
"""

from __future__ import annotations

import ast
import importlib.util
import json
import math
import os
import random
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _binary() -> Path | None:
    given = os.environ.get("SITUATE_BIN")
    if given:
        return Path(given)
    script = Path(sys.executable).parent / "situate"
    return script if script.is_file() else None


BIN = _binary()
needs_bin = pytest.mark.usefixtures("situate_bin")


@pytest.fixture
def situate_bin() -> Path:
    """The program under test; its absence is a failure, not a skip."""
    if BIN is None or not BIN.is_file():
        pytest.fail("no situate program: run scripts/python.sh (or set SITUATE_BIN)")
    return BIN


def demo(
    seed: int,
    *,
    map_file: str | None = None,
    first: str | None = None,
    last: str | None = None,
    limit_s: float = 1800,
    extra: Sequence[str] = (),
) -> dict[str, Any]:
    assert BIN is not None
    cmd = [str(BIN), "demo", "--headless", "--json", "--seed", str(seed)]
    cmd += ["--python", sys.executable, "--limit-s", str(limit_s)]
    if map_file:
        cmd += ["--map", str(ROOT / map_file)]  # an absolute path stays as it is
    cmd += list(extra)
    env = dict(os.environ)
    env.pop("DELIVER_DEBUG", None)
    env["DELIVER_FROM"] = first or ""
    env["DELIVER_TO"] = last or ""
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    assert lines, f"no outcome from `situate demo`:\n{done.stdout}\n{done.stderr[-3000:]}"
    outcome: dict[str, Any] = json.loads(lines[-1])
    outcome["stderr"] = done.stderr[-3000:]
    return outcome


def why(out: dict[str, Any]) -> str:
    """An outcome for a failed assertion: the skills that faulted and the end of the program's
    log first (pytest cuts a long dict's repr short, and they say why a run went another way:
    a body that computed or blocked past its budget is switched off; on the simulated clock the
    time it waited for a CPU on a loaded machine does not count), then the rest."""
    first = ("delivered", "cycles", "skills_faulted", "sequencer_exit", "stderr")
    head = "\n".join(f"{k}: {out.get(k)!r}" for k in first)
    rest = {k: v for k, v in out.items() if k not in first}
    return f"{head}\n{rest!r}"


@needs_bin
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_whole_delivery_succeeds_headless(seed: int) -> None:
    out = demo(seed)
    assert out["delivered"], why(out)
    assert out["sequencer_exit"] == 0, out
    assert out["skill_runs"] > 0
    assert out["mission_time_s"] > 0


@needs_bin
def test_lab_exit_phase() -> None:
    # From the start pose in the cluttered lab to just outside its door.
    out = demo(4, first="lab", last="lab", limit_s=900)
    assert out["sequencer_exit"] == 0, out
    assert not out["delivered"]


@needs_bin
def test_hallways_to_the_lobby_phase() -> None:
    # From just outside the lab door: the route hints, hallway following, the junctions.
    out = demo(1, map_file="maps/scenarios/corridor.yaml", first="corridor", last="corridor")
    assert out["sequencer_exit"] == 0, out


@needs_bin
def test_lobby_and_car_phases() -> None:
    # From the corridor below the lobby: call, wait, identify the car, enter, ride, leave.
    out = demo(2, map_file="maps/scenarios/lobby.yaml", first="lobby", last="ride", limit_s=900)
    assert out["sequencer_exit"] == 0, out


@needs_bin
def test_fourth_floor_corridor_to_the_office() -> None:
    out = demo(1, map_file="maps/scenarios/fourth_floor.yaml", first="office", limit_s=600)
    assert out["delivered"], why(out)
    assert out["sequencer_exit"] == 0, out


@needs_bin
def test_another_building() -> None:
    # maps/scenarios/annex.yaml: other layout, two cars, goal floor 2, other route hints.
    out = demo(1, map_file="maps/scenarios/annex.yaml")
    assert out["delivered"], why(out)
    assert out["sequencer_exit"] == 0, out


HARD = ["--people", "3", "--door-closures", "--dead-sonar"]

#: Generated buildings (generator seed, extra `situate demo` arguments) whose deliveries failed
#: until the skills or the sequencer were mended; each names the failure it reproduced.
GENERATED_REGRESSIONS = [
    (20001, []),  # `until: wall` took a box in the corridor's mouth for the corridor's end
    (20027, []),  # follow_hallway turned into a T's branch after a bin in its corner
    (20023, []),  # a bin inside a side corridor's mouth hid the junction (clutter 0.86 m apart)
    (20034, []),  # lining up with the office's barcode drove through the office door
    (20014, []),  # homing lost the lab door's barcode near the wall, again and again
    (20025, []),  # a car on the lobby's end wall was never seen open by the patrol
    (20000, []),  # the route began facing along the corridor, not out of the lab door
    (20038, []),  # a door found in a line through the lab's clutter: "passed", still inside
    (20170, []),  # a junction the detector missed: followed to the corridor's end
    (20013, []),  # a car's door on an end wall, seen aslant: never boarded
    (20129, []),  # a crossing's stub just before the junction: turned to a wall, the mouth 1.3 m on
    # The hard set: people, doors closing, a dead sonar (HARD + its index).
    (20011, [*HARD, "11"]),  # the office door found in a line 36° off its wall, into the jamb
    (20088, [*HARD, "0"]),  # the car's open door unseen with the front sonar dead
    (20087, [*HARD, "23"]),  # a line through people across the way taken for the office wall
    (20197, [*HARD, "13"]),  # two bins across the corridor taken for the office barcode's wall
    (20049, [*HARD, "9"]),  # the turn after a 12 s look at the wall timed out before it began
    (20084, [*HARD, "20"]),  # stopped just out of the lab door, a jamb beside: no way made
    (20035, [*HARD, "19"]),  # turned at a side corridor's near corner, not its mouth
    (20148, [*HARD, "12"]),  # out of time while people kept the way to the lobby busy
    (20186, [*HARD, "2"]),  # `until: wall` at a T: round the corner first, down the branch
    (20133, [*HARD, "21"]),  # the same, turned into the branch the route then takes
    (20063, [*HARD, "23"]),  # cars on both end walls of a short lobby: each opened behind the robot
    (20021, [*HARD, "5"]),  # a car on the button's wall opened after the patrol walked past it
    (20099, [*HARD, "11"]),  # the goal floor's button hidden once while lining up: given up
    (20106, [*HARD, "18"]),  # turning round twice to start the patrol: the car beside closed
    (20061, [*HARD, "21"]),  # walked past an open car: turning round to face it, it closed
    (20176, [*HARD, "16"]),  # the office door closed: a corridor's mouth 1.1 m off taken for it
    (20111, [*HARD, "23"]),  # someone in the office just beyond its door: stopped short, thrice
]


@needs_bin
@pytest.mark.parametrize(("seed", "extra"), GENERATED_REGRESSIONS)
def test_generated_buildings_that_failed_now_deliver(
    seed: int, extra: list[str], tmp_path: Path
) -> None:
    out = demo(seed, map_file=str(_generated(seed, tmp_path)), extra=extra)
    assert out["delivered"], why(out)
    assert out["sequencer_exit"] == 0, out


#: The same for buildings of the generator's family 2 (the whole documented space), found with
#: issue 37's dev seeds (50000…; the benchmark's 30000… stay held out).
FAMILY_2_REGRESSIONS = [
    (50050, []),  # a box by the wall near a corridor's end kept the robot 1.3 m off it: never
    # taken for the end, the office barcode (its face away, a box beside it) never read
    (50044, [*HARD, "4"]),  # someone standing in the corridor taken for its end: turned back
    (50104, []),  # stopped in the lab's doorway (0.3 m past the wall): taken for a failed pass,
    # the robot looked for the lab door's barcode from outside, where it is never read
]


@needs_bin
@pytest.mark.parametrize(("seed", "extra"), FAMILY_2_REGRESSIONS)
def test_whole_space_buildings_that_failed_now_deliver(
    seed: int, extra: list[str], tmp_path: Path
) -> None:
    out = demo(seed, map_file=str(_generated(seed, tmp_path, family=2)), extra=extra)
    assert out["delivered"], why(out)
    assert out["sequencer_exit"] == 0, out


def _generated(seed: int, where: Path, family: int = 1) -> Path:
    assert BIN is not None
    building = where / f"g{seed}.yaml"
    # Family 1 by default: the generator the first regressions were found with (`map generate
    # --family 1` keeps each seed's building as it was before the generator drew the whole
    # documented space).
    family_args = ["--family", str(family)]
    made = subprocess.run(
        [str(BIN), "map", "generate", *family_args, "--seed", str(seed), "-o", str(building)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert made.returncode == 0, made.stderr
    return building


#: Buildings without route hints (`map generate --no-route`, generator seed) the explorer was
#: written on, each naming what it once got wrong.
NO_ROUTE = [
    5,  # none: the first building tried
    7,  # the exploration began along the far wall's normal, not facing it: no way made
    14,  # a wall with a door in it (the front sonar reads through) never "stayed": a loop
    9,  # the office barcode read aslant on turning back from a dead end: homing lost it
    50,  # read straight ahead, then lined up with from right in front: a box beside it
    # skewed the wall fitted, and the door was looked for in that line
    90,  # a door beside a junction, read with it as one opening, led back into a side corridor
    # explored already: round and round until the time was up
]


@needs_bin
@pytest.mark.parametrize("seed", NO_ROUTE)
def test_without_a_route_the_robot_explores_and_delivers(seed: int, tmp_path: Path) -> None:
    assert BIN is not None
    building = tmp_path / f"n{seed}.yaml"
    made = subprocess.run(
        [str(BIN), "map", "generate", "--no-route", "--seed", str(seed), "-o", str(building)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert made.returncode == 0, made.stderr
    # No hints at all (before the explorer, such a run never got past the lab's corridor:
    # "the call button is nowhere in sight").
    assert "route:" not in building.read_text(), "the building has route hints"
    out = demo(seed, map_file=str(building))
    assert out["delivered"], why(out)
    assert out["sequencer_exit"] == 0, out


@needs_bin
def test_a_task_of_several_stops_is_made_in_order_on_other_floors(tmp_path: Path) -> None:
    # Building 20003: floors 0 to 3. A message in the lobby of floor 1, then the office (3):
    # the robot boards twice, from two floors; the simulator judges each stop.
    out = demo(20003, map_file=str(_generated(20003, tmp_path)), extra=["--task", "lobby:1,office"])
    assert out["task_done"], out
    assert [s["stop"] for s in out["stops"]] == ["lobby:1", "office"]
    first, second = (s["made_at_s"] for s in out["stops"])
    assert 0 < first < second == out["task_time_s"], out
    # Going up for the office, the base changed hands between skills many times.
    assert out["drive_winner_changes"] > 10, out
    assert 0 < out["drive_held_cycles"] <= out["cycles"], out


@needs_bin
def test_a_task_the_building_cannot_hold_is_refused_naming_the_stop() -> None:
    assert BIN is not None
    done = subprocess.run(
        [str(BIN), "demo", "--headless", "--task", "lobby:1,lobby:9", "--python", sys.executable],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done
    assert "stop 2 `lobby:9`: the map has no floor 9" in done.stderr, done.stderr


@needs_bin
def test_the_reactive_robot_delivers_without_a_sequencer() -> None:
    # The experiment's baseline (demo/courier/reactive): a rule list every cycle, no phases.
    out = demo(1, extra=["--mode", "reactive"])
    assert out["delivered"], why(out)
    assert out["mode"] == "reactive"


@needs_bin
@pytest.mark.parametrize(
    "seed",
    [
        20002,  # in a car whose door shut before it was known to be in: walls all round
        20003,  # beside the office door, off at an angle: square to the corridor first
    ],
)
def test_the_reactive_robot_delivers_where_it_once_failed(seed: int, tmp_path: Path) -> None:
    out = demo(seed, map_file=str(_generated(seed, tmp_path)), extra=["--mode", "reactive"])
    assert out["delivered"], why(out)


@needs_bin
@pytest.mark.parametrize(
    ("seed", "task"),
    [
        # `until: wall` met at a bin beside the way, turned by avoidance: a wall across only
        (20008, "lobby:0,office"),
        # the junction's mouth seen just before counting began: counted from nearer the start
        (20022, "lobby:0,office"),
    ],
)
def test_the_reactive_robot_follows_the_office_route(seed: int, task: str, tmp_path: Path) -> None:
    building = str(_generated(seed, tmp_path))
    out = demo(seed, map_file=building, extra=["--mode", "reactive", "--task", task])
    assert out["task_done"], out


@needs_bin
@pytest.mark.parametrize(
    "seed",
    [
        # people in the corridor: avoidance turned the robot round, and the hallway follower
        # took it back the way it came; a closet of 1.8 m read as a car; a turn that ended
        # short was never issued again
        20000,
        # a person across the way ended `until: wall` (a wall now counts once it stayed 3 s)
        20012,
        # a dead sonar not yet found placed the lab door 1.5 m off, and every later placement
        # was held to that first one: the robot waited at the lab's wall for the half hour
        22010,
        # a lobby with four cars: car doors placed on the wrong wall again and again (now
        # only on the walls found: the button's, fitted as it homed, and the end walls)
        22016,
        # sonar 0 dead: filled in from its neighbours, which saw the car's jambs, it never
        # read the door open on the goal floor (now the live sonar nearest ahead watches it)
        24000,
        # no opening in sight from in front of the office's barcode (a wide door beside it is
        # seen too obliquely from there): it stood there for good (now it tries where the
        # route's hint says, once, as the sequenced robot does)
        24003,
        # the office's barcode lost homing on it, near its wall: the robot wandered for good
        # (now it looks for it square in front of its wall, on the side it was seen from)
        24016,
    ],
)
def test_the_reactive_robot_delivers_on_the_hard_set_where_it_once_failed(
    seed: int, tmp_path: Path
) -> None:
    hard = ["--people", "3", "--door-closures", "--dead-sonar", str(seed % 24)]
    building = str(_generated(seed, tmp_path))
    out = demo(seed, map_file=building, extra=["--mode", "reactive", *hard])
    assert out["delivered"], why(out)


@needs_bin
@pytest.mark.parametrize(
    ("seed", "task", "hard"),
    [
        # homed on the lab door's barcode aslant, into the doorway: the corridor beyond was
        # taken for the door, "passed" along it, and the route followed from there
        (24000, "lobby:0", False),
        # the same, with the door placed 37 degrees askew: the wall the barcode is on was
        # fitted from 1.3 m, through the door's jamb (now from 1.5 m to 3 m only)
        (24012, "lobby:-1", True),
    ],
)
def test_the_reactive_robot_leaves_the_lab_where_it_once_failed(
    seed: int, task: str, hard: bool, tmp_path: Path
) -> None:
    people = ["--people", "3", "--door-closures", "--dead-sonar", str(seed % 24)] if hard else []
    building = str(_generated(seed, tmp_path))
    out = demo(seed, map_file=building, extra=["--mode", "reactive", "--task", task, *people])
    assert out["task_done"], out


@needs_bin
def test_a_seed_replays_exactly() -> None:
    a = demo(5, map_file="maps/scenarios/fourth_floor.yaml", first="office", limit_s=600)
    b = demo(5, map_file="maps/scenarios/fourth_floor.yaml", first="office", limit_s=600)
    for key in ("delivered", "mission_time_s", "cycles", "skill_runs"):
        assert a[key] == b[key], key


# ----- the sequencer's own geometry, without a robot ----------------------------------------


def _demo_on_path() -> None:
    """Puts demo/ on the path: the package `courier` is there, beside the entry programs."""
    if str(ROOT / "demo") not in sys.path:
        sys.path.insert(0, str(ROOT / "demo"))


def _entry(name: str) -> ModuleType:
    """Imports the entry program demo/NAME.py as `situate demo` runs it (the package beside it)."""
    _demo_on_path()
    spec = importlib.util.spec_from_file_location(name, ROOT / "demo" / f"{name}.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_entry_programs_run_the_package() -> None:
    _demo_on_path()
    from courier.main import run

    # Imported, they only name the package's program (run as a program, they run it).
    assert _entry("deliver").run is run
    assert _entry("reactive").run is run


def _imports(path: Path, package: str) -> set[str]:
    """The modules ``path`` imports (every import: also under TYPE_CHECKING, in functions)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join([*up, base] if base else up)
            found.add(base)
            found.update(f"{base}.{a.name}" for a in node.names)
    return found


def test_no_module_of_the_demo_imports_one_that_imports_it_back() -> None:
    demo = ROOT / "demo"
    modules: dict[str, Path] = {}
    for path in demo.rglob("*.py"):
        parts = list(path.relative_to(demo).with_suffix("").parts)
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        graph[name] = {m for m in _imports(path, package) if m in modules and m != name}
    # The two designs share the link, the geometry and the mission, never each other's modules.
    for a, b in (("sequenced", "reactive"), ("reactive", "sequenced")):
        crossing = {
            m: i
            for m in graph
            for i in graph[m]
            if m.startswith(f"courier.{a}") and i.startswith(f"courier.{b}")
        }
        assert not crossing, f"the {a} design imports the {b} one's modules: {crossing}"
    # No circle: every module reaches only modules that do not reach it.
    for start in graph:
        seen: set[str] = set()
        todo = list(graph[start])
        while todo:
            m = todo.pop()
            assert m != start, f"{start} imports itself back (through {sorted(seen)})"
            if m not in seen:
                seen.add(m)
                todo.extend(graph[m])


def test_mission_reads_the_maps_mission_section() -> None:
    _demo_on_path()
    from courier.mission import Mission

    text = json.dumps(
        {
            "start": {"floor": -1, "x": 1.5, "y": 1.5, "theta": 0.0},
            "goal_floor": 4,
            "lab_door_barcode": 10,
            "call_button_barcode": 30,
            "office_barcode": 40,
            "car_barcode_first": 201,
            "cars": 4,
            "message": "Hi",
            "route": {"car_to_office": [{"turn": "right"}, {"home": 40}]},
        }
    )
    m = Mission.from_json(text)
    assert (m.goal_floor, m.start_floor, m.cars, m.message) == (4, -1, 4, "Hi")
    assert m.route["car_to_office"][1] == {"home": 40}


def test_heading_off_holds_exactly_outside_the_allowed_range_also_where_it_wraps() -> None:
    _demo_on_path()
    from courier.geometry import wrap
    from courier.sequenced.routes import heading_off

    for along_deg in (0, 45, 150, 179, -179, -120, 180):
        along = math.radians(along_deg)
        cond = heading_off(along, math.radians(60))
        # The monitor language's operators, as Python (the condition reads odom.theta only).
        as_python = cond.replace("&&", " and ").replace("||", " or ").replace("odom.theta", "t")
        for probe_deg in range(-179, 181, 7):
            t = math.radians(probe_deg)
            off = abs(wrap(t - along)) > math.radians(60)
            assert eval(as_python, {}, {"t": t}) == off, (along_deg, probe_deg, cond)


def test_a_side_is_open_when_a_sonar_near_square_to_it_reads_past_a_corridors_wall() -> None:
    _demo_on_path()
    from courier.geometry import SONARS, bearing_of
    from courier.sequenced.explore import SIDE_OPEN_M, side_open

    # A corridor 2 m wide, a wall 1 m ahead: a dead end, open on neither side.
    ranges = []
    for i in range(SONARS):
        b = bearing_of(i)
        ahead, across = math.cos(b), abs(math.sin(b))
        ranges.append(
            min(1.0 / ahead if ahead > 0.01 else 4.0, 1.0 / across if across > 0.01 else 4.0)
        )
    assert not side_open(ranges, 1.0)
    assert not side_open(ranges, -1.0)
    # The left wall gone (a corridor crossing to the left, an L): open on the left only.
    left = [i for i in range(SONARS) if abs(bearing_of(i) - math.pi / 2) <= math.radians(20)]
    for i in left:
        ranges[i] = 4.0
    assert side_open(ranges, 1.0)
    assert not side_open(ranges, -1.0)
    # A door's jamb-to-jamb view narrower than that reads no farther than the limit: closed.
    for i in left:
        ranges[i] = SIDE_OPEN_M
    assert not side_open(ranges, 1.0)


def test_side_walls_are_the_nearest_square_to_each_side_and_corners_count_only_when_asked() -> None:
    _demo_on_path()
    from courier.geometry import SONARS, bearing_of
    from courier.sequenced.routes import side_walls

    ranges = []
    for i in range(SONARS):
        b = bearing_of(i)
        across = math.sin(b)
        ranges.append(4.0 if abs(across) < 0.25 else (0.9 if across > 0 else 1.1) / abs(across))
    left, right = side_walls(ranges)
    assert (round(left, 6), round(right, 6)) == (0.9, 1.1)
    # A corner 0.5 m away at 30° to the left: a wall of the way for recentring (30°-150°),
    # none for the corridor's width (60°-120° only).
    ranges[2] = 0.5
    assert math.isclose(side_walls(ranges)[0], 0.25)
    assert math.isclose(side_walls(ranges, 30.0)[0], 0.9)


def test_pose_methods_are_the_formulas_they_replaced_to_the_last_bit() -> None:
    # A run replays exactly only while every projection keeps its operations and their order.
    _demo_on_path()
    from courier.geometry import Pose, wrap

    rng = random.Random(36)
    for _ in range(5000):
        x, y, th, px, py = (rng.uniform(-60.0, 60.0) for _ in range(5))
        th = rng.choice([th, math.pi, -math.pi, 0.0, wrap(th)])
        h, d = rng.uniform(-7.0, 7.0), rng.uniform(-5.0, 5.0)
        p = Pose(x, y, th)
        c, s = math.cos(th), math.sin(th)
        assert p.turn_to(h) == wrap(h - th)
        assert p.heading_of(h) == wrap(th + h)
        assert p.bearing_to(px, py) == wrap(math.atan2(py - y, px - x) - th)
        assert p.along(px, py, h) == (px - x) * math.cos(h) + (py - y) * math.sin(h)
        assert p.across(px, py) == -(px - x) * s + (py - y) * c
        assert p.ahead(-d) == (x - d * c, y - d * s)  # "back d": the same float as "- d *"
        assert p.seen_at(h, d) == (x + d * math.cos(th + h), y + d * math.sin(th + h))
        assert p.from_robot(px, py) == (x + c * px - s * py, y + s * px + c * py)
        # abs of a heading difference is the same either way round (follow_to_wall's check).
        assert abs(wrap(h - th)) == abs(wrap(th - h))


def test_an_opening_on_the_other_side_of_the_barcode_or_off_its_wall_is_not_its_door() -> None:
    _demo_on_path()
    from courier.sequenced.behaviours import not_its_door

    # Robot frame, left positive: the barcode 0.9 m ahead, 0.1 m to the left, on the wall
    # square ahead (normal 0); the route's door to its left.
    at = (0.9, 0.1)
    door = {"seen": True, "x": 0.9, "y": 0.85, "width": 1.0, "normal": 0.0}
    assert not_its_door(door, at, "left", 40) is None
    assert not_its_door(door, at, None, 40) is None
    # The next room's door, or a corridor's mouth, on the other side: not it, and said why.
    other = {"seen": True, "x": 0.9, "y": -0.8, "width": 1.0, "normal": 0.0}
    assert not_its_door(other, at, "left", 40) == (
        "to the right of barcode 40 (the route's door is to the left)"
    )
    assert not_its_door(other, at, "right", 40) is None
    # Without a hint the side is open; too far from the barcode is never its door.
    assert not_its_door(other, at, None, 40) is None
    far = {"seen": True, "x": 0.9, "y": -2.0, "width": 1.0, "normal": 0.0}  # near jamb 1.6 m off
    assert not_its_door(far, at, "right", 40) == "1.6 m to the right of barcode 40"
    # An opening in another wall, seen through the door (a corridor's end beyond it): not it.
    beyond = {"seen": True, "x": 2.0, "y": 0.6, "width": 1.2, "normal": 0.0}
    assert not_its_door(beyond, at, "left", 40) == "in a wall 1.1 m beyond the wall of barcode 40"
    assert not_its_door({**beyond, "x": 1.2}, at, "left", 40) is None  # 0.3 m: its wall, misplaced
    # Without the barcode's place, the side is the robot's own.
    assert not_its_door(other, None, "left", None) == (
        "to the right of the barcode (the route's door is to the left)"
    )
    assert not_its_door(None, at, "left", 40) is None


def test_the_way_out_square_to_the_corridor_is_the_one_the_sonars_see_farthest_across() -> None:
    _demo_on_path()
    from courier.geometry import SONARS, bearing_of
    from courier.sequenced.delivery import along_corridor

    # Out of a door into a corridor 1.9 m wide running left-right: the robot 0.95 m from each
    # wall, its sonars read each wall along their axes, and 4 m (no echo) along the corridor.
    def reading(i: int) -> float:
        b = bearing_of(i)
        across = abs(math.cos(b))
        return min(4.0, 0.95 / across) if across > 1e-9 else 4.0

    ranges = [reading(i) for i in range(SONARS)]
    square = along_corridor(ranges, 0.0)
    assert square == 8.0
    # A way out turned 35° (a line fitted through clutter on the far wall): its sides see walls.
    for off in (math.radians(35), math.radians(-40)):
        assert along_corridor(ranges, off) < square - 4.0, off
