"""The report of the experiment of issue 13: the markdown of ``experiment.md`` and the figure.

``scripts/experiment.py`` runs the experiment and aggregates the runs; this module renders the
results (as written to ``experiment-results.json``) and draws ``experiment.png``. It imports
nothing from ``experiment.py``: the task class (written with S, G and M) and the class sizes k
are given to it.
"""

from __future__ import annotations

import importlib
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

#: The short names of T1..T8, in order (the tasks are ``experiment.py``'s ``task_class``).
TASK_NAMES = (
    "deliver to the office",
    "announce on the goal floor",
    "two messages in one trip",
    "up and back down",
    "announce in the home lobby",
    "announce on the next floor",
    "up then part way down",
    "three stops",
)
READING_OPEN = "<!-- reading -->"
READING_CLOSE = "<!-- /reading -->"
READING_PLACEHOLDER = "(to be written after looking at the figures)"


# ----- the report (pure) ------------------------------------------------------------------------


def reading_section(existing: str | None) -> str:
    """The "Reading" text between the markers in ``existing`` (the placeholder if none)."""
    if existing:
        start = existing.find(READING_OPEN)
        end = existing.find(READING_CLOSE, start + 1)
        if start >= 0 and end > start:
            return existing[start + len(READING_OPEN) : end].strip("\n")
    return READING_PLACEHOLDER


def _f(x: float | None, fmt: str = ".0f") -> str:
    return "—" if x is None else format(x, fmt)


def k_table(stats: dict[str, dict[int, dict[str, Any]]]) -> str:
    """The markdown table of the figures per design and k."""
    switches = any(
        s.get(key) is not None
        for ks in stats.values()
        for s in ks.values()
        for key in ("rule_switches_per_sim_min", "drive_winner_changes_per_sim_min")
    )
    head = (
        "| design | k | tasks done | success | task time, s (mean / median, done runs) "
        "| task time, s (mean, runs every design did) | skill runs / sim s | skill CPU µs / sim s |"
    )
    sep = "|---|---|---|---|---|---|---|---|"
    if switches:
        head += " rule switches / sim min | drive winner changes / sim min |"
        sep += "---|---|"
    head += " wall s / run |"
    sep += "---|"
    lines = [head, sep]
    for d, ks in stats.items():
        for k, s in ks.items():
            rate = "—" if s["success_rate"] is None else f"{100 * s['success_rate']:.0f}%"
            row = (
                f"| {d} | {k} | {s['done']}/{s['runs']} | {rate} "
                f"| {_f(s['task_time_mean_s'])} / {_f(s['task_time_median_s'])} "
                f"| {_f(s.get('task_time_mean_common_s'))} (n = {s.get('common_done', 0)}) "
                f"| {_f(s['skill_runs_per_sim_s'], '.1f')} | {_f(s['skill_cpu_us_per_sim_s'])} |"
            )
            if switches:
                row += (
                    f" {_f(s['rule_switches_per_sim_min'], '.1f')} "
                    f"| {_f(s['drive_winner_changes_per_sim_min'], '.1f')} |"
                )
            row += f" {_f(s['wall_s_mean'], '.1f')} |"
            lines.append(row)
    return "\n".join(lines)


def task_table(per_task: dict[str, dict[str, tuple[int, int]]], designs: Sequence[str]) -> str:
    """The markdown table of successes per task (rows) and design (columns)."""
    lines = [
        "| task | name | " + " | ".join(designs) + " |",
        "|---|---|" + "---|" * len(designs),
    ]
    for tid, cells in per_task.items():
        name = TASK_NAMES[int(tid[1:]) - 1]
        counts = " | ".join(f"{cells[d][0]}/{cells[d][1]}" for d in designs)
        lines.append(f"| {tid} | {name} | {counts} |")
    return "\n".join(lines)


def class_table(tasks: Sequence[str]) -> str:
    """The markdown table of the task class T1..Tn, given its stops (``--task`` values)."""
    lines = ["| task | name | stops (`--task`) |", "|---|---|---|"]
    for i, t in enumerate(tasks):
        lines.append(f"| T{i + 1} | {TASK_NAMES[i]} | `{t}` |")
    return "\n".join(lines)


def cost_table(cost: dict[str, dict[str, Any]]) -> str:
    """The markdown table of each design's lines of code and rules."""
    lines = [
        "| design | program (non-blank, non-comment lines) | lines | rules | condition methods |",
        "|---|---|---|---|---|",
    ]
    for d, c in cost.items():
        files = ", ".join(f"`{f}` {n}" for f, n in c["files"].items())
        if d == "reactive":
            files += (
                " (what both designs run on is counted for neither: the link, the geometry, the"
                " mission and the program that starts either, `demo/courier/link.py`,"
                " `geometry.py`, `mission.py` and `main.py`)"
            )
        rules = str(c.get("rules", "—"))
        conds = str(c.get("condition_methods", "—"))
        if c.get("inline_conditions"):
            conds += f" (+{c['inline_conditions']} inline)"
        lines.append(f"| {d} | {files} | {c['loc']} | {rules} | {conds} |")
    return "\n".join(lines)


