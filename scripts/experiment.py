"""The message-delivery experiment: explicit sequencing versus every skill always active.

Runs ``situate demo --headless --json`` for each seed in both modes (``sequenced``: the
sequencer switches skills on and off; ``all-active``: every skill on from the start, priority
arbitration only), then writes the raw outcomes (``docs/experiment-results.json``), prints a
markdown table and draws ``docs/experiment.png`` with matplotlib (installed into the running
interpreter's environment if missing). Usage, from the repository's top directory::

    .venv/bin/python scripts/experiment.py [--seeds 20] [--bin target/release/situate]
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
MODES = ("sequenced", "all-active")


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


def run_one(binary: Path, seed: int, mode: str, extra: list[str]) -> dict[str, Any]:
    """Runs one headless demo and returns its JSON outcome."""
    cmd = [str(binary), "demo", "--headless", "--json", "--seed", str(seed), "--mode", mode]
    cmd += ["--python", sys.executable, *extra]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    if not lines:
        raise RuntimeError(f"seed {seed} {mode}: no outcome\n{done.stdout}\n{done.stderr}")
    outcome: dict[str, Any] = json.loads(lines[-1])
    return outcome


def summary(rows: list[dict[str, Any]]) -> dict[str, float]:
    """Success rate and means over ``rows`` (times over the successful runs only)."""
    ok = [r for r in rows if r["delivered"]]
    mean = statistics.fmean

    def ok_mean(key: str) -> float:
        return mean(r[key] for r in ok) if ok else float("nan")

    return {
        "runs": len(rows),
        "delivered": len(ok),
        "mission_time_s": ok_mean("mission_time_s"),
        "sim_time_s_all": mean(r["mission_time_s"] for r in rows),
        "skill_runs": mean(r["skill_runs"] for r in rows),
        "skill_cpu_ms": mean(r["skill_cpu_ms"] for r in rows),
        "runs_per_cycle": mean(r["skill_runs"] / max(r["cycles"], 1) for r in rows),
        "cpu_us_per_sim_s": mean(
            1000 * r["skill_cpu_ms"] / max(r["mission_time_s"], 1e-9) for r in rows
        ),
        "speedup": mean(r["speedup"] for r in rows),
        "speedup_min": min(r["speedup"] for r in rows),
    }


def table(stats: dict[str, dict[str, float]]) -> str:
    """The markdown table of the two modes."""
    lines = [
        "| mode | delivered | mission time, s (delivered runs) | skill runs | skill runs / cycle "
        "| CPU in skills, ms | CPU µs per simulated s | speed vs real time (mean, min) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for mode, s in stats.items():
        time = "—" if s["mission_time_s"] != s["mission_time_s"] else f"{s['mission_time_s']:.0f}"
        lines.append(
            f"| {mode} | {s['delivered']:.0f}/{s['runs']:.0f} | {time} "
            f"| {s['skill_runs']:.0f} | {s['runs_per_cycle']:.1f} | {s['skill_cpu_ms']:.0f} "
            f"| {s['cpu_us_per_sim_s']:.0f} | {s['speedup']:.0f}x, {s['speedup_min']:.0f}x |"
        )
    return "\n".join(lines)


def pyplot() -> Any:
    """Imports matplotlib's pyplot (Agg), installing matplotlib first if it is missing."""
    try:
        importlib.import_module("matplotlib")
    except ImportError:
        subprocess.run([sys.executable, "-m", "pip", "install", "-q", "matplotlib"], check=True)
    mpl = importlib.import_module("matplotlib")
    mpl.use("Agg")
    return importlib.import_module("matplotlib.pyplot")


def plot(results: dict[str, list[dict[str, Any]]], out: Path) -> None:
    """Draws per-seed mission time, skill runs and CPU time of both modes."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    panels = [
        ("mission_time_s", "simulated mission time, s (x: not delivered)"),
        ("skill_runs", "skill executions"),
        ("skill_cpu_ms", "CPU time in skills, ms"),
    ]
    colours = {"sequenced": "tab:blue", "all-active": "tab:red"}
    for ax, (key, title) in zip(axes, panels):
        for mode, rows in results.items():
            seeds = [r["seed"] for r in rows]
            values = [r[key] for r in rows]
            markers = ["o" if r["delivered"] else "x" for r in rows]
            for s, v, mk in zip(seeds, values, markers):
                ax.scatter(s, v, marker=mk, color=colours.get(mode, "k"))
            ax.plot(seeds, values, color=colours.get(mode, "k"), alpha=0.4, label=mode)
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("seed")
        ax.set_xticks(sorted({r["seed"] for rows in results.values() for r in rows}))
        ax.grid(alpha=0.3)
    axes[0].legend()
    fig.suptitle("Message delivery: explicit sequencing vs all skills always active")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main() -> int:
    """Runs the experiment."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=20, help="seeds 1..N")
    p.add_argument("--bin", default=None, help="the situate binary")
    p.add_argument("--modes", default=",".join(MODES))
    p.add_argument("--out", default=str(ROOT / "docs"), help="directory for the results and plot")
    p.add_argument("extra", nargs="*", help="more arguments for `situate demo` (after --)")
    a = p.parse_args()
    binary = find_binary(a.bin)
    out = Path(a.out)
    results: dict[str, list[dict[str, Any]]] = {}
    for mode in a.modes.split(","):
        rows = results.setdefault(mode, [])
        for seed in range(1, a.seeds + 1):
            r = run_one(binary, seed, mode, a.extra)
            rows.append(r)
            print(
                f"{mode:>10} seed {seed:2}: {'delivered' if r['delivered'] else 'FAILED   '} "
                f"t {r['mission_time_s']:7.1f} s  runs {r['skill_runs']:7}  "
                f"cpu {r['skill_cpu_ms']:8.1f} ms  {r['speedup']:6.0f}x",
                flush=True,
            )
    stats = {mode: summary(rows) for mode, rows in results.items()}
    clean = {m: {k: (None if v != v else v) for k, v in st.items()} for m, st in stats.items()}
    (out / "experiment-results.json").write_text(
        json.dumps({"runs": results, "summary": clean}, indent=1) + "\n"
    )
    print()
    print(table(stats))
    plot(results, out / "experiment.png")
    print(f"\nwrote {out / 'experiment.png'} and {out / 'experiment-results.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
