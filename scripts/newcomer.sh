#!/usr/bin/env bash
# The newcomer's path, end to end, as docs/python.md and docs/cli.md tell it: a fresh virtualenv
# outside the checkout, the wheel installed there like any package, and then only what that
# install offers (no file of the checkout is read after the install):
#
#   1. the program and its data: `situate --version`, `situate data-dir`, `situate check`
#   2. the delivery demo, headless, on the shipped small building
#   3. a Python skill of one's own, tested in process with pytest's `situate_robot` fixture
#   4. a C skill built with the shipped CMake package, checked and run in a robot file
#   5. a run recorded and replayed bit for bit
#   6. `--json` and the exit codes: a bad file (3), no robot (4), bad usage (2)
#
#   scripts/newcomer.sh WHEEL [WORKDIR]
#
# WHEEL: the situate wheel to install (scripts/python.sh builds one into target/situate-wheels).
# WORKDIR: where the venv and the newcomer's files go (default: a new temporary folder, removed at
# the end). Every step says what it does; the first that fails ends the script with its status.
set -euo pipefail

die() { echo "newcomer: $*" >&2; exit 1; }
step() { echo "newcomer: $*"; }

[ $# -ge 1 ] || die "usage: scripts/newcomer.sh WHEEL [WORKDIR]"
wheel=$(realpath "$1")
[ -f "$wheel" ] || die "no wheel at $1"
if [ $# -ge 2 ]; then
    work=$(realpath "$2")
    mkdir -p "$work"
else
    work=$(mktemp -d)
    trap 'rm -rf "$work"' EXIT
fi
cd "$work"

step "a fresh virtualenv in $work/venv, the wheel and pytest installed into it"
"${PYTHON:-python3}" -m venv venv
venv/bin/python -m pip install -q --disable-pip-version-check "$wheel" pytest
export PATH="$work/venv/bin:$PATH"
unset SITUATE_BIN SITUATE_PROGRAM SITUATE_CONNECT

# 1. The program and its data.
situate --version
data=$(situate data-dir)
[ -f "$data/examples/toybot.yaml" ] || die "situate data-dir ($data) has no examples/toybot.yaml"
python - "$data" <<'EOF'
import sys
from pathlib import Path

import situate

assert situate.data_dir() == Path(sys.argv[1]), (situate.data_dir(), sys.argv[1])
EOF
cp "$data/examples/toybot.yaml" toybot.yaml
situate check toybot.yaml >/dev/null
step "situate check toybot.yaml: ok"

# 2. The delivery, headless.
step "the delivery demo on the shipped small building"
situate demo --headless --json --map "$data/maps/small.yaml" >demo.json
python - <<'EOF'
import json

outcome = json.loads(open("demo.json").read().splitlines()[-1])
assert outcome["delivered"] is True, outcome
print(f"newcomer: delivered at t = {outcome['mission_time_s']:.1f} s")
EOF

# 3. A Python skill of one's own, tested in process.
step "a Python skill of one's own, tested with pytest's situate_robot fixture"
mkdir -p mine
cat >mine/skills.py <<'EOF'
import situate


@situate.skill(name="mine.cruise", outputs={"drive": "{v: f64, w: f64}"}, priority=5)
def cruise(speed: float = situate.param(0.2, min=0.0, max=1.0, unit="m/s")) -> dict[str, object]:
    """Drives straight ahead at `speed`."""
    return {"drive": {"v": speed, "w": 0.0}}
EOF
cat >mine/robot.yaml <<'EOF'
robot: mine
cycle: {rate_hz: 20, clock: simulated}
python: [skills.py]
devices:
  - {name: wheels, type: toy.wheels}
skills:
  - {name: cruise, type: mine.cruise}
EOF
cat >mine/test_mine.py <<'EOF'
from pathlib import Path

ROBOT = Path(__file__).parent / "robot.yaml"


def test_the_robot_cruises(situate_robot):
    robot = situate_robot(ROBOT)
    robot.step(40)  # 2 s at 20 Hz
    assert robot.query("drive").value == {"v": 0.2, "w": 0.0}
    assert robot.query("odom").value["x"] > 0.2
EOF
(cd mine && python -m pytest -q -p no:cacheprovider test_mine.py)

# 4. A C skill with the shipped CMake package.
if command -v cmake >/dev/null 2>&1; then
    step "a C skill built with the shipped CMake package"
    cp -r "$data/examples/c/runaway" c_runaway
    cmake -S c_runaway -B c_build -Dsituate_DIR="$(situate cmake-dir)" >/dev/null
    cmake --build c_build >/dev/null
    situate types --library c_build/libc_runaway.so --json | python -c \
        'import json, sys; assert "c.runaway" in [t["name"] for t in json.load(sys.stdin)]'
    cat >c_robot.yaml <<'EOF'
robot: cbot
cycle: {rate_hz: 20, clock: simulated}
libraries: [c_build/libc_runaway.so]
devices:
  - {name: sonar, type: toy.sonar}
  - {name: wheels, type: toy.wheels}
skills:
  - {name: runaway, type: c.runaway}
EOF
    situate run c_robot.yaml --cycles 50 --no-link --json >c_run.json
    python - <<'EOF'
import json

run = json.load(open("c_run.json"))
runaway = next(s for s in run["skills"] if s["name"] == "runaway")
assert runaway["faulted"] is None and runaway["timing"]["runs"] >= 49, runaway
EOF
    step "the C skill ran 50 cycles"
else
    step "no cmake here: the C skill is left out"
fi

# 5. Record and replay.
step "a run recorded and replayed"
situate run toybot.yaml --cycles 300 --no-link --clock simulated --record toy.mcap --json >run.json
situate replay toy.mcap --json >replay.json
python - <<'EOF'
import json

run = json.load(open("run.json"))
replay = json.load(open("replay.json"))
assert run["recording"]["cycles"] == 300, run["recording"]
assert replay["identical"] is True, replay
print(f"newcomer: {replay['cycles']} cycles replayed, identical")
EOF

# 6. --json and the exit codes.
step "exit codes: a bad file 3, no robot 4, bad usage 2"
expect_exit() { # code command...
    local want=$1 got=0
    shift
    "$@" >out.json 2>/dev/null || got=$?
    [ "$got" -eq "$want" ] || die "\`$*\` exited with $got, the docs say $want"
    python -c 'import json, sys; e = json.load(open("out.json"))["error"]; assert e["exit"] == int(sys.argv[1]), e' "$want"
}
printf 'robot: broken\nskills:\n  - {name: w, type: toy.wandr}\n' >broken.yaml
expect_exit 3 situate check broken.yaml --json
port=$(python -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
expect_exit 4 situate stats --connect "tcp/127.0.0.1:$port" --timeout 1 --json
expect_exit 2 situate chekc --json

step "all done: the newcomer's path holds"