def _duration(s: float) -> str:
    return f"{s / 60:.1f} min" if s >= 120 else f"{s:.0f} s"


def fault_line(rows: Sequence[dict[str, Any]], designs: Sequence[str]) -> str:
    """How many runs had a skill faulted (runs made before the demo reported faults: unknown)."""
    known = [r for r in rows if "skills_faulted" in r]
    if not known:
        return "not reported by the runs (made before `situate demo` listed them)"
    parts = []
    for d in designs:
        mine = [r for r in known if r["design"] == d]
        hit = [r for r in mine if r["skills_faulted"]]
        n = sum(len(r["skills_faulted"]) for r in hit)
        parts.append(f"{d} {len(hit)} of {len(mine)} runs ({n} fault(s))")
    unknown = len(rows) - len(known)
    extra = f"; {unknown} runs made before faults were reported are not counted" if unknown else ""
    return "; ".join(parts) + extra


def render_report(results: dict[str, Any], reading: str, task_class: Sequence[str]) -> str:
    """The whole of ``experiment.md`` from the results (as written to the JSON) and the reading.

    ``task_class`` is T1..T8 written with S, G and M (``experiment.py``'s
    ``symbolic_task_class``); the report shows its first ``results["config"]["tasks"]``.
    """
    cfg = results["config"]
    designs: list[str] = cfg["designs"]
    kept = results["buildings"]["kept"]
    skipped = results["buildings"]["skipped"]
    reasons: dict[str, int] = {}
    for s in skipped:
        reasons[s["reason"]] = reasons.get(s["reason"], 0) + 1
    skipped_text = (
        "; ".join(f"{n} because {why}" for why, n in reasons.items()) if skipped else "none"
    )
    seeds = ", ".join(str(b["seed"]) for b in kept)
    n_runs = len(results["runs"])
    tm = results["timing"]
    made = f"{tm['runs_this_invocation']} runs made"
    if tm["runs_this_invocation"] < n_runs:
        made += f", {n_runs - tm['runs_this_invocation']} from the cache of an earlier invocation"
    k_stats = {d: {int(k): s for k, s in ks.items()} for d, ks in results["by_k"].items()}
    per_task = {t: {d: (c[0], c[1]) for d, c in ds.items()} for t, ds in results["by_task"].items()}
    hard_section = ""
    if results.get("hard"):
        hard = results["hard"]
        hard_k = {d: {int(k): s for k, s in ks.items()} for d, ks in hard["by_k"].items()}
        hard_task = {
            t: {d: (c[0], c[1]) for d, c in ds.items()} for t, ds in hard["by_task"].items()
        }
        hard_section = f"""
### On the hard set

The same buildings, tasks and seeds, with the delivery's hard set (`scripts/delivery.py`): three
people walking the corridors, doors closed now and then, and one sonar dead (`--people 3
--door-closures --dead-sonar K`, K = building seed mod 24). Neither design was tuned on these
buildings; both were tuned on the hard set of other buildings: the sequenced robot over several
sessions (issue 12), the reactive one in its third to eighth rounds (decision 0008, "Tuning
log").

{k_table(hard_k)}

Tasks done per task, hard set:

{task_table(hard_task, designs)}
"""
    return f"""# Experiment: explicit sequencing vs a reactive design as the class of tasks grows

Generated by `scripts/experiment.py` (issue 13); only the section "Reading" is written by hand.

## Set-up

- **Designs.** `sequenced`: the sequencer of `demo/courier/sequenced/` switches the skills on
  and off, step by step (explicit sequencing). `reactive`: `demo/courier/reactive/` (the rule
  list in `rules.py`, its route follower in `route.py`, its car rules in `car.py`, what it
  senses and keeps in `state.py`), a teleo-reactive ordered rule list evaluated every cycle
  over the same skills, perception always on, no phases.
  Both run as `situate demo --headless --json --mode DESIGN --task TASK`.
- **Tasks.** S is the start floor, G the goal floor (the office's), M = S+1. The class of size k
  is T1..Tk; every design runs every task of the class on every building, once.

{class_table(task_class[: cfg["tasks"]])}

- **Buildings.** {len(kept)} generated building(s) (`situate map generate --family 1`), seeds from
  {cfg["first_seed"]} on, held out from tuning, kept when they have at least 3 floors and the goal
  is at least 2 floors above the start: seeds {seeds}. Skipped: {len(skipped)} ({skipped_text}).
- **Runs.** {n_runs} runs ({len(designs)} designs by {len(kept)} building(s) by
  {cfg["tasks"]} tasks by {len(cfg.get("conditions", ["plain"]))} condition(s):
  {", ".join(cfg.get("conditions", ["plain"]))}),
  demo seed = building seed, simulated time limit {cfg["limit_s"]:.0f} s, wall limit
  {cfg["timeout_s"]:.0f} s per run, {cfg["jobs"]} at a time on a machine of {cfg["cpus"]} CPUs.
  This invocation took {_duration(tm["elapsed_s"])} ({made}); the runs' wall times add up to
  {_duration(tm["run_wall_s_total"])}.
- **Measures.** A task is done when every stop was made, in order (the simulator's ground truth).
  Task time: when the last stop was made (done runs only; the paired column keeps only the
  building and task pairs that every design did, so that the designs' times compare). Rates:
  summed over the runs with an outcome, divided by their summed simulated time.
- **Skill faults** (a body over its execution budget, as a busy machine can make a healthy one;
  the manager switches the skill off, and both controllers switch it on again at once):
  {fault_line(results["runs"], designs)}.

## Results

Per design and class size k (the runs of T1..Tk over all buildings):

{k_table(k_stats)}

Tasks done per task:

{task_table(per_task, designs)}
{hard_section}
![success, task time and cost per class size (dashed: the hard set)](experiment.png)

## Design cost

Measured from the sources by the script:

{cost_table(results["design_cost"])}

## Reading

{READING_OPEN}
{reading}
{READING_CLOSE}
"""


