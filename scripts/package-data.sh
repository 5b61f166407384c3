#!/usr/bin/env bash
# The Python package's data: copies demo/, maps/, examples/, and the CMake package for C/C++
# skills (cmake/, include/) (the files git tracks, or all of them outside a git checkout) into
# python/situate/_data/, where the wheel and the sdist pick them up: `situate demo` finds the demo
# once installed, `situate cmake-dir` prints _data/cmake (whose ../include holds the headers). The originals stay where they are; the copy is
# not tracked (.gitignore) and is made again on every build.
#
#   scripts/package-data.sh [DEST]     DEST defaults to python/situate/_data
#                                      (scripts/publish-crates.sh gives crates/binaries/situate_cli/data)
set -euo pipefail
cd "$(dirname "$0")/.."
DEST=${1:-python/situate/_data}
DIRS=(demo maps examples cmake include)
rm -rf "$DEST"
mkdir -p "$DEST"
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git ls-files -z -- "${DIRS[@]}" | while IFS= read -r -d '' f; do
        [[ -f $f ]] || continue # deleted in the work tree
        mkdir -p "$DEST/$(dirname "$f")"
        cp -p "$f" "$DEST/$f"
    done
else
    cp -rp "${DIRS[@]}" "$DEST/"
fi
# A marker, so the data is never mistaken for the sources.
printf '%s\n' "Copied from the repository's ${DIRS[*]} by scripts/package-data.sh; edit the originals." \
    >"$DEST/README.txt"
