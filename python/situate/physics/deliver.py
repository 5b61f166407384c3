"""The whole delivery on the physics robot: `situate demo --physics`.

That is ``python -m situate.physics.deliver``, here. Three parts, as a robot in the field has
them:

- **the robot**: ``situate run demo/physics.yaml --stopped`` (the delivery robot's skills, its
  devices replaced by ROS 2 topics, in lock-step with ROS time), a program of its own;
- **the physics robot**: a `PhysicsNode` (MuJoCo, `situate.physics`) in this process, on a
  Zenoh session to the robot's link, ticking its ``/clock`` as fast as the two can go (or
  ``--time-scale`` times real time);
- **the sequencer**: the demo's own ``demo/deliver.py``, unchanged, a program of its own.

The outcome is the world's: the message is delivered when the speaker says it in the office.
With ``--json`` it is one JSON object on stdout (`Outcome`); else a line as ``situate demo``
prints. With ``--gui`` the robot and its GUI stay up when the mission is over, until Ctrl-C
(``--exit-when-done``: not), as ``situate demo``'s. The exit status is 0 when delivered, 1 when
not, 2 for bad arguments, 3 for a building that cannot be read.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from situate.physics.cli import add_world_args, world_settings

#: How long the robot may take to start listening, s.
STARTUP_S = 60.0
#: The robot's hello line: ``situate: robot `NAME` serving … on ENDPOINT``.
HELLO = re.compile(r"robot `([^`]+)` serving \S+ on (\S+)")
#: The sequencer's phase lines: ``[  12.3 s] phase 5: …``.
PHASE = re.compile(r"\]\s+phase (\d+): (.*)")


@dataclass
class Outcome:
    """What a run of the delivery came to."""

    map: str
    seed: int
    delivered: bool
    #: When the message was said in the office, else the simulated time the run ended at, s.
    mission_time_s: float
    wall_s: float
    #: Simulated seconds per second of wall time.
    speedup: float
    ticks: int
    #: Where the robot ended: ``(floor, x, y)``, its true pose.
    at: tuple[int, float, float]
    sequencer_exit: int | None
    #: The sequencer's last phase (``"5: pushing the call button"``).
    phase: str | None
    #: The sequencer's last lines, when it failed.
    tail: list[str] = field(default_factory=list)
    recording: str | None = None


def _data(name: str) -> Path:
    """A file of the demo: in the current directory (a checkout), else the package's data."""
    here = Path(name)
    if here.exists():
        return here
    from situate._cli import data_dir

    packaged = data_dir()
    if packaged is not None and (packaged / name).exists():
        return packaged / name
    return here


def _free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