# ----- the figure -------------------------------------------------------------------------------


def pyplot() -> Any:
    """Imports matplotlib's pyplot (Agg), installing matplotlib first if it is missing."""
    try:
        importlib.import_module("matplotlib")
    except ImportError:
        subprocess.run([sys.executable, "-m", "pip", "install", "-q", "matplotlib"], check=True)
    mpl = importlib.import_module("matplotlib")
    mpl.use("Agg")
    return importlib.import_module("matplotlib.pyplot")


def plot(
    stats: dict[str, dict[int, dict[str, Any]]],
    class_sizes: Sequence[int],
    out: Path,
    hard: dict[str, dict[int, dict[str, Any]]] | None = None,
) -> None:
    """Draws success, task time, CPU and switches (or skill runs) against k, one line per design.

    The x axis is marked at ``class_sizes``. The hard set, when there is one, is drawn
    dashed in the same colours.
    """
    plt = pyplot()
    has_switches = any(
        s.get("drive_winner_changes_per_sim_min") is not None
        or s.get("rule_switches_per_sim_min") is not None
        for ks in stats.values()
        for s in ks.values()
    )
    last = (
        ("drive_winner_changes_per_sim_min", "drive winner changes per simulated min")
        if has_switches
        else ("skill_runs_per_sim_s", "skill runs per simulated s")
    )
    panels = [
        ("success_rate", "success rate"),
        ("task_time_mean_s", "mean task time of done runs, s"),
        ("skill_cpu_us_per_sim_s", "skill CPU µs per simulated s"),
        last,
    ]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    markers = ["o", "s", "^", "D", "v"]
    series = [(stats, "", "-")] + ([(hard, " (hard set)", "--")] if hard else [])
    for ax, (key, title) in zip(axes.flat, panels):
        for figures, suffix, style in series:
            for i, (d, ks) in enumerate(figures.items()):
                pts = [(k, s.get(key)) for k, s in ks.items()]
                if key == "drive_winner_changes_per_sim_min":
                    pts = [
                        (k, v if v is not None else s.get("rule_switches_per_sim_min"))
                        for (k, v), s in zip(pts, ks.values())
                    ]
                xs = [k for k, v in pts if v is not None]
                ys = [v for _, v in pts if v is not None]
                ax.plot(
                    xs,
                    ys,
                    marker=markers[i % len(markers)],
                    linestyle=style,
                    color=f"C{i}",
                    label=d + suffix,
                )
        ax.set_xscale("log", base=2)
        ax.set_xticks(list(class_sizes))
        ax.set_xticklabels([str(k) for k in class_sizes])
        ax.set_xlabel("tasks in the class, k")
        ax.set_title(title, fontsize=10)
        ax.grid(alpha=0.3)
        if key == "success_rate":
            ax.set_ylim(-0.05, 1.05)
        ax.legend()
    fig.suptitle("Explicit sequencing vs reactive, as the class of tasks grows")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
