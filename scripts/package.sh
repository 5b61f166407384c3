#!/usr/bin/env bash
# The Python package for publishing: the source distribution and a wheel for this machine, in
# dist/. The package data (demo/, maps/, examples/) is copied in first; the wheel's extension
# module is stripped; the SBOM in the wheel names the workspace's crates by paths relative to
# the repository (maturin writes the build machine's absolute paths).
#
#   scripts/package.sh                 sdist + wheel for this machine (release)
#   scripts/package.sh --manylinux     sdist + manylinux_2_28 wheels for x86_64 and aarch64,
#                                      cross-built with zig (the `ziglang` package, installed into
#                                      .venv) and the Rust target added with rustup when missing;
#                                      glibc 2.28 or newer (RHEL 8, Debian 10, Ubuntu 18.10 on)
#
# Environment: MATURIN (default .venv/bin/maturin, from scripts/python.sh), CARGO_TARGET_DIR,
# TARGETS (with --manylinux; default "x86_64-unknown-linux-gnu aarch64-unknown-linux-gnu").
set -euo pipefail
cd "$(dirname "$0")/.."
MATURIN=${MATURIN:-.venv/bin/maturin}
OUT=dist
say() { printf 'package.sh: %s\n' "$*"; }

scripts/package-data.sh
rm -rf "$OUT"
say "source distribution"
"$MATURIN" sdist --out "$OUT"
if [ "${1:-}" = --manylinux ]; then
    PY=$(dirname "$MATURIN")/python
    "$PY" -m ziglang version >/dev/null 2>&1 || "$PY" -m pip install --quiet "ziglang>=0.13"
    # maturin looks for a `zig` program: one that runs the package's.
    ZIGBIN=$(mktemp -d)
    trap 'rm -rf "$ZIGBIN"' EXIT
    printf '#!/bin/sh\nexec "%s" -m ziglang "$@"\n' "$(cd "$(dirname "$PY")" && pwd)/python" >"$ZIGBIN/zig"
    chmod +x "$ZIGBIN/zig"
    for target in ${TARGETS:-x86_64-unknown-linux-gnu aarch64-unknown-linux-gnu}; do
        rustup target list --installed | grep -qx "$target" || rustup target add "$target"
        say "wheel manylinux_2_28 $target (release, zig)"
        PATH="$ZIGBIN:$PATH" "$MATURIN" build --release --quiet --strip --zig \
            --compatibility manylinux_2_28 --target "$target" --out "$OUT"
    done
else
    say "wheel (release)"
    "$MATURIN" build --release --quiet --out "$OUT"
fi
for wheel in "$OUT"/*.whl; do
    python3 scripts/sbom_relative.py "$wheel" "$PWD"
done
ls -l "$OUT"
