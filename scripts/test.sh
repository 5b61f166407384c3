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

# What the checkout's tracked files hold now: no stage may change them (a build that rewrote
# web/package-lock.json once left every fresh clone dirty).
tracked_state() {
    git rev-parse --is-inside-work-tree >/dev/null 2>&1 || return 0
    { git status --porcelain=v1 --untracked-files=no; git diff; } | sha256sum
}
tracked_before=$(tracked_state)

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

if [ "$status" -eq 0 ] && [ "$(tracked_state)" != "$tracked_before" ]; then
    echo "make test: the stages changed tracked files of the checkout:" >&2
    git status --short --untracked-files=no >&2
    lines+=("$(printf '  %-12s FAILED  tracked files changed' checkout)")
    status=1
fi

echo
echo "make test: stages"
printf '%s\n' "${lines[@]}"
if [ "$status" -eq 0 ]; then
    echo "make test: all green in $(fmt $((SECONDS - start)))"
else
    echo "make test: FAILED after $(fmt $((SECONDS - start)))"
fi
exit "$status"
