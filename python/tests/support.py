"""Helpers: real `situate run` managers on free ports, and the installed `situate` program.

Every test that needs a manager starts its own (`situate run ... --listen
tcp/127.0.0.1:<free port>`, the console script of the installed wheel) and
stops it afterwards, so tests never share state and never touch 7447.
Readiness is a bounded poll of the protocol's `hello`, never a sleep.
"""

from __future__ import annotations

import asyncio
import fcntl
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import pytest
import zenoh

from situate import _link
from situate.errors import SituateError

#: The `files` fixture (conftest.py): writes a dedented file into the test's directory.
Write = Callable[[str, str], Path]

REPO = Path(__file__).resolve().parents[2]
TOYBOT = REPO / "examples" / "toybot.yaml"
T = TypeVar("T")

#: Generous bounds for things that normally take milliseconds (CI machines are slow and shared).
STARTUP_S = 60.0
EVENT_S = 20.0


def run(coro: Awaitable[T]) -> T:
    """Runs a coroutine to completion (tests use plain asyncio, no plugin)."""

    async def main() -> T:
        return await coro

    return asyncio.run(main())


def situate_program() -> str:
    """The `situate` console script installed next to this interpreter."""
    here = Path(sys.executable).parent / "situate"
    if here.exists():
        return str(here)
    pytest.fail("the `situate` console script is not installed: run scripts/python.sh first")


def _ephemeral_start() -> int:
    """Where the kernel's range of ports for outgoing connections starts (Linux; else 32768)."""
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768


def free_port() -> int:
    """A TCP port nobody listens on right now, below the range of outgoing connections' ports.

    A port the kernel picks (`bind(0)`) comes from that range, and once closed it may be given to
    any outgoing connection (a Zenoh client of another test) before the program under test binds
    it: "Address already in use". Picked at random below the range, only another test picking
    the same port can take it first; `start_manager` tries another port then.
    """
    low, high = 20000, max(_ephemeral_start() - 1, 20001)
    for _ in range(100):
        port = random.randint(low, high)
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        fallback: int = s.getsockname()[1]
        return fallback


def zenoh_client(endpoint: str) -> zenoh.Session:
    """A plain Zenoh client session on `endpoint` (no scouting), as a ROS 2 node's would be."""
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    return zenoh.open(conf)


def program_env() -> dict[str, str]:
    env = dict(os.environ)
    env.pop("SITUATE_CONNECT", None)
    env.setdefault("RUST_LOG", "warn,zenoh=error")
    return env


def situate(
    *args: str, timeout: float = 60.0, cwd: Path | None = None
) -> subprocess.CompletedProcess[str]:
    """Runs the installed `situate` program and returns its result (never raises on exit code)."""
    return subprocess.run(
        [situate_program(), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=program_env(),
        cwd=cwd or REPO,
        check=False,
    )


@dataclass
class Manager:
    """A running `situate run` process serving one robot on its own endpoint."""

    process: subprocess.Popen[str]
    robot: str
    endpoint: str

    @property
    def connect_args(self) -> list[str]:
        """The CLI arguments that reach this manager."""
        return ["--connect", self.endpoint, "--robot", self.robot]

    def stop(self) -> str:
        """Stops the process (Ctrl-C, then kill) and returns what it wrote to stderr."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=20)
        _, err = self.process.communicate()
        return err or ""


#: Ports `start_manager` tries before it gives up.
PORT_TRIES = 5


class PortTaken(Exception):
    """The program could not listen on its port: something took it after free_port() chose it."""


def wait_for_hello(process: subprocess.Popen[str], endpoint: str, robot: str) -> None:
    """Polls `hello` until the manager answers (bounded), failing early if it exited."""
    deadline = time.monotonic() + STARTUP_S
    last: Exception | None = None
    while time.monotonic() < deadline:
        if process.poll() is not None:
            _, err = process.communicate()
            if "Address already in use" in err:
                raise PortTaken(err)
            pytest.fail(f"`situate run` exited with {process.returncode}:\n{err}")
        try:
            session = _link.open_session([endpoint])
        except SituateError as e:  # not listening yet
            last = e
            time.sleep(0.05)
            continue
        try:
            _link.hello(session, robot, timeout=2.0, endpoints=[endpoint])
            return
        except SituateError as e:
            last = e
        finally:
            _link.close_session(session)
    pytest.fail(f"the manager did not answer `hello` within {STARTUP_S} s: {last}")


def start_manager(
    robot_file: Path, robot: str, *extra: str, env: dict[str, str] | None = None
) -> Manager:
    """Starts `situate run ROBOT_FILE` on a free port and waits until it answers.

    ``env``: variables set for the program besides the test's own.
    """
    for attempt in range(PORT_TRIES):
        endpoint = f"tcp/127.0.0.1:{free_port()}"
        process = subprocess.Popen(
            [situate_program(), "run", str(robot_file), "--listen", endpoint, *extra],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env={**program_env(), **(env or {})},
            cwd=REPO,
        )
        try:
            wait_for_hello(process, endpoint, robot)
        except PortTaken:
            # Taken between free_port() and the program's bind (another test's): another port.
            if attempt + 1 < PORT_TRIES:
                continue
            raise
        except BaseException:
            process.kill()
            process.communicate()
            raise
        return Manager(process, robot, endpoint)
    raise AssertionError("unreachable")


def situate_gen() -> Path:
    """The generator CMake runs: built by `cargo test --workspace`, else built now."""
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        exe = target / profile / "situate-gen"
        if exe.is_file():
            return exe
    subprocess.run(
        ["cargo", "build", "-q", "--workspace", "--bin", "situate-gen"], cwd=REPO, check=True
    )
    return target / "debug" / "situate-gen"


def build_library(lang: str) -> None:
    """Builds examples/<lang>/runaway with the CMake package, where robot.yaml expects it."""
    if shutil.which("cmake") is None:
        pytest.fail("cmake is needed to build the C and C++ examples")
    build = REPO / "build" / f"{lang}_runaway"
    build.parent.mkdir(exist_ok=True)
    # Tests run in parallel processes (pytest -n): one build of a directory at a time.
    with open(REPO / "build" / f".{lang}_runaway.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        _build_library(lang, build)


def _build_library(lang: str, build: Path) -> None:
    configure = [
        "cmake",
        "-S",
        str(REPO / "examples" / lang / "runaway"),
        "-B",
        str(build),
        f"-DCMAKE_PREFIX_PATH={REPO / 'cmake'}",
        f"-DSITUATE_GEN={situate_gen()}",
    ]
    subprocess.run(configure, check=True, capture_output=True)
    subprocess.run(["cmake", "--build", str(build)], check=True, capture_output=True)
