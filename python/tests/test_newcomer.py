"""The newcomer's whole path (scripts/newcomer.sh) on the wheel this checkout built.

A fresh virtualenv outside the checkout, the wheel installed into it, then the demo, a Python
skill tested with the pytest fixture, a C skill with the shipped CMake package, a recording
replayed, and the CLI's `--json` and exit codes: each with only what the install offers.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest
from support import REPO


def built_wheel() -> Path:
    target = Path(os.environ.get("CARGO_TARGET_DIR") or REPO / "target")
    wheels = sorted((target / "situate-wheels").glob("situate-*.whl"))
    if not wheels:
        pytest.fail(f"no wheel in {target / 'situate-wheels'}: run scripts/python.sh first")
    return wheels[-1]


def test_the_newcomers_path_holds_outside_the_checkout(tmp_path: Path) -> None:
    work = tmp_path / "newcomer"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("SITUATE_", "VIRTUAL_ENV"))}
    done = subprocess.run(
        [str(REPO / "scripts" / "newcomer.sh"), str(built_wheel()), str(work)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    report = done.stdout + done.stderr
    assert done.returncode == 0, report[-6000:]
    assert "newcomer: all done: the newcomer's path holds" in done.stdout, report[-6000:]
    # Nothing of the checkout was on the way: the package ran from the new virtualenv.
    assert (work / "venv" / "bin" / "situate").is_file()
