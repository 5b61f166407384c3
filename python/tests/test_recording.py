"""`situate demo --record FILE` read back with the `mcap` package (the MCAP reference reader).

The demo robot's run on the default building: one channel per signal leaf and per kind of
event, JSON messages under JSON Schemas, each message's cycle and the manager's clock as its
log time, and an index a reader can seek by time with. No timing assertions.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any, Callable

import pytest
from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer
from test_demo import BIN, ROOT, needs_bin, situate_bin  # noqa: F401 (the fixture)


def _record(path: Path) -> dict[str, Any]:
    assert BIN is not None
    cmd = [str(BIN), "demo", "--headless", "--json", "--seed", "1", "--python", sys.executable]
    cmd += ["--record", str(path)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    assert lines, f"no outcome from `situate demo`:\n{done.stdout}\n{done.stderr[-3000:]}"
    outcome: dict[str, Any] = json.loads(lines[-1])
    return outcome


@needs_bin
def test_a_recorded_delivery_reads_back_with_the_mcap_reader(tmp_path: Path) -> None:
    path = tmp_path / "delivery.mcap"
    out = _record(path)
    assert out["delivered"], out
    rec = out["recording"]
    assert rec["path"] == str(path), rec
    assert rec["bytes"] == path.stat().st_size > 0, rec
    assert rec["cycles"] == out["cycles"], rec
    assert rec["dropped_cycles"] == 0, rec
    assert (rec["first_cycle"], rec["last_cycle"]) == (1, out["cycles"]), rec

    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None
        assert summary.statistics is not None
        assert summary.statistics.message_count == rec["messages"]
        assert len(summary.channels) == rec["channels"]
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        period_s = float(meta["situate"]["period_s"])
        # Message times are Unix time: the run's start plus the manager's clock.
        origin_ns = int(meta["situate"]["time_origin_unix_ns"])
        assert 1.7e18 < origin_ns < 4.1e18, origin_ns
        assert meta["situate"]["robot"] == "deliverybot"

        per_topic: dict[str, list[tuple[int, dict[str, Any]]]] = defaultdict(list)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert channel.message_encoding == "json"
            assert schema is not None
            assert schema.encoding == "jsonschema"
            assert json.loads(schema.data)["type"] == "object"
            per_topic[channel.topic].append((message.log_time, json.loads(message.data)))

    topics = set(per_topic)
    # Signals the delivery writes, the simulator's ground truth, events, prints, winners.
    for topic in ["sonar.range", "odom.x", "drive.v", "truth.pose.x", "speaker.say"]:
        assert topic in topics, sorted(topics)
    for topic in ["situate/events/activation_applied", "situate/prints", "situate/winners"]:
        assert topic in topics, sorted(topics)
    # Every message carries its cycle; its log time is the run's start plus the manager's
    # (simulated) clock at it.
    for topic, messages in per_topic.items():
        for log_time, data in messages:
            assert 1 <= data["cycle"] <= out["cycles"], (topic, data)
            clock_ns = log_time - origin_ns
            assert clock_ns == pytest.approx(data["cycle"] * period_s * 1e9, abs=1e3), (topic, data)
    # The sonar ring, read every cycle but the first (readings arrive for the next cycle).
    ranges = per_topic["sonar.range"]
    assert len(ranges) >= out["cycles"] - 1
    assert all(isinstance(r, (int, float, str)) for _, d in ranges[:50] for r in d["value"])
    # The base changed hands as the sequencer switched skills; the activations are there.
    assert len(per_topic["situate/winners"]) > 2
    assert len(per_topic["situate/events/activation_applied"]) > 5
    said = [d["value"] for _, d in per_topic["speaker.say"]]
    assert any(said), said
    # The file ends on the outcome: the robot's own ground truth says the message was delivered
    # (it reports the world one cycle after the speaker's word; the run ends when it has).
    delivered = per_topic["truth.mission.delivered"]
    assert delivered[-1][1]["value"] is True, delivered[-3:]


@needs_bin
def test_a_recording_can_be_read_from_any_time_through_its_index(tmp_path: Path) -> None:
    path = tmp_path / "delivery.mcap"
    out = _record(path)
    middle = int(out["mission_time_s"] / 2 * 1e9)
    with path.open("rb") as f:
        reader = make_reader(f)
        messages = reader.iter_messages(topics=["odom.x"], starting_at=middle)
        late = [m.log_time for _, _, m in messages]
    assert late, middle
    assert min(late) >= middle, (middle, late[:3])
    assert sorted(late) == late, "read in time order"


def _replay(path: Path, *extra: str) -> tuple[int, dict[str, Any]]:
    assert BIN is not None
    cmd = [str(BIN), "replay", str(path), "--json", *extra]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    assert lines, f"no outcome from `situate replay`:\n{done.stdout}\n{done.stderr[-3000:]}"
    result: dict[str, Any] = json.loads(lines[-1])
    return done.returncode, result


def _fingerprints(path: Path) -> list[tuple[int, str]]:
    with path.open("rb") as f:
        reader = make_reader(f)
        return [
            (json.loads(m.data)["cycle"], json.loads(m.data)["hash"])
            for _, _, m in reader.iter_messages(topics=["situate/cycles"])
        ]


@needs_bin
def test_a_recorded_delivery_replays_identically_and_a_changed_skill_names_where_it_differs(
    tmp_path: Path,
) -> None:
    # The delivery, driven by the Python sequencer over the link: its activations and
    # parameter changes are in the recording, applied again at their cycles.
    path = tmp_path / "delivery.mcap"
    out = _record(path)
    assert out["delivered"], out
    code, result = _replay(path)
    assert code == 0, result
    assert result["identical"] is True, result
    assert result["cycles"] == result["matched"] == out["cycles"], result
    assert "follow_hallway" in result["live"], result
    assert "base" in result["played"], result

    # A skill changed (here through a parameter): the replay names the first cycle and the
    # leaf where it starts, and exits 1.
    code, changed = _replay(path, "--set", "follow_hallway.max_turn=0.3")
    assert code == 1, changed
    first = changed["first_difference"]
    assert first is not None, changed
    assert changed["identical"] is False, changed
    assert first["signal"].startswith("drive."), first
    assert first["what"] == "value", first
    assert changed["matched"] < changed["cycles"], changed

    # Played from the recording, the changed skill does not matter.
    code, played = _replay(path, "--set", "follow_hallway.max_turn=0.3", "--live", "sonar_filter")
    assert (code, played["identical"]) == (0, True), played


@needs_bin
def test_two_recordings_of_one_robot_and_seed_are_the_same_every_cycle(tmp_path: Path) -> None:
    assert BIN is not None
    paths = [tmp_path / "a.mcap", tmp_path / "b.mcap"]
    for p in paths:
        cmd = [str(BIN), "run", "examples/toybot.yaml", "--clock", "simulated", "--cycles", "400"]
        cmd += ["--no-link", "--record", str(p)]
        done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
    a, b = (_fingerprints(p) for p in paths)
    assert [c for c, _ in a] == list(range(1, 401))
    assert a == b
    assert len({h for _, h in a}) > 300, "the fingerprints follow the run"
    code, result = _replay(paths[0])
    assert (code, result["identical"], result["matched"]) == (0, True, 400), result


@needs_bin
def test_a_recording_keeps_the_mcap_format_rules_foxglove_reads_by(tmp_path: Path) -> None:
    # What `mcap doctor` checks, as far as the reference reader shows it (the `mcap` CLI could
    # not be installed here): CRCs, a summary whose statistics and chunk indexes agree with the
    # messages, every channel's schema present, and JSON messages under JSON Schema, the
    # encodings Foxglove reads without a plug-in.
    assert BIN is not None
    path = tmp_path / "toy.mcap"
    cmd = [str(BIN), "run", "examples/toybot.yaml", "--clock", "simulated", "--cycles", "300"]
    cmd += ["--no-link", "--record", str(path)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    with path.open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        assert reader.get_header().profile == ""
        summary = reader.get_summary()
        assert summary is not None
        stats = summary.statistics
        assert stats is not None
        counts: dict[int, int] = defaultdict(int)
        times: list[int] = []
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            assert schema is not None
            assert schema.id == channel.schema_id
            counts[channel.id] += 1
            times.append(message.log_time)
            json.loads(message.data)
        assert dict(counts) == dict(stats.channel_message_counts)
        assert sum(counts.values()) == stats.message_count
        assert (stats.message_start_time, stats.message_end_time) == (min(times), max(times))
        assert stats.channel_count == len(summary.channels)
        assert stats.schema_count == len(summary.schemas)
        assert summary.chunk_indexes, "chunked and indexed"
        assert stats.chunk_count == len(summary.chunk_indexes)
        for chunk in summary.chunk_indexes:
            assert chunk.compression in ("zstd", "")
            assert chunk.message_start_time <= chunk.message_end_time
        for channel in summary.channels.values():
            assert channel.topic, channel
            assert channel.message_encoding == "json"
            assert channel.schema_id in summary.schemas
            schema = summary.schemas[channel.schema_id]
            assert schema.encoding == "jsonschema"
            assert json.loads(schema.data)["type"] == "object"
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        assert list(metadata) == ["situate", "situate_drops"]
        # On the simulated clock no cycle is ever dropped: the cycle waits for the writer.
        assert metadata["situate_drops"] == {"dropped_cycles": "0", "ranges": "[]"}


def _record_toy(path: Path, cycles: int = 300) -> None:
    assert BIN is not None
    cmd = [str(BIN), "run", "examples/toybot.yaml", "--clock", "simulated", "--cycles", str(cycles)]
    cmd += ["--no-link", "--no-gui", "--record", str(path)]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]


def _rewrite(
    src: Path,
    dst: Path,
    metadata: Callable[[str, dict[str, str]], None] = lambda name, m: None,
    keep: Callable[[str, dict[str, Any]], bool] = lambda topic, data: True,
    change: Callable[[str, dict[str, Any]], None] = lambda topic, data: None,
    extra: list[tuple[str, int, dict[str, Any]]] | None = None,
    extra_metadata: dict[str, dict[str, str]] | None = None,
) -> None:
    """Writes the recording `src` again as a valid MCAP file (chunk CRCs, summary), its metadata
    and messages changed: the messages `keep` refuses left out, the others changed by `change`;
    `extra` messages (topic, log time, data) and metadata records added."""
    with src.open("rb") as f, dst.open("wb") as out:
        reader = make_reader(f)
        writer = Writer(out, compression=CompressionType.ZSTD)
        writer.start()
        for record in reader.iter_metadata():
            data = dict(record.metadata)
            metadata(record.name, data)
            writer.add_metadata(record.name, data)
        for name, data in (extra_metadata or {}).items():
            writer.add_metadata(name, data)
        channels: dict[str, int] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.topic not in channels:
                assert schema is not None
                schema_id = writer.register_schema(schema.name, schema.encoding, schema.data)
                channels[channel.topic] = writer.register_channel(
                    channel.topic, channel.message_encoding, schema_id, dict(channel.metadata)
                )
            data = json.loads(message.data)
            if not keep(channel.topic, data):
                continue
            change(channel.topic, data)
            writer.add_message(
                channels[channel.topic],
                message.log_time,
                json.dumps(data).encode(),
                message.publish_time,
                message.sequence,
            )
        for topic, log_time, data in extra or []:
            if topic not in channels:
                schema_id = writer.register_schema(
                    "situate.gap", "jsonschema", b'{"type": "object"}'
                )
                channels[topic] = writer.register_channel(topic, "json", schema_id)
            writer.add_message(channels[topic], log_time, json.dumps(data).encode(), log_time)
        writer.finish()  # type: ignore[no-untyped-call]


def _refused(path: Path) -> str:
    """`situate replay FILE` refuses it as a bad file (exit 3), in bounded time; the message."""
    code, result = _replay(path)
    assert code == 3, result
    error = result["error"]
    assert error["kind"] == "bad_file", error
    message: str = error["message"]
    assert message.startswith(str(path)), message
    return message


@needs_bin
def test_a_damaged_or_doctored_recording_is_refused_naming_what_and_where(tmp_path: Path) -> None:
    src = tmp_path / "toy.mcap"
    _record_toy(src)
    bad = tmp_path / "bad.mcap"

    # The last cycle renumbered 10^15: refused, not replayed for ever.
    def renumber(topic: str, data: dict[str, Any]) -> None:
        if topic != "situate/winners" and data.get("cycle") == 300:
            data["cycle"] = 10**15

    _rewrite(src, bad, change=renumber)
    assert "cycle 1000000000000000 follows cycle 299" in _refused(bad)

    # A period that is not a number: refused, not a panic.
    def nan_period(name: str, m: dict[str, str]) -> None:
        if name == "situate":
            m["period_s"] = "nan"

    _rewrite(src, bad, metadata=nan_period)
    message = _refused(bad)
    assert "`period_s`" in message, message
    assert "`nan`" in message, message

    # Parameter sets that are not JSON: refused, not ignored.
    def bad_sets(name: str, m: dict[str, str]) -> None:
        if name == "situate":
            m["sets"] = "wander.speed=0.3"

    _rewrite(src, bad, metadata=bad_sets)
    message = _refused(bad)
    assert "`sets`" in message, message
    assert "not a JSON list" in message, message

    # A chunk's header zeroed: refused where it is, not skipped.
    raw = bytearray(src.read_bytes())
    with src.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    assert summary.chunk_indexes
    at = summary.chunk_indexes[0].chunk_start_offset
    raw[at + 9 : at + 9 + 40] = bytes(40)
    bad.write_bytes(bytes(raw))
    message = _refused(bad)
    assert f"at byte {at} (chunk)" in message, message
    assert "damaged chunk header" in message, message

    # A device that never ends: refused before it is read.
    assert "not a regular file" in _refused(Path("/dev/zero"))


@needs_bin
def test_a_recording_that_lacks_cycles_replays_as_not_identical_naming_them(
    tmp_path: Path,
) -> None:
    # As a wall-clock recording whose writer fell behind: cycles 101-150 dropped, marked by a
    # gap marker and the record at the end.
    src = tmp_path / "toy.mcap"
    _record_toy(src)
    lacking = tmp_path / "lacking.mcap"

    def keep(topic: str, data: dict[str, Any]) -> bool:
        # Those cycles' frames are lost; events go their own way and stay.
        return topic.startswith("situate/events/") or not 101 <= data.get("cycle", 0) <= 150

    def drops(name: str, m: dict[str, str]) -> None:
        if name == "situate_drops":
            m.update({"dropped_cycles": "50", "ranges": "[[101,150]]"})

    gap = ("situate/gaps", 5_050_000_000, {"cycle": 101, "last": 150, "count": 50})
    _rewrite(src, lacking, metadata=drops, keep=keep, extra=[gap])
    code, result = _replay(lacking)
    assert code == 1, result
    assert result["identical"] is False, result
    assert result["dropped_cycles"] == 50, result
    assert result["dropped_ranges"] == [[101, 150]], result
    assert result["stopped_before"] == 101, result
    assert result["cycles"] == result["matched"] == 100, result
    assert result["first_difference"] is None, result
    # In words too.
    assert BIN is not None
    done = subprocess.run(
        [str(BIN), "replay", str(lacking)], cwd=ROOT, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 1, done.stdout + done.stderr
    assert "not identical" in done.stdout, done.stdout
    assert "cycles 101-150" in done.stdout, done.stdout
    assert "identical: every cycle" not in done.stdout, done.stdout

    # Without the marks, the missing cycles are a damaged file, not a replay that "matches".
    unmarked = tmp_path / "unmarked.mcap"
    _rewrite(src, unmarked, keep=keep)
    assert "neither in the file nor marked as dropped" in _refused(unmarked)


def test_the_reader_is_the_reference_one() -> None:
    # The `mcap` package comes from scripts/python.sh; say so if it is missing.
    import mcap

    assert Path(mcap.__file__).exists()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(subprocess.call([sys.executable, "-m", "pytest", __file__]))
