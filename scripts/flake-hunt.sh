#!/usr/bin/env bash
# Hunts flaky tests: runs `make test`'s stages N times each while a CPU load runs beside them (one
# busy loop per core, as on a shared CI machine), and reports every failure with the test that
# failed and where its log is. A flaky test is a failing test: every failure it finds is a race
# to fix, not a run to retry.
#
#   scripts/flake-hunt.sh [-n RUNS] [-l LOADERS] [-p] [stage...]
#
#   -n RUNS      runs of each stage (default 5)
#   -l LOADERS   busy loops beside the tests (default: the number of cores; 0: no load)
#   -p           run `make test`'s whole plan (scripts/test.sh: the test stages side by side)
#                RUNS times instead of the stages one by one
#   stage        stages of scripts/test.sh (default: lint test-rust test-python test-gui; the
#                stages that only build are run once first, unloaded)
#
# Logs go to target/flake-hunt/<stage>-<run>.log; the summary (stage, run, result, time, and the
# names of the failed tests) is printed at the end and written to target/flake-hunt/summary.txt.
# Exit status: 0 when every run of every stage passed, 1 otherwise.
set -uo pipefail
cd "$(dirname "$0")/.."

RUNS=5
LOADERS=$(nproc)
PLAN=0
while getopts "n:l:p" opt; do
    case $opt in
        n) RUNS=$OPTARG ;;
        l) LOADERS=$OPTARG ;;
        p) PLAN=1 ;;
        *) echo "usage: $0 [-n RUNS] [-l LOADERS] [-p] [stage...]" >&2; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
STAGES=("$@")
[ ${#STAGES[@]} -gt 0 ] || STAGES=(lint test-rust test-python test-gui)
[ "$PLAN" -eq 0 ] || STAGES=(plan)
MAKE=${MAKE:-make}
OUT=${CARGO_TARGET_DIR:-target}/flake-hunt
mkdir -p "$OUT"

# The build-only stages, once, without load: what the hunted stages need in place.
for prep in system-deps gui; do
    echo "flake-hunt: preparing ($prep)"
    "$MAKE" --no-print-directory "$prep" >"$OUT/prep-$prep.log" 2>&1 || {
        echo "flake-hunt: $prep failed (see $OUT/prep-$prep.log)" >&2
        exit 1
    }
done

loaders=()
start_load() {
    local i
    for ((i = 0; i < LOADERS; i++)); do
        (while :; do :; done) &
        loaders+=($!)
    done
}
stop_load() {
    local pid
    for pid in "${loaders[@]}"; do kill "$pid" 2>/dev/null; done
    wait "${loaders[@]}" 2>/dev/null
    loaders=()
}
trap stop_load EXIT
# A stop request ends the hunt (the loops go with it), not only the run under way.
trap 'echo "flake-hunt: stopped" >&2; exit 130' INT TERM

# The names of the tests a log says failed: cargo's `test x ... FAILED`, pytest's `FAILED path::test`,
# Playwright's `✘ … › test`.
failed_tests() {
    grep -aoE '^test [^ ]+ \.\.\. FAILED|^FAILED [^ ]+|✘ +[0-9]+ .*' "$1" 2>/dev/null \
        | sed -E 's/^test ([^ ]+) \.\.\. FAILED/\1/; s/^FAILED //' | sort -u | head -20
}

summary=()
failures=0
start_load
echo "flake-hunt: $RUNS runs of ${STAGES[*]}, with $LOADERS busy loops beside them"
for ((run = 1; run <= RUNS; run++)); do
    for stage in "${STAGES[@]}"; do
        log="$OUT/$stage-$run.log"
        t0=$SECONDS
        if [ "$stage" = plan ]; then
            scripts/test.sh >"$log" 2>&1
        else
            "$MAKE" --no-print-directory "$stage" >"$log" 2>&1
        fi
        rc=$?
        took=$((SECONDS - t0))
        if [ "$rc" -eq 0 ]; then
            line=$(printf '%-12s run %d  ok      %4ds' "$stage" "$run" "$took")
        else
            failures=$((failures + 1))
            line=$(printf '%-12s run %d  FAILED  %4ds  (exit %d, %s)' "$stage" "$run" "$took" "$rc" "$log")
            while IFS= read -r t; do
                [ -n "$t" ] && line+=$'\n'"      failed: $t"
            done < <(failed_tests "$log")
        fi
        echo "flake-hunt: $line"
        summary+=("$line")
    done
done
stop_load

{
    echo "flake-hunt: $RUNS runs of ${STAGES[*]} with $LOADERS busy loops beside them"
    printf '%s\n' "${summary[@]}"
    if [ "$failures" -eq 0 ]; then echo "flake-hunt: all green"; else echo "flake-hunt: $failures failed runs"; fi
} | tee "$OUT/summary.txt"
[ "$failures" -eq 0 ]
