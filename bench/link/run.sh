#!/usr/bin/env bash
# Link benchmarks (bench/link/README.md): the flood benchmark (bench/benches/flood.rs: the cycle
# rate under worst-case requests from 4 clients vs idle), then bench/link/linkbench.py with the workspace's
# .venv python, after setting up a separate venv with dora-rs-cli for the comparison
# (default /tmp/dora-venv; never the workspace's .venv). Arguments go to linkbench.py, e.g.
#   bench/link/run.sh                 # both benchmarks, 300 samples each
#   bench/link/run.sh --quick         # a smoke run
#   bench/link/run.sh hop --no-dora   # only the hop, without dora
#   bench/link/run.sh --wait-idle 120 # first wait (≤ 120 s) for other processes to go quiet
# Environment: DORA_VENV (default /tmp/dora-venv), DORA_VERSION (default 1.1.0),
# LINKBENCH_TIMEOUT (seconds, default 900: a hard bound on the whole run).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
PY="$ROOT/.venv/bin/python"
DORA_VENV="${DORA_VENV:-/tmp/dora-venv}"
DORA_VERSION="${DORA_VERSION:-1.1.0}"
LINKBENCH_TIMEOUT="${LINKBENCH_TIMEOUT:-900}"

if [[ ! -x "$ROOT/.venv/bin/situate" ]]; then
    echo "error: $ROOT/.venv/bin/situate is missing: run scripts/python.sh (or make python) first" >&2
    exit 2
fi

want_dora=1
for a in "$@"; do [[ "$a" == "--no-dora" ]] && want_dora=0; done
if [[ $want_dora == 1 && ! -x "$DORA_VENV/bin/dora" ]]; then
    echo "setting up $DORA_VENV (dora-rs-cli==$DORA_VERSION) for the dora-rs comparison ..."
    base_py="$(command -v python3 || true)"
    if [[ -z "$base_py" ]] \
        || ! timeout 300 "$base_py" -m venv "$DORA_VENV" \
        || ! timeout 300 "$DORA_VENV/bin/pip" install -q "dora-rs-cli==$DORA_VERSION"; then
        echo "warning: could not install dora-rs-cli into $DORA_VENV; the hop is reported without dora-rs" >&2
    fi
fi

# The cycle rate under a flood of worst-case requests from 4 clients, beside the idle rate.
flood_args=()
for a in "$@"; do [[ "$a" == "--quick" ]] && flood_args+=(--quick); done
(cd "$ROOT" && timeout --signal=TERM --kill-after=30 600 \
    "${CARGO:-cargo}" bench -q -p situate_bench --locked --bench flood -- "${flood_args[@]}")

export DORA_VENV
exec timeout --signal=TERM --kill-after=30 "$LINKBENCH_TIMEOUT" \
    "$PY" "$HERE/linkbench.py" --dora-venv "$DORA_VENV" --max-s "$((LINKBENCH_TIMEOUT - 20))" "$@"
