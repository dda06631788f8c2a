#!/usr/bin/env bash
# Installs the Debian 12 packages driftlab needs to build, test and benchmark.
# Idempotent: quiet and fast when everything is already there. Needs root (or sudo).
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libboost-dev libboost-filesystem-dev
  libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  zlib1g-dev python3-numpy
  gnuplot-nox
  libfftw3-dev libgsl-dev
)
if [[ "${DRIFTLAB_WITH_MRPT:-OFF}" == "ON" ]]; then
  packages+=(libmrpt-dev)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

sudo=""
[[ $(id -u) -ne 0 ]] && sudo="sudo"
echo "driftlab: installing ${missing[*]}" >&2
$sudo apt-get update -qq -o DPkg::Lock::Timeout=300
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq -o DPkg::Lock::Timeout=300 \
  --no-install-recommends "${missing[@]}" >/dev/null
