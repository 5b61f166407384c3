#!/usr/bin/env bash
# The Python package (python/situate, crates/apis/situate_py): sets up .venv at the repository root
# with the tools, builds the wheel and installs it there. Safe to run again: the tools are
# installed only when their list changed, and cargo rebuilds only what changed.
#
#   scripts/python.sh          set up and install
#   scripts/python.sh test     ... then ruff, mypy (strict) and pytest
#   scripts/python.sh tools    only .venv and the tools (what `make test` downloads while it compiles)
#
# Environment: SITUATE_TESTS_PREBUILT=1 (set by scripts/test.sh: `test` uses the installed
# package as it is), PYTHON (default python3), CARGO_TARGET_DIR (default target/, shared with cargo),
# SITUATE_PY_PROFILE=release|debug (default: release to install, debug under `test`, where it
# reuses the build `cargo test --workspace` made instead of compiling the tree again in release:
# minutes on a 2-core machine), PYTEST_WORKERS (parallel pytest processes, default 2),
# SITUATE_ZENOH_VERSION (the Python zenoh installed for the tests, default 1.10.2).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"

PYTHON=${PYTHON:-python3}
VENV=.venv
TOOLS=("maturin==1.16.*" "pytest>=8" "pytest-xdist>=3.6" "ruff>=0.15" "mypy>=1.18" "eclipse-zenoh==${SITUATE_ZENOH_VERSION:-1.10.2}" "numpy>=1.22")
TOOLS+=("rosbags>=0.10,<1") # python/tests/test_ros2.py decodes the ROS 2 bridge's CDR with it
TOOLS+=("xxhash>=3.4") # python/situate/ros2.py: rmw_zenoh derives an entity's GID as XXH3-128 of its token
TOOLS+=("mujoco>=3.2") # python/tests/test_physics.py: the physics robot (situate.physics)
TOOLS+=("mcap>=1.6,<2") # python/tests/test_recording.py reads `--record` files with the MCAP reference reader
TARGET=${CARGO_TARGET_DIR:-target}
if [[ ${1:-} == test ]]; then PROFILE=${SITUATE_PY_PROFILE:-debug}; else PROFILE=${SITUATE_PY_PROFILE:-release}; fi
say() { if [[ -t 1 ]]; then printf '\033[1mpython.sh:\033[0m %s\n' "$*"; else printf 'python.sh: %s\n' "$*"; fi; }

# 1. The virtualenv and the tools (re-installed only when the list above changes).
if [[ ! -x $VENV/bin/python ]]; then
    say "creating $VENV with $($PYTHON --version)"
    "$PYTHON" -m venv "$VENV"
fi
stamp=$VENV/.situate-tools
if [[ ! -f $stamp || "$(cat "$stamp")" != "${TOOLS[*]}" ]]; then
    say "installing ${TOOLS[*]}"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check "${TOOLS[@]}"
    printf '%s' "${TOOLS[*]}" >"$stamp"
fi

[[ ${1:-} == tools ]] && exit 0

# 2. The wheel (abi3: one wheel for CPython 3.9+), installed like any user's. Its package data
#    (the demo, the maps and the examples, for `situate demo` anywhere) is copied in first.
# Under `make test`'s plan (scripts/test.sh) its `wheel` stage installed it before the test stages
# started side by side; building it again would wait for the cargo build running beside them.
if [[ ${1:-} == test && ${SITUATE_TESTS_PREBUILT:-} == 1 ]]; then
    [[ -x $VENV/bin/situate ]] || { say "SITUATE_TESTS_PREBUILT=1 but no package in $VENV"; exit 1; }
    say "using the package installed by the wheel stage"
else
    scripts/package-data.sh
    wheels=$TARGET/situate-wheels
    rm -rf "$wheels"
    profile_flag=(--release)
    [[ $PROFILE == debug ]] && profile_flag=()
    say "building the wheel ($PROFILE)"
    start=$SECONDS
    "$VENV/bin/maturin" build "${profile_flag[@]}" --quiet --interpreter "$VENV/bin/python" \
        --out "$wheels" 2> >(grep -vE '^\s*(Compiling|Checking|Downloaded|Downloading|Locking|Adding|Updating)' >&2)
    wheel=$(ls "$wheels"/situate-*.whl)
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check --no-deps --force-reinstall "$wheel"
    say "installed $(basename "$wheel") in $((SECONDS - start)) s"
fi

# 3. Lints and tests.
if [[ ${1:-} == test ]]; then
    source "$VENV/bin/activate"
    say "ruff"
    ruff check python demo scripts examples bench/python
    ruff format --check python demo scripts examples bench/python
    say "mypy --strict"
    mypy python/situate demo/deliver.py demo/reactive.py demo/courier scripts/experiment.py scripts/experiment_report.py scripts/delivery.py scripts/delivery_report.py
    # The tests too, as their own run: they import the demo's package, `courier` (demo/ on the path).
    MYPYPATH=demo mypy python/tests
    # In parallel processes (pytest-xdist): the tests pick free ports and lock what they build.
    workers=${PYTEST_WORKERS:-2}
    say "pytest ($workers workers)"
    # Every test's time goes to target/pytest-report.xml (JUnit XML), for finding the slow ones.
    # One test at a time to a worker that frees up (python/tests/conftest.py starts the slow ones
    # first), not chunks of a quarter of the suite each.
    pytest -q -n "$workers" --maxschedchunk 1 --durations=8 --junitxml="$TARGET/pytest-report.xml" python/tests
fi
