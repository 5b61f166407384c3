#!/usr/bin/env bash
# The debugging GUI: build the web app (web/dist, embedded by crates/surfaces/situate_gui), and test it in a
# real browser.
#
#   scripts/gui.sh build     npm install when needed, then type-check and build web/dist
#   scripts/gui.sh chromium  install Debian's chromium when /usr/bin/chromium is missing
#   scripts/gui.sh test      build, then build the testbed and the `situate` CLI, install Debian's
#                            chromium when /usr/bin/chromium is missing, and run the browser tests
#
# Respects CARGO_TARGET_DIR. Fails loudly (non-zero exit) on any failure.
set -euo pipefail

cd "$(dirname "$0")/.."
ROOT=$PWD
export PATH="$HOME/.cargo/bin:$PATH"
CARGO=${CARGO:-cargo}
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
ACTION=${1:-build}

die() { echo "gui.sh: $*" >&2; exit 1; }

need() { command -v "$1" >/dev/null 2>&1 || die "$1 is needed ($2)"; }

npm_ready() {
    need node "Node 20 or newer"
    need npm "Node's npm"
    local major
    major=$(node -p 'process.versions.node.split(".")[0]')
    [ "$major" -ge 20 ] || die "Node 20 or newer is needed, found $(node --version)"
    # Install when node_modules is missing or older than the lock file, with `npm ci`: exactly the
    # locked versions, and the lock is never written (a build must not dirty the checkout). The
    # lock is the one npm itself writes (every platform's optional packages listed, as npm lists
    # them), so `npm install` leaves it as it is too.
    if [ ! -d web/node_modules ] || [ web/package-lock.json -nt web/node_modules/.package-lock.json ]; then
        echo "gui.sh: npm ci in web/ (versions from package-lock.json)"
        (cd web && npm ci --no-audit --no-fund)
    fi
}

# web/dist is newer than every file it is built from (the type-check covers src/ only).
web_built() {
    [ -f web/dist/index.html ] || return 1
    [ -z "$(find web/src web/index.html web/package.json web/package-lock.json \
        web/tsconfig.json web/vite.config.ts -newer web/dist/index.html -print -quit)" ]
}

build_web() {
    npm_ready
    # Not built again when up to date: a new web/dist recompiles the crates that embed it (and
    # under `make test` the stages that run side by side would race over that).
    if web_built; then
        echo "gui.sh: web/dist is up to date"
        return
    fi
    echo "gui.sh: building web/dist"
    (cd web && npm run build)
    [ -f web/dist/index.html ] || die "web/dist/index.html was not built"
}

install_chromium() {
    if [ -x /usr/bin/chromium ]; then
        return
    fi
    echo "gui.sh: /usr/bin/chromium is missing: installing Debian's chromium"
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        need sudo "to install chromium with apt-get (or install the chromium package yourself)"
        sudo="sudo"
    fi
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -q
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends chromium
    [ -x /usr/bin/chromium ] || die "chromium was not installed at /usr/bin/chromium"
}

case "$ACTION" in
    build)
        build_web
        ;;
    chromium)
        install_chromium
        ;;
    test)
        build_web
        install_chromium
        export TESTBED_BIN="$TARGET/debug/examples/testbed"
        export SITUATE_BIN="$TARGET/debug/situate"
        if [ "${SITUATE_TESTS_PREBUILT:-}" = 1 ]; then
            # `make test`'s plan (scripts/test.sh) built them (`cargo test --workspace --no-run`
            # builds the programs and the examples) before the test stages started side by side.
            [ -x "$TESTBED_BIN" ] && [ -x "$SITUATE_BIN" ] \
                || die "SITUATE_TESTS_PREBUILT=1 but $TESTBED_BIN or $SITUATE_BIN is missing"
            echo "gui.sh: using the testbed and the situate CLI built by make test"
        else
            echo "gui.sh: building the testbed and the situate CLI (debug, in $TARGET)"
            # The testbed embeds web/dist at compile time: build it after the web app. Built
            # with the whole workspace's features (as `cargo test --workspace` built them), so
            # that build is reused; `-p` alone would unify fewer features and rebuild much of
            # the tree.
            $CARGO build --workspace --example testbed --bin situate
        fi
        echo "gui.sh: running the browser tests (screenshots in web/test-results/)"
        (cd web && npm test)
        ;;
    *)
        die "usage: scripts/gui.sh [build|chromium|test]"
        ;;
esac
