"""scripts/experiment.py and experiment_report.py: tasks, aggregation, report, cost; no runs."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load() -> ModuleType:
    sys.path.insert(0, str(ROOT / "scripts"))  # experiment.py imports experiment_report beside it
    spec = importlib.util.spec_from_file_location(
        "experiment_script", ROOT / "scripts" / "experiment.py"
    )
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["experiment_script"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


exp = _load()
rep = importlib.import_module("experiment_report")  # the report, as experiment.py imported it
TASK_CLASS = exp.symbolic_task_class()


# ----- buildings and tasks ----------------------------------------------------------------------

MAP = """\
building:
  travel_s_per_floor: 2.0
floors:
  - level: -1
    walls: []
  - level: 0
  - level: 1
  - level: 2
mission:
  start: {floor: -1, x: 2.01, y: 24.05, theta_deg: -90}
  goal_floor: 2
"""


def test_parse_building_reads_floors_start_and_goal() -> None:
    b = exp.parse_building(7, MAP)
    assert b == exp.Building(seed=7, floors=(-1, 0, 1, 2), start=-1, goal=2)
    assert exp.skip_reason(b) is None


def test_parse_building_without_a_mission_is_an_error() -> None:
    with pytest.raises(ValueError, match="building 3"):
        exp.parse_building(3, "floors:\n  - level: 0\n")


def test_skip_reason_needs_three_floors_and_the_goal_two_above() -> None:
    assert exp.skip_reason(exp.Building(1, (0, 1), 0, 1)) == "fewer than 3 floors"
    assert "2 floors above" in exp.skip_reason(exp.Building(1, (0, 1, 2), 0, 1))
    assert "2 floors above" in exp.skip_reason(exp.Building(1, (0, 1, 2), 2, 0))
    assert exp.skip_reason(exp.Building(1, (0, 1, 2), 0, 2)) is None


def test_task_class_from_the_floors() -> None:
    assert exp.task_class(-1, 2) == [
        "office",
        "lobby:2",
        "lobby:0,office",
        "lobby:2,lobby:-1",
        "lobby:-1",
        "lobby:0",
        "lobby:2,lobby:0",
        "lobby:-1,lobby:0,office",
    ]
    assert exp.symbolic_task_class()[7] == "lobby:S,lobby:M,office"
    assert len(rep.TASK_NAMES) == len(exp.symbolic_task_class()) == 8


# ----- aggregation ------------------------------------------------------------------------------


def _run(design: str, task_index: int, done: bool, **kw: Any) -> dict[str, Any]:
    row: dict[str, Any] = {
        "design": design,
        "building": 1,
        "task_index": task_index,
        "task_id": f"T{task_index + 1}",
        "task_done": done,
        "task_time_s": 100.0 * (task_index + 1),
        "mission_time_s": 100.0 * (task_index + 1),
        "skill_runs": 1000,
        "skill_cpu_ms": 10.0,
        "wall_s": 2.0,
    }
    row.update(kw)
    return row


def test_aggregate_times_over_done_runs_and_pooled_rates() -> None:
    rows = [_run("a", 0, True), _run("a", 1, False), _run("a", 2, True)]
    s = exp.aggregate(rows)
    assert (s["runs"], s["done"], s["errors"]) == (3, 2, 0)
    assert s["success_rate"] == pytest.approx(2 / 3)
    assert s["task_time_mean_s"] == pytest.approx(200.0)  # 100 and 300
    assert s["task_time_median_s"] == pytest.approx(200.0)
    assert s["skill_runs_per_sim_s"] == pytest.approx(3000 / 600)
    assert s["skill_cpu_us_per_sim_s"] == pytest.approx(30_000 / 600)
    assert s["rule_switches_per_sim_min"] is None
    assert s["wall_s_mean"] == pytest.approx(2.0)


def test_aggregate_counts_errors_as_failures_without_rates() -> None:
    error = {"design": "a", "building": 1, "task_index": 0, "task_id": "T1"}
    error |= {"error": "timeout", "task_done": False}
    s = exp.aggregate([error, _run("a", 0, True, rule_switches=30)])
    assert (s["runs"], s["done"], s["errors"]) == (2, 1, 1)
    assert s["rule_switches_per_sim_min"] == pytest.approx(60 * 30 / 100)
    assert s["drive_winner_changes_per_sim_min"] is None
    empty = exp.aggregate([])
    assert empty["success_rate"] is None
    assert empty["task_time_mean_s"] is None


def test_by_k_takes_the_first_k_tasks_per_design() -> None:
    rows = [_run("a", i, i % 2 == 0) for i in range(8)] + [_run("b", i, True) for i in range(8)]
    stats = exp.by_k(rows, ["a", "b"], 8)
    assert list(stats["a"]) == [1, 2, 4, 8]
    assert [stats["a"][k]["runs"] for k in (1, 2, 4, 8)] == [1, 2, 4, 8]
    assert [stats["a"][k]["done"] for k in (1, 2, 4, 8)] == [1, 1, 2, 4]
    assert stats["b"][8]["success_rate"] == 1.0
    assert list(exp.by_k(rows, ["a"], 2)["a"]) == [1, 2]


def test_by_task_counts_successes_per_task_and_design() -> None:
    rows = [_run("a", 0, True), _run("a", 0, False), _run("b", 0, True), _run("b", 1, False)]
    table = exp.by_task(rows, ["a", "b"], 2)
    assert table == {"T1": {"a": (1, 2), "b": (1, 1)}, "T2": {"a": (0, 0), "b": (0, 1)}}
    md = rep.task_table(table, ["a", "b"])
    assert "| T1 | deliver to the office | 1/2 | 1/1 |" in md


# ----- the report -------------------------------------------------------------------------------


def test_reading_section_is_kept_between_the_markers() -> None:
    old = "# x\n\n## Reading\n\n<!-- reading -->\nIt holds.\n\nMostly.\n<!-- /reading -->\n"
    assert rep.reading_section(old) == "It holds.\n\nMostly."
    assert rep.reading_section(None) == rep.READING_PLACEHOLDER
    assert rep.reading_section("# no markers") == rep.READING_PLACEHOLDER
    assert rep.reading_section("<!-- /reading --> <!-- reading -->") == rep.READING_PLACEHOLDER


def _results() -> dict[str, Any]:
    rows = [_run(d, i, True) for d in ("sequenced", "reactive") for i in range(2)]
    designs = ["sequenced", "reactive"]
    return {
        "config": {
            "designs": designs,
            "tasks": 2,
            "buildings": 1,
            "first_seed": 50000,
            "limit_s": 1800,
            "timeout_s": 600,
            "jobs": 1,
            "cpus": 2,
        },
        "timing": {"elapsed_s": 12.0, "runs_this_invocation": 4, "run_wall_s_total": 8.0},
        "buildings": {
            "kept": [{"seed": 50000, "floors": [0, 1, 2], "start": 0, "goal": 2}],
            "skipped": [{"seed": 50001, "reason": "fewer than 3 floors"}],
        },
        "design_cost": {
            "sequenced": {"files": {"demo/courier/sequenced/delivery.py": 10}, "loc": 10},
            "reactive": {
                "files": {"demo/courier/reactive/rules.py": 5},
                "loc": 5,
                "rules": 3,
                "condition_methods": 2,
                "inline_conditions": 1,
            },
        },
        "by_k": {
            d: {str(k): s for k, s in ks.items()} for d, ks in exp.by_k(rows, designs, 2).items()
        },
        "by_task": exp.by_task(rows, designs, 2),
        "runs": rows,
    }


def test_render_report_keeps_the_reading_and_regenerates_the_rest() -> None:
    first = rep.render_report(_results(), rep.reading_section(None), TASK_CLASS)
    assert first.startswith("# Experiment")
    assert f"{rep.READING_OPEN}\n{rep.READING_PLACEHOLDER}\n{rep.READING_CLOSE}" in first
    assert "1 because fewer than 3 floors" in first
    assert "| sequenced | 2 | 2/2 | 100% |" in first
    assert "| reactive | `demo/courier/reactive/rules.py` 5" in first
    assert "what both designs run on is counted for neither" in first
    assert "| 3 | 2 (+1 inline) |" in first
    hand = first.replace(rep.READING_PLACEHOLDER, "Sequencing wins at k = 8.")
    second = rep.render_report(_results(), rep.reading_section(hand), TASK_CLASS)
    assert "Sequencing wins at k = 8." in second
    assert rep.READING_PLACEHOLDER not in second
    assert "rule switches" not in second  # absent from every outcome


def test_k_table_shows_switches_when_an_outcome_has_them() -> None:
    rows = [_run("a", 0, True, drive_winner_changes=10)]
    md = rep.k_table(exp.by_k(rows, ["a"], 1))
    assert "drive winner changes / sim min" in md
    assert "| 6.0 |" in md  # 10 changes in 100 s


# ----- design cost ------------------------------------------------------------------------------

SAMPLE = '''\
"""A sample."""

# a comment


class R:
    def __init__(self) -> None:
        self.rules: list[tuple[str, object, object]] = [
            ("done", self.done, lambda s: None),
            ("go", self.ready, self.go),
            ("again", self.ready, self.go),  # same condition
            ("search", lambda s: True, self.go),
        ]

    def done(self, s: object) -> bool:
        return False
'''


def test_count_loc_skips_blank_and_comment_lines() -> None:
    assert exp.count_loc(SAMPLE) == 11
    assert exp.count_loc("\n   \n# x\n  # y\nx = 1  # z\n") == 1


def test_count_rules_parses_the_rules_list() -> None:
    assert exp.count_rules(SAMPLE) == {"rules": 4, "condition_methods": 2, "inline_conditions": 1}
    plain = "class R:\n    def f(self):\n        self.rules = [('a', self.a, self.b)]\n"
    assert exp.count_rules(plain)["rules"] == 1
    assert exp.count_rules("x = 1\n")["rules"] == 0


def test_design_cost_of_the_repositorys_designs() -> None:
    cost = exp.design_cost(ROOT, ["sequenced", "reactive"])
    assert set(cost["sequenced"]["files"]) == set(exp.DESIGN_SOURCES["sequenced"])
    assert cost["sequenced"]["loc"] == sum(cost["sequenced"]["files"].values())
    # Each design's files are its subpackage's modules, all of them; what both run on (the
    # link, the geometry, the mission, the program) is counted for neither.
    for design in ("sequenced", "reactive"):
        package = ROOT / "demo" / "courier" / design
        modules = {str(p.relative_to(ROOT)) for p in package.glob("*.py") if p.stem != "__init__"}
        assert set(cost[design]["files"]) == modules, design
    shared = ("link.py", "geometry.py", "mission.py", "main.py")
    assert not any(f.endswith(shared) for c in cost.values() for f in c["files"])
    assert cost["reactive"]["rules"] >= 5
    assert cost["reactive"]["condition_methods"] >= 5


def test_paired_task_time_keeps_the_runs_every_design_did() -> None:
    rows = [
        _run("a", 0, True),
        _run("a", 1, True),
        _run("b", 0, True, task_time_s=50.0),
        _run("b", 1, False),
    ]
    assert exp.done_by_all(rows, ["a", "b"]) == {(1, 0)}
    stats = exp.by_k(rows, ["a", "b"], 2)
    assert stats["a"][2]["task_time_mean_s"] == pytest.approx(150.0)
    assert stats["a"][2]["task_time_mean_common_s"] == pytest.approx(100.0)
    assert stats["b"][2]["task_time_mean_common_s"] == pytest.approx(50.0)
    assert stats["b"][2]["common_done"] == 1


def test_load_cache_keys_runs_and_skips_broken_lines(tmp_path: Path) -> None:
    cache = tmp_path / "runs.jsonl"
    cache.write_text('{"design": "a", "building": 1, "task_id": "T2"}\n{"trunc\n[]\n')
    assert list(exp.load_cache(cache)) == [exp.run_key("a", 1, "T2")]
    assert exp.load_cache(tmp_path / "none.jsonl") == {}


def test_a_hard_run_has_a_key_of_its_own_and_a_plain_one_keeps_the_old_key(tmp_path: Path) -> None:
    assert exp.run_key("a", 1, "T2") == "a/1/T2" == exp.run_key("a", 1, "T2", "plain")
    assert exp.run_key("a", 1, "T2", "hard") == "a/1/T2/hard"
    cache = tmp_path / "runs.jsonl"
    cache.write_text(
        '{"design": "a", "building": 1, "task_id": "T2"}\n'
        '{"design": "a", "building": 1, "task_id": "T2", "condition": "hard"}\n'
    )
    assert sorted(exp.load_cache(cache)) == ["a/1/T2", "a/1/T2/hard"]
    assert exp.hard_args(50025) == ["--people", "3", "--door-closures", "--dead-sonar", "9"]


def test_the_report_has_a_hard_set_section_only_with_hard_runs() -> None:
    plain = rep.render_report(_results(), rep.reading_section(None), TASK_CLASS)
    assert "### On the hard set" not in plain
    results = _results()
    designs = results["config"]["designs"]
    hard_rows = [_run(d, i, d == "sequenced") for d in designs for i in range(2)]
    results["hard"] = {
        "by_k": {
            d: {str(k): s for k, s in ks.items()}
            for d, ks in exp.by_k(hard_rows, designs, 2).items()
        },
        "by_task": exp.by_task(hard_rows, designs, 2),
    }
    report = rep.render_report(results, rep.reading_section(None), TASK_CLASS)
    hard = report[report.index("### On the hard set") :]
    assert "| sequenced | 2 | 2/2 | 100% |" in hard
    assert "| reactive | 2 | 0/2 | 0% |" in hard


def test_fault_line_counts_runs_with_faults_and_says_what_it_cannot_count() -> None:
    rows = [
        {"design": "a", "skills_faulted": []},
        {"design": "a", "skills_faulted": [{"skill": "x"}, {"skill": "y"}]},
        {"design": "b", "skills_faulted": []},
        {"design": "b"},  # made before the demo reported faults
    ]
    assert rep.fault_line(rows, ["a", "b"]) == (
        "a 1 of 2 runs (2 fault(s)); b 0 of 1 runs (0 fault(s));"
        " 1 runs made before faults were reported are not counted"
    )
    assert "not reported" in rep.fault_line([{"design": "a"}], ["a"])
