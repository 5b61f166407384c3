"""The experiment of issue 13: explicit sequencing versus a reactive design as the task class grows.

Generates buildings from a held-out range of seeds (keeping those of at least three floors),
runs every design on every building for each task of the class T1..T8 (``situate demo
--headless --json --task ... --mode DESIGN``), caches each outcome as a JSON line as it
completes (``--resume`` skips the runs already done), aggregates per design and class size
k = 1, 2, 4, 8, measures each design's cost from its sources, and writes
``experiment-results.json``, ``experiment.png`` and ``experiment.md`` into ``--out``. Every run
is made in two conditions: ``plain`` and ``hard`` (the delivery's hard set: people walking, doors
closed now and then, a dead sonar; ``--conditions`` picks). The
report's "Reading" section (between ``<!-- reading -->`` and ``<!-- /reading -->``) is kept
from the existing report; everything else is generated. The report and the figure are drawn by
``experiment_report.py`` beside this script. Usage, from the repository's top::

    .venv/bin/python scripts/experiment.py [--buildings 24] [--jobs 2] [--resume]
"""

from __future__ import annotations

import argparse
import ast
import concurrent.futures
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from subprocess import PIPE
from typing import Any

from experiment_report import k_table, plot, reading_section, render_report

ROOT = Path(__file__).resolve().parent.parent
DESIGNS = ("sequenced", "reactive")
#: ``plain``: the building alone; ``hard``: with the delivery's hard set (``hard_args``).
CONDITIONS = ("plain", "hard")
KS = (1, 2, 4, 8)
#: Each design's program, measured for the design-cost table (paths from the repository top): the
#: modules of its subpackage of demo/courier. What both designs run on is counted for neither:
#: the link (courier/link.py), the geometry (courier/geometry.py), the mission and what both
#: read the building with (courier/mission.py), and the program that starts either
#: (courier/main.py, with the entry files demo/deliver.py and demo/reactive.py).
DESIGN_SOURCES: dict[str, tuple[str, ...]] = {
    "sequenced": (
        "demo/courier/sequenced/delivery.py",
        "demo/courier/sequenced/lobby.py",
        "demo/courier/sequenced/explore.py",
        "demo/courier/sequenced/behaviours.py",
        "demo/courier/sequenced/routes.py",
    ),
    "reactive": (
        "demo/courier/reactive/rules.py",
        "demo/courier/reactive/route.py",
        "demo/courier/reactive/car.py",
        "demo/courier/reactive/door.py",
        "demo/courier/reactive/state.py",
    ),
}
#: The reactive design's rule list, whose rules are counted.
RULES_SOURCE = "demo/courier/reactive/rules.py"
RUNS_FILE = "experiment-runs.jsonl"


@dataclass(frozen=True)
class Building:
    """A generated building: its seed, its floors and the mission's start and goal floors."""

    seed: int
    floors: tuple[int, ...]
    start: int
    goal: int


# ----- buildings and tasks (pure) -------------------------------------------------------------


def parse_building(seed: int, text: str) -> Building:
    """Reads the floors, the start floor and the goal floor from a generated map's YAML."""
    floors = tuple(int(f) for f in re.findall(r"^\s*-\s*level:\s*(-?\d+)\s*$", text, re.M))
    mission = text[text.index("\nmission:") :] if "\nmission:" in text else text
    start = re.search(r"^\s+start:.*?\bfloor:\s*(-?\d+)", mission, re.M)
    goal = re.search(r"^\s+goal_floor:\s*(-?\d+)", mission, re.M)
    if not start or not goal:
        raise ValueError(f"building {seed}: no mission start floor or goal_floor")
    return Building(seed, floors, int(start.group(1)), int(goal.group(1)))


def skip_reason(b: Building) -> str | None:
    """Why the experiment skips ``b`` (None: kept): it needs a goal two floors above the start."""
    if len(b.floors) < 3:
        return "fewer than 3 floors"
    if b.goal - b.start < 2:
        return "goal floor less than 2 floors above the start floor"
    return None


def _tasks(s: str, g: str, m: str) -> list[str]:
    return [
        "office",
        f"lobby:{g}",
        f"lobby:{m},office",
        f"lobby:{g},lobby:{s}",
        f"lobby:{s}",
        f"lobby:{m}",
        f"lobby:{g},lobby:{m}",
        f"lobby:{s},lobby:{m},office",
    ]


