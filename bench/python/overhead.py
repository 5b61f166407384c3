"""Per-call overhead of a trivial in-process Python skill vs the same skill in Rust.

One robot, one run: a source writes ``x: f64`` every cycle, and N instances of
the Rust ``bench.double`` and N of the Python ``py.double`` (``double.py``) each
read it and write their own ``y``. The manager times every body call (its
per-skill timing: the GIL, the conversions and the call for Python); the
figures are the mean ns per call of each language over all its instances, their
difference and ratio. Simulated clock, serial executor: cycles back to back.

    .venv/bin/python bench/python/overhead.py [--instances 200] [--cycles 2000]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import situate
from situate.info import Timing

HERE = Path(__file__).resolve().parent


def robot_file(directory: Path, instances: int, kinds: tuple[str, ...] = ("rs", "py")) -> Path:
    """Writes a robot file: a source, and N Rust and/or N Python doublers."""
    types = {"rs": "bench.double", "py": "py.double"}
    lines = [
        "robot: bench",
        "cycle: {rate_hz: 1000, clock: simulated, executor: serial}",
        f"python: [{HERE / 'double.py'}]",
        "skills:",
        "  - {name: src, type: bench.source}",
    ]
    for i in range(instances):
        for kind in kinds:
            lines.append(f"  - {{name: {kind}{i}, type: {types[kind]}, remap: {{y: y.{kind}{i}}}}}")
    path = directory / f"bench_{'_'.join(kinds)}.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def cycle_time(
    robots: dict[str, situate.LocalRobot], cycles: int, windows: int
) -> dict[str, float]:
    """Median µs per cycle of each robot, stepped in alternating windows."""
    times: dict[str, list[float]] = {k: [] for k in robots}
    per_window = max(1, cycles // windows)
    for _ in range(windows):
        for k, robot in robots.items():
            started = time.perf_counter()
            robot.step(per_window)
            times[k].append((time.perf_counter() - started) / per_window * 1e6)
    return {k: statistics.median(v) for k, v in times.items()}


def per_call(before: dict[str, Timing], after: dict[str, Timing], prefix: str) -> float:
    """Mean ns per call over the instances whose name starts with ``prefix``."""
    total = runs = 0
    for name, t in after.items():
        if name.startswith(prefix):
            total += t.total_ns - before[name].total_ns
            runs += t.runs - before[name].runs
    return total / runs


def main() -> None:
    """Runs the benchmark and prints the figures."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--instances", type=int, default=200, help="instances per language")
    parser.add_argument("--cycles", type=int, default=2000)
    parser.add_argument("--windows", type=int, default=20, help="measurement windows")
    parser.add_argument("--warmup", type=int, default=100)
    opts = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        robot = situate.LocalRobot(robot_file(Path(tmp), opts.instances))
        robot.step(opts.warmup)
        first = last = {s.name: s.timing for s in robot.skills()}
        py: list[float] = []
        rs: list[float] = []
        per_window = max(1, opts.cycles // opts.windows)
        stepping = 0.0
        for _ in range(opts.windows):
            started = time.perf_counter()
            robot.step(per_window)
            stepping += time.perf_counter() - started
            now = {s.name: s.timing for s in robot.skills()}
            py.append(per_call(last, now, "py"))
            rs.append(per_call(last, now, "rs"))
            last = now
        cycles = per_window * opts.windows
        check = robot.query(f"y.py{opts.instances - 1}")
        expected = 2.0 * (opts.warmup + cycles)
        assert check.value == expected, f"python skill wrote {check.value}, expected {expected}"
        # End to end: a Rust-only and a Python-only robot, cycle times compared.
        alone = {
            k: situate.LocalRobot(robot_file(Path(tmp), opts.instances, (k,))) for k in ("rs", "py")
        }
        for r in alone.values():
            r.step(opts.warmup)
        cycle_us = cycle_time(alone, opts.cycles, opts.windows)
    py_all, rs_all = per_call(first, last, "py"), per_call(first, last, "rs")
    py_med, rs_med = statistics.median(py), statistics.median(rs)
    print(
        f"{opts.instances} instances per language, {cycles} cycles in {opts.windows} windows "
        f"({cycles * opts.instances} calls per language)"
    )
    print("                     median of windows   mean of all calls   (ns per call)")
    print(f"rust   bench.double  {rs_med:17.1f}   {rs_all:17.1f}")
    print(f"python py.double     {py_med:17.1f}   {py_all:17.1f}")
    diff_med, diff_all = py_med - rs_med, py_all - rs_all
    print(f"python - rust        {diff_med:17.1f}   {diff_all:17.1f}   (target <= 1000)")
    print(f"python / rust        {py_med / rs_med:17.1f}   {py_all / rs_all:17.1f}")
    skills = 2 * opts.instances + 1
    print(f"mixed robot: {stepping / cycles * 1e6:.1f} us per cycle for {skills} skills")
    end_to_end = (cycle_us["py"] - cycle_us["rs"]) / opts.instances * 1e3
    print(
        f"end to end: rust-only robot {cycle_us['rs']:.1f} us/cycle, python-only "
        f"{cycle_us['py']:.1f} us/cycle -> python - rust = {end_to_end:.1f} ns per instance"
    )


if __name__ == "__main__":
    main()
