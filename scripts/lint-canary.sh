#!/usr/bin/env bash
# `make test` lints while it compiles: scripts/test.sh sets clippy-driver as the workspace's compiler
# with clippy's arguments, the way `cargo clippy` hands them over (docs/decisions/0012). That
# hand-over is clippy's own, not a documented interface, so this proves it still lints: a crate
# with a known clippy lint, built the same way, must fail on that lint.
set -euo pipefail
: "${RUSTC_WORKSPACE_WRAPPER:?lint-canary: run under scripts/test.sh (clippy-driver as the compiler)}"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir "$dir/src"
cat >"$dir/Cargo.toml" <<'TOML'
[package]
name = "lint_canary"
version = "0.0.0"
edition = "2021"
publish = false

[workspace]
TOML
echo 'pub fn len(v: &Vec<u8>) -> usize { v.len() }' >"$dir/src/lib.rs"
if out=$(cargo build --offline --manifest-path "$dir/Cargo.toml" --target-dir "$dir/target" 2>&1); then
    echo "lint-canary: a crate with a clippy lint (ptr_arg) built cleanly: the build does not fail on clippy's lints" >&2
    exit 1
fi
if ! grep -q 'clippy::ptr_arg' <<<"$out"; then
    echo "lint-canary: the build failed, but not on the lint:" >&2
    echo "$out" >&2
    exit 1
fi
echo "lint-canary: the linted build fails on a clippy lint, as it should"
