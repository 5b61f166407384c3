"""scripts/delivery.py's report: the coverage table of the generated sets (no robot is run)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]


def _delivery() -> ModuleType:
    spec = importlib.util.spec_from_file_location("delivery", ROOT / "scripts" / "delivery.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["delivery"] = module
    spec.loader.exec_module(module)
    return module


def test_the_coverage_table_counts_runs_by_feature_and_never_drops_a_set_silently() -> None:
    d = _delivery()
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
