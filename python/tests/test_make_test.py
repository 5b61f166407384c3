"""`make test` (scripts/test.sh): a line per stage with its time, the total, the exit code.

The stages here are a stand-in `make` that succeeds or fails by name; CI runs the real ones.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from support import REPO


def run_stages(tmp_path: Path, *stages: str) -> subprocess.CompletedProcess[str]:
    make = tmp_path / "make"
    make.write_text(
        "#!/usr/bin/env bash\n"
        'stage="${@: -1}"\n'
        'echo "running $stage"\n'
        'case "$stage" in fail*) exit 3 ;; esac\n'
    )
    make.chmod(0o755)
    return subprocess.run(
        [str(REPO / "scripts" / "test.sh"), *stages],
        env={"PATH": "/usr/bin:/bin", "MAKE": str(make)},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )


def test_every_stage_gets_a_line_with_its_time_and_the_total_is_printed(tmp_path: Path) -> None:
    out = run_stages(tmp_path, "one", "two")
    assert out.returncode == 0, out.stderr
    summary = out.stdout.split("make test: stages\n", 1)[1].splitlines()
    assert [line.split()[:2] for line in summary[:2]] == [["one", "ok"], ["two", "ok"]]
    assert all(line.split()[2].endswith("s") for line in summary[:2])
    assert summary[2].startswith("make test: all green in ")
    assert "running one" in out.stdout
    assert "running two" in out.stdout


def test_a_failing_stage_stops_the_run_with_its_exit_code(tmp_path: Path) -> None:
    out = run_stages(tmp_path, "one", "fail-here", "three")
    assert out.returncode == 3
    summary = out.stdout.split("make test: stages\n", 1)[1].splitlines()
    assert summary[0].split()[:2] == ["one", "ok"]
    assert summary[1].split()[:2] == ["fail-here", "FAILED"]
    assert "(exit 3)" in summary[1]
    assert summary[2].split() == ["three", "not", "run"]
    assert summary[3].startswith("make test: FAILED after ")
    assert "running three" not in out.stdout


def test_a_stage_that_changes_a_tracked_file_fails_the_run(tmp_path: Path) -> None:
    # A build that rewrote web/package-lock.json once left every fresh clone dirty after
    # `make test`. In a checkout of its own (the real one must stay as it is), a stage that
    # changes a tracked file fails the run and names the file.
    repo = tmp_path / "checkout"
    (repo / "scripts").mkdir(parents=True)
    (repo / "scripts" / "test.sh").write_text((REPO / "scripts" / "test.sh").read_text())
    (repo / "scripts" / "test.sh").chmod(0o755)
    (repo / "lock.json").write_text("{}\n")
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@t"]
    for args in (["init", "-q"], ["add", "."], ["commit", "-q", "-m", "x"]):
        subprocess.run([*git, *args], check=True, capture_output=True)
    make = tmp_path / "make"
    make.write_text(
        "#!/usr/bin/env bash\n"
        'stage="${@: -1}"\n'
        f'case "$stage" in dirty) echo changed > {repo / "lock.json"} ;; esac\n'
    )
    make.chmod(0o755)

    def stages(*names: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [str(repo / "scripts" / "test.sh"), *names],
            env={"PATH": "/usr/bin:/bin", "MAKE": str(make)},
            capture_output=True,
            text=True,
            timeout=60,
            check=False,
        )

    clean = stages("one")
    assert clean.returncode == 0, clean.stdout + clean.stderr
    dirty = stages("one", "dirty")
    assert dirty.returncode == 1, dirty.stdout
    assert "lock.json" in dirty.stderr
    assert "checkout     FAILED  tracked files changed" in dirty.stdout


PLAN = [
    "system-deps",
    "prepare",
    "gui",
    "fmt",
    "build-tests",
    "wheel",
    "test-python",
    "test-gui",
    "build-more",
    "test-rust",
]


def run_plan(tmp_path: Path, fail: str) -> subprocess.CompletedProcess[str]:
    """The whole plan (no stages named), with a stand-in `make` and `clippy-driver`.

    The three test stages each wait (with a generous bound) until all three have started, so
    the plan passes only when they run side by side; the stage named `fail` exits 2.
    """
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    driver = bin_dir / "clippy-driver"
    driver.write_text("#!/bin/sh\nexit 0\n")
    driver.chmod(0o755)
    started = tmp_path / "started"
    started.mkdir()
    make = tmp_path / "make"
    make.write_text(
        "#!/usr/bin/env bash\n"
        'stage="${@: -1}"\n'
        'echo "running $stage with $RUSTC_WORKSPACE_WRAPPER"'
        ' "prebuilt=${SITUATE_TESTS_PREBUILT:-0}"\n'
        'case "$stage" in test-*)\n'
        f"  touch {started}/$stage\n"
        "  for _ in $(seq 300); do\n"
        f'    [ "$(ls {started} | wc -l)" -eq 3 ] && break\n'
        "    sleep 0.1\n"
        "  done\n"
        f'  [ "$(ls {started} | wc -l)" -eq 3 ] || {{ echo "$stage ran alone"; exit 9; }}\n'
        ";; esac\n"
        f'[ "$stage" = "{fail}" ] && {{ echo "$stage said no"; exit 2; }}\n'
        "exit 0\n"
    )
    make.chmod(0o755)
    return subprocess.run(
        [str(REPO / "scripts" / "test.sh")],
        env={
            "PATH": f"{bin_dir}:/usr/bin:/bin",
            "MAKE": str(make),
            "CARGO_TARGET_DIR": str(tmp_path / "target"),
        },
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )


def summary_of(out: subprocess.CompletedProcess[str]) -> dict[str, list[str]]:
    lines = out.stdout.split("make test: stages\n", 1)[1].splitlines()[:-1]
    return {line.split()[0]: line.split()[1:] for line in lines}


def test_the_plan_runs_the_test_stages_side_by_side_and_prints_a_failed_ones_output(
    tmp_path: Path,
) -> None:
    out = run_plan(tmp_path, fail="test-python")
    assert out.returncode == 2, out.stdout + out.stderr
    summary = summary_of(out)
    assert list(summary) == PLAN
    assert summary["test-python"][:1] == ["FAILED"]
    assert "(exit 2)" in " ".join(summary["test-python"])
    for stage in set(PLAN) - {"test-python"}:
        assert summary[stage][0] == "ok", (stage, out.stdout)
    # The failed stage's output is printed whole; every stage got clippy-driver as the
    # workspace's compiler (so each reuses the linted build).
    assert "test-python said no" in out.stdout
    driver = tmp_path / "bin" / "clippy-driver"
    assert f"running build-tests with {driver} prebuilt=0" in out.stdout
    # The test stages build nothing of their own (it would wait for build-more's cargo).
    gui_log = (tmp_path / "target" / "test-logs" / "test-gui.log").read_text()
    assert f"running test-gui with {driver} prebuilt=1" in gui_log
    assert "make test: FAILED after " in out.stdout


def test_a_failed_build_leaves_the_test_stages_not_run(tmp_path: Path) -> None:
    out = run_plan(tmp_path, fail="build-tests")
    assert out.returncode == 2, out.stdout + out.stderr
    summary = summary_of(out)
    assert sorted(summary) == sorted(PLAN)
    assert summary["build-tests"][0] == "FAILED"
    assert summary["prepare"][0] == "ok"
    for stage in ("wheel", "test-rust", "test-python", "test-gui", "build-more"):
        assert summary[stage] == ["not", "run"], (stage, out.stdout)


def test_the_plan_refuses_to_run_without_clippy_driver(tmp_path: Path) -> None:
    out = subprocess.run(
        [str(REPO / "scripts" / "test.sh")],
        env={"PATH": "/usr/bin:/bin", "MAKE": "false"},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert out.returncode == 1
    assert "clippy-driver is missing" in out.stderr
