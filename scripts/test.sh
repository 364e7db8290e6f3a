#!/usr/bin/env bash
# The README's test command (and CI's): install what is missing, build, run the whole suite.
#   bash scripts/test.sh [ctest arguments…]
#   bash scripts/test.sh --sanitize [ctest arguments…]   the same suite built with AddressSanitizer
#       and UBSan (optimised, in build-asan/; the fuzz smoke runs are left out: fuzz_smoke has its
#       own sanitized build, and fuzz_cli_smoke's limits, 5 s and 1 GiB a run, are set for a
#       build without the sanitizers); CI runs both.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
configure=()
if [[ ${1:-} == --sanitize ]]; then
    shift
    build_dir=${VTEX_BUILD_DIR:-$root/build-asan}
    configure=(-DVTEX_SANITIZE=ON -DVTEX_FUZZ_SMOKE=OFF -DVTEX_FUZZ_CLI_SMOKE=OFF)
    # Any report fails the test that triggered it; leaks are reports too.
    export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1}
    export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
else
    build_dir=${VTEX_BUILD_DIR:-$root/build}
fi

# The ingest tests read Debian's sample models; the fuzz smoke test wants clang; the cluster
# tests start a one-node Slurm (scripts/slurm-cluster.sh).
VTEX_BUILD_DIR=$build_dir VTEX_EXTRA_PACKAGES="assimp-testmodels clang-14 libclang-rt-14-dev slurm-wlm munge" \
    bash "$root/scripts/build.sh" "${configure[@]}"
cd "$build_dir"
ctest --output-on-failure --parallel "$(nproc)" "$@"
