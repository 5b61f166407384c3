"""``docs/delivery.md`` from the delivery benchmark's runs.

The sets' targets, a run (`Case`) and what its outcome says, the summary table, the coverage
table by feature of the building, the failures by class with the command that reproduces each,
and the physics section. ``scripts/delivery.py`` runs the sets and writes what this makes of
them.
"""

from __future__ import annotations

import json
import os
import re
import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

#: The unseen set's generator seeds: the other sets' failures, listed in each report, are read
#: to find the robot's faults (each fix is for a case the docs allow, never for one seed), and
#: so those sets are no longer quite unseen after a fix. This range's runs were never read
#: before it was first reported: whether fixes carry over shows here. Once its failures have
#: been read to fix something, move it to a range never used.
UNSEEN_SEEDS = 70000
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
        "furniture beside the lab door's barcode",
        "clutter_near_lab_barcode",
        [("yes", "a bin within 0.6 m, on its wall"), ("no", "none")],
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


#: The generator family of the physics sets' buildings: the buildings issue 41's targets were set
#: on (family 2, the whole documented space, is issue 37's, measured by the 2-D sets).
PHYSICS_FAMILY = 1
