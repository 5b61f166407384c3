#!/usr/bin/env bash
# System tools the tests use that a bare machine may lack: iproute2 (`ss`, `ip netns`).
# Installs them with apt when run as root; otherwise says what is missing.
set -euo pipefail
missing=()
command -v ss >/dev/null 2>&1 || missing+=(iproute2)
command -v ip >/dev/null 2>&1 || missing+=(iproute2)
[[ ${#missing[@]} -eq 0 ]] && exit 0
if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq iproute2 >/dev/null
else
    echo "system-deps: please install iproute2 (the tests use ss and ip netns)" >&2
    exit 1
fi
