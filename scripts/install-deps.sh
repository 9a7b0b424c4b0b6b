#!/usr/bin/env bash
# Installs every Debian 12 package millwatch needs to build, test and benchmark.
# Idempotent: only packages that are missing are installed. Run as root.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git clang-format clang libclang-rt-14-dev
  libeigen3-dev libfftw3-dev libspdlog-dev nlohmann-json3-dev libcli11-dev
  liblcm-dev liblcm-bin liblcm-java default-jdk-headless
  libgtest-dev libgmock-dev libbenchmark-dev libcomedi-dev
  python3 python3-numpy python3-scipy iproute2 util-linux
  libmatio-dev libhdf5-dev zlib1g-dev libsystemd-dev gnuplot-nox fonts-dejavu-core systemd dpkg-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

if [[ $(id -u) -ne 0 ]]; then
  echo "install-deps: missing packages: ${missing[*]}; run this script as root" >&2
  exit 1
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
