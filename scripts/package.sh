#!/usr/bin/env bash
# The Python package for publishing: the source distribution and a wheel for this machine, in
# dist/. The package data (demo/, maps/, examples/) is copied in first; the wheel's extension
# module is stripped; the SBOM in the wheel names the workspace's crates by paths relative to
# the repository (maturin writes the build machine's absolute paths).
#
#   scripts/package.sh                 sdist + wheel (release)
#
# Environment: MATURIN (default .venv/bin/maturin, from scripts/python.sh), CARGO_TARGET_DIR.
# Wheels for other platforms (manylinux_2_28, aarch64) need their toolchain or a container:
# `maturin build --release --manylinux 2_28 --zig --target aarch64-unknown-linux-gnu` with
# ziglang installed, or the manylinux_2_28 images.
set -euo pipefail
cd "$(dirname "$0")/.."
MATURIN=${MATURIN:-.venv/bin/maturin}
OUT=dist
say() { printf 'package.sh: %s\n' "$*"; }

scripts/package-data.sh
rm -rf "$OUT"
say "source distribution"
"$MATURIN" sdist --out "$OUT"
say "wheel (release)"
"$MATURIN" build --release --quiet --out "$OUT"
for wheel in "$OUT"/*.whl; do
    python3 scripts/sbom_relative.py "$wheel" "$PWD"
done
ls -l "$OUT"
