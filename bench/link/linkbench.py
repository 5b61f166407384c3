"""Link benchmarks: what the Zenoh link adds, as ratios to raw Zenoh measured in the same run.

1. ``sequencer``: a Python sequencer (``situate.connect``) against ``situate run``
   at 100 Hz on loopback. activate → ``activation_applied`` received, and
   ``set_param`` making an edge monitor's condition true → ``monitor_fired``
   received, interleaved with raw Zenoh gets to a trivial eclipse-zenoh
   queryable in another process. Target: each median ≤ one cycle period +
   1.2 × the raw get round trip.
2. ``hop``: one remote-skill round trip manager → remote skill → manager with
   the real ``situate serve-skill`` server (the harness plays the manager's
   side of the protocol), interleaved with a raw eclipse-zenoh pub/sub echo,
   and the same ping-pong as a two-node dora-rs dataflow (``dora run``).
   Reported per hop (half a round trip) and as ratios.

Run it with the workspace's .venv (``bench/link/run.sh`` does):

    .venv/bin/python bench/link/linkbench.py [sequencer] [hop] [--quick] [--samples N]

See bench/link/README.md for what each figure means.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from typing import Any

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)

from _report import (  # noqa: E402
    CpuTimes,
    Report,
    Summary,
    Target,
    fmt_us,
    loadavg,
    wait_idle,
)


class RunTimeout(BaseException):
    """The whole run took longer than ``--max-s`` (not a TimeoutError: nothing may catch it)."""


PERIOD_S = 0.01  # the robot's cycle: 100 Hz
RAW_FACTOR = 1.2  # the target's allowance over the raw round trip


# ----- processes ---------------------------------------------------------------------


class Proc:
    """A process this run started, in its own process group, stopped by its id."""

    started: list[Proc] = []

    def __init__(
        self,
        name: str,
        argv: list[str],
        log_path: str,
        *,
        cwd: str | None = None,
        env: dict[str, str] | None = None,
    ) -> None:
        self.name = name
        self.log_path = log_path
        self._log = open(log_path, "w")  # noqa: SIM115  (closed in stop())
        self.p = subprocess.Popen(
            argv,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            cwd=cwd,
            env=env,
            start_new_session=True,
        )
        Proc.started.append(self)

    def alive(self) -> bool:
        return self.p.poll() is None

    def wait(self, timeout: float) -> int | None:
        try:
            return self.p.wait(timeout)
        except subprocess.TimeoutExpired:
            return None

    def stop(self, grace_s: float = 5.0) -> int | None:
        """SIGINT, then SIGTERM, then SIGKILL; finally anything left in its own group."""
        for sig, wait_s in ((signal.SIGINT, grace_s), (signal.SIGTERM, 3.0), (signal.SIGKILL, 3.0)):
            if self.p.poll() is not None:
                break
            with contextlib.suppress(ProcessLookupError):
                self.p.send_signal(sig)
            self.wait(wait_s)
        # Children it left behind (dora's nodes) are in the group made for it.
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.p.pid, signal.SIGKILL)
        self._log.close()
        if self in Proc.started:
            Proc.started.remove(self)
        return self.p.returncode

    def tail(self, lines: int = 15) -> str:
        try:
            with open(self.log_path, errors="replace") as f:
                return "".join(f.readlines()[-lines:])
        except OSError:
            return ""

    @classmethod
    def stop_all(cls) -> None:
        for p in list(cls.started):
            p.stop(grace_s=2.0)


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def situate_exe() -> str:
    exe = os.path.join(os.path.dirname(sys.executable), "situate")
    if not os.path.exists(exe):
        sys.exit(
            f"error: {exe} not found: run scripts/python.sh first "
            "(and run this with .venv/bin/python)"
        )
    return exe


def cpu_share_line(before: CpuTimes | None) -> tuple[str | None, dict[str, Any]]:
    """(reason it is busy or None, the share as JSON), printed as a `cpu:` line."""
    after = CpuTimes.now()
    share = before.since(after) if before and after else None
    if share is None:
        return None, {}
    print(f"  cpu: {share}; load average {loadavg()}", flush=True)
    busy = (
        f"other processes {share.others:.0f}% + steal {share.steal:.0f}% of all CPUs' time (> 5%)"
        if share.busy()
        else None
    )
    return busy, share.as_json()


# ----- benchmark 1: the sequencer ----------------------------------------------------

ROBOT_FILE = """\
# linkbench: toy skills at 100 Hz, for bench/link/linkbench.py (sequencer).
robot: linkbench
cycle:
  rate_hz: 100
  clock: wall
  executor: serial
