#!/usr/bin/env bash
# `make test`: every stage, one line per stage with how long it took, and the total.
#
#   scripts/test.sh               the whole plan below
#   scripts/test.sh stage...      only these stages, one after the other, in the order given
#
# The plan, on a 2-core machine where compiling is most of the time:
#   1. system-deps, gui, fmt, build-tests, wheel: one after the other. build-tests compiles every
#      test, program and example once with clippy's lints as errors (clippy-driver as the
#      workspace's compiler, below), so linting costs no second, check-only compile of the tree;
#      wheel installs the Python package from that build.
#   2. prepare (the Python tools, Chromium): downloads, in the background while 1 compiles.
#   3. test-python and test-gui start (SITUATE_TESTS_PREBUILT=1: they build nothing), then
#      build-more compiles the benches and the extension example beside them, then test-rust
#      starts. Each test stage writes its output to target/test-logs/<stage>.log; a failed
#      stage's log is printed whole.
# A failing stage stops the stages not yet started (they are listed as not run) and the exit code
# is the first failure's own.
set -uo pipefail
cd "$(dirname "$0")/.."

MAKE=${MAKE:-make}
LOGS=${CARGO_TARGET_DIR:-target}/test-logs

# clippy-driver as the compiler of the workspace's own crates, with clippy's arguments: what
# `cargo clippy -- -D warnings` sets for `cargo check`, here for the real build. Every stage gets
# it, so each reuses what `build` compiled (cargo keeps builds with and without it apart).
# Without clippy-driver the whole plan refuses to run (its build would lint nothing); stages named
# one by one run without it.
PATH="${HOME:+$HOME/.cargo/bin:}$PATH"
if driver=$(command -v clippy-driver); then
    export RUSTC_WORKSPACE_WRAPPER=$driver
    export CLIPPY_ARGS=-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__
elif [ $# -eq 0 ]; then
    echo "make test: clippy-driver is missing (rustup component add clippy)" >&2
    exit 1
fi

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

declare -A line_of=()
order=()
status=0
start=$SECONDS

record() { # stage rc seconds
    local stage=$1 rc=$2 took
    took=$(fmt "$3")
    if [ "$rc" -eq 0 ]; then
        line_of[$stage]=$(printf '  %-12s ok      %s' "$stage" "$took")
    else
        line_of[$stage]=$(printf '  %-12s FAILED  %s (exit %d)' "$stage" "$took" "$rc")
        [ "$status" -ne 0 ] || status=$rc
    fi
    echo "==> make test:${line_of[$stage]}"
}

not_run() {
    local stage
    for stage in "$@"; do
        order+=("$stage")
        line_of[$stage]=$(printf '  %-12s not run' "$stage")
    done
}

# A stage in the foreground, its output as it comes.
run() {
    local stage=$1 t0=$SECONDS rc
    order+=("$stage")
    if [ "$status" -ne 0 ]; then
        line_of[$stage]=$(printf '  %-12s not run' "$stage")
        return
    fi
    echo "==> make test: $stage"
    "$MAKE" --no-print-directory "$stage"
    rc=$?
    record "$stage" "$rc" $((SECONDS - t0))
}

# Stages in the background, each into its log; `collect` waits for them in the order started.
declare -A pid_of=() t0_of=()
started=()
spawn() {
    local stage=$1 rc
    order+=("$stage")
    mkdir -p "$LOGS"
    rm -f "$LOGS/$stage.end"
    echo "==> make test: $stage (in the background, output in $LOGS/$stage.log)"
    t0_of[$stage]=$(date +%s)
    {
        "$MAKE" --no-print-directory "$stage" >"$LOGS/$stage.log" 2>&1
        rc=$?
        date +%s >"$LOGS/$stage.end" # its own time, not the time until it was collected
        exit "$rc"
    } &
    pid_of[$stage]=$!
    started+=("$stage")
}
collect() {
    local stage rc
    for stage in "${started[@]}"; do
        wait "${pid_of[$stage]}"
        rc=$?
        record "$stage" "$rc" $(($(cat "$LOGS/$stage.end" 2>/dev/null || date +%s) - t0_of[$stage]))
        if [ "$rc" -ne 0 ]; then
            echo "==> make test: $stage failed; its output ($LOGS/$stage.log):"
            cat "$LOGS/$stage.log"
            echo "==> make test: end of $stage's output"
        fi
    done
    started=()
}

if [ $# -gt 0 ]; then
    for stage in "$@"; do run "$stage"; done
else
    run system-deps
    if [ "$status" -eq 0 ]; then spawn prepare; else not_run prepare; fi
    run gui
    run fmt
    run build-tests
    collect # prepare
    run wheel
    # The Python and GUI tests use what build-tests and wheel made, and call no cargo of their
    # own (it would wait for build-more's): they start while the benches and the extension
    # example, which only the Rust tests need, compile.
    export SITUATE_TESTS_PREBUILT=1
    if [ "$status" -eq 0 ]; then
        spawn test-python
        spawn test-gui
        run build-more
        if [ "$status" -eq 0 ]; then spawn test-rust; else not_run test-rust; fi
        collect
    else
        not_run test-python test-gui build-more test-rust
    fi
fi

if [ "$status" -eq 0 ] && [ "$(tracked_state)" != "$tracked_before" ]; then
    echo "make test: the stages changed tracked files of the checkout:" >&2
    git status --short --untracked-files=no >&2
    order+=(checkout)
    line_of[checkout]=$(printf '  %-12s FAILED  tracked files changed' checkout)
    status=1
fi

echo
echo "make test: stages"
for stage in "${order[@]}"; do echo "${line_of[$stage]}"; done
if [ "$status" -eq 0 ]; then
    echo "make test: all green in $(fmt $((SECONDS - start)))"
else
    echo "make test: FAILED after $(fmt $((SECONDS - start)))"
fi
exit "$status"
