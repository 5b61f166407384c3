#!/usr/bin/env bash
# `make test`: every stage in order, one line per stage with how long it took, and the total.
# A failing stage stops the run (later stages are listed as not run) and the exit code is its own.
#
#   scripts/test.sh [stage...]    the stages default to all of them, in this order
set -uo pipefail
cd "$(dirname "$0")/.."

STAGES=("$@")
[ ${#STAGES[@]} -gt 0 ] || STAGES=(system-deps gui lint test-rust test-python test-gui)
MAKE=${MAKE:-make}

fmt() { # seconds -> "1m05s" / "42s"
    local s=$1
    if [ "$s" -ge 60 ]; then printf '%dm%02ds' $((s / 60)) $((s % 60)); else printf '%ds' "$s"; fi
}

lines=()
status=0
start=$SECONDS
for stage in "${STAGES[@]}"; do
    if [ "$status" -ne 0 ]; then
        lines+=("$(printf '  %-12s not run' "$stage")")
        continue
    fi
    echo "==> make test: $stage"
    t0=$SECONDS
    "$MAKE" --no-print-directory "$stage"
    rc=$?
    took=$(fmt $((SECONDS - t0)))
    if [ "$rc" -eq 0 ]; then
        line=$(printf '  %-12s ok      %s' "$stage" "$took")
    else
        line=$(printf '  %-12s FAILED  %s (exit %d)' "$stage" "$took" "$rc")
        status=$rc
    fi
    echo "==> make test:${line}"
    lines+=("$line")
done

echo
echo "make test: stages"
printf '%s\n' "${lines[@]}"
if [ "$status" -eq 0 ]; then
    echo "make test: all green in $(fmt $((SECONDS - start)))"
else
    echo "make test: FAILED after $(fmt $((SECONDS - start)))"
fi
exit "$status"
