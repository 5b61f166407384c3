"""The `situate` console script of the wheel: the Rust program's verbs, run as subprocesses."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from support import (
    EVENT_S,
    TOYBOT,
    Manager,
    free_port,
    program_env,
    situate,
    situate_program,
    start_manager,
)

import situate as situate_pkg


def test_version_and_help_come_from_the_rust_program() -> None:
    result = situate("--version")
    assert result.returncode == 0
    assert result.stdout.strip() == f"situate {situate_pkg.version()}"
    assert "check" in situate("--help").stdout


def test_check_and_types_work_offline() -> None:
    result = situate("check", str(TOYBOT))
    assert result.returncode == 0, result.stderr
    assert "ok — robot `toybot`" in result.stdout
    types = situate("types").stdout
    assert "toy.runaway" in types
    # The simulator's devices too, with their ports and parameters.
    assert "sim.sonar (device, priority 0)" in types
    assert "param cone_deg: f64" in types


@pytest.mark.parametrize(
    "args", [("schema", "robot"), ("schema", "map"), ("completions", "bash"), ("types",)]
)
def test_a_reader_that_went_away_ends_the_program_quietly(args: tuple[str, ...]) -> None:
    # `situate schema robot | head -c1`, made certain: the pipe's read end is closed before the
    # program writes, so its first write fails (EPIPE) whatever the timing.
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        done = subprocess.run(
            [situate_program(), *args],
            stdout=write_end,
            stderr=subprocess.PIPE,
            text=True,
            timeout=60,
            env=program_env(),
            check=False,
        )
    finally:
        os.close(write_end)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # no panic, no traceback


def test_a_bad_command_line_exits_2() -> None:
    result = situate("activat", "wander")
    assert result.returncode == 2
    assert "activate" in result.stderr  # clap suggests the verb


def test_skills_lists_the_robot(toybot: Manager) -> None:
    result = situate("skills", *toybot.connect_args)
    assert result.returncode == 0, result.stderr
    names = [line.split()[0] for line in result.stdout.splitlines()]
    assert names == ["sonar", "wheels", "runaway", "wander"]
    as_json = json.loads(situate("skills", "--json", *toybot.connect_args).stdout)
    assert [s["name"] for s in as_json] == names


def test_activate_and_deactivate(toybot: Manager) -> None:
    off = situate("deactivate", "wander", *toybot.connect_args)
    assert off.returncode == 0, off.stderr
    assert off.stdout.startswith("deactivated wander from cycle")
    assert situate("deactivate", "wander", *toybot.connect_args).stdout.startswith("nothing")
    on = situate("activate", "wander", "--with-providers", *toybot.connect_args)
    assert on.stdout.startswith("activated wander from cycle"), on.stderr
    bad = situate("activate", "wandr", *toybot.connect_args)
    assert bad.returncode == 5  # refused
    assert "did you mean `wander`?" in bad.stderr


def test_param_get_and_set(toybot: Manager) -> None:
    set_ = situate("param", "set", "runaway", "safe_distance", "0.3", *toybot.connect_args)
    assert set_.returncode == 0, set_.stderr
    assert "runaway.safe_distance = 0.3" in set_.stdout
    get = situate("param", "get", "runaway", "safe_distance", *toybot.connect_args)
    assert get.stdout.strip() == "0.3"
    bad = situate("param", "set", "runaway", "safe_distance", "far", *toybot.connect_args)
    assert bad.returncode == 5
    assert "far" in bad.stderr
    unknown = situate("param", "get", "runaway", "safe_distanc", *toybot.connect_args)
    assert unknown.returncode == 5
    assert "did you mean `safe_distance`" in unknown.stderr
    # Nothing close: the parameters there are.
    far_off = situate("param", "get", "runaway", "range", *toybot.connect_args)
    assert far_off.returncode == 5
    assert "unknown parameter `range` (its parameters: `safe_distance`, `speed`)" in far_off.stderr


def test_query(toybot: Manager) -> None:
    result = situate("query", "sonar.range", *toybot.connect_args)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("sonar.range = [")
    assert "(f32[24]" in result.stdout
    reading = json.loads(situate("query", "odom", "--json", *toybot.connect_args).stdout)
    assert set(reading["value"]) == {"x", "y", "theta"}
    bad = situate("query", "sonar.rnge", *toybot.connect_args)
    assert bad.returncode == 5
    assert "did you mean `sonar.range`" in bad.stderr
    # Several: one `query_many`, a line each (a list with --json), all of the same cycle.
    several = situate("query", "odom.x", "sonar.range", *toybot.connect_args)
    assert several.returncode == 0, several.stderr
    lines = several.stdout.splitlines()
    assert [line.split(" = ")[0] for line in lines] == ["odom.x", "sonar.range"]
    listed = json.loads(situate("query", "odom", "odom.x", "--json", *toybot.connect_args).stdout)
    assert [r["signal"] for r in listed] == ["odom", "odom.x"]
    whole, leaf = listed[0]["value"], listed[1]["value"]
    assert leaf == (whole["x"] if whole is not None else None)  # one moment's
    bad = situate("query", "odom", "sonar.rnge", *toybot.connect_args)
    assert bad.returncode == 5
    assert "unknown signal `sonar.rnge` — did you mean `sonar.range`?" in bad.stderr


def test_monitor_prints_its_event(toybot: Manager) -> None:
    result = situate("monitor", "sonar.range[0] < 100", *toybot.connect_args, timeout=EVENT_S + 30)
    assert result.returncode == 0, result.stderr
    assert "registered (once)" in result.stderr
    assert "sonar.range[0] < 100" in result.stdout
    bad = situate("monitor", "sonar.range[0] <", *toybot.connect_args)
    assert bad.returncode == 5
    assert "^" in bad.stderr  # the pointer under the problem


def test_events_count(toybot: Manager) -> None:
    events = subprocess.Popen(
        [situate_program(), "events", "--count", "3", *toybot.connect_args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=program_env(),
    )
    try:
        out, err = _wait_or_nudge(events, toybot)
    finally:
        if events.poll() is None:
            events.kill()
            events.communicate()
    assert events.returncode == 0, err
    lines = [json.loads(line) for line in out.splitlines()]
    assert len(lines) == 3
    assert all(e["kind"] == "param_changed" for e in lines)


def _wait_or_nudge(process: subprocess.Popen[str], toybot: Manager) -> tuple[str, str]:
    """Waits for `situate events` to end, making events (parameter changes) until it does.

    Events published before its subscription is in place are not seen, so
    the test keeps making them: a poll-until, bounded, with no fixed sleep.
    """
    for value in range(200):
        try:
            return process.communicate(timeout=0.2)
        except subprocess.TimeoutExpired:
            situate("param", "set", "wander", "seed", str(value), *toybot.connect_args)
    pytest.fail("`situate events --count 3` saw fewer than 3 events")


def test_record_over_the_link_writes_into_the_record_dir_only(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    robot = start_manager(TOYBOT, "toybot", "--record-dir", str(tmp_path))
    try:
        args = robot.connect_args
        status = json.loads(situate("record", "status", "--json", *args).stdout)
        assert status == {"recording": None, "dir": str(tmp_path)}, status
        # A client names a file, never a path.
        for bad in ["../escape.mcap", "/tmp/x.mcap", "x.txt"]:
            refused = situate("record", "start", bad, *args)
            assert refused.returncode == 5, (bad, refused.stderr)
            assert "file name" in refused.stderr or ".mcap" in refused.stderr, refused.stderr
        assert not (tmp_path.parent / "escape.mcap").exists()

        started = situate("record", "start", "run.mcap", *args)
        assert started.returncode == 0, started.stderr
        assert started.stdout.strip() == f"recording to {tmp_path / 'run.mcap'}"
        again = situate("record", "start", "other.mcap", *args)
        assert again.returncode == 5
        assert "already recording" in again.stderr

        def cycle() -> int:
            out = json.loads(situate("stats", "--json", *args).stdout)
            return int(out["cycle"])

        # Some cycles go by (a condition, generously bounded).
        first = cycle()
        deadline = time.monotonic() + 60
        while cycle() < first + 10 and time.monotonic() < deadline:
            time.sleep(0.05)
        stopped = json.loads(situate("record", "stop", "--json", *args).stdout)
        assert stopped["path"] == str(tmp_path / "run.mcap"), stopped
        assert stopped["cycles"] >= 10, stopped
        assert stopped["dropped_cycles"] == 0, stopped
        nothing = situate("record", "stop", *args)
        assert nothing.returncode == 5
        assert "nothing is being recorded" in nothing.stderr
        # An existing file is never overwritten.
        exists = situate("record", "start", "run.mcap", *args)
        assert exists.returncode == 5
        assert "exists" in exists.stderr
    finally:
        robot.stop()

    with (tmp_path / "run.mcap").open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        assert summary.statistics is not None
        assert summary.statistics.message_count == stopped["messages"]
        topics = {c.topic for c in summary.channels.values()}
    assert {"sonar.range", "situate/cycles"} <= topics, topics


def test_stats_and_cycle(toybot: Manager) -> None:
    stats = situate("stats", *toybot.connect_args)
    assert stats.returncode == 0, stats.stderr
    assert stats.stdout.startswith("robot `toybot`: cycle")
    assert "running" in stats.stdout
    stopped = situate("cycle", "stop", *toybot.connect_args)
    assert stopped.returncode == 0
    assert re.fullmatch(r"robot `toybot`: stopped at cycle \d+ \([\d.]+ s\)\n", stopped.stdout)
    before = json.loads(situate("stats", "--json", *toybot.connect_args).stdout)
    # The stats' time without float noise: to the millisecond at most.
    stats_text = situate("stats", *toybot.connect_args).stdout
    assert re.search(r", \d+(\.\d{1,3})? s, stopped;", stats_text), stats_text
    stepped = situate("cycle", "step", "3", *toybot.connect_args)
    assert stepped.returncode == 0
    at = before["cycle"] + 3
    said = f"robot `toybot`: stepped 3 cycles, now at cycle {at} ("
    assert stepped.stdout.startswith(said), stepped
    assert stepped.stdout.endswith("), stopped\n")
    after = json.loads(situate("stats", "--json", *toybot.connect_args).stdout)
    assert after["cycle"] == at
    assert not after["running"]
    one = json.loads(situate("cycle", "step", "--json", *toybot.connect_args).stdout)
    assert one["cycle"] == "step"
    assert one["at_cycle"] == at + 1
    assert one["running"] is False
    run = situate("cycle", "run", *toybot.connect_args)
    assert run.returncode == 0
    assert run.stdout.startswith("robot `toybot`: running, at cycle "), run.stdout
    assert json.loads(situate("stats", "--json", *toybot.connect_args).stdout)["running"]
    bad = situate("cycle", "step", "0", *toybot.connect_args)
    assert bad.returncode == 5
    assert "cycles" in bad.stderr


def test_a_robot_named_wrong_is_an_error_naming_the_robot_that_answered(toybot: Manager) -> None:
    result = situate("stats", "--connect", toybot.endpoint, "--robot", "otherbot")
    assert result.returncode == 4, result.stderr
    assert "robot `otherbot` did not answer; robot `toybot` did" in result.stderr


def test_the_robot_is_found_without_naming_it(toybot: Manager) -> None:
    result = situate("stats", "--connect", toybot.endpoint)
    assert result.returncode == 0, result.stderr
    assert "robot `toybot`" in result.stdout


def test_no_manager_running_is_a_clear_error() -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    result = situate("skills", "--connect", endpoint, "--timeout", "1")
    assert result.returncode != 0
    assert "no skill manager answered" in result.stderr, result.stderr


NATIVE_IN_A_THREAD = """
import sys, threading
from situate import _link, _native

