"""Summaries, CPU-share accounting, tables, TARGET lines and JSON for the link benchmarks.

The same conventions as the core benchmarks (``bench/src/report.rs``): figures
are medians of samples measured in one run, targets are printed and never
enforced, and a benchmark during which other processes or the hypervisor took
more than 5 % of all CPUs' time prints its verdicts as ``INCONCLUSIVE``.
Standard library only, so it runs under any Python 3.9+.
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import dataclass, field
from typing import Any


def quantile(sorted_xs: list[float], q: float) -> float:
    """Linear-interpolated quantile of an already sorted list (``q`` in [0, 1])."""
    if not sorted_xs:
        return float("nan")
    pos = (len(sorted_xs) - 1) * q
    lo = int(pos)
    hi = min(lo + 1, len(sorted_xs) - 1)
    return sorted_xs[lo] + (sorted_xs[hi] - sorted_xs[lo]) * (pos - lo)


@dataclass
class Summary:
    """Median, quartiles, p90, p99 and extremes of some samples (in µs unless said)."""

    samples: list[float]
    median: float = 0.0
    q1: float = 0.0
    q3: float = 0.0
    p90: float = 0.0
    p99: float = 0.0
    lo: float = 0.0
    hi: float = 0.0

    def __post_init__(self) -> None:
        xs = sorted(self.samples)
        self.median = quantile(xs, 0.5)
        self.q1 = quantile(xs, 0.25)
        self.q3 = quantile(xs, 0.75)
        self.p90 = quantile(xs, 0.9)
        self.p99 = quantile(xs, 0.99)
        self.lo = xs[0] if xs else float("nan")
        self.hi = xs[-1] if xs else float("nan")

    def as_json(self) -> dict[str, Any]:
        return {
            "median": self.median,
            "q1": self.q1,
            "q3": self.q3,
            "p90": self.p90,
            "p99": self.p99,
            "min": self.lo,
            "max": self.hi,
            "samples": len(self.samples),
        }


# ----- where the CPUs' time went ------------------------------------------------------


def _ticks_of(pid: str) -> tuple[int, int, int]:
    """(ppid, own ticks utime+stime, reaped children's ticks cutime+cstime) of a process."""
    with open(f"/proc/{pid}/stat") as f:
        after = f.read().rsplit(")", 1)[1].split()
    # after[0] is the state (field 3); ppid is field 4; utime..cstime are fields 14..17.
    return int(after[1]), int(after[11]) + int(after[12]), int(after[13]) + int(after[14])


def own_tree_ticks() -> int:
    """CPU ticks used by this process and everything it started, alive or reaped.

    Linux adds a reaped child's time (and that of the children it reaped) to
    its parent's ``cutime``/``cstime``, so the sum over the live tree plus
    each one's reaped children counts every process this run started.
    """
    me = os.getpid()
    procs: dict[int, tuple[int, int, int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            procs[int(entry)] = _ticks_of(entry)
        except (OSError, IndexError, ValueError):
            continue
    children: dict[int, list[int]] = {}
    for pid, (ppid, _, _) in procs.items():
        children.setdefault(ppid, []).append(pid)
    total = 0
    todo = [me]
    while todo:
        pid = todo.pop()
        if pid in procs:
            _, own, reaped = procs[pid]
            total += own + reaped
        todo.extend(children.get(pid, []))
    return total


@dataclass
class CpuTimes:
    busy: int
    idle: int
    steal: int
    own: int

    @staticmethod
    def now() -> CpuTimes | None:
        try:
            with open("/proc/stat") as f:
                cpu = [int(x) for x in f.readline().split()[1:]]
        except (OSError, ValueError):
            return None
        get = lambda i: cpu[i] if i < len(cpu) else 0  # noqa: E731
        return CpuTimes(
            busy=get(0) + get(1) + get(2) + get(5) + get(6),
            idle=get(3) + get(4),
            steal=get(7),
            own=own_tree_ticks(),
        )

    def since(self, later: CpuTimes) -> CpuShare | None:
        busy = max(0, later.busy - self.busy)
        idle = max(0, later.idle - self.idle)
        steal = max(0, later.steal - self.steal)
        total = busy + idle + steal
        if total == 0:
            return None
        own = min(max(0, later.own - self.own), busy)
        pct = lambda x: x / total * 100.0  # noqa: E731
        return CpuShare(own=pct(own), others=pct(busy - own), steal=pct(steal), idle=pct(idle))


@dataclass
class CpuShare:
    own: float
    others: float
    steal: float
    idle: float

    def busy(self) -> bool:
        return self.others + self.steal > 5.0

    def __str__(self) -> str:
        return (
            f"of all CPUs' time: this run {self.own:.0f}%, other processes {self.others:.0f}%, "
            f"stolen by the hypervisor {self.steal:.0f}%, idle {self.idle:.0f}%"
        )

    def as_json(self) -> dict[str, float]:
        return {"own": self.own, "others": self.others, "steal": self.steal, "idle": self.idle}


def loadavg() -> str:
    try:
        with open("/proc/loadavg") as f:
            return " ".join(f.read().split()[:3])
    except OSError:
        return ""


def wait_idle(max_wait_s: float, *, window_s: float = 5.0) -> tuple[bool, float]:
    """Waits until other processes and steal stay ≤ 5 % for ``window_s``; (idle?, waited s)."""
    start = time.monotonic()
    while True:
        before = CpuTimes.now()
        time.sleep(window_s)
        after = CpuTimes.now()
        share = before.since(after) if before and after else None
        waited = time.monotonic() - start
        if share is None or not share.busy():
            return True, waited
        if waited >= max_wait_s:
            return False, waited
        print(f"  waiting for an idle machine ({share}) ...", flush=True)


# ----- the report --------------------------------------------------------------------


def fmt_us(x: float) -> str:
    """µs with as many decimals as the size deserves; ms from 10 ms on."""
    if x != x:  # nan
        return "—"
    if abs(x) >= 10_000:
        return f"{x / 1000:.2f} ms"
    if abs(x) >= 1000:
        return f"{x / 1000:.3f} ms"
    if abs(x) >= 100:
        return f"{x:.0f} µs"
    return f"{x:.1f} µs"


@dataclass
class Target:
    bench: str
    name: str
    value_us: float
    limit_us: float
    target: str
    note: str = ""
    inconclusive: str | None = None

    @property
    def met(self) -> bool:
        return self.value_us <= self.limit_us

    def line(self) -> str:
        met = "met" if self.met else "NOT met"
        if self.inconclusive:
            met += ", INCONCLUSIVE"
        note = f" — {self.note}" if self.note else ""
        if self.inconclusive:
            note += f" — INCONCLUSIVE: {self.inconclusive}"
        return (
            f"TARGET {self.name}: {fmt_us(self.value_us)} "
            f"(target {self.target} = {fmt_us(self.limit_us)}): {met}{note}"
        )


@dataclass
class Report:
    figures: list[dict[str, Any]] = field(default_factory=list)
    targets: list[Target] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    cpu: dict[str, Any] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)

    def figure(self, bench: str, name: str, summary: Summary, unit: str = "µs") -> Summary:
        self.figures.append({"bench": bench, "name": name, "unit": unit, **summary.as_json()})
        return summary

    def ratio(self, bench: str, name: str, value: float, detail: str = "") -> float:
        self.figures.append(
            {"bench": bench, "name": name, "unit": "×", "value": value, "detail": detail}
        )
        return value

    def target(self, t: Target) -> None:
        print(t.line(), flush=True)
        self.targets.append(t)

    def note(self, text: str) -> None:
        print(f"  note: {text}", flush=True)
        self.notes.append(text)

    def print_table(self, bench: str, title: str) -> None:
        rows = [f for f in self.figures if f["bench"] == bench]
        width = max([len(f["name"]) for f in rows] + [8])
        print()
        print(f"== {title}")
        print(f"{'':<{width}}  {'median':>10}  {'p90':>10}  {'q1 .. q3':>21}  {'n':>4}")
        for f in rows:
            if f["unit"] == "×":
                print(f"{f['name']:<{width}}  {f['value']:>9.2f}×  {f.get('detail', '')}")
                continue
            rng = f"{fmt_us(f['q1'])} .. {fmt_us(f['q3'])}"
            print(
                f"{f['name']:<{width}}  {fmt_us(f['median']):>10}  {fmt_us(f['p90']):>10}  "
                f"{rng:>21}  {f['samples']:>4}"
            )
        sys_stdout_flush()

    def write_json(self, path: str, args: str) -> None:
        cpu_model = "unknown"
        try:
            with open("/proc/cpuinfo") as f:
                for line in f:
                    if line.startswith("model name"):
                        cpu_model = line.split(":", 1)[1].strip()
                        break
        except OSError:
            pass
        now = time.time()
        doc = {
            "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime(now)),
            "unix_time": int(now),
            "cpus": os.cpu_count(),
            "cpu_model": cpu_model,
            "python": platform.python_version(),
            "args": args,
            "loadavg_at_end": loadavg(),
            "cpu_share": self.cpu,
            "targets": [
                {
                    "bench": t.bench,
                    "name": t.name,
                    "value_us": t.value_us,
                    "limit_us": t.limit_us,
                    "target": t.target,
                    "met": t.met,
                    "inconclusive": t.inconclusive is not None,
                    "line": t.line(),
                }
                for t in self.targets
            ],
            "figures": self.figures,
            "notes": self.notes,
            **self.extra,
        }
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        with open(path, "w") as f:
            json.dump(doc, f, indent=1, ensure_ascii=False)
            f.write("\n")


def sys_stdout_flush() -> None:
    import sys

    sys.stdout.flush()