class _Robot:
    """``situate run ROBOT_FILE --stopped`` on a free port, its stderr kept."""

    def __init__(self, robot_file: Path, extra: Sequence[str], program: Sequence[str]) -> None:
        self.lines: list[str] = []
        self._heard = threading.Event()
        self.name = ""
        self.endpoint = ""
        for _attempt in range(5):
            endpoint = _free_endpoint()
            run = ["run", str(robot_file), "--stopped", "--listen", endpoint, *extra]
            self.process = subprocess.Popen(
                [*program, *run],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.PIPE,
                text=True,
            )
            self._reader = threading.Thread(target=self._read, daemon=True)
            self._reader.start()
            deadline = time.monotonic() + STARTUP_S
            while not self._heard.wait(0.05):
                if self.process.poll() is not None or time.monotonic() > deadline:
                    break
            if self._heard.is_set():
                return
            self.stop()
            if not any("Address already in use" in line for line in self.lines):
                break
        raise RuntimeError("the robot did not start:\n" + "".join(self.lines[-20:]))

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.lines.append(line)
            m = HELLO.search(line)
            if m and not self._heard.is_set():
                self.name, self.endpoint = m.group(1), m.group(2)
                self._heard.set()

    def stop(self) -> None:
        """Stops it as Ctrl-C does (a recording is closed), killing it if it hangs."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._reader.join(timeout=5)


def _sequence(command: list[str], node: Any) -> tuple[str, int | None]:
    """Runs the sequencer to its end; stopped if the physics robot's clock stops first.

    Its output, and its exit status.
    """
    lines: list[str] = []
    with subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    ) as sequencer:
        assert sequencer.stdout is not None
        reader = threading.Thread(target=lambda: lines.extend(sequencer.stdout or []), daemon=True)
        reader.start()
        while sequencer.poll() is None:
            if not node.running:
                # The world's clock died (an error in a tick): nothing will move again.
                lines.append("situate.physics.deliver: the physics robot's clock stopped\n")
                sequencer.terminate()
                break
            time.sleep(0.05)
        status = sequencer.wait()
        reader.join(timeout=5)
    return "".join(lines), status


@contextlib.contextmanager
def _session(endpoint: str) -> Iterator[Any]:
    import zenoh

    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    config.insert_json5("scouting/multicast/enabled", "false")
    with zenoh.open(config) as session:
        yield session


def deliver(
    map_file: Path,
    seed: int,
    *,
    robot_file: Path,
    sequencer: Path,
    time_scale: float = float("inf"),
    limit_s: float = 1800.0,
    record: Path | None = None,
    gui: str | None = None,
    quiet: bool = True,
    program: Sequence[str] | None = None,
    world_settings: dict[str, Any] | None = None,
    linger: Callable[[Outcome], None] | None = None,
) -> Outcome:
    """Runs the delivery once on the physics robot in `map_file`'s building; its outcome.

    `program` runs the robot (default: this package's ``situate``, ``python -m situate``);
    `world_settings` are `PhysicsWorld`'s (people, door closures, dead sonars). `linger`, when
    given, is called with the outcome before the robot is stopped (its GUI still up).
    """
    from situate.physics.building import Building
    from situate.physics.node import PhysicsNode
    from situate.physics.world import PhysicsWorld
    from situate.ros2 import Ros2Peer

    building = Building.load(map_file)
    world = PhysicsWorld(building, seed=seed, **(world_settings or {}))
    extra = ["--record", str(record)] if record is not None else []
    extra += ["--gui", gui, "--map", str(map_file)] if gui is not None else ["--no-gui"]
    started = time.monotonic()
    robot = _Robot(robot_file, extra, program or [sys.executable, "-m", "situate"])
    out = ""
    status: int | None = None
    ticks = 0

    def outcome() -> Outcome:
        wall = time.monotonic() - started
        phases = PHASE.findall(out)
        delivered = world.delivered_at is not None
        pose = world.pose()
        return Outcome(
            map=str(map_file),
            seed=seed,
            delivered=delivered,
            mission_time_s=world.delivered_at if world.delivered_at is not None else world.time,
            wall_s=wall,
            speedup=world.time / wall if wall > 0 else 0.0,
            ticks=ticks,
            at=(pose.floor, round(pose.x, 3), round(pose.y, 3)),
            sequencer_exit=status,
            phase=f"{phases[-1][0]}: {phases[-1][1]}" if phases else None,
            tail=[] if delivered else out.splitlines()[-8:] + robot.lines[-5:],
            recording=str(record) if record is not None else None,
        )

    try:
        with _session(robot.endpoint) as session:
            peer = Ros2Peer(session, node="physics")
            node = PhysicsNode(world, peer, lockstep=f"/{robot.name}/cycle")
            node.start(time_scale)
            try:
                command = [sys.executable, str(sequencer), "--connect", robot.endpoint]
                command += ["--robot", robot.name, "--mission", json.dumps(building.mission)]
                command += ["--seed", str(seed), "--limit-s", str(limit_s)]
                out, status = _sequence(command, node)
                if not quiet:
                    sys.stdout.write(out)
            finally:
                node.close()
                ticks = node.ticks
                peer.close()
        if linger is not None:
            linger(outcome())
    finally:
        robot.stop()
    return outcome()


def _until_interrupted(gui: str) -> Callable[[Outcome], None]:
    """Keeps the robot (and its GUI on `gui`) up after the mission until SIGINT or SIGTERM."""

    def linger(outcome: Outcome) -> None:
        done = threading.Event()
        previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
        for sig in previous:
            signal.signal(sig, lambda *_: done.set())
        try:
            said = "delivered" if outcome.delivered else "NOT delivered"
            print(
                f"demo --physics: the mission is over ({said}); the GUI stays on http://{gui} "
                "until Ctrl-C (--exit-when-done: exit at once)",
                file=sys.stderr,
                flush=True,
            )
            while not done.wait(0.2):
                pass
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    return linger


def main(argv: Sequence[str] | None = None) -> int:
    """The command line; the exit status."""
    p = argparse.ArgumentParser(prog="python -m situate.physics.deliver", description=__doc__)
    p.add_argument("--map", type=Path, help="the building (default: maps/default.yaml)")
    p.add_argument("--seed", type=int, default=1, help="the world's and the sequencer's seed")
    p.add_argument("--robot", type=Path, help="the robot file (default: demo/physics.yaml)")
    p.add_argument("--sequencer", type=Path, help="the sequencer (default: demo/deliver.py)")
    p.add_argument(
        "--time-scale",
        type=float,
        default=None,
        help="simulated seconds per real second (default: as fast as it goes; 4 with --gui)",
    )
    p.add_argument("--limit-s", type=float, default=1800.0, help="give up after this (simulated)")
    p.add_argument("--record", type=Path, help="record the robot's run to this MCAP file")
    p.add_argument("--gui", metavar="ADDR", help="serve the GUI here (e.g. 127.0.0.1:8080)")
    p.add_argument("--json", action="store_true", help="the outcome as one JSON object")
    p.add_argument(
        "--exit-when-done",
        action="store_true",
        help="with --gui: exit when the mission is over (default: the GUI stays up until Ctrl-C)",
    )
    add_world_args(p)
    p.add_argument(
        "--program",
        help="the situate program that runs the robot (default: this package's, "
        "python -m situate; `situate demo --physics` passes itself)",
    )
    a = p.parse_args(argv)
    map_file = a.map or _data("maps/default.yaml")
    time_scale = a.time_scale if a.time_scale is not None else (4.0 if a.gui else float("inf"))
    if not time_scale > 0:
        p.error(f"--time-scale {time_scale}: expected > 0")
    try:
        outcome = deliver(
            map_file,
            a.seed,
            robot_file=a.robot or _data("demo/physics.yaml"),
            sequencer=a.sequencer or _data("demo/deliver.py"),
            time_scale=time_scale,
            limit_s=a.limit_s,
            record=a.record,
            gui=a.gui,
            quiet=a.json,
            program=[a.program] if a.program else None,
            world_settings=world_settings(a),
            linger=_until_interrupted(a.gui) if a.gui and not a.exit_when_done else None,
        )
    except ValueError as e:  # the map file: its loader's message names the file and line
        print(f"python -m situate.physics.deliver: {e}", file=sys.stderr)
        return 3
    if a.json:
        print(json.dumps(asdict(outcome)))
    else:
        said = (
            f"message delivered at t = {outcome.mission_time_s:.1f} s"
            if outcome.delivered
            else f"NOT delivered after {outcome.mission_time_s:.1f} s"
        )
        print(f"demo --physics: {said} (seed {outcome.seed})")
        print(
            f"demo --physics: {outcome.ticks} ticks, {outcome.wall_s:.1f} s wall "
            f"({outcome.speedup:.0f}x real time)"
        )
    return 0 if outcome.delivered else 1


if __name__ == "__main__":
    sys.exit(main())