robot_file, endpoint = sys.argv[1], sys.argv[2]
codes = []
args = ["situate", "run", robot_file, "--listen", endpoint, "--cycles", "1000"]
runner = threading.Thread(target=lambda: codes.append(_native.main(args)))
runner.start()
# Python code in this thread talks to the program while it runs: only possible if it let go
# of the GIL. Then stepping past its last cycle ends it.
session = None
while session is None:
    try:
        session = _link.open_session([endpoint])
    except _link.NotRunning:
        pass
robot = _link.hello(session, None, timeout=30, endpoints=[endpoint])["robot"]
_link.request(session, robot, "step", {"cycles": 1000}, timeout=30, endpoints=[endpoint])
_link.close_session(session)
runner.join()
bad = _native.main(["situate", "check", "/nonexistent/robot.yaml"])
print("result:", robot, codes[0], bad)
"""


def test_the_native_program_releases_the_gil_and_returns_its_exit_code() -> None:
    result = subprocess.run(
        [sys.executable, "-c", NATIVE_IN_A_THREAD, str(TOYBOT), f"tcp/127.0.0.1:{free_port()}"],
        capture_output=True,
        text=True,
        timeout=120,
        env=program_env(),
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("robot `toybot`: ")  # the program's own summary
    assert result.stdout.splitlines()[-1] == "result: toybot 0 3"  # 3: a bad file
