#!/usr/bin/env bash
# GUI benchmark: the mean cycle time of the toy robot with two GUI tabs attached vs none.
#   bench/gui/run.sh [--phase-s 15] [--rounds 3] [--robot FILE]
# Builds the testbed and the situate CLI in release (in $CARGO_TARGET_DIR, default target/), the web
# app first, and needs /usr/bin/chromium (scripts/gui.sh test installs it).
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
export PATH="$HOME/.cargo/bin:$PATH"
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
scripts/gui.sh build
cargo build --release -p situate_gui --example testbed
cargo build --release -p situate_cli --bin situate
[ -x /usr/bin/chromium ] || { echo "bench/gui: /usr/bin/chromium is missing (scripts/gui.sh test installs it)" >&2; exit 1; }
export TESTBED_BIN="$TARGET/release/examples/testbed"
export SITUATE_BIN="$TARGET/release/situate"
node bench/gui/bench.mjs --json "$TARGET/bench-results/gui.json" "$@"
node bench/gui/seek.mjs