devices:
  - name: sonar
    type: toy.sonar
  - name: wheels
    type: toy.wheels
skills:
  - name: runaway
    type: toy.runaway
    params: {safe_distance: 0.5}
  - name: wander
    type: toy.wander
    active: false
"""

LOW, HIGH, THRESHOLD = 0.5, 1.5, 1.0
CONDITION = f"runaway.safe_distance > {THRESHOLD}"


async def _connect(situate: Any, robot: str, endpoint: str, deadline_s: float) -> Any:
    start = time.monotonic()
    while True:
        try:
            return await situate.connect(robot, endpoint=endpoint, timeout=1.0)
        except situate.NotRunning:
            if time.monotonic() - start > deadline_s:
                raise
            await asyncio.sleep(0.2)


async def _until(stream: Any, pred: Callable[[Any], bool], timeout: float) -> Any:
    """The first item of ``stream`` for which ``pred`` holds (TimeoutError after ``timeout`` s)."""
    end = time.monotonic() + timeout
    while True:
        left = end - time.monotonic()
        if left <= 0:
            raise TimeoutError
        try:
            item = await stream.next(timeout=left)
        except asyncio.TimeoutError:  # a distinct class before Python 3.11
            raise TimeoutError from None
        if pred(item):
            return item


async def bench_sequencer(opts: argparse.Namespace, rep: Report, tmp: str) -> None:
    import situate

    bench = "sequencer"
    print(
        f"\n## 1 sequencer: {opts.samples} rounds (+{opts.warmup} warm-up), "
        f"load average {loadavg()}"
    )
    robot_path = os.path.join(tmp, "linkbench.yaml")
    with open(robot_path, "w") as f:
        f.write(ROBOT_FILE)
    mport, qport = free_port(), free_port()
    mend, qend = f"tcp/127.0.0.1:{mport}", f"tcp/127.0.0.1:{qport}"
    manager = Proc(
        "manager",
        [situate_exe(), "run", robot_path, "--listen", mend],
        os.path.join(tmp, "manager.log"),
    )
    rawq = Proc(
        "raw-queryable",
        [
            sys.executable,
            os.path.join(HERE, "raw_queryable.py"),
            "--listen",
            qend,
            "--robot",
            "rawbench",
            "--max-s",
            str(opts.max_s + 60),
        ],
        os.path.join(tmp, "raw_queryable.log"),
    )
    robot = raw = None
    try:
        try:
            robot = await _connect(situate, "linkbench", mend, 20.0)
            raw = await _connect(situate, "rawbench", qend, 20.0)
        except situate.NotRunning as e:
            print(
                f"error: {e}\n--- manager log:\n{manager.tail()}"
                f"\n--- raw queryable log:\n{rawq.tail()}"
            )
            raise
        st = await robot.stats()
        if abs(st.period_s - PERIOD_S) > 1e-9:
            rep.note(f"the manager's period is {st.period_s} s, not {PERIOD_S} s")
        await robot.request("deactivate", skills=["wander"])
        await robot.set_param("runaway", "safe_distance", LOW)
        acts = robot.events("activation_applied")
        mons = robot.events("monitor_fired")
        pars = robot.events("param_changed")
        monitor_id = await robot.monitor(CONDITION, "edge")
        active = False
        last_fire = [0]  # the cycle the monitor last fired in
        rng = random.Random(opts.seed)
        raw_session = raw._session  # the raw baseline's bare blocking get uses the same session
        raw_key = "situate/rawbench/req/ping"
        robot_session = robot._session
        stats_key = "situate/linkbench/req/stats"

        samples: dict[str, list[float]] = {
            k: []
            for k in (
                "activate",
                "deactivate",
                "monitor",
                "raw",
                "raw_bare",
                "stats",
                "stats_bare",
                "activate_reply",
                "set_param_reply",
            )
        }
        cycles_after: dict[str, list[int]] = {"activate": [], "deactivate": [], "monitor": []}
        lost: dict[str, int] = {}

        async def phase() -> None:
            # A random point of the 10 ms cycle, so every sample sees a uniformly random phase.
            await asyncio.sleep(rng.uniform(0.0, PERIOD_S))

        async def toggle(record: bool) -> None:
            nonlocal active
            verb = "deactivate" if active else "activate"
            await phase()
            t0 = time.perf_counter_ns()
            res = await robot.request(verb, skills=["wander"])
            t1 = time.perf_counter_ns()
            key = "deactivated" if active else "activated"
            try:
                ev = await _until(acts, lambda e: "wander" in getattr(e, key), 2.0)
            except TimeoutError:
                lost[verb] = lost.get(verb, 0) + 1
                active = not active
                return
            t2 = time.perf_counter_ns()
            active = not active
            if record:
                samples[verb].append((t2 - t0) / 1e3)
                if verb == "activate":
                    samples["activate_reply"].append((t1 - t0) / 1e3)
                cycles_after[verb].append(ev.cycle - int(res["at_cycle"]))

        async def monitor(record: bool) -> None:
            # Untimed: back below the threshold, and seen false by the monitor at the end of a
            # cycle. (param_changed is published when the request is handled, for the next
            # cycle: waiting for it alone lets LOW and HIGH land in the same cycle, and then
            # the edge monitor rightly never fires.)
            await robot.request("set_param", skill="runaway", param="safe_distance", value=LOW)
            end = time.monotonic() + 2.0
            while time.monotonic() < end:
                if not any(m.holds for m in await robot.monitors() if m.monitor == monitor_id):
                    break
                await asyncio.sleep(PERIOD_S / 4)
            await phase()
            t0 = time.perf_counter_ns()
            await robot.request("set_param", skill="runaway", param="safe_distance", value=HIGH)
            t1 = time.perf_counter_ns()
            try:
                ev = await _until(mons, lambda e: e.monitor == monitor_id, 2.0)
            except TimeoutError:
                lost["monitor"] = lost.get("monitor", 0) + 1
                return
            t2 = time.perf_counter_ns()
            # The HIGH's param_changed (it was published before the monitor fired); older
            # param_changed events still queued are skipped by their cycle.
            pc = None
            with contextlib.suppress(TimeoutError):
                pc = await _until(
                    pars,
                    lambda e: (
                        e.param == "safe_distance" and e.value == HIGH and e.cycle > last_fire[0]
                    ),
                    2.0,
                )
            last_fire[0] = ev.cycle
            if record:
                samples["monitor"].append((t2 - t0) / 1e3)
                samples["set_param_reply"].append((t1 - t0) / 1e3)
                if pc is not None:
                    cycles_after["monitor"].append(ev.cycle - pc.cycle)

        async def raw_client(record: bool) -> None:
            await phase()
            t0 = time.perf_counter_ns()
            await raw.request("ping")  # the sequencer's own path: worker thread, get, JSON
            if record:
                samples["raw"].append((time.perf_counter_ns() - t0) / 1e3)

        async def raw_bare(record: bool) -> None:
            await phase()
            t0 = time.perf_counter_ns()
            got = 0
            for reply in raw_session.get(raw_key, payload="{}", timeout=2.0):
                got += reply.ok is not None
            if record and got:
                samples["raw_bare"].append((time.perf_counter_ns() - t0) / 1e3)

        async def stats_bare(record: bool) -> None:
            await phase()
            t0 = time.perf_counter_ns()
            got = 0
            for reply in robot_session.get(stats_key, payload="{}", timeout=2.0):
                got += reply.ok is not None
            if record and got:
                samples["stats_bare"].append((time.perf_counter_ns() - t0) / 1e3)

        async def stats(record: bool) -> None:
            await phase()
            t0 = time.perf_counter_ns()
            await robot.request("stats")
            if record:
                samples["stats"].append((time.perf_counter_ns() - t0) / 1e3)

        subjects = [toggle, raw_client, monitor, raw_bare, toggle, stats, stats_bare]
        for _ in range(opts.warmup):
            for s in subjects:
                await s(False)
        before = CpuTimes.now()
        st0 = await robot.stats()
        for i in range(opts.samples):
            for s in subjects if i % 2 == 0 else subjects[::-1]:
                await s(True)
        st1 = await robot.stats()
        busy, share = cpu_share_line(before)
        rep.cpu[bench] = share
        await robot.cancel_monitor(monitor_id)
        for s in (acts, mons, pars):
            s.close()
    finally:
        for r in (robot, raw):
            if r is not None:
                with contextlib.suppress(Exception):
                    await asyncio.wait_for(r.close(), 5.0)
        manager.stop()
        rawq.stop()

    S = {k: Summary(v) for k, v in samples.items()}
    names = {
        "activate": "activate → activation_applied received",
        "deactivate": "deactivate → activation_applied received",
        "monitor": "set_param → monitor_fired received (edge)",
        "raw": "raw Zenoh get RT (sequencer's path)",
        "raw_bare": "raw Zenoh get RT (bare blocking get)",
        "stats": "`stats` request RT (sequencer's path)",
        "stats_bare": "`stats` request RT (bare blocking get)",
        "activate_reply": "activate request RT (reply only)",
        "set_param_reply": "set_param request RT (reply only)",
    }
    for k, label in names.items():
        rep.figure(bench, label, S[k])
    raw_med = S["raw"].median
    rep.ratio(bench, "activate → applied / raw RT", S["activate"].median / raw_med, "medians")
    rep.ratio(bench, "monitor → fired / raw RT", S["monitor"].median / raw_med, "medians")
    rep.ratio(bench, "stats RT / raw RT", S["stats"].median / raw_med, "medians, sequencer's path")
    rep.ratio(
        bench,
        "stats RT / raw RT, bare gets",
        S["stats_bare"].median / S["raw_bare"].median,
        "medians",
    )
    rep.ratio(
        bench, "raw RT: sequencer's path / bare get", raw_med / S["raw_bare"].median, "medians"
    )
    rep.print_table(bench, "1 sequencer: Python client ↔ situate run (100 Hz) on loopback")

    period_us = PERIOD_S * 1e6
    for key, label in (
        ("activate", "activate → applied"),
        ("monitor", "monitor condition true → event"),
    ):
        limit = period_us + RAW_FACTOR * raw_med
        p90_limit = period_us + RAW_FACTOR * S["raw"].p90
        rep.target(
            Target(
                bench=bench,
                name=f"{label} (median)",
                value_us=S[key].median,
                limit_us=limit,
                target=(
                    f"≤ 1 cycle ({fmt_us(period_us)}) + {RAW_FACTOR} × raw RT ({fmt_us(raw_med)})"
                ),
                note=(
                    f"p90 {fmt_us(S[key].p90)} vs 1 cycle + {RAW_FACTOR} × raw p90 "
                    f"= {fmt_us(p90_limit)}: "
                    + ("within" if S[key].p90 <= p90_limit else "over")
                    + f"; max {fmt_us(S[key].hi)}"
                ),
                inconclusive=busy,
            )
        )
    for k, v in cycles_after.items():
        if v:
            counts: dict[int, int] = {}
            for c in v:
                counts[c] = counts.get(c, 0) + 1
            what = "the param_changed event's cycle" if k == "monitor" else "the reply's at_cycle"
            rep.note(
                f"{k}: event cycle − {what}: "
                + ", ".join(f"{c}: {n}×" for c, n in sorted(counts.items()))
            )
    if lost:
        rep.note(f"samples with no event within 2 s (left out): {lost}")
    rep.note(
        f"manager during the measured rounds: {st1.cycle - st0.cycle} cycles, "
        f"{st1.overruns - st0.overruns} overruns, max cycle {st1.max_cycle_ns / 1e3:.0f} µs, "
        f"mean {st1.mean_cycle_ns / 1e3:.1f} µs"
    )
    rep.extra.setdefault("raw_samples_us", {})[bench] = {k: v for k, v in samples.items()}


# ----- benchmark 2: the remote-skill hop ---------------------------------------------


class PingPong:
    """One message in flight on ``send_key``; the reply on ``reply_key`` is matched by sequence."""

    def __init__(
        self, session: Any, send_key: str, reply_key: str, seq_of: Callable[[dict[str, Any]], Any]
    ) -> None:
        self.pub = session.declare_publisher(send_key)
        self.seq_of = seq_of
        self.expect: int | None = None
        self.got = threading.Event()
        self.reply: tuple[int, dict[str, Any]] | None = None
        self.sub = session.declare_subscriber(reply_key, self._on_reply)

    def _on_reply(self, sample: Any) -> None:
        now = time.monotonic_ns()
        try:
            msg = json.loads(sample.payload.to_bytes())
            seq = self.seq_of(msg)
        except (ValueError, KeyError, TypeError):
            return
        if seq == self.expect:
            self.reply = (now, msg)
            self.got.set()

    def ping(
        self, seq: int, make: Callable[[int, int], dict[str, Any]], timeout: float
    ) -> tuple[int, int, dict[str, Any]] | None:
        """(sent_ns, received_ns, reply) or None on timeout."""
        self.expect = seq
        self.got.clear()
        sent = time.monotonic_ns()
        self.pub.put(json.dumps(make(seq, sent)))
        if not self.got.wait(timeout):
            return None
        assert self.reply is not None
        return sent, self.reply[0], self.reply[1]

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.sub.undeclare()
        with contextlib.suppress(Exception):
            self.pub.undeclare()


def _situate_inputs(seq: int, sent: int) -> dict[str, Any]:
    # Exactly the manager's message (docs/protocol.md, "Remote skills").
    return {
        "cycle": seq,
        "time_s": sent / 1e9,
        "inputs": {"seq": seq, "sent_ns": sent},
        "params": {},
    }


def _raw_ping(seq: int, sent: int) -> dict[str, Any]:
    return {"seq": seq, "sent_ns": sent}


def _recv_of(msg: dict[str, Any], situate_side: bool) -> int:
    return int(msg["outputs"]["recv_ns"] if situate_side else msg["recv_ns"])


def run_dora_block(
    opts: argparse.Namespace, tmp: str, block: int, n: int
) -> tuple[dict[str, Any] | None, str]:
    """One `dora run` of the ping-pong dataflow; (results or None, why not)."""
    dora = os.path.join(opts.dora_venv, "bin", "dora")
    if not os.path.exists(dora):
        return (
            None,
            f"no dora CLI at {dora} (run.sh installs dora-rs-cli there; it failed or was skipped)",
        )
    work = os.path.join(tmp, f"dora-{block}")
    shutil.copytree(os.path.join(HERE, "dora"), work)
    out = os.path.join(work, "result.json")
    cfg = {
        "samples": n,
        "warmup": opts.warmup,
        "gap_ms": [opts.gap_lo_ms, opts.gap_hi_ms],
        "seed": opts.seed + 1000 * block,
        "out": out,
        "reply_timeout_s": 2.0,
    }
    with open(os.path.join(work, "config.json"), "w") as f:
        json.dump(cfg, f)
    env = dict(os.environ)
    env["PATH"] = os.path.join(opts.dora_venv, "bin") + os.pathsep + env.get("PATH", "")
    env["LINKBENCH_DORA_CONFIG"] = os.path.join(work, "config.json")
    env.pop("VIRTUAL_ENV", None)
    env.pop("PYTHONPATH", None)
    bound = 30 + int((n + opts.warmup) * (opts.gap_hi_ms + 20) / 1000)
    proc = Proc(
        f"dora-{block}",
        [dora, "run", "dataflow.yml", "--stop-after", f"{bound}s", "--log-level", "warn"],
        os.path.join(work, "dora.log"),
        cwd=work,
        env=env,
    )
    rc = proc.wait(bound + 15)
    if rc is None:
        proc.stop()
        return None, f"`dora run` did not finish within {bound + 15} s; log tail:\n{proc.tail()}"
    proc.stop()
    if not os.path.exists(out):
        return None, f"`dora run` exited with {rc} and no results; log tail:\n{proc.tail()}"
    with open(out) as f:
        return json.load(f), ""


def bench_hop(opts: argparse.Namespace, rep: Report, tmp: str) -> None:
    import zenoh

    bench = "hop"
    print(
        f"\n## 2 hop: {opts.blocks} blocks × {opts.samples // opts.blocks} samples "
        f"(+{opts.warmup} warm-up), load average {loadavg()}"
    )
    port = free_port()
    endpoint = f"tcp/127.0.0.1:{port}"
    # The manager's side: a peer listening on loopback, scouting off (docs/protocol.md, "Session").
    config = {
        "mode": "peer",
        "listen": {"endpoints": [endpoint]},
        "connect": {"endpoints": []},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
    }
    session = zenoh.open(zenoh.Config.from_json5(json.dumps(config)))
    server = Proc(
        "serve-skill",
        [
            situate_exe(),
            "serve-skill",
            "hopskill:echo",
            "--robot",
            "hopbench",
            "--name",
            "echo",
            "--connect",
            endpoint,
        ],
        os.path.join(tmp, "serve_skill.log"),
        cwd=HERE,
    )
    rawecho = Proc(
        "raw-echo",
        [
            sys.executable,
            os.path.join(HERE, "raw_echo.py"),
            "--connect",
            endpoint,
            "--prefix",
            "hopbench/raw",
            "--max-s",
            str(opts.max_s + 60),
        ],
        os.path.join(tmp, "raw_echo.log"),
    )
    sit = PingPong(
        session,
        "situate/hopbench/remote/echo/inputs",
        "situate/hopbench/remote/echo/outputs",
        lambda m: int(m["outputs"]["seq"]) if "outputs" in m else None,
    )
    raw = PingPong(session, "hopbench/raw/ping", "hopbench/raw/pong", lambda m: int(m["seq"]))
    rng = random.Random(opts.seed)
    samples: dict[str, dict[str, list[float]]] = {
        k: {"rt": [], "fwd": [], "back": []} for k in ("situate", "raw", "dora")
    }
    lost = {"situate": 0, "raw": 0, "dora": 0}
    blocks_info: list[dict[str, Any]] = []
    dora_why = ""
    seq = 0
    try:
        # Ready when a probe comes back (subscriptions propagate asynchronously).
        for name, pp, make in (("serve-skill", sit, _situate_inputs), ("raw echo", raw, _raw_ping)):
            deadline = time.monotonic() + 20.0
            while True:
                seq += 1
                if pp.ping(seq, make, 0.2) is not None:
                    break
                if time.monotonic() > deadline or not (server.alive() and rawecho.alive()):
                    raise RuntimeError(
                        f"{name} never answered; serve-skill log:\n{server.tail()}"
                        f"\nraw echo log:\n{rawecho.tail()}"
                    )

        def one(which: str, record: bool) -> None:
            nonlocal seq
            time.sleep(rng.uniform(opts.gap_lo_ms, opts.gap_hi_ms) / 1000.0)
            seq += 1
            pp, make = (sit, _situate_inputs) if which == "situate" else (raw, _raw_ping)
            got = pp.ping(seq, make, 2.0)
            if got is None:
                lost[which] += record
                return
            sent, recv, reply = got
            if "error" in reply:
                raise RuntimeError(f"the remote skill faulted: {reply['error']}")
            mid = _recv_of(reply, which == "situate")
            if record:
                samples[which]["rt"].append((recv - sent) / 1e3)
                samples[which]["fwd"].append((mid - sent) / 1e3)
                samples[which]["back"].append((recv - mid) / 1e3)

        for _ in range(opts.warmup):
            one("situate", False)
            one("raw", False)
        per_block = opts.samples // opts.blocks
        for b in range(opts.blocks):
            before = CpuTimes.now()
            for i in range(per_block):
                for which in ("situate", "raw") if i % 2 == 0 else ("raw", "situate"):
                    one(which, True)
            busy_s, share_s = cpu_share_line(before)
            blocks_info.append({"block": b, "side": "situate+raw", "cpu": share_s, "busy": busy_s})
            if opts.no_dora:
                dora_why = dora_why or "skipped (--no-dora)"
                continue
            before = CpuTimes.now()
            res, why = run_dora_block(opts, tmp, b, per_block)
            busy_d, share_d = cpu_share_line(before)
            if res is None:
                dora_why = why
                print(f"  dora: {why}", flush=True)
                opts.no_dora = True
                continue
            blocks_info.append(
                {
                    "block": b,
                    "side": "dora",
                    "cpu": share_d,
                    "busy": busy_d,
                    "median_rt_us": Summary(res["rt_us"]).median,
                }
            )
            samples["dora"]["rt"] += res["rt_us"]
            samples["dora"]["fwd"] += res["fwd_us"]
            samples["dora"]["back"] += res["back_us"]
            lost["dora"] += int(res["lost"])
    finally:
        sit.close()
        raw.close()
        with contextlib.suppress(Exception):
            session.close()
        server.stop()
        rawecho.stop()

    have_dora = bool(samples["dora"]["rt"])
    labels = {
        "situate": "situate remote skill (serve-skill)",
        "raw": "raw Zenoh pub/sub echo",
        "dora": "dora-rs node echo",
    }
    for k, label in labels.items():
        if not samples[k]["rt"]:
            continue
        rt = Summary(samples[k]["rt"])
        rep.figure(bench, f"{label}: round trip (2 hops)", rt)
        rep.figure(bench, f"{label}: per hop (RT / 2)", Summary([x / 2 for x in samples[k]["rt"]]))
        rep.figure(bench, f"{label}: out (sender → body)", Summary(samples[k]["fwd"]))
        rep.figure(bench, f"{label}: back (body → sender)", Summary(samples[k]["back"]))
    s_med = Summary(samples["situate"]["rt"]).median
    r_med = Summary(samples["raw"]["rt"]).median
    rep.ratio(
        bench, "situate hop / raw Zenoh hop", s_med / r_med, "medians; interleaved sample by sample"
    )
    if have_dora:
        d_med = Summary(samples["dora"]["rt"]).median
        rep.ratio(bench, "situate hop / dora-rs hop", s_med / d_med, "medians; alternating blocks")
        per_block_ratios = []
        sit_rt = samples["situate"]["rt"]
        per = len(sit_rt) // opts.blocks if opts.blocks else 0
        dora_blocks = [b for b in blocks_info if b["side"] == "dora"]
        for b, db in enumerate(dora_blocks):
            chunk = sit_rt[b * per : (b + 1) * per]
            if chunk:
                per_block_ratios.append(Summary(chunk).median / db["median_rt_us"])
        if per_block_ratios:
            rep.note(
                "situate / dora per block: " + ", ".join(f"{x:.2f}×" for x in per_block_ratios)
            )
    rep.print_table(bench, "2 hop: remote skill manager → skill → manager, loopback")
    if not have_dora:
        rep.note(f"dora-rs not measured: {dora_why}")
    if any(lost.values()):
        rep.note(f"pings with no reply within 2 s (left out): {lost}")
    for info in blocks_info:
        if info["busy"]:
            rep.note(
                f"block {info['block']} ({info['side']}) ran on a busy machine: {info['busy']}"
            )
    rep.cpu[bench] = blocks_info
    rep.extra.setdefault("raw_samples_us", {})[bench] = samples


# ----- main --------------------------------------------------------------------------


def main() -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("benches", nargs="*", metavar="sequencer|hop", help="default: both")
    ap.add_argument("--samples", type=int, default=300, help="samples per figure (default 300)")
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--blocks", type=int, default=3, help="hop: alternating situate/dora blocks")
    ap.add_argument("--gap-lo-ms", type=float, default=2.0)
    ap.add_argument("--gap-hi-ms", type=float, default=12.0)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument(
        "--quick", action="store_true", help="a smoke run: 40 samples, 5 warm-up, 1 block"
    )
    ap.add_argument(
        "--wait-idle",
        type=float,
        default=0.0,
        metavar="S",
        help="first wait up to S seconds for other processes to go quiet",
    )
    ap.add_argument("--dora-venv", default=os.environ.get("DORA_VENV", "/tmp/dora-venv"))
    ap.add_argument("--no-dora", action="store_true")
    ap.add_argument("--max-s", type=float, default=600.0, help="hard bound on the whole run")
    ap.add_argument("--json", default=None)
    opts = ap.parse_args()
    if opts.quick:
        opts.samples, opts.warmup, opts.blocks = 40, 5, 1
    benches = opts.benches or ["sequencer", "hop"]
    unknown = [b for b in benches if b not in ("sequencer", "hop")]
    if unknown:
        ap.error(f"unknown benchmark {', '.join(unknown)}: choose from sequencer, hop")
    target_dir = os.environ.get("CARGO_TARGET_DIR") or os.path.join(REPO, "target")
    json_path = opts.json or os.path.join(target_dir, "bench-results", "link.json")

    def on_alarm(*_: Any) -> None:
        raise RunTimeout(f"the run took longer than --max-s {opts.max_s:g} s")

    signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(int(opts.max_s))
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))

    rep = Report()
    rep.extra["loadavg_at_start"] = loadavg()
    print(
        f"link benchmarks — {time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime())}, "
        f"{os.cpu_count()} CPUs, load average {loadavg()}"
    )
    if opts.wait_idle > 0:
        idle, waited = wait_idle(opts.wait_idle)
        rep.note(
            f"waited {waited:.0f} s for an idle machine: "
            + ("idle" if idle else "still busy, going on")
        )
    tmp = tempfile.mkdtemp(prefix="linkbench-")
    status = 0
    try:
        if "sequencer" in benches:
            asyncio.run(bench_sequencer(opts, rep, tmp))
        if "hop" in benches:
            bench_hop(opts, rep, tmp)
    except BaseException as e:  # report what we have, clean up, fail
        print(f"error: {type(e).__name__}: {e}", file=sys.stderr)
        status = 1
    finally:
        signal.alarm(0)
        Proc.stop_all()
    rep.write_json(json_path, " ".join(sys.argv[1:]))
    if status == 0:
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"\nresults: {json_path}")
    else:
        print(f"\nresults so far: {json_path}; logs kept in {tmp}")
    return status


if __name__ == "__main__":
    sys.exit(main())
