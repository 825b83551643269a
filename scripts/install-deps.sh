#!/usr/bin/env bash
# Installs the Debian 12 packages mocap needs, skipping those already present.
#   scripts/install-deps.sh          packages to build and run (daemon, viewer, tools)
#   scripts/install-deps.sh --test   also what the test suite needs (Xvfb, fuzzers, oscdump, Blender
#                                    and the numpy its glTF importer needs)
# Works as root or through sudo; fails with a clear message naming the package that failed.
set -euo pipefail

build_pkgs=(build-essential cmake ninja-build pkg-config git
  libeigen3-dev libserialport-dev libhidapi-dev libusb-1.0-0-dev
  libglfw3-dev libgl-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libtomlplusplus-dev
  nlohmann-json3-dev
  zlib1g-dev libzstd-dev libdeflate-dev libpng-dev libcli11-dev xvfb xauth)
test_pkgs=(libgtest-dev libgmock-dev libbenchmark-dev clang-14 libclang-rt-14-dev
  libfuzzer-14-dev liblo-tools socat python3 blender python3-numpy xdotool)

want=("${build_pkgs[@]}")
if [[ "${1:-}" == "--test" ]]; then want+=("${test_pkgs[@]}"); fi

missing=()
for p in "${want[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#want[@]} packages present"
  exit 0
fi

if [[ $(id -u) -eq 0 ]]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1; then
  SUDO=(sudo)
else
  echo "install-deps: need root or sudo to install: ${missing[*]}" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${SUDO[@]}" apt-get update -qq || { echo "install-deps: apt-get update failed" >&2; exit 1; }
if ! "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"; then
  for p in "${missing[@]}"; do
    "${SUDO[@]}" apt-get install -y -qq --no-install-recommends "$p" >/dev/null 2>&1 ||
      echo "install-deps: cannot install Debian package '$p'" >&2
  done
  exit 1
fi
echo "install-deps: done"
