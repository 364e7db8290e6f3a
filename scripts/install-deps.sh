#!/usr/bin/env bash
# Installs the Debian 12 packages vtex builds and tests with. Idempotent: asks apt only for
# what is missing, and runs `apt-get update` only when something is.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libcgal-dev libgmp-dev libmpfr-dev libopenmesh-dev libtinygltf-dev libstb-dev
  libembree-dev libopenexr-dev libimath-dev libtbb-dev libeigen3-dev libcli11-dev
  nlohmann-json3-dev libfmt-dev libspdlog-dev libpng-dev libjpeg-dev libxxhash-dev
  libtomlplusplus-dev libgtest-dev libgmock-dev libbenchmark-dev
  # OpenVDB, for `vtex export` to .vdb: optional to CMake (a build without it refuses .vdb),
  # installed here so that every build has it and its tests run. Its Find-module fails without
  # Boost.Iostreams, which Debian's libopenvdb-dev does not depend on.
  libopenvdb-dev libboost-iostreams-dev
  # Headless Chromium, for the test that loads report.html (links resolve, nothing overflows,
  # a screenshot of its first screen): the test fails without it, so every build has it.
  chromium
)
# Extra packages a caller asks for (the tests want Debian's sample models).
packages+=("$@")

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "vtex: installing ${#missing[@]} Debian packages: ${missing[*]}" >&2
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