def task_class(start: int, goal: int) -> list[str]:
    """The tasks T1..T8 (``--task`` values) for start floor ``start`` and goal floor ``goal``."""
    return _tasks(str(start), str(goal), str(start + 1))


def symbolic_task_class() -> list[str]:
    """The task class written with S (start), G (goal) and M = S+1, for the report."""
    return _tasks("S", "G", "M")


def run_key(design: str, seed: int, task_id: str, condition: str = "plain") -> str:
    """The cache key of one run (a plain run's key has no condition, as before there were two)."""
    key = f"{design}/{seed}/{task_id}"
    return key if condition == "plain" else f"{key}/{condition}"


def hard_args(seed: int) -> list[str]:
    """The demo's options of the hard set, as ``scripts/delivery.py`` gives them.

    Three people walking, doors closed now and then, and one dead sonar chosen by the seed.
    """
    return ["--people", "3", "--door-closures", "--dead-sonar", str(seed % 24)]


# ----- aggregation (pure) -----------------------------------------------------------------------


def _nan_none(x: float) -> float | None:
    return None if x != x else x


def _pooled(rows: Sequence[dict[str, Any]], key: str, scale: float) -> float | None:
    """Sum of ``key`` over the rows' summed simulated time, times ``scale``, or None if absent."""
    with_key = [r for r in rows if r.get(key) is not None and r.get("mission_time_s")]
    sim = sum(float(r["mission_time_s"]) for r in with_key)
    if not with_key or sim <= 0:
        return None
    return scale * sum(float(r[key]) for r in with_key) / sim


