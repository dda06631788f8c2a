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
  libpagmo-dev libdlib-dev   # optimizer/pagmo, regressor/svr
  clang libclang-rt-14-dev   # libFuzzer harnesses of tests/fuzz (ASan + UBSan runtimes)
  clang-format               # the format check (tools/check-format.sh, .clang-format)
  pybind11-dev python3-pybind11 python3-dev python3-pytest   # the Python module (python/) and its tests
  # ROS bag readers (framework/rosbag.hpp); python3-rosbag and python3-sensor-msgs write the ROS 1
  # bags of the tests (an independent writer), sqlite3 gives the reference counts of .db3 fixtures.
  librosbag-storage-dev libsqlite3-dev libzstd-dev liblz4-dev
  python3-rosbag python3-sensor-msgs sqlite3
  libboost-mpi-dev openmpi-bin   # the fleet's MPI engine (tools/driftlab/fleet_mpi.hpp) and its mpirun test
)
# The MRPT bridge (tools/mrpt): libmrpt-obs-dev alone pulls the obs, bayes, poses, math, io and
# serialization modules (~170 MB); mrpt-apps gives rawlog-edit, which the bridge's tests use.
# Never the umbrella libmrpt-dev (~880 MB: Qt, wx, VTK, ROS). DRIFTLAB_WITH_MRPT=OFF leaves them out.
if [[ "${DRIFTLAB_WITH_MRPT:-AUTO}" != "OFF" ]]; then
  packages+=(libmrpt-obs-dev mrpt-apps)
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
