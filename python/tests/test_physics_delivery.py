"""The paper's experiment in real physics: the whole delivery on the MuJoCo robot, through ROS 2.

The robot is `demo/physics.yaml` (the delivery robot's skills, its devices replaced by ROS 2
topics) run by `situate run --stopped`; the world is the physics robot (`situate.physics`:
MuJoCo, the default building, elevator cars on slide joints) on a real Zenoh session, in
lock-step with the robot's cycle; the sequencer is the demo's own `demo/deliver.py`, unchanged.
Nothing of the 2-D simulator runs but its elevator logic, which drives the MuJoCo cars.
`situate.physics.deliver` puts the three together, as `situate demo --physics` does.

Run twice with the same seed, the delivery is the same, cycle for cycle: the two recordings
hold the same messages on every channel (every signal, event and print of every cycle).
"""

from __future__ import annotations

import hashlib
import json
import signal
import subprocess
import sys
import threading
import urllib.request
from pathlib import Path

from support import REPO, free_port, program_env

from situate.physics.building import Building
from situate.physics.deliver import deliver


def _digest(path: Path) -> tuple[int, dict[str, str]]:
    """How many messages a recording holds, and per channel a hash of its messages in order.

    Channel by channel: the file interleaves the cycle's values and the manager's events as its
    writer's threads get to them.
    """
    from mcap.reader import make_reader

    hashes: dict[str, hashlib._Hash] = {}
    n = 0
    with path.open("rb") as f:
        for _schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            h = hashes.setdefault(channel.topic, hashlib.sha256())
            h.update(json.dumps(json.loads(message.data), sort_keys=True).encode())
            n += 1
    return n, {topic: h.hexdigest() for topic, h in hashes.items()}


def test_the_physics_robot_delivers_the_message_the_same_way_twice(tmp_path: Path) -> None:
    building = Building.load(REPO / "maps" / "default.yaml")
    runs = []
    for k in (1, 2):
        record = tmp_path / f"run{k}.mcap"
        outcome = deliver(
            REPO / "maps" / "default.yaml",
            5,
            robot_file=REPO / "demo" / "physics.yaml",
            sequencer=REPO / "demo" / "deliver.py",
            record=record,
        )
        assert outcome.delivered, outcome
        assert outcome.sequencer_exit == 0, outcome
        assert outcome.phase == "13: delivering the message", outcome
        runs.append((outcome, _digest(record)))
    (first, a), (second, b) = runs
    # Delivered on floor 4, in the office, well within the mission's time.
    assert building.mission["goal_floor"] == 4
    assert first.at[0] == 4, first
    assert building.in_office(*first.at), first
    assert 100 < first.mission_time_s < 1200, first
    assert first.ticks > 1000
    # The same run twice: the same mission time, ticks and recording, message for message.
    assert (second.mission_time_s, second.ticks) == (first.mission_time_s, first.ticks)
    assert a[0] > 10_000
    assert a == b


def test_with_a_gui_the_robot_stays_up_after_the_mission_until_ctrl_c() -> None:
    port = free_port()
    cmd = [sys.executable, "-m", "situate.physics.deliver", "--map", "maps/default.yaml"]
    cmd += ["--gui", f"127.0.0.1:{port}", "--limit-s", "3", "--time-scale", "1000"]
    cmd += ["--people", "1", "--door-closures"]
    with subprocess.Popen(
        cmd,
        cwd=REPO,
        env=program_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    ) as p:
        assert p.stderr is not None
        lines: list[str] = []
        lingering = threading.Event()

        def read() -> None:
            for line in p.stderr or []:
                lines.append(line)
                if "the GUI stays on" in line:
                    lingering.set()

        threading.Thread(target=read, daemon=True).start()
        assert lingering.wait(180), "".join(lines)
        assert "the mission is over (NOT delivered)" in lines[-1], "".join(lines)
        assert p.poll() is None, "it exited after the mission"
        # The GUI still answers, and shows the building it was given.
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=30) as page:
            assert page.status == 200
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=120)
    assert p.returncode == 1, out
    assert "NOT delivered" in out
