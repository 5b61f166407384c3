#!/usr/bin/env bash
# Runs the aarch64 wheel on this x86_64 machine, under qemu-user: its glibc symbols (at most
# 2.28), `situate --version`, and the whole delivery demo with its Python sequencer, both on an
# aarch64 CPython (Debian 12's, unpacked into a scratch root, never installed) and the aarch64
# eclipse-zenoh wheel. Not part of `make test`: it needs apt (qemu-user-static) and takes about a
# minute after `scripts/package.sh --manylinux`.
#
#   scripts/check-aarch64-wheel.sh [WHEEL]     default: dist/situate-*-manylinux_2_28_aarch64.whl
#
# Environment: WORK (scratch directory, default /tmp/situate-aarch64), ZENOH_VERSION (default
# 1.10.2, the version the tests pin).
set -euo pipefail
cd "$(dirname "$0")/.."
say() { printf 'check-aarch64-wheel.sh: %s\n' "$*"; }
die() { say "$*" >&2; exit 1; }

wheel=${1:-$(ls dist/situate-*-manylinux_2_28_aarch64.whl 2>/dev/null | head -1)}
[ -n "$wheel" ] && [ -f "$wheel" ] || die "no aarch64 wheel: run scripts/package.sh --manylinux first"
work=${WORK:-/tmp/situate-aarch64}
rm -rf "$work" && mkdir -p "$work/site" "$work/root" "$work/debs"

if ! command -v qemu-aarch64-static >/dev/null; then
    say "qemu-user-static (apt)"
    apt-get install -y -q qemu-user-static >/dev/null || { apt-get update -q >/dev/null && apt-get install -y -q qemu-user-static >/dev/null; }
fi

say "an aarch64 CPython 3.11, unpacked (Debian's packages for arm64; nothing is installed)"
added_arch=no
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    dpkg --add-architecture arm64
    added_arch=yes
fi
trap '[ "$added_arch" = yes ] && dpkg --remove-architecture arm64 2>/dev/null || true' EXIT
apt-get update -q >/dev/null
(cd "$work/debs" && apt-get download -q python3.11-minimal:arm64 libpython3.11-minimal:arm64 \
    libpython3.11-stdlib:arm64 libc6:arm64 libexpat1:arm64 zlib1g:arm64 libffi8:arm64 libgcc-s1:arm64 \
    libssl3:arm64 libbz2-1.0:arm64 liblzma5:arm64 libstdc++6:arm64 >/dev/null 2>&1)
for d in "$work"/debs/*.deb; do dpkg -x "$d" "$work/root"; done

say "the wheel and eclipse-zenoh ${ZENOH_VERSION:-1.10.2} for aarch64"
python3 -m pip download -q "eclipse-zenoh==${ZENOH_VERSION:-1.10.2}" --platform manylinux_2_28_aarch64 \
    --platform manylinux2014_aarch64 --only-binary=:all: --python-version 3.11 --no-deps -d "$work/debs"
for w in "$wheel" "$work"/debs/eclipse_zenoh-*.whl; do python3 -m zipfile -e "$w" "$work/site"; done

newest=$(readelf -V "$work/site/situate/_native.abi3.so" | grep -o 'GLIBC_[0-9.]*' | sort -uV | tail -1)
say "newest glibc symbol: $newest"
[ "$(printf '%s\nGLIBC_2.28\n' "$newest" | sort -V | tail -1)" = GLIBC_2.28 ] || die "needs $newest, above 2.28"

py="$work/python.sh"
printf '#!/bin/sh\nQEMU_LD_PREFIX=%s PYTHONPATH=%s exec qemu-aarch64-static %s "$@"\n' \
    "$work/root" "$work/site" "$work/root/usr/bin/python3.11" > "$py"
chmod +x "$py"
"$py" -c 'import platform; assert platform.machine() == "aarch64", platform.machine()'
say "$("$py" -m situate --version)"
say "the delivery demo, headless, its sequencer on the same aarch64 Python"
out=$("$py" -m situate demo --headless --json --seed 1 --python "$py" | tail -1)
python3 -c 'import json, sys; d = json.loads(sys.argv[1]); print("delivered:", d["delivered"], "in", d["cycles"], "cycles,", round(d["mission_time_s"], 1), "s"); sys.exit(0 if d["delivered"] else 1)' "$out" \
    || die "the demo did not deliver: $out"
say "ok"
