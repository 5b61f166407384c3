#!/usr/bin/env bash
# The README's picture: runs the delivery demo with its GUI and takes a screenshot of the GUI in
# headless Chromium after SECONDS (default 60) of wall time.
#   scripts/demo-screenshot.sh [SECONDS] [OUT.png]
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_WAIT=${1:-60}
OUT=${2:-docs/demo.png}
SITUATE=${SITUATE_BIN:-${CARGO_TARGET_DIR:-target}/release/situate}
[ -x "$SITUATE" ] || { echo "demo-screenshot.sh: no $SITUATE (make demo builds it)" >&2; exit 1; }
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
"$SITUATE" demo --python .venv/bin/python --gui "127.0.0.1:$port" --speed 4 &
demo=$!
trap 'kill $demo 2>/dev/null || true' EXIT
node web/tests/screenshot.mjs "http://127.0.0.1:$port/" "$OUT" "$SECONDS_WAIT"
