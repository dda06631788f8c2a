#!/usr/bin/env bash
# One-command set-up on a fresh Debian 12 machine (as root, or with sudo):
#   bash tools/setup.sh demo   installs the Debian packages, builds, runs the main job
#   bash tools/setup.sh test   installs the Debian packages, builds, runs the whole test suite
# Environment: BUILD_DIR (default ./build), JOBS (default: number of cores).
set -euo pipefail
cd "$(dirname "$0")/.."

mode=${1:-demo}
case "$mode" in demo|test) ;; *) echo "usage: bash tools/setup.sh demo|test" >&2; exit 2 ;; esac

build_dir=${BUILD_DIR:-build}
jobs=${JOBS:-$(nproc)}

bash tools/install-deps.sh
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DDRIFTLAB_BUILD_BENCH=ON >/dev/null
cmake --build "$build_dir" -j "$jobs"

if [[ "$mode" == test ]]; then
  ctest --test-dir "$build_dir" -j "$jobs" --output-on-failure --timeout 600
else
  bash tools/demo.sh "$build_dir"
fi
