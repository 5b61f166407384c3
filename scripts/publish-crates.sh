#!/usr/bin/env bash
# The Rust crates for publishing. A published crate cannot reach files outside its own
# directory, so two get copies first (not tracked, see .gitignore):
#   crates/surfaces/situate_gui/web-dist/   the built web app (web/dist), which its build.rs embeds
#   crates/binaries/situate_cli/data/       demo/, maps/, examples/, cmake/, include/ (scripts/package-data.sh),
#                                  where `situate demo` and `situate cmake-dir` look last
#
#   scripts/publish-crates.sh            copy, check the packages' file lists, then
#                                        `cargo publish --dry-run --workspace`
#   scripts/publish-crates.sh --check    copy and check the file lists only (fast: no build)
#   scripts/publish-crates.sh --publish  copy, check, and publish for real
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH="$HOME/.cargo/bin:$PATH"
MODE=${1:-dry-run}
say() { printf 'publish-crates.sh: %s\n' "$*"; }
die() { printf 'publish-crates.sh: %s\n' "$*" >&2; exit 1; }

[ -f web/dist/index.html ] || scripts/gui.sh build
# The copies are for the packages only: gone again when the script ends, however it ends. Left
# in the checkout, the program built from it would find the demo in them, where a test expects
# it to find none.
trap 'rm -rf crates/surfaces/situate_gui/web-dist crates/binaries/situate_cli/data' EXIT
rm -rf crates/surfaces/situate_gui/web-dist
cp -rp web/dist crates/surfaces/situate_gui/web-dist
scripts/package-data.sh crates/binaries/situate_cli/data

check() {
    local crate=$1
    shift
    local list
    list=$(cargo package -p "$crate" --list --allow-dirty --no-verify 2>/dev/null) || die "cargo package -p $crate --list failed"
    for want in "$@"; do
        grep -qx "$want" <<<"$list" || die "$crate's package lacks $want"
    done
    say "$crate: $(wc -l <<<"$list") files, including $*"
}
check situate_gui web-dist/index.html
check situate_cli data/demo/robot.yaml data/demo/deliver.py data/demo/courier/main.py \
    data/demo/courier/sequenced/delivery.py data/demo/courier/reactive/rules.py data/maps/default.yaml \
    data/cmake/situateConfig.cmake data/include/situate.h data/include/situate.hpp

case $MODE in
    --check) ;;
    dry-run) cargo publish --dry-run --workspace --allow-dirty ;;
    --publish) cargo publish --workspace --allow-dirty ;;
    *) die "unknown argument $MODE (see the comment at the top)" ;;
esac
