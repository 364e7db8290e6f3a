#!/usr/bin/env bash
# The README's main job: install what is missing, build, run `vtex demo`.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VTEX_BUILD_DIR:-$root/build}

bash "$root/scripts/build.sh"
"$build_dir/apps/vtex/vtex" demo "$@"
