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
