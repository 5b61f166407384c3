"""A remote skill on another host: two network namespaces joined by a veth pair.

Host A (its own network namespace) runs the skill manager listening on its veth
address; host B runs `situate serve-skill`, reaching A over the veth link only.
The test checks, from host A, that B's results reach the cycle. The namespaces
are the test's own and are removed afterwards. It needs root (CAP_NET_ADMIN) and
iproute2; without them it is skipped with the reason.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import textwrap
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from support import EVENT_S, STARTUP_S, program_env, situate_program

ROBOT_FILE = """
    robot: nsbot
    cycle: {rate_hz: 50}
    devices:
      - {name: sonar, type: toy.sonar}
    skills:
      - name: nearest
        remote:
          inputs: {ranges: "f32[]"}
          outputs: {y: f64}
          params: {gain: 2.0}
        remap: {ranges: sonar.range}
"""

SKILLS = """
import situate

@situate.remote_skill(inputs={"ranges": "f32[]"}, outputs={"y": "f64"}, params={"gain": 2.0})
def nearest(ranges, gain):
    return {"y": min(ranges) * gain}
"""


def ip(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["ip", *args], capture_output=True, text=True, check=False)


@dataclass
class Hosts:
    a: str
    b: str
    a_addr: str
    b_addr: str


@pytest.fixture
def hosts() -> Iterator[Hosts]:
    """Two namespaces `a` and `b` joined by a veth pair on a /24 of their own."""
    if os.geteuid() != 0 or shutil.which("ip") is None:
        pytest.skip("needs root and iproute2 to make network namespaces")
    tag = f"{os.getpid() % 100000}"
    a, b = f"sit-a-{tag}", f"sit-b-{tag}"
    subnet = f"10.251.{os.getpid() % 250}"
    made = ip("netns", "add", a)
    if made.returncode != 0:
        pytest.skip(f"cannot make network namespaces here: {made.stderr.strip()}")
    try:
        steps = [
            ("netns", "add", b),
            ("link", "add", f"va{tag}", "type", "veth", "peer", "name", f"vb{tag}"),
            ("link", "set", f"va{tag}", "netns", a),
            ("link", "set", f"vb{tag}", "netns", b),
            ("-n", a, "addr", "add", f"{subnet}.1/24", "dev", f"va{tag}"),
            ("-n", b, "addr", "add", f"{subnet}.2/24", "dev", f"vb{tag}"),
            ("-n", a, "link", "set", f"va{tag}", "up"),
            ("-n", b, "link", "set", f"vb{tag}", "up"),
            ("-n", a, "link", "set", "lo", "up"),
            ("-n", b, "link", "set", "lo", "up"),
        ]
        for step in steps:
            done = ip(*step)
            assert done.returncode == 0, f"ip {' '.join(step)}: {done.stderr}"
        yield Hosts(a, b, f"{subnet}.1", f"{subnet}.2")
    finally:
        ip("netns", "del", a)
        ip("netns", "del", b)


def in_ns(ns: str, *cmd: str, cwd: Path | None = None) -> subprocess.Popen[str]:
    return subprocess.Popen(
        ["ip", "netns", "exec", ns, *cmd],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=program_env(),
        cwd=cwd,
    )


def stop(p: subprocess.Popen[str]) -> str:
    if p.poll() is None:
        p.send_signal(signal.SIGINT)
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()
    _, err = p.communicate()
    return err or ""


def query_in(ns: str, endpoint: str, signal_name: str) -> dict[str, object] | None:
    done = subprocess.run(
        [
            *("ip", "netns", "exec", ns, situate_program(), "query", signal_name, "--json"),
            *("--connect", endpoint, "--robot", "nsbot", "--timeout", "2"),
        ],
        capture_output=True,
        text=True,
        env=program_env(),
        check=False,
        timeout=60,
    )
    if done.returncode != 0:
        return None
    reading: dict[str, object] = json.loads(done.stdout)
    return reading


def test_a_remote_skill_on_another_host_joins_the_cycle(hosts: Hosts, tmp_path: Path) -> None:
    robot = tmp_path / "nsbot.yaml"
    robot.write_text(textwrap.dedent(ROBOT_FILE))
    (tmp_path / "ns_skills.py").write_text(textwrap.dedent(SKILLS))
    endpoint = f"tcp/{hosts.a_addr}:7447"
    manager = in_ns(hosts.a, situate_program(), "run", str(robot), "--listen", endpoint)
    server = None
    try:
        # Host B reaches A only over the veth pair; wait until A answers there.
        deadline = time.monotonic() + STARTUP_S
        while query_in(hosts.b, endpoint, "sonar.range") is None:
            assert manager.poll() is None, stop(manager)
            assert time.monotonic() < deadline, "the manager never answered from host B"
            time.sleep(0.1)
        server = in_ns(
            hosts.b,
            situate_program(),
            *("serve-skill", "ns_skills:nearest", "--robot", "nsbot", "--connect", endpoint),
            cwd=tmp_path,
        )
        deadline = time.monotonic() + EVENT_S * 3
        reading = None
        while reading is None or reading.get("value") is None:
            assert server.poll() is None, stop(server)
            assert time.monotonic() < deadline, f"no result from host B: {reading}"
            time.sleep(0.1)
            reading = query_in(hosts.a, endpoint, "y")
        assert reading["writer"] == "nearest"
        value = reading["value"]
        assert isinstance(value, float)
        assert value > 0
        # The manager listens on host A's veth address only: nothing on loopback.
        listeners = subprocess.run(
            ["ip", "netns", "exec", hosts.a, "ss", "-H", "-tuln"],
            capture_output=True,
            text=True,
            check=False,
        ).stdout
        assert f"{hosts.a_addr}:7447" in listeners, listeners
        assert "udp" not in listeners, listeners
    finally:
        if server is not None:
            stop(server)
        stop(manager)
