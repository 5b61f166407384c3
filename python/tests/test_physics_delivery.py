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
from pathlib import Path

from support import REPO

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