def aggregate(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Success and cost figures over ``rows`` (outcomes; a failed run has ``error`` and no times).

    Times are over the successful runs (``task_done``); the rates are pooled over the runs that
    have an outcome: the sum of the count over the sum of the simulated time.
    """
    ok = [r for r in rows if r.get("task_done")]
    outcomes = [r for r in rows if "error" not in r]
    times = [float(r["task_time_s"]) for r in ok]
    walls = [float(r["wall_s"]) for r in outcomes if r.get("wall_s") is not None]
    return {
        "runs": len(rows),
        "done": len(ok),
        "errors": len(rows) - len(outcomes),
        "success_rate": len(ok) / len(rows) if rows else None,
        "task_time_mean_s": statistics.fmean(times) if times else None,
        "task_time_median_s": statistics.median(times) if times else None,
        "skill_runs_per_sim_s": _pooled(outcomes, "skill_runs", 1.0),
        "skill_cpu_us_per_sim_s": _pooled(outcomes, "skill_cpu_ms", 1000.0),
        "rule_switches_per_sim_min": _pooled(outcomes, "rule_switches", 60.0),
        "drive_winner_changes_per_sim_min": _pooled(outcomes, "drive_winner_changes", 60.0),
        "wall_s_mean": statistics.fmean(walls) if walls else None,
    }


def done_by_all(rows: Sequence[dict[str, Any]], designs: Sequence[str]) -> set[tuple[int, int]]:
    """The (building, task index) pairs that every design did: a paired comparison of times."""
    done = [
        {(r["building"], r["task_index"]) for r in rows if r["design"] == d and r.get("task_done")}
        for d in designs
    ]
    return set.intersection(*done) if done else set()


def by_k(
    rows: Sequence[dict[str, Any]], designs: Sequence[str], n_tasks: int
) -> dict[str, dict[int, dict[str, Any]]]:
    """Per design and class size k (1, 2, 4, 8 up to ``n_tasks``): the runs of the first k tasks.

    Besides `aggregate`'s figures, ``task_time_mean_common_s`` is the mean task time over the
    runs whose building and task every design did.
    """
    common = done_by_all(rows, designs)
    stats: dict[str, dict[int, dict[str, Any]]] = {}
    for d in designs:
        stats[d] = {}
        for k in (k for k in KS if k <= n_tasks):
            mine = [r for r in rows if r["design"] == d and r["task_index"] < k]
            paired = [
                float(r["task_time_s"])
                for r in mine
                if r.get("task_done") and (r["building"], r["task_index"]) in common
            ]
            stats[d][k] = aggregate(mine) | {
                "common_done": len(paired),
                "task_time_mean_common_s": statistics.fmean(paired) if paired else None,
            }
    return stats


def by_task(
    rows: Sequence[dict[str, Any]], designs: Sequence[str], n_tasks: int
) -> dict[str, dict[str, tuple[int, int]]]:
    """Per task id and design: (successful runs, runs)."""
    table: dict[str, dict[str, tuple[int, int]]] = {}
    for i in range(n_tasks):
        table[f"T{i + 1}"] = {}
        for d in designs:
            mine = [r for r in rows if r["design"] == d and r["task_index"] == i]
            table[f"T{i + 1}"][d] = (sum(bool(r.get("task_done")) for r in mine), len(mine))
    return table


# ----- design cost (pure) -----------------------------------------------------------------------


def count_loc(source: str) -> int:
    """Non-blank lines that are not comments alone."""
    return sum(1 for ln in source.splitlines() if ln.strip() and not ln.strip().startswith("#"))


def _rules_list(tree: ast.AST) -> ast.List | None:
    for node in ast.walk(tree):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = list(node.targets)
        elif isinstance(node, ast.AnnAssign):
            targets = [node.target]
        else:
            continue
        value = node.value
        for t in targets:
            if (
                isinstance(t, ast.Attribute)
                and t.attr == "rules"
                and isinstance(t.value, ast.Name)
                and t.value.id == "self"
                and isinstance(value, ast.List)
            ):
                return value
    return None


def count_rules(source: str) -> dict[str, int]:
    """The rules of ``self.rules = [(name, condition, action), ...]`` in ``source``.

    Returns the number of rules, of distinct condition methods (``self.NAME``) and of inline
    conditions (lambdas).
    """
    rules = _rules_list(ast.parse(source))
    if rules is None:
        return {"rules": 0, "condition_methods": 0, "inline_conditions": 0}
    methods: set[str] = set()
    inline = 0
    for entry in rules.elts:
        if not isinstance(entry, ast.Tuple) or len(entry.elts) < 2:
            continue
        cond = entry.elts[1]
        if isinstance(cond, ast.Attribute) and isinstance(cond.value, ast.Name):
            methods.add(cond.attr)
        elif isinstance(cond, ast.Lambda):
            inline += 1
    return {
        "rules": len(rules.elts),
        "condition_methods": len(methods),
        "inline_conditions": inline,
    }


def design_cost(root: Path, designs: Iterable[str]) -> dict[str, dict[str, Any]]:
    """Lines of code per source file of each design, and the reactive design's rule counts."""
    cost: dict[str, dict[str, Any]] = {}
    for d in designs:
        files = {f: count_loc((root / f).read_text()) for f in DESIGN_SOURCES.get(d, ())}
        entry: dict[str, Any] = {"files": files, "loc": sum(files.values())}
        if d == "reactive":
            entry.update(count_rules((root / RULES_SOURCE).read_text()))
        cost[d] = entry
    return cost


# ----- running (impure) -------------------------------------------------------------------------


def find_binary(given: str | None) -> Path:
    """Returns the ``situate`` binary: ``given``, ``$SITUATE_BIN`` or a cargo build."""
    candidates = [given, os.environ.get("SITUATE_BIN")]
    target = os.environ.get("CARGO_TARGET_DIR")
    for base in ([Path(target)] if target else []) + [ROOT / "target"]:
        candidates += [str(base / "release" / "situate"), str(base / "debug" / "situate")]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    sys.exit(
        "no situate binary: build it (cargo build --release -p situate_cli) or set SITUATE_BIN"
    )


def generate(binary: Path, seed: int, maps: Path) -> tuple[Building, Path]:
    """Generates the building of ``seed`` into ``maps`` and reads it."""
    path = maps / f"building-{seed}.yaml"
    # Family 1: the buildings docs/experiment.md was made on (the generator before it drew the
    # whole documented space: `map generate --family 1` keeps each seed's building).
    subprocess.run(
        [
            str(binary),
            *("map", "generate", "--family", "1", "--seed", str(seed), "--output", str(path)),
        ],
        check=True,
        capture_output=True,
    )
    return parse_building(seed, path.read_text()), path


def select_buildings(
    binary: Path, first_seed: int, wanted: int, maps: Path
) -> tuple[list[tuple[Building, Path]], list[dict[str, Any]]]:
    """Generates buildings from ``first_seed`` on until ``wanted`` are kept; returns the skipped."""
    kept: list[tuple[Building, Path]] = []
    skipped: list[dict[str, Any]] = []
    seed = first_seed
    while len(kept) < wanted:
        b, path = generate(binary, seed, maps)
        why = skip_reason(b)
        if why is None:
            kept.append((b, path))
        else:
            skipped.append({**asdict(b), "reason": why})
        seed += 1
        if len(skipped) > 50 * wanted + 100:
            sys.exit(f"too many buildings skipped from seed {first_seed} on")
    return kept, skipped


def run_one(
    binary: Path,
    design: str,
    b: Building,
    path: Path,
    task_index: int,
    args: argparse.Namespace,
    condition: str = "plain",
) -> dict[str, Any]:
    """Runs one mission; the outcome, or ``{"error": ...}`` if it failed or timed out."""
    task = task_class(b.start, b.goal)[task_index]
    cmd = [str(binary), "demo", "--headless", "--json", "--seed", str(b.seed)]
    cmd += ["--map", str(path), "--task", task, "--mode", design, "--python", args.python]
    cmd += ["--robot", str(ROOT / "demo" / "robot.yaml"), "--limit-s", str(args.limit_s)]
    if condition == "hard":
        cmd += hard_args(b.seed)
    meta = {"design": design, "building": b.seed, "task_index": task_index, "condition": condition}
    meta |= {"task_id": f"T{task_index + 1}", "task_stops": task, "limit_s": args.limit_s}
    t0 = time.monotonic()
    # A session of its own, so that a timeout ends the demo's sequencer too, not the demo only.
    with subprocess.Popen(
        cmd, cwd=ROOT, stdout=PIPE, stderr=PIPE, text=True, start_new_session=True
    ) as proc:
        try:
            stdout, stderr = proc.communicate(timeout=args.timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            error = f"timeout after {args.timeout_s:.0f} s wall"
            return {**meta, "error": error, "task_done": False, "wall_s": time.monotonic() - t0}
    lines = [ln for ln in stdout.splitlines() if ln.startswith("{")]
    try:
        outcome: dict[str, Any] = json.loads(lines[-1]) if lines else {}
    except json.JSONDecodeError:
        outcome = {}
    if "task_done" not in outcome:
        tail = (stderr or stdout).strip().splitlines()[-3:]
        error = f"exit {proc.returncode}, no outcome: " + " / ".join(tail)
        return {**meta, "error": error, "task_done": False, "wall_s": time.monotonic() - t0}
    return {**outcome, **meta}


def load_cache(path: Path) -> dict[str, dict[str, Any]]:
    """The runs already in the cache file, by key (unreadable lines are ignored)."""
    runs: dict[str, dict[str, Any]] = {}
    if path.is_file():
        for line in path.read_text().splitlines():
            try:
                r = json.loads(line)
                key = run_key(r["design"], r["building"], r["task_id"], r.get("condition", "plain"))
                runs[key] = r
            except (json.JSONDecodeError, KeyError, TypeError):
                continue
    return runs


def progress_line(n: int, total: int, r: dict[str, Any]) -> str:
    """One line about a finished run."""
    head = f"[{n:>4}/{total}] {r['design']:>9} building {r['building']} {r['task_id']}"
    if r.get("condition", "plain") != "plain":
        head += f" ({r['condition']})"
    if "error" in r:
        return f"{head}: ERROR {r['error']}"
    state = "done  " if r.get("task_done") else "FAILED"
    return (
        f"{head}: {state} t {float(r.get('task_time_s', 0)):7.1f} s  "
        f"runs {r.get('skill_runs', 0):7}  wall {float(r.get('wall_s', 0)):6.1f} s"
    )


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    """The command line."""
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--buildings", type=int, default=24, help="buildings to keep (default 24)")
    p.add_argument("--first-seed", type=int, default=50000, help="first building seed (50000)")
    p.add_argument("--designs", default=",".join(DESIGNS), help="comma-separated demo modes")
    p.add_argument("--tasks", type=int, default=8, choices=range(1, 9), help="T1..Tn (8)")
    p.add_argument("--jobs", type=int, default=2, help="runs in parallel (2)")
    p.add_argument("--bin", default=None, help="the situate binary (default $SITUATE_BIN, target/)")
    p.add_argument("--out", default=str(ROOT / "docs"), help="directory of the report (docs/)")
    p.add_argument("--resume", action="store_true", help="keep the runs cached in --out")
    p.add_argument("--limit-s", type=float, default=1800, help="simulated limit per run (1800)")
    p.add_argument("--timeout-s", type=float, default=600, help="wall limit per run (600)")
    p.add_argument("--python", default=sys.executable, help="the sequencer's interpreter")
    p.add_argument(
        "--conditions", default=",".join(CONDITIONS), help="comma-separated: plain, hard (both)"
    )
    return p.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the experiment and writes the results, the plot and the report."""
    args = parse_args(argv)
    started = time.monotonic()
    binary = find_binary(args.bin)
    designs = [d for d in args.designs.split(",") if d]
    conditions = [c for c in args.conditions.split(",") if c]
    if not conditions or any(c not in CONDITIONS for c in conditions):
        sys.exit(f"--conditions: give some of {', '.join(CONDITIONS)}, got {args.conditions!r}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cache_path = out / RUNS_FILE
    cached = {
        key: r
        for key, r in (load_cache(cache_path) if args.resume else {}).items()
        if r.get("limit_s") == args.limit_s  # a run under another limit is run again
    }
    if not args.resume:
        cache_path.write_text("")
    with tempfile.TemporaryDirectory(prefix="situate-experiment-") as tmp:
        kept, skipped = select_buildings(binary, args.first_seed, args.buildings, Path(tmp))
        print(
            f"buildings: kept {[b.seed for b, _ in kept]}, skipped {len(skipped)}",
            flush=True,
        )
        todo = [
            (d, b, path, i, c)
            for c in conditions
            for d in designs
            for b, path in kept
            for i in range(args.tasks)
            if run_key(d, b.seed, f"T{i + 1}", c) not in cached
        ]
        total = len(todo)
        lock = threading.Lock()
        made: list[dict[str, Any]] = []
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            futures = [pool.submit(run_one, binary, d, b, p, i, args, c) for d, b, p, i, c in todo]
            for fut in concurrent.futures.as_completed(futures):
                r = fut.result()
                with lock, cache_path.open("a") as f:
                    f.write(json.dumps(r) + "\n")
                made.append(r)
                print(progress_line(len(made), total, r), flush=True)
    seeds = {b.seed for b, _ in kept}
    wanted = {
        run_key(d, s, f"T{i + 1}", c)
        for c in conditions
        for d in designs
        for s in seeds
        for i in range(args.tasks)
    }
    every = {
        **cached,
        **{
            run_key(r["design"], r["building"], r["task_id"], r.get("condition", "plain")): r
            for r in made
        },
    }
    all_rows = sorted(
        (r for key, r in every.items() if key in wanted),
        key=lambda r: (
            conditions.index(r.get("condition", "plain")),
            designs.index(r["design"]),
            r["building"],
            r["task_index"],
        ),
    )
    per_condition = {
        c: [r for r in all_rows if r.get("condition", "plain") == c] for c in conditions
    }
    rows = per_condition.get("plain", [])
    stats = by_k(rows, designs, args.tasks)
    hard_rows = per_condition.get("hard", [])
    hard_stats = by_k(hard_rows, designs, args.tasks) if hard_rows else None
    results: dict[str, Any] = {
        "config": {
            "designs": designs,
            "tasks": args.tasks,
            "buildings": args.buildings,
            "first_seed": args.first_seed,
            "limit_s": args.limit_s,
            "timeout_s": args.timeout_s,
            "jobs": args.jobs,
            "cpus": os.cpu_count(),
            "conditions": conditions,
        },
        "timing": {
            "elapsed_s": time.monotonic() - started,
            "runs_this_invocation": len(made),
            "run_wall_s_total": sum(float(r.get("wall_s") or 0) for r in all_rows),
        },
        "buildings": {
            "kept": [{**asdict(b), "tasks": task_class(b.start, b.goal)} for b, _ in kept],
            "skipped": skipped,
        },
        "design_cost": design_cost(ROOT, designs),
        "by_k": {d: {str(k): s for k, s in ks.items()} for d, ks in stats.items()},
        "by_task": by_task(rows, designs, args.tasks),
        "runs": all_rows,
    }
    if hard_stats is not None:
        results["hard"] = {
            "by_k": {d: {str(k): s for k, s in ks.items()} for d, ks in hard_stats.items()},
            "by_task": by_task(hard_rows, designs, args.tasks),
        }
    (out / "experiment-results.json").write_text(json.dumps(results, indent=1) + "\n")
    plot(stats, KS, out / "experiment.png", hard_stats)
    report = out / "experiment.md"
    reading = reading_section(report.read_text() if report.is_file() else None)
    report.write_text(render_report(results, reading, symbolic_task_class()))
    print(k_table(stats))
    if hard_stats is not None:
        print("hard set:")
        print(k_table(hard_stats))
    print(f"wrote {report}, {out / 'experiment-results.json'} and {out / 'experiment.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
