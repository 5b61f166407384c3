"""Signals through the wheel's `situate` (the Rust program behind python/situate/_cli.py).

SIGTERM and SIGHUP stop `situate run` as Ctrl-C does (the summary, status 0, no Python
traceback); a Python skill whose body never returns does not keep it from stopping; the
Python `serve-skill` stops on SIGTERM; `situate demo` handles Ctrl-C (at a terminal: the
whole process group) and SIGTERM itself: it stops the sequencer, prints the outcome and exits
128 + the signal. Every wait is for a line or an exit, bounded generously; no fixed sleeps.
"""

from __future__ import annotations

import os
import queue
import re
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path
from typing import IO

import pytest
from support import REPO, TOYBOT, free_port, program_env, situate, situate_program

WAIT_S = 60.0


class Program:
    """A running `situate`, its stdout and stderr read line by line."""

    def __init__(self, *args: str, cwd: Path = REPO, session: bool = False) -> None:
        self.process = subprocess.Popen(
            [situate_program(), *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=program_env(),
            cwd=cwd,
            start_new_session=session,
        )
        self.lines: queue.Queue[tuple[str, str | None]] = queue.Queue()
        self.out: list[str] = []
        self.err: list[str] = []
        self._readers = [
            threading.Thread(target=self._read, args=(name, stream), daemon=True)
            for name, stream in (("out", self.process.stdout), ("err", self.process.stderr))
        ]
        for r in self._readers:
            r.start()

    def _read(self, name: str, stream: IO[str] | None) -> None:
        assert stream is not None
        for line in stream:
            self.lines.put((name, line))
        self.lines.put((name, None))

    def _take(self, timeout: float) -> bool:
        """Files the next line read; False at the end of both streams."""
        name, line = self.lines.get(timeout=timeout)
        if line is not None:
            (self.out if name == "out" else self.err).append(line)
        return line is not None or any(r.is_alive() for r in self._readers)

    def wait_for(self, text: str) -> None:
        """Waits for a line of stdout or stderr containing ``text``."""
        deadline = time.monotonic() + WAIT_S
        while not any(text in line for line in self.out + self.err):
            left = deadline - time.monotonic()
            try:
                if left <= 0 or not self._take(left):
                    break
            except queue.Empty:
                break
        if not any(text in line for line in self.out + self.err):
            self.process.kill()
            pytest.fail(f"no line with {text!r}:\n{''.join(self.out)}\n{''.join(self.err)}")

    def finish(self) -> tuple[int, str, str]:
        """Waits for the exit (bounded); the status, stdout and stderr."""
        try:
            code = self.process.wait(timeout=WAIT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
            pytest.fail(f"situate did not exit within {WAIT_S} s:\n{''.join(self.err)}")
        for r in self._readers:
            r.join(timeout=WAIT_S)
        while not self.lines.empty():
            self._take(0)
        return code, "".join(self.out), "".join(self.err)

    def __enter__(self) -> Program:
        return self

    def __exit__(self, *_: object) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_run_stops_cleanly_on_a_signal(sig: signal.Signals) -> None:
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with Program("run", str(TOYBOT), "--listen", endpoint) as run:
        run.wait_for("serving situate/toybot/**")
        run.process.send_signal(sig)
        code, out, err = run.finish()
    assert code == 0, err
    assert f"situate: {sig.name}: stopping" in err
    assert out.startswith("robot `toybot`: "), out
    assert "Traceback" not in err
    assert "KeyboardInterrupt" not in err


HANGING_SKILL = """
import os
import time

import situate


@situate.skill(name="py.hang", outputs={"x": "f64"})
def hang(h: float = situate.param(0.0, min=0.0, max=1.0)) -> dict[str, float]:
    if h > 0:
        os.write(2, b"py.hang: hanging\\n")
        time.sleep(10**6)
    return {"x": 1.0}
"""


def test_a_stuck_python_skill_does_not_keep_run_from_stopping(tmp_path: Path) -> None:
    (tmp_path / "hang.py").write_text(textwrap.dedent(HANGING_SKILL))
    (tmp_path / "robot.yaml").write_text(
        "robot: pyhang\ncycle: {rate_hz: 50}\npython: [hang.py]\n"
        "skills:\n  - {name: hang, type: py.hang}\n"
    )
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with Program("run", str(tmp_path / "robot.yaml"), "--listen", endpoint) as run:
        run.wait_for("serving situate/pyhang/**")
        connect = ("--connect", endpoint, "--robot", "pyhang")
        assert situate("param", "set", "hang", "h", "1", *connect).returncode == 0
        run.wait_for("py.hang: hanging")
        # Ctrl-C used to be noticed and then wait for the cycle for ever.
        run.process.send_signal(signal.SIGINT)
        code, out, err = run.finish()
    assert "situate: SIGINT: stopping" in err
    assert "Traceback" not in err
    if code == 0:  # a manager that leaves such a body behind stops cleanly
        assert out.startswith("robot `pyhang`: "), out
    else:
        assert code == 1, err
        assert "the cycle did not stop within 2 s of the shutdown request" in err
        assert "exiting without it" in err


REMOTE_SKILL = """
import situate

@situate.remote_skill(outputs={"y": "f64"})
def one():
    return {"y": 1.0}
"""


def test_python_serve_skill_stops_on_sigterm(tmp_path: Path) -> None:
    (tmp_path / "robot.yaml").write_text(
        "robot: rsig\ncycle: {rate_hz: 50}\nskills:\n"
        "  - name: one\n    remote: {outputs: {y: f64}}\n"
    )
    (tmp_path / "rsig_skills.py").write_text(textwrap.dedent(REMOTE_SKILL))
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with Program("run", str(tmp_path / "robot.yaml"), "--listen", endpoint) as manager:
        manager.wait_for("serving situate/rsig/**")
        args = ("serve-skill", "rsig_skills:one", "--robot", "rsig", "--connect", endpoint)
        with Program(*args, cwd=tmp_path) as host:
            host.wait_for("situate: serving remote skill `one`")
            host.process.send_signal(signal.SIGTERM)
            code, _, err = host.finish()
        manager.process.send_signal(signal.SIGTERM)
        assert manager.finish()[0] == 0
    assert code == 0, err
    assert "situate: SIGTERM: stopping" in err
    assert "situate: stopped (SIGTERM);" in err
    assert "Traceback" not in err


def _demo() -> Program:
    # The GUI paces the simulated clock (1x real time): the mission takes minutes, so it is
    # surely still running when the signal comes.
    args = ("demo", "--python", sys.executable, "--gui", "127.0.0.1:0", "--speed", "1")
    return Program(*args, session=True)


def test_ctrl_c_at_a_terminal_stops_the_demo_with_its_outcome() -> None:
    with _demo() as demo:
        demo.wait_for("phase 1: wandering about the lab")
        # A terminal's Ctrl-C: SIGINT to the whole process group (situate and the sequencer).
        os.killpg(demo.process.pid, signal.SIGINT)
        code, out, err = demo.finish()
    assert code == 130, out + err
    assert "demo: interrupted (SIGINT) at t = " in out, out
    # Said once, by the demo: not again by the sequencer, with its own time.
    assert out.count("interrupted (") == 1, out
    assert "in phase 1 (wandering about the lab" in out, out
    assert "message not delivered" in out
    assert "Traceback" not in out + err
    assert "KeyboardInterrupt" not in out + err


def test_sigterm_to_the_demo_stops_its_sequencer() -> None:
    with _demo() as demo:
        demo.wait_for("phase 1: wandering about the lab")
        demo.process.send_signal(signal.SIGTERM)  # to `situate` only: it tells the sequencer
        code, out, err = demo.finish()
    assert code == 143, out + err
    assert "demo: interrupted (SIGTERM) at t = " in out, out
    assert "in phase 1 (wandering" in out, out
    assert out.count("interrupted (") == 1, out
    assert "Traceback" not in out + err


def test_the_demo_is_reached_by_the_cli_where_it_says_with_listen_or_without() -> None:
    # --listen: where the CLI reaches the demo's robot.
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    args = ("demo", "--python", sys.executable, "--gui", "127.0.0.1:0", "--speed", "1")
    with Program(*args, "--listen", endpoint, session=True) as demo:
        demo.wait_for("phase 1: wandering about the lab")
        stats = situate("stats", "--connect", endpoint)
        assert stats.returncode == 0, stats.stderr
        assert stats.stdout.startswith("robot `deliverybot`: cycle ")
        os.killpg(demo.process.pid, signal.SIGINT)
        assert demo.finish()[0] == 130
    # Without it, the CLI's default endpoint; held by another, a free port, said at the start.
    held = socket.socket()
    # As servers do (Zenoh too): a connection of an earlier run in TIME_WAIT does not stop it.
    held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    # Held here, for sure: another test's demo may hold it a while (make test runs the GUI
    # tests beside these), and let it go before this demo starts.
    deadline = time.monotonic() + WAIT_S
    while True:
        try:
            held.bind(("127.0.0.1", 7447))
            held.listen()
            break
        except OSError:
            if time.monotonic() > deadline:
                pytest.fail("tcp/127.0.0.1:7447 stayed held by another process")
            time.sleep(0.2)
    try:
        with Program(*args, session=True) as demo:
            demo.wait_for("the link listens on")
            note = next(line for line in demo.err if "the link listens on" in line)
            found = re.search(r"`--connect (tcp/127\.0\.0\.1:\d+)`", note)
            assert found, note
            assert "tcp/127.0.0.1:7447 is taken" in note, note
            demo.wait_for("phase 1: wandering about the lab")
            stats = situate("stats", "--connect", found.group(1))
            assert stats.returncode == 0, stats.stderr
            os.killpg(demo.process.pid, signal.SIGINT)
            assert demo.finish()[0] == 130
    finally:
        held.close()
