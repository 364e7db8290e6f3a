#!/usr/bin/env bash
# The README's test command (and CI's): install what is missing, build, run the whole suite.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VTEX_BUILD_DIR:-$root/build}

# The ingest tests read Debian's sample models; the fuzz smoke test wants clang.
VTEX_EXTRA_PACKAGES="assimp-testmodels clang-14 libclang-rt-14-dev" bash "$root/scripts/build.sh"
cd "$build_dir"
ctest --output-on-failure --parallel "$(nproc)" "$@"
