#!/usr/bin/env bash
# Installs what is missing, then configures and builds vtex (Release) in ./build.
# Extra arguments are passed to CMake's configure step.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${VTEX_BUILD_DIR:-$root/build}

bash "$root/scripts/install-deps.sh" ${VTEX_EXTRA_PACKAGES:-}
cmake -S "$root" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build_dir" --parallel "$(nproc)"
