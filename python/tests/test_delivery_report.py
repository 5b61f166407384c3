"""The delivery benchmark's report (scripts/delivery_report.py: the coverage table, the failures)
and how scripts/delivery.py runs its cases (no robot is run)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]


def _delivery() -> ModuleType:
    """scripts/delivery.py as a module (it imports scripts/delivery_report.py beside it)."""
    if str(ROOT / "scripts") not in sys.path:
        sys.path.insert(0, str(ROOT / "scripts"))
    spec = importlib.util.spec_from_file_location("delivery", ROOT / "scripts" / "delivery.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["delivery"] = module
    spec.loader.exec_module(module)
    return module


def _report() -> ModuleType:
    """scripts/delivery_report.py: what the benchmark writes of its runs."""
    _delivery()
    return importlib.import_module("delivery_report")


def test_the_coverage_table_counts_runs_by_feature_and_never_drops_a_set_silently() -> None:
    d = _report()
    features = {"lobby": "corner", "car_walls": ["across"], "open_s_bucket": "short"}
    ok = d.Case("no-route", 30000, Path("m.yaml"), 30000, features=features)
    ok.outcome = {"delivered": True}
    failed = d.Case("no-route", 30001, Path("n.yaml"), 30001, features=features)
    failed.outcome = {"delivered": False}
    lines = d.coverage_section({"no-route": [ok, failed]})
    assert lines[0] == "## Coverage by feature of the building"
    assert any("| no-route |" in line for line in lines), lines
    assert any("1/2 (50 %)" in line for line in lines), lines
    # A generated set whose features were not read (the report once left the table out).
    unread = d.Case("generated", 30000, Path("m.yaml"), 30000)
    unread.outcome = {"delivered": True}
    lines = d.coverage_section({"generated": [unread]})
    assert "Not counted: the features of generated were not read." in lines, lines
    # The default building has no features: no table, and nothing to say.
    assert d.coverage_section({"default": [d.Case("default", 10000)]}) == []


#: A run's narrative as `situate demo` prints it without ``--json`` (the benchmark's second run).
DELIVERED = """\
[  994.4 s] phase 13: delivering the message
[  994.6 s]     said: "Hello! I have a message for you."
[  994.6 s] mission complete
demo: message delivered at t = 994.5 s (seed 60000)
demo: 9947 cycles, 39229 skill runs, 33.0 ms in skills, 1.1 s wall (890x real time)
"""
SILENT = """\
[  994.4 s] phase 13: delivering the message
[  999.4 s] mission failed: the speaker said nothing
demo: NOT delivered after 999.4 s (seed 60000)
"""


def test_a_failure_its_second_run_does_not_reproduce_is_never_classed_by_that_run() -> None:
    d = _report()
    # The first run (--json) failed; its second run, for the narrative, delivered: its last
    # phase line is phase 13's, and the failure was once counted as "phase 13".
    first = {"delivered": False, "mission_time_s": 999.4, "sequencer_exit": 1}
    case = d.Case("generated-hard", 60000, Path("m.yaml"), 60000)
    case.outcome = first
    case.stderr = ["situate.errors.NotRunning: no skill manager answered"]
    case.tail = [ln for ln in DELIVERED.splitlines() if ln.startswith("[")]
    case.again, case.reproduced = d.rerun_outcome(first, DELIVERED)
    assert not case.reproduced
    assert case.again == "demo: message delivered at t = 994.5 s (seed 60000)"
    assert d.failure_class(case) == d.NOT_REPRODUCED
    lines = d.failures_section({"generated-hard": [case]}, "## Failures")
    assert f"### {d.NOT_REPRODUCED} (1)" in lines, lines
    assert not any("phase 13" in line and line.startswith("###") for line in lines), lines
    # The first run's own outcome and what it said are shown, with the second's outcome line.
    assert any('"mission_time_s": 999.4' in line for line in lines), lines
    assert case.stderr[0] in lines, lines
    assert case.again in lines, lines
    # Not delivered at another time: another way too.
    assert d.rerun_outcome({**first, "mission_time_s": 1000.0}, SILENT)[1] is False
    # The same failure run again: classed by its own narrative.
    same = d.Case("generated-hard", 60000, Path("m.yaml"), 60000)
    same.outcome = first
    same.tail = [ln for ln in SILENT.splitlines() if ln.startswith("[")]
    same.again, same.reproduced = d.rerun_outcome(first, SILENT)
    assert same.reproduced
    assert d.failure_class(same) == "the speaker said nothing"
    # A drawn building's failure names its map (a generated one's is made by the command given).
    drawn = d.Case("hand-drawn", 40000, Path("maps/hand-drawn/two.yaml"), None)
    drawn.outcome = first
    drawn.tail = same.tail
    drawn.again, drawn.reproduced = d.rerun_outcome(first, SILENT)
    lines = d.failures_section({"hand-drawn": [drawn]}, "## Failures")
    assert (
        "- hand-drawn: `situate demo --headless --seed 40000 --map maps/hand-drawn/two.yaml`"
        in lines
    ), lines
    # A first run that said no outcome (an error) and a second that says none either: the same.
    assert d.rerun_outcome({"delivered": False, "error": "no outcome"}, "")[1] is True
    assert d.rerun_outcome({"delivered": False, "error": "no outcome"}, SILENT)[1] is False


#: A stand-in for the `situate` program: prints an outcome naming itself and its arguments.
FAKE_PROGRAM = """#!{python}
import json, sys
print(json.dumps({{"delivered": {delivered}, "argv": sys.argv}}))
"""


def test_the_benchmark_runs_the_program_and_demo_as_they_were_when_it_began(tmp_path: Path) -> None:
    d = _delivery()
    program = tmp_path / "build" / "situate"
    program.parent.mkdir()
    program.write_text(FAKE_PROGRAM.format(python=sys.executable, delivered=True))
    program.chmod(0o755)
    snap = tmp_path / "snap"
    copy = d.snapshot(program, snap)
    # A build beside the benchmark replaces the program (the first of its runs after that
    # once found it half-written): the runs still use the copy taken at the start.
    program.write_text(FAKE_PROGRAM.format(python=sys.executable, delivered=False))
    drawn = d.Case("hand-drawn", 40000, Path("maps/hand-drawn/one.yaml"), None, [])
    ran = d.run(copy, drawn, snap)
    assert ran.outcome["delivered"] is True, ran.outcome
    argv = ran.outcome["argv"]
    assert argv[0] == str(copy)
    # The robot file, the sequencer and a drawn map are the snapshot's, not the checkout's.
    assert argv[argv.index("--robot") + 1] == str(snap / "demo" / "robot.yaml")
    assert argv[argv.index("--sequencer") + 1] == str(snap / "demo" / "deliver.py")
    assert argv[argv.index("--map") + 1] == str(snap / "maps" / "hand-drawn" / "one.yaml")
    for part in ("demo/deliver.py", "demo/robot.yaml", "maps/hand-drawn/one.yaml"):
        assert (snap / part).read_bytes() == (ROOT / part).read_bytes(), part
    # A generated building's map is the benchmark's own file already; the physics robot's
    # demo finds its own robot file and sequencer.
    generated = d.Case("generated", 30000, tmp_path / "m.yaml", 30000)
    assert d.demo_command(copy, generated, snap)[-6:] == [
        "--map",
        str(tmp_path / "m.yaml"),
        "--robot",
        str(snap / "demo" / "robot.yaml"),
        "--sequencer",
        str(snap / "demo" / "deliver.py"),
    ]
    physics = d.Case("physics-default", 10000, None, None, ["--physics"])
    assert "--robot" not in d.demo_command(copy, physics, snap)
