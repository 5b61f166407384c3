"""The delivery benchmark: how often the demo robot delivers, on buildings it was not tuned on.

Runs ``situate demo --headless --json`` over sets of (building, run seed) pairs and writes
``docs/delivery.md`` (the report: success rate per set against its target, the headless speed,
and every failure with the command that reproduces it) and ``docs/delivery-results.json`` (the
raw outcomes). The sets:

- ``default``: ``maps/default.yaml`` with run seeds 10000, 10001, … (no test uses them);
- ``generated``: buildings from ``situate map generate --seed G`` for G = 30000, 30001, …
  (held out: no test or tuning uses them), one run each with run seed G. (20000 to 20199 were
  the set until the skills were debugged on its failures; those failures are now tests in
  ``python/tests/test_demo.py``, and the set moved to seeds nothing was looked at on.)
- ``generated-hard``: the same buildings with people walking, doors closed now and then and
  one dead sonar (``situate demo --people 3 --door-closures --dead-sonar K``, K from the seed).
- ``unseen-hard``: the hard set on other generator seeds (``UNSEEN_SEEDS``), whose failures
  no one had read when it was first reported.
- ``no-route``: the same generator's buildings without route hints (``situate map generate
  --no-route``): the robot is told only the barcodes and floors, and explores (docs/delivery.md).
- ``hand-drawn`` and ``hand-drawn-hard``: the buildings of ``maps/hand-drawn/``, drawn by hand
  from docs/maps.md (layouts and route hints the generator never makes), run seeds from
  ``HAND_SEEDS``, plain and with people, door closures and a dead sonar.
- ``physics-default`` and ``physics-generated``: the same two kinds of building on the physics
  robot (``situate demo --physics``: MuJoCo, through ROS 2, docs/physics.md), with the same
  sequencer and skills; and the first physics run made twice, its two recordings compared
  channel by channel (the same seed must give the same run); ``physics-generated-hard``: the
  hard buildings on the physics robot (its people and door closures are the 2-D simulator's
  logic). ``--physics-only`` runs these alone and rewrites only the report's physics section.

Usage, from the repository's top directory::

    .venv/bin/python scripts/delivery.py [--default 100] [--generated 200] [--jobs 1]
        [--bin target/release/situate] [--no-report]

A set the ``situate`` program cannot build (an option it does not know) is reported as not run,
with the reason. Failures are rerun once without ``--json`` to show the sequencer's last lines;
a failure that second run does not reproduce (it delivered, or ended at another time: the run was
not a function of its seed) is reported as not reproduced, with the first run's own outcome.
Every run is of copies taken when the benchmark begins (the program, ``demo/`` and ``maps/``), so
that a build or an edit of the checkout beside it changes no run.

The report's coverage table counts the generated sets' runs by the features each building drew
(the comment block ``situate map generate`` writes at the top of the map: where the cars are
relative to the call button, the doors' open time, a box beside the office barcode, the
corridors' widths, the kinds of junction; docs/maps.md, "Generated buildings"), so a case the
robot handles badly shows in the numbers even when the set as a whole meets its target.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_SEEDS = 10000
GENERATED_SEEDS = 30000
#: The unseen set's generator seeds: the other sets' failures, listed in each report, are read
#: to find the robot's faults (each fix is for a case the docs allow, never for one seed), and
#: so those sets are no longer quite unseen after a fix. This range's runs were never read
#: before it was first reported: whether fixes carry over shows here. Once its failures have
#: been read to fix something, move it to a range never used.
UNSEEN_SEEDS = 70000
#: Buildings drawn by hand from docs/maps.md (``maps/hand-drawn/``), each run plain and hard
#: (issue 37's "hand-drawn held-out buildings" target), with run seeds from this.
HAND_SEEDS = 40000
#: Targets per set: the share delivered (issue 37: the whole documented space, and no route;
#: the default building: issue 12; the physics sets: issue 41).
TARGETS = {
    "default": 0.99,
    "generated": 0.98,
    "generated-hard": 0.95,
    "unseen-hard": 0.95,
    "no-route": 0.80,
    "hand-drawn": 0.95,
    "hand-drawn-hard": 0.90,
    "physics-default": 0.95,
    "physics-generated": 0.90,
    "physics-generated-hard": 0.90,
}
#: Headless speed target, x real time.
SPEED_TARGET = 500.0
#: The physics robot's speed target (slowest run), x real time.
PHYSICS_SPEED_TARGET = 20.0
#: Where the physics section of docs/delivery.md begins and ends.
PHYSICS_BEGIN = "<!-- physics: written by scripts/delivery.py -->"
PHYSICS_END = "<!-- /physics -->"


@dataclass
class Case:
    """One run: a set, a map (None: the demo's own), the generator's seed, the run's seed."""

    set: str
    seed: int
    map: Path | None = None
    map_seed: int | None = None
    #: More arguments of ``situate demo`` (the simulator's people and faults, ``--physics``).
    extra: list[str] = field(default_factory=list)
    outcome: dict[str, Any] = field(default_factory=dict)
    tail: list[str] = field(default_factory=list)
    #: A failure's second run (the one ``tail`` is from): its outcome line, and whether it
    #: ended as the first run did (a headless run is a function of its seed: when it did not,
    #: ``tail`` tells nothing about the failure, `failure_class` says so).
    again: str = ""
    reproduced: bool = True
    #: What the failed first run itself said besides its outcome (its standard error's last
    #: lines: a sequencer's traceback, say).
    stderr: list[str] = field(default_factory=list)
    #: What the generated building drew (its map's comment block); empty for a drawn map.
    features: dict[str, str | list[str]] = field(default_factory=dict)
    #: More arguments of ``situate map generate`` (``--family 1``).
    gen_extra: list[str] = field(default_factory=list)

    def demo_args(self) -> list[str]:
        """The arguments of ``situate demo`` that reproduce this run (beside ``--headless``)."""
        args = ["--seed", str(self.seed)]
        if self.map is not None:
            args += ["--map", str(self.map)]
        return args + self.extra


def find_binary(given: str | None) -> Path:
    """The ``situate`` program: ``given``, ``$SITUATE_BIN`` or the cargo build's."""
    candidates = [given, os.environ.get("SITUATE_BIN")]
    target = os.environ.get("CARGO_TARGET_DIR")
    for base in ([Path(target)] if target else []) + [ROOT / "target"]:
        candidates += [str(base / "release" / "situate")]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    sys.exit("no release situate program: run `cargo build --release -p situate_cli` first")


def generate(binary: Path, seed: int, out: Path, extra: list[str]) -> str | None:
    """Writes generated building ``seed`` to ``out``; the error, if the program refused."""
    cmd = [str(binary), "map", "generate", "--seed", str(seed), *extra, "-o", str(out)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        return (done.stderr.strip() or done.stdout.strip() or "failed").splitlines()[0]
    return None


def read_features(path: Path) -> dict[str, str | list[str]]:
    """The features block at the top of a generated map: ``#   key: value`` lines."""
    out: dict[str, str | list[str]] = {}
    for line in path.read_text().splitlines():
        if not line.startswith("#"):
            break
        m = re.match(r"#   (\w+): (.*)$", line)
        if m is None:
            continue
        key, value = m.group(1), m.group(2).strip()
        if value.startswith("[") and value.endswith("]"):
            out[key] = [v.strip() for v in value[1:-1].split(",") if v.strip()]
        else:
            out[key] = value
    return out


#: The coverage table's rows: a feature's title, its key in the map's block and its values in
#: order, each with its label. A list-valued feature (the cars' walls) counts a building under
#: every value it holds; ``none`` is a building that holds none.
COVERAGE: list[tuple[str, str, list[tuple[str, str]]]] = [
    (
        "lobby",
        "lobby",
        [("facing", "button across from the entry"), ("corner", "button beside the entry")],
    ),
    (
        "cars' walls (vs the call button's)",
        "car_walls",
        [
            ("same", "a car on the button's wall"),
            ("side", "a car on a side wall"),
            ("across", "a car across from the button"),
            ("!same", "no car on the button's wall"),
        ],
    ),
    (
        "doors' open time (open_s)",
        "open_s_bucket",
        [("short", "min under 10 s"), ("medium", "min 10-13 s"), ("long", "min 13 s or more")],
    ),
    (
        "clutter beside the office barcode",
        "clutter_near_barcode",
        [("yes", "a box within 0.6 m, on its wall"), ("no", "none")],
    ),
    (
        "corridor widths",
        "corridor_width",
        [
            ("narrow", "all in the range's lower third"),
            ("middle", "all in its middle third"),
            ("wide", "all in its upper third"),
            ("mixed", "each over the whole range"),
        ],
    ),
    ("start floor: junction to the lobby", "junction_lobby", [("T", "T"), ("+", "+"), ("L", "L")]),
    ("goal floor: the lobby corridor's end", "junction_goal", [("T", "T"), ("L", "L")]),
    (
        "goal floor: junction to the office",
        "junction_office",
        [("none", "none (office on the cross corridor)"), ("T", "T"), ("+", "+"), ("L", "L")],
    ),
    (
        "junctions passed on the way",
        "junctions_passed",
        [("T", "a T"), ("+", "a +"), ("none", "none")],
    ),
]


def has_feature(features: dict[str, str | list[str]], key: str, value: str) -> bool:
    """Whether a building's features hold ``value`` under ``key`` (``!v``: not ``v``)."""
    got = features.get(key)
    if got is None:
        return False
    held = got if isinstance(got, list) else [got]
    if value.startswith("!"):
        return value[1:] not in held
    if value == "none" and isinstance(got, list):
        return not held
    return value in held


def coverage_section(sets: dict[str, list[Case]]) -> list[str]:
    """Delivered per feature value of the generated buildings, one column per generated set.

    A value delivered below its set's target is in bold; ``-``: no building of the set has it.
    """
    names = [n for n, cases in sets.items() if any(c.features for c in cases)]
    # A generated set whose buildings' features were not read: said, never left out silently.
    unread = [n for n, cases in sets.items() if any(c.map_seed is not None for c in cases)]
    unread = [n for n in unread if n not in names]
    if not names:
        if unread:
            return [
                "## Coverage by feature of the building",
                "",
                f"Not counted: the features of {', '.join(unread)} were not read.",
                "",
            ]
        return []
    out = [
        "## Coverage by feature of the building",
        "",
        "Runs delivered per feature of the generated building (what `situate map generate` "
        'drew, from the comment block at the top of each map; docs/maps.md, "Generated '
        'buildings"). A building counts under each value it has (cars on two kinds of wall: '
        "under both); a rate below its set's target is in bold.",
        "",
        "| feature | value | " + " | ".join(names) + " |",
        "|---|---|" + "---|" * len(names),
    ]
    for title, key, values in COVERAGE:
        for k, (value, label) in enumerate(values):
            cells = []
            for name in names:
                runs = [c for c in sets[name] if has_feature(c.features, key, value)]
                ok = sum(1 for c in runs if c.outcome.get("delivered"))
                if not runs:
                    cells.append("-")
                    continue
                cell = f"{ok}/{len(runs)} ({100 * ok / len(runs):.0f} %)"
                weak = ok < TARGETS.get(name, 0.0) * len(runs)
                cells.append(f"**{cell}**" if weak else cell)
            out.append(f"| {title if k == 0 else ''} | {label} | " + " | ".join(cells) + " |")
    return [*out, ""]


def knows(binary: Path, command: str, option: str) -> bool:
    """Whether ``situate COMMAND`` takes ``option`` (from its help)."""
    done = subprocess.run(
        [str(binary), command, "--help"], capture_output=True, text=True, check=False
    )
    return option in done.stdout


def snapshot(binary: Path, into: Path) -> Path:
    """Copies the program, and the demo with its maps, into ``into``; the program's copy.

    Every run of the benchmark uses these copies (`run`), so that a build or an edit of the
    checkout while the benchmark runs (a release build beside it replaces the program) changes
    no run: each is a function of its seed and of the program as it was when the benchmark began.
    """
    into.mkdir(parents=True, exist_ok=True)
    program = into / binary.name
    shutil.copy2(binary, program)
    for part in ("demo", "maps"):
        shutil.copytree(ROOT / part, into / part, ignore=shutil.ignore_patterns("__pycache__"))
    return program


def demo_command(binary: Path, case: Case, snap: Path | None = None) -> list[str]:
    """The command that runs ``case`` headless.

    With ``snap`` (see `snapshot`): on the snapshot's robot file, sequencer and hand-drawn maps
    (the physics robot's demo finds its own).
    """
    args = case.demo_args()
    if snap is not None and "--physics" not in case.extra:
        if case.map is not None and not case.map.is_absolute():
            args[args.index(str(case.map))] = str(snap / case.map)
        demo = snap / "demo"
        args += ["--robot", str(demo / "robot.yaml"), "--sequencer", str(demo / "deliver.py")]
    return [str(binary), "demo", "--headless", "--python", sys.executable, *args]


def run(binary: Path, case: Case, snap: Path | None = None) -> Case:
    """Runs one headless demo; fills ``case.outcome`` (and ``tail`` for a failure)."""
    base = demo_command(binary, case, snap)
    done = subprocess.run(
        [*base, "--json"], cwd=ROOT, capture_output=True, text=True, check=False, timeout=600
    )
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    if lines:
        case.outcome = json.loads(lines[-1])
    else:
        case.outcome = {"delivered": False, "error": (done.stderr.strip() or "no outcome")[-400:]}
    if not case.outcome.get("delivered"):
        case.stderr = [ln for ln in done.stderr.splitlines() if ln.strip()][-3:]
        again = subprocess.run(base, cwd=ROOT, capture_output=True, text=True, check=False)
        narrative = [ln for ln in again.stdout.splitlines() if ln.startswith("[")]
        case.tail = narrative[-6:]
        case.again, case.reproduced = rerun_outcome(case.outcome, again.stdout)
    return case


#: The demo's outcome line (without ``--json``; ``demo --physics:`` for the physics robot's):
#: delivered at, or not after, a simulated time.
OUTCOME_LINE = re.compile(
    r"^demo(?: --physics)?: "
    r"(?:message delivered at t = (?P<at>[\d.]+) s|NOT delivered after (?P<after>[\d.]+) s)"
)


def rerun_outcome(first: dict[str, Any], text: str) -> tuple[str, bool]:
    """The second run's outcome line in ``text``, and whether it ended as ``first`` did.

    The same seed must give the same run: not delivered, at the same simulated time (to the
    line's tenth of a second). A second run that delivered, or ended at another time, or said
    no outcome, went another way than the first (a fault on a loaded machine, say). A first run
    that said no outcome (an error) is reproduced by a second that says none either.
    """
    line = next((ln for ln in text.splitlines() if OUTCOME_LINE.match(ln)), "")
    m = OUTCOME_LINE.match(line)
    if "mission_time_s" not in first:
        return line, m is None
    if m is None or m["after"] is None or first.get("delivered"):
        return line, False
    ended = first.get("mission_time_s")
    same = isinstance(ended, (int, float)) and f"{ended:.1f}" == f"{float(m['after']):.1f}"
    return line, same


def digest(path: Path) -> dict[str, str]:
    """Per channel of a recording, a hash of its messages in order (as the test does)."""
    import hashlib

    from mcap.reader import make_reader

    hashes: dict[str, Any] = {}
    with path.open("rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            h = hashes.setdefault(channel.topic, hashlib.sha256())
            h.update(json.dumps(json.loads(message.data), sort_keys=True).encode())
    return {topic: h.hexdigest() for topic, h in hashes.items()}


def same_twice(binary: Path, case: Case, tmp: Path) -> str:
    """Runs ``case`` twice with ``--record``: whether the two recordings are the same."""
    digests = []
    for k in (1, 2):
        path = tmp / f"twice-{k}.mcap"
        cmd = [str(binary), "demo", "--headless", "--python", sys.executable]
        cmd += [*case.demo_args(), "--json", "--record", str(path)]
        subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False, timeout=1200)
        if not path.exists():
            return "not recorded"
        digests.append(digest(path))
    a, b = digests
    differ = sorted(t for t in set(a) | set(b) if a.get(t) != b.get(t))
    if not differ:
        return f"yes: the same messages on all {len(a)} channels"
    return (
        f"**no**: {len(differ)} of {len(set(a) | set(b))} channels differ ({', '.join(differ[:5])})"
    )


#: The class of a failure its second run did not reproduce (see `rerun_outcome`).
NOT_REPRODUCED = "not reproduced: the same seed run again went another way"


def failure_class(case: Case) -> str:
    """A short name for why a run failed: the failure's text without its particulars.

    Read from the second run's narrative (the first is run with ``--json``, quiet): a failure
    that run did not reproduce is classed as such, never by the lines of a run that went
    another way (a run that delivered ends in phase 13, and was once counted there).
    """
    if not case.reproduced:
        return NOT_REPRODUCED
    failed = next((ln for ln in reversed(case.tail) if "mission failed" in ln), "")
    text = failed.split("mission failed: ", 1)[-1]
    if text.startswith("route "):
        # "route LEG, step N (follow hallway, until junction, …) failed": the leg and the kind.
        leg = text.split(",", 1)[0]
        inside = text[text.find("(") + 1 : text.rfind(")")]
        keys = dict(part.strip().split(" ", 1) for part in inside.split(",") if " " in part.strip())
        kind = (
            f"until {keys['until']}"
            if "until" in keys
            else next((k for k in ("home", "pass", "turn") if k in keys), "step")
        )
        return f"{leg}: {kind}"
    if text:
        return re.sub(r"\d+", "N", text)
    phase = next((ln for ln in reversed(case.tail) if "phase " in ln), "")
    return phase.split("] ", 1)[-1][:60] or str(case.outcome.get("error", "?"))[:80]


def report(
    sets: dict[str, list[Case]],
    skipped: dict[str, str],
    wall_s: float,
    jobs: int = 1,
    speed_target: float = SPEED_TARGET,
) -> str:
    """The markdown of ``docs/delivery.md`` but its physics section (``jobs``: runs at a time)."""
    out = [
        "# Delivery benchmark",
        "",
        "How often the demo robot delivers its message, on buildings it was not tuned on. "
        "Regenerate with `.venv/bin/python scripts/delivery.py` (after "
        "`cargo build --release -p situate_cli`); each run is `situate demo --headless` with "
        "the arguments given below. Run seeds and generator seeds here are used by no test. "
        "The failures listed below are read to find the robot's faults (each fix is for a case "
        "the docs allow, never for a seed), so a set is not quite unseen once a fix followed "
        f"its failures: `unseen-hard` (generator seeds from {UNSEEN_SEEDS}) is the hard set on "
        "seeds whose failures no one had read when it was first reported, to show whether the "
        "fixes carry over. Speed is each run's simulated time over its wall time (from "
        "starting the sequencer to its exit, Python's start included), runs made "
        + (
            "one at a time."
            if jobs <= 1
            else f"{jobs} at a time on {os.cpu_count()} cores (sharing them: slower each)."
        ),
        "",
        "| set | runs | delivered | target | met | mean mission time (delivered) "
        "| speed x real time (min / mean) |",
        "|---|---|---|---|---|---|---|",
    ]
    speeds: list[float] = []
    for name, cases in sets.items():
        ok = [c for c in cases if c.outcome.get("delivered")]
        rate = len(ok) / len(cases) if cases else 0.0
        times = [float(c.outcome["mission_time_s"]) for c in ok]
        sp = [float(c.outcome["speedup"]) for c in cases if c.outcome.get("speedup")]
        speeds += sp
        target = TARGETS.get(name, 0.0)
        out.append(
            f"| {name} | {len(cases)} | {len(ok)} ({100 * rate:.1f} %) | ≥ {100 * target:.0f} % "
            f"| {'yes' if rate >= target else '**no**'} "
            f"| {statistics.fmean(times):.0f} s | "
            + (f"{min(sp):.0f} / {statistics.fmean(sp):.0f} |" if sp else "- |")
            if times
            else f"| {name} | {len(cases)} | 0 | ≥ {100 * target:.0f} % | **no** | - | - |"
        )
    for name, why in skipped.items():
        out.append(
            f"| {name} | not run: {why} | | ≥ {100 * TARGETS.get(name, 0):.0f} % | **no** | | |"
        )
    if speeds:
        met = "met" if min(speeds) >= speed_target else "**not met**"
        out += [
            "",
            f"Headless speed: slowest run {min(speeds):.0f}x real time "
            f"(target ≥ {speed_target:.0f}x: {met}).",
        ]
    out += ["", f"The whole benchmark took {wall_s:.0f} s of wall time.", ""]
    out += failures_section(sets, "## Failures")
    return "\n".join(out)


#: What a failure that was not reproduced shows of its own outcome (``situate demo --json``).
FIRST_RUN_KEYS = (
    "delivered",
    "mission_time_s",
    "cycles",
    "sequencer_exit",
    "phase",
    "skills_faulted",
    "error",
)


def failures_section(sets: dict[str, list[Case]], title: str) -> list[str]:
    """Every failed run by class, with the command that reproduces it."""
    out: list[str] = []
    failures = [c for cases in sets.values() for c in cases if not c.outcome.get("delivered")]
    out += [title, ""]
    if not failures:
        out.append("None.")
    by_class: dict[str, list[Case]] = {}
    for c in failures:
        by_class.setdefault(failure_class(c), []).append(c)
    for cls, cases in sorted(by_class.items(), key=lambda kv: -len(kv[1])):
        out += [f"### {cls} ({len(cases)})", ""]
        for c in cases:
            where = (
                f"`situate map generate {' '.join([*c.gen_extra, '--seed', str(c.map_seed)])}` "
                "then "
                if c.map_seed is not None
                else ""
            )
            # A generated map is MAP, made by the command before; a drawn one is named.
            args = (
                " ".join(c.demo_args()).replace(str(c.map), "MAP")
                if c.map and c.map_seed is not None
                else " ".join(c.demo_args())
            )
            out.append(f"- {c.set}: {where}`situate demo --headless {args}`")
        out.append("")
        first = cases[0]
        if not first.reproduced:
            out += ["The first one's own outcome, and its second run's:", "", "```"]
            out += [
                json.dumps({k: first.outcome.get(k) for k in FIRST_RUN_KEYS if k in first.outcome}),
                *first.stderr,
                first.again or "(no outcome line)",
                "```",
                "",
            ]
        out += ["Last lines of the first one, run again:", "", "```", *first.tail, "```", ""]
    return out


def physics_report(sets: dict[str, list[Case]], twice: str, wall_s: float) -> str:
    """The physics section of ``docs/delivery.md``, between its markers."""
    table = report(sets, {}, wall_s, speed_target=PHYSICS_SPEED_TARGET).split("\n")
    rows = [ln for ln in table if ln.startswith("|")]
    # The speed target is the issue's, on its sets; the hard set's speed is told beside it.
    targeted = {k: v for k, v in sets.items() if k in ("physics-default", "physics-generated")}
    lines = report(targeted, {}, wall_s, speed_target=PHYSICS_SPEED_TARGET).split("\n")
    speed = [ln for ln in lines if ln.startswith("Headless speed")]
    hard = [
        float(c.outcome["speedup"])
        for c in sets.get("physics-generated-hard", [])
        if c.outcome.get("speedup")
    ]
    if hard:
        speed.append(
            f"With people, door closures and a dead sonar (physics-generated-hard): slowest run "
            f"{min(hard):.0f}x."
        )
    out = [
        PHYSICS_BEGIN,
        "## The physics robot",
        "",
        "The same sequencer and skills on the physics robot (`situate demo --physics`: MuJoCo, "
        "through ROS 2 in lock-step; [physics.md](physics.md)), the same run seeds as the sets "
        f"above; the generated buildings are `situate map generate --family {PHYSICS_FAMILY}`'s "
        "(the generator the physics targets were set on: the cases the default generator added "
        "since are measured on the 2-D robot above), runs made one at a time. Speed is "
        "simulated time over the whole run's wall time (the robot's and the world's start "
        "included).",
        "",
        *rows,
        "",
        *speed,
        "",
        f"The same seed twice (the first physics run, recorded twice): {twice}.",
        "",
        f"These runs took {wall_s:.0f} s of wall time.",
        "",
        *failures_section(sets, "### Physics failures"),
        PHYSICS_END,
    ]
    return "\n".join(out)


def main() -> int:
    """Runs the sets and writes the report; 0 when every target is met."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--default", type=int, default=100, help="runs on maps/default.yaml")
    p.add_argument("--generated", type=int, default=200, help="generated buildings")
    p.add_argument(
        "--hard",
        type=int,
        default=None,
        help="generated buildings with people (default: --generated)",
    )
    p.add_argument(
        "--unseen",
        type=int,
        default=200,
        help="generated buildings with people etc., on seeds no failure was read of",
    )
    p.add_argument(
        "--no-route",
        type=int,
        default=100,
        help="generated buildings without route hints (the robot explores)",
    )
    p.add_argument(
        "--hand", type=int, default=20, help="plain runs on each map of maps/hand-drawn/"
    )
    p.add_argument(
        "--hand-hard",
        type=int,
        default=10,
        help="runs with people etc. on each map of maps/hand-drawn/",
    )
    p.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="runs at a time (more: quicker, but each run's speed is then shared with others)",
    )
    p.add_argument("--physics", type=int, default=20, help="physics runs on maps/default.yaml")
    p.add_argument("--physics-generated", type=int, default=20, help="generated buildings, physics")
    p.add_argument(
        "--physics-hard",
        type=int,
        default=10,
        help="generated buildings with people, door closures and a dead sonar, physics",
    )
    p.add_argument(
        "--physics-only",
        action="store_true",
        help="only the physics sets: rewrite only the report's physics section",
    )
    p.add_argument("--bin", default=None)
    p.add_argument("--no-report", action="store_true", help="print the report, write nothing")
    a = p.parse_args()
    snap = Path(tempfile.mkdtemp(prefix="situate-delivery-program-"))
    try:
        return measure(a, snapshot(find_binary(a.bin), snap), snap)
    finally:
        shutil.rmtree(snap, ignore_errors=True)


def measure(a: argparse.Namespace, binary: Path, snap: Path) -> int:
    """Runs the sets ``a`` asks for, and writes (or prints) the report; the exit status.

    Every run is of ``binary`` on the demo of ``snap``, copies taken at the start (`snapshot`).
    """
    started = time.monotonic()
    physics_text = ""
    with tempfile.TemporaryDirectory(prefix="situate-delivery-") as tmp:
        if a.physics or a.physics_generated or a.physics_hard:
            physics_text = run_physics(
                binary, a.physics, a.physics_generated, a.physics_hard, Path(tmp)
            )
    if a.physics_only:
        doc = ROOT / "docs" / "delivery.md"
        old = doc.read_text() if doc.exists() else ""
        if PHYSICS_BEGIN in old and PHYSICS_END in old:
            head, rest = old.split(PHYSICS_BEGIN, 1)
            new = head + physics_text + rest.split(PHYSICS_END, 1)[1]
        else:
            new = old.rstrip("\n") + "\n\n" + physics_text + "\n"
        if a.no_report:
            print(physics_text)
        else:
            doc.write_text(new)
            print(physics_text.split("### Physics failures")[0])
        return 0 if "**no**" not in physics_text.split("### Physics failures")[0] else 1
    sets: dict[str, list[Case]] = {}
    if a.default:
        sets["default"] = [Case("default", DEFAULT_SEEDS + k) for k in range(a.default)]
    skipped: dict[str, str] = {}
    with tempfile.TemporaryDirectory(prefix="situate-delivery-") as tmp:
        hard = a.generated if a.hard is None else a.hard
        for name, count, hard_world, gen, base in (
            ("generated", a.generated, False, [], GENERATED_SEEDS),
            ("generated-hard", hard, True, [], GENERATED_SEEDS),
            ("unseen-hard", a.unseen, True, [], UNSEEN_SEEDS),
            ("no-route", a.no_route, False, ["--no-route"], GENERATED_SEEDS),
        ):
            if count == 0:
                continue
            if hard_world and not knows(binary, "demo", "--people"):
                skipped[name] = "this situate program's demo has no --people"
                continue
            cases: list[Case] = []
            for k in range(count):
                seed = base + k
                path = Path(tmp) / f"generated-{seed}{''.join(gen)}.yaml"
                err = None if path.exists() else generate(binary, seed, path, gen)
                if err is not None:
                    skipped[name] = err
                    cases = []
                    break
                extra = (
                    ["--people", "3", "--door-closures", "--dead-sonar", str(seed % 24)]
                    if hard_world
                    else []
                )
                features = read_features(path)
                cases.append(Case(name, seed, path, seed, extra, features=features, gen_extra=gen))
            if cases:
                sets[name] = cases
        for name, count, hard_world in (
            ("hand-drawn", a.hand, False),
            ("hand-drawn-hard", a.hand_hard, True),
        ):
            drawn = sorted((ROOT / "maps" / "hand-drawn").glob("*.yaml"))
            cases = []
            for path in drawn:
                for k in range(count):
                    seed = HAND_SEEDS + k
                    extra = (
                        ["--people", "3", "--door-closures", "--dead-sonar", str(seed % 24)]
                        if hard_world
                        else []
                    )
                    cases.append(Case(name, seed, path.relative_to(ROOT), None, extra))
            if cases:
                sets[name] = cases
        everything = [c for cases in sets.values() for c in cases]
        with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
            for n, case in enumerate(pool.map(lambda c: run(binary, c, snap), everything), 1):
                mark = "." if case.outcome.get("delivered") else "F"
                print(mark, end="" if n % 50 else "\n", flush=True)
        print()
        text = report(sets, skipped, time.monotonic() - started, a.jobs)
        head, failures = text.split("## Failures", 1)
        text = "\n".join([head.rstrip("\n"), "", *coverage_section(sets), "## Failures" + failures])
    if not physics_text:
        # Not run this time: the physics section the report has stays as it is.
        doc = ROOT / "docs" / "delivery.md"
        old = doc.read_text() if doc.exists() else ""
        if PHYSICS_BEGIN in old and PHYSICS_END in old:
            physics_text = PHYSICS_BEGIN + old.split(PHYSICS_BEGIN, 1)[1].split(PHYSICS_END, 1)[0]
            physics_text += PHYSICS_END
    if physics_text:
        text += "\n" + physics_text
    if a.no_report:
        print(text)
    else:
        (ROOT / "docs" / "delivery.md").write_text(text + "\n")
        raw = {
            name: [{"seed": c.seed, "map_seed": c.map_seed, **c.outcome} for c in cases]
            for name, cases in sets.items()
        }
        (ROOT / "docs" / "delivery-results.json").write_text(json.dumps(raw, indent=1) + "\n")
        print(text.split("## Failures")[0])
    met = all(
        sum(1 for c in cases if c.outcome.get("delivered")) >= TARGETS.get(name, 0) * len(cases)
        for name, cases in sets.items()
    )
    return 0 if met and not skipped else 1


#: The generator family of the physics sets' buildings: the buildings issue 41's targets were set
#: on (family 2, the whole documented space, is issue 37's, measured by the 2-D sets).
PHYSICS_FAMILY = 1


def run_physics(binary: Path, default: int, generated: int, hard: int, tmp: Path) -> str:
    """Runs the physics sets one at a time and the same-seed check; the report's section."""
    started = time.monotonic()
    sets: dict[str, list[Case]] = {
        "physics-default": [
            Case("physics-default", DEFAULT_SEEDS + k, extra=["--physics"]) for k in range(default)
        ]
    }
    for name, count, hard_world in (
        ("physics-generated", generated, False),
        ("physics-generated-hard", hard, True),
    ):
        cases: list[Case] = []
        for k in range(count):
            seed = GENERATED_SEEDS + k
            path = tmp / f"generated-{seed}-family{PHYSICS_FAMILY}.yaml"
            gen = ["--family", str(PHYSICS_FAMILY)]
            err = None if path.exists() else generate(binary, seed, path, gen)
            if err is not None:
                sys.exit(f"situate map generate --family {PHYSICS_FAMILY} --seed {seed}: {err}")
            extra = ["--physics"]
            if hard_world:
                extra += ["--people", "3", "--door-closures", "--dead-sonar", str(seed % 24)]
            cases.append(Case(name, seed, path, seed, extra, gen_extra=gen))
        if cases:
            sets[name] = cases
    everything = [c for cs in sets.values() for c in cs]
    for n, case in enumerate(everything, 1):
        run(binary, case)
        print("." if case.outcome.get("delivered") else "F", end="" if n % 50 else "\n", flush=True)
    print()
    twice = same_twice(binary, everything[0], tmp) if everything else "not run"
    return physics_report(sets, twice, time.monotonic() - started)


if __name__ == "__main__":
    sys.exit(main())
